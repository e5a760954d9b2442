//! `phstring`: run scenario files, reproduce the paper's benchmark and figures.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

mod budget;

use anyhow::{Context as _, Result, anyhow, bail};
use budget::{budget, check_budget, check_budget_of};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use phstring_io::checkpoint::CheckpointFile;
use phstring_io::drive::linearize::{ExportError, LinearizeAt};
use phstring_io::drive::modes::ModesRunError;
use phstring_io::drive::outdir::{self, OutLock};
use phstring_io::drive::run::{self as runner, Progress, RunError, RunInfo, RunOptions};
use phstring_io::drive::statics::StaticsRunError;
use phstring_io::drive::sweep::{Sweep, Vary};
use phstring_io::plot::{self, Series};
use phstring_io::scenario::{self, ScenarioFile};
use phstring_io::text::{clip, num, nums, printable};

/// Prints a line to stdout; a closed pipe (`phstring check … | head`) or a full disk is not
/// an error. Control characters (from titles, values) are escaped; line breaks are kept.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let _ = writeln!(std::io::stdout().lock(), "{}", printable(&text, true));
    }};
}

/// Prints a line to stderr like [`say!`]: a closed or full stderr (`2>/dev/full`) neither
/// panics nor changes the exit code.
macro_rules! tell {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let _ = writeln!(std::io::stderr().lock(), "{}", printable(&text, true));
    }};
}

/// The paper's benchmark scenario (also `examples/paper_pendulum.toml`).
const PAPER_SCENARIO: &str = include_str!("../../../examples/paper_pendulum.toml");
/// End of the loading phase of the paper's benchmark [s].
const PAPER_END_OF_LOADING: f64 = 0.2;

#[derive(Parser)]
#[command(
    name = "phstring",
    version,
    about = "Energy-consistent port-Hamiltonian simulation of strings and cables"
)]
struct Cli {
    /// No progress bar.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// For tests: send SIGINT to this process N ms after the command installs its Ctrl-C
    /// handler (`run`, `statics`, `modes`, `linearize`, `sweep`, `paper`), and wait until the
    /// handler has seen it; for phases without steps.
    #[arg(long, value_name = "N", global = true, hide = true)]
    signal_self_after_ms: Option<u64>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the paper's benchmark with DG and MP and redraw its figures.
    Paper {
        /// Output folder.
        #[arg(long, default_value = "out/paper")]
        out: PathBuf,
        /// Overwrite a non-empty output folder.
        #[arg(long)]
        force: bool,
    },
    /// Run a scenario file.
    Run {
        /// Scenario file (TOML); not with --resume.
        #[arg(required_unless_present = "resume", conflicts_with = "resume")]
        scenario: Option<PathBuf>,
        /// Output folder (default: out/<scenario name>; with --resume, the checkpoint's folder).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scenario key by its dotted path, e.g. --set mesh.elements=300.
        #[arg(long = "set", value_name = "KEY=VALUE", conflicts_with = "resume")]
        sets: Vec<String>,
        /// Overwrite a non-empty output folder.
        #[arg(long)]
        force: bool,
        /// Write <out>/checkpoint.json every N steps (an interrupted run always writes one).
        #[arg(long, value_name = "N", value_parser = at_least_one)]
        checkpoint_every: Option<usize>,
        /// Continue an interrupted run from its checkpoint.json, in that folder; the outputs
        /// are then bit for bit those of an uninterrupted run.
        #[arg(long, value_name = "CHECKPOINT", conflicts_with = "force")]
        resume: Option<PathBuf>,
        /// Stop like Ctrl-C after N steps in all (to run in chunks).
        #[arg(long, value_name = "N")]
        stop_after_steps: Option<usize>,
        /// For tests: send SIGINT to this process after step N and wait until the handler has
        /// seen it, so that an interruption by a real signal lands at a known step.
        #[arg(long, value_name = "N", hide = true)]
        signal_self_after_step: Option<usize>,
    },
    /// Run a scenario for every combination of varied values, in parallel.
    Sweep {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// A key and its values, e.g. --vary mesh.elements=100,300,1000 (repeatable: all
        /// combinations run).
        #[arg(long = "vary", value_name = "KEY=V1,V2,...", required = true)]
        vary: Vec<String>,
        /// Fixed overrides for every run.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Output folder (one sub-folder per run, plus sweep.csv).
        #[arg(long, default_value = "out/sweep")]
        out: PathBuf,
        /// Parallel runs (default: number of cores; at most 4 per core).
        #[arg(long, short, value_parser = at_least_one)]
        jobs: Option<usize>,
        /// Overwrite a non-empty output folder.
        #[arg(long)]
        force: bool,
    },
    /// Find the static equilibrium of a scenario under its loads at t = 0 (positions,
    /// tensions, support reactions; CSV, ParaView, plot, summary.json).
    Statics {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output folder (default: out/<scenario name>_statics).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scenario key by its dotted path.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Overwrite a non-empty output folder.
        #[arg(long)]
        force: bool,
    },
    /// Write the linear port-Hamiltonian model about the static equilibrium (or a
    /// checkpoint's positions): MatrixMarket and scipy .npz matrices and manifest.json.
    Linearize {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Linearize at this checkpoint's positions instead of the equilibrium.
        #[arg(long, value_name = "CHECKPOINT")]
        at: Option<PathBuf>,
        /// Also write the modal truncation to the K lowest natural modes (form `modal`).
        #[arg(long, value_name = "K", value_parser = at_least_one)]
        modes: Option<usize>,
        /// Output folder (default: out/<scenario name>_linear).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scenario key by its dotted path.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Overwrite a non-empty output folder.
        #[arg(long)]
        force: bool,
    },
    /// The lowest natural frequencies and mode shapes about the static equilibrium
    /// (modes.csv, ParaView frames, plot, summary.json).
    Modes {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Number of modes.
        #[arg(long, default_value_t = 10, value_parser = at_least_one)]
        count: usize,
        /// Output folder (default: out/<scenario name>_modes).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scenario key by its dotted path.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Overwrite a non-empty output folder.
        #[arg(long)]
        force: bool,
    },
    /// Validate a scenario file and print what would run.
    Check {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Override a scenario key by its dotted path.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Build an FMI 2.0 (or 3.0) Co-Simulation FMU of a scenario: its ports (external = true) as
    /// inputs, port outputs, energies and listed node positions as outputs, EA, ρA and h as
    /// parameters.
    Fmu {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// The FMU file to write; its name (without .fmu) is the model identifier.
        #[arg(short, long, value_name = "NAME.fmu")]
        out: PathBuf,
        /// Override a scenario key by its dotted path (the FMU holds the result).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// The FMU's shared library (default: the one built next to this executable, or
        /// $PHSTRING_FMU_LIBRARY).
        #[arg(long, value_name = "PATH")]
        library: Option<PathBuf>,
        /// FMI version: 2 (2.0, the version most tools import) or 3 (3.0).
        #[arg(long = "fmi-version", value_name = "2|3", default_value = "2", value_parser = ["2", "3"])]
        fmi_version: String,
        /// Replace an existing file NAME.fmu.
        #[arg(long)]
        force: bool,
    },
}

/// Environment variable naming the FMU's shared library (instead of looking next to the
/// `phstring` executable).
const FMU_LIBRARY_ENV: &str = "PHSTRING_FMU_LIBRARY";

/// A count option that must be at least 1 (`--jobs 0` or `--checkpoint-every 0` would do
/// nothing, and are refused rather than ignored).
fn at_least_one(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("{e}")),
    }
}

/// A command other than `run` was interrupted (exit code 130 like an interrupted run); the
/// message says what was written and how to redo it (`paper`, `statics`, `modes`,
/// `linearize`, `sweep`, and `run` in its starting equilibrium).
#[derive(Debug)]
struct Interrupted(String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

/// `result`, with an error that `stopped` recognizes as caused by a stop request replaced by
/// [`Interrupted`] with the message `"{text} {out}"` (exit code 130).
fn interrupted_as<T, E>(
    result: Result<T, E>,
    stopped: impl FnOnce(&E) -> bool,
    text: &str,
    out: &Path,
) -> Result<T>
where
    E: std::error::Error + Send + Sync + 'static,
{
    match result {
        Err(e) if stopped(&e) => Err(Interrupted(format!("{text} {}", out.display())).into()),
        r => Ok(r?),
    }
}

/// Validates `file` and prints its warnings to stderr; returns them.
fn check_and_warn(file: &ScenarioFile) -> Result<Vec<String>> {
    let warnings = file.check_with_warnings()?;
    for w in &warnings {
        tell!("warning: {w}");
    }
    Ok(warnings)
}

/// The messages of a `statics`, `modes`, `linearize` or a run's starting equilibrium
/// interrupted by a stop request; the output folder follows.
const STOPPED_STATICS: &str =
    "interrupted before the equilibrium was found; nothing was written to";
const STOPPED_MODES: &str =
    "interrupted before the modes were written; no modes.csv or summary.json was written to";
const STOPPED_LINEARIZE: &str = "interrupted before the model was written; nothing was written to";
const STOPPED_EQUILIBRIUM: &str = "interrupted while finding the starting equilibrium (initial.equilibrium); no step was run and nothing was written to";

/// `--signal-self-after-ms`, for [`stop_flag`].
static SIGNAL_AFTER_MS: std::sync::OnceLock<u64> = std::sync::OnceLock::new();

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(ms) = cli.signal_self_after_ms {
        let _ = SIGNAL_AFTER_MS.set(ms);
    }
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tell!("error: {}", error_text(&e));
            // 130 = interrupted (as a shell reports SIGINT), 1 = any other failure.
            if matches!(
                e.downcast_ref::<RunError>(),
                Some(RunError::Interrupted { .. })
            ) || e.is::<Interrupted>()
            {
                ExitCode::from(130)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// The error with its causes, each stated once: a cause whose text the message already
/// holds (an error type that prints its source and also returns it from `source()`) is not
/// repeated.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}

fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Paper { out, force } => paper(&out, force, cli.quiet),
        Command::Run {
            scenario,
            out,
            sets,
            force,
            checkpoint_every,
            resume,
            stop_after_steps,
            signal_self_after_step,
        } => {
            // From here on, Ctrl-C or SIGTERM asks the run to stop, and a second one exits.
            let stop = stop_flag();
            // The lock on the output folder is held until the run ends (or the process dies).
            let (file, out, resume, early, _lock) = match (scenario, resume) {
                (_, Some(cp_path)) => {
                    let cp = CheckpointFile::read(&cp_path)?;
                    let file = scenario::parse(&cp.scenario_text, &cp.scenario_path, &[])?;
                    let dir = out.unwrap_or_else(|| {
                        cp_path
                            .parent()
                            .filter(|p| !p.as_os_str().is_empty())
                            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
                    });
                    check_budget(&file)?;
                    let lock = outdir::prepare_resume(&dir)?;
                    (file, dir, Some(cp), Vec::new(), lock)
                }
                (Some(scenario), None) => {
                    let file = budget::load(&scenario, &sets)?;
                    // Before validation, which itself holds the whole mesh.
                    let b = budget(&file)?;
                    if let Some(e) = b.memory_error(1) {
                        bail!("{e}");
                    }
                    // Printed now: a run that fails at its first step may be why.
                    let early = check_and_warn(&file)?;
                    if let Some(w) = b.output_warning() {
                        tell!("warning: {w}");
                    }
                    let out = out.unwrap_or_else(|| {
                        let stem = scenario
                            .file_stem()
                            .map_or("run".into(), |s| s.to_string_lossy().into_owned());
                        Path::new("out").join(stem)
                    });
                    let lock = prepare_out_for(&out, force, &[&scenario])?;
                    (file, out, None, early, lock)
                }
                (None, None) => bail!("give a scenario file or --resume CHECKPOINT"),
            };
            let signal = signal_self_after_step.map(|n| (n, stop.clone()));
            let opts = RunOptions {
                checkpoint_every,
                stop_after_steps,
                stop: Some(stop),
                resume,
                ..Default::default()
            };
            let mut bar = progress_bar(cli.quiet, &run_label(&file));
            bar.signal = signal;
            // An interrupted time loop keeps its own message (with `--resume`).
            let ran = runner::run(&file, &out, &mut bar, opts);
            let statics = |e: &RunError| matches!(e, RunError::Statics(_)) && e.is_interrupted();
            let info = interrupted_as(ran, statics, STOPPED_EQUILIBRIUM, &out)?;
            // The scenario's warnings (also in summary.json) were printed before the run.
            for w in info.warnings.iter().filter(|w| !early.contains(w)) {
                tell!("warning: {w}");
            }
            say!(
                "{}: {} steps, Ĥ(0) = {} J, Ĥ(T) = {} J, max balance error {:.2e} J, {} Newton iterations, time loop {:.3} s",
                info.status,
                info.steps,
                energy(info.hamiltonian_initial),
                energy(info.hamiltonian_final),
                info.max_balance_error,
                info.total_newton_iterations,
                info.time_loop_s
            );
            if info.dissipated_energy > 0.0 {
                say!(
                    "dissipated {} J (Ĥ(T) − Ĥ(0) = supplied − dissipated)",
                    energy(info.dissipated_energy)
                );
            }
            if let Some(s) = &info.settled {
                if s.settled {
                    say!(
                        "settled at t = {} s (step {}): kinetic energy {:.3e} J below {:.3e} J for {} s; fastest node {} at {:.3e} m/s",
                        s.t,
                        s.step,
                        s.kinetic,
                        s.threshold,
                        s.hold,
                        s.fastest_node,
                        s.speed
                    );
                } else {
                    say!(
                        "did not settle by t = {} s: kinetic energy {:.3e} J (threshold {:.3e} J); fastest node {} at {:.3e} m/s",
                        s.t,
                        s.kinetic,
                        s.threshold,
                        s.fastest_node,
                        s.speed
                    );
                }
            }
            say!("outputs in {}", out.display());
            Ok(())
        }
        Command::Check { scenario, sets } => check(&scenario, &sets),
        Command::Fmu {
            scenario,
            out,
            sets,
            library,
            fmi_version,
            force,
        } => {
            let version = if fmi_version == "3" {
                phstring_fmu::package::FmiVersion::V3
            } else {
                phstring_fmu::package::FmiVersion::V2
            };
            fmu(&scenario, &out, &sets, library, version, force)
        }
        Command::Modes {
            scenario,
            count,
            out,
            sets,
            force,
        } => {
            let stop = stop_flag();
            let file = budget::load(&scenario, &sets)?;
            check_budget(&file)?;
            file.check()?;
            let out = out.unwrap_or_else(|| default_out(&scenario, "_modes"));
            let _lock = prepare_out_for(&out, force, &[&scenario])?;
            let found = phstring_io::drive::modes::modes(&file, count, &out, Some(&stop));
            let info = interrupted_as(found, ModesRunError::is_interrupted, STOPPED_MODES, &out)?;
            for w in &info.warnings {
                tell!("warning: {w}");
            }
            for (k, m) in info.modes.iter().enumerate() {
                say!(
                    "mode {:>3}: {:.6e} Hz  {:.6e} rad/s  {}",
                    k + 1,
                    m.frequency_hz,
                    m.omega_rad_s,
                    m.character
                );
            }
            say!(
                "{} ({} solves) about the equilibrium ({}); outputs in {}",
                info.method,
                info.solves,
                info.equilibrium_path,
                out.display()
            );
            Ok(())
        }
        Command::Linearize {
            scenario,
            at,
            modes,
            out,
            sets,
            force,
        } => {
            let stop = stop_flag();
            let file = budget::load(&scenario, &sets)?;
            check_budget(&file)?;
            file.check()?;
            // The checkpoint is read and checked before the folder is touched.
            let at_file = match &at {
                Some(path) => phstring_io::drive::linearize::checkpoint_at(&file, path)?,
                None => LinearizeAt::Equilibrium,
            };
            let out = out.unwrap_or_else(|| default_out(&scenario, "_linear"));
            let inputs: Vec<&Path> = std::iter::once(scenario.as_path())
                .chain(at.as_deref())
                .collect();
            let _lock = prepare_out_for(&out, force, &inputs)?;
            let at = at_file;
            let model =
                phstring_io::drive::linearize::linearize(&file, &at, modes, &out, Some(&stop));
            let m = interrupted_as(model, ExportError::is_interrupted, STOPPED_LINEARIZE, &out)?;
            for w in &m.warnings {
                tell!("warning: {w}");
            }
            for (name, form) in &m.forms {
                say!(
                    "{name}: {} states, {} inputs, {} outputs",
                    form.states.len(),
                    m.inputs.len(),
                    m.outputs.len()
                );
            }
            say!(
                "linearized at {} (static residual {:.3e} N, {})",
                m.linearized_at,
                m.static_residual,
                if m.stable { "stable" } else { "NOT stable" }
            );
            say!("outputs in {}", out.display());
            Ok(())
        }
        Command::Statics {
            scenario,
            out,
            sets,
            force,
        } => {
            let stop = stop_flag();
            let file = budget::load(&scenario, &sets)?;
            check_budget(&file)?;
            file.check()?;
            let out = out.unwrap_or_else(|| default_out(&scenario, "_statics"));
            let _lock = prepare_out_for(&out, force, &[&scenario])?;
            let found = phstring_io::drive::statics::statics(&file, &out, Some(&stop));
            let info = interrupted_as(
                found,
                StaticsRunError::is_interrupted,
                STOPPED_STATICS,
                &out,
            )?;
            say!(
                "equilibrium by {} ({} steps, {} Newton iterations, {:.3} s): residual {:.3e} N (tolerance {:.3e} N){}, tension {} … {} N, internal energy {} J",
                info.path,
                info.path_steps,
                info.newton_iterations,
                info.solve_s,
                info.residual,
                info.tolerance,
                if info.stable {
                    ", stable"
                } else {
                    ", NOT stable (tangent stiffness not positive definite)"
                },
                energy(info.min_tension),
                energy(info.max_tension),
                energy(info.internal_energy)
            );
            say!("outputs in {}", out.display());
            Ok(())
        }
        Command::Sweep {
            scenario,
            vary,
            sets,
            out,
            jobs,
            force,
        } => sweep(&scenario, &vary, &sets, &out, jobs, force, cli.quiet),
    }
}

/// `out/<scenario file stem><suffix>`.
fn default_out(scenario: &Path, suffix: &str) -> PathBuf {
    let stem = scenario
        .file_stem()
        .map_or("run".into(), |s| s.to_string_lossy().into_owned());
    Path::new("out").join(format!("{stem}{suffix}"))
}

/// Prepares and locks an output folder ([`outdir::prepare`]): refuses a non-empty folder
/// unless `force`, a folder another run is using, and symbolic links among phstring's
/// output names; with `force`, removes exactly the outputs of an earlier run.
fn prepare_out(out: &Path, force: bool) -> Result<OutLock> {
    Ok(outdir::prepare(out, force)?)
}

/// [`prepare_out`] for a command that reads `inputs` (its scenario, a checkpoint), all read
/// and checked before: an `out` that holds one of them is refused
/// ([`outdir::refuse_inputs_inside`]), so that `--force` cannot remove what it reads.
fn prepare_out_for(out: &Path, force: bool, inputs: &[&Path]) -> Result<OutLock> {
    outdir::refuse_inputs_inside(out, inputs)?;
    prepare_out(out, force)
}

/// An energy for the terminal: 9 decimals, or scientific notation for very large or small
/// values (never hundreds of digits).
fn energy(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        format!("{x:.9}")
    } else {
        format!("{x:.9e}")
    }
}

/// Progress over simulated time (per mille of `t_end`), with step count and time.
struct Bar {
    bar: Option<ProgressBar>,
    t_end: f64,
    /// `--signal-self-after-step`: the step, and the flag the signal handler sets.
    signal: Option<(usize, std::sync::Arc<AtomicBool>)>,
}

impl Progress for Bar {
    fn start(&mut self, t_end: f64) {
        self.t_end = t_end;
        if let Some(b) = &self.bar {
            b.set_length(1000);
        }
    }
    fn step(&mut self, step: usize, t: f64) {
        if let Some((n, flag)) = &self.signal
            && *n == step
        {
            signal_self(flag);
        }
        if let Some(b) = &self.bar {
            b.set_position((1000.0 * t / self.t_end).round() as u64);
            if step.is_multiple_of(16) {
                b.set_message(format!(
                    "t = {t:.4} s of {} s, step {step}",
                    num(self.t_end)
                ));
            }
        }
    }
    fn finish(&mut self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// Sends SIGINT to this process (with `kill`, as a user would) and waits until the handler
/// has set `flag`, at most 60 s.
fn signal_self(flag: &AtomicBool) {
    let sent = std::process::Command::new("kill")
        .args(["-INT", &std::process::id().to_string()])
        .status()
        .is_ok_and(|s| s.success());
    if sent {
        for _ in 0..60_000 {
            if flag.load(Ordering::SeqCst) {
                return;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

fn progress_bar(quiet: bool, label: &str) -> Bar {
    if quiet || !std::io::stderr().is_terminal() {
        return Bar {
            bar: None,
            t_end: 1.0,
            signal: None,
        };
    }
    let b = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    b.set_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {msg}, ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    // A title is user text: one line, no control characters, not too long.
    b.set_prefix(printable(&clip(label), false).into_owned());
    b.enable_steady_tick(Duration::from_millis(200));
    Bar {
        bar: Some(b),
        t_end: 1.0,
        signal: None,
    }
}

/// The progress bar's label: the scenario's title, else its file name.
fn run_label(file: &ScenarioFile) -> String {
    file.scenario
        .title
        .clone()
        .unwrap_or_else(|| file.path.display().to_string())
}

fn run_one(file: &ScenarioFile, out: &Path, quiet: bool, opts: RunOptions) -> Result<RunInfo> {
    let mut bar = progress_bar(quiet, &run_label(file));
    Ok(runner::run(file, out, &mut bar, opts)?)
}

/// A flag set by the first Ctrl-C or SIGTERM (ctrlc's `termination` feature): runs stop
/// between two Newton iterations (the state stays at the last good step) with their outputs
/// flushed and a checkpoint written; the plot phase skips the plots it has not drawn yet. A second
/// Ctrl-C or SIGTERM exits at once with code 130, whatever the program is doing (what is on
/// disk stays; the checkpoint of an interrupted run may then be missing). `run`, `paper`,
/// `statics`, `modes`, `linearize` and `sweep` install it first thing; `check` and `fmu`
/// keep the default effect of a signal (they end at once). With `--signal-self-after-ms`,
/// a thread sends the signal that long after the handler is installed.
fn stop_flag() -> std::sync::Arc<AtomicBool> {
    static STOP: std::sync::OnceLock<std::sync::Arc<AtomicBool>> = std::sync::OnceLock::new();
    STOP.get_or_init(|| {
        let flag = std::sync::Arc::new(AtomicBool::new(false));
        let set = flag.clone();
        // If no handler can be installed, Ctrl-C keeps its default effect.
        let _ = ctrlc::set_handler(move || {
            if set.swap(true, Ordering::SeqCst) {
                tell!("second interrupt: exiting at once");
                std::process::exit(130);
            }
            tell!("stopping at the end of the current step (press Ctrl-C again to exit at once)");
        });
        if let Some(&ms) = SIGNAL_AFTER_MS.get() {
            let seen = flag.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(ms));
                signal_self(&seen);
            });
        }
        flag
    })
    .clone()
}

/// Most `--jobs` per core.
const MAX_JOBS_PER_CORE: usize = 4;

fn sweep(
    path: &Path,
    vary: &[String],
    sets: &[String],
    out: &Path,
    jobs: Option<usize>,
    force: bool,
    quiet: bool,
) -> Result<()> {
    // Ctrl-C or SIGTERM stops the runs under way (each with a checkpoint) and starts no
    // further one; a second one exits at once.
    let stop = stop_flag();
    let vary: Vec<Vary> = vary
        .iter()
        .map(|v| Vary::parse(v))
        .collect::<Result<_, _>>()?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max_jobs = MAX_JOBS_PER_CORE * cores;
    let jobs = jobs.unwrap_or(cores);
    if jobs > max_jobs {
        bail!(
            "--jobs {jobs}: at most {max_jobs} ({MAX_JOBS_PER_CORE} per core, {cores} cores); each run is single-threaded, so more threads than cores only cost memory"
        );
    }
    // Every combination is checked against the memory budget (before validation allocates
    // its mesh) and validated before the output folder is touched.
    let concurrent = jobs.min(phstring_io::drive::sweep::run_count(&vary)?);
    budget::check_file_size(path)?;
    let plan = Sweep::new_with(path, sets, vary, |index, file| {
        check_budget_of(file, concurrent).map_err(|e| format!("run {index} of the sweep: {e:#}"))
    })?;
    let n = plan.len();
    let _lock = prepare_out_for(out, force, &[path])?;
    let bar = progress_bar(quiet, "sweep");
    if let Some(b) = &bar.bar {
        b.set_length(n as u64);
        b.set_message(format!("{n} runs on {jobs} threads"));
    }
    let done = |r: &phstring_io::drive::sweep::SweepRun| {
        if let Some(b) = &bar.bar {
            b.inc(1);
            if let (Err(e), false) = (&r.result, r.interrupted) {
                b.println(printable(&format!("run {} failed: {e}", r.index), true));
            }
        }
    };
    let runs = plan.run(out, jobs, &done, Some(stop))?;
    if let Some(b) = &bar.bar {
        b.finish_and_clear();
    }
    let stopped = runs.iter().filter(|r| r.interrupted).count();
    if stopped > 0 {
        let completed = runs.iter().filter(|r| r.result.is_ok()).count();
        bail!(Interrupted(format!(
            "interrupted: {completed} of {} runs completed, {stopped} interrupted or not started (status `interrupted` in {}; an interrupted run continues with `phstring run --resume RUN_FOLDER/checkpoint.json`)",
            runs.len(),
            out.join("sweep.csv").display()
        )));
    }
    let failed = runs.iter().filter(|r| r.result.is_err()).count();
    say!(
        "{} runs ({failed} failed) in {}; table: {}",
        runs.len(),
        out.display(),
        out.join("sweep.csv").display()
    );
    if failed > 0 {
        bail!("{failed} of {} runs failed (see sweep.csv)", runs.len());
    }
    Ok(())
}

/// `phstring fmu`: the FMI 2.0 (or 3.0) Co-Simulation FMU of a scenario; an existing file
/// `out` is replaced only with `force`.
fn fmu(
    path: &Path,
    out: &Path,
    sets: &[String],
    library: Option<PathBuf>,
    version: phstring_fmu::package::FmiVersion,
    force: bool,
) -> Result<()> {
    use phstring_fmu::{model::ModelSpec, package};
    if out.extension().and_then(|e| e.to_str()) != Some("fmu") {
        bail!(
            "-o {}: an FMU's file name ends in .fmu (e.g. -o crane.fmu)",
            out.display()
        );
    }
    if out.is_dir() {
        bail!("-o {}: is a folder, not a file name", out.display());
    }
    // Anything at the name, a dangling symbolic link included.
    if !force && std::fs::symlink_metadata(out).is_ok() {
        bail!(
            "-o {}: the file exists; give --force to replace it",
            out.display()
        );
    }
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let identifier =
        package::model_identifier(&stem).map_err(|e| anyhow!("-o {}: {e}", out.display()))?;
    let file = scenario::load(path, sets)?;
    check_budget(&file)?;
    let spec = ModelSpec::new(&file)?;
    let library = match library.or_else(|| std::env::var_os(FMU_LIBRARY_ENV).map(PathBuf::from)) {
        Some(l) => l,
        None => {
            let exe = std::env::current_exe().context("cannot locate the phstring executable")?;
            let candidates = package::library_candidates(&exe);
            match candidates.iter().find(|p| p.is_file()) {
                Some(p) => p.clone(),
                None => bail!(
                    "the FMU's shared library {} is not next to {} (looked in {}); build it with `cargo build --release -p phstring-fmu`, then give it with --library PATH or {FMU_LIBRARY_ENV}",
                    package::library_file_name(),
                    exe.display(),
                    candidates
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            }
        }
    };
    package::write_fmu(&file, &spec, &identifier, &library, out, version)?;
    let count = |c: phstring_fmu::model::Causality| {
        spec.variables.iter().filter(|v| v.causality == c).count()
    };
    use phstring_fmu::model::Causality as C;
    say!(
        "wrote {} (FMI {} Co-Simulation, model identifier {identifier}): {} inputs, {} outputs, {} parameters",
        out.display(),
        if version == package::FmiVersion::V3 {
            "3.0"
        } else {
            "2.0"
        },
        count(C::Input),
        count(C::Output),
        count(C::Parameter)
    );
    if count(C::Input) == 0 {
        say!(
            "  no inputs: mark a [[boundary]] table's force or position with external = true to make it one"
        );
    }
    for v in &spec.variables {
        say!(
            "  {:<10} {:<22} [{}]",
            match v.causality {
                C::Parameter => "parameter",
                C::Input => "input",
                C::Output => "output",
            },
            v.name,
            v.unit
        );
    }
    Ok(())
}

fn check(path: &Path, sets: &[String]) -> Result<()> {
    let file = budget::load(path, sets)?;
    // The system the scenario sets up must be valid too (finite initial energies and
    // forces); set it up only where it fits in memory (otherwise the warning below says so).
    let warnings = if budget(&file)?.memory_error(1).is_none() {
        file.check_with_warnings()?
    } else {
        Vec::new()
    };
    let d = file.dimension()?;
    let text = match d {
        1 => describe::<1>(&file)?,
        2 => describe::<2>(&file)?,
        _ => describe::<3>(&file)?,
    };
    say!("{} is valid:\n{text}", path.display());
    let b = budget(&file)?;
    say!("  estimate:  {}", b.describe());
    for w in warnings.iter().chain(&b.warnings(1)) {
        tell!("warning: {w}");
    }
    Ok(())
}

/// Most entries of one kind (strings, springs, fixed nodes, …) that `check` lists.
const LISTED: usize = 20;

/// Lists `items` with `line`, at most [`LISTED`], then how many more there are.
fn list<T>(out: &mut String, items: &[T], what: &str, line: impl Fn(&T) -> String) {
    use std::fmt::Write;
    for item in items.iter().take(LISTED) {
        let _ = writeln!(out, "{}", line(item));
    }
    if items.len() > LISTED {
        let _ = writeln!(out, "  …          and {} more {what}", items.len() - LISTED);
    }
}

fn describe<const D: usize>(file: &ScenarioFile) -> Result<String> {
    let v = file.validate::<D>()?;
    let p = &v.problem;
    let c = &v.components;
    let s = &v.settings;
    let mut out = String::new();
    use std::fmt::Write;
    let _ = writeln!(
        out,
        "  title:     {}",
        printable(
            &clip(file.scenario.title.as_deref().unwrap_or("(none)")),
            false
        )
    );
    let _ = writeln!(out, "  dimension: {D}");
    let node = |i: usize| c.node_label(i);
    if v.network {
        let _ = writeln!(
            out,
            "  mesh:      {} elements, {} nodes: {} strings, {} springs, {} named nodes",
            p.mesh.n_elements(),
            p.mesh.n_nodes(),
            c.strings.len(),
            c.springs.len(),
            c.nodes.len()
        );
        list(&mut out, &c.nodes, "named nodes", |n| {
            format!("  node:      {} at {} m", node(n.node), nums(&n.position))
        });
        list(&mut out, &c.strings, "strings", |st| {
            let spans = st.path_nodes.len() - 1;
            format!(
                "  string:    {}: {} elements ({spans} span{} of {}), {} to {}, {} ({}), EA = {} N, rhoA = {} kg/m, {} mass, reference length {} m, body force {} N/m",
                st.name,
                st.elements[1] - st.elements[0],
                if spans == 1 { "" } else { "s" },
                st.elements_per_span,
                node(st.path_nodes[0]),
                node(st.path_nodes[spans]),
                st.law,
                st.material,
                num(st.ea),
                num(st.rho_a),
                st.mass,
                num(st.reference_length),
                nums(&st.body_force)
            )
        });
        list(&mut out, &c.springs, "springs", |sp| {
            let to = match &sp.to_point {
                Some(pt) => format!("the fixed point {} m", nums(pt)),
                None => node(sp.nodes[1]),
            };
            format!(
                "  spring:    {}: {} to {to}, k = {} N/m, rest length {} m",
                sp.name,
                node(sp.nodes[0]),
                num(sp.k),
                num(sp.rest)
            )
        });
    } else {
        // One string: its group carries the material.
        let st = &c.strings[0];
        let _ = writeln!(
            out,
            "  mesh:      {} elements, {} nodes, reference length {} m",
            p.mesh.n_elements(),
            p.mesh.n_nodes(),
            num(p.mesh.total_length())
        );
        let _ = writeln!(
            out,
            "  material:  {}, EA = {} N, rhoA = {} kg/m, {} mass",
            st.law,
            num(st.ea),
            num(st.rho_a),
            st.mass
        );
        let _ = writeln!(out, "  body force: {} N/m", nums(&st.body_force));
    }
    list(&mut out, &c.supports, "fixed nodes", |f| {
        format!("  fixed:     {} ({})", node(f.node), f.fixed.join(", "))
    });
    list(&mut out, &c.loads, "loads", |l| {
        let exprs: Vec<String> = l.force.iter().map(|e| clip(e).into_owned()).collect();
        format!("  force:     {}: [{}] N", node(l.node), exprs.join(", "))
    });
    list(&mut out, &c.motions, "motions", |m| {
        format!(
            "  motion:    {} {} = {} m (velocity in, reaction out)",
            node(m.node),
            m.component,
            clip(&m.position)
        )
    });
    list(&mut out, &c.point_masses, "point masses", |pm| {
        format!(
            "  mass:      {}: {} kg, weight {} N",
            node(pm.node),
            num(pm.kg),
            nums(&pm.weight)
        )
    });
    let steps = (s.t_end / s.step.h).round() as usize;
    let _ = writeln!(
        out,
        "  time:      {} scheme, h = {} s, T = {} s, {steps} steps",
        s.step.scheme.name(),
        num(s.step.h),
        num(s.t_end)
    );
    let _ = write!(
        out,
        "  newton:    {}, max {} iterations, solver {}",
        newton_test(&s.step.newton),
        s.step.newton.max_iter,
        s.step.solver.name()
    );
    Ok(out)
}

/// The Newton convergence test in words: `‖R‖ ≤ max(tol, rtol·F)` or `‖R‖ ≤ tol`.
fn newton_test(n: &phstring::NewtonParams) -> String {
    if n.rtol > 0.0 {
        format!("‖R‖ ≤ max({} N, {} × force scale)", num(n.tol), num(n.rtol))
    } else {
        format!("‖R‖ ≤ {} N (absolute)", num(n.tol))
    }
}

/// The error of an interrupted `phstring paper`. A `--resume` of the run's checkpoint
/// would complete that one run only (not the other scheme, nor the figures), and the whole
/// benchmark takes about a second: the honest advice is to run it again.
fn paper_interrupted(scheme: &str, out: &Path) -> Interrupted {
    Interrupted(format!(
        "interrupted during the {scheme} run; the outputs so far are in {}; the benchmark takes about a second: run `phstring paper --force --out {}` again for all of it",
        out.display(),
        out.display()
    ))
}

fn paper(out: &Path, force: bool, quiet: bool) -> Result<()> {
    let stop = stop_flag();
    let _lock = prepare_out(out, force)?;
    let path = Path::new("examples/paper_pendulum.toml (built in)");
    let mut infos = Vec::new();
    for scheme in ["dg", "mp"] {
        let file = scenario::parse(PAPER_SCENARIO, path, &[format!("time.scheme={scheme}")])?;
        let dir = out.join(scheme);
        std::fs::create_dir_all(&dir)?;
        let opts = RunOptions {
            end_of_loading: Some(PAPER_END_OF_LOADING),
            stop: Some(stop.clone()),
            ..Default::default()
        };
        let info = match run_one(&file, &dir, quiet, opts) {
            Err(e) if matches!(e.downcast_ref(), Some(RunError::Interrupted { .. })) => {
                return Err(paper_interrupted(scheme, out).into());
            }
            r => r?,
        };
        infos.push(info);
    }
    let figures = out.join("figures");
    std::fs::create_dir_all(&figures)?;
    let (dg, mp) = (&infos[0].history, &infos[1].history);
    let title = "String pendulum (paper, Section 4)";
    plot::configuration_plot(
        &figures.join("fig2_configurations"),
        "Fig. 2: configurations (DG)",
        &dg.snapshots,
    )?;
    plot::energy_plot(
        &figures.join("fig3_energies"),
        "Fig. 3: energies (DG)",
        &dg.t,
        &dg.kinetic,
        &dg.potential,
        &dg.hamiltonian,
    )?;
    plot::series_plot(
        &figures.join("fig4_hamiltonian"),
        "Fig. 4: Hamiltonian, DG vs MP",
        "t [s]",
        "Ĥ [J]",
        &[
            Series {
                label: "DG",
                x: &dg.t,
                y: &dg.hamiltonian,
            },
            Series {
                label: "MP",
                x: &mp.t,
                y: &mp.hamiltonian,
            },
        ],
        false,
        Some((PAPER_END_OF_LOADING, "end of loading")),
    )?;
    let (ti_dg, inc_dg) = dg.increments();
    let (ti_mp, inc_mp) = mp.increments();
    plot::series_plot(
        &figures.join("fig5_increments"),
        "Fig. 5: energy increments, DG vs MP",
        "t [s]",
        "|Ĥ(n+1) − Ĥ(n)| [J]",
        &[
            Series {
                label: "DG",
                x: &ti_dg,
                y: &inc_dg,
            },
            Series {
                label: "MP",
                x: &ti_mp,
                y: &inc_mp,
            },
        ],
        true,
        Some((PAPER_END_OF_LOADING, "end of loading")),
    )?;
    say!("{title}: 30 elements, h = 0.01 s, T = 1 s");
    say!(
        "{:<7} {:>13} {:>13} {:>24} {:>17} {:>12}",
        "scheme",
        "H(0) [J]",
        "H(T) [J]",
        "max |dH| after loading",
        "Newton it. (avg)",
        "time loop"
    );
    for info in &infos {
        let (t, inc) = info.history.increments();
        let max_after = t
            .iter()
            .zip(&inc)
            .filter(|(t, _)| **t > PAPER_END_OF_LOADING + 1e-9)
            .map(|(_, d)| *d)
            .fold(0.0, f64::max);
        say!(
            "{:<7} {:>13.7} {:>13.7} {:>24.3e} {:>10} ({:.2}) {:>10.2} ms",
            info.scheme,
            info.hamiltonian_initial,
            info.hamiltonian_final,
            max_after,
            info.total_newton_iterations,
            info.total_newton_iterations as f64 / info.steps.max(1) as f64,
            info.time_loop_s * 1e3
        );
    }
    say!("paper:  H(0) = -3.468359, H(1) = -3.403762 (DG), -3.398474 (MP)");
    say!("outputs in {} (dg/, mp/, figures/)", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Finding "`phstring paper` interrupted suggests a `--resume` that completes only
    /// `dg/`": the message suggests re-running the whole benchmark instead.
    #[test]
    fn paper_interrupted_suggests_rerunning_paper() {
        let e = paper_interrupted("dg", Path::new("out/p")).to_string();
        assert!(!e.contains("--resume"), "{e}");
        assert!(
            e.contains("run `phstring paper --force --out out/p` again"),
            "{e}"
        );
        assert!(e.contains("during the dg run"), "{e}");
        let any: anyhow::Error = paper_interrupted("mp", Path::new("x")).into();
        assert!(any.is::<Interrupted>());
    }

    #[test]
    fn error_causes_appear_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        // A message that already holds its cause, with the cause also chained.
        #[derive(Debug)]
        struct Both(std::io::Error);
        impl std::fmt::Display for Both {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "cannot read x: {}", self.0)
            }
        }
        impl std::error::Error for Both {
            fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
                Some(&self.0)
            }
        }
        let e = anyhow::Error::new(Both(io)).context("loading");
        assert_eq!(error_text(&e), "loading: cannot read x: gone");
    }

    #[test]
    fn energies_for_people() {
        assert_eq!(energy(-3.468358762), "-3.468358762");
        assert_eq!(energy(1e300), "1.000000000e300");
    }
}
