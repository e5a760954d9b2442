//! File formats and plots for phstring: scenario files (TOML) validated into problems,
//! output writers (CSV, JSON, ParaView), plots (SVG/PNG), and the run driver used by the
//! `phstring` command line.

pub mod animation;
pub mod checkpoint;
mod csvfile;
pub mod export;
pub mod modes_run;
pub mod outdir;
pub mod output;
pub mod plot;
pub mod runner;
pub mod scenario;
pub mod statics_run;
pub mod sweep;
#[cfg(test)]
mod test_util;
pub mod text;
pub mod vtk;
