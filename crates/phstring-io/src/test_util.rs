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

/// A 2D line of 20 elements of 5 m (`EA = 1e9 N`, `ρA = 100 kg/m`, its weight) in water 50 m
/// deep with a current of 0.5 m/s, on a seabed with stiffness, damping and friction: laid on
/// the seabed from the anchor (0, −50) m, then straight up to the fairlead (70, −5) m, both
/// held (docs/method.md §21). It sinks into the seabed and sways in the current.
pub fn wet_line() -> Simulation<2, Material> {
    use phstring::{
        Boundary, Current, Fixed, Friction, LineHydro, MassMatrix, Mesh, Problem, Seabed, State,
        Vector, Water,
    };
    let (n, l) = (20, 5.0);
    let anchor = Vector::<2>::new(0.0, -50.0);
    let fairlead = Vector::<2>::new(70.0, -5.0);
    // Grounded up to x_b, then straight to the fairlead: a path of length n l.
    let len = |xb: f64| xb + (fairlead - Vector::<2>::new(xb, -50.0)).norm();
    let (mut lo, mut hi) = (0.0, 70.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if len(mid) < n as f64 * l {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let touchdown = Vector::<2>::new(lo, -50.0);
    let r: Vec<Vector<2>> = (0..=n)
        .map(|i| {
            let s = l * i as f64;
            if s <= lo {
                anchor + (touchdown - anchor) * (s / lo)
            } else {
                let up = fairlead - touchdown;
                touchdown + up * ((s - lo) / up.norm()).min(1.0)
            }
        })
        .collect();
    let mesh = Mesh::uniform_chain(n, l * n as f64).unwrap();
    let net: phstring::Network<2, Material> = Problem {
        initial: State::at_rest(&mesh, r),
        mesh,
        material: Material::linear_elastic(1e9),
        rho_a: 100.0,
        body_force: Vector::<2>::new(0.0, -100.0 * phstring::water::STANDARD_GRAVITY),
        mass: MassMatrix::Lumped,
        boundary: Boundary {
            fixed: vec![Fixed::node(0), Fixed::node(n)],
            loads: vec![],
            motions: vec![],
            feedback: vec![],
        },
        point_masses: vec![],
    }
    .into();
    let seabed = Seabed::flat(50.0, 3e6, 3e5).with_friction(Friction::new(0.5, 200.0));
    let water = Water::new(1025.0)
        .with_current(Current::Uniform(Vector::<2>::new(0.5, 0.0)))
        .with_seabed(seabed);
    let hydro = LineHydro {
        diameter: 0.1,
        cd: 1.2,
        cd_axial: 0.4,
        ca: 1.0,
        ca_axial: 0.5,
    };
    let params = StepParams {
        h: 0.01,
        scheme: Scheme::DiscreteGradient,
        ..Default::default()
    };
    Simulation::new(net.with_water(water).with_line_hydro(0, hydro), params).unwrap()
}

/// The point array `name` of the ParaView frame at `path`, `None` if it has none.
pub fn frame_point_array(path: &std::path::Path, name: &str) -> Option<Vec<f64>> {
    use vtkio::model::{Attribute, DataSet, Piece, Vtk};
    let DataSet::PolyData { mut pieces, .. } = Vtk::import(path).unwrap().data else {
        panic!("not PolyData");
    };
    let Piece::Inline(p) = pieces.remove(0) else {
        panic!("not an inline piece");
    };
    p.data.point.iter().find_map(|a| match a {
        Attribute::DataArray(d) if a.name() == name => Some(d.data.clone().cast_into().unwrap()),
        _ => None,
    })
}
