//! The FMU's own failures, typed. Each message is the text the FMU logs (with the FMI status
//! its caller chooses: `Error` for a refused call, `Discard` for a failed step) or the CLI
//! prints. Causes from the other crates are part of the message, not chained sources, so that
//! they are printed once.

use std::path::PathBuf;

use phstring::{InputError, SetupError};
use phstring_io::scenario::ScenarioError;
use thiserror::Error;

/// Why an FMU instance cannot be made or set up, a call is refused, or a state cannot be
/// saved, serialized, read or restored.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum FmuError {
    /// The packaged scenario does not parse or validate, or its variables cannot be derived.
    #[error("{0}")]
    Scenario(ScenarioError),
    /// The GUID (FMI 3.0: instantiation token) the master passed is not this FMU's.
    #[error(
        "GUID {given} does not match this FMU's scenario ({expected}): modelDescription.xml and resources/scenario.toml are from different builds"
    )]
    GuidMismatch {
        /// The GUID the master passed.
        given: String,
        /// This FMU's GUID.
        expected: String,
    },
    /// `fmuResourceLocation` is not a `file:` URI.
    #[error("fmuResourceLocation {uri:?} is not a file: URI")]
    NotAFileUri {
        /// The URI given.
        uri: String,
    },
    /// `fmuResourceLocation` is not UTF-8 once percent-decoded.
    #[error("fmuResourceLocation {uri:?} is not UTF-8 once decoded")]
    UriNotUtf8 {
        /// The URI given.
        uri: String,
    },
    /// The packaged scenario cannot be read.
    #[error("cannot read {}: {cause}", path.display())]
    ReadScenario {
        /// Its path.
        path: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// The parameters the master set make the scenario invalid or unsolvable.
    #[error("the parameters ({sets}) do not fit the scenario: {cause}")]
    ParametersDoNotFit {
        /// The overrides, `key=value` joined by `, `.
        sets: String,
        /// What went wrong with them.
        cause: Box<FmuError>,
    },
    /// The simulation cannot be set up, or a checkpoint not restored into it.
    #[error("{0}")]
    Setup(SetupError),
    /// The starting equilibrium (`initial.equilibrium`) was not found.
    #[error("{cause}")]
    Equilibrium {
        /// The failure of the static solve.
        cause: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The parameters changed the scenario's dimension, which the FMU's variables are
    /// laid out for.
    #[error(
        "dimension: is {got}, expected {expected} (the FMU's variables are those of {expected}D)"
    )]
    DimensionChanged {
        /// The dimension of the FMU.
        expected: usize,
        /// The dimension of the scenario with the parameters set.
        got: usize,
    },
    /// An input value the simulation refused.
    #[error("{0}")]
    Input(InputError),
    /// `fmi2DoStep` (`fmi3DoStep`) outside step mode.
    #[error(
        "{call} is allowed only after initialization and a completed step (the instance is {mode})"
    )]
    StepNotAllowed {
        /// The function's name in the instance's FMI version.
        call: String,
        /// The instance's mode (`Instantiated`, `StepFailed`, …).
        mode: String,
    },
    /// A communication step size that is not positive and finite.
    #[error("the communication step size must be positive and finite, got {h}")]
    StepSize {
        /// The step size given [s].
        h: f64,
    },
    /// A communication step too small to change the master's time.
    #[error(
        "{call}: the communication step H = {h:e} s is below the resolution of t = {t:e} s (there t + H == t in double precision): the FMU cannot advance"
    )]
    StepBelowResolution {
        /// The function's name.
        call: String,
        /// The step size given [s].
        h: f64,
        /// The communication point [s].
        t: f64,
    },
    /// A communication point that is not where the FMU is.
    #[error("{call} at currentCommunicationPoint = {t} s, but the FMU is at t = {at} s")]
    WrongTime {
        /// The function's name.
        call: String,
        /// The communication point given [s].
        t: f64,
        /// The FMU's time [s].
        at: f64,
    },
    /// A communication step past the stop time.
    #[error("{call} to t = {end} s passes stopTime = {stop} s")]
    PastStopTime {
        /// The function's name.
        call: String,
        /// The end of the step [s].
        end: f64,
        /// The experiment's stop time [s].
        stop: f64,
    },
    /// `fmi2GetFMUstate` in the error state.
    #[error("a state can be saved only outside the error state")]
    SaveInErrorState,
    /// A saved state that cannot be written as JSON.
    #[error("{0}")]
    StateJson(serde_json::Error),
    /// Bytes that are not a serialized state of this FMU's kind.
    #[error("not a serialized state of a phstring FMU ({0})")]
    NotSerializedState(serde_json::Error),
    /// A serialized state of another format (its name, clipped to 40 characters).
    #[error("not a serialized state of a phstring FMU (format {0:?})")]
    StateFormat(String),
    /// A serialized state whose checksum does not match.
    #[error("checksum mismatch: the serialized state was edited or damaged after it was written")]
    StateChecksum,
    /// A state handle that is not a live state of this FMU.
    #[error("not an FMU state of this FMU (already freed, or never given out by it)")]
    NotAState,
}

impl From<ScenarioError> for FmuError {
    fn from(e: ScenarioError) -> Self {
        Self::Scenario(e)
    }
}

impl From<SetupError> for FmuError {
    fn from(e: SetupError) -> Self {
        Self::Setup(e)
    }
}

impl From<InputError> for FmuError {
    fn from(e: InputError) -> Self {
        Self::Input(e)
    }
}

/// Why an FMU cannot be packaged.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PackageError {
    /// The FMU's file name is not a C identifier.
    #[error(
        "the FMU's file name {stem:?} must be a C identifier (letters, digits and _, not starting with a digit): FMI tools name the model's shared library after it"
    )]
    NotCIdentifier {
        /// The file name without `.fmu`.
        stem: String,
    },
    /// The FMU's file name is a name C or FMI reserves.
    #[error(
        "the FMU's file name {stem:?} {why}: as the model identifier it would break FMUs compiled from source or linked statically; choose another name"
    )]
    ReservedIdentifier {
        /// The file name without `.fmu`.
        stem: String,
        /// Why it is reserved.
        why: &'static str,
    },
    /// The FMI version names no binaries folder for this platform.
    #[error("FMI {version} names no binaries folder for this platform")]
    NoPlatform {
        /// `2.0` or `3.0`.
        version: &'static str,
    },
    /// The FMU library cannot be read.
    #[error("cannot read the FMU library {}: {cause}", path.display())]
    ReadLibrary {
        /// Its path.
        path: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// The FMU library is not a shared library of this platform exporting the FMI functions.
    #[error("the FMU library {} {what}", path.display())]
    Library {
        /// Its path.
        path: PathBuf,
        /// What is wrong (`is not a shared library …`, `does not export …`).
        what: String,
    },
    /// A data file the scenario reads (a table, a bathymetry grid) cannot be read to be
    /// packed into the FMU.
    #[error("cannot pack `{key}` = {} into the FMU: {cause}", path.display())]
    DataFile {
        /// The scenario key naming it.
        key: String,
        /// The file.
        path: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// The scenario with its data files renamed into the FMU does not parse (a bug).
    #[error("cannot point the FMU's scenario at its packed data files: {0}")]
    Rename(String),
    /// The archive cannot be built in memory.
    #[error("cannot build the archive of {}: {cause}", out.display())]
    Archive {
        /// The FMU's path.
        out: PathBuf,
        /// The zip writer's error.
        cause: std::io::Error,
    },
    /// The FMU cannot be written.
    #[error("cannot write {}: {cause}", out.display())]
    Write {
        /// The FMU's path.
        out: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
}
