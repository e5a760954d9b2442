//! Python bindings of phstring: scenarios, the stepper (with port inputs and checkpoints), a
//! run that returns NumPy arrays or writes the CLI's output folder, static equilibrium,
//! natural modes and the linearized system. Units as in the library: SI (m, s, kg, N, J).

use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;

use numpy::{PyArray1, PyArrayMethods};
use phstring::{Material, Simulation as Sim, StepReport};
use phstring_io::scenario::{self, ScenarioFile, Setup};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

create_exception!(
    _phstring,
    ScenarioError,
    PyValueError,
    "An invalid scenario; the message names the key and its file:line:col."
);
create_exception!(
    _phstring,
    StepError,
    pyo3::exceptions::PyRuntimeError,
    "A failed time step; the message names the step, the time and where."
);

/// A validated scenario file (TOML), with `set` overrides applied as `phstring run --set`.
#[pyclass(module = "phstring._phstring")]
struct Scenario {
    file: ScenarioFile,
}

fn scenario_err(e: impl std::fmt::Display) -> PyErr {
    ScenarioError::new_err(e.to_string())
}

fn sets(set: Option<Vec<String>>) -> Vec<String> {
    set.unwrap_or_default()
}

#[pymethods]
impl Scenario {
    /// Loads and checks the scenario file at `path`, or the scenario a MoorDyn deck maps
    /// onto (docs/moordyn.md), with `set` overrides (`"KEY=VALUE"`).
    #[staticmethod]
    #[pyo3(signature = (path, set=None))]
    fn from_file(path: &str, set: Option<Vec<String>>) -> PyResult<Self> {
        let file = phstring_io::moordyn::load_scenario(Path::new(path), &sets(set), &[])
            .map_err(scenario_err)?
            .file;
        file.check().map_err(scenario_err)?;
        Ok(Self { file })
    }

    /// Parses and checks a scenario given as TOML text (`name` appears in messages).
    #[staticmethod]
    #[pyo3(signature = (text, set=None, name="<string>"))]
    fn from_toml(text: &str, set: Option<Vec<String>>, name: &str) -> PyResult<Self> {
        let file = scenario::parse(text, Path::new(name), &sets(set)).map_err(scenario_err)?;
        file.check().map_err(scenario_err)?;
        Ok(Self { file })
    }

    /// A scenario from its JSON text (e.g. `json.dumps(d)` of a dict with the TOML layout).
    #[staticmethod]
    #[pyo3(signature = (json, set=None))]
    fn from_json(json: &str, set: Option<Vec<String>>) -> PyResult<Self> {
        let value: serde_json::Value = serde_json::from_str(json).map_err(scenario_err)?;
        let text = toml::to_string(&value).map_err(scenario_err)?;
        Self::from_toml(&text, set, "<dict>")
    }

    /// Spatial dimension (1, 2 or 3).
    #[getter]
    fn dimension(&self) -> PyResult<usize> {
        self.file.dimension().map_err(scenario_err)
    }

    /// The scenario text as run (after the overrides).
    #[getter]
    fn text(&self) -> String {
        self.file.text().to_string()
    }
}

/// A simulation of one of the three dimensions.
type Any = phstring::ByDim<Sim<1, Material>, Sim<2, Material>, Sim<3, Material>>;

use phstring::by_dim as each;

/// One port of the last step: node, force port?, input, output, power [W].
type PortRow = (usize, bool, Vec<f64>, Vec<f64>, f64);

/// The simulation of a scenario set up once ([`ScenarioFile::setup`]), at `t = 0` (at the
/// equilibrium with `initial.equilibrium`, as `phstring run` starts), with its end time and
/// output stride.
fn new_sim<const D: usize>(setup: Setup<D>) -> PyResult<(Sim<D, Material>, f64, usize)> {
    let (v, _) = setup.start(true, None).map_err(scenario_err)?;
    let t_end = v.settings.t_end;
    let stride = v.settings.stride.max(1);
    Ok((v.problem, t_end, stride))
}

fn report_dict<'py>(py: Python<'py>, r: &StepReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", r.step)?;
    d.set_item("t", r.t)?;
    d.set_item("h", r.h)?;
    d.set_item("newton_iterations", r.newton_iterations)?;
    d.set_item("rejected", r.rejected)?;
    d.set_item("residual", r.residual)?;
    d.set_item("hamiltonian", r.after.hamiltonian())?;
    d.set_item("supplied", r.supplied)?;
    d.set_item("dissipated", r.dissipated)?;
    d.set_item("balance_error", r.balance_error)?;
    Ok(d)
}

/// The stepper of a scenario (`phstring::Simulation`): `step()` advances one step.
#[pyclass(module = "phstring._phstring")]
struct Simulation {
    /// Behind a mutex: Python objects may be shared between threads.
    sim: std::sync::Mutex<Any>,
    t_end: f64,
    /// The scenario's `output.stride`.
    stride: usize,
}

impl Simulation {
    fn lock(&self) -> std::sync::MutexGuard<'_, Any> {
        // A panic in another thread cannot leave the simulation half-stepped (a failed
        // step leaves the state untouched), so a poisoned lock is still usable.
        self.sim.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[pymethods]
impl Simulation {
    /// Sets up the scenario's simulation at `t = 0`.
    #[new]
    fn new(scenario: &Scenario) -> PyResult<Self> {
        let setup = scenario.file.setup().map_err(scenario_err)?;
        let started = each!(map setup, s => new_sim(s)).transpose()?;
        let (t_end, stride) = each!(&started, s => (s.1, s.2));
        let sim = each!(map started, s => s.0);
        Ok(Self {
            sim: std::sync::Mutex::new(sim),
            t_end,
            stride,
        })
    }

    /// Advances one step (not beyond the scenario's `time.end`); returns its report as a dict
    /// (`step`, `t` [s], `h` [s], `newton_iterations`, `rejected`, `residual` [N],
    /// `hamiltonian`, `supplied`, `dissipated`, `balance_error` [J]).
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t_end = self.t_end;
        let r = each!(&mut *self.lock(), s => s.step_until(t_end))
            .map_err(|e| StepError::new_err(e.to_string()))?;
        report_dict(py, &r)
    }

    /// Holds the force [N] of load port `port` (0, 1, … in the order of the scenario's
    /// `force` tables) at `value` (one number per component) from the next step on, until
    /// set again (zero-order hold); `None` returns it to the scenario's expression. A
    /// controller written in Python closes its loop this way, one step at a time.
    #[pyo3(signature = (port, value))]
    fn set_input(&self, port: usize, value: Option<Vec<f64>>) -> PyResult<()> {
        let mut guard = self.lock();
        let d = each!(&*guard, s => x_dim(&s.state().r[..]));
        let loads = each!(&*guard, s => s.system().boundary().loads.len());
        if port >= loads {
            return Err(PyValueError::new_err(format!(
                "port {port} is not a load: the scenario has {loads} force ports (0 … {})",
                loads.saturating_sub(1)
            )));
        }
        let held = match value {
            None => each!(&mut *guard, s => s.release_load_force(port)),
            Some(v) => {
                if v.len() != d {
                    return Err(PyValueError::new_err(format!(
                        "the input of port {port} needs {d} components (dimension {d}), got {}",
                        v.len()
                    )));
                }
                if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                    return Err(PyValueError::new_err(format!(
                        "the input of port {port} must be finite, got {x}"
                    )));
                }
                each!(&mut *guard, s => s.set_load_force(port, phstring::Vector::from_fn(|i, _| v[i])))
            }
        };
        held.map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The ports of the last step as a list of dicts: `node`, `kind` (`force` or
    /// `velocity`), `u` and `y` (NumPy arrays: force [N] and mid-step velocity [m/s], or
    /// velocity and reaction force), `power` [W]. Loads first, then controls, then supports.
    #[getter]
    fn ports<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let samples: Vec<PortRow> = each!(&*self.lock(), s => {
            s.ports()
                .iter()
                .map(|p| {
                    (
                        p.node,
                        p.kind == phstring::PortKind::Force,
                        p.input.as_slice().to_vec(),
                        p.output.as_slice().to_vec(),
                        p.power(),
                    )
                })
                .collect()
        });
        samples
            .into_iter()
            .map(|(node, force, u, y, power)| {
                let d = PyDict::new(py);
                d.set_item("node", node)?;
                d.set_item("kind", if force { "force" } else { "velocity" })?;
                d.set_item("u", PyArray1::from_vec(py, u))?;
                d.set_item("y", PyArray1::from_vec(py, y))?;
                d.set_item("power", power)?;
                Ok(d)
            })
            .collect()
    }

    /// Holds the wrench port of rigid body `body` (its index in file order, or its name) at
    /// `force` [N] (`d` components, space axes) and `torque` [N·m] (3 components in 3D, the
    /// one about `z` in 2D) from the next step on, until set again (zero-order hold); `None`
    /// for both returns it to the scenario's `wrench` (or to none). A body without a
    /// `wrench` in the scenario gets one. Its work enters `energies["supplied"]`.
    #[pyo3(signature = (body, force, torque=None))]
    fn set_body_wrench(
        &self,
        body: &Bound<'_, PyAny>,
        force: Option<Vec<f64>>,
        torque: Option<Vec<f64>>,
    ) -> PyResult<()> {
        let mut guard = self.lock();
        let b = each!(&*guard, s => body_index(s, body))?;
        let d = each!(&*guard, s => x_dim(&s.state().r[..]));
        let turns = if d == 2 { 1 } else { 3 };
        let held = match (force, torque) {
            (None, None) => each!(&mut *guard, s => s.release_body_wrench(b)),
            (force, torque) => {
                let f = wrench_vector(b, "force", force, d, 0)?;
                let t = wrench_vector(b, "torque", torque, turns, 3 - turns)?;
                each!(&mut *guard, s => s.set_body_wrench(b, f, t))
            }
        };
        held.map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Holds the payout speed of winch `winch` (its index in file order, or its name) at
    /// `speed` [m/s] (negative: hauling in) from the current time on, its payout continuing
    /// from where it is (zero-order hold), until set again; the scenario's `payout` does not
    /// come back. Its energy enters `energies["supplied"]` (docs/method.md §23).
    fn set_winch_speed(&self, winch: &Bound<'_, PyAny>, speed: f64) -> PyResult<()> {
        let mut guard = self.lock();
        let w = each!(&*guard, s => winch_index(s, winch))?;
        each!(&mut *guard, s => s.set_winch_speed(w, speed))
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Holds the motor pull of winch `winch`'s drum (its index in file order, or its name;
    /// a winch with `[winch.drum]`) at `force` [N] at the rope (hauling in positive: a
    /// tension controller's target tension) from the current time on, until set again
    /// (docs/method.md §23.6).
    fn set_winch_force(&self, winch: &Bound<'_, PyAny>, force: f64) -> PyResult<()> {
        let mut guard = self.lock();
        let w = each!(&*guard, s => winch_index(s, winch))?;
        each!(&mut *guard, s => s.set_winch_force(w, force))
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The winches, in file order, as a list of dicts after the last step: `name`, `payout`
    /// [m] (since t = 0, negative: hauled in), `length` [m] (reference length off the drum),
    /// `speed` [m/s] (mean over the last step), `tension` [N] (at the drum), `power` [W]
    /// (mean over the last step), `energy` [J] (supplied since t = 0), `mass` [kg] (off
    /// the drum), and for a drum with dynamics `motor_energy` [J] (its motor's part of
    /// `energy`) and `drum_dissipated` [J] (its damping and brake; both 0 without).
    #[getter]
    fn winches<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let rows: Vec<(String, [f64; 9])> = each!(&*self.lock(), s => winch_rows(s));
        rows.into_iter()
            .map(|(name, v)| {
                let d = PyDict::new(py);
                d.set_item("name", name)?;
                let keys = [
                    "payout",
                    "length",
                    "speed",
                    "tension",
                    "power",
                    "energy",
                    "mass",
                    "motor_energy",
                    "drum_dissipated",
                ];
                for (key, x) in keys.into_iter().zip(v) {
                    d.set_item(key, x)?;
                }
                Ok(d)
            })
            .collect()
    }

    /// Returns the wrench port of rigid body `body` (index or name) to the scenario's from
    /// the next step on (as `set_body_wrench(body, None)`).
    fn release_body_wrench(&self, body: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut guard = self.lock();
        let b = each!(&*guard, s => body_index(s, body))?;
        each!(&mut *guard, s => s.release_body_wrench(b))
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The rigid bodies, in file order, as a list of dicts: `name`; at the current time
    /// `position` [m] (centre of mass), `orientation` (unit quaternion `[w, x, y, z]`, body
    /// axes to space), `velocity` [m/s] and `angular_velocity` [rad/s] (space axes), NumPy
    /// arrays of 3 (in 2D `z`, `x`, `y` parts 0); and the wrench port's sample of the last
    /// step (zero before the first step and without a port): `force` [N] and `torque` [N·m]
    /// (space axes, at the step's mid time) and `power` [W], its mean power `F·v + τ·ω`
    /// over the step, positive into the body.
    #[getter]
    fn body_ports<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let rows: Vec<BodyRow> = each!(&*self.lock(), s => body_rows(s));
        rows.into_iter()
            .map(|(name, x, q, v, w, f, t, power)| {
                let d = PyDict::new(py);
                d.set_item("name", name)?;
                for (key, a) in [
                    ("position", x.to_vec()),
                    ("orientation", q.to_vec()),
                    ("velocity", v.to_vec()),
                    ("angular_velocity", w.to_vec()),
                    ("force", f.to_vec()),
                    ("torque", t.to_vec()),
                ] {
                    d.set_item(key, PyArray1::from_vec(py, a))?;
                }
                d.set_item("power", power)?;
                Ok(d)
            })
            .collect()
    }

    /// The complete dynamic state, to continue from with [`Simulation::restore`] (bit for
    /// bit as if the run had not stopped). Held inputs (`set_input`) are not part of it.
    fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            inner: each!(&*self.lock(), s => Box::new(s.checkpoint())),
        }
    }

    /// Continues from `checkpoint`, taken from a simulation of the same scenario.
    fn restore(&self, checkpoint: &Checkpoint) -> PyResult<()> {
        each!(&mut *self.lock(), s => restore_from(s, checkpoint.inner.as_ref()))
    }

    /// Current time [s].
    #[getter]
    fn time(&self) -> f64 {
        each!(&*self.lock(), s => s.time())
    }

    /// The scenario's end time [s].
    #[getter]
    fn t_end(&self) -> f64 {
        self.t_end
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> usize {
        each!(&*self.lock(), s => s.steps())
    }

    /// Node positions [m], a copy of shape `(nodes, d)`.
    #[getter]
    fn r<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => nodal(py, &s.state().r))
    }

    /// Node velocities [m/s], a copy of shape `(nodes, d)`.
    #[getter]
    fn v<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        each!(&*self.lock(), s => nodal(py, &s.state().v))
    }

    /// Element strains `C` (dimensionless), a copy of shape `(elements,)`.
    #[getter]
    fn c<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let c = each!(&*self.lock(), s => s.state().c.clone());
        PyArray1::from_vec(py, c)
    }

    /// Energies [J] as a dict: `kinetic`, `potential`, `hamiltonian`, `supplied` and
    /// `dissipated` (cumulative); in water also the potential parts `buoyancy` and `seabed`
    /// (in `potential`) and the water's cumulative shares `drag_dissipated`,
    /// `current_supplied`, `seabed_dissipated` and `friction_dissipated` (in `supplied` and
    /// `dissipated`), docs/method.md §21.
    #[getter]
    fn energies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (e, sup, dis, wet, water) = each!(&*self.lock(), s => (
            s.energies(),
            s.supplied_energy(),
            s.dissipated_energy(),
            s.system().has_water(),
            s.water_work()
        ));
        let d = PyDict::new(py);
        d.set_item("kinetic", e.kinetic)?;
        d.set_item("potential", e.potential())?;
        d.set_item("hamiltonian", e.hamiltonian())?;
        d.set_item("supplied", sup)?;
        d.set_item("dissipated", dis)?;
        if wet {
            d.set_item("buoyancy", e.buoyancy)?;
            d.set_item("seabed", e.seabed)?;
            d.set_item("drag_dissipated", water.drag_dissipated)?;
            d.set_item("current_supplied", water.current_supplied)?;
            d.set_item("seabed_dissipated", water.seabed_dissipated)?;
            d.set_item("friction_dissipated", water.friction_dissipated)?;
        }
        Ok(d)
    }
}

/// One rigid body for [`Simulation::body_ports`]: name, position [m], quaternion
/// `[w, x, y, z]`, velocity [m/s], angular velocity [rad/s], port force [N], torque [N·m]
/// and mean power [W].
type BodyRow = (
    String,
    [f64; 3],
    [f64; 4],
    [f64; 3],
    [f64; 3],
    [f64; 3],
    [f64; 3],
    f64,
);

/// The winches of `sim`: name and `[payout, length, speed, tension, power, energy, mass,
/// motor energy, drum dissipated]`.
fn winch_rows<const D: usize>(sim: &Sim<D, Material>) -> Vec<(String, [f64; 9])> {
    let names = sim.system().winches();
    sim.winch_samples()
        .iter()
        .zip(names)
        .map(|(w, (name, _))| {
            let v = [
                w.payout,
                w.length,
                w.speed,
                w.tension,
                w.power,
                w.energy,
                w.mass,
                w.motor,
                w.dissipated,
            ];
            (name.to_string(), v)
        })
        .collect()
}

/// The index of winch `winch` (an index or a name) of `sim`.
fn winch_index<const D: usize>(
    sim: &Sim<D, Material>,
    winch: &Bound<'_, PyAny>,
) -> PyResult<usize> {
    let names: Vec<&str> = sim.system().winches().into_iter().map(|w| w.0).collect();
    let known = || {
        if names.is_empty() {
            "the scenario has no winches".to_string()
        } else {
            format!(
                "the winches are {} (0 … {})",
                names.join(", "),
                names.len() - 1
            )
        }
    };
    if let Ok(name) = winch.extract::<String>() {
        return names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| PyValueError::new_err(format!("no winch named {name:?}: {}", known())));
    }
    let i: usize = winch.extract().map_err(|_| {
        PyValueError::new_err(format!("a winch is an index or a name, got {winch}"))
    })?;
    if i >= names.len() {
        return Err(PyValueError::new_err(format!("no winch {i}: {}", known())));
    }
    Ok(i)
}

/// The rigid bodies of `sim` as [`BodyRow`]s, in file order.
fn body_rows<const D: usize>(sim: &Sim<D, Material>) -> Vec<BodyRow> {
    let names = sim.system().bodies();
    let ports = sim.body_ports();
    sim.state()
        .bodies
        .iter()
        .enumerate()
        .map(|(b, st)| {
            let q = st.orientation.quaternion();
            let (f, t, p) = ports.get(b).map_or(([0.0; 3], [0.0; 3], 0.0), |p| {
                (p.force.into(), p.torque.into(), p.mean_power)
            });
            (
                names.get(b).map_or_else(String::new, |n| n.0.to_string()),
                st.position.into(),
                [q.w, q.i, q.j, q.k],
                st.velocity.into(),
                st.omega_space().into(),
                f,
                t,
                p,
            )
        })
        .collect()
}

/// The index of rigid body `body` of `sim`: an index (in file order) or a name; refused
/// with the bodies there are.
fn body_index<const D: usize>(sim: &Sim<D, Material>, body: &Bound<'_, PyAny>) -> PyResult<usize> {
    let names: Vec<&str> = sim.system().bodies().into_iter().map(|b| b.0).collect();
    let known = || {
        if names.is_empty() {
            "the scenario has no rigid bodies".to_string()
        } else {
            format!(
                "the bodies are {} (0 … {})",
                names.join(", "),
                names.len() - 1
            )
        }
    };
    if let Ok(name) = body.extract::<String>() {
        return names.iter().position(|n| *n == name).ok_or_else(|| {
            PyValueError::new_err(format!("no rigid body named {name:?}: {}", known()))
        });
    }
    let i: usize = body
        .extract()
        .map_err(|_| PyValueError::new_err(format!("a body is an index or a name, got {body}")))?;
    if i >= names.len() {
        return Err(PyValueError::new_err(format!(
            "no rigid body {i}: {}",
            known()
        )));
    }
    Ok(i)
}

/// The force or torque (`what`) of body `b`'s wrench from Python: `n` finite components,
/// placed from component `first` of a 3-vector (a 2D torque is about `z`); `None` is zero.
fn wrench_vector(
    b: usize,
    what: &str,
    v: Option<Vec<f64>>,
    n: usize,
    first: usize,
) -> PyResult<phstring::body::Vec3> {
    let mut out = phstring::body::Vec3::zeros();
    let Some(v) = v else {
        return Ok(out);
    };
    if v.len() != n {
        return Err(PyValueError::new_err(format!(
            "the {what} of body {b} needs {n} components, got {}",
            v.len()
        )));
    }
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "the {what} of body {b} must be finite, got {x}"
        )));
    }
    for (i, x) in v.iter().enumerate() {
        out[first + i] = *x;
    }
    Ok(out)
}

/// A simulation's complete dynamic state ([`Simulation::checkpoint`]).
#[pyclass(module = "phstring._phstring", frozen)]
struct Checkpoint {
    /// The `phstring::Checkpoint<D>` of the simulation's dimension `D`.
    inner: Box<dyn std::any::Any + Send + Sync>,
}

/// Puts `checkpoint` back on `sim`; refused if it is not of `sim`'s dimension or does not
/// fit it.
fn restore_from<const D: usize>(
    sim: &mut Sim<D, Material>,
    checkpoint: &(dyn std::any::Any + Send + Sync),
) -> PyResult<()> {
    let c = checkpoint
        .downcast_ref::<phstring::Checkpoint<D>>()
        .ok_or_else(|| {
            PyValueError::new_err("the checkpoint is of a simulation of another dimension")
        })?;
    sim.restore(c.clone())
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

fn x_dim<const D: usize>(_: &[phstring::Vector<D>]) -> usize {
    D
}

/// The columns of an in-process run: energies etc. per step, Newton iterations, the
/// positions every `stride` steps (flattened) and their times.
struct Columns {
    cols: [Vec<f64>; 8],
    its: Vec<usize>,
    positions: Vec<f64>,
    t_positions: Vec<f64>,
    /// Nodes and dimension of a frame.
    shape: [usize; 2],
}

/// Records what `run` returns as [`Sim::run_until`] steps (its observer); ends the run when
/// Python has a signal pending (Ctrl-C: `KeyboardInterrupt` after the current step).
struct Recorder<'a, 'py> {
    py: Python<'py>,
    out: Columns,
    t_end: f64,
    stride: usize,
    bar: &'a mut Bar,
    steps: usize,
    /// The pending signal's exception.
    error: Option<PyErr>,
}

impl<const D: usize> phstring::Observer<D, Material> for Recorder<'_, '_> {
    fn before_step(&mut self, _sim: &Sim<D, Material>) -> ControlFlow<()> {
        match self.py.check_signals() {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.error = Some(e);
                ControlFlow::Break(())
            }
        }
    }

    fn on_step(&mut self, s: &Sim<D, Material>, r: &StepReport) -> ControlFlow<()> {
        let out = &mut self.out;
        for (c, v) in out.cols.iter_mut().zip([
            r.t,
            r.after.kinetic,
            r.after.potential(),
            r.after.hamiltonian(),
            s.supplied_energy(),
            s.dissipated_energy(),
            r.balance_error,
            r.h,
        ]) {
            c.push(v);
        }
        out.its.push(r.newton_iterations);
        self.bar.show(r.t, self.t_end);
        self.steps += 1;
        if self.steps.is_multiple_of(self.stride) || s.reached(self.t_end) {
            out.positions
                .extend(s.state().r.iter().flat_map(|x| x.iter().copied()));
            out.t_positions.push(r.t);
        }
        ControlFlow::Continue(())
    }
}

/// Steps `s` to `t_end` (under one lock), recording what `run` returns.
fn run_loop<const D: usize>(
    py: Python<'_>,
    s: &mut Sim<D, Material>,
    t_end: f64,
    stride: usize,
    bar: &mut Bar,
) -> PyResult<Columns> {
    let e0 = s.energies();
    let mut out = Columns {
        cols: Default::default(),
        its: vec![0],
        positions: flat(&s.state().r),
        t_positions: vec![0.0],
        shape: [s.state().r.len(), D],
    };
    for (c, v) in out.cols.iter_mut().zip([
        0.0,
        e0.kinetic,
        e0.potential(),
        e0.hamiltonian(),
        0.0,
        0.0,
        0.0,
        0.0,
    ]) {
        c.push(v);
    }
    let mut recorder = Recorder {
        py,
        out,
        t_end,
        stride,
        bar,
        steps: 0,
        error: None,
    };
    s.run_until(t_end, &mut recorder)
        .map_err(|e| StepError::new_err(e.to_string()))?;
    match recorder.error {
        Some(e) => Err(e),
        None => Ok(recorder.out),
    }
}

/// Runs `scenario` to its end time in-process and returns a dict of NumPy arrays, one entry
/// per step from `t = 0`: `t` [s], `kinetic`, `potential`, `hamiltonian`, `supplied`,
/// `dissipated`, `balance_error` [J], `h` [s], `newton_iterations`. The values are those of
/// `phstring run`'s `energy.csv`, bit for bit.
#[pyfunction]
#[pyo3(signature = (scenario, progress=false))]
fn run<'py>(py: Python<'py>, scenario: &Scenario, progress: bool) -> PyResult<Bound<'py, PyDict>> {
    let mut bar = Bar::new(progress);
    let sim = Simulation::new(scenario)?;
    let (t_end, stride) = (sim.t_end, sim.stride);
    let out = each!(&mut *sim.lock(), s => run_loop(py, s, t_end, stride, &mut bar))?;
    let d = PyDict::new(py);
    let names = [
        "t",
        "kinetic",
        "potential",
        "hamiltonian",
        "supplied",
        "dissipated",
        "balance_error",
        "h",
    ];
    for (name, c) in names.iter().zip(out.cols) {
        d.set_item(*name, PyArray1::from_vec(py, c))?;
    }
    d.set_item("newton_iterations", PyArray1::from_vec(py, out.its))?;
    bar.done();
    let frames = out.t_positions.len();
    let [n, dim] = out.shape;
    d.set_item("t_positions", PyArray1::from_vec(py, out.t_positions))?;
    d.set_item(
        "positions",
        PyArray1::from_vec(py, out.positions).reshape([frames, n, dim])?,
    )?;
    Ok(d)
}

/// A one-line progress display on standard error (`t / T` and percent), redrawn at most
/// every percent; silent unless asked for.
struct Bar {
    on: bool,
    last: i64,
}

impl Bar {
    fn new(on: bool) -> Self {
        Self { on, last: -1 }
    }
    fn show(&mut self, t: f64, t_end: f64) {
        let pct = (100.0 * t / t_end).floor() as i64;
        if self.on && pct > self.last {
            self.last = pct;
            eprint!("\rphstring: t = {t:.4} s of {t_end} s ({pct:>3} %)");
        }
    }
    fn done(&mut self) {
        if self.on {
            eprintln!();
        }
    }
}

/// Progress of a run to a folder: checks for Ctrl-C after every step, and shows a bar if
/// asked.
struct Signals<'py> {
    py: Python<'py>,
    stop: Arc<std::sync::atomic::AtomicBool>,
    interrupted: Option<PyErr>,
    bar: Bar,
    t_end: f64,
}

impl phstring_io::drive::run::Progress for Signals<'_> {
    fn start(&mut self, t_end: f64) {
        self.t_end = t_end;
    }
    fn step(&mut self, _step: usize, t: f64) {
        self.bar.show(t, self.t_end);
        if self.interrupted.is_none()
            && let Err(e) = self.py.check_signals()
        {
            self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
            self.interrupted = Some(e);
        }
    }
}

/// Runs `scenario` as `phstring run` does, writing its output folder `out` (created if
/// needed; it must be empty or a folder of an earlier run), and returns `summary.json`'s
/// text. Ctrl-C stops after the current step with the outputs and a checkpoint written,
/// then raises `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (scenario, out, progress=false))]
fn run_to_folder(
    py: Python<'_>,
    scenario: &Scenario,
    out: &str,
    progress: bool,
) -> PyResult<String> {
    let out = Path::new(out);
    std::fs::create_dir_all(out)
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", out.display())))?;
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let mut progress = Signals {
        py,
        stop: stop.clone(),
        interrupted: None,
        bar: Bar::new(progress),
        t_end: 0.0,
    };
    let opts = phstring_io::drive::run::RunOptions {
        stop: Some(stop),
        ..Default::default()
    };
    let result = phstring_io::drive::run::run(&scenario.file, out, &mut progress, opts);
    progress.bar.done();
    if let Some(e) = progress.interrupted {
        return Err(e);
    }
    match result {
        Ok(_) => std::fs::read_to_string(out.join("summary.json"))
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string())),
        Err(phstring_io::drive::run::RunError::Scenario(e)) => Err(scenario_err(e)),
        Err(e) => Err(StepError::new_err(e.to_string())),
    }
}

/// The error of a sweep for Python: refused input as `ScenarioError`, the rest as `OSError`.
fn sweep_err(e: phstring_io::drive::sweep::SweepError) -> PyErr {
    use phstring_io::drive::sweep::SweepError;
    match e {
        SweepError::Scenario(_) | SweepError::Load(_) | SweepError::TooManyRuns { .. } => {
            scenario_err(e)
        }
        e => pyo3::exceptions::PyOSError::new_err(e.to_string()),
    }
}

/// Runs the MoorDyn deck `deck` once per platform table of `motions` (a load-case
/// campaign, `phstring sweep DECK --vary motion=…`) on `jobs` threads (default: the number
/// of cores) into the folder `out` (created if needed; the outputs of an earlier run or
/// sweep there are replaced, as with `--force`), with `set` overrides and `ignore` words as
/// `phstring run`; returns the text of `campaign.csv`. A case that fails is a row of the
/// table. Ctrl-C stops the runs under way (each with a checkpoint) and raises
/// `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (deck, motions, out, jobs=None, set=None, ignore=None))]
fn campaign_raw(
    py: Python<'_>,
    deck: &str,
    motions: Vec<String>,
    out: &str,
    jobs: Option<usize>,
    set: Option<Vec<String>>,
    ignore: Option<Vec<String>>,
) -> PyResult<String> {
    use phstring_io::drive::sweep::{DeckOptions, MOTION_KEY, Sweep, Vary};
    use std::sync::atomic::{AtomicBool, Ordering};
    if motions.is_empty() {
        return Err(PyValueError::new_err("motions: give at least one table"));
    }
    if jobs == Some(0) {
        return Err(PyValueError::new_err("jobs = 0: give at least 1"));
    }
    let vary = vec![Vary {
        key: MOTION_KEY.into(),
        values: motions,
    }];
    let options = DeckOptions {
        ignore: ignore.unwrap_or_default(),
        motion: None,
    };
    let plan = Sweep::new_with(Path::new(deck), &sets(set), vary, options, |_, _| Ok(()))
        .map_err(sweep_err)?;
    let out = Path::new(out);
    let os_err = |e: &dyn std::fmt::Display| pyo3::exceptions::PyOSError::new_err(e.to_string());
    let _lock = phstring_io::drive::outdir::prepare(out, true).map_err(|e| os_err(&e))?;
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let stop = Arc::new(AtomicBool::new(false));
    let mut interrupted = None;
    let ran = std::thread::scope(|scope| {
        let worker = scope.spawn(|| plan.run(out, jobs, &|_| {}, Some(stop.clone())));
        // Python sees Ctrl-C on this thread only: poll for it while the runs go on.
        while !worker.is_finished() {
            if interrupted.is_none()
                && let Err(e) = py.check_signals()
            {
                stop.store(true, Ordering::Relaxed);
                interrupted = Some(e);
            }
            py.detach(|| std::thread::sleep(std::time::Duration::from_millis(20)));
        }
        worker.join()
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    ran.map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the campaign's runs panicked"))?
        .map_err(sweep_err)?;
    std::fs::read_to_string(out.join(phstring_io::files::CAMPAIGN_TABLE)).map_err(|e| os_err(&e))
}

fn flat<const D: usize>(v: &[phstring::Vector<D>]) -> Vec<f64> {
    v.iter().flat_map(|x| x.iter().copied()).collect()
}

/// `(n, d)` array of nodal vectors.
fn nodal<'py, const D: usize>(
    py: Python<'py>,
    v: &[phstring::Vector<D>],
) -> PyResult<Bound<'py, PyAny>> {
    Ok(PyArray1::from_vec(py, flat(v))
        .reshape([v.len(), D])?
        .into_any())
}

fn statics_err(e: impl std::fmt::Display) -> PyErr {
    StepError::new_err(format!("statics: {e}"))
}

fn statics_dim<'py, const D: usize>(py: Python<'py>, v: Setup<D>) -> PyResult<Bound<'py, PyDict>> {
    let eq = v.equilibrium(false, None).map_err(statics_err)?;
    let d = PyDict::new(py);
    d.set_item("positions", nodal(py, &eq.state.r)?)?;
    d.set_item("reactions", nodal(py, &eq.reactions)?)?;
    d.set_item("strains", PyArray1::from_vec(py, eq.state.c.clone()))?;
    d.set_item("residual", eq.residual)?;
    d.set_item("tolerance", eq.tolerance)?;
    d.set_item("stable", eq.stable)?;
    d.set_item("path", eq.path.name())?;
    d.set_item("iterations", eq.iterations)?;
    d.set_item("hamiltonian", eq.energies.hamiltonian())?;
    Ok(d)
}

/// The static equilibrium under the loads at `t = 0` (as `phstring statics`): a dict with
/// `positions` and `reactions` (`(nodes, d)` arrays [m], [N]), `strains`, `residual` and
/// `tolerance` [N], `stable`, `path`, `iterations`, `hamiltonian` [J].
#[pyfunction]
fn statics<'py>(py: Python<'py>, scenario: &Scenario) -> PyResult<Bound<'py, PyDict>> {
    each!(scenario.file.setup().map_err(scenario_err)?, v => statics_dim(py, v))
}

fn modes_dim<'py, const D: usize>(
    py: Python<'py>,
    v: Setup<D>,
    count: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let eq = v.equilibrium(true, None).map_err(statics_err)?;
    let found = phstring::modes::modes(
        &v.problem.system,
        &eq.state.r,
        count,
        v.settings.step.solver,
        None,
    )
    .map_err(|e| StepError::new_err(format!("modes: {e}")))?;
    let k = found.modes.len();
    let n = eq.state.r.len();
    let d = PyDict::new(py);
    let omega: Vec<f64> = found.modes.iter().map(|m| m.omega).collect();
    let shapes: Vec<f64> = found.modes.iter().flat_map(|m| flat(&m.shape)).collect();
    let character: Vec<&str> = found.modes.iter().map(|m| m.character.name()).collect();
    d.set_item("omega", PyArray1::from_vec(py, omega))?;
    d.set_item("shapes", PyArray1::from_vec(py, shapes).reshape([k, n, D])?)?;
    d.set_item("character", character)?;
    d.set_item("positions", nodal(py, &eq.state.r)?)?;
    Ok(d)
}

/// The `count` lowest natural modes about the equilibrium (as `phstring modes`): a dict with
/// `omega` [rad/s], `shapes` (`(count, nodes, d)`, `M`-normalized [kg^-½]), `character`
/// (`longitudinal`, `transverse` or `mixed`) and the equilibrium `positions` [m].
#[pyfunction]
fn modes<'py>(py: Python<'py>, scenario: &Scenario, count: usize) -> PyResult<Bound<'py, PyDict>> {
    each!(scenario.file.setup().map_err(scenario_err)?, v => modes_dim(py, v, count))
}

/// `(shape, indptr, indices, data)` of a CSC matrix.
type Csc = ((usize, usize), Vec<usize>, Vec<usize>, Vec<f64>);

/// The matrices by name, the state names and the inputs `(node, component)`.
type LinearParts = (Vec<(&'static str, Csc)>, Vec<String>, Vec<(usize, usize)>);

fn csc(a: &faer::sparse::SparseColMat<usize, f64>) -> Csc {
    let a = a.as_ref();
    let mut indptr = vec![0];
    let (mut indices, mut data) = (Vec::new(), Vec::new());
    for c in 0..a.ncols() {
        for (r, v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            indices.push(r);
            data.push(*v);
        }
        indptr.push(indices.len());
    }
    ((a.nrows(), a.ncols()), indptr, indices, data)
}

fn linear_dim<const D: usize>(v: Setup<D>, form: &str) -> PyResult<LinearParts> {
    let eq = v.equilibrium(true, None).map_err(statics_err)?;
    let sys = &v.problem.system;
    let ports = phstring::linear::force_ports(sys);
    let model = match form {
        "reduced" => phstring::linear::reduced_model(sys, &eq.state.r, &ports),
        "full" => phstring::linear::full_model(sys, &eq.state.r, &ports),
        other => {
            return Err(PyValueError::new_err(format!(
                "form must be \"reduced\" or \"full\", got \"{other}\""
            )));
        }
    };
    let mats = vec![
        ("E", csc(&model.e)),
        ("J", csc(&model.j)),
        ("R", csc(&model.r)),
        ("Q", csc(&model.q)),
        ("B", csc(&model.b)),
    ];
    let inputs = ports.iter().map(|p| (p.node, p.component)).collect();
    Ok((mats, model.states, inputs))
}

/// The linear port-Hamiltonian model about the equilibrium (as `phstring linearize`,
/// docs/method.md §16), form `reduced` (`x = (q, v)`) or `full` (`x = (r, v, C)`): a dict
/// with `E`, `J`, `R`, `Q`, `B` as `(shape, indptr, indices, data)` of CSC matrices (the
/// Python wrapper makes scipy.sparse matrices of them), `states` and `inputs`
/// (`(node, component)` of each force port).
#[pyfunction]
#[pyo3(signature = (scenario, form="reduced"))]
fn linearize_raw<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    form: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let setup = scenario.file.setup().map_err(scenario_err)?;
    let (mats, states, inputs) = each!(setup, v => linear_dim(v, form))?;
    let d = PyDict::new(py);
    for (name, (shape, indptr, indices, data)) in mats {
        let m = PyDict::new(py);
        m.set_item("shape", shape)?;
        m.set_item(
            "indptr",
            PyArray1::from_vec(py, indptr.iter().map(|&x| x as i64).collect()),
        )?;
        m.set_item(
            "indices",
            PyArray1::from_vec(py, indices.iter().map(|&x| x as i64).collect()),
        )?;
        m.set_item("data", PyArray1::from_vec(py, data))?;
        d.set_item(name, m)?;
    }
    d.set_item("states", states)?;
    d.set_item("inputs", inputs)?;
    Ok(d)
}

/// The compiled part of the `phstring` package.
#[pymodule]
fn _phstring(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scenario>()?;
    m.add_class::<Simulation>()?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(run_to_folder, m)?)?;
    m.add_function(wrap_pyfunction!(campaign_raw, m)?)?;
    m.add_function(wrap_pyfunction!(statics, m)?)?;
    m.add_function(wrap_pyfunction!(modes, m)?)?;
    m.add_function(wrap_pyfunction!(linearize_raw, m)?)?;
    m.add_class::<Checkpoint>()?;
    m.add("ScenarioError", m.py().get_type::<ScenarioError>())?;
    m.add("StepError", m.py().get_type::<StepError>())?;
    // The package version (python/Cargo.toml, the same as pyproject.toml's).
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
