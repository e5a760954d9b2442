//! Checkpoint files: everything needed to continue a run so that its outputs are bit for bit
//! those of an uninterrupted run. JSON, with floats in shortest round-trip form (exact).

use std::path::{Path, PathBuf};

use phstring::{Checkpoint, State, Vector};
use serde::{Deserialize, Serialize};

use crate::output::History;

/// The simulation part of a checkpoint (flattened vectors, `D` components per node).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SimState {
    /// Positions [m].
    pub r: Vec<f64>,
    /// Velocities [m/s].
    pub v: Vec<f64>,
    /// Strains.
    pub c: Vec<f64>,
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
    /// Predictor acceleration [m/s²].
    pub acc: Vec<f64>,
    /// Predictor mid-step velocity [m/s].
    pub v_mid: Vec<f64>,
    /// Cumulative supplied energy [J].
    pub supplied_total: f64,
    /// Newton iterations so far.
    pub total_newton: usize,
}

fn flat<const D: usize>(v: &[Vector<D>]) -> Vec<f64> {
    v.iter().flat_map(|x| x.iter().copied()).collect()
}

fn unflat<const D: usize>(v: &[f64]) -> Vec<Vector<D>> {
    v.chunks(D).map(Vector::<D>::from_column_slice).collect()
}

impl SimState {
    /// From a library checkpoint.
    pub fn from_checkpoint<const D: usize>(cp: &Checkpoint<D>) -> Self {
        Self {
            r: flat(&cp.state.r),
            v: flat(&cp.state.v),
            c: cp.state.c.clone(),
            t_base: cp.t_base,
            k: cp.k,
            h_cur: cp.h_cur,
            steps: cp.steps,
            rejected: cp.rejected,
            easy_streak: cp.easy_streak,
            h_min_used: cp.h_min_used,
            acc: flat(&cp.acc),
            v_mid: flat(&cp.v_mid),
            supplied_total: cp.supplied_total,
            total_newton: cp.total_newton,
        }
    }
    /// To a library checkpoint in dimension `D` (sizes are checked by `Simulation::restore`).
    pub fn to_checkpoint<const D: usize>(&self) -> Checkpoint<D> {
        Checkpoint {
            state: State {
                r: unflat(&self.r),
                v: unflat(&self.v),
                c: self.c.clone(),
            },
            t_base: self.t_base,
            k: self.k,
            h_cur: self.h_cur,
            steps: self.steps,
            rejected: self.rejected,
            easy_streak: self.easy_streak,
            h_min_used: self.h_min_used,
            acc: unflat(&self.acc),
            v_mid: unflat(&self.v_mid),
            supplied_total: self.supplied_total,
            total_newton: self.total_newton,
        }
    }
}

/// The output part of a checkpoint: file lengths at the checkpoint (longer files are cut back
/// on resume), ParaView frames, in-memory history.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct OutputState {
    /// Bytes of `energy.csv`.
    pub energy_bytes: u64,
    /// Bytes of `positions.csv`, if written.
    pub positions_bytes: Option<u64>,
    /// Bytes of `ports.csv`.
    pub ports_bytes: u64,
    /// ParaView frames `(t, file name)`.
    pub frames: Vec<(f64, String)>,
    /// Step of the last frame written.
    pub last_frame: Option<usize>,
    /// Energy history and snapshots for the plots.
    pub history: History,
}

/// Run totals carried across a resume.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Counters {
    /// Steps completed.
    pub steps: usize,
    /// Newton iterations.
    pub total_newton_iterations: usize,
    /// Largest balance error [J].
    pub max_balance_error: f64,
    /// Largest Newton residual [N].
    pub max_newton_residual: f64,
    /// Rejected attempts.
    pub rejected_steps: usize,
    /// Line-search backtracks.
    pub line_search_backtracks: usize,
    /// Newton iterations of rejected attempts.
    #[serde(default)]
    pub rejected_newton_iterations: usize,
    /// Local Newton iterations of nonlinear elimination.
    #[serde(default)]
    pub local_newton_iterations: usize,
    /// Their work in global-iteration equivalents.
    #[serde(default)]
    pub local_newton_work: f64,
    /// Wall time of the time loop so far [s].
    pub time_loop_s: f64,
    /// `Ĥ(0)` [J].
    pub hamiltonian_initial: f64,
}

/// A checkpoint file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CheckpointFile {
    /// Always `"phstring checkpoint"`.
    pub format: String,
    /// Program version that wrote it.
    pub version: String,
    /// Scenario file name (for messages).
    pub scenario_path: PathBuf,
    /// Scenario text as run (with `--set` overrides applied).
    pub scenario_text: String,
    /// End of the loading phase marked in plots [s], if any.
    pub end_of_loading: Option<f64>,
    /// Simulation state.
    pub sim: SimState,
    /// Output files.
    pub outputs: OutputState,
    /// Totals.
    pub counters: Counters,
}

/// Errors reading or writing checkpoints.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// I/O.
    #[error("checkpoint {}: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// Not a checkpoint or from another version.
    #[error("checkpoint {}: {reason}", path.display())]
    Format {
        /// File.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

impl CheckpointFile {
    /// Writes atomically (temporary file, then rename).
    pub fn write(&self, path: &Path) -> Result<(), CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        };
        let text = serde_json::to_string(self).map_err(|e| CheckpointError::Format {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let tmp = path.with_extension("json.tmp");
        std::fs::write(&tmp, text).map_err(io)?;
        std::fs::rename(&tmp, path).map_err(io)
    }

    /// Reads and checks a checkpoint.
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        let text = std::fs::read_to_string(path).map_err(|source| CheckpointError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let cp: Self = serde_json::from_str(&text).map_err(|e| CheckpointError::Format {
            path: path.to_path_buf(),
            reason: format!("not a phstring checkpoint ({e})"),
        })?;
        if cp.format != "phstring checkpoint" {
            return Err(CheckpointError::Format {
                path: path.to_path_buf(),
                reason: format!("unknown format \"{}\"", cp.format),
            });
        }
        if cp.version != env!("CARGO_PKG_VERSION") {
            return Err(CheckpointError::Format {
                path: path.to_path_buf(),
                reason: format!(
                    "written by phstring {}, this is {}: resuming would not be bit-identical",
                    cp.version,
                    env!("CARGO_PKG_VERSION")
                ),
            });
        }
        Ok(cp)
    }
}
