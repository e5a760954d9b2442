//! The initial shape of a deck's line: a deck gives only the two ends and the unstretched
//! length, so the mapping lays the line out itself, stress-free, and lets the static
//! equilibrium (`[initial] equilibrium = true`) find the real shape.

/// A point [m] (x, y, z; z up).
pub(super) type P3 = [f64; 3];

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: P3, b: P3) -> P3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: P3, s: f64) -> P3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn norm(a: P3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The initial nodes of a line and the stretch they start at.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Shape {
    /// The `segments + 1` node positions [m], from end A to end B.
    pub nodes: Vec<P3>,
    /// The stretch `|Δr|/l` of every segment (1: stress-free; above 1 for a line shorter
    /// than the distance between its ends, below 1 for a one-segment slack line).
    pub stretch: f64,
}

/// Lays out a line of unstretched length `length` [m] and `segments` equal segments from
/// `a` to `b`. A line at least as long as the distance between its ends (slack) gets
/// segments of exactly `length/segments` (stress-free): along the horizontal from its
/// lower end towards the other end, as far as whole segments fit, then a circular arc of
/// equal chords up to the other end (sagging where that stays above the lower end, else
/// arched), like a chain lying on the seabed and rising to its fairlead. A shorter line
/// (taut) is straight with equal segments stretched by `distance/length`; so is a slack
/// line of one segment (then the stretch is below 1).
pub(super) fn lay_out(a: P3, b: P3, length: f64, segments: u32) -> Shape {
    let n = segments as usize;
    let d = norm(sub(b, a));
    let straight = |stretch: f64| Shape {
        nodes: (0..=n)
            .map(|i| add(a, scale(sub(b, a), i as f64 / n as f64)))
            .collect(),
        stretch,
    };
    if length <= d || n < 2 {
        return straight(d / length);
    }
    // Build from the lower end, then reverse if that is end B.
    let (p, q) = if a[2] <= b[2] { (a, b) } else { (b, a) };
    let c = length / n as f64;
    let horiz = [q[0] - p[0], q[1] - p[1], 0.0];
    let x = norm(horiz);
    let u = if x > 1e-12 * length {
        scale(horiz, 1.0 / x)
    } else {
        [1.0, 0.0, 0.0]
    };
    // The L-shape (along the horizontal, then straight up) of length `length` runs a* on
    // the horizontal; whole segments up to a*, and at least two left for the arc.
    let a_star = (length * length - d * d) / (2.0 * (length - x));
    let k = ((a_star / c).floor().max(0.0) as usize).min(n - 2);
    let mut nodes: Vec<P3> = (0..=k).map(|j| add(p, scale(u, j as f64 * c))).collect();
    let t = nodes[k];
    nodes.extend(arc(t, q, n - k, c, u).into_iter().skip(1));
    if a[2] > b[2] {
        nodes.reverse();
    }
    // The ends exactly where they are (the arc reaches them to rounding).
    nodes[0] = a;
    nodes[n] = b;
    Shape {
        nodes,
        stretch: 1.0,
    }
}

/// `m + 1` points from `t` to `q` with `m` chords of length `c` (`m c ≥ |q − t|`, `m ≥ 2`)
/// on a circular arc in the vertical plane through `t` and `q` (`u`: the horizontal
/// direction of that plane when `q − t` is vertical). The arc sags below the chord unless
/// that takes it below the lower of `t` and `q`; then it arches above.
fn arc(t: P3, q: P3, m: usize, c: f64, u: P3) -> Vec<P3> {
    let w = sub(q, t);
    let d = norm(w);
    let mf = m as f64;
    if d >= mf * c * (1.0 - 1e-12) {
        return (0..=m).map(|j| add(t, scale(w, j as f64 / mf))).collect();
    }
    // sin(mθ/2)/sin(θ/2) falls from m at θ → 0 to 0 at θ = 2π/m: bisect for d/c.
    let ratio = |th: f64| (mf * th / 2.0).sin() / (th / 2.0).sin();
    let (mut lo, mut hi) = (0.0_f64, 2.0 * std::f64::consts::PI / mf);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid > 0.0 && ratio(mid) > d / c {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let th = 0.5 * (lo + hi);
    let r = c / (2.0 * (th / 2.0).sin());
    let phi = mf * th;
    let e = if d > 0.0 { scale(w, 1.0 / d) } else { u };
    // The unit normal to the chord in the vertical plane, pointing up (or along u).
    let up = [0.0, 0.0, 1.0];
    let along = e[2];
    let nv = sub(up, scale(e, along));
    let n_up = if norm(nv) > 1e-9 {
        scale(nv, 1.0 / norm(nv))
    } else {
        u
    };
    let mid = add(t, scale(w, 0.5));
    let points = |s: f64| -> Vec<P3> {
        let bulge = scale(n_up, s);
        let centre = sub(mid, scale(bulge, r * (phi / 2.0).cos()));
        (0..=m)
            .map(|j| {
                let a = -phi / 2.0 + j as f64 * th;
                add(
                    centre,
                    add(scale(bulge, r * a.cos()), scale(e, r * a.sin())),
                )
            })
            .collect()
    };
    let sag = points(-1.0);
    let floor = t[2].min(q[2]);
    if sag.iter().all(|p| p[2] >= floor - 1e-9 * c) {
        sag
    } else {
        points(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chords(s: &Shape) -> Vec<f64> {
        s.nodes.windows(2).map(|w| norm(sub(w[1], w[0]))).collect()
    }

    /// Slack lines of every kind get equal chords of exactly length/segments, end where
    /// asked, and stay above their lower end.
    #[test]
    fn slack_lines_are_laid_out_stress_free_between_their_ends() {
        let cases: [(P3, P3, f64, u32); 5] = [
            ([420.0, 0.0, -50.0], [40.0, 0.0, -8.0], 400.0, 40),
            ([853.87, 0.0, -320.0], [5.2, 0.0, -70.0], 902.2, 20),
            ([5.2, 0.0, -70.0], [853.87, 0.0, -320.0], 902.2, 20),
            ([0.0, 0.0, -100.0], [0.0, 0.0, -10.0], 150.0, 15),
            ([0.0, 0.0, -50.0], [30.0, 40.0, -50.0], 80.0, 8),
        ];
        for (a, b, l, n) in cases {
            let s = lay_out(a, b, l, n);
            assert_eq!(s.nodes.len(), n as usize + 1);
            assert_eq!(s.stretch, 1.0);
            assert_eq!((s.nodes[0], s.nodes[n as usize]), (a, b));
            for c in chords(&s) {
                assert!(
                    (c - l / n as f64).abs() <= 1e-9 * l,
                    "{a:?} {b:?}: chord {c}"
                );
            }
            let floor = a[2].min(b[2]);
            assert!(s.nodes.iter().all(|p| p[2] >= floor - 1e-9 * l));
        }
    }

    /// A line shorter than the distance between its ends starts straight and stretched.
    #[test]
    fn taut_lines_start_straight_and_stretched() {
        let s = lay_out([0.0, 0.0, -100.0], [60.0, 0.0, -20.0], 99.0, 10);
        assert!((s.stretch - 100.0 / 99.0).abs() <= 1e-15);
        for c in chords(&s) {
            assert!((c - 10.0).abs() <= 1e-12);
        }
    }
}
