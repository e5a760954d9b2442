//! Scenario files (TOML): serde data, `--set` overrides, and validation into a
//! [`phstring::Network`]: one string (`[geometry]`, `[mesh]`, `[material]`, built as the
//! chain [`phstring::Problem`] it always was) or a network of named nodes, strings and
//! springs. Every key is documented in `docs/scenario.md`.
//!
//! Each part of a scenario has its own validator, in its own file: `single.rs` (geometry,
//! mesh), `material.rs` (cross-sections), `network.rs` (materials, nodes, strings,
//! springs), `attach.rs` (point masses, boundary conditions), `initial.rs` (the initial
//! state), `settings.rs` (body force, time, Newton, output); `refs.rs` resolves node
//! references.
//!
//! Errors name the key and its `line:column` in the file (or the `--set` option that gave
//! the value).

mod attach;
mod bathymetry;
mod bodies;
mod body_feedback;
mod body_motion;
mod body_water;
mod components;
mod expr;
mod initial;
mod material;
mod network;
mod overrides;
mod refs;
mod rounding;
mod settings;
mod single;
mod spec;
pub mod start;
mod tables;
mod water;
mod winch;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use phstring::{
    Boundary, Material, Network, NetworkBuilder, PointMass, Problem, State, StepParams, Vector,
};
use toml::Spanned;

pub use body_water::BodyWaterComponent;
pub use components::{
    BodyComponent, BodyPointComponent, Components, LoadComponent, MotionComponent, NamedNode,
    PointMassComponent, SpringComponent, StringComponent, SupportComponent, WinchComponent,
};
pub use expr::Expr;
pub use initial::{InitialConditions, Net};
pub use network::{MAX_NAME_BYTES, MAX_NAMED_NODES, MAX_PATH, MAX_SPRINGS, MAX_STRINGS};
pub use overrides::{MAX_BRACES, MAX_KEY_BYTES, MAX_KEY_SEGMENTS};
pub use refs::NodeRef;
pub use rounding::ROUNDING_FACTOR;
pub use settings::MAX_STEPS;
pub use single::MAX_ELEMENTS;
pub use spec::{
    BodyForceSpec, BodyMotionSpec, BodySpec, BoundarySpec, DeckSpec, FixedSpec, FmuSpec, Geometry,
    InitialSpec, MaterialSpec, MeshSpec, NewtonSpec, NodeSpec, OutputSpec, PointMassSpec, Scenario,
    SpringSpec, StringPathSpec, TimeSpec, WrenchSpec,
};
pub use start::{AnyRunning, AnySetup, Built, Running, Setup, StartError};

use components::AXES;
use overrides::{apply_set, check_braces, clip_lines, line_col, toml_error};
use refs::Nodes;

use crate::text::{clip, num, printable};

/// Where a value came from, for error messages.
#[derive(Debug, Clone, PartialEq)]
pub enum Origin {
    /// A position in the scenario file.
    File {
        /// The file.
        path: PathBuf,
        /// Line, 1-based.
        line: usize,
        /// Column, 1-based.
        column: usize,
        /// `--set` added keys, so lines refer to the file with those keys inserted.
        shifted: bool,
    },
    /// A `--set` option.
    Set(String),
    /// The scenario as a whole (the key was not given, or the error concerns several keys).
    Scenario(PathBuf),
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Origin::File {
                path,
                line,
                column,
                shifted,
            } => {
                write!(f, "{}:{line}:{column}", path.display())?;
                if *shifted {
                    write!(f, " (counting the keys added by --set)")?;
                }
                Ok(())
            }
            Origin::Set(s) => write!(f, "--set {}", printable(&clip(s), false)),
            Origin::Scenario(path) => write!(f, "{}", path.display()),
        }
    }
}

/// Errors while reading or validating a scenario.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario file {}: {cause}", path.display())]
    Read {
        /// File.
        path: PathBuf,
        /// The operating system's reason (part of the message, not a separate source, so
        /// that it is printed once).
        cause: std::io::Error,
    },
    /// The file is larger than [`MAX_SCENARIO_BYTES`].
    #[error(
        "scenario file {} is larger than {} MiB; is it a scenario file?",
        path.display(),
        MAX_SCENARIO_BYTES >> 20
    )]
    TooLarge {
        /// File.
        path: PathBuf,
    },
    /// The text (file or `--set` value) has more `{` than the TOML parser can take: its
    /// inline-table parsing recurses once per `{` and could overflow the stack.
    #[error(
        "{what} has {count} `{{` characters, more than the {MAX_BRACES} a scenario may have (inline tables nest too deep to parse safely)"
    )]
    TooManyBraces {
        /// The scenario file or the `--set` option.
        what: String,
        /// Number of `{` characters.
        count: usize,
    },
    /// The file is not UTF-8 text.
    #[error("scenario file {} is not UTF-8 text (byte {valid_up_to}, on line {line}, is invalid); is it a TOML file?", path.display())]
    NotText {
        /// File.
        path: PathBuf,
        /// Bytes before the first invalid one.
        valid_up_to: usize,
        /// 1-based line of the first invalid byte.
        line: usize,
    },
    /// TOML syntax or type error (unknown key, wrong type, missing key).
    #[error("{}: {}", origin, clip_lines(message))]
    Toml {
        /// Where.
        origin: Origin,
        /// The parser's message, with the offending line.
        message: String,
    },
    /// A `--set` option is malformed.
    #[error("--set {}: {reason}", printable(&clip(option), false))]
    Set {
        /// The option as given.
        option: String,
        /// What is wrong.
        reason: String,
    },
    /// A `--vary` option is malformed.
    #[error("--vary {}: {reason}", printable(&clip(option), false))]
    Vary {
        /// The option as given.
        option: String,
        /// What is wrong.
        reason: String,
    },
    /// A value is invalid.
    #[error("{origin}: `{key}` {reason}")]
    Invalid {
        /// Dotted key path, e.g. `material.ea`.
        key: String,
        /// Where.
        origin: Origin,
        /// What is wrong.
        reason: String,
    },
    /// Every key is valid, but the system they set up is not (a quantity derived from
    /// several keys overflows, e.g. the initial energy of a string at 1e308 m under gravity).
    #[error("{}{}: {cause}", path.display(), if *with_sets { " (with the --set overrides)" } else { "" })]
    Setup {
        /// The scenario file.
        path: PathBuf,
        /// Whether `--set` overrides were applied.
        with_sets: bool,
        /// The cause, part of the message (not a chained source, so that it is printed once).
        cause: phstring::SetupError,
    },
}

/// A scenario with its source text, so that errors can point into the file.
#[derive(Debug, Clone)]
pub struct ScenarioFile {
    /// The parsed scenario.
    pub scenario: Scenario,
    /// Path of the file (for messages).
    pub path: PathBuf,
    text: String,
    /// Dotted keys set with `--set`, with the option text.
    overrides: BTreeMap<String, String>,
    /// Whether `--set` inserted keys that were not in the file (line numbers shift).
    shifted: bool,
}

/// Largest scenario file read [bytes] (16 MiB; the examples have about 1 KiB). Reading
/// stops there, so `/dev/zero` or a huge file is refused instead of read forever.
pub const MAX_SCENARIO_BYTES: u64 = 16 << 20;

/// Reads `path`, applies `--set key=value` overrides and parses the scenario.
pub fn load(path: &Path, sets: &[String]) -> Result<ScenarioFile, ScenarioError> {
    use std::io::Read as _;
    let read_err = |cause| ScenarioError::Read {
        path: path.to_path_buf(),
        cause,
    };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(read_err)?
        .take(MAX_SCENARIO_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_err)?;
    if bytes.len() as u64 > MAX_SCENARIO_BYTES {
        return Err(ScenarioError::TooLarge {
            path: path.to_path_buf(),
        });
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid_up_to = e.utf8_error().valid_up_to();
        ScenarioError::NotText {
            path: path.to_path_buf(),
            valid_up_to,
            line: crate::text::line_of_byte(e.as_bytes(), valid_up_to),
        }
    })?;
    parse(&text, path, sets)
}

/// Parses scenario `text` (named `path` in messages) with `--set` overrides.
pub fn parse(text: &str, path: &Path, sets: &[String]) -> Result<ScenarioFile, ScenarioError> {
    check_braces(text, || format!("scenario file {}", path.display()))?;
    for s in sets {
        check_braces(s, || format!("--set {}", printable(&clip(s), false)))?;
    }
    let mut overrides = BTreeMap::new();
    let mut shifted = false;
    let text = if sets.is_empty() {
        text.to_string()
    } else {
        let mut doc: toml_edit::DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| {
            toml_error(path, text, e.span(), e.message(), false)
        })?;
        for s in sets {
            let lines_before = doc.to_string().lines().count();
            let (key, _) = apply_set(&mut doc, s)?;
            shifted |= doc.to_string().lines().count() != lines_before;
            overrides.insert(key, s.clone());
        }
        doc.to_string()
    };
    let scenario: Scenario = toml::from_str(&text)
        .map_err(|e| toml_error(path, &text, e.span(), e.message(), shifted))?;
    Ok(ScenarioFile {
        scenario,
        path: path.to_path_buf(),
        text,
        overrides,
        shifted,
    })
}

/// The validated run settings that are not part of the problem.
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// Stepper parameters.
    pub step: StepParams,
    /// End time [s].
    pub t_end: f64,
    /// Output stride (steps).
    pub stride: usize,
    /// Rows of `energy.csv`, `ports.csv` and `end_tensions.csv` every so many steps
    /// (`output.row_stride`).
    pub row_stride: usize,
    /// Write an animated GIF of the configuration (`output.animation`; dimension 2 and 3).
    pub animation: bool,
    /// Output switches.
    pub output: OutputSpec,
    /// Static settling (`time.settle`), if asked for.
    pub settle: Option<phstring::Settle>,
}

/// A [`Validated`] scenario of its own dimension.
pub type AnyValidated = phstring::ByDim<Validated<1>, Validated<2>, Validated<3>>;

/// A validated problem in dimension `D` plus run settings and what reports need. `P` is
/// the problem as validated (a [`Network`]), then as built once into a system
/// ([`Built`](start::Built), a [`Setup`](start::Setup)), then as a running simulation
/// ([`Running`](start::Running)): every front end starts from one value of this type.
pub struct Validated<const D: usize, P = Network<D, Material>> {
    /// The problem: a network (a single-string scenario is a network of one group, built
    /// as the chain it always was). Its initial state is the one `[initial]` gives on the
    /// geometry's shape — unless `initial.equilibrium` is set: then it is the geometry's
    /// shape at rest, the starting point for the equilibrium solve, and the run builds the
    /// state with [`Validated::initial_state`] on the equilibrium positions.
    pub problem: P,
    /// `[initial]`: equilibrium start, displacement and velocity fields, per-node lists.
    pub initial: InitialConditions<D>,
    /// Settings.
    pub settings: RunSettings,
    /// Whether the scenario is a network (`[[string]]` tables) rather than one string.
    pub network: bool,
    /// The components (strings, springs, point masses, supports, motions, loads, named
    /// nodes) with their mesh nodes and elements, for reports and `summary.json`.
    pub components: Components,
    /// Force expressions per load (node, component texts), for reports.
    pub loads: Vec<(usize, Vec<String>)>,
    /// The first failure of a force expression during the run (a load that evaluates to an
    /// error is NaN to the library, which stops the step; this says why).
    pub load_error: Arc<std::sync::Mutex<Option<String>>>,
    /// `[fmu] nodes`: the mesh nodes whose positions an FMU reports, in file order.
    pub fmu_nodes: Vec<usize>,
    /// What is valid but likely to fail or mislead (e.g. elements too short for the
    /// rounding of their coordinates); `check` prints them, a run adds them to
    /// `summary.json`'s warnings.
    pub warnings: Vec<String>,
}

/// What the strings and springs of a scenario assemble to, before boundary conditions and
/// point masses are added.
enum Frame<const D: usize> {
    /// One string: the chain problem (without boundary conditions and point masses).
    Single(Problem<D, Material>),
    /// A network under construction.
    Network(NetworkBuilder<D, Material>),
}

/// The assembled strings and springs with what node references resolve against.
struct Skeleton<'s, const D: usize> {
    /// The mesh and its groups.
    frame: Frame<D>,
    /// Node names and strings, for node references.
    nodes: Nodes<'s>,
    /// Named nodes, strings and springs found so far.
    components: Components,
    /// Per node of a network: whether no string touches it (only springs); empty for a
    /// single string.
    massless: Vec<bool>,
    /// Dissipation of a single string (a network's groups carry their own).
    single_damping: phstring::Damping,
    /// `(element group, hydrodynamics)` of the strings with a `diameter`.
    hydro: Vec<(usize, phstring::LineHydro)>,
    /// The rigid bodies (a network's), without their wrench ports yet.
    bodies: Vec<bodies::BodyDraft<D>>,
    /// The strings that winches pay out (a network's).
    winches: Vec<winch::WinchString>,
}

impl<const D: usize> Skeleton<'_, D> {
    /// Initial position of mesh node `i` [m] (`i` must be a node).
    pub fn position(&self, i: usize) -> Vector<D> {
        match &self.frame {
            Frame::Single(p) => p.initial.r[i],
            Frame::Network(b) => b.position(i).unwrap_or_else(Vector::zeros),
        }
    }

    /// The network with `boundary` and `point_masses`.
    fn finish(
        self,
        boundary: Boundary<D>,
        point_masses: Vec<PointMass<D>>,
    ) -> Result<Network<D, Material>, phstring::SetupError> {
        match self.frame {
            Frame::Single(mut p) => {
                p.boundary = boundary;
                p.point_masses = point_masses;
                let mut net = Network::from(p);
                net.groups[0].damping = self.single_damping;
                Ok(net)
            }
            Frame::Network(b) => b.build(boundary, point_masses),
        }
    }
}

/// Whether a scenario is one string or a network.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Layout {
    Single,
    Network,
}

impl ScenarioFile {
    /// The scenario text as run (with `--set` overrides applied).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Where the value with `span` under dotted `key` came from. An element of an array
    /// value (`string.0.path.1`) came from `--set` if the array did (`string.0.path`).
    pub fn origin(&self, key: &str, span: Range<usize>) -> Origin {
        let mut k = key;
        loop {
            if let Some(set) = self.overrides.get(k) {
                return Origin::Set(set.clone());
            }
            match k.rsplit_once('.') {
                Some((parent, last)) if last.bytes().all(|b| b.is_ascii_digit()) => k = parent,
                _ => break,
            }
        }
        if span.is_empty() && span.start == 0 {
            return Origin::Scenario(self.path.clone());
        }
        let (line, column) = line_col(&self.text, span.start);
        Origin::File {
            path: self.path.clone(),
            line,
            column,
            shifted: self.shifted,
        }
    }

    /// The error of entry `index` of `output.channels` (a channel naming a line, node or
    /// point the run does not have), pointing at the entry.
    pub(crate) fn channel_error(&self, index: usize, reason: String) -> ScenarioError {
        let span = self
            .scenario
            .output
            .channels
            .get(index)
            .map_or(0..0, |c| c.span());
        self.invalid(&format!("output.channels.{index}"), span, reason)
    }

    fn invalid(&self, key: &str, span: Range<usize>, reason: impl Into<String>) -> ScenarioError {
        ScenarioError::Invalid {
            key: key.to_string(),
            origin: self.origin(key, span),
            reason: reason.into(),
        }
    }

    /// Validates the whole scenario in its own dimension without running it, including the
    /// system it sets up (quantities derived from several keys, such as the initial
    /// energies, must be finite).
    pub fn check(&self) -> Result<(), ScenarioError> {
        self.setup().map(|_| ())
    }

    /// [`Self::check`], returning the warnings of a valid scenario ([`Validated::warnings`]).
    pub fn check_with_warnings(&self) -> Result<Vec<String>, ScenarioError> {
        self.setup().map(|s| phstring::by_dim!(s, s => s.warnings))
    }

    /// Validates the scenario once and builds its system once, in its own dimension: where
    /// every front end (run, sweep, statics, modes, linearize, check, the FMU, the Python
    /// package) starts.
    pub fn setup(&self) -> Result<AnySetup, ScenarioError> {
        self.build(self.validated()?)
    }

    /// Validates the scenario in its own dimension (without building its system): the one
    /// place where the dimension of the file picks the code.
    pub fn validated(&self) -> Result<AnyValidated, ScenarioError> {
        Ok(match self.dimension()? {
            1 => phstring::ByDim::D1(self.validate::<1>()?),
            2 => phstring::ByDim::D2(self.validate::<2>()?),
            _ => phstring::ByDim::D3(self.validate::<3>()?),
        })
    }

    /// Builds the system of this scenario, validated ([`Self::validated`]).
    pub fn build(&self, validated: AnyValidated) -> Result<AnySetup, ScenarioError> {
        phstring::by_dim!(map validated, v => v.map_problem(|p| {
            start::Built::new(p).map_err(|cause| self.setup_error(cause))
        }))
        .transpose()
    }

    /// The spatial dimension, checked.
    pub fn dimension(&self) -> Result<usize, ScenarioError> {
        let d = &self.scenario.dimension;
        match *d.get_ref() {
            1 => Ok(1),
            2 => Ok(2),
            3 => Ok(3),
            v => Err(self.invalid("dimension", d.span(), format!("must be 1, 2 or 3, got {v}"))),
        }
    }

    /// An optional coefficient at `key`: 0 when absent, else at least 0 and finite.
    fn non_negative(&self, key: &str, v: Option<&Spanned<f64>>) -> Result<f64, ScenarioError> {
        let Some(v) = v else { return Ok(0.0) };
        let x = *v.get_ref();
        if x >= 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(
                key,
                v.span(),
                format!("must be at least 0 and finite, got {}", num(x)),
            ))
        }
    }

    fn positive(&self, key: &str, v: &Spanned<f64>) -> Result<f64, ScenarioError> {
        let x = *v.get_ref();
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(
                key,
                v.span(),
                format!("must be positive and finite, got {}", num(x)),
            ))
        }
    }

    fn vector<const D: usize>(
        &self,
        key: &str,
        v: &Spanned<Vec<f64>>,
    ) -> Result<Vector<D>, ScenarioError> {
        let x = v.get_ref();
        if x.len() != D {
            return Err(self.invalid(
                key,
                v.span(),
                format!(
                    "must have {D} components (dimension = {D}), got {}",
                    x.len()
                ),
            ));
        }
        if let Some(bad) = x.iter().find(|c| !c.is_finite()) {
            return Err(self.invalid(
                key,
                v.span(),
                format!("has a non-finite component {}", num(*bad)),
            ));
        }
        Ok(Vector::<D>::from_column_slice(x))
    }

    /// Which kind of scenario this is: `[[string]]` tables make a network, which has no
    /// `[geometry]`, `[mesh]` or `[material]`; without them, `[[node]]`, `[materials]` and
    /// `[[spring]]` are errors.
    fn layout(&self) -> Result<Layout, ScenarioError> {
        let s = &self.scenario;
        if !s.string.is_empty() {
            let single = [
                ("geometry", s.geometry.as_ref().map(|g| g.span())),
                ("mesh", s.mesh.as_ref().map(|m| m.span())),
                ("material", s.material.as_ref().map(|m| m.span())),
            ];
            if let Some((key, Some(span))) = single.into_iter().find(|(_, sp)| sp.is_some()) {
                return Err(self.invalid(
                    key,
                    span,
                    format!(
                        "belongs to a single-string scenario, but this one has [[string]] tables (a network): its strings run along their `path` with `elements` per span and a [materials.NAME] cross-section; remove [{key}]"
                    ),
                ));
            }
            return Ok(Layout::Network);
        }
        let network = [
            ("node", s.node.first().map(|n| n.span())),
            ("bodies", s.bodies.values().next().map(|b| b.span())),
            ("materials", s.materials.values().next().map(|m| m.span())),
            ("spring", s.spring.first().map(|n| n.span())),
        ];
        if let Some((key, Some(span))) = network.into_iter().find(|(_, sp)| sp.is_some()) {
            return Err(self.invalid(
                key,
                span,
                "belongs to a network, but this scenario has no [[string]] tables: a network's strings are [[string]] tables (and it has no [geometry], [mesh] or [material])",
            ));
        }
        Ok(Layout::Single)
    }

    /// Elements the scenario asks for, read before validation (no mesh is built): the
    /// single string's `mesh.elements` or `len(geometry.nodes) − 1`, or the strings'
    /// `elements × spans` plus one per spring (saturating; invalid counts count as 0). For
    /// memory and time estimates.
    pub fn element_count(&self) -> usize {
        let s = &self.scenario;
        if s.string.is_empty() {
            let elements = s.mesh.as_ref().and_then(|m| m.get_ref().elements.as_ref());
            let nodes = s.geometry.as_ref().and_then(|g| g.get_ref().nodes.as_ref());
            return match (elements, nodes) {
                (Some(n), _) => usize::try_from(*n.get_ref()).unwrap_or(0),
                (None, Some(nodes)) => nodes.get_ref().len().saturating_sub(1),
                (None, None) => 0,
            };
        }
        let strings = s.string.iter().fold(0usize, |sum, st| {
            let st = st.get_ref();
            let per_span = usize::try_from(*st.elements.get_ref()).unwrap_or(0);
            let spans = st.path.get_ref().len().saturating_sub(1);
            sum.saturating_add(per_span.saturating_mul(spans))
        });
        strings.saturating_add(s.spring.len())
    }

    /// Validates everything and builds the problem in dimension `D` (which must equal
    /// [`Self::dimension`]). Each part has its own validator: the layout (one string or a
    /// network), `[body_force]`, the strings and springs ([`Self::single_string`] or
    /// [`Self::network`]: geometry, materials, nodes, strings, springs), point masses,
    /// boundary conditions, and `[time]`, `[newton]`, `[output]`.
    pub fn validate<const D: usize>(&self) -> Result<Validated<D>, ScenarioError> {
        let s = &self.scenario;
        let dim = self.dimension()?;
        if dim != D {
            return Err(self.invalid(
                "dimension",
                s.dimension.span(),
                format!("is {dim}, expected {D}"),
            ));
        }
        let layout = self.layout()?;
        self.check_winch_tables(layout == Layout::Network)?;
        let body = self.body_force::<D>()?;
        let mut skeleton = match layout {
            Layout::Single => self.single_string::<D>(&body)?,
            Layout::Network => self.network::<D>(&body)?,
        };
        let (point_masses, mass_report, point_hydro) = self.point_masses(&skeleton, body.g())?;
        let water = self.water::<D>(body.gravity)?;
        let line_hydro = std::mem::take(&mut skeleton.hydro);
        let parts = self.boundary(&skeleton, self.first_mid_time())?;
        let mut drafts = std::mem::take(&mut skeleton.bodies);
        self.checked_bodies(&skeleton.nodes, &parts, &mut drafts)?;
        let fmu_nodes = self.fmu_nodes(&skeleton.nodes)?;
        if layout == Layout::Network {
            self.check_spring_nodes(&skeleton, &parts.boundary, &point_masses)?;
        }
        let mut components = std::mem::take(&mut skeleton.components);
        let winch_strings = std::mem::take(&mut skeleton.winches);
        let mut problem = skeleton
            .finish(parts.boundary, point_masses)
            .map_err(|cause| self.setup_error(cause))?;
        problem = self.attach_winches(problem, &winch_strings, &mut components.winches)?;
        if let Some(water) = water {
            self.supports_above_seabed(&water, &problem.boundary, &problem.initial.r)?;
            problem = line_hydro
                .into_iter()
                .fold(problem.with_water(water), |p, (g, h)| {
                    p.with_line_hydro(g, h)
                });
            problem = point_hydro
                .into_iter()
                .fold(problem, |p, h| p.with_point_hydro(h));
        }
        let starts = bodies::with_bodies(&mut problem, drafts);
        Self::report_body_drums(&problem, &winch_strings, &mut components.winches);
        let initial = self.initial_conditions((&problem).into(), layout == Layout::Network)?;
        if initial.changes_base() {
            // Every expression is evaluated at every node now, on the geometry's shape; with
            // `equilibrium` the run applies them again to the equilibrium shape.
            let state = initial.apply(&problem, &problem.initial.r)?;
            if !initial.equilibrium {
                problem.initial = initial.on_bodies(&problem.mesh, state, &starts)?;
            }
        }
        // Block Thomas needs a chain mesh: every single string, and a network numbered as one.
        let settings = self.run_settings(problem.mesh.is_chain())?;
        for st in &mut components.strings {
            st.reference_length = problem.mesh.lengths()[st.elements[0]..st.elements[1]]
                .iter()
                .sum();
        }
        let mut warnings = rounding::short_element_warnings(&problem, layout == Layout::Single);
        // A deck's own (its `--motion` table's first row far from the coupled points).
        warnings.extend(s.deck.iter().flat_map(|d| d.warnings.iter().cloned()));
        warnings.extend(self.table_end_warnings(settings.t_end));
        components.point_masses = mass_report;
        components.supports = supports(&problem.boundary);
        components.motions = parts.motions;
        components.controls = parts.controls;
        components.loads = parts
            .loads
            .iter()
            .map(|(node, force, external)| LoadComponent {
                node: *node,
                force: force.clone(),
                external: *external,
            })
            .collect();
        Ok(Validated {
            problem,
            initial,
            settings,
            network: layout == Layout::Network,
            components,
            loads: parts
                .loads
                .into_iter()
                .map(|(node, force, _)| (node, force))
                .collect(),
            load_error: parts.load_error,
            fmu_nodes,
            warnings,
        })
    }

    /// `[fmu] nodes`, resolved: each node once.
    fn fmu_nodes(&self, nodes: &refs::Nodes) -> Result<Vec<usize>, ScenarioError> {
        let Some(fmu) = &self.scenario.fmu else {
            return Ok(Vec::new());
        };
        let mut out: Vec<usize> = Vec::new();
        for (i, r) in fmu.get_ref().nodes.iter().enumerate() {
            let key = format!("fmu.nodes.{i}");
            let node = self.resolve(&key, r, nodes)?;
            if let Some(j) = out.iter().position(|&n| n == node) {
                return Err(self.invalid(
                    &key,
                    r.span(),
                    format!("is node {node} again (fmu.nodes.{j}): list each node once"),
                ));
            }
            out.push(node);
        }
        Ok(out)
    }

    /// `cause` as the error of this scenario's setup.
    fn setup_error(&self, cause: phstring::SetupError) -> ScenarioError {
        ScenarioError::Setup {
            path: self.path.clone(),
            with_sets: !self.overrides.is_empty(),
            cause,
        }
    }
}

impl<const D: usize> Validated<D> {
    /// The initial state from the base positions `base` [m] (one per mesh node: the
    /// equilibrium positions with `initial.equilibrium`), with the displacement, velocity,
    /// positions and velocities of `[initial]`: [`InitialConditions::apply`] on this problem.
    pub fn initial_state(&self, base: &[Vector<D>]) -> Result<State<D>, ScenarioError> {
        self.initial.apply(&self.problem, base)
    }
}

impl<const D: usize, P> Validated<D, P> {
    /// The same scenario with its problem replaced by `f(problem)` (built, started).
    pub fn map_problem<Q, E>(
        self,
        f: impl FnOnce(P) -> Result<Q, E>,
    ) -> Result<Validated<D, Q>, E> {
        let Validated {
            problem,
            initial,
            settings,
            network,
            components,
            loads,
            load_error,
            fmu_nodes,
            warnings,
        } = self;
        Ok(Validated {
            problem: f(problem)?,
            initial,
            settings,
            network,
            components,
            loads,
            load_error,
            fmu_nodes,
            warnings,
        })
    }
}

/// The nodes with fixed components, merged per node, in increasing node order.
fn supports<const D: usize>(boundary: &Boundary<D>) -> Vec<SupportComponent> {
    let mut by_node: BTreeMap<usize, [bool; D]> = BTreeMap::new();
    for f in &boundary.fixed {
        let c = by_node.entry(f.node).or_insert([false; D]);
        for (a, &b) in c.iter_mut().zip(&f.components) {
            *a |= b;
        }
    }
    by_node
        .into_iter()
        .filter(|(_, c)| c.iter().any(|&x| x))
        .map(|(node, c)| SupportComponent {
            node,
            fixed: (0..D).filter(|&i| c[i]).map(|i| AXES[i]).collect(),
        })
        .collect()
}
