//! Prescribed motion of a support (issue 11, item 3; paper Remarks 3–4): velocity in, reaction
//! force out. A crane trolley drags the top of a hanging rope with a payload sideways.

use crate::common::energy_scale;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Mesh, Motion, PointMass, PortKind, Problem, SetupError,
    Simulation, State, StepParams, Vector,
};

const G: f64 = 9.81;

/// The trolley position [m]: at rest, then 2 m to the side within 2 s (smooth start and stop).
fn trolley(t: f64) -> f64 {
    let s = (t / 2.0).clamp(0.0, 1.0);
    2.0 * s * s * (3.0 - 2.0 * s)
}

fn crane(n_el: usize, start: f64) -> Problem<2, Material> {
    let length = 20.0;
    let mesh = Mesh::uniform_chain(n_el, length).unwrap();
    let initial = State::straight(
        &mesh,
        Vector::<2>::new(start, 0.0),
        Vector::<2>::new(start, -length),
    );
    Problem {
        initial,
        mesh,
        material: Material::tension_only_linear(1e7),
        rho_a: 0.5,
        body_force: Vector::<2>::new(0.0, -G * 0.5),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            // The trolley runs on a rail: y fixed, x prescribed.
            fixed: vec![Fixed {
                node: 0,
                components: [false, true],
            }],
            loads: vec![],
            motions: vec![Motion::new(0, 0, trolley)],
            feedback: vec![],
        },
        point_masses: vec![PointMass {
            node: n_el,
            mass: 500.0,
            weight: Vector::<2>::new(0.0, -500.0 * G),
        }],
    }
}

/// The top node follows the trolley to the last bit, the supplied energy is the work of the
/// reaction over the prescribed displacement, the discrete energy balance holds to round-off
/// on every step, and the port's input is the mid-step velocity of the trolley.
#[test]
fn moving_support_drags_the_rope_with_an_exact_energy_balance() {
    let mut sim = Simulation::new(
        crane(40, 0.0),
        StepParams {
            h: 0.01,
            ..StepParams::default()
        },
    )
    .unwrap();
    let ports = sim.ports();
    assert_eq!((ports[0].kind, ports[0].node), (PortKind::Velocity, 0));
    let (mut worst, mut supplied, mut work) = (0.0_f64, 0.0, 0.0);
    let h0 = sim.energies().hamiltonian();
    for _ in 0..400 {
        let x0 = sim.state().r[0][0];
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let x1 = sim.state().r[0][0];
        assert!(
            (x1 - trolley(r.t)).abs() <= 4.0 * f64::EPSILON * 2.0,
            "t = {}: top at {x1}, trolley at {}",
            r.t,
            trolley(r.t)
        );
        let port = sim.ports()[0];
        assert!((port.input[0] - (x1 - x0) / r.h).abs() < 1e-12);
        // Work of the reaction in x over the step.
        work += port.output[0] * (x1 - x0);
        supplied += r.supplied;
        let scale = energy_scale(&r.after);
        worst = worst.max(r.balance_error.abs() / scale);
    }
    let h1 = sim.energies().hamiltonian();
    eprintln!(
        "Ĥ: {h0:.6} → {h1:.6} J, supplied {supplied:.6} J (reaction work {work:.6} J), balance error / energy ≤ {worst:.1e}"
    );
    assert!(worst < 1e-12, "balance error {worst:e} of the energy");
    assert!(
        ((h1 - h0) - supplied).abs() < 1e-9 * h0.abs(),
        "Ĥ changed by {} J, supplied {supplied} J",
        h1 - h0
    );
    // The y-component is fixed (no motion, no work), so the supplied energy is the x-work.
    assert!(
        (supplied - work).abs() < 1e-9 * work.abs().max(1.0),
        "supplied {supplied} J, reaction work {work} J"
    );
    assert!(
        work.abs() > 1.0,
        "the trolley did no work: the test lost its point"
    );
}

/// A prescribed position that does not start where the node is, is refused at setup.
#[test]
fn prescribed_motion_must_start_at_the_initial_position() {
    let err = Simulation::new(crane(10, 0.5), StepParams::default())
        .err()
        .expect("refused");
    assert!(
        matches!(
            err,
            SetupError::MotionStart {
                node: 0,
                component: 0,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string().contains("but the node starts at 0.5 m"),
        "{err}"
    );
}
