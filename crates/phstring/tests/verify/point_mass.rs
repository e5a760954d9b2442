//! Point masses at nodes: a payload on a light rope against the closed-form
//! spring–mass oscillation, and the exact discrete balances with masses attached.

use std::f64::consts::PI;

use crate::common::energy_scale;
use phstring::testing::hanging_chain;
use phstring::{
    Boundary, MassMatrix, Material, Mesh, PointMass, Problem, Simulation, State, StepControl,
    StepParams, Vector,
};

const G: f64 = 9.81;

/// A 1 t payload hooked at t = 0 on 10 m of light rope (EA = 1e6 N, 10 g/m, 100 g in all)
/// hanging from a fixed top, unstretched at rest. The payload bounces on the rope as on a
/// spring of stiffness EA/L: `y(t) = −L − δ (1 − cos ωt)` with `ω = √(EA/(L M))` = 10 rad/s
/// and the static stretch `δ = M g L / EA` = 9.81 cm. The law is linear in `C`, so its force
/// is `EA ε (1 + 3ε/2 + …)`: at ε ≤ 2 % the closed form holds to a few per cent.
#[test]
fn payload_on_a_light_rope_bounces_like_a_spring_mass() {
    let (length, ea, rho_a, payload) = (10.0, 1e6, 0.01, 1000.0);
    let n_el = 10;
    let problem = hanging_chain(
        n_el,
        length,
        Material::linear_elastic(ea),
        rho_a,
        payload,
        Vector::<2>::new(0.0, -1.0),
    );
    let omega = (ea / (length * payload)).sqrt();
    let delta = payload * G * length / ea;
    let period = 2.0 * PI / omega;
    let steps = 400;
    let params = StepParams {
        h: period / steps as f64,
        control: StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..StepParams::default()
    };
    let mut sim = Simulation::new(problem, params).unwrap();
    let (mut lowest, mut t_lowest, mut worst_balance) = (0.0_f64, 0.0, 0.0_f64);
    for _ in 0..steps {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let stretch = -length - sim.state().r[n_el][1];
        if stretch > lowest {
            lowest = stretch;
            t_lowest = r.t;
        }
        let scale = energy_scale(&r.after);
        worst_balance = worst_balance.max(r.balance_error.abs() / scale);
    }
    let back = -length - sim.state().r[n_el][1];
    eprintln!(
        "largest stretch {lowest:.5} m (closed form {:.5}), at t = {t_lowest:.4} s (T/2 = {:.4}), after one period {back:.2e} m, balance error / energy {worst_balance:.1e}",
        2.0 * delta,
        period / 2.0
    );
    assert!(
        (lowest / (2.0 * delta) - 1.0).abs() < 0.03,
        "largest stretch {lowest} m, closed form {}",
        2.0 * delta
    );
    assert!(
        (t_lowest / (period / 2.0) - 1.0).abs() < 0.03,
        "lowest point at t = {t_lowest} s, closed form {}",
        period / 2.0
    );
    assert!(
        back.abs() < 0.05 * delta,
        "after one period the payload is at {back} m"
    );
    assert!(
        worst_balance < 1e-12,
        "balance error {worst_balance:e} of the energy"
    );
}

/// A free string with two point masses, spinning and stretching without gravity: the
/// discrete linear and angular momentum (masses included) are conserved to round-off, and
/// the energy balance holds exactly.
#[test]
fn point_masses_keep_momentum_and_energy_exact() {
    let n_el = 8;
    let mesh = Mesh::uniform_chain(n_el, 1.0).unwrap();
    let r: Vec<Vector<2>> = (0..=n_el)
        .map(|i| Vector::<2>::new(1.3 * i as f64 / n_el as f64 - 0.65, 0.0))
        .collect();
    let v: Vec<Vector<2>> = r
        .iter()
        .map(|p| Vector::<2>::new(0.4 * p[0], 2.0 * p[0]))
        .collect();
    let problem = Problem {
        initial: State::consistent(&mesh, r, v),
        mesh,
        material: Material::hyperelastic(50.0),
        rho_a: 0.2,
        body_force: Vector::zeros(),
        mass: MassMatrix::Consistent,
        boundary: Boundary::default(),
        point_masses: vec![
            PointMass {
                node: 0,
                mass: 0.5,
                weight: Vector::zeros(),
            },
            PointMass {
                node: 5,
                mass: 0.3,
                weight: Vector::zeros(),
            },
            PointMass {
                node: 5,
                mass: 0.2,
                weight: Vector::zeros(),
            },
        ],
    };
    // The momenta are conserved by the step equations; the Newton residual (its force and
    // torque) is what is left, so the tolerance is tight and absolute as in the momentum test.
    let params = StepParams {
        h: 0.01,
        newton: phstring::NewtonParams::absolute(1e-12),
        ..StepParams::default()
    };
    let mut sim = Simulation::new(problem, params).unwrap();
    assert_eq!(sim.system().point_masses(), &[(0, 0.5), (5, 0.5)]);
    let p0 = sim.system().linear_momentum(sim.state());
    let l0 = sim.system().angular_momentum(sim.state());
    let mut worst = 0.0_f64;
    for _ in 0..200 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        worst = worst.max(r.balance_error.abs());
    }
    let p1 = sim.system().linear_momentum(sim.state());
    let l1 = sim.system().angular_momentum(sim.state());
    assert!((p1 - p0).norm() < 1e-13, "linear momentum {p0} → {p1}");
    assert!((l1 - l0).abs() < 1e-13, "angular momentum {l0} → {l1}");
    assert!(worst < 1e-13, "balance error {worst:e} J");
}
