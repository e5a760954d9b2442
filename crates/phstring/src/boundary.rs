//! Boundary conditions and ports (docs/method.md §2 and §4, paper Remarks 3 and 4).
//!
//! * A **fixed** node keeps (some of) its position components at their initial values
//!   (Dirichlet). Its port has the velocity (zero) as input and the reaction force as output.
//! * A **load** applies a nodal force `F(t)` [N] (Neumann). Its port has the force as input
//!   and the node velocity as output. The discrete-gradient scheme evaluates `F` at the mid
//!   time `t_{n+½}` (docs/method.md §5).
//! * A **feedback** port ([`FeedbackLoad`]) is a load whose force is a law of the port's own
//!   output and state, `u = F(t, r, y)` ([`PortLaw`]): damping injection, PD tracking
//!   ([`PdLaw`]). It is evaluated at the mid-step inside Newton, so its power is part of the
//!   exact energy balance (docs/method.md §18).
//! * A load's force or a moving support's path can be **held** from outside a run (a
//!   controller, a co-simulation master): [`PositionRamp`] and the input API of
//!   `Simulation` (`set_load_force`, `set_motion_target`, module `inputs`).

use std::fmt;
use std::sync::Arc;

use nalgebra::{SMatrix, SVector};

/// A nodal force signal `t ↦ F(t)` [s ↦ N].
pub type ForceFn<const D: usize> = Arc<dyn Fn(f64) -> SVector<f64, D> + Send + Sync>;

/// A Dirichlet condition: the listed components of `node` stay at their initial position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed<const D: usize> {
    /// Node index.
    pub node: usize,
    /// Which components (x, y, z) are fixed.
    pub components: [bool; D],
}

impl<const D: usize> Fixed<D> {
    /// All components of `node` fixed.
    pub fn node(node: usize) -> Self {
        Self {
            node,
            components: [true; D],
        }
    }
}

/// A Neumann condition: a nodal force `F(t)` [N] acting on `node`.
#[derive(Clone)]
pub struct NodalLoad<const D: usize> {
    /// Node index.
    pub node: usize,
    /// The force signal.
    pub force: ForceFn<D>,
}

impl<const D: usize> NodalLoad<D> {
    /// A load from any function of time.
    pub fn new(
        node: usize,
        force: impl Fn(f64) -> SVector<f64, D> + Send + Sync + 'static,
    ) -> Self {
        Self {
            node,
            force: Arc::new(force),
        }
    }
}

impl<const D: usize> fmt::Debug for NodalLoad<D> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("NodalLoad")
            .field("node", &self.node)
            .finish_non_exhaustive()
    }
}

/// A position signal `t ↦ x(t)` [s ↦ m].
pub type PositionFn = Arc<dyn Fn(f64) -> f64 + Send + Sync>;

/// A velocity signal `t ↦ ẋ(t)` [s ↦ m/s].
pub type RateFn = Arc<dyn Fn(f64) -> f64 + Send + Sync>;

/// Prescribed motion (paper Remarks 3–4, velocity in / force out): component `component` of
/// `node` follows the absolute position `position(t)` [m], which must equal the initial
/// position at `t = 0`. Its port has the mid-step velocity as input and the reaction force
/// as output, and their power enters the energy balance. The node's velocity state follows
/// the motion's own velocity [`Motion::velocity`] (from `t = 0` on): the change of kinetic
/// energy that this imposes after each step is energy the motion supplies (docs/method.md
/// §14, eq. (14.5)).
#[derive(Clone)]
pub struct Motion {
    /// Node index.
    pub node: usize,
    /// Component (0 = x, 1 = y, 2 = z).
    pub component: usize,
    /// The absolute position signal.
    pub position: PositionFn,
    /// The exact velocity `ẋ(t)` [m/s] of `position`, where it is known (a table's
    /// interpolant, [`Motion::sampled`]); `None`: [`Motion::velocity`] differentiates
    /// `position` numerically.
    pub rate: Option<RateFn>,
}

impl Motion {
    /// Component `component` of `node` follows `position(t)` [m].
    pub fn new(
        node: usize,
        component: usize,
        position: impl Fn(f64) -> f64 + Send + Sync + 'static,
    ) -> Self {
        Self {
            node,
            component,
            position: Arc::new(position),
            rate: None,
        }
    }

    /// Component `component` of `node` follows `position(t)` [m] whose exact velocity is
    /// `rate(t)` [m/s] (the caller's promise: `rate` is the derivative of `position`).
    pub fn with_rate(
        node: usize,
        component: usize,
        position: impl Fn(f64) -> f64 + Send + Sync + 'static,
        rate: impl Fn(f64) -> f64 + Send + Sync + 'static,
    ) -> Self {
        Self {
            node,
            component,
            position: Arc::new(position),
            rate: Some(Arc::new(rate)),
        }
    }

    /// Component `component` of `node` follows the sampled signal `path` [s ↦ m]
    /// (docs/method.md §14, motion tables): position and velocity from the same C¹
    /// interpolant.
    pub fn sampled(node: usize, component: usize, path: crate::signal::Sampled) -> Self {
        let path = Arc::new(path);
        let p = path.clone();
        Self::with_rate(node, component, move |t| p.value(t), move |t| path.rate(t))
    }
}

/// Step [s] of the backward difference with which [`Motion::velocity`] differentiates a
/// position signal. At 1e-6 s the truncation error of a motion with a period of a second or
/// more is below 1e-11 of its speed, and the rounding error of positions of order 100 m below
/// 1e-7 m/s.
pub const MOTION_VELOCITY_DT: f64 = 1e-6;

impl Motion {
    /// The velocity `ẋ(t)` [m/s] of the prescribed position: the exact [`Motion::rate`]
    /// where it is given; otherwise from the left, the second-order backward difference
    /// `(3x(t) − 4x(t − δ) + x(t − 2δ)) / 2δ` with `δ = MOTION_VELOCITY_DT`, one-sided
    /// forward where the signal is not finite before `t`. From the left, so that a signal
    /// that is straight over the last step (an FMU's ramp to the value its master set)
    /// gives that step's slope exactly. The stepper holds the node's velocity state at this
    /// value; NaN if the signal is not finite around `t`.
    pub fn velocity(&self, t: f64) -> f64 {
        if let Some(rate) = &self.rate {
            return rate(t);
        }
        let d = MOTION_VELOCITY_DT;
        let x0 = (self.position)(t);
        let (x1, x2) = ((self.position)(t - d), (self.position)(t - 2.0 * d));
        if x1.is_finite() && x2.is_finite() {
            (3.0 * x0 - 4.0 * x1 + x2) / (2.0 * d)
        } else {
            (-3.0 * x0 + 4.0 * (self.position)(t + d) - (self.position)(t + 2.0 * d)) / (2.0 * d)
        }
    }
}

impl fmt::Debug for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Motion")
            .field("node", &self.node)
            .field("component", &self.component)
            .finish_non_exhaustive()
    }
}

/// A straight path of a moving support: from `from` [m] at `t0` [s] to `to` [m] at `t1` [s]
/// at constant speed, at rest at `from` before `t0` and at `to` from `t1` on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionRamp {
    /// Start time [s].
    pub t0: f64,
    /// End time [s] (`t1 ≥ t0`).
    pub t1: f64,
    /// Position at `t0` [m].
    pub from: f64,
    /// Position at `t1` [m].
    pub to: f64,
}

impl PositionRamp {
    /// At rest at `x` [m] (at all times).
    pub fn at(x: f64) -> Self {
        Self {
            t0: 0.0,
            t1: 0.0,
            from: x,
            to: x,
        }
    }

    /// Position [m] at time `t` [s]. A time within `1e-9 (t1 − t0)` before `t1` (a step
    /// whose end time is rounded just short of the ramp's end) is at `to` exactly.
    pub fn position(&self, t: f64) -> f64 {
        if t >= self.t1 - 1e-9 * (self.t1 - self.t0) {
            self.to
        } else if t <= self.t0 {
            self.from
        } else {
            self.from + (self.to - self.from) * ((t - self.t0) / (self.t1 - self.t0))
        }
    }
}

/// A load's force held by [`crate::Simulation::set_load_force`].
#[derive(Clone)]
pub(crate) struct HeldForce<const D: usize> {
    /// The force [N].
    pub(crate) force: SVector<f64, D>,
    /// The load's signal before it was held, put back by
    /// [`crate::Simulation::release_load_force`].
    pub(crate) signal: ForceFn<D>,
}

/// A motion's ramp set by [`crate::Simulation::set_motion_target`] or
/// [`crate::Simulation::set_motion_ramp`].
#[derive(Clone)]
pub(crate) struct HeldMotion {
    /// The ramp.
    pub(crate) ramp: PositionRamp,
    /// The motion's signal before it was held, put back by
    /// [`crate::Simulation::release_motion`].
    pub(crate) signal: PositionFn,
    /// That signal's exact velocity, if it had one.
    pub(crate) rate: Option<RateFn>,
}

/// The inputs held on a running [`crate::Simulation`], per load and per motion (`None`: the
/// problem's own signal).
#[derive(Clone, Default)]
pub(crate) struct HeldInputs<const D: usize> {
    /// Per load (grown as loads are held).
    pub(crate) loads: Vec<Option<HeldForce<D>>>,
    /// Per motion (grown as motions are held).
    pub(crate) motions: Vec<Option<HeldMotion>>,
}

/// A user port law: the force `u = F(t, r, y)` [N] on a port node as a function of the time
/// `t` [s], the node's position `r` [m] and the port output `y` (the node's velocity) [m/s],
/// with its derivatives. The stepper evaluates it at the mid-step, `t_{n+½}`,
/// `r_{n+½} = (r_n + r_{n+1})/2` and `y = v_{n+½} = (r_{n+1} − r_n)/h`, inside Newton.
pub trait PortLaw<const D: usize>: Send + Sync {
    /// The force [N].
    fn force(&self, t: f64, r: &SVector<f64, D>, y: &SVector<f64, D>) -> SVector<f64, D>;
    /// The derivatives `(∂F/∂r [N/m], ∂F/∂y [N·s/m])` at the same arguments.
    fn jacobian(
        &self,
        t: f64,
        r: &SVector<f64, D>,
        y: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SMatrix<f64, D, D>);
}

/// A reference-path signal `t ↦ r_ref(t)` [s ↦ m] or its velocity [s ↦ m/s].
pub type PathFn<const D: usize> = Arc<dyn Fn(f64) -> SVector<f64, D> + Send + Sync>;

/// PD tracking of a reference path with diagonal gains:
/// `u = K_p (r_ref(t) − r) − K_d (y − v_ref(t))`. With `K_p = 0` and `v_ref = 0` it is damping
/// injection `u = −K_d y`, which is passive: its supplied energy `h u·y = −h y·K_d y ≤ 0`.
/// A PD law is a spring (`K_p`) and a dashpot (`K_d`) to the moving point `r_ref`: control by
/// interconnection.
#[derive(Clone)]
pub struct PdLaw<const D: usize> {
    /// Proportional gains per component [N/m] (≥ 0).
    pub kp: SVector<f64, D>,
    /// Derivative gains per component [N·s/m] (≥ 0).
    pub kd: SVector<f64, D>,
    /// Reference position `r_ref(t)` [m].
    pub r_ref: PathFn<D>,
    /// Reference velocity `v_ref(t)` [m/s].
    pub v_ref: PathFn<D>,
}

impl<const D: usize> PdLaw<D> {
    /// Damping injection `u = −K_d y` with the same gain `kd` [N·s/m] in every component.
    pub fn damping_injection(kd: f64) -> Self {
        Self {
            kp: SVector::zeros(),
            kd: SVector::from_element(kd),
            r_ref: Arc::new(|_| SVector::zeros()),
            v_ref: Arc::new(|_| SVector::zeros()),
        }
    }
    /// PD tracking of `r_ref` [m] with velocity `v_ref` [m/s], gains `kp` [N/m] and `kd`
    /// [N·s/m] in every component.
    pub fn tracking(
        kp: f64,
        kd: f64,
        r_ref: impl Fn(f64) -> SVector<f64, D> + Send + Sync + 'static,
        v_ref: impl Fn(f64) -> SVector<f64, D> + Send + Sync + 'static,
    ) -> Self {
        Self {
            kp: SVector::from_element(kp),
            kd: SVector::from_element(kd),
            r_ref: Arc::new(r_ref),
            v_ref: Arc::new(v_ref),
        }
    }
}

impl<const D: usize> PortLaw<D> for PdLaw<D> {
    fn force(&self, t: f64, r: &SVector<f64, D>, y: &SVector<f64, D>) -> SVector<f64, D> {
        let (rr, vr) = ((self.r_ref)(t), (self.v_ref)(t));
        self.kp.component_mul(&(rr - r)) - self.kd.component_mul(&(y - vr))
    }
    fn jacobian(
        &self,
        _t: f64,
        _r: &SVector<f64, D>,
        _y: &SVector<f64, D>,
    ) -> (SMatrix<f64, D, D>, SMatrix<f64, D, D>) {
        (
            SMatrix::from_diagonal(&(-self.kp)),
            SMatrix::from_diagonal(&(-self.kd)),
        )
    }
}

impl<const D: usize> fmt::Debug for PdLaw<D> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PdLaw")
            .field("kp", &self.kp)
            .field("kd", &self.kd)
            .finish_non_exhaustive()
    }
}

/// A feedback port: the force on `node` is the law `law` of the port's output
/// (force in, velocity out, like a [`NodalLoad`]).
#[derive(Clone)]
pub struct FeedbackLoad<const D: usize> {
    /// Node index.
    pub node: usize,
    /// The port law.
    pub law: Arc<dyn PortLaw<D>>,
}

impl<const D: usize> FeedbackLoad<D> {
    /// A feedback port at `node` with `law`.
    pub fn new(node: usize, law: impl PortLaw<D> + 'static) -> Self {
        Self {
            node,
            law: Arc::new(law),
        }
    }
}

impl<const D: usize> fmt::Debug for FeedbackLoad<D> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FeedbackLoad")
            .field("node", &self.node)
            .finish_non_exhaustive()
    }
}

/// All boundary conditions of a problem.
#[derive(Debug, Clone, Default)]
pub struct Boundary<const D: usize> {
    /// Dirichlet conditions.
    pub fixed: Vec<Fixed<D>>,
    /// Neumann conditions.
    pub loads: Vec<NodalLoad<D>>,
    /// Prescribed motions (moving supports).
    pub motions: Vec<Motion>,
    /// Feedback ports (force laws of the port output).
    pub feedback: Vec<FeedbackLoad<D>>,
}

/// What a port's input is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PortKind {
    /// Force input [N], velocity output [m/s] (a loaded node).
    Force,
    /// Velocity input [m/s], reaction-force output [N] (a fixed node or one whose motion is
    /// prescribed).
    Velocity,
}

/// Input and output of one port over the last step, both at the mid time `t_{n+½}` (for
/// `dg4`, means over the sub-steps).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortSample<const D: usize> {
    /// Node index.
    pub node: usize,
    /// Port type.
    pub kind: PortKind,
    /// Input `û_{n+½}`: force [N] or velocity [m/s].
    pub input: SVector<f64, D>,
    /// Output `ŷ_{n+½}`: velocity [m/s] or reaction force [N].
    pub output: SVector<f64, D>,
    /// Mean power over the step [W]: `û·ŷ` of a single step; for `dg4` the sub-steps'
    /// `Σ_k h_k û_k·ŷ_k / h`, with `input` and `output` their `h_k`-weighted means.
    pub mean_power: f64,
}

impl<const D: usize> PortSample<D> {
    /// Power [W] flowing into the string through this port over the last step (positive
    /// into the string): `h` times it is the energy the port supplied.
    pub fn power(&self) -> f64 {
        self.mean_power
    }
}
