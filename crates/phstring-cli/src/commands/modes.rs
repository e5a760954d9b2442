//! `phstring modes`: the lowest natural frequencies and mode shapes about the static
//! equilibrium of a scenario.

use std::path::PathBuf;

use anyhow::Result;
use phstring_io::drive::modes::ModesRunError;

use super::common::{SetAndForce, interrupted_as, prepare_scenario_command};
use crate::at_least_one;

/// The message of `phstring modes` interrupted by a stop request; the output folder follows.
const STOPPED_MODES: &str =
    "interrupted before the modes were written; no modes.csv or summary.json was written to";

// The arguments of `phstring modes`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct ModesArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// Number of modes.
    #[arg(long, default_value_t = 10, value_parser = at_least_one)]
    pub count: usize,
    /// Output folder (default: out/<scenario name>_modes).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub set_force: SetAndForce,
}

/// `phstring modes`: finds the modes of the scenario of `args`, writes them and prints them.
pub fn modes(args: ModesArgs) -> Result<()> {
    let p = prepare_scenario_command(
        &args.scenario,
        &args.set_force,
        args.out,
        "_modes",
        &[],
        |_| Ok(()),
    )?;
    let out = &p.out;
    let found = phstring_io::drive::modes::modes(&p.file, &p.setup, args.count, out, Some(&p.stop));
    let info = interrupted_as(found, ModesRunError::is_interrupted, STOPPED_MODES, out)?;
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
