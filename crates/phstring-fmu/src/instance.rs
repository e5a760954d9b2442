//! One FMU instance: the FMI 2.0 Co-Simulation state machine over a `phstring::Simulation`,
//! in safe Rust (the C functions in `ffi` only convert arguments).

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use phstring::{Material, Simulation, StepError, Vector};
use phstring_io::checkpoint::SimState;
use phstring_io::scenario::{ScenarioFile, Validated};
use serde::{Deserialize, Serialize};

use crate::model::{Causality, ModelSpec, Quantity};

/// FMI status of a call (`fmi2Status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `fmi2OK`.
    Ok = 0,
    /// `fmi2Warning`.
    Warning = 1,
    /// `fmi2Discard`: the step failed; the FMU stays at the last internal step it completed.
    Discard = 2,
    /// `fmi2Error`: the call failed; the instance can only be reset or freed (or, after a
    /// refused value, the call is simply not carried out, see the method's doc).
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
    /// After an error that ends the run.
    Error,
}

/// Receives the instance's log messages: status, category, message.
pub type Logger = Box<dyn Fn(Status, &str, &str) + Send>;

/// A load's force while it is an FMU input [N] (zero-order hold).
type Held = Arc<Mutex<[f64; 3]>>;

/// The path of a prescribed-motion input over the current communication step: from `from`
/// at `t0` to `to` at `t1` at constant speed [s, m].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ramp {
    t0: f64,
    t1: f64,
    from: f64,
    to: f64,
}

impl Ramp {
    /// Resting at `x` [m].
    fn at(x: f64) -> Self {
        Self {
            t0: 0.0,
            t1: 0.0,
            from: x,
            to: x,
        }
    }
    /// Position at time `t` [s]; a step that ends within `1e-9` of the communication step
    /// of its end (rounding of the step's end time) ends at `to` exactly.
    fn position(&self, t: f64) -> f64 {
        if t >= self.t1 - 1e-9 * (self.t1 - self.t0) {
            self.to
        } else if t <= self.t0 {
            self.from
        } else {
            self.from + (self.to - self.from) * ((t - self.t0) / (self.t1 - self.t0))
        }
    }
}

/// What the instance needs of a simulation of any dimension.
trait Stepper: Send {
    fn time(&self) -> f64;
    fn step_until(&mut self, t_end: f64) -> Result<(), StepError>;
    fn value(&self, q: Quantity) -> f64;
    fn save(&self) -> SimState;
    fn load(&mut self, s: &SimState) -> Result<(), String>;
}

/// A running simulation of dimension `D` with its initial Hamiltonian.
struct Running<const D: usize> {
    sim: Simulation<D, Material>,
    h0: f64,
}

impl<const D: usize> Stepper for Running<D> {
    fn time(&self) -> f64 {
        self.sim.time()
    }
    fn step_until(&mut self, t_end: f64) -> Result<(), StepError> {
        self.sim.step_until(t_end).map(|_| ())
    }
    fn value(&self, q: Quantity) -> f64 {
        let e = self.sim.energies();
        match q {
            Quantity::PortOutput { port, component } => self.sim.ports()[port].output[component],
            Quantity::PortInput { port, component } => self.sim.ports()[port].input[component],
            Quantity::NodePosition { node, component } => self.sim.state().r[node][component],
            Quantity::Hamiltonian => e.hamiltonian(),
            Quantity::Kinetic => e.kinetic,
            Quantity::Potential => e.potential(),
            Quantity::Supplied => self.sim.supplied_energy(),
            Quantity::Dissipated => self.sim.dissipated_energy(),
            Quantity::BalanceError => {
                e.hamiltonian() - self.h0 - self.sim.supplied_energy()
                    + self.sim.dissipated_energy()
            }
            // Parameters and inputs are served by the instance.
            Quantity::Parameter(_)
            | Quantity::LoadForce { .. }
            | Quantity::MotionPosition { .. } => f64::NAN,
        }
    }
    fn save(&self) -> SimState {
        SimState::from_checkpoint(&self.sim.checkpoint())
    }
    fn load(&mut self, s: &SimState) -> Result<(), String> {
        self.sim
            .restore(s.to_checkpoint::<D>())
            .map_err(|e| e.to_string())
    }
}

/// The simulation with the handles through which the inputs reach it.
struct Live {
    stepper: Box<dyn Stepper>,
    /// Per load: its held force, if it is an input.
    loads: Vec<Option<Held>>,
    /// Per motion: its ramp, if it is an input.
    motions: Vec<Option<Arc<Mutex<Ramp>>>>,
    /// The first failure of a scenario expression during the run.
    expression_error: Arc<Mutex<Option<String>>>,
}

/// A saved FMU state (`fmi2GetFMUstate`): the simulation's checkpoint and the instance's
/// own values, serializable to JSON (bit for bit: floats in round-trip form).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Saved {
    mode: Mode,
    values: Vec<f64>,
    ramps: Vec<Option<Ramp>>,
    sim: Option<SimState>,
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
    live: Option<Live>,
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
    ) -> Result<Self, String> {
        let file = phstring_io::scenario::parse(&text, &path, &[]).map_err(|e| e.to_string())?;
        let spec = ModelSpec::new(&file).map_err(|e| e.to_string())?;
        if spec.guid != guid {
            return Err(format!(
                "GUID {guid} does not match this FMU's scenario ({}): modelDescription.xml and resources/scenario.toml are from different builds",
                spec.guid
            ));
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
            spec,
            values,
            mode: Mode::Instantiated,
            start_time: 0.0,
            stop_time: None,
            live: None,
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

    /// Replaces the logger.
    pub fn set_log(&mut self, log: Logger, logging_on: bool) {
        self.log = log;
        self.logging_on = logging_on;
    }

    /// Logs `message` as an error and returns `Error`, leaving the instance as it was (a
    /// call that is refused).
    pub fn refused(&self, message: &str) -> Status {
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

    /// A refused call that leaves the instance as it was (bad arguments, wrong mode).
    fn refuse(&self, message: String) -> Status {
        self.log(Status::Error, "logStatusError", &message);
        Status::Error
    }

    /// `fmi2SetupExperiment`: the scenario's `t = 0` is `start` [s]; `stop` [s], if given,
    /// is the last communication point.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Status {
        if self.mode != Mode::Instantiated {
            return self.refuse(format!(
                "fmi2SetupExperiment is allowed only right after instantiation (the instance is {:?})",
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
        Status::Ok
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Status {
        if self.mode != Mode::Instantiated {
            return self.refuse(format!(
                "fmi2EnterInitializationMode is allowed only after instantiation (the instance is {:?})",
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
                "fmi2ExitInitializationMode is allowed only in initialization mode (the instance is {:?})",
                self.mode
            ));
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
        if self.live.is_some() {
            return Ok(());
        }
        let mut sets = Vec::new();
        for (vr, v) in self.spec.variables.iter().enumerate() {
            if let Quantity::Parameter(k) = v.quantity {
                let p = &self.spec.parameters[k];
                let x = self.values[vr];
                if x.to_bits() != p.value.to_bits() {
                    sets.push(format!("{}={x:?}", p.key));
                }
            }
        }
        // The master chooses the stop time; `time.end` only has to fit the step size (a
        // whole number of steps), so it moves to the nearest multiple of a changed `h`.
        let h = self.step_size();
        if h.to_bits() != self.spec.h.to_bits() {
            let n = (self.spec.t_end / h).round().max(1.0);
            sets.push(format!("time.end={:?}", n * h));
        }
        let error = |e: String| {
            let e = if sets.is_empty() {
                e
            } else {
                format!(
                    "the parameters ({}) do not fit the scenario: {e}",
                    sets.join(", ")
                )
            };
            (Status::Error, e)
        };
        let file = phstring_io::scenario::parse(&self.text, &self.path, &sets)
            .map_err(|e| error(e.to_string()))?;
        let live = match self.spec.dimension {
            1 => self.live_dim::<1>(&file),
            2 => self.live_dim::<2>(&file),
            _ => self.live_dim::<3>(&file),
        }
        .map_err(&error)?;
        self.live = Some(live);
        Ok(())
    }

    fn live_dim<const D: usize>(&self, file: &ScenarioFile) -> Result<Live, String> {
        let mut v: Validated<D> = file.validate::<D>().map_err(|e| e.to_string())?;
        phstring_io::runner::start_at_equilibrium(&mut v, None).map_err(|e| e.to_string())?;
        let mut loads: Vec<Option<Held>> = vec![None; v.problem.boundary.loads.len()];
        let mut motions: Vec<Option<Arc<Mutex<Ramp>>>> =
            vec![None; v.problem.boundary.motions.len()];
        for (vr, var) in self.spec.variables.iter().enumerate() {
            match var.quantity {
                Quantity::LoadForce { load, component } => {
                    let held = loads[load].get_or_insert_with(Held::default);
                    lock(held)[component] = self.values[vr];
                }
                Quantity::MotionPosition { motion } => {
                    // Until the first step, the support rests where the scenario starts it.
                    let x0 = (v.problem.boundary.motions[motion].position)(0.0);
                    motions[motion] = Some(Arc::new(Mutex::new(Ramp::at(x0))));
                }
                _ => {}
            }
        }
        for (load, held) in v.problem.boundary.loads.iter_mut().zip(&loads) {
            if let Some(held) = held {
                let held = held.clone();
                load.force = Arc::new(move |_t| {
                    let u = *lock(&held);
                    Vector::<D>::from_fn(|i, _| u[i])
                });
            }
        }
        for (m, ramp) in v.problem.boundary.motions.iter_mut().zip(&motions) {
            if let Some(ramp) = ramp {
                let ramp = ramp.clone();
                m.position = Arc::new(move |t| lock(&ramp).position(t));
            }
        }
        let expression_error = v.load_error.clone();
        let sim = Simulation::new(v.problem, v.settings.step).map_err(|e| e.to_string())?;
        let h0 = sim.energies().hamiltonian();
        Ok(Live {
            stepper: Box::new(Running { sim, h0 }),
            loads,
            motions,
            expression_error,
        })
    }

    /// `fmi2SetReal`: parameters before initialization ends, inputs at any time before
    /// termination. A refused value leaves everything as it was.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
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
                            "{name} is a fixed parameter: it can be set only before fmi2ExitInitializationMode"
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
                    if matches!(self.mode, Mode::Terminated | Mode::Error) {
                        return self.refuse(format!(
                            "{name} cannot be set after the run ended ({:?})",
                            self.mode
                        ));
                    }
                    if !x.is_finite() {
                        return self.refuse(format!("input {name} = {x} must be finite"));
                    }
                }
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            if let Quantity::Parameter(_) = self.spec.variables[vr as usize].quantity {
                // A changed parameter sets the simulation up anew.
                self.live = None;
            }
            self.values[vr as usize] = x;
        }
        Status::Ok
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        if self.mode == Mode::Error {
            return self.refuse("the instance is in the error state".into());
        }
        let needs_live = vrs.iter().any(|&vr| {
            self.spec
                .variables
                .get(vr as usize)
                .is_some_and(|v| v.causality == Causality::Output)
        });
        if needs_live && let Err(e) = self.ensure_live() {
            return self.fail(e);
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let Some(var) = self.spec.variables.get(vr as usize) else {
                return self.refuse(format!(
                    "value reference {vr} does not exist (0 … {})",
                    self.spec.variables.len().saturating_sub(1)
                ));
            };
            *slot = match var.causality {
                Causality::Output => match &self.live {
                    Some(l) => l.stepper.value(var.quantity),
                    None => f64::NAN,
                },
                _ => self.values[vr as usize],
            };
        }
        Status::Ok
    }

    /// The internal step size `h` [s] (the parameter's current value).
    fn step_size(&self) -> f64 {
        self.spec
            .variables
            .iter()
            .position(|v| {
                matches!(v.quantity, Quantity::Parameter(k) if self.spec.parameters[k].key == "time.h")
            })
            .map_or(self.spec.h, |vr| self.values[vr])
    }

    /// The time the FMU is at, on the master's clock [s].
    pub fn time(&self) -> f64 {
        self.start_time + self.live.as_ref().map_or(0.0, |l| l.stepper.time())
    }

    /// `fmi2DoStep(t, H)`: internal steps of at most the parameter `h` to reach `t + H`,
    /// with the inputs held at the values set before the call. `Discard` if a step fails
    /// (the FMU stays at the last internal step it completed), `Error` for calls that do not
    /// fit (wrong `t`, `H ≤ 0`, past the stop time) and for failing scenario expressions.
    pub fn do_step(&mut self, t: f64, comm_h: f64) -> Status {
        if self.mode != Mode::StepComplete {
            return self.refuse(format!(
                "fmi2DoStep is allowed only after initialization and a completed step (the instance is {:?})",
                self.mode
            ));
        }
        if !(comm_h > 0.0 && comm_h.is_finite()) {
            return self.refuse(format!(
                "the communication step size must be positive and finite, got {comm_h}"
            ));
        }
        let h = self.step_size();
        let now = self.time();
        let off = (t - now).abs();
        if off.is_nan() || off > 1e-6 * h.min(comm_h) {
            return self.refuse(format!(
                "fmi2DoStep at currentCommunicationPoint = {t} s, but the FMU is at t = {now} s"
            ));
        }
        if let Some(stop) = self.stop_time
            && t + comm_h > stop + 1e-9 * comm_h.max(h)
        {
            return self.refuse(format!(
                "fmi2DoStep to t = {} s passes stopTime = {stop} s",
                t + comm_h
            ));
        }
        let Some(live) = self.live.as_mut() else {
            return self.fail((Status::Error, "the simulation is not set up".into()));
        };
        // The inputs, held over this communication step.
        let target = t - self.start_time + comm_h;
        let start = live.stepper.time();
        for (vr, var) in self.spec.variables.iter().enumerate() {
            match var.quantity {
                Quantity::LoadForce { load, component } => {
                    if let Some(held) = &live.loads[load] {
                        lock(held)[component] = self.values[vr];
                    }
                }
                Quantity::MotionPosition { motion } => {
                    if let Some(ramp) = &live.motions[motion] {
                        let mut r = lock(ramp);
                        let here = r.position(start);
                        *r = Ramp {
                            t0: start,
                            t1: target,
                            from: here,
                            to: self.values[vr],
                        };
                    }
                }
                _ => {}
            }
        }
        while live.stepper.time() < target - 1e-9 * h {
            if let Err(e) = live.stepper.step_until(target) {
                let expression = lock(&live.expression_error).take();
                let at = self.start_time + live.stepper.time();
                return match expression {
                    Some(why) => self.fail((
                        Status::Error,
                        format!("{e}; a scenario expression failed: {why}"),
                    )),
                    None => {
                        self.mode = Mode::StepFailed;
                        self.fail((
                            Status::Discard,
                            format!(
                                "{e}; the FMU stays at t = {at} s, the last internal step it completed (fmi2GetRealStatus(fmi2LastSuccessfulTime))"
                            ),
                        ))
                    }
                };
            }
        }
        Status::Ok
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        if matches!(self.mode, Mode::Instantiated | Mode::Initialization) {
            return self.refuse(format!(
                "fmi2Terminate before initialization ended (the instance is {:?})",
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
        self.live = None;
        Status::Ok
    }

    /// `fmi2GetFMUstate`: everything needed to continue from here (bit for bit).
    pub fn save(&self) -> Result<Saved, String> {
        if matches!(self.mode, Mode::Error) {
            return Err("the instance is in the error state".into());
        }
        Ok(Saved {
            mode: self.mode,
            values: self.values.clone(),
            ramps: self.live.as_ref().map_or_else(Vec::new, |l| {
                l.motions
                    .iter()
                    .map(|r| r.as_ref().map(|r| *lock(r)))
                    .collect()
            }),
            sim: self.live.as_ref().map(|l| l.stepper.save()),
        })
    }

    /// `fmi2SetFMUstate`: continues from `saved`, taken from an instance of the same FMU.
    pub fn restore(&mut self, saved: &Saved) -> Status {
        if saved.values.len() != self.values.len() {
            return self.refuse(format!(
                "the FMU state has {} values, this FMU {}: it is of another FMU",
                saved.values.len(),
                self.values.len()
            ));
        }
        let values = std::mem::replace(&mut self.values, saved.values.clone());
        let same_parameters = self
            .spec
            .variables
            .iter()
            .zip(values.iter().zip(&self.values))
            .all(|(v, (a, b))| v.causality != Causality::Parameter || a.to_bits() == b.to_bits());
        if !same_parameters {
            self.live = None;
        }
        let result = match &saved.sim {
            None => {
                self.live = None;
                Ok(())
            }
            Some(state) => self.ensure_live().map_err(|(_, m)| m).and_then(|()| {
                let live = self.live.as_mut().expect("just set up");
                for (slot, ramp) in live.motions.iter().zip(&saved.ramps) {
                    if let (Some(slot), Some(ramp)) = (slot, ramp) {
                        *lock(slot) = *ramp;
                    }
                }
                live.stepper.load(state)
            }),
        };
        match result {
            Ok(()) => {
                self.mode = saved.mode;
                Status::Ok
            }
            Err(m) => {
                self.values = values;
                self.live = None;
                self.refuse(format!("cannot restore the FMU state: {m}"))
            }
        }
    }
}

/// Locks `m`; a poisoned lock is still usable (a panicking step leaves nothing half-set
/// that the next call reads).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}
