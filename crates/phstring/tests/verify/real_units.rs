//! Strings and cables in real SI units run with the default Newton settings.
//!
//! A vertical rope hangs from a fixed top node with a payload's weight at its bottom node and
//! starts unstretched at rest, so it bounces axially. Axial stiffness from a rubber thread
//! (EA = 1 N) to a heavy steel cable (EA = 1e9 N). With the old absolute tolerance of
//! 1e-11 N, the stiff cases could not converge (the residual's round-off floor lies above
//! it) and step-size control halved the step thousands of times.

use crate::common::energy_scale;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Mesh, NodalLoad, Problem, Simulation, State,
    StepControl, StepParams, Vector,
};

const G: f64 = 9.81;

/// A rope case: axial stiffness, mass per length, payload, length.
#[derive(Clone, Copy, Debug)]
struct Rope {
    name: &'static str,
    ea: f64,      // N
    rho_a: f64,   // kg/m
    payload: f64, // kg
    length: f64,  // m
}

const ROPES: [Rope; 8] = [
    Rope {
        name: "rubber thread",
        ea: 1.0,
        rho_a: 1e-3,
        payload: 1e-3,
        length: 0.5,
    },
    Rope {
        name: "elastic cord",
        ea: 1e2,
        rho_a: 1e-2,
        payload: 0.1,
        length: 2.0,
    },
    Rope {
        name: "bungee",
        ea: 1e4,
        rho_a: 0.1,
        payload: 10.0,
        length: 5.0,
    },
    Rope {
        name: "nylon rope",
        ea: 1e5,
        rho_a: 0.1,
        payload: 50.0,
        length: 20.0,
    },
    Rope {
        name: "hanging string",
        ea: 9.81e5,
        rho_a: 1.0,
        payload: 100.0,
        length: 10.0,
    },
    Rope {
        name: "fibre rope",
        ea: 1e6,
        rho_a: 0.5,
        payload: 500.0,
        length: 30.0,
    },
    Rope {
        name: "steel rope",
        ea: 1e8,
        rho_a: 1.0,
        payload: 2000.0,
        length: 50.0,
    },
    Rope {
        name: "steel cable",
        ea: 1e9,
        rho_a: 10.0,
        payload: 20000.0,
        length: 100.0,
    },
];

fn hanging(rope: Rope, material: Material, n_el: usize) -> Problem<2, Material> {
    let mesh = Mesh::uniform_chain(n_el, rope.length).unwrap();
    let bottom = Vector::<2>::new(0.0, -rope.length);
    let initial = State::straight(&mesh, Vector::zeros(), bottom);
    let weight = rope.payload * G;
    Problem {
        point_masses: Vec::new(),
        mesh,
        material,
        rho_a: rope.rho_a,
        body_force: Vector::<2>::new(0.0, -G * rope.rho_a),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            motions: vec![],
            feedback: vec![],
            fixed: vec![Fixed::node(0)],
            loads: vec![NodalLoad::new(n_el, move |_| {
                Vector::<2>::new(0.0, -weight)
            })],
        },
        initial,
    }
}

/// Runs to `t_end` with `params`; returns (steps, rejected, worst balance error relative to
/// the energy scale of its step, worst residual relative to the force scale).
fn run_with(
    problem: Problem<2, Material>,
    params: StepParams,
    t_end: f64,
) -> (usize, usize, f64, f64) {
    let mut sim = Simulation::new(problem, params).unwrap();
    let mut worst_rel = 0.0_f64;
    let mut worst_res = 0.0_f64;
    while sim.time() < t_end - 1e-12 {
        let r = sim.step_until(t_end).unwrap_or_else(|e| panic!("{e}"));
        // Energy scale of the step: the largest magnitude of the energy parts before and
        // after, and the supplied work.
        let scale = energy_scale(&r.before)
            .max(energy_scale(&r.after))
            .max(r.supplied.abs());
        worst_rel = worst_rel.max(r.balance_error.abs() / scale);
        assert!(r.balance_error.is_finite());
        worst_res = worst_res.max(r.residual / r.force_scale);
        assert!(
            r.residual <= r.tolerance || r.at_roundoff,
            "step {}: residual {:e} above the tolerance {:e}",
            r.step,
            r.residual,
            r.tolerance
        );
    }
    (sim.steps(), sim.rejected_steps(), worst_rel, worst_res)
}

/// [`run_with`] the default settings and step size `h`.
fn run(problem: Problem<2, Material>, h: f64, t_end: f64) -> (usize, usize, f64, f64) {
    let params = StepParams {
        h,
        ..StepParams::default()
    };
    run_with(problem, params, t_end)
}

/// EA from 1 to 1e9 N with realistic ρA and payloads runs with the
/// default settings in the planned number of steps (no rejected step), and the energy
/// balance holds to round-off relative to the energy scale.
#[test]
fn stiff_real_unit_ropes_converge_with_default_tolerance() {
    let (h, t_end) = (0.005, 0.05);
    let planned = 10;
    for rope in ROPES {
        for material in [
            Material::hyperelastic(rope.ea),
            Material::tension_only_linear(rope.ea),
        ] {
            let (steps, rejected, rel, res) = run(hanging(rope, material, 100), h, t_end);
            eprintln!(
                "{:14} {:26} EA = {:7.1e} N: {steps} steps, {rejected} rejected, balance error / energy scale {rel:.1e}, residual / force scale {res:.1e}",
                rope.name,
                material.name(),
                rope.ea
            );
            // The tension-only law starts at its kink (C = 1) and some elements go slack in
            // the first steps; a few of those steps are halved for the nonlinearity: their
            // line search fails with residuals of the order of the forces (1e4 N for the
            // steel rope), not at round-off. Before the relative tolerance, the hanging
            // string (EA = 9.81e5 N) took 18,483 steps for 2.
            let (most_steps, most_rejected) = match material {
                Material::Hyperelastic(_) => (planned, 0),
                _ => (2 * planned, planned / 2),
            };
            assert!(
                steps <= most_steps && rejected <= most_rejected,
                "{}: {steps} steps ({rejected} rejected) for {planned}",
                rope.name
            );
            assert!(
                rel < 1e-12,
                "{}: balance error {rel:.2e} of the energy scale",
                rope.name
            );
        }
    }
}

/// A hanging string (EA = 9.81e5 N, N = 100, h = 5 ms), which took 18,483 steps for 2
/// planned with an absolute tolerance, takes the planned 200 steps to T = 1 s without a
/// rejected step.
#[test]
fn hanging_string_runs_in_planned_steps() {
    let rope = ROPES[4];
    let (steps, rejected, rel, _) = run(
        hanging(rope, Material::hyperelastic(rope.ea), 100),
        0.005,
        1.0,
    );
    assert_eq!((steps, rejected), (200, 0));
    assert!(rel < 1e-12, "balance error {rel:.2e} of the energy scale");
}

/// A fixed-step run with an absolute tolerance below the residual's round-off floor does not
/// stop with "line search failed … could not be reduced": such iterates are recognised as
/// converged at the round-off floor, and the energy balance still holds.
#[test]
fn absolute_tolerance_below_roundoff_converges_at_the_floor() {
    let rope = ROPES[6]; // steel rope, forces of 2e4 N: round-off about 1e-12 N
    let params = StepParams {
        h: 0.005,
        newton: phstring::NewtonParams::absolute(1e-11),
        control: StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..StepParams::default()
    };
    let mut sim =
        Simulation::new(hanging(rope, Material::hyperelastic(rope.ea), 100), params).unwrap();
    let mut floor_steps = 0;
    for _ in 0..20 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        if r.at_roundoff {
            floor_steps += 1;
            assert!(
                r.residual > 1e-11,
                "only iterates above the tolerance stop at the floor"
            );
            assert!(
                r.residual <= 1e-3 * r.force_scale,
                "far above round-off: {:e}",
                r.residual
            );
        }
        let scale = energy_scale(&r.after);
        assert!(
            r.balance_error.abs() <= 1e-12 * scale,
            "balance error {:e}",
            r.balance_error
        );
    }
    assert!(
        floor_steps > 0,
        "no step reached the round-off floor: the test lost its point"
    );
}

/// The step-size floor is absolute (halvings counted from the already reduced step size let
/// `h` fall far below `time.h / 2^max_halvings`): a step that cannot
/// converge ends the run at `h = time.h / 2^max_halvings`, and the message says so.
#[test]
fn step_size_floor_is_absolute() {
    let rope = ROPES[6];
    // One Newton iteration cannot solve a step of a stiff rope: every attempt fails.
    let params = StepParams {
        h: 0.005,
        newton: phstring::NewtonParams {
            max_iter: 1,
            progress_extension: 1,
            ..Default::default()
        },
        control: StepControl {
            max_halvings: 5,
            ..Default::default()
        },
        ..StepParams::default()
    };
    let mut sim =
        Simulation::new(hanging(rope, Material::hyperelastic(rope.ea), 20), params).unwrap();
    let floor = sim.step_size_floor();
    assert_eq!(floor, 0.005 / 32.0);
    let mut smallest = f64::INFINITY;
    let err = loop {
        match sim.step() {
            Ok(r) => smallest = smallest.min(r.h),
            Err(e) => break e,
        }
        assert!(sim.steps() < 10_000, "never failed");
    };
    assert!(
        smallest >= floor,
        "accepted h = {smallest:e} below the floor {floor:e}"
    );
    match &err {
        phstring::StepError::StepSizeTooSmall { h, floor: f, .. } => {
            assert_eq!(*h, floor);
            assert_eq!(*f, floor);
        }
        other => panic!("unexpected error {other}"),
    }
    let msg = err.to_string();
    assert!(msg.contains("step-size floor"), "{msg}");
    assert!(msg.contains("2^5"), "{msg}");
}

/// A `time.h` so small that its floor `h/2^max_halvings` underflows to 0 (5e-324 s, found by
/// fuzzing networks): a failed step halved `h` to 0 and never reached the floor, so the step
/// retried forever. It now ends with the step-size error.
#[test]
fn step_size_floor_that_underflows_ends_the_step() {
    let rope = ROPES[6];
    let params = StepParams {
        h: 5e-324,
        control: StepControl {
            max_halvings: 4,
            ..Default::default()
        },
        ..StepParams::default()
    };
    let mut sim =
        Simulation::new(hanging(rope, Material::hyperelastic(rope.ea), 20), params).unwrap();
    assert_eq!(sim.step_size_floor(), 0.0);
    // In a thread, so that a regression fails the test instead of hanging it.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(sim.step().map(|r| r.h).map_err(|e| e.to_string()));
    });
    let result = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("the step did not end within 60 s");
    let msg = result.expect_err("a step of 5e-324 s cannot converge");
    assert!(msg.contains("step-size floor"), "{msg}");
}

/// Found while measuring memory: a stiff rope lying straight at rest, with no load,
/// has stresses of round-off size (`C = 1 ± ε`), and a stress can only change in steps of
/// `EA/2 · ulp(C)`. The residual then cannot fall below about `EA · ε` per element, far above
/// `rtol · F` of such tiny forces, and every step was halved down to the floor. The strain
/// part of the round-off floor makes this converge at once, and the rope stays at rest.
#[test]
fn stiff_rope_at_rest_stays_at_rest() {
    let rope = ROPES[6]; // steel rope, EA = 1e8 N
    let mesh = Mesh::uniform_chain(1000, rope.length).unwrap();
    let end = Vector::<2>::new(rope.length, 0.0);
    let problem = Problem {
        point_masses: Vec::new(),
        initial: State::straight(&mesh, Vector::zeros(), end),
        mesh,
        material: Material::hyperelastic(rope.ea),
        rho_a: rope.rho_a,
        body_force: Vector::zeros(),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            motions: vec![],
            feedback: vec![],
            fixed: vec![Fixed::node(0)],
            loads: vec![],
        },
    };
    let params = StepParams {
        h: 0.01,
        ..StepParams::default()
    };
    let mut sim = Simulation::new(problem, params).unwrap();
    for _ in 0..10 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r.rejected, 0, "step {} was halved", r.step);
    }
    let v_max = sim.state().v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    // The initial strains are C = 1 ± ε: stresses up to EA·ε ≈ 2e-8 N act on nodes of
    // 0.05 kg for 0.1 s, so velocities stay below about 4e-8 m/s.
    assert!(v_max < 1e-7, "the rope at rest moves at {v_max:e} m/s");
}

/// A string at 1e308 m with gravity, or one whose strain overflows (reference length
/// 1e-154 m stretched to 1 m), is refused at setup with the non-finite derived quantity
/// named, instead of running to "completed" with `Ĥ = inf` and NaN in the outputs.
#[test]
fn non_finite_derived_quantities_are_refused_at_setup() {
    let build = |start: Vector<2>, end: Vector<2>, length: f64, gravity: f64| {
        let mesh = Mesh::uniform_chain(30, length).unwrap();
        let initial = State::straight(&mesh, start, end);
        Problem {
            point_masses: Vec::new(),
            initial,
            mesh,
            material: Material::hyperelastic(20.0),
            rho_a: 1.0,
            body_force: Vector::<2>::new(-gravity, -gravity),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                motions: vec![],
                feedback: vec![],
                fixed: vec![Fixed::node(0)],
                loads: vec![],
            },
        }
    };
    let far = build(
        Vector::<2>::new(1e308, 0.0),
        Vector::<2>::new(1e308, -1.0),
        1.0,
        9.81,
    );
    let err = Simulation::new(far, StepParams::default())
        .err()
        .expect("refused");
    let msg = err.to_string();
    assert!(
        msg.contains("initial external potential energy is not finite"),
        "{msg}"
    );

    // A body force of 1e308 N/m: each nodal force is finite, but the residual overflows.
    let huge = build(Vector::zeros(), Vector::<2>::new(1.0, 0.0), 1.0, 1e308);
    let err = Simulation::new(huge, StepParams::default())
        .err()
        .expect("refused");
    let msg = err.to_string();
    assert!(
        msg.contains("squared nodal body forces is not finite"),
        "{msg}"
    );

    let overflowing = build(Vector::zeros(), Vector::<2>::new(1.0, 0.0), 1e-154, 9.81);
    let err = Simulation::new(overflowing, StepParams::default())
        .err()
        .expect("refused");
    let msg = err.to_string();
    assert!(
        msg.contains("not finite") || msg.contains("domain"),
        "{msg}"
    );
}
