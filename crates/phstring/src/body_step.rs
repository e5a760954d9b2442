//! The rigid bodies' part of a step (docs/method.md §22): their unknowns in the Newton
//! vector, the attached nodes' increments, the bodies' rows and their Jacobian border.
//!
//! Body `b` has two slots after the `n` nodes: `n + 2b` holds `Δx` and `n + 2b + 1` the
//! Cayley vector `w` (in 2D `(w_z, 0)`: the second component is a placeholder whose row is
//! `u = 0`). The torque row is divided by the body's radius of gyration, so that both rows
//! are forces [N] in Newton's norm.

use crate::body::{BodyState, Mat3, NodeRow, PointStep, Turn, Vec3, embed, project};
use crate::body_feedback::{FeedbackTarget, FeedbackWrench};
use crate::linsolve::{Block, BlockJacobian, BorderPattern};
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

/// Writes the attached nodes' increments `Δa = Δx + R_n (cay(w) − I) s` into `x`, with an
/// attachment's offset where it has one (a winch drum's payout on the body).
pub(crate) fn fill_attachments<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    slots: &[Vector<D>],
    x: &mut [Vector<D>],
) {
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        let (dx, w) = unknowns(slots, b);
        let turn = Turn::new(&st.orientation, &w);
        for (k, &(node, s)) in model.attachments.iter().enumerate() {
            let offset = model.offset.get(k).copied().unwrap_or_default();
            x[node] = project(&(dx + turn.point(&s).moved + offset));
        }
    }
}

/// The predicted slots of a step of `h` [s]: `Δx = h V_n`, `w = h Ω_n`.
pub(crate) fn predict<const D: usize>(states: &[BodyState], h: f64, slots: &mut [Vector<D>]) {
    for (b, st) in states.iter().enumerate() {
        slots[2 * b] = project(&(st.velocity * h));
        slots[2 * b + 1] = rotation_slot::<D>(&(st.omega * h));
    }
}

/// The bodies' port samples of a step of `h` [s] with slots `slots`, into `out`; returns the
/// energy they supplied [J]. A wrench port's inputs are `wrenches` (force [N], torque [N·m]
/// per body) plus its feedback law's wrench against `targets` (per body, the law's reference
/// at the mid time; `None` without a law); a prescribed motion's output is the reaction wrench, formed from the attached
/// nodes' residuals `reaction` (as the Newton solve left them, with `scratch` for the rows)
/// and the states `next` the step ends in (velocities held), with the impulse and the
/// kinetic energy of the hold.
#[allow(clippy::too_many_arguments)]
pub(crate) fn port_samples<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    h: f64,
    slots: &[Vector<D>],
    (wrenches, targets): (&[(Vec3, Vec3)], &[Option<FeedbackTarget>]),
    (reaction, scratch): (&[Vector<D>], &mut BodyScratch),
    next: &[BodyState],
    out: &mut [crate::body::BodyPortSample],
) -> f64 {
    let mut supplied = 0.0;
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        let (dx, w) = unknowns(slots, b);
        let turned = st.orientation.transform_vector(&w);
        let (velocity, omega) = (dx / h, turned / h);
        let (force, torque, work) = if model.motion.is_some() {
            let water = sys.water.as_deref();
            let parts = (reaction, &mut *scratch);
            reaction_wrench(model, water, st, h, (&dx, &w), parts, &next[b])
        } else {
            // The work F·Δx + τ·R_n w, summed as the step's equations sum it.
            let (mut force, mut torque) = wrenches[b];
            if let Some(fb) = feedback_at::<D>(model, targets, b, st, h, (&dx, &w)) {
                force += fb.force;
                torque += fb.torque;
            }
            (force, torque, force.dot(&dx) + torque.dot(&turned))
        };
        supplied += work;
        out[b] = crate::body::BodyPortSample {
            force,
            torque,
            velocity,
            omega,
            mean_power: work / h,
        };
    }
    supplied
}

/// Body `b`'s feedback wrench over a step of `h` [s] from `st` with unknowns `(Δx, w)`
/// against its reference in `targets` (in 2D in the plane: the force's `z` and the torque's
/// `x`, `y` dropped); `None` without a law.
pub(crate) fn feedback_at<const D: usize>(
    model: &crate::body::BodyModel,
    targets: &[Option<FeedbackTarget>],
    b: usize,
    st: &BodyState,
    h: f64,
    (dx, w): (&Vec3, &Vec3),
) -> Option<FeedbackWrench> {
    let (law, target) = (model.feedback.as_ref()?, targets.get(b)?.as_ref()?);
    let mut out = law.wrench(target, (&st.position, &st.orientation), h, (dx, w));
    if D == 2 {
        out.force.z = 0.0;
        out.torque.x = 0.0;
        out.torque.y = 0.0;
    }
    Some(out)
}

/// The step of each of body `model`'s points under `turn`: its attachments in order, then its
/// centre of buoyancy and its waterplane points where it has them (the rows of [`water_rows`]
/// follow the attachments' in the same order).
fn point_steps<'m>(
    model: &'m crate::body::BodyModel,
    turn: &'m Turn,
) -> impl Iterator<Item = PointStep> + 'm {
    let cb = model.buoyancy.map(|(_, s)| s);
    model
        .attachments
        .iter()
        .map(|(_, s)| *s)
        .chain(cb)
        .chain(model.waterplane.iter().map(|(_, s, _)| *s))
        .map(|s| turn.point(&s))
}

/// Appends to `rows` the water's point rows of a body over a step from `st` with increment
/// `dx` [m]: the buoyancy (a constant force at the centre of buoyancy, a row that asks the
/// body for `−F_b`) and the waterplane's restoring at its points (the last of `points`, from
/// [`point_steps`]).
fn water_rows(
    model: &crate::body::BodyModel,
    st: &BodyState,
    dx: &Vec3,
    points: &[PointStep],
    rows: &mut Vec<NodeRow>,
) {
    if let Some((f, _)) = model.buoyancy {
        rows.push(NodeRow {
            res: -f,
            diag: Mat3::zeros(),
        });
    }
    let first = points.len() - model.waterplane.len();
    for (i, p) in points[first..].iter().enumerate() {
        rows.push(model.waterplane_row(i, st, dx, &p.moved));
    }
}

/// [`crate::body::BodyModel::drag_step`] in the current of `water` at the body's mid-step
/// centre; zero without water or drag.
fn drag_in<const D: usize>(
    model: &crate::body::BodyModel,
    water: Option<&crate::water::WaterModel<D>>,
    st: &BodyState,
    h: f64,
    dx: &Vec3,
) -> (Vec3, Mat3, f64, f64) {
    match water {
        Some(water) if model.drag.is_some() => {
            let flow = current_at::<D>(water, st, dx);
            model.drag_step(h, dx, (&flow.0, &flow.1, &flow.2))
        }
        _ => (Vec3::zeros(), Mat3::zeros(), 0.0, 0.0),
    }
}

/// The wrench [N, N·m] a prescribed motion exerts over a step (the body's rows at the
/// solution, with the hold's impulse), and the energy it supplies [J]: the wrench's work over
/// `(Δx, R_n w)` and the kinetic energy the hold of the velocities adds.
fn reaction_wrench<const D: usize>(
    model: &crate::body::BodyModel,
    water: Option<&crate::water::WaterModel<D>>,
    st: &BodyState,
    h: f64,
    (dx, w): (&Vec3, &Vec3),
    (reaction, scratch): (&[Vector<D>], &mut BodyScratch),
    held: &BodyState,
) -> (Vec3, Vec3, f64) {
    let turn = Turn::new(&st.orientation, w);
    let BodyScratch {
        rows,
        dw_rows,
        reaction_points: points,
        ..
    } = scratch;
    points.clear();
    points.extend(point_steps(model, &turn));
    rows.clear();
    rows.extend(model.attachments.iter().map(|&(node, _)| NodeRow {
        res: embed(&reaction[node]),
        diag: Mat3::zeros(),
    }));
    water_rows(model, st, dx, points, rows);
    dw_rows.clear();
    dw_rows.resize(rows.len(), Mat3::zeros());
    let zero = Vec3::zeros();
    // The drag acts as on a free body (its work is in the water's shares), so the reaction
    // is the motion's own force.
    let applied = model.weight + drag_in(model, water, st, h, dx).0;
    let out = model.rows(
        st,
        h,
        (dx, w),
        &turn,
        rows,
        points,
        (&applied, &zero),
        dw_rows,
    );
    // The rows with the reaction (F, τ) added are zero: F = force row, τ̃ = (I − ½ŵ)⁻¹ torque.
    let force = out.force;
    let torque = turn.rot * (turn.inv_half * out.torque);
    let raw = model.advance(st, h, dx, w);
    let work = force.dot(dx) + torque.dot(&st.orientation.transform_vector(w));
    let hold = model.kinetic(held) - model.kinetic(&raw);
    // The hold's impulse belongs to the reaction, so that the momentum balance is whole.
    let impulse = match model.kirchhoff {
        Some(_) => (model.linear_momentum(held) - model.linear_momentum(&raw)) / h,
        None => (held.velocity - raw.velocity) * (model.mass / h),
    };
    let spin = held
        .orientation
        .transform_vector(&(model.momentum(held) - model.momentum(&raw)))
        / h;
    (force + impulse, torque + spin, work + hold)
}

/// The mid-step velocities of a step of `h` [s] from `states` with slots `slots`, in the
/// predictor's form (per body `Δx/h` and the slot of `R_n w/h`), into `out`.
pub(crate) fn mid_velocities<const D: usize>(
    states: &[BodyState],
    h: f64,
    slots: &[Vector<D>],
    out: &mut [Vector<D>],
) {
    for (b, st) in states.iter().enumerate() {
        let (dx, w) = unknowns(slots, b);
        out[2 * b] = project(&(dx / h));
        out[2 * b + 1] = rotation_slot::<D>(&(st.orientation.transform_vector(&w) / h));
    }
}

/// The slots predicted from the last step's mid-step velocities `v_mid` (the form of
/// [`mid_velocities`]): `Δx = h V_{n−½}`, `w = h R_nᵀ ω_{n−½}`.
pub(crate) fn predict_mid<const D: usize>(
    states: &[BodyState],
    h: f64,
    v_mid: &[Vector<D>],
    slots: &mut [Vector<D>],
) {
    for (b, st) in states.iter().enumerate() {
        let (v, omega) = unknowns(v_mid, b);
        slots[2 * b] = project(&(v * h));
        let w = st.orientation.inverse_transform_vector(&omega) * h;
        slots[2 * b + 1] = rotation_slot::<D>(&w);
    }
}

/// The current's velocity [m/s], its vertical derivative [1/s] and the vertical unit vector
/// at body `st`'s mid-step centre `x_n + Δx/2` (3-vectors).
pub(crate) fn current_at<const D: usize>(
    water: &crate::water::WaterModel<D>,
    st: &BodyState,
    dx: &Vec3,
) -> (Vec3, Vec3, Vec3) {
    let mid = st.position + dx * 0.5;
    let (u, du) = water.current.at(mid[D - 1]);
    let up = Vec3::from_fn(|k, _| if k + 1 == D { 1.0 } else { 0.0 });
    (embed(&u), embed(&du), up)
}

/// The water's work on the bodies over a step of `h` [s] with slots `slots`: their drag's
/// dissipation and the current's supply [J].
pub(crate) fn drag_work<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    h: f64,
    slots: &[Vector<D>],
) -> (f64, f64) {
    let water = sys.water.as_deref();
    let (mut dissipated, mut supplied) = (0.0, 0.0);
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        if model.drag.is_some() {
            let (_, _, d, s) = drag_in(model, water, st, h, &unknowns(slots, b).0);
            dissipated += d;
            supplied += s;
        }
    }
    (dissipated, supplied)
}

/// The bodies' states after a step of `h` [s] with slots `slots`, into `out`.
pub(crate) fn advance<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    (h, t_next): (f64, f64),
    slots: &[Vector<D>],
    out: &mut Vec<BodyState>,
) {
    out.clear();
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        let (dx, w) = unknowns(slots, b);
        let mut next = model.advance(st, h, &dx, &w);
        // A prescribed motion holds the velocities at its own (docs/method.md §22).
        if let Some(m) = &model.motion {
            let (v, omega) = (m.twist)(t_next);
            next.velocity = planar::<D>(&v);
            let omega = next.orientation.inverse_transform_vector(&omega);
            next.omega = if D == 2 {
                Vec3::new(0.0, 0.0, omega.z)
            } else {
                omega
            };
        }
        out.push(next);
    }
}

/// `v` in the plane of a `D`-dimensional network (`z = 0` in 2D).
fn planar<const D: usize>(v: &Vec3) -> Vec3 {
    if D == 2 { Vec3::new(v.x, v.y, 0.0) } else { *v }
}

/// The slots of the prescribed bodies for a step from `states` to `t_next` [s]: `Δx` to the
/// pose's position and the Cayley vector of the turn to its orientation. `Err(b)`: body `b`'s
/// pose is not finite, leaves the plane of a 2D network, or turns by more than 170° in the
/// step.
pub(crate) fn prescribe<const D: usize, M>(
    sys: &PhSystem<D, M>,
    states: &[BodyState],
    t_next: f64,
    slots: &mut [Vector<D>],
) -> Result<(), usize> {
    for (b, (model, st)) in sys.bodies.iter().zip(states).enumerate() {
        let Some(m) = &model.motion else {
            continue;
        };
        let (x, q) = (m.pose)(t_next);
        let rel = st.orientation.inverse() * q;
        let (qw, qv) = (rel.quaternion().w, rel.quaternion().imag());
        // cay(w) has the quaternion (1, w/2)/‖·‖: w = 2 q_v/q_w (q and −q are one rotation).
        let planar = D == 3 || (x.z == 0.0 && qv.x == 0.0 && qv.y == 0.0);
        if !(x.iter().all(|c| c.is_finite()) && qw.abs() > (85f64).to_radians().cos() && planar) {
            return Err(b);
        }
        slots[2 * b] = project(&(x - st.position));
        slots[2 * b + 1] = rotation_slot::<D>(&(qv * (2.0 / qw)));
    }
    Ok(())
}

/// `Q m P`: a body's 3×3 block as a `D×D` block between slots of kinds `row` and `col`
/// (0: `Δx` or force, 1: `w` or torque).
fn slot_block<const D: usize>(m: &Mat3, row: usize, col: usize) -> Block<D> {
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
    /// Per body, its feedback law's reference at the mid time (`None`, or empty: no law).
    pub targets: &'a [Option<FeedbackTarget>],
    /// Buffers the rows reuse from one evaluation to the next.
    pub scratch: &'a mut BodyScratch,
}

/// The buffers of the bodies' rows, kept between evaluations so that a step does not
/// allocate: per body its turn and point steps, one body's attachment rows and torque
/// derivatives at a time, and the point steps of a prescribed motion's reaction.
#[derive(Debug, Clone, Default)]
pub(crate) struct BodyScratch {
    turns: Vec<Turn>,
    points: Vec<Vec<PointStep>>,
    rows: Vec<NodeRow>,
    dw_rows: Vec<Mat3>,
    reaction_points: Vec<PointStep>,
}

impl<const D: usize> BodyStep<'_, D> {
    /// The bodies' rows into `res[n..]` and, with `jac`, their blocks (read before the
    /// attached nodes' rows and columns are masked); returns the squares of their force terms
    /// (force scale).
    pub(crate) fn terms<M>(
        &mut self,
        sys: &PhSystem<D, M>,
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
    ) -> f64 {
        let n = sys.mesh.n_nodes();
        let BodyScratch {
            turns,
            points,
            rows,
            dw_rows,
            ..
        } = &mut *self.scratch;
        turns.clear();
        turns.extend(
            self.states
                .iter()
                .enumerate()
                .map(|(b, st)| Turn::new(&st.orientation, &unknowns(self.slots, b).1)),
        );
        points.resize_with(sys.bodies.len(), Vec::new);
        for ((m, t), p) in sys.bodies.iter().zip(turns.iter()).zip(points.iter_mut()) {
            p.clear();
            p.extend(point_steps(m, t));
        }
        let mut scale2 = 0.0;
        for (b, (model, st)) in sys.bodies.iter().zip(self.states).enumerate() {
            if model.motion.is_some() {
                // Known slots: their rows are `δu = 0`; the reaction is formed after the solve.
                res[n + 2 * b] = Vector::zeros();
                res[n + 2 * b + 1] = Vector::zeros();
                if let Some(j) = jac.as_deref_mut() {
                    let slots = j.border.slots;
                    for s in 0..2 {
                        j.border.own[(2 * b + s) * slots + 2 * b + s] = Block::identity();
                    }
                }
                continue;
            }
            let (dx, w) = unknowns(self.slots, b);
            rows.clear();
            rows.extend(model.attachments.iter().map(|&(node, _)| {
                NodeRow {
                    res: embed(&res[node]),
                    diag: jac
                        .as_deref()
                        .map_or(Mat3::zeros(), |j| embed_block(&j.diag[node])),
                }
            }));
            water_rows(model, st, &dx, &points[b], rows);
            dw_rows.clear();
            dw_rows.resize(rows.len(), Mat3::zeros());
            let (mut f_port, mut torque) = self.wrenches.get(b).copied().unwrap_or_default();
            let fb = feedback_at::<D>(model, self.targets, b, st, self.h, (&dx, &w));
            if let Some(fb) = &fb {
                f_port += fb.force;
                torque += fb.torque;
            }
            let (f_drag, d_drag, _, _) = drag_in(model, sys.water.as_deref(), st, self.h, &dx);
            let force = model.weight + f_port + f_drag;
            let applied = (&force, &torque);
            let mut out = model.rows(
                st,
                self.h,
                (&dx, &w),
                &turns[b],
                rows,
                &points[b],
                applied,
                dw_rows,
            );
            out.jac[0][0] -= d_drag;
            if let Some(fb) = &fb {
                // Force row `… − F`, torque row `… − (I − ½ŵ) R_nᵀ τ` (the factor's own
                // derivative is in `rows`).
                out.jac[0][0] -= fb.d_force;
                let half = Mat3::identity() - crate::body::skew(&w) * 0.5;
                out.jac[1][1] -= half * turns[b].rot.transpose() * fb.d_torque;
            }
            let inv_rg = 1.0 / model.gyration();
            res[n + 2 * b] = project(&out.force);
            res[n + 2 * b + 1] = rotation_slot::<D>(&(out.torque * inv_rg));
            let (inertia, spin) = match model.kirchhoff {
                Some(_) => {
                    let (f, t, _) = model.inertia_rows(st, self.h, (&dx, &w), &turns[b]);
                    (f, t * inv_rg)
                }
                None => (
                    (dx / self.h - st.velocity) * (2.0 * model.mass / self.h),
                    (model.inertia * w / self.h - model.momentum(st)) * (2.0 / self.h * inv_rg),
                ),
            };
            scale2 += inertia.norm_squared()
                + model.weight.norm_squared()
                + f_port.norm_squared()
                + f_drag.norm_squared()
                + model.buoyancy.map_or(0.0, |(f, _)| f.norm_squared())
                + rows[rows.len() - model.waterplane.len()..]
                    .iter()
                    .map(|r| r.res.norm_squared())
                    .sum::<f64>()
                + (torque * inv_rg).norm_squared()
                + spin.norm_squared();
            let Some(j) = jac.as_deref_mut() else {
                continue;
            };
            add_body_blocks(sys, b, &out.jac, (points, dw_rows, inv_rg), j);
        }
        scale2
    }
}

/// Adds body `b`'s own blocks `blocks` (3×3, rows force and torque, columns `Δx` and `w`;
/// the torque row scaled by `inv_rg`, the inverse radius of gyration) to the border of `j`,
/// the 2D placeholder's identity, and its couplings to its neighbours ([`couple`]).
pub(crate) fn add_body_blocks<const D: usize, M>(
    sys: &PhSystem<D, M>,
    b: usize,
    blocks: &[[Mat3; 2]; 2],
    (points, dw_rows, inv_rg): (&[Vec<PointStep>], &[Mat3], f64),
    j: &mut BlockJacobian<D>,
) {
    let slots = j.border.slots;
    let at = |s: usize, t: usize| (2 * b + s) * slots + 2 * b + t;
    for (s, row_scale) in [(0, 1.0), (1, inv_rg)] {
        for t in 0..2 {
            j.border.own[at(s, t)] += slot_block::<D>(&(blocks[s][t] * row_scale), s, t);
        }
    }
    if D == 2 {
        j.border.own[at(1, 1)][(1, 1)] = 1.0;
    }
    couple(sys, b, points, dw_rows, inv_rg, j);
}

/// Where the bodies' border of the step's Newton matrix may have nonzero blocks (the blocks
/// [`add_body_blocks`] and [`couple`] fill): each body's two slots with each other, with the
/// nodes next to its attached nodes, and with the slots of the bodies those nodes are fixed
/// to.
pub(crate) fn border_pattern<const D: usize, M>(sys: &PhSystem<D, M>) -> BorderPattern {
    let mut pattern = BorderPattern {
        slots: 2 * sys.bodies.len(),
        ..Default::default()
    };
    for (b, links) in sys.body_links.iter().enumerate() {
        pattern.pairs.push([2 * b, 2 * b + 1]);
        for &(_, other, _) in links.iter().flatten() {
            match sys.attached.get(other).copied().flatten() {
                Some((b2, _)) => {
                    for (s, t) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                        pattern.pairs.push([2 * b + s, 2 * b2 + t]);
                    }
                }
                None => pattern.links.extend([[other, 2 * b], [other, 2 * b + 1]]),
            }
        }
    }
    pattern
}

/// The blocks between body `b`'s rows and the nodes next to its attached nodes (and the
/// bodies those are fixed to), and between those nodes' rows and body `b`'s slots: `points`
/// per body and attachment, `dw_rows[k]` the torque row's `∂/∂R_k` (before the scaling by
/// `inv_rg`, the inverse radius of gyration).
fn couple<const D: usize, M>(
    sys: &PhSystem<D, M>,
    b: usize,
    points: &[Vec<PointStep>],
    dw_rows: &[Mat3],
    inv_rg: f64,
    j: &mut BlockJacobian<D>,
) {
    let eye = Mat3::identity();
    let slots = j.border.slots;
    // The attachments only (a body's buoyancy and waterplane points follow them).
    let n_att = sys.bodies[b].attachments.len();
    for (k, p) in points[b][..n_att].iter().enumerate() {
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
