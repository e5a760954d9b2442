//! `phstring`: run scenario files, reproduce the paper's benchmark and figures.

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use phstring_io::drive::run::RunError;

/// Prints a line to stdout; a closed pipe (`phstring check … | head`) or a full disk is not
/// an error. Control characters (from titles, values) are escaped; line breaks are kept.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let _ = writeln!(std::io::stdout().lock(), "{}", phstring_io::text::printable(&text, true));
    }};
}

/// Prints a line to stderr like [`say!`]: a closed or full stderr (`2>/dev/full`) neither
/// panics nor changes the exit code.
macro_rules! tell {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = format!($($arg)*);
        let _ = writeln!(std::io::stderr().lock(), "{}", phstring_io::text::printable(&text, true));
    }};
}

mod budget;
mod commands;

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
    /// For tests: send SIGINT to this process N ms after the command installs its Ctrl-C
    /// handler (`run`, `statics`, `modes`, `linearize`, `sweep`, `paper`), and wait until the
    /// handler has seen it; for phases without steps.
    #[arg(long, value_name = "N", global = true, hide = true)]
    signal_self_after_ms: Option<u64>,
    #[command(subcommand)]
    command: Command,
}
#[derive(Subcommand)]
enum Command {
    /// Run the paper's benchmark with DG and MP and redraw its figures.
    Paper(commands::paper::PaperArgs),
    /// Run a scenario file.
    Run(commands::run::RunArgs),
    /// Run a scenario or MoorDyn deck for every combination of varied values, in parallel
    /// (over a deck, --vary motion=a.csv,b.csv is a load-case campaign: campaign.csv).
    Sweep(commands::sweep::SweepArgs),
    /// Find the static equilibrium of a scenario under its loads at t = 0, or (--at) of the
    /// system as a run's checkpoint holds it: its winches' lengths, its supports and loads
    /// at its time (positions, tensions, support reactions; CSV, ParaView, plot,
    /// summary.json).
    Statics(commands::statics::StaticsArgs),
    /// Write the linear port-Hamiltonian model about the static equilibrium (or a
    /// checkpoint's positions on its winches' mesh, or with --equilibrium the equilibrium
    /// there): MatrixMarket and scipy .npz matrices and manifest.json.
    Linearize(commands::linearize::LinearizeArgs),
    /// The lowest natural frequencies and mode shapes about the static equilibrium
    /// (modes.csv, ParaView frames, plot, summary.json).
    Modes(commands::modes::ModesArgs),
    /// A rigid body's mooring about the static equilibrium: its restoring stiffness matrix
    /// (the strings condensed onto its pose) and its offset–tension curve along one degree of
    /// freedom (stiffness.csv, offset.csv, summary.json).
    Mooring(commands::mooring::MooringArgs),
    /// Validate a scenario file (or a MoorDyn deck: with the table of what each deck entry
    /// became) and print what would run.
    Check(commands::check::CheckArgs),
    /// Build an FMI 2.0 (or 3.0) Co-Simulation FMU of a scenario: its ports (external = true) as
    /// inputs, port outputs, energies and listed node positions as outputs, EA, ρA and h as
    /// parameters.
    Fmu(commands::fmu::FmuArgs),
}

/// A count option that must be at least 1 (`--jobs 0` or `--checkpoint-every 0` would do
/// nothing, and are refused rather than ignored).
pub fn at_least_one(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("{e}")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(ms) = cli.signal_self_after_ms {
        let _ = commands::common::SIGNAL_AFTER_MS.set(ms);
    }
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tell!("error: {}", error_text(&e));
            // 130 = interrupted (as a shell reports SIGINT), 1 = any other failure.
            if matches!(
                e.downcast_ref::<RunError>(),
                Some(RunError::Interrupted { .. })
            ) || e.is::<commands::common::Interrupted>()
            {
                ExitCode::from(130)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// The error with its causes, each stated once: a cause whose text the message already
/// holds (an error type that prints its source and also returns it from `source()`) is not
/// repeated.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}
/// Runs the command of `cli`.
fn dispatch(cli: Cli) -> Result<()> {
    use commands::{check, fmu, linearize, modes, mooring, paper, run, statics, sweep};
    match cli.command {
        Command::Paper(a) => paper::paper(&a.out, a.force, cli.quiet),
        Command::Run(a) => run::run(a, cli.quiet),
        Command::Check(a) => check::check(&a),
        Command::Fmu(a) => fmu::fmu(a),
        Command::Modes(a) => modes::modes(a),
        Command::Mooring(a) => mooring::mooring(a),
        Command::Linearize(a) => linearize::linearize(a),
        Command::Statics(a) => statics::statics(a),
        Command::Sweep(a) => sweep::sweep(a, cli.quiet),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_causes_appear_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        // A message that already holds its cause, with the cause also chained.
        #[derive(Debug)]
        struct Both(std::io::Error);
        impl std::fmt::Display for Both {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "cannot read x: {}", self.0)
            }
        }
        impl std::error::Error for Both {
            fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
                Some(&self.0)
            }
        }
        let e = anyhow::Error::new(Both(io)).context("loading");
        assert_eq!(error_text(&e), "loading: cannot read x: gone");
    }
}
