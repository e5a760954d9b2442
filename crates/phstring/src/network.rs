//! Assembling networks: strings through shared nodes, springs, anchors (docs/method.md §14).
//!
//! A [`NetworkBuilder`] collects named nodes, strings that run through them and springs
//! between them, and numbers the mesh: first the nodes added with [`NetworkBuilder::node`]
//! (junctions, anchors, attachment points), then the interior nodes of each string in the
//! order the strings were added. The elements of one string or spring are consecutive and form
//! one [`ElementGroup`].

use crate::boundary::{Boundary, Fixed};
use crate::error::SetupError;
use crate::material::LinearSpring;
use crate::mesh::Mesh;
use crate::system::{Damping, ElementGroup, Law, MassMatrix, Network, PointMass, State, Vector};

/// The cross-section and law of one string of a network.
#[derive(Debug, Clone, PartialEq)]
pub struct StringSpec<const D: usize, M> {
    /// Name for outputs and messages.
    pub name: String,
    /// Stored-energy law.
    pub material: M,
    /// Mass per unit reference length `ρA` [kg/m].
    pub rho_a: f64,
    /// Mass matrix variant.
    pub mass: MassMatrix,
    /// Constant body force per unit reference length `b` [N/m] (gravity: `ρA g`).
    pub body_force: Vector<D>,
    /// Initial stretch `λ = |Δr| / l` of every element (1: the straight string starts
    /// stress-free; above 1 it starts taut).
    pub prestretch: f64,
}

/// Builds a [`Network`] (see the module documentation for the numbering).
#[derive(Debug, Clone)]
pub struct NetworkBuilder<const D: usize, M> {
    r: Vec<Vector<D>>,
    elements: Vec<[usize; 2]>,
    lengths: Vec<f64>,
    groups: Vec<ElementGroup<D, M>>,
    /// Nodes of each group along its path (springs: their two end nodes).
    paths: Vec<Vec<usize>>,
    anchors: Vec<usize>,
}

impl<const D: usize, M> Default for NetworkBuilder<D, M> {
    fn default() -> Self {
        Self {
            r: Vec::new(),
            elements: Vec::new(),
            lengths: Vec::new(),
            groups: Vec::new(),
            paths: Vec::new(),
            anchors: Vec::new(),
        }
    }
}

impl<const D: usize, M: Clone> NetworkBuilder<D, M> {
    /// An empty network.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a node at `r` [m] and returns its index.
    pub fn node(&mut self, r: Vector<D>) -> usize {
        self.r.push(r);
        self.r.len() - 1
    }

    /// Number of nodes so far.
    pub fn n_nodes(&self) -> usize {
        self.r.len()
    }

    /// Position of node `i` [m].
    pub fn position(&self, i: usize) -> Option<Vector<D>> {
        self.r.get(i).copied()
    }

    fn check_node(&self, what: &'static str, node: usize) -> Result<(), SetupError> {
        if node >= self.r.len() {
            return Err(SetupError::NodeOutOfRange {
                what,
                node,
                n_nodes: self.r.len(),
            });
        }
        Ok(())
    }

    /// Adds a string that runs straight from node to node along `path` (at least two nodes,
    /// each consecutive pair distinct), with `elements_per_span` elements between two
    /// consecutive path nodes. Its interior nodes are new; the path nodes are shared with
    /// whatever else uses them (junctions). Returns the group index.
    pub fn string(
        &mut self,
        spec: StringSpec<D, M>,
        path: &[usize],
        elements_per_span: usize,
    ) -> Result<usize, SetupError> {
        if path.len() < 2 || elements_per_span == 0 {
            return Err(SetupError::NoElements);
        }
        if !(spec.prestretch > 0.0 && spec.prestretch.is_finite()) {
            return Err(SetupError::NonPositive {
                what: "prestretch of string",
                index: Some(self.groups.len()),
                value: spec.prestretch,
            });
        }
        for &p in path {
            self.check_node("string path", p)?;
        }
        // Every span is checked before anything is added, so a refused string leaves the
        // builder as it was.
        for (k, pair) in path.windows(2).enumerate() {
            let (a, b) = (pair[0], pair[1]);
            let length = (self.r[b] - self.r[a]).norm();
            if a == b {
                return Err(SetupError::DegenerateElement {
                    element: self.elements.len() + k * elements_per_span,
                    node: a,
                });
            }
            if !(length > 0.0 && length.is_finite()) {
                return Err(SetupError::NonPositive {
                    what: "length of string span (path nodes at the same place)",
                    index: Some(k),
                    value: length,
                });
            }
        }
        let first = self.elements.len();
        let mut nodes = Vec::with_capacity((path.len() - 1) * elements_per_span + 1);
        nodes.push(path[0]);
        for pair in path.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let (ra, rb) = (self.r[a], self.r[b]);
            let l = (rb - ra).norm() / elements_per_span as f64 / spec.prestretch;
            let mut prev = a;
            for k in 1..=elements_per_span {
                let next = if k == elements_per_span {
                    b
                } else {
                    self.node(ra + (rb - ra) * (k as f64 / elements_per_span as f64))
                };
                self.elements.push([prev, next]);
                self.lengths.push(l);
                nodes.push(next);
                prev = next;
            }
        }
        self.groups.push(ElementGroup {
            name: spec.name,
            elements: first..self.elements.len(),
            law: Law::String(spec.material),
            rho_a: spec.rho_a,
            mass: spec.mass,
            body_force: spec.body_force,
            damping: Damping::NONE,
        });
        self.paths.push(nodes);
        Ok(self.groups.len() - 1)
    }

    /// Adds a string as [`Self::string`] does, paid out by a winch whose drum is `path[0]`
    /// (docs/method.md §23): before its first element, `reserve` elements of the first
    /// span's element length lie on the drum, their nodes at the drum point. Returns the
    /// group index; the group's elements start with the reserve.
    pub fn string_on_drum(
        &mut self,
        spec: StringSpec<D, M>,
        path: &[usize],
        elements_per_span: usize,
        reserve: usize,
    ) -> Result<usize, SetupError> {
        if path.len() < 2 || elements_per_span == 0 {
            return Err(SetupError::NoElements);
        }
        for &p in path {
            self.check_node("string path", p)?;
        }
        let drum = self.r[path[0]];
        let span = (self.r[path[1]] - drum).norm();
        let l = span / elements_per_span as f64 / spec.prestretch;
        let before = (self.r.len(), self.elements.len(), self.lengths.len());
        let mut on_drum = vec![path[0]];
        for _ in 0..reserve {
            let next = self.node(drum);
            self.elements.push([on_drum[on_drum.len() - 1], next]);
            self.lengths.push(l);
            on_drum.push(next);
        }
        let mut rest = path.to_vec();
        rest[0] = on_drum[on_drum.len() - 1];
        match self.string(spec, &rest, elements_per_span) {
            Ok(g) => {
                self.groups[g].elements.start = before.1;
                on_drum.pop();
                on_drum.extend_from_slice(&self.paths[g]);
                self.paths[g] = on_drum;
                Ok(g)
            }
            Err(e) => {
                // A refused string leaves the builder as it was.
                self.r.truncate(before.0);
                self.elements.truncate(before.1);
                self.lengths.truncate(before.2);
                Err(e)
            }
        }
    }

    /// Adds a linear spring (massless) between nodes `a` and `b`, stiffness `k` [N/m], rest
    /// length `rest` [m] (≥ 0). Returns the group index.
    pub fn spring(
        &mut self,
        name: impl Into<String>,
        a: usize,
        b: usize,
        k: f64,
        rest: f64,
    ) -> Result<usize, SetupError> {
        self.check_node("spring", a)?;
        self.check_node("spring", b)?;
        if a == b {
            return Err(SetupError::DegenerateElement {
                element: self.elements.len(),
                node: a,
            });
        }
        let e = self.elements.len();
        self.elements.push([a, b]);
        self.lengths.push(1.0);
        self.groups.push(ElementGroup {
            name: name.into(),
            elements: e..e + 1,
            law: Law::Spring(LinearSpring { k, rest }),
            rho_a: 0.0,
            mass: MassMatrix::Lumped,
            body_force: Vector::zeros(),
            damping: Damping::NONE,
        });
        self.paths.push(vec![a, b]);
        Ok(self.groups.len() - 1)
    }

    /// Adds a linear spring from node `a` to the fixed point `p` [m]: a new anchor node at `p`,
    /// fixed in every component, is its other end. Returns the group index.
    pub fn spring_to_point(
        &mut self,
        name: impl Into<String>,
        a: usize,
        p: Vector<D>,
        k: f64,
        rest: f64,
    ) -> Result<usize, SetupError> {
        self.check_node("spring", a)?;
        let anchor = self.node(p);
        self.anchors.push(anchor);
        self.spring(name, a, anchor, k, rest)
    }

    /// Sets the dissipation of group `g` (a string's Kelvin–Voigt viscosity and drag, a
    /// spring's dashpot); the values are checked when the system is set up.
    pub fn set_damping(&mut self, g: usize, damping: Damping) -> Result<(), SetupError> {
        let n = self.groups.len();
        let grp = self.groups.get_mut(g).ok_or(SetupError::NodeOutOfRange {
            what: "element group (set_damping)",
            node: g,
            n_nodes: n,
        })?;
        grp.damping = damping;
        Ok(())
    }

    /// The nodes of group `g` in path order (a spring: its two ends).
    pub fn group_nodes(&self, g: usize) -> Option<&[usize]> {
        self.paths.get(g).map(|p| p.as_slice())
    }

    /// Anchor nodes added by [`Self::spring_to_point`] (fixed by [`Self::build`]).
    pub fn anchors(&self) -> &[usize] {
        &self.anchors
    }

    /// The network with `boundary` (anchors are added to its fixed nodes) and `point_masses`,
    /// starting at rest in the built positions with consistent strains.
    pub fn build(
        self,
        mut boundary: Boundary<D>,
        point_masses: Vec<PointMass<D>>,
    ) -> Result<Network<D, M>, SetupError> {
        let mesh = Mesh::new(self.r.len(), self.elements, self.lengths)?;
        boundary
            .fixed
            .extend(self.anchors.iter().map(|&a| Fixed::node(a)));
        let initial = State::at_rest(&mesh, self.r);
        Ok(Network {
            mesh,
            groups: self.groups,
            boundary,
            point_masses,
            initial,
            water: None,
            hydro: Default::default(),
            bodies: Vec::new(),
            winches: Vec::new(),
        })
    }
}
