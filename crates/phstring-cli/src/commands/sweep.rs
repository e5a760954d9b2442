//! `phstring sweep`: one scenario (or MoorDyn deck) run for every combination of varied
//! values, in parallel, into one folder with a table of the runs; over a deck, also the
//! campaign table of its lines' extremes.

use std::path::PathBuf;

use anyhow::{Result, bail};
use phstring_io::drive::sweep::{DeckOptions, Sweep, SweepRun, Vary};
use phstring_io::files::{CAMPAIGN_TABLE, SWEEP_TABLE};
use phstring_io::text::printable;

use super::common::{Interrupted, prepare_out_for, progress_bar, stop_flag};
use crate::at_least_one;
use crate::budget::{self, check_budget_of};

// The arguments of `phstring sweep`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// A key and its values, e.g. --vary mesh.elements=100,300,1000 (repeatable: all
    /// combinations run). For a deck, --vary motion=a.csv,b.csv runs it driven by each
    /// platform table, as `run DECK --motion a.csv` (a load-case campaign: campaign.csv).
    #[arg(long = "vary", value_name = "KEY=V1,V2,...", required = true)]
    pub vary: Vec<String>,
    /// Fixed overrides for every run.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// For a MoorDyn deck: drop a feature phstring does not model (as `run --ignore`).
    #[arg(long = "ignore", value_name = "FEATURE")]
    pub ignore: Vec<String>,
    /// For a MoorDyn deck: one vessel motion table for every run (as `run --motion`); to
    /// vary it, use --vary motion=… instead.
    #[arg(long, value_name = "FILE")]
    pub motion: Option<PathBuf>,
    /// Output folder (one sub-folder per run, plus sweep.csv).
    #[arg(long, default_value = "out/sweep")]
    pub out: PathBuf,
    /// Parallel runs (default: number of cores; at most 4 per core).
    #[arg(long, short, value_parser = at_least_one)]
    pub jobs: Option<usize>,
    /// Overwrite a non-empty output folder.
    #[arg(long)]
    pub force: bool,
}

/// Most `--jobs` per core.
const MAX_JOBS_PER_CORE: usize = 4;

/// `phstring sweep`: runs the scenario of `args` for every combination of the varied values,
/// `--jobs` at a time, and prints where the table is; `quiet`: no progress bar.
pub fn sweep(args: SweepArgs, quiet: bool) -> Result<()> {
    let SweepArgs {
        scenario,
        vary,
        sets,
        ignore,
        motion,
        out,
        jobs,
        force,
    } = args;
    let (path, out) = (scenario.as_path(), out.as_path());
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
    let deck = DeckOptions { ignore, motion };
    let plan = Sweep::new_with(path, &sets, vary, deck, |index, file| {
        check_budget_of(file, concurrent).map_err(|e| format!("run {index} of the sweep: {e:#}"))
    })?;
    let n = plan.len();
    let _lock = prepare_out_for(out, force, &[path])?;
    let bar = progress_bar(quiet, "sweep");
    if let Some(b) = &bar.bar {
        b.set_length(n as u64);
        b.set_message(format!("{n} runs on {jobs} threads"));
    }
    let done = |r: &SweepRun| {
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
            out.join(SWEEP_TABLE).display()
        )));
    }
    let failed = runs.iter().filter(|r| r.result.is_err()).count();
    let campaign = if plan.is_deck() {
        format!(", campaign: {}", out.join(CAMPAIGN_TABLE).display())
    } else {
        String::new()
    };
    say!(
        "{} runs ({failed} failed) in {}; table: {}{campaign}",
        runs.len(),
        out.display(),
        out.join(SWEEP_TABLE).display()
    );
    if failed > 0 {
        bail!("{failed} of {} runs failed (see sweep.csv)", runs.len());
    }
    Ok(())
}
