//! `phstring run`: a scenario file (or a checkpoint, `--resume`) into an output folder, with
//! a progress bar and a report of the energies.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use phstring_io::checkpoint::CheckpointFile;
use phstring_io::drive::outdir;
use phstring_io::drive::run::{self as runner, RunError, RunOptions};
use phstring_io::scenario;

use super::common::{
    check_and_warn, energy, interrupted_as, prepare_out_for, progress_bar, run_label, stop_flag,
};
use crate::at_least_one;
use crate::budget::{self, budget, check_budget};

/// The message of a run interrupted while finding its starting equilibrium; the output
/// folder follows.
const STOPPED_EQUILIBRIUM: &str = "interrupted while finding the starting equilibrium (initial.equilibrium); no step was run and nothing was written to";

// The arguments of `phstring run`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct RunArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content); not with
    /// --resume.
    #[arg(required_unless_present = "resume", conflicts_with = "resume")]
    pub scenario: Option<PathBuf>,
    /// Output folder (default: out/<scenario name>; with --resume, the checkpoint's folder).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Override a scenario key by its dotted path, e.g. --set mesh.elements=300.
    #[arg(long = "set", value_name = "KEY=VALUE", conflicts_with = "resume")]
    pub sets: Vec<String>,
    /// Overwrite a non-empty output folder.
    #[arg(long)]
    pub force: bool,
    /// For a MoorDyn deck: drop a feature phstring does not model (EI, rods, bodies, …;
    /// docs/moordyn.md), recorded in summary.json.
    #[arg(long = "ignore", value_name = "FEATURE", conflicts_with = "resume")]
    pub ignore: Vec<String>,
    /// For a MoorDyn deck: the vessel motion, a table `t, x, y, z, roll, pitch, yaw` [s, m,
    /// rad] that moves the deck's Vessel/Coupled points rigidly (docs/moordyn.md); the run
    /// ends at its last time unless --set time.end=… is given.
    #[arg(long, value_name = "FILE", conflicts_with = "resume")]
    pub motion: Option<PathBuf>,
    /// Write <out>/checkpoint.json every N steps (an interrupted run always writes one).
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub checkpoint_every: Option<usize>,
    /// Continue an interrupted run from its checkpoint.json, in that folder; the outputs
    /// are then bit for bit those of an uninterrupted run.
    #[arg(long, value_name = "CHECKPOINT", conflicts_with = "force")]
    pub resume: Option<PathBuf>,
    /// Stop like Ctrl-C after N steps in all (to run in chunks).
    #[arg(long, value_name = "N")]
    pub stop_after_steps: Option<usize>,
    /// For tests: send SIGINT to this process after step N and wait until the handler has
    /// seen it, so that an interruption by a real signal lands at a known step.
    #[arg(long, value_name = "N", hide = true)]
    pub signal_self_after_step: Option<usize>,
}

/// `phstring run`: runs the scenario (or resumes the checkpoint) of `args` and prints what
/// it did; `quiet`: no progress bar.
pub fn run(args: RunArgs, quiet: bool) -> Result<()> {
    let RunArgs {
        scenario,
        out,
        sets,
        force,
        ignore,
        motion,
        checkpoint_every,
        resume,
        stop_after_steps,
        signal_self_after_step,
    } = args;
    // From here on, Ctrl-C or SIGTERM asks the run to stop, and a second one exits.
    let stop = stop_flag();
    // The lock on the output folder is held until the run ends (or the process dies).
    let (file, setup, out, resume, early, _lock) = match (scenario, resume) {
        (_, Some(cp_path)) => {
            let cp = CheckpointFile::read(&cp_path)?;
            let file = scenario::parse(&cp.scenario_text, cp.scenario_path_for_resume(), &[])?;
            cp.check_data_files(&file)?;
            let dir = out.unwrap_or_else(|| {
                cp_path
                    .parent()
                    .filter(|p| !p.as_os_str().is_empty())
                    .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
            });
            check_budget(&file)?;
            let setup = file.setup()?;
            let lock = outdir::prepare_resume(&dir)?;
            (file, setup, dir, Some(cp), Vec::new(), lock)
        }
        (Some(scenario), None) => {
            let file = budget::load(&scenario, &sets, &ignore, motion.as_deref())?;
            // Before validation, which itself holds the whole mesh.
            let b = budget(&file)?;
            if let Some(e) = b.memory_error(1) {
                bail!("{e}");
            }
            // Printed now: a run that fails at its first step may be why.
            let (setup, early) = check_and_warn(&file)?;
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
            (file, setup, out, None, early, lock)
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
    let mut bar = progress_bar(quiet, &run_label(&file));
    bar.signal = signal;
    // An interrupted time loop keeps its own message (with `--resume`).
    let ran = runner::run_setup(&file, setup, &out, &mut bar, opts);
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
