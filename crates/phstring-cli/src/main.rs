//! `phstring`: run scenario files, reproduce the paper's benchmark and figures.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use phstring_io::checkpoint::CheckpointFile;
use phstring_io::plot::{self, Series};
use phstring_io::runner::{self, Progress, RunError, RunInfo, RunOptions};
use phstring_io::scenario::{self, ScenarioFile};
use phstring_io::sweep::Vary;

/// Prints a line to stdout; a closed pipe (`phstring check … | head`) is not an error.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
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
        #[arg(long, value_name = "N")]
        checkpoint_every: Option<usize>,
        /// Continue an interrupted run from its checkpoint.json, in that folder; the outputs
        /// are then bit for bit those of an uninterrupted run.
        #[arg(long, value_name = "CHECKPOINT")]
        resume: Option<PathBuf>,
        /// Stop like Ctrl-C after N steps in all (to run in chunks).
        #[arg(long, value_name = "N")]
        stop_after_steps: Option<usize>,
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
        /// Parallel runs (default: number of cores).
        #[arg(long, short)]
        jobs: Option<usize>,
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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            // 130 = interrupted (as a shell reports SIGINT), 1 = any other failure.
            match e.downcast_ref::<RunError>() {
                Some(RunError::Interrupted { .. }) => ExitCode::from(130),
                _ => ExitCode::FAILURE,
            }
        }
    }
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
        } => {
            let (file, out, resume) = match (scenario, resume) {
                (_, Some(cp_path)) => {
                    let cp = CheckpointFile::read(&cp_path)?;
                    let file = scenario::parse(&cp.scenario_text, &cp.scenario_path, &[])?;
                    let dir = out.unwrap_or_else(|| {
                        cp_path
                            .parent()
                            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
                    });
                    (file, dir, Some(cp))
                }
                (Some(scenario), None) => {
                    let file = scenario::load(&scenario, &sets)?;
                    file.check()?;
                    let out = out.unwrap_or_else(|| {
                        let stem = scenario
                            .file_stem()
                            .map_or("run".into(), |s| s.to_string_lossy().into_owned());
                        Path::new("out").join(stem)
                    });
                    prepare_out(&out, force)?;
                    (file, out, None)
                }
                (None, None) => bail!("give a scenario file or --resume CHECKPOINT"),
            };
            let opts = RunOptions {
                checkpoint_every,
                stop_after_steps,
                stop: Some(stop_flag()),
                resume,
                ..Default::default()
            };
            let info = run_one(&file, &out, cli.quiet, opts)?;
            say!(
                "{}: {} steps, Ĥ(0) = {:.9} J, Ĥ(T) = {:.9} J, max balance error {:.2e} J, {} Newton iterations, time loop {:.3} s",
                info.status,
                info.steps,
                info.hamiltonian_initial,
                info.hamiltonian_final,
                info.max_balance_error,
                info.total_newton_iterations,
                info.time_loop_s
            );
            say!("outputs in {}", out.display());
            Ok(())
        }
        Command::Check { scenario, sets } => check(&scenario, &sets),
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

/// Refuses a non-empty output folder unless `force`.
fn prepare_out(out: &Path, force: bool) -> Result<()> {
    if out.exists() {
        if !out.is_dir() {
            bail!("output path {} exists and is not a folder", out.display());
        }
        let non_empty = std::fs::read_dir(out)
            .with_context(|| format!("cannot read output folder {}", out.display()))?
            .flatten()
            .any(|e| !phstring_io::output::is_own_temp_file(&e.file_name().to_string_lossy()));
        if non_empty && !force {
            bail!(
                "output folder {} is not empty; pass --force to overwrite it, or choose another with --out",
                out.display()
            );
        }
        if non_empty {
            clear_outputs(out)?;
        }
    }
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create output folder {}", out.display()))
}

/// Removes the files a previous run wrote into `out` (and nothing else), so that stale
/// frames or plots cannot be mistaken for the new run's.
fn clear_outputs(out: &Path) -> Result<()> {
    let ours = |name: &str| {
        matches!(
            name,
            "energy.csv"
                | "positions.csv"
                | "ports.csv"
                | "summary.json"
                | "string.pvd"
                | "checkpoint.json"
                | "sweep.csv"
        ) || (name.starts_with("frame_") && name.ends_with(".vtp"))
            || ["energy", "configuration", "increments"]
                .iter()
                .any(|s| name == format!("{s}.svg") || name == format!("{s}.png"))
            || (name.starts_with("fig") && (name.ends_with(".svg") || name.ends_with(".png")))
    };
    let mut dirs: Vec<PathBuf> = [
        "",
        "paraview",
        "dg",
        "mp",
        "dg/paraview",
        "mp/paraview",
        "figures",
    ]
    .iter()
    .map(|s| out.join(s))
    .collect();
    // Sweep runs: run_NNN/ and run_NNN/paraview/.
    if let Ok(entries) = std::fs::read_dir(out) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let is_run = name
                .strip_prefix("run_")
                .is_some_and(|n| n.chars().all(|c| c.is_ascii_digit()));
            if is_run && e.path().is_dir() {
                dirs.push(e.path());
                dirs.push(e.path().join("paraview"));
            }
        }
    }
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if entry.path().is_file() && ours(&name) {
                std::fs::remove_file(entry.path()).with_context(|| {
                    format!("cannot remove old output {}", entry.path().display())
                })?;
            }
        }
    }
    Ok(())
}

/// Progress over simulated time (per mille of `t_end`), with step count and time.
struct Bar(Option<ProgressBar>, f64);

impl Progress for Bar {
    fn start(&mut self, t_end: f64) {
        self.1 = t_end;
        if let Some(b) = &self.0 {
            b.set_length(1000);
        }
    }
    fn step(&mut self, step: usize, t: f64) {
        if let Some(b) = &self.0 {
            b.set_position((1000.0 * t / self.1).round() as u64);
            if step.is_multiple_of(16) {
                b.set_message(format!("t = {t:.4} s of {} s, step {step}", self.1));
            }
        }
    }
    fn finish(&mut self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}

fn progress_bar(quiet: bool, label: &str) -> Bar {
    if quiet || !std::io::stderr().is_terminal() {
        return Bar(None, 1.0);
    }
    let b = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    b.set_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {msg}, ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    b.set_prefix(label.to_string());
    b.enable_steady_tick(Duration::from_millis(200));
    Bar(Some(b), 1.0)
}

fn run_one(file: &ScenarioFile, out: &Path, quiet: bool, opts: RunOptions) -> Result<RunInfo> {
    let label = file
        .scenario
        .title
        .clone()
        .unwrap_or_else(|| file.path.display().to_string());
    let mut bar = progress_bar(quiet, &label);
    Ok(runner::run(file, out, &mut bar, opts)?)
}

/// A flag set by Ctrl-C (SIGINT/SIGTERM): runs stop at the end of the current step with
/// their outputs flushed and a checkpoint written.
fn stop_flag() -> std::sync::Arc<AtomicBool> {
    static STOP: std::sync::OnceLock<std::sync::Arc<AtomicBool>> = std::sync::OnceLock::new();
    STOP.get_or_init(|| {
        let flag = std::sync::Arc::new(AtomicBool::new(false));
        let set = flag.clone();
        // If no handler can be installed, Ctrl-C keeps its default effect.
        let _ = ctrlc::set_handler(move || set.store(true, Ordering::SeqCst));
        flag
    })
    .clone()
}

fn sweep(
    path: &Path,
    vary: &[String],
    sets: &[String],
    out: &Path,
    jobs: Option<usize>,
    force: bool,
    quiet: bool,
) -> Result<()> {
    let vary: Vec<Vary> = vary
        .iter()
        .map(|v| Vary::parse(v))
        .collect::<Result<_, _>>()?;
    let n: usize = vary.iter().map(|v| v.values.len()).product();
    prepare_out(out, force)?;
    if out.join("sweep.csv").exists() {
        std::fs::remove_file(out.join("sweep.csv"))?;
    }
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let bar = progress_bar(quiet, "sweep");
    if let Some(b) = &bar.0 {
        b.set_length(n as u64);
        b.set_message(format!("{n} runs on {jobs} threads"));
    }
    let done = |r: &phstring_io::sweep::SweepRun| {
        if let Some(b) = &bar.0 {
            b.inc(1);
            if let Err(e) = &r.result {
                b.println(format!("run {} failed: {e}", r.index));
            }
        }
    };
    let runs = phstring_io::sweep::run(path, sets, &vary, out, jobs, &done)?;
    if let Some(b) = &bar.0 {
        b.finish_and_clear();
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

fn check(path: &Path, sets: &[String]) -> Result<()> {
    let file = scenario::load(path, sets)?;
    let d = file.dimension()?;
    let text = match d {
        1 => describe::<1>(&file)?,
        2 => describe::<2>(&file)?,
        _ => describe::<3>(&file)?,
    };
    say!("{} is valid:\n{text}", path.display());
    Ok(())
}

fn describe<const D: usize>(file: &ScenarioFile) -> Result<String> {
    let v = file.validate::<D>()?;
    let p = &v.problem;
    let s = &v.settings;
    let mut out = String::new();
    use std::fmt::Write;
    let _ = writeln!(
        out,
        "  title:     {}",
        file.scenario.title.as_deref().unwrap_or("(none)")
    );
    let _ = writeln!(out, "  dimension: {D}");
    let _ = writeln!(
        out,
        "  mesh:      {} elements, {} nodes, reference length {} m",
        p.mesh.n_elements(),
        p.mesh.n_nodes(),
        p.mesh.total_length()
    );
    let _ = writeln!(
        out,
        "  material:  {}, EA = {} N, rhoA = {} kg/m, {} mass",
        p.material.name(),
        p.material.ea(),
        p.rho_a,
        match p.mass {
            phstring::MassMatrix::Consistent => "consistent",
            phstring::MassMatrix::Lumped => "lumped",
        }
    );
    let _ = writeln!(out, "  body force: {:?} N/m", p.body_force.as_slice());
    for f in &p.boundary.fixed {
        let comps: Vec<&str> = ["x", "y", "z"][..D]
            .iter()
            .zip(f.components)
            .filter(|(_, c)| *c)
            .map(|(n, _)| *n)
            .collect();
        let _ = writeln!(out, "  fixed:     node {} ({})", f.node, comps.join(", "));
    }
    for (node, exprs) in &v.loads {
        let _ = writeln!(out, "  force:     node {node}: [{}] N", exprs.join(", "));
    }
    let steps = (s.t_end / s.step.h).round() as usize;
    let _ = writeln!(
        out,
        "  time:      {} scheme, h = {} s, T = {} s, {steps} steps",
        s.step.scheme.name(),
        s.step.h,
        s.t_end
    );
    let _ = write!(
        out,
        "  newton:    tol = {:e} N, max {} iterations, solver {}",
        s.step.newton.tol,
        s.step.newton.max_iter,
        s.step.solver.name()
    );
    Ok(out)
}

fn paper(out: &Path, force: bool, quiet: bool) -> Result<()> {
    prepare_out(out, force)?;
    let path = Path::new("examples/paper_pendulum.toml (built in)");
    let mut infos = Vec::new();
    for scheme in ["dg", "mp"] {
        let file = scenario::parse(PAPER_SCENARIO, path, &[format!("time.scheme={scheme}")])?;
        let dir = out.join(scheme);
        std::fs::create_dir_all(&dir)?;
        let opts = RunOptions {
            end_of_loading: Some(PAPER_END_OF_LOADING),
            stop: Some(stop_flag()),
            ..Default::default()
        };
        let info = run_one(&file, &dir, quiet, opts)?;
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
