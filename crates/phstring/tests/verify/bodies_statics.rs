//! Static equilibrium with rigid bodies (docs/method.md, "Statics with rigid bodies"): a box
//! on three ropes (support reactions against the total weight and its moment, independent of
//! the start), a cable robot at rest (tensions against the 6×6 wrench balance of its
//! geometry), a hook block on two slings (the closed form, and the 3×3 balance of an
//! off-centre block), and a run started from the equilibrium.

use std::ops::AddAssign;

use nalgebra::{Matrix2, Matrix3, Matrix6, UnitQuaternion, Vector2, Vector3, Vector6};
use phstring::statics::{self, Equilibrium, StaticsParams, static_load};
use phstring::water::STANDARD_GRAVITY as G;
use phstring::{
    Attachment, BodyState, Boundary, Fixed, MassMatrix, Material, Network, NetworkBuilder,
    PhSystem, RigidBody, Simulation, State, StepParams, StringSpec, Vector,
};

fn v3<const D: usize>(v: &Vector<D>) -> Vector3<f64> {
    Vector3::from_fn(|k, _| if k < D { v[k] } else { 0.0 })
}

fn vd<const D: usize>(v: &Vector3<f64>) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| v[k])
}

/// A box of `mass` [kg] with sides `a × b × c` [m]: its inertia about its centre.
fn box_inertia(mass: f64, (a, b, c): (f64, f64, f64)) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(
        mass * (b * b + c * c) / 12.0,
        mass * (a * a + c * c) / 12.0,
        mass * (a * a + b * b) / 12.0,
    ))
}

/// A rope of the linear elastic law `ea` [N] and `rho_a` [kg/m] in gravity (last axis down),
/// its reference length the built span over `prestretch`.
fn rope<const D: usize>(
    name: &str,
    ea: f64,
    rho_a: f64,
    prestretch: f64,
) -> StringSpec<D, Material> {
    StringSpec {
        name: name.into(),
        material: Material::linear_elastic(ea),
        rho_a,
        mass: MassMatrix::Consistent,
        body_force: Vector::<D>::from_fn(|k, _| if k == D - 1 { -rho_a * G } else { 0.0 }),
        prestretch,
    }
}

/// `supports` [m] held, each joined by a rope of `elements` elements to the body point
/// `points[k]` (body axes) of a body of `mass` [kg] with `inertia`, starting at `pose`.
/// Returns the network and, per rope, its support node and attached node.
#[allow(clippy::too_many_arguments)]
fn hung_body<const D: usize>(
    supports: &[Vector3<f64>],
    points: &[Vector3<f64>],
    (mass, inertia): (f64, Matrix3<f64>),
    pose: &BodyState,
    spec: &StringSpec<D, Material>,
    elements: usize,
) -> (Network<D, Material>, Vec<(usize, usize)>) {
    let mut nb = NetworkBuilder::<D, Material>::new();
    let mut held = Boundary::default();
    let mut ends = Vec::new();
    let mut attachments = Vec::new();
    for (k, (sup, s)) in supports.iter().zip(points).enumerate() {
        let a = nb.node(vd(sup));
        let b = nb.node(vd(&pose.point(s)));
        let spec = StringSpec {
            name: format!("{}{k}", spec.name),
            ..spec.clone()
        };
        nb.string(spec, &[a, b], elements).unwrap();
        held.fixed.push(Fixed::node(a));
        attachments.push(Attachment {
            node: b,
            point: vd(s),
        });
        ends.push((a, b));
    }
    let net = nb.build(held, Vec::new()).unwrap();
    let body = RigidBody {
        name: "body".into(),
        mass,
        inertia,
        weight: Vector::<D>::from_fn(|k, _| if k == D - 1 { -mass * G } else { 0.0 }),
        attachments,
        initial: *pose,
        wrench: None,
        hydro: None,
        motion: None,
        feedback: None,
    };
    (net.with_body(body), ends)
}

/// The tension [N] of the one-element rope between nodes `a` and `b` (linear elastic law
/// `ea` [N]): `EA (λ − 1)` with the stretch `λ` of the equilibrium.
fn tension<const D: usize>(
    sys: &PhSystem<D, Material>,
    eq: &Equilibrium<D>,
    (a, b): (usize, usize),
    ea: f64,
) -> f64 {
    let e = sys
        .mesh()
        .elements()
        .iter()
        .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
        .unwrap();
    let stretch = (eq.state.r[b] - eq.state.r[a]).norm() / sys.mesh().lengths()[e];
    ea * (stretch - 1.0)
}

const BOX_SUPPORTS: [[f64; 3]; 3] = [[-4.0, -3.0, 10.0], [4.0, -3.0, 10.0], [0.0, 5.0, 10.0]];
const BOX_POINTS: [[f64; 3]; 3] = [[-0.8, -0.4, 0.25], [0.8, -0.4, 0.25], [0.0, 0.4, 0.25]];

/// A 2 t box (2 × 1 × 0.5 m) hanging from three steel ropes (EA = 1e8 N, 1.6 kg/m, 10
/// elements, 7.3–8.2 m) to three supports, built straight and stress-free from the box at
/// `(0, 0, 3)`.
fn box_on_three_ropes() -> (PhSystem<3, Material>, State<3>, Vec<(usize, usize)>) {
    let supports: Vec<Vector3<f64>> = BOX_SUPPORTS.iter().map(|s| Vector3::from(*s)).collect();
    let points: Vec<Vector3<f64>> = BOX_POINTS.iter().map(|s| Vector3::from(*s)).collect();
    let pose = BodyState::at_rest(Vector3::new(0.0, 0.0, 3.0), UnitQuaternion::identity());
    let body = (2000.0, box_inertia(2000.0, (2.0, 1.0, 0.5)));
    let spec = rope::<3>("rope", 1e8, 1.6, 1.0);
    let (net, ends) = hung_body(&supports, &points, body, &pose, &spec, 10);
    let (sys, init) = PhSystem::new(net).unwrap();
    (sys, init, ends)
}

/// The sum of the support reactions and the loads [N], and the moment about `x` [m] of the
/// reactions and loads [N·m] (the body's weight acts at `x`): both vanish at an equilibrium.
fn net_wrench(
    sys: &PhSystem<3, Material>,
    eq: &Equilibrium<3>,
    supports: &[usize],
    x: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let f = static_load(sys);
    let weight = Vector3::new(0.0, 0.0, -sys.bodies()[0].1 * G);
    let (mut force, mut moment) = (weight, Vector3::zeros());
    for (i, fi) in f.iter().enumerate() {
        force += v3(fi);
        moment += (v3(&eq.state.r[i]) - x).cross(&v3(fi));
    }
    for &s in supports {
        let r = v3(&eq.reactions[s]);
        force += r;
        moment += (v3(&eq.state.r[s]) - x).cross(&r);
    }
    (force, moment)
}

/// The box on three ropes: the support reactions carry the total weight (box and ropes) to
/// 1e-9 of it and their moment about the centre of mass balances the ropes' weights to 1e-9
/// of the weight times 10 m (measured: 3.5e-13 and 9e-15; the box moves 0.10 m from its
/// start, by the pseudo-transient path); the equilibrium is stable, and a second start (box
/// 0.36 m off and turned by 0.23 rad, ropes straight to its points) ends at the same pose to
/// 1e-9 m and 1e-9 rad (measured: 2.2e-11 m, 1.6e-11 rad) with the same reactions to 1e-9
/// of the weight (measured: 4e-12).
#[test]
fn box_on_three_ropes_reactions_carry_its_weight_from_any_start() {
    let (sys, init, ends) = box_on_three_ropes();
    let params = StaticsParams::default();
    let eq = statics::solve_from(&sys, &init, &params, None).unwrap();
    assert!(eq.stable, "the hanging box is stable");
    let supports: Vec<usize> = ends.iter().map(|e| e.0).collect();
    let body = eq.state.bodies[0];
    let ropes: f64 = sys.mesh().lengths().iter().sum::<f64>() * 1.6 * G;
    let total = 2000.0 * G + ropes;
    let (force, moment) = net_wrench(&sys, &eq, &supports, &body.position);
    assert!(force.norm() < 1e-9 * total, "force balance off by {force}");
    assert!(
        moment.norm() < 1e-9 * total * 10.0,
        "moment balance off by {moment}"
    );
    let lifted: f64 = supports.iter().map(|&s| eq.reactions[s].z).sum();
    assert!(
        (lifted / total - 1.0).abs() < 1e-9,
        "lifted {lifted} N of {total} N"
    );
    // The box moves from its start (the stress-free straight ropes are not at rest).
    let moved = (body.position - Vector3::new(0.0, 0.0, 3.0)).norm();
    assert!(moved > 1e-2, "box moved {moved} m");

    // Second start: the box displaced and turned, the ropes straight to its points.
    let q = UnitQuaternion::from_euler_angles(0.1, -0.05, 0.2);
    let pose = BodyState::at_rest(Vector3::new(0.3, -0.2, 2.8), q);
    let mut start = init.clone();
    for ((sup, att), s) in ends.iter().zip(BOX_POINTS) {
        let (ra, rb) = (v3(&init.r[*sup]), pose.point(&Vector3::from(s)));
        let (r0a, r0b) = (v3(&init.r[*sup]), v3(&init.r[*att]));
        for (i, r) in start.r.iter_mut().enumerate() {
            // The rope's nodes lie on its straight start; move them to the new straight line.
            let p = v3(&init.r[i]);
            let along = (p - r0a).dot(&(r0b - r0a)) / (r0b - r0a).norm_squared();
            if (p - r0a - (r0b - r0a) * along).norm() < 1e-9 && (0.0..=1.0).contains(&along) {
                *r = vd(&(ra + (rb - ra) * along));
            }
        }
    }
    start.bodies[0] = pose;
    let eq2 = statics::solve_from(&sys, &start, &params, None).unwrap();
    let b2 = eq2.state.bodies[0];
    let dx = (b2.position - body.position).norm();
    let dq = b2.orientation.angle_to(&body.orientation);
    assert!(dx < 1e-9, "second start ends {dx:e} m away");
    assert!(dq < 1e-9, "second start ends turned by {dq:e} rad");
    for &s in &supports {
        let d = (eq2.reactions[s] - eq.reactions[s]).norm();
        assert!(d < 1e-9 * total, "reaction at {s} differs by {d:e} N");
    }
}

/// The cable robot: anchors near the top of a 4 × 4 × 3 m frame, platform points on the
/// top face of the 0.6 × 0.6 × 0.3 m platform (radius 0.3 m), paired as in a hexapod.
fn robot_geometry() -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let heights = [3.0, 2.95, 3.0, 2.9, 3.0, 2.95];
    let skew = [0.0, 5.0, -3.0, 0.0, 4.0, -2.0];
    let anchors = (0..6)
        .map(|i| {
            let th = (60.0 * i as f64 + skew[i]).to_radians();
            Vector3::new(1.9 * th.cos(), 1.9 * th.sin(), heights[i])
        })
        .collect();
    let points = (0..6)
        .map(|i| {
            let j = (i / 2) as f64;
            let side = if i % 2 == 0 { 40.0 } else { -40.0 };
            let phi = (120.0 * j + 60.0 + side).to_radians();
            Vector3::new(0.3 * phi.cos(), 0.3 * phi.sin(), 0.15)
        })
        .collect();
    (anchors, points)
}

/// A cable robot at rest, 6 cables on 6 DOF: a 50 kg platform (0.6 × 0.6 × 0.3 m) on six
/// stiff cables (EA = 1e7 N, 0.01 kg/m, one element each, 2.4–2.8 m, unstretched 1e-4
/// shorter than their span at the start). The cable tensions `EA (λ − 1)` at the
/// equilibrium (83–138 N) agree with the independent wrench balance of its geometry,
/// `A t = −w` with columns `[u_i; (R s_i) × u_i]` (`u_i` from platform point to anchor) and
/// `w` the platform's weight plus the cables' weights lumped at the platform points, to
/// 1e-9 of the largest tension (measured: 3.3e-11). With one element per cable the cables
/// are straight and their mass acts only through those lumped weights (0.13 N each, about
/// 1e-3 of a tension, which is what leaving them out of `w` would cost); what limits the
/// agreement is the stretch: `λ − 1 ≈ 1e-5` formed from positions of 1 m carries a rounding
/// of `ε/1e-5 ≈ 2e-11`. The platform's rest pose is stable.
#[test]
fn cable_robot_tensions_match_the_wrench_balance() {
    let (anchors, points) = robot_geometry();
    let (mass, ea) = (50.0, 1e7);
    let q = UnitQuaternion::from_euler_angles(0.02, -0.03, 0.05);
    let pose = BodyState::at_rest(Vector3::new(0.05, -0.04, 1.0), q);
    let body = (mass, box_inertia(mass, (0.6, 0.6, 0.3)));
    let spec = rope::<3>("cable", ea, 0.01, 1.0001);
    let (net, ends) = hung_body(&anchors, &points, body, &pose, &spec, 1);
    let (sys, init) = PhSystem::new(net).unwrap();
    let eq = statics::solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
    assert!(eq.stable, "the platform's rest pose is stable");
    let st = eq.state.bodies[0];
    let f = static_load(&sys);
    let mut a = Matrix6::<f64>::zeros();
    let mut w = Vector6::new(0.0, 0.0, -mass * G, 0.0, 0.0, 0.0);
    for (i, (&(anchor, att), s)) in ends.iter().zip(&points).enumerate() {
        let arm = st.orientation.transform_vector(s);
        // The attached node sits at its body point.
        let off = (v3(&eq.state.r[att]) - st.position - arm).norm();
        assert!(off < 1e-12, "cable {i}'s end is {off:e} m off its point");
        let u = (v3(&eq.state.r[anchor]) - v3(&eq.state.r[att])).normalize();
        a.fixed_view_mut::<3, 1>(0, i).copy_from(&u);
        a.fixed_view_mut::<3, 1>(3, i).copy_from(&arm.cross(&u));
        let lumped = v3(&f[att]);
        w.fixed_rows_mut::<3>(0).add_assign(&lumped);
        let m = arm.cross(&lumped);
        w.fixed_rows_mut::<3>(3).add_assign(&m);
    }
    let t = a.lu().solve(&(-w)).unwrap();
    let largest = t.amax();
    for (i, &end) in ends.iter().enumerate() {
        let ti = tension(&sys, &eq, end, ea);
        assert!(t[i] > 0.0, "cable {i} would push: {}", t[i]);
        let d = (ti - t[i]).abs();
        assert!(d < 1e-9 * largest, "cable {i}: {ti} N against {} N", t[i]);
    }
}

/// A 500 kg hook block (J = 60 kg·m²) on two steel slings (EA = 1e8 N, 1.6 kg/m, one
/// element each) from supports `supports` to its points `points` (body axes), starting level
/// with its centre at `(0, −5.2)`.
fn hook_block(
    supports: [[f64; 2]; 2],
    points: [[f64; 2]; 2],
) -> (PhSystem<2, Material>, State<2>, Vec<(usize, usize)>) {
    let sup: Vec<Vector3<f64>> = supports
        .iter()
        .map(|s| Vector3::new(s[0], s[1], 0.0))
        .collect();
    let pts: Vec<Vector3<f64>> = points
        .iter()
        .map(|s| Vector3::new(s[0], s[1], 0.0))
        .collect();
    let pose = BodyState::at_rest(Vector3::new(0.0, -5.2, 0.0), UnitQuaternion::identity());
    let inertia = Matrix3::from_diagonal_element(60.0);
    let spec = rope::<2>("sling", 1e8, 1.6, 1.0);
    let (net, ends) = hung_body(&sup, &pts, (500.0, inertia), &pose, &spec, 1);
    let (sys, init) = PhSystem::new(net).unwrap();
    (sys, init, ends)
}

/// The symmetric hook block against its closed form: level by symmetry, each sling of
/// tension `T` and stretched length `L = l (1 + T/EA)` over the span `d = 2.5 m` drops
/// `h = √(L² − d²)` and carries `T h/L = m g/2 + w`, `w` the half sling weight lumped at the
/// block (the one scalar root solved by bisection): tensions to 1e-9 relative and the
/// block's height to 1e-9 m (measured: 3.4e-12, and the height exactly), its turn below
/// 1e-12 rad (measured: 0).
#[test]
fn symmetric_hook_block_matches_the_closed_form() {
    let (sys, init, ends) = hook_block([[-3.0, 0.0], [3.0, 0.0]], [[-0.5, 0.4], [0.5, 0.4]]);
    let eq = statics::solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
    assert!(eq.stable);
    let (ea, l) = (1e8, sys.mesh().lengths()[0]);
    let vertical = 500.0 * G / 2.0 + 0.5 * 1.6 * G * l;
    let drop = |t: f64| {
        let len = l * (1.0 + t / ea);
        ((len * len - 2.5 * 2.5).sqrt(), len)
    };
    let (mut lo, mut hi) = (0.0, 1e5);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        let (h, len) = drop(mid);
        if mid * h / len < vertical {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = 0.5 * (lo + hi);
    let y = -drop(t).0 - 0.4;
    for &end in &ends {
        let ti = tension(&sys, &eq, end, ea);
        assert!((ti / t - 1.0).abs() < 1e-9, "tension {ti} N against {t} N");
    }
    let st = eq.state.bodies[0];
    assert!(
        (st.position.y - y).abs() < 1e-9,
        "height {} m against {y} m",
        st.position.y
    );
    assert!(
        st.position.x.abs() < 1e-9,
        "off centre by {} m",
        st.position.x
    );
    assert!(
        st.orientation.angle() < 1e-12,
        "turned by {} rad",
        st.orientation.angle()
    );
}

/// An off-centre hook block (slings to supports at different heights, points at −0.5 and
/// +0.7 m): it turns (by 0.079 rad), and its sling tensions solve the 3×3 balance of its
/// geometry — the two force rows give the tensions, which agree with `EA (λ − 1)` to 1e-9,
/// and the moment row then holds to 1e-9 of the weight times 1 m (measured: 2.6e-12 and
/// 2.3e-17). A run started from the equilibrium stays there: after 200 steps of 5 ms the
/// block has moved less than 1e-9 m and turned less than 1e-9 rad (measured: 2e-14 m,
/// 9e-15 rad); a state whose block is moved off its slings' ends is refused by node.
#[test]
fn off_centre_hook_block_balances_and_rests() {
    let (sys, init, ends) = hook_block([[-3.0, 0.0], [3.5, 0.3]], [[-0.5, 0.4], [0.7, 0.4]]);
    let eq = statics::solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
    assert!(eq.stable);
    let st = eq.state.bodies[0];
    assert!(
        st.orientation.angle() > 0.05,
        "turned by {} rad",
        st.orientation.angle()
    );
    let f = static_load(&sys);
    let (mut a, mut arms, mut w) = (
        Matrix2::<f64>::zeros(),
        Vec::new(),
        Vector2::new(0.0, -500.0 * G),
    );
    let mut moment = 0.0;
    let points = [[-0.5, 0.4], [0.7, 0.4]];
    for (k, (&(sup, att), p)) in ends.iter().zip(points).enumerate() {
        let arm = st
            .orientation
            .transform_vector(&Vector3::new(p[0], p[1], 0.0));
        let u = (eq.state.r[sup] - eq.state.r[att]).normalize();
        a.set_column(k, &u);
        w += f[att];
        moment += arm.x * f[att].y - arm.y * f[att].x;
        arms.push((arm, u));
    }
    let t = a.lu().solve(&(-w)).unwrap();
    for (k, &end) in ends.iter().enumerate() {
        let tk = tension(&sys, &eq, end, 1e8);
        assert!(
            (tk / t[k] - 1.0).abs() < 1e-9,
            "sling {k}: {tk} N against {} N",
            t[k]
        );
        let (arm, u) = arms[k];
        moment += t[k] * (arm.x * u.y - arm.y * u.x);
    }
    assert!(
        moment.abs() < 1e-9 * 500.0 * G,
        "moment row off by {moment} N·m"
    );

    let params = StepParams {
        h: 5e-3,
        ..Default::default()
    };
    let mut sim = Simulation::from_system(sys.clone(), eq.state.clone(), params).unwrap();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    let now = sim.state().bodies[0];
    let moved = (now.position - st.position).norm();
    let turned = now.orientation.angle_to(&st.orientation);
    assert!(moved < 1e-9, "moved {moved:e} m from rest");
    assert!(turned < 1e-9, "turned {turned:e} rad from rest");

    let mut off = eq.state.clone();
    off.bodies[0].position.x += 0.1;
    let Err(err) = Simulation::from_system(sys, off, params) else {
        panic!("a block off its slings' ends was accepted");
    };
    let node = ends[0].1;
    assert!(
        err.to_string().contains(&format!("node {node} is")),
        "{err}"
    );
}

/// A 500 kg block (J = 60 kg·m²) on one steel sling (EA = 1e8 N, 1.6 kg/m, one element,
/// 5 m) from a support at the origin, its point 0.4 m above its centre, starting upside down
/// (turned by `start` [rad]): it comes to hang straight below the support, its centre at
/// `(0, −L − 0.4)` with `L = l (1 + T/EA)`, `T = m g + w` (`w` the half sling weight lumped
/// at the block), turned by a multiple of 2π, to 1e-8 m and 1e-8 rad: the statics accept a
/// residual at the round-off floor of the stiff sling (about 1e-6 N here), which the
/// pendulum's soft stiffness `T/L ≈ 1e3 N/m` turns into about 1e-9 m (measured: 2.1e-10 m
/// and 4.2e-11 rad from 3.04 rad, 2.0e-10 m and 4.0e-11 rad from 3.14 rad, a turn whose
/// Cayley vector from the start would be 2 tan(1.5703) ≈ 4000; the pseudo-transient steps
/// measure each turn from the pose reached).
#[test]
fn block_starting_upside_down_comes_to_hang_below_its_support() {
    for start in [std::f64::consts::PI - 0.1, std::f64::consts::PI - 1e-3] {
        let q = UnitQuaternion::from_euler_angles(0.0, 0.0, start);
        let s = Vector3::new(0.0, 0.4, 0.0);
        let point = Vector3::new(0.3, -5.0, 0.0);
        let pose = BodyState::at_rest(point - q.transform_vector(&s), q);
        let spec = rope::<2>("sling", 1e8, 1.6, 1.0);
        let body = (500.0, Matrix3::from_diagonal_element(60.0));
        let (net, _) = hung_body(&[Vector3::zeros()], &[s], body, &pose, &spec, 1);
        let (sys, init) = PhSystem::new(net).unwrap();
        let eq = statics::solve_system(&sys, &init.r, &StaticsParams::default(), None).unwrap();
        assert!(eq.stable);
        let l = sys.mesh().lengths()[0];
        let t = 500.0 * G + 0.5 * 1.6 * G * l;
        let y = -l * (1.0 + t / 1e8) - 0.4;
        let st = eq.state.bodies[0];
        let off = (st.position - Vector3::new(0.0, y, 0.0)).norm();
        let turn = st.orientation.angle();
        assert!(off < 1e-8, "from {start} rad: centre {off:e} m off");
        assert!(
            turn < 1e-8,
            "from {start} rad: turned {turn:e} rad off hanging"
        );
    }
}
