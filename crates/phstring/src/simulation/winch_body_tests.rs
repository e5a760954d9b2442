//! A winch drum on a rigid body (docs/method.md §23, "A drum on a rigid body"): the step's
//! Jacobian, with the drum node held by the body after cuts have moved it, against central
//! differences; and a checkpoint that carries the drum node on the body.

use super::{Simulation, StepAt, StepControl, StepParams};
use crate::body::{Attachment, BodyState, RigidBody};
use crate::integrator::StepEquations;
use crate::linsolve::BlockJacobian;
use crate::network::{NetworkBuilder, StringSpec};
use crate::newton::NewtonProblem;
use crate::system::{MassMatrix, PointMass, Vector};
use crate::winch::{Winch, WinchDrum};
use crate::{Boundary, Material};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use std::sync::Arc;

/// A free 2 t block (3D) hung from a fixed point by 10 m of 32 mm wire rope (EA = 4.3e7 N,
/// 4.1 kg/m, elements of 1 m) at its top, swinging and turning, with a winch at a point
/// 0.6 m off its centre paying out 0.4 m/s of the same rope (12 m, 5 more on the drum) with
/// a 500 kg hook (or, with `dynamics`, moved by that drum's dynamics); `h` = 5 ms, fixed steps.
fn block_with_a_winch(dynamics: Option<WinchDrum>) -> Simulation<3, Material> {
    let g = 9.81;
    let start = BodyState::new(
        Vector3::new(0.3, 0.0, -10.6),
        Vector3::new(0.2, -0.1, 0.0),
        UnitQuaternion::from_euler_angles(0.05, -0.03, 0.2),
        Vector3::new(0.1, -0.05, 0.3),
    );
    let (top_s, drum_s) = (Vector3::new(0.0, 0.0, 0.5), Vector3::new(0.6, 0.0, -0.5));
    let (top, drum) = (start.point(&top_s), start.point(&drum_s));
    let v_of = |s: &Vector3<f64>| {
        let arm = start.orientation.transform_vector(s);
        let v = start.velocity + start.omega_space().cross(&arm);
        Vector::<3>::new(v.x, v.y, v.z)
    };
    let at = |p: Vector3<f64>| Vector::<3>::new(p.x, p.y, p.z);
    let mut b = NetworkBuilder::<3, Material>::new();
    let fix = b.node(Vector::<3>::zeros());
    let top_n = b.node(at(top));
    let drum_n = b.node(at(drum));
    let hook = b.node(at(drum) - Vector::<3>::new(0.0, 0.0, 12.0 * 1.001));
    let rope = |name: &str| StringSpec {
        name: name.into(),
        material: Material::tension_only_linear(4.3e7),
        rho_a: 4.1,
        mass: MassMatrix::Consistent,
        body_force: Vector::<3>::new(0.0, 0.0, -4.1 * g),
        prestretch: 1.0,
    };
    b.string(rope("hanger"), &[fix, top_n], 10).unwrap();
    let reserve = 5;
    let grp = b
        .string_on_drum(rope("fall"), &[drum_n, hook], 12, reserve)
        .unwrap();
    let nodes = b.group_nodes(grp).unwrap().to_vec();
    let masses = vec![PointMass {
        node: hook,
        mass: 500.0,
        weight: Vector::<3>::new(0.0, 0.0, -500.0 * g),
    }];
    let boundary = Boundary {
        fixed: vec![crate::Fixed::node(fix)],
        ..Default::default()
    };
    let mut net = b.build(boundary, masses).unwrap();
    net.initial.v[top_n] = v_of(&top_s);
    for &i in &nodes[..=reserve] {
        net.initial.v[i] = v_of(&drum_s);
    }
    let net = net
        .with_body(RigidBody {
            name: "block".into(),
            mass: 2000.0,
            inertia: Matrix3::from_diagonal(&Vector3::new(300.0, 420.0, 250.0)),
            weight: Vector::<3>::new(0.0, 0.0, -2000.0 * g),
            attachments: vec![
                Attachment {
                    node: top_n,
                    point: at(top_s),
                },
                Attachment {
                    node: drum_n,
                    point: at(drum_s),
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
            group: grp,
            reserve,
            payout: Arc::new(|t| 0.4 * t),
            drum_motion: None,
            drum: dynamics,
        });
    let params = StepParams {
        h: 0.005,
        control: StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..StepParams::default()
    };
    Simulation::new(net, params).unwrap()
}

/// After 3 s (1.2 m paid out: the body holds the drum node that a cut brought off the drum),
/// the Jacobian of the next step's residual at an increment moved off the predictor (the free
/// nodes by up to 1 mm, the body by 2 mm and 3 mrad) against central differences along a
/// direction in the free components and the body's slots: the largest difference is below
/// 1e-6 of the largest entry of `J·d` (measured 9e-10), in the body's rows too.
#[test]
fn a_drum_on_a_body_has_the_jacobian_of_its_differences() {
    let worst = body_drum_jacobian(None, 600);
    assert!(worst < 1e-6, "Jacobian off by {worst:e} of the scale");
}

/// As [`a_drum_on_a_body_has_the_jacobian_of_its_differences`] with a drum of its own on
/// the block (200 kg at the rope, a motor pulling 4.5 kN, damping 2 kN·s/m and a 3 kN brake
/// slipping at 5 cm/s), whose payout is a slot of the step: its row against the body's slots
/// and the body's rows against it too, after 2 s (the hook's pull paying the rope out).
/// Measured 5e-8 in the nodes' rows, 7e-12 in the body's and the drum's: the differences'
/// truncation (it scales with the square of their step, 4e-9 at 3e-8).
#[test]
fn a_drum_with_dynamics_on_a_body_has_the_jacobian_of_its_differences() {
    let drum = WinchDrum {
        inertia: 200.0,
        force: Arc::new(|t| 4.5e3 + 100.0 * t),
        damping: 2.0e3,
        brake: Some((3.0e3, 0.05)),
    };
    let worst = body_drum_jacobian(Some(drum), 400);
    assert!(worst < 1e-6, "Jacobian off by {worst:e} of the scale");
}

/// The largest difference between the step's Jacobian along a direction and the central
/// differences of its residual, relative to the largest entry of `J·d`, for the block with
/// `drum` after `steps` steps (elements brought off the drum by then), at an increment moved
/// off the predictor: the free nodes by up to 1 mm, the body by 2 mm and 3 mrad, a drum's
/// payout by 3 mm.
fn body_drum_jacobian(drum: Option<WinchDrum>, steps: usize) -> f64 {
    let mut sim = block_with_a_winch(drum);
    let start = sim.run.winches[0].drum;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    assert!(
        sim.run.winches[0].drum < start,
        "cuts brought elements off the drum"
    );
    let (t, h) = (sim.time(), 0.005);
    let at = StepAt {
        step: steps + 1,
        t,
        h,
        t_next: t + h,
    };
    sim.apply_loads(&at).unwrap();
    sim.predict(&at).unwrap();
    let n = sim.sys.mesh.n_nodes();
    let mut x = sim.x.clone();
    for (i, xi) in x[..n].iter_mut().enumerate() {
        let f = i as f64;
        *xi += Vector::<3>::new(1e-3 * f.sin(), 7e-4 * f.cos(), 5e-4 * (2.0 * f).sin());
    }
    x[n] += Vector::<3>::new(2e-3, -1e-3, 1.5e-3);
    x[n + 1] += Vector::<3>::new(3e-3, -2e-3, 1e-3);
    if x.len() > n + 2 {
        x[n + 2][0] += 3e-3;
    }
    let mut reaction = vec![Vector::<3>::zeros(); n];
    let mut eqs = StepEquations::new(
        &sim.sys,
        sim.params.scheme,
        h,
        &sim.run.state,
        t + 0.5 * h,
        &sim.f_ext,
        &mut reaction,
    );
    eqs.drums = &sim.drum_steps;
    let mut jac = BlockJacobian::with_slots(&sim.sys.mesh, x.len() - n);
    let mut res = vec![Vector::<3>::zeros(); x.len()];
    eqs.evaluate(&x, &mut res, Some(&mut jac)).unwrap();
    let mut dir = vec![Vector::<3>::zeros(); x.len()];
    for (i, d) in dir[..n].iter_mut().enumerate() {
        for k in 0..3 {
            if sim.sys.free[i][k] {
                d[k] = ((3 * i + k) as f64 * 0.7).sin();
            }
        }
    }
    dir[n] = Vector::<3>::new(0.4, -0.7, 0.3);
    dir[n + 1] = Vector::<3>::new(0.2, 0.5, -0.6);
    if x.len() > n + 2 {
        dir[n + 2][0] = 0.8;
    }
    let mut jd = vec![Vector::<3>::zeros(); x.len()];
    jac.mul(&sim.sys.mesh, &dir, &mut jd);
    let eps = 1e-7;
    let mut shifted = |s: f64| {
        let xs: Vec<_> = x.iter().zip(&dir).map(|(a, d)| a + d * s).collect();
        let mut r = vec![Vector::<3>::zeros(); x.len()];
        eqs.evaluate(&xs, &mut r, None).unwrap();
        r
    };
    let (plus, minus) = (shifted(eps), shifted(-eps));
    let scale = jd.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let (mut worst, mut worst_body) = (0.0_f64, 0.0_f64);
    for i in 0..x.len() {
        for k in 0..3 {
            // A drum's slot has one unknown; its other rows are placeholders.
            if (i < n && !sim.sys.free[i][k]) || (i >= n + 2 && k > 0) {
                continue;
            }
            let fd = (plus[i][k] - minus[i][k]) / (2.0 * eps);
            let off = (jd[i][k] - fd).abs() / scale;
            worst = worst.max(off);
            if i >= n {
                worst_body = worst_body.max(off);
            }
        }
    }
    eprintln!(
        "body drum Jacobian: worst {worst:.2e} (body and drum rows {worst_body:.2e}) of {scale:.3e}"
    );
    worst
}

/// A run continued from a checkpoint taken at 2 s (with the drum node on the body moved on by
/// cuts) steps exactly as the run that was not interrupted: after 1 s more, the positions
/// and the body's state agree bit for bit.
#[test]
fn a_checkpoint_carries_a_drum_on_a_body() {
    let mut sim = block_with_a_winch(None);
    for _ in 0..400 {
        sim.step().unwrap();
    }
    let cp = sim.checkpoint();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    let mut again = block_with_a_winch(None);
    again.restore(cp).unwrap();
    for _ in 0..200 {
        again.step().unwrap();
    }
    assert_eq!(again.run.state.r, sim.run.state.r);
    assert_eq!(again.run.state.bodies, sim.run.state.bodies);
    assert_eq!(again.run.winches, sim.run.winches);
}
