//! `phstring statics`: the static equilibrium of a scenario under its loads at `t = 0`.

use std::path::PathBuf;

use anyhow::Result;
use phstring_io::drive::statics::StaticsRunError;

use super::common::{SetAndForce, energy, interrupted_as, prepare_scenario_command};

/// The message of `phstring statics` interrupted by a stop request; the output folder
/// follows.
const STOPPED_STATICS: &str =
    "interrupted before the equilibrium was found; nothing was written to";

// The arguments of `phstring statics`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct StaticsArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// Output folder (default: out/<scenario name>_statics).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub set_force: SetAndForce,
}

/// `phstring statics`: solves the equilibrium of the scenario of `args`, writes it and
/// prints a summary.
pub fn statics(args: StaticsArgs) -> Result<()> {
    let p = prepare_scenario_command(
        &args.scenario,
        &args.set_force,
        args.out,
        "_statics",
        &[],
        |_| Ok(()),
    )?;
    let out = &p.out;
    let found = phstring_io::drive::statics::statics(&p.file, &p.setup, out, Some(&p.stop));
    let info = interrupted_as(found, StaticsRunError::is_interrupted, STOPPED_STATICS, out)?;
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
    if info.path != "catenary_guess" {
        say!("catenary first guess {}", info.first_guess);
    }
    say!("outputs in {}", out.display());
    Ok(())
}
