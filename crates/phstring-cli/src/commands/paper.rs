//! `phstring paper`: the paper's benchmark with both schemes, its figures and its table.

use std::path::{Path, PathBuf};

use anyhow::Result;
use phstring_io::drive::run::{RunError, RunOptions};
use phstring_io::files::{FIGURES_DIR, PAPER_FIGURE_STEMS, PAPER_RUN_DIRS};
use phstring_io::plot::{self, Series};
use phstring_io::scenario;

use super::common::{Interrupted, prepare_out, run_one, stop_flag};

/// The paper's benchmark scenario, kept in this crate so that it is packaged with it; the
/// same bytes as `examples/paper_pendulum.toml` (a test checks it).
const PAPER_SCENARIO: &str = include_str!("../../examples-data/paper_pendulum.toml");
/// End of the loading phase of the paper's benchmark [s].
const PAPER_END_OF_LOADING: f64 = 0.2;

// The arguments of `phstring paper`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct PaperArgs {
    /// Output folder.
    #[arg(long, default_value = "out/paper")]
    pub out: PathBuf,
    /// Overwrite a non-empty output folder.
    #[arg(long)]
    pub force: bool,
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

/// `phstring paper`: runs the paper's benchmark with both schemes into `out` (`force`: over
/// an earlier one), draws its figures and prints its table; `quiet`: no progress bar.
pub fn paper(out: &Path, force: bool, quiet: bool) -> Result<()> {
    let stop = stop_flag();
    let _lock = prepare_out(out, force)?;
    let path = Path::new("examples/paper_pendulum.toml (built in)");
    let mut infos = Vec::new();
    for &scheme in PAPER_RUN_DIRS {
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
    let figures = out.join(FIGURES_DIR);
    let [fig2, fig3, fig4, fig5] = PAPER_FIGURE_STEMS;
    std::fs::create_dir_all(&figures)?;
    let (dg, mp) = (&infos[0].history, &infos[1].history);
    let title = "String pendulum (paper, Section 4)";
    plot::configuration_plot(
        &figures.join(fig2),
        "Fig. 2: configurations (DG)",
        &dg.snapshots,
    )?;
    plot::energy_plot(
        &figures.join(fig3),
        "Fig. 3: energies (DG)",
        &dg.t,
        &dg.kinetic,
        &dg.potential,
        &dg.hamiltonian,
    )?;
    plot::series_plot(
        &figures.join(fig4),
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
        &figures.join(fig5),
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

    /// An interrupted `phstring paper` does not suggest a `--resume` (which would complete
    /// only `dg/`): the message suggests re-running the whole benchmark instead.
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

    /// The embedded benchmark is the user-facing example byte for byte, so that `phstring
    /// paper` runs what `examples/paper_pendulum.toml` shows (checked where the crate sits
    /// in its workspace; a packaged crate has no `examples/` folder).
    #[test]
    fn embedded_paper_scenario_is_the_example() {
        let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
        let workspace = crate_dir.join("../..");
        if !workspace.join("Cargo.toml").is_file() {
            return;
        }
        let example = std::fs::read(workspace.join("examples/paper_pendulum.toml"))
            .expect("examples/paper_pendulum.toml is in the workspace");
        assert!(
            example == PAPER_SCENARIO.as_bytes(),
            "examples/paper_pendulum.toml and crates/phstring-cli/examples-data/paper_pendulum.toml differ: change both alike"
        );
    }
}
