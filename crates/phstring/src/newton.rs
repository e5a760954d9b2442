//! Newton's method on the reduced step equations (METHOD §3).
//!
//! Convergence test: the Euclidean norm of the residual over all free degrees of freedom,
//! in newtons (the momentum balance of the step divided by `h`), is at most
//! [`NewtonParams::tol`]. The test is made before each solve, so `iterations` counts linear
//! solves (Jacobian factorizations).

use crate::error::LinearSolveError;
use crate::linsolve::{BlockJacobian, LinearSolver};
use crate::system::Vector;

/// Newton parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonParams {
    /// Residual tolerance `ε_Newton` [N] (Euclidean norm of the force residual). The paper
    /// uses 1e-11.
    pub tol: f64,
    /// Largest number of iterations (linear solves) per step.
    pub max_iter: usize,
}

impl Default for NewtonParams {
    fn default() -> Self {
        Self {
            tol: 1e-11,
            max_iter: 25,
        }
    }
}

/// What one Newton solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NewtonStats {
    /// Iterations (linear solves).
    pub iterations: usize,
    /// Final residual norm [N].
    pub residual: f64,
}

/// A nonlinear system `R(x) = 0` in node-block form.
pub trait NewtonProblem<const D: usize> {
    /// Error type of a failed evaluation (e.g. a strain outside the material's domain).
    type Error;
    /// Evaluates `R(x)` into `res` and, if given, the Jacobian `∂R/∂x` into `jac`.
    fn evaluate(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        jac: Option<&mut BlockJacobian<D>>,
    ) -> Result<(), Self::Error>;
}

/// Why a Newton solve failed.
#[derive(Debug, Clone, PartialEq)]
pub enum NewtonError<E> {
    /// The evaluation failed.
    Eval(E),
    /// The linear solve failed.
    Linear(LinearSolveError),
    /// The residual is NaN or infinite at this node.
    NonFinite {
        /// Node index.
        node: usize,
    },
    /// No convergence within the iteration limit.
    MaxIterations(NewtonStats),
}

/// Newton workspace (residual and Jacobian storage), allocated once.
#[derive(Debug, Clone)]
pub struct NewtonWorkspace<const D: usize> {
    res: Vec<Vector<D>>,
    jac: BlockJacobian<D>,
}

impl<const D: usize> NewtonWorkspace<D> {
    /// Workspace for a mesh.
    pub fn new(mesh: &crate::mesh::Mesh) -> Self {
        Self {
            res: vec![Vector::zeros(); mesh.n_nodes()],
            jac: BlockJacobian::zeros(mesh),
        }
    }
    /// The last residual evaluated.
    pub fn residual(&self) -> &[Vector<D>] {
        &self.res
    }
}

/// Euclidean norm of a node-block vector.
pub fn norm<const D: usize>(x: &[Vector<D>]) -> f64 {
    x.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt()
}

/// Solves `R(x) = 0` starting from `x`, which holds the solution on success.
pub fn solve<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    solver: &mut dyn LinearSolver<D>,
    params: &NewtonParams,
) -> Result<NewtonStats, NewtonError<P::Error>> {
    let mut stats = NewtonStats::default();
    loop {
        problem
            .evaluate(x, &mut ws.res, Some(&mut ws.jac))
            .map_err(NewtonError::Eval)?;
        stats.residual = norm(&ws.res);
        if !stats.residual.is_finite() {
            let node = ws.res.iter().position(|v| !v.iter().all(|c| c.is_finite()));
            return Err(NewtonError::NonFinite {
                node: node.unwrap_or(0),
            });
        }
        if stats.residual <= params.tol {
            return Ok(stats);
        }
        if stats.iterations >= params.max_iter {
            return Err(NewtonError::MaxIterations(stats));
        }
        ws.res.iter_mut().for_each(|r| *r = -*r);
        solver
            .solve(&ws.jac, &mut ws.res)
            .map_err(NewtonError::Linear)?;
        for (xi, di) in x.iter_mut().zip(&ws.res) {
            *xi += di;
        }
        stats.iterations += 1;
    }
}
