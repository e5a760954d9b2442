//! Newton's method on the reduced step equations (docs/method.md §8–§10).
//!
//! Convergence test: the Euclidean norm of the residual over all free degrees of freedom,
//! in newtons (the momentum balance of the step divided by `h`), is at most
//! [`NewtonParams::tolerance`] of the step's force scale, or stagnates at the round-off floor
//! (see [`NewtonParams`]). The test is made before each solve, so `iterations` counts linear
//! solves (Jacobian factorizations) of the whole system.
//!
//! **Nonlinear elimination** ([`NewtonParams::elimination`]). On fine meshes the residual of a
//! step concentrates where the string is most nonlinear (near a free end: slack or compressed
//! elements, kinks at the scale of one element). There a full Newton step overshoots, and a
//! line search on the whole residual would shorten the step for the whole chain, so the bulk,
//! which the full step had right, crawls along with the few hard nodes. Instead, at the
//! predictor and at every trial point of the line search, the node ranges that carry the
//! residual (the nodes whose residual exceeds 5 % of the largest, in up to four separate
//! clusters — nearby clusters merge, the merging distance doubling from 19 nodes until at
//! most four are left — each widened by 8 nodes) are first solved alone, with the other
//! nodes held, by a local damped Newton iteration; the trial point is judged (Armijo) after
//! these local solves. This runs if the mesh is a chain of at least 64 nodes and the ranges
//! cover at most a third of it. The convergence test is that of global Newton, so every accepted step solves the
//! step equations to `tol` and keeps the energy balance. Where the step has one solution near
//! the predictor the result is the same; where it has several (a compressed free end with a
//! law that carries compression, for `h` beyond the element-scale stability limit)
//! elimination may reach another one.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::LinearSolveError;
use crate::linsolve::{Block, BlockJacobian, LinearSolver, block_thomas};
use crate::system::Vector;

/// Newton parameters.
///
/// Convergence test (docs/method.md §9, eq. (9.1)): `‖R‖₂ ≤ max(tol, rtol · F)`, where `F` [N] is the
/// force scale of the step, [`NewtonProblem::force_scale`]: the root-sum-square of the
/// magnitudes of every force term that enters the residual. Each nodal residual is a sum of
/// such terms, so its round-off is about `ε · F`; a test relative to `F` works alike for a
/// 20 N rubber string and a steel rope with `EA = 1e8 N`, where an absolute 1e-11 N lies below
/// round-off. With `rtol = 0` the test is absolute (the paper's `tol = 1e-11 N`).
///
/// Whatever the tolerance, an iterate at the round-off floor is converged: when a Newton
/// step no longer halves the residual (or the line search cannot reduce it) and the residual
/// is at most [`roundoff_floor`], the solve ends successfully ([`NewtonStats::at_roundoff`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonParams {
    /// Absolute tolerance [N] on the Euclidean norm of the force residual: alone when
    /// `rtol = 0`, otherwise a floor under `rtol · F`.
    pub tol: f64,
    /// Tolerance relative to the step's force scale `F` (dimensionless); 0 for a purely
    /// absolute test.
    pub rtol: f64,
    /// Largest number of iterations (linear solves) per step for a solve that stalls; one
    /// that still cuts its residual by at least 10 % per iteration may go on to
    /// `progress_extension` times this.
    pub max_iter: usize,
    /// How many times `max_iter` a steadily progressing solve may take (1: `max_iter` is a
    /// hard limit). Default 4.
    pub progress_extension: usize,
    /// Globalize with a backtracking line search on the merit function `½‖R‖²` (Armijo
    /// condition). An iterate whose strain leaves the material's domain or whose residual is
    /// not finite counts as too long a step. When `false`, plain Newton (full steps).
    pub line_search: bool,
    /// Nonlinear elimination of the region where the residual concentrates (see the module
    /// documentation); only with `line_search`, and only on chain meshes.
    pub elimination: bool,
}

/// Default relative tolerance: `‖R‖ ≤ 1e-12 F`. Converged residuals of real-unit ropes
/// (EA = 1 … 1e9 N) reach 0.9e-14 … 2e-14 `F` (40–90 ε), so this leaves a margin of about 50
/// over round-off.
pub const DEFAULT_RTOL: f64 = 1e-12;
/// Default absolute floor under the relative test [N]: it matters only for steps whose
/// forces are all below about 1e-3 N.
pub const DEFAULT_ATOL: f64 = 1e-15;
/// Round-off floor of the residual, summation part: `ROUNDOFF_FLOOR · ε · F`.
pub const ROUNDOFF_FLOOR: f64 = 1000.0;
/// Round-off floor of the residual, strain part: `ROUNDOFF_STRAIN · ε · K`, with `K` the
/// strain scale ([`NewtonProblem::strain_scale`]). A stiff element's stress can only change
/// in steps of `∂S̄/∂C · ulp(C)`, so a residual below that cannot be reached however small
/// the forces are (a steel rope at rest: `EA/2 · 2.2e-16 ≈ 1e-8 N` per element).
pub const ROUNDOFF_STRAIN: f64 = 16.0;
/// A Newton step that leaves more than this fraction of the residual has stagnated.
const STAGNATION_RATIO: f64 = 0.5;
/// Beyond `max_iter`, a solve goes on while each iteration leaves at most this fraction of
/// the residual (up to [`NewtonParams::progress_extension`] times `max_iter`).
const PROGRESS_RATIO: f64 = 0.9;

impl Default for NewtonParams {
    fn default() -> Self {
        Self {
            tol: DEFAULT_ATOL,
            rtol: DEFAULT_RTOL,
            max_iter: 25,
            progress_extension: 4,
            line_search: true,
            elimination: true,
        }
    }
}

impl NewtonParams {
    /// Default parameters with a purely absolute tolerance `tol` [N] (the paper's benchmark
    /// uses 1e-11 N).
    pub fn absolute(tol: f64) -> Self {
        Self {
            tol,
            rtol: 0.0,
            ..Self::default()
        }
    }
    /// The tolerance [N] for a step of force scale `scale` [N]; the absolute `tol` alone if
    /// the scale is not finite (forces whose squares overflow), so that an overflow never
    /// makes every residual acceptable.
    pub fn tolerance(&self, scale: f64) -> f64 {
        if scale.is_finite() {
            self.tol.max(self.rtol * scale)
        } else {
            self.tol
        }
    }
}

/// Round-off floor [N] of a residual with force scale `force` and strain scale `strain` [N]:
/// `ε (ROUNDOFF_FLOOR · force + ROUNDOFF_STRAIN · strain)`.
pub fn roundoff_floor(force: f64, strain: f64) -> f64 {
    let floor = f64::EPSILON * (ROUNDOFF_FLOOR * force + ROUNDOFF_STRAIN * strain);
    // Scales that overflow give no floor (never a licence to accept any residual).
    if floor.is_finite() { floor } else { 0.0 }
}

/// Smallest chain (in nodes) on which nonlinear elimination is tried.
const ELIMINATION_MIN_NODES: usize = 64;
/// Nodes whose residual exceeds this fraction of the largest one form the local ranges.
const ELIMINATION_THRESHOLD: f64 = 0.05;
/// Each local range is widened by this many nodes on each side.
const ELIMINATION_PAD: usize = 8;
/// The local solve stops when its residual is below this fraction of the residual outside.
const ELIMINATION_REDUCTION: f64 = 1e-3;
/// Most local iterations per range and elimination.
const ELIMINATION_MAX_ITER: usize = 30;

/// Armijo constant of the line search: accept `α` if `φ(α) ≤ (1 − 2σα) φ(0)`.
const ARMIJO_SIGMA: f64 = 1e-4;
/// Smallest step length of the line search before it gives up.
const ALPHA_MIN: f64 = 1.0 / 1024.0;
/// A full Newton step whose residual quadratic convergence predicts below this fraction of
/// the tolerance is evaluated first without the Jacobian.
const PREDICTED_MARGIN: f64 = 0.1;

/// What one Newton solve did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NewtonStats {
    /// Iterations (linear solves).
    pub iterations: usize,
    /// Final residual norm [N].
    pub residual: f64,
    /// Force scale `F` of the step [N], taken at the predictor (see [`NewtonParams`]).
    pub force_scale: f64,
    /// Strain scale `K` of the step [N], taken at the predictor (see [`ROUNDOFF_STRAIN`]).
    pub strain_scale: f64,
    /// The tolerance the residual was tested against [N].
    pub tolerance: f64,
    /// The solve ended at the round-off floor (stagnation) instead of below `tolerance`.
    pub at_roundoff: bool,
    /// Line-search backtracks (step halvings) in all iterations.
    pub backtracks: usize,
    /// Iterations of the local solves of nonlinear elimination (each on a node range, not
    /// counted in `iterations`).
    pub local_iterations: usize,
    /// Nodes in all local solves together (`Σ` range length × local iterations), to compare
    /// their cost with that of the global iterations.
    pub local_node_iterations: usize,
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
    /// Force scale [N] of the step (a full [`Self::evaluate`] may measure it; the step
    /// equations do so at the predictor): the root-sum-square of the
    /// magnitudes of the force terms whose sum is the residual. Relative tolerances and the
    /// round-off floor are measured against it; 0 (the default) makes both absolute.
    fn force_scale(&self) -> f64 {
        0.0
    }
    /// Strain scale [N] of the step (measured like [`Self::force_scale`]): the root-sum-square over the
    /// elements of the internal force's change for a relative strain change of 1 (`2 ∂q/∂C ·
    /// C · |r'|` on each node). The residual cannot resolve less than about `ε` times it.
    fn strain_scale(&self) -> f64 {
        0.0
    }
    /// `true` if the Jacobian is block tridiagonal in node order (a chain mesh), so that
    /// [`Self::evaluate_nodes`] may be called on a node range.
    fn chain(&self) -> bool {
        false
    }
    /// Like [`Self::evaluate`], but only for the residual rows and Jacobian blocks of the node
    /// range `nodes` (the diagonal blocks of its nodes and the coupling blocks of the elements
    /// touching it); every other row and block is left as it was. Only called when
    /// [`Self::chain`] is `true`.
    fn evaluate_nodes(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        jac: Option<&mut BlockJacobian<D>>,
        nodes: std::ops::Range<usize>,
    ) -> Result<(), Self::Error> {
        let _ = nodes;
        self.evaluate(x, res, jac)
    }
}

/// Why a Newton solve failed.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum NewtonError<E> {
    /// The evaluation failed.
    Eval(E),
    /// The linear solve failed.
    Linear(LinearSolveError),
    /// The residual is NaN or infinite at this node, or (`overflow`) every entry is finite
    /// but its norm overflows; `node` is then the node with the largest residual.
    NonFinite {
        /// Node index.
        node: usize,
        /// Finite entries whose norm overflows (forces of about 1e154 N and more).
        overflow: bool,
    },
    /// No convergence within the iteration limit.
    MaxIterations(NewtonStats),
    /// The line search found no acceptable step length down to its minimum.
    LineSearch(NewtonStats),
    /// The stop flag was set; the solve ended between iterations.
    Interrupted(NewtonStats),
}

/// Newton workspace (residual, direction, Jacobian storage), allocated once.
#[derive(Debug, Clone)]
pub struct NewtonWorkspace<const D: usize> {
    res: Vec<Vector<D>>,
    dir: Vec<Vector<D>>,
    x_old: Vec<Vector<D>>,
    jac: BlockJacobian<D>,
    /// Block-Thomas workspace of the local solves.
    thomas: Vec<Block<D>>,
    last: NewtonStats,
}

impl<const D: usize> NewtonWorkspace<D> {
    /// Workspace for a mesh.
    pub fn new(mesh: &crate::mesh::Mesh) -> Self {
        Self::with_slots(mesh, 0)
    }
    /// Workspace for a mesh and `slots` unknowns after its nodes (rigid bodies).
    pub fn with_slots(mesh: &crate::mesh::Mesh, slots: usize) -> Self {
        let n = mesh.n_nodes();
        let all = n + slots;
        Self {
            res: vec![Vector::zeros(); all],
            dir: vec![Vector::zeros(); all],
            x_old: vec![Vector::zeros(); all],
            jac: BlockJacobian::with_slots(mesh, slots),
            thomas: vec![Block::zeros(); n],
            last: NewtonStats::default(),
        }
    }
    /// Counts of the last solve, whether it converged or not.
    pub fn last_stats(&self) -> &NewtonStats {
        &self.last
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
/// evaluation error ends the solve. With `params.elimination` (and the line search), local
/// solves run at the predictor and at every trial point (module documentation).
///
/// `stop`, when given and set, ends the solve between two iterations with
/// [`NewtonError::Interrupted`] (a long solve on a huge mesh can thus be interrupted).
pub fn solve<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    solver: &mut dyn LinearSolver<D>,
    params: &NewtonParams,
    stop: Option<&AtomicBool>,
) -> Result<NewtonStats, NewtonError<P::Error>> {
    let mut stats = NewtonStats::default();
    let result = solve_counting(problem, x, ws, solver, params, stop, &mut stats);
    ws.last = stats;
    result.map(|()| stats)
}

/// [`solve`], keeping its counts in `stats` however it ends.
fn solve_counting<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    solver: &mut dyn LinearSolver<D>,
    params: &NewtonParams,
    stop: Option<&AtomicBool>,
    stats: &mut NewtonStats,
) -> Result<(), NewtonError<P::Error>> {
    stats.residual = evaluate_checked(problem, x, ws)?;
    let eliminate = params.elimination
        && params.line_search
        && problem.chain()
        && x.len() >= ELIMINATION_MIN_NODES;
    stats.force_scale = problem.force_scale();
    stats.strain_scale = problem.strain_scale();
    stats.tolerance = params.tolerance(stats.force_scale);
    if eliminate && stats.residual > stats.tolerance {
        stats.residual =
            match eliminate_measured(problem, x, ws, stats.residual, stats.tolerance, stats) {
                Ok(r) if r.is_finite() => r,
                Ok(_) => return Err(non_finite(&ws.res)),
                Err(e) => return Err(NewtonError::Eval(e)),
            };
    }
    // Residual before the last iteration, to recognise stagnation, and the one before it.
    let mut previous = f64::INFINITY;
    let mut older;
    loop {
        if stats.residual <= stats.tolerance {
            return Ok(());
        }
        if stats.residual > STAGNATION_RATIO * previous
            && stats.residual <= roundoff_floor(stats.force_scale, stats.strain_scale)
        {
            stats.at_roundoff = true;
            return Ok(());
        }
        // At the iteration limit, a solve that still cuts its residual steadily goes on (up
        // to `progress_extension` times the limit): Newton converges only linearly while a
        // tension-only element's strain crosses C = 1 within the step by a small difference,
        // because the discrete gradient then bends over that difference (docs/method.md §10).
        let progressing = stats.residual <= PROGRESS_RATIO * previous;
        if stats.iterations >= params.max_iter
            && (!progressing
                || stats.iterations >= params.progress_extension.max(1) * params.max_iter)
        {
            return Err(NewtonError::MaxIterations(*stats));
        }
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Err(NewtonError::Interrupted(*stats));
        }
        older = previous;
        previous = stats.residual;
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
        // The full step's residual as quadratic convergence predicts it from the last two,
        // `r_{k+1} ≈ r_k³/r_{k−1}²`: far below the tolerance, the full step is first tried
        // without its Jacobian, which a converged solve never uses.
        let predicted = if older.is_finite() {
            previous * (previous / older) * (previous / older)
        } else {
            f64::INFINITY
        };
        let mut alpha = 1.0;
        loop {
            for ((xi, x0), di) in x.iter_mut().zip(&ws.x_old).zip(&ws.dir) {
                *xi = x0 + di * alpha;
            }
            if alpha == 1.0 && predicted <= PREDICTED_MARGIN * stats.tolerance {
                let r = match problem.evaluate(x, &mut ws.res, None) {
                    Ok(()) => norm(&ws.res),
                    Err(_) => f64::INFINITY,
                };
                // Accepted as the full evaluation below would accept it (converged, Armijo);
                // otherwise that evaluation follows, with the Jacobian.
                if r <= stats.tolerance && r * r <= (1.0 - 2.0 * ARMIJO_SIGMA) * phi0 {
                    stats.residual = r;
                    break;
                }
            }
            let mut r = match problem.evaluate(x, &mut ws.res, Some(&mut ws.jac)) {
                Ok(()) => norm(&ws.res),
                Err(_) => f64::INFINITY,
            };
            // The trial point is judged after the local solves: a full Newton step that is
            // right for the bulk of the chain is not damped for the nonlinearity of a few
            // nodes, which the local solves take care of.
            if eliminate && r.is_finite() && r > stats.tolerance {
                r = eliminate_measured(problem, x, ws, r, stats.tolerance, stats)
                    .unwrap_or(f64::INFINITY);
            }
            if r.is_finite() && r * r <= (1.0 - 2.0 * ARMIJO_SIGMA * alpha) * phi0 {
                stats.residual = r;
                break;
            }
            alpha *= 0.5;
            stats.backtracks += 1;
            if alpha < ALPHA_MIN {
                // Leave x at the last accepted iterate.
                x.copy_from_slice(&ws.x_old);
                if stats.residual <= roundoff_floor(stats.force_scale, stats.strain_scale) {
                    // No direction reduces a residual that is already round-off: converged.
                    // The workspace (and the problem's outputs) must be those of `x`.
                    evaluate_checked(problem, x, ws)?;
                    stats.at_roundoff = true;
                    return Ok(());
                }
                return Err(NewtonError::LineSearch(*stats));
            }
        }
    }
}

/// Runs [`eliminate_locally`] at `x`, whose residual norm `residual` and Jacobian the
/// workspace holds, and returns the residual norm afterwards (the workspace is current for the
/// returned `x`).
fn eliminate_measured<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    residual: f64,
    tol: f64,
    stats: &mut NewtonStats,
) -> Result<f64, P::Error> {
    Ok(
        match eliminate_locally(problem, x, ws, residual, tol, stats) {
            Elimination::Unchanged => residual,
            Elimination::Refreshed => norm(&ws.res),
            Elimination::Stale => {
                problem.evaluate(x, &mut ws.res, Some(&mut ws.jac))?;
                norm(&ws.res)
            }
        },
    )
}

/// What a nonlinear elimination left in the workspace.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Elimination {
    /// Nothing was evaluated; `x` and the workspace are as before.
    Unchanged,
    /// `x` may have changed and the workspace is current for it.
    Refreshed,
    /// The workspace must be evaluated again at `x`.
    Stale,
}

/// One nonlinear elimination: picks the node ranges that carry the residual in `ws` (which
/// must hold `R(x)`, of norm `residual`, and its Jacobian; at most four separate clusters,
/// together at most a third of the chain) and runs damped Newton on each with the rest of `x`
/// held.
/// On return `x` holds the last accepted local iterate and, if it says
/// [`Elimination::Refreshed`], `ws` holds its residual and Jacobian (the rows next to the
/// range, which depend on it, included).
fn eliminate_locally<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    residual: f64,
    tol: f64,
    stats: &mut NewtonStats,
) -> Elimination {
    let n = x.len();
    // Squared norms throughout: this runs over the whole chain.
    let r2_max = ws.res.iter().map(|v| v.norm_squared()).fold(0.0, f64::max);
    let thr2 = ELIMINATION_THRESHOLD * ELIMINATION_THRESHOLD * r2_max;
    // Clusters of large-residual nodes; two clusters closer than `gap` merge. The smallest
    // gap keeps the padded ranges two nodes apart (a range's refresh touches one row on each
    // side); while there are more clusters than ranges, the gap doubles.
    let mut gap = 2 * ELIMINATION_PAD + 3;
    let (ranges, count) = loop {
        if let Some(found) = clusters(&ws.res, thr2, gap) {
            break found;
        }
        gap *= 2;
        if gap > n / 3 {
            return Elimination::Unchanged;
        }
    };
    if count == 0 {
        return Elimination::Unchanged;
    }
    let ranges = &ranges[..count];
    let covered: usize = ranges.iter().map(|r| r.len()).sum();
    if covered > n / 3 {
        return Elimination::Unchanged;
    }
    let r2_in: f64 = ranges
        .iter()
        .map(|r| {
            ws.res[r.clone()]
                .iter()
                .map(|v| v.norm_squared())
                .sum::<f64>()
        })
        .sum();
    let r_out = (residual * residual - r2_in).max(0.0).sqrt();
    let target = (ELIMINATION_REDUCTION * r_out).max(tol);
    let mut outcome = Elimination::Unchanged;
    for range in ranges {
        match solve_range(problem, x, ws, range.clone(), target, stats) {
            Elimination::Unchanged => {}
            Elimination::Refreshed => {
                if outcome == Elimination::Unchanged {
                    outcome = Elimination::Refreshed;
                }
            }
            Elimination::Stale => outcome = Elimination::Stale,
        }
    }
    outcome
}

/// The padded ranges of the clusters of nodes whose squared residual exceeds `thr2`, two
/// clusters merging when at most `gap` nodes apart, and their number; `None` if there are
/// more than four.
fn clusters<const D: usize>(
    res: &[Vector<D>],
    thr2: f64,
    gap: usize,
) -> Option<([std::ops::Range<usize>; 4], usize)> {
    let n = res.len();
    let mut ranges = [0..0, 0..0, 0..0, 0..0];
    let mut count = 0;
    let mut current: Option<(usize, usize)> = None;
    for (i, v) in res.iter().enumerate() {
        if v.norm_squared() <= thr2 {
            continue;
        }
        current = match current {
            Some((first, last)) if i - last <= gap => Some((first, i)),
            Some((first, last)) => {
                if count == ranges.len() {
                    return None;
                }
                ranges[count] = padded(first, last, n);
                count += 1;
                Some((i, i))
            }
            None => Some((i, i)),
        };
    }
    if let Some((first, last)) = current {
        if count == ranges.len() {
            return None;
        }
        ranges[count] = padded(first, last, n);
        count += 1;
    }
    Some((ranges, count))
}

/// The node range `first − pad .. last + pad + 1`, clipped to the chain.
fn padded(first: usize, last: usize, n: usize) -> std::ops::Range<usize> {
    first.saturating_sub(ELIMINATION_PAD)..(last + ELIMINATION_PAD + 1).min(n)
}

/// Damped Newton on the node range `range` with the rest of `x` held, until the range's
/// residual is at most `target`.
fn solve_range<const D: usize, P: NewtonProblem<D>>(
    problem: &mut P,
    x: &mut [Vector<D>],
    ws: &mut NewtonWorkspace<D>,
    range: std::ops::Range<usize>,
    target: f64,
    stats: &mut NewtonStats,
) -> Elimination {
    let n = x.len();
    // The workspace holds R(x) and J(x), so the range's rows are current.
    let mut r = norm(&ws.res[range.clone()]);
    let mut evaluated = false;
    'local: for _ in 0..ELIMINATION_MAX_ITER {
        if r <= target {
            break;
        }
        for (d, res) in ws.dir[range.clone()].iter_mut().zip(&ws.res[range.clone()]) {
            *d = -res;
        }
        let (diag, off) = (
            &ws.jac.diag[range.clone()],
            &ws.jac.off[range.start..range.end - 1],
        );
        if block_thomas(diag, off, &mut ws.thomas, &mut ws.dir[range.clone()], None).is_err() {
            break;
        }
        stats.local_iterations += 1;
        stats.local_node_iterations += range.len();
        ws.x_old[range.clone()].copy_from_slice(&x[range.clone()]);
        let mut alpha = 1.0;
        loop {
            for ((xi, x0), di) in x[range.clone()]
                .iter_mut()
                .zip(&ws.x_old[range.clone()])
                .zip(&ws.dir[range.clone()])
            {
                *xi = x0 + di * alpha;
            }
            evaluated = true;
            let ok = problem
                .evaluate_nodes(x, &mut ws.res, Some(&mut ws.jac), range.clone())
                .is_ok();
            let r_new = if ok {
                norm(&ws.res[range.clone()])
            } else {
                f64::INFINITY
            };
            if r_new.is_finite() && r_new * r_new <= (1.0 - 2.0 * ARMIJO_SIGMA * alpha) * r * r {
                r = r_new;
                break;
            }
            alpha *= 0.5;
            if alpha < ALPHA_MIN {
                x[range.clone()].copy_from_slice(&ws.x_old[range.clone()]);
                break 'local;
            }
        }
    }
    if evaluated {
        // The range's rows are those of the last trial, and the two rows next to it depend
        // on the range's nodes: evaluate the widened range at the final x.
        let wide = range.start.saturating_sub(1)..(range.end + 1).min(n);
        if problem
            .evaluate_nodes(x, &mut ws.res, Some(&mut ws.jac), wide)
            .is_err()
        {
            // Cannot happen for an x that was evaluated before; let the caller evaluate all.
            return Elimination::Stale;
        }
        return Elimination::Refreshed;
    }
    Elimination::Unchanged
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
    match res.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
        Some(node) => NewtonError::NonFinite {
            node,
            overflow: false,
        },
        None => NewtonError::NonFinite {
            node: res
                .iter()
                .map(|v| v.amax())
                .enumerate()
                .fold(
                    (0, 0.0),
                    |best, (i, m)| if m > best.1 { (i, m) } else { best },
                )
                .0,
            overflow: true,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linsolve::BlockTridiagonal;
    use crate::mesh::Mesh;

    /// A chain of scalar unknowns: `R_i = x_i + x_i³ + κ (2x_i − x_{i−1} − x_{i+1}) − b_i`
    /// (missing neighbours count as 0).
    struct Cubic {
        b: Vec<f64>,
        kappa: f64,
    }

    impl NewtonProblem<1> for Cubic {
        type Error = ();
        fn evaluate(
            &mut self,
            x: &[Vector<1>],
            res: &mut [Vector<1>],
            jac: Option<&mut BlockJacobian<1>>,
        ) -> Result<(), ()> {
            self.evaluate_nodes(x, res, jac, 0..x.len())
        }
        fn chain(&self) -> bool {
            true
        }
        fn evaluate_nodes(
            &mut self,
            x: &[Vector<1>],
            res: &mut [Vector<1>],
            mut jac: Option<&mut BlockJacobian<1>>,
            nodes: std::ops::Range<usize>,
        ) -> Result<(), ()> {
            let n = x.len();
            let at = |i: isize| {
                if i < 0 || i as usize >= n {
                    0.0
                } else {
                    x[i as usize][0]
                }
            };
            for i in nodes {
                let xi = x[i][0];
                let lap = 2.0 * xi - at(i as isize - 1) - at(i as isize + 1);
                res[i][0] = xi + xi * xi * xi + self.kappa * lap - self.b[i];
                if let Some(j) = jac.as_deref_mut() {
                    j.diag[i][(0, 0)] = 1.0 + 3.0 * xi * xi + 2.0 * self.kappa;
                    if i + 1 < n {
                        j.off[i] = [Block::from_element(-self.kappa); 2];
                    }
                }
            }
            Ok(())
        }
    }

    /// Residual concentrated at both ends: elimination solves two separate ranges, leaves the
    /// workspace equal to a full evaluation, and the global solve then converges.
    #[test]
    fn elimination_handles_two_separate_clusters() {
        let n = 200;
        let mut b = vec![0.0; n];
        for i in (0..5).chain(n - 5..n) {
            b[i] = 5.0;
        }
        let mut p = Cubic { b, kappa: 0.2 };
        let mesh = Mesh::uniform_chain(n - 1, 1.0).unwrap();
        let mut ws = NewtonWorkspace::<1>::new(&mesh);
        let mut x = vec![Vector::<1>::zeros(); n];
        let residual = evaluate_checked(&mut p, &x, &mut ws).unwrap();
        let mut stats = NewtonStats::default();
        let out = eliminate_locally(&mut p, &mut x, &mut ws, residual, 1e-12, &mut stats);
        assert_eq!(out, Elimination::Refreshed);
        assert!(x[0][0] > 1.0 && x[n - 1][0] > 1.0, "both ends solved");
        assert_eq!(x[n / 2][0], 0.0, "the middle is held");
        // The refreshed workspace is what a full evaluation gives.
        let (res, jac) = (ws.res.clone(), ws.jac.clone());
        evaluate_checked(&mut p, &x, &mut ws).unwrap();
        assert_eq!(res, ws.res);
        assert_eq!(jac, ws.jac);
        // Only the coupling into the held middle is left.
        assert!(norm(&ws.res) < 0.1 * 5.0, "residual {}", norm(&ws.res));
        let mut solver = BlockTridiagonal::<1>::new(&mesh).unwrap();
        let stats = solve(
            &mut p,
            &mut x,
            &mut ws,
            &mut solver,
            &NewtonParams::absolute(1e-11),
            None,
        )
        .unwrap();
        assert!(stats.residual <= 1e-11);
    }

    /// Ten residual peaks 30 nodes apart near one end (as on a crumpled free end of a fine
    /// mesh): more clusters than ranges, so nearby ones merge, and all peaks are solved while
    /// the far end is held.
    #[test]
    fn elimination_merges_many_clusters() {
        let n = 2000;
        let mut b = vec![0.0; n];
        let peaks: Vec<usize> = (0..10).map(|k| n - 10 - 30 * k).collect();
        for &i in &peaks {
            b[i] = 5.0;
        }
        let mut p = Cubic { b, kappa: 0.2 };
        let mesh = Mesh::uniform_chain(n - 1, 1.0).unwrap();
        let mut ws = NewtonWorkspace::<1>::new(&mesh);
        let mut x = vec![Vector::<1>::zeros(); n];
        // The smallest merging distance (19 nodes) leaves ten clusters.
        let r2_max = ws_res_max2(&mut p, &x, &mut ws);
        let thr2 = ELIMINATION_THRESHOLD * ELIMINATION_THRESHOLD * r2_max;
        assert!(clusters(&ws.res, thr2, 2 * ELIMINATION_PAD + 3).is_none());
        let residual = norm(&ws.res);
        let mut stats = NewtonStats::default();
        let out = eliminate_locally(&mut p, &mut x, &mut ws, residual, 1e-12, &mut stats);
        assert_eq!(out, Elimination::Refreshed);
        for &i in &peaks {
            assert!(
                x[i][0] > 1.0,
                "peak at node {i} not solved: x = {}",
                x[i][0]
            );
        }
        assert_eq!(x[0][0], 0.0, "the far end is held");
        assert!(
            norm(&ws.res) < 1e-2 * residual,
            "residual {}",
            norm(&ws.res)
        );
    }

    /// A cubic chain that raises the stop flag on its second evaluation, as a Ctrl-C during a
    /// long solve would.
    struct Raising<'a> {
        inner: Cubic,
        flag: &'a AtomicBool,
        evaluations: usize,
    }

    impl NewtonProblem<1> for Raising<'_> {
        type Error = ();
        fn evaluate(
            &mut self,
            x: &[Vector<1>],
            res: &mut [Vector<1>],
            jac: Option<&mut BlockJacobian<1>>,
        ) -> Result<(), ()> {
            self.evaluations += 1;
            if self.evaluations == 2 {
                self.flag.store(true, Ordering::Relaxed);
            }
            self.inner.evaluate(x, res, jac)
        }
    }

    /// A stop request is honoured between Newton iterations, not only between
    /// steps (a step on a huge mesh can take minutes).
    #[test]
    fn stop_flag_ends_the_solve_between_iterations() {
        let n = 10;
        let flag = AtomicBool::new(false);
        let mut p = Raising {
            inner: Cubic {
                b: vec![50.0; n],
                kappa: 0.2,
            },
            flag: &flag,
            evaluations: 0,
        };
        let mesh = Mesh::uniform_chain(n - 1, 1.0).unwrap();
        let mut ws = NewtonWorkspace::<1>::new(&mesh);
        let mut solver = BlockTridiagonal::<1>::new(&mesh).unwrap();
        let mut x = vec![Vector::<1>::zeros(); n];
        let params = NewtonParams::absolute(1e-11);
        match solve(&mut p, &mut x, &mut ws, &mut solver, &params, Some(&flag)) {
            Err(NewtonError::Interrupted(stats)) => assert_eq!(stats.iterations, 1),
            other => panic!("expected an interruption, got {other:?}"),
        }
        // Without the flag the same problem converges.
        let (mut p, mut x) = (
            Cubic {
                b: vec![50.0; n],
                kappa: 0.2,
            },
            vec![Vector::<1>::zeros(); n],
        );
        let stats = solve(&mut p, &mut x, &mut ws, &mut solver, &params, None).unwrap();
        assert!(
            stats.iterations > 2,
            "converged too fast to test: {}",
            stats.iterations
        );
    }

    /// A cubic chain that counts its evaluations with and without the Jacobian, and with
    /// `always` assembles the Jacobian even when the solver does not ask for it.
    struct Counting {
        inner: Cubic,
        always: bool,
        with_jacobian: usize,
        without: usize,
        scratch: BlockJacobian<1>,
    }

    impl NewtonProblem<1> for Counting {
        type Error = ();
        fn evaluate(
            &mut self,
            x: &[Vector<1>],
            res: &mut [Vector<1>],
            jac: Option<&mut BlockJacobian<1>>,
        ) -> Result<(), ()> {
            match jac {
                Some(j) => {
                    self.with_jacobian += 1;
                    self.inner.evaluate(x, res, Some(j))
                }
                None if self.always => {
                    self.with_jacobian += 1;
                    self.inner.evaluate(x, res, Some(&mut self.scratch))
                }
                None => {
                    self.without += 1;
                    self.inner.evaluate(x, res, None)
                }
            }
        }
    }

    /// A solve that converges quadratically ends with a residual-only evaluation: one
    /// Jacobian per trial point whose Jacobian is used, not one per evaluation, and the same iterates, to the bit,
    /// as when every evaluation assembles it.
    #[test]
    fn converged_step_is_evaluated_without_its_jacobian() {
        let n = 40;
        let mesh = Mesh::uniform_chain(n - 1, 1.0).unwrap();
        let mut ws = NewtonWorkspace::<1>::new(&mesh);
        let mut solver = BlockTridiagonal::<1>::new(&mesh).unwrap();
        let params = NewtonParams::absolute(1e-9);
        let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * (i as f64 * 0.7).sin()).collect();
        let run = |always: bool, ws: &mut NewtonWorkspace<1>, solver: &mut BlockTridiagonal<1>| {
            let mut p = Counting {
                inner: Cubic {
                    b: b.clone(),
                    kappa: 0.2,
                },
                always,
                with_jacobian: 0,
                without: 0,
                scratch: BlockJacobian::zeros(&mesh),
            };
            let mut x = vec![Vector::<1>::zeros(); n];
            let stats = solve(&mut p, &mut x, ws, solver, &params, None).unwrap();
            (x, stats, p.with_jacobian, p.without)
        };
        let (x, stats, jacobians, without) = run(false, &mut ws, &mut solver);
        assert!(stats.iterations >= 3, "{} iterations", stats.iterations);
        assert_eq!(without, 1, "the converged evaluation");
        // One Jacobian per trial point of the line search (a full step or a shortened one).
        let trials = stats.iterations + stats.backtracks;
        assert_eq!(jacobians, trials, "{stats:?}");
        let (x_all, stats_all, jacobians_all, without_all) = run(true, &mut ws, &mut solver);
        assert_eq!(without_all, 0);
        assert_eq!(jacobians_all, trials + 1);
        assert_eq!(stats_all.iterations, stats.iterations);
        assert_eq!(stats_all.residual.to_bits(), stats.residual.to_bits());
        for (a, b) in x.iter().zip(&x_all) {
            assert_eq!(a[0].to_bits(), b[0].to_bits());
        }
    }

    /// Forces whose squares overflow give an infinite force scale, which
    /// must not make every residual acceptable.
    #[test]
    fn overflowing_scale_falls_back_to_the_absolute_tolerance() {
        let p = NewtonParams::default();
        assert_eq!(p.tolerance(f64::INFINITY), DEFAULT_ATOL);
        assert_eq!(p.tolerance(f64::NAN), DEFAULT_ATOL);
        assert_eq!(p.tolerance(10.0), 10.0 * DEFAULT_RTOL);
        assert_eq!(roundoff_floor(f64::INFINITY, 1.0), 0.0);
        assert!(roundoff_floor(1.0, 1.0) > 0.0);
    }

    /// Evaluates at `x` and returns the largest squared nodal residual.
    fn ws_res_max2(p: &mut Cubic, x: &[Vector<1>], ws: &mut NewtonWorkspace<1>) -> f64 {
        evaluate_checked(p, x, ws).unwrap();
        ws.res.iter().map(|v| v.norm_squared()).fold(0.0, f64::max)
    }
}
