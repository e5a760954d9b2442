//! Stored-energy functions `W(C)` and their discrete gradients (docs/method.md §3, §6).
//!
//! A material is described by the stored energy per unit reference length `W(C)` [J/m = N]
//! as a function of the strain `C = r'·r'` (dimensionless), with derivatives `W'(C)` and
//! `W''(C)`. The stress is `S = 2 W'(C)` [N]. The discrete-gradient scheme needs the
//! Greenspan quotient `(W(C₁) − W(C₀)) / (C₁ − C₀)`; the built-in laws evaluate it in a form
//! that has no switch tolerance and no cancellation, so the directionality identity
//! `S̄ (C₁ − C₀) = 2 (W(C₁) − W(C₀))` holds to a few ulps for every `ΔC`.

use std::fmt::Debug;

/// A hyperelastic stored-energy function `W(C)` of the string (energy per unit reference
/// length, in N), with its derivatives in `C`.
///
/// Implement `w`, `dw`, `d2w` for a custom law. The default [`StoredEnergy::quotient`] is
/// a plain difference quotient with a Taylor fallback for tiny `ΔC` (accurate to about
/// `sqrt(eps)`-relative near the switch); override it with an exact form for full accuracy, as
/// the built-in laws do.
pub trait StoredEnergy: Debug + Send + Sync {
    /// Stored energy per unit reference length `W(C)` [N].
    fn w(&self, c: f64) -> f64;
    /// First derivative `W'(C)` [N]; the stress is `S = 2 W'(C)`.
    fn dw(&self, c: f64) -> f64;
    /// Second derivative `W''(C)` [N].
    fn d2w(&self, c: f64) -> f64;
    /// Whether `C` lies in the domain of `W` (for example `C > 0` for the logarithmic law).
    fn admissible(&self, c: f64) -> bool {
        c.is_finite()
    }
    /// Greenspan quotient `q = (W(C₁) − W(C₀)) / (C₁ − C₀)`, equal to `W'(C₀)` when
    /// `C₁ = C₀`, together with its partial derivative `∂q/∂C₁` (used by Newton's method).
    /// The discrete-gradient stress is `S̄ = 2 q` (docs/method.md eq. (5.4), paper eq. (36)).
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        let dc = c1 - c0;
        let m = 0.5 * (c0 + c1);
        let scale = c0.abs().max(c1.abs()).max(1.0);
        if dc.abs() > 1e-4 * scale {
            let q = (self.w(c1) - self.w(c0)) / dc;
            (q, (self.dw(c1) - q) / dc)
        } else {
            // Midpoint Taylor expansion: q = W'(m) + W'''(m) ΔC²/24 + O(ΔC⁴).
            let d3 = if dc == 0.0 {
                0.0
            } else {
                (self.d2w(c1) - self.d2w(c0)) / dc
            };
            (
                self.dw(m) + d3 * dc * dc / 24.0,
                0.5 * self.d2w(m) + d3 * dc / 6.0,
            )
        }
    }
}

/// The paper's hyperelastic law (eq. (7)): `W = EA/4 (C − ln C − 1)`, `S = EA/2 (1 − 1/C)`.
/// Defined for `C > 0` only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hyperelastic {
    /// Axial stiffness `EA` [N].
    pub ea: f64,
}

/// Linear elastic law (paper Remark 1): `W = EA/2 (√C − 1)²`, `S = EA (1 − 1/√C)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearElastic {
    /// Axial stiffness `EA` [N].
    pub ea: f64,
}

/// St. Venant–Kirchhoff law (paper Remark 2): `W = EA/8 (C − 1)²`, `S = EA/2 (C − 1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StVenantKirchhoff {
    /// Axial stiffness `EA` [N].
    pub ea: f64,
}

/// `C − 1`, exact for `C ∈ [0.5, 2]` (Sterbenz) and correctly rounded otherwise.
#[inline]
fn cm1(c: f64) -> f64 {
    c - 1.0
}

/// `1/(2k+1)` for `k = 0 … 31`: enough terms for `t² ≤ 1/4` to reach `1e-17` relative.
const RECIP_ODD: [f64; 32] = {
    let mut r = [0.0; 32];
    let mut k = 0;
    while k < 32 {
        r[k] = 1.0 / (2 * k + 1) as f64;
        k += 1;
    }
    r
};

/// For `|t| < 1`: `A(t) − 1 = atanh(t)/t − 1 = Σ_{k≥1} t^{2k}/(2k+1)` without cancellation,
/// and its derivative `A'(t) = Σ_{k≥1} 2k t^{2k−1}/(2k+1)`.
#[inline]
fn atanh_ratio(t: f64) -> (f64, f64) {
    let t2 = t * t;
    if t2 < 1e-6 {
        // Four terms: the first omitted one, t^10/11, is below 1e-24 of the sum t²/3 + ….
        const R: [f64; 4] = [1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0];
        let a = t2 * (R[0] + t2 * (R[1] + t2 * (R[2] + t2 * R[3])));
        let da = t * (2.0 * R[0] + t2 * (4.0 * R[1] + t2 * (6.0 * R[2] + t2 * (8.0 * R[3]))));
        return (a, da);
    }
    if t2 > 0.25 {
        let a = t.atanh() / t;
        return (a - 1.0, (1.0 / (1.0 - t2) - a) / t);
    }
    // Fixed-length Horner forms: the first omitted term is below 1e-17 of the sum.
    if t2 < 1e-3 {
        return atanh_series::<6>(t, t2);
    }
    if t2 < 1e-2 {
        return atanh_series::<9>(t, t2);
    }
    if t2 < 0.0625 {
        return atanh_series::<14>(t, t2);
    }
    // p = t^{2k}; terms decrease at least geometrically with ratio t² ≤ 1/4.
    let (mut sum, mut dsum) = (0.0, 0.0);
    let mut p = t2;
    for (k, r) in RECIP_ODD.iter().enumerate().skip(1) {
        let term = p * r;
        sum += term;
        dsum += (2 * k) as f64 * term;
        if term <= sum * 1e-17 {
            break;
        }
        p *= t2;
    }
    // dsum = Σ 2k t^{2k}/(2k+1) = t A'(t).
    (sum, if t == 0.0 { 0.0 } else { dsum / t })
}

/// `(Σ_{k=1..K} t^{2k}/(2k+1), Σ_{k=1..K} 2k t^{2k−1}/(2k+1))`: Horner's rule in `t⁴` on the
/// odd and even `k` separately (four independent chains instead of two twice as long).
#[inline(always)]
fn atanh_series<const K: usize>(t: f64, t2: f64) -> (f64, f64) {
    let t4 = t2 * t2;
    // Terms k = 1, 3, 5, … (powers t2^0, t2^2, …) and k = 2, 4, … (t2^1, t2^3, …).
    let (mut a_odd, mut a_even, mut d_odd, mut d_even) = (0.0, 0.0, 0.0, 0.0);
    let mut k = K;
    while k >= 1 {
        let (a, d) = (RECIP_ODD[k], (2 * k) as f64 * RECIP_ODD[k]);
        if k % 2 == 1 {
            a_odd = a_odd * t4 + a;
            d_odd = d_odd * t4 + d;
        } else {
            a_even = a_even * t4 + a;
            d_even = d_even * t4 + d;
        }
        k -= 1;
    }
    (t2 * (a_odd + t2 * a_even), t * (d_odd + t2 * d_even))
}

impl StoredEnergy for Hyperelastic {
    /// `W = EA/4 (x − log1p x)` with `x = C − 1`; for `|x| < 1/2` evaluated as
    /// `x²/(2+x) − 2u (atanh(u)/u − 1)`, `u = x/(2+x)`, so that it keeps full relative
    /// accuracy near `C = 1` (where `W ≈ EA x²/8`).
    fn w(&self, c: f64) -> f64 {
        let x = cm1(c);
        if x.abs() >= 0.5 {
            return 0.25 * self.ea * (x - x.ln_1p());
        }
        let u = x / (2.0 + x);
        let (a_m1, _) = atanh_ratio(u);
        0.25 * self.ea * (x * x / (2.0 + x) - 2.0 * u * a_m1)
    }
    fn dw(&self, c: f64) -> f64 {
        0.25 * self.ea * cm1(c) / c
    }
    fn d2w(&self, c: f64) -> f64 {
        0.25 * self.ea / (c * c)
    }
    fn admissible(&self, c: f64) -> bool {
        c.is_finite() && c > 0.0
    }
    /// Exact form: with `m = (C₀+C₁)/2`, `δ = (C₁−C₀)/2`, `t = δ/m`,
    /// `ln(C₁/C₀)/(C₁−C₀) = atanh(t)/(t m)`, so
    /// `q = EA/4 · ((m − 1) − (atanh(t)/t − 1)) / m` with both brackets free of cancellation.
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        let m = 0.5 * (c0 + c1);
        let mm1 = 0.5 * (cm1(c0) + cm1(c1));
        let t = 0.5 * (c1 - c0) / m;
        let (a_m1, da) = atanh_ratio(t);
        let q = 0.25 * self.ea * (mm1 - a_m1) / m;
        // ℓ = A(t)/m with A = atanh(t)/t; ∂ℓ/∂C₁ = (A'(t)(1 − t) − A(t)) / (2 m²), q = EA/4 (1 − ℓ).
        // (Only Newton's matrix uses it, so one reciprocal suffices.)
        let inv_m = 1.0 / m;
        let dl = (da * (1.0 - t) - (1.0 + a_m1)) * (0.5 * inv_m * inv_m);
        (q, -0.25 * self.ea * dl)
    }
}

impl StoredEnergy for LinearElastic {
    fn w(&self, c: f64) -> f64 {
        let e = cm1(c) / (c.sqrt() + 1.0);
        0.5 * self.ea * e * e
    }
    fn dw(&self, c: f64) -> f64 {
        let s = c.sqrt();
        0.5 * self.ea * (cm1(c) / (s + 1.0)) / s
    }
    fn d2w(&self, c: f64) -> f64 {
        0.25 * self.ea / (c * c.sqrt())
    }
    fn admissible(&self, c: f64) -> bool {
        c.is_finite() && c > 0.0
    }
    /// Exact form: with `a = C₀ − 1`, `b = C₁ − 1` (exact near 1) and `s = √C`,
    /// `q = EA/2 · (a/(s₀+1) + b/(s₁+1)) / (s₀+s₁)`, evaluated as
    /// `EA/2 · ((a+b)(1+s₀)(s₀+s₁) + a (C₁−C₀)) / ((s₀+1)(s₁+1)(s₀+s₁)²)` so that the
    /// near-cancellation of the two terms happens exactly in `a + b`; `∂q/∂C₁` is
    /// `EA/2 / ((s₀+s₁)² s₁)`. Both share one reciprocal.
    #[inline]
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        let (s0, s1) = (c0.sqrt(), c1.sqrt());
        let sum = s0 + s1;
        let (a, b) = (cm1(c0), cm1(c1));
        let num = (a + b) * (1.0 + s0) * sum + a * (c1 - c0);
        let p = (s0 + 1.0) * (s1 + 1.0);
        let inv = 0.5 * self.ea / (p * sum * sum * s1);
        (num * s1 * inv, p * inv)
    }
}

impl StoredEnergy for StVenantKirchhoff {
    fn w(&self, c: f64) -> f64 {
        let x = cm1(c);
        0.125 * self.ea * x * x
    }
    fn dw(&self, c: f64) -> f64 {
        0.25 * self.ea * cm1(c)
    }
    fn d2w(&self, _c: f64) -> f64 {
        0.25 * self.ea
    }
    /// Exact form: `q = EA/8 ((C₀ − 1) + (C₁ − 1))`.
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        (0.125 * self.ea * (cm1(c0) + cm1(c1)), 0.125 * self.ea)
    }
}

/// Tension-only cable law: `W(C) = 0` for `C < 1` (the cable goes slack instead of carrying
/// compression) and the branch law for `C ≥ 1`. The branch must satisfy `W(1) = W'(1) = 0`
/// ([`Hyperelastic`] and [`LinearElastic`] do), so `W` is continuously differentiable; `W''`
/// jumps at `C = 1`. Defined for every finite `C`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TensionOnly<B> {
    /// The law in tension (`C ≥ 1`).
    pub branch: B,
}

impl<B: StoredEnergy> StoredEnergy for TensionOnly<B> {
    fn w(&self, c: f64) -> f64 {
        if c < 1.0 { 0.0 } else { self.branch.w(c) }
    }
    fn dw(&self, c: f64) -> f64 {
        if c < 1.0 { 0.0 } else { self.branch.dw(c) }
    }
    fn d2w(&self, c: f64) -> f64 {
        if c < 1.0 { 0.0 } else { self.branch.d2w(c) }
    }
    fn admissible(&self, c: f64) -> bool {
        c.is_finite()
    }
    /// Piecewise exact: `0` when both strains are slack, the branch's exact quotient when
    /// both are taut, `W(C_taut)/|C₁ − C₀|` (with sign) when the element crosses `C = 1`.
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        match (c0 < 1.0, c1 < 1.0) {
            (true, true) => (0.0, 0.0),
            (false, false) => self.branch.quotient(c0, c1),
            (true, false) => {
                let dc = c1 - c0;
                let q = self.branch.w(c1) / dc;
                (q, (self.branch.dw(c1) - q) / dc)
            }
            (false, true) => {
                let dc = c0 - c1;
                let q = self.branch.w(c0) / dc;
                (q, q / dc)
            }
        }
    }
}

/// The built-in material laws as one type (enum dispatch), as chosen in a scenario file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Material {
    /// [`Hyperelastic`], the paper's default.
    Hyperelastic(Hyperelastic),
    /// [`LinearElastic`] (paper Remark 1).
    LinearElastic(LinearElastic),
    /// [`StVenantKirchhoff`] (paper Remark 2).
    StVenantKirchhoff(StVenantKirchhoff),
    /// [`TensionOnly`] with the linear elastic branch (a cable: `N = EA (ν − 1)` in tension).
    TensionOnlyLinear(TensionOnly<LinearElastic>),
    /// [`TensionOnly`] with the paper's hyperelastic branch.
    TensionOnlyHyperelastic(TensionOnly<Hyperelastic>),
}

impl Material {
    /// The paper's hyperelastic law with axial stiffness `ea` [N].
    pub fn hyperelastic(ea: f64) -> Self {
        Self::Hyperelastic(Hyperelastic { ea })
    }
    /// The linear elastic law with axial stiffness `ea` [N].
    pub fn linear_elastic(ea: f64) -> Self {
        Self::LinearElastic(LinearElastic { ea })
    }
    /// The St. Venant–Kirchhoff law with axial stiffness `ea` [N].
    pub fn st_venant_kirchhoff(ea: f64) -> Self {
        Self::StVenantKirchhoff(StVenantKirchhoff { ea })
    }
    /// Tension-only cable with the linear elastic branch, axial stiffness `ea` [N].
    pub fn tension_only_linear(ea: f64) -> Self {
        Self::TensionOnlyLinear(TensionOnly {
            branch: LinearElastic { ea },
        })
    }
    /// Tension-only cable with the hyperelastic branch, axial stiffness `ea` [N].
    pub fn tension_only_hyperelastic(ea: f64) -> Self {
        Self::TensionOnlyHyperelastic(TensionOnly {
            branch: Hyperelastic { ea },
        })
    }
    /// Axial stiffness `EA` [N].
    pub fn ea(&self) -> f64 {
        match self {
            Self::Hyperelastic(m) => m.ea,
            Self::LinearElastic(m) => m.ea,
            Self::StVenantKirchhoff(m) => m.ea,
            Self::TensionOnlyLinear(m) => m.branch.ea,
            Self::TensionOnlyHyperelastic(m) => m.branch.ea,
        }
    }
    /// Short name as used in scenario files: `hyperelastic`, `linear_elastic`,
    /// `st_venant_kirchhoff`, `tension_only_linear`, `tension_only_hyperelastic`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Hyperelastic(_) => "hyperelastic",
            Self::LinearElastic(_) => "linear_elastic",
            Self::StVenantKirchhoff(_) => "st_venant_kirchhoff",
            Self::TensionOnlyLinear(_) => "tension_only_linear",
            Self::TensionOnlyHyperelastic(_) => "tension_only_hyperelastic",
        }
    }
    /// The law named `name` (see [`Self::name`]) with axial stiffness `ea` [N].
    pub fn from_name(name: &str, ea: f64) -> Option<Self> {
        Some(match name {
            "hyperelastic" => Self::hyperelastic(ea),
            "linear_elastic" => Self::linear_elastic(ea),
            "st_venant_kirchhoff" => Self::st_venant_kirchhoff(ea),
            "tension_only_linear" => Self::tension_only_linear(ea),
            "tension_only_hyperelastic" => Self::tension_only_hyperelastic(ea),
            _ => return None,
        })
    }
}

macro_rules! dispatch {
    ($self:ident, $m:ident => $e:expr) => {
        match $self {
            Material::Hyperelastic($m) => $e,
            Material::LinearElastic($m) => $e,
            Material::StVenantKirchhoff($m) => $e,
            Material::TensionOnlyLinear($m) => $e,
            Material::TensionOnlyHyperelastic($m) => $e,
        }
    };
}

impl StoredEnergy for Material {
    #[inline]
    fn w(&self, c: f64) -> f64 {
        dispatch!(self, m => m.w(c))
    }
    #[inline]
    fn dw(&self, c: f64) -> f64 {
        dispatch!(self, m => m.dw(c))
    }
    #[inline]
    fn d2w(&self, c: f64) -> f64 {
        dispatch!(self, m => m.d2w(c))
    }
    #[inline]
    fn admissible(&self, c: f64) -> bool {
        dispatch!(self, m => m.admissible(c))
    }
    #[inline]
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        dispatch!(self, m => m.quotient(c0, c1))
    }
}

/// A linear spring between two nodes, as the stored energy of a one-element link whose
/// reference length is 1 m, so that `C = |r_b − r_a|²` is the squared spring length [m²]:
/// `W(C) = k/2 (√C − L₀)²` [J], with stiffness `k` [N/m] and rest length `L₀ ≥ 0` [m]. The
/// "stress" `S = 2W'(C) = k (1 − L₀/√C)` is in N/m and the spring force is `S √C = k (|d| − L₀)`
/// [N] (positive in tension). With `L₀ = 0` the energy `k/2 |d|²` is defined for every `C`;
/// with `L₀ > 0` the direction of the force is undefined at zero length, so `C > 0` is required.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearSpring {
    /// Stiffness `k` [N/m].
    pub k: f64,
    /// Rest length `L₀` [m].
    pub rest: f64,
}

impl StoredEnergy for LinearSpring {
    fn w(&self, c: f64) -> f64 {
        if self.rest == 0.0 {
            return 0.5 * self.k * c;
        }
        let d = c.sqrt() - self.rest;
        0.5 * self.k * d * d
    }
    fn dw(&self, c: f64) -> f64 {
        if self.rest == 0.0 {
            return 0.5 * self.k;
        }
        0.5 * self.k * (1.0 - self.rest / c.sqrt())
    }
    fn d2w(&self, c: f64) -> f64 {
        if self.rest == 0.0 {
            // W is linear in C; 0/0 at C = 0 must not leak into the midpoint Jacobian.
            return 0.0;
        }
        0.25 * self.k * self.rest / (c * c.sqrt())
    }
    fn admissible(&self, c: f64) -> bool {
        c.is_finite() && (self.rest == 0.0 || c > 0.0)
    }
    /// `W(C₁) − W(C₀) = k/2 (C₁ − C₀) (1 − 2L₀/(√C₀ + √C₁))`, exact in the difference.
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        if self.rest == 0.0 {
            return (0.5 * self.k, 0.0);
        }
        let (s0, s1) = (c0.sqrt(), c1.sqrt());
        let sum = s0 + s1;
        let q = 0.5 * self.k * (1.0 - 2.0 * self.rest / sum);
        let dq = 0.5 * self.k * self.rest / (sum * sum * s1);
        (q, dq)
    }
}

impl<T: StoredEnergy + ?Sized> StoredEnergy for &T {
    fn w(&self, c: f64) -> f64 {
        (**self).w(c)
    }
    fn dw(&self, c: f64) -> f64 {
        (**self).dw(c)
    }
    fn d2w(&self, c: f64) -> f64 {
        (**self).d2w(c)
    }
    fn admissible(&self, c: f64) -> bool {
        (**self).admissible(c)
    }
    fn quotient(&self, c0: f64, c1: f64) -> (f64, f64) {
        (**self).quotient(c0, c1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotient_limit_is_derivative() {
        for m in [
            Material::hyperelastic(20.0),
            Material::linear_elastic(20.0),
            Material::st_venant_kirchhoff(20.0),
            Material::tension_only_linear(20.0),
            Material::tension_only_hyperelastic(20.0),
        ] {
            for c in [0.3, 1.0, 1.7] {
                let (q, dq) = m.quotient(c, c);
                assert!(
                    (q - m.dw(c)).abs() <= 1e-15 * m.dw(c).abs().max(1.0),
                    "{m:?} {c}"
                );
                assert!((dq - 0.5 * m.d2w(c)).abs() <= 1e-14 * m.d2w(c), "{m:?} {c}");
            }
        }
    }
}
