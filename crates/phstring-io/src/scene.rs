//! How a configuration is drawn in the plane (configuration plot, animation): the plane a
//! 3D run is projected on, and the water drawn behind a run in water.
//!
//! A 2D run is drawn in its own plane. A 3D run whose body force points straight down the
//! z axis (gravity, as every run in water has it) is drawn from the side: projected on the
//! vertical plane through the principal horizontal direction `u` of its nodes at `t = 0`
//! (the horizontal axis is `u · (x, y)`, the vertical one `z`, equal scales), so that its
//! catenaries show. Any other 3D run keeps the plan view (`x`, `y`).

/// How a configuration is drawn: the plane of a 3D run and the water behind it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// Side view of a 3D run: the unit horizontal direction `(u_x, u_y)` of the drawing's
    /// horizontal axis, `z` up. `None`: a 2D run, or the `x`-`y` plan of a 3D run.
    pub side: Option<[f64; 2]>,
    /// The water drawn behind the configuration; `None`: dry, nothing drawn.
    pub water: Option<WaterLines>,
}

/// The water in the drawing plane: its surface, the line at height 0 (light blue), and
/// the seabed under it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterLines {
    /// The seabed's line: a point of it and its normal pointing up into the water, both in
    /// the drawing plane [m] (a 3D seabed plane cut by the vertical plane of the side view
    /// through its point); `None` without a seabed.
    pub seabed: Option<([f64; 2], [f64; 2])>,
}

impl WaterLines {
    /// The water of a run: the seabed plane through `point` with the upward `normal` (model
    /// coordinates, `d` components each) drawn in `scene`'s plane; `None` without a seabed.
    pub fn new(scene: &Scene, seabed: Option<(&[f64], &[f64])>) -> Self {
        Self {
            seabed: seabed.map(|(p, n)| (scene.plane(p), scene.direction(n))),
        }
    }

    /// The seabed's height at abscissa `x` in the drawing plane (none without a seabed or
    /// for a vertical one).
    pub fn seabed_at(&self, x: f64) -> Option<f64> {
        let (p, n) = self.seabed?;
        (n[1] > 0.0).then(|| p[1] - n[0] * (x - p[0]) / n[1])
    }
}

impl Scene {
    /// The point of the drawing of the model point `p` [m] (`d` components).
    pub fn plane(&self, p: &[f64]) -> [f64; 2] {
        match (self.side, p) {
            (Some(u), [x, y, z, ..]) => [u[0] * x + u[1] * y, *z],
            (_, [x, y, ..]) => [*x, *y],
            (_, [x]) => [*x, 0.0],
            _ => [0.0, 0.0],
        }
    }

    /// The direction in the drawing of the model direction `v` (not normalized).
    fn direction(&self, v: &[f64]) -> [f64; 2] {
        self.plane(v)
    }

    /// The axis descriptions of the drawing: `x [m]`, `y [m]`, or in a side view the
    /// horizontal direction and `z [m]`.
    pub fn axis_labels(&self) -> (String, String) {
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
            water: None,
        };
        assert_eq!(scene.plane(&[3.0, 4.0, -7.0]), [5.0, -7.0]);
        assert_eq!(scene.axis_labels().1, "z [m]");
        // A seabed sloping up along x by 1 in 10, seen along x: z = −60 + 0.1 (x − 10).
        let side_x = Scene {
            side: Some([1.0, 0.0]),
            water: None,
        };
        let n = [-0.1, 0.0, 1.0];
        let w = WaterLines::new(&side_x, Some((&[10.0, 5.0, -60.0], &n)));
        assert!((w.seabed_at(110.0).unwrap() + 50.0).abs() < 1e-12);
    }
}
