//! Checkpoint files: everything needed to continue a run so that its outputs are bit for bit
//! those of an uninterrupted run. JSON, with floats in shortest round-trip form (exact).
//!
//! A checkpoint's size does not grow with the number of steps: it holds the dynamic state,
//! the lengths of the output files and a few counters (the plots read `energy.csv` back).
//! Reading one is bounded ([`MAX_CHECKPOINT_BYTES`], [`MAX_STREAMED_CHECKPOINT_BYTES`]), its [`checksum`](CheckpointFile::checksum)
//! detects any edit, and [`CheckpointFile::check_against`] checks every length and value
//! range against the scenario before anything is restored, so that a damaged or edited file
//! is refused with a message instead of panicking or silently continuing a different run.
//!
//! The simulation part, `sim`, is the core's record in flat form,
//! [`phstring::FlatCheckpoint`]: its fields, their serialization (the JSON keys and their
//! order), their conversion and their checks against a simulation are all in the core,
//! beside the record (`phstring/src/simulation/checkpoint.rs`); this module adds what belongs
//! to the file (outputs, counters, run id, scenario text, checksum) and its checks.

use std::hash::Hasher;
use std::io::Read;
use std::path::{Path, PathBuf};

use phstring::{CheckpointFit, FlatCheckpoint, Material, Simulation};
use serde::{Deserialize, Serialize};

/// The `format` field of every checkpoint.
pub const FORMAT: &str = "phstring checkpoint";

/// Largest checkpoint file read, in bytes, derived from the largest mesh a scenario may
/// have (5e7 elements): per node at most 13 numbers of state (`r`, `v`, `acc`, `v_mid` in
/// 3D and a strain) and 6 snapshot points, each number at most 25 bytes in JSON, so about
/// 640 bytes; 700 bytes per node plus 64 MiB for the scenario text and the rest.
pub const MAX_CHECKPOINT_BYTES: u64 = 50_000_001 * 700 + (64 << 20);

/// Largest checkpoint read from something other than a regular file (a pipe or a device,
/// whose length is not known in advance), in bytes: 1 GiB.
pub const MAX_STREAMED_CHECKPOINT_BYTES: u64 = 1 << 30;

/// FNV-1a (64 bit) hash of `bytes`, as 16 hex digits.
pub fn fnv1a64_hex(bytes: &[u8]) -> String {
    let mut h = fnv::FnvHasher::default();
    h.write(bytes);
    format!("{:016x}", h.finish())
}

/// The output part of a checkpoint: file lengths at the checkpoint (longer files are cut back
/// on resume), the number of ParaView frames, and the configuration snapshots. Its size does
/// not depend on the number of steps.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct OutputState {
    /// Bytes of `energy.csv`.
    pub energy_bytes: u64,
    /// Bytes of `positions.csv`, if written.
    pub positions_bytes: Option<u64>,
    /// Bytes of `ports.csv`.
    pub ports_bytes: u64,
    /// Bytes of `end_tensions.csv`, if written (`None` in checkpoints written before it
    /// existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_tensions_bytes: Option<u64>,
    /// Bytes of `bodies.csv`, if written (runs with rigid bodies).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bodies_bytes: Option<u64>,
    /// Bytes of `winches.csv`, if written (runs with winches).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub winches_bytes: Option<u64>,
    /// Bytes of `winch_arclength.csv`, if written (runs with winches and `positions.csv`;
    /// `None` in checkpoints written before it existed: a resume then does not write it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub winch_arclength_bytes: Option<u64>,
    /// The channel table (`output.channels`), if written: its file name and bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channels: Option<(String, u64)>,
    /// ParaView frames written so far: the first `frames` entries of `paraview/string.pvd`.
    pub frames: usize,
    /// FNV-1a hash of those frames' times and file names (checks `string.pvd` on resume).
    pub frames_hash: u64,
    /// Step of the last frame written.
    pub last_frame: Option<usize>,
    /// Configuration snapshots `(t, node positions in the drawing plane)` for the
    /// configuration plot (at most six).
    pub snapshots: Vec<(f64, Vec<[f64; 2]>)>,
    /// The side view of a 3D run the snapshots are drawn in (`None`: 2D, the plan of a 3D
    /// run, or a checkpoint written before side views).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side: Option<[f64; 2]>,
    /// The view of one plane per line the snapshots are drawn in, if chosen (`None` too in
    /// checkpoints written before it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lines: Option<crate::scene::LinePlanes>,
    /// The nodes on the seabed at each snapshot (empty: dry, or a checkpoint written before
    /// they were recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grounded: Vec<crate::scene::Grounded>,
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
    /// Largest balance error relative to its step's energy scale (0 in checkpoints
    /// written before it was recorded).
    #[serde(default)]
    pub max_relative_balance_error: f64,
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
    /// Steps whose Newton solve ended at the round-off floor.
    #[serde(default)]
    pub steps_at_roundoff: usize,
    /// Steps accepted at the step-size floor over the error tolerance.
    #[serde(default)]
    pub steps_over_tolerance: usize,
    /// Wall time of the time loop so far [s].
    pub time_loop_s: f64,
    /// `Ĥ(0)` [J].
    pub hamiltonian_initial: f64,
    /// `time.settle`: whether the watch is armed.
    #[serde(default)]
    pub settle_armed: bool,
    /// `time.settle`: start of the current stretch below the threshold [s].
    #[serde(default)]
    pub settle_since: Option<f64>,
    /// In water: the extremes of the seabed contact so far (`summary.json`'s `water`).
    /// Absent without water, so that a dry run's checkpoint is the file it always was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water: Option<WaterCounters>,
    /// The extremes of every line so far (`summary.json`'s `lines`); absent without
    /// strings, and in checkpoints written before they were recorded (a run resumed from
    /// one reports no `lines`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lines: Option<Vec<crate::extremes::LineExtremes>>,
}

/// The extremes of the seabed contact over a run in water so far, sampled at every row of
/// `energy.csv` and carried across a resume.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct WaterCounters {
    /// Per string of the network (in its order), the smallest grounded length [m].
    pub grounded_length_min: Vec<f64>,
    /// The largest contact force on a node [N] (0 if nothing touched the seabed).
    pub max_contact_force: f64,
    /// The node it acted on (`None` if nothing touched the seabed).
    pub max_contact_force_node: Option<usize>,
    /// When [s].
    pub max_contact_force_t: f64,
}

/// A checkpoint file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CheckpointFile {
    /// Always [`FORMAT`].
    pub format: String,
    /// Program version that wrote it.
    pub version: String,
    /// Id of the run that wrote it; the output folder carries the same id in
    /// [`RUN_ID_FILE`](crate::files::RUN_ID_FILE), and a resume into a folder with another
    /// id is refused.
    pub run_id: String,
    /// Scenario file, absolute (its tables are found from it).
    pub scenario_path: PathBuf,
    /// The scenario file as the run was given it (relative to its working directory), for a
    /// resume of a run whose folders were moved since: used when the absolute path's folder
    /// is gone. Empty in checkpoints written before it was kept.
    #[serde(default, skip_serializing_if = "is_empty_path")]
    pub scenario_path_given: PathBuf,
    /// Scenario text as run (with `--set` overrides applied).
    pub scenario_text: String,
    /// The data files the scenario reads (its tables, the bathymetry) with a fingerprint of
    /// their contents: a resume reads them again, and refuses one that changed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub data_files: Vec<DataFile>,
    /// End of the loading phase marked in plots [s], if any.
    pub end_of_loading: Option<f64>,
    /// Simulation state: the core's record in flat form, which serializes, checks and
    /// converts itself ([`FlatCheckpoint::check_fits`], [`FlatCheckpoint::into_checkpoint`]).
    pub sim: FlatCheckpoint,
    /// Output files.
    pub outputs: OutputState,
    /// Totals.
    pub counters: Counters,
    /// FNV-1a (64 bit, hex) of the JSON of this checkpoint with an empty `checksum`; any edit
    /// of a value changes it. Set by [`Self::write`], checked by [`Self::read`].
    #[serde(default)]
    pub checksum: String,
    /// The file it was read from (empty if it was not read from a file).
    #[serde(skip)]
    pub path: PathBuf,
}

/// Whether `p` is the empty path (a field a checkpoint leaves out).
fn is_empty_path(p: &Path) -> bool {
    p.as_os_str().is_empty()
}

/// A data file a run reads (a table, the bathymetry), as a checkpoint records it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DataFile {
    /// The scenario key that names it (`winch.0.payout_table`).
    pub key: String,
    /// The file, as the key resolves it, absolute.
    pub path: PathBuf,
    /// FNV-1a (64 bit, hex) of its bytes.
    pub fnv: String,
}

/// The data files `file` reads ([`crate::scenario::ScenarioFile::data_files`]) with the
/// fingerprints of their contents now; a file that cannot be read gets the fingerprint
/// `unreadable`.
pub fn data_files(file: &crate::scenario::ScenarioFile) -> Vec<DataFile> {
    file.data_files()
        .into_iter()
        .map(|(key, path)| {
            let fnv =
                std::fs::read(&path).map_or_else(|_| "unreadable".to_string(), |b| fnv1a64_hex(&b));
            // Absolute, as the checkpoint's scenario path is.
            let path = std::path::absolute(&path).unwrap_or(path);
            DataFile { key, path, fnv }
        })
        .collect()
}

/// Errors reading or writing checkpoints.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CheckpointError {
    /// I/O.
    #[error("checkpoint {}: {cause}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// The cause, part of the message (not a chained source, so that it is printed once).
        cause: std::io::Error,
    },
    /// Not a checkpoint, from another version, or edited (checksum mismatch).
    #[error("checkpoint {}: {reason}", path.display())]
    Format {
        /// File.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A length or value that cannot belong to a run of this scenario.
    #[error("checkpoint {} is damaged or does not belong to this scenario: {reason}", path.display())]
    Invalid {
        /// File.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A data file the run read differs now (or is gone, or the scenario names other files).
    #[error(
        "checkpoint {}: {what} since the checkpoint was written, so the resumed run would not continue this run; restore it, or start the run anew",
        path.display()
    )]
    DataChanged {
        /// Checkpoint file.
        path: PathBuf,
        /// What changed: the key and the file.
        what: String,
    },
    /// The output folder holds another run (or none) than the one that wrote the checkpoint.
    #[error(
        "checkpoint {} was written by the run in {}, but the output folder {} {}; resume into {} (omit --out) so that no other run is overwritten",
        path.display(), checkpoint_dir.display(), out.display(),
        match found { Some(id) => format!("holds another run (run id {id}, the checkpoint's is {expected})"), None => "holds no phstring run".to_string() },
        checkpoint_dir.display()
    )]
    OtherRun {
        /// Checkpoint file.
        path: PathBuf,
        /// Folder of the checkpoint file.
        checkpoint_dir: PathBuf,
        /// Output folder of the resume.
        out: PathBuf,
        /// Run id of the checkpoint.
        expected: String,
        /// Run id found in the output folder, if any.
        found: Option<String>,
    },
}

/// A [`CheckpointFile`] by reference, with the checksum given apart: it serializes to the
/// same JSON as the file with that checksum, without copying the state.
#[derive(Serialize)]
struct CheckpointView<'a> {
    format: &'a str,
    version: &'a str,
    run_id: &'a str,
    scenario_path: &'a Path,
    #[serde(skip_serializing_if = "is_empty_path")]
    scenario_path_given: &'a Path,
    scenario_text: &'a str,
    #[serde(skip_serializing_if = "<[DataFile]>::is_empty")]
    data_files: &'a [DataFile],
    end_of_loading: Option<f64>,
    sim: &'a FlatCheckpoint,
    outputs: &'a OutputState,
    counters: &'a Counters,
    checksum: &'a str,
}

/// Feeds what is written into an FNV-1a hasher.
struct HashWriter(fnv::FnvHasher);

impl std::io::Write for HashWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl CheckpointFile {
    /// This checkpoint with `checksum` as its checksum, by reference.
    fn view<'a>(&'a self, checksum: &'a str) -> CheckpointView<'a> {
        CheckpointView {
            format: &self.format,
            version: &self.version,
            run_id: &self.run_id,
            scenario_path: &self.scenario_path,
            scenario_path_given: &self.scenario_path_given,
            scenario_text: &self.scenario_text,
            data_files: &self.data_files,
            end_of_loading: self.end_of_loading,
            sim: &self.sim,
            outputs: &self.outputs,
            counters: &self.counters,
            checksum,
        }
    }

    /// The scenario path a resume parses the checkpoint's scenario with: the absolute one
    /// while its folder exists, else the one the run was given (folders moved since).
    pub fn scenario_path_for_resume(&self) -> &Path {
        let here = self.scenario_path.parent().is_some_and(Path::exists);
        if here || self.scenario_path_given.as_os_str().is_empty() {
            &self.scenario_path
        } else {
            &self.scenario_path_given
        }
    }

    /// Refuses a resume of this checkpoint by `file` (the scenario it holds) when a data file
    /// the run read has changed: its fingerprint differs, it cannot be read, or the scenario
    /// names no file for the key (a file found elsewhere, the folders moved, is the same
    /// file if its fingerprint is).
    pub fn check_data_files(
        &self,
        file: &crate::scenario::ScenarioFile,
    ) -> Result<(), CheckpointError> {
        let now = data_files(file);
        for was in &self.data_files {
            let what = match now.iter().find(|d| d.key == was.key) {
                None => format!("`{}` names no file now", was.key),
                Some(d) if d.fnv == "unreadable" => {
                    format!("`{}`: {} cannot be read", was.key, d.path.display())
                }
                Some(d) if d.fnv != was.fnv => {
                    format!("`{}`: {} has changed", was.key, d.path.display())
                }
                Some(_) => continue,
            };
            return Err(CheckpointError::DataChanged {
                path: self.path.clone(),
                what,
            });
        }
        Ok(())
    }

    /// The checksum of this checkpoint's content: FNV-1a (64 bit) over its JSON with an
    /// empty `checksum` field (hashed as it is serialized, without a copy). Floats print in
    /// shortest round-trip form, so the JSON of a checkpoint read back is that of the one
    /// written, and any changed value changes it.
    pub fn checksum(&self) -> String {
        let mut h = HashWriter(fnv::FnvHasher::default());
        // Serializing plain data into a hasher cannot fail.
        let _ = serde_json::to_writer(&mut h, &self.view(""));
        format!("{:016x}", h.0.finish())
    }

    /// Writes atomically (a temporary file in the same folder, then rename), with the
    /// checksum set.
    pub fn write(&self, path: &Path) -> Result<(), CheckpointError> {
        // JSON has no NaN or infinity (serde_json would write `null`, unreadable).
        if let Some(what) = self.non_finite() {
            return Err(CheckpointError::Format {
                path: path.to_path_buf(),
                reason: format!("refusing to write a non-finite value in {what}"),
            });
        }
        let checksum = self.checksum();
        let text =
            serde_json::to_string(&self.view(&checksum)).map_err(|e| CheckpointError::Format {
                path: path.to_path_buf(),
                reason: e.to_string(),
            })?;
        crate::files::atomic_write(path, text.as_bytes()).map_err(|source| CheckpointError::Io {
            path: path.to_path_buf(),
            cause: source,
        })
    }

    /// The first field holding NaN or infinity, if any: the simulation record's
    /// ([`FlatCheckpoint::non_finite`]), then the counters', the end of loading and the
    /// snapshots.
    fn non_finite(&self) -> Option<&'static str> {
        let c = &self.counters;
        let scalars = [
            ("counters.max_balance_error", c.max_balance_error),
            (
                "counters.max_relative_balance_error",
                c.max_relative_balance_error,
            ),
            ("counters.max_newton_residual", c.max_newton_residual),
            ("counters.local_newton_work", c.local_newton_work),
            ("counters.time_loop_s", c.time_loop_s),
            ("counters.hamiltonian_initial", c.hamiltonian_initial),
            ("end_of_loading", self.end_of_loading.unwrap_or(0.0)),
        ];
        self.sim
            .non_finite()
            .or_else(|| {
                scalars
                    .into_iter()
                    .find(|(_, x)| !x.is_finite())
                    .map(|(n, _)| n)
            })
            .or_else(|| {
                self.outputs
                    .snapshots
                    .iter()
                    .any(|(t, p)| !t.is_finite() || p.iter().flatten().any(|x| !x.is_finite()))
                    .then_some("outputs.snapshots")
            })
    }

    /// Reads a checkpoint (at most [`MAX_CHECKPOINT_BYTES`], or
    /// [`MAX_STREAMED_CHECKPOINT_BYTES`] from a pipe or device) and checks its format, version
    /// and checksum. The lengths and ranges that depend on the scenario are checked by
    /// [`Self::check_against`].
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        let format_err = |reason: String| CheckpointError::Format {
            path: path.to_path_buf(),
            reason,
        };
        let io = |source| CheckpointError::Io {
            path: path.to_path_buf(),
            cause: source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        if meta.is_dir() {
            return Err(format_err("is a folder, not a checkpoint file".into()));
        }
        let cap = if meta.is_file() {
            MAX_CHECKPOINT_BYTES
        } else {
            MAX_STREAMED_CHECKPOINT_BYTES
        };
        if meta.is_file() && meta.len() > cap {
            return Err(format_err(format!(
                "is {} bytes, more than a checkpoint can be ({cap} bytes): not a phstring checkpoint",
                meta.len()
            )));
        }
        // Bounded even for devices and pipes (`/dev/zero`); the parser stops at the first
        // byte that cannot start a checkpoint.
        let mut limited = std::io::BufReader::new(file).take(cap + 1);
        let parsed: Result<Self, _> = serde_json::from_reader(&mut limited);
        if limited.limit() == 0 {
            return Err(format_err(format!(
                "longer than {cap} bytes: not a phstring checkpoint"
            )));
        }
        let mut cp = parsed.map_err(|e| format_err(format!("not a phstring checkpoint ({e})")))?;
        cp.path = path.to_path_buf();
        if cp.format != FORMAT {
            return Err(format_err(format!(
                "unknown format \"{}\"",
                crate::text::sanitize_text(&cp.format, 80)
            )));
        }
        if cp.version != env!("CARGO_PKG_VERSION") {
            return Err(format_err(format!(
                "written by phstring {}, this is {}: resuming would not be bit-identical",
                crate::text::sanitize_text(&cp.version, 80),
                env!("CARGO_PKG_VERSION")
            )));
        }
        let expected = cp.checksum();
        if cp.checksum != expected {
            return Err(format_err(if cp.checksum.is_empty() {
                "has no checksum: not written by this phstring".to_string()
            } else {
                "checksum mismatch: the file was edited or damaged after it was written".to_string()
            }));
        }
        if !crate::files::is_valid_run_id(&cp.run_id) {
            return Err(format_err("invalid run id".into()));
        }
        Ok(cp)
    }

    /// Checks every array length and value range of the checkpoint against the simulation
    /// set up from its scenario (before [`Simulation::restore`]) and the run settings: the
    /// simulation record's ([`FlatCheckpoint::check_fits`]: node and element counts, finite
    /// values, strains in the material's domain, the step size between the floor
    /// `time.h / 2^max_halvings` and `time.h`, the time within `[0, time.end]`, counts a run
    /// to that time can reach), then the counters' (the same limits), and output lengths at
    /// least the files' headers.
    pub fn check_against<const D: usize>(
        &self,
        sim: &Simulation<D, Material>,
        settings: &crate::scenario::RunSettings,
    ) -> Result<(), CheckpointError> {
        let n = sim.system().mesh().n_nodes();
        let checks = || {
            let fit = self.sim.check_fits(sim, settings.t_end)?;
            self.check_counts(&fit)?;
            self.check_totals()?;
            self.check_water(sim, n, fit.t)?;
            self.check_lines(sim, fit.t)?;
            self.check_outputs::<D>(settings, n, fit.t)
        };
        checks().map_err(|reason| CheckpointError::Invalid {
            path: self.path.clone(),
            reason,
        })
    }

    /// Checks this checkpoint against `sim` ([`Self::check_against`]) and puts its state
    /// into it ([`Simulation::restore`]: the state, the progress of the run and the winches'
    /// meshes): how a resumed run and the analyses at a checkpoint (`statics --at`,
    /// `linearize --at`) start. The flat record is turned into the simulation's one array at
    /// a time (each freed as it goes), so that a large state is not held twice in full.
    /// Returns the file's own parts that a resumed run continues: its counters and the
    /// state of its output files.
    pub fn restore_into<const D: usize>(
        self,
        sim: &mut Simulation<D, Material>,
        settings: &crate::scenario::RunSettings,
    ) -> Result<(Counters, OutputState), CheckpointError> {
        self.check_against(sim, settings)?;
        let Self {
            path,
            sim: flat,
            counters,
            outputs,
            ..
        } = self;
        sim.restore(flat.into_checkpoint::<D>())
            .map_err(|e| CheckpointError::Invalid {
                path,
                reason: e.to_string(),
            })?;
        Ok((counters, outputs))
    }

    /// The water counters: present exactly for a run in water, one grounded length per
    /// string, finite and non-negative values, a node of the mesh, a time up to `t`.
    fn check_water<const D: usize>(
        &self,
        sim: &Simulation<D, Material>,
        n: usize,
        t: f64,
    ) -> Result<(), String> {
        let sys = sim.system();
        let w = match (&self.counters.water, sys.has_water()) {
            (None, false) => return Ok(()),
            (Some(w), true) => w,
            (w, _) => {
                return Err(format!(
                    "counters.water is {} but the scenario {} water",
                    if w.is_some() { "set" } else { "missing" },
                    if sys.has_water() { "has" } else { "has no" }
                ));
            }
        };
        let strings = sys
            .groups()
            .iter()
            .filter(|g| matches!(g.law, phstring::Law::String(_)))
            .count();
        if w.grounded_length_min.len() != strings {
            return Err(format!(
                "counters.water.grounded_length_min has {} values for {strings} strings",
                w.grounded_length_min.len()
            ));
        }
        let values = w
            .grounded_length_min
            .iter()
            .chain([&w.max_contact_force, &w.max_contact_force_t]);
        if values.into_iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err("counters.water holds a negative or non-finite value".into());
        }
        if w.max_contact_force_node.is_some_and(|i| i >= n) || w.max_contact_force_t > t {
            return Err("counters.water.max_contact_force_node or _t is out of range".into());
        }
        Ok(())
    }

    /// The lines' extremes, if recorded: one record per string, each consistent
    /// ([`LineExtremes::check`](crate::extremes::LineExtremes::check)) with times up to `t`.
    fn check_lines<const D: usize>(
        &self,
        sim: &Simulation<D, Material>,
        t: f64,
    ) -> Result<(), String> {
        let Some(lines) = &self.counters.lines else {
            return Ok(());
        };
        let strings = sim
            .system()
            .groups()
            .iter()
            .filter(|g| matches!(g.law, phstring::Law::String(_)) && !g.elements.is_empty())
            .count();
        if lines.len() != strings {
            return Err(format!(
                "counters.lines has {} records for {strings} strings",
                lines.len()
            ));
        }
        lines
            .iter()
            .try_for_each(|x| x.check(t))
            .map_err(|e| format!("counters.lines: {e}"))
    }

    /// The counters' step count (that of the simulation record), and their rejection and
    /// iteration counts: at most what `sim.steps` steps can have.
    fn check_counts(&self, fit: &CheckpointFit) -> Result<(), String> {
        let c = &self.counters;
        if c.steps != fit.steps {
            return Err(format!(
                "counters.steps = {} differs from sim.steps = {}",
                c.steps, fit.steps
            ));
        }
        let max_iterations = fit.max_iterations;
        for (name, value, limit) in [
            (
                "counters.rejected_steps",
                c.rejected_steps,
                fit.max_rejected,
            ),
            (
                "counters.total_newton_iterations",
                c.total_newton_iterations,
                max_iterations,
            ),
            (
                "counters.rejected_newton_iterations",
                c.rejected_newton_iterations,
                max_iterations,
            ),
            (
                "counters.line_search_backtracks",
                c.line_search_backtracks,
                max_iterations.saturating_mul(64),
            ),
            (
                "counters.local_newton_iterations",
                c.local_newton_iterations,
                max_iterations.saturating_mul(1024),
            ),
            ("counters.steps_at_roundoff", c.steps_at_roundoff, fit.steps),
            (
                "counters.steps_over_tolerance",
                c.steps_over_tolerance,
                fit.steps,
            ),
        ] {
            fit.check_count(name, value, limit)?;
        }
        Ok(())
    }

    /// The counters' energy totals and timings: finite, and non-negative where they must
    /// be; the end of loading finite.
    fn check_totals(&self) -> Result<(), String> {
        let c = &self.counters;
        for (name, value, nonneg) in [
            ("counters.hamiltonian_initial", c.hamiltonian_initial, false),
            ("counters.max_balance_error", c.max_balance_error, true),
            (
                "counters.max_relative_balance_error",
                c.max_relative_balance_error,
                true,
            ),
            ("counters.max_newton_residual", c.max_newton_residual, true),
            ("counters.local_newton_work", c.local_newton_work, true),
            ("counters.time_loop_s", c.time_loop_s, true),
        ] {
            if !value.is_finite() || (nonneg && value < 0.0) {
                return Err(format!(
                    "{name} = {value:e} must be finite{}",
                    if nonneg { " and ≥ 0" } else { "" }
                ));
            }
        }
        if let Some(e) = self.end_of_loading
            && !e.is_finite()
        {
            return Err("end_of_loading is not finite".into());
        }
        Ok(())
    }

    /// The output state: file lengths at least the headers (dimension `D`), the positions
    /// file as `output.positions` says, frame and snapshot counts a run of `sim.steps` steps
    /// writes, and snapshots of `n` finite positions at times up to the time reached.
    fn check_outputs<const D: usize>(
        &self,
        settings: &crate::scenario::RunSettings,
        n: usize,
        t: f64,
    ) -> Result<(), String> {
        let s = &self.sim;
        let o = &self.outputs;
        let (energy_header, positions_header, ports_header) = crate::files::headers(D);
        for (name, bytes, header) in [
            ("outputs.energy_bytes", Some(o.energy_bytes), &energy_header),
            (
                "outputs.positions_bytes",
                o.positions_bytes,
                &positions_header,
            ),
            ("outputs.ports_bytes", Some(o.ports_bytes), &ports_header),
        ] {
            // energy.csv holds the header and the t = 0 row at least.
            let min = header.len() as u64 + if name == "outputs.energy_bytes" { 3 } else { 1 };
            if let Some(b) = bytes
                && b < min
            {
                return Err(format!(
                    "{name} = {b} is shorter than the file's header and first row ({min} bytes)"
                ));
            }
        }
        if o.positions_bytes.is_some() != settings.output.positions {
            return Err(format!(
                "outputs.positions_bytes is {} but output.positions = {}",
                if o.positions_bytes.is_some() {
                    "set"
                } else {
                    "missing"
                },
                settings.output.positions
            ));
        }
        let max_frames = s.steps / settings.stride.max(1) + 2;
        if (!settings.output.vtk && o.frames > 0) || o.frames > max_frames {
            return Err(format!(
                "outputs.frames = {} is more than {} steps write with output.stride = {}{}",
                o.frames,
                s.steps,
                settings.stride,
                if settings.output.vtk {
                    ""
                } else {
                    " and output.vtk = false"
                }
            ));
        }
        if o.last_frame.is_some_and(|f| f > s.steps) {
            return Err(format!(
                "outputs.last_frame is beyond the {} steps done",
                s.steps
            ));
        }
        let max_snapshots = if D >= 2 { crate::files::SNAPSHOTS } else { 0 };
        if o.snapshots.len() > max_snapshots {
            return Err(format!(
                "outputs.snapshots has {} snapshots, at most {max_snapshots} are taken",
                o.snapshots.len()
            ));
        }
        for (k, (ts, pts)) in o.snapshots.iter().enumerate() {
            if !(ts.is_finite() && *ts >= 0.0 && *ts <= t * (1.0 + 1e-9) + s.h_cur) {
                return Err(format!(
                    "outputs.snapshots[{k}] has time {ts:e} s outside [0, t = {t:e} s]"
                ));
            }
            if pts.len() != n || pts.iter().flatten().any(|x| !x.is_finite()) {
                return Err(format!(
                    "outputs.snapshots[{k}] must have {n} finite node positions"
                ));
            }
        }
        check_view(o, n)?;
        Ok(())
    }
}

/// Checks the drawing record of a checkpoint's outputs for a mesh of `n` nodes: grounded
/// nodes below `n` for at most the snapshots taken, finite lengths, and a view of one plane
/// per line with a finite layout and a line for each node.
fn check_view(o: &OutputState, n: usize) -> Result<(), String> {
    if o.grounded.len() > o.snapshots.len() {
        return Err(format!(
            "outputs.grounded has {} entries for {} snapshots",
            o.grounded.len(),
            o.snapshots.len()
        ));
    }
    for (k, g) in o.grounded.iter().enumerate() {
        if g.nodes.iter().any(|&i| i >= n) || g.lengths.iter().any(|x| !x.is_finite()) {
            return Err(format!(
                "outputs.grounded[{k}] must list nodes below {n} and finite lengths"
            ));
        }
    }
    if let Some(l) = &o.lines {
        let finite = l.width.is_finite()
            && l.width > 0.0
            && l.lines.iter().all(|p| {
                p.fairlead
                    .iter()
                    .chain(&p.azimuth)
                    .chain([&p.offset])
                    .all(|x| x.is_finite())
            });
        if !finite || l.node_line.len() != n || l.node_line.iter().any(|&k| k >= l.lines.len()) {
            return Err(format!(
                "outputs.lines must have a finite layout and a line for each of the {n} nodes"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkpoint as written by phstring before the simulation record's flat form moved to
    /// the core: a 12-element taut string in 2D with error control (`time.rtol = 1e-5`),
    /// interrupted after 12 steps (two points of acceleration history). Written by
    /// `phstring run examples/taut_string.toml --set mesh.elements=12 --set time.rtol=1e-5
    /// --stop-after-steps 12`; only a deliberate change of the file format replaces it.
    const FIXTURE: &str = include_str!("../tests/fixtures/checkpoint_taut_string_2d.json");

    /// The fixture parses, its checksum verifies, it serializes back to the same bytes, and it
    /// fits and restores into a simulation of its scenario, which steps on from it.
    #[test]
    fn checkpoint_fixture_reads_back_byte_for_byte_and_resumes() {
        let cp: CheckpointFile = serde_json::from_str(FIXTURE).unwrap();
        assert_eq!(cp.checksum, "f66484bd11cfd6b4");
        assert_eq!(cp.checksum(), cp.checksum);
        assert_eq!(serde_json::to_string(&cp).unwrap(), FIXTURE);
        let s = &cp.sim;
        assert_eq!((s.steps, s.rejected, s.total_newton), (12, 4, 14));
        assert_eq!((s.r.len(), s.c.len(), s.acc_history.len()), (26, 12, 2));
        assert_eq!(s.err_prev, 0.5204494196047398);
        assert_eq!(s.h_cur, 9.389162555012371e-6);

        let file =
            crate::scenario::parse(&cp.scenario_text, Path::new("checkpoint.toml"), &[]).unwrap();
        let v = file.validate::<2>().unwrap();
        let t_end = v.settings.t_end;
        let mut sim = Simulation::<2, Material>::new(v.problem, v.settings.step).unwrap();
        cp.check_against(&sim, &v.settings).unwrap();
        sim.restore(cp.sim.clone().into_checkpoint::<2>()).unwrap();
        // The record as it was read, and now the run's energies (the fixture has none: it
        // was written before a checkpoint carried them).
        let mut back = sim.flat_checkpoint();
        let e = sim.energies();
        assert_eq!(
            back.energies,
            [
                e.kinetic,
                e.internal,
                e.external,
                e.buoyancy,
                e.seabed,
                e.magnitude
            ]
        );
        back.energies.clear();
        assert_eq!(back, cp.sim);
        assert_eq!(sim.checkpoint().acc_history.points.len(), 2);
        let report = sim.step_until(t_end).unwrap();
        assert!(report.balance_error.is_finite());
        assert_eq!(sim.steps(), 13);
    }

    /// A file without the error-control fields (written before error control) reads with
    /// an empty history and a last error of 1; a record that does not fit the scenario is
    /// refused with a message that names the field and the bad value.
    #[test]
    fn checkpoint_defaults_and_refusals_name_the_field() {
        let mut v: serde_json::Value = serde_json::from_str(FIXTURE).unwrap();
        let sim = v["sim"].as_object_mut().unwrap();
        sim.remove("acc_history");
        sim.remove("err_prev");
        let cp: CheckpointFile = serde_json::from_value(v).unwrap();
        assert!(cp.sim.acc_history.is_empty());
        assert_eq!(cp.sim.err_prev, 1.0);
        // Written before the drawing record: nothing on the seabed, one plane.
        assert!(cp.outputs.grounded.is_empty() && cp.outputs.lines.is_none());
        let snapshots = cp.outputs.snapshots.len();
        assert!(snapshots >= 1);

        let file =
            crate::scenario::parse(&cp.scenario_text, Path::new("checkpoint.toml"), &[]).unwrap();
        let v = file.validate::<2>().unwrap();
        let sim = Simulation::<2, Material>::new(v.problem, v.settings.step).unwrap();
        let refused = |edit: fn(&mut CheckpointFile)| {
            let mut bad = cp.clone();
            edit(&mut bad);
            bad.check_against(&sim, &v.settings)
                .unwrap_err()
                .to_string()
        };
        for (edit, message) in [
            (
                (|c: &mut CheckpointFile| c.sim.err_prev = -2.0) as fn(&mut CheckpointFile),
                "sim.err_prev = -2e0 must be positive and finite",
            ),
            (
                |c| c.sim.acc_history = vec![(0.0, vec![0.0; 3])],
                "sim.acc_history[0] has 3 numbers, the scenario needs 26 (13 nodes × 2 components)",
            ),
            (
                |c| c.sim.v_mid.push(0.0),
                "sim.v_mid has 27 numbers, the scenario needs 26 (13 nodes × 2 components)",
            ),
            (
                |c| c.sim.total_newton = usize::MAX,
                "sim.total_newton = 18446744073709551615 is more than 12 steps can have",
            ),
            (
                |c| c.sim.dissipated_total = f64::INFINITY,
                "sim.dissipated_total = inf must be finite",
            ),
            (
                |c| c.sim.water.friction_dissipated = f64::NAN,
                "sim.water.friction_dissipated = NaN must be finite",
            ),
            (
                |c| c.sim.water.drag_dissipated = 3.5,
                "sim.water has shares (drag 3.5e0 J, current 0e0 J, seabed 0e0 J, friction 0e0 J) but the scenario has no water",
            ),
            (
                |c| c.counters.steps = 11,
                "counters.steps = 11 differs from sim.steps = 12",
            ),
            (
                |c| {
                    c.outputs.grounded = vec![crate::scene::Grounded {
                        nodes: vec![3, 13],
                        lengths: vec![1.0],
                    }]
                },
                "outputs.grounded[0] must list nodes below 13 and finite lengths",
            ),
            (
                |c| {
                    let one = crate::scene::Grounded::default();
                    c.outputs.grounded = vec![one; c.outputs.snapshots.len() + 1];
                },
                "entries for",
            ),
            (
                |c| {
                    c.outputs.lines = Some(crate::scene::LinePlanes {
                        lines: vec![crate::scene::LinePlane {
                            fairlead: [0.0, 0.0],
                            azimuth: [1.0, 0.0],
                            offset: 0.0,
                        }],
                        width: 1000.0,
                        node_line: vec![0; 2],
                    })
                },
                "outputs.lines must have a finite layout and a line for each of the 13 nodes",
            ),
        ] {
            let e = refused(edit);
            assert!(e.contains(message), "expected {message:?} in {e}");
        }
        let mut bad = cp.clone();
        bad.sim.acc[3] = f64::NAN;
        let e = bad.write(Path::new("unused.json")).unwrap_err().to_string();
        assert!(e.contains("non-finite value in sim.acc"), "{e}");
    }
}
