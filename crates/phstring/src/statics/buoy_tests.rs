//! The statics of rigid bodies in water and with a prescribed motion: a moored buoy's draft
//! against the balance of its buoyancy, its weight and the elastic catenaries of its chains,
//! and a body that a prescribed motion holds at its pose at `t = 0`.

use std::f64::consts::PI;
use std::sync::Arc;

use nalgebra::{UnitQuaternion, Vector3};

use super::*;
use crate::body::{Attachment, BodyHydro, BodyMotion, RigidBody};
use crate::catenary::{Catenary, Line};
use crate::network::{NetworkBuilder, StringSpec};
use crate::system::MassMatrix;
use crate::water::{LineHydro, Water};
use crate::{Boundary, Material, Simulation, StepParams};

const G: f64 = 9.81;
const RHO_W: f64 = 1025.0;

/// A studless chain (EA = 6e8 N, 115 kg/m, volume-equivalent diameter 0.137 m) of unstretched
/// length `l` [m] spanning the chord `chord` [m] (straight, so `prestretch = chord / l`).
fn chain(name: &str, l: f64, chord: f64) -> StringSpec<2, Material> {
    StringSpec {
        name: name.into(),
        material: Material::linear_elastic(6e8),
        rho_a: 115.0,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -115.0 * G),
        prestretch: chord / l,
    }
}

/// The chain's wet weight per unstretched metre [N/m].
fn wet_weight() -> f64 {
    (115.0 - RHO_W * PI * 0.137 * 0.137 / 4.0) * G
}

/// The buoy of [`moored_buoy_floats_at_the_draft_of_its_buoyancy_and_chains`]: the system
/// and its chains' anchors (nodes).
fn moored_buoy(
    depth: f64,
    span: f64,
    l: f64,
    n: usize,
) -> (PhSystem<2, Material>, State<2>, [usize; 2]) {
    let z0 = -2.0;
    let points = [Vector3::new(-1.5, -2.0, 0.0), Vector3::new(1.5, -2.0, 0.0)];
    let mut nb = NetworkBuilder::<2, Material>::new();
    let mut held = Boundary::default();
    let (mut anchors, mut attachments) = ([0; 2], Vec::new());
    for (k, s) in points.iter().enumerate() {
        let side = if k == 0 { -1.0 } else { 1.0 };
        let anchor = Vector::<2>::new(side * span, -depth);
        let fairlead = Vector::<2>::new(s.x, z0 + s.y);
        let a = nb.node(anchor);
        let f = nb.node(fairlead);
        held.fixed.push(crate::Fixed::node(a));
        nb.string(
            chain(&format!("chain{k}"), l, (fairlead - anchor).norm()),
            &[a, f],
            n,
        )
        .unwrap();
        anchors[k] = a;
        attachments.push(Attachment {
            node: f,
            point: Vector::<2>::new(s.x, s.y),
        });
    }
    let hydro = LineHydro {
        diameter: 0.137,
        cd: 2.4,
        ..Default::default()
    };
    let net = nb
        .build(held, Vec::new())
        .unwrap()
        .with_water(Water::new(RHO_W).with_gravity(G))
        .with_line_hydro(0, hydro)
        .with_line_hydro(1, hydro)
        .with_body(RigidBody {
            name: "buoy".into(),
            mass: 1e4,
            inertia: nalgebra::Matrix3::from_diagonal(&Vector3::new(4e4, 4e4, 3e4)),
            weight: Vector::<2>::new(0.0, -1e4 * G),
            attachments,
            initial: BodyState::at_rest(Vector3::new(0.0, z0, 0.0), UnitQuaternion::identity()),
            wrench: None,
            hydro: Some(BodyHydro {
                volume: 80.0,
                centre_of_buoyancy: Vector3::new(0.0, 0.5, 0.0),
                cda: 8.0,
                ca: 0.8,
                waterplane_area: 20.0,
                waterline: Vector3::new(0.0, 2.0, 0.0),
                ..Default::default()
            }),
            motion: None,
            feedback: None,
        });
    let (sys, init) = PhSystem::new(net).unwrap();
    (sys, init, anchors)
}

/// A 10 t buoy (80 m³ with its waterline point at the surface, a 20 m² waterplane, the
/// waterline point 2 m above its centre of mass) moored in 150 m of water by two 340 m
/// studless chains (EA = 6e8 N, 115 kg/m, 980 N/m wet) from anchors 300 m to either side, to
/// points 1.5 m off its axis and 2 m below its centre. Its heave `z` [m] (of the centre of
/// mass) balances the buoyancy less the waterplane's `ρ_w g A_w z_w` against its weight and
/// the chains' vertical pull at the fairleads, each from the elastic catenary
/// (`crate::catenary`) between its anchor and its fairlead at `(298.5, z − 2 + 150)` m:
///
/// `ρ_w g (V − A_w (z + 2)) = m g + 2 (V_A + w L)`,
///
/// solved here by bisection (z = −1.94268 m: the waterline point 0.057 m above the surface,
/// V_F = 347.4 kN per chain). The statics find it to 1e-4 m (measured 2.8e-5 m: the chains'
/// 2 m elements), the anchors' horizontal tension to 1e-4 of the closed form's (measured
/// 1.6e-5), the buoy level (by symmetry) and stable; a run from the equilibrium (h = 0.05 s,
/// 100 steps) leaves the buoy within 1e-6 m of it (measured 1.0e-9 m), so the statics' water
/// terms are those of the time step.
#[test]
fn moored_buoy_floats_at_the_draft_of_its_buoyancy_and_chains() {
    let (depth, span, l, n) = (150.0, 300.0, 340.0, 170);
    let (sys, init, anchors) = moored_buoy(depth, span, l, n);
    let line = Line {
        length: l,
        weight: wet_weight(),
        ea: 6e8,
    };
    let pull = |z: f64| Catenary::between(line, span - 1.5, z - 2.0 + depth).unwrap();
    let balance = |z: f64| {
        RHO_W * G * (80.0 - 20.0 * (z + 2.0)) - 1e4 * G - 2.0 * (pull(z).v_a + line.weight * l)
    };
    let (mut lo, mut hi) = (-4.0, 2.0);
    assert!(
        balance(lo) > 0.0 && balance(hi) < 0.0,
        "{} {}",
        balance(lo),
        balance(hi)
    );
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if balance(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let z = 0.5 * (lo + hi);
    let cat = pull(z);
    let eq = solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
    let buoy = eq.state.bodies[0];
    println!(
        "buoy at z = {} m (closed form {z} m), H = {} N (closed form {} N), V_F = {} N, turned {} rad",
        buoy.position.y,
        eq.reactions[anchors[1]].x.abs(),
        cat.h,
        cat.v_a + line.weight * l,
        buoy.orientation.angle()
    );
    println!(
        "anchor reactions {:?} {:?}, closed form V_A {} N at z, {} N at the buoy's z; wet weight {} N/m",
        eq.reactions[anchors[0]],
        eq.reactions[anchors[1]],
        cat.v_a,
        pull(buoy.position.y).v_a,
        line.weight
    );
    assert!(
        (buoy.position.y - z).abs() < 1e-4,
        "z {} vs {z}",
        buoy.position.y
    );
    assert!(buoy.position.x.abs() < 1e-9, "x = {}", buoy.position.x);
    assert!(buoy.orientation.angle() < 1e-12);
    for &a in &anchors {
        let h = eq.reactions[a].x.abs();
        assert!((h - cat.h).abs() < 1e-4 * cat.h, "H {h} vs {}", cat.h);
    }
    assert!(eq.stable);
    let params = StepParams {
        h: 0.05,
        ..Default::default()
    };
    let mut sim = Simulation::from_system(sys, eq.state.clone(), params).unwrap();
    let mut moved = 0.0f64;
    for _ in 0..100 {
        sim.step().unwrap();
        moved = moved.max((sim.state().bodies[0].position - buoy.position).norm());
    }
    println!("moved {moved:e} m in 5 s from the equilibrium");
    assert!(moved < 1e-6, "moved {moved:e} m");
}

/// A vessel held by a prescribed motion (heaving `2 (1 − cos 0.5t)` m and pitching
/// `0.05 (1 − cos 0.5t)` rad: at rest, level and at the origin at `t = 0`) with a 30 m wire rope
/// (EA = 1e8 N, 8 kg/m) from a point 10 m off its centre down to a 2 t clump at its end: the
/// statics hold the vessel at its pose at `t = 0` (to round-off) and the rope hangs plumb
/// from the point, whose reaction (the force the vessel exerts on it, upwards) is the
/// hanging weight `(2000 + 8 · 30) g` to 1e-9. The
/// vessel's own weight (5e6 kg) is not a load: the motion carries it.
#[test]
fn a_prescribed_body_is_held_at_its_pose_at_t_zero() {
    let mut nb = NetworkBuilder::<3, Material>::new();
    let s = Vector3::new(10.0, 0.0, -2.0);
    let top = nb.node(Vector::<3>::new(10.0, 0.0, -2.0));
    let clump = nb.node(Vector::<3>::new(10.0, 0.0, -32.0));
    let rope = StringSpec {
        name: "rope".into(),
        material: Material::linear_elastic(1e8),
        rho_a: 8.0,
        mass: MassMatrix::Consistent,
        body_force: Vector::<3>::new(0.0, 0.0, -8.0 * G),
        prestretch: 1.0,
    };
    nb.string(rope, &[top, clump], 10).unwrap();
    let net = nb
        .build(
            Boundary::default(),
            vec![crate::PointMass {
                node: clump,
                mass: 2000.0,
                weight: Vector::<3>::new(0.0, 0.0, -2000.0 * G),
            }],
        )
        .unwrap();
    let motion = BodyMotion {
        pose: Arc::new(|t: f64| {
            let c = 1.0 - (0.5 * t).cos();
            let x = Vector3::new(0.0, 0.0, 2.0 * c);
            (x, UnitQuaternion::from_euler_angles(0.0, 0.05 * c, 0.0))
        }),
        twist: Arc::new(|t: f64| {
            let s = 0.5 * (0.5 * t).sin();
            (
                Vector3::new(0.0, 0.0, 2.0 * s),
                Vector3::new(0.0, 0.05 * s, 0.0),
            )
        }),
    };
    let initial = BodyState::at_rest(Vector3::zeros(), UnitQuaternion::identity());
    let net = net.with_body(RigidBody {
        name: "vessel".into(),
        mass: 5e6,
        inertia: nalgebra::Matrix3::from_diagonal(&Vector3::new(4e8, 4e9, 4e9)),
        weight: Vector::<3>::new(0.0, 0.0, -5e6 * G),
        attachments: vec![Attachment {
            node: top,
            point: Vector::<3>::new(s.x, s.y, s.z),
        }],
        initial,
        wrench: None,
        hydro: None,
        motion: Some(motion),
        feedback: None,
    });
    let (sys, mut init) = PhSystem::new(net).unwrap();
    // Start the rope's other nodes off the plumb line: the statics must bring them back.
    for (i, r) in init.r.iter_mut().enumerate() {
        if i != top {
            r.x += 0.5;
        }
    }
    let eq = solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
    let vessel = eq.state.bodies[0];
    assert_eq!(vessel.position, Vector3::zeros());
    assert!(vessel.orientation.angle() < 1e-15);
    let hanging = (2000.0 + 8.0 * 30.0) * G;
    let reaction = eq.reactions[top];
    println!("reaction at the vessel's point {reaction:?} N, hanging weight {hanging} N");
    assert!(
        (reaction.z - hanging).abs() < 1e-9 * hanging,
        "{reaction:?}"
    );
    assert!(reaction.x.abs() < 1e-9 * hanging && reaction.y.abs() < 1e-9 * hanging);
    assert!((eq.state.r[clump].x - 10.0).abs() < 1e-9);
}
