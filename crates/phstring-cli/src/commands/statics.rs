//! `phstring statics`: the static equilibrium of a scenario under its loads at `t = 0`, or
//! of the system as a run's checkpoint holds it (`--at`).

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
    /// The equilibrium of the system as this checkpoint of a run of the scenario holds it
    /// (its winches' lengths, supports and loads at its time), from its positions.
    #[arg(long, value_name = "CHECKPOINT")]
    pub at: Option<PathBuf>,
    /// Output folder (default: out/<scenario name>_statics).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub set_force: SetAndForce,
}

/// `phstring statics`: solves the equilibrium of the scenario of `args`, writes it and
/// prints a summary.
pub fn statics(args: StaticsArgs) -> Result<()> {
    let at = args.at.as_deref();
    // The checkpoint is read and checked before the folder is touched.
    let p = prepare_scenario_command(
        &args.scenario,
        &args.set_force,
        args.out,
        "_statics",
        at.as_slice(),
        |setup| match at {
            Some(path) => Ok(Some(phstring_io::drive::at::read_at(setup, path)?)),
            None => Ok(None),
        },
    )?;
    let out = &p.out;
    let stop = Some(&*p.stop);
    let found = match &p.read {
        Some(at) => phstring_io::drive::statics::statics_at(&p.file, at, out, stop),
        None => phstring_io::drive::statics::statics(&p.file, &p.setup, out, stop),
    };
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
    if let Some(from) = &info.started_from {
        say!(
            "from {} at t = {} s",
            from.checkpoint,
            phstring::Num(from.time)
        );
        for w in &from.winches {
            say!(
                "winch {}: payout {} m, {} m off the drum (drum node {})",
                w.name,
                phstring::Num(w.payout),
                phstring::Num(w.length),
                w.drum_node
            );
        }
    }
    if info.path != "catenary_guess" {
        say!("catenary first guess {}", info.first_guess);
    }
    say!("outputs in {}", out.display());
    Ok(())
}
