//! Natural frequencies and mode shapes about a rest state (docs/method.md §17): the
//! symmetric generalized eigenproblem `K_T φ = ω² M φ` on the free position components.
//!
//! Small problems (at most [`DENSE_LIMIT`] free components) are solved dense; larger ones by
//! shift-invert Lanczos ([`crate::eigen`]) whose solves by `K_T − σM` use the time step's
//! O(N) linear solvers.

use std::f64::consts::PI;
use std::sync::atomic::{AtomicBool, Ordering};

use faer::Mat;
use thiserror::Error;

use crate::assembly::{free_dofs, mass_blocks, positive_definite, restrict, tangent_blocks};
use crate::eigen::{self, EigenError, LanczosParams};
use crate::error::{LinearSolveError, SetupError};
use crate::linsolve::{BlockJacobian, SolverKind, make_solver};
use crate::material::StoredEnergy;
use crate::system::{PhSystem, Vector};

pub(crate) mod bodies;

/// Largest number of free components solved by the dense decomposition.
pub const DENSE_LIMIT: usize = 1500;

/// Whether a mode moves the string along or across itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Character {
    /// At least 90 % of the mode's kinetic energy is along the string's tangent.
    Longitudinal,
    /// At most 10 % of it is along the tangent.
    Transverse,
    /// In between.
    Mixed,
    /// Rigid bodies hold at least half of the mode's kinetic energy.
    Body,
}

impl Character {
    /// `longitudinal`, `transverse` or `mixed`.
    pub fn name(self) -> &'static str {
        match self {
            Character::Longitudinal => "longitudinal",
            Character::Transverse => "transverse",
            Character::Mixed => "mixed",
            Character::Body => "body",
        }
    }
}

/// One natural mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode<const D: usize> {
    /// Angular frequency `ω` [rad/s].
    pub omega: f64,
    /// Shape per node (zero at fixed components), `M`-normalized: `φᵀ M φ = 1` [kg^-½].
    pub shape: Vec<Vector<D>>,
    /// Share of the mode's kinetic energy along the string's local tangent, in `[0, 1]`.
    pub axial_share: f64,
    /// Longitudinal, transverse, mixed or a body's.
    pub character: Character,
    /// Per rigid body, its translation [kg^-½] and its small turn about the space axes
    /// [rad·m^-1·kg^-½] in the mode (same normalization as `shape`); empty without bodies.
    pub bodies: Vec<(crate::body::Vec3, crate::body::Vec3)>,
}

impl<const D: usize> Mode<D> {
    /// Frequency [Hz].
    pub fn hertz(&self) -> f64 {
        self.omega / (2.0 * PI)
    }
}

/// The modes found and how.
#[derive(Debug, Clone, PartialEq)]
pub struct Modes<const D: usize> {
    /// Modes by ascending frequency.
    pub modes: Vec<Mode<D>>,
    /// `dense` or `lanczos`.
    pub method: &'static str,
    /// Linear solves (Lanczos) or 0 (dense).
    pub solves: usize,
}

/// Why no modes were computed.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ModesError {
    /// The problem is invalid.
    #[error(transparent)]
    Setup(#[from] SetupError),
    /// The state is not a stable equilibrium.
    #[error(
        "the tangent stiffness is not positive definite at this state (not a stable equilibrium: a compressed or slack element, or a free rigid-body motion); natural modes need a stable rest state"
    )]
    NotStable,
    /// Nothing is free.
    #[error("no free position components: nothing can vibrate")]
    NoFreeDofs,
    /// Too many coordinates for the dense solve that takes rigid bodies.
    #[error(
        "the modal analysis with rigid bodies is solved dense, up to {limit} coordinates, and this model has {size}: use fewer elements"
    )]
    TooLarge {
        /// Coordinates (free components and the bodies' translations and turns).
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// The eigensolver failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// The stop flag was set.
    #[error("interrupted")]
    Interrupted,
    /// A rigid body's pose is prescribed (a motion).
    #[error(
        "rigid body '{name}' has a prescribed pose (a motion), which the statics hold: modes about a prescribed body are not available yet (give it no motion for the analysis)"
    )]
    Prescribed {
        /// The body's name.
        name: String,
    },
}

/// The `count` lowest natural modes about the rest state at positions `r` [m] (at most the
/// number of free components). `solver` is used by Lanczos for large problems. With rigid
/// bodies, use [`modes_with_bodies`].
///
/// `stop`, when given and set, ends the computation with [`ModesError::Interrupted`]:
/// Lanczos between two of its steps; the dense decomposition (at most [`DENSE_LIMIT`] free
/// components, about a second) before and after it.
pub fn modes<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    count: usize,
    solver: SolverKind,
    stop: Option<&AtomicBool>,
) -> Result<Modes<D>, ModesError> {
    let stopped = || stop.is_some_and(|s| s.load(Ordering::Relaxed));
    if !sys.bodies.is_empty() {
        return modes_with_bodies(sys, r, &sys.body_start, count, stop);
    }
    let kb = tangent_blocks(sys, r);
    if !positive_definite(sys, &kb) {
        return Err(ModesError::NotStable);
    }
    let mb = mass_blocks(sys);
    let (dof, n) = free_dofs(sys);
    if n == 0 {
        return Err(ModesError::NoFreeDofs);
    }
    let count = count.min(n);
    let expand = |x: &[f64]| -> Vec<Vector<D>> {
        (0..sys.mesh.n_nodes())
            .map(|i| Vector::<D>::from_fn(|k, _| dof[i * D + k].map_or(0.0, |j| x[j])))
            .collect()
    };
    // Shift-invert resolves the lowest modes to their own precision (it works with K_T⁻¹);
    // a dense decomposition only to ε times the stiffest (axial) one. So dense is for
    // small problems that want most of their modes.
    let (values, vectors, method, solves) = if n <= DENSE_LIMIT && (n <= 12 || 2 * count > n) {
        if stopped() {
            return Err(ModesError::Interrupted);
        }
        let k: Mat<f64> = restrict(&sys.mesh, &kb, &dof, n).as_ref().to_dense();
        let m: Mat<f64> = restrict(&sys.mesh, &mb, &dof, n).as_ref().to_dense();
        let (vals, vecs) = eigen::dense_generalized(&k, &m)?;
        if stopped() {
            return Err(ModesError::Interrupted);
        }
        let vectors = (0..count)
            .map(|c| (0..n).map(|i| vecs[(i, c)]).collect::<Vec<f64>>())
            .collect();
        (vals[..count].to_vec(), vectors, "dense", 0)
    } else {
        // K_T − σM with σ = 0 (K_T is positive definite), fixed components as identity rows.
        let mut lin = make_solver::<D>(solver, &sys.mesh)?;
        let masked = masked(sys, &kb, true);
        let mass = masked_mass(sys, &mb);
        let mut full = vec![Vector::<D>::zeros(); sys.mesh.n_nodes()];
        let mut prod = vec![Vector::<D>::zeros(); sys.mesh.n_nodes()];
        let solve = |x: &mut [f64]| -> Result<(), LinearSolveError> {
            for (i, f) in full.iter_mut().enumerate() {
                *f = Vector::<D>::from_fn(|k, _| dof[i * D + k].map_or(0.0, |j| x[j]));
            }
            lin.solve(&masked, &mut full)?;
            for (i, f) in full.iter().enumerate() {
                for k in 0..D {
                    if let Some(j) = dof[i * D + k] {
                        x[j] = f[k];
                    }
                }
            }
            Ok(())
        };
        let m_mul = |x: &[f64], out: &mut [f64]| {
            let v = expand(x);
            mass.mul(&sys.mesh, &v, &mut prod);
            for (i, p) in prod.iter().enumerate() {
                for k in 0..D {
                    if let Some(j) = dof[i * D + k] {
                        out[j] = p[k];
                    }
                }
            }
        };
        let params = LanczosParams::new(count, 0.0);
        let pairs = match eigen::lanczos_shift_invert(n, solve, m_mul, &params, stop) {
            Err(EigenError::Interrupted { .. }) => return Err(ModesError::Interrupted),
            found => found?,
        };
        (pairs.values, pairs.vectors, "lanczos", pairs.iterations)
    };
    let tangents = node_tangents(sys, r);
    let node_mass = lumped_mass(sys);
    let modes = values
        .iter()
        .zip(vectors)
        .map(|(&lambda, x)| {
            let shape = expand(&x);
            let (axial_share, character) = classify(&shape, &tangents, &node_mass);
            Mode {
                omega: lambda.max(0.0).sqrt(),
                shape,
                axial_share,
                character,
                bodies: Vec::new(),
            }
        })
        .collect();
    Ok(Modes {
        modes,
        method,
        solves,
    })
}

/// The `count` lowest natural modes of a system with rigid bodies about the rest state of
/// node positions `r` [m] and body poses `poses` (an equilibrium's `state.bodies`), on the
/// free components and each body's translation and turn (docs/method.md §22, "Modes with
/// rigid bodies"). Solved dense (at most [`DENSE_LIMIT`] coordinates, else
/// [`ModesError::TooLarge`]); `stop` is checked before and after.
pub fn modes_with_bodies<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
    r: &[Vector<D>],
    poses: &[crate::body::BodyState],
    count: usize,
    stop: Option<&AtomicBool>,
) -> Result<Modes<D>, ModesError> {
    let stopped = || stop.is_some_and(|s| s.load(Ordering::Relaxed));
    if poses.len() != sys.bodies.len() {
        return Err(SetupError::StateSize {
            what: "rigid bodies' poses",
            got: poses.len(),
            expected: sys.bodies.len(),
        }
        .into());
    }
    if let Some(b) = sys.bodies.iter().position(|b| b.motion.is_some()) {
        return Err(ModesError::Prescribed {
            name: sys.body_names[b].clone(),
        });
    }
    if stopped() {
        return Err(ModesError::Interrupted);
    }
    let found = bodies::modes_with_bodies(sys, r, poses, count)?;
    if stopped() {
        return Err(ModesError::Interrupted);
    }
    Ok(found)
}

/// The share of a mode's kinetic energy along the strings' tangents (lumped node masses)
/// and its character.
fn classify<const D: usize>(
    shape: &[Vector<D>],
    tangents: &[Vector<D>],
    node_mass: &[f64],
) -> (f64, Character) {
    let (mut axial, mut total) = (0.0, 0.0);
    for ((phi, t), m) in shape.iter().zip(tangents).zip(node_mass) {
        axial += m * t.dot(phi).powi(2);
        total += m * phi.norm_squared();
    }
    let axial_share = if total > 0.0 { axial / total } else { 0.0 };
    let character = if axial_share >= 0.9 {
        Character::Longitudinal
    } else if axial_share <= 0.1 {
        Character::Transverse
    } else {
        Character::Mixed
    };
    (axial_share, character)
}

/// `blocks` with the rows and columns of fixed components zeroed and, if `unit`, 1 on
/// their diagonal.
fn masked<const D: usize, M>(
    sys: &PhSystem<D, M>,
    blocks: &BlockJacobian<D>,
    unit: bool,
) -> BlockJacobian<D> {
    let mut j = blocks.clone();
    for &i in &sys.constrained {
        let fi = sys.free[i];
        for k in 0..D {
            for m in 0..D {
                if !fi[k] || !fi[m] {
                    j.diag[i][(k, m)] = if unit && k == m { 1.0 } else { 0.0 };
                }
            }
        }
    }
    for &e in &sys.constrained_elements {
        let [a, b] = sys.mesh.elements()[e];
        let (fa, fb) = (sys.free[a], sys.free[b]);
        for k in 0..D {
            for m in 0..D {
                if !fa[k] || !fb[m] {
                    j.off[e][0][(k, m)] = 0.0;
                }
                if !fb[k] || !fa[m] {
                    j.off[e][1][(k, m)] = 0.0;
                }
            }
        }
    }
    j
}

fn masked_mass<const D: usize, M>(
    sys: &PhSystem<D, M>,
    blocks: &BlockJacobian<D>,
) -> BlockJacobian<D> {
    masked(sys, blocks, false)
}

/// Unit tangent at each node: the mean of its elements' directions (zero if they cancel).
fn node_tangents<const D: usize, M>(sys: &PhSystem<D, M>, r: &[Vector<D>]) -> Vec<Vector<D>> {
    let mut t = vec![Vector::<D>::zeros(); r.len()];
    for &[a, b] in sys.mesh.elements() {
        let d = r[b] - r[a];
        let n = d.norm();
        if n > 0.0 {
            t[a] += d / n;
            t[b] += d / n;
        }
    }
    for x in &mut t {
        let n = x.norm();
        if n > 0.0 {
            *x /= n;
        }
    }
    t
}

/// Row-sum lumped mass per node [kg].
fn lumped_mass<const D: usize, M: StoredEnergy>(sys: &PhSystem<D, M>) -> Vec<f64> {
    let mb = mass_blocks(sys);
    let mut m: Vec<f64> = mb.diag.iter().map(|b| b[(0, 0)]).collect();
    for (&[a, b], off) in sys.mesh.elements().iter().zip(&mb.off) {
        m[a] += off[0][(0, 0)];
        m[b] += off[1][(0, 0)];
    }
    m
}
