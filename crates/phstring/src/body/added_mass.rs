//! A rigid body's full added-mass matrix (docs/method.md §22, "A full added-mass matrix"):
//! its checks, the body's total 6×6 mass matrix in body axes, and the step's inertia rows in
//! the Kirchhoff form, whose kinetic energy `½ ξ·𝕄ξ` depends on the orientation through the
//! body-axes velocity `ξ = (Rᵀ V, Ω)`.

use super::{BodyState, Mat3, Turn, Vec3, skew};

/// A 6×6 matrix of a rigid body in body axes about its centre of mass, rows and columns in
/// the order (translation x, y, z, rotation about x, y, z): its blocks are in kg
/// (translation–translation), kg·m (translation–rotation) and kg·m² (rotation–rotation).
pub type Mat6 = nalgebra::Matrix6<f64>;

/// The indices of the plane motion `(x, y, θ_z)` in a [`Mat6`].
pub(crate) const PLANE: [usize; 3] = [0, 1, 5];

/// Checks an added-mass matrix `a` (square, 6×6 in 3D or the 3×3 `(x, y, θ)` of 2D): every
/// entry finite, symmetric within 1e-9 of its largest entry, positive semi-definite (no
/// eigenvalue of its symmetric part below −1e-12 of its largest entry). The message names
/// the bad entry by row and column, counted from 1.
pub fn check_added_mass(a: &nalgebra::DMatrix<f64>) -> Result<(), String> {
    let n = a.nrows();
    if n != a.ncols() || !(n == 3 || n == 6) {
        return Err(format!(
            "added mass must be a 6×6 matrix (3×3 in 2D), got {}×{}",
            a.nrows(),
            a.ncols()
        ));
    }
    for ((r, c), v) in (0..n)
        .flat_map(|c| (0..n).map(move |r| (r, c)))
        .zip(a.iter())
    {
        if !v.is_finite() {
            return Err(format!(
                "added mass entry (row {}, column {}) is not finite: {v}",
                r + 1,
                c + 1
            ));
        }
    }
    let scale = a.amax();
    for r in 0..n {
        for c in r + 1..n {
            let (x, y) = (a[(r, c)], a[(c, r)]);
            if (x - y).abs() > 1e-9 * scale {
                return Err(format!(
                    "added mass is not symmetric: entry (row {}, column {}) = {x} but (row {}, \
                     column {}) = {y}",
                    r + 1,
                    c + 1,
                    c + 1,
                    r + 1
                ));
            }
        }
    }
    let sym = (a + a.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    let (k, low) =
        eig.eigenvalues
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |m, (k, l)| if l < m.1 { (k, l) } else { m },
            );
    if low < -1e-12 * scale {
        let dir: Vec<String> = eig
            .eigenvectors
            .column(k)
            .iter()
            .map(|x| format!("{x:.3}"))
            .collect();
        return Err(format!(
            "added mass is not positive semi-definite: eigenvalue {low:e} along ({})",
            dir.join(", ")
        ));
    }
    Ok(())
}

/// The blocks `[[tt, tr], [rt, rr]]` of a 6×6 matrix.
pub(crate) fn blocks(m: &Mat6) -> [[Mat3; 2]; 2] {
    let b = |r: usize, c: usize| -> Mat3 { m.fixed_view::<3, 3>(3 * r, 3 * c).into_owned() };
    [[b(0, 0), b(0, 1)], [b(1, 0), b(1, 1)]]
}

/// An added-mass matrix `a_o` given about a body point `O` [kg, kg·m, kg·m²] (body axes,
/// ordered as [`Mat6`]) moved to the centre of mass `C`, which lies at `c` [m] from `O` in
/// body axes (MoorDyn's `CG`): `A_C = Tᵀ A_O T` with `T = [[I, ĉ], [0, I]]`, the map of the
/// body-axes velocities about `C` onto those about `O` (`u_O = u_C + Ω × (O − C) =
/// u_C + ĉ Ω`, `Ω` unchanged), so that the kinetic energy `½ ξ·A ξ` is the same. Returned
/// exactly symmetric (the mean of the product and its transpose).
pub fn added_mass_about_centre(a_o: &Mat6, c: &Vec3) -> Mat6 {
    let mut t = Mat6::identity();
    t.fixed_view_mut::<3, 3>(0, 3).copy_from(&skew(c));
    let a = t.transpose() * a_o * t;
    (a + a.transpose()) * 0.5
}

/// How a body's added-mass matrix `a` (symmetrized) enters the step of a `D`-dimensional
/// network, with the body's mass `m` [kg] and inertia `j` [kg·m²] (body axes): the added mass
/// on its translation [kg], its added inertia [kg·m²] (body axes; in 2D its `z` moment), and
/// `None` when the translation block is isotropic (`a_t I`) and uncoupled from the rotation,
/// which then adds `a_t` to the mass and the rotation block to the inertia as `C_a` and the
/// added inertia do; otherwise the body's total mass matrix `𝕄 = diag(m I, J) + A` (in 2D the
/// plane's `(x, y, θ)` entries of `a`, with `z` and the turns about `x`, `y` kept uncoupled),
/// with the mean of the translational diagonal and the rotation block as the first two (the
/// body's scales).
pub(crate) fn total<const D: usize>(a: &Mat6, m: f64, j: &Mat3) -> (f64, Mat3, Option<Mat6>) {
    let a = (a + a.transpose()) * 0.5;
    let mut mm = Mat6::zeros();
    if D == 2 {
        let [x, y, t] = PLANE;
        let za = Mat3::from_diagonal(&Vec3::new(0.0, 0.0, a[(t, t)]));
        if a[(x, x)] == a[(y, y)] && a[(x, y)] == 0.0 && a[(x, t)] == 0.0 && a[(y, t)] == 0.0 {
            return (a[(x, x)], za, None);
        }
        let jz = j[(2, 2)] + a[(t, t)];
        for k in 0..3 {
            mm[(k, k)] = m;
            mm[(3 + k, 3 + k)] = jz;
        }
        for (r, &ar) in [x, y].iter().enumerate() {
            for (c, &ac) in [x, y].iter().enumerate() {
                mm[(r, c)] += a[(ar, ac)];
            }
            mm[(r, 5)] = a[(ar, t)];
            mm[(5, r)] = a[(ar, t)];
        }
        return (0.5 * (a[(x, x)] + a[(y, y)]), za, Some(mm));
    }
    let [[tt, tr], [_, rr]] = blocks(&a);
    let iso = tt[(0, 0)];
    if tt == Mat3::identity() * iso && tr == Mat3::zeros() {
        return (iso, rr, None);
    }
    mm.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Mat3::identity() * m));
    mm.fixed_view_mut::<3, 3>(3, 3).copy_from(j);
    (tt.trace() / 3.0, rr, Some(mm + a))
}

/// The body-axes velocities `ξ = (Rᵀ V, Ω)` [m/s, rad/s] of state `st`.
pub(crate) fn body_velocity(st: &BodyState) -> (Vec3, Vec3) {
    (turned(&st.orientation.inverse(), &st.velocity), st.omega)
}

/// `v` [any unit] turned by `q`, with its length kept exactly: a quaternion renormalized to
/// round-off turns with a scale `1 ± ε` whose rounding is not balanced, and the velocity is
/// turned into body axes and back at every step.
fn turned(q: &nalgebra::UnitQuaternion<f64>, v: &Vec3) -> Vec3 {
    let t = q.transform_vector(v);
    let n = t.norm();
    if n > 0.0 { t * (v.norm() / n) } else { t }
}

/// The body-axes momenta `(P, Π) = 𝕄 ξ` [kg·m/s, kg·m²/s] of state `st` with the total mass
/// matrix `mm`.
pub(crate) fn momenta(mm: &Mat6, st: &BodyState) -> (Vec3, Vec3) {
    let (u, om) = body_velocity(st);
    let [[tt, tr], [rt, rr]] = blocks(mm);
    (tt * u + tr * om, rt * u + rr * om)
}

/// The translation part `ν = (I − ŵ/2) R_nᵀ Δx` [m] of the step's increment in the Lie
/// algebra of the body's motions: the Cayley map of `(ν, w)` is the step's motion
/// `(R_nᵀ Δx, cay(w))` in the body axes of `R_n`.
pub(crate) fn nu(turn: &Turn, dx: &Vec3, w: &Vec3) -> Vec3 {
    let c = turn.rot.transpose() * dx;
    c - w.cross(&c) * 0.5
}

/// The velocity after a step of `h` [s] from `st` with increment `dx` [m] and Cayley vector
/// `w`: `u_{n+1} = 2ν/h − u_n` in the new body axes, returned in space axes
/// `V_{n+1} = R_{n+1} u_{n+1}` (`next` = `R_{n+1}`, turned as [`body_velocity`] turns back).
pub(crate) fn next_velocity(
    st: &BodyState,
    h: f64,
    (turn, next): (&Turn, &nalgebra::UnitQuaternion<f64>),
    dx: &Vec3,
    w: &Vec3,
) -> Vec3 {
    let u0 = body_velocity(st).0;
    turned(next, &(nu(turn, dx, w) * (2.0 / h) - u0))
}

/// The inertia part of a body's step rows in the Kirchhoff form, with total mass matrix
/// `mm`, for a step of `h` [s] from `st` with increment `dx` [m], Cayley vector `w` and its
/// turn `turn` (docs/method.md eq. (22.9)): the force row's
/// `R_n (cay(w) P_{n+1} − P_n)/h` [N] (space axes), the torque row's
/// `(I − ŵ/2) [cay(w) Π_{n+1} − Π_n + ½ c × (cay(w) P_{n+1} + P_n)]/h` [N·m] (body axes of
/// `R_n`, `c = R_nᵀ Δx`), and their Jacobian `[[∂f/∂Δx, ∂f/∂w], [∂t/∂Δx, ∂t/∂w]]`.
pub(crate) fn inertia_rows(
    mm: &Mat6,
    st: &BodyState,
    h: f64,
    (dx, w): (&Vec3, &Vec3),
    turn: &Turn,
) -> (Vec3, Vec3, [[Mat3; 2]; 2]) {
    let inv_h = 1.0 / h;
    let k = 2.0 * inv_h;
    let rt = turn.rot.transpose();
    let c = rt * dx;
    let half = Mat3::identity() - skew(w) * 0.5;
    let (u0, om0) = body_velocity(st);
    let u1 = half * c * k - u0;
    let om1 = w * k - om0;
    let [[tt, tr], [rt_, rr]] = blocks(mm);
    let (p0, pi0) = (tt * u0 + tr * om0, rt_ * u0 + rr * om0);
    let (p1, pi1) = (tt * u1 + tr * om1, rt_ * u1 + rr * om1);
    let (qp1, qpi1) = (turn.cay * p1, turn.cay * pi1);
    let force = turn.rot * (qp1 - p0) * inv_h;
    let y = (qpi1 - pi0 + c.cross(&(qp1 + p0)) * 0.5) * inv_h;
    let torque = half * y;
    // ∂ν/∂Δx = (I − ŵ/2) R_nᵀ, ∂ν/∂w = ½ [c×]; ∂(cay(w) v)/∂w = −(I − ŵ/2)⁻¹ [v̄×],
    // v̄ = ½ (v + cay(w) v).
    let (dnu_dx, dnu_dw) = (half * rt, skew(&c) * 0.5);
    let dq = |v: &Vec3| -(turn.inv_half * skew(&((v + turn.cay * v) * 0.5)));
    let dqp1 = [
        turn.cay * tt * dnu_dx * k,
        turn.cay * (tt * dnu_dw + tr) * k + dq(&p1),
    ];
    let dqpi1 = [
        turn.cay * rt_ * dnu_dx * k,
        turn.cay * (rt_ * dnu_dw + rr) * k + dq(&pi1),
    ];
    let sc = skew(&c) * 0.5;
    let dy_dx = (dqpi1[0] + sc * dqp1[0] - skew(&(qp1 + p0)) * 0.5 * rt) * inv_h;
    let dy_dw = (dqpi1[1] + sc * dqp1[1]) * inv_h;
    let jac = [
        [turn.rot * dqp1[0] * inv_h, turn.rot * dqp1[1] * inv_h],
        [half * dy_dx, half * dy_dw + skew(&y) * 0.5],
    ];
    (force, torque, jac)
}

#[cfg(test)]
mod tests {
    //! The Kirchhoff step of a free body with a full added-mass matrix: its rows against
    //! finite differences, the exact energy and momenta over 1e4 steps, uniform acceleration
    //! along a body axis, and the Munk moment of a body moving across its axes.

    use super::super::tests::{
        assert_rows_jacobian, box_body, jacobian_loads, spinning, step_free,
    };
    use super::super::{BodyModel, UnitQuaternion};
    use super::*;
    use nalgebra::SVector;

    /// A 20 t body (inertia 4e5, 4e5, 5e4 kg·m²) with a spar-like added mass: unequal
    /// translational entries and surge–pitch, sway–roll couplings (kg·m).
    fn spar() -> BodyModel {
        let mut a =
            Mat6::from_diagonal(&nalgebra::Vector6::new(1.5e4, 2.5e4, 2e3, 3e5, 2.5e5, 1e4));
        for (r, c, v) in [(0, 4, -6e4), (1, 3, 5e4)] {
            a[(r, c)] = v;
            a[(c, r)] = v;
        }
        diagonal_body(a)
    }

    /// A 20 t body (inertia 4e5, 4e5, 5e4 kg·m²) with added mass `a`, no weight.
    fn diagonal_body(a: Mat6) -> BodyModel {
        let j = Mat3::from_diagonal(&Vec3::new(4e5, 4e5, 5e4));
        let m = 2e4;
        let mm = total::<3>(&a, m, &j).2.expect("coupled or anisotropic");
        BodyModel {
            mass: mm.fixed_view::<3, 3>(0, 0).trace() / 3.0,
            inertia: blocks(&mm)[1][1],
            weight: Vec3::zeros(),
            dry_mass: m,
            dry_inertia: j,
            kirchhoff: Some(mm),
            ..box_body()
        }
    }

    fn space_momenta(body: &BodyModel, st: &BodyState) -> (Vec3, Vec3) {
        let p = body.linear_momentum(st);
        let l = st.position.cross(&p) + st.orientation.transform_vector(&body.momentum(st));
        (p, l)
    }

    #[test]
    fn matrix_checks_name_the_bad_entry() {
        let good = nalgebra::DMatrix::from_fn(6, 6, |r, c| spar().kirchhoff.unwrap()[(r, c)]);
        assert_eq!(check_added_mass(&good), Ok(()));
        let mut skew = good.clone();
        skew[(0, 4)] += 1.0;
        let e = check_added_mass(&skew).unwrap_err();
        assert!(e.contains("row 1, column 5"), "{e}");
        let mut indefinite = nalgebra::DMatrix::<f64>::identity(3, 3) * 1e3;
        indefinite[(0, 2)] = 2e3;
        indefinite[(2, 0)] = 2e3;
        let e = check_added_mass(&indefinite).unwrap_err();
        assert!(e.contains("not positive semi-definite"), "{e}");
        let e = check_added_mass(&nalgebra::DMatrix::zeros(6, 5)).unwrap_err();
        assert!(e.contains("6×5"), "{e}");
    }

    /// Moving a translational added mass from a reference point to the centre of mass:
    /// MoorDyn's `ρ_w V Ca_i` (400 m³, Ca 0.8|0.6|0.4) about a point 0.5, −0.3, 1.0 m from
    /// the centre gives the blocks `[[a, a ĉ], [ĉᵀ a, ĉᵀ a ĉ]]`, entry by entry as worked by
    /// hand; and the kinetic energy of any motion is the same about either point, with the
    /// reference point's velocity from the rigid-body formula `u_O = u_C + Ω × (O − C)`.
    #[test]
    fn added_mass_moves_to_the_centre_of_mass_with_its_lever() {
        let (a1, a2, a3) = (
            1025.0 * 400.0 * 0.8,
            1025.0 * 400.0 * 0.6,
            1025.0 * 400.0 * 0.4,
        );
        let a_o = Mat6::from_diagonal(&nalgebra::Vector6::new(a1, a2, a3, 0.0, 0.0, 0.0));
        let c = Vec3::new(0.5, -0.3, 1.0);
        let a = added_mass_about_centre(&a_o, &c);
        let tol = 1e-12 * a1;
        #[rustfmt::skip]
        let hand = Mat6::from_row_slice(&[
            a1, 0.0, 0.0, 0.0, -a1, -0.3 * a1,
            0.0, a2, 0.0, a2, 0.0, -0.5 * a2,
            0.0, 0.0, a3, 0.3 * a3, 0.5 * a3, 0.0,
            0.0, a2, 0.3 * a3, a2 + 0.09 * a3, 0.15 * a3, -0.5 * a2,
            -a1, 0.0, 0.5 * a3, 0.15 * a3, a1 + 0.25 * a3, 0.3 * a1,
            -0.3 * a1, -0.5 * a2, 0.0, -0.5 * a2, 0.3 * a1, 0.09 * a1 + 0.25 * a2,
        ]);
        assert!((a - hand).amax() < tol, "{a}\n{hand}");
        assert_eq!(a, a.transpose());
        let dm = nalgebra::DMatrix::from_fn(6, 6, |r, k| a[(r, k)]);
        assert_eq!(check_added_mass(&dm), Ok(()));
        for (u, om) in [
            (Vec3::new(0.3, -1.2, 0.7), Vec3::new(0.05, 0.2, -0.1)),
            (Vec3::zeros(), Vec3::new(0.0, 0.0, 1.0)),
            (Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.4, 0.0)),
        ] {
            let xi = SVector::<f64, 6>::new(u.x, u.y, u.z, om.x, om.y, om.z);
            let u_o = u + om.cross(&(-c));
            let xi_o = SVector::<f64, 6>::new(u_o.x, u_o.y, u_o.z, om.x, om.y, om.z);
            let (t_c, t_o) = (0.5 * xi.dot(&(a * xi)), 0.5 * xi_o.dot(&(a_o * xi_o)));
            assert!((t_c - t_o).abs() < 1e-12 * t_o, "{t_c} vs {t_o} J");
        }
        // Without an offset nothing moves.
        assert_eq!(added_mass_about_centre(&a_o, &Vec3::zeros()), a_o);
    }

    /// An isotropic translational block without coupling folds into the mass and inertia
    /// (the `C_a` path), in 3D and in the plane.
    #[test]
    fn isotropic_matrix_is_the_scalar_added_mass() {
        let j = Mat3::from_diagonal(&Vec3::new(4e5, 4e5, 5e4));
        let mut a = Mat6::from_diagonal(&nalgebra::Vector6::new(7e3, 7e3, 7e3, 1e5, 2e5, 3e4));
        a[(3, 4)] = 1e4;
        a[(4, 3)] = 1e4;
        let (at, ar, none) = total::<3>(&a, 2e4, &j);
        assert_eq!((at, ar, none), (7e3, blocks(&a)[1][1], None));
        a[(2, 2)] = 6e3;
        assert!(total::<3>(&a, 2e4, &j).2.is_some());
        // In 2D only (x, y, θ) counts: z differs, still isotropic in the plane.
        let (at, ar, none) = total::<2>(&a, 2e4, &j);
        assert_eq!((at, ar[(2, 2)], none), (7e3, 3e4, None));
    }

    /// The rows with attachments and a torque, and the Kirchhoff inertia's couplings, against
    /// central differences (the same tolerance as the body without added mass).
    #[test]
    fn kirchhoff_jacobian_matches_finite_differences() {
        let body = BodyModel {
            weight: Vec3::new(0.0, 0.0, -2e5),
            ..spar()
        };
        let st = spinning(Vec3::new(0.4, -1.3, 0.8));
        let (springs, torque) =
            jacobian_loads([Vec3::new(1.0, 0.5, -0.25), Vec3::new(-1.0, -0.5, 3.0)]);
        let u = SVector::<f64, 6>::from_column_slice(&[0.04, -0.02, 0.01, 0.05, -0.08, 0.03]);
        assert_rows_jacobian(&body, &st, 0.01, &u, (&springs, &torque));
    }

    /// A free body with the spar's coupled added mass, tumbling and drifting, over 1e4 steps
    /// of 10 ms: the energy `½ ξ·𝕄ξ` and the Kirchhoff impulses in space axes (linear
    /// `R P`, angular `x × R P + R Π`) stay constant to round-off (measured: energy 1.6e-13,
    /// `p` 5.5e-13, `L` 1.1e-12 relative).
    #[test]
    fn free_kirchhoff_body_keeps_energy_and_momenta() {
        let body = spar();
        let mut st = BodyState::new(
            Vec3::new(3.0, -2.0, -40.0),
            Vec3::new(1.2, -0.4, 0.3),
            UnitQuaternion::from_euler_angles(0.2, -0.4, 0.9),
            Vec3::new(0.05, 0.2, -0.1),
        );
        let e0 = body.kinetic(&st);
        let (p0, l0) = space_momenta(&body, &st);
        let (mut de, mut dp, mut dl) = (0.0f64, 0.0f64, 0.0f64);
        let n = 10_000;
        for _ in 0..n {
            st = step_free(&body, &st, 0.01);
            let (p, l) = space_momenta(&body, &st);
            de = de.max((body.kinetic(&st) - e0).abs() / e0);
            dp = dp.max((p - p0).norm() / p0.norm());
            dl = dl.max((l - l0).norm() / l0.norm());
        }
        eprintln!("free Kirchhoff body, {n} steps: energy {de:e}, p {dp:e}, L {dl:e}");
        // Round-off: at most one ulp of drift per step on average.
        let ulp_per_step = n as f64 * f64::EPSILON;
        assert!(de < ulp_per_step, "energy drift {de}");
        assert!(dp < ulp_per_step, "linear momentum drift {dp}");
        assert!(dl < ulp_per_step, "angular momentum drift {dl}");
    }

    /// A diagonal added mass and a constant force along body axis 1, from rest, turned: the
    /// body does not turn and accelerates uniformly at `F/(m + A₁₁)` (the midpoint rule
    /// integrates a constant acceleration exactly: to round-off). Axis 1 has the largest
    /// added mass: along an axis of smaller added mass the Munk moment makes the straight
    /// motion unstable, and round-off grows into a turn.
    #[test]
    fn force_along_a_body_axis_accelerates_with_its_added_mass() {
        let a = Mat6::from_diagonal(&nalgebra::Vector6::new(4e4, 1.5e4, 2e3, 3e5, 2.5e5, 1e4));
        let q = UnitQuaternion::from_euler_angles(0.3, -0.5, 1.2);
        let f = 5e4;
        let axis = q.transform_vector(&Vec3::x());
        let body = BodyModel {
            weight: axis * f,
            ..diagonal_body(a)
        };
        let mut st = BodyState::at_rest(Vec3::zeros(), q);
        let (h, n) = (0.02, 500);
        for _ in 0..n {
            st = step_free(&body, &st, h);
        }
        let t = h * n as f64;
        let acc = f / (2e4 + 4e4);
        let x = axis * (0.5 * acc * t * t);
        let err = (st.position - x).norm() / x.norm();
        assert!(err < 1e-12, "position {} vs {x}: {err:e}", st.position);
        assert!((st.velocity - axis * (acc * t)).norm() < 1e-12 * acc * t);
        // Round-off only: the turn's rate times the radius of gyration (4.5 m) against the
        // speed (measured 6e-15 rad/s against 8.3 m/s).
        assert!(
            st.omega.norm() * 4.5 < 1e-12 * acc * t,
            "turned: {}",
            st.omega
        );
    }

    /// The Munk moment: a body with `A₁₁ ≠ A₂₂` moving at `u = (u₁, u₂, 0)` (body axes),
    /// not turning, feels the moment `(A₁₁ − A₂₂) u₁ u₂` about axis 3, so its initial
    /// angular acceleration is that over `J₃₃ + A₆₆`. `u̇(0) = 0` (no turn, so `Ṗ = −Ω × P = 0`),
    /// so `Ω₃(h)/h` is the initial rate to O(h²) (measured 2.2e-7 at h = 1 ms; 1e-6
    /// asserted).
    #[test]
    fn munk_moment_turns_a_body_moving_across_its_axes() {
        let a = Mat6::from_diagonal(&nalgebra::Vector6::new(1.5e4, 6e4, 2e3, 3e5, 2.5e5, 1e4));
        let body = diagonal_body(a);
        let q = UnitQuaternion::from_euler_angles(0.1, 0.2, -0.3);
        let (u1, u2) = (2.0, 0.5);
        let v = q.transform_vector(&Vec3::new(u1, u2, 0.0));
        let st = BodyState::new(Vec3::zeros(), v, q, Vec3::zeros());
        let h = 1e-3;
        let next = step_free(&body, &st, h);
        let exact = (1.5e4 - 6e4) * u1 * u2 / (5e4 + 1e4);
        let rate = next.omega.z / h;
        let err = (rate / exact - 1.0).abs();
        eprintln!("Munk: initial angular acceleration {rate} vs {exact} rad/s², {err:e}");
        assert!(err < 1e-6, "rate {rate} vs {exact}");
        assert!(next.omega.x.abs() + next.omega.y.abs() < 1e-12 * exact.abs() * h);
    }
}
