//! `winches.csv`: the winches' payout, tension at the drum and power at the end of every
//! step whose `energy.csv` row is written (and at `t = 0`), one row per winch (header:
//! [`crate::files::WINCHES_HEADER`]); `winch_arclength.csv`: the arc length of every node
//! of each winch's string at the frames of `positions.csv` (header:
//! [`crate::files::WINCH_ARCLENGTH_HEADER`]).

use std::path::Path;

use phstring::{Material, Simulation};

use super::csv::Csv;
use super::{OutputError, check_finite};
use crate::files::{WINCH_ARCLENGTH_FILE, WINCH_ARCLENGTH_HEADER, WINCHES_FILE, WINCHES_HEADER};

/// Creates `winches.csv` in `dir` for a run with winches (`None` without) and writes the
/// rows of `sim` at its start.
pub(super) fn create<const D: usize>(
    dir: &Path,
    sim: &Simulation<D, Material>,
) -> Result<Option<Csv>, OutputError> {
    if sim.system().winches().is_empty() {
        return Ok(None);
    }
    let mut csv = Csv::create(dir.join(WINCHES_FILE), WINCHES_HEADER)?;
    rows(&mut csv, sim)?;
    Ok(Some(csv))
}

/// Writes one row per winch of `sim` at its time: payout, length and mass off the drum,
/// the last step's mean speed, the drum tension, the last step's mean power, the energy
/// supplied so far, and of a drum with dynamics the energy its motor supplied and its damping
/// and brake dissipated so far (0 without) (speed and power zero before the first step).
pub(super) fn rows<const D: usize>(
    csv: &mut Csv,
    sim: &Simulation<D, Material>,
) -> Result<(), OutputError> {
    let t = sim.time();
    let names = sim.system().winches();
    for (w, s) in sim.winch_samples().iter().enumerate() {
        let values = [
            s.payout,
            s.length,
            s.speed,
            s.tension,
            s.power,
            s.energy,
            s.mass,
            s.motor,
            s.dissipated,
        ];
        check_finite(&csv.path, "winch", t, &values)?;
        let name = names.get(w).map_or("", |(name, _)| name);
        csv.num(t).field(name).nums(&values).end_line()?;
    }
    csv.end_record()
}

/// Creates `winch_arclength.csv` in `dir` for a run with winches (`None` without); its
/// rows are written with the frames of `positions.csv` ([`arc_rows`]).
pub(super) fn create_arclength<const D: usize>(
    dir: &Path,
    sim: &Simulation<D, Material>,
) -> Result<Option<Csv>, OutputError> {
    if sim.system().winches().is_empty() {
        return Ok(None);
    }
    Csv::create(dir.join(WINCH_ARCLENGTH_FILE), WINCH_ARCLENGTH_HEADER).map(Some)
}

/// Writes one row per node of each winch's string of `sim` at its time: the winch, the
/// mesh node and its unstretched arc length from the drum point
/// ([`Simulation::winch_arc_lengths`]).
pub(super) fn arc_rows<const D: usize>(
    csv: &mut Csv,
    sim: &Simulation<D, Material>,
) -> Result<(), OutputError> {
    let t = sim.time();
    let mut nodes = Vec::new();
    for (w, (name, _)) in sim.system().winches().into_iter().enumerate() {
        sim.winch_arc_lengths(w, &mut nodes);
        for &(node, s) in &nodes {
            check_finite(&csv.path, "winch arc length", t, &[s])?;
            csv.num(t).field(name).field(node).nums(&[s]).end_line()?;
        }
    }
    csv.end_record()
}
