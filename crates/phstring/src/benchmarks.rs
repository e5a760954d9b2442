//! Ready-made problems: the paper's benchmark (docs/method.md §12) and verification cases.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use crate::boundary::{Boundary, Fixed, NodalLoad};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::newton::NewtonParams;
use crate::simulation::StepParams;
use crate::system::{MassMatrix, Problem, State, Vector};

/// Published values of the paper's benchmark: `Ĥ(0)`, and `Ĥ(1)` for DG and MP [J].
pub const PAPER_H0: f64 = -3.468359;
/// `Ĥ(1)` with the discrete-gradient scheme [J].
pub const PAPER_H1_DG: f64 = -3.403762;
/// `Ĥ(1)` with the implicit midpoint rule [J].
pub const PAPER_H1_MP: f64 = -3.398474;

/// The paper's step parameters: `h = 0.01 s`, discrete gradient, and the paper's absolute
/// Newton tolerance 1e-11 N (not the relative default, so that the published run is
/// reproduced bit for bit).
pub fn paper_params() -> StepParams {
    StepParams {
        h: 0.01,
        newton: NewtonParams::absolute(1e-11),
        ..StepParams::default()
    }
}

/// The load of the paper's benchmark: `F_N(t) = ρA (1, 1) sin(πt/0.2)` for `t ∈ [0, 0.2]`,
/// zero after [N].
pub fn paper_load(rho_a: f64, t: f64) -> Vector<2> {
    let a = if (0.0..=0.2).contains(&t) {
        rho_a * (PI * t / 0.2).sin()
    } else {
        0.0
    };
    Vector::<2>::new(a, a)
}

/// The paper's string pendulum (docs/method.md §12) with `n_el` elements: `L = 1 m`, `EA = 20 N`,
/// `ρA = 1 kg/m`, hyperelastic, left end fixed at the origin, load at the right end,
/// gravity `9.81 m/s²`. Run it with `h = 0.01 s` to `T = 1 s`.
pub fn paper_pendulum(n_el: usize) -> Problem<2, Material> {
    let mesh = Mesh::uniform_chain(n_el.max(1), 1.0).expect("n_el ≥ 1 and L = 1 > 0");
    let end = Vector::<2>::new(FRAC_1_SQRT_2, -FRAC_1_SQRT_2);
    let initial = State::straight(&mesh, Vector::zeros(), end);
    let tip = mesh.n_nodes() - 1;
    Problem {
        point_masses: Vec::new(),
        mesh,
        material: Material::hyperelastic(20.0),
        rho_a: 1.0,
        body_force: Vector::<2>::new(0.0, -9.81),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            motions: vec![],
            feedback: vec![],
            fixed: vec![Fixed::node(0)],
            loads: vec![NodalLoad::new(tip, |t| paper_load(1.0, t))],
        },
        initial,
    }
}

/// A taut string for order-of-accuracy checks (docs/method.md §13, §19): `n_el` elements,
/// reference length 1 m stretched to 1.2 m (`C = 1.44`), `EA = 20 N` hyperelastic,
/// `ρA = 1 kg/m`, no gravity, both ends fixed, released at rest from a transverse sine of
/// 0.1 m amplitude. Its motion is smooth.
pub fn taut_string(n_el: usize) -> Problem<2, Material> {
    let n_el = n_el.max(1);
    let mesh = Mesh::uniform_chain(n_el, 1.0).expect("n_el ≥ 1 and L = 1 > 0");
    let r = (0..=n_el)
        .map(|i| {
            let s = i as f64 / n_el as f64;
            Vector::<2>::new(1.2 * s, 0.1 * (std::f64::consts::PI * s).sin())
        })
        .collect();
    Problem {
        point_masses: Vec::new(),
        initial: State::at_rest(&mesh, r),
        mesh,
        material: Material::hyperelastic(20.0),
        rho_a: 1.0,
        body_force: Vector::zeros(),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            fixed: vec![Fixed::node(0), Fixed::node(n_el)],
            ..Default::default()
        },
    }
}
