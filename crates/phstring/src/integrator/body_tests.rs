//! The step's Jacobian with bodies (border included) against central differences of
//! its residual, in 2D and 3D, on a network where a body hangs from a support by a rope,
//! a second body hangs from the first by a one-element rope (body–body blocks), a rope
//! from it ends at a partly fixed node, and a load acts on an attached node; both bodies
//! feel buoyancy off their centre, a waterplane's heave restoring, drag in a sheared current
//! and added mass (the first `C_a` and added inertia, the second a full matrix with
//! translation–rotation couplings, the Kirchhoff form); the first is under PD feedback on
//! its pose.

use crate::body::{Attachment, RigidBody};
use crate::body::{BodyState, Mat3, Vec3, project};
use crate::body_step::predict;
use crate::boundary::{Boundary, Fixed, NodalLoad};
use crate::integrator::{Scheme, StepEquations};
use crate::linsolve::BlockJacobian;
use crate::material::Material;
use crate::network::{NetworkBuilder, StringSpec};
use crate::newton::NewtonProblem;
use crate::system::Vector;
use crate::system::{MassMatrix, PhSystem};
use nalgebra::UnitQuaternion;

fn v<const D: usize>(x: f64, y: f64, z: f64) -> Vector<D> {
    embed_inv::<D>(&Vec3::new(x, y, z))
}

fn embed_inv<const D: usize>(p: &Vec3) -> Vector<D> {
    project(p)
}

/// The check on the network above, its bodies' orientations turned and the trial point
/// perturbed by `seed` (numbers in [−1, 1], cycled).
fn check<const D: usize>(scheme: Scheme, seed: &[f64]) {
    let mut it = seed.iter().copied().cycle();
    let mut next = move || it.next().unwrap_or(0.0);
    let turns: Vec<f64> = (0..6).map(|_| 0.5 * next()).collect();
    let planar = |p: Vec3| if D == 2 { Vec3::new(p.x, p.y, 0.0) } else { p };
    let q = |a: f64, b: f64, c: f64| {
        if D == 2 {
            UnitQuaternion::from_euler_angles(0.0, 0.0, c)
        } else {
            UnitQuaternion::from_euler_angles(a, b, c)
        }
    };
    let inertia = Mat3::new(300.0, 20.0, -10.0, 20.0, 500.0, 15.0, -10.0, 15.0, 650.0);
    let sa = BodyState::new(
        planar(Vec3::new(0.0, -10.0, 0.5)),
        planar(Vec3::new(0.3, -0.2, 0.4)),
        q(0.1 + turns[0], -0.2 + turns[1], 0.3 + turns[2]),
        if D == 2 {
            Vec3::new(0.0, 0.0, -0.5)
        } else {
            Vec3::new(0.2, 0.3, -0.5)
        },
    );
    let sb = BodyState::new(
        planar(Vec3::new(1.0, -14.0, -0.3)),
        planar(Vec3::new(-0.1, 0.2, 0.3)),
        q(-0.2 + turns[3], 0.1 + turns[4], -0.4 + turns[5]),
        Vec3::new(0.0, 0.0, 0.7),
    );
    let (top_a, bot_a, side_a) = (
        planar(Vec3::new(0.2, 1.0, 0.1)),
        planar(Vec3::new(-0.3, -1.0, 0.2)),
        planar(Vec3::new(1.0, 0.1, -0.2)),
    );
    let top_b = planar(Vec3::new(0.1, 1.2, -0.1));
    let spec = StringSpec {
        name: "rope".into(),
        material: Material::hyperelastic(2e7),
        rho_a: 1.6,
        mass: MassMatrix::Consistent,
        body_force: v::<D>(0.0, -15.7, 0.0),
        prestretch: 1.002,
    };
    let mut nb = NetworkBuilder::<D, Material>::new();
    let support = nb.node(v::<D>(0.5, 0.0, 0.0));
    let na = nb.node(project(&sa.point(&top_a)));
    let nab = nb.node(project(&sa.point(&bot_a)));
    let nb_top = nb.node(project(&sb.point(&top_b)));
    let nside = nb.node(project(&sa.point(&side_a)));
    let end = nb.node(v::<D>(6.0, -9.0, 1.0));
    nb.string(spec.clone(), &[support, na], 4).unwrap();
    nb.string(spec.clone(), &[nab, nb_top], 1).unwrap();
    nb.string(spec, &[nside, end], 3).unwrap();
    let mut partly = [false; D];
    partly[1] = true;
    let boundary = Boundary {
        fixed: vec![
            Fixed::node(support),
            Fixed {
                node: end,
                components: partly,
            },
        ],
        loads: vec![NodalLoad::new(nside, |t| {
            Vector::<D>::from_element(100.0 * t)
        })],
        motions: vec![],
        feedback: vec![],
    };
    let mut net = nb.build(boundary, vec![]).unwrap();
    // Attached nodes with their bodies' velocities.
    for (node, st, s) in [
        (na, &sa, top_a),
        (nab, &sa, bot_a),
        (nside, &sa, side_a),
        (nb_top, &sb, top_b),
    ] {
        let om = st.orientation.transform_vector(&st.omega);
        let arm = st.orientation.transform_vector(&s);
        net.initial.v[node] = project(&(st.velocity + om.cross(&arm)));
    }
    let att = |node, s: Vec3| Attachment {
        node,
        point: project(&s),
    };
    let body = |name: &str, atts, initial| RigidBody {
        name: name.into(),
        mass: 800.0,
        inertia,
        weight: v::<D>(0.0, -800.0 * 9.81, 0.0),
        attachments: atts,
        initial,
        wrench: None,
        hydro: Some(crate::body::BodyHydro {
            volume: 0.6,
            centre_of_buoyancy: planar(Vec3::new(0.1, 0.3, -0.2)),
            cda: 1.2,
            linear_drag: 300.0,
            ca: 0.8,
            added_inertia: Vec3::new(20.0, 30.0, 40.0),
            added_mass: None,
            waterplane_area: 3.0,
            waterline: planar(Vec3::new(-0.2, 0.5, 0.3)),
            waterplane_moments: [0.9, 1.4],
        }),
        motion: None,
        feedback: None,
    };
    // Body a under PD on its pose (a reference off its pose, moving), so that the feedback's
    // blocks are in the Jacobian too.
    let feedback = crate::body_feedback::BodyFeedback {
        kp: Vec3::new(2e4, 3e4, 1e4),
        kd: Vec3::new(3e3, 1e3, 2e3),
        kp_turn: Vec3::new(4e3, 6e3, 5e3),
        kd_turn: Vec3::new(600.0, 400.0, 900.0),
        reference: std::sync::Arc::new(move |t| {
            let x = planar(Vec3::new(0.2 * t, -10.3, 0.4));
            (x, q(0.3, 0.1, -0.6 + t))
        }),
        reference_rate: std::sync::Arc::new(move |_| {
            (planar(Vec3::new(0.2, 0.0, 0.0)), Vec3::new(0.0, 0.0, 1.0))
        }),
    };
    let net = net
        .with_body(RigidBody {
            feedback: Some(feedback),
            ..body(
                "a",
                vec![att(na, top_a), att(nab, bot_a), att(nside, side_a)],
                sa,
            )
        })
        .with_body(coupled(body("b", vec![att(nb_top, top_b)], sb)));
    // Water with a current that turns and grows with height, so that the drag's dependence
    // on the mid-step height is in the Jacobian too.
    let profile = vec![
        (-20.0, v::<D>(0.2, 0.0, -0.1)),
        (0.0, v::<D>(1.2, 0.3, 0.4)),
    ];
    let water =
        crate::water::Water::new(1025.0).with_current(crate::water::Current::Profile(profile));
    let (sys, state) = PhSystem::new(net.with_water(water)).unwrap();
    let n = sys.mesh().n_nodes();
    let slots = 4;
    // A trial point: the predictor plus a perturbation.
    let h = 0.01;
    let mut x: Vec<Vector<D>> = state.v.iter().map(|v| v * h).collect();
    x.resize(n + slots, Vector::zeros());
    predict(&state.bodies, h, &mut x[n..]);
    for xi in x.iter_mut() {
        for k in 0..D {
            xi[k] += 1e-3 * next();
        }
    }
    if D == 2 {
        x[n + 1][1] = 0.0;
        x[n + 3][1] = 0.0;
    }
    let f_ext = sys.body_force_vector().to_vec();
    let mut reaction = vec![Vector::<D>::zeros(); n];
    let wrenches = [(
        Vec3::new(300.0, -200.0, 100.0),
        Vec3::new(50.0, 40.0, -30.0),
    ); 2];
    let mut eqs = StepEquations::new(&sys, scheme, h, &state, 0.3, &f_ext, &mut reaction);
    eqs.wrenches = &wrenches;
    let targets: Vec<_> = sys
        .bodies
        .iter()
        .map(|m| m.feedback.as_ref().map(|f| f.target(0.3)))
        .collect();
    assert!(targets[0].is_some());
    eqs.targets = &targets;
    let mut res = vec![Vector::<D>::zeros(); n + slots];
    let mut jac = BlockJacobian::<D>::with_slots(sys.mesh(), slots);
    eqs.evaluate(&x, &mut res, Some(&mut jac)).unwrap();
    solvers_agree(&sys, &jac, &res);
    // Directions: each unknown component alone.
    // Central differences: rounding ε|R|/eps ≈ 1e-16·1e5/1e-7 = 1e-4 against entries of
    // 1e6–1e7 (m/h², EA/l); a missing term is of order the torque or force, 1e3 and more.
    let eps = 1e-7;
    for i in 0..n + slots {
        for k in 0..D {
            let mut d = vec![Vector::<D>::zeros(); n + slots];
            d[i][k] = 1.0;
            let mut jd = vec![Vector::<D>::zeros(); n + slots];
            jac.mul(sys.mesh(), &d, &mut jd);
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[i][k] += eps;
            xm[i][k] -= eps;
            let (mut rp, mut rm) = (res.clone(), res.clone());
            eqs.evaluate(&xp, &mut rp, None).unwrap();
            eqs.evaluate(&xm, &mut rm, None).unwrap();
            // Held components (masked) and the 2D placeholder are identity columns.
            let held = (i < n && !sys.free_components()[i][k])
                || (D == 2 && i >= n && (i - n) % 2 == 1 && k == 1);
            for r in 0..n + slots {
                let fd = (rp[r] - rm[r]) / (2.0 * eps);
                let fd = if held {
                    Vector::<D>::from_fn(|c, _| if r == i && c == k { 1.0 } else { 0.0 })
                } else {
                    fd
                };
                let scale = 1.0 + jd[r].norm().max(fd.norm());
                assert!(
                    (fd - jd[r]).norm() <= 2e-5 * scale.max(1e4),
                    "row {r} column ({i}, {k}): fd {fd} vs {}",
                    jd[r]
                );
            }
        }
    }
}

/// `body` with a full added-mass matrix (kg, kg·m, kg·m²; diagonally dominant, so positive
/// definite) in place of its `C_a` and added inertia: unequal translational entries, and
/// couplings among the plane's `(x, y, θ_z)` and between translation and rotation out of it.
fn coupled<const D: usize>(mut body: RigidBody<D>) -> RigidBody<D> {
    let mut a = crate::body::Mat6::from_diagonal(&nalgebra::Vector6::new(
        400.0, 700.0, 300.0, 60.0, 80.0, 90.0,
    ));
    for (r, c, x) in [
        (0, 1, 100.0),
        (0, 5, 30.0),
        (1, 5, -20.0),
        (0, 4, -50.0),
        (1, 3, 40.0),
    ] {
        a[(r, c)] = x;
        a[(c, r)] = x;
    }
    body.hydro = body.hydro.map(|h| crate::body::BodyHydro {
        ca: 0.0,
        added_inertia: Vec3::zeros(),
        added_mass: Some(a),
        ..h
    });
    body
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(6))]
    /// The bodies turned anywhere within ±0.5 rad of the base poses and the trial point
    /// perturbed by up to 1 mm per component.
    #[test]
    fn jacobian_with_bodies_matches_finite_differences(
        seed in proptest::collection::vec(-1.0f64..1.0, 16..64)
    ) {
        check::<3>(Scheme::DiscreteGradient, &seed);
        check::<3>(Scheme::Midpoint, &seed);
        check::<2>(Scheme::DiscreteGradient, &seed);
    }
}

/// The step's Newton matrix with bodies `jac` (its border filled by the step, in the pattern
/// of [`crate::body_step::border_pattern`]) solved for `rhs` with the bodies as junctions of
/// the network solver agrees with the bordered solve (Schur complement) over faer's sparse
/// LU and over the network solver to 1e-12 relative (measured: 3D 3.0e-15 to 8.4e-15 over
/// both schemes, 2D 1.1e-15 and 1.3e-15), and its residual `‖J x − b‖` is at round-off of
/// `‖b‖` (1e-12 asserted).
fn solvers_agree<const D: usize>(
    sys: &PhSystem<D, Material>,
    jac: &BlockJacobian<D>,
    rhs: &[Vector<D>],
) {
    use crate::linsolve::{SolverKind, make_border_solver, make_bordered_solver};
    let mesh = sys.mesh();
    let border = crate::body_step::border_pattern(sys);
    let solve = |mut solver: Box<dyn crate::linsolve::LinearSolver<D>>| {
        let mut x = rhs.to_vec();
        solver.solve(jac, &mut x).unwrap();
        x
    };
    let junction = solve(make_border_solver::<D>(SolverKind::Network, mesh, &border).unwrap());
    let norm = |v: &[Vector<D>]| v.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt();
    let mut jx = vec![Vector::<D>::zeros(); rhs.len()];
    jac.mul(mesh, &junction, &mut jx);
    let r: Vec<Vector<D>> = jx.iter().zip(rhs).map(|(a, b)| a - b).collect();
    assert!(
        norm(&r) <= 1e-12 * norm(rhs),
        "residual {:e}",
        norm(&r) / norm(rhs)
    );
    for kind in [SolverKind::SparseLu, SolverKind::Network] {
        let slots = border.slots;
        let bordered = solve(make_bordered_solver::<D>(kind, mesh, slots).unwrap());
        let d: Vec<Vector<D>> = junction.iter().zip(&bordered).map(|(a, b)| a - b).collect();
        let rel = norm(&d) / norm(&bordered);
        eprintln!("D = {D}: junction vs bordered {}: {rel:e}", kind.name());
        assert!(
            rel <= 1e-12,
            "D = {D}: vs bordered {}: {rel:e}",
            kind.name()
        );
    }
}
