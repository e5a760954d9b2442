//! The elastic catenary (docs/method.md §15 "Catenary first guess", §21 eq. (21.8)): the
//! shape and end forces of a uniform, linearly elastic line under its weight, between two
//! points, or from an anchor on a rigid frictionless seabed with a grounded length.
//!
//! Coordinates are in the vertical plane of the line's ends: `x` horizontal [m] from the
//! lower end (the anchor) towards the upper one, `z` up [m]. The line has unstretched length
//! `L` [m], weight `w` per unstretched metre [N/m] (in water: its wet weight) and axial
//! stiffness `EA` [N]; its tension has the constant horizontal component `H` [N] and the
//! vertical component `V(s) = V_A + w s` at the unstretched arc length `s` [m] of the
//! suspended part (`V_A` at its lower end, positive when the line rises from there).
//! With `a = V_A/H` and `b = V(s)/H`, a suspended part starting at `(x₀, z₀)` runs through
//!
//! ```text
//!   x(s) = x₀ + H s/EA + (H/w) (asinh b − asinh a) ,
//!   z(s) = z₀ + (V_A s + w s²/2)/EA + (H/w) (√(1 + b²) − √(1 + a²)) .
//! ```
//!
//! On the seabed the grounded length `L_b` lies straight, stretched by `H/EA`, and the
//! suspended part starts there with `V_A = 0`.

/// A uniform linearly elastic line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Unstretched length `L` [m], > 0.
    pub length: f64,
    /// Weight per unstretched length `w` [N/m] (in water the wet weight), > 0.
    pub weight: f64,
    /// Axial stiffness `EA` [N], > 0.
    pub ea: f64,
}

/// A solved elastic catenary of a [`Line`]: its end forces and grounded length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Catenary {
    /// The line.
    pub line: Line,
    /// Horizontal tension `H` [N].
    pub h: f64,
    /// Vertical tension `V_A` [N] where the suspended part starts (at the touchdown point, 0,
    /// when part of the line is grounded), positive when the line rises from there.
    pub v_a: f64,
    /// Grounded length `L_b` [m] (unstretched), 0 for a line between two points.
    pub grounded: f64,
}

impl Catenary {
    /// The catenary from an anchor on a rigid frictionless seabed to a fairlead `x` [m] away
    /// and `hv` [m] above the seabed, with a grounded length (eq. (21.8)). `None` when the
    /// line has no such shape: it lifts the anchor (then [`Catenary::between`] applies), or
    /// it is longer than the path along the seabed and straight up.
    pub fn on_seabed(line: Line, x: f64, hv: f64) -> Option<Self> {
        let Line {
            length: l,
            weight: w,
            ea,
        } = line;
        let (h, v_f, grounded) = on_seabed(l, w, ea, x, hv);
        let ls = l - grounded;
        // The bisections return their bracket's end where (21.8) has no root: check it.
        let span = grounded + (h / w) * (v_f / h).asinh() + h * l / ea - x;
        let height =
            (h / w) * ((1.0 + (v_f / h).powi(2)).sqrt() - 1.0) + w * ls * ls / (2.0 * ea) - hv;
        let fits = span.abs() <= SHAPE_RTOL * (x + hv) && height.abs() <= SHAPE_RTOL * (x + hv);
        (fits && grounded > 0.0 && ls > 0.0 && h.is_finite()).then_some(Self {
            line,
            h,
            v_a: 0.0,
            grounded,
        })
    }

    /// The catenary between its lower end at the origin and the point `(x, z)` [m], `x > 0`:
    /// Newton's method on `(H, V_A)` from the inextensible estimate of Peyrot and Goulois.
    /// `None` if it does not converge.
    pub fn between(line: Line, x: f64, z: f64) -> Option<Self> {
        let Line {
            length: l,
            weight: w,
            ..
        } = line;
        if !(x > 0.0 && l > 0.0 && w > 0.0 && line.ea > 0.0) {
            return None;
        }
        let chord2 = x * x + z * z;
        let lambda = if l * l > chord2 {
            (3.0 * ((l * l - z * z) / (x * x) - 1.0)).sqrt()
        } else {
            0.2
        };
        let mut h = w * x / (2.0 * lambda);
        let mut v = 0.5 * w * (z / lambda.tanh() - l);
        let scale = x + z.abs() + l;
        let misfit = |h: f64, v: f64| {
            let c = Self {
                line,
                h,
                v_a: v,
                grounded: 0.0,
            };
            let (px, pz) = c.point(l);
            (px - x, pz - z)
        };
        let (mut fx, mut fz) = misfit(h, v);
        for _ in 0..MAX_NEWTON {
            if fx.hypot(fz) <= SHAPE_RTOL * scale {
                let c = Self {
                    line,
                    h,
                    v_a: v,
                    grounded: 0.0,
                };
                return c.h.is_finite().then_some(c);
            }
            let [[xh, xv], [zh, zv]] = end_jacobian(line, h, v);
            let det = xh * zv - xv * zh;
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let dh = -(zv * fx - xv * fz) / det;
            let dv = -(-zh * fx + xh * fz) / det;
            // Damped: H stays positive, the misfit decreases.
            let mut t = if dh < -0.9 * h { -0.9 * h / dh } else { 1.0 };
            let norm = fx.hypot(fz);
            loop {
                let (gx, gz) = misfit(h + t * dh, v + t * dv);
                if gx.hypot(gz) < norm || t < 1e-6 {
                    (h, v, fx, fz) = (h + t * dh, v + t * dv, gx, gz);
                    break;
                }
                t *= 0.5;
            }
        }
        None
    }

    /// The point `(x, z)` [m] of the line at unstretched arc length `s` [m] from its lower end
    /// (the anchor), relative to that end.
    pub fn point(&self, s: f64) -> (f64, f64) {
        let Line { weight: w, ea, .. } = self.line;
        let (h, lb) = (self.h, self.grounded);
        if s <= lb {
            return (s * (1.0 + h / ea), 0.0);
        }
        let sigma = s - lb;
        let (a, b) = (self.v_a / h, (self.v_a + w * sigma) / h);
        let x = lb * (1.0 + h / ea) + h * sigma / ea + (h / w) * (b.asinh() - a.asinh());
        let z = (self.v_a * sigma + 0.5 * w * sigma * sigma) / ea
            + (h / w) * ((1.0 + b * b).sqrt() - (1.0 + a * a).sqrt());
        (x, z)
    }
}

/// A chain of straight, linearly elastic elements under weights at its interior nodes: the
/// discrete counterpart of the catenary (docs/method.md §15). Element `e` (from node `e` to
/// node `e + 1`, numbered from the lower end) carries the constant horizontal tension `H`
/// [N] and the vertical tension `V_e = c + Σ_{i=1}^{e} W_i` [N], `c` the first element's,
/// and lies along its tension `(H, V_e)` with the length `l_e (1 + T_e/EA)`,
/// `T_e = √(H² + V_e²)`: each interior node is in equilibrium under the two elements'
/// tensions and its weight `W_i`. On a seabed (`grounded`) the seabed carries the weight of
/// the nodes where the line lies, `V_e = max(0, ·)`, so the elements up to the touchdown
/// lie flat.
#[derive(Debug, Clone, Copy)]
pub struct Chain<'a> {
    /// Unstretched element lengths `l_e` [m] from the lower end.
    pub lengths: &'a [f64],
    /// Weights `W_i` [N] of the interior nodes `1 … n − 1` (in water, less their buoyancy).
    pub weights: &'a [f64],
    /// Axial stiffness `EA` [N].
    pub ea: f64,
    /// The lower end lies on a seabed that carries the line where it touches it.
    pub grounded: bool,
}

impl Chain<'_> {
    /// `V_e` [N] of each element for the first element's `c` [N], and whether `c` moves it.
    fn verticals(&self, c: f64) -> impl Iterator<Item = (f64, bool)> + '_ {
        let mut acc = c;
        (0..self.lengths.len()).map(move |e| {
            if e > 0 {
                acc += self.weights[e - 1];
            }
            if self.grounded && acc < 0.0 {
                (0.0, false)
            } else {
                (acc, true)
            }
        })
    }

    /// The upper end `(x, z)` [m] relative to the lower one for `(H, c)`, and its derivatives
    /// `[[∂x/∂H, ∂x/∂c], [∂z/∂H, ∂z/∂c]]`.
    fn end(&self, h: f64, c: f64) -> ((f64, f64), [[f64; 2]; 2]) {
        let (mut x, mut z) = (0.0, 0.0);
        let mut j = [[0.0; 2]; 2];
        for ((v, moves), &l) in self.verticals(c).zip(self.lengths) {
            let t = h.hypot(v);
            let f = l * (1.0 / t + 1.0 / self.ea);
            let g = l / (t * t * t);
            x += f * h;
            z += f * v;
            j[0][0] += f - g * h * h;
            j[1][0] -= g * h * v;
            if moves {
                j[0][1] -= g * h * v;
                j[1][1] += f - g * v * v;
            }
        }
        ((x, z), j)
    }

    /// The forces `(H, c)` [N] that put the upper end at `(x, z)` [m] from the lower one, by
    /// damped Newton from `(h0, c0)` (e.g. the continuous catenary's); `None` if it does
    /// not converge.
    pub fn solve(&self, x: f64, z: f64, h0: f64, c0: f64) -> Option<(f64, f64)> {
        let (mut h, mut c) = (h0, c0);
        let scale = x.abs() + z.abs();
        let misfit = |h: f64, c: f64| {
            let ((ex, ez), j) = self.end(h, c);
            ((ex - x, ez - z), j)
        };
        let ((mut fx, mut fz), mut j) = misfit(h, c);
        for _ in 0..MAX_NEWTON {
            let norm = fx.hypot(fz);
            if norm <= CHAIN_RTOL * scale {
                return (h > 0.0 && h.is_finite() && c.is_finite()).then_some((h, c));
            }
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let dh = -(j[1][1] * fx - j[0][1] * fz) / det;
            let dc = -(-j[1][0] * fx + j[0][0] * fz) / det;
            let mut t = if dh < -0.9 * h { -0.9 * h / dh } else { 1.0 };
            loop {
                let ((gx, gz), jt) = misfit(h + t * dh, c + t * dc);
                if gx.hypot(gz) < norm || t < 1e-8 {
                    (h, c, fx, fz, j) = (h + t * dh, c + t * dc, gx, gz, jt);
                    break;
                }
                t *= 0.5;
            }
        }
        None
    }

    /// The nodes' positions `(x, z)` [m] relative to the lower end for `(H, c)`, from the
    /// lower end (node 0, at the origin) to the upper one.
    pub fn points(&self, h: f64, c: f64) -> Vec<(f64, f64)> {
        let mut p = vec![(0.0, 0.0)];
        for ((v, _), &l) in self.verticals(c).zip(self.lengths) {
            let f = l * (1.0 / h.hypot(v) + 1.0 / self.ea);
            let (x, z) = p[p.len() - 1];
            p.push((x + f * h, z + f * v));
        }
        p
    }
}

/// Relative misfit of the upper end (to the span plus height) at which a chain is solved.
const CHAIN_RTOL: f64 = 1e-12;

/// The derivatives `[[∂x/∂H, ∂x/∂V_A], [∂z/∂H, ∂z/∂V_A]]` of the upper end of a line without
/// grounded part.
fn end_jacobian(line: Line, h: f64, v: f64) -> [[f64; 2]; 2] {
    let Line {
        length: l,
        weight: w,
        ea,
    } = line;
    let (a, b) = (v / h, (v + w * l) / h);
    let (ra, rb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    let xh = l / ea + (b.asinh() - a.asinh() - b / rb + a / ra) / w;
    let xv = (1.0 / rb - 1.0 / ra) / w;
    let zv = l / ea + (b / rb - a / ra) / w;
    [[xh, xv], [xv, zv]]
}

/// Relative misfit of the end point (to the span plus height) at which a shape is taken.
const SHAPE_RTOL: f64 = 1e-9;
/// Most Newton iterations of [`Catenary::between`].
const MAX_NEWTON: usize = 100;

/// The elastic catenary of a line of unstretched length `L`, wet weight `w` [N/m] and axial
/// stiffness `EA` from an anchor on a rigid frictionless seabed to a fairlead `X` away and
/// `Hv` above the seabed, with a grounded length `L_b` (docs/method.md eq. (21.8)): with
/// `L_s = L − L_b` suspended, `V_F = w L_s`,
///
///   X  = L_b + (H/w) asinh(V_F/H) + H L/EA ,
///   Hv = (H/w) (√(1 + (V_F/H)²) − 1) + w L_s²/(2 EA) ,
///
/// solved by bisection in `H` (1 N to 1e9 N) around a bisection in `L_s`. Returns
/// `(H, V_F, L_b)`. Where the equations have no root (a line that lifts its anchor, or one
/// longer than the path along the seabed and straight up), the result is a bracket's end:
/// [`Catenary::on_seabed`] checks it.
pub fn on_seabed(l: f64, w: f64, ea: f64, x: f64, hv: f64) -> (f64, f64, f64) {
    let bisect = |f: &dyn Fn(f64) -> f64, mut lo: f64, mut hi: f64| {
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) < 0.0 { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    };
    let suspended = |h: f64| {
        let height = |ls: f64| {
            let v = w * ls;
            (h / w) * ((1.0 + (v / h).powi(2)).sqrt() - 1.0) + w * ls * ls / (2.0 * ea) - hv
        };
        bisect(&height, 0.0, l)
    };
    let span = |h: f64| {
        let ls = suspended(h);
        l - ls + (h / w) * (w * ls / h).asinh() + h * l / ea - x
    };
    let h = bisect(&span, 1.0, 1e9);
    let ls = suspended(h);
    (h, w * ls, l - ls)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 400 m of chain (wet weight 3410 N/m, EA = 1.674e9 N) from an anchor at 50 m depth to
    /// a fairlead 390 m away and 42 m up: the shape's end is the fairlead, the tension at
    /// the top is `(H, w L_s)`, and the between-points form with the same length and the
    /// anchor lifted reproduces a taut shape's own end.
    #[test]
    fn shapes_end_at_their_end_points() {
        let line = Line {
            length: 400.0,
            weight: 3410.0,
            ea: 1.674e9,
        };
        let c = Catenary::on_seabed(line, 390.0, 42.0).unwrap();
        let (x, z) = c.point(line.length);
        assert!(
            (x - 390.0).abs() <= 1e-6 && (z - 42.0).abs() <= 1e-6,
            "{x} {z}"
        );
        assert!(c.grounded > 100.0 && c.grounded < 300.0, "{}", c.grounded);
        // A taut line: 300 m of it between points 280 m and 100 m apart (chord 297.3 m).
        let taut = Catenary::between(
            Line {
                length: 300.0,
                ..line
            },
            280.0,
            100.0,
        )
        .unwrap();
        let (x, z) = taut.point(300.0);
        assert!(
            (x - 280.0).abs() <= 1e-6 && (z - 100.0).abs() <= 1e-6,
            "{x} {z}"
        );
        assert!(taut.v_a > 0.0, "lifts its lower end: V_A = {}", taut.v_a);
        // Slack between points at equal height: symmetric, V_A = −w L/2.
        let sag = Catenary::between(line, 300.0, 0.0).unwrap();
        let half = 0.5 * line.weight * line.length;
        assert!((sag.v_a + half).abs() <= 1e-9 * half, "{}", sag.v_a);
        // A line too long to lie along the seabed and go straight up has no such shape.
        assert!(Catenary::on_seabed(line, 300.0, 42.0).is_none());
    }
}
