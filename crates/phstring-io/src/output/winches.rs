//! `winches.csv`: the winches' payout, tension at the drum and power at the end of every
//! step whose `energy.csv` row is written (and at `t = 0`), one row per winch (header:
//! [`crate::files::WINCHES_HEADER`]).

use std::path::Path;

use phstring::{Material, Simulation};

use super::csv::Csv;
use super::{OutputError, check_finite};
use crate::files::{WINCHES_FILE, WINCHES_HEADER};

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
