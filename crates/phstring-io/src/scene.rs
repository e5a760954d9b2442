//! How a configuration is drawn in the plane (configuration plot, animation): the plane a
//! 3D run is projected on, and the water drawn behind a run in water.
//!
//! A 2D run is drawn in its own plane. A 3D run whose body force points straight down the
//! z axis (gravity, as every run in water has it) is drawn from the side: projected on the
//! vertical plane through the principal horizontal direction `u` of its nodes at `t = 0`
//! (the horizontal axis is `u · (x, y)`, the vertical one `z`, equal scales), so that its
//! catenaries show. Any other 3D run keeps the plan view (`x`, `y`).
//!
//! A spread mooring (strings radiating from a centre) is drawn one vertical plane per line
//! instead ([`LinePlanes`]): each string in the plane through its two ends, unrolled, the
//! strings side by side in strips of one width. The rule that chooses it is
//! [`LinePlanes::layout`]'s.
//!
//! In water, the nodes on the seabed at a snapshot ([`Grounded`], the core's seabed contact
//! test) are marked, and each string's grounded length at the last snapshot is written in
//! the legend.
//!
//! Rigid bodies are drawn as the boxes of their inertia with their body axes
//! ([`crate::body_shape`], [`Scene::body_outline`]), projected like the nodes; the view of
//! one plane per line leaves them out (a body lies in no single string's plane).

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::body_shape::{BOX_EDGES, BodyBox, BodyPose};

/// How a configuration is drawn: the plane of a 3D run and the water behind it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// Side view of a 3D run: the unit horizontal direction `(u_x, u_y)` of the drawing's
    /// horizontal axis, `z` up. `None`: a 2D run, or the `x`-`y` plan of a 3D run.
    pub side: Option<[f64; 2]>,
    /// One vertical plane per string (a spread mooring); when set it replaces `side`.
    pub lines: Option<LinePlanes>,
    /// The water drawn behind the configuration; `None`: dry, nothing drawn.
    pub water: Option<WaterLines>,
    /// The nodes on the seabed at each configuration snapshot, in snapshot order (empty:
    /// dry, or nothing recorded).
    pub grounded: Vec<Grounded>,
    /// The seabed contact test of the run, for frames read back from `positions.csv` (the
    /// animation); `None`: no seabed, or not known.
    pub contact: Option<ContactTest>,
    /// The rigid bodies' boxes, in body order (empty: no bodies drawn); see
    /// [`crate::body_shape`].
    pub bodies: Vec<BodyBox>,
    /// The bodies' poses at each configuration snapshot, in snapshot order (empty: not
    /// known; the animation reads its own from `bodies.csv`).
    pub body_poses: Vec<Vec<BodyPose>>,
}

/// A rigid body as drawn in the plane [m]: the box's 12 edges and the body axes `x`, `y`,
/// `z` from the centre of mass, each as its two end points.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyOutline {
    /// The box's edges.
    pub edges: [[[f64; 2]; 2]; 12],
    /// The body axes `x`, `y`, `z`.
    pub axes: [[[f64; 2]; 2]; 3],
}

/// The nodes in contact with the seabed at one configuration snapshot (penetration > 0,
/// the test of the contact energy) and the grounded length of every element group then.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Grounded {
    /// Mesh nodes on the seabed, increasing.
    pub nodes: Vec<usize>,
    /// Grounded length of each element group [m] (half an element per grounded node, as the
    /// core's `PhSystem::grounded_length`; springs 0).
    pub lengths: Vec<f64>,
}

/// The seabed contact test of a run on positions read back from a file: given every node's
/// position `[x, y, z]` [m] (unused components 0), the nodes on the seabed, increasing.
#[derive(Clone)]
pub struct ContactTest(Arc<GroundedNodes>);

/// Given every node's position `[x, y, z]` [m], the nodes on the seabed.
type GroundedNodes = dyn Fn(&[[f64; 3]]) -> Vec<usize> + Send + Sync;

impl ContactTest {
    /// The test of `system` (its `seabed_contacts`, nodes with penetration > 0); `None`
    /// without a seabed.
    pub fn of<const D: usize>(system: &phstring::PhSystem<D, phstring::Material>) -> Option<Self> {
        let n = system.mesh().n_nodes();
        let probe = vec![phstring::Vector::<D>::zeros(); n];
        if !system.has_water() || system.seabed_contacts(&probe).is_empty() {
            return None;
        }
        let system = system.clone();
        Some(Self(Arc::new(move |pts: &[[f64; 3]]| {
            let r: Vec<phstring::Vector<D>> = pts
                .iter()
                .map(|p| phstring::Vector::<D>::from_fn(|i, _| p[i.min(2)]))
                .collect();
            if r.len() != n {
                return Vec::new();
            }
            system
                .seabed_contacts(&r)
                .into_iter()
                .filter(|c| c.grounded)
                .map(|c| c.node)
                .collect()
        })))
    }

    /// The nodes on the seabed at the positions `pts` (see [`ContactTest`]).
    pub fn grounded(&self, pts: &[[f64; 3]]) -> Vec<usize> {
        (self.0)(pts)
    }
}

impl std::fmt::Debug for ContactTest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ContactTest")
    }
}

impl PartialEq for ContactTest {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The water in the drawing plane: its surface, the line at height 0 (light blue), and
/// the seabed under it.
#[derive(Debug, Clone, PartialEq)]
pub struct WaterLines {
    /// The seabed's line: a point of it and its normal pointing up into the water, both in
    /// the drawing plane [m] (a 3D seabed plane cut by the vertical plane of the side view
    /// through its point); `None` without a seabed.
    pub seabed: Option<([f64; 2], [f64; 2])>,
    /// In the view of one plane per line ([`LinePlanes`]): the seabed cut by each string's
    /// plane, `(x_start, point, normal)` in the drawing [m], valid from `x_start` to the
    /// next piece's (the first from −∞, the last to +∞). Empty otherwise.
    pub pieces: Vec<(f64, [f64; 2], [f64; 2])>,
}

impl WaterLines {
    /// The water of a run: the seabed plane through `point` with the upward `normal` (model
    /// coordinates, `d` components each) drawn in `scene`'s plane; `None` without a seabed.
    pub fn new(scene: &Scene, seabed: Option<(&[f64], &[f64])>) -> Self {
        let pieces = match (&scene.lines, seabed) {
            (Some(l), Some((p, n))) => l.seabed_pieces(p, n),
            _ => Vec::new(),
        };
        Self {
            seabed: seabed.map(|(p, n)| (scene.plane(p), scene.direction(n))),
            pieces,
        }
    }

    /// The seabed's height at abscissa `x` in the drawing plane (none without a seabed or
    /// for a vertical one).
    pub fn seabed_at(&self, x: f64) -> Option<f64> {
        height(self.line_at(x)?, x)
    }

    /// The seabed's line (point, normal) in the drawing at abscissa `x`.
    fn line_at(&self, x: f64) -> Option<([f64; 2], [f64; 2])> {
        match self.pieces.iter().rposition(|q| q.0 <= x) {
            Some(k) => Some((self.pieces[k].1, self.pieces[k].2)),
            None => match self.pieces.first() {
                Some(q) => Some((q.1, q.2)),
                None => self.seabed,
            },
        }
    }

    /// The seabed's line from `x0` to `x1` in the drawing as straight segments
    /// `[(x_a, z_a), (x_b, z_b)]` [m]: one, or one per line's piece in the view of one plane
    /// per line; none without a seabed or for a vertical one.
    pub fn seabed_segments(&self, (x0, x1): (f64, f64)) -> Vec<[(f64, f64); 2]> {
        let mut xs = vec![x0];
        xs.extend(
            self.pieces
                .iter()
                .skip(1)
                .map(|q| q.0)
                .filter(|x| *x > x0 && *x < x1),
        );
        xs.push(x1);
        xs.windows(2)
            .filter_map(|w| {
                let line = self.line_at(0.5 * (w[0] + w[1]))?;
                Some([(w[0], height(line, w[0])?), (w[1], height(line, w[1])?)])
            })
            .collect()
    }
}

/// The height at abscissa `x` of the line through `p` with the normal `n` (none for a
/// vertical line).
fn height((p, n): ([f64; 2], [f64; 2]), x: f64) -> Option<f64> {
    (n[1] > 0.0).then(|| p[1] - n[0] * (x - p[0]) / n[1])
}

impl Scene {
    /// The point of the drawing of node `node` at the model point `p` [m] (`d` components):
    /// in its string's plane in the view of one plane per line, else [`Self::plane`].
    pub fn node_point(&self, node: usize, p: &[f64]) -> [f64; 2] {
        match &self.lines {
            Some(l) => l.point(node, p),
            None => self.plane(p),
        }
    }

    /// The point of the drawing of the model point `p` [m] (`d` components).
    pub fn plane(&self, p: &[f64]) -> [f64; 2] {
        match (self.side, p) {
            (Some(u), [x, y, z, ..]) => [u[0] * x + u[1] * y, *z],
            (_, [x, y, ..]) => [*x, *y],
            (_, [x]) => [*x, 0.0],
            _ => [0.0, 0.0],
        }
    }

    /// The drawing of body `b` at `pose` in the plane ([`Self::plane`]); `None` in the view
    /// of one plane per line, where a body belongs to no string's plane and is not drawn.
    pub fn body_outline(&self, b: &BodyBox, pose: &BodyPose) -> Option<BodyOutline> {
        if self.lines.is_some() {
            return None;
        }
        let c = b.corners(pose).map(|p| self.plane(&p));
        let f = b.frame(pose).map(|p| self.plane(&p));
        Some(BodyOutline {
            edges: BOX_EDGES.map(|[i, j]| [c[i], c[j]]),
            axes: [[f[0], f[1]], [f[0], f[2]], [f[0], f[3]]],
        })
    }

    /// The direction in the drawing of the model direction `v` (not normalized).
    fn direction(&self, v: &[f64]) -> [f64; 2] {
        self.plane(v)
    }

    /// The axis descriptions of the drawing: `x [m]`, `y [m]`, or in a side view the
    /// horizontal direction and `z [m]`.
    pub fn axis_labels(&self) -> (String, String) {
        if let Some(l) = &self.lines {
            return (
                format!(
                    "distance from each line's fairlead [m]; line k from k × {} m",
                    l.width
                ),
                "z [m]".into(),
            );
        }
        match self.side {
            None => ("x [m]".into(), "y [m]".into()),
            Some([ux, uy]) if uy == 0.0 && ux > 0.0 => ("x [m]".into(), "z [m]".into()),
            Some([ux, uy]) if ux == 0.0 && uy > 0.0 => ("y [m]".into(), "z [m]".into()),
            Some([ux, uy]) => (
                format!("horizontal along ({ux:.3}, {uy:.3}) [m]"),
                "z [m]".into(),
            ),
        }
    }
}

/// Strings are drawn one vertical plane per line when the horizontal axes of two of them
/// (their end-to-end directions, as undirected lines) differ by more than this angle [°].
pub const LINE_PLANES_ANGLE_DEG: f64 = 10.0;

/// One string's vertical plane in the view of one plane per line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinePlane {
    /// Horizontal position `(x, y)` of the string's fairlead end [m]: the end that was
    /// higher when the view was chosen (the last node of its path on a tie).
    pub fairlead: [f64; 2],
    /// Unit horizontal direction from the fairlead towards the other (anchor) end.
    pub azimuth: [f64; 2],
    /// Abscissa of the fairlead in the drawing [m].
    pub offset: f64,
}

/// The view of one vertical plane per line of a spread mooring: string `k` is drawn in the
/// vertical plane through its two ends, unrolled; a node at `(x, y, z)` is drawn at
/// `(offset_k + s, z)`, `s = ((x, y) − fairlead_k) · azimuth_k` its horizontal distance
/// from the fairlead along the line's azimuth. Strip `k` starts at `k · width`; its fairlead
/// at `k · width` (later if the line reaches behind its fairlead), so that the lines, in
/// the order of the strings, stand side by side and never overlap.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinePlanes {
    /// The plane of each string, in string order.
    pub lines: Vec<LinePlane>,
    /// Width of one line's strip [m]: a round number at least 1.1 times the longest
    /// horizontal extent of a line when the view was chosen.
    pub width: f64,
    /// The string of each mesh node (an index into `lines`).
    pub node_line: Vec<usize>,
}

impl LinePlanes {
    /// The view of one plane per line of strings through the node paths `strings` (each in
    /// path order, its ends first and last) of a mesh of `n_nodes` nodes at positions `r`
    /// [m], or `None` when one plane for the whole network is right. The rule: at least two
    /// strings, no other elements (`springs` false), no node shared by two strings or left
    /// out of all (so that each node has one plane), and two strings whose end-to-end
    /// horizontal axes differ by more than [`LINE_PLANES_ANGLE_DEG`]. A string whose ends
    /// are above one another takes the principal horizontal direction of its nodes.
    pub fn layout(strings: &[Vec<usize>], springs: bool, r: &[[f64; 3]]) -> Option<Self> {
        if strings.len() < 2 || springs {
            return None;
        }
        let mut node_line = vec![usize::MAX; r.len()];
        for (k, path) in strings.iter().enumerate() {
            for &i in path {
                match node_line.get_mut(i) {
                    Some(slot) if *slot == usize::MAX || *slot == k => *slot = k,
                    _ => return None,
                }
            }
        }
        if node_line.contains(&usize::MAX) {
            return None;
        }
        let axes: Vec<([f64; 2], [f64; 2])> = strings
            .iter()
            .map(|path| line_axis(path, r))
            .collect::<Option<_>>()?;
        let cos_max = LINE_PLANES_ANGLE_DEG.to_radians().cos();
        let spread = axes.iter().enumerate().any(|(i, a)| {
            axes[i + 1..]
                .iter()
                .any(|b| (a.1[0] * b.1[0] + a.1[1] * b.1[1]).abs() < cos_max)
        });
        if !spread {
            return None;
        }
        // Each line's extent along its azimuth, then strips of one round width.
        let extents: Vec<(f64, f64)> = strings
            .iter()
            .zip(&axes)
            .map(|(path, (f, a))| {
                path.iter().fold((0.0f64, 0.0f64), |(lo, hi), &i| {
                    let s = (r[i][0] - f[0]) * a[0] + (r[i][1] - f[1]) * a[1];
                    (lo.min(s), hi.max(s))
                })
            })
            .collect();
        let longest = extents.iter().fold(0.0f64, |m, (lo, hi)| m.max(hi - lo));
        let width = round_up(1.1 * longest);
        if !(width.is_finite() && width > 0.0) {
            return None;
        }
        let lines = axes
            .iter()
            .zip(&extents)
            .enumerate()
            .map(|(k, ((f, a), (lo, _)))| LinePlane {
                fairlead: *f,
                azimuth: *a,
                offset: k as f64 * width - lo,
            })
            .collect();
        Some(Self {
            lines,
            width,
            node_line,
        })
    }

    /// The point of the drawing of node `node` at the model point `p` [m] (see
    /// [`LinePlanes`]); a node outside the mesh, or a point with fewer than three
    /// components, is drawn in the first line's plane.
    pub fn point(&self, node: usize, p: &[f64]) -> [f64; 2] {
        let k = self.node_line.get(node).copied().unwrap_or(0);
        let Some(l) = self.lines.get(k).or(self.lines.first()) else {
            return [0.0, 0.0];
        };
        match p {
            [x, y, z, ..] => [
                l.offset + (x - l.fairlead[0]) * l.azimuth[0] + (y - l.fairlead[1]) * l.azimuth[1],
                *z,
            ],
            _ => [l.offset, 0.0],
        }
    }

    /// The seabed plane through `p` with the upward normal `n` (3 components each) cut by
    /// each line's plane: pieces of [`WaterLines::pieces`], line `k`'s from `k · width`.
    fn seabed_pieces(&self, p: &[f64], n: &[f64]) -> Vec<(f64, [f64; 2], [f64; 2])> {
        let ([px, py, pz, ..], [nx, ny, nz, ..]) = (p, n) else {
            return Vec::new();
        };
        self.lines
            .iter()
            .enumerate()
            .map(|(k, l)| {
                let (f, a) = (l.fairlead, l.azimuth);
                // Height of the plane under the fairlead, and its normal in (s, z).
                let z0 = if *nz != 0.0 {
                    pz - (nx * (f[0] - px) + ny * (f[1] - py)) / nz
                } else {
                    *pz
                };
                let ns = nx * a[0] + ny * a[1];
                (k as f64 * self.width, [l.offset, z0], [ns, *nz])
            })
            .collect()
    }
}

/// The fairlead end `(x, y)` [m] and the unit horizontal direction towards the other end of
/// the string through the node path `path` at positions `r`; `None` for an empty path or
/// a non-finite position.
fn line_axis(path: &[usize], r: &[[f64; 3]]) -> Option<([f64; 2], [f64; 2])> {
    let (first, last) = (r.get(*path.first()?)?, r.get(*path.last()?)?);
    let (top, bottom) = if first[2] > last[2] {
        (first, last)
    } else {
        (last, first)
    };
    let (dx, dy) = (bottom[0] - top[0], bottom[1] - top[1]);
    let d = dx.hypot(dy);
    if !d.is_finite() || !top.iter().all(|x| x.is_finite()) {
        return None;
    }
    let scale = top.iter().chain(bottom).fold(1.0f64, |m, x| m.max(x.abs()));
    let azimuth = if d > 1e-9 * scale {
        [dx / d, dy / d]
    } else {
        principal_horizontal(path.iter().filter_map(|&i| r.get(i).copied()))
    };
    Some(([top[0], top[1]], azimuth))
}

/// The smallest of `1, 2, 2.5, 5 × 10^k` [m] at least `x` (for `x > 0`).
fn round_up(x: f64) -> f64 {
    if !(x > 0.0 && x.is_finite()) {
        return f64::NAN;
    }
    let decade = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|v| *v >= x * (1.0 - 1e-12))
        .unwrap_or(10.0 * decade)
}

/// The principal horizontal direction `(u_x, u_y)` (unit, `u_x ≥ 0`) of the 3D points
/// `points` [m]: the eigenvector of the largest eigenvalue of the covariance of their
/// `(x, y)`. When the two eigenvalues agree to 1e-6 of their sum (a symmetric spread, a
/// vertical line, no points), the `x` axis `(1, 0)`.
pub fn principal_horizontal(points: impl Iterator<Item = [f64; 3]> + Clone) -> [f64; 2] {
    let n = points.clone().count() as f64;
    if n == 0.0 {
        return [1.0, 0.0];
    }
    let (mx, my) = points
        .clone()
        .fold((0.0, 0.0), |(a, b), p| (a + p[0] / n, b + p[1] / n));
    let (a, b, c) = points.fold((0.0, 0.0, 0.0), |(a, b, c), p| {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        (a + dx * dx, b + dx * dy, c + dy * dy)
    });
    let spread = ((a - c) * (a - c) + 4.0 * b * b).sqrt();
    if spread.is_nan() || spread <= 1e-6 * (a + c) {
        return [1.0, 0.0];
    }
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    let u = [theta.cos(), theta.sin()];
    if u[0] < 0.0 || (u[0] == 0.0 && u[1] < 0.0) {
        [-u[0], -u[1]]
    } else {
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_principal_direction_is_that_of_the_line() {
        // A line along (3, 4)/5 with some scatter across it.
        let pts: Vec<[f64; 3]> = (0..11)
            .map(|k| {
                let s = f64::from(k) * 10.0;
                let off = if k % 2 == 0 { 0.5 } else { -0.5 };
                [0.6 * s - 0.8 * off, 0.8 * s + 0.6 * off, -s]
            })
            .collect();
        let u = principal_horizontal(pts.iter().copied());
        assert!(
            (u[0] - 0.6).abs() < 1e-12 && (u[1] - 0.8).abs() < 1e-12,
            "{u:?}"
        );
        // Pointing the other way: the same axis, x component ≥ 0.
        let back = principal_horizontal(pts.iter().map(|p| [-p[0], -p[1], p[2]]));
        assert!((back[0] - 0.6).abs() < 1e-12 && (back[1] - 0.8).abs() < 1e-12);
        // Three lines 120° apart: no principal direction, the x axis.
        let spread = (0..3).flat_map(|k| {
            let a = f64::from(k) * 2.0 * std::f64::consts::PI / 3.0;
            (0..5).map(move |j| {
                let r = 100.0 * f64::from(j);
                [r * a.cos(), r * a.sin(), 0.0]
            })
        });
        assert_eq!(principal_horizontal(spread), [1.0, 0.0]);
        let scene = Scene {
            side: Some(u),
            ..Scene::default()
        };
        assert_eq!(scene.plane(&[3.0, 4.0, -7.0]), [5.0, -7.0]);
        assert_eq!(scene.axis_labels().1, "z [m]");
        // A seabed sloping up along x by 1 in 10, seen along x: z = −60 + 0.1 (x − 10).
        let side_x = Scene {
            side: Some([1.0, 0.0]),
            ..Scene::default()
        };
        let n = [-0.1, 0.0, 1.0];
        let w = WaterLines::new(&side_x, Some((&[10.0, 5.0, -60.0], &n)));
        assert!((w.seabed_at(110.0).unwrap() + 50.0).abs() < 1e-12);
    }

    /// Three straight lines from fairleads 5.2 m from the centre, 70 m down, to anchors
    /// 853.87 m out on a seabed 320 m down, 120° apart (the spar's spread), `n` nodes each
    /// from the anchor up.
    fn spread(n: usize) -> (Vec<Vec<usize>>, Vec<[f64; 3]>) {
        let (mut strings, mut r) = (Vec::new(), Vec::new());
        for k in 0..3 {
            let a = f64::from(k) * 2.0 * std::f64::consts::PI / 3.0;
            let (c, s) = (a.cos(), a.sin());
            let mut path = Vec::new();
            for j in 0..n {
                let f = j as f64 / (n - 1) as f64;
                let rad = 853.87 + f * (5.2 - 853.87);
                path.push(r.len());
                r.push([rad * c, rad * s, -320.0 + f * 250.0]);
            }
            strings.push(path);
        }
        (strings, r)
    }

    #[test]
    fn each_line_of_a_spread_is_drawn_in_its_own_plane_side_by_side() {
        let (strings, r) = spread(21);
        let view = LinePlanes::layout(&strings, false, &r).expect("a spread");
        // 1.1 × 848.67 m rounds up to strips of 1000 m.
        assert_eq!(view.width, 1000.0);
        let mut ranges = Vec::new();
        for (k, path) in strings.iter().enumerate() {
            let (anchor, fairlead) = (r[path[0]], r[*path.last().unwrap()]);
            let pa = view.point(path[0], &anchor);
            let pf = view.point(*path.last().unwrap(), &fairlead);
            // The fairlead at the strip's start, the anchor at their horizontal distance.
            let d = (anchor[0] - fairlead[0]).hypot(anchor[1] - fairlead[1]);
            assert!((pf[0] - 1000.0 * k as f64).abs() < 1e-9, "{pf:?}");
            assert!((pa[0] - pf[0] - d).abs() < 1e-9 * d, "{pa:?} {pf:?} {d}");
            assert!((d - 848.67).abs() < 1e-9);
            assert_eq!((pa[1], pf[1]), (anchor[2], fairlead[2]));
            let xs: Vec<f64> = path.iter().map(|&i| view.point(i, &r[i])[0]).collect();
            ranges.push(
                xs.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                        (a.min(*x), b.max(*x))
                    }),
            );
        }
        // The lines never overlap: each ends at least 10 % of a strip before the next.
        for w in ranges.windows(2) {
            assert!(w[0].1 + 100.0 < w[1].0, "{ranges:?}");
        }
        // A seabed 320 m down under every line; one sloping up along +x by 1 in 100 cut by
        // line 0's plane (azimuth +x) rises 1 m per 100 m away from its fairlead, by
        // line 1's (azimuth 120° from +x) half that.
        let flat = WaterLines::new(
            &Scene {
                lines: Some(view.clone()),
                ..Scene::default()
            },
            Some((&[0.0, 0.0, -320.0], &[0.0, 0.0, 1.0])),
        );
        for x in [-50.0, 400.0, 1500.0, 2999.0] {
            assert_eq!(flat.seabed_at(x), Some(-320.0));
        }
        let len = 1.0f64.hypot(0.01);
        let n = [-0.01 / len, 0.0, 1.0 / len];
        let slope = WaterLines::new(
            &Scene {
                lines: Some(view.clone()),
                ..Scene::default()
            },
            Some((&[0.0, 0.0, -320.0], &n)),
        );
        let z0 = slope.seabed_at(0.0).unwrap();
        assert!((z0 - (-320.0 + 0.01 * 5.2)).abs() < 1e-9);
        assert!((slope.seabed_at(100.0).unwrap() - z0 - 1.0).abs() < 1e-9);
        let z1 = slope.seabed_at(1000.0).unwrap();
        assert!((slope.seabed_at(1100.0).unwrap() - z1 + 0.5).abs() < 1e-9);
        let segments = slope.seabed_segments((-100.0, 2900.0));
        assert_eq!(segments.len(), 3);
        assert_eq!((segments[1][0].0, segments[2][1].0), (1000.0, 2900.0));
    }

    #[test]
    fn one_plane_is_kept_where_it_is_right() {
        let (strings, r) = spread(5);
        // Springs, a shared node, a node in no string, one string: one plane.
        assert!(LinePlanes::layout(&strings, true, &r).is_none());
        let mut shared = strings.clone();
        shared[1][0] = shared[0][0];
        assert!(LinePlanes::layout(&shared, false, &r).is_none());
        assert!(LinePlanes::layout(&strings[..2], false, &r[..10]).is_some());
        assert!(LinePlanes::layout(&strings[..1], false, &r[..5]).is_none());
        // Two lines in one vertical plane, on either side of the centre (axes 0° apart),
        // and two 8° apart: one plane; 12° apart: a plane each.
        let turned = |deg: f64| {
            let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
            let mut r2: Vec<[f64; 3]> = r[..5].to_vec();
            r2.extend(
                r[..5]
                    .iter()
                    .map(|p| [p[0] * c - p[1] * s, p[0] * s + p[1] * c, p[2]]),
            );
            LinePlanes::layout(&[strings[0].clone(), (5..10).collect()], false, &r2)
        };
        assert!(turned(180.0).is_none());
        assert!(turned(8.0).is_none());
        assert!(turned(12.0).is_some());
    }
}
