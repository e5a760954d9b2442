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

/// A free rigid body hung from a fixed point at the origin by 10 m of 32 mm wire rope
/// (EA = 4.3e7 N, 4.1 kg/m, elements of 1 m) at its point `top`, starting in `start`, with a
/// winch at its point `drum` paying out `payout(t)` of the same rope (`fall` elements,
/// stretched 0.1 %, hanging straight down, 5 more on the drum) with a 500 kg hook (or, with
/// `dynamics`, moved by that drum's dynamics); the body's mass [kg] and principal inertia
/// [kg·m²] in `mass`; `h` = 5 ms, fixed steps.
struct HungBody {
    start: BodyState,
    mass: (f64, Vector3<f64>),
    top: Vector3<f64>,
    drum: Vector3<f64>,
    fall: usize,
}

impl HungBody {
    /// The simulation of this body with its winch (see [`HungBody`]).
    fn with_winch<const D: usize>(
        &self,
        dynamics: Option<WinchDrum>,
        payout: fn(f64) -> f64,
    ) -> Simulation<D, Material> {
        let g = 9.81;
        let st = &self.start;
        let at = |p: Vector3<f64>| crate::body::project::<D>(&p);
        let v_of = |s: &Vector3<f64>| {
            let arm = st.orientation.transform_vector(s);
            at(st.velocity + st.omega_space().cross(&arm))
        };
        let up = Vector::<D>::from_fn(|k, _| if k + 1 == D { 1.0 } else { 0.0 });
        let mut b = NetworkBuilder::<D, Material>::new();
        let fix = b.node(Vector::<D>::zeros());
        let top_n = b.node(at(st.point(&self.top)));
        let drum_n = b.node(at(st.point(&self.drum)));
        let hook = b.node(at(st.point(&self.drum)) - up * (self.fall as f64 * 1.001));
        let rope = |name: &str| StringSpec {
            name: name.into(),
            material: Material::tension_only_linear(4.3e7),
            rho_a: 4.1,
            mass: MassMatrix::Consistent,
            body_force: up * (-4.1 * g),
            prestretch: 1.0,
        };
        b.string(rope("hanger"), &[fix, top_n], 10).unwrap();
        let reserve = 5;
        let grp = b
            .string_on_drum(rope("fall"), &[drum_n, hook], self.fall, reserve)
            .unwrap();
        let nodes = b.group_nodes(grp).unwrap().to_vec();
        let masses = vec![PointMass {
            node: hook,
            mass: 500.0,
            weight: up * (-500.0 * g),
        }];
        let boundary = Boundary {
            fixed: vec![crate::Fixed::node(fix)],
            ..Default::default()
        };
        let mut net = b.build(boundary, masses).unwrap();
        net.initial.v[top_n] = v_of(&self.top);
        for &i in &nodes[..=reserve] {
            net.initial.v[i] = v_of(&self.drum);
        }
        let (mass, inertia) = self.mass;
        let attach = |node, s| Attachment { node, point: at(s) };
        let net = net
            .with_body(RigidBody {
                name: "body".into(),
                mass,
                inertia: Matrix3::from_diagonal(&inertia),
                weight: up * (-mass * g),
                attachments: vec![attach(top_n, self.top), attach(drum_n, self.drum)],
                initial: *st,
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
}

/// A free 2 t block (3D) of [`HungBody`], swinging and turning about all three axes, its top
/// 0.5 m above its centre, its winch 0.6 m off its centre with 15 m of rope.
fn block_with_a_winch(
    dynamics: Option<WinchDrum>,
    payout: fn(f64) -> f64,
) -> Simulation<3, Material> {
    let block = HungBody {
        start: BodyState::new(
            Vector3::new(0.3, 0.0, -10.6),
            Vector3::new(0.2, -0.1, 0.0),
            UnitQuaternion::from_euler_angles(0.05, -0.03, 0.2),
            Vector3::new(0.1, -0.05, 0.3),
        ),
        mass: (2000.0, Vector3::new(300.0, 420.0, 250.0)),
        top: Vector3::new(0.0, 0.0, 0.5),
        drum: Vector3::new(0.6, 0.0, -0.5),
        fall: 15,
    };
    block.with_winch(dynamics, payout)
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
/// `min_cuts` cuts. Returns the winch's state at the end and its drum element at the start.
fn free_block_run(
    dynamics: Option<WinchDrum>,
    min_cuts: usize,
) -> (crate::winch::WinchState, usize) {
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
    assert!(cuts >= min_cuts, "{cuts} cuts");
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
    let (ws, drum0) = free_block_run(None, 6);
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
        derivative_time: 0.0,
        inertia: 300.0,
        force: Arc::new(|_| 4.0e3),
        damping: 2.0e3,
        brake: Some((1.0e3, 0.02)),
    };
    let (ws, _) = free_block_run(Some(drum), 5);
    assert!(
        ws.dissipated > 0.0,
        "the drum dissipated {} J",
        ws.dissipated
    );
}

/// The drum of [`drum_with_dynamics_on_a_free_turning_body_keeps_an_exact_balance`] with a
/// derivative part (`τ` = 0.2 s, 40 times the step): its pull on the turning body's drum node
/// enters its row with the gain `1 + τ/h`, its work is the motor's, and every step's balance
/// holds to 1e-12 of the energy scale ([`free_block_run`], 2.8 m paid out, 3 cuts); the
/// previous pull is recorded after every step.
#[test]
fn a_drum_with_a_derivative_part_on_a_free_turning_body_keeps_an_exact_balance() {
    let drum = WinchDrum {
        derivative_time: 0.2,
        inertia: 300.0,
        force: Arc::new(|_| 4.0e3),
        damping: 2.0e3,
        brake: Some((1.0e3, 0.02)),
    };
    let (ws, _) = free_block_run(Some(drum), 3);
    assert_eq!(ws.pull_step, 0.005);
    assert!(ws.pull > 0.0 && ws.dissipated > 0.0, "{ws:?}");
}

/// After 3 s (1.2 m paid out: the body holds the drum node that a cut brought off the drum),
/// the Jacobian of the next step's residual at an increment moved off the predictor (the free
/// nodes by up to 1 mm, the body by up to 3 mm and 3 mrad) against central differences along
/// a direction in the free components and the body's slots: the largest difference is below
/// 1e-6 of the largest entry of `J·d` (measured 1.3e-8; 2.7e-11 in the body's rows).
#[test]
fn a_drum_on_a_body_has_the_jacobian_of_its_differences() {
    let worst = body_drum_jacobian(None, 600);
    assert!(worst < 1e-6, "Jacobian off by {worst:e} of the scale");
}

/// As [`a_drum_on_a_body_has_the_jacobian_of_its_differences`] with a drum of its own on
/// the block (200 kg at the rope, a motor pulling 4.5 kN, damping 2 kN·s/m and a 3 kN brake
/// slipping at 5 cm/s), whose payout is a slot of the step: its row against the body's slots
/// and the body's rows against it too, after 2 s (the hook's pull paying the rope out).
/// Measured 8e-11, 3e-11 in the body's and the drum's rows.
#[test]
fn a_drum_with_dynamics_on_a_body_has_the_jacobian_of_its_differences() {
    let worst = body_drum_jacobian(Some(jacobian_drum(0.0)), 400);
    assert!(worst < 1e-6, "Jacobian off by {worst:e} of the scale");
}

/// The drum of the Jacobian tests: 200 kg at the rope, a motor pulling 4.5 kN (growing
/// 100 N/s), damping 2 kN·s/m, a 3 kN brake slipping at 5 cm/s and the derivative time `tau`
/// [s].
fn jacobian_drum(tau: f64) -> WinchDrum {
    WinchDrum {
        derivative_time: tau,
        inertia: 200.0,
        force: Arc::new(|t| 4.5e3 + 100.0 * t),
        damping: 2.0e3,
        brake: Some((3.0e3, 0.05)),
    }
}

/// The largest difference between the step's Jacobian along a direction and the central
/// differences of its residual, relative to the largest entry of `J·d`, for the block with
/// `drum` after `steps` steps (elements brought off the drum by then), at an increment moved
/// off the predictor: the free nodes by up to 1 mm, the body by 2 mm and 3 mrad, a drum's
/// payout by 3 mm.
fn body_drum_jacobian(drum: Option<WinchDrum>, steps: usize) -> f64 {
    jacobian_after(block_with_a_winch(drum, steady), steps, 0.005)
}

/// The worst difference of [`body_drum_jacobian`] for `sim` after `steps` steps of `h` [s]
/// (in 2D the rotation slot's second entry and a drum slot's entries after the first are
/// placeholders, left out).
fn jacobian_after<const D: usize>(mut sim: Simulation<D, Material>, steps: usize, h: f64) -> f64 {
    let start = sim.run.winches[0].drum;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    assert!(
        sim.run.winches[0].drum < start,
        "cuts brought elements off the drum"
    );
    sim.prepare_step(h);
    let n = sim.sys.mesh.n_nodes();
    let placeholder = |i: usize, k: usize| (i == n + 1 && D == 2 && k > 0) || (i >= n + 2 && k > 0);
    let wave = |i: usize, a: f64| Vector::<D>::from_fn(|k, _| a * ((3 * i + k) as f64 * 0.7).sin());
    let mut x = sim.x.clone();
    let mut dir = vec![Vector::<D>::zeros(); x.len()];
    for i in 0..x.len() {
        for k in 0..D {
            let free = if i < n {
                sim.sys.free[i][k]
            } else {
                !placeholder(i, k)
            };
            if free {
                // Away from the predictor: nodes by up to 1 mm, the body by up to 3 mm and
                // 3 mrad, a drum's payout by up to 3 mm.
                x[i][k] += wave(i + 1, if i < n { 1e-3 } else { 3e-3 })[k];
                dir[i][k] = wave(i, 1.0)[k];
            }
        }
    }
    let (jd, fd) = sim.jacobian_along(h, (&x, &dir), 1e-7);
    let scale = jd.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let (mut worst, mut worst_body) = (0.0_f64, 0.0_f64);
    for i in 0..x.len() {
        for k in 0..D {
            if (i < n && !sim.sys.free[i][k]) || placeholder(i, k) {
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
        "body drum Jacobian ({D}D): worst {worst:.2e} (body and drum rows {worst_body:.2e}) of {scale:.3e}"
    );
    worst
}

/// A free 3 t boom (2D, 8 m, `J` = 16 000 kg·m²) of [`HungBody`], hung at one end and
/// started swinging, its winch at the other end with 12 m of rope paying out 0.4 m/s.
fn boom_with_a_winch(dynamics: Option<WinchDrum>) -> Simulation<2, Material> {
    let boom = HungBody {
        start: BodyState::new(
            Vector3::new(4.0, -10.5, 0.0),
            Vector3::new(0.3, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.05),
            Vector3::new(0.0, 0.0, 0.1),
        ),
        mass: (3000.0, Vector3::new(16000.0, 16000.0, 16000.0)),
        top: Vector3::new(-4.0, 0.5, 0.0),
        drum: Vector3::new(4.0, -0.5, 0.0),
        fall: 12,
    };
    boom.with_winch(dynamics, steady)
}

/// The Jacobian of [`a_drum_with_dynamics_on_a_body_has_the_jacobian_of_its_differences`]
/// in 2D, on the free boom after 2 s: the plane's slots (a rotation slot `(w_z, 0)`, the
/// drum's `(Δp, 0)`) map the drum's and the body's couplings; below 1e-6 of the scale
/// (measured 4e-10, 2e-11 in the body's and the drum's rows).
#[test]
fn a_drum_with_dynamics_on_a_body_in_2d_has_the_jacobian_of_its_differences() {
    let worst = jacobian_after(boom_with_a_winch(Some(jacobian_drum(0.0))), 400, 0.005);
    assert!(worst < 1e-6, "Jacobian off by {worst:e} of the scale");
}

/// The drum's row with a derivative part (`τ` = 0.2 s, the pull's derivatives times
/// `1 + τ/h` = 41 in the drum's row, through the body's slots too), on the free block (3D)
/// after 2 s and the free boom (2D) after 2 s: below 1e-6 of the scale.
#[test]
fn a_drum_with_a_derivative_part_on_a_body_has_the_jacobian_of_its_differences() {
    let worst = body_drum_jacobian(Some(jacobian_drum(0.2)), 400);
    assert!(worst < 1e-6, "3D: Jacobian off by {worst:e} of the scale");
    let worst = jacobian_after(boom_with_a_winch(Some(jacobian_drum(0.2))), 400, 0.005);
    assert!(worst < 1e-6, "2D: Jacobian off by {worst:e} of the scale");
}

/// A flat checkpoint (the checkpoint file's form) of the block after cuts fits the run, with
/// its drum node on the path from the body's point; moved 1 µm off that path, it is refused
/// naming the winch.
#[test]
fn a_flat_checkpoint_puts_the_drum_node_on_the_bodys_path() {
    let mut sim = block_with_a_winch(None, steady);
    for _ in 0..400 {
        sim.step().unwrap();
    }
    let flat = sim.flat_checkpoint();
    assert!(flat.check_fits(&sim, 10.0).is_ok());
    let ws = sim.run.winches[0];
    let d = sim.sys.winches[0].drum_node(&ws);
    let mut off = flat;
    off.r[3 * d + 2] += 1e-6;
    let err = off.check_fits(&sim, 10.0).unwrap_err();
    assert!(err.contains("(winch \"winch\"): its drum node"), "{err}");
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
