//! Validation of a single-string scenario: `[geometry]`, `[mesh]` and `[material]` give a
//! chain mesh (element `e` joins nodes `e` and `e + 1`), solved by the block-tridiagonal
//! solver. The problem is built exactly as before networks existed, so that single-string
//! results stay bit-identical.

use phstring::{Mesh, Problem, State, Vector};

use super::components::{Components, StringComponent, StringLayout};
use super::material::Longest;
use super::refs::Nodes;
use super::settings::BodyForce;
use super::spec::{Geometry, MeshSpec};
use super::{ScenarioError, ScenarioFile, Skeleton};
use crate::text::{num, nums};

/// Most elements of a scenario (of a single string, or of all strings and springs of a
/// network).
pub const MAX_ELEMENTS: usize = 50_000_000;

impl ScenarioFile {
    /// `[geometry]` and `[mesh]`: the chain mesh and its initial state (at rest), whose
    /// strains must lie in `material`'s domain.
    fn single_geometry<const D: usize>(
        &self,
        g: &Geometry,
        mesh_spec: Option<&MeshSpec>,
        material: &phstring::Material,
    ) -> Result<(Mesh, State<D>), ScenarioError> {
        let elements = mesh_spec.and_then(|m| m.elements.as_ref());
        let positions: Vec<Vector<D>> = match (&g.nodes, &g.start, &g.end) {
            (Some(nodes), None, None) => {
                if let Some(el) = elements {
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
                let el = elements.ok_or_else(|| {
                    self.invalid("mesh.elements", 0..0, "is required with geometry.start/end")
                })?;
                let n = *el.get_ref();
                if !(1..=MAX_ELEMENTS as i64).contains(&n) {
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
        let seg = self.element_lengths(&positions, geometry_span.clone())?;
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
            .find(|(_, c)| !phstring::StoredEnergy::admissible(material, **c))
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
        Ok((mesh, initial))
    }

    /// The initial lengths [m] of the elements between consecutive `positions`, each finite,
    /// nonzero and with a square that does not underflow; errors name `geometry` at `span`.
    fn element_lengths<const D: usize>(
        &self,
        positions: &[Vector<D>],
        span: std::ops::Range<usize>,
    ) -> Result<Vec<f64>, ScenarioError> {
        let seg: Vec<f64> = positions
            .windows(2)
            .map(|w| super::rounding::length(&(w[1] - w[0])))
            .collect();
        if let Some(i) = seg.iter().position(|&l| !l.is_finite()) {
            return Err(self.invalid(
                "geometry",
                span.clone(),
                format!(
                    "the length of element {i} (nodes {i} to {}) overflows: the coordinates are too large",
                    i + 1
                ),
            ));
        }
        if let Some(i) = seg.iter().position(|&l| l <= 0.0) {
            return Err(self.invalid(
                "geometry",
                span.clone(),
                format!(
                    "element {i} has zero initial length (nodes {i} and {} coincide)",
                    i + 1
                ),
            ));
        }
        if let Some(i) = seg.iter().position(|&l| l * l < f64::MIN_POSITIVE) {
            return Err(self.invalid(
                "geometry",
                span.clone(),
                format!(
                    "element {i} (nodes {i} to {}) is {} m long, too short for floating point: its squared length (in the strain C) underflows below {:.1e} m²; elements must be longer than {:.1e} m",
                    i + 1,
                    num(seg[i]),
                    f64::MIN_POSITIVE,
                    f64::MIN_POSITIVE.sqrt()
                ),
            ));
        }
        Ok(seg)
    }

    /// A single string: `[material]`, then `[geometry]` and `[mesh]`, with the body force
    /// `body`. Boundary conditions and point masses are added later.
    pub(super) fn single_string<'s, const D: usize>(
        &'s self,
        body: &BodyForce<D>,
    ) -> Result<Skeleton<'s, D>, ScenarioError> {
        let s = &self.scenario;
        let (Some(material_spec), Some(geometry)) = (&s.material, &s.geometry) else {
            return Err(self.invalid(
                if s.geometry.is_none() {
                    "geometry"
                } else {
                    "material"
                },
                0..0,
                "is required: a scenario describes one string ([geometry], [mesh], [material]) or a network ([[string]] tables)",
            ));
        };
        let cs = self.cross_section("material", material_spec.get_ref())?;
        let mesh_spec = s.mesh.as_ref().map(|m| m.get_ref());
        let (mesh, initial) =
            self.single_geometry::<D>(geometry.get_ref(), mesh_spec, &cs.material)?;
        let body_force = body.on_string(cs.rho_a);
        let l = mesh.lengths().iter().copied().fold(0.0, f64::max);
        let key = match &geometry.get_ref().length {
            Some(len) => (
                "geometry.length".to_string(),
                len.span(),
                format!("= {} ", num(*len.get_ref())),
            ),
            None => ("geometry".to_string(), geometry.span(), String::new()),
        };
        let longest = Longest {
            owner: "the string".into(),
            l,
            from: "the geometry over mesh.elements".into(),
            key,
        };
        self.element_scales(
            "material",
            Some(material_spec.get_ref()),
            &cs,
            body,
            longest,
        )?;
        let n_el = mesh.n_elements();
        let n_nodes = mesh.n_nodes();
        let components = Components {
            strings: vec![StringComponent::new(
                "string".into(),
                StringLayout {
                    elements: [0, n_el],
                    nodes: n_nodes,
                    path_nodes: vec![0, n_el],
                    elements_per_span: n_el,
                    interior_nodes: [1, n_el],
                },
                "material".into(),
                &cs,
                body_force.as_slice(),
            )],
            ..Components::default()
        };
        let problem = Problem {
            point_masses: Vec::new(),
            mesh,
            material: cs.material,
            rho_a: cs.rho_a,
            body_force,
            mass: cs.mass,
            boundary: phstring::Boundary::default(),
            initial,
        };
        Ok(Skeleton {
            frame: super::Frame::Single(problem),
            nodes: Nodes::chain(n_nodes),
            components,
            massless: Vec::new(),
            single_damping: cs.damping,
            hydro: cs.hydro.map(|h| (0, h)).into_iter().collect(),
            bodies: Vec::new(),
            winches: Vec::new(),
        })
    }
}
