//! The cost of a winch (docs/method.md §23): a 5 t payload lowered on a 32 mm steel wire
//! rope (EA = 4.3e7 N, 4.1 kg/m, elements of 1 m) from a drum, 2D, in gravity. The rope
//! starts with 10 m off the drum, hanging at rest in its static shape, and 1001 elements on
//! the drum; the payout speed ramps linearly from 0 to 1 m/s over the first 10 s and holds,
//! so that 1000 m are paid out at t = 1005 s (1010 elements off the drum at the end), with a
//! fixed step `h` (`dg`, the default solver). `cargo bench -p phstring --bench winch` prints,
//! per step size, the wall time, the ratio of simulated to wall time (the real-time
//! factor), and the median time of a step that ends with a cut (an element comes off the
//! drum), of the step after it and of the other steps (over the whole run, 510 elements
//! off the drum at the median), and of the other steps of the last 2 % of the run (about
//! 1000 elements off the drum); and what a cut adds to its step (the median cut step less
//! the median other step) in the first 10 % of the run (10–110 elements off the drum) and
//! in the last 2 %. Each step size runs four times: with the payout prescribed;
//! with a drum with dynamics (docs/method.md §23.6) whose tension controller (damping 1e5
//! N·s/m, no inertia) follows the same payout speed through its target tension, the static
//! weight less `d` times the speed (its payout is a Newton unknown, solved with the bordered
//! solve), the drum's payout ending within 1 % of 1000 m; and with the drum, its payout
//! prescribed, on a 50 t vessel (a rigid body, docs/method.md §23.7) that heaves
//! 0.5 m and rolls 1° from rest at an 8 s period, the drum point 2 m above its centre; and
//! with the payout prescribed and the rope in water (32 mm, drag coefficient 1.2, added mass
//! coefficient 1, below the surface at the drum), whose water is lumped again at each cut.

use nalgebra::{UnitQuaternion, Vector3};
use phstring::{
    Attachment, BodyMotion, BodyState, Boundary, LineHydro, MassMatrix, Material, NetworkBuilder,
    PointMass, RigidBody, Simulation, State, StepControl, StepParams, StringSpec, Vector, Water,
    Winch, WinchDrum,
};
use std::sync::Arc;
use std::time::Instant;

const G: f64 = 9.81;
const EA: f64 = 4.3e7;
const RHO_A: f64 = 4.1;
const PAYLOAD: f64 = 5000.0;
/// Rope off the drum at the start [m], elements on the drum, payout [m], speed [m/s] and
/// the speed's ramp [s].
const START: usize = 10;
const RESERVE: usize = 1001;
const PAYOUT: f64 = 1000.0;
const SPEED: f64 = 1.0;
const RAMP: f64 = 10.0;

/// The paid-out length [m] at `t` [s]: the speed ramps linearly to `SPEED` over `RAMP`.
fn payout(t: f64) -> f64 {
    if t < RAMP {
        SPEED * t * t / (2.0 * RAMP)
    } else {
        SPEED * (t - 0.5 * RAMP)
    }
}

/// The payout speed [m/s] at `t` [s].
fn speed(t: f64) -> f64 {
    SPEED * (t / RAMP).min(1.0)
}

/// The tension controller's damping [N·s/m].
const DAMPING: f64 = 1.0e5;

/// How the winch of a run is driven and where it sits.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// The payout prescribed, the drum fixed.
    Prescribed,
    /// A drum's tension controller.
    Drum,
    /// The payout prescribed, the drum on a heaving, rolling vessel.
    Vessel,
    /// The payout prescribed, the rope in water (drag, buoyancy, added mass), lumped again
    /// at each cut.
    Water,
}

/// The vessel's pose at `t` [s]: heave `0.5 (1 − cos ωt)` m and roll `1° (1 − cos ωt)`,
/// `ω = 2π/8 s⁻¹`, its centre 2 m below the drum point.
fn vessel_pose(t: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let c = 1.0 - (std::f64::consts::TAU / 8.0 * t).cos();
    (
        Vector3::new(0.0, -2.0 + 0.5 * c, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 1f64.to_radians() * c),
    )
}

/// The vessel's velocity and angular velocity at `t` [s].
fn vessel_twist(t: f64) -> (Vector3<f64>, Vector3<f64>) {
    let w = std::f64::consts::TAU / 8.0;
    let s = w * (w * t).sin();
    (
        Vector3::new(0.0, 0.5 * s, 0.0),
        Vector3::new(0.0, 0.0, 1f64.to_radians() * s),
    )
}

/// The lowering run with step `h` [s] of `kind`: the simulation and the time the payout is
/// done [s].
fn setup(h: f64, kind: Kind) -> (Simulation<2, Material>, f64) {
    let with_drum = kind == Kind::Drum;
    let a = START as f64;
    // The static shape of the hanging rope below the drum, at unstretched distance `s`.
    let hanging = |s: f64| -(s + G * ((PAYLOAD + RHO_A * a) * s - 0.5 * RHO_A * s * s) / EA);
    let mut b = NetworkBuilder::<2, Material>::new();
    let drum = b.node(Vector::<2>::zeros());
    let hook = b.node(Vector::<2>::new(0.0, -a));
    let spec = StringSpec {
        name: "rope".into(),
        material: Material::tension_only_linear(EA),
        rho_a: RHO_A,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -RHO_A * G),
        prestretch: 1.0,
    };
    let g = b
        .string_on_drum(spec, &[drum, hook], START, RESERVE)
        .unwrap();
    let nodes = b.group_nodes(g).unwrap().to_vec();
    let masses = vec![PointMass {
        node: hook,
        mass: PAYLOAD,
        weight: Vector::<2>::new(0.0, -PAYLOAD * G),
    }];
    let mut net = b.build(Boundary::default(), masses).unwrap();
    let mut r = net.initial.r.clone();
    for (j, &i) in nodes[RESERVE..].iter().enumerate() {
        r[i] = Vector::<2>::new(0.0, hanging(j as f64));
    }
    net.initial = State::at_rest(&net.mesh, r);
    if kind == Kind::Vessel {
        let (x0, q0) = vessel_pose(0.0);
        net = net.with_body(RigidBody {
            name: "vessel".into(),
            mass: 5e4,
            inertia: nalgebra::Matrix3::from_diagonal_element(4e6),
            weight: Vector::<2>::new(0.0, -5e4 * G),
            attachments: vec![Attachment {
                node: drum,
                point: Vector::<2>::new(0.0, 2.0),
            }],
            initial: BodyState::new(x0, Vector3::zeros(), q0, Vector3::zeros()),
            wrench: None,
            hydro: None,
            motion: Some(BodyMotion {
                pose: Arc::new(vessel_pose),
                twist: Arc::new(vessel_twist),
            }),
            feedback: None,
        });
    }
    if kind == Kind::Water {
        net = net.with_water(Water::new(1025.0)).with_line_hydro(
            g,
            LineHydro {
                diameter: 0.032,
                cd: 1.2,
                ca: 1.0,
                ..Default::default()
            },
        );
    }
    net = net.with_winch(Winch {
        name: "lowering".into(),
        group: g,
        reserve: RESERVE,
        payout: Arc::new(payout),
        drum_motion: None,
        drum: with_drum.then(|| WinchDrum {
            derivative_time: 0.0,
            inertia: 0.0,
            // The static weight at the drum less `d` times the speed: at steady state the
            // controller pays out at the speed.
            force: Arc::new(move |t| G * (PAYLOAD + RHO_A * (a + payout(t))) - DAMPING * speed(t)),
            damping: DAMPING,
            brake: None,
        }),
    });
    let params = StepParams {
        h,
        control: StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..StepParams::default()
    };
    let end = PAYOUT / SPEED + 0.5 * RAMP;
    (Simulation::new(net, params).unwrap(), end)
}

fn main() {
    println!(
        "h [s]   payout      steps   wall [s]  real-time factor  cuts  Newton it/step  ms per step: cut  after  other (at 1000 elements: other)  µs a cut adds: early  late"
    );
    let kinds = [Kind::Prescribed, Kind::Drum, Kind::Vessel, Kind::Water];
    for (h, kind) in [0.05, 0.02].into_iter().flat_map(|h| kinds.map(|k| (h, k))) {
        let (mut sim, end) = setup(h, kind);
        let steps = (end / h).round() as usize;
        let mut times = Vec::with_capacity(steps);
        let mut drum_nodes = Vec::with_capacity(steps);
        let mut iterations = 0;
        let t0 = Instant::now();
        for _ in 0..steps {
            let s = Instant::now();
            iterations += sim.step().unwrap().newton_iterations;
            times.push(s.elapsed().as_secs_f64());
            drum_nodes.push(sim.winch_samples()[0].port.0);
        }
        let wall = t0.elapsed().as_secs_f64();
        let w = sim.winch_samples()[0];
        let off = if kind == Kind::Drum {
            1e-2 * PAYOUT
        } else {
            1e-9
        };
        assert!((w.payout - PAYOUT).abs() < off, "payout {}", w.payout);
        // Step k ends with a cut when the drum node of step k + 1 is another node.
        let mut cut = vec![false; steps];
        for k in 0..steps - 1 {
            cut[k] = drum_nodes[k + 1] != drum_nodes[k];
        }
        // The median step time of a class of steps (robust to the machine's hiccups) and
        // how many steps it has.
        let median = |pick: &dyn Fn(usize) -> bool| {
            let mut t: Vec<f64> = (0..steps - 1)
                .filter(|&k| pick(k))
                .map(|k| times[k])
                .collect();
            t.sort_by(f64::total_cmp);
            (t.get(t.len() / 2).copied().unwrap_or(f64::NAN), t.len())
        };
        let after = |k: usize| k > 0 && cut[k - 1];
        let (t_cut, n_cut) = median(&|k| cut[k]);
        let (t_after, _) = median(&after);
        let (t_other, _) = median(&|k| !(cut[k] || after(k)));
        let last = steps / 50;
        let (t_late, _) = median(&|k| k + last >= steps && !(cut[k] || after(k)));
        // What a cut adds to its step, early (the first 10 % of the run, 10–110 elements off
        // the drum) and late (the last 2 %, about 1000): O(1) per cut keeps the two alike.
        let early = steps / 10;
        let (t_cut_early, _) = median(&|k| k < early && cut[k]);
        let (t_other_early, _) = median(&|k| k < early && !(cut[k] || after(k)));
        let (t_cut_late, _) = median(&|k| k + last >= steps && cut[k]);
        let kind = match kind {
            Kind::Prescribed => "prescribed",
            Kind::Drum => "drum",
            Kind::Vessel => "on vessel",
            Kind::Water => "in water",
        };
        println!(
            "{h:<6}  {kind:<10}  {steps:>6}  {wall:>8.2}  {:>16.0}  {n_cut:>4}  {:>14.2}  {:>16.3}  {:>5.3}  {:>5.3}  ({:.3})  {:>6.1}  {:>6.1}",
            end / wall,
            iterations as f64 / steps as f64,
            t_cut * 1e3,
            t_after * 1e3,
            t_other * 1e3,
            t_late * 1e3,
            (t_cut_early - t_other_early) * 1e6,
            (t_cut_late - t_late) * 1e6,
        );
    }
}
