//! The scenario file as written: serde data with `toml::Spanned` values, so that
//! validation can point at the line and column of a value. Every key is documented in
//! `docs/scenario.md`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::refs::NodeRef;

/// A scenario as written in the file (before validation): one string (`[geometry]`,
/// `[mesh]`, `[material]`) or a network (`[[node]]`, `[materials.NAME]`, `[[string]]`,
/// `[[spring]]`); the other tables belong to both.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free-text title, printed in reports.
    #[serde(default)]
    pub title: Option<String>,
    /// Spatial dimension `d` ∈ {1, 2, 3}.
    pub dimension: Spanned<i64>,
    /// Initial (and reference) geometry of a single string (not in a network).
    #[serde(default)]
    pub geometry: Option<Spanned<Geometry>>,
    /// Discretization of a single string (not in a network).
    #[serde(default)]
    pub mesh: Option<Spanned<MeshSpec>>,
    /// Material law and parameters of a single string (not in a network).
    #[serde(default)]
    pub material: Option<Spanned<MaterialSpec>>,
    /// Named points of a network: junctions, anchors, attachment points.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub node: Vec<Spanned<NodeSpec>>,
    /// Named cross-sections of a network, used by its strings.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub materials: BTreeMap<String, Spanned<MaterialSpec>>,
    /// The strings of a network, each running straight from node to node along its path.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub string: Vec<Spanned<StringPathSpec>>,
    /// Linear springs of a network.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spring: Vec<Spanned<SpringSpec>>,
    /// Body force.
    #[serde(default)]
    pub body_force: BodyForceSpec,
    /// Boundary conditions, one table per node.
    #[serde(default)]
    pub boundary: Vec<BoundarySpec>,
    /// Rigid platforms moving several supports from one table of surge, sway, heave, roll,
    /// pitch and yaw (dimension 3).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub platform: Vec<PlatformSpec>,
    /// Point masses at nodes (payloads, clump weights), one table each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub point_mass: Vec<PointMassSpec>,
    /// Winches of a network (`[[winch]]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub winch: Vec<Spanned<WinchSpec>>,
    /// Rigid bodies of a network (`[bodies.NAME]`), by name; strings attach to their points
    /// as `"NAME.POINT"` (dimension 2 or 3).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub bodies: BTreeMap<String, Spanned<BodySpec>>,
    /// The initial state, if it is not the straight one at rest: static equilibrium,
    /// displacement and velocity fields, or per-node lists.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial: Option<InitialSpec>,
    /// Time stepping.
    pub time: TimeSpec,
    /// Newton's method and the linear solver.
    #[serde(default)]
    pub newton: NewtonSpec,
    /// What to write.
    #[serde(default)]
    pub output: OutputSpec,
    /// What an FMU built from this scenario reports (`phstring fmu`; ignored otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fmu: Option<Spanned<FmuSpec>>,
    /// Water (surface at height 0 on the vertical axis, the last one): density, depth,
    /// current. Dimension 2 or 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water: Option<Spanned<WaterSpec>>,
    /// The seabed under `[water]`: contact stiffness and damping, friction, slope.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seabed: Option<Spanned<SeabedSpec>>,
    /// Where a scenario generated from a MoorDyn deck came from (written by the mapping,
    /// `phstring_io::moordyn::map`); a record only, it plays no part in the run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deck: Option<DeckSpec>,
}

/// `[deck]`: the record of a scenario generated from a MoorDyn deck: the deck, what was
/// converted with a caveat, what the deck asks that phstring does not need, and what was
/// dropped on purpose (`--ignore`). Copied into `summary.json` as `deck`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DeckSpec {
    /// The deck's path, as given.
    pub path: String,
    /// The deck's format generation (`v1` or `v2`).
    #[serde(default)]
    pub version: String,
    /// Conversions that are not one to one, with the deck line (`deck.dat:14: BA = -0.8 …`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub converted: Vec<String>,
    /// Deck entries phstring does not need, by name, with the reason.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub not_needed: BTreeMap<String, String>,
    /// Features dropped on purpose with `--ignore`, with the deck lines they were on.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ignored: Vec<String>,
    /// What in the deck or its `--motion` table looks like a mistake but runs (a table that
    /// puts a coupled point far from its deck position); also the run's warnings.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// `[water]`: the water the strings with a `diameter` are in. Its surface is at height 0
/// on the vertical axis (`y` in 2D, `z` in 3D); buoyancy acts against `body_force.gravity`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WaterSpec {
    /// Density `ρ_w` [kg/m³] (default 1025, sea water).
    #[serde(default)]
    pub density: Option<Spanned<f64>>,
    /// Water depth `h` [m]: a flat seabed at height `−h` (with `[seabed]`).
    #[serde(default)]
    pub depth: Option<Spanned<f64>>,
    /// Uniform current [m/s], one component per axis (default still water).
    #[serde(default)]
    pub current: Option<Spanned<Vec<f64>>>,
    /// A current profile instead: rows `[z, u_x, …]` [m, m/s] with increasing height `z`,
    /// linear in between and constant beyond the first and last row.
    #[serde(default)]
    pub current_profile: Option<Spanned<Vec<Vec<f64>>>>,
    /// Smoothing speed `δ` [m/s] of the drag laws' `|v|` (default 1e-3).
    #[serde(default)]
    pub drag_smoothing: Option<Spanned<f64>>,
    /// Velocity amplitude [m/s] of the equivalent linear drag in `linearize` and `modes`
    /// (default 0: the drag's derivative at rest only).
    #[serde(default)]
    pub linear_drag_amplitude: Option<Spanned<f64>>,
}

/// `[seabed]`: a flat seabed at `−water.depth`, or a plane through `point` with upward
/// `normal`; penalty contact per unit length and diameter of line, as MoorDyn's `kBot` and
/// `cBot`; optional Coulomb friction.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SeabedSpec {
    /// Contact stiffness `k` [Pa/m]: force per unit length `k d p` at penetration `p` [m].
    pub stiffness: Spanned<f64>,
    /// Contact damping `c` [Pa·s/m]: force per unit length `−c d v_n` (default 0).
    #[serde(default)]
    pub damping: Option<Spanned<f64>>,
    /// Coulomb friction coefficient `μ` (default 0: no friction).
    #[serde(default)]
    pub friction: Option<Spanned<f64>>,
    /// MoorDyn's `FricDamp` [N·s/m]: the friction force is `μ · friction_damping · |v|` at
    /// small slip (default 200, MoorDyn's default).
    #[serde(default)]
    pub friction_damping: Option<Spanned<f64>>,
    /// Coulomb friction coefficient `μ_a` along the line's axis (MoorDyn-F's `mu_kA`; default:
    /// none, the isotropic law); `friction` is then the transverse coefficient.
    #[serde(default)]
    pub friction_axial: Option<Spanned<f64>>,
    /// Static over kinetic friction `μ_s/μ_k` (MoorDyn's `StatDynFricScale`; default 1: no
    /// static peak).
    #[serde(default)]
    pub friction_static_scale: Option<Spanned<f64>>,
    /// A point of an inclined seabed plane [m] (default: on the flat seabed below the origin).
    #[serde(default)]
    pub point: Option<Spanned<Vec<f64>>>,
    /// The plane's normal, pointing up into the water (default vertical: a flat seabed).
    #[serde(default)]
    pub normal: Option<Spanned<Vec<f64>>>,
    /// Penetration [m] over which the damping ramps up (default 1e-3).
    #[serde(default)]
    pub damping_ramp: Option<Spanned<f64>>,
    /// A bathymetry file (CSV of depths [m], positive down; the path relative to the
    /// scenario file): the seabed as a grid instead of a plane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bathymetry: Option<Spanned<String>>,
}

/// A named point of a network (`[[node]]`): a junction, an anchor, an attachment point.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    /// Name, referred to as `"NAME"` by strings, springs, point masses and boundaries.
    pub name: Spanned<String>,
    /// Initial position [m].
    pub position: Spanned<Vec<f64>>,
}

/// A string of a network (`[[string]]`): it runs straight from node to node along `path`,
/// with `elements` elements between two consecutive path nodes.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StringPathSpec {
    /// Name, referred to as `"NAME:INDEX"` (the INDEX-th node along the string).
    pub name: Spanned<String>,
    /// Node references, at least 2; consecutive ones must differ.
    pub path: Spanned<Vec<Spanned<NodeRef>>>,
    /// Elements per span (between two consecutive path nodes).
    pub elements: Spanned<i64>,
    /// Name of a `[materials.NAME]` table.
    pub material: Spanned<String>,
    /// Initial stretch `|Δr|/l` of every element (default 1: stress-free; above 1: taut).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prestretch: Option<Spanned<f64>>,
}

/// A linear spring of a network (`[[spring]]`), massless: between two nodes, or from one
/// node to a fixed point.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    /// Name (for outputs and messages).
    pub name: Spanned<String>,
    /// Two node references, or one with `to_point`.
    pub between: Spanned<Vec<Spanned<NodeRef>>>,
    /// Fixed end point [m] (with one node in `between`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to_point: Option<Spanned<Vec<f64>>>,
    /// Stiffness `k` [N/m] (0 allowed with `damping`: a pure dashpot).
    pub k: Spanned<f64>,
    /// Rest length [m], at least 0.
    pub rest: Spanned<f64>,
    /// Dashpot across the spring `c` [N·s/m]: the forces `∓c (v_b − v_a)` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<Spanned<f64>>,
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
    /// Kelvin–Voigt viscosity `η` [N·s]: the stress gains `η Ċ` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kelvin_voigt: Option<Spanned<f64>>,
    /// Linear drag per unit reference length `c` [N·s/m²]: the force `−c v` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drag: Option<Spanned<f64>>,
    /// Hydrodynamic (volume-equivalent) diameter `d` [m]: with `[water]`, the string
    /// displaces `π d²/4` per unit length, feels drag and added mass, and touches the
    /// seabed. Without it the string feels no water.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diameter: Option<Spanned<f64>>,
    /// Transverse drag coefficient `Cd` on `d·l` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cd: Option<Spanned<f64>>,
    /// Axial drag coefficient `CdAx` on `π·d·l` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cd_axial: Option<Spanned<f64>>,
    /// Transverse added-mass coefficient `Ca` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ca: Option<Spanned<f64>>,
    /// Axial added-mass coefficient `CaAx` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ca_axial: Option<Spanned<f64>>,
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
    /// One flag per component, e.g. `[true, true, false]` (x and y fixed).
    Mask(Vec<bool>),
}

/// A boundary condition at one node.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// Node reference: an index (negative values count from the end, `-1` is the last
    /// node), `"NAME"` of a `[[node]]` or `"STRING:INDEX"` (a node along a string).
    pub node: Spanned<NodeRef>,
    /// Fixed components (Dirichlet): `true` or a list like `["x", "y"]`.
    #[serde(default)]
    pub fixed: Option<Spanned<FixedSpec>>,
    /// Nodal force [N], one expression in `t` [s] per component.
    #[serde(default)]
    pub force: Option<Spanned<Vec<String>>>,
    /// Prescribed absolute position [m], one expression in `t` [s] per component; `""` leaves
    /// a component free. Each must equal the initial position at `t = 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<Spanned<Vec<Spanned<String>>>>,
    /// Feedback control through the node's force port (PD tracking or damping injection).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<Spanned<ControlSpec>>,
    /// Prescribed absolute position [m] from a table file (path relative to the scenario
    /// file): columns `t` [s] and one per component, interpolated C¹ (docs/scenario.md,
    /// "Motion and force tables"). Instead of `position`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_table: Option<Spanned<String>>,
    /// The columns of `motion_table` holding the components x[, y[, z]] (1-based; the time
    /// is column 1), for a table of several nodes' motions (MoorDyn's per-point motion
    /// files); default: columns 2 … d + 1 of a table of d + 1 columns.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_columns: Option<Spanned<Vec<i64>>>,
    /// Nodal force [N] from a table file (path relative to the scenario file): columns
    /// `t` [s] and one per component. Instead of `force`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_table: Option<Spanned<String>>,
    /// Whether this table's `force` or `position` is an input of the FMU that
    /// `phstring fmu` builds (its expression at `t = 0` is the input's start value).
    /// `phstring run` and the other commands follow the expression regardless.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external: Option<Spanned<bool>>,
}

/// `[[platform]]`: supports moved rigidly by a platform whose motion is a table of
/// `t, x, y, z, roll, pitch, yaw` [s, m, m, m, rad, rad, rad].
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformSpec {
    /// Free-text name, for reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The support nodes the platform carries (node references); each moves in x, y and z.
    pub nodes: Spanned<Vec<Spanned<NodeRef>>>,
    /// The table file (path relative to the scenario file).
    pub motion_table: Spanned<String>,
}

/// `[fmu]`: what the FMU built by `phstring fmu` reports besides its ports and energies.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FmuSpec {
    /// Nodes whose positions [m] are outputs: indices (negative from the end), names or
    /// `"STRING:INDEX"`.
    #[serde(default)]
    pub nodes: Vec<Spanned<NodeRef>>,
}

/// A gain: one value for every component, or one per component.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum GainSpec {
    /// The same gain in every component.
    One(f64),
    /// One gain per component.
    Each(Vec<f64>),
}

/// `control = { … }` of a `[[boundary]]` table: the force
/// `u = kp (r_ref(t) − r) − kd (v − v_ref(t))` on the node, evaluated at the mid-step.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    /// Proportional gain [N/m] (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kp: Option<Spanned<GainSpec>>,
    /// Derivative gain [N·s/m] (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd: Option<Spanned<GainSpec>>,
    /// Reference position `r_ref(t)` [m], one expression in `t` [s] per component (needed
    /// with `kp`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<Spanned<Vec<Spanned<String>>>>,
    /// Reference velocity `v_ref(t)` [m/s], one expression per component (default: the
    /// central difference of `reference`, or 0 without one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_velocity: Option<Spanned<Vec<Spanned<String>>>>,
}

/// A winch (`[[winch]]`): it pays out or hauls in a string of a network from a drum at the
/// string's first path node (docs/method.md §23).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WinchSpec {
    /// Name (for outputs and messages).
    pub name: Spanned<String>,
    /// Name of the `[[string]]` it pays out; its first path node is the drum.
    pub string: Spanned<String>,
    /// The length paid out since `t = 0` [m] (negative: hauled in), an expression of `t`
    /// that is 0 at `t = 0`; required unless `external = true` or `[winch.drum]`, and not
    /// given with either.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payout: Option<Spanned<String>>,
    /// The payout [m] from a table file (path relative to the scenario file): columns
    /// `t, payout`, interpolated C¹ as a motion table, 0 at `t = 0`, held beyond the table's
    /// ends; instead of `payout`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payout_table: Option<Spanned<String>>,
    /// `external = true`: the payout speed [m/s] is an input of a front end (the FMU's
    /// `winch.NAME.speed`, held over each communication step), starting at 0; commands
    /// without an input (`phstring run`) hold the payout at 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external: Option<Spanned<bool>>,
    /// A drum with dynamics (`[winch.drum]`): the payout follows from the rope's pull against
    /// the drum's inertia, motor, damping and brake.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drum: Option<Spanned<DrumSpec>>,
    /// Cable on the drum [m] that it can pay out beyond the string's starting length
    /// (default 0: it can only haul in); rounded up to whole elements.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reserve: Option<Spanned<f64>>,
    /// The drum's position [m] as expressions of `t`, one per component (a crane's
    /// trolley); at the drum node's position at `t = 0`. Default: the drum stays.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drum_position: Option<Spanned<Vec<String>>>,
}

/// A winch drum with dynamics (`[winch.drum]`, docs/method.md §23.6). Every key is optional;
/// `inertia` and `torque` need `radius`, and `tension` and `torque` exclude each other.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DrumSpec {
    /// The drum's (and motor's) moment of inertia `J` [kg·m²] (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<Spanned<f64>>,
    /// The drum's radius `R` [m] where the rope leaves it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<Spanned<f64>>,
    /// Target tension [N] as an expression of `t`: the motor pulls the rope with it (a
    /// tension controller with `damping` as its gain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tension: Option<Spanned<String>>,
    /// Motor torque [N·m] as an expression of `t` (hauling in positive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque: Option<Spanned<String>>,
    /// Damping of the payout speed [N·s/m] (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<Spanned<f64>>,
    /// The brake's holding force at the rope [N] (default: no brake).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub brake: Option<Spanned<f64>>,
    /// The brake's slip speed [m/s] (default 1e-3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub brake_slip: Option<Spanned<f64>>,
    /// The tension controller's derivative time `τ` [s] (default 0: none): the law becomes
    /// `d ṗ = (T − T_ref) + τ dT/dt` at the rope, the rate taken inside the step; not with
    /// `time.scheme = "dg4"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub derivative_time: Option<Spanned<f64>>,
}

/// A point mass at a node; gravity (`body_force.gravity`) acts on it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PointMassSpec {
    /// Node reference: an index (negative values count from the end, `-1` is the last
    /// node), `"NAME"` of a `[[node]]` or `"STRING:INDEX"` (a node along a string).
    pub node: Spanned<NodeRef>,
    /// Mass [kg].
    pub kg: Spanned<f64>,
    /// Displaced volume [m³] in `[water]`: buoyancy `ρ_w g V` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<Spanned<f64>>,
    /// Drag coefficient times area `CdA` [m²] in `[water]` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cda: Option<Spanned<f64>>,
    /// Added-mass coefficient `Ca` on `ρ_w V` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ca: Option<Spanned<f64>>,
}

/// `[bodies.NAME]`: a rigid body of a network, its attachment points in body axes and an
/// optional wrench port. Angles and rates about axes are scalars in 2D (about `z`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Mass [kg].
    pub mass: Spanned<f64>,
    /// Inertia about the centre of mass in body axes [kg·m²]: the principal moments
    /// `[Ixx, Iyy, Izz]`, or the tensor's entries `[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`.
    pub inertia: Spanned<Vec<f64>>,
    /// Initial position of the centre of mass [m].
    pub position: Spanned<Vec<f64>>,
    /// Initial orientation [deg]: `[roll, pitch, yaw]` with `R = Rx Ry Rz` in 3D, `[yaw]`
    /// (about `z`) in 2D (default: body axes along space axes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<Spanned<Vec<f64>>>,
    /// Initial velocity of the centre of mass [m/s] (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<Spanned<Vec<f64>>>,
    /// Initial angular velocity in space axes [rad/s]: 3 components in 3D, the rate about
    /// `z` in 2D (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<Spanned<Vec<f64>>>,
    /// Attachment points in body axes relative to the centre of mass [m], by name.
    pub points: Spanned<BTreeMap<String, Spanned<Vec<f64>>>>,
    /// A wrench port: force and torque in space axes as expressions of `t` [s].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrench: Option<Spanned<WrenchSpec>>,
    /// Displaced volume [m³] in `[water]`: buoyancy `ρ_w g V` at the centre of buoyancy
    /// (MoorDyn's body `Volume`; default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<Spanned<f64>>,
    /// Centre of buoyancy in body axes relative to the centre of mass [m] (default: the
    /// centre of mass).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_of_buoyancy: Option<Spanned<Vec<f64>>>,
    /// Drag coefficient times area `CdA` [m²] of the quadratic drag at the centre of mass
    /// (MoorDyn's body `CdA`; default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cda: Option<Spanned<f64>>,
    /// Linear drag coefficient [N·s/m] at the centre of mass (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear_drag: Option<Spanned<f64>>,
    /// Added-mass coefficient `Ca` on `ρ_w V`, the same in every direction (MoorDyn's body
    /// `Ca`; default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ca: Option<Spanned<f64>>,
    /// Added moments of inertia about the body axes [kg·m²]: 3 in 3D, the one about `z` in
    /// 2D (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub added_inertia: Option<Spanned<Vec<f64>>>,
    /// The full added-mass matrix in body axes about the centre of mass: 6 rows of 6 in 3D
    /// (translation x, y, z, then rotation about x, y, z; kg, kg·m, kg·m²), 3 rows of 3 in
    /// 2D (x, y, θ); symmetric positive semi-definite. Not together with `ca` or
    /// `added_inertia` (default: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub added_mass: Option<Spanned<Vec<Vec<f64>>>>,
    /// Waterplane area `A_w` [m²] of a floater: heave restoring `ρ_w g A_w` at `waterline`
    /// (default 0: submerged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waterplane_area: Option<Spanned<f64>>,
    /// The waterline point in body axes relative to the centre of mass [m] (default: the
    /// centre of mass).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waterline: Option<Spanned<Vec<f64>>>,
    /// The waterplane's second moments of area about the body's `x` and `y` axes through
    /// the waterline point [m⁴]: `[I_x, I_y]` in 3D, `[I]` in 2D (default: none, the heave
    /// restoring alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waterplane_moments: Option<Spanned<Vec<f64>>>,
    /// A prescribed motion of the whole body: absolute pose as expressions of `t` [s].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<Spanned<BodyMotionSpec>>,
    /// A prescribed motion from a table file of seven columns `t, x, y, z, roll, pitch,
    /// yaw` [s, m, rad] (a `[[platform]]` table; dimension 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_table: Option<Spanned<String>>,
    /// A feedback law on the wrench port: PD on the pose with damping.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feedback: Option<Spanned<BodyFeedbackSpec>>,
}

/// `feedback = { … }` of a body: the force `kp (x_ref − x) − kd (v − v_ref)` at the centre
/// of mass and the torque of a rotational spring `kp_turn` to the reference orientation with
/// the damping `−kd_turn (ω − ω_ref)`, gains per space axis, evaluated at the mid-step.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BodyFeedbackSpec {
    /// Translational proportional gain [N/m]: one number, or `d` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kp: Option<Spanned<GainSpec>>,
    /// Translational derivative gain [N·s/m]: one number, or `d` (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd: Option<Spanned<GainSpec>>,
    /// Rotational proportional gain [N·m/rad]: one number, or 3 in 3D (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kp_turn: Option<Spanned<GainSpec>>,
    /// Rotational derivative gain [N·m·s/rad]: one number, or 3 in 3D (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd_turn: Option<Spanned<GainSpec>>,
    /// Reference position of the centre of mass [m], one expression of `t` [s] per
    /// component (default: the initial position).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<Spanned<Vec<Spanned<String>>>>,
    /// Reference orientation [deg]: `[roll, pitch, yaw]` (`R = Rx Ry Rz`) in 3D, the angle
    /// about `z` in 2D, expressions of `t` (default: the initial orientation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<Spanned<Vec<Spanned<String>>>>,
}

/// `motion = { position = […], orientation = […] }` of a body: its absolute pose as
/// expressions of `t` [s].
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BodyMotionSpec {
    /// Position of the centre of mass [m], one expression per component.
    pub position: Spanned<Vec<Spanned<String>>>,
    /// Orientation [deg]: `[roll, pitch, yaw]` (`R = Rx Ry Rz`) in 3D, the angle about `z`
    /// in 2D (default: the body's constant `orientation`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation: Option<Spanned<Vec<Spanned<String>>>>,
}

/// `wrench = { force = […], torque = […] }` of a body: expressions of `t` [s] in space axes,
/// evaluated at the mid time of each step.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WrenchSpec {
    /// Force at the centre of mass [N], one expression per component (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<Spanned<Vec<Spanned<String>>>>,
    /// Torque about the centre of mass [N·m]: 3 expressions in 3D, the one about `z` in 2D
    /// (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque: Option<Spanned<Vec<Spanned<String>>>>,
    /// `external = true`: the force and torque are inputs of a front end, which start at the
    /// expressions' values at `t = 0` (default `false`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub external: Option<Spanned<bool>>,
}

/// `[initial]`: how the run starts, instead of at rest in the straight (or polyline, or
/// straight-span) shape the geometry gives.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Start from the static equilibrium under the loads at `t = 0` (default `false`); the
    /// displacement and velocity are then applied to the equilibrium shape.
    #[serde(default = "no")]
    pub equilibrium: Spanned<bool>,
    /// Displacement [m] added to the base shape: one expression per component of the
    /// reference arc length `s` [m], the string's reference length `L` [m] and the base
    /// position `x`, `y`, `z` [m] of the node.
    #[serde(default)]
    pub displacement: Option<Spanned<Vec<Spanned<String>>>>,
    /// Initial velocity [m/s]: one expression per component, of the same variables.
    #[serde(default)]
    pub velocity: Option<Spanned<Vec<Spanned<String>>>>,
    /// Initial position of every mesh node [m], in mesh order (replaces the base shape).
    #[serde(default)]
    pub positions: Option<Spanned<Vec<Spanned<Vec<f64>>>>>,
    /// Initial velocity of every mesh node [m/s], in mesh order.
    #[serde(default)]
    pub velocities: Option<Spanned<Vec<Spanned<Vec<f64>>>>>,
}

fn no() -> Spanned<bool> {
    Spanned::new(0..0, false)
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
    /// Error control: relative tolerance of the local error (docs/method.md §19); with
    /// `atol`, `h` is chosen for accuracy, `time.h` being the first and largest step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rtol: Option<Spanned<f64>>,
    /// Error control: absolute tolerance of the local error of positions [m] (velocities:
    /// `atol / time.h` [m/s]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atol: Option<Spanned<f64>>,
    /// Error control: the tolerances bound each step's local error (`true`) instead of its
    /// error per unit step (`false`, the default); needs `rtol` or `atol`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error_per_step: Option<Spanned<bool>>,
    /// Static settling: end the run once the kinetic energy has stayed below a threshold.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle: Option<Spanned<SettleSpec>>,
}

/// `time.settle = { kinetic = …, hold = … }`: the run ends (before `time.end`) once the
/// kinetic energy has stayed below `kinetic` [J] for `hold` [s], after it was above it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SettleSpec {
    /// Kinetic-energy threshold [J] (> 0).
    pub kinetic: Spanned<f64>,
    /// How long the kinetic energy must stay below it [s] (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold: Option<Spanned<f64>>,
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
    /// Write an animated GIF of the configuration (dimension 2 and 3).
    #[serde(default = "yes")]
    pub animation: bool,
    /// MoorDyn output channels (`FairTen1`, `AnchTen1`, `L1N10T`, `Point4FZ`, …; see
    /// [`crate::channels`]) written as a MoorDyn-style table (`channels_file`) at the times
    /// of `positions.csv`. Line `i` is the `i`-th string, point `k` the node named
    /// `point<k>`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<Spanned<String>>,
    /// File name of the channel table in the output folder (default `channels.out`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channels_file: Option<Spanned<String>>,
    /// Write the rows of `energy.csv`, `ports.csv` and `end_tensions.csv` every
    /// `row_stride` steps (and the last step) instead of every step (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub row_stride: Option<Spanned<i64>>,
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
            animation: true,
            channels: Vec::new(),
            channels_file: None,
            row_stride: None,
        }
    }
}
