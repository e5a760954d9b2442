//! Prescribed motion of a support (paper Remarks 3–4): velocity in, reaction
//! force out. A crane trolley drags the top of a hanging rope with a payload sideways.

use crate::common::energy_scale;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Mesh, Motion, Network, PointMass, PortKind, Problem,
    SetupError, Simulation, State, StepParams, Vector,
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
    let (mut worst, mut supplied, mut work, mut held) = (0.0_f64, 0.0, 0.0, 0.0);
    let h0 = sim.energies().hamiltonian();
    for _ in 0..400 {
        let (x0, v0) = (sim.state().r[0][0], sim.state().v[0][0]);
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let x1 = sim.state().r[0][0];
        // The support's velocity is held at the trolley's, and the kinetic energy that
        // imposes over the scheme's own update 2Δ/h − v_n is supplied by the trolley.
        let s = (r.t / 2.0).clamp(0.0, 1.0);
        let speed = if r.t < 2.0 { 6.0 * s * (1.0 - s) } else { 0.0 };
        // The backward difference of the motion: second-order, to 1e-8 m/s.
        assert!(
            (sim.state().v[0][0] - speed).abs() < 1e-8,
            "t = {}: support velocity {} m/s, trolley {speed} m/s",
            r.t,
            sim.state().v[0][0]
        );
        let mut unheld = sim.state().clone();
        unheld.v[0][0] = 2.0 * (x1 - x0) / r.h - v0;
        // Its impulse is part of the reaction (whose work over Δx is in `work`); the
        // kinetic energy it imposes beyond that work is the rest of the trolley's supply.
        let impulse =
            (sim.system().linear_momentum(sim.state()) - sim.system().linear_momentum(&unheld))[0];
        held += sim.energies().kinetic
            - sim.system().energies(&unheld).kinetic
            - impulse * (x1 - x0) / r.h;
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
    // The y-component is fixed (no motion, no work), so the supplied energy is the x-work
    // plus the kinetic energy of the held velocity beyond its impulse's work (small: the
    // scheme's update is second-order accurate for the smooth trolley).
    assert!(
        (supplied - work - held).abs() < 1e-9 * work.abs().max(1.0),
        "supplied {supplied} J, reaction work {work} J, held velocity {held} J"
    );
    assert!(
        held.abs() < 1e-5 * work.abs(),
        "held velocity {held} J, reaction work {work} J"
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

/// A soft 50 m rope (EA = 1e6 N, 20 kg/m, 40 lumped elements) with a 2 t payload, hanging at
/// rest in its static equilibrium, its top heaved by `sin(2πt/10)` from t = 0: the heave
/// starts at 0.63 m/s while the rope is at rest. The reaction at the top is read every step
/// at `h`.
fn heaved_reactions(h: f64) -> Vec<f64> {
    let (length, n_el, rho_a, payload, ea) = (50.0, 40, 20.0, 2000.0, 1e6);
    let mesh = Mesh::uniform_chain(n_el, length).unwrap();
    // The lumped chain's equilibrium: element e carries the payload and every node below it,
    // N_e = g (m_p + ρA l (n − e − ½)), at the stretch ν_e = 1 + N_e/EA.
    let l = length / n_el as f64;
    let mut r = vec![Vector::<2>::zeros()];
    for e in 0..n_el {
        let tension = G * (payload + rho_a * l * (n_el as f64 - e as f64 - 0.5));
        let y = r[e][1] - l * (1.0 + tension / ea);
        r.push(Vector::<2>::new(0.0, y));
    }
    let initial = State::at_rest(&mesh, r);
    let heave = |t: f64| (2.0 * std::f64::consts::PI * t / 10.0).sin();
    let problem = Problem {
        initial,
        mesh,
        material: Material::tension_only_linear(ea),
        rho_a,
        body_force: Vector::<2>::new(0.0, -G * rho_a),
        mass: MassMatrix::Lumped,
        boundary: Boundary {
            fixed: vec![Fixed {
                node: 0,
                components: [true, false],
            }],
            loads: vec![],
            motions: vec![Motion::new(0, 1, heave)],
            feedback: vec![],
        },
        point_masses: vec![PointMass {
            node: n_el,
            mass: payload,
            weight: Vector::<2>::new(0.0, -payload * G),
        }],
    };
    // Kelvin–Voigt damping (η = 5 kN·s: about half critical for one element, 1 % for the
    // payload's bounce) lets the rope's own response to the sudden start die out.
    let mut network: Network<2, Material> = problem.into();
    network.groups[0].damping.kelvin_voigt = 5e3;
    let mut sim = Simulation::new(
        network,
        StepParams {
            h,
            ..StepParams::default()
        },
    )
    .unwrap();
    assert!((sim.state().v[0][1] - 0.2 * std::f64::consts::PI).abs() < 1e-9);
    let steps = (5.0 / h).round() as usize;
    (0..steps)
        .map(|_| {
            let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
            assert!(r.relative_balance_error() < 1e-13);
            sim.ports()[0].output[1]
        })
        .collect()
}

/// The reaction at a support heaved by `sin(ωt)` (which starts moving while the rope is at
/// rest) has no mode that alternates from step to step: without the held velocity the
/// support's velocity error `ẋ(0) − v_0 = 0.63 m/s` would flip sign every step forever, and
/// the reaction with it by `2 m Δv / h` (1.6 kN at h = 0.01 s for the 12.5 kg top node,
/// growing as `h` shrinks). The reaction converges as `h` shrinks.
#[test]
fn a_heaved_support_reports_a_reaction_without_an_alternating_mode() {
    let hs = [0.01, 0.005, 0.0025];
    let runs: Vec<Vec<f64>> = hs.iter().map(|&h| heaved_reactions(h)).collect();
    for (h, r) in hs.iter().zip(&runs) {
        // The alternating part of the reaction after the start (t ≥ 2 s): a quarter of its
        // second difference.
        let alternating = r[(2.0 / h) as usize..]
            .windows(3)
            .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs() / 4.0)
            .fold(0.0, f64::max);
        eprintln!("h = {h} s: alternating part ≤ {alternating:.3e} N");
        assert!(
            alternating < 5.0,
            "h = {h}: alternating part {alternating} N"
        );
    }
    // The reaction at t = 1, 2, …, 5 s: the differences between successive h shrink.
    let at = |k: usize, t: f64| runs[k][(t / hs[k]).round() as usize - 1];
    let (mut d1, mut d2, mut scale) = (0.0_f64, 0.0_f64, 0.0_f64);
    for t in [1.0, 2.0, 3.0, 4.0, 5.0] {
        d1 = d1.max((at(0, t) - at(1, t)).abs());
        d2 = d2.max((at(1, t) - at(2, t)).abs());
        scale = scale.max(at(2, t).abs());
    }
    eprintln!("|R(h) − R(h/2)| ≤ {d1:.3e} N, |R(h/2) − R(h/4)| ≤ {d2:.3e} N, |R| ≤ {scale:.3e} N");
    assert!(d2 < 0.5 * d1, "no convergence: {d1} N, then {d2} N");
    assert!(d2 < 1e-3 * scale, "R(h/2) − R(h/4) = {d2} N of {scale} N");
}

/// A motion far beyond floating point (found by fuzzing networks: a fairlead moving at
/// 1e154 m/s under `mp`, which has no balance test): the setup refuses an initial energy that
/// overflows, and no step is accepted with an energy or a supply that overflows.
#[test]
fn a_motion_whose_energy_overflows_is_refused_not_accepted() {
    for (speed, scheme) in [
        (1e154, phstring::Scheme::Midpoint),
        (3e153, phstring::Scheme::Midpoint),
        (3e153, phstring::Scheme::DiscreteGradient),
    ] {
        let mut problem = crane(10, 0.0);
        problem.boundary.motions = vec![Motion::new(0, 0, move |t| speed * t)];
        let params = StepParams {
            h: 1e-3,
            scheme,
            ..StepParams::default()
        };
        match Simulation::new(problem, params) {
            Err(e) => assert!(e.to_string().contains("initial energy"), "{e}"),
            Ok(mut sim) => {
                assert!(sim.energies().hamiltonian().is_finite());
                for _ in 0..3 {
                    match sim.step() {
                        Ok(r) => {
                            assert!(r.after.hamiltonian().is_finite() && r.supplied.is_finite())
                        }
                        Err(_) => break,
                    }
                }
            }
        }
    }
}
