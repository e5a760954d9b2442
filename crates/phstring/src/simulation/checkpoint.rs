//! The one record of a running simulation's state and progress, [`Checkpoint`], and its
//! flat form [`FlatCheckpoint`], the one a checkpoint file stores, with the checks of a
//! flat record against a simulation.
//!
//! # One place for a new field
//! Everything a field of the record needs besides the physics that updates it is in this
//! file, and every function here that must handle a field names all of them (a destructuring
//! `let Checkpoint { .. } = ..` without `..`), so that a new field does not compile until
//! each has been given its line:
//! [`Checkpoint::start`] (its value at `t = 0`), `Clone` (`clone` and `clone_from`),
//! [`Checkpoint::check_sizes`] (what [`Simulation::restore`] refuses),
//! `From<&Checkpoint<D>> for FlatCheckpoint` and [`FlatCheckpoint::into_checkpoint`] (the
//! flat form), [`FlatCheckpoint::non_finite`] (what is never written) and
//! [`FlatCheckpoint::check_fits`] (what a file must satisfy to be restored). Its
//! serialization is [`FlatCheckpoint`]'s field list itself (derived, with the optional
//! `serde` feature). A new field changes the files' JSON: files written before it parse
//! only if it has a `#[serde(default)]`, and even then their checksum (over the JSON as this
//! build writes it) no longer verifies, as their version does not either; phstring-io's
//! checkpoint fixture, written by an older build, then fails its byte-for-byte test and is
//! replaced by one the new build writes.
//!
//! # Why a flat form, serialized by derive
//! A checkpoint file is read before its dimension `D` is known (it is the dimension of the
//! scenario the file carries as text), and what edits and checks a file works on are its
//! numbers as stored: positions as `D` numbers per node, node by node. So the file holds
//! [`FlatCheckpoint`], the record with its nodal vectors flattened, whose fields are the
//! file's keys in the file's order; `serde`'s derive streams each array straight into its
//! `Vec<f64>` (no intermediate buffering of the document, unlike `#[serde(flatten)]`, which
//! collects every field into serde's generic `Content` first and so holds the whole state
//! three to four times while reading a large file). [`FlatCheckpoint::into_checkpoint`] then
//! turns the flat arrays into nodal vectors one array at a time, freeing each as it goes.
//! Hand-written (de)serialization of `Checkpoint<D>` itself was not taken: it would need
//! `D` while parsing and would list the keys a second time beside the fields.

use crate::accuracy::AccelerationHistory;
use crate::body::BodyState;
use crate::error::SetupError;
use crate::material::StoredEnergy;
use crate::system::{Energies, State, Vector};
use crate::water::WaterWork;
use crate::winch::WinchState;

use super::{Simulation, StepParams};

/// The complete dynamic state of a [`Simulation`]: its state and the progress of its run.
/// The simulation keeps it as one record, which a checkpoint copies, a restore puts back and
/// a failed or rejected step is undone to; restoring it into a simulation of the same problem
/// and parameters continues the run bit for bit as if it had not stopped.
#[derive(Debug, PartialEq)]
pub struct Checkpoint<const D: usize> {
    /// State `(r, v, C)`.
    pub state: State<D>,
    /// Time bookkeeping: `t = t_base + k h_cur` [s].
    pub t_base: f64,
    /// Steps since `t_base`.
    pub k: usize,
    /// Current step size [s].
    pub h_cur: f64,
    /// Steps taken.
    pub steps: usize,
    /// Rejected step attempts so far.
    pub rejected: usize,
    /// Successive easy steps (step-size growth).
    pub easy_streak: usize,
    /// Smallest accepted step size [s].
    pub h_min_used: f64,
    /// Acceleration estimate of the predictor [m/s²], per node.
    pub acc: Vec<Vector<D>>,
    /// Mid-step velocity of the last step (predictor) [m/s], per node, then two per rigid
    /// body: `Δx/h` and the angular velocity `R_n w/h` [rad/s] in space axes (its slot form).
    pub v_mid: Vec<Vector<D>>,
    /// Cumulative supplied energy [J].
    pub supplied_total: f64,
    /// Cumulative dissipated energy [J].
    pub dissipated_total: f64,
    /// Newton iterations so far.
    pub total_newton: usize,
    /// Error control: mean accelerations of the last steps (docs/method.md §19).
    pub acc_history: AccelerationHistory<D>,
    /// Error control: the last accepted step's error (dimensionless, 1 before the first
    /// step).
    pub err_prev: f64,
    /// The water's shares of `supplied_total` and `dissipated_total` [J] (docs/method.md
    /// §21): drag, the current's work, seabed damping, friction; all zero without water.
    pub water: WaterWork,
    /// The winches' states (docs/method.md §23), one per winch; empty without winches.
    pub winches: Vec<WinchState>,
    /// The energies of `state` [J] as the run held them when [`Simulation::checkpoint`] took
    /// the record (`None` in the running record). A winch's cut updates them in place
    /// (docs/method.md §23, "The cost of a cut"), so they can differ from an evaluation of
    /// `state` in the last bits; [`Simulation::restore`] takes them where they agree with
    /// that evaluation to 1e-12 of their magnitude, so that a run continues bit for bit.
    pub energies: Option<Energies>,
}

impl<const D: usize> Checkpoint<D> {
    /// The record at `t = 0` of a run from `state` with time step `h` [s]: no step taken,
    /// the predictor's history zero.
    pub(super) fn start(state: State<D>, h: f64) -> Self {
        let n = state.r.len();
        let slots = 2 * state.bodies.len();
        Self {
            state,
            t_base: 0.0,
            k: 0,
            h_cur: h,
            steps: 0,
            rejected: 0,
            easy_streak: 0,
            h_min_used: h,
            acc: vec![Vector::zeros(); n],
            v_mid: vec![Vector::zeros(); n + slots],
            supplied_total: 0.0,
            dissipated_total: 0.0,
            total_newton: 0,
            acc_history: Default::default(),
            err_prev: 1.0,
            water: WaterWork::default(),
            winches: Vec::new(),
            energies: None,
        }
    }

    /// Checks that this record fits a simulation of `n` nodes and `n_el` elements and can
    /// be stepped from: array lengths, a positive finite step size, at most two finite points
    /// of error-control history of `n` accelerations each, a positive finite last error.
    /// What [`Simulation::restore`] refuses; a checkpoint file's values are checked further
    /// (ranges against the run's settings) by [`FlatCheckpoint::check_fits`].
    pub fn check_sizes(&self, n: usize, n_el: usize, n_bodies: usize) -> Result<(), SetupError> {
        // Counts and totals of any value restore; they are checked against the run by
        // `FlatCheckpoint::check_fits`.
        let Self {
            state,
            t_base: _,
            k: _,
            h_cur,
            steps: _,
            rejected: _,
            easy_streak: _,
            h_min_used: _,
            acc,
            v_mid,
            supplied_total: _,
            dissipated_total: _,
            total_newton: _,
            acc_history,
            err_prev,
            water: _,
            winches: _,
            energies: _,
        } = self;
        for (what, got, expected) in [
            ("positions", state.r.len(), n),
            ("velocities", state.v.len(), n),
            ("strains", state.c.len(), n_el),
            ("rigid bodies", state.bodies.len(), n_bodies),
            ("predictor accelerations", acc.len(), n),
            ("predictor velocities", v_mid.len(), n + 2 * n_bodies),
        ] {
            if got != expected {
                return Err(SetupError::StateSize {
                    what,
                    got,
                    expected,
                });
            }
        }
        if !(*h_cur > 0.0 && h_cur.is_finite()) {
            return Err(SetupError::NonPositive {
                what: "checkpoint step size",
                index: None,
                value: *h_cur,
            });
        }
        // Error-control history: at most two points of n finite accelerations, a finite
        // positive last error.
        let points = &acc_history.points;
        if let Some(bad) = points.iter().find(|(_, a)| a.len() != n) {
            return Err(SetupError::StateSize {
                what: "error-control accelerations",
                got: bad.1.len(),
                expected: n,
            });
        }
        let finite = points
            .iter()
            .all(|(t, a)| t.is_finite() && a.iter().all(|x| x.iter().all(|y| y.is_finite())));
        if points.len() > 2 || !finite {
            return Err(SetupError::OutOfRange {
                what: "error-control history (points)",
                value: points.len() as f64,
                range: "at most 2 points, all finite",
            });
        }
        if !(*err_prev > 0.0 && err_prev.is_finite()) {
            return Err(SetupError::NonPositive {
                what: "checkpoint error-control error",
                index: None,
                value: *err_prev,
            });
        }
        Ok(())
    }
}

impl<const D: usize> Clone for Checkpoint<D> {
    fn clone(&self) -> Self {
        let mut c = Self {
            state: self.state.clone(),
            t_base: 0.0,
            k: 0,
            h_cur: 0.0,
            steps: 0,
            rejected: 0,
            easy_streak: 0,
            h_min_used: 0.0,
            acc: Vec::new(),
            v_mid: Vec::new(),
            supplied_total: 0.0,
            dissipated_total: 0.0,
            total_newton: 0,
            acc_history: Default::default(),
            err_prev: 0.0,
            water: WaterWork::default(),
            winches: Vec::new(),
            energies: None,
        };
        c.clone_from(self);
        c
    }

    /// Field by field, reusing the buffers (a step saves the record this way).
    fn clone_from(&mut self, source: &Self) {
        let Self {
            state,
            t_base,
            k,
            h_cur,
            steps,
            rejected,
            easy_streak,
            h_min_used,
            acc,
            v_mid,
            supplied_total,
            dissipated_total,
            total_newton,
            acc_history,
            err_prev,
            water,
            winches,
            energies,
        } = self;
        state.clone_from(&source.state);
        *t_base = source.t_base;
        *k = source.k;
        *h_cur = source.h_cur;
        *steps = source.steps;
        *rejected = source.rejected;
        *easy_streak = source.easy_streak;
        *h_min_used = source.h_min_used;
        acc.clone_from(&source.acc);
        v_mid.clone_from(&source.v_mid);
        *supplied_total = source.supplied_total;
        *dissipated_total = source.dissipated_total;
        *total_newton = source.total_newton;
        acc_history.clone_from(&source.acc_history);
        *err_prev = source.err_prev;
        *water = source.water;
        winches.clone_from(&source.winches);
        *energies = source.energies;
    }
}

/// A [`Checkpoint`] of any dimension, its nodal vectors flattened (`D` numbers per node,
/// node by node, components `x, y, z`): the form a checkpoint file stores, under its key
/// `sim`. With the `serde` feature it serializes as a JSON object whose keys are the fields
/// below, in this order; `acc_history` and `err_prev` may be missing (files written before
/// error control), and then are empty and 1. The check messages of
/// [`Self::check_fits`] and [`Self::non_finite`] name the fields as `sim.<field>`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FlatCheckpoint {
    /// Positions [m], `D` per node.
    pub r: Vec<f64>,
    /// Velocities [m/s], `D` per node.
    pub v: Vec<f64>,
    /// Strains (dimensionless), one per element.
    pub c: Vec<f64>,
    /// Rigid bodies' states, [`BODY_NUMBERS`] per body: position [m], velocity [m/s],
    /// orientation quaternion `(w, x, y, z)`, angular velocity in body axes [rad/s];
    /// written only when there are bodies, empty when missing.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Vec::is_empty")
    )]
    pub bodies: Vec<f64>,
    /// Time bookkeeping `t = t_base + k h_cur` [s].
    pub t_base: f64,
    /// Steps since `t_base`.
    pub k: usize,
    /// Current step size [s].
    pub h_cur: f64,
    /// Steps taken.
    pub steps: usize,
    /// Rejected attempts.
    pub rejected: usize,
    /// Easy-step streak.
    pub easy_streak: usize,
    /// Smallest accepted step [s].
    pub h_min_used: f64,
    /// Predictor acceleration [m/s²], `D` per node.
    pub acc: Vec<f64>,
    /// Predictor mid-step velocity [m/s], `D` per node.
    pub v_mid: Vec<f64>,
    /// Cumulative supplied energy [J].
    pub supplied_total: f64,
    /// Cumulative dissipated energy [J].
    pub dissipated_total: f64,
    /// Error control: `(mid time [s], mean accelerations [m/s²], D per node)` of the last
    /// steps, newest first.
    #[cfg_attr(feature = "serde", serde(default))]
    pub acc_history: Vec<(f64, Vec<f64>)>,
    /// Error control: the last accepted step's error (dimensionless).
    #[cfg_attr(feature = "serde", serde(default = "one"))]
    pub err_prev: f64,
    /// Newton iterations so far.
    pub total_newton: usize,
    /// The water's shares of the totals [J]: written only when one is not zero, so that a
    /// run without water writes the file it always wrote; zero when missing.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "WaterWork::is_zero")
    )]
    pub water: WaterWork,
    /// The winches' states, one per winch: written only when there are winches, empty when
    /// missing.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Vec::is_empty")
    )]
    pub winches: Vec<WinchState>,
    /// [`Checkpoint::energies`] [J]: kinetic, internal, external, buoyancy, seabed and
    /// magnitude; empty when missing (a file written before it, or a record without them;
    /// a restore then evaluates the state).
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Vec::is_empty")
    )]
    pub energies: Vec<f64>,
}

/// Numbers per rigid body in [`FlatCheckpoint::bodies`].
pub const BODY_NUMBERS: usize = 13;

/// The bodies' states as one flat array, [`BODY_NUMBERS`] per body.
fn flat_bodies(bodies: &[BodyState]) -> Vec<f64> {
    let mut out = Vec::with_capacity(BODY_NUMBERS * bodies.len());
    for b in bodies {
        out.extend(b.position.iter().chain(&b.velocity));
        let q = b.orientation.quaternion();
        out.extend([q.w, q.i, q.j, q.k]);
        out.extend(b.omega.iter());
    }
    out
}

/// Bodies' states from a flat array (an incomplete last body is dropped; the lengths are
/// checked by [`FlatCheckpoint::check_fits`] and [`Checkpoint::check_sizes`]).
fn unflat_bodies(v: &[f64]) -> Vec<BodyState> {
    v.chunks_exact(BODY_NUMBERS)
        .map(|b| {
            let v3 = |i: usize| crate::body::Vec3::new(b[i], b[i + 1], b[i + 2]);
            BodyState {
                position: v3(0),
                velocity: v3(3),
                // Unchecked, so that a record restores bit for bit; `check_fits` has checked
                // that it is a unit quaternion.
                orientation: nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
                    b[6], b[7], b[8], b[9],
                )),
                omega: v3(10),
            }
        })
        .collect()
}

/// `err_prev` of a file written before error control.
#[cfg(feature = "serde")]
fn one() -> f64 {
    1.0
}

/// The nodal vectors `v` as one flat array, `D` numbers per node.
fn flat<const D: usize>(v: &[Vector<D>]) -> Vec<f64> {
    v.iter().flat_map(|x| x.iter().copied()).collect()
}

/// Nodal vectors from a flat array, which is freed; an incomplete last vector is dropped
/// (lengths are checked by [`FlatCheckpoint::check_fits`] and again by
/// [`Checkpoint::check_sizes`]).
fn unflat<const D: usize>(v: Vec<f64>) -> Vec<Vector<D>> {
    v.chunks_exact(D)
        .map(Vector::<D>::from_column_slice)
        .collect()
}

impl<const D: usize> From<&Checkpoint<D>> for FlatCheckpoint {
    fn from(cp: &Checkpoint<D>) -> Self {
        let Checkpoint {
            state: State { r, v, c, bodies },
            t_base,
            k,
            h_cur,
            steps,
            rejected,
            easy_streak,
            h_min_used,
            acc,
            v_mid,
            supplied_total,
            dissipated_total,
            total_newton,
            acc_history,
            err_prev,
            water,
            winches,
            energies,
        } = cp;
        Self {
            r: flat(r),
            v: flat(v),
            c: c.clone(),
            bodies: flat_bodies(bodies),
            t_base: *t_base,
            k: *k,
            h_cur: *h_cur,
            steps: *steps,
            rejected: *rejected,
            easy_streak: *easy_streak,
            h_min_used: *h_min_used,
            acc: flat(acc),
            v_mid: flat(v_mid),
            supplied_total: *supplied_total,
            dissipated_total: *dissipated_total,
            acc_history: acc_history
                .points
                .iter()
                .map(|(t, a)| (*t, flat(a)))
                .collect(),
            err_prev: *err_prev,
            total_newton: *total_newton,
            water: *water,
            winches: winches.clone(),
            energies: energies.map_or_else(Vec::new, |e| e.to_array().to_vec()),
        }
    }
}

/// What [`FlatCheckpoint::check_fits`] found: the time reached and the most that the run's
/// counts can be, for the checks of the counts a checkpoint file keeps beside the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckpointFit {
    /// Time reached, `t_base + k h_cur` [s].
    pub t: f64,
    /// Steps taken (`sim.steps`).
    pub steps: usize,
    /// Most rejected attempts `steps` steps can have: one more than `max_halvings` per step
    /// and one more step.
    pub max_rejected: usize,
    /// Most Newton iterations `steps` steps and `max_rejected` attempts can take.
    pub max_iterations: usize,
}

impl CheckpointFit {
    /// Refuses a count `value` of field `name` above `limit`, with a message that names both.
    pub fn check_count(&self, name: &str, value: usize, limit: usize) -> Result<(), String> {
        if value > limit {
            return Err(format!(
                "{name} = {value} is more than {} steps can have (at most {limit})",
                self.steps
            ));
        }
        Ok(())
    }
}

impl FlatCheckpoint {
    /// The record in dimension `D`, consuming this one: each flat array is freed as soon as
    /// its nodal vectors are made, so that the two forms are never both held in full. Sizes
    /// are checked by [`Simulation::restore`] (and the values before by [`Self::check_fits`]).
    pub fn into_checkpoint<const D: usize>(self) -> Checkpoint<D> {
        let Self {
            r,
            v,
            c,
            bodies,
            t_base,
            k,
            h_cur,
            steps,
            rejected,
            easy_streak,
            h_min_used,
            acc,
            v_mid,
            supplied_total,
            dissipated_total,
            acc_history,
            err_prev,
            total_newton,
            water,
            winches,
            energies,
        } = self;
        Checkpoint {
            state: State {
                r: unflat(r),
                v: unflat(v),
                c,
                bodies: unflat_bodies(&bodies),
            },
            t_base,
            k,
            h_cur,
            steps,
            rejected,
            easy_streak,
            h_min_used,
            acc: unflat(acc),
            v_mid: unflat(v_mid),
            supplied_total,
            dissipated_total,
            total_newton,
            acc_history: AccelerationHistory {
                points: acc_history
                    .into_iter()
                    .map(|(t, a)| (t, unflat(a)))
                    .collect(),
            },
            err_prev,
            water,
            winches,
            energies: <[f64; 6]>::try_from(&energies[..])
                .ok()
                .map(Energies::from_array),
        }
    }

    /// The record in dimension `D`, as [`Self::into_checkpoint`] of a copy.
    pub fn to_checkpoint<const D: usize>(&self) -> Checkpoint<D> {
        self.clone().into_checkpoint()
    }

    /// The first field holding NaN or infinity (as `sim.<field>`), if any: such a record is
    /// not written (JSON has no NaN or infinity).
    pub fn non_finite(&self) -> Option<&'static str> {
        let Self {
            r,
            v,
            c,
            bodies,
            t_base,
            k: _,
            h_cur,
            steps: _,
            rejected: _,
            easy_streak: _,
            h_min_used,
            acc,
            v_mid,
            supplied_total,
            dissipated_total,
            acc_history,
            err_prev,
            total_newton: _,
            water,
            winches,
            energies,
        } = self;
        if winches.iter().any(|w| {
            let numbers = [
                w.stretch,
                w.payout_cut,
                w.behind_cut,
                w.payout,
                w.energy,
                w.speed,
                w.dissipated,
                w.motor,
                w.pull,
                w.pull_step,
            ];
            !(numbers.iter().chain(&w.origin).chain(&w.direction)).all(|x| x.is_finite())
        }) {
            return Some("sim.winches");
        }
        let arrays: [(&'static str, &[f64]); 7] = [
            ("sim.r", r),
            ("sim.v", v),
            ("sim.c", c),
            ("sim.bodies", bodies),
            ("sim.acc", acc),
            ("sim.v_mid", v_mid),
            ("sim.energies", energies),
        ];
        let scalars = [
            ("sim.t_base", t_base),
            ("sim.h_cur", h_cur),
            ("sim.h_min_used", h_min_used),
            ("sim.supplied_total", supplied_total),
            ("sim.dissipated_total", dissipated_total),
            ("sim.err_prev", err_prev),
            ("sim.water.drag_dissipated", &water.drag_dissipated),
            ("sim.water.current_supplied", &water.current_supplied),
            ("sim.water.seabed_dissipated", &water.seabed_dissipated),
            ("sim.water.friction_dissipated", &water.friction_dissipated),
        ];
        arrays
            .into_iter()
            .find(|(_, a)| a.iter().any(|x| !x.is_finite()))
            .map(|(n, _)| n)
            .or_else(|| {
                acc_history
                    .iter()
                    .any(|(t, a)| !t.is_finite() || a.iter().any(|x| !x.is_finite()))
                    .then_some("sim.acc_history")
            })
            .or_else(|| {
                scalars
                    .into_iter()
                    .find(|(_, x)| !x.is_finite())
                    .map(|(n, _)| n)
            })
    }

    /// Checks every length and value range of this record against `sim` (set up from the
    /// same scenario, before [`Simulation::restore`]) and the run's end time `t_end` [s]:
    /// node and element counts of the arrays in dimension `D`, finite values, at most two
    /// points of acceleration history, a positive last error, strains in the material's
    /// domain, the step size between the floor `h / 2^max_halvings` and `h`, the time within
    /// `[0, t_end]`, step, rejection and iteration counts a run to that time can reach, and
    /// each winch's drum node where its path puts it at that time (docs/method.md eq.
    /// (23.1)). `Err` names the field (`sim.<field>`) and its bad value or length.
    pub fn check_fits<const D: usize, M: StoredEnergy>(
        &self,
        sim: &Simulation<D, M>,
        t_end: f64,
    ) -> Result<CheckpointFit, String> {
        // Every field is named, so that a new one is not forgotten here; those bound to `_`
        // are the time bookkeeping, checked by `check_time`.
        let Self {
            r,
            v,
            c,
            bodies,
            t_base: _,
            k: _,
            h_cur: _,
            steps,
            rejected,
            easy_streak,
            h_min_used: _,
            acc,
            v_mid,
            supplied_total,
            dissipated_total,
            acc_history,
            err_prev,
            total_newton,
            water,
            winches,
            energies,
        } = self;
        sim.check_winch_states(winches)?;
        if !(energies.is_empty() || energies.len() == 6) {
            return Err(format!(
                "sim.energies has {} numbers, not 6 (kinetic, internal, external, buoyancy, \
                 seabed, magnitude) or none",
                energies.len()
            ));
        }
        if let Some(i) = energies.iter().position(|x| !x.is_finite()) {
            return Err(format!("sim.energies[{i}] is not finite"));
        }
        let (n, n_el) = (
            sim.system().mesh().n_nodes(),
            sim.system().mesh().n_elements(),
        );
        let n_bodies = sim.system().bodies().len();
        for (name, values, expected, count) in [
            ("sim.r", r, D * n, None),
            ("sim.v", v, D * n, None),
            ("sim.acc", acc, D * n, None),
            (
                "sim.v_mid",
                v_mid,
                D * (n + 2 * n_bodies),
                (n_bodies > 0).then_some("slots"),
            ),
            ("sim.c", c, n_el, Some("elements")),
            (
                "sim.bodies",
                bodies,
                BODY_NUMBERS * n_bodies,
                Some("bodies"),
            ),
        ] {
            if values.len() != expected {
                let count = match count {
                    None => format!("{n} nodes × {D} components"),
                    Some("bodies") => format!("{n_bodies} bodies × {BODY_NUMBERS} numbers"),
                    Some("slots") => {
                        format!("{n} nodes and 2 × {n_bodies} body slots, × {D} components")
                    }
                    Some(what) => format!("{n_el} {what}"),
                };
                return Err(format!(
                    "{name} has {} numbers, the scenario needs {expected} ({count})",
                    values.len()
                ));
            }
            if let Some(i) = values.iter().position(|x| !x.is_finite()) {
                return Err(format!("{name}[{i}] is not finite"));
            }
        }
        for (b, body) in bodies.chunks_exact(BODY_NUMBERS).enumerate() {
            let norm = body[6..10].iter().map(|x| x * x).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > 1e-12 {
                return Err(format!(
                    "sim.bodies: body {b}'s orientation quaternion has norm {norm:e}, not 1"
                ));
            }
        }
        check_history::<D>(acc_history, n)?;
        if !(*err_prev > 0.0 && err_prev.is_finite()) {
            return Err(format!(
                "sim.err_prev = {err_prev:e} must be positive and finite"
            ));
        }
        if let Some(i) = sim.system().first_inadmissible(c) {
            return Err(format!(
                "sim.c[{i}] = {:e} is outside the material's domain",
                c[i]
            ));
        }
        let fit = self.check_time(sim.params(), t_end)?;
        sim.check_winch_positions(winches, r, &unflat_bodies(bodies), fit.t)?;
        fit.check_count("sim.rejected", *rejected, fit.max_rejected)?;
        fit.check_count("sim.easy_streak", *easy_streak, *steps)?;
        fit.check_count("sim.total_newton", *total_newton, fit.max_iterations)?;
        // dg4's backward sub-step can give back dissipated energy: finite only.
        for (name, value) in [
            ("sim.supplied_total", supplied_total),
            ("sim.dissipated_total", dissipated_total),
            ("sim.water.drag_dissipated", &water.drag_dissipated),
            ("sim.water.current_supplied", &water.current_supplied),
            ("sim.water.seabed_dissipated", &water.seabed_dissipated),
            ("sim.water.friction_dissipated", &water.friction_dissipated),
        ] {
            if !value.is_finite() {
                return Err(format!("{name} = {value:e} must be finite"));
            }
        }
        if sim.system().water.is_none() && !water.is_zero() {
            return Err(format!(
                "sim.water has shares (drag {:e} J, current {:e} J, seabed {:e} J, friction {:e} J) but the scenario has no water",
                water.drag_dissipated,
                water.current_supplied,
                water.seabed_dissipated,
                water.friction_dissipated
            ));
        }
        Ok(fit)
    }

    /// The step size (between the floor `h / 2^max_halvings` and `h` of `params`), the time
    /// (within `[0, t_end]`) and the step count a run to that time can reach; returns the
    /// time reached and the limits of the counts.
    fn check_time(&self, params: &StepParams, t_end: f64) -> Result<CheckpointFit, String> {
        let h = params.h;
        let halvings = params.control.max_halvings.min(1074);
        let floor = h * 0.5f64.powi(halvings as i32);
        let h_cur = self.h_cur;
        if !(h_cur.is_finite()
            && h_cur > 0.0
            && h_cur >= floor * (1.0 - 1e-9)
            && h_cur <= h * (1.0 + 1e-12))
        {
            return Err(format!(
                "sim.h_cur = {h_cur:e} s is not between the step-size floor {floor:e} s and time.h = {h:e} s"
            ));
        }
        let h_min = self.h_min_used;
        if !(h_min.is_finite() && h_min > 0.0 && h_min <= h * (1.0 + 1e-12)) {
            return Err(format!(
                "sim.h_min_used = {h_min:e} s is not in (0, time.h = {h:e} s]"
            ));
        }
        let t_base = self.t_base;
        if !(t_base.is_finite() && t_base >= 0.0 && t_base <= t_end * (1.0 + 1e-9)) {
            return Err(format!(
                "sim.t_base = {t_base:e} s is not in [0, time.end = {t_end:e} s]"
            ));
        }
        let (k, steps) = (self.k, self.steps);
        let t = t_base + k as f64 * h_cur;
        if !(t.is_finite() && t <= t_end * (1.0 + 1e-9) + h_cur) || k > steps {
            return Err(format!(
                "sim.t_base + sim.k × sim.h_cur = {t:e} s (k = {k}, {steps} steps) is beyond time.end = {t_end:e} s"
            ));
        }
        // Every accepted step but a last, clipped one advances at least the floor.
        // Capped far below usize::MAX, so that the counts below and those a resumed run adds
        // cannot overflow.
        let max_steps = ((t / floor).ceil() + 2.0).min(1e15);
        if steps as f64 > max_steps {
            return Err(format!(
                "sim.steps = {steps} is more than a run to t = {t:e} s can take with steps of at least {floor:e} s"
            ));
        }
        let attempts_per_step = halvings as usize + 1;
        let max_rejected = steps.saturating_add(1).saturating_mul(attempts_per_step);
        let max_iterations = (steps.saturating_add(max_rejected).saturating_add(1))
            .saturating_mul(params.newton.max_iter.max(1));
        Ok(CheckpointFit {
            t,
            steps,
            max_rejected,
            max_iterations,
        })
    }
}

/// At most two points of acceleration history, each of `n` nodes × `D` finite numbers at a
/// finite time.
fn check_history<const D: usize>(history: &[(f64, Vec<f64>)], n: usize) -> Result<(), String> {
    if history.len() > 2 {
        return Err(format!(
            "sim.acc_history has {} points, at most 2",
            history.len()
        ));
    }
    for (k, (t, a)) in history.iter().enumerate() {
        if a.len() != D * n {
            return Err(format!(
                "sim.acc_history[{k}] has {} numbers, the scenario needs {} ({n} nodes × {D} components)",
                a.len(),
                D * n
            ));
        }
        if !t.is_finite() || a.iter().any(|x| !x.is_finite()) {
            return Err(format!("sim.acc_history[{k}] is not finite"));
        }
    }
    Ok(())
}

impl<const D: usize, M> Simulation<D, M> {
    /// The complete dynamic state in flat form (without a copy of the record in dimension
    /// `D` first), for a checkpoint file: as [`Self::checkpoint`], the run's energies
    /// included.
    pub fn flat_checkpoint(&self) -> FlatCheckpoint {
        let mut flat = FlatCheckpoint::from(&self.run);
        flat.energies = self.energies.to_array().to_vec();
        flat
    }
}
