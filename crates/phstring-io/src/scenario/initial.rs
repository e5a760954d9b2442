//! `[initial]`: the initial state when it is not the base shape at rest. The base shape is
//! the one the geometry gives (a straight string, a polyline, straight spans between a
//! network's nodes) or, with `equilibrium = true`, the static equilibrium under the loads at
//! `t = 0`, which the run solves for before the state is built. On the base shape go a
//! displacement field and a velocity field (expressions of the reference arc length `s`
//! along each string, its reference length `L` and the base position `x`, `y`, `z`), or
//! per-node lists of positions and velocities; the strains `C` follow from the positions.
//!
//! [`InitialConditions::apply`] builds the state from any base shape, with the same checks
//! and messages at validation (straight base) and in a run (equilibrium base).

use std::collections::HashMap;
use std::path::PathBuf;

use nanoexpr::{Instruction, Math};
use phstring::{
    Boundary, ElementGroup, Law, Material, Mesh, Network, PhSystem, State, StoredEnergy, Vector,
};
use toml::Spanned;

use super::components::AXES;
use super::expr::describe;
use super::{Origin, ScenarioError, ScenarioFile};
use crate::text::{clip, num, nums};

/// A value at a fixed or moved component counts as zero when it is at most this fraction of
/// the largest value of its field (so that `sin(pi*s/L)` at `s = L`, about 1e-16, passes).
const NEGLIGIBLE: f64 = 1e-9;

/// Longest instruction buffer for a compiled expression; longer expressions are evaluated
/// from their text at every node (same results, slower).
const MAX_CODE: usize = 1024;

/// Marks a node on no string in [`ArcLengths::owner`].
const NO_STRING: u32 = u32::MAX;

/// One expression per component (`initial.displacement` or `initial.velocity`), with where
/// each came from.
#[derive(Debug, Clone)]
struct Field {
    /// `initial.displacement` or `initial.velocity`.
    key: &'static str,
    /// Unit of the values, for messages.
    unit: &'static str,
    /// The expressions, one per component.
    texts: Vec<String>,
    /// Where each expression came from.
    origins: Vec<Origin>,
    /// Where the list came from.
    origin: Origin,
}

/// A per-node list (`initial.positions` or `initial.velocities`).
#[derive(Debug, Clone)]
struct List<const D: usize> {
    /// `initial.positions` or `initial.velocities`.
    key: &'static str,
    /// One value per mesh node.
    values: Vec<Vector<D>>,
    /// Where the entries of the nodes with fixed or moved components came from (the only
    /// entries [`InitialConditions::apply`] can refuse; computing every entry's line would
    /// take a pass over the text per entry).
    origins: HashMap<usize, Origin>,
    /// Where the list came from.
    origin: Origin,
}

impl<const D: usize> List<D> {
    /// Where entry `i` came from.
    fn origin_of(&self, i: usize) -> Origin {
        self.origins
            .get(&i)
            .cloned()
            .unwrap_or_else(|| self.origin.clone())
    }
}

/// The validated `[initial]` table: how the state at `t = 0` is built from a base shape.
/// Without an `[initial]` table it changes nothing ([`Self::changes_base`] is `false`).
#[derive(Debug, Clone)]
pub struct InitialConditions<const D: usize> {
    /// `initial.equilibrium`: the run starts from the static equilibrium under the loads at
    /// `t = 0`. The runner solves for it from the validated problem (whose initial state is
    /// then the geometry's shape at rest), and builds the state with [`Self::apply`] on the
    /// equilibrium positions.
    pub equilibrium: bool,
    displacement: Option<Field>,
    velocity: Option<Field>,
    positions: Option<List<D>>,
    velocities: Option<List<D>>,
    /// The scenario file, for errors that concern no single key.
    path: PathBuf,
    /// Whether the scenario is a network (messages then name the string of a node).
    network: bool,
}

/// What holds a node's component.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hold {
    Free,
    Fixed,
    Moved,
}

/// The reference arc length of every node that lies on a string.
struct ArcLengths {
    /// `s` [m] of each node along the string that owns it (NaN on no string).
    s: Vec<f64>,
    /// The group (string) that owns each node: the first in element order that passes
    /// through it; [`NO_STRING`] for nodes on no string.
    owner: Vec<u32>,
    /// The reference length `L` [m] of each group (NaN for springs).
    total: Vec<f64>,
}

/// The parts of a problem that `[initial]` is applied on: its mesh, element groups and
/// boundary conditions, of a validated network or of the system built from it.
#[derive(Clone, Copy)]
pub struct Net<'a, const D: usize> {
    mesh: &'a Mesh,
    groups: &'a [ElementGroup<D, Material>],
    boundary: &'a Boundary<D>,
}

impl<'a, const D: usize> From<&'a Network<D, Material>> for Net<'a, D> {
    fn from(n: &'a Network<D, Material>) -> Self {
        Self {
            mesh: &n.mesh,
            groups: &n.groups,
            boundary: &n.boundary,
        }
    }
}

impl<'a, const D: usize> From<&'a PhSystem<D, Material>> for Net<'a, D> {
    fn from(s: &'a PhSystem<D, Material>) -> Self {
        Self {
            mesh: s.mesh(),
            groups: s.groups(),
            boundary: s.boundary(),
        }
    }
}

/// `s` along every string (group of [`Law::String`]): the compensated sum of the reference
/// lengths of its elements up to the node, from its first path node. A node shared by several
/// strings (or met twice along one) takes its first value, in element order (= file order).
fn arc_lengths<const D: usize>(net: Net<'_, D>) -> ArcLengths {
    let n = net.mesh.n_nodes();
    let mut s = vec![f64::NAN; n];
    let mut owner = vec![NO_STRING; n];
    let mut total = vec![f64::NAN; net.groups.len()];
    let (elements, lengths) = (net.mesh.elements(), net.mesh.lengths());
    for (g, grp) in net.groups.iter().enumerate() {
        if !matches!(grp.law, Law::String(_)) || grp.elements.is_empty() {
            continue;
        }
        let mut claim = |node: usize, value: f64| {
            if owner[node] == NO_STRING {
                owner[node] = g as u32;
                s[node] = value;
            }
        };
        claim(elements[grp.elements.start][0], 0.0);
        // Neumaier's compensated sum: `s` to about one rounding, however many elements.
        let (mut sum, mut carry) = (0.0f64, 0.0f64);
        for e in grp.elements.clone() {
            let l = lengths[e];
            let t = sum + l;
            carry += if sum.abs() >= l.abs() {
                (sum - t) + l
            } else {
                (l - t) + sum
            };
            sum = t;
            claim(elements[e][1], sum + carry);
        }
        total[g] = sum + carry;
    }
    ArcLengths { s, owner, total }
}

/// What holds each component of the nodes that have fixed or moved components.
fn holds<const D: usize>(net: Net<'_, D>) -> HashMap<usize, [Hold; D]> {
    let mut held: HashMap<usize, [Hold; D]> = HashMap::new();
    for f in &net.boundary.fixed {
        let h = held.entry(f.node).or_insert([Hold::Free; D]);
        for (h, &c) in h.iter_mut().zip(&f.components) {
            if c {
                *h = Hold::Fixed;
            }
        }
    }
    for m in &net.boundary.motions {
        if m.component < D {
            held.entry(m.node).or_insert([Hold::Free; D])[m.component] = Hold::Moved;
        }
    }
    held
}

/// Largest absolute component of `values`.
fn largest<const D: usize>(values: &[Vector<D>]) -> f64 {
    values
        .iter()
        .flat_map(|v| v.iter())
        .fold(0.0, |m, x| m.max(x.abs()))
}

impl<const D: usize> InitialConditions<D> {
    /// No `[initial]` table: the base shape at rest.
    fn none(path: PathBuf, network: bool) -> Self {
        Self {
            equilibrium: false,
            displacement: None,
            velocity: None,
            positions: None,
            velocities: None,
            path,
            network,
        }
    }

    /// The scenario file, for errors that concern no single key.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// Whether [`Self::apply`] changes the base state at all: whether a displacement,
    /// velocity, positions or velocities are given. Without them the initial state is the
    /// base shape at rest, exactly as [`State::at_rest`] builds it.
    pub fn changes_base(&self) -> bool {
        self.displacement.is_some()
            || self.velocity.is_some()
            || self.positions.is_some()
            || self.velocities.is_some()
    }

    /// The initial state of `net` from the base positions `base` [m] (one per mesh node: the
    /// geometry's shape, or the static equilibrium with `equilibrium = true`):
    ///
    /// * positions: `initial.positions` if given (then `base` only supplies the fixed and
    ///   moved components, which the list must repeat), else `base`; plus the displacement
    ///   field at every node on a string, evaluated with `x`, `y`, `z` = the node's `base`
    ///   position;
    /// * velocities: `initial.velocities`, or the velocity field at every node on a string
    ///   (zero elsewhere), or zero;
    /// * strains consistent with the positions, [`State::consistent`].
    ///
    /// Fixed and moved components stay exactly at `base`: a displacement there must vanish
    /// (at most 1e-9 of the field's largest value), a listed position must equal `base` (to
    /// 1e-9 relative); a velocity at a fixed component must vanish likewise (it is set to 0).
    /// Every expression is evaluated at every node on a string; an evaluation error, a
    /// non-finite value or position, and a strain outside an element's law are errors that
    /// name the key, the node (with `s`) and the value.
    pub fn apply<'a>(
        &self,
        net: impl Into<Net<'a, D>>,
        base: &[Vector<D>],
    ) -> Result<State<D>, ScenarioError> {
        let net = net.into();
        let n = net.mesh.n_nodes();
        if base.len() != n {
            return Err(ScenarioError::Invalid {
                key: "initial".into(),
                origin: Origin::Scenario(self.path.clone()),
                reason: format!(
                    "cannot be applied to a base shape of {} nodes: the mesh has {n}",
                    base.len()
                ),
            });
        }
        let held = holds(net);
        let arc =
            (self.displacement.is_some() || self.velocity.is_some()).then(|| arc_lengths(net));
        let mut r = match &self.positions {
            Some(list) => self.listed_positions(list, &held, base)?,
            None => base.to_vec(),
        };
        if let (Some(f), Some(arc)) = (&self.displacement, &arc) {
            let mut d = self.field(f, net, arc, base)?;
            self.constrained(f, &mut d, &held, net, arc, |h| h != Hold::Free)?;
            for (i, (ri, di)) in r.iter_mut().zip(&d).enumerate() {
                let moved = *ri + di;
                if let Some(c) = (0..D).find(|&c| !moved[c].is_finite()) {
                    return Err(ScenarioError::Invalid {
                        key: format!("{}.{c}", f.key),
                        origin: f.origins[c].clone(),
                        reason: format!(
                            "\"{}\" moves {} to a non-finite position in component {} (base {} m, displacement {} m)",
                            clip(&f.texts[c]),
                            self.label(net, arc, i, false),
                            AXES[c],
                            num(ri[c]),
                            num(di[c])
                        ),
                    });
                }
                *ri = moved;
            }
        }
        let v = match (&self.velocities, &self.velocity, &arc) {
            (Some(list), _, _) => self.listed_velocities(list, &held)?,
            (None, Some(f), Some(arc)) => {
                let mut v = self.field(f, net, arc, base)?;
                self.constrained(f, &mut v, &held, net, arc, |h| h == Hold::Fixed)?;
                v
            }
            _ => vec![Vector::<D>::zeros(); n],
        };
        let state = State::consistent(net.mesh, r, v);
        self.check_strains(net, &state)?;
        Ok(state)
    }

    /// `state` with every node fixed to a rigid body (`points`: its node, the body point's
    /// position [m] and velocity [m/s], and its name `"BODY.POINT"`) at its point with the
    /// body's velocity there: the displacement and velocity fields do not apply to body
    /// points, and `initial.positions` and `initial.velocities` must repeat the body's values
    /// there (to 1e-9 relative). The strains follow from the positions.
    pub(super) fn on_bodies(
        &self,
        mesh: &Mesh,
        state: State<D>,
        points: &[(usize, Vector<D>, Vector<D>, String)],
    ) -> Result<State<D>, ScenarioError> {
        if points.is_empty() {
            return Ok(state);
        }
        let State { mut r, mut v, .. } = state;
        for (node, rb, vb, name) in points {
            let lists = [(&self.positions, rb, "m"), (&self.velocities, vb, "m/s")];
            for (list, want, unit) in lists {
                let Some(list) = list else { continue };
                let got = list.values[*node];
                let tol = NEGLIGIBLE * want.amax().max(1.0);
                if (got - want).amax() > tol {
                    return Err(ScenarioError::Invalid {
                        key: format!("{}.{node}", list.key),
                        origin: list.origin_of(*node),
                        reason: format!(
                            "= {} {unit} at node {node}, body point \"{}\", where the body gives {} {unit}: a body point starts with its body (repeat the body's value there)",
                            nums(got.as_slice()),
                            clip(name),
                            nums(want.as_slice())
                        ),
                    });
                }
            }
            r[*node] = *rb;
            v[*node] = *vb;
        }
        Ok(State::consistent(mesh, r, v))
    }

    /// `initial.positions`, which must repeat `base` at fixed and moved components (which
    /// then take `base` exactly).
    fn listed_positions(
        &self,
        list: &List<D>,
        held: &HashMap<usize, [Hold; D]>,
        base: &[Vector<D>],
    ) -> Result<Vec<Vector<D>>, ScenarioError> {
        let mut r = list.values.clone();
        for (&i, h) in held {
            for c in (0..D).filter(|&c| h[c] != Hold::Free) {
                let (given, at) = (r[i][c], base[i][c]);
                if (given - at).abs() > NEGLIGIBLE * at.abs().max(1.0) {
                    return Err(ScenarioError::Invalid {
                        key: format!("{}.{i}", list.key),
                        origin: list.origin_of(i),
                        reason: format!(
                            "= {} puts node {i} at {} m in component {}, but the node is {} there and starts at {} m (a support cannot be displaced)",
                            nums(list.values[i].as_slice()),
                            num(given),
                            AXES[c],
                            how(h[c]),
                            num(at)
                        ),
                    });
                }
                r[i][c] = at;
            }
        }
        Ok(r)
    }

    /// `initial.velocities`, which must vanish at fixed components (which then are 0).
    fn listed_velocities(
        &self,
        list: &List<D>,
        held: &HashMap<usize, [Hold; D]>,
    ) -> Result<Vec<Vector<D>>, ScenarioError> {
        let mut v = list.values.clone();
        let scale = largest(&v);
        for (&i, h) in held {
            for c in (0..D).filter(|&c| h[c] == Hold::Fixed) {
                if v[i][c].abs() > NEGLIGIBLE * scale {
                    return Err(ScenarioError::Invalid {
                        key: format!("{}.{i}", list.key),
                        origin: list.origin_of(i),
                        reason: format!(
                            "= {} gives node {i} the velocity {} m/s in component {}, but the node is fixed there: its initial velocity must be 0",
                            nums(list.values[i].as_slice()),
                            num(v[i][c]),
                            AXES[c]
                        ),
                    });
                }
                v[i][c] = 0.0;
            }
        }
        Ok(v)
    }

    /// Refuses a value of field `f` at a component for which `refused` holds (fixed, or
    /// fixed or moved) unless it is negligible; such values are set to 0.
    fn constrained(
        &self,
        f: &Field,
        values: &mut [Vector<D>],
        held: &HashMap<usize, [Hold; D]>,
        net: Net<'_, D>,
        arc: &ArcLengths,
        refused: impl Fn(Hold) -> bool,
    ) -> Result<(), ScenarioError> {
        let scale = largest(values);
        // In node order, so that the error names the first node.
        let mut nodes: Vec<usize> = held.keys().copied().collect();
        nodes.sort_unstable();
        for i in nodes {
            let h = held[&i];
            for c in (0..D).filter(|&c| refused(h[c])) {
                let x = values[i][c];
                if x.abs() > NEGLIGIBLE * scale {
                    let why = match (f.unit, h[c]) {
                        ("m", Hold::Moved) => format!(
                            "its component {} follows a prescribed `position`, which starts at the node's base position, so it cannot be displaced (the expression must vanish there)",
                            AXES[c]
                        ),
                        ("m", _) => format!(
                            "the node is fixed in component {}, and a support cannot be displaced (the expression must vanish there)",
                            AXES[c]
                        ),
                        _ => format!(
                            "the node is fixed in component {}, so its initial velocity must be 0 there",
                            AXES[c]
                        ),
                    };
                    return Err(ScenarioError::Invalid {
                        key: format!("{}.{c}", f.key),
                        origin: f.origins[c].clone(),
                        reason: format!(
                            "\"{}\" is {} {} at {}: {why}",
                            clip(&f.texts[c]),
                            num(x),
                            f.unit,
                            self.label(net, arc, i, false)
                        ),
                    });
                }
                values[i][c] = 0.0;
            }
        }
        Ok(())
    }

    /// The values of `f` at every node on a string (zero elsewhere), each component finite.
    fn field(
        &self,
        f: &Field,
        net: Net<'_, D>,
        arc: &ArcLengths,
        base: &[Vector<D>],
    ) -> Result<Vec<Vector<D>>, ScenarioError> {
        let n = base.len();
        let mut out = vec![Vector::<D>::zeros(); n];
        const NAMES: [&str; 5] = ["s", "L", "x", "y", "z"];
        for (c, text) in f.texts.iter().enumerate() {
            let mut code = vec![Instruction::<f64>::default(); (2 * text.len() + 8).min(MAX_CODE)];
            // A text the compiler refuses (too long for the buffer, or invalid) is evaluated
            // from its text, which gives the same values and errors.
            let program = nanoexpr::compile::<f64, 32>(text, &mut code).ok();
            let mut vars = NAMES.map(|name| (name, 0.0));
            for i in 0..n {
                let g = arc.owner[i];
                if g == NO_STRING {
                    continue;
                }
                vars[0].1 = arc.s[i];
                vars[1].1 = arc.total[g as usize];
                for k in 0..D {
                    vars[2 + k].1 = base[i][k];
                }
                let ctx = (&vars[..2 + D], Math);
                let value = match &program {
                    Some(p) => p.evaluate(&ctx),
                    None => nanoexpr::evaluate_with(text, &ctx),
                };
                let bad = match value {
                    Ok(x) if x.is_finite() => {
                        out[i][c] = x;
                        continue;
                    }
                    Ok(x) => format!("the value {} is not finite", num(x)),
                    Err(e) => describe(text, &e),
                };
                return Err(ScenarioError::Invalid {
                    key: format!("{}.{c}", f.key),
                    origin: f.origins[c].clone(),
                    reason: format!(
                        "\"{}\" at {}: {bad}",
                        clip(text),
                        self.label(net, arc, i, true)
                    ),
                });
            }
        }
        Ok(out)
    }

    /// Every element's strain finite and in its law's domain.
    fn check_strains(&self, net: Net<'_, D>, state: &State<D>) -> Result<(), ScenarioError> {
        for grp in net.groups {
            for e in grp.elements.clone() {
                let c = state.c[e];
                if c.is_finite() && grp.law.admissible(c) {
                    continue;
                }
                let (key, origin) = if let Some(l) = &self.positions {
                    (l.key, l.origin.clone())
                } else if let Some(f) = &self.displacement {
                    (f.key, f.origin.clone())
                } else {
                    ("initial", Origin::Scenario(self.path.clone()))
                };
                let [a, b] = net.mesh.elements()[e];
                let (what, law) = match grp.law {
                    Law::String(m) => ("string", m.name()),
                    Law::Spring(_) => ("spring", "a spring"),
                };
                let of = if self.network {
                    format!(" ({what} \"{}\")", clip(&grp.name))
                } else {
                    String::new()
                };
                return Err(ScenarioError::Invalid {
                    key: key.into(),
                    origin,
                    reason: format!(
                        "gives element {e}{of} (nodes {a} and {b}) the initial strain C = {}, outside the domain of {law}",
                        num(c)
                    ),
                });
            }
        }
        Ok(())
    }

    /// Node `i` for messages: `node 12 (s = 24 m)`, in a network with its string and index
    /// along it, `node 12 (s = 3 m along string "cable0", its node 6)`; with `with_l`, the
    /// string's reference length `L` too.
    fn label(&self, net: Net<'_, D>, arc: &ArcLengths, i: usize, with_l: bool) -> String {
        let g = arc.owner[i];
        if g == NO_STRING {
            return format!("node {i}");
        }
        let grp = &net.groups[g as usize];
        let l = if with_l {
            format!(", L = {} m", num(arc.total[g as usize]))
        } else {
            String::new()
        };
        if !self.network {
            return format!("node {i} (s = {} m{l})", num(arc.s[i]));
        }
        let elements = net.mesh.elements();
        let along = if elements[grp.elements.start][0] == i {
            0
        } else {
            grp.elements
                .clone()
                .position(|e| elements[e][1] == i)
                .map_or(0, |k| k + 1)
        };
        format!(
            "node {i} (s = {} m{l} along string \"{}\", its node {along})",
            num(arc.s[i]),
            clip(&grp.name)
        )
    }
}

/// `fixed` or `moved` for messages.
fn how(h: Hold) -> &'static str {
    match h {
        Hold::Moved => "moved (a prescribed `position`)",
        _ => "fixed",
    }
}

impl ScenarioFile {
    /// `[initial]`, checked against the built network `net` (node count) but not yet applied:
    /// each field has `D` expressions, each list one finite entry per mesh node, and no two
    /// keys that set the same thing.
    pub(super) fn initial_conditions<const D: usize>(
        &self,
        net: Net<'_, D>,
        network: bool,
    ) -> Result<InitialConditions<D>, ScenarioError> {
        let mut out = InitialConditions::none(self.path.clone(), network);
        let Some(spec) = &self.scenario.initial else {
            return Ok(out);
        };
        out.equilibrium = *spec.equilibrium.get_ref();
        if let (Some(p), true) = (&spec.positions, out.equilibrium) {
            return Err(self.invalid(
                "initial.positions",
                p.span(),
                "gives the initial shape, so it cannot be combined with `initial.equilibrium = true`, which solves for it: remove one of them",
            ));
        }
        if let (Some(_), Some(d)) = (&spec.positions, &spec.displacement) {
            return Err(self.invalid(
                "initial.displacement",
                d.span(),
                "cannot be combined with `initial.positions`, which gives the shape itself (add the displacement to the positions, or give the displacement alone)",
            ));
        }
        if let (Some(_), Some(v)) = (&spec.velocities, &spec.velocity) {
            return Err(self.invalid(
                "initial.velocity",
                v.span(),
                "cannot be combined with `initial.velocities`: give the velocity as expressions or as a list, not both",
            ));
        }
        out.displacement = spec
            .displacement
            .as_ref()
            .map(|d| self.initial_field::<D>("initial.displacement", "m", d))
            .transpose()?;
        out.velocity = spec
            .velocity
            .as_ref()
            .map(|v| self.initial_field::<D>("initial.velocity", "m/s", v))
            .transpose()?;
        out.positions = spec
            .positions
            .as_ref()
            .map(|p| self.initial_list::<D>("initial.positions", p, net, network))
            .transpose()?;
        out.velocities = spec
            .velocities
            .as_ref()
            .map(|v| self.initial_list::<D>("initial.velocities", v, net, network))
            .transpose()?;
        Ok(out)
    }

    /// `key` (`initial.displacement` or `initial.velocity`): `D` expressions.
    fn initial_field<const D: usize>(
        &self,
        key: &'static str,
        unit: &'static str,
        list: &Spanned<Vec<Spanned<String>>>,
    ) -> Result<Field, ScenarioError> {
        let texts = list.get_ref();
        if texts.len() != D {
            return Err(self.invalid(
                key,
                list.span(),
                format!(
                    "must have {D} expressions (dimension = {D}), one per component, got {}",
                    texts.len()
                ),
            ));
        }
        Ok(Field {
            key,
            unit,
            texts: texts.iter().map(|t| t.get_ref().clone()).collect(),
            origins: texts
                .iter()
                .enumerate()
                .map(|(c, t)| self.origin(&format!("{key}.{c}"), t.span()))
                .collect(),
            origin: self.origin(key, list.span()),
        })
    }

    /// `key` (`initial.positions` or `initial.velocities`): one entry of `D` finite
    /// components per mesh node of `net`.
    fn initial_list<const D: usize>(
        &self,
        key: &'static str,
        list: &Spanned<Vec<Spanned<Vec<f64>>>>,
        net: Net<'_, D>,
        network: bool,
    ) -> Result<List<D>, ScenarioError> {
        let n = net.mesh.n_nodes();
        let entries = list.get_ref();
        if entries.len() != n {
            let order = if network {
                "the [[node]]s in file order, then the interior nodes of each string, then the fixed points of springs; `phstring check` lists them"
            } else {
                "from the first node of the string to the last"
            };
            return Err(self.invalid(
                key,
                list.span(),
                format!(
                    "has {} entries, but the mesh has {n} nodes: give one entry of {D} components per node, nodes 0..={} in mesh order ({order})",
                    entries.len(),
                    n.saturating_sub(1)
                ),
            ));
        }
        let held = holds(net);
        let mut values = Vec::with_capacity(n);
        let mut origins = HashMap::new();
        for (i, e) in entries.iter().enumerate() {
            let x = e.get_ref();
            if x.len() != D || x.iter().any(|c| !c.is_finite()) {
                return Err(self.invalid(
                    &format!("{key}.{i}"),
                    e.span(),
                    format!(
                        "(node {i}) must have {D} finite components (dimension = {D}), got {}",
                        nums(x)
                    ),
                ));
            }
            values.push(Vector::<D>::from_column_slice(x));
            if held.contains_key(&i) {
                origins.insert(i, self.origin(&format!("{key}.{i}"), e.span()));
            }
        }
        Ok(List {
            key,
            values,
            origins,
            origin: self.origin(key, list.span()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A compiled expression gives the values and errors of the evaluator, bit for bit.
    #[test]
    fn compiled_expressions_evaluate_like_the_text() {
        let texts = [
            "0.01*sin(pi*s/L)",
            "s < L/2 ? 2*s/L : 2*(1 - s/L)",
            "-2*y + x^2/3 - hypot(x, y)",
            "1/(s - 3)",
            "sqrt(s - 5) + max(x, y, 1e-3)",
            "exp(s*100)",
            "q + 1",
        ];
        for text in texts {
            let mut code = vec![Instruction::<f64>::default(); 2 * text.len() + 8];
            let program = nanoexpr::compile::<f64, 32>(text, &mut code).unwrap();
            for s in [0.0, 1.5, 3.0, 5.0, 7.25, 10.0] {
                let vars = [("s", s), ("L", 10.0), ("x", s - 4.0), ("y", 0.3 * s)];
                let ctx = (&vars[..], Math);
                let a = program.evaluate(&ctx).map(f64::to_bits);
                let b = nanoexpr::evaluate_with::<f64, _>(text, &ctx).map(f64::to_bits);
                assert_eq!(a, b, "{text} at s = {s}");
            }
        }
        // Too long for the code buffer: refused by the compiler, so evaluated from the text.
        let long = vec!["s"; 2 * MAX_CODE].join("+");
        let mut code = vec![Instruction::<f64>::default(); MAX_CODE];
        assert!(nanoexpr::compile::<f64, 32>(&long, &mut code).is_err());
    }

    /// `s` along a two-span path with a repeated node: first value wins.
    #[test]
    fn arc_length_is_claimed_once() {
        use phstring::{MassMatrix, NetworkBuilder, StringSpec};
        let mut b = NetworkBuilder::<2, Material>::new();
        let a = b.node(Vector::<2>::new(0.0, 0.0));
        let c = b.node(Vector::<2>::new(3.0, 0.0));
        let spec = StringSpec {
            name: "loop".into(),
            material: Material::hyperelastic(10.0),
            rho_a: 1.0,
            mass: MassMatrix::Consistent,
            body_force: Vector::<2>::zeros(),
            prestretch: 1.0,
        };
        b.string(spec, &[a, c, a], 3).unwrap();
        let net = b.build(phstring::Boundary::default(), Vec::new()).unwrap();
        let arc = arc_lengths((&net).into());
        assert_eq!(arc.s[a], 0.0);
        assert_eq!(arc.s[c], 3.0);
        assert_eq!(arc.total[0], 6.0);
        // The interior nodes of the way back: 4 and 5 m.
        assert_eq!(&arc.s[4..6], &[4.0, 5.0]);
        assert!(arc.owner.iter().all(|&g| g == 0));
    }
}
