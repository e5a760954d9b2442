//! The `water` part of a run's `summary.json` (docs/method.md §21): where the energy went,
//! mechanism by mechanism, the final buoyancy and seabed energies, and the seabed contact
//! of each string, sampled at every row of `energy.csv`.

use phstring::{Law, Material, PhSystem, Simulation, Vector};
use serde::Serialize;

use crate::checkpoint::WaterCounters;

/// The grounded length of one string on the seabed.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GroundedString {
    /// The string's name.
    pub name: String,
    /// Grounded length at the end of the run [m]: its elements' reference lengths, each
    /// counted half for each of its two nodes on the seabed.
    pub grounded_length_final: f64,
    /// Smallest grounded length over the run [m], sampled at every row of `energy.csv`
    /// (`t = 0` and every step).
    pub grounded_length_min: f64,
}

/// The `water` object of `summary.json` of a run in water. The running totals are those of
/// `energy.csv`'s last row (and shares of `supplied_energy` and `dissipated_energy`); the
/// extremes are sampled at every row of `energy.csv`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct WaterSummary {
    /// Energy dissipated by drag relative to the water [J] (≥ 0).
    pub drag_dissipated: f64,
    /// Work of the current through the drag [J] (either sign; a port, part of the supplied
    /// energy).
    pub current_supplied: f64,
    /// Energy dissipated by the seabed's damping [J] (≥ 0).
    pub seabed_dissipated: f64,
    /// Energy dissipated by seabed friction [J] (≥ 0).
    pub friction_dissipated: f64,
    /// Buoyancy potential at the end [J] (part of `V̂`; its zero is the surface).
    pub buoyancy_final: f64,
    /// Seabed contact potential at the end [J] (≥ 0, part of `V̂`).
    pub seabed_final: f64,
    /// Per string (springs excluded), its grounded length at the end and the smallest
    /// over the run; all zero without a seabed.
    pub strings: Vec<GroundedString>,
    /// Largest contact force of the seabed on a node over the run [N] (0 if nothing touched
    /// it).
    pub max_contact_force: f64,
    /// The node it acted on (`null` if nothing touched the seabed).
    pub max_contact_force_node: Option<usize>,
    /// When [s].
    pub max_contact_force_t: f64,
}

/// The indices of the network's strings among its groups.
fn string_groups<const D: usize>(sys: &PhSystem<D, Material>) -> Vec<usize> {
    sys.groups()
        .iter()
        .enumerate()
        .filter(|(_, g)| matches!(g.law, Law::String(_)))
        .map(|(k, _)| k)
        .collect()
}

/// The grounded length [m] of each group in `groups` and the largest contact force [N] with
/// its node, at positions `r`, from one computation of the seabed contacts (the lengths are
/// those of [`PhSystem::grounded_length`]).
fn contact_state<const D: usize>(
    sys: &PhSystem<D, Material>,
    groups: &[usize],
    r: &[Vector<D>],
) -> (Vec<f64>, Option<(usize, f64)>) {
    let contacts = sys.seabed_contacts(r);
    let largest =
        contacts
            .iter()
            .filter(|c| c.grounded)
            .fold(None, |best: Option<(usize, f64)>, c| {
                if best.is_none_or(|(_, f)| c.force > f) {
                    Some((c.node, c.force))
                } else {
                    best
                }
            });
    let all = sys.grounded_lengths(&contacts);
    let lengths = groups.iter().map(|&g| all[g]).collect();
    (lengths, largest)
}

impl WaterSummary {
    /// The summary of `sim` before its first step (its state sampled), or `None` if it is
    /// not in water.
    pub fn start<const D: usize>(sim: &Simulation<D, Material>) -> Option<Self> {
        let sys = sim.system();
        if !sys.has_water() {
            return None;
        }
        let names = string_groups(sys)
            .into_iter()
            .map(|g| sys.groups()[g].name.clone());
        let mut w = Self {
            drag_dissipated: 0.0,
            current_supplied: 0.0,
            seabed_dissipated: 0.0,
            friction_dissipated: 0.0,
            buoyancy_final: 0.0,
            seabed_final: 0.0,
            strings: names
                .map(|name| GroundedString {
                    name,
                    grounded_length_final: 0.0,
                    grounded_length_min: f64::INFINITY,
                })
                .collect(),
            max_contact_force: 0.0,
            max_contact_force_node: None,
            max_contact_force_t: 0.0,
        };
        w.observe(sim);
        w.finish(sim);
        Some(w)
    }

    /// Samples the state of `sim` (at a row of `energy.csv`): the grounded lengths and the
    /// contact forces.
    pub fn observe<const D: usize>(&mut self, sim: &Simulation<D, Material>) {
        let sys = sim.system();
        let (lengths, largest) = contact_state(sys, &string_groups(sys), &sim.state().r);
        for (s, l) in self.strings.iter_mut().zip(lengths) {
            s.grounded_length_final = l;
            s.grounded_length_min = s.grounded_length_min.min(l);
        }
        if let Some((node, f)) = largest
            && f > self.max_contact_force
        {
            self.max_contact_force = f;
            self.max_contact_force_node = Some(node);
            self.max_contact_force_t = sim.time();
        }
    }

    /// Takes the running totals and the final energies from `sim` (at the end of the run,
    /// or of the part of it done so far).
    pub fn finish<const D: usize>(&mut self, sim: &Simulation<D, Material>) {
        let w = sim.water_work();
        let e = sim.energies();
        self.drag_dissipated = w.drag_dissipated;
        self.current_supplied = w.current_supplied;
        self.seabed_dissipated = w.seabed_dissipated;
        self.friction_dissipated = w.friction_dissipated;
        self.buoyancy_final = e.buoyancy;
        self.seabed_final = e.seabed;
        let sys = sim.system();
        let (lengths, _) = contact_state(sys, &string_groups(sys), &sim.state().r);
        for (s, l) in self.strings.iter_mut().zip(lengths) {
            s.grounded_length_final = l;
        }
    }

    /// The extremes to carry in a checkpoint.
    pub fn counters(&self) -> WaterCounters {
        WaterCounters {
            grounded_length_min: self.strings.iter().map(|s| s.grounded_length_min).collect(),
            max_contact_force: self.max_contact_force,
            max_contact_force_node: self.max_contact_force_node,
            max_contact_force_t: self.max_contact_force_t,
        }
    }

    /// The summary of `sim` restored from a checkpoint whose counters are `c` (checked
    /// against the scenario: one grounded length per string): the extremes carried on,
    /// the totals and the state those of `sim`.
    pub fn resumed<const D: usize>(
        sim: &Simulation<D, Material>,
        c: Option<&WaterCounters>,
    ) -> Option<Self> {
        let mut w = Self::start(sim)?;
        if let Some(c) = c {
            for (s, m) in w.strings.iter_mut().zip(&c.grounded_length_min) {
                s.grounded_length_min = *m;
            }
            w.max_contact_force = c.max_contact_force;
            w.max_contact_force_node = c.max_contact_force_node;
            w.max_contact_force_t = c.max_contact_force_t;
        }
        Some(w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{sim, wet_line};

    #[test]
    fn summary_samples_the_contact_and_takes_the_totals() {
        assert!(WaterSummary::start(&sim()).is_none());
        let mut s = wet_line();
        let mut w = WaterSummary::start(&s).unwrap();
        // Laid exactly on the surface: nothing grounded yet.
        assert_eq!(w.strings.len(), 1);
        assert_eq!(w.strings[0].grounded_length_min, 0.0);
        let mut largest = 0.0f64;
        for _ in 0..30 {
            s.step().unwrap();
            w.observe(&s);
            let contacts = s.system().seabed_contacts(&s.state().r);
            largest = contacts.iter().fold(largest, |m, c| m.max(c.force));
        }
        w.finish(&s);
        let r = &s.state().r;
        // One pass over the contacts gives the core's grounded length.
        let (lengths, _) = contact_state(s.system(), &[0], r);
        assert_eq!(lengths, [s.system().grounded_length(0, r)]);
        let g = &w.strings[0];
        assert_eq!(g.grounded_length_final, lengths[0]);
        assert!(g.grounded_length_final >= 25.0, "{g:?}");
        assert_eq!(g.grounded_length_min, 0.0);
        assert_eq!(w.max_contact_force, largest);
        assert!(w.max_contact_force > 0.0 && w.max_contact_force_t > 0.0);
        let ww = s.water_work();
        assert_eq!(w.drag_dissipated, ww.drag_dissipated);
        assert_eq!(w.friction_dissipated, ww.friction_dissipated);
        assert_eq!(w.seabed_final, s.energies().seabed);
        // A resume carries the extremes on.
        let again = WaterSummary::resumed(&s, Some(&w.counters())).unwrap();
        assert_eq!(again, w);
    }
}
