//! Local error estimation and step-size selection for error-controlled runs
//! (docs/method.md §19).
//!
//! The error of a step is measured per node, on positions and velocities, relative to
//! `atol + rtol · |value|`; the largest ratio over the free components, times `h_max / h`
//! (error per unit step; without that factor with `StepControl::error_per_step`), is the
//! step's error `err`; the step is accepted if `err ≤ 1`. Two estimates:
//!
//! * `dg` and `mp` (order 2): the local error of the scheme, which is the trapezoidal rule on
//!   `ṙ = v` and `v̇ = a` (exactly so for a linear system), is `−h³/12 ȧ` in the positions and
//!   `−h³/12 ä` in the velocities; `ȧ`, `ä` are divided differences of the steps' mean
//!   accelerations `ā = (v_{n+1} − v_n)/h` at their mid times, the first of them the
//!   acceleration at `t = 0` (Zienkiewicz–Xie's estimate for Newmark's average-acceleration
//!   rule). No extra solve.
//! * `dg4`: the embedded pair, the second-order DG step over the same `h` against the
//!   composition (one extra solve, started from the composition's result). It measures the
//!   second-order step's error; the run advances with the fourth-order result.

use crate::system::Vector;

/// Mean accelerations of the last accepted steps at their mid times, newest first, for the
/// second-order estimate (at most two kept).
#[derive(Debug, Default, PartialEq)]
pub struct AccelerationHistory<const D: usize> {
    /// `(τ, ā)`: mid time [s] and mean acceleration per node [m/s²], newest first.
    pub points: Vec<(f64, Vec<Vector<D>>)>,
}

impl<const D: usize> Clone for AccelerationHistory<D> {
    fn clone(&self) -> Self {
        Self {
            points: self.points.clone(),
        }
    }

    /// Reuses the buffers of the points already held.
    fn clone_from(&mut self, source: &Self) {
        self.points.truncate(source.points.len());
        for (p, q) in self.points.iter_mut().zip(&source.points) {
            p.0 = q.0;
            p.1.clone_from(&q.1);
        }
        let n = self.points.len();
        self.points.extend_from_slice(&source.points[n..]);
    }
}

impl<const D: usize> AccelerationHistory<D> {
    /// Adds the point `(tau, acc)`, dropping the oldest beyond two (its buffer is reused).
    pub fn push(&mut self, tau: f64, acc: &[Vector<D>]) {
        let mut buf = if self.points.len() >= 2 {
            self.points.pop().expect("two points").1
        } else {
            Vec::new()
        };
        buf.clear();
        buf.extend_from_slice(acc);
        self.points.insert(0, (tau, buf));
    }
}

/// The second-order local error estimate of a step of size `h` [s] whose mean acceleration
/// is `acc` at mid time `tau`, from the history: `(e_r, e_v)` of node `node`, position [m] and
/// velocity [m/s] error magnitudes over its `free` components. With one point in the history
/// only `e_r` (`e_v = 0`).
pub(crate) fn second_order_estimate<const D: usize>(
    h: f64,
    tau: f64,
    acc: &[Vector<D>],
    history: &AccelerationHistory<D>,
    node: usize,
    free: &[bool; D],
) -> (f64, f64) {
    let c = h * h * h / 12.0;
    let Some((t1, a1)) = history.points.first() else {
        return (0.0, 0.0);
    };
    let mask = |v: Vector<D>| Vector::<D>::from_fn(|k, _| if free[k] { v[k] } else { 0.0 });
    let d1 = mask(acc[node] - a1[node]) / (tau - t1);
    let e_r = c * d1.norm();
    let e_v = match history.points.get(1) {
        Some((t2, a2)) => {
            let d0 = mask(a1[node] - a2[node]) / (t1 - t2);
            c * ((d1 - d0) * (2.0 / (tau - t2))).norm()
        }
        None => 0.0,
    };
    (e_r, e_v)
}

/// The error ratio of one node: the larger of `e_r / (atol + rtol·r_mag)` and
/// `e_v / (atol_v + rtol·v_mag)`.
pub(crate) fn ratio(
    e_r: f64,
    e_v: f64,
    r_mag: f64,
    v_mag: f64,
    rtol: f64,
    atol: f64,
    atol_v: f64,
) -> f64 {
    (e_r / (atol + rtol * r_mag)).max(e_v / (atol_v + rtol * v_mag))
}

/// Safety factor of the step-size choice.
pub const SAFETY: f64 = 0.9;
/// Largest growth of `h` from one step to the next.
pub const MAX_GROWTH: f64 = 5.0;
/// Largest cut of `h` after a rejected or accepted step.
pub const MAX_CUT: f64 = 0.2;

/// The next step size factor after an accepted step with error `err` (previous accepted step:
/// `err_prev`), for an error of order `p + 1` in `h` (the error per unit step of §19: `p = 1`;
/// the error per step: `p = 2`):
/// the PI controller
/// `0.9 err^(−0.7/(p+1)) err_prev^(0.4/(p+1))` (Gustafsson; Hairer–Wanner IV.2), limited to
/// `[0.2, 5]`.
pub fn accept_factor(err: f64, err_prev: f64, p: u32) -> f64 {
    let k = (p + 1) as f64;
    let err = err.max(1e-10);
    let prev = err_prev.max(1e-10);
    (SAFETY * err.powf(-0.7 / k) * prev.powf(0.4 / k)).clamp(MAX_CUT, MAX_GROWTH)
}

/// The step size factor after a step rejected with error `err > 1`: `0.9 err^(−1/(p+1))`,
/// at least 0.2.
pub fn reject_factor(err: f64, p: u32) -> f64 {
    let k = (p + 1) as f64;
    if err.is_finite() {
        (SAFETY * err.powf(-1.0 / k)).clamp(MAX_CUT, 0.9)
    } else {
        MAX_CUT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimate of a motion with constant jerk `j`: `ā` grows linearly, so `e_r = h³|j|/12`
    /// exactly and `e_v = 0`.
    #[test]
    fn estimate_of_a_constant_jerk() {
        let j = Vector::<2>::new(3.0, -4.0);
        let mut hist = AccelerationHistory::<2>::default();
        let (h0, h1) = (0.1, 0.05);
        hist.push(0.0, &[j * 0.0]);
        hist.push(h0 / 2.0, &[j * (h0 / 2.0)]);
        let tau = h0 + h1 / 2.0;
        let (e_r, e_v) = second_order_estimate(h1, tau, &[j * tau], &hist, 0, &[true; 2]);
        assert!((e_r - h1.powi(3) * 5.0 / 12.0).abs() < 1e-15, "{e_r}");
        assert!(e_v.abs() < 1e-12, "{e_v}");
    }

    #[test]
    fn controller_factors_are_limited() {
        assert_eq!(accept_factor(0.0, 1.0, 2), MAX_GROWTH);
        assert_eq!(accept_factor(1e9, 1.0, 2), MAX_CUT);
        assert!((accept_factor(1.0, 1.0, 2) - SAFETY).abs() < 1e-15);
        assert_eq!(reject_factor(f64::NAN, 2), MAX_CUT);
        assert!((reject_factor(8.0, 2) - 0.45).abs() < 1e-12);
    }
}
