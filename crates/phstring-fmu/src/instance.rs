//! One FMU instance: the FMI 2.0 Co-Simulation state machine over a `phstring::Simulation`,
//! in safe Rust (the C functions in `ffi` only convert arguments).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use phstring::{
    ByDim, FlatCheckpoint, InputError, Material, PositionRamp, SetupError, Simulation, StepError,
    Vector, by_dim,
};
use phstring_io::checkpoint::fnv1a64_hex;
use phstring_io::scenario::{Setup, StartError};
use serde::{Deserialize, Serialize};

use crate::error::FmuError;
use crate::model::{BodyValue, Causality, ModelSpec, Quantity, WinchValue};

/// A rigid body's wrench: force [N] and torque [N·m], space axes.
type Wrench = ([f64; 3], [f64; 3]);

/// FMI status of a call (`fmi2Status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `fmi2OK`.
    Ok = 0,
    /// `fmi2Warning`.
    Warning = 1,
    /// `fmi2Discard`: the step failed; the FMU stays at the last internal step it completed.
    Discard = 2,
    /// `fmi2Error`: the call failed and was not carried out; from here on the instance only
    /// accepts getters, a restore of a saved state (`fmi2SetFMUstate`), reset and free (the
    /// FMI state machine's error state, [`Mode::Error`]).
    Error = 3,
    /// `fmi2Fatal`.
    Fatal = 4,
}

/// Where the instance is in the FMI 2.0 Co-Simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mode {
    /// After `fmi2Instantiate`: parameters and inputs may be set.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initialization,
    /// Ready for `fmi2DoStep`.
    StepComplete,
    /// The last `fmi2DoStep` returned `fmi2Discard`.
    StepFailed,
    /// After `fmi2Terminate`.
    Terminated,
    /// After a call that returned `Error` (or `Fatal`): only getters, a restore of a saved
    /// state, reset and free are accepted.
    Error,
}

/// Receives the instance's log messages: status, category, message.
pub type Logger = Box<dyn Fn(Status, &str, &str) + Send>;

/// The path of a prescribed-motion input over the current communication step, as saved in
/// an FMU state: a [`PositionRamp`] from `from` at `t0` to `to` at `t1` at constant speed
/// [s, m].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ramp {
    t0: f64,
    t1: f64,
    from: f64,
    to: f64,
}

impl From<PositionRamp> for Ramp {
    fn from(r: PositionRamp) -> Self {
        Self {
            t0: r.t0,
            t1: r.t1,
            from: r.from,
            to: r.to,
        }
    }
}

impl From<Ramp> for PositionRamp {
    fn from(r: Ramp) -> Self {
        Self {
            t0: r.t0,
            t1: r.t1,
            from: r.from,
            to: r.to,
        }
    }
}

/// The simulation of the instance, in the scenario's dimension.
struct Stepper(AnySim);

/// A simulation of any dimension.
type AnySim = ByDim<Simulation<1, Material>, Simulation<2, Material>, Simulation<3, Material>>;

impl Stepper {
    fn time(&self) -> f64 {
        by_dim!(&self.0, s => s.time())
    }
    fn step_until(&mut self, t_end: f64) -> Result<(), StepError> {
        by_dim!(&mut self.0, s => s.step_until(t_end).map(|_| ()))
    }
    fn value(&self, q: Quantity) -> f64 {
        by_dim!(&self.0, s => value(s, q))
    }
    fn save(&self) -> FlatCheckpoint {
        by_dim!(&self.0, s => s.flat_checkpoint())
    }
    fn load(&mut self, state: &FlatCheckpoint) -> Result<(), SetupError> {
        by_dim!(&mut self.0, s => s.restore(state.to_checkpoint()))
    }
    /// Holds load `load`'s force at `force` [N] (its first `D` components).
    fn set_load_force(&mut self, load: usize, force: [f64; 3]) -> Result<(), InputError> {
        by_dim!(&mut self.0, s => s.set_load_force(load, Vector::from_fn(|i, _| force[i])))
    }
    /// Holds body `body`'s wrench port at `force` [N] and `torque` [N·m] (space axes).
    fn set_body_wrench(&mut self, body: usize, (force, torque): Wrench) -> Result<(), InputError> {
        let (f, t) = (force.into(), torque.into());
        by_dim!(&mut self.0, s => s.set_body_wrench(body, f, t))
    }
    /// Holds winch `winch`'s payout speed at `speed` [m/s] from the payout it has reached.
    fn set_winch_speed(&mut self, winch: usize, speed: f64) -> Result<(), InputError> {
        by_dim!(&mut self.0, s => s.set_winch_speed(winch, speed))
    }
    /// Ramps motion `motion` from where it is to `target` [m] at time `t_target` [s].
    fn set_motion_target(
        &mut self,
        motion: usize,
        target: f64,
        t_target: f64,
    ) -> Result<(), InputError> {
        by_dim!(&mut self.0, s => s.set_motion_target(motion, target, t_target).map(|_| ()))
    }
    /// Makes motion `motion` follow `ramp`.
    fn set_motion_ramp(&mut self, motion: usize, ramp: PositionRamp) -> Result<(), InputError> {
        by_dim!(&mut self.0, s => s.set_motion_ramp(motion, ramp))
    }
    /// Per motion: the ramp it follows, if it is an input.
    fn motion_ramps(&self) -> Vec<Option<PositionRamp>> {
        by_dim!(&self.0, s => (0..s.system().boundary().motions.len())
            .map(|k| s.motion_ramp(k))
            .collect())
    }
}

/// The value of output quantity `q` of `sim`.
fn value<const D: usize>(sim: &Simulation<D, Material>, q: Quantity) -> f64 {
    let e = sim.energies();
    match q {
        Quantity::PortOutput { port, component } => sim.ports()[port].output[component],
        Quantity::PortInput { port, component } => sim.ports()[port].input[component],
        Quantity::NodePosition { node, component } => sim.state().r[node][component],
        Quantity::Body {
            body,
            what,
            component,
        } => body_value(sim, body, what, component),
        Quantity::Winch { winch, what } => winch_value(sim, winch, what),
        Quantity::Hamiltonian => e.hamiltonian(),
        Quantity::Kinetic => e.kinetic,
        Quantity::Potential => e.potential(),
        Quantity::Supplied => sim.supplied_energy(),
        Quantity::Dissipated => sim.dissipated_energy(),
        // The balance needs `Ĥ(0)` (the instance's), parameters and inputs are the
        // instance's values.
        Quantity::BalanceError
        | Quantity::Parameter(_)
        | Quantity::LoadForce { .. }
        | Quantity::MotionPosition { .. }
        | Quantity::BodyForce { .. }
        | Quantity::BodyTorque { .. }
        | Quantity::WinchSpeed { .. } => f64::NAN,
    }
}

/// Value `what` of winch `winch` of `sim` after its last step (NaN if there is no such
/// winch).
fn winch_value<const D: usize>(
    sim: &Simulation<D, Material>,
    winch: usize,
    what: WinchValue,
) -> f64 {
    let Some(s) = sim.winch_samples().get(winch).copied() else {
        return f64::NAN;
    };
    match what {
        WinchValue::Payout => s.payout,
        WinchValue::Length => s.length,
        WinchValue::Speed => s.speed,
        WinchValue::Tension => s.tension,
        WinchValue::Power => s.power,
        WinchValue::Energy => s.energy,
    }
}

/// Component `component` of value `what` of rigid body `body` of `sim` (NaN if there is no
/// such body).
fn body_value<const D: usize>(
    sim: &Simulation<D, Material>,
    body: usize,
    what: BodyValue,
    component: usize,
) -> f64 {
    let (Some(st), Some(port)) = (sim.state().bodies.get(body), sim.body_ports().get(body)) else {
        return f64::NAN;
    };
    let q = st.orientation.quaternion();
    match what {
        BodyValue::Position => st.position[component],
        BodyValue::Orientation => [q.w, q.i, q.j, q.k][component],
        // The angle of a turn about z, from the quaternion's rotation matrix entries
        // (either sign of the quaternion gives the same angle).
        BodyValue::Angle => {
            (2.0 * (q.w * q.k + q.i * q.j)).atan2(1.0 - 2.0 * (q.j * q.j + q.k * q.k))
        }
        BodyValue::Velocity => st.velocity[component],
        BodyValue::AngularVelocity => st.omega_space()[component],
        BodyValue::MidVelocity => port.velocity[component],
        BodyValue::MidAngularVelocity => port.omega[component],
        BodyValue::ReactionForce => port.force[component],
        BodyValue::ReactionTorque => port.torque[component],
    }
}

/// The simulation with what the instance keeps beside it.
struct Live {
    /// The simulation; it holds the inputs (`phstring::inputs`).
    stepper: Stepper,
    /// `Ĥ(0)` [J], the reference of `balance_error`.
    h0: f64,
    /// The first failure of a scenario expression during the run.
    expression_error: Arc<Mutex<Option<String>>>,
    /// After `fmi2SetFMUstate`: the port variables' values at the saved point, by value
    /// reference, served until the next internal step (the simulation's port samples are
    /// those of its last step, not part of its checkpoint).
    ports_saved: Option<Vec<Option<f64>>>,
}

impl Live {
    /// The value of output quantity `q`.
    fn value(&self, q: Quantity) -> f64 {
        match q {
            Quantity::BalanceError => {
                let s = &self.stepper;
                s.value(Quantity::Hamiltonian) - self.h0 - s.value(Quantity::Supplied)
                    + s.value(Quantity::Dissipated)
            }
            _ => self.stepper.value(q),
        }
    }
}

/// A saved FMU state (`fmi2GetFMUstate`): the simulation's checkpoint and the instance's
/// own values, serializable to JSON (bit for bit: floats in round-trip form).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Saved {
    /// The FMU's GUID (instantiation token): a state restores only into its own FMU.
    guid: String,
    mode: Mode,
    values: Vec<f64>,
    start_time: f64,
    stop_time: Option<f64>,
    /// The master's time [s].
    time: f64,
    ramps: Vec<Option<Ramp>>,
    /// The port variables' values by value reference (`None` for the others).
    ports: Vec<Option<f64>>,
    sim: Option<FlatCheckpoint>,
    /// `Ĥ(0)` of the run [J] (it depends on the inputs a starting equilibrium was found for).
    h0: Option<f64>,
}

/// Format name of a serialized FMU state.
const STATE_FORMAT: &str = "phstring-fmu-state";

/// A serialized [`Saved`] as written: the state with its checksum beside it.
#[derive(Serialize)]
struct SealedRef<'a> {
    format: &'a str,
    checksum: &'a str,
    state: &'a Saved,
}

/// A serialized [`Saved`] as read.
#[derive(Deserialize)]
struct Sealed {
    format: String,
    checksum: String,
    state: Saved,
}

impl Saved {
    /// The serialized form (`fmi2SerializeFMUstate`): JSON `{"format", "checksum",
    /// "state"}`, floats in round-trip form; the checksum is FNV-1a (64 bit, hex, as in
    /// `checkpoint.json`) over the state's JSON, so any edited value is detected on reading.
    pub fn to_bytes(&self) -> Result<Vec<u8>, FmuError> {
        let state = serde_json::to_vec(self).map_err(FmuError::StateJson)?;
        serde_json::to_vec(&SealedRef {
            format: STATE_FORMAT,
            checksum: &fnv1a64_hex(&state),
            state: self,
        })
        .map_err(FmuError::StateJson)
    }

    /// A state from its serialized form ([`Self::to_bytes`]); an error says what is wrong
    /// (not a state of phstring's FMU, or edited or damaged since it was serialized).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FmuError> {
        let sealed: Sealed = serde_json::from_slice(bytes).map_err(FmuError::NotSerializedState)?;
        if sealed.format != STATE_FORMAT {
            return Err(FmuError::StateFormat(
                sealed.format.chars().take(40).collect(),
            ));
        }
        let state = serde_json::to_vec(&sealed.state).map_err(FmuError::StateJson)?;
        if fnv1a64_hex(&state) != sealed.checksum {
            return Err(FmuError::StateChecksum);
        }
        Ok(sealed.state)
    }
}

/// One FMU instance.
pub struct Instance {
    name: String,
    log: Logger,
    logging_on: bool,
    /// The scenario as packaged.
    text: String,
    /// Its path, for messages (inside the FMU's resources).
    path: PathBuf,
    spec: ModelSpec,
    /// Current values of parameters and inputs, by value reference (outputs unused).
    values: Vec<f64>,
    mode: Mode,
    start_time: f64,
    stop_time: Option<f64>,
    /// The master's time: the end of the last communication step [s].
    time: f64,
    live: Option<Live>,
    /// The FMI version of the calls, for messages.
    api: Api,
    /// The value reference of the parameter `h`.
    h_vr: Option<usize>,
}

/// The FMI version an instance is called through (for the function names in messages).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Api {
    /// FMI 2.0 (`fmi2DoStep`, …).
    Fmi2,
    /// FMI 3.0 (`fmi3DoStep`, …).
    Fmi3,
}

/// Tolerance [s] for times near `t` [s] in a run with steps `h` [s]: the library's landing
/// rule (`1e-9 h`) plus a few units of rounding of `t` itself.
fn time_tol(h: f64, t: f64) -> f64 {
    1e-9 * h + 8.0 * f64::EPSILON * t.abs()
}

/// Whether `q` is read from the simulation's port samples, values of its last step that its
/// checkpoint does not hold (the string's ports, the bodies' wrench ports, the winches'
/// speed and power).
fn is_port(q: Quantity) -> bool {
    use BodyValue::*;
    match q {
        Quantity::PortOutput { .. } | Quantity::PortInput { .. } => true,
        Quantity::Winch { what, .. } => matches!(what, WinchValue::Speed | WinchValue::Power),
        Quantity::Body { what, .. } => matches!(
            what,
            MidVelocity | MidAngularVelocity | ReactionForce | ReactionTorque
        ),
        _ => false,
    }
}

/// A failed call: its status and the message logged.
type Fail = (Status, String);

impl Instance {
    /// An instance of the scenario `text` (read from `path`) whose variables must hash to
    /// `guid`. Errors say why the instance cannot be made.
    pub fn new(
        name: &str,
        guid: &str,
        text: String,
        path: PathBuf,
        log: Logger,
        logging_on: bool,
    ) -> Result<Self, FmuError> {
        let file = phstring_io::scenario::parse(&text, &path, &[])?;
        let spec = ModelSpec::new(&file)?;
        if spec.guid != guid {
            return Err(FmuError::GuidMismatch {
                given: guid.into(),
                expected: spec.guid,
            });
        }
        let values = spec
            .variables
            .iter()
            .map(|v| v.start.unwrap_or(0.0))
            .collect();
        Ok(Self {
            name: name.to_string(),
            log,
            logging_on,
            text,
            path,
            values,
            mode: Mode::Instantiated,
            start_time: 0.0,
            stop_time: None,
            time: 0.0,
            live: None,
            api: Api::Fmi2,
            h_vr: spec.variables.iter().position(|v| {
                matches!(v.quantity, Quantity::Parameter(k) if spec.parameters[k].key == "time.h")
            }),
            spec,
        })
    }

    /// The instance name given at instantiation.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The variables.
    pub fn spec(&self) -> &ModelSpec {
        &self.spec
    }

    /// The state-machine mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The FMI version the instance is called through (FMI 2.0 unless set).
    pub fn set_api(&mut self, api: Api) {
        self.api = api;
    }

    /// The name of FMI function `name` (`DoStep`) in the instance's version.
    fn call(&self, name: &str) -> String {
        match (self.api, name) {
            (Api::Fmi2, _) => format!("fmi2{name}"),
            (Api::Fmi3, "SetupExperiment") => "fmi3EnterInitializationMode".into(),
            (Api::Fmi3, "SetReal") => "fmi3SetFloat64".into(),
            (Api::Fmi3, "SetFMUstate") => "fmi3SetFMUState".into(),
            (Api::Fmi3, _) => format!("fmi3{name}"),
        }
    }

    /// Replaces the logger.
    pub fn set_log(&mut self, log: Logger, logging_on: bool) {
        self.log = log;
        self.logging_on = logging_on;
    }

    /// Logs `message` as an error and returns `Error`: the call is not carried out, and the
    /// instance goes to the error state ([`Mode::Error`]) with its simulation as it was.
    pub fn refused(&mut self, message: &str) -> Status {
        self.refuse(message.to_string())
    }

    /// Turns informational logging on or off (errors and discards are always logged).
    pub fn set_logging(&mut self, on: bool) {
        self.logging_on = on;
    }

    /// Logs `message` under `category`.
    pub fn log(&self, status: Status, category: &str, message: &str) {
        if self.logging_on || status != Status::Ok {
            (self.log)(status, category, message);
        }
    }

    /// Logs a failure and returns its status; an `Error` ends the run.
    fn fail(&mut self, (status, message): Fail) -> Status {
        let category = if status == Status::Discard {
            "logStatusDiscard"
        } else {
            "logStatusError"
        };
        self.log(status, category, &message);
        if status == Status::Error || status == Status::Fatal {
            self.mode = Mode::Error;
        }
        status
    }

    /// A refused call (bad arguments, wrong mode): nothing of it is carried out, and the
    /// instance goes to the error state, as FMI prescribes after `fmi2Error` (a master that
    /// ignores the status must not get a run that silently differs from what it asked for).
    /// The simulation stays as it was, so a restore of a saved state continues from there.
    fn refuse(&mut self, message: String) -> Status {
        let message = format!(
            "{message}; the instance is in the error state: restore a saved FMU state with {}, or reset it",
            self.call("SetFMUstate")
        );
        self.log(Status::Error, "logStatusError", &message);
        self.mode = Mode::Error;
        Status::Error
    }

    /// `fmi2SetupExperiment`: the scenario's `t = 0` is `start` [s]; `stop` [s], if given,
    /// is the last communication point.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Status {
        if self.mode != Mode::Instantiated {
            return self.refuse(format!(
                "{} (the experiment's start and stop) is allowed only right after instantiation (the instance is {:?})",
                self.call("SetupExperiment"),
                self.mode
            ));
        }
        if !start.is_finite() {
            return self.refuse(format!("startTime must be finite, got {start}"));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s >= start)
        {
            return self.refuse(format!(
                "stopTime must be finite and not before startTime = {start} s, got {s}"
            ));
        }
        self.start_time = start;
        self.stop_time = stop;
        self.time = start;
        Status::Ok
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Status {
        if self.mode != Mode::Instantiated {
            return self.refuse(format!(
                "{} is allowed only after instantiation (the instance is {:?})",
                self.call("EnterInitializationMode"),
                self.mode
            ));
        }
        self.mode = Mode::Initialization;
        Status::Ok
    }

    /// `fmi2ExitInitializationMode`: sets up the simulation with the parameters.
    pub fn exit_initialization(&mut self) -> Status {
        if self.mode != Mode::Initialization {
            return self.refuse(format!(
                "{} is allowed only in initialization mode (the instance is {:?})",
                self.call("ExitInitializationMode"),
                self.mode
            ));
        }
        if let Some(stop) = self.stop_time {
            let (h, span) = (self.step_size(&self.values), stop - self.start_time);
            if h > span + time_tol(span, stop) {
                return self.fail((
                    Status::Error,
                    format!(
                        "the parameter h = {h} s (the internal step) is longer than the experiment, {span} s from startTime = {} s to stopTime = {stop} s: set h to at most {span} s",
                        self.start_time
                    ),
                ));
            }
        }
        if let Err(e) = self.ensure_live() {
            return self.fail(e);
        }
        self.mode = Mode::StepComplete;
        self.log(
            Status::Ok,
            "logEvents",
            &format!(
                "{}: set up ({} variables), starting at t = {} s",
                self.name,
                self.spec.variables.len(),
                self.start_time
            ),
        );
        Status::Ok
    }

    /// Sets up the simulation if it is not yet (parameters are final from here on).
    fn ensure_live(&mut self) -> Result<(), Fail> {
        if self.live.is_none() {
            self.live = Some(self.build_live(&self.values, true)?);
        }
        Ok(())
    }

    /// A simulation of the packaged scenario with the parameters and inputs in `values` (by
    /// value reference), at its starting equilibrium if the scenario asks for one and
    /// `equilibrium` is set.
    fn build_live(&self, values: &[f64], equilibrium: bool) -> Result<Live, Fail> {
        let mut sets = Vec::new();
        for (vr, v) in self.spec.variables.iter().enumerate() {
            if let Quantity::Parameter(k) = v.quantity {
                let p = &self.spec.parameters[k];
                let x = values[vr];
                if x.to_bits() != p.value.to_bits() {
                    sets.push(format!("{}={x:?}", p.key));
                }
            }
        }
        // The master chooses the stop time; `time.end` only has to fit the step size (a
        // whole number of steps), so it moves to the nearest multiple of a changed `h`.
        let h = self.step_size(values);
        if h.to_bits() != self.spec.h.to_bits() {
            let n = (self.spec.t_end / h).round().max(1.0);
            sets.push(format!("time.end={:?}", n * h));
        }
        let error = |e: FmuError| {
            let e = if sets.is_empty() {
                e
            } else {
                FmuError::ParametersDoNotFit {
                    sets: sets.join(", "),
                    cause: Box::new(e),
                }
            };
            (Status::Error, e.to_string())
        };
        let file = phstring_io::scenario::parse(&self.text, &self.path, &sets)
            .map_err(|e| error(e.into()))?;
        let setup = file.setup().map_err(|e| error(e.into()))?;
        if setup.dimension() != self.spec.dimension {
            return Err(error(FmuError::DimensionChanged {
                expected: self.spec.dimension,
                got: setup.dimension(),
            }));
        }
        let expression_error = by_dim!(&setup, v => v.load_error.clone());
        let sim = by_dim!(map setup, v => self.start(v, values, equilibrium))
            .transpose()
            .map_err(&error)?;
        let stepper = Stepper(sim);
        Ok(Live {
            h0: stepper.value(Quantity::Hamiltonian),
            stepper,
            expression_error,
            ports_saved: None,
        })
    }

    /// The simulation of `v` with the inputs `values` held, started at the equilibrium
    /// under them if `equilibrium` (and `initial.equilibrium`).
    fn start<const D: usize>(
        &self,
        mut v: Setup<D>,
        values: &[f64],
        equilibrium: bool,
    ) -> Result<Simulation<D, Material>, FmuError> {
        // The inputs are held on the system already: the starting equilibrium and the
        // supports' velocities at `t = 0` are those under the inputs.
        let system = &mut v.problem.system;
        let forces = input_forces(&self.spec, values);
        for (&load, u) in &forces {
            system.hold_load_force(load, Vector::<D>::from_fn(|i, _| u[i]))?;
        }
        let wrenches = input_wrenches(&self.spec, values);
        for (&body, (f, t)) in &wrenches {
            system.hold_body_wrench(body, (*f).into(), (*t).into())?;
        }
        // Until the first step, the support rests where the scenario starts it.
        let mut rests = Vec::new();
        for (motion, _) in input_positions(&self.spec, values) {
            let at_zero = system
                .boundary()
                .motions
                .get(motion)
                .map_or(f64::NAN, |m| (m.position)(0.0));
            let rest = PositionRamp::at(at_zero);
            system.hold_motion(motion, rest)?;
            rests.push((motion, rest));
        }
        // With `initial.equilibrium`, the equilibrium under the load and wrench inputs as set
        // now (the supports at their scenario positions).
        let (v, _) = v.start(equilibrium, None).map_err(|e| match e {
            StartError::Setup(e) => FmuError::Setup(e),
            e => FmuError::Equilibrium { cause: Box::new(e) },
        })?;
        let mut sim = v.problem;
        // The simulation holds the same inputs from here on (its signals do not change).
        for (&load, u) in &forces {
            sim.set_load_force(load, Vector::<D>::from_fn(|i, _| u[i]))?;
        }
        for (&body, (f, t)) in &wrenches {
            sim.set_body_wrench(body, (*f).into(), (*t).into())?;
        }
        for (motion, rest) in rests {
            sim.set_motion_ramp(motion, rest)?;
        }
        for (winch, speed) in input_speeds(&self.spec, values) {
            sim.set_winch_speed(winch, speed)?;
        }
        Ok(sim)
    }

    /// `fmi2SetReal`: parameters before initialization ends, inputs at any time before
    /// termination except after a discarded step. A refused value leaves everything as it
    /// was.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if matches!(self.mode, Mode::StepFailed | Mode::Terminated | Mode::Error) {
            return self.refuse(format!(
                "{} is not allowed now (the instance is {:?})",
                self.call("SetReal"),
                self.mode,
            ));
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            let Some(var) = self.spec.variables.get(vr as usize) else {
                return self.refuse(format!(
                    "value reference {vr} does not exist (0 … {})",
                    self.spec.variables.len().saturating_sub(1)
                ));
            };
            let name = &var.name;
            match var.causality {
                Causality::Output => {
                    return self.refuse(format!("{name} is an output and cannot be set"));
                }
                Causality::Parameter => {
                    if !matches!(self.mode, Mode::Instantiated | Mode::Initialization) {
                        return self.refuse(format!(
                            "{name} is a fixed parameter: it can be set only before {}",
                            self.call("ExitInitializationMode")
                        ));
                    }
                    if !(x > 0.0 && x.is_finite()) {
                        return self.refuse(format!(
                            "{name} = {x} must be positive and finite ({} [{}])",
                            var.description, var.unit
                        ));
                    }
                }
                Causality::Input => {
                    if !x.is_finite() {
                        return self.refuse(format!("input {name} = {x} must be finite"));
                    }
                }
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            self.values[vr as usize] = x;
        }
        // Before initialization ends the simulation is set up anew with these values (a
        // parameter changes the system; an input changes a starting equilibrium).
        if matches!(self.mode, Mode::Instantiated | Mode::Initialization) {
            self.live = None;
        }
        Status::Ok
    }

    /// `fmi2GetReal`: parameters and inputs at any time; outputs from initialization mode
    /// on (and in the error state, for a look at where the run stopped).
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        let needs_live = vrs.iter().any(|&vr| {
            self.spec
                .variables
                .get(vr as usize)
                .is_some_and(|v| v.causality == Causality::Output)
        });
        if needs_live {
            match self.mode {
                Mode::Instantiated => {
                    return self.refuse(format!(
                        "outputs can be read from {} on",
                        self.call("EnterInitializationMode")
                    ));
                }
                Mode::Error | Mode::Terminated => {}
                _ => {
                    // A parameter that does not fit is refused here (FMI's error state
                    // follows: the master resets the instance and sets another value).
                    if let Err((_, m)) = self.ensure_live() {
                        return self.refuse(m);
                    }
                }
            }
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let Some(var) = self.spec.variables.get(vr as usize) else {
                return self.refuse(format!(
                    "value reference {vr} does not exist (0 … {})",
                    self.spec.variables.len().saturating_sub(1)
                ));
            };
            *slot = match (var.causality, &self.live) {
                (Causality::Output, Some(l)) => match &l.ports_saved {
                    Some(saved) if is_port(var.quantity) => saved[vr as usize].unwrap_or(f64::NAN),
                    _ => l.value(var.quantity),
                },
                (Causality::Output, None) => f64::NAN,
                _ => self.values[vr as usize],
            };
        }
        Status::Ok
    }

    /// The internal step size `h` [s] in `values` (by value reference).
    fn step_size(&self, values: &[f64]) -> f64 {
        self.h_vr.map_or(self.spec.h, |vr| values[vr])
    }

    /// The time the FMU is at, on the master's clock [s]: the end of the last communication
    /// step, or after a step that failed the last internal step completed.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The landing tolerance of `fmi2DoStep(t, H)` [s]: how far the FMU's time may be from
    /// the master's `t` (and the end of the step from `stopTime`) by rounding. It scales with
    /// the step actually asked for, `min(h, H)`, so that a huge parameter `h` cannot make a
    /// whole communication step look like rounding.
    fn landing_tol(&self, t: f64, comm_h: f64) -> f64 {
        let h = self.step_size(&self.values).min(comm_h);
        // Times are compared on the master's clock, rounding included (start time and all).
        time_tol(h, t.abs().max(self.start_time.abs()) + comm_h)
    }

    /// Why `fmi2DoStep(t, comm_h)` cannot be carried out, if it cannot.
    fn check_step(&self, t: f64, comm_h: f64) -> Result<(), FmuError> {
        let call = || self.call("DoStep");
        if self.mode != Mode::StepComplete {
            return Err(FmuError::StepNotAllowed {
                call: call(),
                mode: format!("{:?}", self.mode),
            });
        }
        if !(comm_h > 0.0 && comm_h.is_finite()) {
            return Err(FmuError::StepSize { h: comm_h });
        }
        if t + comm_h == t {
            return Err(FmuError::StepBelowResolution {
                call: call(),
                h: comm_h,
                t,
            });
        }
        let tol = self.landing_tol(t, comm_h);
        let off = (t - self.time).abs();
        if off.is_nan() || off > tol {
            return Err(FmuError::WrongTime {
                call: call(),
                t,
                at: self.time,
            });
        }
        if let Some(stop) = self.stop_time
            && t + comm_h > stop + tol
        {
            return Err(FmuError::PastStopTime {
                call: call(),
                end: t + comm_h,
                stop,
            });
        }
        Ok(())
    }

    /// `fmi2DoStep(t, H)`: internal steps of at most the parameter `h` to reach `t + H`,
    /// with the inputs held at the values set before the call. `Ok` only when the simulation
    /// reached `t + H` (up to the landing tolerance); `Discard` if a step fails (the FMU stays
    /// at the last internal step it completed); `Error` for calls that do not fit (wrong `t`,
    /// `H ≤ 0`, past the stop time, `H` below the resolution of `t`, so that the simulation
    /// would not move) and for failing scenario expressions.
    pub fn do_step(&mut self, t: f64, comm_h: f64) -> Status {
        if let Err(e) = self.check_step(t, comm_h) {
            return self.refuse(e.to_string());
        }
        let tol = self.landing_tol(t, comm_h);
        let target = t - self.start_time + comm_h;
        let (api, start_time) = (self.api, self.start_time);
        let Some(live) = self.live.as_mut() else {
            return self.fail((Status::Error, "the simulation is not set up".into()));
        };
        if live.stepper.time() >= target - tol {
            let step = self.call("DoStep");
            return self.refuse(format!(
                "{step}: the communication step H = {comm_h:e} s from t = {t} s is below the resolution of the FMU's time there ({tol:.1e} s): the simulation would not move"
            ));
        }
        let failure = match hold_inputs(&self.spec, &self.values, live, target) {
            Ok(()) => step_to(live, target, tol, api, start_time),
            Err(e) => Some((Status::Error, FmuError::from(e).to_string())),
        };
        match failure {
            None => {
                self.time = t + comm_h;
                Status::Ok
            }
            Some(f) => {
                // The FMU is where its last internal step ended.
                self.time = start_time + live.stepper.time();
                if f.0 == Status::Discard {
                    self.mode = Mode::StepFailed;
                }
                self.fail(f)
            }
        }
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        if !matches!(self.mode, Mode::StepComplete | Mode::StepFailed) {
            return self.refuse(format!(
                "{} is allowed only after initialization (the instance is {:?})",
                self.call("Terminate"),
                self.mode
            ));
        }
        self.mode = Mode::Terminated;
        Status::Ok
    }

    /// `fmi2Reset`: back to the state right after instantiation.
    pub fn reset(&mut self) -> Status {
        self.values = self
            .spec
            .variables
            .iter()
            .map(|v| v.start.unwrap_or(0.0))
            .collect();
        self.mode = Mode::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
        self.time = 0.0;
        self.live = None;
        Status::Ok
    }

    /// Puts the instance in the error state after an internal failure (a caught panic):
    /// only getters, reset and free remain.
    pub fn poison(&mut self) {
        self.mode = Mode::Error;
    }

    /// `fmi2GetFMUstate`: everything needed to continue from here (bit for bit). Refused in
    /// the error state (FMI restores only states saved outside it).
    pub fn save(&self) -> Result<Saved, FmuError> {
        if self.mode == Mode::Error {
            return Err(FmuError::SaveInErrorState);
        }
        let ports = self
            .spec
            .variables
            .iter()
            .enumerate()
            .map(|(vr, v)| match &self.live {
                Some(l) if is_port(v.quantity) => match &l.ports_saved {
                    Some(saved) => saved[vr],
                    None => Some(l.value(v.quantity)),
                },
                _ => None,
            })
            .collect();
        Ok(Saved {
            guid: self.spec.guid.clone(),
            mode: self.mode,
            values: self.values.clone(),
            start_time: self.start_time,
            stop_time: self.stop_time,
            time: self.time(),
            ramps: self.live.as_ref().map_or_else(Vec::new, |l| {
                let ramps = l.stepper.motion_ramps();
                ramps.into_iter().map(|r| r.map(Ramp::from)).collect()
            }),
            ports,
            sim: self.live.as_ref().map(|l| l.stepper.save()),
            h0: self.live.as_ref().map(|l| l.h0),
        })
    }

    /// `fmi2SetFMUstate`: continues from `saved`, taken from an instance of the same FMU.
    /// If it cannot be restored, the instance stays as it was.
    pub fn restore(&mut self, saved: &Saved) -> Status {
        if saved.guid != self.spec.guid {
            return self.refuse(format!(
                "the FMU state is of another FMU (GUID {}, this one {})",
                saved.guid, self.spec.guid
            ));
        }
        let n = self.values.len();
        if saved.values.len() != n || saved.ports.len() != n {
            return self.refuse(format!(
                "the FMU state has {} values, this FMU {n}: it is of another FMU",
                saved.values.len()
            ));
        }
        let live = match &saved.sim {
            None => None,
            Some(state) => {
                // After an internal failure the running simulation is not trusted.
                let same_parameters = self.live.is_some()
                    && self.mode != Mode::Error
                    && self
                        .spec
                        .variables
                        .iter()
                        .zip(self.values.iter().zip(&saved.values))
                        .all(|(v, (a, b))| {
                            v.causality != Causality::Parameter || a.to_bits() == b.to_bits()
                        });
                // The running simulation if its parameters are the saved ones (kept as it is
                // until the saved state is in), else a new one with the saved parameters.
                let mut live = match same_parameters {
                    true => None,
                    // The saved state replaces the starting state: no equilibrium solve.
                    false => match self.build_live(&saved.values, false) {
                        Ok(l) => Some(l),
                        Err((_, m)) => {
                            return self.refuse(format!("cannot restore the FMU state: {m}"));
                        }
                    },
                };
                let target = match live.as_mut() {
                    Some(l) => l,
                    None => self.live.as_mut().expect("checked above"),
                };
                let before = target.stepper.save();
                let ramps_before = target.stepper.motion_ramps();
                let ramps: Vec<_> = saved
                    .ramps
                    .iter()
                    .map(|r| r.map(PositionRamp::from))
                    .collect();
                let loaded = match target.stepper.load(state) {
                    Ok(()) => set_ramps(&mut target.stepper, &ramps).map_err(FmuError::from),
                    Err(e) => Err(e.into()),
                };
                if let Err(m) = loaded {
                    // A failed load may have changed the running simulation: put it back.
                    let _ = target.stepper.load(&before);
                    let _ = set_ramps(&mut target.stepper, &ramps_before);
                    return self.refuse(format!("cannot restore the FMU state: {m}"));
                }
                target.ports_saved = Some(saved.ports.clone());
                if let Some(h0) = saved.h0 {
                    target.h0 = h0;
                }
                Some(live.unwrap_or_else(|| self.live.take().expect("checked above")))
            }
        };
        self.live = live;
        self.values = saved.values.clone();
        self.mode = saved.mode;
        self.start_time = saved.start_time;
        self.stop_time = saved.stop_time;
        self.time = saved.time;
        Status::Ok
    }
}

/// Per load that is an input: the force [N] its variables in `values` (by value reference)
/// hold it at, components that are not variables 0.
fn input_forces(spec: &ModelSpec, values: &[f64]) -> BTreeMap<usize, [f64; 3]> {
    let mut forces = BTreeMap::new();
    for (vr, var) in spec.variables.iter().enumerate() {
        if let Quantity::LoadForce { load, component } = var.quantity {
            forces.entry(load).or_insert([0.0; 3])[component] = values[vr];
        }
    }
    forces
}

/// Per body whose wrench port is an input: the force [N] and torque [N·m] its variables in
/// `values` (by value reference) hold it at, components that are not variables 0.
fn input_wrenches(spec: &ModelSpec, values: &[f64]) -> BTreeMap<usize, Wrench> {
    let mut wrenches = BTreeMap::<usize, Wrench>::new();
    for (vr, var) in spec.variables.iter().enumerate() {
        match var.quantity {
            Quantity::BodyForce { body, component } => {
                wrenches.entry(body).or_default().0[component] = values[vr];
            }
            Quantity::BodyTorque { body, component } => {
                wrenches.entry(body).or_default().1[component] = values[vr];
            }
            _ => {}
        }
    }
    wrenches
}

/// Per winch whose payout speed is an input: its index and the speed [m/s] its variable in
/// `values` (by value reference) holds.
fn input_speeds(spec: &ModelSpec, values: &[f64]) -> Vec<(usize, f64)> {
    let winches = spec.variables.iter().enumerate();
    winches
        .filter_map(|(vr, var)| match var.quantity {
            Quantity::WinchSpeed { winch } => Some((winch, values[vr])),
            _ => None,
        })
        .collect()
}

/// Per motion that is an input: its index and the position [m] its variable in `values`
/// (by value reference) asks for.
fn input_positions(spec: &ModelSpec, values: &[f64]) -> Vec<(usize, f64)> {
    let motions = spec.variables.iter().enumerate();
    motions
        .filter_map(|(vr, var)| match var.quantity {
            Quantity::MotionPosition { motion } => Some((motion, values[vr])),
            _ => None,
        })
        .collect()
}

/// Holds the inputs of `spec` (values `values`, by value reference) over the communication
/// step from the simulation's time to `target` [s]: load forces, body wrenches and winch
/// speeds at their values (a winch's payout continuing from where it is), motions on a ramp
/// from where they are to their values.
fn hold_inputs(
    spec: &ModelSpec,
    values: &[f64],
    live: &mut Live,
    target: f64,
) -> Result<(), InputError> {
    for (load, u) in input_forces(spec, values) {
        live.stepper.set_load_force(load, u)?;
    }
    for (body, wrench) in input_wrenches(spec, values) {
        live.stepper.set_body_wrench(body, wrench)?;
    }
    for (winch, speed) in input_speeds(spec, values) {
        live.stepper.set_winch_speed(winch, speed)?;
    }
    for (motion, x) in input_positions(spec, values) {
        live.stepper.set_motion_target(motion, x, target)?;
    }
    Ok(())
}

/// Puts `ramps` (per motion, as saved) back on the motions of `stepper` that follow one.
fn set_ramps(stepper: &mut Stepper, ramps: &[Option<PositionRamp>]) -> Result<(), InputError> {
    let now = stepper.motion_ramps();
    for (motion, (now, saved)) in now.iter().zip(ramps).enumerate() {
        if let (Some(_), Some(ramp)) = (now, saved) {
            stepper.set_motion_ramp(motion, *ramp)?;
        }
    }
    Ok(())
}

/// Steps `live` until it is within `tol` [s] of `target` [s] (simulation time); the failure,
/// if a step fails or does not advance (messages in the times of the master, whose clock
/// starts at `start_time` [s]).
fn step_to(live: &mut Live, target: f64, tol: f64, api: Api, start_time: f64) -> Option<Fail> {
    while live.stepper.time() < target - tol {
        let before = live.stepper.time();
        match live.stepper.step_until(target) {
            Ok(()) if live.stepper.time() > before => live.ports_saved = None,
            Ok(()) => {
                return Some((
                    Status::Error,
                    format!(
                        "the internal step from t = {} s did not advance the simulation (below the resolution of its time)",
                        start_time + before
                    ),
                ));
            }
            Err(e) => {
                if let Some(why) = lock(&live.expression_error).take() {
                    return Some((
                        Status::Error,
                        format!("{e}; a scenario expression failed: {why}"),
                    ));
                }
                let last = match api {
                    Api::Fmi2 => "fmi2GetRealStatus(fmi2LastSuccessfulTime)",
                    Api::Fmi3 => "lastSuccessfulTime of fmi3DoStep",
                };
                return Some((
                    Status::Discard,
                    format!(
                        "{e}; the FMU stays at t = {} s, the last internal step it completed ({last})",
                        start_time + live.stepper.time()
                    ),
                ));
            }
        }
    }
    None
}

/// Locks `m`; a poisoned lock is still usable (a panicking step leaves nothing half-set
/// that the next call reads).
pub(crate) fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}
