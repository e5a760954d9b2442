//! Rigid bodies in the statics (docs/method.md, "Statics with rigid bodies"): their pose
//! unknowns, their force and moment balances with the tangent, the stability check with
//! them, and the bodies that cannot be held.
//!
//! Body `b` has two slots after the `n` nodes, as in the time step: `n + 2b` holds the
//! displacement `δx` [m] of its centre from a reference pose `(x₀, R₀)` and `n + 2b + 1` the
//! Cayley vector `w` (body axes) of its turn from it: the pose is `x = x₀ + δx`,
//! `R = R₀ cay(w)`, and an attached node sits at `x + R s`. Its rows are the force balance
//! `Σ R_k − W − F_port(0) = 0` [N] and the moment balance about the centre
//! `R₀ᵀ (Σ (R s_k) × R_k − τ_port(0)) = 0` [N·m] (in the reference body axes, divided by the
//! radius of gyration so that it is a force too), `R_k` the attached node's static residual:
//! the force the body must exert on that node.

use faer::Side;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::UnitQuaternion;

use crate::assembly::free_dofs;
use crate::body::{
    BodyState, Mat3, PointStep, Turn, Vec3, cayley_quaternion, embed, project, skew,
};
use crate::body_step::{add_body_blocks, current_at, embed_block, rotation_slot, unknowns};
use crate::linsolve::BlockJacobian;
use crate::system::{PhSystem, Vector};

/// The bodies' part of one evaluation of the static equations.
pub(super) struct BodyTerms<'a, const D: usize> {
    /// Reference poses `(x₀, R₀)` (at rest).
    pub poses: &'a [BodyState],
    /// Per body the wrench port's force [N] and torque [N·m] at `t = 0` (space axes).
    pub ports: &'a [(Vec3, Vec3)],
    /// The bodies' slots of the Newton vector.
    pub slots: &'a [Vector<D>],
    /// Load factor (weights and ports are loads).
    pub lambda: f64,
    /// Pseudo-transient shift [1/s²] and the slots it pulls towards (`anchor`, read only when
    /// `mu > 0`).
    pub mu: f64,
    pub anchor: &'a [Vector<D>],
    /// Shift of the Newton matrix only [1/s²].
    pub jac_shift: f64,
    /// Whether the current's drag on the bodies at rest is in (it is left out where the
    /// potential's stiffness alone is wanted).
    pub drag: bool,
}

/// A point row of a body at rest: the point in body axes [m], its step under the turn, the
/// row `R` [N] (the force the body must exert there, so it feels `−R`) and `∂R/∂r` [N/m].
struct PointRow {
    point: Vec3,
    step: PointStep,
    res: Vec3,
    diag: Mat3,
}

/// The wrench ports' force [N] and torque [N·m] at `t = 0`, per body.
pub(super) fn ports_at_rest<const D: usize, M>(sys: &PhSystem<D, M>) -> Vec<(Vec3, Vec3)> {
    sys.bodies.iter().map(|m| m.wrench_at::<D>(0.0)).collect()
}

/// Writes the attached nodes' displacements from their start `offsets[node] + δx +
/// R₀ (cay(w) − I) s` [m] into `x` (per node), from the reference poses `poses` and the
/// slots `slots`.
pub(super) fn fill<const D: usize, M>(
    sys: &PhSystem<D, M>,
    poses: &[BodyState],
    offsets: &[Vector<D>],
    slots: &[Vector<D>],
    x: &mut [Vector<D>],
) {
    for (b, (model, st)) in sys.bodies.iter().zip(poses).enumerate() {
        let (dx, w) = unknowns(slots, b);
        let turn = Turn::new(&st.orientation, &w);
        for &(node, s) in &model.attachments {
            x[node] = offsets[node] + project(&(dx + turn.point(&s).moved));
        }
    }
}

/// The pose (at rest) of body `b` from its reference pose `pose` and the slots `slots`.
pub(super) fn pose_of<const D: usize>(
    pose: &BodyState,
    slots: &[Vector<D>],
    b: usize,
) -> BodyState {
    let (dx, w) = unknowns(slots, b);
    let q: UnitQuaternion<f64> = pose.orientation * cayley_quaternion(&w);
    BodyState::at_rest(pose.position + dx, q)
}

impl<const D: usize> BodyTerms<'_, D> {
    /// The bodies' rows into `res[n..]` and, with `jac`, their blocks, read from the attached
    /// nodes' rows and blocks before those are masked; returns the squares of the bodies'
    /// force terms (force scale).
    pub(super) fn terms<M>(
        &self,
        sys: &PhSystem<D, M>,
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
    ) -> f64 {
        let n = sys.mesh.n_nodes();
        let turns: Vec<Turn> = self
            .poses
            .iter()
            .enumerate()
            .map(|(b, st)| Turn::new(&st.orientation, &unknowns(self.slots, b).1))
            .collect();
        let points: Vec<Vec<PointStep>> = sys
            .bodies
            .iter()
            .zip(&turns)
            .map(|(m, t)| m.attachments.iter().map(|(_, s)| t.point(s)).collect())
            .collect();
        let mut scale2 = 0.0;
        for (b, model) in sys.bodies.iter().enumerate() {
            if model.motion.is_some() {
                // Held at its pose ([`hold_flagged`] writes its rows).
                continue;
            }
            let (dx, w) = unknowns(self.slots, b);
            let turn = &turns[b];
            let rt = turn.rot.transpose();
            let inv_rg = 1.0 / model.gyration();
            let (f_port, t_port) = self.ports[b];
            let load = (model.weight + f_port) * self.lambda;
            let mut force = -load;
            let mut moment = -t_port * self.lambda;
            scale2 += load.norm_squared() + (moment * inv_rg).norm_squared();
            // Unscaled blocks, the moment row in space axes.
            let mut jb = [[Mat3::zeros(); 2]; 2];
            let mut dw_rows = Vec::with_capacity(points[b].len());
            let attached = model
                .attachments
                .iter()
                .zip(&points[b])
                .map(|(&(node, s), p)| PointRow {
                    point: s,
                    step: *p,
                    res: embed(&res[node]),
                    diag: jac
                        .as_deref()
                        .map_or(Mat3::zeros(), |j| embed_block(&j.diag[node])),
                });
            let water = self.water_rows(sys, model, &self.poses[b], turn, &dx);
            let n_att = model.attachments.len();
            for (k, row) in attached.chain(water).enumerate() {
                let (rk, p) = (row.res, &row.step);
                let arm = turn.rot * row.point + p.moved;
                let m = arm.cross(&rk);
                force += rk;
                moment += m;
                // An attached node's row is counted with the nodes', a water row here.
                if k >= n_att {
                    scale2 += rk.norm_squared();
                }
                scale2 += (m * inv_rg).norm_squared();
                let ak = skew(&arm);
                if k < n_att {
                    dw_rows.push(rt * ak);
                }
                if jac.is_some() {
                    // R_k moves with the point, the arm with w.
                    let kk = row.diag;
                    jb[0][0] += kk;
                    jb[0][1] += kk * p.dw;
                    jb[1][0] += ak * kk;
                    jb[1][1] += ak * kk * p.dw - skew(&rk) * p.dw;
                }
            }
            let mut spin = rt * moment;
            if self.mu > 0.0 {
                let (ax, aw) = unknowns(self.anchor, b);
                let fm = (dx - ax) * (self.mu * model.mass);
                let sm = model.inertia * (w - aw) * self.mu;
                force += fm;
                spin += sm;
                scale2 += fm.norm_squared() + (sm * inv_rg).norm_squared();
            }
            res[n + 2 * b] = project(&force);
            res[n + 2 * b + 1] = rotation_slot::<D>(&(spin * inv_rg));
            let Some(j) = jac.as_deref_mut() else {
                continue;
            };
            let shift = self.mu + self.jac_shift;
            let blocks = [
                [jb[0][0] + Mat3::identity() * (shift * model.mass), jb[0][1]],
                [rt * jb[1][0], rt * jb[1][1] + model.inertia * shift],
            ];
            add_body_blocks(sys, b, &blocks, (&points, &dw_rows, inv_rg), j);
        }
        scale2
    }
}

impl<const D: usize> BodyTerms<'_, D> {
    /// The water's point rows of body `model` at rest at the pose `(x₀ + δx, R₀ cay(w))`
    /// (`pose` the reference, `turn` the turn by `w`, `dx` = `δx`): the buoyancy at the centre
    /// of buoyancy (a load, `R = −λ F_b`), the waterplane's heave restoring at the waterline
    /// point (`R = k z_w e_z`, `∂R/∂r = k e_z e_zᵀ`, the gradient of `½ k z_w²`, not scaled by
    /// `λ`: a stiffness) and, with `drag`, the current's steady drag at the centre of mass
    /// (a load, `F = (c + c_q √(|u|² + δ²)) u` at rest, `u` the current there, with its
    /// derivative by the height where the current varies with it).
    fn water_rows<M>(
        &self,
        sys: &PhSystem<D, M>,
        model: &crate::body::BodyModel,
        pose: &BodyState,
        turn: &Turn,
        dx: &Vec3,
    ) -> Vec<PointRow> {
        let mut rows = Vec::new();
        let lambda = self.lambda;
        if let Some((f, s)) = model.buoyancy {
            rows.push(PointRow {
                point: s,
                step: turn.point(&s),
                res: -f * lambda,
                diag: Mat3::zeros(),
            });
        }
        for &(k, s, up) in &model.waterplane {
            let step = turn.point(&s);
            let z = (pose.position + dx + turn.rot * s + step.moved).dot(&up);
            rows.push(PointRow {
                point: s,
                step,
                res: up * (k * z),
                diag: up * up.transpose() * k,
            });
        }
        if let Some(water) = sys
            .water
            .as_deref()
            .filter(|_| self.drag && model.drag.is_some())
        {
            let at_rest = BodyState::at_rest(pose.position + dx, pose.orientation);
            let flow = current_at::<D>(water, &at_rest, &Vec3::zeros());
            // At rest (a step of infinite length with no increment), as for the points' drag:
            // the position enters the mid-step height with weight ½.
            let (f, df, _, _) =
                model.drag_step(f64::INFINITY, &Vec3::zeros(), (&flow.0, &flow.1, &flow.2));
            let centre = Vec3::zeros();
            rows.push(PointRow {
                point: centre,
                step: turn.point(&centre),
                res: -f * lambda,
                diag: -df * (2.0 * lambda),
            });
        }
        rows
    }
}

/// Whether the tangent `j` of the static equations with bodies, evaluated at the reference
/// pose (`w = 0`) of an equilibrium, is positive definite on the free components and the
/// bodies' slots: there the moment row in body axes is the gradient of the potential, so `j`
/// with its rotation columns divided by the radius of gyration (as its rows are) is the
/// potential's Hessian, symmetric. Checked by a sparse Cholesky factorization.
pub(super) fn positive_definite<const D: usize, M>(
    sys: &PhSystem<D, M>,
    j: &BlockJacobian<D>,
) -> bool {
    let (_, n_free) = free_dofs(sys);
    let total = n_free + j.border.slots * D;
    let t = hessian_triplets(sys, j, |s, k| Some(n_free + s * D + k));
    match SparseColMat::try_new_from_triplets(total, total, &t) {
        Ok(k) => k.sp_cholesky(Side::Lower).is_ok(),
        Err(_) => false,
    }
}

/// The triplets of the potential's Hessian of [`positive_definite`] on the free components
/// (numbered by [`free_dofs`]) and the slot components numbered by `slot_dof(slot,
/// component)` (`None`: left out), the rotation columns divided by the radius of gyration.
pub(super) fn hessian_triplets<const D: usize, M>(
    sys: &PhSystem<D, M>,
    j: &BlockJacobian<D>,
    slot_dof: impl Fn(usize, usize) -> Option<usize>,
) -> Vec<Triplet<usize, usize, f64>> {
    let (dof, _) = free_dofs(sys);
    let slots = j.border.slots;
    let col_scale = |s: usize| {
        if s % 2 == 1 {
            1.0 / sys.bodies[s / 2].gyration()
        } else {
            1.0
        }
    };
    let mut t = Vec::new();
    let mut push = |r: Option<usize>, c: Option<usize>, v: f64| {
        if let (Some(r), Some(c)) = (r, c)
            && v != 0.0
        {
            t.push(Triplet::new(r, c, v));
        }
    };
    let node = |i: usize, k: usize| dof[i * D + k];
    for (i, d) in j.diag.iter().enumerate() {
        for (k, m) in (0..D).flat_map(|k| (0..D).map(move |m| (k, m))) {
            push(node(i, k), node(i, m), d[(k, m)]);
        }
    }
    for (&[a, b], off) in sys.mesh.elements().iter().zip(&j.off) {
        for (k, m) in (0..D).flat_map(|k| (0..D).map(move |m| (k, m))) {
            push(node(a, k), node(b, m), off[0][(k, m)]);
            push(node(b, k), node(a, m), off[1][(k, m)]);
        }
    }
    for s in 0..slots {
        for c in 0..slots {
            let blk = &j.border.own[s * slots + c];
            for (k, m) in (0..D).flat_map(|k| (0..D).map(move |m| (k, m))) {
                push(slot_dof(s, k), slot_dof(c, m), blk[(k, m)] * col_scale(c));
            }
        }
    }
    for &(i, s, row, col) in &j.border.links {
        for (k, m) in (0..D).flat_map(|k| (0..D).map(move |m| (k, m))) {
            push(slot_dof(s, k), node(i, m), row[(k, m)]);
            push(node(i, k), slot_dof(s, m), col[(k, m)] * col_scale(s));
        }
    }
    t
}

/// The start poses `poses` with each body that a prescribed motion moves at its pose at
/// `t = 0` (at rest), where the statics hold it.
pub(super) fn held_poses<const D: usize, M>(
    sys: &PhSystem<D, M>,
    poses: &[BodyState],
) -> Vec<BodyState> {
    sys.bodies
        .iter()
        .zip(poses)
        .map(|(m, st)| match &m.motion {
            Some(motion) => {
                let (x, q) = (motion.pose)(0.0);
                BodyState::at_rest(x, q)
            }
            None => *st,
        })
        .collect()
}

/// Checks start poses `poses` (one per body): finite, and in 2D in the plane `z = 0` turned
/// about `z` only.
pub(super) fn check_poses<const D: usize, M>(
    sys: &PhSystem<D, M>,
    poses: &[BodyState],
) -> Result<(), crate::error::SetupError> {
    for (b, (st, name)) in poses.iter().zip(&sys.body_names).enumerate() {
        let q = st.orientation.quaternion();
        let finite = st
            .position
            .iter()
            .chain(q.coords.iter())
            .all(|x| x.is_finite());
        let planar = D != 2 || (st.position.z == 0.0 && q.i == 0.0 && q.j == 0.0);
        if !(finite && planar) {
            return Err(crate::error::SetupError::Body {
                index: b,
                name: name.clone(),
                problem: format!(
                    "start pose at {:?} with orientation {:?} is not finite{}",
                    st.position.as_slice(),
                    q.coords.as_slice(),
                    if D == 2 {
                        " or not in the plane z = 0 turned about z"
                    } else {
                        ""
                    }
                ),
            });
        }
    }
    Ok(())
}

/// The first body not flagged in `held` whose attachment points, with the points where its
/// water acts at an offset (the centre of buoyancy of a body with a volume, the waterline
/// point of a floater), all lie on one line through its centre of mass (in 3D; in 2D, all at
/// the centre): it can turn about that line with nothing resisting, so no rest state holds
/// that turn. Returns `(index, name, the line's direction in body axes)` (`x` when every
/// point is at the centre).
pub(super) fn free_spin<const D: usize, M>(
    sys: &PhSystem<D, M>,
    held: &[bool],
) -> Option<(usize, String, [f64; 3])> {
    let free =
        |b: &usize| !held.get(*b).copied().unwrap_or(false) && sys.bodies[*b].motion.is_none();
    sys.bodies
        .iter()
        .enumerate()
        .filter(|(b, _)| free(b))
        .find_map(|(b, m)| {
            let mut points: Vec<Vec3> = m.attachments.iter().map(|(_, s)| *s).collect();
            points.extend(m.buoyancy.map(|(_, at)| at));
            points.extend(m.waterplane.iter().map(|(_, at, _)| *at));
            let far = points
                .iter()
                .copied()
                .max_by(|a, c| a.norm().total_cmp(&c.norm()))?;
            let length = far.norm();
            let axis = if length > 0.0 {
                far / length
            } else {
                Vec3::x()
            };
            let on_line = points
                .iter()
                .all(|s| s.cross(&axis).norm() <= 1e-9 * length);
            let free = if D == 3 { on_line } else { length == 0.0 };
            free.then(|| (b, sys.body_names[b].clone(), [axis.x, axis.y, axis.z]))
        })
}

/// The first body fixed to no node and not flagged in `held`: `(index, name)`. Nothing
/// holds it (its tangent is singular), so the statics refuse it.
pub(super) fn loose_body<const D: usize, M>(
    sys: &PhSystem<D, M>,
    held: &[bool],
) -> Option<(usize, String)> {
    sys.bodies
        .iter()
        .zip(&sys.body_names)
        .enumerate()
        .find(|(b, (m, _))| {
            m.attachments.is_empty()
                && m.motion.is_none()
                && !held.get(*b).copied().unwrap_or(false)
        })
        .map(|(b, (_, name))| (b, name.clone()))
}

/// Holds the bodies flagged in `held` (those a prescribed motion holds at its pose at
/// `t = 0`, and those a caller holds) at their reference poses: their rows become their
/// slots `slots` (so that Newton keeps them at zero) and their blocks the identity,
/// decoupled from the nodes and the other bodies (a held slot never moves, so the blocks
/// that multiply it do not matter, and the stability check reads one triangle).
pub(super) fn hold_flagged<const D: usize>(
    held: &[bool],
    n: usize,
    slots: &[Vector<D>],
    res: &mut [Vector<D>],
    jac: Option<&mut BlockJacobian<D>>,
) {
    let is_held = |s: usize| held.get(s / 2).copied().unwrap_or(false);
    for s in (0..slots.len()).filter(|&s| is_held(s)) {
        res[n + s] = slots[s];
    }
    let Some(j) = jac else {
        return;
    };
    let m = j.border.slots;
    for s in 0..m {
        for t in 0..m {
            if is_held(s) || is_held(t) {
                j.border.own[s * m + t] = if s == t {
                    crate::linsolve::Block::<D>::identity()
                } else {
                    crate::linsolve::Block::<D>::zeros()
                };
            }
        }
    }
    for link in j.border.links.iter_mut().filter(|l| is_held(l.1)) {
        link.2.fill(0.0);
        link.3.fill(0.0);
    }
}

/// Checks that the feedback law of each body not in `held` exerts no wrench at rest at the
/// equilibrium `eq` (its reference at `t = 0`, zero velocities): the force within the
/// equilibrium's tolerance, the torque within it times the body's radius of gyration (the
/// scaling of the torque rows). Statics leave the laws out (docs/method.md §22).
pub(crate) fn check_feedback_at_rest<const D: usize, M>(
    sys: &PhSystem<D, M>,
    eq: &crate::statics::Equilibrium<D>,
    held: &[bool],
) -> Result<(), crate::statics::StaticsError> {
    let tol = eq.tolerance.max(1e-9 * eq.force_scale);
    for (b, (model, st)) in sys.bodies.iter().zip(&eq.state.bodies).enumerate() {
        if held.get(b).copied().unwrap_or(false) {
            continue;
        }
        let Some(law) = &model.feedback else {
            continue;
        };
        let targets = [Some(law.target(0.0))];
        let zero = Vec3::zeros();
        let Some(w) =
            crate::body_step::feedback_at::<D>(model, &targets, 0, st, 1.0, (&zero, &zero))
        else {
            continue;
        };
        let (force, torque) = (w.force.norm(), w.torque.norm());
        // NaN fails too.
        if !(force <= tol && torque <= tol * model.gyration()) {
            return Err(crate::statics::StaticsError::BodyFeedback {
                index: b,
                name: sys.body_names[b].clone(),
                force,
                torque,
            });
        }
    }
    Ok(())
}
