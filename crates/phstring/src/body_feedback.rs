//! Feedback on a rigid body's wrench port (docs/method.md §22, "Feedback on a body"): a
//! force and a torque that are a law of the port's own output (the mid-step velocity
//! `Δx/h` and angular velocity `R_n w/h`) and of the body's pose over the step, evaluated
//! inside Newton so that their work is the port's supply in the exact energy balance.
//!
//! The law ([`BodyFeedback`]) is PD on the pose with damping, gains per space axis:
//!
//! * force `F = K_p (x_ref − x_{n+½}) − K_d (Δx/h − v_ref)`, `x_{n+½} = x_n + Δx/2`;
//! * torque `τ = R_n g(w) − K_{d,r} (R_n w/h − ω_ref)`, where `g` is the exact discrete
//!   gradient over the Cayley turn `w` of the rotational spring potential
//!   `V(R) = tr(G (I − R R_refᵀ))`, `G = ½ tr(K_{p,r}) I − K_{p,r}`; for a rotation `E = R R_refᵀ`
//!   by the angle `θ` about the unit axis `n` (space axes) `V = (1 − cos θ) nᵀ K_{p,r} n`.
//!
//! With zero proportional gains it is damping injection: its supply
//! `h (F·Δx/h + τ·R_n w/h)` is a sum of non-positive products, ≤ 0 on every step exactly.
//!
//! This module imports no other module of the crate (the bodies' modules use it).

use std::sync::Arc;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// A 3-vector [m, m/s, rad/s, N or N·m].
type Vec3 = Vector3<f64>;
/// A 3×3 matrix.
type Mat3 = Matrix3<f64>;

/// A reference pose `t ↦ (x_ref [m], R_ref)` [s ↦ m, rotation body axes to space].
pub type ReferencePoseFn = Arc<dyn Fn(f64) -> (Vec3, UnitQuaternion<f64>) + Send + Sync>;
/// A reference twist `t ↦ (v_ref [m/s], ω_ref [rad/s])`, both in space axes.
pub type ReferenceTwistFn = Arc<dyn Fn(f64) -> (Vec3, Vec3) + Send + Sync>;

/// A feedback law on a rigid body's wrench port: PD on the pose with damping injection,
/// diagonal gains in space axes (docs/method.md §22, "Feedback on a body"). With all
/// proportional gains zero and zero reference rates it is damping injection, which is
/// passive.
#[derive(Clone)]
pub struct BodyFeedback {
    /// Translational proportional gains per space axis [N/m] (≥ 0).
    pub kp: Vec3,
    /// Translational derivative gains per space axis [N·s/m] (≥ 0).
    pub kd: Vec3,
    /// Rotational proportional gains per space axis [N·m/rad] (≥ 0): the stiffness of the
    /// rotational spring to the reference orientation for small turns.
    pub kp_turn: Vec3,
    /// Rotational derivative gains per space axis [N·m·s/rad] (≥ 0).
    pub kd_turn: Vec3,
    /// The reference pose (position of the centre of mass [m] and orientation) at time `t`.
    pub reference: ReferencePoseFn,
    /// The reference velocity [m/s] and angular velocity [rad/s] (space axes) at time `t`
    /// (used by the derivative terms; the caller chooses them, usually the pose's rate).
    pub reference_rate: ReferenceTwistFn,
}

impl std::fmt::Debug for BodyFeedback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BodyFeedback")
            .field("kp", &self.kp)
            .field("kd", &self.kd)
            .field("kp_turn", &self.kp_turn)
            .field("kd_turn", &self.kd_turn)
            .finish_non_exhaustive()
    }
}

/// The reference of a [`BodyFeedback`] evaluated at one time (the step's mid time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeedbackTarget {
    /// Reference position of the centre of mass [m].
    pub position: Vec3,
    /// Reference orientation (body axes to space) as a rotation matrix.
    pub orientation: Mat3,
    /// Reference velocity [m/s].
    pub velocity: Vec3,
    /// Reference angular velocity [rad/s], space axes.
    pub omega: Vec3,
}

impl FeedbackTarget {
    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.position
            .iter()
            .chain(self.orientation.iter())
            .chain(self.velocity.iter())
            .chain(self.omega.iter())
            .all(|x| x.is_finite())
    }
}

/// The feedback wrench of one step and its derivatives by the step's unknowns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeedbackWrench {
    /// Force [N] at the centre of mass, space axes.
    pub force: Vec3,
    /// Torque [N·m], space axes.
    pub torque: Vec3,
    /// `∂F/∂Δx` [N/m] (the force does not depend on `w`).
    pub d_force: Mat3,
    /// `∂τ/∂w` [N·m] (the torque does not depend on `Δx`).
    pub d_torque: Mat3,
}

impl BodyFeedback {
    /// Damping injection: `F = −k_d Δx/h`, `τ = −k_{d,r} R_n w/h`, the same gain `kd` [N·s/m]
    /// on every axis and `kd_turn` [N·m·s/rad] on every rotation axis.
    pub fn damping_injection(kd: f64, kd_turn: f64) -> Self {
        Self::holding(
            (0.0, kd),
            (0.0, kd_turn),
            Vec3::zeros(),
            UnitQuaternion::identity(),
        )
    }

    /// PD holding the constant pose `(position [m], orientation)` with gains
    /// `(kp [N/m], kd [N·s/m])` on every axis and `(kp_turn [N·m/rad], kd_turn [N·m·s/rad])`
    /// on every rotation axis.
    pub fn holding(
        (kp, kd): (f64, f64),
        (kp_turn, kd_turn): (f64, f64),
        position: Vec3,
        orientation: UnitQuaternion<f64>,
    ) -> Self {
        Self {
            kp: Vec3::from_element(kp),
            kd: Vec3::from_element(kd),
            kp_turn: Vec3::from_element(kp_turn),
            kd_turn: Vec3::from_element(kd_turn),
            reference: Arc::new(move |_| (position, orientation)),
            reference_rate: Arc::new(|_| (Vec3::zeros(), Vec3::zeros())),
        }
    }

    /// The first gain that is negative or not finite, as `(name, value)`; `None`: all valid.
    pub fn bad_gain(&self) -> Option<(&'static str, f64)> {
        let gains = [
            ("kp", &self.kp),
            ("kd", &self.kd),
            ("kp_turn", &self.kp_turn),
            ("kd_turn", &self.kd_turn),
        ];
        gains.into_iter().find_map(|(name, g)| {
            g.iter()
                .find(|x| !(**x >= 0.0 && x.is_finite()))
                .map(|&x| (name, x))
        })
    }

    /// The gains of a plane body (network in 2D, plane `z = 0`): the translational gains'
    /// `z` and the rotational gains about `x` and `y` set to zero.
    pub fn planar(&self) -> Self {
        let mut out = self.clone();
        out.kp.z = 0.0;
        out.kd.z = 0.0;
        for g in [&mut out.kp_turn, &mut out.kd_turn] {
            g.x = 0.0;
            g.y = 0.0;
        }
        out
    }

    /// The reference at time `t` [s].
    pub fn target(&self, t: f64) -> FeedbackTarget {
        let ((position, q), (velocity, omega)) = ((self.reference)(t), (self.reference_rate)(t));
        FeedbackTarget {
            position,
            orientation: *q.to_rotation_matrix().matrix(),
            velocity,
            omega,
        }
    }

    /// The rotational spring's `G = ½ tr(K_{p,r}) I − K_{p,r}`.
    fn g_matrix(&self) -> Mat3 {
        let k = Mat3::from_diagonal(&self.kp_turn);
        Mat3::identity() * (0.5 * k.trace()) - k
    }

    /// The potential of the proportional part at the pose `(x [m], R)` against `target`
    /// [J]: `½ (x − x_ref)·K_p (x − x_ref) + tr(G (I − R R_refᵀ))` (≥ 0). Not part of `Ĥ`:
    /// the port's supply carries the law's work (docs/method.md §22); a constant reference
    /// makes the supply of the proportional part minus this potential's change exactly.
    pub fn potential(&self, target: &FeedbackTarget, x: &Vec3, q: &UnitQuaternion<f64>) -> f64 {
        let e = x - target.position;
        let r = q.to_rotation_matrix();
        let turn =
            self.g_matrix() * (Mat3::identity() - r.matrix() * target.orientation.transpose());
        0.5 * e.dot(&self.kp.component_mul(&e)) + turn.trace()
    }

    /// The wrench over a step of `h` [s] from the pose `(x_n [m], R_n)` with the unknowns
    /// `Δx` [m] and Cayley vector `w` (`R_{n+1} = R_n cay(w)`), against `target` (the
    /// reference at `t_{n+½}`), and its derivatives.
    pub fn wrench(
        &self,
        target: &FeedbackTarget,
        (x, q): (&Vec3, &UnitQuaternion<f64>),
        h: f64,
        (dx, w): (&Vec3, &Vec3),
    ) -> FeedbackWrench {
        let inv_h = 1.0 / h;
        let mid = x + dx * 0.5;
        let force = self.kp.component_mul(&(target.position - mid))
            - self.kd.component_mul(&(dx * inv_h - target.velocity));
        let d_force = -Mat3::from_diagonal(&(self.kp * 0.5 + self.kd * inv_h));
        let rot = *q.to_rotation_matrix().matrix();
        // The output ω = R_n w/h formed as the port sample forms it.
        let turned = q.transform_vector(w);
        let damping = -self.kd_turn.component_mul(&(turned * inv_h - target.omega));
        let (g, dg) = self.spring_gradient(target, &rot, w);
        FeedbackWrench {
            force,
            torque: rot * g + damping,
            d_force,
            d_torque: rot * dg - Mat3::from_diagonal(&self.kd_turn) * rot * inv_h,
        }
    }

    /// The exact discrete gradient `g` (body axes) of the rotational spring over the turn
    /// `w` from `R_n = rot`, `g·w = V(R_n) − V(R_n cay(w))` for every `w`, and `∂g/∂w`:
    /// with `B = R_refᵀ G R_n`, `β = vee(½(B − Bᵀ))`, `S = ½(B + Bᵀ) − tr(B) I`,
    /// `c = 4/(4 + |w|²)`: `g = c (−2β + ½ S w)`.
    fn spring_gradient(&self, target: &FeedbackTarget, rot: &Mat3, w: &Vec3) -> (Vec3, Mat3) {
        if self.kp_turn == Vec3::zeros() {
            return (Vec3::zeros(), Mat3::zeros());
        }
        let b = target.orientation.transpose() * self.g_matrix() * rot;
        let beta = Vec3::new(
            b[(2, 1)] - b[(1, 2)],
            b[(0, 2)] - b[(2, 0)],
            b[(1, 0)] - b[(0, 1)],
        ) * 0.5;
        let s = (b + b.transpose()) * 0.5 - Mat3::identity() * b.trace();
        let c = 4.0 / (4.0 + w.norm_squared());
        let p = -beta * 2.0 + s * w * 0.5;
        let g = p * c;
        // ∂c/∂w = −½ c² w.
        let dg = s * (0.5 * c) - p * w.transpose() * (0.5 * c * c);
        (g, dg)
    }
}

#[cfg(test)]
mod tests {
    //! The law's discrete gradient and derivatives against the potential and finite
    //! differences.

    use super::*;

    fn law() -> BodyFeedback {
        let q_ref = UnitQuaternion::from_euler_angles(0.4, -0.3, 0.9);
        let x_ref = Vec3::new(1.0, -2.0, 3.0);
        BodyFeedback {
            kp: Vec3::new(2e4, 3e4, 5e4),
            kd: Vec3::new(4e3, 1e3, 2e3),
            kp_turn: Vec3::new(6e3, 2e3, 9e3),
            kd_turn: Vec3::new(500.0, 800.0, 300.0),
            reference: Arc::new(move |_| (x_ref, q_ref)),
            reference_rate: Arc::new(|_| (Vec3::new(0.1, 0.0, -0.2), Vec3::new(0.0, 0.3, 0.1))),
        }
    }

    /// The rotational spring's supply `τ_p·R_n w` equals the potential's drop over the
    /// turn to round-off, for small and large turns and beyond 180° from the reference
    /// (the exactness the energy balance of a constant reference relies on).
    #[test]
    fn rotational_spring_is_an_exact_discrete_gradient() {
        let fb = BodyFeedback {
            kd: Vec3::zeros(),
            kd_turn: Vec3::zeros(),
            kp: Vec3::zeros(),
            ..law()
        };
        let target = fb.target(0.0);
        let x = Vec3::zeros();
        for (q, w) in [
            (
                UnitQuaternion::from_euler_angles(0.1, 0.2, -0.3),
                Vec3::new(1e-3, -2e-3, 5e-4),
            ),
            (
                UnitQuaternion::from_euler_angles(1.0, -0.5, 2.0),
                Vec3::new(0.3, 0.8, -0.6),
            ),
            (
                UnitQuaternion::from_euler_angles(3.0, 0.1, -3.0),
                Vec3::new(-2.0, 1.5, 4.0),
            ),
        ] {
            let wr = fb.wrench(&target, (&x, &q), 0.01, (&Vec3::zeros(), &w));
            let next = q * UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
                1.0,
                0.5 * w.x,
                0.5 * w.y,
                0.5 * w.z,
            ));
            let drop = fb.potential(&target, &x, &q) - fb.potential(&target, &x, &next);
            let work = wr.torque.dot(&q.transform_vector(&w));
            // Round-off of sums of terms of size Σ k ≈ 2e4 J.
            assert!(
                (work - drop).abs() <= 1e-10 * 2e4,
                "work {work} vs drop {drop}"
            );
        }
    }

    /// For small turns the potential is `½ θ·K_{p,r} θ` about a space axis, so the torque of
    /// a small turn `θ` from the reference is `−K_{p,r} θ` (to the turn's second order).
    #[test]
    fn small_turn_torque_is_the_stiffness() {
        let fb = BodyFeedback {
            reference: Arc::new(|_| (Vec3::zeros(), UnitQuaternion::identity())),
            ..law()
        };
        let target = fb.target(0.0);
        let theta = Vec3::new(1e-4, -2e-4, 3e-4);
        let q = UnitQuaternion::from_scaled_axis(theta);
        let wr = fb.wrench(
            &target,
            (&Vec3::zeros(), &q),
            1.0,
            (&Vec3::zeros(), &Vec3::zeros()),
        );
        let damping = fb.kd_turn.component_mul(&target.omega);
        let expected = -fb.kp_turn.component_mul(&theta) + damping;
        // Relative error O(|θ|) = 4e-4 from the turn's curvature.
        assert!(
            (wr.torque - expected).norm() <= 1e-3 * fb.kp_turn.component_mul(&theta).norm(),
            "{} vs {expected}",
            wr.torque
        );
    }

    /// `∂F/∂Δx` and `∂τ/∂w` against central differences.
    #[test]
    fn derivatives_match_finite_differences() {
        let fb = law();
        let target = fb.target(0.0);
        let x = Vec3::new(0.5, -1.0, 2.0);
        let q = UnitQuaternion::from_euler_angles(-0.7, 0.2, 2.5);
        let (dx, w) = (Vec3::new(0.01, -0.02, 0.005), Vec3::new(0.2, -0.1, 0.3));
        let h = 0.02;
        let wr = fb.wrench(&target, (&x, &q), h, (&dx, &w));
        let eps = 1e-6;
        for c in 0..3 {
            let e = Vec3::from_fn(|k, _| if k == c { eps } else { 0.0 });
            let fd_f = (fb.wrench(&target, (&x, &q), h, (&(dx + e), &w)).force
                - fb.wrench(&target, (&x, &q), h, (&(dx - e), &w)).force)
                / (2.0 * eps);
            let fd_t = (fb.wrench(&target, (&x, &q), h, (&dx, &(w + e))).torque
                - fb.wrench(&target, (&x, &q), h, (&dx, &(w - e))).torque)
                / (2.0 * eps);
            // Truncation O(eps²)·|g'''| and rounding ε|τ|/eps ≈ 1e-16·1e4/1e-6 = 1e-6.
            assert!((fd_f - wr.d_force.column(c)).norm() <= 1e-6 * wr.d_force.norm());
            assert!(
                (fd_t - wr.d_torque.column(c)).norm() <= 1e-6 * wr.d_torque.norm(),
                "column {c}: {fd_t} vs {}",
                wr.d_torque.column(c)
            );
        }
    }

    /// Damping injection: the supply `F·Δx + τ·R_n w` is ≤ 0 for any step.
    #[test]
    fn damping_injection_supplies_no_energy() {
        let fb = BodyFeedback::damping_injection(3e3, 7e2);
        let target = fb.target(1.0);
        let q = UnitQuaternion::from_euler_angles(0.3, 1.2, -2.0);
        for k in 0..200 {
            let a = k as f64;
            let dx = Vec3::new((a * 0.7).sin(), (a * 1.3).cos(), (a * 0.1).sin()) * 1e-3;
            let w = Vec3::new((a * 0.9).cos(), (a * 0.4).sin(), (a * 2.1).sin()) * 1e-2;
            let wr = fb.wrench(&target, (&Vec3::zeros(), &q), 1e-3, (&dx, &w));
            let supply = wr.force.dot(&dx) + wr.torque.dot(&q.transform_vector(&w));
            assert!(supply <= 0.0, "step {k}: {supply}");
        }
    }
}
