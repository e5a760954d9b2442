//! Runs a validated scenario into an output folder (the work behind `phstring run`):
//! outputs written as the run goes, checkpoints, interruption, resume.
//!
//! An output folder carries the id of the run that writes it ([`RUN_ID_FILE`], also in
//! `summary.json` and in every checkpoint); a resume into a folder with another id is
//! refused, so that a checkpoint can never overwrite another run. `summary.json` is
//! replaced atomically, written before the plots and again after them, and a run that fails
//! on an I/O error still tries to leave a summary with `"status": "failed"`.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use phstring::{Material, SettleWatch, Simulation, StepError, StepReport};
use serde::Serialize;

use super::campaign::LineWatch;
use super::water::WaterSummary;
use crate::checkpoint::{CheckpointError, CheckpointFile, Counters, FORMAT};
use crate::extremes::LineExtremes;
use crate::figures::{draw_animation, draw_plots};
use crate::files::{
    CHECKPOINT, COMPONENTS_FILE, RUN_ID_FILE, SCENARIO_FILE, SNAPSHOTS, SUMMARY_FILE, atomic_write,
    new_run_id, overwrite_in_place, read_run_id,
};
use crate::history::{History, read_history};
use crate::output::{self, OutputError, Writers};
use crate::scenario::{
    AnySetup, Components, RunSettings, ScenarioError, ScenarioFile, Setup, StartError,
};
use crate::scene::Scene;

pub use phstring::nan_max;

/// Refuses to resume `cp` into `out` unless `out` carries the run id of the run that wrote
/// the checkpoint.
pub fn check_resume_folder(cp: &CheckpointFile, out: &Path) -> Result<(), CheckpointError> {
    let found = read_run_id(out);
    if found.as_deref() == Some(cp.run_id.as_str()) {
        return Ok(());
    }
    let checkpoint_dir = cp
        .path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    Err(CheckpointError::OtherRun {
        path: cp.path.clone(),
        checkpoint_dir,
        out: out.to_path_buf(),
        expected: cp.run_id.clone(),
        found,
    })
}

/// Receives progress of a run (a progress bar, or nothing).
pub trait Progress {
    /// The run starts and will end at simulated time `t_end` [s].
    fn start(&mut self, _t_end: f64) {}
    /// Step `step` finished at time `t` [s].
    fn step(&mut self, _step: usize, _t: f64) {}
    /// The run ended.
    fn finish(&mut self) {}
}

/// No progress reporting.
impl Progress for () {}

/// Options of a run beyond the scenario.
#[derive(Default)]
pub struct RunOptions {
    /// End of a loading phase to mark in the increments plot [s].
    pub end_of_loading: Option<f64>,
    /// Write `checkpoint.json` every this many steps.
    pub checkpoint_every: Option<usize>,
    /// Stop (as if interrupted) after this many steps in all.
    pub stop_after_steps: Option<usize>,
    /// Set (e.g. by Ctrl-C) to stop: a step under way ends between two Newton iterations
    /// and is not taken (the state stays at the last good step), a checkpoint is written,
    /// and the plots not yet drawn are skipped.
    pub stop: Option<Arc<AtomicBool>>,
    /// Continue from this checkpoint instead of starting at `t = 0`.
    pub resume: Option<CheckpointFile>,
}

/// Most components (named nodes, strings, springs, point masses, supports, motions, loads
/// and controls together) that `summary.json` lists itself; a larger network has them in
/// [`COMPONENTS_FILE`] (compact JSON), and `summary.json` counts them.
pub const SUMMARY_COMPONENTS: usize = 1000;

/// Longest scenario text [bytes] that `summary.json` holds itself (as JSON); a longer one is
/// in [`SCENARIO_FILE`] (compact JSON).
pub const SUMMARY_SCENARIO_BYTES: usize = 64 << 10;

/// Spaces after the summary written when a run starts (`"status": "running"`): room for
/// the final summary to be written over it in place when a full disk leaves no room for a
/// new file ([`write_summary`]).
pub const SUMMARY_RESERVE: usize = 4096;

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The simulation could not be set up.
    #[error("setup failed: {0}")]
    Setup(phstring::SetupError),
    /// A step failed; outputs up to the last good step are written.
    #[error("{0}{1} (outputs up to the last good step are in {2})")]
    Step(StepError, String, PathBuf),
    /// Writing outputs failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Writing an output failed during the run (a full disk): what was written stays, each
    /// CSV file cut back to its last whole row; `note` says where the outputs are, which
    /// are incomplete, and whether `summary.json` records the failure.
    #[error("{cause}; {note}")]
    Incomplete {
        /// The write that failed.
        cause: Box<RunError>,
        /// Where the outputs are and what became of them.
        note: String,
    },
    /// Reading or writing a checkpoint failed.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The starting equilibrium (`initial.equilibrium`) was not found.
    #[error("initial.equilibrium: {0}")]
    Statics(phstring::statics::StaticsError),
    /// The run was stopped (Ctrl-C or `--stop-after-steps`); it can be resumed.
    #[error("interrupted at t = {} s after {steps} steps; outputs so far are in {}; continue with `phstring run --resume {}`", phstring::Num(*t), dir.display(), checkpoint.display())]
    Interrupted {
        /// Time reached [s].
        t: f64,
        /// Steps done.
        steps: usize,
        /// Output folder.
        dir: PathBuf,
        /// Checkpoint to resume from.
        checkpoint: PathBuf,
    },
}

impl RunError {
    /// Whether a stop request (Ctrl-C, `--stop-after-steps`) ended the run: in its time loop
    /// ([`RunError::Interrupted`], resumable) or in the starting equilibrium
    /// (`initial.equilibrium`, before anything is written).
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            RunError::Interrupted { .. }
                | RunError::Statics(phstring::statics::StaticsError::Interrupted)
        )
    }
}

impl From<StartError> for RunError {
    fn from(e: StartError) -> Self {
        match e {
            StartError::Scenario(e) => RunError::Scenario(e),
            StartError::Statics(e) => RunError::Statics(e),
            StartError::Setup(e) => RunError::Setup(e),
        }
    }
}

impl From<phstring::SetupError> for RunError {
    fn from(e: phstring::SetupError) -> Self {
        RunError::Setup(e)
    }
}

/// What a run did: the content of `summary.json` plus the in-memory history.
#[derive(Debug, Clone, Serialize)]
pub struct RunInfo {
    /// Always `"phstring"`.
    pub program: &'static str,
    /// Program version.
    pub version: &'static str,
    /// `completed`, `failed` or `interrupted`; `running` in the summary written when the
    /// run starts (a summary that still says so belongs to a run that was killed).
    pub status: String,
    /// The reason for a failure.
    pub error: Option<String>,
    /// Title of the scenario.
    pub title: Option<String>,
    /// Spatial dimension.
    pub dimension: usize,
    /// Number of elements.
    pub elements: usize,
    /// The components (strings, springs, point masses, supports, motions, loads, controls,
    /// named nodes) with their mesh nodes and elements; for a network of more than
    /// [`SUMMARY_COMPONENTS`] entries, their counts and the file that lists them
    /// ([`COMPONENTS_FILE`]).
    pub components: serde_json::Value,
    /// Scheme (`dg` or `mp`).
    pub scheme: &'static str,
    /// Linear solver used.
    pub solver: &'static str,
    /// Step size [s] (largest with step-size control).
    pub h: f64,
    /// End time [s].
    pub t_end: f64,
    /// Steps planned (`T/h`; more when step-size control shortens steps).
    pub steps_planned: usize,
    /// Steps completed.
    pub steps: usize,
    /// Whether step-size control was on.
    pub adaptive: bool,
    /// Step attempts rejected and retried with a smaller step (Newton failure: half; error control: its cut).
    pub rejected_steps: usize,
    /// Smallest accepted step size [s].
    pub h_min_used: f64,
    /// Line-search backtracks in all.
    pub line_search_backtracks: usize,
    /// Newton iterations spent in rejected step attempts (not in `total_newton_iterations`).
    pub rejected_newton_iterations: usize,
    /// Local Newton iterations of nonlinear elimination in all (not in
    /// `total_newton_iterations`).
    pub local_newton_iterations: usize,
    /// Their work in global-iteration equivalents: `Σ` range length × local iterations,
    /// divided by the number of nodes.
    pub local_newton_work: f64,
    /// Simulated time reached [s].
    pub t_reached: f64,
    /// Newton iterations in all.
    pub total_newton_iterations: usize,
    /// Newton convergence test.
    pub newton_norm: &'static str,
    /// Newton tolerance [N]: the absolute floor under `newton_rtol · F`, or, with
    /// `newton_rtol = 0`, the absolute tolerance.
    pub newton_tol: f64,
    /// Newton tolerance relative to each step's force scale `F` (0: absolute test).
    pub newton_rtol: f64,
    /// Steps whose Newton solve ended at the round-off floor of the residual (docs/method.md
    /// §9) instead of below the tolerance.
    pub steps_at_roundoff: usize,
    /// Error control (`time.rtol`, `time.atol`): steps accepted at the smallest step size
    /// although their error estimate exceeded the tolerance (a warning says so).
    pub steps_over_tolerance: usize,
    /// Largest `|Ĥ_{n+1} − Ĥ_n − h û·ŷ|` [J].
    pub max_balance_error: f64,
    /// Largest balance error of a step relative to that step's energy scale (the magnitudes
    /// of its energy terms, docs/method.md eq. (9.6)). An accepted step of `dg` or `dg4` stays
    /// within `balance_bound`; `mp` is not exact and reports what it gives.
    pub max_relative_balance_error: f64,
    /// The bound on the relative balance error of every accepted step of an exact scheme.
    pub balance_bound: f64,
    /// Largest Newton residual at convergence [N].
    pub max_newton_residual: f64,
    /// `Ĥ(0)` [J].
    pub hamiltonian_initial: f64,
    /// `Ĥ` at the last completed step [J].
    pub hamiltonian_final: f64,
    /// Cumulative dissipated energy `Σ D_n` at the last completed step [J] (0 without
    /// damping).
    pub dissipated_energy: f64,
    /// In water (docs/method.md §21): the energy each mechanism dissipated or supplied
    /// [J], the final buoyancy and seabed energies [J], per string its grounded length at
    /// the end and the smallest over the run [m], and the largest seabed contact force [N]
    /// (see [`WaterSummary`]); absent without water.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub water: Option<WaterSummary>,
    /// Per line (string), in the column order of `end_tensions.csv`: its extreme end
    /// tensions, smallest grounded length and slack, sampled at `t = 0` and every step
    /// (see [`LineExtremes`]); absent without strings, and after a resume from a checkpoint
    /// that lacks them. For more than [`SUMMARY_COMPONENTS`] lines, `summary.json` has
    /// their count only (`{"count": N}`; a sweep's `campaign.csv` lists them all).
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "super::campaign::summary_lines"
    )]
    pub lines: Option<Vec<LineExtremes>>,
    /// With `time.settle`: where and when the run came to rest (it then ended before
    /// `t_end`), or `settled: false` with the state at the end if it did not; absent
    /// without `time.settle`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settled: Option<SettledInfo>,
    /// The rigid bodies with their state at the last completed step (at the start in the
    /// summary written when the run starts); absent without bodies.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySummary>,
    /// The winches at the last completed step (at the start in the summary written when the
    /// run starts); absent without winches.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub winches: Vec<WinchSummary>,
    /// Progress of the `time.settle` watch `(armed, since)`, carried in checkpoints.
    #[serde(skip)]
    pub settle_progress: (bool, Option<f64>),
    /// Wall time of the time loop alone (stepping, no output) [s], summed over resumes.
    pub time_loop_s: f64,
    /// Whether the run was resumed from a checkpoint.
    pub resumed: bool,
    /// With `initial.equilibrium`: how the starting equilibrium was found (path, steps,
    /// iterations, residual); absent otherwise and on a resume.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub initial_equilibrium: Option<String>,
    /// Id of the run (also in the folder's [`RUN_ID_FILE`] and in its checkpoints).
    pub run_id: String,
    /// Plots written (stems, each as `.svg` and `.png`).
    pub plots: Vec<String>,
    /// Plots not written (degenerate or extreme data, a stop request, a failure); the
    /// reasons are in `warnings`.
    pub plots_skipped: Vec<String>,
    /// Problems that did not fail the run (e.g. a plot that could not be drawn).
    pub warnings: Vec<String>,
    /// Outputs (relative to the run folder) that a failed write left short of the steps the
    /// run took (see [`Writers::incomplete_files`]); empty unless a write failed.
    pub incomplete_files: Vec<String>,
    /// For a scenario generated from a MoorDyn deck: the deck, its conversions, the entries
    /// phstring does not need and the features dropped with `--ignore` (the scenario's
    /// `[deck]` table); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deck: Option<crate::scenario::DeckSpec>,
    /// The scenario as run (after `--set` overrides); for a scenario text longer than
    /// [`SUMMARY_SCENARIO_BYTES`], the file that holds it ([`SCENARIO_FILE`]).
    pub scenario: serde_json::Value,
    /// Energies read back from `energy.csv` after the run, decimated to at most
    /// [`output::PLOT_POINTS`] points per curve, and the configuration snapshots (not
    /// serialized; empty if `output.plots` is off or the run was stopped before it was read).
    #[serde(skip)]
    pub history: History,
}

/// A rigid body and its state, in `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BodySummary {
    /// Name.
    pub name: String,
    /// Mass [kg].
    pub mass: f64,
    /// Position of the centre of mass [m] (3 components, `z = 0` in 2D).
    pub position: [f64; 3],
    /// Orientation, the unit quaternion `[w, x, y, z]` from body axes to space.
    pub orientation: [f64; 4],
    /// Velocity of the centre of mass [m/s].
    pub velocity: [f64; 3],
    /// Angular velocity in space axes `ω = R Ω` [rad/s].
    pub angular_velocity: [f64; 3],
}

/// A winch at the last completed step (docs/method.md §23).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WinchSummary {
    /// Name.
    pub name: String,
    /// Length paid out since `t = 0` [m] (negative: hauled in).
    pub payout: f64,
    /// The string's reference length off the drum [m].
    pub length: f64,
    /// Tension of the element at the drum [N].
    pub tension: f64,
    /// Energy the winch supplied since `t = 0` [J] (negative: taken), its share of
    /// `supplied_energy`.
    pub energy: f64,
    /// The string's mass off the drum [kg].
    pub mass: f64,
}

/// The winches of `sim` at its current state.
fn winch_summaries<const D: usize>(sim: &Simulation<D, Material>) -> Vec<WinchSummary> {
    sim.system()
        .winches()
        .into_iter()
        .zip(sim.winch_samples())
        .map(|((name, _), s)| WinchSummary {
            name: name.to_string(),
            payout: s.payout,
            length: s.length,
            tension: s.tension,
            energy: s.energy,
            mass: s.mass,
        })
        .collect()
}

/// The rigid bodies of `sim` with their current states.
fn body_summaries<const D: usize>(sim: &Simulation<D, Material>) -> Vec<BodySummary> {
    sim.system()
        .bodies()
        .into_iter()
        .zip(&sim.state().bodies)
        .map(|((name, mass), st)| {
            let q = st.orientation.quaternion();
            let w = st.omega_space();
            BodySummary {
                name: name.to_string(),
                mass,
                position: [st.position.x, st.position.y, st.position.z],
                orientation: [q.w, q.i, q.j, q.k],
                velocity: [st.velocity.x, st.velocity.y, st.velocity.z],
                angular_velocity: [w.x, w.y, w.z],
            }
        })
        .collect()
}

/// Records the end of the run of `sim` in `info`: the time reached, the smallest step, the
/// final energies and the bodies' final states.
fn record_end<const D: usize>(info: &mut RunInfo, sim: &Simulation<D, Material>) {
    info.t_reached = sim.time();
    info.h_min_used = sim.smallest_step_size();
    info.hamiltonian_final = sim.energies().hamiltonian();
    info.dissipated_energy = sim.dissipated_energy();
    info.bodies = body_summaries(sim);
    info.winches = winch_summaries(sim);
}

/// Where and when a run with `time.settle` came to rest.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SettledInfo {
    /// Whether it settled before `time.end`.
    pub settled: bool,
    /// Time [s] at which it met the criterion (the end time reached if it did not).
    pub t: f64,
    /// Step index.
    pub step: usize,
    /// Kinetic energy there [J].
    pub kinetic: f64,
    /// The threshold [J].
    pub threshold: f64,
    /// The hold time [s].
    pub hold: f64,
    /// The fastest node there.
    pub fastest_node: usize,
    /// Its speed [m/s].
    pub speed: f64,
}

/// Runs `file` into folder `out` (created if needed). Writes all outputs as it goes; on a
/// step failure or an interruption the outputs up to the last good step and a
/// `summary.json` with `"status": "failed"` / `"interrupted"` are written before the error
/// is returned.
pub fn run(
    file: &ScenarioFile,
    out: &Path,
    progress: &mut dyn Progress,
    opts: RunOptions,
) -> Result<RunInfo, RunError> {
    run_setup(file, file.setup()?, out, progress, opts)
}

/// [`run`] of `file` validated and built already (`setup`, from [`ScenarioFile::setup`]).
pub fn run_setup(
    file: &ScenarioFile,
    setup: AnySetup,
    out: &Path,
    progress: &mut dyn Progress,
    opts: RunOptions,
) -> Result<RunInfo, RunError> {
    phstring::by_dim!(setup, s => run_dim(file, s, out, progress, opts))
}

/// What a run needs besides the simulation and the writers, shared by its parts.
struct RunContext<'a> {
    file: &'a ScenarioFile,
    out: &'a Path,
    settings: RunSettings,
    run_id: String,
    end_of_loading: Option<f64>,
    checkpoint_path: PathBuf,
    /// How the extremes of the lines are sampled (`None` without strings).
    lines: Option<LineWatch>,
    /// The data files the scenario reads, fingerprinted at the start (for the checkpoints).
    data_files: Vec<crate::checkpoint::DataFile>,
}

fn run_dim<const D: usize>(
    file: &ScenarioFile,
    setup: Setup<D>,
    out: &Path,
    progress: &mut dyn Progress,
    mut opts: RunOptions,
) -> Result<RunInfo, RunError> {
    // The starting equilibrium, then the scenario's displacement and velocity on it; a
    // resume takes its state from the checkpoint instead.
    let (v, initial_equilibrium) = setup.start(opts.resume.is_none(), opts.stop.as_deref())?;
    let settings = v.settings;
    let load_error = v.load_error;
    let scenario_warnings = v.warnings;
    let components = v.components;
    let mut sim = v.problem;
    sim.set_stop_flag(opts.stop.clone());
    let resume = opts.resume.take();
    let ends = super::ends::end_forces(file, &components, sim.system());
    let ctx = RunContext {
        file,
        out,
        run_id: resume
            .as_ref()
            .map_or_else(|| new_run_id(out), |cp| cp.run_id.clone()),
        end_of_loading: resume
            .as_ref()
            .map_or(opts.end_of_loading, |cp| cp.end_of_loading),
        checkpoint_path: out.join(CHECKPOINT),
        settings,
        lines: ends.clone().map(|e| LineWatch::new(e, sim.system())),
        data_files: crate::checkpoint::data_files(file),
    };
    let mut info = new_info(&ctx, &sim, &components, resume.is_some());
    info.lines = ctx
        .lines
        .as_ref()
        .map(|w| w.start(&sim, info.water.as_ref()));
    info.initial_equilibrium = initial_equilibrium;
    info.warnings = scenario_warnings;
    let fresh = resume.is_none();
    let channels = match super::ends::channel_table(file, &components, ends.as_ref()) {
        Ok(c) => c,
        Err(e) => {
            let e = RunError::from(e);
            if fresh {
                let _ = record_failure(out, &mut info, &e);
            }
            return Err(e);
        }
    };
    let writers = match resume {
        Some(cp) => resume_writers(&ctx, &mut sim, &mut info, cp),
        None => start_writers(&ctx, &sim, &components).map_err(RunError::from),
    };
    drop(components);
    let writers = writers.and_then(|mut w| {
        w.set_row_stride(ctx.settings.row_stride);
        if let Some(model) = ends {
            w.end_tensions(model, &sim)?;
        }
        if let Some((model, name)) = channels {
            w.channels(model, &name, &sim)?;
        }
        Ok(w)
    });
    let mut writers = match writers.and_then(|w| write_running_summary(out, &mut info).map(|()| w))
    {
        Ok(w) => w,
        Err(e) => {
            if fresh {
                let _ = record_failure(out, &mut info, &e);
            }
            return Err(e);
        }
    };
    progress.start(ctx.settings.t_end);
    let looped = step_loop(&ctx, &mut sim, &mut writers, &mut info, progress, &opts);
    progress.finish();
    record_end(&mut info, &sim);
    if let Some(w) = &mut info.water {
        w.finish(&sim);
    }
    if let Some(w) = over_tolerance_warning(&info, &ctx.settings) {
        info.warnings.push(w);
    }
    let (failure, interrupted) = match looped {
        Ok(outcome) => outcome,
        Err(e) => return Err(fail_writing(out, &mut info, &mut writers, e, sim.time())),
    };
    let detail = match &failure {
        Some(e) if e.is_input_failure() => load_error
            .lock()
            .ok()
            .and_then(|m| m.clone())
            .map(|m| format!(": {m}"))
            .unwrap_or_default(),
        _ => String::new(),
    };
    if let Some(e) = &failure {
        info.status = "failed".into();
        info.error = Some(format!("{e}{detail}"));
    } else if interrupted {
        info.status = "interrupted".into();
        info.error = Some(format!(
            "interrupted at t = {} s; resume from {CHECKPOINT}",
            phstring::Num(sim.time())
        ));
    } else if ctx.checkpoint_path.exists() {
        // A completed run needs no checkpoint; a stale one could be resumed by mistake.
        let _ = std::fs::remove_file(&ctx.checkpoint_path);
    }
    // The summary is on disk before the plots, whatever happens to them.
    write_summary(out, &info)?;
    let mut scene = super::ends::scene(file, &writers);
    info.warnings.extend(super::ends::add_bodies(
        &mut scene,
        &sim,
        out,
        writers.snapshots(),
    ));
    if ctx.settings.output.plots {
        draw(&ctx, (&writers, &scene), &mut info, opts.stop.as_deref())?;
    }
    // The animation reads positions.csv back; without it (output.positions = false) there is
    // nothing to animate. Written for failed runs too: it shows how far the run got.
    if ctx.settings.animation && ctx.settings.output.positions && info.dimension >= 2 {
        let title = ctx.file.scenario.title.as_deref().unwrap_or("phstring");
        // Its frames' nodes on the seabed: the run's own contact test (a copy of the system).
        scene.contact = crate::scene::ContactTest::of(sim.system());
        let anim = draw_animation(out, info.dimension, (title, &scene), opts.stop.as_deref());
        info.plots.extend(anim.written);
        info.plots_skipped.extend(anim.skipped);
        info.warnings.extend(anim.warnings);
        write_summary(out, &info)?;
    }
    if let Some(e) = failure {
        return Err(RunError::Step(e, detail, out.to_path_buf()));
    }
    if interrupted {
        return Err(RunError::Interrupted {
            t: sim.time(),
            steps: info.steps,
            dir: out.to_path_buf(),
            checkpoint: ctx.checkpoint_path,
        });
    }
    Ok(info)
}

/// The warning for steps that error control accepted at its step-size floor although their
/// error estimate exceeded the tolerance (docs/method.md §19: such a step is accepted
/// whatever its error), or `None` if there were none.
fn over_tolerance_warning(info: &RunInfo, settings: &RunSettings) -> Option<String> {
    let n = info.steps_over_tolerance;
    if n == 0 {
        return None;
    }
    let c = &settings.step.control;
    Some(format!(
        "{n} of {} steps missed the error tolerance (time.rtol = {}, time.atol = {}): error control accepted them at its smallest step size time.h/2^time.max_halvings = {} s whatever their error estimate; loosen the tolerance, or allow smaller steps with time.max_halvings",
        info.steps,
        phstring::Num(c.rtol),
        phstring::Num(c.atol),
        phstring::Num(info.h / 2f64.powi(settings.step.control.max_halvings as i32))
    ))
}

/// The summary of a run that has not taken a step yet.
fn new_info<const D: usize>(
    ctx: &RunContext,
    sim: &Simulation<D, Material>,
    components: &Components,
    resumed: bool,
) -> RunInfo {
    let settings = &ctx.settings;
    RunInfo {
        program: "phstring",
        version: env!("CARGO_PKG_VERSION"),
        status: "completed".into(),
        error: None,
        title: ctx.file.scenario.title.clone(),
        dimension: D,
        elements: sim.system().mesh().n_elements(),
        components: components_entry(components),
        scheme: settings.step.scheme.name(),
        solver: sim.solver_name(),
        h: settings.step.h,
        t_end: settings.t_end,
        steps_planned: (settings.t_end / settings.step.h).round() as usize,
        steps: 0,
        adaptive: settings.step.control.adaptive,
        rejected_steps: 0,
        h_min_used: settings.step.h,
        line_search_backtracks: 0,
        rejected_newton_iterations: 0,
        local_newton_iterations: 0,
        local_newton_work: 0.0,
        t_reached: 0.0,
        total_newton_iterations: 0,
        newton_norm: "Euclidean norm of the force residual (momentum balance / h) over free DOFs [N], at most max(newton_tol, newton_rtol × force scale of the step)",
        newton_tol: settings.step.newton.tol,
        newton_rtol: settings.step.newton.rtol,
        steps_at_roundoff: 0,
        steps_over_tolerance: 0,
        max_balance_error: 0.0,
        max_relative_balance_error: 0.0,
        balance_bound: phstring::observe::BALANCE_RTOL,
        max_newton_residual: 0.0,
        hamiltonian_initial: sim.energies().hamiltonian(),
        hamiltonian_final: sim.energies().hamiltonian(),
        dissipated_energy: 0.0,
        water: WaterSummary::start(sim),
        lines: None,
        settled: None,
        bodies: body_summaries(sim),
        winches: winch_summaries(sim),
        settle_progress: (false, None),
        time_loop_s: 0.0,
        resumed,
        initial_equilibrium: None,
        run_id: ctx.run_id.clone(),
        plots: Vec::new(),
        plots_skipped: Vec::new(),
        warnings: Vec::new(),
        incomplete_files: Vec::new(),
        deck: ctx.file.scenario.deck.clone(),
        scenario: scenario_entry(ctx.file),
        history: History::default(),
    }
}

/// Number of entries of `c` (named nodes, strings, springs, point masses, supports,
/// motions, loads, controls).
fn component_count(c: &Components) -> usize {
    c.nodes.len()
        + c.strings.len()
        + c.springs.len()
        + c.point_masses.len()
        + c.supports.len()
        + c.motions.len()
        + c.loads.len()
        + c.controls.len()
}

/// The `components` of `summary.json`: the components themselves, or for more than
/// [`SUMMARY_COMPONENTS`] entries the file that lists them and their counts per kind.
fn components_entry(c: &Components) -> serde_json::Value {
    if component_count(c) <= SUMMARY_COMPONENTS {
        return serde_json::to_value(c).unwrap_or(serde_json::Value::Null);
    }
    serde_json::json!({
        "file": COMPONENTS_FILE,
        "nodes": c.nodes.len(),
        "strings": c.strings.len(),
        "springs": c.springs.len(),
        "point_masses": c.point_masses.len(),
        "supports": c.supports.len(),
        "motions": c.motions.len(),
        "loads": c.loads.len(),
        "controls": c.controls.len(),
    })
}

/// The `scenario` of `summary.json`: the scenario as run, or for a text longer than
/// [`SUMMARY_SCENARIO_BYTES`] the file that holds it.
fn scenario_entry(file: &ScenarioFile) -> serde_json::Value {
    if file.text().len() <= SUMMARY_SCENARIO_BYTES {
        return serde_json::to_value(&file.scenario).unwrap_or(serde_json::Value::Null);
    }
    serde_json::json!({ "file": SCENARIO_FILE })
}

/// Writes [`COMPONENTS_FILE`] and [`SCENARIO_FILE`] (compact JSON) into `out` when
/// `summary.json` refers to them, and removes stale ones of an earlier run when it does not.
fn write_large_parts(
    out: &Path,
    file: &ScenarioFile,
    components: &Components,
) -> Result<(), OutputError> {
    let components_json =
        (component_count(components) > SUMMARY_COMPONENTS).then(|| serde_json::to_vec(components));
    let scenario_json =
        (file.text().len() > SUMMARY_SCENARIO_BYTES).then(|| serde_json::to_vec(&file.scenario));
    for (name, json) in [
        (COMPONENTS_FILE, components_json),
        (SCENARIO_FILE, scenario_json),
    ] {
        let path = out.join(name);
        match json {
            Some(json) => {
                let mut bytes = json.map_err(|e| OutputError::Io {
                    path: path.clone(),
                    cause: std::io::Error::other(e),
                })?;
                bytes.push(b'\n');
                atomic_write(&path, &bytes).map_err(|cause| OutputError::Io { path, cause })?;
            }
            None if std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file()) => {
                let _ = std::fs::remove_file(&path);
            }
            None => {}
        }
    }
    Ok(())
}

/// The times of the configuration snapshots: `t_end · k / (SNAPSHOTS − 1)`.
fn snapshot_times(t_end: f64) -> Vec<f64> {
    (0..SNAPSHOTS)
        .map(|k| t_end * k as f64 / (SNAPSHOTS - 1) as f64)
        .collect()
}

/// Creates the outputs of a fresh run (and the folder's run id, and the files of a large
/// network's components and scenario).
fn start_writers<const D: usize>(
    ctx: &RunContext,
    sim: &Simulation<D, Material>,
    components: &Components,
) -> Result<Writers, OutputError> {
    let s = &ctx.settings;
    let w = Writers::start(
        ctx.out,
        sim,
        s.stride,
        s.output.positions,
        s.output.vtk,
        snapshot_times(s.t_end),
    )?;
    let path = ctx.out.join(RUN_ID_FILE);
    std::fs::write(&path, format!("{}\n", ctx.run_id))
        .map_err(|cause| OutputError::Io { path, cause })?;
    write_large_parts(ctx.out, ctx.file, components)?;
    Ok(w)
}

/// Restores `sim` and the counters of `info` from checkpoint `cp` and reopens the outputs
/// at its state; everything is checked before the folder is touched.
fn resume_writers<const D: usize>(
    ctx: &RunContext,
    sim: &mut Simulation<D, Material>,
    info: &mut RunInfo,
    cp: CheckpointFile,
) -> Result<Writers, RunError> {
    check_resume_folder(&cp, ctx.out)?;
    let (c, outputs) = cp.restore_into(sim, &ctx.settings)?;
    info.steps = c.steps;
    info.total_newton_iterations = c.total_newton_iterations;
    info.max_balance_error = c.max_balance_error;
    info.max_relative_balance_error = c.max_relative_balance_error;
    info.max_newton_residual = c.max_newton_residual;
    info.rejected_steps = c.rejected_steps;
    info.line_search_backtracks = c.line_search_backtracks;
    info.rejected_newton_iterations = c.rejected_newton_iterations;
    info.local_newton_iterations = c.local_newton_iterations;
    info.local_newton_work = c.local_newton_work;
    info.steps_at_roundoff = c.steps_at_roundoff;
    info.steps_over_tolerance = c.steps_over_tolerance;
    info.time_loop_s = c.time_loop_s;
    info.hamiltonian_initial = c.hamiltonian_initial;
    info.settle_progress = (c.settle_armed, c.settle_since);
    info.water = WaterSummary::resumed(sim, c.water.as_ref());
    info.lines = ctx.lines.as_ref().and(c.lines);
    let s = &ctx.settings;
    Ok(Writers::resume::<D>(
        ctx.out,
        s.stride,
        s.output.vtk,
        snapshot_times(s.t_end),
        outputs,
        (sim.system().has_water(), sim.system().winches().len()),
    )?)
}

/// Writes `checkpoint.json` (atomically) with the state of `sim`, the outputs and `info`.
fn write_checkpoint<const D: usize>(
    ctx: &RunContext,
    sim: &Simulation<D, Material>,
    writers: &mut Writers,
    info: &RunInfo,
) -> Result<(), RunError> {
    let cp = CheckpointFile {
        format: FORMAT.into(),
        version: env!("CARGO_PKG_VERSION").into(),
        run_id: ctx.run_id.clone(),
        // Absolute: a resume from another working directory finds the scenario's tables.
        scenario_path: std::path::absolute(&ctx.file.path)
            .unwrap_or_else(|_| ctx.file.path.clone()),
        scenario_path_given: ctx.file.path.clone(),
        scenario_text: ctx.file.text().to_string(),
        data_files: ctx.data_files.clone(),
        end_of_loading: ctx.end_of_loading,
        sim: sim.flat_checkpoint(),
        outputs: writers.state()?,
        counters: Counters {
            steps: info.steps,
            total_newton_iterations: info.total_newton_iterations,
            max_balance_error: info.max_balance_error,
            max_relative_balance_error: info.max_relative_balance_error,
            max_newton_residual: info.max_newton_residual,
            rejected_steps: info.rejected_steps,
            line_search_backtracks: info.line_search_backtracks,
            rejected_newton_iterations: info.rejected_newton_iterations,
            local_newton_iterations: info.local_newton_iterations,
            local_newton_work: info.local_newton_work,
            steps_at_roundoff: info.steps_at_roundoff,
            steps_over_tolerance: info.steps_over_tolerance,
            time_loop_s: info.time_loop_s,
            hamiltonian_initial: info.hamiltonian_initial,
            settle_armed: info.settle_progress.0,
            settle_since: info.settle_progress.1,
            water: info.water.as_ref().map(WaterSummary::counters),
            lines: info.lines.clone(),
        },
        checksum: String::new(),
        path: ctx.checkpoint_path.clone(),
    };
    cp.write(&ctx.checkpoint_path)?;
    Ok(())
}

/// The observer of a run ([`phstring::Observer`]): writes the outputs after every step,
/// keeps the counters of `summary.json`, shows progress, watches for static settling and
/// writes periodic checkpoints; it ends the run after `stop_after_steps` steps, once the
/// string has settled, or on a failed write (kept in `error`).
struct Recorder<'a, 'b> {
    ctx: &'a RunContext<'b>,
    writers: &'a mut Writers,
    info: &'a mut RunInfo,
    progress: &'a mut dyn Progress,
    opts: &'a RunOptions,
    watch: Option<SettleWatch>,
    /// When the step under way started, and the steps over tolerance before it.
    started: (Instant, usize),
    /// Stopped by `stop_after_steps`.
    stopped: bool,
    /// The write that failed.
    error: Option<RunError>,
}

impl<const D: usize> phstring::Observer<D, Material> for Recorder<'_, '_> {
    fn before_step(&mut self, sim: &Simulation<D, Material>) -> ControlFlow<()> {
        // A stop request (the flag) is seen by the simulation itself, before and during
        // the step: `StepError::Interrupted`.
        if self.opts.stop_after_steps.is_some_and(|n| sim.steps() >= n) {
            self.stopped = true;
            return ControlFlow::Break(());
        }
        self.started = (Instant::now(), sim.steps_over_tolerance());
        ControlFlow::Continue(())
    }

    fn on_step(&mut self, sim: &Simulation<D, Material>, report: &StepReport) -> ControlFlow<()> {
        let info = &mut *self.info;
        info.time_loop_s += self.started.0.elapsed().as_secs_f64();
        info.steps += 1;
        info.rejected_steps += report.rejected;
        info.line_search_backtracks += report.backtracks;
        info.total_newton_iterations += report.newton_iterations;
        info.rejected_newton_iterations += report.rejected_iterations;
        info.local_newton_iterations += report.local_iterations;
        info.local_newton_work += (report.local_node_iterations
            + report.rejected_local_node_iterations) as f64
            / sim.system().mesh().n_nodes() as f64;
        info.max_balance_error = nan_max(info.max_balance_error, report.balance_error.abs());
        info.max_relative_balance_error = nan_max(
            info.max_relative_balance_error,
            report.relative_balance_error(),
        );
        info.max_newton_residual = nan_max(info.max_newton_residual, report.residual);
        info.steps_at_roundoff += usize::from(report.at_roundoff);
        info.steps_over_tolerance += sim.steps_over_tolerance() - self.started.1;
        if let Some(w) = &mut info.water {
            w.observe(sim);
        }
        // The end tensions of the state, computed once for the extremes and the file.
        let tensions = self.ctx.lines.as_ref().map(|w| w.tensions(sim));
        if let (Some(watch), Some(lines), Some(t)) = (&self.ctx.lines, &mut info.lines, &tensions) {
            watch.observe(sim, lines, info.water.as_ref(), t);
        }
        if let Err(e) = self.writers.step_with(sim, report, tensions.as_deref()) {
            self.error = Some(e.into());
            return ControlFlow::Break(());
        }
        self.progress.step(report.step, report.t);
        let at_rest = self.watch.as_mut().and_then(|w| w.check(sim, report));
        if let Some(w) = &self.watch {
            info.settle_progress = w.progress();
        }
        if let (Some(at), Some(s)) = (at_rest, self.ctx.settings.settle) {
            info.settled = Some(SettledInfo {
                settled: true,
                t: at.t,
                step: at.step,
                kinetic: at.kinetic,
                threshold: s.kinetic,
                hold: s.hold,
                fastest_node: at.node,
                speed: at.speed,
            });
            return ControlFlow::Break(());
        }
        if self
            .opts
            .checkpoint_every
            .is_some_and(|n| n > 0 && sim.steps().is_multiple_of(n))
            && let Err(e) = write_checkpoint(self.ctx, sim, self.writers, info)
        {
            self.error = Some(e);
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }
}

/// Steps to the end time (or a failed step, or a stop), writing the outputs as it goes;
/// then writes the checkpoint (stopped) or the final state (completed or failed) and
/// flushes. Returns the failed step's error, if any, and whether the run was stopped.
fn step_loop<const D: usize>(
    ctx: &RunContext,
    sim: &mut Simulation<D, Material>,
    writers: &mut Writers,
    info: &mut RunInfo,
    progress: &mut dyn Progress,
    opts: &RunOptions,
) -> Result<(Option<StepError>, bool), RunError> {
    // A fresh run arms the watch on the initial state; a resumed one continues it.
    let watch = ctx.settings.settle.map(|s| {
        if info.resumed {
            SettleWatch::resume(s, info.settle_progress)
        } else {
            let mut w = SettleWatch::new(s);
            w.update(sim.time(), sim.energies().kinetic);
            w
        }
    });
    let mut recorder = Recorder {
        ctx,
        writers,
        info,
        progress,
        opts,
        watch,
        started: (Instant::now(), 0),
        stopped: false,
        error: None,
    };
    let looped = sim.run_until(ctx.settings.t_end, &mut recorder);
    let Recorder {
        writers,
        info,
        stopped,
        error,
        ..
    } = recorder;
    if let Some(e) = error {
        return Err(e);
    }
    let (failure, interrupted) = match looped {
        Ok(_) => (None, stopped),
        // A stop request during the step: the state is that of the last good step.
        Err(StepError::Interrupted { .. }) => (None, true),
        Err(e) => (Some(e), false),
    };
    if let Some(s) = ctx.settings.settle
        && info.settled.is_none()
        && failure.is_none()
        && !interrupted
    {
        let (fastest_node, speed) = phstring::fastest_node(&sim.state().v);
        info.settled = Some(SettledInfo {
            settled: false,
            t: sim.time(),
            step: sim.steps(),
            kinetic: sim.energies().kinetic,
            threshold: s.kinetic,
            hold: s.hold,
            fastest_node,
            speed,
        });
    }
    if interrupted {
        // The checkpoint records the file lengths of this moment: write it before the
        // final frame and plots, which a resumed run writes itself.
        write_checkpoint(ctx, sim, writers, info)?;
    } else {
        // Completed, or failed: the last good state is written either way (a failed step
        // leaves the state at the last good step, finite).
        writers.finish(sim)?;
    }
    writers.flush()?;
    Ok((failure, interrupted))
}

/// Draws the plots from `energy.csv` read back (the run keeps no history in memory),
/// records them in `info` and rewrites `summary.json`.
fn draw(
    ctx: &RunContext,
    (writers, scene): (&Writers, &Scene),
    info: &mut RunInfo,
    stop: Option<&AtomicBool>,
) -> Result<(), RunError> {
    let history = match read_history(
        writers.energy_path(),
        output::PLOT_POINTS,
        writers.snapshots().to_vec(),
        stop,
    ) {
        Ok(Some(h)) => Ok(h),
        Ok(None) => Err("stop requested".to_string()),
        Err(e) => Err(e.to_string()),
    };
    let title = ctx.file.scenario.title.as_deref().unwrap_or("phstring");
    let report = draw_plots(
        ctx.out,
        info.dimension,
        (title, scene),
        ctx.end_of_loading,
        history.as_ref().map_err(String::as_str),
        stop,
    );
    info.plots = report.written;
    info.plots_skipped = report.skipped;
    info.warnings.extend(report.warnings);
    write_summary(ctx.out, info)?;
    info.history = history.unwrap_or_default();
    Ok(())
}

/// Marks `info` failed with `e` and tries to write `summary.json`; returns the error of
/// that write, if it failed (the caller reports `e` either way).
fn record_failure(out: &Path, info: &mut RunInfo, e: &RunError) -> Result<(), OutputError> {
    info.status = "failed".into();
    info.error = Some(e.to_string());
    write_summary(out, info)
}

/// A write failed during the run (`e`, at simulated time `t`; a full disk): writes out what
/// the other files still hold, records the failure and the incomplete files in
/// `summary.json`, and returns the error to report, which says where the outputs are, which
/// are incomplete, and — if even `summary.json` could not be written — that the run failed
/// and how far it got.
fn fail_writing(
    out: &Path,
    info: &mut RunInfo,
    writers: &mut Writers,
    e: RunError,
    t: f64,
) -> RunError {
    info.incomplete_files = writers.salvage();
    let summary = record_failure(out, info, &e);
    let mut note = format!(
        "the outputs written up to the failure are in {}",
        out.display()
    );
    if !info.incomplete_files.is_empty() {
        note += &format!(
            " (incomplete, each ending on a whole row: {})",
            info.incomplete_files.join(", ")
        );
    }
    match summary {
        Ok(()) => note += "; summary.json records the failure",
        Err(se) => {
            note += &format!(
                "; summary.json could not be written either ({se}): the run failed at t = {} s after {} steps",
                phstring::Num(t),
                info.steps
            );
        }
    }
    RunError::Incomplete {
        cause: Box::new(e),
        note,
    }
}

/// `summary.json` of `info` as text: pretty-printed (large parts are in files of their own,
/// see [`SUMMARY_COMPONENTS`] and [`SUMMARY_SCENARIO_BYTES`]), ending in a line break.
fn summary_text(info: &RunInfo) -> String {
    serde_json::to_string_pretty(info).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}")) + "\n"
}

/// Writes `summary.json` atomically (a temporary file in `out`, then renamed), so that it
/// is never half-written and never left stale by a failed write. When that fails (a full
/// disk has no room for the temporary file), it is written in place over the summary the
/// run wrote when it started, if it fits in that file's reserve ([`SUMMARY_RESERVE`]).
pub fn write_summary(out: &Path, info: &RunInfo) -> Result<(), OutputError> {
    let path = out.join(SUMMARY_FILE);
    let text = summary_text(info);
    atomic_write(&path, text.as_bytes()).or_else(|cause| {
        overwrite_in_place(&path, text.as_bytes()).map_err(|_| OutputError::Io { path, cause })
    })
}

/// Writes the summary of a run that starts (`"status": "running"`), followed by
/// [`SUMMARY_RESERVE`] spaces, so that the final summary finds room in its place on a full
/// disk; `info` keeps its status.
fn write_running_summary(out: &Path, info: &mut RunInfo) -> Result<(), RunError> {
    let status = std::mem::replace(&mut info.status, "running".into());
    let text = summary_text(info) + &" ".repeat(SUMMARY_RESERVE) + "\n";
    info.status = status;
    let path = out.join(SUMMARY_FILE);
    atomic_write(&path, text.as_bytes())
        .map_err(|cause| RunError::Output(OutputError::Io { path, cause }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The whole chain of `e` as `{:#}` prints it: the message, then each source.
    fn chain(e: &dyn std::error::Error) -> String {
        let mut text = e.to_string();
        let mut next = e.source();
        while let Some(s) = next {
            text += &format!(": {s}");
            next = s.source();
        }
        text
    }

    /// An error's cause is printed once along the whole chain: no error type both writes its
    /// cause into its message and chains it as a source.
    #[test]
    fn error_causes_are_printed_once() {
        let io = || std::io::Error::other("disk full");
        let errors: Vec<Box<dyn std::error::Error>> = vec![
            Box::new(OutputError::Io {
                path: "energy.csv".into(),
                cause: io(),
            }),
            Box::new(CheckpointError::Io {
                path: "checkpoint.json".into(),
                cause: io(),
            }),
            Box::new(crate::vtk::VtkError::Io {
                path: "string.pvd".into(),
                cause: io(),
            }),
            Box::new(crate::plot::PlotError::Io {
                path: "energy.svg".into(),
                cause: io(),
            }),
            Box::new(RunError::Output(OutputError::Io {
                path: "energy.csv".into(),
                cause: io(),
            })),
        ];
        for e in &errors {
            let text = chain(e.as_ref());
            assert_eq!(text.matches("disk full").count(), 1, "{text}");
        }
        let setup = RunError::from(phstring::SetupError::NoElements);
        let text = chain(&setup);
        assert_eq!(text.matches("no elements").count(), 1, "{text}");
        let linear = phstring::StepError::Linear {
            step: 3,
            t: 0.5,
            cause: phstring::LinearSolveError::Singular { block: 7 },
        };
        let text = chain(&linear);
        assert_eq!(text.matches("singular").count(), 1, "{text}");
    }

    /// The running maximum keeps a NaN (`f64::max` would drop it), so a broken run cannot
    /// report `max_balance_error: 0`.
    #[test]
    fn non_finite_maximum_propagates_nan() {
        assert!(nan_max(0.0, f64::NAN).is_nan());
        assert!(nan_max(f64::NAN, 1.0).is_nan());
        assert_eq!(nan_max(1.0, 2.0), 2.0);
        assert_eq!(nan_max(0.0, f64::INFINITY), f64::INFINITY);
        let m = [1e-15, f64::NAN, 3e-15].into_iter().fold(0.0, nan_max);
        assert!(m.is_nan());
    }

    #[test]
    fn run_ids_differ_and_are_read_back() {
        let a = new_run_id(Path::new("x"));
        let b = new_run_id(Path::new("x"));
        assert_ne!(a, b);
        assert_eq!(a.len(), 16);
        let dir = crate::test_util::temp_dir("runner", "runid");
        assert_eq!(read_run_id(&dir), None);
        std::fs::write(dir.join(RUN_ID_FILE), format!("{a}\n")).unwrap();
        assert_eq!(read_run_id(&dir), Some(a));
        std::fs::write(dir.join(RUN_ID_FILE), "\0\x1b[2J").unwrap();
        assert_eq!(read_run_id(&dir).as_deref(), Some("(unreadable)"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
