//! The FMU's variables, derived from a scenario, and its `modelDescription.xml`.
//!
//! The CLI (which writes the description) and the shared library (which serves the
//! variables) both derive the list from the same scenario text with [`ModelSpec::new`], so
//! value references agree; the GUID is a hash of that list and the scenario text, and the
//! library refuses an instance whose GUID does not match.

mod bodies;
mod winches;

use phstring::{Material, PortKind, Simulation};
use phstring_io::checkpoint::fnv1a64_hex;
use phstring_io::scenario::{Components, Scenario, ScenarioError, ScenarioFile, Setup, Validated};

/// FMI causality of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialization (`variability = "fixed"`).
    Parameter,
    /// Set by the master at communication points (zero-order hold over the step).
    Input,
    /// Computed by the FMU.
    Output,
}

/// What a variable's value is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Parameter `k` of [`ModelSpec::parameters`].
    Parameter(usize),
    /// Component `component` of the force [N] of load `load` (force port, file order).
    LoadForce {
        /// Index among the scenario's loads.
        load: usize,
        /// Component (0 = x).
        component: usize,
    },
    /// The position [m] that prescribed motion `motion` reaches at the end of the
    /// communication step (index into the problem's motions, one component each).
    MotionPosition {
        /// Index among the problem's motions.
        motion: usize,
    },
    /// Component `component` of the output of port `port` over the last step: mid-step
    /// velocity [m/s] of a force port, reaction force [N] of a velocity port.
    PortOutput {
        /// Port index (loads, feedback, supports).
        port: usize,
        /// Component.
        component: usize,
    },
    /// Component `component` of the input of port `port` over the last step (the force
    /// [N] a feedback law applied).
    PortInput {
        /// Port index.
        port: usize,
        /// Component.
        component: usize,
    },
    /// Component `component` of the position [m] of mesh node `node`.
    NodePosition {
        /// Mesh node index.
        node: usize,
        /// Component.
        component: usize,
    },
    /// Component `component` of the force [N] (space axes, at the centre of mass) of the
    /// wrench port of rigid body `body` (an input).
    BodyForce {
        /// Body index (file order).
        body: usize,
        /// Component (0 = x).
        component: usize,
    },
    /// Component `component` of the torque [N·m] (space axes) of the wrench port of rigid
    /// body `body` (an input; in 2D only `z`, component 2).
    BodyTorque {
        /// Body index (file order).
        body: usize,
        /// Component (0 = x).
        component: usize,
    },
    /// A value of rigid body `body`'s state or of its port sample (an output).
    Body {
        /// Body index (file order).
        body: usize,
        /// Which value.
        what: BodyValue,
        /// Component (0 = x; for [`BodyValue::Orientation`] 0 = w, 1 = x, 2 = y, 3 = z).
        component: usize,
    },
    /// The payout speed [m/s] of winch `winch` (index among the system's winches), held
    /// over each communication step from the payout reached (an input).
    WinchSpeed {
        /// Winch index.
        winch: usize,
    },
    /// A value of winch `winch` after the last internal step (an output).
    Winch {
        /// Winch index (among the system's winches).
        winch: usize,
        /// Which value.
        what: WinchValue,
    },
    /// `Ĥ` [J].
    Hamiltonian,
    /// `T̂` [J].
    Kinetic,
    /// `V̂` [J] (internal plus external potential).
    Potential,
    /// Energy supplied through the ports since `t = 0` [J].
    Supplied,
    /// Energy dissipated since `t = 0` [J].
    Dissipated,
    /// `Ĥ(t) − Ĥ(0) − supplied + dissipated` [J]: zero up to the Newton tolerance and
    /// rounding.
    BalanceError,
}

/// Which value of a rigid body an output is (docs/method.md §22).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyValue {
    /// Position of the centre of mass [m].
    Position,
    /// Orientation, body axes to space, as the unit quaternion `(w, x, y, z)` (3D).
    Orientation,
    /// Angle of the body axes about `z` [rad], in `(−π, π]` (2D).
    Angle,
    /// Velocity of the centre of mass [m/s].
    Velocity,
    /// Angular velocity [rad/s], space axes.
    AngularVelocity,
    /// The wrench port's output over the last internal step: the mid-step velocity
    /// `Δx/h` [m/s].
    MidVelocity,
    /// The wrench port's output over the last internal step: the mid-step angular velocity
    /// [rad/s], space axes.
    MidAngularVelocity,
    /// A prescribed motion's reaction force over the last internal step [N], space axes: the
    /// force the motion exerts on the body.
    ReactionForce,
    /// A prescribed motion's reaction torque over the last internal step [N·m], space axes.
    ReactionTorque,
}

/// Which value of a winch an output is (docs/method.md §23, `phstring::WinchSample`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WinchValue {
    /// Length paid out since `t = 0` [m] (negative: hauled in).
    Payout,
    /// Reference length of string off the drum, beyond the drum point [m].
    Length,
    /// Mean payout speed over the last internal step [m/s].
    Speed,
    /// Tension of the element at the drum [N].
    Tension,
    /// Mean power the winch supplied over the last internal step [W] (negative: taken).
    Power,
    /// Energy the winch supplied since `t = 0` [J].
    Energy,
}

/// One FMI scalar variable (all are `Real`).
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Name in `modelDescription.xml` (flat naming convention).
    pub name: String,
    /// Causality.
    pub causality: Causality,
    /// Unit symbol: `N`, `m`, `m/s`, `J`, `kg/m`, `s`, `N.m`, `rad`, `rad/s`, `W`, `1`.
    pub unit: &'static str,
    /// Description shown by tools.
    pub description: String,
    /// Start value (parameters and inputs).
    pub start: Option<f64>,
    /// What it is.
    pub quantity: Quantity,
}

/// A parameter: a scenario key the FMU overrides (as `--set key=value`) before it sets up
/// the simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Dotted scenario key (`material.ea`, `materials.NAME.rho_a`, `time.h`).
    pub key: String,
    /// The scenario's value.
    pub value: f64,
}

/// Everything the FMU exposes, in value-reference order (value reference = index).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSpec {
    /// `modelName`: the scenario's title, or the file name.
    pub model_name: String,
    /// Spatial dimension.
    pub dimension: usize,
    /// The rigid bodies' names, in file order (body `b` is `body{b}.*`).
    pub bodies: Vec<String>,
    /// The variables; a variable's value reference is its index.
    pub variables: Vec<Variable>,
    /// The parameters, in the order of their variables.
    pub parameters: Vec<Parameter>,
    /// `time.end` [s] (the default experiment's stop time).
    pub t_end: f64,
    /// `time.h` [s] (the default experiment's step size).
    pub h: f64,
    /// The GUID, `{8-4-4-4-12}` hexadecimal digits.
    pub guid: String,
}

/// Axis names.
const AXES: [&str; 3] = ["x", "y", "z"];

impl ModelSpec {
    /// The variables of the FMU of scenario `file` (validated in full, the simulation set
    /// up once to learn its ports).
    pub fn new(file: &ScenarioFile) -> Result<Self, ScenarioError> {
        phstring::by_dim!(file.setup()?, v => Self::of(file, v))
    }

    /// The variables of the FMU of `file` in `D` dimensions: parameters, inputs, outputs.
    fn of<const D: usize>(file: &ScenarioFile, v: Setup<D>) -> Result<Self, ScenarioError> {
        let (mut vars, parameters) = parameter_variables(&file.scenario);
        // Inputs: external loads, then external motions, then external body wrenches.
        vars.extend(load_inputs(file, &v)?);
        vars.extend(motion_inputs(&v));
        vars.extend(bodies::wrench_inputs(file, &v)?);
        vars.extend(winches::speed_inputs(&v));
        let body_vars = bodies::outputs(&v);
        let winch_vars = winches::outputs(&v);
        let body_names = v.components.bodies.iter().map(|b| b.name.clone()).collect();
        // Outputs: the ports (one simulation is set up to learn them), energies, nodes.
        let boundary = v.problem.system.boundary();
        let (loads, feedback) = (boundary.loads.len(), boundary.feedback.len());
        let step = v.settings.step;
        let v = v.map_problem(|b| {
            Simulation::<D, Material>::from_system(b.system, b.state, step).map_err(|cause| {
                ScenarioError::Setup {
                    path: file.path.clone(),
                    with_sets: false,
                    cause,
                }
            })
        })?;
        let Validated {
            problem: sim,
            settings,
            components,
            fmu_nodes,
            ..
        } = v;
        let (t_end, h) = (settings.t_end, settings.step.h);
        vars.extend(port_outputs(&sim, loads, feedback, &components));
        vars.extend(energy_outputs());
        vars.extend(node_outputs::<D>(&fmu_nodes, &components));
        vars.extend(body_vars);
        vars.extend(winch_vars);
        let model_name = file.scenario.title.clone();
        let mut spec = Self {
            model_name: model_name.unwrap_or_else(|| file.path.display().to_string()),
            dimension: D,
            bodies: body_names,
            variables: vars,
            parameters,
            t_end,
            h,
            guid: String::new(),
        };
        spec.guid = spec.compute_guid(file.text());
        Ok(spec)
    }

    /// The GUID: FNV-1a hashes of the crate version, the variable list and the scenario.
    fn compute_guid(&self, text: &str) -> String {
        let mut content = format!("phstring-fmu {}\n", env!("CARGO_PKG_VERSION"));
        for v in &self.variables {
            content.push_str(&format!("{}|{:?}|{:?}\n", v.name, v.causality, v.start));
        }
        content.push_str(text);
        let a = fnv1a64_hex(content.as_bytes());
        let b = fnv1a64_hex(format!("guid\n{content}").as_bytes());
        format!(
            "{{{}-{}-{}-{}-{}}}",
            &a[..8],
            &a[8..12],
            &a[12..16],
            &b[..4],
            &b[4..16]
        )
    }

    /// `modelDescription.xml` for FMI 2.0 Co-Simulation with the shared library
    /// `model_identifier`.
    pub fn model_description(&self, model_identifier: &str) -> String {
        self.describe(false, model_identifier)
    }

    /// `modelDescription.xml` for FMI 3.0 Co-Simulation with the shared library
    /// `model_identifier`: the same variables as FMI 2.0 (`Float64`), plus the independent
    /// variable `time` (value reference [`Self::time_reference`]).
    pub fn model_description_fmi3(&self, model_identifier: &str) -> String {
        self.describe(true, model_identifier)
    }

    /// The value reference of the independent variable `time` in FMI 3.0 (after all others).
    pub fn time_reference(&self) -> u32 {
        self.variables.len() as u32
    }

    /// The model's one-line description: the dimension and the rigid bodies by name.
    fn description(&self) -> String {
        let bodies = match self.bodies.len() {
            0 => String::new(),
            1 => format!(" with the rigid body {}", self.bodies[0]),
            _ => format!(" with the rigid bodies {}", self.bodies.join(", ")),
        };
        format!(
            "Port-Hamiltonian string{bodies} (dimension {}): exact energy balance through its ports",
            self.dimension
        )
    }

    /// The model description in FMI 3.0 (`v3`) or 2.0.
    fn describe(&self, v3: bool, model_identifier: &str) -> String {
        let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let (version, token, extra) = match v3 {
            true => ("3.0", "instantiationToken", ""),
            false => ("2.0", "guid", " numberOfEventIndicators=\"0\""),
        };
        x.push_str(&format!(
            "<fmiModelDescription fmiVersion=\"{version}\" modelName=\"{}\" {token}=\"{}\" description=\"{}\" generationTool=\"phstring {}\" variableNamingConvention=\"flat\"{extra}>\n",
            escape(&self.model_name),
            self.guid,
            escape(&self.description()),
            env!("CARGO_PKG_VERSION")
        ));
        let capabilities = match v3 {
            true => {
                "canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" providesDirectionalDerivatives=\"false\" providesAdjointDerivatives=\"false\" hasEventMode=\"false\" providesIntermediateUpdate=\"false\" canReturnEarlyAfterIntermediateUpdate=\"false\" maxOutputDerivativeOrder=\"0\""
            }
            false => {
                "canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" providesDirectionalDerivative=\"false\""
            }
        };
        x.push_str(&format!(
            "  <CoSimulation modelIdentifier=\"{}\" canHandleVariableCommunicationStepSize=\"true\" {capabilities}/>\n",
            escape(model_identifier)
        ));
        x.push_str(&self.common_sections());
        x.push_str("  <ModelVariables>\n");
        if v3 {
            x.push_str(&format!(
                "    <Float64 name=\"time\" valueReference=\"{}\" causality=\"independent\" variability=\"continuous\" description=\"simulation time\" unit=\"s\"/>\n",
                self.time_reference()
            ));
        }
        for (vr, v) in self.variables.iter().enumerate() {
            let (causality, variability, initial) = match v.causality {
                Causality::Parameter => ("parameter", "fixed", " initial=\"exact\""),
                Causality::Input => ("input", "continuous", ""),
                Causality::Output => ("output", "continuous", " initial=\"calculated\""),
            };
            let common = format!(
                "name=\"{}\" valueReference=\"{vr}\" description=\"{}\" causality=\"{causality}\" variability=\"{variability}\"{initial}",
                escape(&v.name),
                escape(&v.description)
            );
            let start = v
                .start
                .map_or_else(String::new, |s| format!(" start=\"{}\"", num(s)));
            let min = match v.quantity {
                Quantity::Parameter(_) => " min=\"0\"",
                _ => "",
            };
            let real = format!("unit=\"{}\"{min}{start}", escape(v.unit));
            x.push_str(&match v3 {
                true => format!("    <Float64 {common} {real}/>\n"),
                false => format!(
                    "    <ScalarVariable {common}>\n      <Real {real}/>\n    </ScalarVariable>\n"
                ),
            });
        }
        x.push_str("  </ModelVariables>\n");
        x.push_str("  <ModelStructure>\n");
        let outputs: Vec<usize> = (0..self.variables.len())
            .filter(|&i| self.variables[i].causality == Causality::Output)
            .collect();
        // FMI 2.0 names a variable by its 1-based position, FMI 3.0 by its value reference.
        let unknowns = |element: &str, list: &str| {
            let mut y = String::new();
            for &i in &outputs {
                y.push_str(&match v3 {
                    true => format!("    <{element} valueReference=\"{i}\"/>\n"),
                    false => format!("      <Unknown index=\"{}\"/>\n", i + 1),
                });
            }
            match (v3, outputs.is_empty()) {
                (true, _) => y,
                (false, true) => String::new(),
                (false, false) => format!("    <{list}>\n{y}    </{list}>\n"),
            }
        };
        x.push_str(&unknowns("Output", "Outputs"));
        x.push_str(&unknowns("InitialUnknown", "InitialUnknowns"));
        x.push_str("  </ModelStructure>\n");
        x.push_str("</fmiModelDescription>\n");
        x
    }

    /// Units, log categories and the default experiment: the same elements in FMI 2.0 and
    /// 3.0.
    fn common_sections(&self) -> String {
        let mut x = String::from("  <UnitDefinitions>\n");
        for (unit, base) in UNITS {
            x.push_str(&format!(
                "    <Unit name=\"{unit}\"><BaseUnit {base}/></Unit>\n"
            ));
        }
        x.push_str("  </UnitDefinitions>\n");
        x.push_str("  <LogCategories>\n");
        for (name, what) in LOG_CATEGORIES {
            x.push_str(&format!(
                "    <Category name=\"{name}\" description=\"{}\"/>\n",
                escape(what)
            ));
        }
        x.push_str("  </LogCategories>\n");
        x.push_str(&format!(
            "  <DefaultExperiment startTime=\"0\" stopTime=\"{}\" stepSize=\"{}\"/>\n",
            num(self.t_end),
            num(self.h)
        ));
        x
    }
}

/// `node N`, with the node's name if it has one (`node 4 ("fairlead")`).
fn node_label(c: &Components, node: usize) -> String {
    match c.node_name(node) {
        Some(name) => format!("node {node} (\"{name}\")"),
        None => format!("node {node}"),
    }
}

/// The parameter variables of scenario `s` (material stiffness and mass per length, the
/// step size) with their parameters, in value-reference order.
fn parameter_variables(s: &Scenario) -> (Vec<Variable>, Vec<Parameter>) {
    let mut vars = Vec::new();
    let mut parameters = Vec::new();
    let mut param = |name: String, key: String, value: f64| {
        let (unit, what) = match key.rsplit('.').next() {
            Some("ea") => ("N", "axial stiffness EA"),
            Some("rho_a") => ("kg/m", "mass per unit length ρA"),
            _ => ("s", "internal step size h (largest)"),
        };
        vars.push(Variable {
            name,
            causality: Causality::Parameter,
            unit,
            description: format!("{what} (scenario key {key})"),
            start: Some(value),
            quantity: Quantity::Parameter(parameters.len()),
        });
        parameters.push(Parameter { key, value });
    };
    if let Some(m) = &s.material {
        let m = m.get_ref();
        param("EA".into(), "material.ea".into(), *m.ea.get_ref());
        param("rhoA".into(), "material.rho_a".into(), *m.rho_a.get_ref());
    }
    for (name, m) in &s.materials {
        let m = m.get_ref();
        param(
            format!("EA.{name}"),
            format!("materials.{name}.ea"),
            *m.ea.get_ref(),
        );
        param(
            format!("rhoA.{name}"),
            format!("materials.{name}.rho_a"),
            *m.rho_a.get_ref(),
        );
    }
    param("h".into(), "time.h".into(), *s.time.h.get_ref());
    (vars, parameters)
}

/// The input variables of the external loads of `v`, one per component, starting at the
/// load's force at `t = 0` (which must be finite: an error points at the scenario's key).
fn load_inputs<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
) -> Result<Vec<Variable>, ScenarioError> {
    let (s, c) = (&file.scenario, &v.components);
    let mut vars = Vec::new();
    for (k, load) in v.problem.system.boundary().loads.iter().enumerate() {
        if !c.loads[k].external {
            continue;
        }
        let at_zero = (load.force)(0.0);
        if let Some(i) = (0..D).find(|&i| !at_zero[i].is_finite()) {
            // The k-th table with a `force` is load k.
            let (j, spec) = s
                .boundary
                .iter()
                .enumerate()
                .filter(|(_, b)| b.force.is_some())
                .nth(k)
                .expect("one table per load");
            let key = format!("boundary.{j}.force");
            let span = spec.force.as_ref().map_or(0..0, |f| f.span());
            return Err(ScenarioError::Invalid {
                origin: file.origin(&key, span),
                key,
                reason: format!(
                    "component {} is {} at t = 0, the start value of the FMU input load{k}.F.{}: an input starts at a finite force",
                    AXES[i], at_zero[i], AXES[i]
                ),
            });
        }
        for i in 0..D {
            vars.push(Variable {
                name: format!("load{k}.F.{}", AXES[i]),
                causality: Causality::Input,
                unit: "N",
                description: format!(
                    "force on {} in {} (held over each communication step)",
                    node_label(c, load.node),
                    AXES[i]
                ),
                start: Some(at_zero[i]),
                quantity: Quantity::LoadForce {
                    load: k,
                    component: i,
                },
            });
        }
    }
    Ok(vars)
}

/// The input variables of the external motions of `v`, starting at their positions at
/// `t = 0`.
fn motion_inputs<const D: usize>(v: &Setup<D>) -> Vec<Variable> {
    let c = &v.components;
    let motions = v.problem.system.boundary().motions.iter().enumerate();
    motions
        .filter(|(m, _)| c.motions[*m].external)
        .map(|(m, motion)| Variable {
            name: format!("motion{m}.{}", AXES[motion.component]),
            causality: Causality::Input,
            unit: "m",
            description: format!(
                "position in {} that {} reaches at the end of each communication step (moving there at constant speed)",
                AXES[motion.component],
                node_label(c, motion.node)
            ),
            start: Some((motion.position)(0.0)),
            quantity: Quantity::MotionPosition { motion: m },
        })
        .collect()
}

/// The components (0 = x) of `node` that its supports and motions hold.
fn held_components(c: &Components, node: usize) -> Vec<usize> {
    let mut comps: Vec<usize> = c
        .supports
        .iter()
        .filter(|sc| sc.node == node)
        .flat_map(|sc| sc.fixed.iter())
        .filter_map(|a| AXES.iter().position(|x| x == a))
        .collect();
    comps.extend(
        c.motions
            .iter()
            .filter(|mc| mc.node == node)
            .filter_map(|mc| AXES.iter().position(|x| *x == mc.component)),
    );
    comps.sort_unstable();
    comps.dedup();
    comps
}

/// The output variables of the ports of `sim` (`loads` load ports, then `feedback` control
/// ports, then the supports): each port's output per component, and a control port's force.
fn port_outputs<const D: usize>(
    sim: &Simulation<D, Material>,
    loads: usize,
    feedback: usize,
    c: &Components,
) -> Vec<Variable> {
    let mut vars = Vec::new();
    for (p, port) in sim.ports().iter().enumerate() {
        let control = (loads..loads + feedback).contains(&p);
        let (prefix, comps) = if p < loads {
            (format!("load{p}"), (0..D).collect::<Vec<_>>())
        } else if p < loads + feedback {
            (format!("control{}", p - loads), (0..D).collect())
        } else {
            (
                format!("support{}", port.node),
                held_components(c, port.node),
            )
        };
        for &i in &comps {
            let (name, unit, what) = match port.kind {
                PortKind::Force => (
                    format!("{prefix}.v.{}", AXES[i]),
                    "m/s",
                    "mid-step velocity",
                ),
                PortKind::Velocity => (
                    format!("{prefix}.R.{}", AXES[i]),
                    "N",
                    "force the support exerts on the string",
                ),
            };
            vars.push(Variable {
                name,
                causality: Causality::Output,
                unit,
                description: format!(
                    "{what} of {} in {} over the last internal step",
                    node_label(c, port.node),
                    AXES[i]
                ),
                start: None,
                quantity: Quantity::PortOutput {
                    port: p,
                    component: i,
                },
            });
        }
        if control {
            for i in 0..D {
                vars.push(Variable {
                    name: format!("{prefix}.F.{}", AXES[i]),
                    causality: Causality::Output,
                    unit: "N",
                    description: format!(
                        "force of the feedback law on {} in {} over the last internal step",
                        node_label(c, port.node),
                        AXES[i]
                    ),
                    start: None,
                    quantity: Quantity::PortInput {
                        port: p,
                        component: i,
                    },
                });
            }
        }
    }
    vars
}

/// The energy output variables [J]: `Ĥ`, `T̂`, `V̂`, supplied, dissipated, balance error.
fn energy_outputs() -> Vec<Variable> {
    let energies = [
        ("H", Quantity::Hamiltonian, "Hamiltonian Ĥ = T̂ + V̂"),
        ("T", Quantity::Kinetic, "kinetic energy T̂"),
        (
            "V",
            Quantity::Potential,
            "potential energy V̂ (strain energy plus potential of the body force)",
        ),
        (
            "supplied",
            Quantity::Supplied,
            "energy supplied through the ports since the start",
        ),
        (
            "dissipated",
            Quantity::Dissipated,
            "energy dissipated since the start",
        ),
        (
            "balance_error",
            Quantity::BalanceError,
            "energy balance Ĥ(t) − Ĥ(0) − supplied + dissipated",
        ),
    ];
    energies
        .into_iter()
        .map(|(name, quantity, description)| Variable {
            name: name.into(),
            causality: Causality::Output,
            unit: "J",
            description: description.into(),
            start: None,
            quantity,
        })
        .collect()
}

/// The output variables of the positions [m] of `nodes`, per component.
fn node_outputs<const D: usize>(nodes: &[usize], c: &Components) -> Vec<Variable> {
    let mut vars = Vec::new();
    for &node in nodes {
        for i in 0..D {
            vars.push(Variable {
                name: format!("node{node}.r.{}", AXES[i]),
                causality: Causality::Output,
                unit: "m",
                description: format!("position of {} in {}", node_label(c, node), AXES[i]),
                start: None,
                quantity: Quantity::NodePosition { node, component: i },
            });
        }
    }
    vars
}

/// The units used, with their SI base-unit exponents.
const UNITS: [(&str, &str); 11] = [
    ("N", "kg=\"1\" m=\"1\" s=\"-2\""),
    ("m", "m=\"1\""),
    ("m/s", "m=\"1\" s=\"-1\""),
    ("J", "kg=\"1\" m=\"2\" s=\"-2\""),
    ("kg/m", "kg=\"1\" m=\"-1\""),
    ("s", "s=\"1\""),
    ("N.m", "kg=\"1\" m=\"2\" s=\"-2\""),
    ("rad", "rad=\"1\""),
    ("rad/s", "s=\"-1\" rad=\"1\""),
    ("W", "kg=\"1\" m=\"2\" s=\"-3\""),
    ("1", ""),
];

/// The log categories the FMU reports under.
pub const LOG_CATEGORIES: [(&str, &str); 3] = [
    (
        "logStatusError",
        "errors: bad values, calls out of order, failures that end the run",
    ),
    (
        "logStatusDiscard",
        "a step that failed (the FMU stays at the last step it completed)",
    ),
    ("logEvents", "set-up and progress of the simulation"),
];

/// A real number as XML attribute text, shortest round-trip form.
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// `s` with the five XML special characters escaped.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_handles_markup_and_control_characters() {
        assert_eq!(escape("a<b & \"c\"\u{1}"), "a&lt;b &amp; &quot;c&quot; ");
    }
}
