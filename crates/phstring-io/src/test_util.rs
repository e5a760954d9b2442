//! Helpers shared by the unit tests of this crate.

use std::path::PathBuf;

use phstring::benchmarks::paper_pendulum;
use phstring::{Material, Scheme, Simulation, StepParams};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh, empty directory under the system temp dir, unique per process and call.
pub fn temp_dir(prefix: &str, name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!(
        "phstring-{prefix}-{}-{n}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The paper's pendulum (10 elements) with the discrete gradient scheme, `h = 0.01 s`.
pub fn sim() -> Simulation<2, Material> {
    let params = StepParams {
        h: 0.01,
        scheme: Scheme::DiscreteGradient,
        ..Default::default()
    };
    Simulation::new(paper_pendulum(10), params).unwrap()
}

/// A network of two strings with awkward names and a spring, with a point mass.
pub fn named_network() -> Simulation<2, Material> {
    use phstring::{Boundary, MassMatrix, NetworkBuilder, PointMass, StringSpec, Vector};
    let mut b = NetworkBuilder::<2, Material>::new();
    let n: Vec<usize> = [(0.0, 0.0), (1.0, -1.0), (2.0, 0.0)]
        .iter()
        .map(|&(x, y)| b.node(Vector::<2>::new(x, y)))
        .collect();
    let spec = |name: &str| StringSpec {
        name: name.into(),
        material: Material::linear_elastic(1e3),
        rho_a: 0.1,
        mass: MassMatrix::Lumped,
        body_force: Vector::zeros(),
        prestretch: 1.0,
    };
    b.string(spec("a,b \"c\""), &[n[0], n[1]], 3).unwrap();
    b.string(spec(" line\nbreak"), &[n[1], n[2]], 2).unwrap();
    b.spring("plain", n[0], n[2], 10.0, 2.0).unwrap();
    let net = b
        .build(
            Boundary::default(),
            vec![PointMass {
                node: n[1],
                mass: 0.5,
                weight: Vector::zeros(),
            }],
        )
        .unwrap();
    let params = StepParams {
        h: 0.01,
        ..Default::default()
    };
    Simulation::new(net, params).unwrap()
}
