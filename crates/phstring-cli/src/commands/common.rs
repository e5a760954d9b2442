//! What several commands share: stop requests (Ctrl-C, SIGTERM) and the error of an
//! interrupted command, the progress bar, output folders, and the preamble of the commands
//! that solve one scenario into one folder (`statics`, `modes`, `linearize`).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use phstring_io::drive::outdir::{self, OutLock};
use phstring_io::drive::run::{self as runner, Progress, RunInfo, RunOptions};
use phstring_io::scenario::{AnySetup, ScenarioFile};
use phstring_io::text::{clip, num, printable};

use crate::budget::{self, check_budget};

/// A command other than `run` was interrupted (exit code 130 like an interrupted run); the
/// message says what was written and how to redo it (`paper`, `statics`, `modes`,
/// `linearize`, `sweep`, and `run` in its starting equilibrium).
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

/// `result`, with an error that `stopped` recognizes as caused by a stop request replaced by
/// [`Interrupted`] with the message `"{text} {out}"` (exit code 130).
pub fn interrupted_as<T, E>(
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

/// Validates `file` and builds its system once ([`ScenarioFile::setup`]) and prints its
/// warnings to stderr; returns the setup and the warnings.
pub fn check_and_warn(file: &ScenarioFile) -> Result<(AnySetup, Vec<String>)> {
    let setup = file.setup()?;
    let warnings = phstring::by_dim!(&setup, s => s.warnings.clone());
    for w in &warnings {
        tell!("warning: {w}");
    }
    Ok((setup, warnings))
}

/// `--signal-self-after-ms`, for [`stop_flag`].
pub static SIGNAL_AFTER_MS: std::sync::OnceLock<u64> = std::sync::OnceLock::new();

/// `out/<scenario file stem><suffix>`.
pub fn default_out(scenario: &Path, suffix: &str) -> PathBuf {
    let stem = scenario
        .file_stem()
        .map_or("run".into(), |s| s.to_string_lossy().into_owned());
    Path::new("out").join(format!("{stem}{suffix}"))
}

/// Prepares and locks an output folder ([`outdir::prepare`]): refuses a non-empty folder
/// unless `force`, a folder another run is using, and symbolic links among phstring's
/// output names; with `force`, removes exactly the outputs of an earlier run.
pub fn prepare_out(out: &Path, force: bool) -> Result<OutLock> {
    Ok(outdir::prepare(out, force)?)
}

/// [`prepare_out`] for a command that reads `inputs` (its scenario, a checkpoint), all read
/// and checked before: an `out` that holds one of them is refused
/// ([`outdir::refuse_inputs_inside`]), so that `--force` cannot remove what it reads.
pub fn prepare_out_for(out: &Path, force: bool, inputs: &[&Path]) -> Result<OutLock> {
    outdir::refuse_inputs_inside(out, inputs)?;
    prepare_out(out, force)
}

/// An energy for the terminal: 9 decimals, or scientific notation for very large or small
/// values (never hundreds of digits).
pub fn energy(x: f64) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        format!("{x:.9}")
    } else {
        format!("{x:.9e}")
    }
}

/// Progress over simulated time (per mille of `t_end`), with step count and time.
pub struct Bar {
    /// The bar on a terminal (`None`: quiet, or stderr is not a terminal).
    pub bar: Option<ProgressBar>,
    /// End time of the run [s].
    pub t_end: f64,
    /// `--signal-self-after-step`: the step, and the flag the signal handler sets.
    pub signal: Option<(usize, std::sync::Arc<AtomicBool>)>,
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
pub fn signal_self(flag: &AtomicBool) {
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

/// The progress bar of a run (or a sweep) labelled `label`; drawn only on a terminal and
/// without `quiet`.
pub fn progress_bar(quiet: bool, label: &str) -> Bar {
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
pub fn run_label(file: &ScenarioFile) -> String {
    file.scenario
        .title
        .clone()
        .unwrap_or_else(|| file.path.display().to_string())
}

/// Runs `file` into `out` with a progress bar.
pub fn run_one(file: &ScenarioFile, out: &Path, quiet: bool, opts: RunOptions) -> Result<RunInfo> {
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
pub fn stop_flag() -> std::sync::Arc<AtomicBool> {
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

// The `--set` overrides and `--force` of `statics`, `modes` and `linearize`, last among their
// arguments.
#[derive(clap::Args)]
pub struct SetAndForce {
    /// Override a scenario key by its dotted path.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Overwrite a non-empty output folder.
    #[arg(long)]
    pub force: bool,
    /// For a MoorDyn deck: drop a feature phstring does not model (EI, rods, bodies, …;
    /// docs/moordyn.md), recorded in the outputs.
    #[arg(long = "ignore", value_name = "FEATURE")]
    pub ignore: Vec<String>,
    /// For a MoorDyn deck: the vessel motion, a table `t, x, y, z, roll, pitch, yaw` [s, m,
    /// rad] that moves the deck's Vessel/Coupled points rigidly (docs/moordyn.md); the run
    /// ends at its last time unless --set time.end=… is given.
    #[arg(long, value_name = "FILE")]
    pub motion: Option<PathBuf>,
}

/// What a command that solves one scenario into one output folder starts from
/// ([`prepare_scenario_command`]); the folder stays locked while it lives.
pub struct Prepared<T> {
    /// Set by a stop request (Ctrl-C, SIGTERM), see [`stop_flag`].
    pub stop: Arc<AtomicBool>,
    /// The scenario with its overrides.
    pub file: ScenarioFile,
    /// The scenario validated and its system built, once.
    pub setup: AnySetup,
    /// The output folder, prepared and locked.
    pub out: PathBuf,
    /// What the command read and checked before the folder was touched.
    pub read: T,
    /// The lock on `out`, released when this is dropped.
    _lock: OutLock,
}

/// The preamble of `statics`, `modes` and `linearize`: installs the stop handler, loads
/// `scenario` with the `--set` overrides of `set_force` within the memory budget and checks
/// it, calls `read` for what else the command reads and checks before the folder is touched
/// (a checkpoint: `inputs` lists such files), then prepares and locks the output folder
/// `out` (default `out/<scenario stem><suffix>`; an earlier run's outputs are replaced only
/// with `--force`), refusing one that holds the scenario or one of `inputs`.
pub fn prepare_scenario_command<T>(
    scenario: &Path,
    set_force: &SetAndForce,
    out: Option<PathBuf>,
    suffix: &str,
    inputs: &[&Path],
    read: impl FnOnce(&AnySetup) -> Result<T>,
) -> Result<Prepared<T>> {
    let stop = stop_flag();
    let file = budget::load(
        scenario,
        &set_force.sets,
        &set_force.ignore,
        set_force.motion.as_deref(),
    )?;
    check_budget(&file)?;
    // The scenario's warnings, as `run` prints them: the command may fail for what they say.
    let (setup, _) = check_and_warn(&file)?;
    let read = read(&setup)?;
    let out = out.unwrap_or_else(|| default_out(scenario, suffix));
    let inputs: Vec<&Path> = std::iter::once(scenario)
        .chain(inputs.iter().copied())
        .collect();
    let lock = prepare_out_for(&out, set_force.force, &inputs)?;
    Ok(Prepared {
        stop,
        file,
        setup,
        out,
        read,
        _lock: lock,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energies_for_people() {
        assert_eq!(energy(-3.468358762), "-3.468358762");
        assert_eq!(energy(1e300), "1.000000000e300");
    }
}
