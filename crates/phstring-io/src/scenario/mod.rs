//! Scenario files (TOML): serde data, `--set` overrides, and validation into a
//! [`phstring::Problem`]. Every key is documented in `docs/scenario.md`.
//!
//! Errors name the key and its `line:column` in the file (or the `--set` option that gave
//! the value).

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nanoexpr::Math;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Mesh, NewtonParams, NodalLoad, Problem, Scheme,
    SolverKind, State, StepParams, Vector,
};
use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::text::{clip, num, nums, printable};

/// A scenario as written in the file (before validation).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free-text title, printed in reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Spatial dimension `d` ∈ {1, 2, 3}.
    pub dimension: Spanned<i64>,
    /// Initial (and reference) geometry.
    pub geometry: Geometry,
    /// Discretization.
    #[serde(default)]
    pub mesh: MeshSpec,
    /// Material law and parameters.
    pub material: MaterialSpec,
    /// Body force.
    #[serde(default)]
    pub body_force: BodyForceSpec,
    /// Boundary conditions, one table per node.
    #[serde(default)]
    pub boundary: Vec<BoundarySpec>,
    /// Point masses at nodes (payloads, clump weights), one table each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub point_mass: Vec<PointMassSpec>,
    /// Time stepping.
    pub time: TimeSpec,
    /// Newton's method and the linear solver.
    #[serde(default)]
    pub newton: NewtonSpec,
    /// What to write.
    #[serde(default)]
    pub output: OutputSpec,
}

/// Geometry: a straight string from `start` to `end`, or an explicit polyline `nodes`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// First node position [m] (with `end`).
    #[serde(default)]
    pub start: Option<Spanned<Vec<f64>>>,
    /// Last node position [m] (with `start`).
    #[serde(default)]
    pub end: Option<Spanned<Vec<f64>>>,
    /// Explicit node positions [m] of a chain (instead of `start`/`end` and
    /// `mesh.elements`).
    #[serde(default)]
    pub nodes: Option<Spanned<Vec<Vec<f64>>>>,
    /// Unstretched (reference) length `L` [m]; default: the length of the initial polyline
    /// (no prestretch). Reference lengths of elements are proportional to their initial
    /// lengths.
    #[serde(default)]
    pub length: Option<Spanned<f64>>,
}

/// Mesh size.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Number of elements (with `geometry.start`/`end`).
    #[serde(default)]
    pub elements: Option<Spanned<i64>>,
}

/// Material law.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// `hyperelastic` (default), `linear_elastic`, `st_venant_kirchhoff`,
    /// `tension_only_linear` or `tension_only_hyperelastic`.
    #[serde(default = "default_law")]
    pub law: Spanned<String>,
    /// Axial stiffness `EA` [N].
    pub ea: Spanned<f64>,
    /// Mass per unit length `ρA` [kg/m].
    pub rho_a: Spanned<f64>,
    /// Mass matrix: `consistent` (default) or `lumped`.
    #[serde(default = "default_mass")]
    pub mass: Spanned<String>,
}

fn default_law() -> Spanned<String> {
    Spanned::new(0..0, "hyperelastic".into())
}
fn default_mass() -> Spanned<String> {
    Spanned::new(0..0, "consistent".into())
}

/// Body force `b = ρA g + per_length`.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BodyForceSpec {
    /// Gravitational acceleration vector `g` [m/s²], e.g. `[0, -9.81]`.
    #[serde(default)]
    pub gravity: Option<Spanned<Vec<f64>>>,
    /// Additional force per unit reference length [N/m].
    #[serde(default)]
    pub per_length: Option<Spanned<Vec<f64>>>,
}

/// Which components of a node are fixed.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum FixedSpec {
    /// `true`: all components; `false`: none.
    All(bool),
    /// A list of components, e.g. `["x", "z"]`.
    Components(Vec<String>),
}

/// A boundary condition at one node.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// Node index; negative values count from the end (`-1` is the last node).
    pub node: Spanned<i64>,
    /// Fixed components (Dirichlet): `true` or a list like `["x", "y"]`.
    #[serde(default)]
    pub fixed: Option<Spanned<FixedSpec>>,
    /// Nodal force [N], one expression in `t` [s] per component.
    #[serde(default)]
    pub force: Option<Spanned<Vec<String>>>,
    /// Prescribed absolute position [m], one expression in `t` [s] per component; `""` leaves
    /// a component free. Each must equal the initial position at `t = 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<Spanned<Vec<String>>>,
}

/// A point mass at a node; gravity (`body_force.gravity`) acts on it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PointMassSpec {
    /// Node index; negative values count from the end (`-1` is the last node).
    pub node: Spanned<i64>,
    /// Mass [kg].
    pub kg: Spanned<f64>,
}

/// Time stepping.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// `dg` (discrete gradient, default) or `mp` (implicit midpoint).
    #[serde(default = "default_scheme")]
    pub scheme: Spanned<String>,
    /// Step size `h` [s].
    pub h: Spanned<f64>,
    /// End time `T` [s].
    pub end: Spanned<f64>,
    /// Step-size control: halve `h` when a step fails, grow it back after easy steps
    /// (default `true`). `false`: fixed steps, the run stops at the first failure.
    #[serde(default = "yes")]
    pub adaptive: bool,
    /// Most successive halvings of one step (default 12: `h` down to `h/4096`).
    #[serde(default = "default_max_halvings")]
    pub max_halvings: Spanned<i64>,
}

fn default_max_halvings() -> Spanned<i64> {
    Spanned::new(0..0, 12)
}

fn default_scheme() -> Spanned<String> {
    Spanned::new(0..0, "dg".into())
}

/// Newton's method.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NewtonSpec {
    /// Absolute residual tolerance [N] (Euclidean norm of the force residual). Given alone,
    /// the convergence test is absolute (the paper's 1e-11 N); with `rtol`, a floor under
    /// the relative test.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tol: Option<Spanned<f64>>,
    /// Tolerance relative to the step's force scale (see docs/method.md §9). When neither
    /// `tol` nor `rtol` is given: `rtol = 1e-12` with an absolute floor of 1e-15 N.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rtol: Option<Spanned<f64>>,
    /// Iteration limit per step.
    #[serde(default = "default_max_iter")]
    pub max_iter: Spanned<i64>,
    /// Linear solver: `auto` (default), `block_tridiagonal` or `sparse_lu`.
    #[serde(default = "default_solver")]
    pub solver: Spanned<String>,
    /// Backtracking line search on `½‖R‖²` (default `true`); `false`: plain Newton.
    #[serde(default = "yes")]
    pub line_search: bool,
    /// Nonlinear elimination: local Newton solves on the node range that carries the residual
    /// (default `true`; chain meshes with line search only).
    #[serde(default = "yes")]
    pub elimination: bool,
    /// Starting guess: `velocity` (`Δ = h v`), `acceleration`
    /// (`Δ = h v + ½h² a` with `a` from the previous step) or `midpoint_velocity`
    /// (`Δ = h v_{n−½}`, the previous step's mid-step velocity; the default).
    #[serde(default = "default_predictor")]
    pub predictor: Spanned<String>,
}

fn default_predictor() -> Spanned<String> {
    Spanned::new(0..0, "midpoint_velocity".into())
}

fn default_max_iter() -> Spanned<i64> {
    Spanned::new(0..0, 25)
}
fn default_solver() -> Spanned<String> {
    Spanned::new(0..0, "auto".into())
}

impl Default for NewtonSpec {
    fn default() -> Self {
        Self {
            tol: None,
            rtol: None,
            max_iter: default_max_iter(),
            solver: default_solver(),
            line_search: true,
            elimination: true,
            predictor: default_predictor(),
        }
    }
}

/// Output options.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write positions and VTK frames every `stride` steps (energies: every step).
    #[serde(default = "default_stride")]
    pub stride: Spanned<i64>,
    /// Write `positions.csv`.
    #[serde(default = "yes")]
    pub positions: bool,
    /// Write `paraview/string.pvd` and frames.
    #[serde(default = "yes")]
    pub vtk: bool,
    /// Write plots (SVG and PNG).
    #[serde(default = "yes")]
    pub plots: bool,
}

fn default_stride() -> Spanned<i64> {
    Spanned::new(0..0, 1)
}
fn yes() -> bool {
    true
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            stride: default_stride(),
            positions: true,
            vtk: true,
            plots: true,
        }
    }
}

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
    #[error("scenario file {} is not UTF-8 text (byte {valid_up_to} is invalid); is it a TOML file?", path.display())]
    NotText {
        /// File.
        path: PathBuf,
        /// Bytes before the first invalid one.
        valid_up_to: usize,
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
    let text = String::from_utf8(bytes).map_err(|e| ScenarioError::NotText {
        path: path.to_path_buf(),
        valid_up_to: e.utf8_error().valid_up_to(),
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

/// Most `{` characters in a scenario file or a `--set` option. The TOML parser recurses once
/// per `{` in some malformed inline tables (about 1 KB of stack each in release builds, more
/// in debug builds); real scenarios have a handful.
pub const MAX_BRACES: usize = 256;

/// Refuses `text` with more than [`MAX_BRACES`] `{` (see [`ScenarioError::TooManyBraces`]).
fn check_braces(text: &str, what: impl FnOnce() -> String) -> Result<(), ScenarioError> {
    let count = text.bytes().filter(|&b| b == b'{').count();
    if count > MAX_BRACES {
        return Err(ScenarioError::TooManyBraces {
            what: what(),
            count,
        });
    }
    Ok(())
}

fn toml_error(
    path: &Path,
    text: &str,
    span: Option<Range<usize>>,
    message: &str,
    shifted: bool,
) -> ScenarioError {
    let start = span.map_or(0, |s| s.start);
    let (line, column) = line_col(text, start);
    let origin = Origin::File {
        path: path.to_path_buf(),
        line,
        column,
        shifted,
    };
    let excerpt = match &origin {
        Origin::File { line, .. } => text
            .lines()
            .nth(line - 1)
            .map(|l| format!("\n  | {}", clip(l)))
            .unwrap_or_default(),
        _ => String::new(),
    };
    ScenarioError::Toml {
        origin,
        message: format!("{}{excerpt}", message.trim_end()),
    }
}

/// `message` with each line shortened by [`clip`] (a parser message quotes the offending
/// line, which may be megabytes long).
fn clip_lines(message: &str) -> String {
    message.lines().map(clip).collect::<Vec<_>>().join("\n")
}

/// 1-based line and column of byte offset `pos` in `text`.
fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(text.len());
    let before = &text[..text.floor_char_boundary(pos)];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Most planned steps (`time.end / time.h`) of a run: 1e10 steps take days even on the
/// smallest mesh.
pub const MAX_STEPS: f64 = 1e10;

/// Most segments of a `--set` key (the deepest scenario key has three, `boundary.0.force`).
pub const MAX_KEY_SEGMENTS: usize = 32;
/// Longest `--set` key [bytes].
pub const MAX_KEY_BYTES: usize = 256;

/// Applies one `key.path=value` to the document; returns the dotted key (array indices
/// counted from the start, as validation names keys) and the value text.
fn apply_set(
    doc: &mut toml_edit::DocumentMut,
    option: &str,
) -> Result<(String, String), ScenarioError> {
    let err = |reason: &str| ScenarioError::Set {
        option: option.to_string(),
        reason: reason.to_string(),
    };
    let (key, value) = option
        .split_once('=')
        .ok_or_else(|| err("expected key=value, e.g. mesh.elements=300"))?;
    let key = key.trim();
    if key.len() > MAX_KEY_BYTES {
        return Err(err(&format!(
            "the key is {} bytes long; scenario keys have at most {MAX_KEY_BYTES}",
            key.len()
        )));
    }
    let parts: Vec<&str> = key.split('.').map(str::trim).collect();
    if parts.len() > MAX_KEY_SEGMENTS {
        return Err(err(&format!(
            "the key has {} segments; scenario keys have at most {MAX_KEY_SEGMENTS}",
            parts.len()
        )));
    }
    if parts.iter().any(|p| p.is_empty()) {
        return Err(err("empty key segment"));
    }
    let parsed = set_value(value).map_err(&err)?;
    // Walk down the tables; `path` is the key as validation names it.
    let mut table: &mut dyn toml_edit::TableLike = doc.as_table_mut();
    let mut path: Vec<String> = Vec::new();
    let mut i = 0;
    loop {
        let part = parts[i];
        path.push(part.to_string());
        if i + 1 == parts.len() {
            table.insert(part, toml_edit::Item::Value(parsed));
            return Ok((path.join("."), value.to_string()));
        }
        if table.get(part).is_none() {
            // Implicit: a table that only holds other tables gets no `[a.b]` header line of
            // its own.
            let mut t = toml_edit::Table::new();
            t.set_implicit(true);
            table.insert(part, toml_edit::Item::Table(t));
        }
        let here = path.join(".");
        let item = table
            .get_mut(part)
            .ok_or_else(|| err(&format!("no key `{here}`")))?;
        i += 1;
        table = match item {
            toml_edit::Item::ArrayOfTables(arr) => {
                let len = arr.len();
                let idx: i64 = parts[i].parse().map_err(|_| {
                    let rest = match parts.get(i + 1..) {
                        Some(r) if !r.is_empty() => r.join("."),
                        _ => "node".to_string(),
                    };
                    err(&format!(
                        "`{here}` is an array of tables: address an entry by its 0-based index, e.g. {here}.0.{rest} (negative indices count from the end)"
                    ))
                })?;
                let k = if idx < 0 { idx + len as i64 } else { idx };
                if !(0..len as i64).contains(&k) {
                    return Err(err(&format!("index {idx} out of range ({len} entries)")));
                }
                if i + 1 == parts.len() {
                    return Err(err("cannot replace a whole table"));
                }
                path.push(k.to_string());
                i += 1;
                arr.get_mut(k as usize)
                    .ok_or_else(|| err(&format!("index {idx} out of range ({len} entries)")))?
            }
            other => other
                .as_table_like_mut()
                .ok_or_else(|| err(&format!("`{here}` is not a table")))?,
        };
    }
}

/// The value of a `--set` option: one TOML value (which may span lines, like an array), or
/// else the text as a string. A string cannot span lines: such text is refused instead of
/// being cut at the line break.
fn set_value(value: &str) -> Result<toml_edit::Value, &'static str> {
    match value.trim().parse::<toml_edit::Value>() {
        Ok(v) => Ok(v.decorated(" ", "")),
        Err(_) if value.contains(['\n', '\r']) => Err(
            "the value has a line break but is not one TOML value (text that is not TOML is taken as a string, which must fit on one line)",
        ),
        Err(_) => Ok(toml_edit::Value::from(value.trim())),
    }
}

/// Node `raw` of a mesh of `n_nodes` nodes, negative indices counting from the end (`-1` is
/// the last node); `None` if out of range.
fn resolve_node(raw: i64, n_nodes: usize) -> Option<usize> {
    let node = if raw < 0 { n_nodes as i64 + raw } else { raw };
    usize::try_from(node).ok().filter(|&n| n < n_nodes)
}

/// The value of `expr` at `t`, component `component` of `boundary.{k}.{key}`; a failure or a
/// non-finite value gives NaN (the step then fails) and is kept in `slot` for the message,
/// the first one only (later ones are consequences).
fn eval_or_record(
    expr: &Expr,
    slot: &std::sync::Mutex<Option<String>>,
    key: &str,
    k: usize,
    component: usize,
    t: f64,
) -> f64 {
    let what = match expr.eval(t) {
        Ok(x) if x.is_finite() => return x,
        Ok(x) => format!("value {}", num(x)),
        Err(m) => m,
    };
    if let Ok(mut s) = slot.lock()
        && s.is_none()
    {
        *s = Some(format!(
            "`boundary.{k}.{key}` component {} \"{}\" at t = {} s: {what}",
            ["x", "y", "z"][component.min(2)],
            clip(expr.text()),
            num(t)
        ));
    }
    f64::NAN
}

/// Whether a force expression is the literal zero (`"0"`, `"0.0"`, …).
fn is_zero(text: &str) -> bool {
    text.trim().parse::<f64>() == Ok(0.0)
}

/// A force expression `t ↦ f(t)` [N].
#[derive(Debug, Clone)]
pub struct Expr {
    text: String,
}

impl Expr {
    /// Parses `text` and checks it by evaluating it at `t_check` [s] (the first time it will
    /// be used: the mid time of the first step).
    pub fn new(text: &str, t_check: f64) -> Result<Self, String> {
        let e = Self {
            text: text.to_string(),
        };
        e.eval(t_check)
            .map_err(|m| format!("expression \"{}\" is invalid: {m}", clip(text)))?;
        Ok(e)
    }
    /// Evaluates at time `t` [s].
    pub fn eval(&self, t: f64) -> Result<f64, String> {
        let ctx = ([("t", t)], Math);
        nanoexpr::evaluate_with::<f64, _>(&self.text, &ctx).map_err(|e| {
            let s = e.span;
            let part = self.text.get(s.start..s.end).unwrap_or("");
            format!(
                "{} (at \"{}\", characters {}..{})",
                e.kind,
                clip(part),
                s.start,
                s.end
            )
        })
    }
    /// The expression text.
    pub fn text(&self) -> &str {
        &self.text
    }
}

/// The validated run settings that are not part of the [`Problem`].
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// Stepper parameters.
    pub step: StepParams,
    /// End time [s].
    pub t_end: f64,
    /// Output stride (steps).
    pub stride: usize,
    /// Output switches.
    pub output: OutputSpec,
}

/// A validated problem in dimension `D` plus run settings.
pub struct Validated<const D: usize> {
    /// The problem.
    pub problem: Problem<D, Material>,
    /// Settings.
    pub settings: RunSettings,
    /// Force expressions per load (node, component texts), for reports.
    pub loads: Vec<(usize, Vec<String>)>,
    /// The first failure of a force expression during the run (a load that evaluates to an
    /// error is NaN to the library, which stops the step; this says why).
    pub load_error: Arc<std::sync::Mutex<Option<String>>>,
}

impl ScenarioFile {
    /// The scenario text as run (with `--set` overrides applied).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Where the value with `span` under dotted `key` came from.
    pub fn origin(&self, key: &str, span: Range<usize>) -> Origin {
        if let Some(set) = self.overrides.get(key) {
            return Origin::Set(set.clone());
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
        match self.dimension()? {
            1 => self.check_setup::<1>(),
            2 => self.check_setup::<2>(),
            _ => self.check_setup::<3>(),
        }
    }

    fn check_setup<const D: usize>(&self) -> Result<(), ScenarioError> {
        let v = self.validate::<D>()?;
        phstring::PhSystem::new(v.problem)
            .map(|_| ())
            .map_err(|cause| ScenarioError::Setup {
                path: self.path.clone(),
                with_sets: !self.overrides.is_empty(),
                cause,
            })
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

    /// The node a `node` key names (negative counts from the end), or an error naming `key`.
    fn node_index(
        &self,
        key: &str,
        spec: &Spanned<i64>,
        n_nodes: usize,
    ) -> Result<usize, ScenarioError> {
        let raw = *spec.get_ref();
        resolve_node(raw, n_nodes).ok_or_else(|| {
            self.invalid(
                key,
                spec.span(),
                format!(
                    "= {raw} is out of range: the mesh has nodes 0..={} (or -1..=-{n_nodes} from the end)",
                    n_nodes - 1
                ),
            )
        })
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

    /// Validates everything and builds the problem in dimension `D` (which must equal
    /// [`Self::dimension`]).
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
        // Material.
        let ea = self.positive("material.ea", &s.material.ea)?;
        let rho_a = self.positive("material.rho_a", &s.material.rho_a)?;
        let law = s.material.law.get_ref();
        let material = Material::from_name(law, ea).ok_or_else(|| {
            self.invalid(
                "material.law",
                s.material.law.span(),
                format!(
                    "must be hyperelastic, linear_elastic, st_venant_kirchhoff, tension_only_linear or tension_only_hyperelastic, got \"{}\"",
                    clip(law)
                ),
            )
        })?;
        let mass = match s.material.mass.get_ref().as_str() {
            "consistent" => MassMatrix::Consistent,
            "lumped" => MassMatrix::Lumped,
            other => {
                return Err(self.invalid(
                    "material.mass",
                    s.material.mass.span(),
                    format!("must be consistent or lumped, got \"{}\"", clip(other)),
                ));
            }
        };
        // Geometry and mesh.
        let g = &s.geometry;
        let positions: Vec<Vector<D>> = match (&g.nodes, &g.start, &g.end) {
            (Some(nodes), None, None) => {
                if let Some(el) = &s.mesh.elements {
                    return Err(self.invalid(
                        "mesh.elements",
                        el.span(),
                        "must not be given together with geometry.nodes (the nodes define the elements)",
                    ));
                }
                let list = nodes.get_ref();
                if list.len() < 2 {
                    return Err(self.invalid(
                        "geometry.nodes",
                        nodes.span(),
                        "needs at least 2 nodes",
                    ));
                }
                let mut out = Vec::with_capacity(list.len());
                for (i, p) in list.iter().enumerate() {
                    if p.len() != D || p.iter().any(|c| !c.is_finite()) {
                        return Err(self.invalid(
                            "geometry.nodes",
                            nodes.span(),
                            format!("node {i} must have {D} finite components, got {}", nums(p)),
                        ));
                    }
                    out.push(Vector::<D>::from_column_slice(p));
                }
                out
            }
            (None, Some(a), Some(b)) => {
                let a = self.vector::<D>("geometry.start", a)?;
                let b = self.vector::<D>("geometry.end", b)?;
                let el = s.mesh.elements.as_ref().ok_or_else(|| {
                    self.invalid("mesh.elements", 0..0, "is required with geometry.start/end")
                })?;
                let n = *el.get_ref();
                if !(1..=50_000_000).contains(&n) {
                    return Err(self.invalid(
                        "mesh.elements",
                        el.span(),
                        format!("must be between 1 and 5e7, got {n}"),
                    ));
                }
                let n = n as usize;
                (0..=n)
                    .map(|i| a + (b - a) * (i as f64 / n as f64))
                    .collect()
            }
            _ => {
                return Err(self.invalid(
                    "geometry",
                    0..0,
                    "needs either `start` and `end` (with mesh.elements) or `nodes`",
                ));
            }
        };
        let n_el = positions.len() - 1;
        let geometry_span = g.nodes.as_ref().map_or(0..0, |n| n.span());
        // Interpolating between start and end overflows when they are too far apart.
        if let Some(i) = positions
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(self.invalid(
                "geometry",
                geometry_span,
                format!(
                    "node {i} has a non-finite position: the distance from start to end overflows (too large coordinates)"
                ),
            ));
        }
        let seg: Vec<f64> = positions.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
        if let Some(i) = seg.iter().position(|&l| !l.is_finite()) {
            return Err(self.invalid(
                "geometry",
                geometry_span,
                format!(
                    "the length of element {i} (nodes {i} to {}) overflows: the coordinates are too large",
                    i + 1
                ),
            ));
        }
        if let Some(i) = seg.iter().position(|&l| l <= 0.0) {
            return Err(self.invalid(
                "geometry",
                geometry_span,
                format!(
                    "element {i} has zero initial length (nodes {i} and {} coincide)",
                    i + 1
                ),
            ));
        }
        let total: f64 = seg.iter().sum();
        if !total.is_finite() {
            return Err(self.invalid(
                "geometry",
                geometry_span,
                "the total length of the string overflows: the coordinates are too large",
            ));
        }
        let lengths: Vec<f64> = match &g.length {
            Some(l) => {
                let l0 = self.positive("geometry.length", l)?;
                let lengths: Vec<f64> = seg.iter().map(|s| s * l0 / total).collect();
                if let Some(i) = lengths.iter().position(|&x| !x.is_finite() || x <= 0.0) {
                    return Err(self.invalid(
                        "geometry.length",
                        l.span(),
                        format!(
                            "= {} gives element {i} the reference length {}, which is not a positive finite number",
                            num(l0),
                            num(lengths[i])
                        ),
                    ));
                }
                lengths
            }
            None => seg.clone(),
        };
        let mesh = Mesh::new(n_el + 1, (0..n_el).map(|e| [e, e + 1]).collect(), lengths)
            .map_err(|e| self.invalid("geometry", 0..0, e.to_string()))?;
        let initial = State::at_rest(&mesh, positions);
        if let Some((e, c)) = initial.c.iter().enumerate().find(|(_, c)| !c.is_finite()) {
            return Err(self.invalid(
                "geometry",
                0..0,
                format!(
                    "initial strain C = {} of element {e} is not finite: the initial length is too large for the reference length (geometry.length)",
                    num(*c)
                ),
            ));
        }
        if let Some((e, c)) = initial
            .c
            .iter()
            .enumerate()
            .find(|(_, c)| !phstring::StoredEnergy::admissible(&material, **c))
        {
            return Err(self.invalid(
                "geometry",
                0..0,
                format!(
                    "initial strain C = {} of element {e} is outside the material's domain",
                    num(*c)
                ),
            ));
        }
        // Body force.
        let mut body = Vector::<D>::zeros();
        let mut gravity = Vector::<D>::zeros();
        if let Some(gv) = &s.body_force.gravity {
            gravity = self.vector::<D>("body_force.gravity", gv)?;
            body += gravity * rho_a;
        }
        if let Some(pl) = &s.body_force.per_length {
            body += self.vector::<D>("body_force.per_length", pl)?;
        }
        // Boundary conditions. Expressions are checked at the first time they are used.
        let t_check = match *s.time.h.get_ref() {
            h if h > 0.0 && h.is_finite() => 0.5 * h,
            _ => 0.0,
        };
        let n_nodes = n_el + 1;
        let mut point_masses = Vec::with_capacity(s.point_mass.len());
        for (k, pm) in s.point_mass.iter().enumerate() {
            let key = |f: &str| format!("point_mass.{k}.{f}");
            let node = self.node_index(&key("node"), &pm.node, n_nodes)?;
            let kg = self.positive(&key("kg"), &pm.kg)?;
            let weight = gravity * kg;
            if !weight.iter().all(|w| w.is_finite()) {
                return Err(self.invalid(
                    &key("kg"),
                    pm.kg.span(),
                    format!(
                        "= {}: its weight under body_force.gravity overflows",
                        num(kg)
                    ),
                ));
            }
            point_masses.push(phstring::PointMass {
                node,
                mass: kg,
                weight,
            });
        }
        let mut boundary = Boundary::<D>::default();
        let mut loads_text = Vec::new();
        let mut fixed_mask: Vec<[bool; D]> = vec![[false; D]; n_nodes];
        // (boundary index, node, span, components with a non-zero force expression)
        let mut loaded: Vec<(usize, usize, Range<usize>, Vec<bool>)> = Vec::new();
        let load_error: Arc<std::sync::Mutex<Option<String>>> = Arc::default();
        for (k, b) in s.boundary.iter().enumerate() {
            let key = |f: &str| format!("boundary.{k}.{f}");
            let node = self.node_index(&key("node"), &b.node, n_nodes)?;
            if b.fixed.is_none() && b.force.is_none() && b.position.is_none() {
                return Err(self.invalid(
                    &key("node"),
                    b.node.span(),
                    "has neither `fixed`, `force` nor `position`",
                ));
            }
            if let Some(p) = &b.position {
                let texts = p.get_ref();
                if texts.len() != D {
                    return Err(self.invalid(
                        &key("position"),
                        p.span(),
                        format!(
                            "must have {D} expressions (dimension = {D}; \"\" for a free component), got {}",
                            texts.len()
                        ),
                    ));
                }
                for (i, txt) in texts.iter().enumerate() {
                    if txt.trim().is_empty() {
                        continue;
                    }
                    let e = Expr::new(txt, t_check)
                        .map_err(|m| self.invalid(&key("position"), p.span(), m))?;
                    let at_zero = e
                        .eval(0.0)
                        .map_err(|m| self.invalid(&key("position"), p.span(), m))?;
                    let start = initial.r[node][i];
                    // NaN (an expression undefined at 0) fails too.
                    let starts_there = (at_zero - start).abs() <= 1e-9 * start.abs().max(1.0);
                    if !starts_there {
                        return Err(self.invalid(
                            &key("position"),
                            p.span(),
                            format!(
                                "component {} is at {} m at t = 0, but node {node} starts at {} m: the expression gives the absolute position",
                                ["x", "y", "z"][i],
                                num(at_zero),
                                num(start)
                            ),
                        ));
                    }
                    if fixed_mask[node][i] {
                        return Err(self.invalid(
                            &key("position"),
                            p.span(),
                            format!(
                                "node {node} is already fixed in component {} (give \"\" there)",
                                ["x", "y", "z"][i]
                            ),
                        ));
                    }
                    fixed_mask[node][i] = true;
                    let errors = load_error.clone();
                    boundary
                        .motions
                        .push(phstring::Motion::new(node, i, move |t| {
                            eval_or_record(&e, &errors, "position", k, i, t)
                        }));
                }
            }
            if let Some(f) = &b.fixed {
                let comps = match f.get_ref() {
                    FixedSpec::All(v) => [*v; D],
                    FixedSpec::Components(list) => {
                        let mut c = [false; D];
                        for name in list {
                            let i = match name.as_str() {
                                "x" => 0,
                                "y" => 1,
                                "z" => 2,
                                _ => D,
                            };
                            if i >= D {
                                return Err(self.invalid(
                                    &key("fixed"),
                                    f.span(),
                                    format!("component \"{}\" is not one of x, y, z up to dimension {D}", clip(name)),
                                ));
                            }
                            c[i] = true;
                        }
                        c
                    }
                };
                for i in 0..D {
                    fixed_mask[node][i] |= comps[i];
                }
                if comps.iter().any(|&c| c) {
                    boundary.fixed.push(Fixed {
                        node,
                        components: comps,
                    });
                }
            }
            if let Some(f) = &b.force {
                let texts = f.get_ref();
                if texts.len() != D {
                    return Err(self.invalid(
                        &key("force"),
                        f.span(),
                        format!(
                            "must have {D} expressions (dimension = {D}), got {}",
                            texts.len()
                        ),
                    ));
                }
                let mut exprs = Vec::with_capacity(D);
                for txt in texts {
                    exprs.push(
                        Expr::new(txt, t_check)
                            .map_err(|m| self.invalid(&key("force"), f.span(), m))?,
                    );
                }
                let exprs = Arc::new(exprs);
                loads_text.push((node, texts.clone()));
                let comps: Vec<bool> = texts.iter().map(|t| !is_zero(t)).collect();
                loaded.push((k, node, f.span(), comps));
                let errors = load_error.clone();
                boundary.loads.push(NodalLoad::new(node, move |t| {
                    Vector::<D>::from_fn(|i, _| {
                        eval_or_record(&exprs[i], &errors, "force", k, i, t)
                    })
                }));
            }
        }
        for m in &boundary.motions {
            if boundary
                .fixed
                .iter()
                .any(|f| f.node == m.node && f.components[m.component])
            {
                let k = s
                    .boundary
                    .iter()
                    .position(|b| {
                        b.position.is_some()
                            && resolve_node(*b.node.get_ref(), n_nodes) == Some(m.node)
                    })
                    .unwrap_or(0);
                return Err(self.invalid(
                    &format!("boundary.{k}.position"),
                    s.boundary[k]
                        .position
                        .as_ref()
                        .map_or(0..0, |p| p.span()),
                    format!(
                        "node {} is also fixed in component {} (give \"\" there, or drop it from `fixed`)",
                        m.node,
                        ["x", "y", "z"][m.component]
                    ),
                ));
            }
        }
        for (k, node, span, comps) in &loaded {
            let (k, node) = (*k, *node);
            if let Some(i) = (0..D).find(|&i| fixed_mask[node][i] && comps[i]) {
                return Err(self.invalid(
                    &format!("boundary.{k}.force"),
                    span.clone(),
                    format!(
                        "node {node} is fixed in component {} and cannot also be loaded in it (give \"0\" there)",
                        ["x", "y", "z"][i]
                    ),
                ));
            }
        }
        // Time and Newton.
        let h = self.positive("time.h", &s.time.h)?;
        let t_end = self.positive("time.end", &s.time.end)?;
        let steps = (t_end / h).round();
        if steps > MAX_STEPS {
            return Err(self.invalid(
                "time.h",
                s.time.h.span(),
                format!(
                    "= {} gives {} steps up to time.end = {}; at most {MAX_STEPS:.0e} are allowed (use a larger time.h or a shorter time.end)",
                    num(h),
                    if steps.is_finite() {
                        format!("{steps:.2e}")
                    } else {
                        "too many".to_string()
                    },
                    num(t_end)
                ),
            ));
        }
        if steps < 1.0 || ((steps * h) - t_end).abs() > 1e-9 * t_end {
            return Err(self.invalid(
                "time.h",
                s.time.h.span(),
                format!(
                    "= {} does not divide time.end = {} into a whole number of steps",
                    num(h),
                    num(t_end)
                ),
            ));
        }
        let scheme = match s.time.scheme.get_ref().as_str() {
            "dg" => Scheme::DiscreteGradient,
            "mp" => Scheme::Midpoint,
            other => {
                return Err(self.invalid(
                    "time.scheme",
                    s.time.scheme.span(),
                    format!("must be dg or mp, got \"{}\"", clip(other)),
                ));
            }
        };
        let tol = match &s.newton.tol {
            Some(t) => Some(self.positive("newton.tol", t)?),
            None => None,
        };
        let rtol = match &s.newton.rtol {
            Some(r) => {
                let x = *r.get_ref();
                if !(0.0..1.0).contains(&x) {
                    return Err(self.invalid(
                        "newton.rtol",
                        r.span(),
                        format!("must be at least 0 and below 1, got {}", phstring::Num(x)),
                    ));
                }
                Some(x)
            }
            None => None,
        };
        // `tol` alone: absolute test; otherwise relative with `tol` (or the default) as floor.
        let (tol, rtol) = match (tol, rtol) {
            (Some(t), None) => (t, 0.0),
            (t, r) => (
                t.unwrap_or(phstring::newton::DEFAULT_ATOL),
                r.unwrap_or(phstring::newton::DEFAULT_RTOL),
            ),
        };
        let max_iter = *s.newton.max_iter.get_ref();
        if !(1..=10_000).contains(&max_iter) {
            return Err(self.invalid(
                "newton.max_iter",
                s.newton.max_iter.span(),
                format!("must be between 1 and 10000, got {max_iter}"),
            ));
        }
        let solver = match s.newton.solver.get_ref().as_str() {
            "auto" => SolverKind::Auto,
            "block_tridiagonal" => SolverKind::BlockTridiagonal,
            "sparse_lu" => SolverKind::SparseLu,
            other => {
                return Err(self.invalid(
                    "newton.solver",
                    s.newton.solver.span(),
                    format!(
                        "must be auto, block_tridiagonal or sparse_lu, got \"{}\"",
                        clip(other)
                    ),
                ));
            }
        };
        let predictor = match s.newton.predictor.get_ref().as_str() {
            "velocity" => phstring::Predictor::Velocity,
            "acceleration" => phstring::Predictor::Acceleration,
            "midpoint_velocity" => phstring::Predictor::MidpointVelocity,
            other => {
                return Err(self.invalid(
                    "newton.predictor",
                    s.newton.predictor.span(),
                    format!(
                        "must be velocity, acceleration or midpoint_velocity, got \"{}\"",
                        clip(other)
                    ),
                ));
            }
        };
        let mh = *s.time.max_halvings.get_ref();
        if !(0..=40).contains(&mh) {
            return Err(self.invalid(
                "time.max_halvings",
                s.time.max_halvings.span(),
                format!("must be between 0 and 40, got {mh}"),
            ));
        }
        let max_halvings = mh as u32;
        let stride = *s.output.stride.get_ref();
        if stride < 1 {
            return Err(self.invalid(
                "output.stride",
                s.output.stride.span(),
                format!("must be at least 1, got {stride}"),
            ));
        }
        Ok(Validated {
            problem: Problem {
                point_masses,
                mesh,
                material,
                rho_a,
                body_force: body,
                mass,
                boundary,
                initial,
            },
            settings: RunSettings {
                step: StepParams {
                    h,
                    scheme,
                    newton: NewtonParams {
                        tol,
                        rtol,
                        max_iter: max_iter as usize,
                        line_search: s.newton.line_search,
                        elimination: s.newton.elimination,
                    },
                    solver,
                    predictor,
                    control: phstring::StepControl {
                        adaptive: s.time.adaptive,
                        max_halvings,
                        ..Default::default()
                    },
                },
                t_end,
                stride: stride as usize,
                output: s.output.clone(),
            },
            loads: loads_text,
            load_error,
        })
    }
}
