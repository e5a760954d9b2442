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
    /// Globalize with a backtracking line search on the merit function `½‖R‖²` (Armijo
    /// condition). An iterate whose strain leaves the material's domain or whose residual is
    /// not finite counts as too long a step. When `false`, plain Newton (full steps).
    pub line_search: bool,
}

impl Default for NewtonParams {
    fn default() -> Self {
        Self {
            tol: 1e-11,
            max_iter: 25,
            line_search: true,
        }
    }
}

/// Armijo constant of the line search: accept `α` if `φ(α) ≤ (1 − 2σα) φ(0)`.
const ARMIJO_SIGMA: f64 = 1e-4;
/// Smallest step length of the line search before it gives up.
const ALPHA_MIN: f64 = 1.0 / 1024.0;

/// What one Newton solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NewtonStats {
    /// Iterations (linear solves).
    pub iterations: usize,
    /// Final residual norm [N].
    pub residual: f64,
    /// Line-search backtracks (step halvings) in all iterations.
    pub backtracks: usize,
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
    /// The line search found no acceptable step length down to its minimum.
    LineSearch(NewtonStats),
}

/// Newton workspace (residual, direction, Jacobian storage), allocated once.
#[derive(Debug, Clone)]
pub struct NewtonWorkspace<const D: usize> {
    res: Vec<Vector<D>>,
    dir: Vec<Vector<D>>,
    x_old: Vec<Vector<D>>,
    jac: BlockJacobian<D>,
}

impl<const D: usize> NewtonWorkspace<D> {
    /// Workspace for a mesh.
    pub fn new(mesh: &crate::mesh::Mesh) -> Self {
        let n = mesh.n_nodes();
        Self {
            res: vec![Vector::zeros(); n],
            dir: vec![Vector::zeros(); n],
            x_old: vec![Vector::zeros(); n],
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
///
/// With `params.line_search`, each Newton direction `d = −J⁻¹R` is tried with step lengths
/// `α = 1, ½, ¼, …` until `½‖R(x + αd)‖² ≤ (1 − 2σα) ½‖R(x)‖²`; an evaluation error or a
/// non-finite residual at a trial point also halves `α`. Without it, `α = 1` always and an
/// evaluation error ends the solve.
pub fn solve<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    solver: &mut dyn LinearSolver<D>,
    params: &NewtonParams,
) -> Result<NewtonStats, NewtonError<P::Error>> {
    let mut stats = NewtonStats {
        residual: evaluate_checked(problem, x, ws)?,
        ..Default::default()
    };
    loop {
        if stats.residual <= params.tol {
            return Ok(stats);
        }
        if stats.iterations >= params.max_iter {
            return Err(NewtonError::MaxIterations(stats));
        }
        for (d, r) in ws.dir.iter_mut().zip(&ws.res) {
            *d = -r;
        }
        solver
            .solve(&ws.jac, &mut ws.dir)
            .map_err(NewtonError::Linear)?;
        stats.iterations += 1;
        if !params.line_search {
            for (xi, di) in x.iter_mut().zip(&ws.dir) {
                *xi += di;
            }
            stats.residual = evaluate_checked(problem, x, ws)?;
            continue;
        }
        ws.x_old.copy_from_slice(x);
        let phi0 = stats.residual * stats.residual;
        let mut alpha = 1.0;
        loop {
            for ((xi, x0), di) in x.iter_mut().zip(&ws.x_old).zip(&ws.dir) {
                *xi = x0 + di * alpha;
            }
            let ok = problem.evaluate(x, &mut ws.res, Some(&mut ws.jac)).is_ok();
            let r = if ok { norm(&ws.res) } else { f64::INFINITY };
            if r.is_finite() && r * r <= (1.0 - 2.0 * ARMIJO_SIGMA * alpha) * phi0 {
                stats.residual = r;
                break;
            }
            alpha *= 0.5;
            stats.backtracks += 1;
            if alpha < ALPHA_MIN {
                // Leave x at the last accepted iterate.
                x.copy_from_slice(&ws.x_old);
                return Err(NewtonError::LineSearch(stats));
            }
        }
    }
}

/// Evaluates residual and Jacobian at `x`; returns the residual norm, which must be finite.
fn evaluate_checked<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &[Vector<D>],
    ws: &mut NewtonWorkspace<D>,
) -> Result<f64, NewtonError<P::Error>> {
    problem
        .evaluate(x, &mut ws.res, Some(&mut ws.jac))
        .map_err(NewtonError::Eval)?;
    let r = norm(&ws.res);
    if r.is_finite() {
        Ok(r)
    } else {
        Err(non_finite(&ws.res))
    }
}

fn non_finite<const D: usize, E>(res: &[Vector<D>]) -> NewtonError<E> {
    let node = res.iter().position(|v| !v.iter().all(|c| c.is_finite()));
    NewtonError::NonFinite {
        node: node.unwrap_or(0),
    }
}
