//! The time loop: [`Simulation::step`] advances one step and reports; the caller owns the
//! loop, [`Simulation::run_until`] is a thin convenience over it.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::boundary::{PortKind, PortSample};
use crate::error::{SetupError, StepError};
use crate::integrator::{Scheme, StepEquations, StrainError, element_step};
use crate::linsolve::{LinearSolver, SolverKind};
use crate::material::StoredEnergy;
use crate::newton::{self, NewtonError, NewtonParams, NewtonStats, NewtonWorkspace};
use crate::observe::{
    BALANCE_RTOL, Observer, RunSummary, Settle, SettleWatch, Settled, StepReport,
};

use crate::system::{Energies, Network, PhSystem, State, Vector};
use crate::water::WaterWork;

mod checkpoint;
mod winch;
#[cfg(test)]
mod winch_body_tests;
#[cfg(test)]
mod winch_cut_tests;
pub use checkpoint::{Checkpoint, CheckpointFit, FlatCheckpoint};
pub use winch::WinchSample;

/// Parameters of the time stepper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams {
    /// Time step `h` [s]; with step-size control, the largest step taken.
    pub h: f64,
    /// Scheme (DG or MP).
    pub scheme: Scheme,
    /// Newton parameters.
    pub newton: NewtonParams,
    /// Linear solver.
    pub solver: SolverKind,
    /// Newton's starting guess for the position increment.
    pub predictor: Predictor,
    /// Step-size control.
    pub control: StepControl,
}

impl Default for StepParams {
    fn default() -> Self {
        Self {
            h: 0.01,
            scheme: Scheme::DiscreteGradient,
            newton: NewtonParams::default(),
            solver: SolverKind::Auto,
            predictor: Predictor::default(),
            control: StepControl::default(),
        }
    }
}

/// Largest [`StepControl::max_halvings`]: a floor of `h / 2^60` is already far below any
/// step a simulation can make progress with.
pub const MAX_HALVINGS: u32 = 60;

/// Estimated heap memory [bytes] of a [`Simulation`] of a chain of `n_elements` elements in
/// `dimension` (1, 2 or 3) dimensions with the block-tridiagonal solver, including its
/// [`Problem`] while it is being set up: per node the state `r, v`, the predictor's `a, v_{n−½}`,
/// the step's `Δ`, external forces and reactions, Newton's residual, direction and last
/// iterate, the Jacobian's diagonal block and the two block-Thomas workspaces; per element the
/// strain and the step's new strain, the two off-diagonal Jacobian blocks, the connectivity and the reference length.
/// For the sparse LU solver (any other mesh) add its factors, which this does not count.
/// Measured against the allocator in the tests (within 5 %).
pub fn estimated_memory_bytes(dimension: usize, n_elements: usize) -> u64 {
    let d = dimension as u64;
    let (vector, block) = (8 * d, 8 * d * d);
    let nodes = (n_elements as u64).saturating_add(1);
    // r, v, acc, v_mid, x, f_ext, reaction, f_body, res, dir, x_old: 11 vectors per node;
    // Jacobian diagonal, Newton's Thomas workspace, the solver's: 3 blocks; `free` flags.
    let per_node = 11 * vector + 3 * block + d;
    // C and the step's new C, off-diagonal blocks, [a, b], l.
    let per_element = 16 + 2 * block + 16 + 8;
    // Saturating: the estimate is also asked for unvalidated element counts.
    nodes
        .saturating_mul(per_node)
        .saturating_add((n_elements as u64).saturating_mul(per_element))
}

/// Cost of a time step on a chain with the block-tridiagonal solver [s per element], by
/// dimension 1, 2, 3: (every step, whatever its iterations; each Newton iteration). A step
/// of `k` iterations costs `n_el (c_step + k c_iter)`. `c_iter` is the linear solve
/// (`block_thomas`) with the residual and Jacobian evaluations (`evaluate_nodes`) and the
/// line search of one iteration; `c_step` is what a step evaluates besides its counted
/// iterations (the predictor, the energies and balance of the accepted state, the
/// bookkeeping). Calibration: CPU time (`perf stat -e task-clock`, release build, one core
/// of a shared 2-core machine) of `phstring run` at 25 minus 5 steps (10 and 110 at 1e4
/// elements) with outputs off, `time.adaptive = false`, and 1, 2 or 3 iterations per step
/// (`newton.rtol` 1e-8, default, 1e-14): a 1000 m hanging steel rope (EA = 1e8 N, 2 t at
/// its end, from its equilibrium, h = 0.01 s) in 3D and 2D, and `examples/axial_rod_1d.toml`
/// (h = 1e-3 s). Measured per element-step at 1e5 elements: 3D 278, 435, 631 ns (1, 2, 3
/// iterations), 2D 164, 249, 384 ns, 1D 90 ns (1.1 iterations), 120 ns (2); at 1e4 about
/// 10 % less, at 1e6 (3D, 2 iterations) 429 ns. Fitted and rounded up.
const STEP_SECONDS_PER_ELEMENT: [(f64, f64); 3] =
    [(60e-9, 35e-9), (60e-9, 110e-9), (100e-9, 180e-9)];

/// Estimated wall time of one Newton iteration [s] on a chain of `n_elements` elements in
/// `dimension` dimensions (1, 2 or 3), on one otherwise idle core (release build): `c_iter`
/// of [`STEP_SECONDS_PER_ELEMENT`]. A step costs more than its iterations: see
/// [`estimated_seconds_per_step`].
pub fn estimated_seconds_per_iteration(dimension: usize, n_elements: usize) -> f64 {
    STEP_SECONDS_PER_ELEMENT[dimension.clamp(1, 3) - 1].1 * n_elements as f64
}

/// Estimated wall time of one time step of `iterations` Newton iterations [s] on a chain of
/// `n_elements` elements in `dimension` dimensions (1, 2 or 3), on one otherwise idle core
/// (release build): `n_el (c_step + iterations · c_iter)` with [`STEP_SECONDS_PER_ELEMENT`],
/// so that what a step evaluates besides its counted iterations is included. Steps usually
/// take 2–6 iterations; a shortened or rejected step costs its attempts on top.
pub fn estimated_seconds_per_step(dimension: usize, n_elements: usize, iterations: f64) -> f64 {
    let (step, iteration) = STEP_SECONDS_PER_ELEMENT[dimension.clamp(1, 3) - 1];
    (step + iterations.max(0.0) * iteration) * n_elements as f64
}

/// Newton's starting guess for `Δ = r_{n+1} − r_n`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Predictor {
    /// `Δ = h v_n`.
    Velocity,
    /// `Δ = h v_n + ½ h² a_n` with `a_n = (v_n − v_{n−1})/h_{n−1}` from the previous step
    /// (`a_0 = 0`).
    Acceleration,
    /// `Δ = h v_{n−½}` with the previous step's mid-step velocity `v_{n−½} = Δ_{n−1}/h_{n−1}`
    /// (`h v_0` for the first step). Unlike `h v_n` it is not thrown off by unresolved
    /// high-frequency modes, whose velocity the scheme flips every step. The default.
    #[default]
    MidpointVelocity,
}

/// Automatic step-size control: halve `h` when a step fails (Newton does not converge, the
/// line search fails, a strain leaves the material's domain), double it back (up to
/// [`StepParams::h`]) after a run of easy steps. Every accepted step satisfies the scheme's
/// equations, so the DG energy balance holds for every accepted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepControl {
    /// On (`true`) or a fixed-step run that stops at the first failure (`false`).
    pub adaptive: bool,
    /// The step-size floor is `h / 2^max_halvings`: a step that fails there ends the run.
    pub max_halvings: u32,
    /// Double `h` after this many successive easy steps.
    pub grow_after: usize,
    /// A step is easy if it needs at most this many Newton iterations and no backtracking.
    pub easy_iterations: usize,
    /// Error control (docs/method.md §19), relative tolerance (dimensionless); 0 with
    /// `atol = 0`: off (the default), and `h` is chosen for solvability alone as above.
    pub rtol: f64,
    /// Error control, absolute tolerance on positions [m]; velocities get `atol / h_max`
    /// [m/s] (`h_max` = [`StepParams::h`]: a velocity error that moves a node by `atol` in one
    /// largest step).
    pub atol: f64,
    /// Error control: the tolerance bounds each step's local error (`true`), instead of its
    /// error per unit step, the local error times `h_max / h` (`false`, the default). Per
    /// step, a short transient is taken with fewer small steps; with `dg` and `mp` the global
    /// error then scales like `tol^(2/3)` instead of in proportion to the tolerance
    /// (docs/method.md §19). No effect without error control (`rtol = atol = 0`).
    pub error_per_step: bool,
}

impl StepControl {
    /// The default control with error control at `rtol` (dimensionless) and `atol` [m].
    pub fn with_tolerance(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            ..Self::default()
        }
    }

    /// Whether error control is on (`rtol > 0` or `atol > 0`).
    pub fn error_control(&self) -> bool {
        self.rtol > 0.0 || self.atol > 0.0
    }
}

impl Default for StepControl {
    fn default() -> Self {
        Self {
            adaptive: true,
            max_halvings: 12,
            grow_after: 2,
            easy_iterations: 6,
            rtol: 0.0,
            atol: 0.0,
            error_per_step: false,
        }
    }
}

/// A running simulation: system, state, time and all workspaces.
pub struct Simulation<const D: usize, M> {
    sys: PhSystem<D, M>,
    params: StepParams,
    /// The run's state and progress: what a checkpoint saves and a restore puts back.
    run: Checkpoint<D>,
    energies: Energies,
    // Workspaces (allocated once).
    x: Vec<Vector<D>>,
    f_ext: Vec<Vector<D>>,
    reaction: Vec<Vector<D>>,
    /// The new strains of the current step, swapped into the state once its energies are
    /// known to be finite.
    c_next: Vec<f64>,
    ports: Vec<PortSample<D>>,
    newton_ws: NewtonWorkspace<D>,
    solver: Box<dyn LinearSolver<D>>,
    /// Set from outside (Ctrl-C) to end the current step between Newton iterations.
    stop: Option<Arc<AtomicBool>>,
    /// The state before the current step, for `dg4` and error control (allocated on first
    /// use, reused after).
    backup: Option<Backup<D>>,
    /// `dg4`: the ports' sums over the sub-steps (a buffer reused from step to step).
    port_sums: Vec<(Vector<D>, Vector<D>, f64)>,
    /// Error control: steps accepted at the step-size floor although their error estimate
    /// exceeded the tolerance.
    over_tolerance: usize,
    /// The port samples before the current step, put back if the step fails after the
    /// ports were formed (a buffer reused from step to step).
    ports_prev: Vec<PortSample<D>>,
    /// Prescribed motions: where the velocity state is held at the motion's own velocity.
    held: HeldVelocities,
    /// Inputs set from outside the run (held forces, ramps of moving supports).
    inputs: crate::boundary::HeldInputs<D>,
    /// `dg4`: the damped seabed contacts that set how many triple jumps a step takes (§19).
    contacts: Vec<crate::integrator::DampedContact>,
    /// The rigid bodies' states at the end of the current step, swapped into the state
    /// when the step is committed.
    bodies_next: Vec<crate::body::BodyState>,
    /// Per body, its wrench port's force [N] and torque [N·m] at the current step's mid time.
    body_wrenches: Vec<(crate::body::Vec3, crate::body::Vec3)>,
    /// Per body, its feedback law's reference at the current step's mid time (`None`: no
    /// law).
    body_targets: Vec<Option<crate::body_feedback::FeedbackTarget>>,
    /// The bodies' wrench port samples of the last step, and of the one before (put back
    /// if a step fails after they were formed).
    body_ports: Vec<crate::body::BodyPortSample>,
    body_ports_prev: Vec<crate::body::BodyPortSample>,
    /// Per body with a held wrench (inputs), the wrench port it had before.
    held_wrenches: Vec<Option<Option<crate::body::BodyWrench>>>,
    /// Per winch, the payout [m] and the energy it supplied [J] in the last step (during a
    /// step, the payout it started from and the energy so far).
    winch_step: Vec<(f64, f64)>,
    /// The size [s] of the last accepted step, which the winches' rates are over.
    winch_h: f64,
    /// `dg4`: per winch, its port's `h_k`-weighted sums of the drum node's velocity and
    /// reaction over the sub-steps (a buffer reused from step to step).
    winch_port_sums: Vec<([f64; 3], [f64; 3])>,
    /// Per winch, the work of its drum node's reaction in the current step [J].
    winch_work: Vec<f64>,
    /// Per winch, its port in the last step: drum node, mid-step velocity, reaction.
    winch_port: Vec<(usize, [f64; 3], [f64; 3])>,
    /// The winch drums' data for the current step (docs/method.md §23.6).
    drum_steps: Vec<crate::winch_step::DrumStep<D>>,
    /// The nodes' increments with the bodies' attached nodes and the drum nodes filled in
    /// from their slots: the step equations' work vector, kept between steps.
    nodes_x: Vec<Vector<D>>,
    /// The buffers of the bodies' rows, kept between steps (no allocation in a step).
    body_scratch: crate::body_step::BodyScratch,
    /// Per winch with a drum (else unused): its payout [m] and payout speed [m/s] at the end
    /// of the current step, the energy its damping and brake dissipated in it [J] and the
    /// energy its motor supplied in it [J].
    drum_next: Vec<winch::DrumNext>,
}

/// The prescribed motions' hold on the velocity state (docs/method.md §14, eq. (14.5)): after each
/// step the velocity of a moving support's component is set to the motion's velocity
/// [`crate::boundary::Motion::velocity`] at the step's end, and the change of kinetic energy
/// this makes is energy supplied through that support's port.
#[derive(Debug, Clone, Default)]
struct HeldVelocities {
    /// Per node: whether a component of it is prescribed.
    moving: Vec<bool>,
    /// The velocity [m/s] each motion holds its component at, at the end of the current step.
    velocity: Vec<f64>,
    /// The mass matrix's entries `(port, i, j, M_ij)` [kg] of the rows `i` of moving nodes,
    /// with the index of node `i`'s port.
    mass: Vec<(usize, usize, usize, f64)>,
}

/// Refuses a feedback law whose gains no double-precision step can resolve against the
/// structure: a stiffness `‖∂u/∂r‖` or `‖∂u/∂y‖/h` [N/m] (at `t = 0` and the initial state)
/// beyond `K/ε`, with `K` the stiffest element's `EA/l` (`EA = 4 W''` at `C = 1` or just
/// above) or a point mass's `2m/h²`. Beyond it the control force changes by more than the
/// structure's own forces when a coordinate changes by one unit of rounding.
fn check_gains<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    state: &State<D>,
    h: f64,
) -> Result<(), SetupError> {
    if sys.boundary.feedback.is_empty() {
        return Ok(());
    }
    let mut stiffness = 0.0f64;
    for (g, _, _, l) in sys.each_element() {
        if let crate::system::Law::String(m) = &g.law {
            let ea = 4.0 * m.d2w(1.0).abs().max(m.d2w(1.01).abs());
            stiffness = stiffness.max(ea / l);
        }
    }
    for &(_, m) in &sys.point_mass {
        stiffness = stiffness.max(2.0 * m / (h * h));
    }
    let limit = stiffness / f64::EPSILON;
    for fb in &sys.boundary.feedback {
        let i = fb.node;
        let (dr, dy) = fb.law.jacobian(0.0, &state.r[i], &state.v[i]);
        for (what, gain) in [
            ("position gain |du/dr|", dr.amax()),
            ("velocity gain |du/dy| / h", dy.amax() / h),
        ] {
            // A NaN gain is refused too.
            if gain.is_nan() || gain > limit {
                return Err(SetupError::UnresolvableGain {
                    node: i,
                    what,
                    gain,
                    stiffness,
                    limit,
                });
            }
        }
    }
    Ok(())
}

impl HeldVelocities {
    /// Sets the velocity of each prescribed component of `state` to its motion's velocity at
    /// `t = 0` and gathers the mass-matrix rows of the moving nodes.
    fn new<const D: usize, M: StoredEnergy>(
        sys: &PhSystem<D, M>,
        state: &mut State<D>,
    ) -> Result<Self, SetupError> {
        let motions = &sys.boundary.motions;
        let n = sys.mesh.n_nodes();
        let mut moving = vec![false; n];
        for (k, m) in motions.iter().enumerate() {
            let v = m.velocity(0.0);
            if !v.is_finite() {
                return Err(SetupError::NotFinite {
                    what: "velocity at t = 0 of prescribed motion",
                    index: k,
                    value: v,
                });
            }
            state.v[m.node][m.component] = v;
            moving[m.node] = true;
        }
        // The moving nodes' ports: after the load and feedback ports, in `constrained` order.
        let first = sys.boundary.loads.len() + sys.boundary.feedback.len();
        let port = |i: usize| first + sys.support_nodes().position(|c| c == i).unwrap_or(0);
        let mut mass = Vec::new();
        for (g, _, [a, b], l) in sys.each_element() {
            let (md, mo) = crate::system::element_mass(g.mass, g.rho_a, l);
            for (i, j) in [(a, b), (b, a)] {
                if moving[i] {
                    mass.extend([(port(i), i, i, md), (port(i), i, j, mo)]);
                }
            }
        }
        for &(i, m) in &sys.point_mass {
            if moving[i] {
                mass.push((port(i), i, i, m));
            }
        }
        mass.retain(|e| e.3 != 0.0);
        Ok(Self {
            moving,
            velocity: vec![0.0; motions.len()],
            mass,
        })
    }

    /// The velocity `v` [m/s] of node `i` with its prescribed components set to the held
    /// velocities.
    fn apply<const D: usize>(
        &self,
        i: usize,
        mut v: Vector<D>,
        motions: &[crate::boundary::Motion],
    ) -> Vector<D> {
        if self.moving[i] {
            for (m, &u) in motions.iter().zip(&self.velocity) {
                if m.node == i {
                    v[m.component] = u;
                }
            }
        }
        v
    }
}

/// Refuses step parameters out of range (step size, tolerances, step-size control).
fn check_params(params: &StepParams) -> Result<(), SetupError> {
    if !(params.h > 0.0 && params.h.is_finite()) {
        return Err(SetupError::NonPositive {
            what: "time step h",
            index: None,
            value: params.h,
        });
    }
    let nw = &params.newton;
    if !(nw.tol > 0.0 && nw.tol.is_finite()) {
        return Err(SetupError::NonPositive {
            what: "Newton tolerance (absolute floor)",
            index: None,
            value: nw.tol,
        });
    }
    if !(nw.rtol >= 0.0 && nw.rtol < 1.0) {
        return Err(SetupError::OutOfRange {
            what: "relative Newton tolerance",
            value: nw.rtol,
            range: "0 <= rtol < 1",
        });
    }
    let c = &params.control;
    for (what, v) in [("time.rtol", c.rtol), ("time.atol [m]", c.atol)] {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(SetupError::OutOfRange {
                what,
                value: v,
                range: "0 <= value < infinity",
            });
        }
    }
    if params.control.max_halvings > MAX_HALVINGS {
        return Err(SetupError::OutOfRange {
            what: "max_halvings",
            value: params.control.max_halvings as f64,
            range: "at most 60 (a floor of time.h / 2^60)",
        });
    }
    Ok(())
}

/// What a step changes, saved to put it back (a failed `dg4` sub-step, a step rejected by
/// error control). Buffers are reused from step to step.
#[derive(Debug, Clone, Default)]
struct Backup<const D: usize> {
    run: Option<Checkpoint<D>>,
    energies: Energies,
    ports: Vec<PortSample<D>>,
    body_ports: Vec<crate::body::BodyPortSample>,
}

impl<const D: usize, M: StoredEnergy> Simulation<D, M> {
    /// Validates `problem`, sets up the solver and starts at time `t = 0`.
    pub fn new(problem: impl Into<Network<D, M>>, params: StepParams) -> Result<Self, SetupError> {
        check_params(&params)?;
        // `PhSystem::new` has checked the state already.
        let (sys, state) = PhSystem::new(problem)?;
        Self::start(sys, state, params)
    }

    /// Starts `sys` from `state` at time `t = 0` (a system built once, e.g. for a static
    /// equilibrium that then starts the run). `state` is checked as [`PhSystem::new`]
    /// checks a problem's initial state ([`PhSystem::check_state`]).
    pub fn from_system(
        sys: PhSystem<D, M>,
        state: State<D>,
        params: StepParams,
    ) -> Result<Self, SetupError> {
        check_params(&params)?;
        sys.check_state(&state)?;
        Self::start(sys, state, params)
    }

    /// Starts `sys` from `state` (both checked) at `t = 0` with `params` (checked).
    fn start(sys: PhSystem<D, M>, state: State<D>, params: StepParams) -> Result<Self, SetupError> {
        let n_el = sys.mesh.n_elements();
        let n = sys.mesh.n_nodes();
        let n_drums = sys.winches.iter().filter(|w| w.drum.is_some()).count();
        let slots = 2 * sys.bodies.len() + n_drums;
        if slots > n_drums && params.control.error_control() {
            return Err(SetupError::Body {
                index: 0,
                name: sys.body_names[0].clone(),
                problem: "error control (rtol, atol) does not cover rigid bodies yet: run \
                          without it (the step size is then controlled for solvability)"
                    .into(),
            });
        }
        winch::check_drum_scheme(&sys, params.scheme)?;
        let mut sys = sys;
        let winch_start = sys.winch_start.clone();
        sys.place_winches(&winch_start);
        let border = crate::body_step::border_pattern(&sys);
        // A drum couples with whichever node its drum element reaches: the bordered solve
        // takes any coupling (docs/method.md §23.6).
        let on_bodies = sys.winches.iter().any(|w| w.body.is_some());
        let solver = if n_drums > 0 || on_bodies {
            crate::linsolve::make_bordered_solver::<D>(params.solver, &sys.mesh, slots)?
        } else {
            crate::linsolve::make_border_solver::<D>(params.solver, &sys.mesh, &border)?
        };
        let mut ports: Vec<PortSample<D>> = sys
            .boundary
            .loads
            .iter()
            .map(|l| PortSample {
                node: l.node,
                kind: PortKind::Force,
                input: Vector::zeros(),
                output: Vector::zeros(),
                mean_power: 0.0,
            })
            .collect();
        ports.extend(sys.boundary.feedback.iter().map(|f| PortSample {
            node: f.node,
            kind: PortKind::Force,
            input: Vector::zeros(),
            output: Vector::zeros(),
            mean_power: 0.0,
        }));
        ports.extend(sys.support_nodes().map(|node| PortSample {
            node,
            kind: PortKind::Velocity,
            input: Vector::zeros(),
            output: Vector::zeros(),
            mean_power: 0.0,
        }));
        check_gains(&sys, &state, params.h)?;
        let mut state = state;
        let held = HeldVelocities::new(&sys, &mut state)?;
        // A drum node's path runs along its element in the starting state, and the node
        // starts with its payout's rate (docs/method.md §23).
        let mut winch_start = winch_start;
        for (m, ws) in sys.winches.iter().zip(&mut winch_start) {
            m.align(ws, &state.r, &state.c, &m.frame(0.0, &state.bodies));
            state.v[m.drum_node(ws)] = m.path(ws, 0.0, &state.bodies).1;
        }
        sys.place_body_drums(&winch_start);
        let energies = sys.energies(&state);
        if !energies.hamiltonian().is_finite() {
            return Err(SetupError::DerivedNotFinite {
                what: "initial energy with the prescribed motions' velocities at t = 0".into(),
                value: energies.hamiltonian(),
            });
        }
        let contacts = crate::integrator::damped_contacts(&sys);
        Ok(Self {
            newton_ws: NewtonWorkspace::with_slots(&sys.mesh, slots),
            bodies_next: Vec::with_capacity(sys.bodies.len()),
            body_wrenches: vec![Default::default(); sys.bodies.len()],
            body_targets: vec![None; sys.bodies.len()],
            body_ports: vec![Default::default(); sys.bodies.len()],
            body_ports_prev: vec![Default::default(); sys.bodies.len()],
            held_wrenches: Vec::new(),
            winch_step: vec![(0.0, 0.0); winch_start.len()],
            winch_h: params.h,
            winch_port_sums: vec![([0.0; 3], [0.0; 3]); winch_start.len()],
            winch_work: vec![0.0; winch_start.len()],
            winch_port: vec![(0, [0.0; 3], [0.0; 3]); winch_start.len()],
            drum_steps: Vec::with_capacity(n_drums),
            nodes_x: Vec::new(),
            body_scratch: Default::default(),
            drum_next: vec![Default::default(); winch_start.len()],
            sys,
            params,
            run: Checkpoint {
                winches: winch_start,
                ..Checkpoint::start(state, params.h)
            },
            energies,
            x: vec![Vector::zeros(); n + slots],
            f_ext: vec![Vector::zeros(); n],
            reaction: vec![Vector::zeros(); n],
            c_next: vec![0.0; n_el],
            ports,
            solver,
            stop: None,
            backup: None,
            port_sums: Vec::new(),
            over_tolerance: 0,
            ports_prev: Vec::new(),
            held,
            inputs: Default::default(),
            contacts,
        })
    }

    /// A flag that, once set (e.g. by a Ctrl-C handler), ends the current step between two
    /// Newton iterations with [`StepError::Interrupted`], the state left at the last good
    /// step; `None` removes it.
    pub fn set_stop_flag(&mut self, flag: Option<Arc<AtomicBool>>) {
        self.stop = flag;
    }

    fn stop_requested(&self) -> bool {
        self.stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// The step-size floor `h / 2^max_halvings` [s]: step-size control never goes below it.
    pub fn step_size_floor(&self) -> f64 {
        self.params.h / 2f64.powi(self.params.control.max_halvings as i32)
    }

    /// The system.
    pub fn system(&self) -> &PhSystem<D, M> {
        &self.sys
    }
    /// The inputs held from outside the run.
    pub(crate) fn held_inputs(&self) -> &crate::boundary::HeldInputs<D> {
        &self.inputs
    }
    /// The bodies' models and, per body, the wrench it had before a held one (inputs).
    pub(crate) fn bodies_and_held(
        &mut self,
    ) -> (
        &mut [crate::body::BodyModel],
        &mut Vec<Option<Option<crate::body::BodyWrench>>>,
    ) {
        (&mut self.sys.bodies, &mut self.held_wrenches)
    }
    /// The held inputs and the boundary conditions they act on, to set an input.
    pub(crate) fn inputs_and_boundary(
        &mut self,
    ) -> (
        &mut crate::boundary::HeldInputs<D>,
        &mut crate::boundary::Boundary<D>,
    ) {
        (&mut self.inputs, &mut self.sys.boundary)
    }
    /// The current state.
    pub fn state(&self) -> &State<D> {
        &self.run.state
    }
    /// Step parameters.
    pub fn params(&self) -> &StepParams {
        &self.params
    }
    /// Current time `t_n` [s] (`n h` in a fixed-step run).
    pub fn time(&self) -> f64 {
        self.run.t_base + self.run.k as f64 * self.run.h_cur
    }
    /// Step size the next step will try [s].
    pub fn step_size(&self) -> f64 {
        self.run.h_cur
    }
    /// Smallest step size accepted so far [s].
    pub fn smallest_step_size(&self) -> f64 {
        self.run.h_min_used
    }
    /// Steps rejected (and retried with a smaller step) so far.
    pub fn rejected_steps(&self) -> usize {
        self.run.rejected
    }
    /// Error control: steps this simulation accepted at the step-size floor although their
    /// error estimate exceeded the tolerance (`time.rtol`, `time.atol`), so far (not counted
    /// across a [`Self::restore`]: it starts at 0 with each `Simulation`).
    pub fn steps_over_tolerance(&self) -> usize {
        self.over_tolerance
    }

    /// The complete dynamic state, for [`Self::restore`].
    pub fn checkpoint(&self) -> Checkpoint<D> {
        let mut cp = self.run.clone();
        cp.energies = Some(self.energies);
        cp
    }

    /// Continues from `cp`, taken from a simulation of the same problem and parameters.
    pub fn restore(&mut self, cp: Checkpoint<D>) -> Result<(), SetupError> {
        let (n, n_el) = (self.run.state.r.len(), self.run.state.c.len());
        cp.check_sizes(n, n_el, self.sys.bodies.len())?;
        self.check_winch_states(&cp.winches)
            .map_err(|problem| SetupError::Winch {
                index: 0,
                name: "checkpoint".into(),
                problem,
            })?;
        let held = cp.energies;
        self.run = cp;
        self.run.energies = None;
        self.place_winches();
        let e = self.with_drums(self.sys.energies(&self.run.state), false);
        // The record's own energies where they are those of its state (a cut updated them in
        // place: they differ in the last bits), so that the run continues bit for bit; every
        // term, the magnitude included, within 1e-12 of the evaluation's magnitude.
        let agree = |h: &Energies| {
            let tol = 1e-12 * e.magnitude;
            let (a, b) = (h.to_array(), e.to_array());
            a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
        };
        self.energies = held.filter(agree).unwrap_or(e);
        Ok(())
    }

    /// Saves what a step changes into `b`.
    fn save(&self, b: &mut Backup<D>) {
        match &mut b.run {
            Some(run) => run.clone_from(&self.run),
            None => b.run = Some(self.run.clone()),
        }
        b.energies = self.energies;
        b.ports.clone_from(&self.ports);
        b.body_ports.clone_from(&self.body_ports);
    }

    /// Puts back what [`Self::save`] saved.
    fn restore_from(&mut self, b: &Backup<D>) {
        if let Some(run) = &b.run {
            self.run.clone_from(run);
            if !self.sys.winches.is_empty() {
                self.place_winches();
            }
        }
        self.energies = b.energies;
        self.ports.clone_from(&b.ports);
        self.body_ports.clone_from(&b.body_ports);
    }

    /// Puts the run's winch states into the system (the whole of it,
    /// [`PhSystem::place_winches`]) and the damped contacts with them.
    fn place_winches(&mut self) {
        self.sys.place_winches(&self.run.winches);
        self.refresh_contacts();
    }

    /// `dg4` with winches: the damped contacts of the system as now placed (a winch's cut
    /// lumps nodes anew); O(N) on every cut, and nothing without `dg4` or winches.
    fn refresh_contacts(&mut self) {
        if self.params.scheme == Scheme::DiscreteGradient4 && !self.sys.winches.is_empty() {
            self.contacts = crate::integrator::damped_contacts(&self.sys);
        }
    }

    fn set_step_size(&mut self, h: f64) {
        self.run.t_base = self.time();
        self.run.k = 0;
        self.run.h_cur = h;
    }
    /// Number of steps taken.
    pub fn steps(&self) -> usize {
        self.run.steps
    }
    /// Energies of the current state [J].
    pub fn energies(&self) -> Energies {
        self.energies
    }
    /// The rigid bodies' wrench port samples of the last step (docs/method.md §22), in body
    /// order.
    pub fn body_ports(&self) -> &[crate::body::BodyPortSample] {
        &self.body_ports
    }
    /// The rigid bodies' own masses [kg] and inertia tensors about their centres of mass in
    /// body axes [kg·m²] (as given, without the water's added mass and inertia), in body
    /// order.
    pub fn body_inertias(&self) -> Vec<(f64, crate::body::Mat3)> {
        self.sys
            .bodies
            .iter()
            .map(|b| (b.dry_mass, b.dry_inertia))
            .collect()
    }
    /// Cumulative supplied energy `Σ h û·ŷ` [J].
    pub fn supplied_energy(&self) -> f64 {
        self.run.supplied_total
    }
    /// Cumulative dissipated energy `Σ D_n` [J] (docs/method.md §18).
    pub fn dissipated_energy(&self) -> f64 {
        self.run.dissipated_total
    }
    /// The water's shares of [`Self::supplied_energy`] and [`Self::dissipated_energy`] so far
    /// [J] (docs/method.md §21): drag, the current's work, seabed damping, friction (part of
    /// the [`Checkpoint`]).
    pub fn water_work(&self) -> WaterWork {
        self.run.water
    }
    /// Total Newton iterations so far.
    pub fn total_newton_iterations(&self) -> usize {
        self.run.total_newton
    }
    /// Name of the linear solver in use.
    pub fn solver_name(&self) -> &'static str {
        self.solver.name()
    }
    /// Port inputs and outputs of the last step (loads first, in the order given, then the
    /// feedback ports in the order given, then constrained nodes in increasing order). Before
    /// the first step both are zero.
    pub fn ports(&self) -> &[PortSample<D>] {
        &self.ports
    }

    /// Advances one step (docs/method.md §5, §8) with the current step size, halving it
    /// and retrying on failure when step-size control is on.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        self.step_until(f64::INFINITY)
    }

    /// Like [`Self::step`], but shortens the step so as not to pass `t_end` [s].
    pub fn step_until(&mut self, t_end: f64) -> Result<StepReport, StepError> {
        let mut tries = Retries::default();
        let tolerant = self.params.control.error_control();
        let composed = self.params.scheme == Scheme::DiscreteGradient4;
        if tolerant && !composed && self.run.acc_history.points.is_empty() {
            let a0 = self.initial_acceleration()?;
            self.run.acc_history.push(self.time(), &a0);
        }
        loop {
            let t = self.time();
            if self.stop_requested() {
                return Err(StepError::Interrupted {
                    step: self.run.steps + 1,
                    t,
                });
            }
            // Clip only a real overshoot: a step that lands on t_end up to rounding keeps h.
            let (h, t_next) = if t + self.run.h_cur > t_end + 1e-9 * self.run.h_cur {
                (t_end - t, Some(t_end))
            } else {
                (self.run.h_cur, None)
            };
            // Error control needs the state before the step (dg4 saves it itself).
            if tolerant && !composed {
                let mut b = self.backup.take().unwrap_or_default();
                self.save(&mut b);
                self.backup = Some(b);
            }
            match self.try_step(h, t_next) {
                Ok(report) if tolerant => {
                    if let Some(report) = self.judge_accuracy(report, t, h, t_next, &mut tries)? {
                        return Ok(self.cut_winches(report));
                    }
                }
                Ok(mut report) => {
                    tries.mark(&mut report);
                    let report = self.accept_fixed(report, h, t_next, t_end);
                    return Ok(self.cut_winches(report));
                }
                Err(e) => self.after_failure(e, t, h, &mut tries)?,
            }
        }
    }

    /// With error control: accepts the step of `report` (from `t` by `h`, clipped to
    /// `t_next`) and sets the next step size, or undoes it and shrinks the step when its
    /// error estimate exceeds the tolerance (`None`).
    fn judge_accuracy(
        &mut self,
        mut report: StepReport,
        t: f64,
        h: f64,
        t_next: Option<f64>,
        tries: &mut Retries,
    ) -> Result<Option<StepReport>, StepError> {
        let floor = self.step_size_floor();
        let composed = self.params.scheme == Scheme::DiscreteGradient4;
        let (err, embedded_iterations) = match self.step_error(t, h) {
            Ok(e) => e,
            Err(e) => {
                // A stop request during the embedded solve: the step is
                // undone, nothing is counted.
                self.undo_step();
                return Err(e);
            }
        };
        // The embedded solve is part of the step's work.
        report.newton_iterations += embedded_iterations;
        self.run.total_newton += embedded_iterations;
        // The local error is O(h³) (p = 2), the error per unit step O(h²) (p = 1).
        let p = if self.params.control.error_per_step {
            2
        } else {
            1
        };
        // step_error maps NaN to infinity.
        if err > 1.0 && h > floor * (1.0 + 1e-12) {
            // Rejected for accuracy: back to the state before the step.
            self.undo_step();
            tries.iterations += report.newton_iterations;
            tries.local += report.local_node_iterations;
            tries.rejected += 1;
            self.run.rejected += 1;
            let cut = crate::accuracy::reject_factor(err, p);
            self.set_step_size((h * cut).max(floor));
            return Ok(None);
        }
        self.over_tolerance += usize::from(err > 1.0); // at the floor
        let tau = t + 0.5 * h;
        if !composed {
            self.run.acc_history.push(tau, &self.run.acc);
        }
        let grow = crate::accuracy::accept_factor(err, self.run.err_prev, p);
        // Finite, also for a step accepted at the floor with err = ∞.
        self.run.err_prev = err.clamp(1e-10, 1e4);
        tries.mark(&mut report);
        self.run.h_min_used = self.run.h_min_used.min(h);
        // After a rejection in this step, no growth (Hairer–Wanner's facmax = 1);
        // a step clipped to t_end does not grow the unclipped size.
        let grow = if tries.rejected > 0 {
            grow.min(1.0)
        } else {
            grow
        };
        let next = if t_next.is_some() {
            self.run.h_cur * grow.min(1.0)
        } else {
            h * grow
        };
        let next = next.min(self.params.h).max(floor);
        self.run.t_base = report.t;
        self.run.k = 0;
        self.run.h_cur = next;
        Ok(Some(report))
    }

    /// After the step of `report` is accepted: the winches' cuts (docs/method.md §23), their
    /// energy booked as the winches' supply in the report and the run's totals. Only here,
    /// so that neither a `dg4` sub-step nor an attempt that error control rejects cuts.
    fn cut_winches(&mut self, mut report: StepReport) -> StepReport {
        if self.sys.winches.is_empty() {
            return report;
        }
        let changes = self.winch_cuts(report.t, report.h);
        self.run.supplied_total += changes;
        report.after = self.energies;
        report.supplied += changes;
        report.winch += changes;
        report
    }

    /// Without error control: accepts the step of `report` (by `h`, clipped to `t_next`
    /// at `t_end`), advances the time base and grows the step after easy steps.
    fn accept_fixed(
        &mut self,
        report: StepReport,
        h: f64,
        t_next: Option<f64>,
        t_end: f64,
    ) -> StepReport {
        let composed = self.params.scheme == Scheme::DiscreteGradient4;
        if t_next.is_some() {
            self.run.t_base = t_end;
            self.run.k = 0;
        } else {
            self.run.k += 1;
        }
        self.run.h_min_used = self.run.h_min_used.min(h);
        let c = self.params.control;
        // dg4 makes three solves per step.
        let solves = if composed { 3 } else { 1 };
        let easy = report.newton_iterations <= c.easy_iterations * solves && report.backtracks == 0;
        self.run.easy_streak = if easy { self.run.easy_streak + 1 } else { 0 };
        if c.adaptive && self.run.easy_streak >= c.grow_after && self.run.h_cur < self.params.h {
            self.set_step_size((2.0 * self.run.h_cur).min(self.params.h));
            self.run.easy_streak = 0;
        }
        report
    }

    /// After a failed try from `t` by `h`: halves the step (counting the work spent) when
    /// the failure is recoverable and the floor is not reached, or returns the failure.
    fn after_failure(
        &mut self,
        e: StepError,
        t: f64,
        h: f64,
        tries: &mut Retries,
    ) -> Result<(), StepError> {
        let floor = self.step_size_floor();
        let tolerant = self.params.control.error_control();
        let c = self.params.control;
        if !c.adaptive || !e.is_recoverable() {
            return Err(e);
        }
        // The floor is absolute: without error control h_cur is always
        // time.h / 2^k; with it, the step tried is halved down to the floor.
        let at_floor = if tolerant {
            h <= floor * (1.0 + 1e-12)
        } else {
            // A floor that underflows to 0 is reached once h/2 does.
            0.5 * self.run.h_cur < floor * (1.0 - 1e-12) || 0.5 * self.run.h_cur == 0.0
        };
        if at_floor {
            return Err(StepError::StepSizeTooSmall {
                step: self.run.steps + 1,
                t,
                h,
                floor,
                max_halvings: c.max_halvings,
                halvings: tries.halvings,
                last: Box::new(e),
            });
        }
        let spent = self.newton_ws.last_stats();
        tries.iterations += spent.iterations;
        tries.local += spent.local_node_iterations;
        tries.halvings += 1;
        tries.rejected += 1;
        self.run.rejected += 1;
        self.run.easy_streak = 0;
        if tolerant {
            self.set_step_size((0.5 * h).max(floor));
        } else {
            self.set_step_size(0.5 * self.run.h_cur);
        }
        Ok(())
    }

    /// Puts back the state and progress before the step just taken (in the backup): its
    /// step count and Newton iterations are undone with it.
    fn undo_step(&mut self) {
        let b = self.backup.take().expect("saved before the step");
        self.restore_from(&b);
        self.backup = Some(b);
    }

    /// The error of the step just taken from `t` by `h` (docs/method.md §19), relative to the
    /// tolerances: ≤ 1 to accept (NaN is infinite). The state before the step is in the
    /// backup. With it, the Newton iterations of `dg4`'s embedded solve (0 otherwise). `Err`
    /// only for a stop request during that solve.
    fn step_error(&mut self, t: f64, h: f64) -> Result<(f64, usize), StepError> {
        let c = self.params.control;
        let (rtol, atol, atol_v) = (c.rtol, c.atol, c.atol / self.params.h);
        let b = self.backup.take().expect("saved before the step");
        let saved = b.run.as_ref().expect("saved before the step");
        let before = &saved.state;
        let mut err: f64 = 0.0;
        let mut embedded_iterations = 0;
        // The larger of the two, NaN kept.
        let worse = |err: f64, r: f64| if r <= err { err } else { r };
        if self.params.scheme == Scheme::DiscreteGradient4 {
            let converged = match self.embedded_second_order((before, &saved.winches), t, h) {
                Ok(c) => c,
                Err(e) => {
                    self.backup = Some(b);
                    return Err(e);
                }
            };
            match converged {
                Some(iterations) => {
                    embedded_iterations = iterations;
                    // self.x holds the second-order increment.
                    let inv_h = 1.0 / h;
                    for i in 0..self.run.state.r.len() {
                        if !self.sys.free[i].iter().any(|&f| f) {
                            continue;
                        }
                        let mask = |v: Vector<D>| {
                            Vector::<D>::from_fn(
                                |k, _| if self.sys.free[i][k] { v[k] } else { 0.0 },
                            )
                        };
                        let r2 = before.r[i] + self.x[i];
                        let v2 = self.x[i] * (2.0 * inv_h) - before.v[i];
                        let e_r = mask(r2 - self.run.state.r[i]).norm();
                        let e_v = mask(v2 - self.run.state.v[i]).norm();
                        let r_mag = before.r[i].norm().max(self.run.state.r[i].norm());
                        let v_mag = before.v[i].norm().max(self.run.state.v[i].norm());
                        err = worse(
                            err,
                            crate::accuracy::ratio(e_r, e_v, r_mag, v_mag, rtol, atol, atol_v),
                        );
                    }
                    // The drums' payouts and speeds (docs/method.md §23.6) likewise.
                    let n = self.sys.mesh.n_nodes();
                    for d in &self.drum_steps {
                        let (ws0, ws) = (&saved.winches[d.winch], &self.run.winches[d.winch]);
                        let dp = self.x[n + d.slot][0];
                        let speed = d.speed_after(dp, h);
                        let e_r = (ws0.payout + dp - ws.payout).abs();
                        let e_v = (speed - ws.speed).abs();
                        let r_mag = ws0.payout.abs().max(ws.payout.abs());
                        let v_mag = ws0.speed.abs().max(ws.speed.abs());
                        err = worse(
                            err,
                            crate::accuracy::ratio(e_r, e_v, r_mag, v_mag, rtol, atol, atol_v),
                        );
                    }
                }
                None => err = f64::INFINITY,
            }
        } else {
            let tau = t + 0.5 * h;
            for i in 0..self.run.state.r.len() {
                if !self.sys.free[i].iter().any(|&f| f) {
                    continue;
                }
                let (e_r, e_v) = crate::accuracy::second_order_estimate(
                    h,
                    tau,
                    &self.run.acc,
                    &self.run.acc_history,
                    i,
                    &self.sys.free[i],
                );
                let r_mag = before.r[i].norm().max(self.run.state.r[i].norm());
                let v_mag = before.v[i].norm().max(self.run.state.v[i].norm());
                err = worse(
                    err,
                    crate::accuracy::ratio(e_r, e_v, r_mag, v_mag, rtol, atol, atol_v),
                );
            }
        }
        self.backup = Some(b);
        // Error per unit step (relative to the largest step): a step of h/k may make 1/k of
        // the error of a step of h, so that the global error is proportional to the tolerance.
        // Or, as asked, the error of the step itself.
        let err = if self.params.control.error_per_step {
            err
        } else {
            err * (self.params.h / h)
        };
        Ok((
            if err.is_nan() { f64::INFINITY } else { err },
            embedded_iterations,
        ))
    }

    /// The second-order DG step from `before` (at `t`, with the winch states `winches`) by
    /// `h`, started from the increment the step just taken made; its increment (and the
    /// drums' payout increments in their slots) is left in `self.x`. The drum nodes of
    /// prescribed payouts move as in that step (no cut happens inside a step); a drum with
    /// dynamics has its row (docs/method.md §23.6) from its state before the step.
    /// `Ok(Some(iterations))` if Newton converged, `Ok(None)` if not, `Err` on a stop
    /// request. Nothing else changes.
    fn embedded_second_order(
        &mut self,
        (before, winches): (&State<D>, &[crate::winch::WinchState]),
        t: f64,
        h: f64,
    ) -> Result<Option<usize>, StepError> {
        let t_mid = t + 0.5 * h;
        self.sum_loads(t_mid);
        for (x, (a, b)) in self
            .x
            .iter_mut()
            .zip(self.run.state.r.iter().zip(&before.r))
        {
            *x = a - b;
        }
        self.drum_steps.clear();
        if self.sys.winches.iter().any(|m| m.drum.is_some()) {
            let at = StepAt {
                step: self.run.steps,
                t,
                h,
                t_next: t + h,
            };
            let (sys, x) = (&self.sys, &mut self.x);
            if Self::drum_data(sys, (winches, &before.r), &at, &mut self.drum_steps, x).is_err() {
                return Ok(None);
            }
            // Started from the composition's payout increments.
            let (nodes, slots) = x.split_at_mut(sys.mesh.n_nodes());
            for d in &self.drum_steps {
                slots[d.slot][0] = self.run.winches[d.winch].payout - winches[d.winch].payout;
            }
            crate::winch_step::fill_drums(&self.drum_steps, slots, nodes);
        }
        let mut eqs = StepEquations::new(
            &self.sys,
            Scheme::DiscreteGradient,
            h,
            before,
            t_mid,
            &self.f_ext,
            &mut self.reaction,
        );
        eqs.drums = &self.drum_steps;
        match newton::solve(
            &mut eqs,
            &mut self.x,
            &mut self.newton_ws,
            self.solver.as_mut(),
            &self.params.newton,
            self.stop.as_deref(),
        ) {
            Ok(stats) => Ok(Some(stats.iterations)),
            Err(NewtonError::Interrupted(_)) => Err(StepError::Interrupted {
                step: self.run.steps,
                t,
            }),
            Err(_) => Ok(None),
        }
    }

    /// `f_ext = F_b + F_N(t)` (the loads unchecked: a step evaluates them first and refuses
    /// non-finite ones).
    fn sum_loads(&mut self, t: f64) {
        self.f_ext.copy_from_slice(&self.sys.f_body);
        for load in &self.sys.boundary.loads {
            self.f_ext[load.node] += (load.force)(t);
        }
    }

    /// The acceleration [m/s²] at the current state, `M_ρ a = F(t, r, v)` on the free
    /// components (0 on the others): the first point of the second-order error estimate.
    fn initial_acceleration(&mut self) -> Result<Vec<Vector<D>>, StepError> {
        let t = self.time();
        // The step residual at Δ = ε v (so v_{n+1} = v_n: no inertia) is −F at r + εv/2.
        let eps = 1e-9 * self.params.h;
        self.sum_loads(t + 0.5 * eps);
        // Every component, prescribed ones too, so that no inertia term appears anywhere.
        for (x, v) in self.x.iter_mut().zip(&self.run.state.v) {
            *x = v * eps;
        }
        // The nodes only: a winch drum's slot (after the nodes) has no row here; its drum
        // node is held.
        let n = self.sys.mesh.n_nodes();
        let mut res = vec![Vector::<D>::zeros(); self.x.len()];
        let mut eqs = StepEquations::new(
            &self.sys,
            Scheme::DiscreteGradient,
            eps,
            &self.run.state,
            t + 0.5 * eps,
            &self.f_ext,
            &mut self.reaction,
        );
        use crate::newton::NewtonProblem;
        eqs.evaluate(&self.x[..n], &mut res[..n], None)
            .map_err(|s| StepError::InvalidStrain {
                step: self.run.steps + 1,
                t,
                element: s.element,
                c: s.c,
            })?;
        // M a = −res on the free components; identity rows and columns elsewhere (and for
        // the drums' slots, whose right-hand side is 0).
        let mut m = crate::assembly::mass_blocks(&self.sys);
        crate::assembly::mask_fixed(&self.sys, &mut m);
        let slots = self.x.len() - n;
        if slots > 0 {
            let nodes = std::mem::replace(
                &mut m,
                crate::linsolve::BlockJacobian::with_slots(&self.sys.mesh, slots),
            );
            (m.diag, m.off) = (nodes.diag, nodes.off);
            for s in 0..slots {
                m.border.own[s * slots + s] = crate::linsolve::Block::<D>::identity();
            }
        }
        for (r, free) in res.iter_mut().zip(&self.sys.free) {
            *r = Vector::from_fn(|k, _| if free[k] { -r[k] } else { 0.0 });
        }
        self.solver
            .solve(&m, &mut res)
            .map_err(|cause| StepError::Linear {
                step: self.run.steps + 1,
                t,
                cause,
            })?;
        if let Some(node) = res.iter().position(|a| !a.iter().all(|x| x.is_finite())) {
            return Err(StepError::NonFinite {
                step: self.run.steps + 1,
                t,
                what: "initial acceleration",
                node,
            });
        }
        res.truncate(n);
        Ok(res)
    }

    /// One attempt at a step of size `h` to `t_next` (default `t_base + (k+1) h_cur`):
    /// one step of the scheme, or for `dg4` its three sub-steps. Leaves the state untouched
    /// on failure.
    fn try_step(&mut self, h: f64, t_next: Option<f64>) -> Result<StepReport, StepError> {
        let t = self.time();
        let t_next = t_next.unwrap_or(self.run.t_base + (self.run.k + 1) as f64 * self.run.h_cur);
        let step_no = self.run.steps + 1;
        if !self.sys.winches.is_empty() {
            self.winch_begin();
        }
        let report = if self.params.scheme == Scheme::DiscreteGradient4 {
            self.try_composed(t, h, t_next, step_no)?
        } else {
            self.try_single(t, h, t_next, step_no)?
        };
        self.run.steps += 1;
        self.run.total_newton += report.newton_iterations;
        Ok(report)
    }

    /// The triple jump (docs/method.md §19): DG sub-steps `γ_k h` from `t` (or `n` triple
    /// jumps of `h/n` where a damped seabed contact asks for it, (19.4)), with the state
    /// saved first and put back if one fails. The report sums the sub-steps' Newton work,
    /// supplied and dissipated energy; its ports hold the `h_k`-weighted means.
    fn try_composed(
        &mut self,
        t: f64,
        h: f64,
        t_next: f64,
        step_no: usize,
    ) -> Result<StepReport, StepError> {
        let mut backup = self.backup.take().unwrap_or_default();
        self.save(&mut backup);
        let gammas = crate::integrator::triple_jump();
        // n triple jumps of h/n (19.4): none of their backward sub-steps near a damped
        // contact's singular step.
        let n = crate::integrator::compositions(&self.contacts, h);
        let part = h / n as f64;
        // The ports' h_k-weighted sums, in a buffer kept from step to step.
        let mut sums = std::mem::take(&mut self.port_sums);
        sums.clear();
        sums.resize(self.ports.len(), (Vector::zeros(), Vector::zeros(), 0.0));
        // The bodies' ports likewise (empty without bodies).
        let mut body_sums = vec![crate::body::BodyPortSample::default(); self.body_ports.len()];
        let mut total: Option<StepReport> = None;
        let mut start = t;
        let sub_steps = (0..n).flat_map(|j| gammas.iter().enumerate().map(move |(k, g)| (j, k, g)));
        for (j, k, g) in sub_steps {
            let hk = g * part;
            // The sub-steps' ends: t + (j + γ₁ + … + γ_k) h/n, the step's last one t_next.
            let frac: f64 = gammas[..=k].iter().sum();
            let end = match (j + 1 == n, k == 2) {
                (true, true) => t_next,
                (false, true) => t + (j + 1) as f64 * part,
                _ => t + (j as f64 + frac) * part,
            };
            match self.try_single(start, hk, end, step_no) {
                Ok(r) => {
                    for (s, p) in sums.iter_mut().zip(&self.ports) {
                        s.0 += p.input * hk;
                        s.1 += p.output * hk;
                        s.2 += p.mean_power * hk;
                    }
                    for (s, p) in body_sums.iter_mut().zip(&self.body_ports) {
                        s.force += p.force * hk;
                        s.torque += p.torque * hk;
                        s.velocity += p.velocity * hk;
                        s.omega += p.omega * hk;
                        s.mean_power += p.mean_power * hk;
                    }
                    self.winch_port_add(hk);
                    total = Some(match total {
                        None => r,
                        Some(a) => StepReport {
                            newton_iterations: a.newton_iterations + r.newton_iterations,
                            backtracks: a.backtracks + r.backtracks,
                            local_iterations: a.local_iterations + r.local_iterations,
                            local_node_iterations: a.local_node_iterations
                                + r.local_node_iterations,
                            residual: a.residual.max(r.residual),
                            tolerance: a.tolerance.max(r.tolerance),
                            force_scale: a.force_scale.max(r.force_scale),
                            at_roundoff: a.at_roundoff || r.at_roundoff,
                            after: r.after,
                            supplied: a.supplied + r.supplied,
                            dissipated: a.dissipated + r.dissipated,
                            water: {
                                let mut w = a.water;
                                w.add(&r.water);
                                w
                            },
                            energy_scale: a.energy_scale + r.energy_scale,
                            winch: a.winch + r.winch,
                            ..a
                        },
                    });
                }
                Err(e) => {
                    // Newton's work of the failed sub-step is what the caller counts.
                    self.restore_from(&backup);
                    self.backup = Some(backup);
                    self.port_sums = sums;
                    return Err(e);
                }
            }
            start = end;
        }
        self.backup = Some(backup);
        for (p, s) in self.ports.iter_mut().zip(&sums) {
            p.input = s.0 / h;
            p.output = s.1 / h;
            p.mean_power = s.2 / h;
        }
        for (p, s) in self.body_ports.iter_mut().zip(&body_sums) {
            *p = crate::body::BodyPortSample {
                force: s.force / h,
                torque: s.torque / h,
                velocity: s.velocity / h,
                omega: s.omega / h,
                mean_power: s.mean_power / h,
            };
        }
        self.port_sums = sums;
        self.winch_port_means(h);
        let mut r = total.expect("at least three sub-steps");
        r.t = t_next;
        r.h = h;
        r.balance_error =
            r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
        Ok(r)
    }

    /// One step of the scheme's stress formula from `t` by `h` (negative for the backward
    /// sub-step of `dg4`) to `t_next`; commits the state, energies, ports and energy totals
    /// on success, leaves them untouched on failure.
    fn try_single(
        &mut self,
        t: f64,
        h: f64,
        t_next: f64,
        step_no: usize,
    ) -> Result<StepReport, StepError> {
        if self.sys.winches.is_empty() {
            return self.try_dg(t, h, t_next, step_no);
        }
        // The winches (docs/method.md §23): their drum nodes move with the payout inside
        // the step; after it, their velocities are held (the cuts wait for the accepted
        // step, [`Self::cut_winches`]).
        let start = self.energies;
        let mut report = self.try_dg(t, h, t_next, step_no)?;
        let changes = self.winch_hold(t_next);
        self.run.supplied_total += changes;
        report.before = start;
        report.after = self.energies;
        report.supplied += changes;
        report.winch = self.winch_work.iter().sum::<f64>() + changes;
        Ok(report)
    }

    /// One discrete-gradient (or midpoint) step from `t` by `h` to `t_next`.
    fn try_dg(
        &mut self,
        t: f64,
        h: f64,
        t_next: f64,
        step_no: usize,
    ) -> Result<StepReport, StepError> {
        let at = StepAt {
            step: step_no,
            t,
            h,
            t_next,
        };
        let t_mid = t + 0.5 * h;
        self.apply_loads(&at)?;
        self.predict(&at)?;
        let (stats, damped, water) = self.solve_increment(&at)?;
        self.check_new_state(&at)?;
        let after = self.energies_after(&at)?;
        self.ports_prev.clone_from(&self.ports);
        let ports = self.form_ports(t_mid, h);
        // Without water its shares are 0 and these sums change nothing (x + 0 = x).
        let (supplied, dissipated) = if self.sys.has_water() {
            (ports + water.current_supplied, damped + water.dissipated())
        } else {
            (ports, damped)
        };
        // The winch drums' damping and brakes (docs/method.md §23.6).
        let dissipated = if self.drum_steps.is_empty() {
            dissipated
        } else {
            dissipated + self.drum_next.iter().map(|d| d.dissipated).sum::<f64>()
        };
        let before = self.energies;
        let (balance_error, energy_scale) =
            self.check_balance(&at, &stats, before, after, (supplied, dissipated), &water)?;
        self.commit(h, after, supplied, dissipated);
        self.run.water.add(&water);
        Ok(StepReport {
            step: step_no,
            t: t_next,
            h,
            newton_iterations: stats.iterations,
            backtracks: stats.backtracks,
            local_iterations: stats.local_iterations,
            local_node_iterations: stats.local_node_iterations,
            rejected_iterations: 0,
            rejected_local_node_iterations: 0,
            rejected: 0,
            residual: stats.residual,
            tolerance: stats.tolerance,
            force_scale: stats.force_scale,
            at_roundoff: stats.at_roundoff,
            before,
            after,
            supplied,
            dissipated,
            water,
            winch: 0.0,
            balance_error,
            energy_scale,
        })
    }

    /// External forces `F_b + F_N(t_{n+½})` into `f_ext`, with the load ports' inputs; a load
    /// or a feedback law that is not finite at the start of the step fails it.
    fn apply_loads(&mut self, at: &StepAt) -> Result<(), StepError> {
        let (step_no, t) = (at.step, at.t);
        let t_mid = t + 0.5 * at.h;
        self.f_ext.copy_from_slice(&self.sys.f_body);
        for (port, load) in self.ports.iter_mut().zip(&self.sys.boundary.loads) {
            let f = (load.force)(t_mid);
            if !f.iter().all(|x| x.is_finite()) {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "load",
                    node: load.node,
                });
            }
            port.input = f;
            self.f_ext[load.node] += f;
        }
        for (b, model) in self.sys.bodies.iter().enumerate() {
            let (f, tau) = model.wrench_at::<D>(t_mid);
            if !(f.iter().chain(&tau).all(|x| x.is_finite())) {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "rigid body's wrench (at the body's first attached node)",
                    node: model.attachments.first().map_or(0, |a| a.0),
                });
            }
            self.body_wrenches[b] = (f, tau);
            let target = model.feedback.as_ref().map(|law| law.target(t_mid));
            if target.is_some_and(|g| !g.is_finite()) {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "rigid body's feedback reference (at the body's first attached node)",
                    node: model.attachments.first().map_or(0, |a| a.0),
                });
            }
            self.body_targets[b] = target;
        }
        // A feedback law that is not finite at the start of the step (a failing reference
        // expression) fails the step at once, like a load, rather than through Newton.
        for fb in &self.sys.boundary.feedback {
            let i = fb.node;
            let f = fb
                .law
                .force(t_mid, &self.run.state.r[i], &self.run.state.v[i]);
            if !f.iter().all(|x| x.is_finite()) {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "feedback force",
                    node: i,
                });
            }
        }
        Ok(())
    }

    /// The predictor of the increment `Δ` on the free components, and the known increments
    /// of the prescribed motions (Newton holds them: their rows are the reactions).
    fn predict(&mut self, at: &StepAt) -> Result<(), StepError> {
        let (step_no, t, h, t_next) = (at.step, at.t, at.h, at.t_next);
        let (acc_w, mid) = match self.params.predictor {
            Predictor::Velocity => (0.0, false),
            Predictor::Acceleration => (0.5 * h * h, false),
            Predictor::MidpointVelocity => (0.0, self.run.steps > 0),
        };
        for ((((x, v), a), vm), free) in self
            .x
            .iter_mut()
            .zip(&self.run.state.v)
            .zip(&self.run.acc)
            .zip(&self.run.v_mid)
            .zip(&self.sys.free)
        {
            *x = if mid { vm * h } else { v * h + a * acc_w };
            for k in 0..D {
                if !free[k] {
                    x[k] = 0.0;
                }
            }
        }
        // Prescribed motions: their increments are known; Newton holds them (their rows are
        // the reactions).
        for m in &self.sys.boundary.motions {
            let target = (m.position)(t_next);
            if !target.is_finite() {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "prescribed position",
                    node: m.node,
                });
            }
            self.x[m.node][m.component] = target - self.run.state.r[m.node][m.component];
        }
        if !self.sys.winches.is_empty() {
            self.winch_prescribe(at)?;
        }
        if !self.sys.bodies.is_empty() {
            let n = self.sys.mesh.n_nodes();
            let states = &self.run.state.bodies;
            if mid {
                let v_mid = &self.run.v_mid[n..];
                crate::body_step::predict_mid(states, h, v_mid, &mut self.x[n..]);
            } else {
                crate::body_step::predict(states, h, &mut self.x[n..]);
            }
            crate::body_step::prescribe(&self.sys, states, t_next, &mut self.x[n..]).map_err(
                |b| StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "prescribed body pose (not finite, out of the plane of a 2D \
                           network, or a turn of more than 170° in one step; at the body's \
                           first attached node)",
                    node: self.sys.bodies[b].attachments.first().map_or(0, |a| a.0),
                },
            )?;
        }
        Ok(())
    }

    /// Newton on the step's residual from the predicted increment; returns its statistics,
    /// the energy dissipated over the step by the damping of §18 [J] and the water's work.
    fn solve_increment(&mut self, at: &StepAt) -> Result<(NewtonStats, f64, WaterWork), StepError> {
        let (h, t_mid) = (at.h, at.t + 0.5 * at.h);
        let mut eqs = StepEquations::new(
            &self.sys,
            self.params.scheme,
            h,
            &self.run.state,
            t_mid,
            &self.f_ext,
            &mut self.reaction,
        );
        eqs.wrenches = &self.body_wrenches;
        eqs.targets = &self.body_targets;
        eqs.drums = &self.drum_steps;
        eqs.nodes_x = std::mem::take(&mut self.nodes_x);
        eqs.body_scratch = std::mem::take(&mut self.body_scratch);
        let result = newton::solve(
            &mut eqs,
            &mut self.x,
            &mut self.newton_ws,
            self.solver.as_mut(),
            &self.params.newton,
            self.stop.as_deref(),
        );
        if result.is_ok() && !self.sys.bodies.is_empty() {
            // The attached nodes move with their bodies (Newton held their increments).
            let (nodes, slots) = self.x.split_at_mut(self.sys.mesh.n_nodes());
            let states = &self.run.state.bodies;
            crate::body_step::fill_attachments(&self.sys, states, slots, nodes);
        }
        if result.is_ok() && !self.drum_steps.is_empty() {
            let (nodes, slots) = self.x.split_at_mut(self.sys.mesh.n_nodes());
            crate::winch_step::fill_drums(&self.drum_steps, slots, nodes);
        }
        let dissipated = if result.is_ok() && self.sys.has_damping() {
            eqs.dissipated(&self.x)
        } else {
            0.0
        };
        let water = if result.is_ok() {
            eqs.water_work(&self.x)
        } else {
            WaterWork::default()
        };
        self.nodes_x = std::mem::take(&mut eqs.nodes_x);
        self.body_scratch = std::mem::take(&mut eqs.body_scratch);
        let stats = result.map_err(|e| self.newton_failure(e, at))?;
        Ok((stats, dissipated, water))
    }

    /// The step error of a failed Newton solve.
    fn newton_failure(&self, e: NewtonError<StrainError>, at: &StepAt) -> StepError {
        let (step_no, t, t_next) = (at.step, at.t, at.t_next);
        let worst_node = || {
            let res = self.newton_ws.residual();
            (0..res.len())
                .max_by(|&i, &j| res[i].norm_squared().total_cmp(&res[j].norm_squared()))
                .unwrap_or(0)
        };
        match e {
            NewtonError::Eval(s) => StepError::InvalidStrain {
                step: step_no,
                t,
                element: s.element,
                c: s.c,
            },
            NewtonError::Linear(source) => StepError::Linear {
                step: step_no,
                t,
                cause: source,
            },
            NewtonError::NonFinite { node, overflow } => StepError::NonFinite {
                step: step_no,
                t,
                what: if overflow {
                    "residual's norm (it overflows: forces of 1e154 N or more; largest at this node)"
                } else {
                    "residual"
                },
                node,
            },
            NewtonError::MaxIterations(s) => StepError::NewtonDiverged {
                worst_node: worst_node(),
                step: step_no,
                t,
                t_next,
                residual: s.residual,
                tol: s.tolerance,
                force_scale: s.force_scale,
                iterations: s.iterations,
            },
            NewtonError::Interrupted(_) => StepError::Interrupted { step: step_no, t },
            NewtonError::LineSearch(s) => StepError::LineSearchFailed {
                worst_node: worst_node(),
                step: step_no,
                t,
                t_next,
                residual: s.residual,
                tol: s.tolerance,
                force_scale: s.force_scale,
                iterations: s.iterations,
            },
        }
    }

    /// Checks that the solved step's state is finite, forms its strains into `c_next` and
    /// the velocities the prescribed motions hold at its end, before anything is overwritten
    /// (a failed step leaves the state untouched).
    fn check_new_state(&mut self, at: &StepAt) -> Result<(), StepError> {
        let (step_no, t, h, t_next) = (at.step, at.t, at.h, at.t_next);
        // The new state must be finite before anything is overwritten, so that a failed step
        // leaves the state untouched.
        let two_over_h = 2.0 / h;
        if let Some(node) = self
            .x
            .iter()
            .zip(&self.run.state.v)
            .zip(&self.run.state.r)
            .position(|((x, v), r)| {
                !(x.iter().all(|c| c.is_finite())
                    && (x * two_over_h - v).iter().all(|c| c.is_finite())
                    && (r + x).iter().all(|c| c.is_finite()))
            })
        {
            return Err(StepError::NonFinite {
                step: step_no,
                t,
                what: "state",
                node,
            });
        }
        // New strains first (they need r_n), into the spare buffer: they replace the old ones
        // only once the energies of the new state are known to be finite (a strain can
        // overflow `W`), so that a failed step leaves the state untouched.
        let mesh = &self.sys.mesh;
        for (e, (&[a, b], &l)) in mesh.elements().iter().zip(mesh.lengths()).enumerate() {
            let (_, _, dc) = element_step(
                &self.run.state.r[a],
                &self.run.state.r[b],
                &self.x[a],
                &self.x[b],
                l,
            );
            self.c_next[e] = self.run.state.c[e] + dc;
        }
        // The rigid bodies' new states.
        let n = mesh.n_nodes();
        let bodies = &self.run.state.bodies;
        let times = (h, t_next);
        crate::body_step::advance(
            &self.sys,
            bodies,
            times,
            &self.x[n..],
            &mut self.bodies_next,
        );
        if let Some(b) = self.bodies_next.iter().position(|st| {
            let finite = |v: &crate::body::Vec3| v.iter().all(|c| c.is_finite());
            !(finite(&st.position) && finite(&st.velocity) && finite(&st.omega))
        }) {
            let node = self.sys.bodies[b].attachments.first().map_or(0, |a| a.0);
            return Err(StepError::NonFinite {
                step: step_no,
                t,
                what: "rigid body state (at the body's first attached node)",
                node,
            });
        }
        if !self.drum_steps.is_empty() {
            self.drums_next(at)?;
        }
        // The velocities the prescribed motions hold at the step's end.
        for (k, m) in self.sys.boundary.motions.iter().enumerate() {
            let v = m.velocity(t_next);
            if !v.is_finite() {
                return Err(StepError::NonFinite {
                    step: step_no,
                    t,
                    what: "prescribed velocity",
                    node: m.node,
                });
            }
            self.held.velocity[k] = v;
        }
        Ok(())
    }

    /// The energies of the new state, with `r` and `v` formed as the update forms them
    /// (bit-identical to `energies` of the updated state); fails where one is not finite.
    fn energies_after(&self, at: &StepAt) -> Result<Energies, StepError> {
        let (step_no, t) = (at.step, at.t);
        let inv_h = 1.0 / at.h;
        let after = {
            let (r0, v0, c, x) = (&self.run.state.r, &self.run.state.v, &self.c_next, &self.x);
            let (held, motions) = (&self.held, &self.sys.boundary.motions);
            self.sys.energies_with(
                |i| r0[i] + x[i],
                |i| held.apply(i, x[i] * (2.0 * inv_h) - v0[i], motions),
                |e| c[e],
                &self.bodies_next,
            )
        };
        let after = self.with_drums(after, true);
        if !(after.kinetic.is_finite() && after.internal.is_finite() && after.external.is_finite())
        {
            let node = self.non_finite_energy_node();
            return Err(StepError::NonFinite {
                step: step_no,
                t,
                what: "energy",
                node,
            });
        }
        Ok(after)
    }

    /// The step's balance error and energy scale [J]; an exact scheme's step that misses the
    /// bound (docs/method.md eq. (9.6)), or any step whose balance overflows, fails, with the
    /// ports put back.
    fn check_balance(
        &mut self,
        at: &StepAt,
        stats: &NewtonStats,
        before: Energies,
        after: Energies,
        (supplied, dissipated): (f64, f64),
        water: &WaterWork,
    ) -> Result<(f64, f64), StepError> {
        let (step_no, t, h, t_next) = (at.step, at.t, at.h, at.t_next);
        let balance_error = after.hamiltonian() - before.hamiltonian() - supplied + dissipated;
        // Finite terms whose sum overflows (Ĥ or the supply beyond 1.8e308 J) end the step
        // for every scheme, `mp` included.
        if !balance_error.is_finite() {
            std::mem::swap(&mut self.ports, &mut self.ports_prev);
            std::mem::swap(&mut self.body_ports, &mut self.body_ports_prev);
            return Err(StepError::NonFinite {
                step: step_no,
                t,
                what: "energy",
                node: self.non_finite_energy_node(),
            });
        }
        let supplied_magnitude = h.abs()
            * (self.ports.iter().map(|p| p.power().abs()).sum::<f64>()
                + self
                    .body_ports
                    .iter()
                    .map(|p| p.mean_power.abs())
                    .sum::<f64>())
            + self.winch_work.iter().map(|w| w.abs()).sum::<f64>();
        // The work the strain-rounding floor of Newton's test may leave undone, as a scale
        // (its rounding is ε times this, docs/method.md eq. (9.6)).
        let strain_work = newton::ROUNDOFF_STRAIN * stats.strain_scale * newton::norm(&self.x);
        let mut energy_scale = before.magnitude
            + after.magnitude
            + supplied_magnitude
            + dissipated.abs()
            + strain_work;
        if self.sys.has_water() {
            energy_scale += water.magnitude();
        }
        let bound = BALANCE_RTOL * energy_scale;
        // A NaN balance misses the bound too.
        let missed = balance_error.is_nan() || balance_error.abs() > bound;
        if self.params.scheme != Scheme::Midpoint && missed {
            std::mem::swap(&mut self.ports, &mut self.ports_prev);
            std::mem::swap(&mut self.body_ports, &mut self.body_ports_prev);
            return Err(StepError::BalanceNotResolved {
                step: step_no,
                t,
                t_next,
                error: balance_error,
                bound,
                energy_scale,
                residual: stats.residual,
                force_scale: stats.force_scale,
            });
        }
        Ok((balance_error, energy_scale))
    }

    /// Commits the solved step: strains, positions, velocities (the prescribed ones held),
    /// the predictor's history, energies and energy totals.
    fn commit(&mut self, h: f64, after: Energies, supplied: f64, dissipated: f64) {
        let inv_h = 1.0 / h;
        std::mem::swap(&mut self.run.state.c, &mut self.c_next);
        for ((((r, v), a), vm), x) in self
            .run
            .state
            .r
            .iter_mut()
            .zip(&mut self.run.state.v)
            .zip(&mut self.run.acc)
            .zip(&mut self.run.v_mid)
            .zip(&self.x)
        {
            *r += x;
            *vm = x * inv_h;
            let v_new = x * (2.0 * inv_h) - *v;
            *a = (v_new - *v) * inv_h;
            *v = v_new;
        }
        for (m, &v) in self.sys.boundary.motions.iter().zip(&self.held.velocity) {
            self.run.state.v[m.node][m.component] = v;
        }
        if !self.sys.bodies.is_empty() {
            let n = self.sys.mesh.n_nodes();
            let states = &self.run.state.bodies;
            let v_mid = &mut self.run.v_mid[n..];
            crate::body_step::mid_velocities(states, h, &self.x[n..], v_mid);
        }
        std::mem::swap(&mut self.run.state.bodies, &mut self.bodies_next);
        debug_assert_eq!(
            after,
            self.with_drums(self.sys.energies(&self.run.state), true)
        );
        self.energies = after;
        self.run.supplied_total += supplied;
        self.run.dissipated_total += dissipated;
    }

    /// Forms the port samples of the step just solved (before the state is updated: the
    /// feedback laws are evaluated at the mid-step from `r_n` and `Δ`): feedback inputs,
    /// velocities at `t_{n+½}`, reactions, each port's mean power including the kinetic
    /// energy its held velocity imposes; returns the energy supplied `h Σ P` [J].
    fn form_ports(&mut self, t_mid: f64, h: f64) -> f64 {
        let inv_h = 1.0 / h;
        // Feedback inputs: the law at the converged step, formed as the residual forms it.
        let n_loads = self.sys.boundary.loads.len();
        for (port, fb) in self.ports[n_loads..]
            .iter_mut()
            .zip(&self.sys.boundary.feedback)
        {
            let i = fb.node;
            let (r_mid, y) = (self.run.state.r[i] + self.x[i] * 0.5, self.x[i] * inv_h);
            port.input = fb.law.force(t_mid, &r_mid, &y);
        }
        // Outputs at t_{n+½}: velocity v_{n+½} = Δ/h, reaction forces.
        let n_force = n_loads + self.sys.boundary.feedback.len();
        for (i, port) in self.ports.iter_mut().enumerate() {
            let v_mid = self.x[port.node] * inv_h;
            if i < n_force {
                port.output = v_mid;
            } else {
                let free = &self.sys.free[port.node];
                for k in 0..D {
                    let fixed = !free[k];
                    port.input[k] = if fixed { v_mid[k] } else { 0.0 };
                    port.output[k] = if fixed {
                        self.reaction[port.node][k]
                    } else {
                        0.0
                    };
                }
            }
        }
        // Held velocities (docs/method.md eq. (14.5)): the impulse `M δv` that sets a moving
        // node's velocity is part of its reaction (so that the reactions carry the whole
        // momentum balance), and the kinetic energy it imposes beyond that impulse's work
        // over `Δ` is part of its port's power (so that the energy balance stays exact).
        let (held, motions) = (&self.held, &self.sys.boundary.motions);
        let (x, v0) = (&self.x, &self.run.state.v);
        let raw = |j: usize| x[j] * (2.0 * inv_h) - v0[j];
        let dv = |j: usize| held.apply(j, raw(j), motions) - raw(j);
        for &(port, i, _, m) in &held.mass {
            self.ports[port].output += dv(i) * (m * inv_h);
        }
        for p in &mut self.ports {
            p.mean_power = p.input.dot(&p.output);
        }
        for &(port, i, j, m) in &held.mass {
            let (dvi, dvj) = (dv(i), dv(j));
            let beyond = m * dvi.dot(&(raw(j) + dvj * 0.5 - x[i] * inv_h));
            self.ports[port].mean_power += beyond * inv_h;
        }
        let mut nodes = h * self.ports.iter().map(|p| p.power()).sum::<f64>();
        if !self.sys.winches.is_empty() {
            nodes += self.winch_reaction_work(h);
        }
        if self.sys.bodies.is_empty() {
            return nodes;
        }
        self.body_ports_prev.clone_from(&self.body_ports);
        let n = self.sys.mesh.n_nodes();
        nodes
            + crate::body_step::port_samples::<D, M>(
                &self.sys,
                &self.run.state.bodies,
                h,
                &self.x[n..],
                (&self.body_wrenches, &self.body_targets),
                (&self.reaction, &mut self.body_scratch),
                &self.bodies_next,
                &mut self.body_ports,
            )
    }

    /// The first node of the first element whose stored energy at the new strains of the
    /// step is not finite, else the first node of the mesh: where a non-finite energy comes
    /// from.
    fn non_finite_energy_node(&self) -> usize {
        let mesh = &self.sys.mesh;
        let bad = self
            .sys
            .each_element()
            .position(|(g, e, _, l)| !(l * g.law.w(self.c_next[e])).is_finite());
        bad.map_or(0, |e| mesh.elements()[e][0])
    }

    /// Like [`Self::run_until`], but ends early once the run has settled (`settle`, static
    /// settling); returns where it came to rest, or `None` if it reached `t_end` first.
    pub fn run_until_settled(
        &mut self,
        t_end: f64,
        settle: Settle,
        observer: &mut dyn Observer<D, M>,
    ) -> Result<(RunSummary, Option<Settled>), StepError> {
        let mut watch = SettleWatch::new(settle);
        watch.update(self.time(), self.energies.kinetic);
        let mut settled = None;
        let summary = self.run_loop(t_end, observer, |sim, report| {
            settled = watch.check(sim, report);
            settled.is_some()
        })?;
        Ok((summary, settled))
    }

    /// Steps until `t_end` [s] (the last step is shortened if it would pass `t_end`), calling
    /// the observer at the start, after every step and at the end.
    pub fn run_until(
        &mut self,
        t_end: f64,
        observer: &mut dyn Observer<D, M>,
    ) -> Result<RunSummary, StepError> {
        self.run_loop(t_end, observer, |_, _| false)
    }

    /// Whether the run has reached `t_end` [s]: its time is within `1e-9` of a step of it
    /// (a step that would land on `t_end` up to rounding is not taken). The end-of-run test
    /// of every loop that drives a simulation to a time.
    /// An end that is not a number counts as reached, so no loop runs on without end.
    pub fn reached(&self, t_end: f64) -> bool {
        let last = t_end - 1e-9 * self.run.h_cur;
        !matches!(
            self.time().partial_cmp(&last),
            Some(std::cmp::Ordering::Less)
        )
    }

    /// Steps until `t_end` [s] or until `done` says so after a step, calling the observer
    /// at the start, after every step and at the end.
    fn run_loop(
        &mut self,
        t_end: f64,
        observer: &mut dyn Observer<D, M>,
        mut done: impl FnMut(&Self, &StepReport) -> bool,
    ) -> Result<RunSummary, StepError> {
        observer.on_start(self);
        let mut summary = RunSummary::default();
        while !self.reached(t_end) {
            if observer.before_step(self).is_break() {
                break;
            }
            let report = self.step_until(t_end)?;
            summary.record(&report);
            if observer.on_step(self, &report).is_break() || done(self, &report) {
                break;
            }
        }
        observer.on_end(self);
        Ok(summary)
    }
}

/// Where a step is: its number, start time [s], size [s] (negative for the backward
/// sub-step of `dg4`) and end time [s].
struct StepAt {
    step: usize,
    t: f64,
    h: f64,
    t_next: f64,
}

/// The retries of one step so far: halvings after failures, rejections (failures and
/// accuracy rejections) and the Newton work they spent.
#[derive(Default)]
struct Retries {
    halvings: u32,
    rejected: usize,
    iterations: usize,
    local: usize,
}

impl Retries {
    /// Records the retries in the accepted step's report.
    fn mark(&self, report: &mut StepReport) {
        report.rejected = self.rejected;
        report.rejected_iterations = self.iterations;
        report.rejected_local_node_iterations = self.local;
    }
}

/// Test support shared by the simulation's test modules.
#[cfg(test)]
mod test_support {
    use super::{Simulation, StepAt, StepControl, StepParams};
    use crate::Material;
    use crate::integrator::StepEquations;
    use crate::linsolve::BlockJacobian;
    use crate::newton::NewtonProblem;
    use crate::system::Vector;

    /// Fixed steps of `h` [s], the defaults otherwise.
    pub(crate) fn fixed_steps(h: f64) -> StepParams {
        StepParams {
            h,
            control: StepControl {
                adaptive: false,
                ..Default::default()
            },
            ..StepParams::default()
        }
    }

    impl<const D: usize> Simulation<D, Material> {
        /// Prepares the next step of `h` [s] (loads, predictor, drums) and returns its
        /// Jacobian at the increment `x` along the direction `dir`, and the central
        /// difference of its residual along `dir` with step `eps`, per row of the Newton
        /// vector.
        pub(crate) fn jacobian_along(
            &mut self,
            h: f64,
            (x, dir): (&[Vector<D>], &[Vector<D>]),
            eps: f64,
        ) -> (Vec<Vector<D>>, Vec<Vector<D>>) {
            let n = self.sys.mesh.n_nodes();
            let t = self.time();
            let mut reaction = vec![Vector::<D>::zeros(); n];
            let mut eqs = StepEquations::new(
                &self.sys,
                self.params.scheme,
                h,
                &self.run.state,
                t + 0.5 * h,
                &self.f_ext,
                &mut reaction,
            );
            eqs.drums = &self.drum_steps;
            let mut jac = BlockJacobian::with_slots(&self.sys.mesh, x.len() - n);
            let mut res = vec![Vector::<D>::zeros(); x.len()];
            eqs.evaluate(x, &mut res, Some(&mut jac)).unwrap();
            let mut jd = vec![Vector::<D>::zeros(); x.len()];
            jac.mul(&self.sys.mesh, dir, &mut jd);
            let mut shifted = |s: f64| {
                let xs: Vec<_> = x.iter().zip(dir).map(|(a, d)| a + d * s).collect();
                let mut r = vec![Vector::<D>::zeros(); x.len()];
                eqs.evaluate(&xs, &mut r, None).unwrap();
                r
            };
            let (plus, minus) = (shifted(eps), shifted(-eps));
            let fd = plus
                .iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * eps))
                .collect();
            (jd, fd)
        }

        /// Brings the simulation to the start of its next step of `h` [s]: its loads
        /// applied, the increment predicted (drum nodes, attached nodes, drums' data).
        pub(crate) fn prepare_step(&mut self, h: f64) {
            let t = self.time();
            let at = StepAt {
                step: self.run.steps + 1,
                t,
                h,
                t_next: t + h,
            };
            self.apply_loads(&at).unwrap();
            self.predict(&at).unwrap();
        }
    }
}
