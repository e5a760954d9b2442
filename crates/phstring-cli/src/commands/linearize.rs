//! `phstring linearize`: the linear port-Hamiltonian model of a scenario about its static
//! equilibrium or a checkpoint's positions.

use std::path::PathBuf;

use anyhow::Result;
use phstring_io::drive::linearize::{ExportError, LinearizeAt};

use super::common::{SetAndForce, interrupted_as, prepare_scenario_command};
use crate::at_least_one;

/// The message of `phstring linearize` interrupted by a stop request; the output folder
/// follows.
const STOPPED_LINEARIZE: &str = "interrupted before the model was written; nothing was written to";

// The arguments of `phstring linearize`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct LinearizeArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// Linearize at this checkpoint's positions instead of the equilibrium, on the mesh it
    /// holds (its winches' lengths).
    #[arg(long, value_name = "CHECKPOINT")]
    pub at: Option<PathBuf>,
    /// With --at: about the equilibrium of the system as the checkpoint holds it (from its
    /// positions) instead of its positions.
    #[arg(long, requires = "at")]
    pub equilibrium: bool,
    /// Also write the modal truncation to the K lowest natural modes (form `modal`).
    #[arg(long, value_name = "K", value_parser = at_least_one)]
    pub modes: Option<usize>,
    /// Output folder (default: out/<scenario name>_linear).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub set_force: SetAndForce,
}

/// `phstring linearize`: writes the linear model of the scenario of `args` and prints its
/// forms.
pub fn linearize(args: LinearizeArgs) -> Result<()> {
    let at = args.at.as_deref();
    // The checkpoint is read and checked before the folder is touched.
    let p = prepare_scenario_command(
        &args.scenario,
        &args.set_force,
        args.out,
        "_linear",
        at.as_slice(),
        |setup| match at {
            Some(path) => Ok(phstring_io::drive::linearize::checkpoint_at(
                setup,
                path,
                args.equilibrium,
            )?),
            None => Ok(LinearizeAt::Equilibrium),
        },
    )?;
    let out = &p.out;
    let model = phstring_io::drive::linearize::linearize(
        &p.file,
        &p.setup,
        &p.read,
        args.modes,
        out,
        Some(&p.stop),
    );
    let m = interrupted_as(model, ExportError::is_interrupted, STOPPED_LINEARIZE, out)?;
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
