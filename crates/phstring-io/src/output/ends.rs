//! The forces of the strings on their end nodes, for `end_tensions.csv` (MoorDyn's
//! `FairTen` and `AnchTen`).
//!
//! MoorDyn reports as a line's end tension the magnitude of the net force `Fnet` of the line
//! on its end node (everything but the node's inertia): the end segment's tension, the
//! node's share of the line's wet weight (half a segment), its drag, seabed contact and
//! fluid-acceleration forces. Here the force of string `s` on its end node `n`, whose end
//! element is `e = (n, m)` of reference length `l_e`, is
//!
//! `F = N_e (r_m − r_n)/|r_m − r_n| + (l_e/2) b_s + (l_e/2) ρ_w g (π d_s²/4) φ(z_n) ê_up
//!      + σ f_c(n) n̂`
//!
//! with `N_e = S_e √C_e` the element's axial force (elastic), `b_s` the string's body force
//! per unit reference length (its weight in air), `φ` the node's submerged fraction (band
//! `d_s`), and `f_c(n)` the seabed's contact force on the node along the seabed's normal
//! `n̂`, of which the string takes the share `σ` of its end element's contact length
//! (`d l_e / 2`) in the node's. Drag, seabed damping and friction and material damping
//! are left out: they vanish at rest, where `|F|` is the reaction a support must hold.

use phstring::StoredEnergy as _;
use phstring::{Law, Material, PhSystem, Simulation, Vector};

/// The water that acts on the ends of the strings (see the module's formula).
#[derive(Debug, Clone, PartialEq)]
pub struct EndWater {
    /// Water density `ρ_w` [kg/m³].
    pub density: f64,
    /// Gravity `g` [m/s²] of the buoyancy, along the vertical axis (the last one).
    pub gravity: f64,
    /// The seabed's unit normal pointing up into the water, `d` components; `None`
    /// without a seabed.
    pub seabed_normal: Option<Vec<f64>>,
}

/// One end of a string: its node, the other node of its end element, the element.
#[derive(Debug, Clone, Copy, PartialEq)]
struct End {
    node: usize,
    other: usize,
    element: usize,
    /// The string's share `σ` of the node's seabed contact.
    share: f64,
}

/// How the forces of every string on its two end nodes are computed: end A (the first
/// node of its path, "anchor") and end B (the last, "fairlead").
#[derive(Debug, Clone, PartialEq)]
pub struct EndForces {
    /// Per string: its name, its group, its ends `[A, B]`.
    strings: Vec<(String, usize, [End; 2])>,
    /// Per group: body force per unit reference length [N/m], `d` components.
    body: Vec<Vec<f64>>,
    /// Per group: hydrodynamic diameter [m] (0: feels no water).
    diameter: Vec<f64>,
    water: Option<EndWater>,
}

impl EndForces {
    /// The end forces of the strings of `sys` (springs have none), each string's elements
    /// numbered from its first path node to its last; `diameters[g]` is the hydrodynamic
    /// diameter [m] of group `g` (`None` or absent: it feels no water), `water` the water
    /// (`None`: dry). `None` if `sys` has no string.
    pub fn new<const D: usize>(
        sys: &PhSystem<D, Material>,
        diameters: &[Option<f64>],
        water: Option<EndWater>,
    ) -> Option<Self> {
        let elements = sys.mesh().elements();
        let lengths = sys.mesh().lengths();
        let diameter: Vec<f64> = (0..sys.groups().len())
            .map(|g| diameters.get(g).copied().flatten().unwrap_or(0.0))
            .collect();
        // Each node's contact length Σ d l/2 over the string elements meeting there.
        let mut contact = vec![0.0; sys.mesh().n_nodes()];
        for (g, group) in sys.groups().iter().enumerate() {
            if matches!(group.law, Law::String(_)) {
                for e in group.elements.clone() {
                    for n in elements[e] {
                        contact[n] += 0.5 * diameter[g] * lengths[e];
                    }
                }
            }
        }
        let end = |node: usize, other: usize, element: usize, g: usize| End {
            node,
            other,
            element,
            share: if contact[node] > 0.0 {
                0.5 * diameter[g] * lengths[element] / contact[node]
            } else {
                0.0
            },
        };
        let strings: Vec<(String, usize, [End; 2])> = sys
            .groups()
            .iter()
            .enumerate()
            .filter(|(_, g)| matches!(g.law, Law::String(_)) && !g.elements.is_empty())
            .map(|(g, group)| {
                let (first, last) = (group.elements.start, group.elements.end - 1);
                let [a, a1] = elements[first];
                let [b1, b] = elements[last];
                (
                    group.name.clone(),
                    g,
                    [end(a, a1, first, g), end(b, b1, last, g)],
                )
            })
            .collect();
        if strings.is_empty() {
            return None;
        }
        Some(Self {
            strings,
            body: sys
                .groups()
                .iter()
                .map(|g| g.body_force.as_slice().to_vec())
                .collect(),
            diameter,
            water,
        })
    }

    /// The header of `end_tensions.csv`: `t`, then `FairTen<i>,AnchTen<i>` for every string
    /// `i = 1, 2, …` in group order.
    pub fn header(&self) -> String {
        let mut h = String::from("t");
        for i in 1..=self.strings.len() {
            h.push_str(&format!(",FairTen{i},AnchTen{i}"));
        }
        h
    }

    /// The end nodes `[A, B]` of every string, in column order.
    pub fn end_nodes(&self) -> Vec<[usize; 2]> {
        self.strings
            .iter()
            .map(|(_, _, [a, b])| [a.node, b.node])
            .collect()
    }

    /// The element group of string `s` (in column order).
    pub(super) fn group(&self, s: usize) -> usize {
        self.strings[s].1
    }

    /// The names of the strings, in column order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.strings.iter().map(|s| s.0.as_str())
    }

    /// The forces [N] of every string on its end nodes `[A, B]` in the state of `sim`.
    pub fn forces<const D: usize>(&self, sim: &Simulation<D, Material>) -> Vec<[Vector<D>; 2]> {
        let sys = sim.system();
        let st = sim.state();
        let contact_force = |node: usize| sys.seabed_contact(node, &st.r).map_or(0.0, |c| c.force);
        let lengths = sys.mesh().lengths();
        self.strings
            .iter()
            .map(|(_, g, ends)| {
                ends.map(|end| {
                    let rn = st.r[end.node];
                    let l = lengths[end.element];
                    // The end element's stress alone, not every element's.
                    let mut f = element_pull(sim, *g, end.element, end.node, end.other);
                    for k in 0..D {
                        f[k] += 0.5 * l * self.body[*g][k];
                    }
                    if let Some(w) = &self.water {
                        let d = self.diameter[*g];
                        let phi = phstring::water::submerged_fraction(rn[D - 1], d);
                        let area = std::f64::consts::PI * d * d / 4.0;
                        f[D - 1] += 0.5 * l * w.density * w.gravity * area * phi;
                        if let Some(n) = &w.seabed_normal {
                            let fc = end.share * contact_force(end.node);
                            for k in 0..D {
                                f[k] += fc * n[k];
                            }
                        }
                    }
                    f
                })
            })
            .collect()
    }

    /// The row values of `end_tensions.csv` in the state of `sim`: `|F_B|, |F_A|` [N] of
    /// every string (fairlead, then anchor).
    pub fn tensions<const D: usize>(&self, sim: &Simulation<D, Material>) -> Vec<f64> {
        self.forces(sim)
            .iter()
            .flat_map(|[a, b]| [b.norm(), a.norm()])
            .collect()
    }
}

/// The pull [N] of element `e` of group `g` on its node `from`, towards its other node
/// `to`: the axial force `N = S√C`, `S = 2W'(C)`, along the chord (zero for a chord of zero
/// length).
pub(super) fn element_pull<const D: usize>(
    sim: &Simulation<D, Material>,
    g: usize,
    e: usize,
    from: usize,
    to: usize,
) -> Vector<D> {
    let st = sim.state();
    let chord = st.r[to] - st.r[from];
    let len = chord.norm();
    let c = st.c[e];
    let axial = 2.0 * sim.system().groups()[g].law.dw(c) * c.max(0.0).sqrt();
    if len > 0.0 {
        chord * (axial / len)
    } else {
        Vector::<D>::zeros()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A 100 m chain (100 kg/m, EA = 1e9 N) hanging in 20 elements between fixed ends at
    /// (0, 0) and (80, −30), started from its static equilibrium.
    fn hanging_chain() -> Simulation<2, Material> {
        let text = r#"dimension = 2
[geometry]
start = [0.0, 0.0]
end = [80.0, -30.0]
length = 100.0
[mesh]
elements = 20
[material]
law = "linear_elastic"
ea = 1.0e9
rho_a = 100.0
[body_force]
gravity = [0.0, -9.81]
[[boundary]]
node = 0
fixed = true
[[boundary]]
node = -1
fixed = true
[initial]
equilibrium = true
[time]
h = 0.01
end = 0.1
"#;
        let file = crate::scenario::parse(text, Path::new("chain.toml"), &[]).unwrap();
        match file.setup().unwrap() {
            phstring::ByDim::D2(s) => s.start(true, None).unwrap().0.problem,
            _ => unreachable!("a 2D scenario"),
        }
    }

    /// At equilibrium every inner node's forces cancel, so the forces of the chain on its
    /// two ends add up to its whole weight, 100 m · 100 kg/m · 9.81 m/s² = 98 100 N down:
    /// the horizontal parts cancel and the vertical ones share the weight.
    #[test]
    fn the_end_forces_of_a_hanging_chain_carry_its_weight() {
        let sim = hanging_chain();
        let ends = EndForces::new(sim.system(), &[], None).unwrap();
        assert_eq!(ends.header(), "t,FairTen1,AnchTen1");
        assert_eq!(ends.names().collect::<Vec<_>>(), ["string"]);
        let [[a, b]] = ends.forces(&sim)[..] else {
            panic!("one string")
        };
        let weight = 100.0 * 100.0 * 9.81;
        let sum = a + b;
        assert!(sum[0].abs() < 1e-6 * weight, "{sum:?}");
        assert!((sum[1] + weight).abs() < 1e-6 * weight, "{sum:?}");
        // The higher end (A at y = 0) carries more of it, and pulls toward the line.
        assert!(a[1] < b[1] && a[0] > 0.0 && b[0] < 0.0, "{a:?} {b:?}");
        assert_eq!(ends.tensions(&sim), [b.norm(), a.norm()]);
    }
}
