//! Step reports, run summaries and the observer interface.

use std::ops::ControlFlow;

use crate::system::Energies;

/// Bound on the energy-balance error of a step of an exact scheme (`dg`, `dg4`), relative to
/// the step's energy scale [`StepReport::energy_scale`]: a step whose balance misses it is
/// treated like a failed Newton solve (docs/method.md eq. (9.6)). The examples' steps stay
/// below 1e-15 of the scale.
pub const BALANCE_RTOL: f64 = 1e-11;

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Step index (1 = the first step).
    pub step: usize,
    /// Time at the end of the step `t_{n+1}` [s].
    pub t: f64,
    /// Step size [s].
    pub h: f64,
    /// Newton iterations (linear solves).
    pub newton_iterations: usize,
    /// Line-search backtracks.
    pub backtracks: usize,
    /// Local Newton iterations of nonlinear elimination (on node ranges).
    pub local_iterations: usize,
    /// `Σ` range length × local iterations: the local work in node-iterations (a global
    /// iteration costs one per node).
    pub local_node_iterations: usize,
    /// Attempts rejected (and retried with a smaller step) before this step.
    pub rejected: usize,
    /// Newton iterations (linear solves) spent in those rejected attempts.
    pub rejected_iterations: usize,
    /// Local node-iterations of nonlinear elimination spent in those rejected attempts.
    pub rejected_local_node_iterations: usize,
    /// Final Newton residual norm [N].
    pub residual: f64,
    /// The Newton tolerance of this step [N]: `max(tol, rtol · F)` (docs/method.md §9).
    pub tolerance: f64,
    /// The step's force scale `F` [N] (docs/method.md §9).
    pub force_scale: f64,
    /// Newton ended at the round-off floor of the residual (stagnation below
    /// `ε (1000 F + 16 K)`, docs/method.md eq. (9.4)) rather than below `tolerance`.
    pub at_roundoff: bool,
    /// Energies at `t_n` [J].
    pub before: Energies,
    /// Energies at `t_{n+1}` [J].
    pub after: Energies,
    /// Energy supplied in this step [J]: through the ports, `h û_{n+½}·ŷ_{n+½}`, and by the
    /// current through the drag (`water.current_supplied`, docs/method.md §21), and by the
    /// winches (`winch`, §23).
    pub supplied: f64,
    /// Energy dissipated in this step `D_n ≥ 0` [J]: the damping of docs/method.md §18 and the
    /// water's drag, seabed damping and friction (§21); 0 without any.
    pub dissipated: f64,
    /// The water's shares of `supplied` and `dissipated` (all 0 without water).
    pub water: crate::water::WaterWork,
    /// The winches' share of `supplied` [J] (docs/method.md §23): the energy their payout
    /// changes bring in (negative: take out); 0 without winches.
    pub winch: f64,
    /// Energy-balance error `Ĥ_{n+1} − Ĥ_n − h û·ŷ + D_n` [J].
    pub balance_error: f64,
    /// The step's energy scale [J]: the magnitudes of the energy terms at both ends of the
    /// step ([`crate::system::Energies::magnitude`]) plus `|h P|` of each port and `D_n`
    /// (for `dg4`, the sum over its sub-steps). The balance error of an exact step is
    /// rounding of order `ε` times this; see [`BALANCE_RTOL`].
    pub energy_scale: f64,
}

impl StepReport {
    /// `|balance_error| / energy_scale` (0 for a step with no energy at all).
    pub fn relative_balance_error(&self) -> f64 {
        if self.energy_scale > 0.0 {
            self.balance_error.abs() / self.energy_scale
        } else {
            self.balance_error.abs()
        }
    }
}

/// Totals over a run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunSummary {
    /// Steps taken.
    pub steps: usize,
    /// Newton iterations in all.
    pub newton_iterations: usize,
    /// Largest `|balance_error|` [J].
    pub max_balance_error: f64,
    /// Largest balance error relative to its step's energy scale
    /// ([`StepReport::relative_balance_error`]).
    pub max_relative_balance_error: f64,
    /// Largest Newton residual at convergence [N].
    pub max_residual: f64,
    /// Rejected step attempts.
    pub rejected: usize,
    /// Steps whose Newton solve ended at the round-off floor.
    pub at_roundoff: usize,
}

/// The larger of `a` and `b`, NaN if either is NaN (unlike [`f64::max`], which drops a NaN,
/// so that a NaN never disappears from a running maximum).
pub fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

impl RunSummary {
    /// Adds one step.
    pub fn record(&mut self, r: &StepReport) {
        self.steps += 1;
        self.newton_iterations += r.newton_iterations;
        self.max_balance_error = nan_max(self.max_balance_error, r.balance_error.abs());
        self.max_relative_balance_error =
            nan_max(self.max_relative_balance_error, r.relative_balance_error());
        self.max_residual = nan_max(self.max_residual, r.residual);
        self.rejected += r.rejected;
        self.at_roundoff += usize::from(r.at_roundoff);
    }
}

/// Static settling: a run that ends once the string has come to rest, `T̂ < kinetic` for at
/// least `hold` seconds. The watch arms only once `T̂` has been at or above `kinetic` (a run
/// that starts at rest does not stop at once).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settle {
    /// Kinetic-energy threshold [J] (> 0).
    pub kinetic: f64,
    /// How long `T̂` must stay below it [s] (≥ 0; 0: the first step below it). Use about a
    /// period of the slowest swing, so that a turning point, where `T̂` dips, is not taken
    /// for rest.
    pub hold: f64,
}

/// Where and when a run came to rest ([`Settle`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settled {
    /// Time [s] at the end of the step that met the criterion.
    pub t: f64,
    /// That step's index.
    pub step: usize,
    /// Kinetic energy `T̂` there [J].
    pub kinetic: f64,
    /// The fastest node there.
    pub node: usize,
    /// Its speed [m/s].
    pub speed: f64,
}

/// Watches a run for [`Settle`]: call [`SettleWatch::check`] after every step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettleWatch {
    settle: Settle,
    armed: bool,
    /// Start of the current stretch below the threshold [s].
    since: Option<f64>,
}

impl SettleWatch {
    /// A watch for `settle` (armed once `T̂ ≥ settle.kinetic`); call [`Self::update`] with
    /// the initial state's `(0, T̂(0))` too, so that a run that starts moving is armed from
    /// the start. A threshold that is not positive and finite never settles.
    pub fn new(settle: Settle) -> Self {
        Self {
            settle,
            armed: false,
            since: None,
        }
    }
    /// The watch's progress, to store in a checkpoint: `(armed, start of the current
    /// stretch below the threshold [s])`.
    pub fn progress(&self) -> (bool, Option<f64>) {
        (self.armed, self.since)
    }
    /// A watch for `settle` that continues from `progress` ([`Self::progress`]).
    pub fn resume(settle: Settle, progress: (bool, Option<f64>)) -> Self {
        Self {
            settle,
            armed: progress.0,
            since: progress.1,
        }
    }
    /// After a step that ended at time `t` [s] with kinetic energy `kinetic` [J]: whether
    /// the run has settled.
    pub fn update(&mut self, t: f64, kinetic: f64) -> bool {
        if !(self.settle.kinetic > 0.0 && self.settle.kinetic.is_finite()) {
            return false;
        }
        // NaN counts as not at rest.
        let below = kinetic < self.settle.kinetic;
        if !below {
            self.armed = true;
            self.since = None;
            return false;
        }
        if !self.armed {
            return false;
        }
        let since = *self.since.get_or_insert(t);
        t - since >= self.settle.hold
    }
    /// [`Self::update`] with the simulation's state after its last step (`report`): where
    /// it came to rest, if it has.
    pub fn check<const D: usize, M: crate::StoredEnergy>(
        &mut self,
        sim: &crate::Simulation<D, M>,
        report: &StepReport,
    ) -> Option<Settled> {
        let kinetic = report.after.kinetic;
        if !self.update(report.t, kinetic) {
            return None;
        }
        let (node, speed) = fastest_node(&sim.state().v);
        Some(Settled {
            t: report.t,
            step: report.step,
            kinetic,
            node,
            speed,
        })
    }
}

/// The fastest node of the velocities `v` [m/s] and its speed (node 0 and 0 if all are at
/// rest).
pub fn fastest_node<const D: usize>(v: &[crate::Vector<D>]) -> (usize, f64) {
    v.iter().map(|x| x.norm()).enumerate().fold(
        (0, 0.0),
        |best, (i, s)| if s > best.1 { (i, s) } else { best },
    )
}

/// Receives the simulation at the start, before and after each step and at the end of a run
/// driven by [`Simulation::run_until`](crate::Simulation::run_until): the one loop that
/// drives a run to its end. Everything that records or watches a run (files, progress, a
/// script's recorder, stop requests) is an observer; the library never prints. An observer
/// that returns [`ControlFlow::Break`] ends the run there (the simulation keeps the state of
/// its last step); one that meets an error keeps it and breaks.
pub trait Observer<const D: usize, M> {
    /// Before the first step.
    fn on_start(&mut self, _sim: &crate::Simulation<D, M>) {}
    /// Before each step; `Break` ends the run before it.
    fn before_step(&mut self, _sim: &crate::Simulation<D, M>) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    /// After each successful step; `Break` ends the run after it.
    fn on_step(&mut self, _sim: &crate::Simulation<D, M>, _report: &StepReport) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    /// After the last step (not after a failed one: the step's error ends the run).
    fn on_end(&mut self, _sim: &crate::Simulation<D, M>) {}
}

/// An observer that does nothing.
impl<const D: usize, M> Observer<D, M> for () {}
