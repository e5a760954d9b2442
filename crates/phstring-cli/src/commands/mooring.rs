//! `phstring mooring`: a rigid body's mooring stiffness matrix and offset–tension curve about
//! the static equilibrium of a scenario.

use std::path::PathBuf;

use anyhow::Result;
use phstring_io::drive::mooring::{MooringRequest, MooringRunError};

use super::common::{SetAndForce, interrupted_as, prepare_scenario_command};
use crate::at_least_one;

/// The message of `phstring mooring` interrupted by a stop request; the output folder
/// follows.
const STOPPED_MOORING: &str = "interrupted before the curve was complete; nothing was written to";

// The arguments of `phstring mooring`; their help text is the doc comment of the
// command's variant in `Command`.
#[derive(clap::Args)]
pub struct MooringArgs {
    /// Scenario file (TOML), or a MoorDyn input deck (told by its content).
    pub scenario: PathBuf,
    /// The rigid body (default: the scenario's only one).
    #[arg(long)]
    pub body: Option<String>,
    /// The offset–tension curve's degree of freedom: x, y, z, rx, ry, rz (2D: x, y, rz).
    #[arg(long, default_value = "x")]
    pub dof: String,
    /// The largest offset, in m (a turn: in degrees); default 5 % of the largest distance
    /// from the body to a support, or 10°.
    #[arg(long)]
    pub max: Option<f64>,
    /// Offsets on each side of the equilibrium.
    #[arg(long, default_value_t = 10, value_parser = at_least_one)]
    pub steps: usize,
    /// Output folder (default: out/<scenario name>_mooring).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub set_force: SetAndForce,
}

/// `phstring mooring`: the stiffness and the curve of the body of `args`, written and
/// summarized.
pub fn mooring(args: MooringArgs) -> Result<()> {
    let p = prepare_scenario_command(
        &args.scenario,
        &args.set_force,
        args.out,
        "_mooring",
        &[],
        |_| Ok(()),
    )?;
    let out = &p.out;
    let request = MooringRequest {
        body: args.body,
        dof: args.dof,
        max: args.max,
        steps: args.steps,
    };
    let found =
        phstring_io::drive::mooring::mooring(&p.file, &p.setup, &request, out, Some(&p.stop));
    let info = interrupted_as(found, MooringRunError::is_interrupted, STOPPED_MOORING, out)?;
    say!(
        "rigid body '{}' at its equilibrium ({}): position {:?} m",
        info.body,
        info.equilibrium_path,
        info.position
    );
    say!(
        "stiffness K [N/m, N/rad, N, N·m/rad] ({}):",
        info.dofs.join(", ")
    );
    for (d, row) in info.dofs.iter().zip(&info.stiffness) {
        let cells: Vec<String> = row.iter().map(|x| format!("{x:>13.5e}")).collect();
        say!("  {d:>2} {}", cells.join(" "));
    }
    if let (Some(first), Some(last)) = (info.curve.first(), info.curve.last()) {
        let top = |p: &phstring_io::drive::mooring::CurvePoint| {
            p.tensions.iter().copied().fold(0.0, f64::max)
        };
        say!(
            "offset {} from {:.4} to {:.4} {} ({} points): largest point tension {:.4e} N … {:.4e} N",
            info.curve_dof,
            first.offset,
            last.offset,
            info.curve_unit,
            info.curve.len(),
            top(first),
            top(last)
        );
    }
    say!("outputs in {} ({:.3} s)", out.display(), info.solve_s);
    Ok(())
}
