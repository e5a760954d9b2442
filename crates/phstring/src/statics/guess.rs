//! The catenary first guess of the statics (docs/method.md §15): every string placed on the
//! elastic catenary through its two supports, in the vertical plane of its ends, with its
//! grounded part on the seabed where its lower end lies on it.
//!
//! It applies when every element group is a string whose two end nodes are held in every
//! component (fixed, or moving supports at their `t = 0` positions) and whose interior nodes
//! belong to it alone, with neither supports, loads nor point masses: strings between two
//! supports, in or out of water. Junction networks, springs, free ends and buoyant lines are
//! left to the other paths. The current's drag at rest is not in the guess. A string end
//! fixed to a rigid body counts as a support at the body's start pose (the body is free in
//! the Newton solve from the guess).

use crate::catenary::{Catenary, Chain, Line};
use crate::material::StoredEnergy;
use crate::system::{ElementGroup, Law, PhSystem, Vector};
use crate::water::{Bed, WaterModel};

/// The catenary first guess: the positions [m] of every node with each string on its
/// discrete elastic catenary (the supports where `r0` has them), or why the guess does not
/// apply (a sentence naming the string).
pub fn catenary_guess<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r0: &[Vector<D>],
) -> Result<Vec<Vector<D>>, String> {
    if D < 2 {
        return Err("a line needs a vertical plane (dimension 1)".into());
    }
    let mut degree = vec![0usize; r0.len()];
    for &[a, b] in sys.mesh.elements() {
        degree[a] += 1;
        degree[b] += 1;
    }
    let held = |i: usize| sys.free[i].iter().all(|f| !f);
    let mut r = r0.to_vec();
    for grp in &sys.groups {
        let name = &grp.name;
        let Law::String(law) = &grp.law else {
            return Err(format!("'{name}' is a spring"));
        };
        let nodes = chain_nodes(sys, grp)?;
        let (first, last) = (nodes[0], nodes[nodes.len() - 1]);
        if let Some(end) = [first, last].into_iter().find(|&i| !held(i)) {
            return Err(format!(
                "string '{name}' ends at node {end}, which is not a support"
            ));
        }
        for &i in &nodes[1..nodes.len() - 1] {
            let why = if degree[i] != 2 {
                "a junction"
            } else if !sys.free[i].iter().all(|&f| f) {
                "a support"
            } else if sys.point_mass.iter().any(|&(j, _)| j == i) {
                "a point mass"
            } else if sys.boundary.loads.iter().any(|l| l.node == i) {
                "a load"
            } else {
                continue;
            };
            return Err(format!(
                "string '{name}' has {why} at its interior node {i}"
            ));
        }
        let ea = 4.0 * law.d2w(1.0);
        place(sys, grp, ea, &nodes, &mut r)?;
    }
    Ok(r)
}

/// The nodes of group `grp` in order along it, if its elements form a chain `[n₀, n₁],
/// [n₁, n₂], …`.
fn chain_nodes<const D: usize, M>(
    sys: &PhSystem<D, M>,
    grp: &ElementGroup<D, M>,
) -> Result<Vec<usize>, String> {
    let els = &sys.mesh.elements()[grp.elements.clone()];
    let mut nodes = vec![els[0][0]];
    for &[a, b] in els {
        if a != nodes[nodes.len() - 1] {
            return Err(format!(
                "string '{}' is not one chain of elements",
                grp.name
            ));
        }
        nodes.push(b);
    }
    Ok(nodes)
}

/// Places the interior nodes `nodes` of string `grp` (axial stiffness `ea` [N] at rest) on
/// its discrete catenary in `r`: the continuous catenary gives the start of the chain's
/// solve ([`Chain::solve`]), whose nodes are the guess.
fn place<const D: usize, M>(
    sys: &PhSystem<D, M>,
    grp: &ElementGroup<D, M>,
    ea: f64,
    nodes: &[usize],
    r: &mut [Vector<D>],
) -> Result<(), String> {
    let name = &grp.name;
    if nodes.len() < 3 {
        return Ok(());
    }
    let water = sys.water.as_deref();
    let (up, mut weights) = node_weights(sys, grp, nodes)?;
    let mut lengths = sys.mesh.lengths()[grp.elements.clone()].to_vec();
    let (first, last) = (nodes[0], nodes[nodes.len() - 1]);
    let rises = (r[last] - r[first]).dot(&up) >= 0.0;
    let mut order = nodes.to_vec();
    if !rises {
        lengths.reverse();
        weights.reverse();
        order.reverse();
    }
    let (pa, pb) = (r[order[0]], r[order[order.len() - 1]]);
    let chord = pb - pa;
    let z = chord.dot(&up);
    let horizontal = chord - up * z;
    let x = horizontal.norm();
    let length: f64 = lengths.iter().sum();
    if x.is_nan() || x <= VERTICAL * length {
        return Err(format!("string '{name}' hangs vertically between its ends"));
    }
    let across = horizontal / x;
    let spanned = length - 0.5 * (lengths[0] + lengths[lengths.len() - 1]);
    let line = Line {
        length,
        weight: weights.iter().sum::<f64>() / spanned,
        ea,
    };
    let bed = water.and_then(|m| m.bed.as_ref());
    let below = bed.and_then(|b| height_above(b, &pa));
    let on_bed = below.is_some_and(|g| g.abs() <= ON_BED * (z + g).abs().max(1.0));
    let below = below.filter(|_| on_bed);
    let no_shape = || {
        format!(
            "string '{name}' has no elastic catenary between its ends ({length} m of line, {x:.6} m apart, {z:.6} m up)"
        )
    };
    let start = catenary(line, x, z, below).ok_or_else(no_shape)?;
    let chain = Chain {
        lengths: &lengths,
        weights: &weights,
        ea,
        grounded: on_bed,
    };
    let c0 = start.v_a + line.weight * (0.5 * lengths[0] - start.grounded);
    let (h, c) = chain.solve(x, z, start.h, c0).ok_or_else(no_shape)?;
    let points = chain.points(h, c);
    for (k, &i) in order.iter().enumerate().skip(1).take(order.len() - 2) {
        let (px, pz) = points[k];
        let mut p = pa + across * px + up * pz;
        if let (Some(bed), Some(g), true) = (bed, below, pz == 0.0 && points[k + 1].1 == 0.0) {
            // On the seabed, pressed in by its weight, if the seabed there is as deep as at
            // the lower end.
            let off = height_above(bed, &p).map_or(f64::INFINITY, |h| h - g);
            if off.is_nan() || off.abs() > ON_BED * (z + g).abs().max(1.0) {
                return Err(format!(
                    "the seabed under string '{name}' is not flat: {off:.6} m off the depth at its lower end at node {i}"
                ));
            }
            p -= up * (g + off + penetration(water, i, weights[k - 1]));
        }
        if p.iter().any(|c| !c.is_finite()) {
            return Err(format!(
                "string '{name}': its catenary is not finite at node {i}"
            ));
        }
        r[i] = p;
    }
    Ok(())
}

/// The catenary of `line` to a point `x` [m] across and `z` [m] above its lower end, whose
/// height above the seabed is `below` [m] if it lies on the seabed: grounded where the line
/// between the points would sag below the seabed, else between the points.
fn catenary(line: Line, x: f64, z: f64, below: Option<f64>) -> Option<Catenary> {
    let free = Catenary::between(line, x, z);
    match below {
        Some(g) => match free {
            Some(c) if c.v_a >= 0.0 => Some(c),
            _ => Catenary::on_seabed(line, x, z + g),
        },
        None => free,
    }
}

/// The unit vector up (against the string's weight) and the weight [N] of each interior
/// node of `nodes` along it (its share of the body force less its buoyancy).
fn node_weights<const D: usize, M>(
    sys: &PhSystem<D, M>,
    grp: &ElementGroup<D, M>,
    nodes: &[usize],
) -> Result<(Vector<D>, Vec<f64>), String> {
    let name = &grp.name;
    let weight = grp.body_force.norm();
    if weight.is_nan() || weight <= 0.0 {
        return Err(format!("string '{name}' has no weight"));
    }
    let up = -grp.body_force / weight;
    let water = sys.water.as_deref();
    if water.is_some() && (up[D - 1] - 1.0).abs() > 1e-12 {
        return Err(format!(
            "string '{name}' has a weight off the vertical in water"
        ));
    }
    let mut weights = Vec::with_capacity(nodes.len() - 2);
    for &i in &nodes[1..nodes.len() - 1] {
        let f = sys.f_body[i];
        let down = -f.dot(&up);
        if (f + up * down).norm() > 1e-9 * down.abs() {
            return Err(format!(
                "string '{name}' has a weight off its vertical at node {i}"
            ));
        }
        let lift = water
            .and_then(|m| {
                m.nodes
                    .binary_search_by_key(&i, |n| n.node)
                    .ok()
                    .map(|j| m.nodes[j].buoyancy)
            })
            .unwrap_or(0.0);
        weights.push(down - lift);
    }
    let total: f64 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(format!("string '{name}' floats (wet weight {total:.6e} N)"));
    }
    Ok((up, weights))
}

/// The height [m] of `p` above the seabed, measured vertically (a plane's normal gap over
/// its normal's vertical component; a grid's gap is vertical); `None` for a vertical plane.
fn height_above<const D: usize>(bed: &Bed<D>, p: &Vector<D>) -> Option<f64> {
    let gap = bed.gap(p);
    match &bed.grid {
        Some(_) => Some(gap),
        None => (bed.n[D - 1] > 0.0).then(|| gap / bed.n[D - 1]),
    }
}

/// The depth [m] by which grounded node `i` of weight `weight` [N] sinks into the seabed:
/// its weight over its contact stiffness `k d L_i`.
fn penetration<const D: usize>(water: Option<&WaterModel<D>>, i: usize, weight: f64) -> f64 {
    let Some(m) = water else { return 0.0 };
    match m.nodes.binary_search_by_key(&i, |n| n.node) {
        Ok(j) if m.nodes[j].stiffness > 0.0 => weight / m.nodes[j].stiffness,
        _ => 0.0,
    }
}

/// A lower end within this fraction of the fairlead's height (or of 1 m) of the seabed lies
/// on it.
const ON_BED: f64 = 1e-2;
/// A string whose ends are less than this fraction of its length apart across is vertical.
const VERTICAL: f64 = 1e-6;
