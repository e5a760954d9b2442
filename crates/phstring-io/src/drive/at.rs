//! The system as a checkpoint holds it, for the analyses at a checkpoint (`phstring statics
//! --at`, `phstring linearize --at`; docs/method.md §23, "Analyses at a checkpoint").
//!
//! A run's checkpoint is restored exactly as `phstring run --resume` restores it
//! ([`CheckpointFile::restore_into`] on a simulation started from the scenario), so that
//! every check of a resume applies (lengths, value ranges, the winches' states and their drum
//! nodes on their paths) and the system carries the checkpoint's mesh: each winch's string
//! with the elements paid out or hauled in so far (its group's range, the nodes held on the
//! drum, the body forces, the water lumped again). The analyses then take the system as it
//! is at the checkpoint's time `t`:
//! * the supports and prescribed motions, and each winch's drum node, where the run had
//!   them at `t` (the checkpoint's positions; a support is held where it is);
//! * the nodal loads and the rigid bodies' wrench ports held at their values at `t`.
//!
//! A rigid body with a prescribed motion or a feedback law is refused: the statics would
//! take its pose or its reference at `t = 0`.

use std::path::{Path, PathBuf};

use phstring::statics::StaticsParams;
use phstring::{ByDim, Material, PhSystem, SetupError, Simulation, State};
use serde::Serialize;

use crate::checkpoint::{CheckpointError, CheckpointFile};
use crate::scenario::{AnySetup, Setup};

/// Why the system at a checkpoint could not be set up.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AtError {
    /// The checkpoint could not be read, or does not belong to a run of this scenario.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The checkpoint's positions are not the scenario's nodes in its dimension (a checkpoint
    /// of another scenario).
    #[error(
        "{} holds {values} position values, but the scenario has {nodes} nodes in {dimension}D ({} values)",
        path.display(), nodes * dimension
    )]
    Size {
        /// The checkpoint file.
        path: PathBuf,
        /// Position values it holds.
        values: usize,
        /// Nodes of the scenario's mesh (the winches' reserves included).
        nodes: usize,
        /// The scenario's dimension.
        dimension: usize,
    },
    /// The simulation could not be set up from the scenario.
    #[error("setup failed: {0}")]
    Setup(#[from] SetupError),
    /// What the analyses at a checkpoint do not cover (yet).
    #[error("{}: {reason}", path.display())]
    Unsupported {
        /// The checkpoint file.
        path: PathBuf,
        /// What is not covered, and what to do instead.
        reason: String,
    },
}

/// A winch at the checkpoint, as `summary.json` and `manifest.json` report it.
#[derive(Debug, Clone, Serialize)]
pub struct WinchAt {
    /// The winch's name.
    pub name: String,
    /// Length paid out since `t = 0` [m] (negative: hauled in).
    pub payout: f64,
    /// Reference (unstretched) length of its string off the drum, beyond the drum point [m].
    pub length: f64,
    /// Reference length of the string's elements off the drum (from the drum node on) [m]:
    /// `length` plus the model's cable behind the drum point (docs/method.md §23), what
    /// hangs from the drum node.
    pub elements_length: f64,
    /// The drum node (mesh index), held where the checkpoint has it.
    pub drum_node: usize,
    /// The drum element (mesh index), the first element off the drum.
    pub drum_element: usize,
    /// Tension of the drum element [N] in the checkpoint's state.
    pub tension: f64,
}

/// Where the analysis started: the checkpoint, its time and its winches.
#[derive(Debug, Clone, Serialize)]
pub struct CheckpointInfo {
    /// The checkpoint file.
    pub checkpoint: String,
    /// Its time `t` [s]: the loads and wrench ports are held at their values then.
    pub time: f64,
    /// Steps the run had taken.
    pub steps: usize,
    /// Its winches (empty without).
    pub winches: Vec<WinchAt>,
}

/// The system and state of a checkpoint in dimension `D`.
#[derive(Debug, Clone)]
pub struct AtCheckpoint<const D: usize> {
    /// Where it comes from.
    pub info: CheckpointInfo,
    /// The scenario's system with the checkpoint's winch meshes, its loads and wrench ports
    /// held at their values at the checkpoint's time.
    pub system: PhSystem<D, Material>,
    /// The checkpoint's state (positions [m], velocities [m/s], strains, body poses).
    pub state: State<D>,
    /// The scenario's statics settings (Newton, linear solver), closed loop.
    pub statics: StaticsParams,
}

/// An [`AtCheckpoint`] of the scenario's dimension.
pub type AnyAt = ByDim<AtCheckpoint<1>, AtCheckpoint<2>, AtCheckpoint<3>>;

/// Reads the checkpoint at `path`, checks it against the scenario of `setup` as a resume
/// does, and sets up the system as it holds it. Everything is checked here, before a command
/// touches its output folder.
pub fn read_at(setup: &AnySetup, path: &Path) -> Result<AnyAt, AtError> {
    let cp = CheckpointFile::read(path)?;
    let nodes = phstring::by_dim!(setup, s => s.problem.system.mesh().n_nodes());
    let d = setup.dimension();
    if cp.sim.r.len() != nodes * d {
        return Err(AtError::Size {
            path: cp.path.clone(),
            values: cp.sim.r.len(),
            nodes,
            dimension: d,
        });
    }
    phstring::by_dim!(map setup, s => at_checkpoint(s, cp)).transpose()
}

/// [`read_at`] in dimension `D`, for a checkpoint of the right size.
fn at_checkpoint<const D: usize>(
    v: &Setup<D>,
    cp: CheckpointFile,
) -> Result<AtCheckpoint<D>, AtError> {
    let path = cp.path.clone();
    let unsupported = |reason: String| AtError::Unsupported {
        path: path.clone(),
        reason,
    };
    let built = &v.problem;
    let mut sim =
        Simulation::from_system(built.system.clone(), built.state.clone(), v.settings.step)?;
    cp.restore_into(&mut sim, &v.settings)?;
    let t = sim.time();
    let sys = sim.system();
    for (b, (name, _)) in sys.bodies().iter().enumerate() {
        if sys.body_has_motion(b) || sys.body_has_feedback(b) {
            return Err(unsupported(format!(
                "rigid body \"{name}\" has a {}: the analyses at a checkpoint do not cover it yet (the statics would take its {} at t = 0, not at t = {t} s)",
                if sys.body_has_motion(b) {
                    "prescribed motion"
                } else {
                    "feedback law"
                },
                if sys.body_has_motion(b) {
                    "pose"
                } else {
                    "reference"
                }
            )));
        }
    }
    let mut system = sys.clone();
    for k in 0..system.boundary().loads.len() {
        let force = (system.boundary().loads[k].force)(t);
        system
            .hold_load_force(k, force)
            .map_err(|e| unsupported(format!("load {k} at t = {t} s cannot be held: {e}")))?;
    }
    for b in 0..system.bodies().len() {
        if let Some((force, torque)) = system.body_wrench_at(b, t) {
            system.hold_body_wrench(b, force, torque).map_err(|e| {
                unsupported(format!(
                    "the wrench of rigid body {b} at t = {t} s cannot be held: {e}"
                ))
            })?;
        }
    }
    let winches = winches_at(&sim);
    Ok(AtCheckpoint {
        info: CheckpointInfo {
            checkpoint: path.display().to_string(),
            time: t,
            steps: sim.steps(),
            winches,
        },
        system,
        state: sim.state().clone(),
        statics: v.statics_params(false),
    })
}

/// The winches of `sim` as restored from a checkpoint.
fn winches_at<const D: usize>(sim: &Simulation<D, Material>) -> Vec<WinchAt> {
    let sys = sim.system();
    let layout = sys.winch_layout(&sim.checkpoint().winches);
    sys.winches()
        .iter()
        .zip(sim.winch_samples())
        .zip(layout)
        .map(|((&(name, group), sample), (drum_node, drum_element))| {
            let span = sys.group_span(group);
            let elements_length = sys.mesh().lengths()[drum_element..span.end].iter().sum();
            WinchAt {
                name: name.to_string(),
                payout: sample.payout,
                length: sample.length,
                elements_length,
                drum_node,
                drum_element,
                tension: sample.tension,
            }
        })
        .collect()
}
