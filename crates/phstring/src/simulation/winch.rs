//! The winches in a step (docs/method.md §23): the drum node moves with the payout as a
//! prescribed motion inside the step, its reaction's work the winch's supply; after the
//! step its velocity is held at the payout rate and the string is cut where the drum node
//! has left its band, each change's energy booked as the winch's supply.

use super::{Simulation, StepAt};
use crate::error::StepError;
use crate::material::StoredEnergy;
use crate::winch::{Touched, WinchState};

/// One winch's output after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WinchSample {
    /// Length paid out since `t = 0` [m] (negative: hauled in).
    pub payout: f64,
    /// Reference (unstretched) length of string off the drum, beyond the drum point [m].
    pub length: f64,
    /// Mean payout speed over the last step [m/s].
    pub speed: f64,
    /// Tension [N] of the drum element at the end of the last step.
    pub tension: f64,
    /// Mean power the winch supplied over the last step [W] (negative: taken).
    pub power: f64,
    /// Energy the winch has supplied since `t = 0` [J].
    pub energy: f64,
    /// The string's mass off the drum [kg]: `ρA` times `length`.
    pub mass: f64,
    /// The winch's port in the last step: the drum node then, its mid-step velocity `Δ/h`
    /// [m/s] and the reaction force of the drum on it [N] (`x, y, z`; `z` 0 in 2D). Their
    /// product is the port's work rate; `power` adds the held velocity and the cuts.
    pub port: (usize, [f64; 3], [f64; 3]),
}

impl<const D: usize, M: StoredEnergy> Simulation<D, M> {
    /// Checks winch states from a checkpoint against the system: one per winch, each drum
    /// element inside its string, a positive stretch, a unit direction and the drum node
    /// within an element of the drum point.
    pub(crate) fn check_winch_states(&self, states: &[WinchState]) -> Result<(), String> {
        let models = &self.sys.winches;
        if states.len() != models.len() {
            return Err(format!(
                "sim.winches has {} winch states, the scenario has {} winches",
                states.len(),
                models.len()
            ));
        }
        for (k, (m, ws)) in models.iter().zip(states).enumerate() {
            let n_el = m.elements.len();
            let norm = ws.direction.iter().map(|x| x * x).sum::<f64>().sqrt();
            let behind = ws.behind(ws.payout);
            let fine = ws.drum < n_el
                && ws.stretch > 0.0
                && ws.stretch.is_finite()
                && (norm - 1.0).abs() < 1e-9
                && (-m.l..=2.0 * m.l).contains(&behind)
                && ws.origin.iter().all(|x| x.is_finite());
            if !fine {
                return Err(format!(
                    "sim.winches[{k}]: drum element {} of {n_el}, stretch {}, direction of norm {norm}, {behind} m behind the drum point: not a state of this winch",
                    ws.drum, ws.stretch
                ));
            }
        }
        Ok(())
    }

    /// The payout [m] winch `winch` has reached (`None`: no such winch).
    pub(crate) fn winch_payout(&self, winch: usize) -> Option<f64> {
        self.run.winches.get(winch).map(|w| w.payout)
    }

    /// The number of winches.
    pub(crate) fn winch_count(&self) -> usize {
        self.run.winches.len()
    }

    /// Replaces winch `winch`'s payout function (an index checked by the caller).
    pub(crate) fn set_winch_payout(&mut self, winch: usize, payout: crate::winch::PayoutFn) {
        self.sys.winches[winch].payout = payout;
    }

    /// The winches' outputs after the last step.
    pub fn winch_samples(&self) -> Vec<WinchSample> {
        let h = self.run.h_cur;
        self.sys
            .winches
            .iter()
            .zip(&self.run.winches)
            .zip(&self.winch_step)
            .zip(&self.winch_port)
            .map(|(((m, ws), &(moved, supplied)), &port)| {
                let e = m.drum_element(ws);
                let grp = &self.sys.groups[m.group];
                let c = self.run.state.c[e];
                let length = m.length_off(ws, ws.payout);
                WinchSample {
                    payout: ws.payout,
                    length,
                    speed: moved / h,
                    tension: 2.0 * grp.law.dw(c) * c.max(0.0).sqrt(),
                    power: supplied / h,
                    energy: ws.energy,
                    mass: grp.rho_a * length,
                    port,
                }
            })
            .collect()
    }

    /// The unstretched arc length `s` [m] of every node of winch `winch`'s string, measured
    /// from the drum point along the string (docs/method.md §23), as `(mesh node, s)` in path
    /// order, into `out` (cleared first). The nodes off the drum have `s > 0`, the last
    /// node's `s` is the length off the drum ([`WinchSample::length`]); the drum node,
    /// behind the drum point by the model's cable still on the drum, and the nodes parked
    /// on the drum have `s ≤ 0`. Consecutive nodes differ by the string's element length.
    /// Returns `false` (and leaves `out` empty) if there is no such winch.
    pub fn winch_arc_lengths(&self, winch: usize, out: &mut Vec<(usize, f64)>) -> bool {
        out.clear();
        let (Some(m), Some(ws)) = (self.sys.winches.get(winch), self.run.winches.get(winch)) else {
            return false;
        };
        out.extend(
            m.nodes
                .iter()
                .enumerate()
                .map(|(j, &i)| (i, m.arc_length(ws, j))),
        );
        true
    }

    /// The drum nodes' increments of the step to `at.t_next` (their paths), after checking
    /// that each winch can follow its payout there.
    pub(super) fn winch_prescribe(&mut self, at: &StepAt) -> Result<(), StepError> {
        for (m, ws) in self.sys.winches.iter().zip(&self.run.winches) {
            let payout = (m.payout)(at.t_next);
            if let Err(limit) = m.check(ws, payout) {
                return Err(StepError::Winch {
                    step: at.step,
                    t: at.t,
                    at: at.t_next,
                    winch: m.name.clone(),
                    problem: limit.to_string(),
                });
            }
            let a = m.drum_node(ws);
            self.x[a] = m.path(ws, at.t_next).0 - self.run.state.r[a];
        }
        Ok(())
    }

    /// The work [J] of each drum node's reaction over the step of size `h` [s] just solved,
    /// into `winch_work` (and the port's values into `winch_port`); returns their sum.
    pub(super) fn winch_reaction_work(&mut self, h: f64) -> f64 {
        let mut total = 0.0;
        let inv_h = 1.0 / h;
        for (((m, ws), w), port) in self
            .sys
            .winches
            .iter()
            .zip(&self.run.winches)
            .zip(&mut self.winch_work)
            .zip(&mut self.winch_port)
        {
            let a = m.drum_node(ws);
            *w = self.reaction[a].dot(&self.x[a]);
            total += *w;
            let (mut u, mut y) = ([0.0; 3], [0.0; 3]);
            for k in 0..D {
                u[k] = self.x[a][k] * inv_h;
                y[k] = self.reaction[a][k];
            }
            *port = (a, u, y);
        }
        total
    }

    /// After a committed step to `t` [s]: per winch, its drum node's velocity held at the
    /// payout rate and the string cut where the drum node has left its band, each change's
    /// energy `Ĥ(after) − Ĥ(before)` booked as the winch's supply with the step's reaction
    /// work. Returns the energy of the changes [J].
    pub(super) fn winch_after(&mut self, t: f64) -> f64 {
        let mut total = 0.0;
        for k in 0..self.sys.winches.len() {
            let m = &self.sys.winches[k];
            let ws = &mut self.run.winches[k];
            let (payout, dt) = ((m.payout)(t), 1e-6 * t.abs().max(1.0));
            let rate = ((m.payout)(t + dt) - (m.payout)(t - dt)) / (2.0 * dt);
            let a = m.drum_node(ws);
            let state = &mut self.run.state;
            state.v[a] = m.path(ws, t).1;
            let mut touched = Touched::default();
            let parts = (&mut state.r[..], &mut state.v[..], &mut state.c[..]);
            m.cut(ws, (t, payout, rate), parts, &mut touched);
            self.sys.place_winches(&self.run.winches);
            let after = self.sys.energies(&self.run.state);
            let de = after.hamiltonian() - self.energies.hamiltonian();
            self.energies = after;
            let step = self.winch_work[k] + de;
            self.run.winches[k].energy += step;
            let before = self.winch_step[k].0;
            self.winch_step[k] = (payout - before, step);
            total += de;
        }
        total
    }
}
