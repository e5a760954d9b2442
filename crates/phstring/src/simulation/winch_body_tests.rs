//! A winch drum on a free rigid body (docs/method.md §23.7): every step's balance through
//! payout, haul-in and the cuts, with a prescribed payout and with a drum of its own; the
//! step's Jacobian, with the drum node held by the body after cuts have moved it, against
//! central differences; and a checkpoint that carries the drum node on the body.

use super::Simulation;
use super::test_support::fixed_steps;
use crate::body::{Attachment, BodyState, RigidBody};
use crate::network::{NetworkBuilder, StringSpec};
use crate::system::{MassMatrix, PointMass, Vector};
use crate::winch::{Winch, WinchDrum};
use crate::{Boundary, Material};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use std::sync::Arc;

/// A free 2 t block (3D) hung from a fixed point by 10 m of 32 mm wire rope (EA = 4.3e7 N,
/// 4.1 kg/m, elements of 1 m) at its top, swinging and turning about all three axes, with a
/// winch at a point 0.6 m off its centre paying out `payout(t)` of the same rope (15 m,
/// stretched 0.1 %, 5 more on the drum) with a 500 kg hook (or, with `dynamics`, moved by
/// that drum's dynamics); `h` = 5 ms, fixed steps.
fn block_with_a_winch(
    dynamics: Option<WinchDrum>,
    payout: fn(f64) -> f64,
) -> Simulation<3, Material> {
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
    let hook = b.node(at(drum) - Vector::<3>::new(0.0, 0.0, 15.0 * 1.001));
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
        .string_on_drum(rope("fall"), &[drum_n, hook], 15, reserve)
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
            payout: Arc::new(payout),
            drum_motion: None,
            drum: dynamics,
        });
    Simulation::new(net, fixed_steps(0.005)).unwrap()
}

/// 0.4 m/s paid out.
fn steady(t: f64) -> f64 {
    0.4 * t
}

/// 3 m paid out and hauled back in over 8 s, from rest to rest: `1.5 (1 − cos(πt/4))` [m].
fn out_and_in(t: f64) -> f64 {
    1.5 * (1.0 - (0.25 * std::f64::consts::PI * t).cos())
}

/// The block paying out 3 m and hauling it back in over 8 s (cuts both ways), its winch
/// driven by that payout or by `dynamics`, 1600 steps: every step's balance holds to 1e-12 of
/// the energy scale (the body's kinetic and potential energy, the rope's, the winch's
/// supply), and the rope's mass off the drum is `ρA` times its length throughout; at least
/// 2 cuts. Returns the winch's state at the end and its drum element at the start.
fn free_block_run(dynamics: Option<WinchDrum>) -> (crate::winch::WinchState, usize) {
    let mut sim = block_with_a_winch(dynamics, out_and_in);
    let (drum0, start) = (sim.run.winches[0].drum, sim.run.state.bodies[0].orientation);
    let (mut worst, mut mass_off, mut cuts) = (0.0f64, 0.0f64, 0);
    let mut last = drum0;
    for _ in 0..1600 {
        let rep = sim.step().unwrap();
        worst = worst.max(rep.balance_error.abs() / rep.energy_scale);
        let s = &sim.winch_samples()[0];
        mass_off = mass_off.max((s.mass - 4.1 * s.length).abs() / (4.1 * s.length));
        let d = sim.run.winches[0].drum;
        cuts += usize::from(d != last);
        last = d;
    }
    let ws = sim.run.winches[0];
    eprintln!(
        "free block: {cuts} cuts, balance {worst:.2e}, mass off {mass_off:.1e}, payout at the end {:.2e} m, drum element {} (start {drum0}), body turned {:.3} rad",
        ws.payout,
        ws.drum,
        sim.run.state.bodies[0].orientation.angle_to(&start)
    );
    assert!(cuts >= 2, "{cuts} cuts");
    assert!(worst < 1e-12, "balance error {worst:e} of the energy scale");
    assert!(
        mass_off < 1e-12,
        "mass off the drum off ρA × length by {mass_off:e}"
    );
    (ws, drum0)
}

/// The free block with its winch paying out 3 m and hauling it back in (6 cuts): the
/// balance and mass of [`free_block_run`], and back at payout 0 the drum element is the one it
/// started from.
#[test]
fn drum_on_a_free_turning_body_keeps_an_exact_balance() {
    let (ws, drum0) = free_block_run(None);
    assert!(ws.payout.abs() < 1e-12);
    assert_eq!(ws.drum, drum0);
}

/// The free block with a drum of its own (300 kg at the rope, a motor pulling 4 kN against
/// the hook's 4.9 kN, damping 2 kN·s/m, a 1 kN brake slipping at 2 cm/s): its payout a slot
/// of the step, coupled with the turning body's, the balance and mass of [`free_block_run`]
/// hold, with the drum's kinetic energy in `Ĥ` and its damping and brake dissipating.
#[test]
fn drum_with_dynamics_on_a_free_turning_body_keeps_an_exact_balance() {
    let drum = WinchDrum {
        inertia: 300.0,
        force: Arc::new(|_| 4.0e3),
        damping: 2.0e3,
        brake: Some((1.0e3, 0.02)),
    };
    let (ws, _) = free_block_run(Some(drum));
    assert!(
        ws.dissipated > 0.0,
        "the drum dissipated {} J",
        ws.dissipated
    );
}

/// After 3 s (1.2 m paid out: the body holds the drum node that a cut brought off the drum),
/// the Jacobian of the next step's residual at an increment moved off the predictor (the free
/// nodes by up to 1 mm, the body by 2 mm and 3 mrad) against central differences along a
/// direction in the free components and the body's slots: the largest difference is below
/// 1e-6 of the largest entry of `J·d` (measured 6e-9; 7e-11 in the body's rows).
#[test]
fn a_drum_on_a_body_has_the_jacobian_of_its_differences() {
    let worst = body_drum_jacobian(None, 600);
    assert!(worst < 1e-6, "Jacobian off by {worst:e} of the scale");
}

/// As [`a_drum_on_a_body_has_the_jacobian_of_its_differences`] with a drum of its own on
/// the block (200 kg at the rope, a motor pulling 4.5 kN, damping 2 kN·s/m and a 3 kN brake
/// slipping at 5 cm/s), whose payout is a slot of the step: its row against the body's slots
/// and the body's rows against it too, after 2 s (the hook's pull paying the rope out).
/// Measured 7e-8 in the nodes' rows, 1e-11 in the body's and the drum's: the differences'
/// truncation (it scales with the square of their step).
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
    let mut sim = block_with_a_winch(drum, steady);
    let start = sim.run.winches[0].drum;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    assert!(
        sim.run.winches[0].drum < start,
        "cuts brought elements off the drum"
    );
    let h = 0.005;
    sim.prepare_step(h);
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
    let (jd, fd) = sim.jacobian_along(h, (&x, &dir), 1e-7);
    let scale = jd.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let (mut worst, mut worst_body) = (0.0_f64, 0.0_f64);
    for i in 0..x.len() {
        for k in 0..3 {
            // A drum's slot has one unknown; its other rows are placeholders.
            if (i < n && !sim.sys.free[i][k]) || (i >= n + 2 && k > 0) {
                continue;
            }
            let off = (jd[i][k] - fd[i][k]).abs() / scale;
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
    let mut sim = block_with_a_winch(None, steady);
    for _ in 0..400 {
        sim.step().unwrap();
    }
    let cp = sim.checkpoint();
    for _ in 0..200 {
        sim.step().unwrap();
    }
    let mut again = block_with_a_winch(None, steady);
    again.restore(cp).unwrap();
    for _ in 0..200 {
        again.step().unwrap();
    }
    assert_eq!(again.run.state.r, sim.run.state.r);
    assert_eq!(again.run.state.bodies, sim.run.state.bodies);
    assert_eq!(again.run.winches, sim.run.winches);
}
