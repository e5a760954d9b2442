//! A seabed given by a grid of water depths (docs/method.md §21, "Bathymetry grid"): the
//! seabed's height `b(x)` [m] over the horizontal coordinates, a C¹ piecewise-cubic Hermite
//! interpolant of the depths (tensor product in 3D), continued by its edge tangent outside
//! the grid; and the exact discrete gradient of `b` along a step (its average gradient over
//! the segment, integrated exactly).

use nalgebra::{SMatrix, SVector};

use crate::error::SetupError;

/// A seabed's depths on a rectilinear grid [m], positive down: the seabed lies at height
/// `−depth`. In 2D a profile along `x` (no `y` coordinates); in 3D a grid over `x` and `y`.
/// Between the grid points the depth is a C¹ cubic Hermite interpolant whose slopes at the
/// grid points are those of the parabola through the point and its neighbours (one-sided at
/// the ends; the secant with two points); beyond the grid it continues along its tangent at
/// the edge (docs/method.md §21).
#[derive(Debug, Clone, PartialEq)]
pub struct Bathymetry {
    x: Vec<f64>,
    y: Vec<f64>,
    depth: Vec<f64>,
}

/// The height `b` [m] of the seabed at a horizontal point, its gradient and its Hessian by
/// the horizontal coordinates (`[x, y]`; `y` entries 0 for a profile).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Height {
    pub b: f64,
    pub grad: [f64; 2],
    pub hess: [[f64; 2]; 2],
}

/// Checks `t` (named `what`) for at least two finite, strictly increasing values.
fn check_axis(what: &'static str, t: &[f64]) -> Result<(), SetupError> {
    if t.len() < 2 {
        return Err(SetupError::WaterParameter {
            what,
            index: None,
            value: t.len() as f64,
            range: "given at 2 or more grid points (the number given is shown)",
        });
    }
    for (k, &v) in t.iter().enumerate() {
        if !(v.is_finite() && (k == 0 || v > t[k - 1])) {
            return Err(SetupError::WaterParameter {
                what,
                index: Some(k),
                value: v,
                range: "finite and above the previous grid point's",
            });
        }
    }
    Ok(())
}

impl Bathymetry {
    /// A profile for 2D: depths `depth` [m] (positive down) at the strictly increasing
    /// coordinates `x` [m], at least two.
    pub fn profile(x: Vec<f64>, depth: Vec<f64>) -> Result<Self, SetupError> {
        Self::grid(x, Vec::new(), depth)
    }

    /// A grid for 3D (or a profile, with `y` empty): `depth[j·x.len() + i]` [m] (positive
    /// down) is the depth at `(x[i], y[j])`; `x` and `y` strictly increasing, at least two
    /// each.
    pub fn grid(x: Vec<f64>, y: Vec<f64>, depth: Vec<f64>) -> Result<Self, SetupError> {
        check_axis("bathymetry x coordinate [m]", &x)?;
        if !y.is_empty() {
            check_axis("bathymetry y coordinate [m]", &y)?;
        }
        let n = x.len() * y.len().max(1);
        if depth.len() != n {
            return Err(SetupError::WaterParameter {
                what: "bathymetry number of depths",
                index: None,
                value: depth.len() as f64,
                range: "one per grid point (x count times y count)",
            });
        }
        if let Some(k) = depth.iter().position(|d| !d.is_finite()) {
            return Err(SetupError::WaterParameter {
                what: "bathymetry depth [m] of grid point",
                index: Some(k),
                value: depth[k],
                range: "finite",
            });
        }
        Ok(Self { x, y, depth })
    }

    /// Grid coordinates along `x` [m].
    pub fn x(&self) -> &[f64] {
        &self.x
    }
    /// Grid coordinates along `y` [m] (empty for a profile).
    pub fn y(&self) -> &[f64] {
        &self.y
    }
    /// Depths [m], positive down, `x` fastest.
    pub fn depths(&self) -> &[f64] {
        &self.depth
    }
    /// Whether this is a profile (2D) rather than a grid (3D).
    pub fn is_profile(&self) -> bool {
        self.y.is_empty()
    }

    /// The interpolated depth [m] (positive down) at the horizontal point `(x, y)` [m]
    /// (`y` ignored for a profile).
    pub fn depth_at(&self, x: f64, y: f64) -> f64 {
        -self.height([x, y]).b
    }

    /// Whether the seabed's height varies along horizontal axis `k` (0: x, 1: y).
    pub(crate) fn slopes_along(&self, k: usize) -> bool {
        let nx = self.x.len();
        let mut rows = self.depth.chunks(nx);
        match k {
            0 => rows.any(|row| row.iter().any(|&d| d != row[0])),
            1 => !self.y.is_empty() && rows.any(|row| row != &self.depth[..nx]),
            _ => false,
        }
    }

    /// The seabed's height, gradient and Hessian at the horizontal point `p` [m].
    pub(crate) fn height(&self, p: [f64; 2]) -> Height {
        let sx = Stencil::at(&self.x, p[0]);
        let nx = self.x.len();
        let mut h = Height {
            b: 0.0,
            grad: [0.0; 2],
            hess: [[0.0; 2]; 2],
        };
        if self.y.is_empty() {
            for (a, i) in sx.indices(nx) {
                let d = -self.depth[i];
                h.b += sx.w[0][a] * d;
                h.grad[0] += sx.w[1][a] * d;
                h.hess[0][0] += sx.w[2][a] * d;
            }
            return h;
        }
        let sy = Stencil::at(&self.y, p[1]);
        for (c, j) in sy.indices(self.y.len()) {
            for (a, i) in sx.indices(nx) {
                let d = -self.depth[j * nx + i];
                let (wx, wy) = (&sx.w, &sy.w);
                h.b += wx[0][a] * wy[0][c] * d;
                h.grad[0] += wx[1][a] * wy[0][c] * d;
                h.grad[1] += wx[0][a] * wy[1][c] * d;
                h.hess[0][0] += wx[2][a] * wy[0][c] * d;
                h.hess[0][1] += wx[1][a] * wy[1][c] * d;
                h.hess[1][1] += wx[0][a] * wy[2][c] * d;
            }
        }
        h.hess[1][0] = h.hess[0][1];
        h
    }

    /// The exact discrete gradient of the height along the step from `p0` to `p1` [m]: the
    /// mean gradient `Ḡ = ∫₀¹ ∇b(p0 + s Δ) ds`, so that `Ḡ·Δ = b(p1) − b(p0)`, and its
    /// derivative by `p1`, `∫₀¹ s ∇²b(p0 + s Δ) ds` (docs/method.md §21). The segment is
    /// cut where it crosses grid lines; on each piece `b` is a polynomial of degree ≤ 6 in
    /// `s`, so three-point Gauss–Legendre integrates both exactly.
    pub(crate) fn mean_gradient(&self, p0: [f64; 2], p1: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
        let d = [p1[0] - p0[0], p1[1] - p0[1]];
        let mut walk = [
            Crossings::new(&self.x, p0[0], d[0]),
            Crossings::new(&self.y, p0[1], d[1]),
        ];
        let (mut g, mut j) = ([0.0; 2], [[0.0; 2]; 2]);
        let mut s0 = 0.0;
        while s0 < 1.0 {
            let s1 = walk[0].next_s().min(walk[1].next_s()).min(1.0);
            let len = s1 - s0;
            if len > 0.0 {
                for (node, weight) in GAUSS3 {
                    let s = s0 + node * len;
                    let h = self.height([p0[0] + s * d[0], p0[1] + s * d[1]]);
                    for a in 0..2 {
                        g[a] += weight * len * h.grad[a];
                        for (c, jac) in j[a].iter_mut().enumerate() {
                            *jac += weight * len * s * h.hess[a][c];
                        }
                    }
                }
            }
            for w in &mut walk {
                w.pass(s1);
            }
            s0 = s1;
        }
        (g, j)
    }
}

/// Three-point Gauss–Legendre on `[0, 1]`: `(node, weight)`, exact for degree 5.
const GAUSS3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// The parameters `s ∈ (0, 1)` at which the segment `a + s·d` crosses the knots `t`, in
/// increasing order, without allocation.
struct Crossings<'a> {
    t: &'a [f64],
    a: f64,
    d: f64,
    /// The next knot to cross (increasing for `d > 0`, decreasing for `d < 0`).
    next: Option<usize>,
}

impl<'a> Crossings<'a> {
    fn new(t: &'a [f64], a: f64, d: f64) -> Self {
        let next = if d > 0.0 {
            Some(t.partition_point(|&v| v <= a)).filter(|&k| k < t.len())
        } else if d < 0.0 {
            t.partition_point(|&v| v < a).checked_sub(1)
        } else {
            None
        };
        Self { t, a, d, next }
    }
    /// The next crossing's parameter (∞ when none is left).
    fn next_s(&self) -> f64 {
        self.next
            .map_or(f64::INFINITY, |k| (self.t[k] - self.a) / self.d)
    }
    /// Moves past every crossing at or before `s`.
    fn pass(&mut self, s: f64) {
        while self.next_s() <= s {
            self.next = match self.next {
                Some(k) if self.d > 0.0 => Some(k + 1).filter(|&k| k < self.t.len()),
                Some(k) => k.checked_sub(1),
                None => None,
            };
        }
    }
}

/// The weights of the 1-D scheme at a coordinate: knot `base + a` (for `a` in 0..4) gets
/// the weight `w[0][a]` in the value, `w[1][a]` in the first and `w[2][a]` in the second
/// derivative.
struct Stencil {
    base: isize,
    w: [[f64; 4]; 3],
}

impl Stencil {
    /// The weights at `s` on the knots `t` (at least two, increasing).
    fn at(t: &[f64], s: f64) -> Self {
        let n = t.len();
        let last = n - 1;
        if s < t[0] || s > t[last] {
            // The tangent at the edge: b(e) + (s − t_e) b'(e).
            let e = if s < t[0] { 0 } else { last };
            let mut st = Self {
                base: e as isize - if e == 0 { 0 } else { 3 },
                w: [[0.0; 4]; 3],
            };
            st.add(0, e, 1.0);
            for (i, c) in slope(t, e) {
                st.add(0, i, (s - t[e]) * c);
                st.add(1, i, c);
            }
            return st;
        }
        let k = t.partition_point(|&v| v <= s).clamp(1, last) - 1;
        let h = t[k + 1] - t[k];
        let u = (s - t[k]) / h;
        let (u2, u3) = (u * u, u * u * u);
        let mut st = Self {
            base: k as isize - 1,
            w: [[0.0; 4]; 3],
        };
        // Hermite basis (value, d/du, d²/du²) of f_k, m_k, f_{k+1}, m_{k+1}.
        let basis = [
            [
                2.0 * u3 - 3.0 * u2 + 1.0,
                6.0 * u2 - 6.0 * u,
                12.0 * u - 6.0,
            ],
            [u3 - 2.0 * u2 + u, 3.0 * u2 - 4.0 * u + 1.0, 6.0 * u - 4.0],
            [-2.0 * u3 + 3.0 * u2, -6.0 * u2 + 6.0 * u, -12.0 * u + 6.0],
            [u3 - u2, 3.0 * u2 - 2.0 * u, 6.0 * u - 2.0],
        ];
        let scale = [1.0, 1.0 / h, 1.0 / (h * h)];
        for (row, sc) in scale.iter().enumerate() {
            st.add(row, k, basis[0][row] * sc);
            st.add(row, k + 1, basis[2][row] * sc);
            for (i, c) in slope(t, k) {
                st.add(row, i, basis[1][row] * sc * h * c);
            }
            for (i, c) in slope(t, k + 1) {
                st.add(row, i, basis[3][row] * sc * h * c);
            }
        }
        st
    }

    fn add(&mut self, row: usize, knot: usize, c: f64) {
        let a = (knot as isize - self.base) as usize;
        self.w[row][a] += c;
    }

    /// `(slot, knot index)` of the knots that exist (`0..n`).
    fn indices(&self, n: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..4).filter_map(move |a| {
            let i = self.base + a as isize;
            (i >= 0 && (i as usize) < n).then_some((a, i as usize))
        })
    }
}

/// The slope at knot `i` as weights of the knot values: the derivative at `t_i` of the
/// parabola through `t_i` and its neighbours (the two next ones at an end), or the secant
/// with two knots.
fn slope(t: &[f64], i: usize) -> [(usize, f64); 3] {
    let n = t.len();
    if n == 2 {
        let h = t[1] - t[0];
        return [(0, -1.0 / h), (1, 1.0 / h), (1, 0.0)];
    }
    let a = i.clamp(1, n - 2) - 1;
    let (p, q, r) = (t[a], t[a + 1], t[a + 2]);
    let s = t[i];
    // Derivatives of the Lagrange basis through p, q, r at s.
    [
        (a, ((s - q) + (s - r)) / ((p - q) * (p - r))),
        (a + 1, ((s - p) + (s - r)) / ((q - p) * (q - r))),
        (a + 2, ((s - p) + (s - q)) / ((r - p) * (r - q))),
    ]
}

/// The height field as `D`-vectors: `b`, `∇b` and `∇²b` with zero vertical entries.
pub(crate) fn height_d<const D: usize>(
    bathy: &Bathymetry,
    r: &SVector<f64, D>,
) -> (f64, SVector<f64, D>, SMatrix<f64, D, D>) {
    let h = bathy.height(horizontal(r));
    let (g, m) = widen::<D>(h.grad, h.hess);
    (h.b, g, m)
}

/// The horizontal coordinates `[x, y]` of `r` (`y` = 0 in 2D).
pub(crate) fn horizontal<const D: usize>(r: &SVector<f64, D>) -> [f64; 2] {
    [r[0], if D == 3 { r[1] } else { 0.0 }]
}

/// A horizontal vector and matrix as `D`-dimensional ones (zero vertical row and column).
pub(crate) fn widen<const D: usize>(
    g: [f64; 2],
    m: [[f64; 2]; 2],
) -> (SVector<f64, D>, SMatrix<f64, D, D>) {
    let mut gv = SVector::<f64, D>::zeros();
    let mut mm = SMatrix::<f64, D, D>::zeros();
    for a in 0..D - 1 {
        gv[a] = g[a];
        for c in 0..D - 1 {
            mm[(a, c)] = m[a][c];
        }
    }
    (gv, mm)
}

#[cfg(test)]
mod tests {
    //! The interpolant against its defining properties, and the mean gradient against the
    //! difference of heights it must reproduce.

    use super::*;
    use proptest::prelude::*;

    /// A 3D grid, unevenly spaced, of a smooth seabed 100–140 m deep.
    fn grid() -> Bathymetry {
        let x: Vec<f64> = vec![-100.0, -40.0, 0.0, 25.0, 90.0, 200.0];
        let y: Vec<f64> = vec![-50.0, 0.0, 30.0, 80.0];
        let mut d = Vec::new();
        for &yj in &y {
            for &xi in &x {
                d.push(120.0 - 0.08 * xi + 10.0 * (0.02 * yj).sin() + 1e-4 * xi * yj);
            }
        }
        Bathymetry::grid(x, y, d).unwrap()
    }

    /// At the grid points the interpolant takes the given depths; a plane is reproduced
    /// everywhere, also beyond the grid (every slope rule is exact for linear data).
    #[test]
    fn interpolates_the_depths_and_reproduces_a_plane() {
        let b = grid();
        for (j, &yj) in b.y.iter().enumerate() {
            for (i, &xi) in b.x.iter().enumerate() {
                let want = b.depth[j * b.x.len() + i];
                assert!((b.depth_at(xi, yj) - want).abs() <= 1e-12 * want);
            }
        }
        let x = vec![0.0, 10.0, 35.0, 50.0];
        let y = vec![0.0, 7.0, 30.0];
        let plane = |x: f64, y: f64| 150.0 - 0.05 * x + 0.02 * y;
        let d = y
            .iter()
            .flat_map(|&yj| x.iter().map(move |&xi| plane(xi, yj)))
            .collect();
        let p = Bathymetry::grid(x, y, d).unwrap();
        for &(x, y) in &[(3.3, 2.2), (49.0, 29.0), (-40.0, 12.0), (80.0, -9.0)] {
            let h = p.height([x, y]);
            assert!((-h.b - plane(x, y)).abs() <= 1e-12 * 150.0, "({x}, {y})");
            let (e0, e1) = (h.grad[0] - 0.05, h.grad[1] + 0.02);
            assert!(e0.abs() <= 1e-13 && e1.abs() <= 1e-13, "{e0:e} {e1:e}");
            // Rounding of depths ~150 m over cells of ~10 m: ε·150/10² ≈ 2e-16 per term.
            assert!(
                h.hess.iter().flatten().all(|v| v.abs() <= 1e-13),
                "{:?}",
                h.hess
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// The gradient and the Hessian against central differences of the height, inside
        /// and outside the grid (away from grid lines, where `∇²b` jumps).
        #[test]
        fn derivatives_match_differences(x in -150.0f64..260.0, y in -90.0f64..120.0) {
            let b = grid();
            let eps = 1e-4;
            let near = |t: &[f64], v: f64| t.iter().any(|k| (k - v).abs() < 2.0 * eps);
            prop_assume!(!near(&b.x, x) && !near(&b.y, y));
            let h = b.height([x, y]);
            for a in 0..2 {
                let mut p = [x, y];
                p[a] += eps;
                let hp = b.height(p);
                p[a] -= 2.0 * eps;
                let hm = b.height(p);
                let fd = (hp.b - hm.b) / (2.0 * eps);
                prop_assert!((h.grad[a] - fd).abs() <= 1e-7, "grad {a}: {} vs {fd}", h.grad[a]);
                for c in 0..2 {
                    let fd = (hp.grad[c] - hm.grad[c]) / (2.0 * eps);
                    prop_assert!((h.hess[a][c] - fd).abs() <= 1e-7, "hess {a}{c}: {} vs {fd}", h.hess[a][c]);
                }
            }
        }

        /// C¹: across a grid line the height and the gradient are continuous.
        #[test]
        fn continuous_across_grid_lines(k in 0usize..6, y in -90.0f64..120.0) {
            let b = grid();
            let x = b.x[k];
            let (l, r) = (b.height([x - 1e-9, y]), b.height([x + 1e-9, y]));
            prop_assert!((l.b - r.b).abs() <= 1e-9);
            for a in 0..2 {
                prop_assert!((l.grad[a] - r.grad[a]).abs() <= 1e-8, "{} vs {}", l.grad[a], r.grad[a]);
            }
        }

        /// `Ḡ·Δ = b(p1) − b(p0)` to rounding over steps crossing several grid lines, and
        /// the derivative by `p1` against central differences.
        #[test]
        fn mean_gradient_is_exact(x in -150.0f64..260.0, y in -90.0f64..120.0,
                                  dx in -80.0f64..80.0, dy in -60.0f64..60.0) {
            let b = grid();
            let (p0, p1) = ([x, y], [x + dx, y + dy]);
            let (g, j) = b.mean_gradient(p0, p1);
            let (b0, b1) = (b.height(p0).b, b.height(p1).b);
            let diff = b1 - b0;
            // Both sides are differences of heights of ~150 m, each rounded to a few ulps:
            // the floor is ε (|b0| + |b1|) times a few, besides the products' own rounding.
            let scale = (g[0] * dx).abs() + (g[1] * dy).abs() + 1.0;
            let floor = 8.0 * f64::EPSILON * (b0.abs() + b1.abs());
            prop_assert!((g[0] * dx + g[1] * dy - diff).abs() <= 1e-13 * scale + floor,
                "{} vs {diff}", g[0] * dx + g[1] * dy);
            let eps = 1e-5;
            for c in 0..2 {
                let mut q = p1;
                q[c] += eps;
                let gp = b.mean_gradient(p0, q).0;
                q[c] -= 2.0 * eps;
                let gm = b.mean_gradient(p0, q).0;
                for a in 0..2 {
                    let fd = (gp[a] - gm[a]) / (2.0 * eps);
                    prop_assert!((j[a][c] - fd).abs() <= 1e-8, "J{a}{c}: {} vs {fd}", j[a][c]);
                }
            }
            // A step of zero length: the gradient at the point.
            let (g0, _) = b.mean_gradient(p0, p0);
            let h = b.height(p0);
            prop_assert!((g0[0] - h.grad[0]).abs() <= 1e-15 && (g0[1] - h.grad[1]).abs() <= 1e-15);
        }

        /// The same in 2D, for a profile.
        #[test]
        fn profile_mean_gradient_is_exact(x in -50.0f64..250.0, dx in -120.0f64..120.0) {
            let b = Bathymetry::profile(vec![0.0, 20.0, 50.0, 60.0, 200.0],
                                        vec![100.0, 101.5, 99.0, 98.0, 80.0]).unwrap();
            let (g, _) = b.mean_gradient([x, 0.0], [x + dx, 0.0]);
            let (b0, b1) = (b.height([x, 0.0]).b, b.height([x + dx, 0.0]).b);
            let diff = b1 - b0;
            // As for the grid: the difference of two heights of ~100 m is rounded to a few
            // ulps of them, a floor of ε (|b0| + |b1|) times a few.
            let floor = 8.0 * f64::EPSILON * (b0.abs() + b1.abs());
            prop_assert!((g[0] * dx - diff).abs() <= 1e-13 * ((g[0] * dx).abs() + 1.0) + floor);
            prop_assert_eq!(g[1], 0.0);
        }
    }

    /// Bad grids are refused with the value and its place.
    #[test]
    fn refuses_bad_grids() {
        let e = Bathymetry::profile(vec![0.0, 10.0, 10.0], vec![1.0; 3]).unwrap_err();
        assert!(e.to_string().contains("x coordinate [m] [2]"), "{e}");
        let e = Bathymetry::profile(vec![0.0], vec![1.0]).unwrap_err();
        assert!(e.to_string().contains("2 or more"), "{e}");
        let e = Bathymetry::profile(vec![0.0, 1.0], vec![1.0, f64::NAN]).unwrap_err();
        assert!(e.to_string().contains("depth [m] of grid point [1]"), "{e}");
        let e = Bathymetry::grid(vec![0.0, 1.0], vec![0.0, 1.0], vec![1.0; 3]).unwrap_err();
        assert!(e.to_string().contains("number of depths"), "{e}");
    }
}
