//! The winches in a step (docs/method.md §23): the drum node moves with the payout as a
//! prescribed motion inside the step, its reaction's work the winch's supply; after the
//! step its velocity is held at the payout rate and the string is cut where the drum node
//! has left its band, each change's energy booked as the winch's supply.

use super::{Simulation, StepAt};
use crate::error::StepError;
use crate::material::StoredEnergy;
use crate::system::{Energies, Vector};
use crate::winch::WinchState;
use crate::winch_step::DrumStep;
use std::ops::Range;

/// A drum's state at the end of the current step and its shares of the step.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct DrumNext {
    /// Payout [m].
    pub payout: f64,
    /// Payout speed [m/s].
    pub speed: f64,
    /// Energy its damping and brake dissipated in the step [J].
    pub dissipated: f64,
    /// Energy its motor supplied in the step [J].
    pub motor: f64,
    /// The rope's pull at the drum over the step, `−t̂·R_d` [N], and the step's size [s]:
    /// recorded for a drum with a derivative time (the size 0 otherwise).
    pub pull: (f64, f64),
}

impl StepAt {
    /// The error of winch `name` that cannot take this step, for `problem`.
    fn winch_error(&self, name: &str, problem: String) -> StepError {
        StepError::Winch {
            step: self.step,
            t: self.t,
            at: self.t_next,
            winch: name.to_string(),
            problem,
        }
    }
}

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
    /// Energy the drum's damping and brake have dissipated since `t = 0` [J] (0 without a
    /// drum).
    pub dissipated: f64,
    /// Energy the drum's motor has supplied since `t = 0` [J] (negative: taken; part of
    /// `energy`; 0 without a drum).
    pub motor: f64,
    /// The winch's port in the last step: the drum node then, its mid-step velocity `Δ/h`
    /// [m/s] and the reaction force of the drum on it [N] (`x, y, z`; `z` 0 in 2D). Their
    /// product is the port's work rate; `power` adds the held velocity and the cuts.
    pub port: (usize, [f64; 3], [f64; 3]),
}

/// Refuses a drum with a derivative time under `dg4` (docs/method.md §23.6): its backward
/// sub-step runs the time between mid times negative, so the derivative part's gain
/// `1 + τ/Δt` of the rope's pull in the drum's row passes through 0 for some `τ`.
pub(super) fn check_drum_scheme<const D: usize, M>(
    sys: &crate::system::PhSystem<D, M>,
    scheme: crate::Scheme,
) -> Result<(), crate::error::SetupError> {
    if scheme != crate::Scheme::DiscreteGradient4 {
        return Ok(());
    }
    for (index, m) in sys.winches.iter().enumerate() {
        if let Some((drum, _)) = m.drum.as_ref().filter(|(d, _)| d.derivative_time > 0.0) {
            return Err(crate::error::SetupError::Winch {
                index,
                name: m.name.clone(),
                problem: format!(
                    "its drum's derivative_time {} s is not supported with the scheme dg4 (its backward sub-step makes the derivative of the rope's pull change sign): use dg or mp, or derivative_time = 0",
                    drum.derivative_time
                ),
            });
        }
    }
    Ok(())
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
                && ws.pull.is_finite()
                && ws.pull_step.is_finite()
                && ws.pull_step >= 0.0
                && ws.stretch > 0.0
                && ws.stretch.is_finite()
                && (norm - 1.0).abs() < 1e-9
                && (-m.l..=2.0 * m.l).contains(&behind)
                && ws.origin.iter().all(|x| x.is_finite());
            if !fine {
                return Err(format!(
                    "sim.winches[{k}]: drum element {} of {n_el}, stretch {}, direction of norm {norm}, {behind} m behind the drum point, pull {} N over a step of {} s: not a state of this winch",
                    ws.drum, ws.stretch, ws.pull, ws.pull_step
                ));
            }
        }
        Ok(())
    }

    /// Checks that each winch's drum node in the flat positions `r` (`D` numbers per node,
    /// lengths checked by the caller) sits where its path of `states` puts it at time `t`
    /// [s] with the rigid bodies in `bodies` (eq. (23.1)): a step leaves it there up to
    /// rounding, so a checkpoint whose mesh is not what the winches produced (another
    /// scenario's, or an edited one) is refused with the distance [m] (tolerance
    /// `1e-9 (1 m + |X| + L)`, `X` the path's point).
    pub(crate) fn check_winch_positions(
        &self,
        states: &[WinchState],
        r: &[f64],
        bodies: &[crate::body::BodyState],
        t: f64,
    ) -> Result<(), String> {
        for (k, (m, ws)) in self.sys.winches.iter().zip(states).enumerate() {
            let node = m.drum_node(ws);
            let Some(at) = r.get(D * node..D * (node + 1)) else {
                continue;
            };
            if m.body.is_some_and(|(b, _, _)| b >= bodies.len()) {
                continue;
            }
            let on_path = m.path_at(ws, &m.frame(t, bodies), (ws.payout, 0.0)).0;
            let off = (Vector::<D>::from_column_slice(at) - on_path).norm();
            let tol = 1e-9 * (1.0 + on_path.norm() + m.l);
            // A NaN distance is refused too.
            if off.is_nan() || off > tol {
                return Err(format!(
                    "sim.winches[{k}] (winch \"{}\"): its drum node {node} is {off:e} m from where its path puts it at t = {t} s (payout {} m, drum element {} of {}): the mesh is not what this winch produced",
                    m.name,
                    ws.payout,
                    ws.drum,
                    m.elements.len()
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

    /// Whether winch `winch` (an index checked by the caller) has a drum with dynamics.
    pub(crate) fn winch_has_drum(&self, winch: usize) -> bool {
        self.sys.winches[winch].drum.is_some()
    }

    /// Replaces the motor pull of winch `winch`'s drum (a winch with a drum, checked by the
    /// caller).
    pub(crate) fn set_winch_drum_force(&mut self, winch: usize, force: crate::DrumForceFn) {
        if let Some((drum, _)) = &mut self.sys.winches[winch].drum {
            drum.force = force;
        }
    }

    /// The winches' outputs after the last step.
    pub fn winch_samples(&self) -> Vec<WinchSample> {
        let h = self.winch_h;
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
                    dissipated: ws.dissipated,
                    motor: ws.motor,
                    port,
                }
            })
            .collect()
    }

    /// `e` with the drums' kinetic energy `½ λ² (J/R²) ṗ²` added to its kinetic energy and
    /// magnitude: at the states' speeds, or with `next` at the current step's new ones.
    pub(super) fn with_drums(&self, mut e: Energies, next: bool) -> Energies {
        for (k, (m, ws)) in self.sys.winches.iter().zip(&self.run.winches).enumerate() {
            let Some((drum, _)) = &m.drum else {
                continue;
            };
            let speed = if next {
                self.drum_next[k].speed
            } else {
                ws.speed
            };
            let u = ws.stretch * speed;
            let t = 0.5 * drum.inertia * u * u;
            e.kinetic += t;
            e.magnitude += t;
        }
        e
    }

    /// The part of `Ĥ` [J] a cut of winch `k` can change (docs/method.md §23, "The cost of a
    /// cut"): its string's elements and nodes in `window` (string-local, [`cut_window`]) and
    /// its drum's kinetic energy, as [`Self::with_drums`] and [`PhSystem::energies`]
    /// evaluate them.
    ///
    /// [`cut_window`]: crate::winch_cut::cut_window
    /// [`PhSystem::energies`]: crate::PhSystem::energies
    fn cut_part(&self, k: usize, window: (Range<usize>, Range<usize>)) -> Energies {
        let mut part = self.sys.winch_energies(k, window, &self.run.state);
        if let Some((drum, _)) = &self.sys.winches[k].drum {
            let ws = &self.run.winches[k];
            let u = ws.stretch * ws.speed;
            let t = 0.5 * drum.inertia * u * u;
            part.kinetic += t;
            part.magnitude += t;
        }
        part
    }

    /// The winch drums' data for the step `at` (docs/method.md §23.6) into `drum_steps`, with
    /// their slots and drum nodes predicted at the drums' speeds; fails where a motor force
    /// is not finite or a drum element reaches a node held by a rigid body.
    fn drum_prescribe(&mut self, at: &StepAt) -> Result<(), StepError> {
        let (winches, r) = (&self.run.winches, &self.run.state.r);
        Self::drum_data(
            &self.sys,
            (winches, r),
            at,
            &mut self.drum_steps,
            &mut self.x,
        )
    }

    /// The drums' data for the step `at` from the winch states `winches` and node positions
    /// `r` [m] into `steps`, their slots and drum nodes in `x` predicted at the drums' speeds
    /// (what [`Self::drum_prescribe`] does for the current state; `dg4`'s embedded
    /// second-order step takes it from the state before the step).
    pub(super) fn drum_data(
        sys: &crate::system::PhSystem<D, M>,
        (winches, r): (&[WinchState], &[Vector<D>]),
        at: &StepAt,
        steps: &mut Vec<DrumStep<D>>,
        x: &mut [Vector<D>],
    ) -> Result<(), StepError> {
        steps.clear();
        let n = sys.mesh.n_nodes();
        let first = 2 * sys.bodies.len();
        let t_mid = at.t + 0.5 * at.h;
        for (k, (m, ws)) in sys.winches.iter().zip(winches).enumerate() {
            let Some((drum, j)) = &m.drum else {
                continue;
            };
            let fail = |problem: String| at.winch_error(&m.name, problem);
            let (a, other) = (m.drum_node(ws), m.nodes[ws.drum + 1]);
            if sys.attached.get(other).copied().flatten().is_some() {
                return Err(fail(format!(
                    "its drum element reaches the node held by a rigid body (mesh node {other}): a drum with dynamics needs two elements off the drum"
                )));
            }
            let force = (drum.force)(t_mid);
            if !force.is_finite() {
                return Err(fail(format!(
                    "its motor force at t = {t_mid} s is {force} N (not finite)"
                )));
            }
            // On a body the body's slots move the drum node with the drum point.
            let base = match m.body {
                Some(_) => Vector::<D>::zeros(),
                None => m.path_at(ws, &m.frame(at.t_next, &[]), (ws.payout, 0.0)).0 - r[a],
            };
            let (axis, stretch) = (m.axis(ws), ws.stretch);
            let step = DrumStep {
                winch: k,
                slot: first + j,
                node: a,
                other,
                element: m.drum_element(ws),
                base,
                body: m.body.map(|(b, _, s)| (b, s)),
                axis,
                stretch,
                speed: ws.speed,
                inertia: stretch * stretch * drum.inertia,
                force: stretch * force,
                derivative: 0.0,
                pull_before: 0.0,
            };
            // The derivative part, once a previous pull is known (docs/method.md §23.6).
            let tau = drum.derivative_time;
            let step = if tau > 0.0 && ws.pull_step > 0.0 {
                DrumStep {
                    derivative: tau / (0.5 * (ws.pull_step + at.h)),
                    pull_before: stretch * ws.pull,
                    ..step
                }
            } else {
                step
            };
            let dp = ws.speed * at.h;
            x[n + step.slot] = Vector::<D>::zeros();
            x[n + step.slot][0] = dp;
            x[a] = base + axis * dp;
            steps.push(step);
        }
        Ok(())
    }

    /// The drums' payouts and speeds at the end of the solved step `at` into `drum_next`;
    /// fails where one is not finite or leaves the drum's range.
    pub(super) fn drums_next(&mut self, at: &StepAt) -> Result<(), StepError> {
        let n = self.sys.mesh.n_nodes();
        for d in &self.drum_steps {
            let (m, ws) = (&self.sys.winches[d.winch], &self.run.winches[d.winch]);
            let dp = self.x[n + d.slot][0];
            let next = (ws.payout + dp, d.speed_after(dp, at.h));
            let limit = if next.1.is_finite() {
                m.check(ws, next.0)
            } else {
                Err(crate::winch::WinchLimit::NotFinite(next.1))
            };
            if let Err(limit) = limit {
                return Err(at.winch_error(&m.name, limit.to_string()));
            }
            self.drum_next[d.winch] = DrumNext {
                payout: next.0,
                speed: next.1,
                ..Default::default()
            };
        }
        Ok(())
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
    /// that each winch can follow its payout there; the drums' data for the step.
    pub(super) fn winch_prescribe(&mut self, at: &StepAt) -> Result<(), StepError> {
        for (m, ws) in self.sys.winches.iter().zip(&self.run.winches) {
            if m.drum_motion.is_some() {
                // The nodes parked on a moving drum go with its drum point (they carry no
                // mass, weight or element: held, their reactions and so their work are 0).
                let point = m.drum_at(at.t_next).0;
                for &i in &m.nodes[..ws.drum] {
                    self.x[i] = point - self.run.state.r[i];
                }
            }
            if m.drum.is_some() {
                continue;
            }
            let payout = (m.payout)(at.t_next);
            if let Err(limit) = m.check(ws, payout) {
                return Err(at.winch_error(&m.name, limit.to_string()));
            }
            match m.body {
                // A drum on a body: the body moves its drum node with the drum point, and the
                // payout slides it along its path (docs/method.md §23.7).
                Some((b, k, _)) => {
                    let slide = m.axis(ws) * (payout - ws.payout);
                    self.sys.bodies[b].offset[k] = crate::body::embed(&slide);
                }
                None => {
                    let a = m.drum_node(ws);
                    self.x[a] = m.path(ws, at.t_next, &[]).0 - self.run.state.r[a];
                }
            }
        }
        self.drum_prescribe(at)
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
            let (mut u, mut y) = ([0.0; 3], [0.0; 3]);
            for k in 0..D {
                u[k] = self.x[a][k] * inv_h;
                y[k] = self.reaction[a][k];
            }
            *port = (a, u, y);
            *w = match (&m.drum, m.body) {
                // A drum's supply is its own ([`crate::winch_step::shares`], below).
                (Some(_), _) => continue,
                // On a body the reaction's work over the drum point's motion is the body's;
                // the winch's is its work over the slide (docs/method.md §23.7).
                (None, Some((b, k, _))) => {
                    let slide = &self.sys.bodies[b].offset[k];
                    crate::body::embed(&self.reaction[a]).dot(slide)
                }
                (None, None) => self.reaction[a].dot(&self.x[a]),
            };
            total += *w;
        }
        // A drum's own storage is in `Ĥ`: the winch supplies the reaction's work over the
        // drum's motion and the motor's; the damping and brake dissipate.
        let n = self.sys.mesh.n_nodes();
        for d in &self.drum_steps {
            let dp = self.x[n + d.slot][0];
            let reaction = &self.reaction[d.node];
            let (supply, loss, motor) = crate::winch_step::shares(&self.sys, d, dp, h, reaction);
            total += supply;
            self.winch_work[d.winch] = supply;
            self.drum_next[d.winch].dissipated = loss;
            self.drum_next[d.winch].motor = motor;
            if self.sys.winches[d.winch]
                .drum
                .as_ref()
                .is_some_and(|(drum, _)| drum.derivative_time > 0.0)
            {
                let pull = -d.axis.dot(reaction) / d.stretch;
                self.drum_next[d.winch].pull = (pull, h);
            }
        }
        total
    }

    /// After a committed step (or `dg4` sub-step) to `t` [s]: per winch, its payout and drum
    /// speed brought to the step's end and its drum node's velocity held at the payout rate,
    /// each hold's energy `Ĥ(after) − Ĥ(before)` booked as the winch's supply with the step's
    /// reaction work (into the winch's total and the step record's energy). No cut: the
    /// string is cut only once a whole step is accepted ([`Self::winch_cuts`]). Returns the
    /// energy of the holds [J].
    pub(super) fn winch_hold(&mut self, t: f64) -> f64 {
        let mut total = 0.0;
        // The drums' new speeds first: `Ĥ` after the step has them all.
        for d in &self.drum_steps {
            let ws = &mut self.run.winches[d.winch];
            let next = &self.drum_next[d.winch];
            ws.speed = next.speed;
            ws.dissipated += next.dissipated;
            ws.motor += next.motor;
            if next.pull.1 > 0.0 {
                (ws.pull, ws.pull_step) = next.pull;
            }
        }
        for k in 0..self.sys.winches.len() {
            // Off a body, the hold changes the drum node's velocity alone: the energy of
            // the elements at that node (docs/method.md §23, "The cost of a cut"). On a
            // body it also slides the drum point: `Ĥ` evaluated in full.
            let before = self.sys.winches[k].body.is_none().then(|| {
                let drum = self.run.winches[k].drum;
                let window = crate::winch_cut::cut_window(drum, drum);
                (window.clone(), self.cut_part(k, window))
            });
            let m = &self.sys.winches[k];
            let ws = &mut self.run.winches[k];
            let (payout, rate) = match &m.drum {
                None => m.payout_at(ws, t),
                Some(_) => (self.drum_next[k].payout, ws.speed),
            };
            let a = m.drum_node(ws);
            let frame = m.frame(t, &self.run.state.bodies);
            self.run.state.v[a] = m.path_at(ws, &frame, (payout, rate)).1;
            ws.payout = payout;
            if let Some((b, k, _)) = m.body {
                // The slide is done; the nodes on the drum (no mass, weight or element) go
                // with the drum point.
                self.sys.bodies[b].offset[k] = crate::body::Vec3::zeros();
                for &i in &m.nodes[..ws.drum] {
                    self.run.state.r[i] = frame.point;
                    self.run.state.v[i] = frame.velocity;
                }
            }
            let de = match before {
                Some((window, before)) => {
                    let after = self.cut_part(k, window);
                    self.energies = self.energies.replaced(&before, &after);
                    after.hamiltonian() - before.hamiltonian()
                }
                None => {
                    let after = self.with_drums(self.sys.energies(&self.run.state), false);
                    let de = after.hamiltonian() - self.energies.hamiltonian();
                    self.energies = after;
                    de
                }
            };
            let step = self.winch_work[k] + de;
            self.run.winches[k].energy += step;
            self.winch_step[k].1 += step;
            total += de;
        }
        total
    }

    /// After an accepted step to `t` [s] (never inside a `dg4` composition, never for an
    /// attempt that error control may still reject): per winch, the string cut where the
    /// drum node has left its band at the payout the step reached, each cut's energy
    /// `Ĥ(after) − Ĥ(before)` booked as the winch's supply; then the step record holds the
    /// payout moved and the energy supplied over the step `h` [s]. Returns the energy of the
    /// cuts [J].
    pub(super) fn winch_cuts(&mut self, t: f64, h: f64) -> f64 {
        let mut total = 0.0;
        for k in 0..self.sys.winches.len() {
            let (m, ws) = (&self.sys.winches[k], &self.run.winches[k]);
            // The payout the step reached (the state holds it already): a cut where the
            // drum node has left its band there.
            let (from, payout) = (ws.drum, ws.payout);
            let to = m.drum_after(ws, payout);
            if to != from {
                let window = crate::winch_cut::cut_window(from, to);
                let before = self.cut_part(k, window.clone());
                let (m, ws) = (&self.sys.winches[k], &mut self.run.winches[k]);
                // A new drum node moves at the prescribed rate or the drum's speed.
                let rate = m.payout_at(ws, t).1;
                let state = &mut self.run.state;
                let frame = m.frame(t, &state.bodies);
                let parts = (&mut state.r[..], &mut state.v[..], &mut state.c[..]);
                m.cut(ws, (&frame, payout, rate), parts);
                // The nodes a payout brought off the drum (the new drum node, held, and
                // with more than one element the free nodes between it and the old one):
                // parked through the step, their mid-step velocity is zero, so they predict
                // the next step from the velocity the cut gave them. The old drum node keeps
                // its own; hauling in, the range is empty.
                for &i in &m.nodes[ws.drum..from.max(ws.drum)] {
                    self.run.v_mid[i] = state.v[i];
                }
                let ws = *ws;
                self.sys.place_cut(k, &ws, from);
                self.refresh_contacts();
                let after = self.cut_part(k, window);
                let de = after.hamiltonian() - before.hamiltonian();
                self.energies = self.energies.replaced(&before, &after);
                self.run.winches[k].energy += de;
                self.winch_step[k].1 += de;
                total += de;
            }
            let start = self.winch_step[k].0;
            self.winch_step[k].0 = self.run.winches[k].payout - start;
        }
        self.winch_h = h;
        total
    }

    /// Before an attempt at a step: each winch's step record set to the payout it starts
    /// from and no energy yet, and its port's sums (for `dg4`'s means) cleared.
    pub(super) fn winch_begin(&mut self) {
        for (s, w) in self.winch_step.iter_mut().zip(&self.run.winches) {
            *s = (w.payout, 0.0);
        }
        for s in &mut self.winch_port_sums {
            *s = ([0.0; 3], [0.0; 3]);
        }
    }

    /// `dg4`: adds the sub-step of size `hk` [s] just taken to the winch ports' sums.
    pub(super) fn winch_port_add(&mut self, hk: f64) {
        for (s, (_, u, y)) in self.winch_port_sums.iter_mut().zip(&self.winch_port) {
            for k in 0..3 {
                s.0[k] += u[k] * hk;
                s.1[k] += y[k] * hk;
            }
        }
    }

    /// `dg4`: the winch ports' `h_k`-weighted means over the step of size `h` [s] (the drum
    /// node is the same in every sub-step: no cut inside the composition).
    pub(super) fn winch_port_means(&mut self, h: f64) {
        for (p, s) in self.winch_port.iter_mut().zip(&self.winch_port_sums) {
            for k in 0..3 {
                p.1[k] = s.0[k] / h;
                p.2[k] = s.1[k] / h;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    //! The Newton Jacobian with a winch drum's row and its coupling to the drum element's
    //! other node against central finite differences; a checkpoint's drum node on its path.

    use super::super::Simulation;
    use super::super::test_support::fixed_steps;
    use crate::network::{NetworkBuilder, StringSpec};
    use crate::system::{MassMatrix, PointMass, State, Vector};
    use crate::winch::{Winch, WinchDrum};
    use crate::{Boundary, Material};
    use std::sync::Arc;

    /// A 5 t payload at `hook` [m] on 12 elements of 32 mm wire rope (EA = 4.3e7 N, 4.1 kg/m)
    /// from a drum at the origin with 5 more elements on it, without its winch: the network
    /// and the rope's group.
    fn hoist_on_drum(hook: Vector<2>, mass: MassMatrix) -> (crate::Network<2, Material>, usize) {
        let (g, ea, rho_a, m) = (9.81, 4.3e7, 4.1, 5000.0);
        let mut b = NetworkBuilder::<2, Material>::new();
        let top = b.node(Vector::<2>::zeros());
        let hook = b.node(hook);
        let spec = StringSpec {
            name: "rope".into(),
            material: Material::tension_only_linear(ea),
            rho_a,
            mass,
            body_force: Vector::<2>::new(0.0, -rho_a * g),
            prestretch: 1.0,
        };
        let grp = b.string_on_drum(spec, &[top, hook], 12, 5).unwrap();
        let masses = vec![PointMass {
            node: hook,
            mass: m,
            weight: Vector::<2>::new(0.0, -m * g),
        }];
        (b.build(Boundary::default(), masses).unwrap(), grp)
    }

    /// A 5 t payload on 12 m of 32 mm steel rope below a drum with inertia (2 t at the
    /// rope), a motor pulling 40 kN, damping 2e4 N·s/m, a 30 kN brake and the derivative time
    /// `tau` [s], swinging sideways so that the rope is not along the drum's path: after 30
    /// steps of 10 ms (so that the previous pull is known), the Jacobian of the next step's
    /// residual at a perturbed increment against central differences, in the free rows and
    /// the drum's row. Returns the worst difference over the rows relative to the Jacobian's
    /// scale.
    fn drum_jacobian_error(tau: f64) -> f64 {
        let (mut net, grp) = hoist_on_drum(Vector::<2>::new(3.0, -11.6), MassMatrix::Consistent);
        // Stretched 0.1 % along the chord, at rest.
        let r: Vec<_> = net.initial.r.iter().map(|x| x * 1.001).collect();
        net.initial = State::at_rest(&net.mesh, r);
        net = net.with_winch(Winch {
            name: "drum".into(),
            group: grp,
            reserve: 5,
            payout: Arc::new(|_| 0.0),
            drum_motion: None,
            drum: Some(WinchDrum {
                derivative_time: tau,
                inertia: 2000.0,
                force: Arc::new(|t| 4.0e4 + 1e3 * t),
                damping: 2.0e4,
                brake: Some((3.0e4, 0.05)),
            }),
        });
        let mut sim = Simulation::new(net, fixed_steps(0.01)).unwrap();
        for _ in 0..30 {
            sim.step().unwrap();
        }
        let h = 0.01;
        sim.prepare_step(h);
        let expected = if tau > 0.0 { tau / h } else { 0.0 };
        assert_eq!(
            sim.drum_steps[0].derivative, expected,
            "the derivative gain"
        );
        let n = sim.sys.mesh.n_nodes();
        let slot = n + sim.drum_steps[0].slot;
        let mut x = sim.x.clone();
        // Away from the predictor: a payout increment of 3 mm and nodes moved by up to 1 mm.
        x[slot][0] += 3e-3;
        for (i, xi) in x[..n].iter_mut().enumerate() {
            *xi += Vector::<2>::new(1e-3 * (i as f64).sin(), 7e-4 * (i as f64).cos());
        }
        // A direction in the free components and the drum's payout.
        let mut dir = vec![Vector::<2>::zeros(); x.len()];
        for (i, d) in dir[..n].iter_mut().enumerate() {
            for k in 0..2 {
                if sim.sys.free[i][k] {
                    d[k] = ((3 * i + k) as f64 * 0.7).sin();
                }
            }
        }
        dir[slot][0] = 0.8;
        let (jd, fd) = sim.jacobian_along(h, (&x, &dir), 1e-7);
        let scale = jd.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let mut worst = 0.0_f64;
        for i in 0..x.len() {
            for k in 0..2 {
                let free = if i < n { sim.sys.free[i][k] } else { k == 0 };
                if free {
                    worst = worst.max((jd[i][k] - fd[i][k]).abs() / scale);
                }
            }
        }
        let drum_row = fd[slot][0];
        eprintln!(
            "derivative time {tau} s: drum row: J·d {:.6e}, differences {drum_row:.6e}; worst over the rows {worst:.2e} of {scale:.3e}",
            jd[slot][0]
        );
        assert!(
            jd[slot][0].abs() > 1e-3 * scale,
            "the drum row is exercised"
        );
        worst
    }

    /// The drum's row and its couplings (inertia, motor, damping and brake) against central
    /// differences, without a derivative part and with a derivative time of 0.3 s (the
    /// pull's derivatives times `1 + τ/h` = 31): worst over the rows ≤ 1e-6 of the scale.
    #[test]
    fn the_drum_rows_jacobian_matches_finite_differences() {
        for tau in [0.0, 0.3] {
            let worst = drum_jacobian_error(tau);
            assert!(
                worst < 1e-6,
                "τ = {tau} s: Jacobian off by {worst:e} of its scale"
            );
        }
    }

    /// A 5 t payload on 12 m of 32 mm wire rope (EA = 4.3e7 N, 4.1 kg/m, elements of 1 m, 5
    /// more on the drum), paid out at 0.5 m/s from a drum travelling at 0.2 m/s, `h` =
    /// 0.01 s, fixed steps.
    fn travelling_hoist() -> Simulation<2, Material> {
        let (net, grp) = hoist_on_drum(Vector::<2>::new(0.0, -12.0), MassMatrix::Lumped);
        let net = net.with_winch(Winch {
            name: "hoist".into(),
            group: grp,
            reserve: 5,
            payout: Arc::new(|t| 0.5 * t),
            drum_motion: Some(Arc::new(|t| [0.2 * t, 0.0, 0.0])),
            drum: None,
        });
        Simulation::new(net, fixed_steps(0.01)).unwrap()
    }

    /// A checkpoint's drum node must lie on its winch's path (eq. (23.1)): after 3 s of a
    /// 0.5 m/s payout from a drum travelling 0.2 m/s (elements brought off the drum), the
    /// run's flat checkpoint fits; its drum node moved 1e-12 m (rounding) still fits, moved
    /// 1 µm (a hundred times the tolerance `1e-9 (1 m + |X| + L)`) it is refused, naming the
    /// winch and its drum node.
    #[test]
    fn a_checkpoint_whose_drum_node_is_off_its_path_is_refused() {
        let mut sim = travelling_hoist();
        for _ in 0..300 {
            sim.step().unwrap();
        }
        let ws = sim.run.winches[0];
        assert!(ws.drum < 5, "elements came off the drum");
        let d = sim.sys.winches[0].drum_node(&ws);
        let flat = sim.flat_checkpoint();
        assert!(flat.check_fits(&sim, 10.0).is_ok());
        let mut near = flat.clone();
        near.r[2 * d] += 1e-12;
        assert!(near.check_fits(&sim, 10.0).is_ok());
        let mut off = flat;
        off.r[2 * d] += 1e-6;
        let err = off.check_fits(&sim, 10.0).unwrap_err();
        assert!(
            err.contains(&format!("(winch \"hoist\"): its drum node {d} is "))
                && err.contains("the mesh is not what this winch produced"),
            "{err}"
        );
    }

    /// The nodes parked on a travelling drum go with its drum point: after each of 300 steps
    /// (the drum 0.6 m on, 1.5 m paid out, elements coming off the drum) every parked node
    /// is at the drum point to 1e-12 m, and the step's balance holds to 1e-12 of its energy
    /// scale (the parked nodes carry nothing, so their motion does no work).
    #[test]
    fn parked_nodes_go_with_a_travelling_drum() {
        let mut sim = travelling_hoist();
        let mut cuts = 0;
        for _ in 0..300 {
            let before = sim.run.winches[0].drum;
            let report = sim.step().unwrap();
            assert!(
                report.relative_balance_error() <= 1e-12,
                "balance {:e}",
                report.relative_balance_error()
            );
            let (m, ws) = (&sim.sys.winches[0], sim.run.winches[0]);
            cuts += usize::from(ws.drum != before);
            let point = m.drum_at(sim.time()).0;
            for &i in &m.nodes[..ws.drum] {
                let off = (sim.run.state.r[i] - point).norm();
                assert!(
                    off <= 1e-12,
                    "parked node {i} is {off:e} m off the drum point"
                );
            }
        }
        let ws = sim.run.winches[0];
        assert!(cuts >= 1 && ws.drum >= 3, "{cuts} cuts, {} parked", ws.drum);
    }
}
