//! A winch drum on a rigid body (docs/method.md §23.7): on a vessel that moves and turns it is
//! the moving drum of space at the vessel's point, with a prescribed payout or a drum of its
//! own. (A drum on a free, turning body: `src/simulation/winch_body_tests.rs`.)

use super::winch::{G, PAYLOAD, fixed_step, rope_below};
use nalgebra::{UnitQuaternion, Vector3};
use phstring::{
    Attachment, BodyMotion, BodyState, DrumFn, Material, Network, RigidBody, Simulation, Vector,
    Winch, WinchDrum,
};
use std::f64::consts::PI;
use std::sync::Arc;

/// A vessel's prescribed pose and twist as functions of time.
type Pose = Arc<dyn Fn(f64) -> (Vector3<f64>, UnitQuaternion<f64>) + Send + Sync>;
type Twist = Arc<dyn Fn(f64) -> (Vector3<f64>, Vector3<f64>) + Send + Sync>;

/// The drum point in the vessel's axes [m] (10 m forward of its centre of mass, 2 m up).
const DRUM: [f64; 2] = [10.0, 2.0];

/// A 50 t vessel (2D) with the prescribed `pose` and `twist`, its point [`DRUM`] fixed to
/// node `drum`.
fn vessel(
    net: Network<2, Material>,
    drum: usize,
    pose: Pose,
    twist: Twist,
) -> Network<2, Material> {
    let (x0, q0) = pose(0.0);
    let (v0, om0) = twist(0.0);
    let m = 5e4;
    net.with_body(RigidBody {
        name: "vessel".into(),
        mass: m,
        inertia: nalgebra::Matrix3::from_diagonal_element(4e6),
        weight: Vector::<2>::new(0.0, -m * G),
        attachments: vec![Attachment {
            node: drum,
            point: Vector::<2>::new(DRUM[0], DRUM[1]),
        }],
        initial: BodyState::new(x0, v0, q0, om0),
        wrench: None,
        hydro: None,
        motion: Some(BodyMotion {
            pose: pose.clone(),
            twist: twist.clone(),
        }),
        feedback: None,
    })
}

/// The winch on the rope's group `g`, paying out `p(t)`, its drum moving as `drum_motion`.
fn winch(g: usize, reserve: usize, p: fn(f64) -> f64, drum_motion: Option<DrumFn>) -> Winch {
    Winch {
        name: "winch".into(),
        group: g,
        reserve,
        payout: Arc::new(p),
        drum_motion,
        drum: None,
    }
}

/// 3 m paid out and hauled back in over 8 s, from rest to rest: `1.5 (1 − cos(πt/4))` [m].
fn out_and_in(t: f64) -> f64 {
    1.5 * (1.0 - (0.25 * PI * t).cos())
}

/// A vessel surging 4 m (period 12 s), heaving 1 m (8 s) and rolling 6° (10 s) from rest, with a
/// winch at its drum point paying out 3 m and hauling it back in over 8 s (cuts both ways) on 20 m of rope with
/// the 5 t payload, against the same winch as a drum of space moving with that point
/// (`drum_motion` = the vessel's `x(t) + R(t) s_X`), 8 s at 10 ms. On the body the drum
/// point is the body's, and the drum node, fixed to the body, slides from it along its path
/// in space axes; so both runs put the drum node at the same place and the hooks agree to the
/// Newton tolerance (bound 1e-8 m) and the drum tensions to 1e-6 of the payload's weight.
/// Each run's balance is exact on every step (1e-12 of the energy scale), and the winch's
/// energy on the body is that of the drum of space less the drive's work, which the vessel's
/// motion supplies instead.
#[test]
fn drum_on_a_moving_vessel_is_the_moving_drum_at_its_point() {
    vessel_against_the_moving_drum(None, 6);
}

/// As [`drum_on_a_moving_vessel_is_the_moving_drum_at_its_point`] with a tension controller
/// on the vessel instead of the payout (a drum of 2 t at the rope, its motor pulling 45 kN
/// against the 50.7 kN the rope and payload weigh, damping 1e4 N·s/m): the drum's payout is a
/// slot of the step, coupled with the vessel's, and the two runs still agree to the Newton
/// tolerance (3.4 m paid out by 8 s, 4 cuts).
#[test]
fn drum_with_dynamics_on_a_moving_vessel_is_the_moving_drum_at_its_point() {
    let drum = WinchDrum {
        derivative_time: 0.0,
        inertia: 2000.0,
        force: Arc::new(|_| 45.0e3),
        damping: 1.0e4,
        brake: None,
    };
    vessel_against_the_moving_drum(Some(drum), 4);
}

/// The vessel of [`drum_on_a_moving_vessel_is_the_moving_drum_at_its_point`], its winch
/// driven by the payout or by `dynamics`, against the drum of space moving with its point:
/// hooks, drum tensions, balances, the winch energies and at least `min_cuts` cuts.
fn vessel_against_the_moving_drum(dynamics: Option<WinchDrum>, min_cuts: usize) {
    let (a1, a2, a3) = (2.0, 0.5, 3f64.to_radians());
    let (w1, w2, w3) = (2.0 * PI / 12.0, 2.0 * PI / 8.0, 2.0 * PI / 10.0);
    // From rest: `a (1 − cos ωt)` in each motion.
    let centre = move |t: f64| {
        Vector3::new(
            a1 * (1.0 - (w1 * t).cos()),
            -3.0 + a2 * (1.0 - (w2 * t).cos()),
            0.0,
        )
    };
    let turn =
        move |t: f64| UnitQuaternion::from_euler_angles(0.0, 0.0, a3 * (1.0 - (w3 * t).cos()));
    let pose: Pose = Arc::new(move |t| (centre(t), turn(t)));
    let twist: Twist = Arc::new(move |t| {
        let v = Vector3::new(a1 * w1 * (w1 * t).sin(), a2 * w2 * (w2 * t).sin(), 0.0);
        (v, Vector3::new(0.0, 0.0, a3 * w3 * (w3 * t).sin()))
    });
    let point =
        move |t: f64| centre(t) + turn(t).transform_vector(&Vector3::new(DRUM[0], DRUM[1], 0.0));
    let top = move |t: f64| Vector::<2>::new(point(t).x, point(t).y);
    let (v, om) = twist(0.0);
    let v0 = v + om.cross(&turn(0.0).transform_vector(&Vector3::new(DRUM[0], DRUM[1], 0.0)));
    let (n_el, reserve) = (20, 6);

    let (net, g, drum, _) = rope_below(top(0.0), Vector::<2>::new(v0.x, v0.y), n_el, reserve);
    let net = vessel(net, drum, pose, twist).with_winch(Winch {
        drum: dynamics.clone(),
        ..winch(g, reserve, out_and_in, None)
    });
    let mut on_body = Simulation::new(net, fixed_step(0.01)).unwrap();

    let (net, g, _, hook) = rope_below(top(0.0), Vector::<2>::zeros(), n_el, reserve);
    let motion: DrumFn = Arc::new(move |t| {
        let p = top(t);
        [p.x, p.y, 0.0]
    });
    let net = net.with_winch(Winch {
        drum: dynamics,
        ..winch(g, reserve, out_and_in, Some(motion))
    });
    let mut in_space = Simulation::new(net, fixed_step(0.01)).unwrap();

    let (mut apart, mut tension, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    let mut cuts = 0;
    let mut drum_el = on_body.checkpoint().winches[0].drum;
    for _ in 0..800 {
        let a = on_body.step().unwrap();
        let b = in_space.step().unwrap();
        worst = worst
            .max(a.balance_error.abs() / a.energy_scale)
            .max(b.balance_error.abs() / b.energy_scale);
        apart = apart.max((on_body.state().r[hook] - in_space.state().r[hook]).norm());
        let (sa, sb) = (&on_body.winch_samples()[0], &in_space.winch_samples()[0]);
        tension = tension.max((sa.tension - sb.tension).abs());
        let d = on_body.checkpoint().winches[0].drum;
        cuts += usize::from(d != drum_el);
        drum_el = d;
    }
    // The drum of space's winch supplies its reaction's work over the drum point's motion
    // too; on the body that work goes to the body, whose motion supplies the rest of its
    // energy change: `E_space = E_body + (W_motion − ΔH_vessel)`, with `W_motion` the body
    // run's supply less its winch's.
    let (ea, eb) = (
        on_body.winch_samples()[0].energy,
        in_space.winch_samples()[0].energy,
    );
    let h_vessel = |st: &BodyState| {
        let m = 5e4;
        0.5 * m * st.velocity.norm_squared()
            + 0.5 * 4e6 * st.omega.z * st.omega.z
            + m * G * st.position.y
    };
    let start = BodyState::new(centre(0.0), Vector3::zeros(), turn(0.0), Vector3::zeros());
    let dh = h_vessel(&on_body.state().bodies[0]) - h_vessel(&start);
    let motion = on_body.supplied_energy() - ea;
    eprintln!(
        "moving vessel: hooks {apart:.2e} m apart, tensions {tension:.2e} N apart, {cuts} cuts, balance {worst:.2e}; winch energy on the body {ea:.6e} J, in space {eb:.6e} J; the vessel's motion supplied {motion:.6e} J, ΔH_vessel {dh:.6e} J"
    );
    let payout = on_body.winch_samples()[0].payout;
    eprintln!("payout at the end {payout:.4} m");
    assert!(cuts >= min_cuts, "{cuts} cuts");
    assert!(apart < 1e-8, "the hooks are {apart:e} m apart");
    assert!(
        tension < 1e-6 * PAYLOAD * G,
        "the drum tensions differ by {tension:e} N"
    );
    assert!(worst < 1e-12, "balance error {worst:e} of the energy scale");
    let drive = motion - dh;
    eprintln!(
        "drive's work {drive:.6e} J; the energies' difference off it by {:.1e} of the winch's",
        (eb - ea - drive).abs() / eb.abs().max(1.0)
    );
    assert!(
        (eb - ea - drive).abs() < 1e-6 * eb.abs().max(1.0),
        "the winches' energies differ by {} J, the drive's work is {drive} J",
        eb - ea
    );
}
