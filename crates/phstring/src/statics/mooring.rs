//! A rigid body's mooring at a static equilibrium (docs/method.md, "The mooring stiffness
//! and the offset–tension curve"): the restoring stiffness of the strings that hold it,
//! condensed onto its pose, and the curve of restoring force and line tensions against an
//! offset along one of its degrees of freedom.

use std::sync::atomic::AtomicBool;

use nalgebra::{DMatrix, UnitQuaternion};
use thiserror::Error;

use super::{Equilibrium, StaticEquations, StaticsError, StaticsParams, solve_held, static_load};
use crate::body::{Mat3, Vec3, embed, skew};
use crate::linsolve::{BlockJacobian, make_bordered_solver};
use crate::material::StoredEnergy;
use crate::newton::NewtonProblem;
use crate::system::{PhSystem, Vector};

/// Why a mooring analysis failed.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MooringError {
    /// The body index is out of range.
    #[error("there is no rigid body {index}: the model has {count}")]
    NoBody {
        /// The index asked for.
        index: usize,
        /// The number of bodies.
        count: usize,
    },
    /// The degree of freedom is out of range.
    #[error(
        "there is no degree of freedom {index} of a body in {dim}D: there are {count} ({names})"
    )]
    NoDof {
        /// The index asked for.
        index: usize,
        /// The dimension.
        dim: usize,
        /// The number of degrees of freedom.
        count: usize,
        /// Their names.
        names: String,
    },
    /// The tangent of the static equations at the equilibrium could not be factorized, or
    /// the body's condensed compliance could not be inverted: the equilibrium is not held
    /// in every direction (a free direction of a string or of the body).
    #[error(
        "the mooring stiffness of rigid body {index} ('{name}') cannot be formed at this equilibrium: {why}"
    )]
    Singular {
        /// Index of the body.
        index: usize,
        /// Its name.
        name: String,
        /// What failed.
        why: String,
    },
    /// The statics of a displaced body failed.
    #[error("the statics at offset {offset:.6e} of {dof} failed: {source}")]
    Offset {
        /// The offset [m] or turn [rad].
        offset: f64,
        /// The degree of freedom's name.
        dof: &'static str,
        /// Why.
        source: StaticsError,
    },
}

/// The degrees of freedom of a body in `D` dimensions: in 3D `x, y, z` (translations of the
/// centre of mass [m]) and `rx, ry, rz` (small turns about the space axes [rad]); in 2D
/// `x, y, rz`.
pub fn body_dofs(dim: usize) -> &'static [&'static str] {
    if dim == 2 {
        &["x", "y", "rz"]
    } else {
        &["x", "y", "z", "rx", "ry", "rz"]
    }
}

/// The restoring stiffness of a rigid body at a static equilibrium: the derivative of the
/// restoring force and moment by the body's displacement, with every string (and every other
/// body) settling into its new equilibrium, quasi-statically.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyStiffness {
    /// Index of the body.
    pub body: usize,
    /// The degrees of freedom, as [`body_dofs`].
    pub dofs: &'static [&'static str],
    /// `K[(i, j)] = ∂G_i/∂q_j`: `G` the restoring force [N] and moment about the centre of
    /// mass [N·m] (minus the strings' force and moment on the body; space axes), `q_j` a
    /// translation of the centre [m] or a small turn about a space axis [rad]. So the units
    /// are N/m (force by translation), N/rad (force by turn), N (moment by translation) and
    /// N·m/rad (moment by turn). The body's own loads enter only as far as they depend on
    /// its pose (its weight, at the centre of mass, does not). Not symmetric in general: the
    /// strings alone are not in equilibrium with the body's turns.
    pub matrix: DMatrix<f64>,
}

/// The restoring stiffness ([`BodyStiffness`]) of rigid body `body` at the equilibrium `eq`
/// of `sys` (found by [`super::solve_system`] or its kin): the Schur complement of the
/// tangent of the static equations onto the body's pose, the nodes and the other bodies
/// condensed out. Linear solves of the `params.solver` kind, one per degree of freedom.
pub fn body_stiffness<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    eq: &Equilibrium<D>,
    body: usize,
    params: &StaticsParams,
) -> Result<BodyStiffness, MooringError> {
    let count = sys.bodies.len();
    if body >= count {
        return Err(MooringError::NoBody { index: body, count });
    }
    let singular = |why: String| MooringError::Singular {
        index: body,
        name: sys.body_names[body].clone(),
        why,
    };
    if sys.bodies[body].motion.is_some() {
        return Err(singular(
            "its pose is prescribed (a motion), and the statics hold it there: the stiffness \
             of a prescribed body is not available yet (give it no motion for the analysis)"
                .into(),
        ));
    }
    let n = sys.mesh.n_nodes();
    let slots = 2 * count;
    let f = static_load(sys);
    let mut se = StaticEquations::new(sys, &eq.state.r, &f, &eq.state.bodies);
    let zeros = vec![Vector::<D>::zeros(); n + slots];
    let mut res = zeros.clone();
    let mut jac = BlockJacobian::<D>::with_slots(&sys.mesh, slots);
    se.evaluate(&zeros, &mut res, Some(&mut jac))
        .map_err(|e| singular(format!("element {} leaves its law's domain", e.element)))?;
    let mut solver = make_bordered_solver::<D>(params.solver, &sys.mesh, slots)
        .map_err(|e| singular(e.to_string()))?;
    // The body's unknowns: (slot, component); in 2D the turn is the rotation slot's first.
    let turns = if D == 2 { 1 } else { 3 };
    let kept: Vec<(usize, usize)> = (0..D)
        .map(|k| (n + 2 * body, k))
        .chain((0..turns).map(|k| (n + 2 * body + 1, k)))
        .collect();
    // The kept block of the inverse tangent is the inverse of the Schur complement.
    let m = kept.len();
    let mut compliance = DMatrix::<f64>::zeros(m, m);
    for (c, &(slot, k)) in kept.iter().enumerate() {
        let mut x = zeros.clone();
        x[slot][k] = 1.0;
        solver
            .solve(&jac, &mut x)
            .map_err(|e| singular(e.to_string()))?;
        for (r, &(s, i)) in kept.iter().enumerate() {
            compliance[(r, c)] = x[s][i];
        }
    }
    let schur = compliance
        .try_inverse()
        .ok_or_else(|| singular("its condensed compliance is singular".into()))?;
    Ok(BodyStiffness {
        body,
        dofs: body_dofs(D),
        matrix: to_space::<D>(&schur, sys.bodies[body].gyration(), &eq.state.bodies[body]),
    })
}

/// The Schur complement `s` of the static equations onto a body's slots (rows: force [N]
/// and moment in the reference body axes divided by the radius of gyration `rg` [m];
/// columns: displacement [m] and Cayley vector in body axes) in space axes and unscaled.
fn to_space<const D: usize>(
    s: &DMatrix<f64>,
    rg: f64,
    pose: &crate::body::BodyState,
) -> DMatrix<f64> {
    if D == 2 {
        // A turn about z is the Cayley vector's z component in both frames.
        let mut k = s.clone();
        k.row_mut(2).scale_mut(rg);
        return k;
    }
    let r0: Mat3 = pose.orientation.to_rotation_matrix().into_inner();
    // Rows: moment = rg R₀ (row); columns: w = R₀ᵀ δθ.
    let mut rows = DMatrix::<f64>::identity(6, 6);
    rows.view_mut((3, 3), (3, 3)).copy_from(&(r0 * rg));
    let mut cols = DMatrix::<f64>::identity(6, 6);
    cols.view_mut((3, 3), (3, 3)).copy_from(&r0.transpose());
    rows * s * cols
}

/// One point of an offset–tension curve.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetPoint {
    /// The body's offset from its equilibrium pose along the curve's degree of freedom [m]
    /// (a translation) or [rad] (a turn about a space axis through the centre of mass).
    pub offset: f64,
    /// The strings' force on the body [N] (space axes; in 2D `z = 0`).
    pub force: Vec3,
    /// The strings' moment on the body about its centre of mass [N·m].
    pub moment: Vec3,
    /// Per attachment point of the body (in its order), the tension there [N]: the size of
    /// the force the body exerts on its node.
    pub tensions: Vec<f64>,
    /// Per support node (a node with a fixed component that is not on a body), `(node, the
    /// size of its reaction [N])`: the anchors' loads.
    pub anchors: Vec<(usize, f64)>,
    /// Newton iterations of this point's statics.
    pub iterations: usize,
}

/// The offset–tension curve of rigid body `body` about the equilibrium `eq` of `sys`: for
/// each offset of `offsets` (in their order, each statics starting from the previous one's
/// equilibrium), the body is displaced from its equilibrium pose along degree of freedom
/// `dof` (an index into [`body_dofs`]), held there ([`solve_held`]; the other bodies stay
/// free) and the strings settle. `stop` interrupts it between Newton iterations.
pub fn offset_curve<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    eq: &Equilibrium<D>,
    (body, dof): (usize, usize),
    offsets: &[f64],
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Vec<OffsetPoint>, MooringError> {
    let count = sys.bodies.len();
    if body >= count {
        return Err(MooringError::NoBody { index: body, count });
    }
    let names = body_dofs(D);
    if dof >= names.len() {
        return Err(MooringError::NoDof {
            index: dof,
            dim: D,
            count: names.len(),
            names: names.join(", "),
        });
    }
    let mut held = vec![false; count];
    held[body] = true;
    let base = eq.state.bodies[body];
    let mut start = eq.state.clone();
    let mut out = Vec::with_capacity(offsets.len());
    for &offset in offsets {
        let pose = &mut start.bodies[body];
        *pose = base;
        if dof < D {
            pose.position[dof] += offset;
        } else {
            let axis = Vec3::ith_axis(dof - D + if D == 2 { 2 } else { 0 });
            pose.orientation = UnitQuaternion::from_axis_angle(&axis, offset) * base.orientation;
        }
        let found = solve_held(sys, &start, &held, params, stop).map_err(|source| {
            MooringError::Offset {
                offset,
                dof: names[dof],
                source,
            }
        })?;
        out.push(offset_point(sys, &found, body, offset));
        start = found.state;
    }
    Ok(out)
}

/// The [`OffsetPoint`] of body `body` held at `offset` in the equilibrium `found`.
fn offset_point<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    found: &Equilibrium<D>,
    body: usize,
    offset: f64,
) -> OffsetPoint {
    let pose = &found.state.bodies[body];
    let (mut force, mut moment) = (Vec3::zeros(), Vec3::zeros());
    let mut tensions = Vec::new();
    for (node, s) in &sys.bodies[body].attachments {
        // The reaction is the force the body exerts on the node.
        let on_body = -embed(&found.reactions[*node]);
        let arm: Vec3 = pose.orientation * s;
        force += on_body;
        moment += skew(&arm) * on_body;
        tensions.push(on_body.norm());
    }
    let anchors = sys
        .support_nodes()
        .map(|i| (i, found.reactions[i].norm()))
        .collect();
    OffsetPoint {
        offset,
        force,
        moment,
        tensions,
        anchors,
        iterations: found.iterations,
    }
}
