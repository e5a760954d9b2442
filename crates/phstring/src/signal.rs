//! Signals given by samples: a table of times and values, interpolated by a C¹ piecewise
//! cubic (docs/method.md §14, "Motion and force tables"), and the rigid motion of a platform
//! given by six such signals (surge, sway, heave, roll, pitch, yaw).
//!
//! A moving support driven by a [`Sampled`] signal gets both its position `x(t)` and its
//! velocity `ẋ(t)` from the same interpolant, so the velocity the stepper holds at the support
//! (docs/method.md eq. (14.5)) is the exact derivative of the path the support follows.

use nalgebra::{Matrix3, Vector3};

/// Why samples cannot make a [`Sampled`] signal.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// Fewer than two samples.
    #[error("a table needs at least 2 rows, got {count}")]
    TooFew {
        /// Number of samples.
        count: usize,
    },
    /// Times and values of different lengths.
    #[error("{times} times but {values} values")]
    Lengths {
        /// Number of times.
        times: usize,
        /// Number of values.
        values: usize,
    },
    /// A time or value that is not finite.
    #[error("row {row}: {what} is {value}, not a finite number")]
    NotFinite {
        /// Row (0-based).
        row: usize,
        /// `time` or `value`.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A time not after the one before it.
    #[error("row {row}: time {time} s is not after the previous row's {previous} s")]
    NotIncreasing {
        /// Row (0-based).
        row: usize,
        /// Its time [s].
        time: f64,
        /// The previous row's time [s].
        previous: f64,
    },
}

/// A scalar signal sampled at strictly increasing times `t_i` [s] with values `x_i`,
/// interpolated by the piecewise cubic Hermite polynomial whose slope at each sample is the
/// derivative of the parabola through it and its two neighbours (three-point slopes on
/// uneven spacing; one-sided three-point slopes at the first and the last sample, the chord
/// slope with two samples). The interpolant passes through every sample, is C¹ (its
/// derivative is continuous, also at the samples), reproduces quadratics exactly, and
/// approximates a smooth signal to `O(Δt³)` in value and `O(Δt²)` in slope. Each piece
/// depends on four samples only, so a bad sample disturbs its neighbourhood, not the whole
/// table, and no linear system is solved.
///
/// Outside `[t_0, t_last]` the signal holds the nearest end value with zero rate.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampled {
    times: Vec<f64>,
    values: Vec<f64>,
    slopes: Vec<f64>,
}

impl Sampled {
    /// The signal through `(times[i], values[i])` [s, unit of the value]. Refused: fewer than
    /// two samples, different lengths, non-finite entries, times not strictly increasing.
    pub fn new(times: Vec<f64>, values: Vec<f64>) -> Result<Self, SampleError> {
        if times.len() != values.len() {
            return Err(SampleError::Lengths {
                times: times.len(),
                values: values.len(),
            });
        }
        if times.len() < 2 {
            return Err(SampleError::TooFew { count: times.len() });
        }
        for (row, (&t, &x)) in times.iter().zip(&values).enumerate() {
            for (what, value) in [("time", t), ("value", x)] {
                if !value.is_finite() {
                    return Err(SampleError::NotFinite { row, what, value });
                }
            }
            if row > 0 && t <= times[row - 1] {
                return Err(SampleError::NotIncreasing {
                    row,
                    time: t,
                    previous: times[row - 1],
                });
            }
        }
        let slopes = three_point_slopes(&times, &values);
        Ok(Self {
            times,
            values,
            slopes,
        })
    }

    /// The sample times [s].
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The sample values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The interpolant's slopes at the samples [value unit / s].
    pub fn slopes(&self) -> &[f64] {
        &self.slopes
    }

    /// The piece that `t` lies in: `i` with `t_i ≤ t ≤ t_{i+1}`, `None` outside the table.
    fn piece(&self, t: f64) -> Option<usize> {
        let last = self.times.len() - 1;
        if !(t >= self.times[0] && t <= self.times[last]) {
            return None;
        }
        // The first sample after `t`, minus one; `t = t_last` is in the last piece.
        let after = self.times.partition_point(|&s| s <= t);
        Some(after.saturating_sub(1).min(last - 1))
    }

    /// The value at time `t` [s]; outside the table the nearest end value (NaN for a NaN
    /// time).
    pub fn value(&self, t: f64) -> f64 {
        let Some(i) = self.piece(t) else {
            return self.outside(t);
        };
        let h = self.times[i + 1] - self.times[i];
        let s = (t - self.times[i]) / h;
        let (s2, s3) = (s * s, s * s * s);
        let h01 = 3.0 * s2 - 2.0 * s3;
        let h10 = s3 - 2.0 * s2 + s;
        let h11 = s3 - s2;
        let (x0, x1) = (self.values[i], self.values[i + 1]);
        // h00 = 1 − h01: the form x0 + h01 (x1 − x0) keeps x0 exact at s = 0.
        x0 + h01 * (x1 - x0) + h * (h10 * self.slopes[i] + h11 * self.slopes[i + 1])
    }

    /// The rate `dx/dt` at time `t` [value unit / s]: the derivative of [`Self::value`];
    /// zero outside the table (NaN for a NaN time).
    pub fn rate(&self, t: f64) -> f64 {
        let Some(i) = self.piece(t) else {
            return if t.is_nan() { f64::NAN } else { 0.0 };
        };
        let h = self.times[i + 1] - self.times[i];
        let s = (t - self.times[i]) / h;
        let s2 = s * s;
        let d01 = 6.0 * (s - s2);
        let d10 = 3.0 * s2 - 4.0 * s + 1.0;
        let d11 = 3.0 * s2 - 2.0 * s;
        let (x0, x1) = (self.values[i], self.values[i + 1]);
        d01 * (x1 - x0) / h + d10 * self.slopes[i] + d11 * self.slopes[i + 1]
    }

    /// The held end value outside the table.
    fn outside(&self, t: f64) -> f64 {
        if t < self.times[0] {
            self.values[0]
        } else if t > self.times[self.times.len() - 1] {
            self.values[self.values.len() - 1]
        } else {
            f64::NAN
        }
    }
}

/// The slope at every sample: the derivative there of the parabola through the sample and
/// its neighbours (at the ends, of the parabola through the first or last three samples).
fn three_point_slopes(t: &[f64], x: &[f64]) -> Vec<f64> {
    let n = t.len();
    let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let d: Vec<f64> = (0..n - 1).map(|i| (x[i + 1] - x[i]) / h[i]).collect();
    if n == 2 {
        return vec![d[0]; 2];
    }
    let mut m = Vec::with_capacity(n);
    m.push(((2.0 * h[0] + h[1]) * d[0] - h[0] * d[1]) / (h[0] + h[1]));
    for i in 1..n - 1 {
        m.push((h[i] * d[i - 1] + h[i - 1] * d[i]) / (h[i - 1] + h[i]));
    }
    let (a, b) = (h[n - 2], h[n - 3]);
    m.push(((2.0 * a + b) * d[n - 2] - a * d[n - 3]) / (a + b));
    m
}

/// The rotation of a platform by roll `φ`, pitch `θ` and yaw `ψ` [rad], MoorDyn's
/// convention: `R = Rx(φ) Ry(θ) Rz(ψ)` (rotations about the fixed x, y, z axes; positive
/// roll lowers the `−y` side, positive pitch lowers the `+x` side, positive yaw turns `+x`
/// towards `+y`). Exact, not linearized in the angles.
pub fn rotation(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    let [rx, ry, rz] = axis_rotations(roll, pitch, yaw);
    rx * ry * rz
}

/// `[Rx(φ), Ry(θ), Rz(ψ)]`.
fn axis_rotations(roll: f64, pitch: f64, yaw: f64) -> [Matrix3<f64>; 3] {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        Matrix3::new(1.0, 0.0, 0.0, 0.0, cf, -sf, 0.0, sf, cf),
        Matrix3::new(ct, 0.0, st, 0.0, 1.0, 0.0, -st, 0.0, ct),
        Matrix3::new(cp, -sp, 0.0, sp, cp, 0.0, 0.0, 0.0, 1.0),
    ]
}

/// `[dRx/dφ, dRy/dθ, dRz/dψ]`.
fn axis_rotation_derivatives(roll: f64, pitch: f64, yaw: f64) -> [Matrix3<f64>; 3] {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        Matrix3::new(0.0, 0.0, 0.0, 0.0, -sf, -cf, 0.0, cf, -sf),
        Matrix3::new(-st, 0.0, ct, 0.0, 0.0, 0.0, -ct, 0.0, -st),
        Matrix3::new(-sp, -cp, 0.0, cp, -sp, 0.0, 0.0, 0.0, 0.0),
    ]
}

/// The rigid motion of a platform at one time: where its reference point is and how it is
/// turned, and how fast both change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlatformState {
    /// The time [s].
    pub t: f64,
    /// The reference point `p(t)` [m].
    pub position: Vector3<f64>,
    /// The rotation `R(t) = Rx(φ) Ry(θ) Rz(ψ)` ([`rotation`]).
    pub rotation: Matrix3<f64>,
    /// The reference point's velocity `ṗ(t)` [m/s].
    pub velocity: Vector3<f64>,
    /// The rotation's rate `Ṙ(t)` [1/s], from the angle rates.
    pub rotation_rate: Matrix3<f64>,
}

impl PlatformState {
    /// The state of `channels` (surge, sway, heave [m], roll, pitch, yaw [rad]) at `t` [s].
    fn of(channels: &[Sampled; 6], t: f64) -> Self {
        let c = channels;
        let (f, th, ps) = (c[3].value(t), c[4].value(t), c[5].value(t));
        let [rx, ry, rz] = axis_rotations(f, th, ps);
        let [dx, dy, dz] = axis_rotation_derivatives(f, th, ps);
        let rotation_rate =
            dx * ry * rz * c[3].rate(t) + rx * dy * rz * c[4].rate(t) + rx * ry * dz * c[5].rate(t);
        Self {
            t,
            position: Vector3::new(c[0].value(t), c[1].value(t), c[2].value(t)),
            rotation: rx * ry * rz,
            velocity: Vector3::new(c[0].rate(t), c[1].rate(t), c[2].rate(t)),
            rotation_rate,
        }
    }
}

/// The rigid motion of a platform: the position `p(t)` [m] of its reference point and its
/// orientation `R(t) = Rx(φ) Ry(θ) Rz(ψ)` ([`rotation`]) from six sampled signals, surge,
/// sway, heave [m] and roll, pitch, yaw [rad]. A point with body coordinates `b` [m] (its
/// offset from the reference point when the platform is not rotated) is at
/// `p(t) + R(t) b` and moves at `ṗ(t) + Ṙ(t) b`, with `Ṙ` from the interpolated angle rates:
/// every point of the platform follows a C¹ path whose velocity is its exact derivative.
///
/// The path remembers the [`PlatformState`] of the last time it was asked about, so that the
/// supports it carries (three position and three velocity components each, all asked at the
/// same times by a step) share one evaluation of the six channels per time. The remembered
/// state is the same computation as a fresh one, so answers do not depend on it.
#[derive(Debug)]
pub struct PlatformPath {
    /// Surge, sway, heave [m], roll, pitch, yaw [rad], in this order.
    channels: [Sampled; 6],
    /// The state at the last time asked (`None` before the first).
    last: std::sync::Mutex<Option<PlatformState>>,
}

impl Clone for PlatformPath {
    fn clone(&self) -> Self {
        Self::new(self.channels.clone())
    }
}

impl PartialEq for PlatformPath {
    fn eq(&self, other: &Self) -> bool {
        self.channels == other.channels
    }
}

impl PlatformPath {
    /// The path of the six `channels`: surge, sway, heave [m], roll, pitch, yaw [rad].
    pub fn new(channels: [Sampled; 6]) -> Self {
        Self {
            channels,
            last: std::sync::Mutex::new(None),
        }
    }

    /// The six channels: surge, sway, heave [m], roll, pitch, yaw [rad].
    pub fn channels(&self) -> &[Sampled; 6] {
        &self.channels
    }

    /// The platform's pose and rates at `t` [s] (evaluated once per distinct time).
    pub fn state(&self, t: f64) -> PlatformState {
        // A poisoned lock only means another thread panicked while holding it; the cached
        // value is a plain copy and stays valid.
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        match *last {
            Some(s) if s.t.to_bits() == t.to_bits() => s,
            _ => {
                let s = PlatformState::of(&self.channels, t);
                *last = Some(s);
                s
            }
        }
    }

    /// The pose at `t` [s]: reference point [m] and rotation.
    pub fn pose(&self, t: f64) -> (Vector3<f64>, Matrix3<f64>) {
        let s = self.state(t);
        (s.position, s.rotation)
    }

    /// The position [m] at `t` [s] of the point with body coordinates `b` [m].
    pub fn point(&self, t: f64, b: &Vector3<f64>) -> Vector3<f64> {
        let s = self.state(t);
        s.position + s.rotation * b
    }

    /// The velocity [m/s] at `t` [s] of the point with body coordinates `b` [m].
    pub fn point_velocity(&self, t: f64, b: &Vector3<f64>) -> Vector3<f64> {
        let s = self.state(t);
        s.velocity + s.rotation_rate * b
    }

    /// The body coordinates [m] of the point that is at `r` [m] at time `t` [s]:
    /// `R(t)ᵀ (r − p(t))`.
    pub fn body_coordinates(&self, t: f64, r: &Vector3<f64>) -> Vector3<f64> {
        let (p, rot) = self.pose(t);
        rot.transpose() * (r - p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampled(f: impl Fn(f64) -> f64, t: &[f64]) -> Sampled {
        Sampled::new(t.to_vec(), t.iter().map(|&s| f(s)).collect()).unwrap()
    }

    /// Uneven times from −1 to 3 s.
    fn uneven() -> Vec<f64> {
        vec![-1.0, -0.4, 0.0, 0.3, 1.1, 1.5, 2.2, 3.0]
    }

    #[test]
    fn passes_through_the_samples_and_reproduces_a_quadratic() {
        let q = |t: f64| 100.0 + 2.0 * t - 0.75 * t * t;
        let s = sampled(q, &uneven());
        for (&t, &x) in s.times().iter().zip(s.values()) {
            assert_eq!(s.value(t), x);
        }
        for k in 0..=400 {
            let t = -1.0 + 4.0 * k as f64 / 400.0;
            assert!((s.value(t) - q(t)).abs() < 1e-12, "t = {t}");
            assert!((s.rate(t) - (2.0 - 1.5 * t)).abs() < 1e-12, "t = {t}");
        }
    }

    /// C¹: the rate has no jump at the samples (left and right limits agree to round-off,
    /// while the second derivative does jump there), and the rate is the derivative of the
    /// value (central difference, error `O(δ²)` between the samples).
    #[test]
    fn interpolant_is_c1_and_its_rate_is_the_derivative_of_its_value() {
        let s = sampled(|t| (2.0 * t).sin() * (0.3 * t).exp(), &uneven());
        let eps = 1e-9;
        let mut second_jump = 0.0f64;
        for &t in &s.times()[1..s.times().len() - 1] {
            let (left, right) = (s.rate(t - eps), s.rate(t + eps));
            assert!(
                (left - right).abs() < 1e-7,
                "rate jumps at t = {t}: {left} vs {right}"
            );
            let d2 = |a: f64| (s.rate(a + 1e-6) - s.rate(a - 1e-6)) / 2e-6;
            second_jump = second_jump.max((d2(t + 1e-4) - d2(t - 1e-4)).abs());
        }
        // The interpolant is not C²: the test would not see a missing C¹ by accident.
        assert!(second_jump > 1e-2, "second derivative jump {second_jump}");
        // Off the samples, where the difference would straddle the jump of the second
        // derivative.
        let d = 1e-5;
        for k in 0..399 {
            let t = -1.0 + 4.0 * (k as f64 + 0.37) / 400.0;
            let fd = (s.value(t + d) - s.value(t - d)) / (2.0 * d);
            assert!(
                (fd - s.rate(t)).abs() < 1e-8,
                "t = {t}: {fd} vs {}",
                s.rate(t)
            );
        }
    }

    #[test]
    fn holds_the_end_values_at_rest_outside_the_table() {
        let s = sampled(|t| 3.0 + t, &[0.0, 1.0, 2.0]);
        assert_eq!((s.value(-5.0), s.rate(-5.0)), (3.0, 0.0));
        assert_eq!((s.value(9.0), s.rate(9.0)), (5.0, 0.0));
        assert_eq!(s.rate(0.0), 1.0);
        assert_eq!(s.rate(2.0), 1.0);
        assert!(s.value(f64::NAN).is_nan() && s.rate(f64::NAN).is_nan());
    }

    /// Third order in the value and second order in the rate: halving the spacing divides
    /// the largest errors for `sin(t)` by about 8 and 4.
    #[test]
    fn converges_at_third_order_in_value_and_second_in_rate() {
        let errors = |n: usize| {
            let t: Vec<f64> = (0..=n).map(|i| 6.0 * i as f64 / n as f64).collect();
            let s = sampled(f64::sin, &t);
            let (mut ev, mut er) = (0.0f64, 0.0f64);
            for k in 0..=3000 {
                let x = 6.0 * k as f64 / 3000.0;
                ev = ev.max((s.value(x) - x.sin()).abs());
                er = er.max((s.rate(x) - x.cos()).abs());
            }
            (ev, er)
        };
        let (v1, r1) = errors(60);
        let (v2, r2) = errors(120);
        let (pv, pr) = ((v1 / v2).log2(), (r1 / r2).log2());
        assert!(
            (2.8..3.3).contains(&pv),
            "value order {pv} ({v1:e}, {v2:e})"
        );
        assert!((1.8..2.3).contains(&pr), "rate order {pr} ({r1:e}, {r2:e})");
    }

    #[test]
    fn refuses_bad_samples() {
        let e = |t: Vec<f64>, x: Vec<f64>| Sampled::new(t, x).unwrap_err();
        assert_eq!(e(vec![0.0], vec![1.0]), SampleError::TooFew { count: 1 });
        assert_eq!(
            e(vec![0.0, 1.0, 1.0], vec![1.0; 3]),
            SampleError::NotIncreasing {
                row: 2,
                time: 1.0,
                previous: 1.0
            }
        );
        assert!(matches!(
            e(vec![0.0, 1.0], vec![1.0, f64::NAN]),
            SampleError::NotFinite {
                row: 1,
                what: "value",
                ..
            }
        ));
        assert_eq!(
            e(vec![0.0, 1.0], vec![1.0]),
            SampleError::Lengths {
                times: 2,
                values: 1
            }
        );
    }

    /// MoorDyn's convention: yaw turns +x to +y, pitch lowers +x, roll raises +y; the
    /// rotation of (roll, pitch, yaw) applies yaw first (R = Rx Ry Rz).
    #[test]
    fn rotation_follows_the_convention() {
        let q = std::f64::consts::FRAC_PI_2;
        let close = |a: Vector3<f64>, b: Vector3<f64>| (a - b).amax() < 1e-15;
        assert!(close(rotation(0.0, 0.0, q) * Vector3::x(), Vector3::y()));
        assert!(close(rotation(0.0, q, 0.0) * Vector3::x(), -Vector3::z()));
        assert!(close(rotation(q, 0.0, 0.0) * Vector3::y(), Vector3::z()));
        // Yaw first, then pitch about the fixed y axis: +x → +y → +y.
        assert!(close(rotation(0.0, q, q) * Vector3::x(), Vector3::y()));
        let r = rotation(0.3, -0.2, 1.1);
        assert!((r.transpose() * r - Matrix3::identity()).amax() < 1e-15);
        assert!((r.determinant() - 1.0).abs() < 1e-15);
    }

    /// A platform point's velocity is the derivative of its position (central difference, off
    /// the samples).
    #[test]
    fn platform_point_velocity_is_the_derivative_of_its_path() {
        let t: Vec<f64> = (0..=40).map(|i| -1.0 + 0.25 * i as f64).collect();
        let ch = |f: &dyn Fn(f64) -> f64| sampled(f, &t);
        let path = PlatformPath::new([
            ch(&|t| 3.0 * (0.4 * t).sin()),
            ch(&|t| 0.5 * t),
            ch(&|t| (0.7 * t).cos()),
            ch(&|t| 0.05 * (0.9 * t).sin()),
            ch(&|t| -0.08 * (0.6 * t).cos()),
            ch(&|t| 0.3 * (0.2 * t).sin()),
        ]);
        let b = Vector3::new(40.0, -25.0, -15.0);
        let d = 1e-5;
        for k in 0..90 {
            let s = -0.87 + 0.1 * k as f64;
            let fd = (path.point(s + d, &b) - path.point(s - d, &b)) / (2.0 * d);
            let v = path.point_velocity(s, &b);
            assert!((fd - v).amax() < 1e-6, "t = {s}: {fd:?} vs {v:?}");
        }
        let r = path.point(1.3, &b);
        assert!((path.body_coordinates(1.3, &r) - b).amax() < 1e-12);
    }

    /// The remembered state changes nothing: positions and velocities of three points, asked
    /// in the order a step asks (every position, then every velocity, at each of the times
    /// of a `dg4` step's sub-steps and a repeated time), are bit for bit those of the
    /// formulas `p + R b` and `ṗ + Ṙ b` evaluated afresh from the channels.
    #[test]
    fn remembered_pose_gives_the_same_bits_as_a_fresh_evaluation() {
        let t: Vec<f64> = (0..=30).map(|i| 0.5 * i as f64).collect();
        let ch = |f: &dyn Fn(f64) -> f64| sampled(f, &t);
        let channels = [
            ch(&|t| 20.0 + 1.5 * (0.52 * t).sin()),
            ch(&|t| 0.4 * (0.05 * t).sin()),
            ch(&|t| 0.8 * (0.52 * t).cos()),
            ch(&|t| 0.01 * (0.3 * t).sin()),
            ch(&|t| 0.02 * (0.52 * t + 1.0).sin()),
            ch(&|t| 0.005 * (0.07 * t).sin()),
        ];
        let path = PlatformPath::new(channels.clone());
        let fresh = |t: f64, b: &Vector3<f64>| {
            let c = &channels;
            let (f, th, ps) = (c[3].value(t), c[4].value(t), c[5].value(t));
            let p = Vector3::new(c[0].value(t), c[1].value(t), c[2].value(t));
            let [rx, ry, rz] = axis_rotations(f, th, ps);
            let [dx, dy, dz] = axis_rotation_derivatives(f, th, ps);
            let r_dot = dx * ry * rz * c[3].rate(t)
                + rx * dy * rz * c[4].rate(t)
                + rx * ry * dz * c[5].rate(t);
            let v = Vector3::new(c[0].rate(t), c[1].rate(t), c[2].rate(t));
            (p + rotation(f, th, ps) * b, v + r_dot * b)
        };
        let points = [
            Vector3::new(-40.87, 70.79, -70.0),
            Vector3::new(81.75, 0.0, -70.0),
            Vector3::new(-40.87, -70.79, -70.0),
        ];
        // The triple jump's sub-step ends (docs/method.md §19).
        let g1 = 1.0 / (2.0 - 2f64.cbrt());
        let g2 = 1.0 - 2.0 * g1;
        let h = 0.02;
        let mut times = Vec::new();
        for n in 0..200 {
            let t0 = n as f64 * h;
            times.extend([t0 + g1 * h, t0 + (g1 + g2) * h, t0 + h, t0 + h]);
        }
        for &s in &times {
            let x: Vec<_> = points.iter().map(|b| path.point(s, b)).collect();
            let v: Vec<_> = points.iter().map(|b| path.point_velocity(s, b)).collect();
            for (k, b) in points.iter().enumerate() {
                let (xf, vf) = fresh(s, b);
                assert_eq!((x[k], v[k]), (xf, vf), "t = {s}, point {k}");
            }
        }
        assert_eq!(path.clone(), path);
        assert_eq!(path.state(3.7), PlatformPath::new(channels).state(3.7));
    }
}
