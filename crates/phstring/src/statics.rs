//! Static equilibrium (docs/method.md §15): the rest state `∇V̂(r) = F` of a string or
//! network under its loads at `t = 0`.
//!
//! The equations are the dynamic step's without inertia: for every free position component
//! `R(r) = K(r) S(C(r)) − F_b − F_N(0) = 0` with `C_e = |r'_e|²` and `S = 2 W'(C)`, the same
//! element laws as the time step. Fixed components and prescribed motions stay at their
//! `t = 0` positions; there the residual is the support reaction (the force the support
//! exerts on the string, as in the dynamic ports).
//!
//! Four paths, tried in this order, each with Newton's method, the line search and the
//! linear solvers of the time step:
//! 0. **Catenary first guess** (`guess.rs`): where every string hangs between two supports,
//!    Newton at the full load from the strings placed on their elastic catenaries (with
//!    their grounded parts on the seabed).
//! 1. **Newton** at the full load, from the scenario's initial positions.
//! 2. **Load continuation**: the load `λ F`, `λ` from 0 to 1 in steps that halve on failure
//!    and grow after success.
//! 3. **Pseudo-transient continuation**: proximal steps
//!    `μ M_ρ (r − r_k) + R(r) = 0` with the mass matrix as metric and the shift `μ` [1/s²]
//!    lowered after easy steps. Each such step lowers `V̂` (it minimizes
//!    `V̂(r) − r·F + ½ μ |r − r_k|²_M`), and the shifted matrix stays non-singular where
//!    elements are slack (tension-only laws) or compressed. It ends when the unshifted
//!    residual meets the tolerance.
//!
//! Which path succeeded is reported in [`Equilibrium::path`], what became of the first guess
//! in [`Equilibrium::guess`].
//!
//! **Rigid bodies** (docs/method.md, "Statics with rigid bodies"; `bodies.rs`): each body's
//! pose joins the unknowns (two slots after the nodes, as in the time step: the centre's
//! displacement and the Cayley vector of the turn from a reference pose), with its force and
//! moment balance as rows; the nodes fixed to it follow it exactly and their residual is the
//! force it exerts on them. All four paths take bodies: the catenary guess treats a body's
//! points as fixed ends at the body's start pose (the body is then free in the Newton solve
//! from there), the pseudo-transient shift gives a body its mass and inertia, and each
//! pseudo-time step measures the turns from the pose reached. A body fixed to no node is
//! refused ([`StaticsError::LooseBody`]), and so is one whose points all lie on a line
//! through its centre ([`StaticsError::FreeSpin`]); the stability check includes the
//! bodies' slots.

mod bodies;
mod guess;
mod mooring;

pub use guess::catenary_guess;
pub use mooring::{
    BodyStiffness, MooringError, OffsetPoint, body_dofs, body_stiffness, offset_curve,
};

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::SMatrix;
use thiserror::Error;

use crate::assembly::{element_tangent, mask_fixed, positive_definite, tangent_blocks};
use crate::body::{BodyState, Vec3};
use crate::error::SetupError;
use crate::linsolve::{BlockJacobian, SolverKind, make_bordered_solver};
use crate::material::StoredEnergy;
use crate::newton::{self, NewtonError, NewtonParams, NewtonProblem, NewtonWorkspace};
use crate::system::{Energies, Law, Network, PhSystem, State, Vector, element_mass};
use crate::water::WaterModel;

/// Parameters of the equilibrium solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticsParams {
    /// Newton's method (tolerances as in a time step: `‖R‖ ≤ max(tol, rtol·F)` with `F` the
    /// force scale of the loads and internal forces, or the round-off floor).
    pub newton: NewtonParams,
    /// Linear solver.
    pub solver: SolverKind,
    /// Most load steps of the continuation (path 2).
    pub max_load_steps: usize,
    /// Most pseudo-time steps (path 3).
    pub max_pseudo_steps: usize,
    /// Try the catenary first guess (path 0) where it applies. Default `true`.
    pub first_guess: bool,
    /// The equilibrium of the open-loop plant: feedback laws are left out without the check
    /// that they vanish at rest (for the linear model and modes, whose feedback ports are
    /// open inputs). Default `false`.
    pub open_loop: bool,
}

impl Default for StaticsParams {
    fn default() -> Self {
        Self {
            newton: NewtonParams {
                max_iter: 40,
                ..NewtonParams::default()
            },
            solver: SolverKind::Auto,
            max_load_steps: 200,
            max_pseudo_steps: 2000,
            first_guess: true,
            open_loop: false,
        }
    }
}

/// How the equilibrium was reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StaticsPath {
    /// Newton's method at the full load from the catenary first guess.
    CatenaryGuess,
    /// Newton's method at the full load.
    Newton,
    /// Load continuation in `steps` load steps.
    LoadContinuation {
        /// Accepted load steps.
        steps: usize,
    },
    /// Pseudo-transient continuation in `steps` pseudo-time steps.
    PseudoTransient {
        /// Accepted pseudo-time steps.
        steps: usize,
    },
}

impl StaticsPath {
    /// Short name: `catenary_guess`, `newton`, `load_continuation` or `pseudo_transient`.
    pub fn name(self) -> &'static str {
        match self {
            StaticsPath::CatenaryGuess => "catenary_guess",
            StaticsPath::Newton => "newton",
            StaticsPath::LoadContinuation { .. } => "load_continuation",
            StaticsPath::PseudoTransient { .. } => "pseudo_transient",
        }
    }
    /// Steps of the path (1 for Newton, from the guess or the start).
    pub fn steps(self) -> usize {
        match self {
            StaticsPath::CatenaryGuess | StaticsPath::Newton => 1,
            StaticsPath::LoadContinuation { steps } | StaticsPath::PseudoTransient { steps } => {
                steps
            }
        }
    }
}

/// What became of the catenary first guess (docs/method.md §15).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FirstGuess {
    /// Newton from the guess reached the equilibrium ([`StaticsPath::CatenaryGuess`]).
    Used,
    /// The guess was placed but Newton from it failed, for the reason given; the other
    /// paths started from the initial positions.
    Failed(String),
    /// The guess does not apply to the problem, for the reason given (e.g. a string with a
    /// free end).
    NotApplicable(String),
}

impl FirstGuess {
    /// `used`, `failed: WHY` or `not applicable: WHY`, for reports.
    pub fn describe(&self) -> String {
        match self {
            FirstGuess::Used => "used".into(),
            FirstGuess::Failed(why) => format!("failed: {why}"),
            FirstGuess::NotApplicable(why) => format!("not applicable: {why}"),
        }
    }
}

/// A static equilibrium.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium<const D: usize> {
    /// The rest state: equilibrium positions [m], zero velocities, `C_e = |r'_e|²`, and the
    /// rigid bodies' equilibrium poses at rest (`state.bodies`, in the network's body order),
    /// so that a run can start from it ([`crate::Simulation::from_system`]).
    pub state: State<D>,
    /// Per node, the force [N] that the supports (fixed components and prescribed motions)
    /// exert on the string; at a node fixed to a rigid body, the force the body exerts on it;
    /// zero at free components.
    pub reactions: Vec<Vector<D>>,
    /// Euclidean norm of the residual over the free components [N].
    pub residual: f64,
    /// The tolerance it met [N] (or the round-off floor, see `at_roundoff`).
    pub tolerance: f64,
    /// Force scale `F` of the equilibrium [N]: root-sum-square of the loads and the internal
    /// nodal forces.
    pub force_scale: f64,
    /// The residual met the round-off floor rather than the tolerance.
    pub at_roundoff: bool,
    /// Path that reached it.
    pub path: StaticsPath,
    /// Newton iterations (linear solves) over all paths, failed attempts included.
    pub iterations: usize,
    /// What became of the catenary first guess.
    pub guess: FirstGuess,
    /// Energies at the equilibrium [J] (kinetic energy 0).
    pub energies: Energies,
    /// The tangent stiffness is positive definite on the free components: a stable
    /// equilibrium (Newton and the load continuation accept only stable ones; the
    /// pseudo-transient path lowers `V̂` and so ends at a minimum unless it is degenerate).
    pub stable: bool,
}

/// Why no equilibrium was found.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum StaticsError {
    /// The problem definition is invalid.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// A rigid-body translation is free and the loads push along it.
    #[error(
        "no equilibrium: the structure is under-constrained, free to translate along {axis} (no node is held in {axis}), and the net load along {axis} is {net:.6e} N; hold a node in {axis} or remove that load"
    )]
    UnderConstrained {
        /// Axis name, `x`, `y` or `z`.
        axis: &'static str,
        /// Net load along it [N].
        net: f64,
    },
    /// Every path failed.
    #[error("{0}")]
    NotFound(Box<NotFound>),
    /// A rigid body is fixed to no node, so nothing holds it.
    #[error(
        "no equilibrium: rigid body {index} ('{name}') is fixed to no node, so nothing holds it; attach strings to it"
    )]
    LooseBody {
        /// Index of the body.
        index: usize,
        /// Its name.
        name: String,
    },
    /// A rigid body's attachment points (and the points where its water acts at an offset:
    /// its centre of buoyancy, its waterline point) all lie on one line through its centre
    /// of mass, so it can turn about that line with nothing to resist (a block on a single
    /// string in 3D; in 2D, every point at the centre).
    #[error(
        "no equilibrium: rigid body {index} ('{name}') has all its attachment points on one line through its centre of mass (direction {axis:?} in body axes), so nothing holds its turn about that line; attach a string off that line (or, in water, give it a centre of buoyancy off that line)"
    )]
    FreeSpin {
        /// Index of the body.
        index: usize,
        /// Its name.
        name: String,
        /// The line's direction in body axes (unit vector).
        axis: [f64; 3],
    },
    /// The stop flag was set.
    #[error("interrupted")]
    Interrupted,
    /// A feedback port pushes at the equilibrium found without it (statics leave feedback
    /// laws out: they are taken at rest, `F(0, r, 0)`, and must vanish there).
    #[error(
        "feedback port {index} (the {ordinal} control) at node {node} pushes with {force:.6e} N at rest at the equilibrium found without the feedback: statics leave feedback laws out, so at t = 0 its reference must be at that equilibrium and its reference velocity 0", ordinal = ordinal(*index + 1)
    )]
    Feedback {
        /// Index of the feedback port.
        index: usize,
        /// Its node.
        node: usize,
        /// Magnitude of its force on the free components there [N].
        force: f64,
    },
    /// A rigid body's feedback law pushes at the equilibrium found without it (statics leave
    /// feedback laws out, as for nodes: taken at rest at `t = 0`, it must vanish there).
    #[error(
        "rigid body {index} ('{name}') has a feedback law that pushes with {force:.6e} N and turns with {torque:.6e} N·m at rest at the equilibrium found without it: statics leave feedback laws out, so at t = 0 its reference pose must be the equilibrium pose and its reference velocities 0 (or use proportional gains 0: damping injection)"
    )]
    BodyFeedback {
        /// Index of the body.
        index: usize,
        /// Its name.
        name: String,
        /// Magnitude of the law's force at rest [N].
        force: f64,
        /// Magnitude of the law's torque at rest [N·m].
        torque: f64,
    },
}

/// What every path of a failed equilibrium solve ended with.
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "no equilibrium found: Newton at the full load failed ({newton}); the load continuation failed at load step {load_step}, load factor {lambda:.6} of the full load ({continuation}); the pseudo-transient continuation failed after {pseudo_steps} steps ({pseudo}). Largest strain C = {c_max:.6e} at element {element}{hint}"
)]
pub struct NotFound {
    /// Why Newton at the full load failed.
    pub newton: String,
    /// Load step of the continuation that failed (1-based).
    pub load_step: usize,
    /// Last load factor reached by the continuation.
    pub lambda: f64,
    /// Why that step failed.
    pub continuation: String,
    /// Pseudo-time steps taken.
    pub pseudo_steps: usize,
    /// Why the pseudo-transient continuation stopped.
    pub pseudo: String,
    /// Largest strain of the last pseudo-transient iterate.
    pub c_max: f64,
    /// Its element.
    pub element: usize,
    /// What may be wrong, e.g. free rigid-body motions; empty if nothing is known.
    pub hint: String,
}

/// The static equations `R(u) = K S − λ F + μ M (u − u_k)` in the displacement `u = r − r₀`
/// from the starting positions `r₀`.
struct StaticEquations<'a, const D: usize, M> {
    sys: &'a PhSystem<D, M>,
    r0: &'a [Vector<D>],
    /// Full load `F = F_b + F_N(0)` per node [N].
    f_ext: &'a [Vector<D>],
    /// Load factor.
    lambda: f64,
    /// Pseudo-transient shift [1/s²] and its anchor `u_k`.
    mu: f64,
    anchor: Vec<Vector<D>>,
    /// A shift `ε M_ρ` [kg/s²] of the Newton matrix only (not of the residual): it keeps the
    /// matrix regular where a free direction has no stiffness yet (a stress-free start),
    /// without moving the solution.
    jac_shift: f64,
    /// Strings carry no compression (an element with `C < 1` is slack) while set.
    release: bool,
    /// The current's drag is left out while cleared (a stability check judges the
    /// potential's stiffness alone: the drag at rest is no potential, its tangent not
    /// symmetric).
    drag: bool,
    /// Reactions of the last full evaluation [N].
    reaction: Vec<Vector<D>>,
    scale: f64,
    strain_scale: f64,
    /// The rigid bodies' reference poses (the Newton vector's slots hold their displacement
    /// and Cayley vector from them) and their wrench ports at `t = 0` (force [N], torque
    /// [N·m]); empty without bodies.
    poses: Vec<BodyState>,
    ports: Vec<(Vec3, Vec3)>,
    /// Per node fixed to a body, its reference point's displacement from `r₀` [m] (zero until
    /// the reference poses move, see [`Self::rebase`]).
    offsets: Vec<Vector<D>>,
    /// With bodies: the nodes' displacements with the attached nodes' filled in (workspace).
    nodes_x: Vec<Vector<D>>,
    /// Per body, whether it is held at its reference pose (its slots stay zero and its force
    /// and moment balance is left out): a body with a prescribed motion always, others as
    /// a caller asks ([`Self::hold`]).
    held: Vec<bool>,
}

/// A strain outside the law's domain during the equilibrium iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Inadmissible {
    element: usize,
    c: f64,
}

impl<const D: usize, M: StoredEnergy> NewtonProblem<D> for StaticEquations<'_, D, M> {
    type Error = Inadmissible;

    fn evaluate(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
    ) -> Result<(), Inadmissible> {
        let sys = self.sys;
        let n = sys.mesh.n_nodes();
        let (scale2, strain2) = if sys.bodies.is_empty() {
            self.node_terms(x, res, jac.as_deref_mut())?
        } else {
            let mut xt = std::mem::take(&mut self.nodes_x);
            xt.clear();
            xt.extend_from_slice(&x[..n]);
            bodies::fill(sys, &self.poses, &self.offsets, &x[n..], &mut xt);
            let out = self.node_terms(&xt, res, jac.as_deref_mut());
            self.nodes_x = xt;
            let (s2, k2) = out?;
            // The bodies' rows take the attached nodes' rows before those are masked.
            let terms = bodies::BodyTerms {
                poses: &self.poses,
                ports: &self.ports,
                slots: &x[n..],
                lambda: self.lambda,
                mu: self.mu,
                anchor: if self.mu > 0.0 {
                    &self.anchor[n..]
                } else {
                    &[]
                },
                jac_shift: self.jac_shift,
                drag: self.drag,
            };
            let s2 = s2 + terms.terms(sys, res, jac.as_deref_mut());
            bodies::hold_flagged(&self.held, n, &x[n..], res, jac.as_deref_mut());
            (s2, k2)
        };
        for &i in &sys.constrained {
            for k in 0..D {
                if !sys.free[i][k] {
                    self.reaction[i][k] = res[i][k];
                    res[i][k] = 0.0;
                }
            }
        }
        if let Some(j) = jac {
            mask_fixed(sys, j);
        }
        self.scale = scale2.sqrt();
        self.strain_scale = strain2.sqrt();
        Ok(())
    }

    fn force_scale(&self) -> f64 {
        self.scale
    }

    fn strain_scale(&self) -> f64 {
        self.strain_scale
    }
}

impl<'a, const D: usize, M: StoredEnergy> StaticEquations<'a, D, M> {
    /// The equations at the full load `f_ext` [N] from node positions `r0` [m] and the
    /// bodies' reference poses `poses` (attached nodes of `r0` at their points), without
    /// shifts.
    fn new(
        sys: &'a PhSystem<D, M>,
        r0: &'a [Vector<D>],
        f_ext: &'a [Vector<D>],
        poses: &[BodyState],
    ) -> Self {
        let n = sys.mesh.n_nodes();
        Self {
            sys,
            r0,
            f_ext,
            lambda: 1.0,
            mu: 0.0,
            anchor: vec![Vector::zeros(); n + 2 * sys.bodies.len()],
            jac_shift: 0.0,
            release: false,
            drag: true,
            reaction: vec![Vector::zeros(); n],
            scale: 0.0,
            strain_scale: 0.0,
            poses: poses.to_vec(),
            offsets: vec![Vector::zeros(); if sys.bodies.is_empty() { 0 } else { n }],
            ports: bodies::ports_at_rest(sys),
            nodes_x: Vec::with_capacity(if sys.bodies.is_empty() { 0 } else { n }),
            held: sys.bodies.iter().map(|m| m.motion.is_some()).collect(),
        }
    }

    /// Also holds the bodies flagged in `held` (one flag per body; an empty slice holds
    /// none).
    fn hold(&mut self, held: &[bool]) {
        for (h, &x) in self.held.iter_mut().zip(held) {
            *h |= x;
        }
    }

    /// The Newton vector's length: the nodes, then two slots per body.
    fn unknowns(&self) -> usize {
        self.sys.mesh.n_nodes() + 2 * self.sys.bodies.len()
    }

    /// Sets the pseudo-transient anchor to `u` (the attached nodes' displacements filled in
    /// from the bodies' slots).
    fn set_anchor(&mut self, u: &[Vector<D>]) {
        self.anchor.copy_from_slice(u);
        if !self.sys.bodies.is_empty() {
            let (nodes, slots) = self.anchor.split_at_mut(self.sys.mesh.n_nodes());
            bodies::fill(self.sys, &self.poses, &self.offsets, slots, nodes);
        }
    }

    /// The node positions [m] at the displacement `u` (attached nodes at their body points).
    fn positions(&self, u: &[Vector<D>]) -> Vec<Vector<D>> {
        let n = self.sys.mesh.n_nodes();
        let mut x = u[..n].to_vec();
        if !self.sys.bodies.is_empty() {
            bodies::fill(self.sys, &self.poses, &self.offsets, &u[n..], &mut x);
        }
        self.r0.iter().zip(&x).map(|(a, b)| a + b).collect()
    }

    /// Makes the bodies' poses at the displacement `u` their reference poses and zeroes their
    /// slots in `u` (the positions stay): a turn is then measured from the pose reached, so
    /// that the Cayley vector stays away from its singularity at a half turn.
    fn rebase(&mut self, u: &mut [Vector<D>]) {
        if self.poses.is_empty() {
            return;
        }
        let n = self.sys.mesh.n_nodes();
        let mut x = u[..n].to_vec();
        bodies::fill(self.sys, &self.poses, &self.offsets, &u[n..], &mut x);
        for model in &self.sys.bodies {
            for &(node, _) in &model.attachments {
                self.offsets[node] = x[node];
            }
        }
        self.poses = self.body_poses(u);
        u[n..].iter_mut().for_each(|v| *v = Vector::zeros());
    }

    /// Back to the reference poses `poses` and no offsets.
    fn reset_poses(&mut self, poses: &[BodyState]) {
        self.poses.copy_from_slice(poses);
        self.offsets.iter_mut().for_each(|v| *v = Vector::zeros());
    }

    /// The bodies' poses (at rest) at the displacement `u`.
    fn body_poses(&self, u: &[Vector<D>]) -> Vec<BodyState> {
        let slots = &u[self.sys.mesh.n_nodes()..];
        (0..self.poses.len())
            .map(|b| bodies::pose_of(&self.poses[b], slots, b))
            .collect()
    }

    /// The nodes' rows (and, with `jac`, blocks) at the displacements `x` (attached nodes'
    /// included), before the fixed components are masked: loads, elements, the shifts and
    /// the water; returns the squares of the force terms and of the strain terms.
    fn node_terms(
        &self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
    ) -> Result<(f64, f64), Inadmissible> {
        let sys = self.sys;
        for (r, f) in res.iter_mut().zip(self.f_ext) {
            *r = -f * self.lambda;
        }
        let mut scale2 = self.lambda * self.lambda * sq_sum(self.f_ext);
        let mut strain2 = 0.0;
        if let Some(j) = jac.as_deref_mut() {
            j.clear();
        }
        for grp in &sys.groups {
            let els = grp.elements.clone();
            match &grp.law {
                Law::String(m) => {
                    let scales = (&mut scale2, &mut strain2);
                    self.elements(m, self.release, els, x, res, jac.as_deref_mut(), scales)?
                }
                Law::Spring(s) => {
                    let scales = (&mut scale2, &mut strain2);
                    self.elements(s, false, els, x, res, jac.as_deref_mut(), scales)?
                }
            }
            if self.mu > 0.0 || self.jac_shift > 0.0 {
                let eye = SMatrix::<f64, D, D>::identity();
                let shift = self.mu + self.jac_shift;
                for e in grp.elements.clone() {
                    let [a, b] = sys.mesh.elements()[e];
                    let (md, mo) = element_mass(grp.mass, grp.rho_a, sys.mesh.lengths()[e]);
                    if self.mu > 0.0 {
                        let (da, db) = (x[a] - self.anchor[a], x[b] - self.anchor[b]);
                        let fa = (da * md + db * mo) * self.mu;
                        let fb = (db * md + da * mo) * self.mu;
                        res[a] += fa;
                        res[b] += fb;
                        scale2 += fa.norm_squared() + fb.norm_squared();
                    }
                    if let Some(j) = jac.as_deref_mut() {
                        j.diag[a] += eye * (shift * md);
                        j.diag[b] += eye * (shift * md);
                        j.off[e][0] += eye * (shift * mo);
                        j.off[e][1] += eye * (shift * mo);
                    }
                }
            }
        }
        if let Some(w) = sys.water.as_deref() {
            scale2 += self.water_terms(w, x, res, jac.as_deref_mut());
        }
        if self.mu > 0.0 || self.jac_shift > 0.0 {
            let shift = self.mu + self.jac_shift;
            for &(i, m) in &sys.point_mass {
                if self.mu > 0.0 {
                    let fi = (x[i] - self.anchor[i]) * (self.mu * m);
                    res[i] += fi;
                    scale2 += fi.norm_squared();
                }
                if let Some(j) = jac.as_deref_mut() {
                    j.diag[i] += SMatrix::<f64, D, D>::identity() * (shift * m);
                }
            }
        }
        Ok((scale2, strain2))
    }
}

fn sq_sum<const D: usize>(v: &[Vector<D>]) -> f64 {
    v.iter().map(|f| f.norm_squared()).sum()
}

impl<const D: usize, M: StoredEnergy> StaticEquations<'_, D, M> {
    /// The water at rest (docs/method.md §21): buoyancy and the current's drag (loads,
    /// scaled by `λ`) and the seabed contact, at `r₀ + x`; returns the squares of the forces.
    fn water_terms(
        &self,
        w: &WaterModel<D>,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
    ) -> f64 {
        let lambda = self.lambda;
        let mut scale2 = 0.0;
        for node in &w.nodes {
            let i = node.node;
            let r = self.r0[i] + x[i];
            let (mut f, mut k) = w.static_potential(node, &r, lambda);
            if node.drag > 0.0 && self.drag {
                let (fd, kd) = w.static_point_drag(node, &r);
                f += fd * lambda;
                k += kd * lambda;
            }
            res[i] += f;
            scale2 += f.norm_squared();
            if let Some(j) = jac.as_deref_mut() {
                j.diag[i] += k;
            }
        }
        if w.still || !self.drag {
            return scale2;
        }
        for el in &w.elements {
            let [a, b] = self.sys.mesh.elements()[el.e];
            let (ra, rb) = (self.r0[a] + x[a], self.r0[b] + x[b]);
            let l = self.sys.mesh.lengths()[el.e];
            let (f, [ja, jb]) = w.static_element_drag(el, (&ra, &rb), l, jac.is_some());
            let half = f * (0.5 * lambda);
            res[a] -= half;
            res[b] -= half;
            scale2 += 2.0 * half.norm_squared();
            if let Some(j) = jac.as_deref_mut() {
                j.diag[a] += ja * lambda;
                j.diag[b] += jb * lambda;
                j.off[el.e][0] += jb * lambda;
                j.off[el.e][1] += ja * lambda;
            }
        }
        scale2
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn elements<L: StoredEnergy>(
        &self,
        law: &L,
        release: bool,
        els: std::ops::Range<usize>,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
        (scale2, strain2): (&mut f64, &mut f64),
    ) -> Result<(), Inadmissible> {
        let sys = self.sys;
        for e in els {
            let [a, b] = sys.mesh.elements()[e];
            let l = sys.mesh.lengths()[e];
            // Relative positions from the displacement, without forming r = r₀ + u first.
            let dr = (self.r0[b] - self.r0[a]) + (x[b] - x[a]);
            let rp = dr / l;
            let c = rp.norm_squared();
            let slack = release && c < 1.0;
            if !slack && !law.admissible(c) {
                return Err(Inadmissible { element: e, c });
            }
            let (dw, d2w) = if slack {
                (0.0, 0.0)
            } else {
                (law.dw(c), law.d2w(c))
            };
            let f = rp * (2.0 * dw);
            res[a] -= f;
            res[b] += f;
            let f2 = f.norm_squared();
            *scale2 += 2.0 * f2;
            let kk = 2.0 * d2w * c;
            *strain2 += 2.0 * kk * kk * rp.norm_squared();
            if let Some(j) = jac.as_deref_mut() {
                let g = (SMatrix::<f64, D, D>::identity() * (2.0 * dw)
                    + rp * rp.transpose() * (4.0 * d2w))
                    / l;
                j.diag[a] += g;
                j.diag[b] += g;
                j.off[e] = [-g, -g];
            }
        }
        Ok(())
    }
}

/// The full load `F = F_b + F_N(0)` per node [N] of a system: body forces, point-mass
/// weights and the nodal loads at `t = 0`.
pub fn static_load<const D: usize, M: StoredEnergy>(sys: &PhSystem<D, M>) -> Vec<Vector<D>> {
    let mut f = sys.f_body.clone();
    for load in &sys.boundary.loads {
        f[load.node] += (load.force)(0.0);
    }
    f
}

/// The static residual `K(r) S(C(r)) − F` [N] per node at positions `r`, with the reactions
/// (the residual at fixed components) moved to `reactions` and zeros left in their place (at
/// a node fixed to a rigid body: the force the body must exert on it). `Err(element)` if a
/// strain leaves its law's domain.
pub fn static_residual<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
) -> Result<(Vec<Vector<D>>, Vec<Vector<D>>), usize> {
    let f = static_load(sys);
    let mut eq = StaticEquations::new(sys, r, &f, &sys.body_start);
    let zeros = vec![Vector::<D>::zeros(); eq.unknowns()];
    let mut res = zeros.clone();
    eq.evaluate(&zeros, &mut res, None).map_err(|e| e.element)?;
    res.truncate(r.len());
    Ok((res, eq.reaction))
}

/// Finds the static equilibrium of `problem` under its loads at `t = 0`, starting from its
/// initial positions (the initial velocities are ignored). `stop`, when set, interrupts it
/// between Newton iterations.
pub fn solve<const D: usize, M: StoredEnergy>(
    problem: impl Into<Network<D, M>>,
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Equilibrium<D>, StaticsError> {
    let (sys, initial) = PhSystem::new(problem)?;
    solve_system(&sys, &initial.r, params, stop)
}

/// [`solve`] for a validated system, from positions `r_start` [m] (fixed components must be
/// at their `t = 0` positions) and the rigid bodies at their initial poses (as the network
/// gave them; the nodes fixed to them start at their body points, whatever `r_start` holds
/// there). Feedback ports are left out; unless
/// [`StaticsParams::open_loop`], each must exert no force at rest at the equilibrium found
/// (`F(0, r, 0)` within the tolerance), else
/// [`StaticsError::Feedback`]: damping injection always passes, a PD law if its reference
/// starts at the equilibrium.
pub fn solve_system<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r_start: &[Vector<D>],
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Equilibrium<D>, StaticsError> {
    solve_posed(sys, r_start, &sys.body_start, &[], params, stop)
}

/// [`solve_system`] from the node positions and the rigid bodies' poses of `start` (its
/// velocities are ignored; the nodes fixed to a body start at their body points). A pose
/// that is not finite (or, in 2D, not in the plane turned about `z`) is refused by body.
pub fn solve_from<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    start: &State<D>,
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Equilibrium<D>, StaticsError> {
    if start.bodies.len() != sys.bodies.len() {
        return Err(SetupError::StateSize {
            what: "rigid bodies",
            got: start.bodies.len(),
            expected: sys.bodies.len(),
        }
        .into());
    }
    bodies::check_poses(sys, &start.bodies)?;
    solve_posed(sys, &start.r, &start.bodies, &[], params, stop)
}

/// [`solve_from`] with the rigid bodies marked in `held` (one flag per body) held at their
/// poses in `start`, as supports hold nodes: the nodes fixed to a held body stay at its
/// points, its force and moment balance is left out, and the reactions at those nodes are
/// the forces it exerts on them. A body displaced from its equilibrium and held there gives
/// the restoring force of its strings (a mooring's offset–tension curve,
/// [`offset_curve`]).
pub fn solve_held<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    start: &State<D>,
    held: &[bool],
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Equilibrium<D>, StaticsError> {
    if start.bodies.len() != sys.bodies.len() || held.len() != sys.bodies.len() {
        return Err(SetupError::StateSize {
            what: "rigid bodies (start poses and held flags)",
            got: start.bodies.len().min(held.len()),
            expected: sys.bodies.len(),
        }
        .into());
    }
    bodies::check_poses(sys, &start.bodies)?;
    solve_posed(sys, &start.r, &start.bodies, held, params, stop)
}

/// [`solve_system`] from node positions `r_start` [m] and body poses `poses`, the bodies
/// flagged in `held` held there (none if it is empty).
fn solve_posed<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r_start: &[Vector<D>],
    poses: &[BodyState],
    held: &[bool],
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Equilibrium<D>, StaticsError> {
    if r_start.len() != sys.mesh.n_nodes() {
        return Err(SetupError::StateSize {
            what: "start positions",
            got: r_start.len(),
            expected: sys.mesh.n_nodes(),
        }
        .into());
    }
    if let Some((index, name)) = bodies::loose_body(sys, held) {
        return Err(StaticsError::LooseBody { index, name });
    }
    // A body with a prescribed motion is held at its pose at t = 0.
    let poses = bodies::held_poses(sys, poses);
    let poses = &poses[..];
    // The attached nodes start at their bodies' points.
    let mut r0 = r_start.to_vec();
    for (model, st) in sys.bodies.iter().zip(poses) {
        for (node, s) in &model.attachments {
            r0[*node] = crate::body::project(&st.point(s));
        }
    }
    let eq = solve_without_feedback(sys, &r0, (poses, held), params, stop)?;
    if !params.open_loop {
        bodies::check_feedback_at_rest(sys, &eq, held)?;
    }
    let checked = if params.open_loop {
        &[][..]
    } else {
        &sys.boundary.feedback[..]
    };
    for (index, fb) in checked.iter().enumerate() {
        let node = fb.node;
        let f = fb.law.force(0.0, &eq.state.r[node], &Vector::zeros());
        let on_free: f64 = (0..D)
            .filter(|&k| sys.free[node][k])
            .map(|k| f[k] * f[k])
            .sum::<f64>()
            .sqrt();
        // NaN fails too.
        let vanishes = on_free <= eq.tolerance.max(1e-9 * eq.force_scale);
        if !vanishes {
            return Err(StaticsError::Feedback {
                index,
                node,
                force: on_free,
            });
        }
    }
    Ok(eq)
}

fn solve_without_feedback<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r_start: &[Vector<D>],
    (poses, held): (&[BodyState], &[bool]),
    params: &StaticsParams,
    stop: Option<&AtomicBool>,
) -> Result<Equilibrium<D>, StaticsError> {
    let f = static_load(sys);
    // A held body holds the structure as a support does.
    let free_motions = if held.contains(&true) {
        Vec::new()
    } else {
        free_translations(sys)
    };
    let ports = bodies::ports_at_rest(sys);
    for &k in &free_motions {
        // The loads on the nodes and on the bodies (weights and ports).
        let on_bodies = sys
            .bodies
            .iter()
            .zip(&ports)
            .filter(|(m, _)| m.motion.is_none())
            .map(|(m, p)| (m.weight + p.0)[k]);
        let loads: Vec<f64> = f.iter().map(|v| v[k]).chain(on_bodies).collect();
        let net: f64 = loads.iter().sum();
        let total: f64 = loads.iter().map(|x| x.abs()).sum();
        if net.abs() > 1e-9 * total && net.abs() > 0.0 {
            return Err(StaticsError::UnderConstrained { axis: AXES[k], net });
        }
    }
    if let Some((index, name, axis)) = bodies::free_spin(sys, held) {
        return Err(StaticsError::FreeSpin { index, name, axis });
    }
    let slots = 2 * sys.bodies.len();
    let solver = make_bordered_solver::<D>(params.solver, &sys.mesh, slots)?;
    let ws = NewtonWorkspace::<D>::with_slots(&sys.mesh, slots);
    let mut eq = StaticEquations::new(sys, r_start, &f, poses);
    eq.hold(held);
    eq.jac_shift =
        JAC_SHIFT * initial_shift(sys, r_start, &f) / (sys.mesh.n_elements() as f64).powi(2);
    let mut s = Search {
        u: vec![Vector::<D>::zeros(); eq.unknowns()],
        eq,
        ws,
        solver,
        params,
        stop,
        iterations: 0,
        start_poses: poses,
    };
    let guess = match guess_path(&mut s)? {
        Ok(found) => return Ok(found),
        Err(outcome) => outcome,
    };
    let with = |found: Equilibrium<D>| Equilibrium {
        guess: guess.clone(),
        ..found
    };
    let newton_msg = match newton_path(&mut s, StaticsPath::Newton)? {
        Ok(found) => return Ok(with(found)),
        Err(msg) => msg,
    };
    let (lambda, failed_step, cont_msg) = match continuation_path(&mut s)? {
        Ok(found) => return Ok(with(found)),
        Err(end) => end,
    };
    let (pseudo_steps, pseudo_msg) = match pseudo_transient_path(&mut s, &f)? {
        Ok(found) => return Ok(with(found)),
        Err(end) => end,
    };
    let (element, c_max) = largest_strain(sys, &s.eq.positions(&s.u));
    let hint = if free_motions.is_empty() {
        String::new()
    } else {
        format!(
            "; the structure is free to translate along {}",
            free_motions
                .iter()
                .map(|&k| AXES[k])
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    Err(StaticsError::NotFound(Box::new(NotFound {
        newton: newton_msg,
        load_step: failed_step,
        lambda,
        continuation: cont_msg,
        pseudo_steps,
        pseudo: pseudo_msg,
        c_max,
        element,
        hint,
    })))
}

/// The workspace the three paths of [`solve_without_feedback`] share: the equations, the
/// displacement `u` [m] from the start, Newton's workspace and solver, the parameters, the
/// stop request and the Newton iterations spent so far.
struct Search<'a, 's, const D: usize, M> {
    eq: StaticEquations<'a, D, M>,
    u: Vec<Vector<D>>,
    ws: NewtonWorkspace<D>,
    solver: Box<dyn crate::linsolve::LinearSolver<D>>,
    params: &'a StaticsParams,
    stop: Option<&'s AtomicBool>,
    iterations: usize,
    /// The bodies' start poses (a path that starts over starts from them).
    start_poses: &'a [BodyState],
}

impl<const D: usize, M: StoredEnergy> Search<'_, '_, D, M> {
    /// Back to the start: zero displacement, the bodies at their start poses.
    fn restart(&mut self) {
        self.u.iter_mut().for_each(|x| *x = Vector::zeros());
        self.eq.reset_poses(self.start_poses);
    }

    /// Newton in rounds ([`solve_rescaled`]) on the equations as they are set, from `u`.
    fn newton(&mut self) -> Result<newton::NewtonStats, NewtonError<Inadmissible>> {
        solve_rescaled(
            &mut self.eq,
            &mut self.u,
            &mut self.ws,
            self.solver.as_mut(),
            &self.params.newton,
            self.stop,
        )
    }
}

/// The end of a search path: the equilibrium found, or what the path leaves for the message
/// and the next path (`T`); an interruption is the error.
type PathEnd<const D: usize, T> = Result<Result<Equilibrium<D>, T>, StaticsError>;

/// Path 0: Newton at the full load from the catenary first guess. Fails with what became of
/// the guess, the displacement `u` back at zero.
fn guess_path<const D: usize, M: StoredEnergy>(
    s: &mut Search<'_, '_, D, M>,
) -> PathEnd<D, FirstGuess> {
    let (sys, r_start) = (s.eq.sys, s.eq.r0);
    if !s.params.first_guess {
        return Ok(Err(FirstGuess::NotApplicable("switched off".into())));
    }
    let placed = match guess::catenary_guess(sys, r_start) {
        Ok(r) => r,
        Err(why) => return Ok(Err(FirstGuess::NotApplicable(why))),
    };
    for ((u, g), r) in s.u.iter_mut().zip(&placed).zip(r_start) {
        *u = g - r;
    }
    let end = newton_path(s, StaticsPath::CatenaryGuess)?;
    s.restart();
    Ok(match end {
        Ok(found) => Ok(Equilibrium {
            guess: FirstGuess::Used,
            ..found
        }),
        Err(msg) => Err(FirstGuess::Failed(msg)),
    })
}

/// Path 1: Newton at the full load from `u` (the start, or the first guess, reported as
/// `path`). Fails with its message.
fn newton_path<const D: usize, M: StoredEnergy>(
    s: &mut Search<'_, '_, D, M>,
    path: StaticsPath,
) -> PathEnd<D, String> {
    let sys = s.eq.sys;
    let msg = match s.newton() {
        Ok(st) => {
            s.iterations += st.iterations;
            let found = finish(sys, &s.u, &mut s.eq, st, path, s.iterations);
            if found.stable {
                return Ok(Ok(found));
            }
            UNSTABLE.to_string()
        }
        Err(e) => {
            s.iterations += spent(&e, &s.ws);
            if matches!(e, NewtonError::Interrupted(_)) {
                return Err(StaticsError::Interrupted);
            }
            describe(&e)
        }
    };
    Ok(Err(msg))
}

/// Path 2: load continuation from the start, the load factor stepped from 0 to 1. Fails
/// with the last load factor reached, the load step that failed and its message.
fn continuation_path<const D: usize, M: StoredEnergy>(
    s: &mut Search<'_, '_, D, M>,
) -> PathEnd<D, (f64, usize, String)> {
    let sys = s.eq.sys;
    let n = s.u.len();
    let (mut lambda, mut dl, mut steps) = (0.0f64, 0.25f64, 0usize);
    let mut u_ok = vec![Vector::<D>::zeros(); n];
    s.restart();
    let mut cont_msg = String::new();
    let mut failed_step = 0;
    let mut attempts = 0;
    while attempts < s.params.max_load_steps {
        // Newton checks it too, but not when a step fails at once (a strain off its domain).
        if s.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Err(StaticsError::Interrupted);
        }
        attempts += 1;
        let target = (lambda + dl).min(1.0);
        s.eq.lambda = target;
        match s.newton() {
            Ok(st) => {
                s.iterations += st.iterations;
                steps += 1;
                lambda = target;
                cont_msg.clear();
                u_ok.copy_from_slice(&s.u);
                if lambda >= 1.0 {
                    let path = StaticsPath::LoadContinuation { steps };
                    let found = finish(sys, &s.u, &mut s.eq, st, path, s.iterations);
                    if found.stable {
                        return Ok(Ok(found));
                    }
                    cont_msg = UNSTABLE.to_string();
                    failed_step = steps;
                    break;
                }
                if st.iterations <= 4 {
                    dl *= 2.0;
                }
            }
            Err(e) => {
                s.iterations += s.ws.last_stats().iterations;
                if matches!(e, NewtonError::Interrupted(_)) {
                    return Err(StaticsError::Interrupted);
                }
                cont_msg = describe(&e);
                failed_step = steps + 1;
                s.u.copy_from_slice(&u_ok);
                dl *= 0.25;
                if dl < 1e-6 {
                    break;
                }
            }
        }
    }
    if cont_msg.is_empty() {
        cont_msg = format!("{} load steps were not enough", s.params.max_load_steps);
        failed_step = steps + 1;
    }

    Ok(Err((lambda, failed_step, cont_msg)))
}

/// Path 3: pseudo-transient continuation at the full load `f` [N] from the start, first with
/// compression released, then with the law as is. Fails with its steps and message.
fn pseudo_transient_path<const D: usize, M: StoredEnergy>(
    s: &mut Search<'_, '_, D, M>,
    f: &[Vector<D>],
) -> PathEnd<D, (usize, String)> {
    let (sys, r_start) = (s.eq.sys, s.eq.r0);
    // Path 3: pseudo-transient continuation at the full load from the start, first with
    // the strings' compression released (slack instead: a string whose start is longer than
    // its hanging shape falls into it instead of snapping through), then with the law as is.
    s.eq.lambda = 1.0;
    s.eq.jac_shift = 0.0;
    let mu0 = initial_shift(sys, r_start, f);
    let mut pseudo_steps = 0;
    let mut pseudo_msg = String::new();
    for release in [true, false] {
        s.restart();
        s.eq.release = release;
        let end = pseudo_transient(
            &mut s.eq,
            &mut s.u,
            (&mut s.ws, s.solver.as_mut()),
            s.params,
            mu0,
            s.stop,
            &mut s.iterations,
        );
        s.eq.release = false;
        let (steps, st) = match end {
            Ok(x) => x,
            Err(PseudoEnd::Interrupted) => return Err(StaticsError::Interrupted),
            Err(PseudoEnd::Failed(steps, msg)) => {
                pseudo_steps += steps;
                pseudo_msg = msg;
                continue;
            }
        };
        pseudo_steps += steps;
        let path = StaticsPath::PseudoTransient {
            steps: pseudo_steps,
        };
        if !release {
            return Ok(Ok(finish(sys, &s.u, &mut s.eq, st, path, s.iterations)));
        }
        // The slack equilibrium; now Newton with the law as is from there.
        let solved = s.newton();
        s.iterations += match &solved {
            Ok(st) => st.iterations,
            Err(_) => s.ws.last_stats().iterations,
        };
        match solved {
            Ok(st2) => {
                let found = finish(sys, &s.u, &mut s.eq, st2, path, s.iterations);
                if found.stable {
                    return Ok(Ok(found));
                }
                pseudo_msg = UNSTABLE.into();
            }
            Err(NewtonError::Interrupted(_)) => return Err(StaticsError::Interrupted),
            Err(e) => pseudo_msg = describe(&e),
        }
    }
    Ok(Err((pseudo_steps, pseudo_msg)))
}

/// Newton's method on the static equations, in rounds of at most [`ROUND_ITER`] iterations
/// (up to `params.max_iter` in all), each starting with the force and strain scales measured
/// at its starting point. One solve would measure them once, at its start, which for a
/// stress-free start holds the loads only: its tolerance and round-off floor would be far
/// below what the tensioned equilibrium can resolve. A round whose line search can no longer
/// reduce a residual of at most [`STALL_RTOL`] times the force scale ends the solve at the
/// round-off floor: a 1e6-element steel rope stalls at 1.5e-3 N against forces of 3.5e7 N.
fn solve_rescaled<const D: usize, M: StoredEnergy>(
    eq: &mut StaticEquations<'_, D, M>,
    u: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    solver: &mut dyn crate::linsolve::LinearSolver<D>,
    params: &NewtonParams,
    stop: Option<&AtomicBool>,
) -> Result<newton::NewtonStats, NewtonError<Inadmissible>> {
    let mut res = vec![Vector::<D>::zeros(); u.len()];
    let mut done = 0;
    loop {
        let floor = match eq.evaluate(u, &mut res, None) {
            Ok(()) => {
                FLOOR_MARGIN * newton::roundoff_floor(eq.scale, eq.strain_scale)
                    + LONG_CHAIN_NOISE
                        * f64::EPSILON
                        * eq.strain_scale
                        * eq.sys.mesh.n_elements() as f64
            }
            Err(_) => 0.0,
        };
        let round = NewtonParams {
            tol: params.tol.max(floor),
            max_iter: ROUND_ITER.min(params.max_iter.saturating_sub(done)).max(1),
            // Rounds count their iterations against the statics' own limit.
            progress_extension: 1,
            ..*params
        };
        let add = |mut st: newton::NewtonStats| {
            st.iterations += done;
            st
        };
        match newton::solve(eq, u, ws, solver, &round, stop) {
            Ok(mut st) => {
                st.at_roundoff |= st.residual > params.tolerance(st.force_scale);
                return Ok(add(st));
            }
            Err(NewtonError::LineSearch(mut st))
                if st.residual <= STALL_RTOL * eq.scale.max(st.force_scale) =>
            {
                st.at_roundoff = true;
                st.tolerance = STALL_RTOL * eq.scale.max(st.force_scale);
                return Ok(add(st));
            }
            Err(NewtonError::MaxIterations(st) | NewtonError::LineSearch(st))
                if st.residual.is_finite() && done + st.iterations.max(1) < params.max_iter =>
            {
                done += st.iterations.max(1);
            }
            Err(NewtonError::MaxIterations(st)) => {
                return Err(NewtonError::MaxIterations(add(st)));
            }
            Err(NewtonError::LineSearch(st)) => return Err(NewtonError::LineSearch(add(st))),
            Err(e) => return Err(e),
        }
    }
}

/// Rounding noise of the static residual that grows with the number of elements `n`, as a
/// multiple of `ε K n` (`K` the strain scale): measured `1.0e-4 ε K n` on hanging steel ropes
/// of 2e5 and 1e6 elements (1.37e-4 N and 1.53e-3 N), where the floor of §9, which grows
/// like `K ∝ √n`, falls short; twice that is added to a round's tolerance, so that such a
/// residual ends the solve instead of a line search that cannot reduce it.
const LONG_CHAIN_NOISE: f64 = 2e-4;
/// Newton iterations per round of [`solve_rescaled`].
const ROUND_ITER: usize = 4;
/// A static residual that the line search cannot reduce is at round-off below this fraction
/// of the force scale.
const STALL_RTOL: f64 = 1e-10;
/// Margin on the round-off floor estimate of a round's tolerance: the rounding noise of
/// long stiff chains exceeds the estimate (a 2e5-element steel rope: 1.37e-4 N against
/// 1.12e-4 N).
const FLOOR_MARGIN: f64 = 4.0;

/// How a pseudo-transient run ended without an equilibrium.
enum PseudoEnd {
    Interrupted,
    /// Steps taken and why it stopped.
    Failed(usize, String),
}

/// Pseudo-transient continuation (path 3) from `u` at the load of `eq`: proximal steps with the
/// shift `μ` starting at `mu0`, until the unshifted residual meets the tolerance or an
/// unshifted Newton solve from the iterate reaches a stable equilibrium. Returns the steps
/// and the statistics of the last solve; `u` holds the equilibrium.
#[allow(clippy::too_many_arguments)]
fn pseudo_transient<const D: usize, M: StoredEnergy>(
    eq: &mut StaticEquations<'_, D, M>,
    u: &mut [Vector<D>],
    (ws, solver): (
        &mut NewtonWorkspace<D>,
        &mut dyn crate::linsolve::LinearSolver<D>,
    ),
    params: &StaticsParams,
    mu0: f64,
    stop: Option<&AtomicBool>,
    iterations: &mut usize,
) -> Result<(usize, newton::NewtonStats), PseudoEnd> {
    let n = u.len();
    let mut res = vec![Vector::<D>::zeros(); n];
    let mut trial = vec![Vector::<D>::zeros(); n];
    // Pseudo-time steps need not be solved to round-off: only the path's end must be.
    let loose = NewtonParams {
        rtol: PSEUDO_RTOL,
        max_iter: 15,
        progress_extension: 1,
        ..params.newton
    };
    let polish = NewtonParams {
        max_iter: 15,
        progress_extension: 1,
        ..params.newton
    };
    let mut mu = mu0;
    let mut steps = 0;
    while steps < params.max_pseudo_steps {
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Err(PseudoEnd::Interrupted);
        }
        eq.mu = mu;
        eq.rebase(u);
        eq.set_anchor(u);
        match newton::solve(eq, u, ws, solver, &loose, stop) {
            Ok(st) => {
                *iterations += st.iterations;
                steps += 1;
                // The unshifted residual at the new iterate.
                eq.mu = 0.0;
                let r = match eq.evaluate(u, &mut res, None) {
                    Ok(()) => newton::norm(&res),
                    Err(_) => f64::INFINITY,
                };
                let tol = params.newton.tolerance(eq.scale);
                let floor = newton::roundoff_floor(eq.scale, eq.strain_scale);
                if r <= tol || r <= floor {
                    let st = newton::NewtonStats {
                        residual: r,
                        tolerance: tol,
                        force_scale: eq.scale,
                        at_roundoff: r > tol,
                        ..st
                    };
                    return Ok((steps, st));
                }
                // Newton without the shift, once the residual is small or every few steps.
                if r <= POLISH_BELOW * eq.scale || steps % POLISH_EVERY == 0 {
                    trial.copy_from_slice(u);
                    let polished = solve_rescaled(eq, &mut trial, ws, solver, &polish, stop);
                    *iterations += ws.last_stats().iterations;
                    if let Ok(st2) = polished
                        && stable_at(eq, &trial)
                    {
                        u.copy_from_slice(&trial);
                        return Ok((steps, st2));
                    }
                }
                mu *= match st.iterations {
                    0..=5 => 0.2,
                    6..=10 => 0.5,
                    _ => 1.0,
                };
            }
            Err(NewtonError::Interrupted(_)) => return Err(PseudoEnd::Interrupted),
            Err(e) => {
                *iterations += ws.last_stats().iterations;
                u.copy_from_slice(&eq.anchor);
                mu *= 4.0;
                if mu > 1e12 * mu0 {
                    let msg = format!(
                        "the shift grew beyond 1e12 times its start ({})",
                        describe(&e)
                    );
                    return Err(PseudoEnd::Failed(steps, msg));
                }
            }
        }
    }
    Err(PseudoEnd::Failed(
        steps,
        format!(
            "{} pseudo-time steps were not enough",
            params.max_pseudo_steps
        ),
    ))
}

/// Whether the equilibrium at the displacement `u` is stable: the tangent stiffness (of the
/// released laws while `eq.release` is set; the potential's only, without the current's
/// drag) is positive definite on the free components (and the bodies' slots).
fn stable_at<const D: usize, M: StoredEnergy>(
    eq: &mut StaticEquations<'_, D, M>,
    u: &[Vector<D>],
) -> bool {
    if eq.sys.bodies.is_empty() {
        let k = tangent_or_released(eq, u);
        return positive_definite(eq.sys, &k);
    }
    let held = eq.held.clone();
    stable_with_bodies(
        eq.sys,
        &eq.positions(u),
        &eq.body_poses(u),
        eq.release,
        &held,
    )
}

/// [`stable_at`] with rigid bodies, at node positions `r` [m] and body poses `poses`: the
/// tangent taken with the poses as reference (`w = 0`), where it is the potential's Hessian.
fn stable_with_bodies<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    poses: &[BodyState],
    release: bool,
    held: &[bool],
) -> bool {
    let f = static_load(sys);
    let mut eq = StaticEquations::new(sys, r, &f, poses);
    eq.release = release;
    eq.hold(held);
    eq.drag = false;
    let x = vec![Vector::<D>::zeros(); eq.unknowns()];
    let mut res = x.clone();
    let mut j = BlockJacobian::with_slots(&sys.mesh, 2 * sys.bodies.len());
    eq.evaluate(&x, &mut res, Some(&mut j)).is_ok() && bodies::positive_definite(sys, &j)
}

/// One entry `(row, column, value)` of a sparse matrix.
pub(crate) type Entry = faer::sparse::Triplet<usize, usize, f64>;

/// The number of coordinates of a rigid body in the modal analysis: its translation and its
/// turn (3 + 3 in 3D, 2 + 1 in 2D).
pub(crate) fn body_coordinates(dim: usize) -> usize {
    if dim == 2 { 3 } else { 6 }
}

/// The potential's Hessian at the rest state of node positions `r` [m] and body poses
/// `poses` (without the current's drag), on the free components (numbered by
/// [`crate::assembly::free_dofs`], `n` of them) and then per body its translation [m] and
/// its turn scaled by its radius of gyration `ρ w` [m] (`w` the body-axes Cayley vector;
/// [`body_coordinates`] per body): `(n + coordinates, triplets)`. `None` if a strain is
/// off its law's domain.
pub(crate) fn body_hessian<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    poses: &[BodyState],
) -> Option<(usize, Vec<Entry>)> {
    let f = static_load(sys);
    let mut eq = StaticEquations::new(sys, r, &f, poses);
    eq.drag = false;
    let x = vec![Vector::<D>::zeros(); eq.unknowns()];
    let mut res = x.clone();
    let mut j = BlockJacobian::with_slots(&sys.mesh, 2 * sys.bodies.len());
    eq.evaluate(&x, &mut res, Some(&mut j)).ok()?;
    let (_, n) = crate::assembly::free_dofs(sys);
    let per = body_coordinates(D);
    let slot_dof = |s: usize, k: usize| {
        let base = n + (s / 2) * per;
        match (s % 2, D) {
            (0, _) => Some(base + k),
            (_, 3) => Some(base + 3 + k),
            (_, _) => (k == 0).then_some(base + 2),
        }
    };
    let t = bodies::hessian_triplets(sys, &j, slot_dof);
    Some((n + per * sys.bodies.len(), t))
}

/// The tangent stiffness at `r₀ + u`, of the released laws while `eq.release` is set; the
/// potential's only (without the current's drag). Without bodies.
fn tangent_or_released<const D: usize, M: StoredEnergy>(
    eq: &mut StaticEquations<'_, D, M>,
    u: &[Vector<D>],
) -> BlockJacobian<D> {
    let mut j = BlockJacobian::zeros(&eq.sys.mesh);
    let mut res = vec![Vector::<D>::zeros(); u.len()];
    let (mu, shift) = (eq.mu, eq.jac_shift);
    eq.mu = 0.0;
    eq.jac_shift = 0.0;
    eq.drag = false;
    let ok = eq.evaluate(u, &mut res, Some(&mut j)).is_ok();
    eq.mu = mu;
    eq.jac_shift = shift;
    eq.drag = true;
    if !ok {
        j.clear();
    }
    j
}

const AXES: [&str; 3] = ["x", "y", "z"];
/// The Newton-matrix shift of paths 1 and 2, relative to the starting shift of path 3
/// divided by the squared number of elements. `μ₀` is an element's stiffness over its mass;
/// a chain of `n` elements is `n²` times softer as a whole (its lowest axial mode), and a
/// shift near that would slow Newton to linear convergence (a 1e5-element rope: factor 0.5
/// per iteration with `1e-10 μ₀`).
const JAC_SHIFT: f64 = 1e-8;
/// Why a converged path is not taken.
const UNSTABLE: &str =
    "it converged to an unstable equilibrium (the tangent stiffness is not positive definite)";
/// Relative tolerance of a pseudo-time step (the path, not the end, is solved loosely).
const PSEUDO_RTOL: f64 = 1e-8;
/// Unshifted Newton is tried once the residual is below this fraction of the force scale…
const POLISH_BELOW: f64 = 1e-3;
/// …or every this many pseudo-time steps.
const POLISH_EVERY: usize = 10;

/// Axes along which no node is held (a node fixed to a rigid body is not held). In water the vertical axis is not counted (buoyancy
/// is a load that depends on the height), nor is any axis along which a seabed's normal has
/// a component (the seabed holds it).
fn free_translations<const D: usize, M>(sys: &PhSystem<D, M>) -> Vec<usize> {
    let held_by_water = |k: usize| {
        sys.water
            .as_deref()
            .is_some_and(|w| k == D - 1 || w.bed.as_ref().is_some_and(|b| b.holds(k)))
    };
    // A node fixed to a free rigid body holds nothing: the body moves it (a body with a
    // prescribed motion holds its nodes).
    let on_body = |i: usize| {
        sys.attached
            .get(i)
            .copied()
            .flatten()
            .is_some_and(|(b, _)| sys.bodies[b].motion.is_none())
    };
    (0..D)
        .filter(|&k| {
            let held = (0..sys.free.len()).any(|i| !sys.free[i][k] && !on_body(i));
            !held && !held_by_water(k)
        })
        .collect()
}

/// The starting shift `μ₀` [1/s²]: the ratio of the stiffness to the mass on the diagonal
/// (so that the first pseudo-time step is about as stiff as it is heavy), or, where nothing
/// is stiff yet, the load's acceleration over the shortest element.
fn initial_shift<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r0: &[Vector<D>],
    f: &[Vector<D>],
) -> f64 {
    let (mut k_tr, mut m_tr, mut l_min) = (0.0, 0.0, f64::INFINITY);
    for (g, _, [a, b], l) in sys.each_element() {
        let (_, _, t) = match &g.law {
            Law::String(m) => element_tangent(m, &r0[a], &r0[b], l),
            Law::Spring(s) => element_tangent(s, &r0[a], &r0[b], l),
        };
        k_tr += 2.0 * t.trace().abs();
        m_tr += 2.0 * D as f64 * element_mass(g.mass, g.rho_a, l).0;
        if g.rho_a > 0.0 {
            l_min = l_min.min(l);
        }
    }
    m_tr += sys
        .point_mass
        .iter()
        .map(|&(_, m)| D as f64 * m)
        .sum::<f64>();
    // A body's mass on its position and (scaled by the radius of gyration) on its turn.
    m_tr += sys
        .bodies
        .iter()
        .map(|b| 2.0 * D as f64 * b.mass)
        .sum::<f64>();
    let stiff = if m_tr > 0.0 { k_tr / m_tr } else { 0.0 };
    let f_norm: f64 = f.iter().map(|v| v.norm()).sum();
    let accel = if m_tr > 0.0 && l_min.is_finite() {
        f_norm / (m_tr / D as f64) / l_min
    } else {
        0.0
    };
    let mu = stiff.max(accel);
    if mu > 0.0 && mu.is_finite() { mu } else { 1.0 }
}

/// The element with the largest strain at positions `r` [m], and that strain.
fn largest_strain<const D: usize, M>(sys: &PhSystem<D, M>, r: &[Vector<D>]) -> (usize, f64) {
    let mut best = (0, f64::NEG_INFINITY);
    for (e, (&[a, b], &l)) in sys
        .mesh
        .elements()
        .iter()
        .zip(sys.mesh.lengths())
        .enumerate()
    {
        let c = ((r[b] - r[a]) / l).norm_squared();
        if c > best.1 || c.is_nan() {
            best = (e, c);
        }
    }
    best
}

/// Newton iterations that a failed [`solve_rescaled`] spent: all its rounds' where the error
/// counts them, else its last round's.
fn spent<E, const D: usize>(e: &NewtonError<E>, ws: &NewtonWorkspace<D>) -> usize {
    match e {
        NewtonError::MaxIterations(st) | NewtonError::LineSearch(st) => st.iterations,
        _ => ws.last_stats().iterations,
    }
}

fn describe<E: std::fmt::Debug>(e: &NewtonError<E>) -> String {
    match e {
        NewtonError::Eval(x) => format!("a strain left the law's domain: {x:?}"),
        NewtonError::Linear(l) => format!("singular Newton matrix: {l}"),
        NewtonError::NonFinite { node, overflow } => {
            if *overflow {
                format!("the residual norm overflows (largest at node {node})")
            } else {
                format!("non-finite residual at node {node}")
            }
        }
        NewtonError::MaxIterations(s) => format!(
            "no convergence in {} iterations, residual {:.3e} N against tolerance {:.3e} N",
            s.iterations, s.residual, s.tolerance
        ),
        NewtonError::LineSearch(s) => format!(
            "the line search found no descent after {} iterations, residual {:.3e} N",
            s.iterations, s.residual
        ),
        NewtonError::Interrupted(_) => "interrupted".into(),
    }
}

fn finish<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    u: &[Vector<D>],
    eq: &mut StaticEquations<'_, D, M>,
    st: newton::NewtonStats,
    path: StaticsPath,
    iterations: usize,
) -> Equilibrium<D> {
    let r = eq.positions(u);
    let mut state = State::at_rest(&sys.mesh, r);
    state.bodies = eq.body_poses(u);
    // Reactions and the residual at the final displacement, without shift.
    eq.mu = 0.0;
    eq.lambda = 1.0;
    let mut res = vec![Vector::<D>::zeros(); u.len()];
    let (residual, scale) = match eq.evaluate(u, &mut res, None) {
        Ok(()) => (newton::norm(&res), eq.scale),
        Err(_) => (st.residual, st.force_scale),
    };
    let mut reactions = vec![Vector::<D>::zeros(); u.len()];
    for &i in &sys.constrained {
        for k in 0..D {
            if !sys.free[i][k] {
                reactions[i][k] = eq.reaction[i][k];
            }
        }
    }
    let energies = sys.energies(&state);
    let stable = if sys.bodies.is_empty() {
        positive_definite(sys, &tangent_blocks(sys, &state.r))
    } else {
        stable_with_bodies(sys, &state.r, &state.bodies, false, &eq.held)
    };
    Equilibrium {
        stable,
        state,
        reactions,
        residual,
        tolerance: st.tolerance,
        force_scale: scale,
        at_roundoff: st.at_roundoff,
        path,
        iterations,
        guess: FirstGuess::NotApplicable(String::new()),
        energies,
    }
}

/// `1st`, `2nd`, `3rd`, `4th`, … for messages.
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (1, 11) | (2, 12) | (3, 13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

#[cfg(test)]
mod body_tests;
#[cfg(test)]
mod buoy_tests;
#[cfg(test)]
mod mooring_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::water::{Current, LineHydro, Water};
    use crate::{Boundary, Fixed, MassMatrix, Material, Mesh, Problem};

    /// The static residual's Jacobian with the water at rest (buoyancy, a sheared current's
    /// drag) against central differences.
    #[test]
    fn static_water_jacobian_matches_finite_differences() {
        let n = 6;
        let mesh = Mesh::uniform_chain(n, 6.0).unwrap();
        let r: Vec<Vector<2>> = (0..=n)
            .map(|i| {
                Vector::<2>::new(
                    0.3 * i as f64,
                    -0.5 - 0.9 * i as f64 + 0.05 * (i * i) as f64,
                )
            })
            .collect();
        let problem = Problem {
            initial: State::at_rest(&mesh, r),
            mesh,
            material: Material::linear_elastic(50.0),
            rho_a: 1.0,
            body_force: Vector::<2>::new(0.0, -2.0),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                fixed: vec![Fixed::node(0)],
                loads: vec![],
                motions: vec![],
                feedback: vec![],
            },
            point_masses: vec![],
        };
        let current = Current::Profile(vec![
            (-4.0, Vector::<2>::new(0.5, 0.1)),
            (0.0, Vector::<2>::new(1.5, -0.2)),
        ]);
        let mut water = Water::new(1.0).with_current(current);
        water.drag_smoothing = 0.1;
        let net = Network::from(problem).with_water(water).with_line_hydro(
            0,
            LineHydro {
                diameter: 0.6,
                cd: 1.2,
                cd_axial: 0.5,
                ca: 0.0,
                ca_axial: 0.0,
            },
        );
        let (sys, init) = PhSystem::new(net).unwrap();
        let f = static_load(&sys);
        let mk = |r0| StaticEquations {
            lambda: 0.7,
            ..StaticEquations::new(&sys, r0, &f, &[])
        };
        let mut eq = mk(&init.r);
        let x: Vec<Vector<2>> = (0..=n)
            .map(|i| Vector::<2>::new(0.03 * (i as f64).sin(), 0.02 * (i as f64).cos()))
            .collect();
        let mut res = vec![Vector::<2>::zeros(); n + 1];
        let mut jac = BlockJacobian::zeros(&sys.mesh);
        eq.evaluate(&x, &mut res, Some(&mut jac)).unwrap();
        let eps = 1e-7;
        let mut worst = 0.0f64;
        for j in 1..=n {
            for m in 0..2 {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[j][m] += eps;
                xm[j][m] -= eps;
                let (mut rp, mut rm) = (res.clone(), res.clone());
                eq.evaluate(&xp, &mut rp, None).unwrap();
                eq.evaluate(&xm, &mut rm, None).unwrap();
                for i in 1..=n {
                    for k in 0..2 {
                        let num = (rp[i][k] - rm[i][k]) / (2.0 * eps);
                        let mut an = if i == j { jac.diag[i][(k, m)] } else { 0.0 };
                        if j == i + 1 {
                            an += jac.off[i][0][(k, m)];
                        }
                        if i == j + 1 {
                            an += jac.off[j][1][(k, m)];
                        }
                        worst = worst.max((an - num).abs());
                    }
                }
            }
        }
        assert!(worst <= 1e-6, "static Jacobian error {worst:e}");
    }
}
