//! The semi-discrete port-Hamiltonian system (docs/method.md §4, paper eqs. (24)–(31)).
//!
//! State `x̂ = (r̂, v̂, Ĉ)`: nodal positions [m], nodal velocities [m/s], element strains
//! (dimensionless). Efforts `ẑ = (−F_b, v̂, ½ Ŝ)` so that `Eᵀẑ = ∇Ĥ`, with
//! `E = diag(I, M_ρ, M_S)`.

use nalgebra::SVector;

use crate::body::{BodyModel, BodyState, RigidBody};
use crate::boundary::Boundary;
use crate::error::SetupError;
use std::ops::Range;

use crate::material::{LinearSpring, StoredEnergy};
use crate::mesh::Mesh;
use crate::water::{GroupInfo, Hydrodynamics, LineHydro, PointHydro, Water, WaterModel};

/// A nodal vector in `R^D` [m, m/s or N].
pub type Vector<const D: usize> = SVector<f64, D>;

/// Mass matrix `M_ρ` variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MassMatrix {
    /// Consistent mass `ρA l_e/6 [[2,1],[1,2]] ⊗ I` (docs/method.md eq. (4.3); the default).
    #[default]
    Consistent,
    /// Row-sum lumped mass `ρA l_e/2` per node of each element (an option, not the paper's).
    Lumped,
}

/// The state `(r̂, v̂, Ĉ)` of the semi-discrete system.
#[derive(Debug, PartialEq)]
pub struct State<const D: usize> {
    /// Nodal positions `r̂` [m].
    pub r: Vec<Vector<D>>,
    /// Nodal velocities `v̂` [m/s].
    pub v: Vec<Vector<D>>,
    /// Element strains `Ĉ` (dimensionless), `C_e = |r'_e|²` for a consistent state.
    pub c: Vec<f64>,
    /// The rigid bodies' states, in the network's body order (empty without bodies).
    pub bodies: Vec<BodyState>,
}

// By hand: `clone_from` copies into the existing vectors (the derived one allocates anew),
// so saving and restoring the state around a step (`dg4`, error control) does not allocate.
impl<const D: usize> Clone for State<D> {
    fn clone(&self) -> Self {
        Self {
            r: self.r.clone(),
            v: self.v.clone(),
            c: self.c.clone(),
            bodies: self.bodies.clone(),
        }
    }
    fn clone_from(&mut self, source: &Self) {
        self.r.clone_from(&source.r);
        self.v.clone_from(&source.v);
        self.c.clone_from(&source.c);
        self.bodies.clone_from(&source.bodies);
    }
}

impl<const D: usize> State<D> {
    /// A state with velocities `v` and strains consistent with the positions,
    /// `C_e = |r'_e|²` (paper Remark 5).
    pub fn consistent(mesh: &Mesh, r: Vec<Vector<D>>, v: Vec<Vector<D>>) -> Self {
        let c = mesh
            .elements()
            .iter()
            .zip(mesh.lengths())
            .map(|(&[a, b], &l)| ((r[b] - r[a]) / l).norm_squared())
            .collect();
        Self {
            r,
            v,
            c,
            bodies: Vec::new(),
        }
    }

    /// A state at rest (`v̂ = 0`) with consistent strains.
    pub fn at_rest(mesh: &Mesh, r: Vec<Vector<D>>) -> Self {
        let v = vec![Vector::<D>::zeros(); r.len()];
        Self::consistent(mesh, r, v)
    }

    /// Nodes `from + s (to − from)` at the mesh's cumulative reference arc length
    /// `s ∈ [0, 1]`, at rest. For a chain mesh this is a straight string from `from` to `to`.
    pub fn straight(mesh: &Mesh, from: Vector<D>, to: Vector<D>) -> Self {
        let total = mesh.total_length();
        let mut r = Vec::with_capacity(mesh.n_nodes());
        let mut s = 0.0;
        r.push(from);
        for &l in mesh.lengths() {
            s += l;
            r.push(from + (to - from) * (s / total));
        }
        r.truncate(mesh.n_nodes());
        while r.len() < mesh.n_nodes() {
            r.push(from);
        }
        Self::at_rest(mesh, r)
    }

    /// Largest deviation `max_e |C_e − |r'_e|²|` from the kinematic relation (Remark 5).
    pub fn kinematic_defect(&self, mesh: &Mesh) -> f64 {
        mesh.elements()
            .iter()
            .zip(mesh.lengths())
            .zip(&self.c)
            .map(|((&[a, b], &l), &c)| (c - ((self.r[b] - self.r[a]) / l).norm_squared()).abs())
            .fold(0.0, f64::max)
    }
}

/// Energies of a state [J].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Energies {
    /// Kinetic energy `T̂ = ½ v̂ᵀ M_ρ v̂`.
    pub kinetic: f64,
    /// Stored (internal) energy `Σ_e l_e W(C_e)`.
    pub internal: f64,
    /// External potential `−r̂ᵀ F_b`.
    pub external: f64,
    /// Buoyancy potential `Σ_i −ρ_w g V_i Φ(z_i)` (docs/method.md §21; 0 without water).
    pub buoyancy: f64,
    /// Seabed contact potential `Σ_i ½ k d L_i p_i²` (docs/method.md §21; 0 without seabed).
    pub seabed: f64,
    /// The sum of the magnitudes of the terms summed into the three energies [J]: per element
    /// its kinetic energy and `l_e |W(C_e)|`, per point mass its kinetic energy, per node
    /// `|r̂_i·F_b,i|`, per wet node its buoyancy and contact potentials. The rounding of the energies is of order `ε` times this, wherever the
    /// origin lies (a potential near zero by cancellation has large terms).
    pub magnitude: f64,
}

impl Energies {
    /// Potential energy `V̂ = internal + external + buoyancy + seabed`.
    pub fn potential(&self) -> f64 {
        self.internal + self.external + self.buoyancy + self.seabed
    }
    /// Hamiltonian `Ĥ = T̂ + V̂` (docs/method.md eq. (4.8), paper eq. (26); with water
    /// eq. (21.1)).
    pub fn hamiltonian(&self) -> f64 {
        self.kinetic + self.internal + self.external + self.buoyancy + self.seabed
    }
    /// The terms as `[kinetic, internal, external, buoyancy, seabed, magnitude]` [J].
    pub(crate) fn to_array(self) -> [f64; 6] {
        [
            self.kinetic,
            self.internal,
            self.external,
            self.buoyancy,
            self.seabed,
            self.magnitude,
        ]
    }
    /// The energies of the terms `[kinetic, internal, external, buoyancy, seabed,
    /// magnitude]` [J] ([`Self::to_array`]).
    pub(crate) fn from_array(
        [kinetic, internal, external, buoyancy, seabed, magnitude]: [f64; 6],
    ) -> Self {
        Energies {
            kinetic,
            internal,
            external,
            buoyancy,
            seabed,
            magnitude,
        }
    }
    /// These energies with the part `from` of them replaced by `to`, term by term (the
    /// magnitude too): the energies after a change confined to that part.
    pub(crate) fn replaced(&self, from: &Energies, to: &Energies) -> Energies {
        let f = |x: f64, a: f64, b: f64| x - a + b;
        Energies {
            kinetic: f(self.kinetic, from.kinetic, to.kinetic),
            internal: f(self.internal, from.internal, to.internal),
            external: f(self.external, from.external, to.external),
            buoyancy: f(self.buoyancy, from.buoyancy, to.buoyancy),
            seabed: f(self.seabed, from.seabed, to.seabed),
            magnitude: f(self.magnitude, from.magnitude, to.magnitude),
        }
    }
}

/// A point mass attached to a node (a payload, a clump weight): it adds `mass` to the node's
/// inertia and the constant force `weight` (usually `mass · g`) to the node's loads; its
/// potential `−r·weight` is part of `V̂`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass<const D: usize> {
    /// Node index.
    pub node: usize,
    /// Mass [kg].
    pub mass: f64,
    /// Constant force on the mass [N], e.g. its weight `mass · g`.
    pub weight: Vector<D>,
}

/// The problem: everything that defines the semi-discrete system and its initial state.
#[derive(Debug, Clone)]
pub struct Problem<const D: usize, M> {
    /// Reference configuration.
    pub mesh: Mesh,
    /// Stored-energy function.
    pub material: M,
    /// Mass per unit reference length `ρA` [kg/m].
    pub rho_a: f64,
    /// Constant body force per unit reference length `b` [N/m] (gravity: `−g ρA e_y`).
    pub body_force: Vector<D>,
    /// Mass matrix variant.
    pub mass: MassMatrix,
    /// Boundary conditions.
    pub boundary: Boundary<D>,
    /// Point masses at nodes (none by default).
    pub point_masses: Vec<PointMass<D>>,
    /// Initial state.
    pub initial: State<D>,
}

/// The stored-energy law of an element group: a string law `M`, or a linear spring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law<M> {
    /// A string (cable, rope) of the law `M`, `W` per unit reference length.
    String(M),
    /// Linear springs; their elements have reference length 1 m (see [`LinearSpring`]).
    Spring(LinearSpring),
}

impl<M: StoredEnergy> StoredEnergy for Law<M> {
    #[inline]
    fn w(&self, c: f64) -> f64 {
        match self {
            Law::String(m) => m.w(c),
            Law::Spring(s) => s.w(c),
        }
    }
    #[inline]
    fn dw(&self, c: f64) -> f64 {
        match self {
            Law::String(m) => m.dw(c),
            Law::Spring(s) => s.dw(c),
        }
    }
    #[inline]
    fn d2w(&self, c: f64) -> f64 {
        match self {
            Law::String(m) => m.d2w(c),
            Law::Spring(s) => s.d2w(c),
        }
    }
    #[inline]
    fn admissible(&self, c: f64) -> bool {
        match self {
            Law::String(m) => m.admissible(c),
            Law::Spring(s) => s.admissible(c),
        }
    }
    #[inline]
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        match self {
            Law::String(m) => m.quotient(c0, c1),
            Law::Spring(s) => s.quotient(c0, c1),
        }
    }
}

/// A run of consecutive elements `elements` that share one law and cross-section: one
/// string of a network, or a set of springs.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementGroup<const D: usize, M> {
    /// Name for outputs and messages, e.g. the string's name in the scenario.
    pub name: String,
    /// The elements of the group (indices into the mesh's element list).
    pub elements: Range<usize>,
    /// Stored-energy law.
    pub law: Law<M>,
    /// Mass per unit reference length `ρA` [kg/m] (positive for strings, 0 for springs).
    pub rho_a: f64,
    /// Mass matrix variant of the group's elements.
    pub mass: MassMatrix,
    /// Constant body force per unit reference length `b` [N/m] (gravity: `ρA g`; 0 for
    /// springs).
    pub body_force: Vector<D>,
    /// Dissipation of the group's elements (none by default; docs/method.md §18).
    pub damping: Damping,
}

/// Dissipation of an element group, the resistive structure `R ≥ 0` of the port-Hamiltonian
/// system (docs/method.md §18). Every coefficient is ≥ 0; all zero (the default) is a
/// lossless group.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Damping {
    /// Kelvin–Voigt viscosity `η` [N·s] of a string: the stress is `S = 2W'(C) + η Ċ`, the
    /// dissipated power `∫ ½ η Ċ² ds` (reference arc length). Strings only.
    pub kelvin_voigt: f64,
    /// Linear drag per unit reference length `c` [N·s/m²]: the distributed force `−c v`,
    /// the dissipated power `∫ c |v|² ds`. Strings only.
    pub drag: f64,
    /// Linear dashpot `c` [N·s/m] across each spring element: the forces `∓c (v_b − v_a)` on
    /// its ends `a` and `b` (all components: a Cartesian damper), the dissipated power
    /// `c |v_b − v_a|²`. Springs only (a spring of stiffness 0 is a pure dashpot).
    pub dashpot: f64,
}

impl Damping {
    /// No dissipation.
    pub const NONE: Self = Self {
        kelvin_voigt: 0.0,
        drag: 0.0,
        dashpot: 0.0,
    };
    /// Whether every coefficient is zero.
    pub fn is_none(&self) -> bool {
        self.kelvin_voigt == 0.0 && self.drag == 0.0 && self.dashpot == 0.0
    }
}

/// A network: any number of strings and springs on one mesh, joined at shared nodes, with
/// point masses, supports, loads and prescribed motions. One Hamiltonian, one step.
#[derive(Debug, Clone)]
pub struct Network<const D: usize, M> {
    /// Reference configuration of all strings and springs.
    pub mesh: Mesh,
    /// Element groups, in element order, covering every element once.
    pub groups: Vec<ElementGroup<D, M>>,
    /// Boundary conditions.
    pub boundary: Boundary<D>,
    /// Point masses at nodes.
    pub point_masses: Vec<PointMass<D>>,
    /// Initial state.
    pub initial: State<D>,
    /// Water, current and seabed (docs/method.md §21); `None`: dry.
    pub water: Option<Water<D>>,
    /// Hydrodynamic parameters of the lines and points that the water acts on.
    pub hydro: Hydrodynamics,
    /// Rigid bodies (docs/method.md §22); their initial states are theirs, the attached
    /// nodes' initial positions and velocities must agree with them.
    pub bodies: Vec<RigidBody<D>>,
    /// Winches (docs/method.md §23), each paying out one string from a drum at its first
    /// node.
    pub winches: Vec<crate::winch::Winch>,
}

impl<const D: usize, M> Network<D, M> {
    /// The network in `water` (replacing any water set before).
    pub fn with_water(mut self, water: Water<D>) -> Self {
        self.water = Some(water);
        self
    }
    /// The network with line hydrodynamics `hydro` for element group `group` (a string); a
    /// string without them feels no water.
    pub fn with_line_hydro(mut self, group: usize, hydro: LineHydro) -> Self {
        self.hydro.lines.push((group, hydro));
        self
    }
    /// The network with the hydrodynamics `point` of a node (buoyancy, drag, added mass).
    pub fn with_point_hydro(mut self, point: PointHydro) -> Self {
        self.hydro.points.push(point);
        self
    }
    /// The network with the rigid body `body`.
    pub fn with_body(mut self, body: RigidBody<D>) -> Self {
        self.bodies.push(body);
        self
    }
    /// The network with the winch `winch`.
    pub fn with_winch(mut self, winch: crate::winch::Winch) -> Self {
        self.winches.push(winch);
        self
    }
}

impl<const D: usize, M> From<Problem<D, M>> for Network<D, M> {
    /// The single string of `problem` as a network of one group named `string`.
    fn from(p: Problem<D, M>) -> Self {
        let n_el = p.mesh.n_elements();
        Network {
            groups: vec![ElementGroup {
                name: "string".into(),
                elements: 0..n_el,
                law: Law::String(p.material),
                rho_a: p.rho_a,
                mass: p.mass,
                body_force: p.body_force,
                damping: Damping::NONE,
            }],
            mesh: p.mesh,
            boundary: p.boundary,
            point_masses: p.point_masses,
            initial: p.initial,
            water: None,
            hydro: Hydrodynamics::default(),
            bodies: Vec::new(),
            winches: Vec::new(),
        }
    }
}

/// The validated semi-discrete PH system with its precomputed constant operators.
#[derive(Debug, Clone)]
pub struct PhSystem<const D: usize, M> {
    pub(crate) mesh: Mesh,
    pub(crate) groups: Vec<ElementGroup<D, M>>,
    pub(crate) boundary: Boundary<D>,
    /// `F_b` per node [N].
    pub(crate) f_body: Vec<Vector<D>>,
    /// Per node: which components are free (not fixed).
    pub(crate) free: Vec<[bool; D]>,
    /// Nodes with at least one fixed component, sorted.
    pub(crate) constrained: Vec<usize>,
    /// Elements with a node in `constrained`.
    pub(crate) constrained_elements: Vec<usize>,
    /// Point masses `(node, mass [kg])`, sorted by node (their weights are in `f_body`),
    /// with the points' added masses.
    pub(crate) point_mass: Vec<(usize, f64)>,
    /// Water, lumped to nodes and elements (docs/method.md §21); `None`: dry.
    pub(crate) water: Option<Box<WaterModel<D>>>,
    /// Rigid bodies (docs/method.md §22), with their names.
    pub(crate) bodies: Vec<BodyModel>,
    pub(crate) body_names: Vec<String>,
    /// Per body and attachment, the elements at the attached node: `(element, other node,
    /// the attached node is the element's first)`.
    pub(crate) body_links: Vec<Vec<Vec<(usize, usize, bool)>>>,
    /// Per node, the body and attachment it is fixed to (empty without bodies).
    pub(crate) attached: Vec<Option<(usize, usize)>>,
    /// The bodies' initial states as the network gave them (the start of the statics).
    pub(crate) body_start: Vec<BodyState>,
    /// Winches (docs/method.md §23) with their starting states.
    pub(crate) winches: Vec<crate::winch::WinchModel<D>>,
    pub(crate) winch_start: Vec<crate::winch::WinchState>,
    /// Per node: whether a winch may hold it (its string's nodes but the last); such nodes
    /// are not support ports.
    pub(crate) winch_node: Vec<bool>,
    /// The water and hydrodynamics as given, kept with winches to lump the water again
    /// over the elements off the drums.
    pub(crate) water_spec: Option<Box<(Water<D>, Hydrodynamics)>>,
}

/// Element mass-matrix coefficients `(m_diag, m_off)` [kg] of an element of reference length
/// `l` [m]: it contributes `m_diag I` to each diagonal node block and `m_off I` to the two
/// off-diagonal blocks.
#[inline]
pub(crate) fn element_mass(mass: MassMatrix, rho_a: f64, l: f64) -> (f64, f64) {
    match mass {
        MassMatrix::Consistent => (rho_a * l / 3.0, rho_a * l / 6.0),
        MassMatrix::Lumped => (rho_a * l / 2.0, 0.0),
    }
}

/// The kinetic and stored energies [J] of an element of group `g` and reference length `l`
/// [m] with its nodes' velocities `(va, vb)` [m/s] and strain `c`.
#[inline]
pub(crate) fn element_energies<const D: usize, M: StoredEnergy>(
    g: &ElementGroup<D, M>,
    l: f64,
    (va, vb): (&Vector<D>, &Vector<D>),
    c: f64,
) -> (f64, f64) {
    let (md, mo) = element_mass(g.mass, g.rho_a, l);
    (
        0.5 * md * (va.norm_squared() + vb.norm_squared()) + mo * va.dot(vb),
        l * g.law.w(c),
    )
}

/// Checks that the groups cover the elements in order, each once, and each group's
/// parameters (law, mass, damping, body force).
fn check_groups<const D: usize, M: StoredEnergy>(
    mesh: &Mesh,
    groups: &[ElementGroup<D, M>],
) -> Result<(), SetupError> {
    let n_el = mesh.n_elements();
    let mut next = 0;
    for (g, grp) in groups.iter().enumerate() {
        let (start, end) = (grp.elements.start, grp.elements.end);
        if start != next || end <= start || end > n_el {
            return Err(SetupError::GroupCoverage {
                group: g,
                start,
                end,
                expected: next,
                n_elements: n_el,
            });
        }
        next = end;
        check_group(g, grp, groups.len())?;
    }
    if next != n_el {
        return Err(SetupError::GroupCoverage {
            group: groups.len(),
            start: n_el,
            end: n_el,
            expected: next,
            n_elements: n_el,
        });
    }
    Ok(())
}

/// Checks the parameters of group `g` (of `n_groups`): its law's constants, its mass, its
/// damping (and that the damping suits the law) and its body force.
fn check_group<const D: usize, M: StoredEnergy>(
    g: usize,
    grp: &ElementGroup<D, M>,
    n_groups: usize,
) -> Result<(), SetupError> {
    match grp.law {
        Law::String(_) => {
            if !(grp.rho_a > 0.0 && grp.rho_a.is_finite()) {
                return Err(SetupError::NonPositive {
                    what: "rho_a",
                    index: (n_groups > 1).then_some(g),
                    value: grp.rho_a,
                });
            }
        }
        Law::Spring(sp) => {
            if grp.rho_a != 0.0 || grp.body_force.iter().any(|&x| x != 0.0) {
                return Err(SetupError::MassiveSpring {
                    group: g,
                    name: grp.name.clone(),
                });
            }
            // A spring of stiffness 0 and rest length 0 is allowed as the carrier of a
            // dashpot (a rest length would restrict its strain to C > 0 for nothing).
            let pure_dashpot = sp.k == 0.0 && sp.rest == 0.0 && grp.damping.dashpot > 0.0;
            if !(pure_dashpot || sp.k > 0.0 && sp.k.is_finite()) {
                return Err(SetupError::NonPositive {
                    what: "spring stiffness k [N/m] of group",
                    index: Some(g),
                    value: sp.k,
                });
            }
            if !(sp.rest >= 0.0 && sp.rest.is_finite()) {
                return Err(SetupError::OutOfRange {
                    what: "spring rest length [m]",
                    value: sp.rest,
                    range: "0 <= rest < infinity",
                });
            }
        }
    }
    let d = &grp.damping;
    for (what, value) in [
        ("Kelvin-Voigt viscosity eta [N s]", d.kelvin_voigt),
        ("drag coefficient [N s/m^2]", d.drag),
        ("dashpot coefficient [N s/m]", d.dashpot),
    ] {
        if !(value >= 0.0 && value.is_finite()) {
            return Err(SetupError::OutOfRange {
                what,
                value,
                range: "0 <= value < infinity",
            });
        }
    }
    let is_string = matches!(grp.law, Law::String(_));
    let misplaced = if is_string {
        (d.dashpot != 0.0).then_some("dashpot (springs only; strings take kelvin_voigt or drag)")
    } else if d.kelvin_voigt != 0.0 {
        Some("Kelvin-Voigt viscosity (strings only; springs take a dashpot)")
    } else {
        (d.drag != 0.0).then_some("drag (strings only; springs take a dashpot)")
    };
    if let Some(what) = misplaced {
        return Err(SetupError::MisplacedDamping {
            group: g,
            name: grp.name.clone(),
            what,
        });
    }
    for (i, x) in grp.body_force.iter().enumerate() {
        if !x.is_finite() {
            return Err(SetupError::NotFinite {
                what: "body force component",
                index: i,
                value: *x,
            });
        }
    }
    Ok(())
}

/// Checks the initial state's sizes against the mesh, that its positions and velocities are
/// finite and that every element's strain is in its law's domain.
fn check_initial<const D: usize, M: StoredEnergy>(
    mesh: &Mesh,
    groups: &[ElementGroup<D, M>],
    initial: &State<D>,
) -> Result<(), SetupError> {
    let n = mesh.n_nodes();
    for (what, got) in [
        ("positions", initial.r.len()),
        ("velocities", initial.v.len()),
    ] {
        if got != n {
            return Err(SetupError::StateSize {
                what,
                got,
                expected: n,
            });
        }
    }
    if initial.c.len() != mesh.n_elements() {
        return Err(SetupError::StateSize {
            what: "strains",
            got: initial.c.len(),
            expected: mesh.n_elements(),
        });
    }
    for (i, (r, v)) in initial.r.iter().zip(&initial.v).enumerate() {
        if let Some(x) = r.iter().chain(v.iter()).find(|x| !x.is_finite()) {
            return Err(SetupError::NotFinite {
                what: "initial position/velocity of node",
                index: i,
                value: *x,
            });
        }
    }
    for grp in groups {
        for e in grp.elements.clone() {
            let c = initial.c[e];
            if !grp.law.admissible(c) {
                return Err(SetupError::InadmissibleStrain { element: e, c });
            }
        }
    }
    Ok(())
}

/// The free components per node of `n`: all but the fixed and the prescribed ones. Checks the
/// node references of fixed conditions and motions and that each motion starts at the
/// initial position.
fn free_components<const D: usize>(
    boundary: &Boundary<D>,
    initial: &State<D>,
    n: usize,
) -> Result<Vec<[bool; D]>, SetupError> {
    let mut free = vec![[true; D]; n];
    for fx in &boundary.fixed {
        if fx.node >= n {
            return Err(SetupError::NodeOutOfRange {
                what: "fixed condition",
                node: fx.node,
                n_nodes: n,
            });
        }
        for k in 0..D {
            free[fx.node][k] &= !fx.components[k];
        }
    }
    for (k, m) in boundary.motions.iter().enumerate() {
        if m.node >= n {
            return Err(SetupError::NodeOutOfRange {
                what: "prescribed motion",
                node: m.node,
                n_nodes: n,
            });
        }
        if m.component >= D {
            return Err(SetupError::NodeOutOfRange {
                what: "prescribed motion (component)",
                node: m.component,
                n_nodes: D,
            });
        }
        let (at_zero, initial) = ((m.position)(0.0), initial.r[m.node][m.component]);
        // NaN (a signal undefined at 0) fails too.
        let starts_there = (at_zero - initial).abs() <= 1e-9 * initial.abs().max(1.0);
        if !starts_there {
            return Err(SetupError::MotionStart {
                index: k,
                node: m.node,
                component: m.component,
                at_zero,
                initial,
            });
        }
        free[m.node][m.component] = false;
    }
    Ok(free)
}

/// Checks the node references of the loads and feedback ports (`n` nodes).
fn check_port_nodes<const D: usize>(boundary: &Boundary<D>, n: usize) -> Result<(), SetupError> {
    for load in &boundary.loads {
        if load.node >= n {
            return Err(SetupError::NodeOutOfRange {
                what: "load",
                node: load.node,
                n_nodes: n,
            });
        }
    }
    for fb in &boundary.feedback {
        if fb.node >= n {
            return Err(SetupError::NodeOutOfRange {
                what: "feedback port",
                node: fb.node,
                n_nodes: n,
            });
        }
    }
    Ok(())
}

/// Whether a node with the free flags `free` has a fixed or prescribed component.
pub(crate) fn is_held<const D: usize>(free: &[bool; D]) -> bool {
    free.iter().any(|f| !f)
}

/// The nodes with a fixed or prescribed component, and the elements touching them, into
/// the two lists (emptied first; a refill within their capacity does not allocate).
fn constrained_sets<const D: usize>(
    mesh: &Mesh,
    free: &[[bool; D]],
    (constrained, constrained_elements): (&mut Vec<usize>, &mut Vec<usize>),
) {
    let is_constrained = |i: usize| is_held(&free[i]);
    constrained.clear();
    constrained.extend((0..free.len()).filter(|&i| is_constrained(i)));
    constrained_elements.clear();
    constrained_elements.extend(
        mesh.elements()
            .iter()
            .enumerate()
            .filter(|(_, [a, b])| is_constrained(*a) || is_constrained(*b))
            .map(|(e, _)| e),
    );
}

/// The strings' body forces lumped to the nodes, `F_b` [N] per node, and the lumped mass
/// [kg] per node (to find free nodes without inertia).
fn distributed_loads<const D: usize, M>(
    mesh: &Mesh,
    groups: &[ElementGroup<D, M>],
) -> (Vec<Vector<D>>, Vec<f64>) {
    let n = mesh.n_nodes();
    let mut f_body = vec![Vector::<D>::zeros(); n];
    // Lumped mass per node, to find free nodes without inertia.
    let mut node_mass = vec![0.0; n];
    for grp in groups {
        let els = grp.elements.clone();
        for (&[a, b], &l) in mesh.elements()[els.clone()]
            .iter()
            .zip(&mesh.lengths()[els])
        {
            f_body[a] += grp.body_force * (0.5 * l);
            f_body[b] += grp.body_force * (0.5 * l);
            node_mass[a] += grp.rho_a * l;
            node_mass[b] += grp.rho_a * l;
        }
    }
    (f_body, node_mass)
}

/// Checks the point masses, adds their weights to `f_body` and their masses to `node_mass`,
/// and returns them as `(node, mass [kg])` sorted by node, several at one node added up.
fn add_point_masses<const D: usize>(
    point_masses: &[PointMass<D>],
    f_body: &mut [Vector<D>],
    node_mass: &mut [f64],
) -> Result<Vec<(usize, f64)>, SetupError> {
    let n = f_body.len();
    let mut point_mass = Vec::with_capacity(point_masses.len());
    for (k, pm) in point_masses.iter().enumerate() {
        if pm.node >= n {
            return Err(SetupError::NodeOutOfRange {
                what: "point mass",
                node: pm.node,
                n_nodes: n,
            });
        }
        if !(pm.mass > 0.0 && pm.mass.is_finite()) {
            return Err(SetupError::NonPositive {
                what: "point mass [kg]",
                index: Some(k),
                value: pm.mass,
            });
        }
        if let Some(x) = pm.weight.iter().find(|x| !x.is_finite()) {
            return Err(SetupError::NotFinite {
                what: "weight of point mass",
                index: k,
                value: *x,
            });
        }
        f_body[pm.node] += pm.weight;
        node_mass[pm.node] += pm.mass;
        point_mass.push((pm.node, pm.mass));
    }
    // Several masses at one node add up.
    point_mass.sort_by_key(|&(node, _)| node);
    point_mass.dedup_by(|later, first| {
        let same = later.0 == first.0;
        if same {
            first.1 += later.1;
        }
        same
    });
    Ok(point_mass)
}

/// What the water's lumping needs of each group: whether it is a string, its name and its
/// (active) elements.
fn group_info<const D: usize, M>(groups: &[ElementGroup<D, M>]) -> Vec<GroupInfo<'_>> {
    groups
        .iter()
        .map(|g| GroupInfo {
            is_string: matches!(g.law, Law::String(_)),
            name: &g.name,
            elements: g.elements.clone(),
        })
        .collect()
}

/// Validates the water and the hydrodynamics (none without water), adds the lines' added
/// masses to their groups' `ρA` and the points' to `point_mass`, and returns the lumped model.
fn attach_water<const D: usize, M>(
    water: Option<&Water<D>>,
    hydro: &Hydrodynamics,
    mesh: &Mesh,
    groups: &mut [ElementGroup<D, M>],
    point_mass: &mut Vec<(usize, f64)>,
) -> Result<Option<Box<WaterModel<D>>>, SetupError> {
    let Some(water) = water else {
        return if hydro.is_empty() {
            Ok(None)
        } else {
            Err(SetupError::HydroWithoutWater)
        };
    };
    let info = group_info(groups);
    let (model, added_rho_a, added_point) = crate::water::build(water, hydro, mesh, &info)?;
    for (g, add) in groups.iter_mut().zip(added_rho_a) {
        g.rho_a += add;
    }
    if !added_point.is_empty() {
        point_mass.extend(added_point);
        point_mass.sort_by_key(|&(node, _)| node);
        point_mass.dedup_by(|later, first| {
            let same = later.0 == first.0;
            if same {
                first.1 += later.1;
            }
            same
        });
    }
    Ok(Some(Box::new(model)))
}

/// Checks the winches (docs/method.md §23): the
/// checks of [`crate::winch::attach`], with the nodes that carry a support, load, port, point
/// mass or body attachment claimed (but a drum node on a body, `on_body`).
#[allow(clippy::too_many_arguments)]
fn attach_winches<const D: usize, M>(
    winches: &[crate::winch::Winch],
    mesh: &Mesh,
    groups: &[ElementGroup<D, M>],
    (boundary, point_masses, bodies): (&Boundary<D>, &[PointMass<D>], &[RigidBody<D>]),
    (initial, water_points): (&State<D>, &[PointHydro]),
    on_body: &[Option<crate::winch::BodyDrum>],
) -> Result<Vec<(crate::winch::WinchModel<D>, crate::winch::WinchState)>, SetupError> {
    if winches.is_empty() {
        return Ok(Vec::new());
    }
    let mut claimed = vec![false; mesh.n_nodes()];
    let nodes = boundary
        .fixed
        .iter()
        .map(|f| f.node)
        .chain(boundary.motions.iter().map(|m| m.node))
        .chain(boundary.loads.iter().map(|l| l.node))
        .chain(boundary.feedback.iter().map(|f| f.node))
        .chain(point_masses.iter().map(|p| p.node))
        .chain(water_points.iter().map(|p| p.node))
        .chain(bodies.iter().enumerate().flat_map(|(b, body)| {
            // A drum on a body: its attachment holds the drum node for the winch.
            let drum = move |k: usize| on_body.iter().flatten().any(|d| (d.0, d.1) == (b, k));
            body.attachments
                .iter()
                .enumerate()
                .filter(move |&(k, _)| !drum(k))
                .map(|(_, a)| a.node)
        }));
    for i in nodes {
        if let Some(c) = claimed.get_mut(i) {
            *c = true;
        }
    }
    let info: Vec<_> = groups
        .iter()
        .map(|g| {
            (
                g.elements.clone(),
                g.body_force,
                matches!(g.law, Law::String(_)),
            )
        })
        .collect();
    crate::winch::attach(
        winches,
        mesh,
        &info,
        (&initial.r, &initial.v),
        |i| claimed[i],
        on_body,
    )
}

/// The winches whose drum is a rigid body's point (docs/method.md §23, "A drum on a rigid
/// body"): per winch, `(body, attachment, drum point in body axes)` where its string's first
/// node is fixed to a body. Each such attachment is moved to the drum node (the first node
/// off the drum), which starts at the same point, and the nodes on the drum are given the
/// drum point's velocity. A drum on a body takes no drum motion of its own (refused naming
/// the winch).
fn body_drums<const D: usize, M>(
    winches: &[crate::winch::Winch],
    mesh: &Mesh,
    groups: &[ElementGroup<D, M>],
    bodies: &mut [RigidBody<D>],
    initial: &mut State<D>,
) -> Result<Vec<Option<crate::winch::BodyDrum>>, SetupError> {
    let mut out = Vec::with_capacity(winches.len());
    for (k, w) in winches.iter().enumerate() {
        let range = match groups.get(w.group) {
            Some(g) if w.reserve < g.elements.len() => g.elements.clone(),
            _ => {
                // `winch::attach` names what is wrong with the group.
                out.push(None);
                continue;
            }
        };
        let first = mesh.elements()[range.start][0];
        let found = bodies.iter().enumerate().find_map(|(b, body)| {
            let k = body.attachments.iter().position(|a| a.node == first)?;
            Some((b, k))
        });
        let Some((b, j)) = found else {
            out.push(None);
            continue;
        };
        let problem = |problem: &str| SetupError::Winch {
            index: k,
            name: w.name.clone(),
            problem: problem.into(),
        };
        if w.drum_motion.is_some() {
            return Err(problem(
                "its drum is a point of a rigid body and moves with the body: give it no drum motion of its own",
            ));
        }
        let drum_node = mesh.elements()[range.start + w.reserve][0];
        let point = crate::body::embed(&bodies[b].attachments[j].point);
        bodies[b].attachments[j].node = drum_node;
        // (A state of the wrong size is refused by the checks that follow.)
        if let Some(&v0) = initial.v.get(first) {
            for e in range.start..range.start + w.reserve {
                let [_, next] = mesh.elements()[e];
                if let Some(v) = initial.v.get_mut(next) {
                    *v = v0;
                }
            }
        }
        out.push(Some((b, j, point)));
    }
    Ok(out)
}

/// Refuses nodal body forces that are not finite or whose squares overflow.
fn check_body_forces<const D: usize>(f_body: &[Vector<D>]) -> Result<(), SetupError> {
    if let Some((i, f)) = f_body
        .iter()
        .enumerate()
        .find(|(_, f)| !f.iter().all(|x| x.is_finite()))
    {
        return Err(SetupError::DerivedNotFinite {
            what: format!("body force at node {i}"),
            value: f
                .iter()
                .copied()
                .find(|x| !x.is_finite())
                .unwrap_or(f64::NAN),
        });
    }
    // The residual's force scale squares the forces: they must stay below about 1e154 N.
    let f2: f64 = f_body.iter().map(|f| f.norm_squared()).sum();
    if !f2.is_finite() {
        return Err(SetupError::DerivedNotFinite {
            what: "sum of the squared nodal body forces".into(),
            value: f2,
        });
    }
    Ok(())
}

impl<const D: usize, M: StoredEnergy> PhSystem<D, M> {
    /// Validates `problem` (a single [`Problem`] or a [`Network`]) and precomputes `F_b`.
    /// Returns the system and the initial state.
    pub fn new(problem: impl Into<Network<D, M>>) -> Result<(Self, State<D>), SetupError> {
        let Network {
            mesh,
            groups,
            boundary,
            point_masses,
            initial,
            water,
            hydro,
            bodies,
            winches,
        } = problem.into();
        let mut groups = groups;
        let mut initial = initial;
        let mut bodies = bodies;
        check_groups(&mesh, &groups)?;
        let on_body = body_drums(&winches, &mesh, &groups, &mut bodies, &mut initial)?;
        let winch_data = attach_winches(
            &winches,
            &mesh,
            &groups,
            (&boundary, &point_masses, &bodies),
            (&initial, &hydro.points),
            &on_body,
        )?;
        for (m, ws) in &winch_data {
            groups[m.group].elements.start = m.drum_element(ws);
        }
        check_initial(&mesh, &groups, &initial)?;
        let n = mesh.n_nodes();
        let mut free = free_components(&boundary, &initial, n)?;
        check_port_nodes(&boundary, n)?;
        let mut rigid = crate::body::attach_bodies(
            &bodies,
            &mesh,
            &boundary,
            water.as_ref(),
            &mut free,
            &initial.r,
            &initial.v,
        )?;
        for &(b, _, _) in on_body.iter().flatten() {
            let model = &mut rigid.models[b];
            model.offset = vec![crate::body::Vec3::zeros(); model.attachments.len()];
        }
        initial.bodies.clone_from(&rigid.states);
        for (e, &l) in mesh.lengths().iter().enumerate() {
            if !l.is_finite() {
                return Err(SetupError::DerivedNotFinite {
                    what: format!("reference length of element {e}"),
                    value: l,
                });
            }
        }
        let (mut f_body, mut node_mass) = distributed_loads(&mesh, &groups);
        let mut point_mass = add_point_masses(&point_masses, &mut f_body, &mut node_mass)?;
        let water_model =
            attach_water(water.as_ref(), &hydro, &mesh, &mut groups, &mut point_mass)?;
        // With winches the lumped water is lumped again where an element comes off or goes
        // onto a drum (docs/method.md §23), in lists with room for every node and element.
        let water_spec = match (&water, winch_data.is_empty()) {
            (Some(w), false) => Some(Box::new((w.clone(), hydro.clone()))),
            _ => None,
        };
        let mut water = water_model;
        if let (Some(w), Some(_)) = (water.as_deref_mut(), &water_spec) {
            w.reserve_all(&mesh);
        }
        let mut winch_node = vec![false; n];
        let (mut winch_models, mut winch_start) = (Vec::new(), Vec::new());
        for (m, ws) in winch_data {
            m.place(
                &ws,
                &mesh,
                &mut groups[m.group].elements,
                &mut f_body,
                &mut free,
                true,
            );
            for &i in &m.nodes[..m.nodes.len() - 1] {
                winch_node[i] = true;
            }
            winch_models.push(m);
            winch_start.push(ws);
        }
        // With winches the sets are filled again after every cut: room for every node and
        // element from the start, so that a cut does not allocate.
        let (mut constrained, mut constrained_elements) = if winch_models.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            (Vec::with_capacity(n), Vec::with_capacity(mesh.n_elements()))
        };
        constrained_sets(&mesh, &free, (&mut constrained, &mut constrained_elements));
        check_body_forces(&f_body)?;
        if let Some(node) = (0..n).find(|&i| free[i].iter().any(|&f| f) && node_mass[i] <= 0.0) {
            return Err(SetupError::MasslessNode { node });
        }
        let sys = Self {
            mesh,
            groups,
            boundary,
            f_body,
            free,
            constrained,
            constrained_elements,
            point_mass,
            water,
            bodies: rigid.models,
            body_names: rigid.names,
            body_links: rigid.links,
            attached: rigid.attached,
            body_start: rigid.states,
            winches: winch_models,
            winch_start,
            winch_node,
            water_spec,
        };
        sys.check_initial_energies(&initial)?;
        Ok((sys, initial))
    }

    /// Checks that `state` can start this system: its sizes, finite positions and
    /// velocities, admissible strains, every prescribed motion at its position at `t = 0`,
    /// every node fixed to a rigid body at its body point and moving with the body, and
    /// finite energies (the checks [`Self::new`] makes of the problem's initial state).
    pub fn check_state(&self, state: &State<D>) -> Result<(), SetupError> {
        check_initial(&self.mesh, &self.groups, state)?;
        if state.bodies.len() != self.bodies.len() {
            return Err(SetupError::StateSize {
                what: "rigid bodies",
                got: state.bodies.len(),
                expected: self.bodies.len(),
            });
        }
        free_components(&self.boundary, state, self.mesh.n_nodes())?;
        crate::body::check_attached(
            &self.bodies,
            &self.body_names,
            &state.bodies,
            (&state.r, &state.v),
            |i| self.winch_node.get(i).copied().unwrap_or(false),
        )?;
        self.check_initial_energies(state)
    }

    /// Refuses an initial state whose energies are not finite.
    fn check_initial_energies(&self, initial: &State<D>) -> Result<(), SetupError> {
        let en = self.energies(initial);
        for (what, value) in [
            ("initial kinetic energy", en.kinetic),
            ("initial internal energy", en.internal),
            ("initial external potential energy", en.external),
            ("initial buoyancy potential", en.buoyancy),
            ("initial seabed contact potential", en.seabed),
            ("initial Hamiltonian", en.hamiltonian()),
        ] {
            if !value.is_finite() {
                return Err(SetupError::DerivedNotFinite {
                    what: what.into(),
                    value,
                });
            }
        }
        Ok(())
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }
    /// The element groups, in element order.
    pub fn groups(&self) -> &[ElementGroup<D, M>] {
        &self.groups
    }
    /// The law of the first group: the material of a single-string problem.
    pub fn material(&self) -> &Law<M> {
        &self.groups[0].law
    }
    /// `ρA` [kg/m] of the first group: that of a single-string problem.
    pub fn rho_a(&self) -> f64 {
        self.groups[0].rho_a
    }
    /// Boundary conditions.
    pub fn boundary(&self) -> &Boundary<D> {
        &self.boundary
    }
    /// Mass matrix variant of the first group: that of a single-string problem.
    pub fn mass_matrix(&self) -> MassMatrix {
        self.groups[0].mass
    }
    /// Nodal body-force vector `F_b = ∫ Φᵀ b` [N] (docs/method.md §4).
    pub fn body_force_vector(&self) -> &[Vector<D>] {
        &self.f_body
    }
    /// Whether any element group dissipates (Kelvin–Voigt, drag or dashpots).
    pub fn has_damping(&self) -> bool {
        self.groups.iter().any(|g| !g.damping.is_none())
    }
    /// Whether the system is in water (docs/method.md §21).
    pub fn has_water(&self) -> bool {
        self.water.is_some()
    }
    /// Seabed contact of every node that can touch it (lines with hydrodynamics) at
    /// positions `r` [m]: grounded flag, penetration [m], contact force [N] (docs/method.md
    /// §21). Empty without seabed.
    pub fn seabed_contacts(&self, r: &[Vector<D>]) -> Vec<crate::water::NodeContact> {
        self.water
            .as_deref()
            .map_or_else(Vec::new, |w| w.contacts(r))
    }
    /// Seabed contact of mesh node `node` at positions `r` [m] (see
    /// [`Self::seabed_contacts`]); `None` if it cannot touch the seabed or there is none.
    pub fn seabed_contact(
        &self,
        node: usize,
        r: &[Vector<D>],
    ) -> Option<crate::water::NodeContact> {
        self.water.as_deref()?.contact(node, r)
    }
    /// Grounded length [m] of element group `group` at positions `r`: the reference length
    /// of its elements, each counted half for each of its two nodes that is grounded.
    pub fn grounded_length(&self, group: usize, r: &[Vector<D>]) -> f64 {
        self.grounded_lengths(&self.seabed_contacts(r))
            .get(group)
            .copied()
            .unwrap_or(0.0)
    }
    /// Grounded length [m] of every element group, in group order, with the seabed contacts
    /// `contacts` ([`Self::seabed_contacts`] at some positions): as
    /// [`Self::grounded_length`], for a caller that has the contacts already.
    pub fn grounded_lengths(&self, contacts: &[crate::water::NodeContact]) -> Vec<f64> {
        let mut grounded = vec![false; self.mesh.n_nodes()];
        for c in contacts {
            grounded[c.node] = c.grounded;
        }
        self.groups
            .iter()
            .map(|g| {
                g.elements
                    .clone()
                    .map(|e| {
                        let [a, b] = self.mesh.elements()[e];
                        let k = u8::from(grounded[a]) + u8::from(grounded[b]);
                        0.5 * f64::from(k) * self.mesh.lengths()[e]
                    })
                    .sum()
            })
            .collect()
    }
    /// The kinetic energy [J] that the isotropic added mass (with `Ca`) gives to the axial
    /// motion of the lines beyond their `CaAx`: `Σ_e ½ ρ_w π d²/4 (Ca − CaAx) l_e (v̄_e·t_e)²`
    /// with the element's mean velocity `v̄_e` and tangent `t_e` (docs/method.md §21). Part
    /// of `T̂`; it measures the approximation, 0 when `Ca = CaAx`.
    pub fn added_mass_axial_excess(&self, state: &State<D>) -> f64 {
        let Some(w) = self.water.as_deref() else {
            return 0.0;
        };
        w.elements
            .iter()
            .map(|el| {
                let [a, b] = self.mesh.elements()[el.e];
                let d = state.r[b] - state.r[a];
                let len = d.norm();
                let vt = if len > 0.0 {
                    (state.v[a] + state.v[b]).dot(&d) * 0.5 / len
                } else {
                    0.0
                };
                0.5 * el.axial_excess * vt * vt
            })
            .sum()
    }
    /// Which components of each node are free.
    pub fn free_components(&self) -> &[[bool; D]] {
        &self.free
    }

    /// Every element as `(group, element index, [a, b], l_e)`, in element order.
    pub(crate) fn each_element(
        &self,
    ) -> impl Iterator<Item = (&ElementGroup<D, M>, usize, [usize; 2], f64)> + '_ {
        self.groups.iter().flat_map(move |g| {
            g.elements
                .clone()
                .map(move |e| (g, e, self.mesh.elements()[e], self.mesh.lengths()[e]))
        })
    }

    /// The first element whose strain `c[e]` is outside its law's domain, if any.
    pub fn first_inadmissible(&self, c: &[f64]) -> Option<usize> {
        self.each_element()
            .find(|&(g, e, _, _)| !g.law.admissible(c[e]))
            .map(|(_, e, _, _)| e)
    }

    /// `out = M_ρ v` [kg·m/s] (momenta per node).
    pub fn mass_mul(&self, v: &[Vector<D>], out: &mut [Vector<D>]) {
        out.iter_mut().for_each(|x| *x = Vector::zeros());
        for (g, _, [a, b], l) in self.each_element() {
            let (md, mo) = element_mass(g.mass, g.rho_a, l);
            out[a] += v[a] * md + v[b] * mo;
            out[b] += v[b] * md + v[a] * mo;
        }
        for &(i, m) in &self.point_mass {
            out[i] += v[i] * m;
        }
    }

    /// Point masses `(node, mass [kg])`, sorted by node, several at one node added up.
    pub fn point_masses(&self) -> &[(usize, f64)] {
        &self.point_mass
    }

    /// `out = K(r) S` [N]: element `e` adds `−S_e r'_e` to node `a` and `+S_e r'_e` to node `b`
    /// (docs/method.md eq. (4.5); enters the momentum balance with a minus sign).
    pub fn k_mul(&self, r: &[Vector<D>], s: &[f64], out: &mut [Vector<D>]) {
        out.iter_mut().for_each(|x| *x = Vector::zeros());
        for ((&[a, b], &l), &se) in self.mesh.elements().iter().zip(self.mesh.lengths()).zip(s) {
            let f = (r[b] - r[a]) * (se / l);
            out[a] -= f;
            out[b] += f;
        }
    }

    /// `out = K(r)ᵀ v` [m/s]: element `e` gets `r'_e · (v_b − v_a)` (docs/method.md eq. (4.6); the
    /// element's `l_e` and `1/l_e` cancel).
    pub fn kt_mul(&self, r: &[Vector<D>], v: &[Vector<D>], out: &mut [f64]) {
        for ((o, &[a, b]), &l) in out
            .iter_mut()
            .zip(self.mesh.elements())
            .zip(self.mesh.lengths())
        {
            *o = ((r[b] - r[a]) / l).dot(&(v[b] - v[a]));
        }
    }

    /// `M_S = diag(l_e)` [m] (docs/method.md §4): the element reference lengths.
    pub fn m_s(&self) -> &[f64] {
        self.mesh.lengths()
    }

    /// Efforts `ẑ = (∂Ĥ/∂r̂, v̂, ½ Ŝ) = (−F_b, v̂, ½ Ŝ)` of `state` (paper eqs. (27)–(28)), so that
    /// `Eᵀ ẑ = ∇Ĥ` with `E = diag(I, M_ρ, M_S)`: units N, m/s, N.
    pub fn efforts(&self, state: &State<D>) -> (Vec<Vector<D>>, Vec<Vector<D>>, Vec<f64>) {
        let neg_fb = self.f_body.iter().map(|f| -f).collect();
        let half_s = self
            .each_element()
            .map(|(g, e, _, _)| g.law.dw(state.c[e]))
            .collect();
        (neg_fb, state.v.clone(), half_s)
    }

    /// Stresses `S_e = 2 W'(C_e)` [N] (paper eq. (24d) with element-wise constant `Ψ`).
    pub fn stresses(&self, c: &[f64], out: &mut [f64]) {
        for (g, e, _, _) in self.each_element() {
            out[e] = 2.0 * g.law.dw(c[e]);
        }
    }

    /// Energies `T̂`, `Σ l_e W(C_e)`, `−r̂ᵀF_b` of `state` [J] (paper eq. (26)).
    pub fn energies(&self, state: &State<D>) -> Energies {
        let bodies = &state.bodies;
        self.energies_with(|i| state.r[i], |i| state.v[i], |e| state.c[e], bodies)
    }

    /// [`Self::energies`] of the state with node positions `r(i)`, velocities `v(i)` and
    /// element strains `c(e)` (each called once per node or element, in the same order as
    /// for a stored state, so the result is bit-identical to `energies` of that state), and
    /// the rigid bodies' states `bodies`.
    pub(crate) fn energies_with(
        &self,
        r: impl Fn(usize) -> Vector<D>,
        v: impl Fn(usize) -> Vector<D>,
        c: impl Fn(usize) -> f64,
        bodies: &[BodyState],
    ) -> Energies {
        let mut kinetic = 0.0;
        let mut internal = 0.0;
        let mut magnitude = 0.0;
        for (g, e, [a, b], l) in self.each_element() {
            let (t, w) = element_energies(g, l, (&v(a), &v(b)), c(e));
            kinetic += t;
            internal += w;
            magnitude += t.abs() + w.abs();
        }
        for &(i, m) in &self.point_mass {
            let t = 0.5 * m * v(i).norm_squared();
            kinetic += t;
            magnitude += t;
        }
        let mut external = 0.0;
        for (i, f) in self.f_body.iter().enumerate() {
            let p = r(i).dot(f);
            external -= p;
            magnitude += p.abs();
        }
        let (mut buoyancy, mut seabed) = (0.0, 0.0);
        for (model, st) in self.bodies.iter().zip(bodies) {
            let (t, p, u) = (
                model.kinetic(st),
                model.potential(st),
                model.buoyancy_potential(st),
            );
            kinetic += t;
            external += p;
            buoyancy += u;
            magnitude += t + p.abs() + u.abs();
        }
        if let Some(w) = &self.water {
            for node in &w.nodes {
                let (u, c) = w.node_energies(node, &r(node.node));
                buoyancy += u;
                seabed += c;
                magnitude += u.abs() + c;
            }
        }
        Energies::from_array([kinetic, internal, external, buoyancy, seabed, magnitude])
    }

    /// Linear momentum `Σ M_ρ v̂` [kg·m/s].
    pub fn linear_momentum(&self, state: &State<D>) -> Vector<D> {
        let mut p = Vector::zeros();
        for (g, _, [a, b], l) in self.each_element() {
            let (md, mo) = element_mass(g.mass, g.rho_a, l);
            p += (state.v[a] + state.v[b]) * (md + mo);
        }
        for &(i, m) in &self.point_mass {
            p += state.v[i] * m;
        }
        for (model, st) in self.bodies.iter().zip(&state.bodies) {
            p += crate::body::project::<D>(&model.linear_momentum(st));
        }
        p
    }

    /// The rigid bodies' angular momenta about the origin, `x × p + R Π` [kg·m²/s], summed
    /// (`p = m V`, or the Kirchhoff impulses `p = R P` and `Π` of an added-mass matrix;
    /// 3-vector; in 2D only `z` is non-zero).
    fn bodies_angular_momentum(&self, state: &State<D>) -> crate::body::Vec3 {
        let mut l = crate::body::Vec3::zeros();
        for (model, st) in self.bodies.iter().zip(&state.bodies) {
            l += st.position.cross(&model.linear_momentum(st))
                + st.orientation.transform_vector(&model.momentum(st));
        }
        l
    }

    /// The nodes with a fixed or moving component (the supports, each a velocity port), in
    /// increasing order: the constrained nodes less those fixed to rigid bodies.
    pub fn support_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.constrained
            .iter()
            .copied()
            .filter(|&i| self.attached.get(i).is_none_or(|a| a.is_none()))
            .filter(|&i| !self.winch_node.get(i).copied().unwrap_or(false))
    }

    /// The elements of group `g` including those parked on a winch's drum (which are not
    /// in the group's active range, [`ElementGroup::elements`]).
    pub fn group_span(&self, g: usize) -> Range<usize> {
        match self.winches.iter().find(|w| w.group == g) {
            Some(w) => w.elements.clone(),
            None => self.groups[g].elements.clone(),
        }
    }

    /// The winches' names and their strings' element groups, in order.
    pub fn winches(&self) -> Vec<(&str, usize)> {
        self.winches
            .iter()
            .map(|w| (w.name.as_str(), w.group))
            .collect()
    }

    /// The winches' states at `t = 0`.
    pub fn winch_start(&self) -> &[crate::winch::WinchState] {
        &self.winch_start
    }

    /// Per winch: the mesh index of its drum node and of its drum element in `states`.
    pub fn winch_layout(&self, states: &[crate::winch::WinchState]) -> Vec<(usize, usize)> {
        self.winches
            .iter()
            .zip(states)
            .map(|(m, ws)| (m.drum_node(ws), m.drum_element(ws)))
            .collect()
    }

    /// Per winch, its string's group and all the string's elements, those on the drum (outside
    /// the group's current range) included.
    pub fn winch_elements(&self) -> Vec<(usize, Range<usize>)> {
        self.winches
            .iter()
            .map(|m| (m.group, m.elements.clone()))
            .collect()
    }

    /// Lumps the water again over the elements in the groups (after a winch changed them);
    /// nothing without water. The water was checked when the system was built, so its
    /// lumping cannot fail here; the added masses stay those of the start.
    fn lump_water_again(&mut self) {
        let Some(spec) = &self.water_spec else {
            return;
        };
        let info = group_info(&self.groups);
        if let Ok((mut model, _, _)) = crate::water::build(&spec.0, &spec.1, &self.mesh, &info) {
            model.reserve_all(&self.mesh);
            self.water = Some(Box::new(model));
        }
    }

    /// Puts the winches' states into the system: each string's group range, held nodes and
    /// body forces, over the whole string; where a node came off or went onto a drum the
    /// constrained sets are rebuilt and the water lumped again (a restore; a cut after a
    /// step places only what it changed, [`Self::place_cut`]).
    pub(crate) fn place_winches(&mut self, states: &[crate::winch::WinchState]) {
        let mut moved = false;
        for (m, ws) in self.winches.iter().zip(states) {
            let range = &mut self.groups[m.group].elements;
            moved |= m.place(
                ws,
                &self.mesh,
                range,
                &mut self.f_body,
                &mut self.free,
                false,
            );
        }
        if moved {
            let sets = (&mut self.constrained, &mut self.constrained_elements);
            constrained_sets(&self.mesh, &self.free, sets);
            self.lump_water_again();
        }
        self.place_body_drums(states);
    }

    /// Fixes each winch drum on a rigid body to the drum node of its state in `states`: the
    /// body's attachment at the drum point holds that node (which slides along its path from
    /// there), with no offset yet, and links the body to the drum element (docs/method.md
    /// §23, "A drum on a rigid body").
    pub(crate) fn place_body_drums(&mut self, states: &[crate::winch::WinchState]) {
        for (k, ws) in states.iter().enumerate() {
            self.place_body_drum(k, ws);
        }
    }

    /// [`Self::place_body_drums`] for winch `w` at state `ws` alone (nothing for a drum that
    /// is not on a rigid body).
    pub(crate) fn place_body_drum(&mut self, w: usize, ws: &crate::winch::WinchState) {
        let m = &self.winches[w];
        let Some((b, k, _)) = m.body else {
            return;
        };
        let node = m.drum_node(ws);
        let old = self.bodies[b].attachments[k].0;
        if old != node {
            self.attached[old] = None;
        }
        self.attached[node] = Some((b, k));
        self.bodies[b].attachments[k].0 = node;
        self.bodies[b].offset[k] = crate::body::Vec3::zeros();
        let links = &mut self.body_links[b][k];
        links.clear();
        links.push((m.drum_element(ws), m.nodes[ws.drum + 1], true));
    }

    /// Refuses an analysis (`what`: "statics", "modes", …) that does not cover rigid bodies
    /// yet, naming the first body.
    pub fn refuse_bodies(&self, what: &str) -> Result<(), SetupError> {
        match self.body_names.first() {
            None => Ok(()),
            Some(name) => Err(SetupError::Body {
                index: 0,
                name: name.clone(),
                problem: format!(
                    "{what} does not cover rigid bodies yet (the time stepper does): run the \
                     dynamics from a hand-placed start instead"
                ),
            }),
        }
    }

    /// The nodes fixed to rigid body `b`, in its attachment order (empty if there is no
    /// body `b`).
    pub fn body_attachments(&self, b: usize) -> Vec<usize> {
        self.bodies
            .get(b)
            .map(|m| m.attachments.iter().map(|a| a.0).collect())
            .unwrap_or_default()
    }

    /// Whether rigid body `b` has a prescribed motion (its port's output is the reaction
    /// wrench).
    pub fn body_has_motion(&self, b: usize) -> bool {
        self.bodies.get(b).is_some_and(|m| m.motion.is_some())
    }

    /// Whether rigid body `b` has a wrench port (a force and torque input).
    pub fn body_has_wrench(&self, b: usize) -> bool {
        self.bodies.get(b).is_some_and(|m| m.wrench.is_some())
    }

    /// Whether body `b` has a feedback law on its wrench port (docs/method.md §22).
    pub fn body_has_feedback(&self, b: usize) -> bool {
        self.bodies.get(b).is_some_and(|m| m.feedback.is_some())
    }

    /// Rigid body `b`'s wrench port at time `t` [s]: its force [N] and torque [N·m] in space
    /// axes at the centre of mass (in 2D the force's `z` and the torque's `x`, `y` are 0);
    /// `None` if there is no body `b` or it has no wrench port.
    pub fn body_wrench_at(
        &self,
        b: usize,
        t: f64,
    ) -> Option<(crate::body::Vec3, crate::body::Vec3)> {
        self.bodies
            .get(b)
            .filter(|m| m.wrench.is_some())
            .map(|m| m.wrench_at::<D>(t))
    }

    /// The rigid bodies (docs/method.md §22), as `(name, mass [kg])` (their own mass,
    /// without the added mass).
    pub fn bodies(&self) -> Vec<(&str, f64)> {
        self.body_names
            .iter()
            .zip(&self.bodies)
            .map(|(n, b)| (n.as_str(), b.dry_mass))
            .collect()
    }
}

impl<M: StoredEnergy> PhSystem<2, M> {
    /// Angular momentum about the origin `Σ_ij M_ij r_i × v_j` (z-component) [kg·m²/s].
    pub fn angular_momentum(&self, state: &State<2>) -> f64 {
        let cross = |r: &Vector<2>, v: &Vector<2>| r[0] * v[1] - r[1] * v[0];
        self.angular(state, cross) + self.bodies_angular_momentum(state).z
    }
}

impl<M: StoredEnergy> PhSystem<3, M> {
    /// Angular momentum about the origin `Σ_ij M_ij r_i × v_j` [kg·m²/s].
    pub fn angular_momentum(&self, state: &State<3>) -> Vector<3> {
        self.angular(state, |r, v| r.cross(v)) + self.bodies_angular_momentum(state)
    }
}

impl<const D: usize, M: StoredEnergy> PhSystem<D, M> {
    fn angular<
        T: std::ops::AddAssign + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T> + Default,
    >(
        &self,
        state: &State<D>,
        cross: impl Fn(&Vector<D>, &Vector<D>) -> T,
    ) -> T {
        let mut l_tot = T::default();
        for (g, _, [a, b], l) in self.each_element() {
            let (md, mo) = element_mass(g.mass, g.rho_a, l);
            let (ra, rb, va, vb) = (&state.r[a], &state.r[b], &state.v[a], &state.v[b]);
            l_tot += (cross(ra, va) + cross(rb, vb)) * md;
            l_tot += (cross(ra, vb) + cross(rb, va)) * mo;
        }
        for &(i, m) in &self.point_mass {
            l_tot += cross(&state.r[i], &state.v[i]) * m;
        }
        l_tot
    }
}
