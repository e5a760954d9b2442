//! File formats and plots for phstring: scenario files (TOML) validated into problems,
//! output writers (CSV, JSON, ParaView), plots (SVG/PNG), and the command drivers used by
//! the `phstring` command line.
//!
//! The modules are floors; each uses only the floors below it:
//!
//! 1. [`text`] (numbers and text in messages), [`channels`] (MoorDyn's output channel
//!    names), [`files`] (the names and layout of the
//!    output files, the run id, atomic writes) and [`tables`] (time tables of motions and
//!    forces read from text files), [`extremes`] (the extremes of every line over a run);
//! 2. [`plot`], [`vtk`] and [`animation`] (figure and ParaView formats), [`scenario`]
//!    (scenario files, validation, and starting a simulation from one), and [`moordyn`]
//!    (MoorDyn input decks read into a typed deck);
//! 3. [`checkpoint`] (the checkpoint file);
//! 4. [`output`] (the writers of a run);
//! 5. [`history`] (a run's outputs read back) and [`figures`] (the plots drawn from them);
//! 6. [`drive`]: the command drivers (run, statics, modes, linearize, sweep, output folder
//!    preparation); nothing below imports them.

pub mod animation;
pub mod body_shape;
pub mod channels;
pub mod checkpoint;
pub mod drive;
pub mod extremes;
pub mod figures;
pub mod files;
pub mod history;
pub mod moordyn;
pub mod output;
pub mod plot;
pub mod scenario;
pub mod scene;
pub mod tables;
#[cfg(test)]
mod test_util;
pub mod text;
pub mod vtk;
