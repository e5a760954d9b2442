//! Symmetric generalized eigenproblems `K φ = λ M φ` for natural frequencies `ω = √λ` about
//! an equilibrium: [`dense_generalized`] returns every eigenpair of small dense matrices
//! (Cholesky of `M`, standard form, self-adjoint eigendecomposition), and
//! [`lanczos_shift_invert`] returns the few eigenpairs just above a shift `σ` of large sparse
//! problems, with the linear solves by `K − σM` left to the caller's own factorization. The
//! Lanczos results are checked against the dense decomposition and against the closed-form
//! spectrum of the taut string in this module's tests.
//!
//! Conventions: `λ` has the units of `K/M` (for stiffness [N/m] and mass [kg], rad²/s²);
//! eigenvectors are `M`-orthonormal (`Φᵀ M Φ = I`), so they carry units of `M^(-1/2)`; their
//! sign is arbitrary.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::Num;
use faer::linalg::solvers::LltError;
use faer::{Mat, Side};
use thiserror::Error;

/// Why an eigenproblem could not be solved.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum EigenError {
    /// A matrix or vector has the wrong size.
    #[error("size mismatch: {what} is {got}, expected {expected}")]
    SizeMismatch {
        /// What was measured (e.g. "M rows").
        what: &'static str,
        /// The size required.
        expected: usize,
        /// The size given.
        got: usize,
    },
    /// An input entry is NaN or infinite.
    #[error("{what} has a non-finite entry {} at ({row}, {col})", Num(*value))]
    NonFinite {
        /// Which matrix.
        what: &'static str,
        /// Row index.
        row: usize,
        /// Column index.
        col: usize,
        /// The entry.
        value: f64,
    },
    /// A matrix that must be symmetric is not (beyond `1e-8` of its largest entry).
    #[error(
        "{what} is not symmetric: entries ({row}, {col}) and ({col}, {row}) differ by {} \
         (largest entry {})",
        Num(*difference),
        Num(*scale)
    )]
    NotSymmetric {
        /// Which matrix.
        what: &'static str,
        /// Row index of the worst pair.
        row: usize,
        /// Column index of the worst pair.
        col: usize,
        /// `|a_rc − a_cr|`.
        difference: f64,
        /// Largest `|a_ij|`.
        scale: f64,
    },
    /// The Cholesky factorization of `M` met a non-positive pivot.
    #[error("the mass matrix M is not positive definite (Cholesky pivot {index} is not positive)")]
    NotPositiveDefinite {
        /// Index of the failing pivot.
        index: usize,
    },
    /// A nonzero vector has a non-positive `M`-norm, so `M` is not positive definite.
    #[error(
        "the mass matrix M is not positive definite: a nonzero vector x has xᵀMx = {}",
        Num(*value)
    )]
    MassNotPositive {
        /// The value of `xᵀ M x`.
        value: f64,
    },
    /// The dense self-adjoint eigensolver did not converge.
    #[error("the dense symmetric eigendecomposition did not converge")]
    NoConvergence,
    /// The number of requested eigenpairs is 0 or more than the problem size.
    #[error("cannot compute {count} eigenpairs of a problem of size {n} (need 1 ≤ count ≤ n)")]
    InvalidCount {
        /// Requested number.
        count: usize,
        /// Problem size.
        n: usize,
    },
    /// A parameter is out of range.
    #[error("invalid parameter {what} = {}: {why}", Num(*value))]
    InvalidParameter {
        /// Parameter name.
        what: &'static str,
        /// The value given.
        value: f64,
        /// The requirement.
        why: &'static str,
    },
    /// The caller's solve with `K − σM` failed or returned non-finite values.
    #[error("the linear solve with K − σM failed: {0}")]
    Solve(String),
    /// Lanczos reached its basis limit before the requested eigenpairs converged.
    #[error(
        "Lanczos did not converge: {converged} of {count} eigenpairs converged with a basis of \
         {basis} vectors ({iterations} solves); worst relative residual {} (tolerance {})",
        Num(*worst_residual),
        Num(*tol)
    )]
    NotConverged {
        /// Eigenpairs converged.
        converged: usize,
        /// Eigenpairs requested.
        count: usize,
        /// The basis limit (`LanczosParams::max_basis`, resolved).
        basis: usize,
        /// Solves performed.
        iterations: usize,
        /// Largest estimated relative residual among the unconverged wanted Ritz pairs.
        worst_residual: f64,
        /// The tolerance.
        tol: f64,
    },
    /// The stop flag was set; the iteration ended between two Lanczos steps.
    #[error("interrupted after {iterations} Lanczos solves")]
    Interrupted {
        /// Solves performed before the stop.
        iterations: usize,
    },
    /// Fewer eigenvalues lie above the shift than were requested.
    #[error(
        "only {found} eigenvalues lie above the shift σ = {}, but {count} were requested",
        Num(*sigma)
    )]
    TooFewAboveShift {
        /// Eigenvalues found above `σ`.
        found: usize,
        /// Eigenvalues requested.
        count: usize,
        /// The shift.
        sigma: f64,
    },
}

/// All eigenpairs of `K φ = λ M φ` for dense symmetric `K` and symmetric positive definite
/// `M`, both `n × n`.
///
/// Returns the eigenvalues `λ` in ascending order (units of `K/M`, e.g. rad²/s²) and the
/// matrix `Φ` whose column `i` is the eigenvector of `λ_i`, normalized so that
/// `Φᵀ M Φ = I`. `K` may be indefinite. Both matrices must be symmetric to `1e-8` of their
/// largest entry; their symmetric parts `(A + Aᵀ)/2` are used.
///
/// # Errors
/// [`EigenError::SizeMismatch`] for non-square or differently sized matrices,
/// [`EigenError::NonFinite`], [`EigenError::NotSymmetric`],
/// [`EigenError::NotPositiveDefinite`] if `M` is not positive definite,
/// [`EigenError::NoConvergence`] if the dense eigensolver fails.
pub fn dense_generalized(k: &Mat<f64>, m: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>), EigenError> {
    let n = k.nrows();
    let sizes = [
        ("K columns", k.ncols()),
        ("M rows", m.nrows()),
        ("M columns", m.ncols()),
    ];
    for (what, got) in sizes {
        if got != n {
            return Err(EigenError::SizeMismatch {
                what,
                expected: n,
                got,
            });
        }
    }
    let ks = symmetric_part("K", k)?;
    let ms = symmetric_part("M", m)?;
    if n == 0 {
        return Ok((Vec::new(), Mat::zeros(0, 0)));
    }
    let llt = ms.llt(Side::Lower).map_err(|e| match e {
        LltError::NonPositivePivot { index } => EigenError::NotPositiveDefinite { index },
    })?;
    let l = llt.L();
    // C = L⁻¹ K L⁻ᵀ = L⁻¹ (L⁻¹ K)ᵀ since K is symmetric.
    let mut x = ks;
    l.solve_lower_triangular_in_place(x.as_mut());
    let mut c = x.transpose().to_owned();
    l.solve_lower_triangular_in_place(c.as_mut());
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = c
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| EigenError::NoConvergence)?;
    let s = evd.S().column_vector();
    let values: Vec<f64> = (0..n).map(|i| s[i]).collect();
    let mut phi = evd.U().to_owned();
    l.transpose().solve_upper_triangular_in_place(phi.as_mut());
    Ok((values, phi))
}

/// Checks a square matrix for finite, symmetric entries and returns `(A + Aᵀ)/2`.
fn symmetric_part(what: &'static str, a: &Mat<f64>) -> Result<Mat<f64>, EigenError> {
    let n = a.nrows();
    let mut scale = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let value = a[(i, j)];
            if !value.is_finite() {
                return Err(EigenError::NonFinite {
                    what,
                    row: i,
                    col: j,
                    value,
                });
            }
            scale = scale.max(value.abs());
        }
    }
    let mut worst = (0.0f64, 0, 0);
    for j in 0..n {
        for i in j + 1..n {
            let d = (a[(i, j)] - a[(j, i)]).abs();
            if d > worst.0 {
                worst = (d, i, j);
            }
        }
    }
    if worst.0 > 1e-8 * scale {
        return Err(EigenError::NotSymmetric {
            what,
            row: worst.1,
            col: worst.2,
            difference: worst.0,
            scale,
        });
    }
    Ok(Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)])))
}

/// Settings of [`lanczos_shift_invert`].
#[derive(Debug, Clone, PartialEq)]
pub struct LanczosParams {
    /// Number of eigenpairs wanted: the `count` smallest eigenvalues `λ > σ`.
    pub count: usize,
    /// The shift `σ` (units of `λ`). Use `0` for the lowest modes of a positive definite
    /// `K`, or slightly below `0` (e.g. `−1e-6 λ₁`) if `K` may be singular.
    pub sigma: f64,
    /// Relative tolerance on the Ritz residual of the shift-inverted operator,
    /// `‖A y − θ y‖_M ≤ tol |θ|`. Default `1e-10`.
    pub tol: f64,
    /// Most basis vectors of length `n` held at once (memory `8 n max_basis` bytes), and so
    /// the largest Krylov subspace; never more than `n`. `None`: `min(n, max(10 count, 200))`.
    pub max_basis: Option<usize>,
    /// Seed of the pseudo-random start vectors; equal seeds give identical results.
    pub seed: u64,
    /// After convergence, run Lanczos again from a start vector `M`-orthogonal to the
    /// converged eigenvectors until no further eigenvalue among the wanted ones is found.
    /// A single Krylov space holds one eigenvector per distinct eigenvalue, so without this
    /// the extra copies of a repeated eigenvalue (e.g. the two transverse directions of a
    /// straight 3D string) are missed. Costs one short extra run when nothing is missed.
    /// Default `true`.
    pub check_multiplicity: bool,
}

impl LanczosParams {
    /// The `count` smallest eigenvalues above `sigma`, with the default tolerance `1e-10`,
    /// basis limit, seed and multiplicity check.
    pub fn new(count: usize, sigma: f64) -> Self {
        Self {
            count,
            sigma,
            tol: 1e-10,
            max_basis: None,
            seed: 0x5EED_1A2C_305E_ED00,
            check_multiplicity: true,
        }
    }
}

/// Eigenpairs returned by [`lanczos_shift_invert`].
#[derive(Debug, Clone, PartialEq)]
pub struct EigenPairs {
    /// Eigenvalues `λ`, ascending (units of `K/M`, e.g. rad²/s²; `ω = √λ` in rad/s).
    pub values: Vec<f64>,
    /// Eigenvectors, `vectors[i]` for `values[i]`, each of length `n`, `M`-orthonormal.
    pub vectors: Vec<Vec<f64>>,
    /// Estimated relative residual of each pair in the shift-inverted operator
    /// `A = (K − σM)⁻¹ M`: `‖A φ − θ φ‖_M / |θ|` with `θ = 1/(λ − σ)`; each is `≤ tol`.
    pub residuals: Vec<f64>,
    /// Number of solves with `K − σM` performed (one per Lanczos step).
    pub iterations: usize,
    /// Number of Lanczos runs (1 plus the multiplicity checks).
    pub runs: usize,
}

/// The `count` smallest eigenvalues `λ > σ` of `K φ = λ M φ` and their eigenvectors, by
/// shift-invert Lanczos in the `M`-inner product with full reorthogonalization.
///
/// `K` and `M` are given only through callbacks on vectors of length `n`:
/// * `solve(x)` overwrites `x` with `(K − σM)⁻¹ x` (the caller factors `K − σM` once);
///   its error is reported as [`EigenError::Solve`];
/// * `m_mul(x, out)` sets `out = M x`.
///
/// `K` must be symmetric and `M` symmetric positive definite; `K − σM` must be nonsingular.
/// The eigenvalues of the operator `A = (K − σM)⁻¹ M` are `θ = 1/(λ − σ)`; the `count`
/// largest positive `θ` are returned, i.e. the eigenvalues nearest above `σ`, in ascending
/// `λ`, with `M`-orthonormal eigenvectors. Eigenvalues below `σ` are never returned. The
/// start vectors are pseudo-random from `params.seed`, so results are reproducible.
///
/// `stop`, when given and set, ends the iteration between two Lanczos steps (before the
/// next solve, and before a Ritz decomposition of the tridiagonal matrix) with
/// [`EigenError::Interrupted`].
///
/// # Errors
/// [`EigenError::InvalidCount`] unless `1 ≤ count ≤ n`; [`EigenError::InvalidParameter`]
/// for a non-finite `σ`, a `tol` outside `(0, 1)` or a `max_basis` below `count`;
/// [`EigenError::Solve`]; [`EigenError::MassNotPositive`]; [`EigenError::NotConverged`]
/// (with the number converged and the worst residual) when `max_basis` is reached;
/// [`EigenError::TooFewAboveShift`] when fewer than `count` eigenvalues lie above `σ`;
/// [`EigenError::Interrupted`].
///
/// # Example
/// The taut string fixed at both ends, 3 elements (`T/l = 1`, `ρA l = 6`): `K = [[2, −1],
/// [−1, 2]]`, `M = [[4, 1], [1, 4]]`, `λ = 1/5, 1`.
/// ```
/// use phstring::eigen::{LanczosParams, lanczos_shift_invert};
/// let solve = |x: &mut [f64]| -> Result<(), String> {
///     let (a, b) = (x[0], x[1]); // K⁻¹ = [[2, 1], [1, 2]] / 3
///     x[0] = (2.0 * a + b) / 3.0;
///     x[1] = (a + 2.0 * b) / 3.0;
///     Ok(())
/// };
/// let m_mul = |x: &[f64], out: &mut [f64]| {
///     out[0] = 4.0 * x[0] + x[1];
///     out[1] = x[0] + 4.0 * x[1];
/// };
/// let pairs = lanczos_shift_invert(2, solve, m_mul, &LanczosParams::new(2, 0.0), None)?;
/// assert!((pairs.values[0] - 0.2).abs() < 1e-14 && (pairs.values[1] - 1.0).abs() < 1e-14);
/// # Ok::<(), phstring::eigen::EigenError>(())
/// ```
pub fn lanczos_shift_invert<E: std::fmt::Display>(
    n: usize,
    mut solve: impl FnMut(&mut [f64]) -> Result<(), E>,
    mut m_mul: impl FnMut(&[f64], &mut [f64]),
    params: &LanczosParams,
    stop: Option<&AtomicBool>,
) -> Result<EigenPairs, EigenError> {
    let count = params.count;
    if count == 0 || count > n {
        return Err(EigenError::InvalidCount { count, n });
    }
    if !params.sigma.is_finite() {
        return Err(EigenError::InvalidParameter {
            what: "sigma",
            value: params.sigma,
            why: "must be finite",
        });
    }
    if !(params.tol > 0.0 && params.tol < 1.0) {
        return Err(EigenError::InvalidParameter {
            what: "tol",
            value: params.tol,
            why: "must lie in (0, 1)",
        });
    }
    let max_basis = params
        .max_basis
        .unwrap_or_else(|| (10 * count).max(200))
        .min(n);
    if max_basis < count {
        return Err(EigenError::InvalidParameter {
            what: "max_basis",
            value: max_basis as f64,
            why: "must be at least count",
        });
    }
    let mut lz = Lanczos {
        n,
        tol: params.tol,
        count,
        max_basis,
        rng: SplitMix64(params.seed),
        locked: Vec::new(),
        iterations: 0,
        solve: |x: &mut [f64]| solve(x).map_err(|e| EigenError::Solve(e.to_string())),
        m_mul: &mut m_mul,
        stop,
    };
    let mut runs = 0;
    loop {
        runs += 1;
        let outcome = lz.run()?;
        if outcome.exhausted || outcome.accepted == 0 || !params.check_multiplicity {
            break;
        }
    }
    let mut locked = lz.locked;
    locked.sort_by(|a, b| b.theta.total_cmp(&a.theta));
    let found = locked.iter().filter(|p| p.theta > 0.0).count();
    if found < count {
        return Err(EigenError::TooFewAboveShift {
            found,
            count,
            sigma: params.sigma,
        });
    }
    locked.truncate(count);
    // θ descending is λ = σ + 1/θ ascending for θ > 0.
    Ok(EigenPairs {
        values: locked
            .iter()
            .map(|p| params.sigma + 1.0 / p.theta)
            .collect(),
        residuals: locked.iter().map(|p| p.residual).collect(),
        vectors: locked.into_iter().map(|p| p.vector).collect(),
        iterations: lz.iterations,
        runs,
    })
}

/// A converged Ritz pair, kept for the result and deflated from later runs.
struct Locked {
    theta: f64,
    vector: Vec<f64>,
    residual: f64,
}

/// How one Lanczos run ended.
struct RunOutcome {
    /// Ritz pairs added to the locked set.
    accepted: usize,
    /// The locked vectors and this run's basis spanned the whole space.
    exhausted: bool,
}

/// State shared by the Lanczos runs.
struct Lanczos<'m, S, MM> {
    n: usize,
    tol: f64,
    count: usize,
    max_basis: usize,
    rng: SplitMix64,
    locked: Vec<Locked>,
    iterations: usize,
    solve: S,
    m_mul: &'m mut MM,
    stop: Option<&'m AtomicBool>,
}

impl<S, MM> Lanczos<'_, S, MM>
where
    S: FnMut(&mut [f64]) -> Result<(), EigenError>,
    MM: FnMut(&[f64], &mut [f64]),
{
    /// The `count`-th largest locked `θ` (or `0` while fewer are locked): a run looks for
    /// Ritz values above it.
    fn threshold(&self) -> f64 {
        if self.locked.len() < self.count {
            return 0.0;
        }
        let mut t: Vec<f64> = self.locked.iter().map(|p| p.theta).collect();
        t.sort_by(|a, b| b.total_cmp(a));
        t[self.count - 1].max(0.0)
    }

    /// One Lanczos run from a fresh start vector, deflated against the locked vectors. Adds
    /// the converged Ritz pairs above the threshold to `locked`.
    fn run(&mut self) -> Result<RunOutcome, EigenError> {
        let n = self.n;
        let tau = self.threshold();
        let mut chain: Vec<Vec<f64>> = Vec::new();
        let mut alpha: Vec<f64> = Vec::new();
        let mut beta: Vec<f64> = Vec::new();
        let Some((q, mut mq)) = self.random_start(&chain)? else {
            return Ok(RunOutcome {
                accepted: 0,
                exhausted: true,
            });
        };
        chain.push(q);
        let mut next_check = 1;
        loop {
            self.check_stop()?;
            let j = chain.len();
            let mut w = mq.clone();
            (self.solve)(&mut w)?;
            self.iterations += 1;
            if let Some(i) = w.iter().position(|x| !x.is_finite()) {
                return Err(EigenError::Solve(format!(
                    "entry {i} of the solution is {}",
                    w[i]
                )));
            }
            let (a, next) = self.orthogonalize(&mut w, &chain, Some(j - 1))?;
            alpha.push(a);
            let (beta_j, mut next) = match next {
                Some((norm, z)) => {
                    let q: Vec<f64> = w.iter().map(|x| x / norm).collect();
                    let mq: Vec<f64> = z.iter().map(|x| x / norm).collect();
                    (norm, Some((q, mq)))
                }
                None => (0.0, None),
            };
            let mut restarted = false;
            if next.is_none() {
                next = self.random_start(&chain)?;
                restarted = next.is_some();
            }
            // A full basis leaves no new direction: the Ritz pairs are exact.
            let exhausted = next.is_none() || self.locked.len() + j >= n;
            let at_cap = self.locked.len() + j >= self.max_basis;
            if exhausted || at_cap || restarted || j >= next_check {
                // The decomposition costs O(j³): not after a stop request.
                self.check_stop()?;
                let ritz = ritz(&alpha, &beta)?;
                let est = |i: usize| {
                    if exhausted {
                        0.0
                    } else {
                        (beta_j * ritz.vectors[(j - 1, i)]).abs()
                    }
                };
                let status = self.status(&ritz.values, est, tau, exhausted);
                if status.done || exhausted {
                    let mut accepted = 0;
                    for &i in &status.accept {
                        let mut y = vec![0.0; n];
                        for (k, qk) in chain.iter().enumerate() {
                            let s = ritz.vectors[(k, i)];
                            for (y, q) in y.iter_mut().zip(qk) {
                                *y += s * q;
                            }
                        }
                        let theta = ritz.values[i];
                        self.locked.push(Locked {
                            theta,
                            vector: y,
                            residual: est(i) / theta.abs(),
                        });
                        accepted += 1;
                    }
                    return Ok(RunOutcome {
                        accepted,
                        exhausted,
                    });
                }
                if at_cap {
                    return Err(EigenError::NotConverged {
                        converged: (self.locked.len() + status.converged).min(self.count),
                        count: self.count,
                        basis: self.max_basis,
                        iterations: self.iterations,
                        worst_residual: status.worst,
                        tol: self.tol,
                    });
                }
                next_check = j + (j / 10).max(1);
            }
            let (q, m) = next.expect("not exhausted");
            chain.push(q);
            mq = m;
            beta.push(if restarted { 0.0 } else { beta_j });
        }
    }

    /// [`EigenError::Interrupted`] if the stop flag is set.
    fn check_stop(&self) -> Result<(), EigenError> {
        if self.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Err(EigenError::Interrupted {
                iterations: self.iterations,
            });
        }
        Ok(())
    }

    /// Which Ritz values of the current run are done: the leading ones (largest `θ`, at most
    /// `count`) down to and including the first at or below `tau` must be converged.
    fn status(
        &self,
        values: &[f64],
        est: impl Fn(usize) -> f64,
        tau: f64,
        exhausted: bool,
    ) -> Status {
        let mut s = Status {
            done: true,
            accept: Vec::new(),
            converged: 0,
            worst: 0.0,
        };
        let mut reached_tau = false;
        let mut all_converged_so_far = true;
        // Ritz values are ascending; walk them from the largest.
        for i in (0..values.len()).rev().take(self.count) {
            let theta = values[i];
            let rel = est(i) / theta.abs();
            let converged = exhausted || rel <= self.tol;
            if converged && all_converged_so_far && theta > tau {
                s.accept.push(i);
                s.converged += 1;
            }
            if !converged {
                all_converged_so_far = false;
                s.done = false;
                s.worst = s.worst.max(rel);
            }
            if theta <= tau {
                reached_tau = true;
                break;
            }
        }
        if !reached_tau && values.len() < self.count && !exhausted {
            s.done = false;
        }
        s
    }

    /// `M`-orthogonalizes `w` against the locked vectors and `chain` by classical Gram–Schmidt,
    /// at least two passes and more while a pass shrinks `w` by more than `1/√2`
    /// (Kahan–Parlett). Returns the summed coefficient on `chain[track]` and, unless `w` is
    /// numerically in the span, its `M`-norm and `M w`.
    fn orthogonalize(
        &mut self,
        w: &mut [f64],
        chain: &[Vec<f64>],
        track: Option<usize>,
    ) -> Result<(f64, Option<NormAndMw>), EigenError> {
        let mut z = vec![0.0; self.n];
        (self.m_mul)(w, &mut z);
        let norm0 = self.m_norm(w, &z)?;
        let mut prev = norm0;
        let mut tracked = 0.0;
        if norm0 == 0.0 {
            return Ok((0.0, None));
        }
        for pass in 1..=4 {
            let basis = self.locked.iter().map(|p| &p.vector).chain(chain.iter());
            let coef: Vec<f64> = basis.clone().map(|v| dot(v, &z)).collect();
            for (v, c) in basis.zip(&coef) {
                for (w, v) in w.iter_mut().zip(v) {
                    *w -= c * v;
                }
            }
            if let Some(t) = track {
                tracked += coef[self.locked.len() + t];
            }
            (self.m_mul)(w, &mut z);
            let norm = self.m_norm(w, &z)?;
            if norm <= 1e-14 * norm0 {
                return Ok((tracked, None));
            }
            if pass >= 2 && norm >= prev * std::f64::consts::FRAC_1_SQRT_2 {
                return Ok((tracked, Some((norm, z))));
            }
            prev = norm;
        }
        Ok((tracked, None))
    }

    /// `√(wᵀ M w)`, an error if clearly negative; round-off below zero counts as zero.
    fn m_norm(&self, w: &[f64], mw: &[f64]) -> Result<f64, EigenError> {
        let s = dot(w, mw);
        if s.is_nan() {
            return Err(EigenError::MassNotPositive { value: s });
        }
        if s < 0.0 {
            let scale = dot(w, w).sqrt() * dot(mw, mw).sqrt();
            if s < -1e-12 * scale {
                return Err(EigenError::MassNotPositive { value: s });
            }
            return Ok(0.0);
        }
        Ok(s.sqrt())
    }

    /// A pseudo-random unit vector `M`-orthogonal to the locked vectors and `chain`, with
    /// its `M` product; `None` when they already span the space.
    fn random_start(&mut self, chain: &[Vec<f64>]) -> Result<Option<VecAndMv>, EigenError> {
        let n = self.n;
        if self.locked.len() + chain.len() >= n {
            return Ok(None);
        }
        // A few tries: a draw (almost) inside the span is replaced by another.
        for _ in 0..3 {
            let mut w: Vec<f64> = (0..n).map(|_| self.rng.symmetric()).collect();
            if let (_, Some((norm, z))) = self.orthogonalize(&mut w, chain, None)? {
                let q = w.iter().map(|x| x / norm).collect();
                let mq = z.iter().map(|x| x / norm).collect();
                return Ok(Some((q, mq)));
            }
        }
        Ok(None)
    }
}

/// `(‖w‖_M, M w)` of an orthogonalized vector `w`.
type NormAndMw = (f64, Vec<f64>);

/// `(q, M q)` of a new basis vector `q`.
type VecAndMv = (Vec<f64>, Vec<f64>);

/// Verdict of [`Lanczos::status`].
struct Status {
    /// The wanted Ritz values of this run are converged.
    done: bool,
    /// Indices (into the ascending Ritz values) of converged values above the threshold.
    accept: Vec<usize>,
    /// Leading Ritz values converged.
    converged: usize,
    /// Worst relative residual among the unconverged wanted values.
    worst: f64,
}

/// Eigenpairs of the symmetric tridiagonal `T` (diagonal `alpha`, off-diagonal `beta`).
struct Ritz {
    values: Vec<f64>,
    vectors: Mat<f64>,
}

fn ritz(alpha: &[f64], beta: &[f64]) -> Result<Ritz, EigenError> {
    let j = alpha.len();
    let t = Mat::from_fn(j, j, |r, c| {
        if r == c {
            alpha[r]
        } else if r == c + 1 {
            beta[c]
        } else if c == r + 1 {
            beta[r]
        } else {
            0.0
        }
    });
    let evd = t
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| EigenError::NoConvergence)?;
    let s = evd.S().column_vector();
    Ok(Ritz {
        values: (0..j).map(|i| s[i]).collect(),
        vectors: evd.U().to_owned(),
    })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// SplitMix64, for reproducible start vectors.
struct SplitMix64(u64);

impl SplitMix64 {
    /// Uniform in `[−1, 1)`.
    fn symmetric(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linsolve::test_rng::Rng;
    use faer::linalg::solvers::Solve;
    use std::f64::consts::PI;

    /// Taut string, `T = 1e5 N`, `ρA = 1.2 kg/m`, length 100 m, fixed at both ends.
    const TENSION: f64 = 1e5;
    const RHO_A: f64 = 1.2;
    const LENGTH: f64 = 100.0;

    /// Interior-DOF tridiagonal `K` and consistent `M` of the fixed–fixed taut string with
    /// `n_el` elements: `(diag, off)` of each.
    fn string_bands(n_el: usize) -> ((f64, f64), (f64, f64)) {
        let l = LENGTH / n_el as f64;
        let (k, m) = (TENSION / l, RHO_A * l / 6.0);
        ((2.0 * k, -k), (4.0 * m, m))
    }

    /// `λ_k = 6T/(ρA l²) (1 − cos θ_k)/(2 + cos θ_k)`, `θ_k = kπ/N`, `k = 1..N−1`, with
    /// `1 − cos θ = 2 sin²(θ/2)` to avoid cancellation.
    fn string_closed_form(n_el: usize) -> Vec<f64> {
        let l = LENGTH / n_el as f64;
        (1..n_el)
            .map(|k| {
                let th = k as f64 * PI / n_el as f64;
                6.0 * TENSION / (RHO_A * l * l) * 2.0 * (th / 2.0).sin().powi(2) / (2.0 + th.cos())
            })
            .collect()
    }

    fn tridiagonal_dense(n: usize, (d, o): (f64, f64)) -> Mat<f64> {
        Mat::from_fn(n, n, |i, j| {
            if i == j {
                d
            } else if i.abs_diff(j) == 1 {
                o
            } else {
                0.0
            }
        })
    }

    /// Random symmetric banded matrix, strictly diagonally dominant (so SPD), diagonal
    /// growing along the band so the spectrum is spread.
    fn random_spd_banded(rng: &mut Rng, n: usize, bw: usize, growth: f64) -> Mat<f64> {
        let mut a = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            for j in i + 1..(i + bw + 1).min(n) {
                let v = rng.sym();
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
        }
        for i in 0..n {
            let off: f64 = (0..n).filter(|&j| j != i).map(|j| a[(i, j)].abs()).sum();
            a[(i, i)] = off + 0.1 + growth * (i as f64 / n as f64).powi(2) + 0.5 * rng.sym().abs();
        }
        a
    }

    fn mat_vec(a: &Mat<f64>, x: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = (0..x.len()).map(|j| a[(i, j)] * x[j]).sum();
        }
    }

    fn rel_err(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// Max over pairs of `|Φᵀ M Φ − I|` and of `‖Kφ − λMφ‖ / (|λ| ‖Mφ‖)`.
    fn check_pairs(k: &Mat<f64>, m: &Mat<f64>, values: &[f64], vectors: &[Vec<f64>]) -> (f64, f64) {
        let n = k.nrows();
        let mphi: Vec<Vec<f64>> = vectors
            .iter()
            .map(|v| {
                let mut o = vec![0.0; n];
                mat_vec(m, v, &mut o);
                o
            })
            .collect();
        let mut orth = 0.0f64;
        for (a, va) in vectors.iter().enumerate() {
            for (b, mb) in mphi.iter().enumerate() {
                let target = if a == b { 1.0 } else { 0.0 };
                orth = orth.max((dot(va, mb) - target).abs());
            }
        }
        let mut res = 0.0f64;
        for ((lam, v), mv) in values.iter().zip(vectors).zip(&mphi) {
            let mut kv = vec![0.0; n];
            mat_vec(k, v, &mut kv);
            let r: f64 = kv
                .iter()
                .zip(mv)
                .map(|(a, b)| (a - lam * b).powi(2))
                .sum::<f64>()
                .sqrt();
            res = res.max(r / (lam.abs() * dot(mv, mv).sqrt()));
        }
        (orth, res)
    }

    fn columns(phi: &Mat<f64>) -> Vec<Vec<f64>> {
        (0..phi.ncols())
            .map(|c| (0..phi.nrows()).map(|r| phi[(r, c)]).collect())
            .collect()
    }

    /// Lanczos with a dense Cholesky of `K − σM` as the solve.
    fn lanczos_dense(
        k: &Mat<f64>,
        m: &Mat<f64>,
        params: &LanczosParams,
    ) -> Result<EigenPairs, EigenError> {
        let n = k.nrows();
        let shifted = Mat::from_fn(n, n, |i, j| k[(i, j)] - params.sigma * m[(i, j)]);
        let lu = shifted.partial_piv_lu();
        let solve = |x: &mut [f64]| -> Result<(), String> {
            lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(x, n, 1));
            Ok(())
        };
        lanczos_shift_invert(n, solve, |x, o| mat_vec(m, x, o), params, None)
    }

    /// Thomas algorithm for a constant symmetric tridiagonal `(d, o)`, in place.
    fn thomas(n: usize, (d, o): (f64, f64)) -> impl FnMut(&mut [f64]) -> Result<(), String> {
        let mut c = vec![0.0; n]; // modified super-diagonal
        let mut piv = vec![0.0; n];
        piv[0] = d;
        for i in 1..n {
            c[i - 1] = o / piv[i - 1];
            piv[i] = d - o * c[i - 1];
        }
        move |x: &mut [f64]| {
            x[0] /= piv[0];
            for i in 1..n {
                x[i] = (x[i] - o * x[i - 1]) / piv[i];
            }
            for i in (0..n - 1).rev() {
                x[i] -= c[i] * x[i + 1];
            }
            Ok(())
        }
    }

    fn tridiagonal_mul((d, o): (f64, f64)) -> impl FnMut(&[f64], &mut [f64]) {
        move |x: &[f64], out: &mut [f64]| {
            let n = x.len();
            for i in 0..n {
                let mut s = d * x[i];
                if i > 0 {
                    s += o * x[i - 1];
                }
                if i + 1 < n {
                    s += o * x[i + 1];
                }
                out[i] = s;
            }
        }
    }

    /// Dense solver against the closed-form taut-string spectrum, N = 20 (19 interior DOFs).
    #[test]
    fn dense_matches_taut_string_closed_form() {
        let n_el = 20;
        let (kb, mb) = string_bands(n_el);
        let (k, m) = (
            tridiagonal_dense(n_el - 1, kb),
            tridiagonal_dense(n_el - 1, mb),
        );
        let (values, phi) = dense_generalized(&k, &m).unwrap();
        let exact = string_closed_form(n_el);
        let err = values
            .iter()
            .zip(&exact)
            .map(|(a, b)| rel_err(*a, *b))
            .fold(0.0, f64::max);
        let (orth, res) = check_pairs(&k, &m, &values, &columns(&phi));
        eprintln!("dense string: max rel err {err:.2e}, orth {orth:.2e}, residual {res:.2e}");
        assert!(err <= 1e-12, "{err:e}");
        assert!(orth <= 1e-12, "{orth:e}");
        assert!(res <= 1e-12, "{res:e}");
    }

    /// Lanczos (dense LU solve) against the dense solver and the closed form, N = 20.
    #[test]
    fn lanczos_matches_dense_on_taut_string() {
        let n_el = 20;
        let (kb, mb) = string_bands(n_el);
        let (k, m) = (
            tridiagonal_dense(n_el - 1, kb),
            tridiagonal_dense(n_el - 1, mb),
        );
        let (dense, _) = dense_generalized(&k, &m).unwrap();
        let exact = string_closed_form(n_el);
        let pairs = lanczos_dense(&k, &m, &LanczosParams::new(10, 0.0)).unwrap();
        let mut err_dense = 0.0f64;
        let mut err_exact = 0.0f64;
        for i in 0..10 {
            err_dense = err_dense.max(rel_err(pairs.values[i], dense[i]));
            err_exact = err_exact.max(rel_err(pairs.values[i], exact[i]));
        }
        let (orth, res) = check_pairs(&k, &m, &pairs.values, &pairs.vectors);
        eprintln!(
            "lanczos string N=20: vs dense {err_dense:.2e}, vs exact {err_exact:.2e}, orth {orth:.2e}, \
             residual {res:.2e}, {} solves, {} runs",
            pairs.iterations, pairs.runs
        );
        assert!(err_dense <= 1e-9 && err_exact <= 1e-9);
        assert!(orth <= 1e-10, "{orth:e}");
        assert!(res <= 1e-8, "{res:e}");
    }

    /// Lanczos against the dense solver on random SPD banded K and M, n = 200, with σ = 0 and
    /// a negative shift; eigenvectors compared with the dense ones (simple eigenvalues).
    #[test]
    fn lanczos_matches_dense_on_random_banded() {
        let n = 200;
        let mut rng = Rng(0xE16E);
        let k = random_spd_banded(&mut rng, n, 3, 40.0);
        let m = random_spd_banded(&mut rng, n, 2, 0.0);
        let (dense, phi) = dense_generalized(&k, &m).unwrap();
        let (orth_d, res_d) = check_pairs(&k, &m, &dense, &columns(&phi));
        eprintln!("dense random n=200: orth {orth_d:.2e}, residual {res_d:.2e}");
        assert!(orth_d <= 1e-12 && res_d <= 1e-11);
        for sigma in [0.0, -0.5 * dense[0]] {
            let pairs = lanczos_dense(&k, &m, &LanczosParams::new(10, sigma)).unwrap();
            let err = (0..10)
                .map(|i| rel_err(pairs.values[i], dense[i]))
                .fold(0.0, f64::max);
            let (orth, res) = check_pairs(&k, &m, &pairs.values, &pairs.vectors);
            // |φ_lanczosᵀ M φ_dense| = 1 for simple eigenvalues.
            let mut align = 0.0f64;
            for (i, v) in pairs.vectors.iter().enumerate() {
                let mut mv = vec![0.0; n];
                mat_vec(&m, v, &mut mv);
                let c: f64 = (0..n).map(|r| phi[(r, i)] * mv[r]).sum();
                align = align.max((c.abs() - 1.0).abs());
            }
            eprintln!(
                "lanczos random σ={sigma:.3}: vs dense {err:.2e}, orth {orth:.2e}, residual {res:.2e}, \
                 |φᵀMφ_dense|−1 {align:.2e}, {} solves, {} runs",
                pairs.iterations, pairs.runs
            );
            assert!(err <= 1e-9, "{err:e}");
            assert!(orth <= 1e-10, "{orth:e}");
            assert!(res <= 1e-8, "{res:e}");
            assert!(align <= 1e-8, "{align:e}");
            assert!(pairs.residuals.iter().all(|&r| r <= 1e-10));
            assert!(pairs.iterations < n, "{}", pairs.iterations);
        }
    }

    /// Large taut string, N = 2000, Thomas-algorithm solve: the 10 lowest against the closed form.
    #[test]
    fn lanczos_large_taut_string_closed_form() {
        let n_el = 2000;
        let n = n_el - 1;
        let (kb, mb) = string_bands(n_el);
        let exact = string_closed_form(n_el);
        for sigma in [0.0, -0.01 * exact[0]] {
            let shifted = (kb.0 - sigma * mb.0, kb.1 - sigma * mb.1);
            let params = LanczosParams::new(10, sigma);
            let pairs =
                lanczos_shift_invert(n, thomas(n, shifted), tridiagonal_mul(mb), &params, None)
                    .unwrap();
            let err = (0..10)
                .map(|i| rel_err(pairs.values[i], exact[i]))
                .fold(0.0, f64::max);
            eprintln!(
                "lanczos string N=2000 σ={sigma:.3e}: vs exact {err:.2e}, {} solves, {} runs, \
                 ω₁ = {:.6} rad/s",
                pairs.iterations,
                pairs.runs,
                pairs.values[0].sqrt()
            );
            assert!(err <= 1e-9, "{err:e}");
            // ω₁ ≈ (π/L) √(T/ρA) of the continuous string.
            assert!(
                rel_err(
                    pairs.values[0].sqrt(),
                    PI / LENGTH * (TENSION / RHO_A).sqrt()
                ) < 1e-6
            );
            // Reproducible: same seed, same bits.
            let again =
                lanczos_shift_invert(n, thomas(n, shifted), tridiagonal_mul(mb), &params, None)
                    .unwrap();
            assert_eq!(again, pairs);
        }
    }

    /// A stop request (here raised by the 5th solve, as a Ctrl-C during it would) ends the
    /// iteration before the next solve: no solve is made after it, and the error counts the
    /// five. The same problem without the flag needs many more solves.
    #[test]
    fn lanczos_stops_between_steps_when_the_flag_is_set() {
        let n_el = 2000;
        let n = n_el - 1;
        let (kb, mb) = string_bands(n_el);
        let params = LanczosParams::new(10, 0.0);
        let stop = AtomicBool::new(false);
        let mut solves = 0;
        let mut inner = thomas(n, kb);
        let solve = |x: &mut [f64]| {
            solves += 1;
            if solves == 5 {
                stop.store(true, Ordering::Relaxed);
            }
            inner(x)
        };
        let e =
            lanczos_shift_invert(n, solve, tridiagonal_mul(mb), &params, Some(&stop)).unwrap_err();
        assert_eq!(e, EigenError::Interrupted { iterations: 5 });
        assert_eq!(solves, 5);
        assert_eq!(e.to_string(), "interrupted after 5 Lanczos solves");
        // A flag set before the start: not a single solve.
        let e = lanczos_shift_invert(
            n,
            |_: &mut [f64]| -> Result<(), String> { panic!("no solve after a stop request") },
            tridiagonal_mul(mb),
            &params,
            Some(&stop),
        )
        .unwrap_err();
        assert_eq!(e, EigenError::Interrupted { iterations: 0 });
        let unstopped = AtomicBool::new(false);
        let pairs = lanczos_shift_invert(
            n,
            thomas(n, kb),
            tridiagonal_mul(mb),
            &params,
            Some(&unstopped),
        )
        .unwrap();
        assert!(pairs.iterations > 20, "{}", pairs.iterations);
    }

    /// Repeated eigenvalues: two identical decoupled strings (like the two transverse
    /// directions of a 3D string) give double eigenvalues. In exact arithmetic one Krylov
    /// space holds only one copy of each; the multiplicity check guarantees both (without it,
    /// round-off often, but not reliably, brings the second copy in: printed, not asserted).
    #[test]
    fn lanczos_finds_repeated_eigenvalues() {
        let n_el = 100;
        let (kb, mb) = string_bands(n_el);
        let h = n_el - 1;
        let block = |b: (f64, f64)| {
            let t = tridiagonal_dense(h, b);
            Mat::from_fn(2 * h, 2 * h, |i, j| {
                if i / h == j / h {
                    t[(i % h, j % h)]
                } else {
                    0.0
                }
            })
        };
        let (k, m) = (block(kb), block(mb));
        let exact = string_closed_form(n_el);
        let pairs = lanczos_dense(&k, &m, &LanczosParams::new(6, 0.0)).unwrap();
        let err = (0..6)
            .map(|i| rel_err(pairs.values[i], exact[i / 2]))
            .fold(0.0, f64::max);
        let (orth, res) = check_pairs(&k, &m, &pairs.values, &pairs.vectors);
        eprintln!(
            "repeated: err {err:.2e}, orth {orth:.2e}, residual {res:.2e}, {} solves, {} runs",
            pairs.iterations, pairs.runs
        );
        assert!(err <= 1e-9, "{err:e} {:?}", pairs.values);
        assert!(orth <= 1e-10 && res <= 1e-8);
        assert!(pairs.runs >= 2);
        let single = LanczosParams {
            check_multiplicity: false,
            ..LanczosParams::new(6, 0.0)
        };
        let pairs = lanczos_dense(&k, &m, &single).unwrap();
        let distinct = (0..6)
            .map(|i| rel_err(pairs.values[i], exact[i]))
            .fold(0.0, f64::max);
        eprintln!(
            "single run: {:?} (err vs distinct values {distinct:.2e})",
            pairs.values
        );
    }

    /// Few distinct eigenvalues: the Krylov space becomes invariant after 3 steps, so Lanczos
    /// restarts; with n = count every eigenpair is returned.
    #[test]
    fn lanczos_invariant_subspaces_and_full_size() {
        let n = 12;
        let k = Mat::from_fn(n, n, |i, j| if i == j { (1 + i / 4) as f64 } else { 0.0 });
        let m = Mat::<f64>::identity(n, n);
        let pairs = lanczos_dense(&k, &m, &LanczosParams::new(6, 0.0)).unwrap();
        eprintln!(
            "invariant: {:?}, {} solves, {} runs",
            pairs.values, pairs.iterations, pairs.runs
        );
        for (v, want) in pairs.values.iter().zip([1.0, 1.0, 1.0, 1.0, 2.0, 2.0]) {
            assert!((v - want).abs() <= 1e-12, "{:?}", pairs.values);
        }
        let (orth, res) = check_pairs(&k, &m, &pairs.values, &pairs.vectors);
        assert!(orth <= 1e-12 && res <= 1e-12, "{orth:e} {res:e}");
        // count = n on the random problem: everything, matching the dense solver.
        let mut rng = Rng(3);
        let k = random_spd_banded(&mut rng, 15, 2, 5.0);
        let m = random_spd_banded(&mut rng, 15, 1, 0.0);
        let (dense, _) = dense_generalized(&k, &m).unwrap();
        let pairs = lanczos_dense(&k, &m, &LanczosParams::new(15, 0.0)).unwrap();
        let err = (0..15)
            .map(|i| rel_err(pairs.values[i], dense[i]))
            .fold(0.0, f64::max);
        let (orth, res) = check_pairs(&k, &m, &pairs.values, &pairs.vectors);
        eprintln!("count = n: err {err:.2e}, orth {orth:.2e}, residual {res:.2e}");
        assert!(err <= 1e-12 && orth <= 1e-12 && res <= 1e-10);
    }

    /// An interior shift returns only eigenvalues above it; too few above is an error.
    #[test]
    fn lanczos_interior_shift() {
        let n_el = 20;
        let (kb, mb) = string_bands(n_el);
        let (k, m) = (
            tridiagonal_dense(n_el - 1, kb),
            tridiagonal_dense(n_el - 1, mb),
        );
        let exact = string_closed_form(n_el);
        let sigma = 0.5 * (exact[4] + exact[5]);
        let pairs = lanczos_dense(&k, &m, &LanczosParams::new(3, sigma)).unwrap();
        let err = (0..3)
            .map(|i| rel_err(pairs.values[i], exact[5 + i]))
            .fold(0.0, f64::max);
        eprintln!("interior shift: err {err:.2e}, {} solves", pairs.iterations);
        assert!(err <= 1e-9, "{:?}", pairs.values);
        let sigma = 0.5 * (exact[16] + exact[17]); // only exact[17], exact[18] above

        let e = lanczos_dense(&k, &m, &LanczosParams::new(3, sigma)).unwrap_err();
        assert!(
            matches!(
                e,
                EigenError::TooFewAboveShift {
                    found: 2,
                    count: 3,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn error_paths() {
        let (kb, mb) = string_bands(6);
        let (k, m) = (tridiagonal_dense(5, kb), tridiagonal_dense(5, mb));
        // count > n and count = 0.
        for count in [0, 6] {
            let e = lanczos_dense(&k, &m, &LanczosParams::new(count, 0.0)).unwrap_err();
            assert_eq!(e, EigenError::InvalidCount { count, n: 5 });
        }
        // Indefinite M.
        let mut bad = m.clone();
        bad[(2, 2)] = -1.0;
        let e = dense_generalized(&k, &bad).unwrap_err();
        assert!(
            matches!(e, EigenError::NotPositiveDefinite { index: 2 }),
            "{e}"
        );
        eprintln!("{e}");
        // Size mismatch, non-finite, asymmetric.
        let small = tridiagonal_dense(4, mb);
        let e = dense_generalized(&k, &small).unwrap_err();
        assert_eq!(
            e,
            EigenError::SizeMismatch {
                what: "M rows",
                expected: 5,
                got: 4
            }
        );
        let mut nan = k.clone();
        nan[(1, 3)] = f64::NAN;
        assert!(matches!(
            dense_generalized(&nan, &m),
            Err(EigenError::NonFinite {
                what: "K",
                row: 1,
                col: 3,
                ..
            })
        ));
        let mut asym = k.clone();
        asym[(0, 1)] *= 1.01;
        assert!(matches!(
            dense_generalized(&asym, &m),
            Err(EigenError::NotSymmetric { .. })
        ));
        // The solve callback's error is passed on as text.
        let e = lanczos_shift_invert(
            5,
            |_: &mut [f64]| Err("factor is stale"),
            |x, o| mat_vec(&m, x, o),
            &LanczosParams::new(2, 0.0),
            None,
        )
        .unwrap_err();
        assert_eq!(e, EigenError::Solve("factor is stale".into()));
        eprintln!("{e}");
        // A basis too small to converge reports the numbers.
        let n_el = 400;
        let (kb, mb) = string_bands(n_el);
        let params = LanczosParams {
            max_basis: Some(12),
            ..LanczosParams::new(10, 0.0)
        };
        let e = lanczos_shift_invert(
            n_el - 1,
            thomas(n_el - 1, kb),
            tridiagonal_mul(mb),
            &params,
            None,
        )
        .unwrap_err();
        eprintln!("{e}");
        match e {
            EigenError::NotConverged {
                count: 10,
                basis: 12,
                iterations: 12,
                converged,
                worst_residual,
                ..
            } => {
                assert!(converged < 10 && worst_residual > 1e-10 && worst_residual.is_finite());
            }
            e => panic!("{e}"),
        }
        // Bad parameters.
        let tol0 = LanczosParams {
            tol: 0.0,
            ..LanczosParams::new(2, 0.0)
        };
        assert!(matches!(
            lanczos_dense(&k, &m, &tol0),
            Err(EigenError::InvalidParameter { what: "tol", .. })
        ));
        // Indefinite M seen through the M-inner product.
        let e = lanczos_dense(&k, &bad, &LanczosParams::new(2, 0.0)).unwrap_err();
        eprintln!("{e}");
        assert!(
            matches!(
                e,
                EigenError::MassNotPositive { .. } | EigenError::TooFewAboveShift { .. }
            ),
            "{e}"
        );
    }
}
