//! A winch drum on a rigid body (docs/method.md §23, "A drum on a rigid body"): on a vessel
//! that moves and turns it is the moving drum of space at the vessel's point; on a free body
//! that turns, every step's balance holds through payout, haul-in and the cuts.

use super::winch::{EA, G, L, PAYLOAD, RHO_A, fixed_step};
use nalgebra::{UnitQuaternion, Vector3};
use phstring::{
    Attachment, BodyMotion, BodyState, Boundary, DrumFn, MassMatrix, Material, Network,
    NetworkBuilder, PointMass, RigidBody, Simulation, State, StringSpec, Vector, Winch, WinchDrum,
};
use std::f64::consts::PI;
use std::sync::Arc;

/// A vessel's prescribed pose and twist as functions of time.
type Pose = Arc<dyn Fn(f64) -> (Vector3<f64>, UnitQuaternion<f64>) + Send + Sync>;
type Twist = Arc<dyn Fn(f64) -> (Vector3<f64>, Vector3<f64>) + Send + Sync>;

/// The drum point in the vessel's axes [m] (10 m forward of its centre of mass, 2 m up).
const DRUM: [f64; 2] = [10.0, 2.0];

/// A 2D hoist of `n_el` elements of 1 m of the 32 mm rope with the 5 t payload at its end,
/// `reserve` elements on the drum, hanging in its static shape below the drum point `top`
/// [m], moving at `v0` [m/s] (the drum point's velocity at `t = 0`: the nodes on the drum
/// and the drum node move with it). Returns the builder's network, the rope's group, its
/// drum node (the path's first node) and the hook.
fn rope_below(
    top: Vector<2>,
    v0: Vector<2>,
    n_el: usize,
    reserve: usize,
) -> (Network<2, Material>, usize, usize, usize) {
    let a = n_el as f64 * L;
    let mut b = NetworkBuilder::<2, Material>::new();
    let drum = b.node(top);
    let hook = b.node(top + Vector::<2>::new(0.0, -a));
    let spec = StringSpec {
        name: "rope".into(),
        material: Material::tension_only_linear(EA),
        rho_a: RHO_A,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -RHO_A * G),
        prestretch: 1.0,
    };
    let g = b
        .string_on_drum(spec, &[drum, hook], n_el, reserve)
        .unwrap();
    let nodes = b.group_nodes(g).unwrap().to_vec();
    let masses = vec![PointMass {
        node: hook,
        mass: PAYLOAD,
        weight: Vector::<2>::new(0.0, -PAYLOAD * G),
    }];
    let mut net = b.build(Boundary::default(), masses).unwrap();
    let mut r = net.initial.r.clone();
    for (j, &i) in nodes[reserve..].iter().enumerate() {
        // The static stretch of a vertical rope carrying the payload and the rope below.
        let s = j as f64 * L;
        let y = s + G * ((PAYLOAD + RHO_A * a) * s - 0.5 * RHO_A * s * s) / EA;
        r[i] = top + Vector::<2>::new(0.0, -y);
    }
    net.initial = State::at_rest(&net.mesh, r);
    for &i in &nodes[..=reserve] {
        net.initial.v[i] = v0;
    }
    (net, g, drum, hook)
}

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
        inertia: 2000.0,
        force: Arc::new(|_| 45.0e3),
        damping: 1.0e4,
        brake: None,
    };
    vessel_against_the_moving_drum(Some(drum), 3);
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
    assert!(
        (eb - ea - drive).abs() < 1e-6 * eb.abs().max(1.0),
        "the winches' energies differ by {} J, the drive's work is {drive} J",
        eb - ea
    );
}

/// A free 2 t body (3D), hung from a fixed point by 10 m of rope at its top and started
/// swinging and turning about all three axes, with a winch at a point 0.6 m off its centre
/// paying out 3 m and hauling it back in over 8 s (cuts both ways) 15 m of rope with a 500 kg
/// hook below: every step's balance holds to 1e-12 of the energy scale (the body's
/// kinetic and potential energy, the rope's, the winch's supply), the rope's mass off the
/// drum is `ρA` times its length throughout, and back at payout 0 the drum element is the
/// one it started from.
#[test]
fn drum_on_a_free_turning_body_keeps_an_exact_balance() {
    let cp = free_body_run(None);
    assert!(cp.payout.abs() < 1e-12);
}

/// As [`drum_on_a_free_turning_body_keeps_an_exact_balance`] with a drum of its own on the
/// body (300 kg at the rope, a motor pulling 4 kN against the hook's 4.9 kN, damping
/// 2 kN·s/m, a 1 kN brake slipping at 2 cm/s): its payout a slot of the step, coupled with the
/// turning body's, every step's balance still holds to 1e-12 of the energy scale, with the
/// drum's kinetic energy in `Ĥ` and its damping and brake dissipating.
#[test]
fn drum_with_dynamics_on_a_free_turning_body_keeps_an_exact_balance() {
    let drum = WinchDrum {
        inertia: 300.0,
        force: Arc::new(|_| 4.0e3),
        damping: 2.0e3,
        brake: Some((1.0e3, 0.02)),
    };
    let cp = free_body_run(Some(drum));
    assert!(
        cp.dissipated > 0.0,
        "the drum dissipated {} J",
        cp.dissipated
    );
}

/// The free block of [`drum_on_a_free_turning_body_keeps_an_exact_balance`] with its winch
/// driven by the payout or by `dynamics`, 8 s at 5 ms: asserts every step's balance, the mass
/// off the drum and at least 2 cuts; returns the winch's state at the end.
fn free_body_run(dynamics: Option<WinchDrum>) -> phstring::WinchState {
    let mut b = NetworkBuilder::<3, Material>::new();
    let m_body = 2000.0;
    let start = BodyState::new(
        Vector3::new(0.3, 0.0, -10.6),
        Vector3::new(0.2, -0.1, 0.0),
        UnitQuaternion::from_euler_angles(0.05, -0.03, 0.2),
        Vector3::new(0.1, -0.05, 0.3),
    );
    let top_s = Vector3::new(0.0, 0.0, 0.5);
    let drum_s = Vector3::new(0.6, 0.0, -0.5);
    let (top, drum) = (start.point(&top_s), start.point(&drum_s));
    let v_of = |s: &Vector3<f64>| {
        let arm = start.orientation.transform_vector(s);
        start.velocity + start.omega_space().cross(&arm)
    };
    let fix = b.node(Vector::<3>::zeros());
    let top_n = b.node(Vector::<3>::new(top.x, top.y, top.z));
    let drum_n = b.node(Vector::<3>::new(drum.x, drum.y, drum.z));
    let hook = b.node(Vector::<3>::new(drum.x, drum.y, drum.z - 15.0));
    let rope = |name: &str| StringSpec {
        name: name.into(),
        material: Material::tension_only_linear(EA),
        rho_a: RHO_A,
        mass: MassMatrix::Consistent,
        body_force: Vector::<3>::new(0.0, 0.0, -RHO_A * G),
        prestretch: 1.0,
    };
    b.string(rope("hanger"), &[fix, top_n], 10).unwrap();
    let reserve = 5;
    let g = b
        .string_on_drum(rope("fall"), &[drum_n, hook], 15, reserve)
        .unwrap();
    let nodes = b.group_nodes(g).unwrap().to_vec();
    let m_hook = 500.0;
    let masses = vec![PointMass {
        node: hook,
        mass: m_hook,
        weight: Vector::<3>::new(0.0, 0.0, -m_hook * G),
    }];
    let boundary = Boundary {
        fixed: vec![phstring::Fixed::node(fix)],
        ..Default::default()
    };
    let mut net = b.build(boundary, masses).unwrap();
    // The hanger from the fixed point to the body's top, the fall hanging below the drum,
    // each stretched 0.1 %, at rest but for the nodes that move with the body.
    let mut r = net.initial.r.clone();
    for (j, &i) in nodes[reserve..].iter().enumerate() {
        r[i] = Vector::<3>::new(drum.x, drum.y, drum.z - 1.001 * j as f64 * L);
    }
    net.initial = State::at_rest(&net.mesh, r);
    let vt = v_of(&top_s);
    let vd = v_of(&drum_s);
    net.initial.v[top_n] = Vector::<3>::new(vt.x, vt.y, vt.z);
    for &i in &nodes[..=reserve] {
        net.initial.v[i] = Vector::<3>::new(vd.x, vd.y, vd.z);
    }
    let net = net
        .with_body(RigidBody {
            name: "block".into(),
            mass: m_body,
            inertia: nalgebra::Matrix3::from_diagonal(&Vector3::new(300.0, 420.0, 250.0)),
            weight: Vector::<3>::new(0.0, 0.0, -m_body * G),
            attachments: vec![
                Attachment {
                    node: top_n,
                    point: Vector::<3>::new(top_s.x, top_s.y, top_s.z),
                },
                Attachment {
                    node: drum_n,
                    point: Vector::<3>::new(drum_s.x, drum_s.y, drum_s.z),
                },
            ],
            initial: start,
            wrench: None,
            hydro: None,
            motion: None,
            feedback: None,
        })
        .with_winch(Winch {
            name: "winch".into(),
            group: g,
            reserve,
            payout: Arc::new(out_and_in),
            drum_motion: None,
            drum: dynamics,
        });
    let mut sim = Simulation::new(net, fixed_step(0.005)).unwrap();
    let drum0 = sim.checkpoint().winches[0].drum;
    let (mut worst, mut mass_off, mut cuts) = (0.0f64, 0.0f64, 0);
    let mut last = drum0;
    for _ in 0..1600 {
        let rep = sim.step().unwrap();
        worst = worst.max(rep.balance_error.abs() / rep.energy_scale);
        let s = &sim.winch_samples()[0];
        mass_off = mass_off.max((s.mass - RHO_A * s.length).abs() / (RHO_A * s.length));
        let d = sim.checkpoint().winches[0].drum;
        cuts += usize::from(d != last);
        last = d;
    }
    let cp = sim.checkpoint();
    eprintln!(
        "free body: {cuts} cuts, balance {worst:.2e}, mass off {mass_off:.1e}, payout at the end {:.2e} m, drum element {} (start {drum0}), body turned {:.3} rad",
        cp.winches[0].payout,
        cp.winches[0].drum,
        sim.state().bodies[0]
            .orientation
            .angle_to(&start.orientation)
    );
    assert!(cuts >= 2, "{cuts} cuts");
    assert!(worst < 1e-12, "balance error {worst:e} of the energy scale");
    assert!(
        mass_off < 1e-12,
        "mass off the drum off ρA × length by {mass_off:e}"
    );
    if cp.winches[0].payout.abs() < 1e-12 {
        assert_eq!(cp.winches[0].drum, drum0);
    }
    cp.winches[0]
}
