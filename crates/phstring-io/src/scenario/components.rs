//! The components of a validated scenario, for reports (`phstring check`, the
//! `components` object of `summary.json`): named nodes, strings, springs, point masses,
//! supports, prescribed motions and loads, with the mesh nodes and elements they occupy.

use serde::Serialize;

use super::material::{CrossSection, mass_name};

/// Everything a scenario is made of, in mesh numbering.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Components {
    /// Named nodes (`[[node]]`), in file order (their mesh indices are 0, 1, …).
    pub nodes: Vec<NamedNode>,
    /// Strings, in element order (a single-string scenario has one, named `string`).
    pub strings: Vec<StringComponent>,
    /// Springs, in element order (after the strings).
    pub springs: Vec<SpringComponent>,
    /// Point masses, in file order.
    pub point_masses: Vec<PointMassComponent>,
    /// Nodes with fixed components, in increasing node order (the ends of springs with
    /// `to_point` included).
    pub supports: Vec<SupportComponent>,
    /// Prescribed motions, in file order.
    pub motions: Vec<MotionComponent>,
    /// Nodal loads, in file order (the order of the force ports).
    pub loads: Vec<LoadComponent>,
    /// Feedback controls, in file order (their force ports follow the loads').
    pub controls: Vec<ControlComponent>,
    /// Rigid bodies, in file order (their points are also in `nodes`, as `"BODY.POINT"`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodyComponent>,
    /// Winches, in file order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub winches: Vec<WinchComponent>,
}

/// A winch (`[[winch]]`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WinchComponent {
    /// Name.
    pub name: String,
    /// The string it pays out.
    pub string: String,
    /// The drum's mesh node at `t = 0` (the string's first node off the drum).
    pub drum_node: usize,
    /// Elements parked on the drum at `t = 0`, before the string's own.
    pub reserve_elements: usize,
    /// The string's element length [m].
    pub element_length: f64,
    /// The most it can pay out from `t = 0` [m]: its reserve elements.
    pub capacity: f64,
    /// The payout expression [m] (empty for a payout table, an external winch or a drum with
    /// dynamics).
    pub payout: String,
    /// The payout table's file, as the scenario names it (`payout_table`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub payout_table: Option<String>,
    /// `external = true`: the payout speed [m/s] is a front end's input (the FMU's
    /// `winch.NAME.speed`); `phstring run` holds the payout at 0.
    pub external: bool,
    /// The drum's position expressions [m], empty for a drum that stays.
    pub drum_position: Vec<String>,
    /// A drum on a rigid body: the body's name and the drum point in body axes [m] (the
    /// string's first path node `"BODY.POINT"`); the drum moves with the body.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub on_body: Option<(String, Vec<f64>)>,
    /// A drum with dynamics, described (`None`: the payout is prescribed).
    pub drum: Option<String>,
}

/// A rigid body (`[bodies.NAME]`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyComponent {
    /// Name.
    pub name: String,
    /// Mass [kg].
    pub mass: f64,
    /// Weight [N] (`mass · body_force.gravity`).
    pub weight: Vec<f64>,
    /// Inertia tensor about the centre of mass in body axes [kg·m²], by rows.
    pub inertia: [[f64; 3]; 3],
    /// Initial position of the centre of mass [m].
    pub position: Vec<f64>,
    /// Initial orientation as given [deg]: roll, pitch, yaw (`R = Rx Ry Rz`) in 3D, the angle
    /// about `z` in 2D.
    pub orientation: Vec<f64>,
    /// Its attachment points, in file order.
    pub points: Vec<BodyPointComponent>,
    /// The wrench port's force [N], one expression of `t` [s] per component (empty: none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub wrench_force: Vec<String>,
    /// The wrench port's torque [N·m] (3 expressions in 3D, the one about `z` in 2D; empty:
    /// none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub wrench_torque: Vec<String>,
    /// The wrench port is an input of a front end (`wrench.external = true`), which sets its
    /// force and torque.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub wrench_external: bool,
    /// Its water terms (none: the body feels no water).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub water: Option<super::body_water::BodyWaterComponent>,
    /// Its prescribed motion: the expressions of the position [m] and of the angles [deg]
    /// (`motion`), or `["table FILE"]` (`motion_table`); empty: the body moves freely.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub motion: Vec<String>,
    /// Its feedback law (`feedback`): the gains per space axis, then the reference's
    /// expressions (position [m], angles [deg]); empty: none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub feedback: Vec<String>,
}

/// An attachment point of a rigid body: a mesh node that moves with the body.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyPointComponent {
    /// `"BODY.POINT"`.
    pub name: String,
    /// Mesh node index.
    pub node: usize,
    /// The point in body axes, relative to the centre of mass [m].
    pub point: Vec<f64>,
    /// Its initial position [m].
    pub position: Vec<f64>,
    /// What attaches there: `string NAME` (on its path) and `spring NAME` (an end).
    pub attached: Vec<String>,
}

/// A feedback control at a node (a force port whose force is a law of its output).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ControlComponent {
    /// Mesh node index.
    pub node: usize,
    /// Proportional gains per component [N/m].
    pub kp: Vec<f64>,
    /// Derivative gains per component [N·s/m].
    pub kd: Vec<f64>,
    /// Reference position [m], one expression of `t` [s] per component (empty: none).
    pub reference: Vec<String>,
    /// Reference velocity [m/s], one expression per component (empty: the central
    /// difference of `reference`, or 0).
    pub reference_velocity: Vec<String>,
}

/// A named node.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedNode {
    /// Name.
    pub name: String,
    /// Mesh node index.
    pub node: usize,
    /// Initial position [m].
    pub position: Vec<f64>,
}

/// A string: one element group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StringComponent {
    /// Name.
    pub name: String,
    /// Its elements `[first, one past the last]` (mesh element indices).
    pub elements: [usize; 2],
    /// Number of nodes along the string (elements + 1).
    pub nodes: usize,
    /// Mesh nodes of its path, in order. Along the string, each span from `path_nodes[i]`
    /// to `path_nodes[i+1]` has `elements_per_span − 1` interior nodes in between.
    pub path_nodes: Vec<usize>,
    /// Elements per span.
    pub elements_per_span: usize,
    /// Its interior nodes `[first, one past the last]`: consecutive mesh indices, span
    /// after span, in the order along the string.
    pub interior_nodes: [usize; 2],
    /// Material law (`hyperelastic`, …).
    pub law: &'static str,
    /// Material name (`[materials.NAME]`; `material` for a single string).
    pub material: String,
    /// Axial stiffness `EA` [N].
    pub ea: f64,
    /// Mass per unit reference length `ρA` [kg/m].
    pub rho_a: f64,
    /// Mass matrix: `consistent` or `lumped`.
    pub mass: &'static str,
    /// Body force per unit reference length [N/m].
    pub body_force: Vec<f64>,
    /// Unstretched length `Σ l_e` [m].
    pub reference_length: f64,
    /// Kelvin–Voigt viscosity `η` [N·s] (0: none).
    pub kelvin_voigt: f64,
    /// Drag per unit reference length [N·s/m²] (0: none).
    pub drag: f64,
}

/// Where a string lies in the mesh, for [`StringComponent::new`].
pub(super) struct StringLayout {
    /// Its elements `[first, one past the last]`.
    pub elements: [usize; 2],
    /// Number of nodes along the string.
    pub nodes: usize,
    /// Mesh nodes of its path, in order.
    pub path_nodes: Vec<usize>,
    /// Elements per span.
    pub elements_per_span: usize,
    /// Its interior nodes `[first, one past the last]`.
    pub interior_nodes: [usize; 2],
}

impl StringComponent {
    /// The string `name` laid out as `layout`, of cross-section `cs` made of the material
    /// named `material`, under `body_force` [N/m] per unit reference length; its reference
    /// length is filled in from the mesh when the network is built.
    pub(super) fn new(
        name: String,
        layout: StringLayout,
        material: String,
        cs: &CrossSection,
        body_force: &[f64],
    ) -> Self {
        Self {
            name,
            elements: layout.elements,
            nodes: layout.nodes,
            path_nodes: layout.path_nodes,
            elements_per_span: layout.elements_per_span,
            interior_nodes: layout.interior_nodes,
            law: cs.material.name(),
            material,
            ea: cs.material.ea(),
            rho_a: cs.rho_a,
            mass: mass_name(cs.mass),
            body_force: body_force.to_vec(),
            // Filled in from the mesh when the network is built.
            reference_length: 0.0,
            kelvin_voigt: cs.damping.kelvin_voigt,
            drag: cs.damping.drag,
        }
    }
}

/// A linear spring: a one-element group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpringComponent {
    /// Name.
    pub name: String,
    /// Its element (mesh element index).
    pub element: usize,
    /// Its end nodes (with `to_point`, the second is the fixed node created at that point).
    pub nodes: [usize; 2],
    /// Stiffness `k` [N/m].
    pub k: f64,
    /// Rest length [m].
    pub rest: f64,
    /// The fixed point [m] of a spring given with `to_point`.
    pub to_point: Option<Vec<f64>>,
    /// Dashpot across the spring [N·s/m] (0: none).
    pub damping: f64,
}

/// A point mass.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointMassComponent {
    /// Mesh node index.
    pub node: usize,
    /// Mass [kg].
    pub kg: f64,
    /// Weight [N] (`kg · body_force.gravity`).
    pub weight: Vec<f64>,
}

/// A node with fixed components (a velocity port).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SupportComponent {
    /// Mesh node index.
    pub node: usize,
    /// Fixed components, e.g. `["x", "y"]`.
    pub fixed: Vec<&'static str>,
}

/// A prescribed motion of one component of a node.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionComponent {
    /// Mesh node index.
    pub node: usize,
    /// Component: `x`, `y` or `z`.
    pub component: &'static str,
    /// Absolute position [m] as an expression of `t` [s].
    pub position: String,
    /// An input of the FMU (`external = true`).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub external: bool,
}

/// A nodal load (a force port).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadComponent {
    /// Mesh node index.
    pub node: usize,
    /// Force [N], one expression of `t` [s] per component.
    pub force: Vec<String>,
    /// An input of the FMU (`external = true`).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub external: bool,
}

/// Component names, by index.
pub(super) const AXES: [&str; 3] = ["x", "y", "z"];

impl Components {
    /// The name of mesh node `node`, if it is a named node.
    pub fn node_name(&self, node: usize) -> Option<&str> {
        // Named nodes are numbered 0, 1, … in file order.
        self.nodes
            .get(node)
            .filter(|n| n.node == node)
            .map(|n| n.name.as_str())
    }

    /// Where mesh node `node` lies along a string of a network: `(string, index along
    /// it)` for an interior node (path nodes are shared; see [`Self::node_name`]).
    pub fn along_string(&self, node: usize) -> Option<(&str, usize)> {
        self.strings.iter().find_map(|st| {
            let [first, end] = st.interior_nodes;
            let per_span = st.elements_per_span;
            (first..end).contains(&node).then(|| {
                let o = node - first;
                let k = o / (per_span - 1) * per_span + o % (per_span - 1) + 1;
                (st.name.as_str(), k)
            })
        })
    }

    /// Mesh node `node` for messages: `node 5`, `node 0 "platform"`, or in a network
    /// `node 10 "cable0:6"` for the 6th node along string `cable0`.
    pub fn node_label(&self, node: usize) -> String {
        if let Some(name) = self.node_name(node) {
            return format!("node {node} \"{name}\"");
        }
        match self.along_string(node) {
            Some((string, k)) if !self.nodes.is_empty() || self.strings.len() > 1 => {
                format!("node {node} \"{string}:{k}\"")
            }
            _ => format!("node {node}"),
        }
    }
}
