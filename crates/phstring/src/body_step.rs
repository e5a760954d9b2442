//! The rigid bodies' part of a step (docs/method.md §22): their unknowns in the Newton
//! vector, the attached nodes' increments, the bodies' rows and their Jacobian border.
//!
//! Body `b` has two slots after the `n` nodes: `n + 2b` holds `Δx` and `n + 2b + 1` the
//! Cayley vector `w` (in 2D `(w_z, 0)`: the second component is a placeholder whose row is
//! `u = 0`). The torque row is divided by the body's radius of gyration, so that both rows
//! are forces [N] in Newton's norm.

use crate::body::{BodyState, Mat3, NodeRow, PointStep, Turn, Vec3, embed, project};
use crate::linsolve::{Block, BlockJacobian};
use crate::system::{PhSystem, Vector};

/// `(Δx, w)` of body `b` from the slots `slots` (the Newton vector after the nodes).
pub(crate) fn unknowns<const D: usize>(slots: &[Vector<D>], b: usize) -> (Vec3, Vec3) {
    let dx = embed(&slots[2 * b]);
    let w = if D == 2 {
        Vec3::new(0.0, 0.0, slots[2 * b + 1][0])
    } else {
        embed(&slots[2 * b + 1])
    };
    (dx, w)
}

/// The slot of a rotation vector `w` (in 2D its `z` component).
pub(crate) fn rotation_slot<const D: usize>(w: &Vec3) -> Vector<D> {
    if D == 2 {
        Vector::<D>::from_fn(|k, _| if k == 0 { w.z } else { 0.0 })
    } else {
        project(w)
    }
}

/// Writes the attached nodes' increments `Δa = Δx + R_n (cay(w) − I) s` into `x`.
pub(crate) fn fill_attachments<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    slots: &[Vector<D>],
    x: &mut [Vector<D>],
) {
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        let (dx, w) = unknowns(slots, b);
        let turn = Turn::new(&st.orientation, &w);
        for &(node, s) in &model.attachments {
            x[node] = project(&(dx + turn.point(&s).moved));
        }
    }
}

/// The predicted slots of a step of `h` [s]: `Δx = h V_n`, `w = h Ω_n`.
pub(crate) fn predict<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    h: f64,
    slots: &mut [Vector<D>],
) {
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        slots[2 * b] = project(&(st.velocity * h));
        slots[2 * b + 1] = rotation_slot::<D>(&(model.omega(st) * h));
    }
}

/// The wrench ports' samples of a step of `h` [s] with slots `slots` and inputs `wrenches`
/// (force [N], torque [N·m] per body), into `out`; returns the energy they supplied [J].
pub(crate) fn port_samples<const D: usize>(
    states: &[BodyState],
    h: f64,
    slots: &[Vector<D>],
    wrenches: &[(Vec3, Vec3)],
    out: &mut [crate::body::BodyPortSample],
) -> f64 {
    let mut supplied = 0.0;
    for (b, ((st, &(force, torque)), p)) in states.iter().zip(wrenches).zip(out).enumerate() {
        let (dx, w) = unknowns(slots, b);
        let turned = st.orientation.transform_vector(&w);
        // The work F·Δx + τ·R_n w, summed as the step's equations sum it.
        supplied += force.dot(&dx) + torque.dot(&turned);
        let (velocity, omega) = (dx / h, turned / h);
        *p = crate::body::BodyPortSample {
            force,
            torque,
            velocity,
            omega,
            mean_power: force.dot(&velocity) + torque.dot(&omega),
        };
    }
    supplied
}

/// The bodies' states after a step of `h` [s] with slots `slots`, into `out`.
pub(crate) fn advance<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    h: f64,
    slots: &[Vector<D>],
    out: &mut Vec<BodyState>,
) {
    out.clear();
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        let (dx, w) = unknowns(slots, b);
        out.push(model.advance(st, h, &dx, &w));
    }
}

/// `Q m P`: a body's 3×3 block as a `D×D` block between slots of kinds `row` and `col`
/// (0: `Δx` or force, 1: `w` or torque).
pub(crate) fn slot_block<const D: usize>(m: &Mat3, row: usize, col: usize) -> Block<D> {
    // In 2D the rotation slot's first component is the z component.
    let pick = |kind: usize, k: usize| {
        if D == 2 && kind == 1 {
            (k == 0).then_some(2)
        } else {
            Some(k)
        }
    };
    Block::<D>::from_fn(|r, c| match (pick(row, r), pick(col, c)) {
        (Some(i), Some(j)) => m[(i, j)],
        _ => 0.0,
    })
}

/// A node block (`D×D`) in 3D.
pub(crate) fn embed_block<const D: usize>(b: &Block<D>) -> Mat3 {
    Mat3::from_fn(|i, j| if i < D && j < D { b[(i, j)] } else { 0.0 })
}

/// The slot-to-node block `∂R_node/∂u` (`D×D`) of a 3×3 block `m = ∂R_node/∂(Δx or w)`.
fn node_slot_block<const D: usize>(m: &Mat3, col: usize) -> Block<D> {
    let pick = |k: usize| {
        if D == 2 && col == 1 {
            (k == 0).then_some(2)
        } else {
            Some(k)
        }
    };
    Block::<D>::from_fn(|r, c| pick(c).map_or(0.0, |j| m[(r, j)]))
}

/// The slot-from-node block `∂R_slot/∂x_node` (`D×D`) of a 3×3 block.
fn slot_node_block<const D: usize>(m: &Mat3, row: usize) -> Block<D> {
    let pick = |k: usize| {
        if D == 2 && row == 1 {
            (k == 0).then_some(2)
        } else {
            Some(k)
        }
    };
    Block::<D>::from_fn(|r, c| pick(r).map_or(0.0, |i| m[(i, c)]))
}

/// Zeroes the rows (`rows`) or columns of the fixed components `fixed` of a block.
fn mask<const D: usize>(mut b: Block<D>, free: &[bool; D], rows: bool) -> Block<D> {
    for k in (0..D).filter(|&k| !free[k]) {
        if rows {
            b.row_mut(k).fill(0.0);
        } else {
            b.column_mut(k).fill(0.0);
        }
    }
    b
}

/// The step's inputs a body needs beyond its state.
pub(crate) struct BodyStep<'a, const D: usize> {
    pub states: &'a [BodyState],
    pub h: f64,
    /// The slots of the Newton vector.
    pub slots: &'a [Vector<D>],
    /// Per body, the wrench port's force [N] and torque [N·m] at the mid time.
    pub wrenches: &'a [(Vec3, Vec3)],
}

impl<const D: usize> BodyStep<'_, D> {
    /// The bodies' rows into `res[n..]` and, with `jac`, their blocks (read before the
    /// attached nodes' rows and columns are masked); returns the squares of their force terms
    /// (force scale).
    pub(crate) fn terms<M>(
        &self,
        sys: &PhSystem<D, M>,
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
    ) -> f64 {
        let n = sys.mesh.n_nodes();
        let turns: Vec<Turn> = sys
            .bodies
            .iter()
            .zip(self.states)
            .enumerate()
            .map(|(b, (_, st))| Turn::new(&st.orientation, &unknowns(self.slots, b).1))
            .collect();
        let points: Vec<Vec<PointStep>> = sys
            .bodies
            .iter()
            .zip(&turns)
            .map(|(m, t)| m.attachments.iter().map(|(_, s)| t.point(s)).collect())
            .collect();
        let mut scale2 = 0.0;
        for (b, (model, st)) in sys.bodies.iter().zip(self.states).enumerate() {
            let (dx, w) = unknowns(self.slots, b);
            let rows: Vec<NodeRow> = model
                .attachments
                .iter()
                .map(|&(node, _)| NodeRow {
                    res: embed(&res[node]),
                    diag: jac
                        .as_deref()
                        .map_or(Mat3::zeros(), |j| embed_block(&j.diag[node])),
                })
                .collect();
            let mut dw_rows = vec![Mat3::zeros(); rows.len()];
            let (f_port, torque) = self.wrenches.get(b).copied().unwrap_or_default();
            let force = model.weight + f_port;
            let applied = (&force, &torque);
            let out = model.rows(
                st,
                self.h,
                (&dx, &w),
                &turns[b],
                &rows,
                &points[b],
                applied,
                &mut dw_rows,
            );
            let inv_rg = 1.0 / model.gyration();
            res[n + 2 * b] = project(&out.force);
            res[n + 2 * b + 1] = rotation_slot::<D>(&(out.torque * inv_rg));
            let inertia = (dx / self.h - st.velocity) * (2.0 * model.mass / self.h);
            let spin = (model.inertia * w / self.h - st.momentum) * (2.0 / self.h * inv_rg);
            scale2 += inertia.norm_squared()
                + model.weight.norm_squared()
                + f_port.norm_squared()
                + (torque * inv_rg).norm_squared()
                + spin.norm_squared();
            let Some(j) = jac.as_deref_mut() else {
                continue;
            };
            let slots = j.border.slots;
            let at = |s: usize, t: usize| (2 * b + s) * slots + 2 * b + t;
            for (s, row_scale) in [(0, 1.0), (1, inv_rg)] {
                for t in 0..2 {
                    j.border.own[at(s, t)] += slot_block::<D>(&(out.jac[s][t] * row_scale), s, t);
                }
            }
            if D == 2 {
                j.border.own[at(1, 1)][(1, 1)] = 1.0;
            }
            couple(sys, b, &points, &dw_rows, inv_rg, j);
        }
        scale2
    }
}

/// The blocks between body `b`'s rows and the nodes next to its attached nodes (and the
/// bodies those are fixed to), and between those nodes' rows and body `b`'s slots: `points`
/// per body and attachment, `dw_rows[k]` the torque row's `∂/∂R_k` (before the scaling by
/// `inv_rg`, the inverse radius of gyration).
pub(crate) fn couple<const D: usize, M>(
    sys: &PhSystem<D, M>,
    b: usize,
    points: &[Vec<PointStep>],
    dw_rows: &[Mat3],
    inv_rg: f64,
    j: &mut BlockJacobian<D>,
) {
    let eye = Mat3::identity();
    let slots = j.border.slots;
    for (k, p) in points[b].iter().enumerate() {
        // Body rows from R_k: force ∂/∂R_k = I, torque (scaled) ∂/∂R_k = dw_rows[k].
        let by_res = [eye, dw_rows[k] * inv_rg];
        let da = [eye, p.dw];
        for &(e, other, first) in &sys.body_links[b][k] {
            let (kj, jk) = if first {
                (j.off[e][0], j.off[e][1])
            } else {
                (j.off[e][1], j.off[e][0])
            };
            let (kj, jk) = (embed_block(&kj), embed_block(&jk));
            match sys.attached.get(other).copied().flatten() {
                Some((b2, k2)) => {
                    let da2 = [eye, points[b2][k2].dw];
                    for (s, rs) in by_res.iter().enumerate() {
                        for (t, d2) in da2.iter().enumerate() {
                            let blk = slot_block::<D>(&(rs * kj * d2), s, t);
                            j.border.own[(2 * b + s) * slots + 2 * b2 + t] += blk;
                        }
                    }
                }
                None => {
                    let free = &sys.free[other];
                    if !free.iter().any(|&f| f) {
                        continue;
                    }
                    for s in 0..2 {
                        let row = mask(slot_node_block::<D>(&(by_res[s] * kj), s), free, false);
                        let col = mask(node_slot_block::<D>(&(jk * da[s]), s), free, true);
                        j.border.links.push((other, 2 * b + s, row, col));
                    }
                }
            }
        }
    }
}
