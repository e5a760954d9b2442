//! How a rigid body is drawn (configuration plot, animation, ParaView): the box of its
//! inertia at its pose, with its body frame.
//!
//! The box is the uniform box with the body's mass and principal moments: for principal
//! moments `I1, I2, I3` [kg·m²] about the principal axes and mass `m` [kg], its sides along
//! those axes are `a_i = sqrt(6 (I_j + I_k − I_i) / m)` (the inverse of
//! `I_i = m (a_j² + a_k²) / 12`). A real body's moments satisfy `I_i ≤ I_j + I_k`; moments
//! that do not (a scenario may give any positive definite tensor) have no box, and the body
//! is drawn as the cube with their mean moment `Ī` instead (side `sqrt(6 Ī / m)`,
//! [`BodyBox::cube`] set). A 2D body turns about `z` in the `x`-`y` plane: it is drawn as the
//! rectangle of sides `a_x, a_y` from the diagonal moments as given (body axes), or, when
//! those are not real (only `Izz` given), as the square with the moment `Izz` of a uniform
//! square plate (side `sqrt(6 Izz / m)`); its box is flat (`a_z = 0`).
//!
//! The body frame is drawn as three lines from the centre of mass along the body axes `x`,
//! `y`, `z`, each [`FRAME_SCALE`] times the box's longest side.
//!
//! Poses are the centre of mass `[x, y, z]` [m] and the orientation as the unit quaternion
//! `[w, x, y, z]` (body axes to space), as `bodies.csv` gives them; [`read_poses`] reads them
//! back at chosen times.

use std::io::{BufRead, BufReader};
use std::path::Path;

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// The length of each drawn body axis as a fraction of the box's longest side.
pub const FRAME_SCALE: f64 = 0.75;

/// The drawn box of one rigid body (body axes, m).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyBox {
    /// The body's name.
    pub name: String,
    /// Side lengths `[a1, a2, a3]` [m] along the columns of `axes`.
    pub sides: [f64; 3],
    /// The box's axes in body axes: column `i` is the unit direction of side `i` (the
    /// principal axes of the inertia; right-handed).
    pub axes: [[f64; 3]; 3],
    /// The moments have no box ([`crate::body_shape`]): drawn as the cube of their mean.
    pub cube: bool,
}

/// A body's pose: centre of mass [m] and orientation (unit quaternion `[w, x, y, z]`, body
/// axes to space).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    /// Centre of mass `[x, y, z]` [m] (2D: `z = 0`).
    pub position: [f64; 3],
    /// Orientation `[w, x, y, z]` (body axes to space).
    pub orientation: [f64; 4],
}

/// The 12 edges of a box as pairs of corner indices (corners as [`BodyBox::corners`]).
pub const BOX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [2, 3],
    [4, 5],
    [6, 7],
    [0, 2],
    [1, 3],
    [4, 6],
    [5, 7],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// The 6 faces of a box as corner indices in order around each face (outward normal by the
/// right-hand rule).
pub const BOX_FACES: [[usize; 4]; 6] = [
    [0, 2, 3, 1],
    [4, 5, 7, 6],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 4, 6, 2],
    [1, 3, 7, 5],
];

/// Side of the uniform cube (or square plate) of mass `m` [kg] whose moment is `moment`
/// [kg·m²] about an axis through its centre parallel to a side: `sqrt(6 I / m)` [m].
fn cube_side(moment: f64, mass: f64) -> f64 {
    (6.0 * moment / mass).sqrt()
}

/// The sides `a_i = sqrt(6 (I_j + I_k − I_i) / m)` [m] of the uniform box of mass `mass`
/// with principal moments `moments`; `None` if a side is not real (beyond rounding).
pub fn box_sides(moments: [f64; 3], mass: f64) -> Option<[f64; 3]> {
    let scale = moments.iter().map(|i| i.abs()).fold(0.0, f64::max);
    let mut sides = [0.0; 3];
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let s = moments[j] + moments[k] - moments[i];
        // NaN moments or mass fail these tests too.
        let real = s >= -1e-12 * scale && mass > 0.0;
        if !real {
            return None;
        }
        sides[i] = (6.0 * s.max(0.0) / mass).sqrt();
    }
    sides.iter().all(|a| a.is_finite()).then_some(sides)
}

/// The principal axes `vectors` (columns) with their `moments`, reordered and signed so
/// that axis `i` is the one nearest body axis `i` and points along it (a diagonal tensor
/// keeps the body axes), and right-handed.
fn aligned(vectors: &Matrix3<f64>, moments: &Vector3<f64>) -> (Matrix3<f64>, [f64; 3]) {
    let nearest = |c: usize| vectors.column(c).iamax();
    let mut order = [0, 1, 2];
    order.sort_by_key(|&c| nearest(c));
    let distinct = (0..3).all(|i| nearest(order[i]) == i);
    if !distinct {
        order = [0, 1, 2];
    }
    let mut v = Matrix3::from_fn(|r, c| vectors[(r, order[c])]);
    for c in 0..3 {
        if v[(v.column(c).iamax(), c)] < 0.0 {
            v.column_mut(c).neg_mut();
        }
    }
    if v.determinant() < 0.0 {
        v.column_mut(2).neg_mut();
    }
    (v, order.map(|c| moments[c]))
}

impl BodyBox {
    /// The box of the body `name` of mass `mass` [kg] and inertia tensor `inertia` about its
    /// centre of mass in body axes [kg·m²], in dimension `dim` (2: the rectangle in the
    /// `x`-`y` plane), as [`crate::body_shape`] describes.
    pub fn new(name: &str, mass: f64, inertia: [[f64; 3]; 3], dim: usize) -> Self {
        let j = Matrix3::from_fn(|r, c| inertia[r][c]);
        let name = name.to_string();
        if dim < 3 {
            let (ixx, iyy, izz) = (j[(0, 0)], j[(1, 1)], j[(2, 2)]);
            let planar = box_sides([ixx, iyy, izz], mass).map(|s| [s[0], s[1], 0.0]);
            let cube = planar.is_none();
            let side = cube_side(izz, mass);
            return Self {
                name,
                sides: planar.unwrap_or([side, side, 0.0]),
                axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                cube,
            };
        }
        let eig = j.symmetric_eigen();
        let (v, moments) = aligned(&eig.eigenvectors, &eig.eigenvalues);
        let axes = [0, 1, 2].map(|r| [0, 1, 2].map(|c| v[(r, c)]));
        match box_sides(moments, mass) {
            Some(sides) => Self {
                name,
                sides,
                axes,
                cube: false,
            },
            None => {
                let side = cube_side(j.trace() / 3.0, mass);
                Self {
                    name,
                    sides: [side; 3],
                    axes,
                    cube: true,
                }
            }
        }
    }

    /// The boxes of the rigid bodies of `sim`, in body order.
    pub fn of<const D: usize>(sim: &phstring::Simulation<D, phstring::Material>) -> Vec<Self> {
        let names = sim.system().bodies();
        sim.body_inertias()
            .iter()
            .zip(names)
            .map(|((mass, j), (name, _))| {
                let inertia = [0, 1, 2].map(|r| [0, 1, 2].map(|c| j[(r, c)]));
                Self::new(name, *mass, inertia, D)
            })
            .collect()
    }

    /// The rotation from the box's axes to space at `pose`.
    fn rotation(&self, pose: &BodyPose) -> Matrix3<f64> {
        let [w, x, y, z] = pose.orientation;
        let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let axes = Matrix3::from_fn(|r, c| self.axes[r][c]);
        q.to_rotation_matrix().into_inner() * axes
    }

    /// The 8 corners [m] of the box at `pose`: corner `k` is the centre plus, along box axis
    /// `i`, `+a_i/2` if bit `i` of `k` is set, else `−a_i/2`.
    pub fn corners(&self, pose: &BodyPose) -> [[f64; 3]; 8] {
        let rot = self.rotation(pose);
        let centre = Vector3::from(pose.position);
        std::array::from_fn(|k| {
            let local = Vector3::from_fn(|i, _| {
                let sign = if k >> i & 1 == 1 { 0.5 } else { -0.5 };
                sign * self.sides[i]
            });
            (centre + rot * local).into()
        })
    }

    /// The body frame at `pose`: the centre of mass and the tips of the body axes `x`, `y`,
    /// `z` [m], each [`FRAME_SCALE`] times the longest side from the centre.
    pub fn frame(&self, pose: &BodyPose) -> [[f64; 3]; 4] {
        let [w, x, y, z] = pose.orientation;
        let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        let len = FRAME_SCALE * self.sides.iter().copied().fold(0.0, f64::max);
        let centre = Vector3::from(pose.position);
        let mut out = [pose.position; 4];
        for (i, tip) in out.iter_mut().skip(1).enumerate() {
            let axis = q * Vector3::ith(i, len);
            *tip = (centre + axis).into();
        }
        out
    }
}

/// The poses of `n_bodies` bodies read back from `bodies.csv` at `path` (header
/// [`crate::files::bodies_header`]), at the record (one row per body at one time) nearest
/// each of `times` [s] (ascending), one list per time. `Err(reason)` if the file cannot be
/// read, a row is malformed, or it holds no complete record.
pub fn read_poses(
    path: &Path,
    n_bodies: usize,
    times: &[f64],
) -> Result<Vec<Vec<BodyPose>>, String> {
    let file =
        std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = BufReader::new(file).lines();
    let header = match lines.next() {
        Some(Ok(h)) => h,
        _ => return Err(format!("{} has no header", path.display())),
    };
    // The numbers after the name: 13, or 20 with the wrench columns.
    let numbers = header.split(',').count().saturating_sub(2);
    let mut out: Vec<Option<(f64, Vec<BodyPose>)>> = vec![None; times.len()];
    let mut record: (f64, Vec<BodyPose>) = (f64::NAN, Vec::with_capacity(n_bodies));
    let mut prev: Option<(f64, Vec<BodyPose>)> = None;
    let mut next = 0;
    for (i, line) in lines.enumerate() {
        let line = line.map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let at = || format!("{}:{}", path.display(), i + 2);
        let (t, pose) =
            parse_row(&line, numbers).ok_or_else(|| format!("{}: malformed row", at()))?;
        if record.1.is_empty() {
            record.0 = t;
        } else if t != record.0 {
            return Err(format!(
                "{}: t = {t} s inside the record of t = {} s",
                at(),
                record.0
            ));
        }
        record.1.push(pose);
        if record.1.len() < n_bodies {
            continue;
        }
        let done = std::mem::replace(&mut record, (f64::NAN, Vec::with_capacity(n_bodies)));
        // Every wanted time up to this record takes the nearer of it and the one before.
        while next < times.len() && times[next] <= done.0 {
            let nearer = match &prev {
                Some(p) if times[next] - p.0 < done.0 - times[next] => p.clone(),
                _ => done.clone(),
            };
            out[next] = Some(nearer);
            next += 1;
        }
        prev = Some(done);
    }
    let last = prev.ok_or_else(|| format!("{} holds no complete record", path.display()))?;
    Ok(out
        .into_iter()
        .map(|r| r.unwrap_or_else(|| last.clone()).1)
        .collect())
}

/// The time [s] and pose of one row of `bodies.csv` whose last `numbers` fields are the
/// numbers after the name (the name itself may hold commas).
fn parse_row(line: &str, numbers: usize) -> Option<(f64, BodyPose)> {
    let fields: Vec<&str> = line.trim_end().split(',').collect();
    if fields.len() < numbers + 2 || numbers < 7 {
        return None;
    }
    let t: f64 = fields[0].parse().ok()?;
    let start = fields.len() - numbers;
    let mut v = [0.0; 7];
    for (x, f) in v.iter_mut().zip(&fields[start..start + 7]) {
        *x = f.parse().ok()?;
    }
    v.iter().chain([&t]).all(|x| x.is_finite()).then_some((
        t,
        BodyPose {
            position: [v[0], v[1], v[2]],
            orientation: [v[3], v[4], v[5], v[6]],
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The corners sorted, for comparing boxes whose axes may come in any order.
    fn sorted(mut c: Vec<[f64; 3]>) -> Vec<[f64; 3]> {
        c.sort_by(|a, b| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x * 1e9).round().total_cmp(&(y * 1e9).round()))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        c
    }

    fn assert_close(a: &[[f64; 3]], b: &[[f64; 3]], tol: f64) {
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(b) {
            for k in 0..3 {
                assert!((p[k] - q[k]).abs() <= tol, "{p:?} vs {q:?}");
            }
        }
    }

    /// All 8 sign combinations of `(±h0, ±h1, ±h2)` about `c`.
    fn box_at(c: [f64; 3], h: [f64; 3]) -> Vec<[f64; 3]> {
        (0..8)
            .map(|k| std::array::from_fn(|i| c[i] + if k >> i & 1 == 1 { h[i] } else { -h[i] }))
            .collect()
    }

    /// The hook block of `examples/hook_block_3d.toml`: 600 kg with principal moments
    /// 40, 50, 26 kg·m² is the 0.6 m × 0.4 m × 0.8 m uniform box; turned 90° about z
    /// (body x to space y, body y to space −x) at (1, 2, 3) m, its corners are
    /// (1 ± 0.2, 2 ± 0.3, 3 ± 0.4) m.
    #[test]
    fn hook_block_box_has_the_hand_corners() {
        let b = BodyBox::new(
            "hook",
            600.0,
            [[40.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 26.0]],
            3,
        );
        assert!(!b.cube);
        let mut sides = b.sides;
        sides.sort_by(f64::total_cmp);
        for (a, want) in sides.iter().zip([0.4, 0.6, 0.8]) {
            assert!((a - want).abs() < 1e-14, "{sides:?}");
        }
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let pose = BodyPose {
            position: [1.0, 2.0, 3.0],
            orientation: [s, 0.0, 0.0, s],
        };
        let got = sorted(b.corners(&pose).to_vec());
        assert_close(
            &got,
            &sorted(box_at([1.0, 2.0, 3.0], [0.2, 0.3, 0.4])),
            1e-14,
        );
        // Every edge joins corners one side apart.
        let c = b.corners(&pose);
        for (e, [i, j]) in BOX_EDGES.iter().enumerate() {
            let d: f64 = (0..3)
                .map(|k| (c[*i][k] - c[*j][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!((d - b.sides[e / 4]).abs() < 1e-14, "edge {e}: {d}");
        }
        // The frame: body x along space y, body y along −x, body z along z, 0.6 m long.
        let f = b.frame(&pose);
        let want = [
            [1.0, 2.0, 3.0],
            [1.0, 2.6, 3.0],
            [0.4, 2.0, 3.0],
            [1.0, 2.0, 3.6],
        ];
        assert_close(&f, &want, 1e-14);
    }

    /// A tensor given off its principal axes: the box of diag(40, 50, 26) kg·m² turned 30°
    /// about body x has its sides along the turned axes, so at the identity pose its
    /// corners are the turned corners (±0.3, ±0.2, ±0.4) m.
    #[test]
    fn a_full_tensor_draws_the_box_along_its_principal_axes() {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let r = Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c);
        let j = r * Matrix3::from_diagonal(&Vector3::new(40.0, 50.0, 26.0)) * r.transpose();
        let inertia = [0, 1, 2].map(|i| [0, 1, 2].map(|k| j[(i, k)]));
        let b = BodyBox::new("turned", 600.0, inertia, 3);
        let pose = BodyPose {
            position: [0.0; 3],
            orientation: [1.0, 0.0, 0.0, 0.0],
        };
        let want: Vec<[f64; 3]> = box_at([0.0; 3], [0.3, 0.2, 0.4])
            .into_iter()
            .map(|p| (r * Vector3::from(p)).into())
            .collect();
        assert_close(&sorted(b.corners(&pose).to_vec()), &sorted(want), 1e-12);
    }

    /// Moments no body has (1, 1, 5 kg·m²: 5 > 1 + 1) are drawn as the cube of their mean
    /// moment 7/3 kg·m² for 1 kg, side sqrt(14) m; in 2D a body given only Izz = 150 kg·m²
    /// at 1 t is the square plate of that moment, side sqrt(6 · 150 / 1000) = 0.9487 m (flat).
    #[test]
    fn impossible_moments_fall_back_to_a_cube_and_2d_to_a_square() {
        let b = BodyBox::new(
            "odd",
            1.0,
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 5.0]],
            3,
        );
        assert!(b.cube);
        for a in b.sides {
            assert!((a - 14f64.sqrt()).abs() < 1e-14);
        }
        let p = BodyBox::new("plate", 1000.0, [[0.0; 3], [0.0; 3], [0.0, 0.0, 150.0]], 2);
        assert!(p.cube);
        assert_eq!(p.sides[2], 0.0);
        for a in &p.sides[..2] {
            assert!((a - 0.9f64.sqrt()).abs() < 1e-15, "{a}");
            // The plate's own moment: m (a² + a²) / 12 = Izz.
            assert!((1000.0 * 2.0 * a * a / 12.0 - 150.0).abs() < 1e-12);
        }
        // A 2D body with all three moments keeps its x-y rectangle (0.6 m × 0.4 m).
        let r = BodyBox::new(
            "hook",
            600.0,
            [[40.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 26.0]],
            2,
        );
        assert!(!r.cube);
        assert_close(&[r.sides], &[[0.6, 0.4, 0.0]], 1e-14);
    }

    /// The poses at chosen times are those of the nearest record, past the last record the
    /// last; names with commas and the wrench columns are read past; a malformed row is
    /// named by file and line.
    #[test]
    fn poses_are_read_back_at_the_nearest_record() {
        let dir = crate::test_util::temp_dir("body_shape", "poses");
        let path = dir.join("bodies.csv");
        let mut text = crate::files::bodies_header(true);
        text.push('\n');
        for (t, x) in [(0.0, 1.0), (0.5, 2.0), (1.0, 3.0)] {
            for (name, y) in [("hook", 10.0), ("\"beam, main\"", 20.0)] {
                text.push_str(&format!(
                    "{t},{name},{x},{y},-5,1,0,0,0,0,0,0,0,0,0,1,2,3,4,5,6,7\n"
                ));
            }
        }
        std::fs::write(&path, &text).unwrap();
        let poses = read_poses(&path, 2, &[0.1, 0.3, 0.9, 2.0]).unwrap();
        let xs: Vec<[f64; 2]> = poses
            .iter()
            .map(|p| [p[0].position[0], p[1].position[1]])
            .collect();
        assert_eq!(xs, [[1.0, 20.0], [2.0, 20.0], [3.0, 20.0], [3.0, 20.0]]);
        assert_eq!(poses[0][1].position, [1.0, 20.0, -5.0]);
        assert_eq!(poses[0][1].orientation, [1.0, 0.0, 0.0, 0.0]);
        text.push_str("1.5,hook,oops\n");
        std::fs::write(&path, &text).unwrap();
        let e = read_poses(&path, 2, &[0.1]).unwrap_err();
        assert!(e.ends_with("bodies.csv:8: malformed row"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
