//! `bodies.csv`: the rigid bodies' states at the end of every step whose `energy.csv` row is
//! written (and at `t = 0`), one row per body, with the wrench ports' inputs and power when a
//! body has one (header: [`crate::files::bodies_header`]).

use std::path::Path;

use phstring::{Material, Simulation};

use super::csv::Csv;
use super::{OutputError, check_finite};
use crate::files::{BODIES_FILE, bodies_header};

/// Whether any body of `sim` has a wrench port, a feedback law or a prescribed motion (then
/// `bodies.csv` has the port's columns: the input wrench with the feedback's, or the motion's
/// reaction wrench).
pub(super) fn any_wrench<const D: usize>(sim: &Simulation<D, Material>) -> bool {
    let sys = sim.system();
    (0..sys.bodies().len())
        .any(|b| sys.body_has_wrench(b) || sys.body_has_feedback(b) || sys.body_has_motion(b))
}

/// Creates `bodies.csv` in `dir` for a run with bodies (`None` without) and writes the rows
/// of the state of `sim` (`t = 0`, no port sample yet).
pub(super) fn create<const D: usize>(
    dir: &Path,
    sim: &Simulation<D, Material>,
) -> Result<Option<Csv>, OutputError> {
    if sim.system().bodies().is_empty() {
        return Ok(None);
    }
    let mut csv = Csv::create(dir.join(BODIES_FILE), &bodies_header(any_wrench(sim)))?;
    rows(&mut csv, sim, false)?;
    Ok(Some(csv))
}

/// Writes one row per body of the state of `sim` at its time: position, orientation
/// quaternion `(w, x, y, z)`, velocity and angular velocity in space axes; with the wrench
/// columns, the last step's port sample (`sampled`), or zeros before the first step.
pub(super) fn rows<const D: usize>(
    csv: &mut Csv,
    sim: &Simulation<D, Material>,
    sampled: bool,
) -> Result<(), OutputError> {
    let sys = sim.system();
    let t = sim.time();
    let wrench = any_wrench(sim);
    let names = sys.bodies();
    for (b, st) in sim.state().bodies.iter().enumerate() {
        let q = st.orientation.quaternion();
        let omega = st.omega_space();
        let mut values = [0.0; 20];
        values[..3].copy_from_slice(st.position.as_slice());
        values[3..7].copy_from_slice(&[q.w, q.i, q.j, q.k]);
        values[7..10].copy_from_slice(st.velocity.as_slice());
        values[10..13].copy_from_slice(omega.as_slice());
        let n = if wrench { 20 } else { 13 };
        if wrench
            && sampled
            && let Some(p) = sim.body_ports().get(b)
        {
            values[13..16].copy_from_slice(p.force.as_slice());
            values[16..19].copy_from_slice(p.torque.as_slice());
            values[19] = p.mean_power;
        }
        check_finite(&csv.path, "body state", t, &values[..n])?;
        let name = names.get(b).map_or("", |(name, _)| name);
        csv.num(t).field(name).nums(&values[..n]).end_line()?;
    }
    csv.end_record()
}
