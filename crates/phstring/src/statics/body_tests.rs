//! The static equations with rigid bodies: their tangent against central differences (2D and
//! 3D; bodies on supports, a body hanging from another by direct and meshed strings, a wrench
//! port, the load factor and the pseudo-transient shift), and the refusals.

use nalgebra::{UnitQuaternion, Vector3};

use super::*;
use crate::body::{Attachment, BodyHydro, BodyWrench, RigidBody};
use crate::network::{NetworkBuilder, StringSpec};
use crate::system::MassMatrix;
use crate::water::{Current, Water};
use crate::{Boundary, Material};

const G: f64 = 9.81;

/// A steel wire rope (EA = 1e8 N, 1.6 kg/m) in gravity along the last axis, pre-stretched.
fn rope<const D: usize>(name: &str) -> StringSpec<D, Material> {
    StringSpec {
        name: name.into(),
        material: Material::linear_elastic(1e8),
        rho_a: 1.6,
        mass: MassMatrix::Consistent,
        body_force: Vector::<D>::from_fn(|k, _| if k == D - 1 { -1.6 * G } else { 0.0 }),
        prestretch: 1.001,
    }
}

/// A box of `mass` [kg] and sides `a × b × c` [m]: its inertia in body axes.
fn box_inertia(mass: f64, (a, b, c): (f64, f64, f64)) -> nalgebra::Matrix3<f64> {
    nalgebra::Matrix3::from_diagonal(&Vector3::new(
        mass * (b * b + c * c) / 12.0,
        mass * (a * a + c * c) / 12.0,
        mass * (a * a + b * b) / 12.0,
    ))
}

fn vd<const D: usize>(v: &Vector3<f64>) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| v[k])
}

/// Body A (2 t) hangs from supports by 2-element ropes; body B (500 kg) hangs from A by
/// one-element ropes (body to body) and a 2-element rope; A carries a wrench port. Both
/// start turned. 3D: three ropes each; 2D: two each. `wet`: in sea water with a current that
/// grows with height (0.2 to 1.1 m/s from 8 m below B to 2 m above A, along x and y), A
/// with all water terms (1.2 m³ with its centre of buoyancy off the centre, drag, a 3 m²
/// waterplane at a point off its axes), B with buoyancy and drag only.
fn two_bodies<const D: usize>(wet: bool) -> (PhSystem<D, Material>, State<D>) {
    let turn = |a: f64, b: f64, c: f64| {
        if D == 3 {
            UnitQuaternion::from_euler_angles(a, b, c)
        } else {
            UnitQuaternion::from_euler_angles(0.0, 0.0, c)
        }
    };
    let plane = |v: Vector3<f64>| {
        if D == 2 {
            Vector3::new(v.x, v.z, 0.0)
        } else {
            v
        }
    };
    let xa = Vector3::zeros();
    let xb = plane(Vector3::new(0.5, 0.2, -4.0));
    let (qa, qb) = (turn(0.1, -0.2, 0.3), turn(-0.2, 0.1, 0.4));
    let n = if D == 3 { 3 } else { 2 };
    let top: Vec<Vector3<f64>> = [
        Vector3::new(0.8, 0.4, 0.25),
        Vector3::new(-0.8, 0.4, 0.25),
        Vector3::new(0.0, -0.4, 0.25),
    ]
    .into_iter()
    .map(plane)
    .take(n)
    .collect();
    let below: Vec<Vector3<f64>> = top
        .iter()
        .map(|s| plane(Vector3::new(s.x, 0.0, -s.z)))
        .collect();
    let on_b: Vec<Vector3<f64>> = top.iter().map(|s| s * 0.4).collect();
    let mut nb = NetworkBuilder::<D, Material>::new();
    let (mut att_a, mut att_b, mut held) = (Vec::new(), Vec::new(), Boundary::default());
    for (k, s) in top.iter().enumerate() {
        let p = qa * s + xa;
        let sup = nb.node(vd(&(p + plane(Vector3::new(0.5 * s.x, 0.3, 6.0)))));
        let a = nb.node(vd(&p));
        held.fixed.push(crate::Fixed::node(sup));
        nb.string(rope(&format!("up{k}")), &[sup, a], 2).unwrap();
        att_a.push(Attachment {
            node: a,
            point: vd(s),
        });
    }
    for (k, (s, t)) in below.iter().zip(&on_b).enumerate() {
        let a = nb.node(vd(&(qa * s + xa)));
        let b = nb.node(vd(&(qb * t + xb)));
        nb.string(rope(&format!("down{k}")), &[a, b], 1 + k % 2)
            .unwrap();
        att_a.push(Attachment {
            node: a,
            point: vd(s),
        });
        att_b.push(Attachment {
            node: b,
            point: vd(t),
        });
    }
    let net = nb.build(held, Vec::new()).unwrap();
    let wrench = BodyWrench {
        force: std::sync::Arc::new(|_| Vector3::new(300.0, -200.0, 150.0)),
        torque: std::sync::Arc::new(|_| Vector3::new(-400.0, 250.0, 500.0)),
    };
    let body = |name: &str, m: f64, x, q, atts, wrench| RigidBody {
        name: name.into(),
        mass: m,
        inertia: box_inertia(m, (2.0, 1.0, 0.5)),
        weight: Vector::<D>::from_fn(|k, _| if k == D - 1 { -m * G } else { 0.0 }),
        attachments: atts,
        initial: BodyState::at_rest(x, q),
        wrench,
        hydro: None,
        motion: None,
        feedback: None,
    };
    let (mut a, mut b) = (
        body("a", 2000.0, xa, qa, att_a, Some(wrench)),
        body("b", 500.0, xb, qb, att_b, None),
    );
    let mut net = net;
    if wet {
        let v = |x: f64, y: f64| Vector::<D>::from_fn(|k, _| [x, y, 0.0][k]);
        let profile = Current::Profile(vec![(-12.0, v(0.2, -0.1)), (2.0, v(1.1, 0.4))]);
        net = net.with_water(Water::new(1025.0).with_current(profile));
        a.hydro = Some(BodyHydro {
            volume: 1.2,
            centre_of_buoyancy: plane(Vector3::new(0.1, -0.05, 0.3)),
            cda: 1.5,
            linear_drag: 200.0,
            ca: 0.5,
            added_inertia: Vector3::new(30.0, 40.0, 50.0),
            added_mass: None,
            waterplane_area: 3.0,
            waterline: plane(Vector3::new(0.2, 0.1, 0.25)),
            waterplane_moments: [0.9, 1.4],
        });
        b.hydro = Some(BodyHydro {
            volume: 0.2,
            cda: 0.6,
            ..Default::default()
        });
    }
    PhSystem::new(net.with_body(a).with_body(b)).unwrap()
}

/// A deterministic spread of values in `[-1, 1]`.
fn spread(i: usize) -> f64 {
    ((i as f64 + 1.0) * 0.754_877_666).fract() * 2.0 - 1.0
}

/// The Jacobian of the static equations with bodies against central differences at a point
/// off the equilibrium (nodes moved up to 2 cm, bodies up to 5 cm and 0.1 rad), at load
/// factor 0.7 with a pseudo-transient shift towards another point, the reference poses moved
/// off the start first (rebasing keeps the positions to 1e-14 m): every column of a free
/// component or slot, on the rows of the free components and slots, to 1e-6 of the
/// column's size (measured: 5.3e-9 in 3D over 24 columns, 6.1e-10 in 2D over 12; without
/// the arm's turn in the moment's tangent, 1.4 and 1.5e-2).
fn jacobian_matches_finite_differences<const D: usize>(wet: bool) {
    let (sys, init) = two_bodies::<D>(wet);
    let f = static_load(&sys);
    let mut eq = StaticEquations::new(&sys, &init.r, &f, &init.bodies);
    eq.lambda = 0.7;
    eq.mu = 50.0;
    let n = sys.mesh.n_nodes();
    let m = eq.unknowns();
    let placeholder = |i: usize| D == 2 && i >= n && (i - n) % 2 == 1;
    let point = |scale_nodes: f64, seed: usize| -> Vec<Vector<D>> {
        (0..m)
            .map(|i| {
                let s = if i < n {
                    scale_nodes
                } else if (i - n) % 2 == 0 {
                    0.05
                } else {
                    0.1
                };
                let v = Vector::<D>::from_fn(|k, _| s * spread(seed + D * i + k));
                if placeholder(i) {
                    Vector::<D>::from_fn(|k, _| if k == 0 { v[0] } else { 0.0 })
                } else {
                    v
                }
            })
            .collect()
    };
    // Reference poses moved off the start (as the pseudo-transient steps move them): the
    // positions stay, and the tangent is taken about the new poses with their offsets.
    let mut first = point(0.03, 11);
    let before = eq.positions(&first);
    eq.rebase(&mut first);
    let after = eq.positions(&first);
    let shifted = before
        .iter()
        .zip(&after)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(
        shifted < 1e-14,
        "{D}D: rebasing moved a node by {shifted:e} m"
    );
    assert!(first[n..].iter().all(|v| v.norm() == 0.0));
    let anchor = point(0.01, 7);
    eq.set_anchor(&anchor);
    let x = point(0.02, 0);
    let mut res = vec![Vector::<D>::zeros(); m];
    let mut jac = BlockJacobian::with_slots(&sys.mesh, 2 * sys.bodies.len());
    eq.evaluate(&x, &mut res, Some(&mut jac)).unwrap();
    let active = |i: usize, k: usize| {
        if i < n {
            sys.free[i][k]
        } else {
            !(placeholder(i) && k == 1)
        }
    };
    let eps = 1e-6;
    let (mut worst, mut columns) = (0.0f64, 0);
    for i in 0..m {
        for k in (0..D).filter(|&k| active(i, k)) {
            let mut e = vec![Vector::<D>::zeros(); m];
            e[i][k] = 1.0;
            let mut col = vec![Vector::<D>::zeros(); m];
            jac.mul(&sys.mesh, &e, &mut col);
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[i][k] += eps;
            xm[i][k] -= eps;
            let (mut rp, mut rm) = (res.clone(), res.clone());
            eq.evaluate(&xp, &mut rp, None).unwrap();
            eq.evaluate(&xm, &mut rm, None).unwrap();
            let (mut err, mut size) = (0.0f64, 0.0f64);
            for r in 0..m {
                for c in (0..D).filter(|&c| active(r, c)) {
                    let fd = (rp[r][c] - rm[r][c]) / (2.0 * eps);
                    err = err.max((fd - col[r][c]).abs());
                    size = size.max(fd.abs());
                }
            }
            worst = worst.max(err / size.max(1.0));
            columns += 1;
        }
    }
    // Central differences: truncation ~ eps² W''' and rounding ~ ε |R| / eps ≈ 1e-5 N/m
    // against columns of 1e6–1e8 N/m.
    assert!(
        worst < 1e-6,
        "{D}D: worst column error {worst:e} of the column's size"
    );
    // Both bodies' slots (6 or 3 components each) and some free nodes.
    let per_body = if D == 3 { 6 } else { 3 };
    assert!(
        columns > per_body * sys.bodies.len(),
        "{D}D: only {columns} columns checked"
    );
}

#[test]
fn body_statics_jacobian_matches_finite_differences_3d() {
    jacobian_matches_finite_differences::<3>(false);
}

#[test]
fn body_statics_jacobian_matches_finite_differences_2d() {
    jacobian_matches_finite_differences::<2>(false);
}

/// The same with the water on the bodies: buoyancy at an off-centre centre of buoyancy, a
/// waterplane at a point off the axes (its stiffness is not scaled by the load factor) and
/// the drag in a current that changes with height (its derivative by the height), to the
/// same 1e-6 of the column's size.
#[test]
fn body_statics_jacobian_in_water_matches_finite_differences() {
    jacobian_matches_finite_differences::<3>(true);
    jacobian_matches_finite_differences::<2>(true);
}

/// A body fixed to no node is refused by name.
#[test]
fn loose_body_is_refused_by_name() {
    let mut nb = NetworkBuilder::<3, Material>::new();
    let a = nb.node(Vector::<3>::zeros());
    let b = nb.node(Vector::<3>::new(0.0, 0.0, -5.0));
    nb.string(rope("r"), &[a, b], 2).unwrap();
    let mut held = Boundary::default();
    held.fixed.push(crate::Fixed::node(a));
    let net = nb.build(held, Vec::new()).unwrap();
    let net = net.with_body(RigidBody {
        name: "drifter".into(),
        mass: 100.0,
        inertia: box_inertia(100.0, (1.0, 1.0, 1.0)),
        weight: Vector::<3>::new(0.0, 0.0, -100.0 * G),
        attachments: vec![],
        initial: BodyState::at_rest(Vector3::new(3.0, 0.0, 0.0), UnitQuaternion::identity()),
        wrench: None,
        hydro: None,
        motion: None,
        feedback: None,
    });
    let (sys, init) = PhSystem::new(net).unwrap();
    let err = solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap_err();
    assert_eq!(
        err,
        StaticsError::LooseBody {
            index: 0,
            name: "drifter".into()
        }
    );
    assert!(err.to_string().contains("'drifter'"), "{err}");
}

/// A body hanging from strings that end at no support is free to fall: refused along the
/// vertical with the net load (body and rope weights): a node fixed to a body holds nothing.
#[test]
fn body_on_free_strings_is_under_constrained() {
    let mut nb = NetworkBuilder::<3, Material>::new();
    let a = nb.node(Vector::<3>::new(0.0, 0.0, 0.25));
    let b = nb.node(Vector::<3>::new(0.0, 0.0, 5.25));
    nb.string(rope("r"), &[a, b], 2).unwrap();
    let net = nb.build(Boundary::default(), Vec::new()).unwrap();
    let net = net.with_body(RigidBody {
        name: "falling".into(),
        mass: 100.0,
        inertia: box_inertia(100.0, (1.0, 1.0, 0.5)),
        weight: Vector::<3>::new(0.0, 0.0, -100.0 * G),
        attachments: vec![Attachment {
            node: a,
            point: Vector::<3>::new(0.0, 0.0, 0.25),
        }],
        initial: BodyState::at_rest(Vector3::zeros(), UnitQuaternion::identity()),
        wrench: None,
        hydro: None,
        motion: None,
        feedback: None,
    });
    let (sys, init) = PhSystem::new(net).unwrap();
    let err = solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap_err();
    let StaticsError::UnderConstrained { axis, net } = err else {
        panic!("expected under-constrained, got {err}");
    };
    // x and y carry no load; along z the body's 100 kg and the rope's 1.6 kg/m over its
    // reference length 5 m / 1.001.
    assert_eq!(axis, "z");
    let weight = -(100.0 + 1.6 * 5.0 / 1.001) * G;
    assert!(
        (net / weight - 1.0).abs() < 1e-12,
        "net load {net} N against {weight} N"
    );
}

/// A start pose out of the plane of a 2D network is refused by the body's name.
#[test]
fn start_pose_out_of_the_plane_is_refused() {
    let (sys, init) = two_bodies::<2>(false);
    let mut start = init.clone();
    start.bodies[1].orientation = UnitQuaternion::from_euler_angles(0.1, 0.0, 0.4);
    let err = solve_from(&sys, &start, &StaticsParams::default(), None).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("rigid body 1 ('b')") && msg.contains("plane"),
        "{msg}"
    );
}

/// A hook block (500 kg) on a single rope in 3D: its spin about the line through its point
/// and its centre is held by nothing, so the statics refuse it by name with that line; a
/// block whose two points lie on a line through its centre likewise; in 2D a single point
/// off the centre is a pendulum and is not refused.
#[test]
fn free_spin_about_the_attachment_line_is_refused() {
    let hook = |points: &[Vector3<f64>]| {
        let mut nb = NetworkBuilder::<3, Material>::new();
        let q = UnitQuaternion::from_euler_angles(0.2, -0.1, 0.3);
        let x = Vector3::new(0.5, 0.2, -5.0);
        let mut held = Boundary::default();
        let mut attachments = Vec::new();
        for (k, s) in points.iter().enumerate() {
            let a = nb.node(Vector::<3>::new(k as f64, 0.0, 0.0));
            let b = nb.node(vd(&(x + q * s)));
            nb.string(rope("r"), &[a, b], 4).unwrap();
            held.fixed.push(crate::Fixed::node(a));
            attachments.push(Attachment {
                node: b,
                point: vd(s),
            });
        }
        let net = nb.build(held, Vec::new()).unwrap();
        let net = net.with_body(RigidBody {
            name: "hook".into(),
            mass: 500.0,
            inertia: box_inertia(500.0, (0.6, 0.4, 0.8)),
            weight: Vector::<3>::new(0.0, 0.0, -500.0 * G),
            attachments,
            initial: BodyState::at_rest(x, q),
            wrench: None,
            hydro: None,
            motion: None,
            feedback: None,
        });
        let (sys, init) = PhSystem::new(net).unwrap();
        solve_system(&sys, &init.r, &StaticsParams::default(), None)
    };
    let s = Vector3::new(0.1, 0.0, 0.4);
    let err = hook(&[s]).unwrap_err();
    let StaticsError::FreeSpin {
        index,
        ref name,
        axis,
    } = err
    else {
        panic!("expected a free spin, got {err}");
    };
    assert_eq!((index, name.as_str()), (0, "hook"));
    assert!(
        (Vector3::from(axis) - s.normalize()).norm() < 1e-15,
        "axis {axis:?}"
    );
    assert!(err.to_string().contains("'hook'"), "{err}");
    let err = hook(&[s, -s * 2.0]).unwrap_err();
    assert!(matches!(err, StaticsError::FreeSpin { .. }), "{err}");
    // Two points off a line through the centre hold every turn.
    let held = hook(&[s, Vector3::new(-0.1, 0.2, 0.4)]).unwrap();
    assert!(held.stable);
}

/// A 2D buoy (2 t, 2.5 m³) pulled down at its centre of mass by one rope to an anchor 20 m
/// below and 5 m aside: no string holds its turn, its centre of buoyancy 0.5 m above the
/// centre does. The statics take it (not a free spin) and find it upright, its net uplift
/// `(ρ_w V − m) g` along the rope.
#[test]
fn a_centre_of_buoyancy_off_the_centre_holds_a_buoys_turn() {
    let mut nb = NetworkBuilder::<2, Material>::new();
    let anchor = nb.node(Vector::<2>::new(-5.0, -20.0));
    let fair = nb.node(Vector::<2>::new(0.0, 0.0));
    nb.string(rope::<2>("rope"), &[anchor, fair], 4).unwrap();
    let mut held = Boundary::default();
    held.fixed.push(crate::Fixed::node(anchor));
    let (mass, volume) = (2000.0, 2.5);
    let hydro = |cob: Vector3<f64>| BodyHydro {
        volume,
        centre_of_buoyancy: cob,
        ..Default::default()
    };
    let solve = |cob: Vector3<f64>| {
        let net = nb
            .clone()
            .build(held.clone(), Vec::new())
            .unwrap()
            .with_water(Water::<2>::new(1025.0).with_gravity(G))
            .with_body(RigidBody {
                name: "buoy".into(),
                mass,
                inertia: box_inertia(mass, (1.5, 1.5, 1.5)),
                weight: Vector::<2>::new(0.0, -mass * G),
                attachments: vec![Attachment {
                    node: fair,
                    point: Vector::<2>::zeros(),
                }],
                initial: BodyState::at_rest(Vector3::zeros(), UnitQuaternion::identity()),
                wrench: None,
                hydro: Some(hydro(cob)),
                motion: None,
                feedback: None,
            });
        let (sys, init) = PhSystem::new(net).unwrap();
        solve_system(&sys, &init.r, &StaticsParams::default(), None)
    };
    let err = solve(Vector3::zeros()).unwrap_err();
    assert!(matches!(err, StaticsError::FreeSpin { .. }), "{err}");
    let eq = solve(Vector3::new(0.0, 0.5, 0.0)).unwrap();
    assert!(eq.stable);
    let pose = &eq.state.bodies[0];
    // The buoyancy's moment about the centre vanishes only when the buoy is upright.
    assert!(
        pose.orientation.angle() < 1e-9,
        "turned by {}",
        pose.orientation.angle()
    );
    let uplift = (1025.0 * volume - mass) * G;
    let pull = eq.reactions[fair];
    assert!(
        (pull.norm() - uplift).abs() < 1e-6 * uplift,
        "{pull} vs {uplift}"
    );
    let along = eq.state.r[fair] - eq.state.r[anchor];
    assert!(
        pull.normalize().perp(&along.normalize()).abs() < 1e-6,
        "{pull} along {along}"
    );
}
