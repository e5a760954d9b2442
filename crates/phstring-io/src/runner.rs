//! Runs a validated scenario into an output folder (the work behind `phstring run`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use phstring::{Material, Simulation};
use serde::Serialize;

use crate::output::{History, OutputError, Writers};
use crate::scenario::{ScenarioError, ScenarioFile};

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

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The simulation could not be set up.
    #[error("setup failed: {0}")]
    Setup(#[from] phstring::SetupError),
    /// A step failed; outputs up to the last good step are written.
    #[error("{0} (outputs up to the last good step are in {1})")]
    Step(phstring::StepError, PathBuf),
    /// Writing outputs failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What a run did: the content of `summary.json` plus the in-memory history.
#[derive(Debug, Clone, Serialize)]
pub struct RunInfo {
    /// Always `"phstring"`.
    pub program: &'static str,
    /// Program version.
    pub version: &'static str,
    /// `completed` or `failed`.
    pub status: String,
    /// The reason for a failure.
    pub error: Option<String>,
    /// Title of the scenario.
    pub title: Option<String>,
    /// Spatial dimension.
    pub dimension: usize,
    /// Number of elements.
    pub elements: usize,
    /// Scheme (`dg` or `mp`).
    pub scheme: &'static str,
    /// Linear solver used.
    pub solver: &'static str,
    /// Step size [s].
    pub h: f64,
    /// End time [s].
    pub t_end: f64,
    /// Steps planned (`T/h`; more when step-size control shortens steps).
    pub steps_planned: usize,
    /// Steps completed.
    pub steps: usize,
    /// Whether step-size control was on.
    pub adaptive: bool,
    /// Step attempts rejected and retried with half the step size.
    pub rejected_steps: usize,
    /// Smallest accepted step size [s].
    pub h_min_used: f64,
    /// Line-search backtracks in all.
    pub line_search_backtracks: usize,
    /// Simulated time reached [s].
    pub t_reached: f64,
    /// Newton iterations in all.
    pub total_newton_iterations: usize,
    /// Newton convergence test.
    pub newton_norm: &'static str,
    /// Newton tolerance [N].
    pub newton_tol: f64,
    /// Largest `|Ĥ_{n+1} − Ĥ_n − h û·ŷ|` [J].
    pub max_balance_error: f64,
    /// Largest Newton residual at convergence [N].
    pub max_newton_residual: f64,
    /// `Ĥ(0)` [J].
    pub hamiltonian_initial: f64,
    /// `Ĥ` at the last completed step [J].
    pub hamiltonian_final: f64,
    /// Wall time of the time loop alone (stepping, no output) [s].
    pub time_loop_s: f64,
    /// Plots written (stems, each as `.svg` and `.png`).
    pub plots: Vec<String>,
    /// The scenario as run (after `--set` overrides).
    pub scenario: serde_json::Value,
    /// Energy history (not serialized).
    #[serde(skip)]
    pub history: History,
}

/// Runs `file` into folder `out` (created if needed). Writes all outputs; on a step failure
/// the outputs up to the last good step and a `summary.json` with `"status": "failed"` are
/// written before the error is returned.
pub fn run(
    file: &ScenarioFile,
    out: &Path,
    progress: &mut dyn Progress,
    end_of_loading: Option<f64>,
) -> Result<RunInfo, RunError> {
    match file.dimension()? {
        1 => run_dim::<1>(file, out, progress, end_of_loading),
        2 => run_dim::<2>(file, out, progress, end_of_loading),
        _ => run_dim::<3>(file, out, progress, end_of_loading),
    }
}

fn run_dim<const D: usize>(
    file: &ScenarioFile,
    out: &Path,
    progress: &mut dyn Progress,
    end_of_loading: Option<f64>,
) -> Result<RunInfo, RunError> {
    let v = file.validate::<D>()?;
    let settings = v.settings.clone();
    let mut sim: Simulation<D, Material> = Simulation::new(v.problem, settings.step)?;
    let steps_planned = (settings.t_end / settings.step.h).round() as usize;
    let snapshots: Vec<f64> = (0..=5).map(|k| settings.t_end * k as f64 / 5.0).collect();
    let mut writers = Writers::start(
        out,
        &sim,
        settings.stride,
        settings.output.positions,
        settings.output.vtk,
        snapshots,
    )?;
    let mut info = RunInfo {
        program: "phstring",
        version: env!("CARGO_PKG_VERSION"),
        status: "completed".into(),
        error: None,
        title: file.scenario.title.clone(),
        dimension: D,
        elements: sim.system().mesh().n_elements(),
        scheme: settings.step.scheme.name(),
        solver: sim.solver_name(),
        h: settings.step.h,
        t_end: settings.t_end,
        steps_planned,
        steps: 0,
        adaptive: settings.step.control.adaptive,
        rejected_steps: 0,
        h_min_used: settings.step.h,
        line_search_backtracks: 0,
        t_reached: 0.0,
        total_newton_iterations: 0,
        newton_norm: "Euclidean norm of the force residual (momentum balance / h) over free DOFs [N]",
        newton_tol: settings.step.newton.tol,
        max_balance_error: 0.0,
        max_newton_residual: 0.0,
        hamiltonian_initial: sim.energies().hamiltonian(),
        hamiltonian_final: sim.energies().hamiltonian(),
        time_loop_s: 0.0,
        plots: Vec::new(),
        scenario: serde_json::to_value(&file.scenario).unwrap_or(serde_json::Value::Null),
        history: History::default(),
    };
    progress.start(settings.t_end);
    let mut loop_time = 0.0;
    let mut failure = None;
    let t_end = settings.t_end;
    while sim.time() < t_end - 1e-9 * sim.step_size() {
        let t0 = Instant::now();
        let res = sim.step_until(t_end);
        loop_time += t0.elapsed().as_secs_f64();
        match res {
            Ok(report) => {
                info.steps += 1;
                info.rejected_steps += report.rejected;
                info.line_search_backtracks += report.backtracks;
                info.total_newton_iterations += report.newton_iterations;
                info.max_balance_error = info.max_balance_error.max(report.balance_error.abs());
                info.max_newton_residual = info.max_newton_residual.max(report.residual);
                writers.step(&sim, &report)?;
                progress.step(report.step, report.t);
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
    }
    progress.finish();
    writers.finish(&sim)?;
    info.time_loop_s = loop_time;
    info.t_reached = sim.time();
    info.h_min_used = sim.smallest_step_size();
    info.hamiltonian_final = writers
        .history
        .hamiltonian
        .last()
        .copied()
        .unwrap_or(f64::NAN);
    if settings.output.plots {
        let title = file
            .scenario
            .title
            .clone()
            .unwrap_or_else(|| "phstring".into());
        info.plots = writers.plots(&title, end_of_loading)?;
    }
    if let Some(e) = &failure {
        info.status = "failed".into();
        info.error = Some(e.to_string());
    }
    write_summary(out, &info)?;
    info.history = writers.history;
    match failure {
        Some(e) => Err(RunError::Step(e, out.to_path_buf())),
        None => Ok(info),
    }
}

/// Writes `summary.json`.
pub fn write_summary(out: &Path, info: &RunInfo) -> Result<(), OutputError> {
    let path = out.join("summary.json");
    let text =
        serde_json::to_string_pretty(info).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    std::fs::write(&path, text + "\n").map_err(|source| OutputError::Io { path, source })
}
