//! Rigid bodies in the step (docs/method.md §22): momentum maps and the energy balance of
//! bodies joined by strings, a body hanging on a string.

use nalgebra::{UnitQuaternion, Vector3};
use phstring::{
    Attachment, BodyState, BodyWrench, Boundary, MassMatrix, Material, Network, NetworkBuilder,
    NewtonParams, RigidBody, Scheme, Simulation, SolverKind, StepParams, StringSpec, Vector,
};

/// A steel box of 2 t (2 m × 1 m × 0.5 m) in body axes.
fn box_inertia(mass: f64) -> nalgebra::Matrix3<f64> {
    let (a, b, c) = (2.0f64, 1.0f64, 0.5f64);
    nalgebra::Matrix3::from_diagonal(&Vector3::new(
        mass * (b * b + c * c) / 12.0,
        mass * (a * a + c * c) / 12.0,
        mass * (a * a + b * b) / 12.0,
    ))
}

/// A 20 mm wire rope (EA = 2e7 N, 1.6 kg/m), no gravity, 10 elements per string.
fn rope<const D: usize>(name: &str) -> StringSpec<D, Material> {
    StringSpec {
        name: name.into(),
        material: Material::hyperelastic(2e7),
        rho_a: 1.6,
        mass: MassMatrix::Consistent,
        body_force: Vector::zeros(),
        prestretch: 1.001,
    }
}

fn embed<const D: usize>(v: &Vector3<f64>) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| v[k])
}

/// Two boxes of 2 t and 3 t, 20 m apart, joined by three pre-stretched ropes (3D) or two
/// (2D), each body moving and spinning; no support, no gravity.
fn two_boxes<const D: usize>(wrench: Option<BodyWrench>) -> Network<D, Material> {
    let mut nb = NetworkBuilder::<D, Material>::new();
    let (qa, qb) = if D == 3 {
        (
            UnitQuaternion::from_euler_angles(0.2, -0.1, 0.3),
            UnitQuaternion::from_euler_angles(-0.3, 0.25, 0.1),
        )
    } else {
        (
            UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3),
            UnitQuaternion::from_euler_angles(0.0, 0.0, -0.2),
        )
    };
    let (ma, mb) = (2000.0, 3000.0);
    let (ja, jb) = (box_inertia(ma), box_inertia(mb));
    let planar = |v: Vector3<f64>| {
        if D == 2 {
            Vector3::new(v.x, v.y, 0.0)
        } else {
            v
        }
    };
    let spin_a = if D == 2 {
        Vector3::new(0.0, 0.0, 0.8)
    } else {
        Vector3::new(0.3, -0.5, 0.8)
    };
    let spin_b = if D == 2 {
        Vector3::new(0.0, 0.0, -0.4)
    } else {
        Vector3::new(-0.2, 0.4, -0.4)
    };
    let sa = BodyState::new(
        Vector3::zeros(),
        planar(Vector3::new(0.5, 1.0, 0.3)),
        qa,
        spin_a,
    );
    let sb = BodyState::new(
        Vector3::new(20.0, 0.0, 0.0),
        planar(Vector3::new(-0.4, -0.5, 0.2)),
        qb,
        spin_b,
    );
    let points: Vec<Vector3<f64>> = if D == 3 {
        vec![
            Vector3::new(1.0, 0.5, 0.25),
            Vector3::new(1.0, -0.5, 0.25),
            Vector3::new(1.0, 0.0, -0.25),
        ]
    } else {
        vec![Vector3::new(1.0, 0.5, 0.0), Vector3::new(1.0, -0.5, 0.0)]
    };
    let mut att_a = Vec::new();
    let mut att_b = Vec::new();
    for (k, s) in points.iter().enumerate() {
        let sb_point = Vector3::new(-s.x, s.y, s.z);
        let a = nb.node(embed(&sa.point(s)));
        let b = nb.node(embed(&sb.point(&sb_point)));
        nb.string(rope(&format!("rope{k}")), &[a, b], 10).unwrap();
        att_a.push(Attachment {
            node: a,
            point: embed(s),
        });
        att_b.push(Attachment {
            node: b,
            point: embed(&sb_point),
        });
    }
    let mut net = nb.build(Boundary::default(), Vec::new()).unwrap();
    // Node velocities: the attached nodes move with their bodies, the ropes' interior
    // nodes with the straight line between their ends.
    let vel = |st: &BodyState, s: &Vector3<f64>| {
        let omega = st.orientation.transform_vector(&st.omega);
        st.velocity + omega.cross(&st.orientation.transform_vector(s))
    };
    for g in 0..points.len() {
        let s = &points[g];
        let (va, vb) = (vel(&sa, s), vel(&sb, &Vector3::new(-s.x, s.y, s.z)));
        let (ra, rb) = (sa.point(s), sb.point(&Vector3::new(-s.x, s.y, s.z)));
        for (i, r) in net.initial.r.iter().enumerate() {
            let r3 = Vector3::from_fn(|k, _| if k < D { r[k] } else { 0.0 });
            let along = (r3 - ra).dot(&(rb - ra)) / (rb - ra).norm_squared();
            let off = (r3 - ra - (rb - ra) * along).norm();
            if off < 1e-9 && (-1e-12..=1.0 + 1e-12).contains(&along) {
                net.initial.v[i] = embed(&(va + (vb - va) * along));
            }
        }
    }
    let body = |name: &str, mass, inertia, atts, initial, wrench| RigidBody {
        name: name.into(),
        mass,
        inertia,
        weight: Vector::zeros(),
        attachments: atts,
        initial,
        wrench,
        hydro: None,
        motion: None,
        feedback: None,
    };
    net.with_body(body("a", ma, ja, att_a, sa, wrench))
        .with_body(body("b", mb, jb, att_b, sb, None))
}

fn params() -> StepParams {
    StepParams {
        h: 2e-3,
        newton: NewtonParams {
            tol: 1e-9,
            rtol: 0.0,
            max_iter: 30,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Runs `two_boxes` for 500 steps of 2 ms; returns the largest relative drifts of the
/// linear and angular momentum, the largest balance error per step (of the step's energy
/// scale) and the relative change of `Ĥ`.
fn drifts<const D: usize>(
    momentum: impl Fn(&Simulation<D, Material>) -> (f64, Vector3<f64>),
) -> [f64; 4] {
    let mut sim = Simulation::new(two_boxes::<D>(None), params()).unwrap();
    let (p0, l0) = momentum(&sim);
    let h0 = sim.energies().hamiltonian();
    let (mut dp, mut dl, mut db) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..500 {
        let rep = sim.step().unwrap();
        let (p, l) = momentum(&sim);
        dp = dp.max((p - p0).abs() / p0.abs());
        dl = dl.max((l - l0).norm() / l0.norm());
        db = db.max(rep.balance_error.abs() / rep.energy_scale);
    }
    let dh = (sim.energies().hamiltonian() - h0).abs() / h0;
    [dp, dl, db, dh]
}

/// Two boxes of 2 t and 3 t on three wire ropes, free in space (3D), 500 steps of 2 ms:
/// linear and angular momentum constant to 1e-13 relative, the energy balance exact on every
/// step (measured: 7.9e-15, 3.2e-15, 1e-18 of the step's energy scale, Ĥ within 5.5e-14).
#[test]
fn bodies_on_strings_keep_momentum_and_energy_3d() {
    let [dp, dl, db, dh] = drifts::<3>(|sim| {
        let sys = sim.system();
        (
            sys.linear_momentum(sim.state()).norm(),
            sys.angular_momentum(sim.state()),
        )
    });
    assert!(dp < 1e-13, "linear momentum drift {dp:e}");
    assert!(dl < 1e-13, "angular momentum drift {dl:e}");
    assert!(db < 1e-13, "balance error {db:e} of the energy scale");
    assert!(dh < 1e-12, "energy drift {dh:e}");
}

/// The same in 2D with two ropes.
#[test]
fn bodies_on_strings_keep_momentum_and_energy_2d() {
    let [dp, dl, db, dh] = drifts::<2>(|sim| {
        let sys = sim.system();
        let l = sys.angular_momentum(sim.state());
        (
            sys.linear_momentum(sim.state()).norm(),
            Vector3::new(0.0, 0.0, l),
        )
    });
    assert!(dp < 1e-13, "linear momentum drift {dp:e}");
    assert!(dl < 1e-13, "angular momentum drift {dl:e}");
    assert!(db < 1e-13, "balance error {db:e} of the energy scale");
    assert!(dh < 1e-12, "energy drift {dh:e}");
}

/// A compound pendulum on a stiff, light string (2D): a 2 t body (J = 1500 kg·m² about its
/// centre) hangs by a point 1.5 m above its centre from a 10 m string (EA = 1e9 N,
/// 0.01 kg/m) fixed at the origin, in gravity. Released in one of the two small-oscillation
/// modes (largest angle 0.002 rad), it swings at that mode's closed-form frequency of the
/// double pendulum
/// `det(K − ω² M) = 0`, `M = [[mL², mLd], [mLd, J + md²]]`, `K = diag(mgL, mgd)` (measured
/// at h = 5 ms: 7.8e-5 and 2.5e-6 off).
#[test]
fn compound_pendulum_on_a_string_swings_at_the_closed_form_frequencies() {
    let (m, j, d, l, g): (f64, f64, f64, f64, f64) = (2000.0, 1500.0, 1.5, 10.0, 9.81);
    let mass = nalgebra::Matrix2::<f64>::new(m * l * l, m * l * d, m * l * d, j + m * d * d);
    let stiff = nalgebra::Matrix2::new(m * g * l, 0.0, 0.0, m * g * d);
    // Generalized eigenproblem through M^{-1/2} K M^{-1/2} (M is SPD).
    let ch = mass.cholesky().unwrap();
    let li = ch.l().try_inverse().unwrap();
    let eig = (li * stiff * li.transpose()).symmetric_eigen();
    for mode in 0..2 {
        let omega = eig.eigenvalues[mode].sqrt();
        let shape = li.transpose() * eig.eigenvectors.column(mode);
        let amp = 0.002 / shape[0].abs().max(shape[1].abs());
        let (th1, th2) = (amp * shape[0], amp * shape[1]);
        let period = 2.0 * std::f64::consts::PI / omega;
        let measured = swing(
            (m, j, d, l, g),
            (th1, th2),
            period,
            Scheme::DiscreteGradient,
            5e-3,
        );
        // The scheme's phase error (hω)²/12 ≤ 4.7e-5, the string's mass about 3e-5 (measured
        // by changing it), the amplitude's nonlinearity about 6e-6 at 0.002 rad.
        assert!(
            (measured / omega - 1.0).abs() < 1.2e-4,
            "mode {mode}: {measured} rad/s against {omega}"
        );
    }
}

/// The fourth-order composition (`dg4`) with bodies: at h = 20 ms the compound pendulum's
/// fast mode (4.76 rad/s) is off by 3.6e-5 with `dg4` (the model's own floor: the string's
/// mass and the amplitude, about 3.4e-5), against 7.9e-4 with `dg`, whose phase error
/// `(hω)²/12` is 7.6e-4.
#[test]
fn compound_pendulum_with_dg4_converges_at_fourth_order() {
    let (m, j, d, l, g): (f64, f64, f64, f64, f64) = (2000.0, 1500.0, 1.5, 10.0, 9.81);
    let mass = nalgebra::Matrix2::<f64>::new(m * l * l, m * l * d, m * l * d, j + m * d * d);
    let stiff = nalgebra::Matrix2::new(m * g * l, 0.0, 0.0, m * g * d);
    let li = mass.cholesky().unwrap().l().try_inverse().unwrap();
    let eig = (li * stiff * li.transpose()).symmetric_eigen();
    let fast = if eig.eigenvalues[0] > eig.eigenvalues[1] {
        0
    } else {
        1
    };
    let omega = eig.eigenvalues[fast].sqrt();
    let shape = li.transpose() * eig.eigenvectors.column(fast);
    let amp = 0.002 / shape[0].abs().max(shape[1].abs());
    let period = 2.0 * std::f64::consts::PI / omega;
    let angles = (amp * shape[0], amp * shape[1]);
    let err = |scheme| swing((m, j, d, l, g), angles, period, scheme, 0.02) / omega - 1.0;
    let (e2, e4) = (
        err(Scheme::DiscreteGradient),
        err(Scheme::DiscreteGradient4),
    );
    assert!(e2.abs() > 6e-4, "dg: {e2:e}");
    assert!(e4.abs() < 6e-5, "dg4: {e4:e}");
}

/// The compound pendulum of [`swing`] at string angle `th1` and body angle `th2` [rad]: the
/// network (a 4-element string of EA = 1e9 N and 0.01 kg/m, prestretched by the body's
/// weight) and the string's node at the body.
fn compound_pendulum(
    (m, j, d, l, g): (f64, f64, f64, f64, f64),
    (th1, th2): (f64, f64),
) -> (phstring::Network<2, Material>, usize) {
    let n_el = 4;
    let mut nb = NetworkBuilder::<2, Material>::new();
    let top = nb.node(Vector::<2>::zeros());
    let hook = Vector3::new(l * th1.sin(), -l * th1.cos(), 0.0);
    let end = nb.node(Vector::<2>::new(hook.x, hook.y));
    let ea = 1e9;
    let spec = StringSpec {
        name: "string".into(),
        material: Material::linear_elastic(ea),
        rho_a: 0.01,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -0.01 * g),
        prestretch: 1.0 + m * g / ea,
    };
    nb.string(spec, &[top, end], n_el).unwrap();
    let mut fixed = Boundary::default();
    fixed.fixed.push(phstring::Fixed::node(top));
    let net = nb.build(fixed, Vec::new()).unwrap();
    let q = UnitQuaternion::from_euler_angles(0.0, 0.0, th2);
    let s = Vector3::new(0.0, d, 0.0);
    let centre = hook - q.transform_vector(&s);
    let inertia = nalgebra::Matrix3::from_diagonal_element(j);
    let body = RigidBody {
        name: "block".into(),
        mass: m,
        inertia,
        weight: Vector::<2>::new(0.0, -m * g),
        attachments: vec![Attachment {
            node: end,
            point: Vector::<2>::new(0.0, d),
        }],
        initial: BodyState::at_rest(centre, q),
        wrench: None,
        hydro: None,
        motion: None,
        feedback: None,
    };
    (net.with_body(body), end)
}

/// The natural modes of the compound pendulum of [`swing`] about its static equilibrium
/// (`modes::modes_with_bodies`): the two lowest are the double pendulum's closed-form
/// frequencies `det(K − ω² M) = 0` to 1e-4 (measured: 5.9e-6 and 2.5e-5, the string's mass
/// and stretch, which the closed form leaves out), and the body holds most of their kinetic
/// energy (`Character::Body`); the string's own modes come next, above 100 rad/s; the
/// shapes are `M`-normalized through the body's inertia: the lower mode turns the string and
/// the body the same way, the upper one opposite ways, in the closed form's ratio to 1e-3.
#[test]
fn compound_pendulum_modes_match_the_closed_form() {
    let (m, j, d, l, g): (f64, f64, f64, f64, f64) = (2000.0, 1500.0, 1.5, 10.0, 9.81);
    let mass = nalgebra::Matrix2::<f64>::new(m * l * l, m * l * d, m * l * d, j + m * d * d);
    let stiff = nalgebra::Matrix2::new(m * g * l, 0.0, 0.0, m * g * d);
    let li = mass.cholesky().unwrap().l().try_inverse().unwrap();
    let eig = (li * stiff * li.transpose()).symmetric_eigen();
    let mut pairs: Vec<(f64, nalgebra::Vector2<f64>)> = (0..2)
        .map(|k| {
            (
                eig.eigenvalues[k].sqrt(),
                li.transpose() * eig.eigenvectors.column(k),
            )
        })
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (net, end) = compound_pendulum((m, j, d, l, g), (0.0, 0.0));
    let (sys, start) = phstring::PhSystem::new(net).unwrap();
    let eq = phstring::statics::solve_system(&sys, &start.r, &Default::default(), None).unwrap();
    let found =
        phstring::modes::modes_with_bodies(&sys, &eq.state.r, &eq.state.bodies, 4, None).unwrap();
    for (k, (omega, shape)) in pairs.iter().enumerate() {
        let mode = &found.modes[k];
        let rel = (mode.omega / omega - 1.0).abs();
        eprintln!("mode {k}: {} rad/s against {omega}: {rel:.2e}", mode.omega);
        assert!(rel < 1e-4, "mode {k}: {} against {omega}", mode.omega);
        assert_eq!(mode.character, phstring::modes::Character::Body);
        // String angle: the end node's sideways motion over L; body angle: its turn.
        let th1 = mode.shape[end].x / l;
        let th2 = mode.bodies[0].1.z;
        let ratio = th2 / th1;
        let want = shape[1] / shape[0];
        assert!(
            (ratio / want - 1.0).abs() < 1e-3,
            "mode {k}: ratio {ratio} against {want}"
        );
    }
    assert!(found.modes[2].omega > 100.0, "{}", found.modes[2].omega);
}

/// The reduced linear model with the compound pendulum's body and its wrench port
/// (`linear::reduced_model_with_bodies`): `J = −Jᵀ`, `R = 0` (no damping), `Eᵀ Q`
/// symmetric; its static gain `K⁻¹ B` from the body's horizontal force and its torque to the
/// body's displacement and turn equals the compliance `K_b⁻¹` of the body's mooring
/// stiffness (`statics::body_stiffness`, the Schur complement by the bordered solves) to
/// 1e-10 (measured: 5e-16); and `Bᵀ` reads the body's velocity and angular velocity.
#[test]
fn linear_model_with_a_body_has_the_mooring_compliance() {
    let (m, j, d, l, g): (f64, f64, f64, f64, f64) = (2000.0, 1500.0, 1.5, 10.0, 9.81);
    let (net, _) = compound_pendulum((m, j, d, l, g), (0.0, 0.0));
    let (sys, start) = phstring::PhSystem::new(net).unwrap();
    let params = phstring::statics::StaticsParams::default();
    let eq = phstring::statics::solve_system(&sys, &start.r, &params, None).unwrap();
    let lin =
        phstring::linear::reduced_model_with_bodies(&sys, &eq.state.r, &eq.state.bodies, &[], &[0])
            .unwrap();
    let dense = |a: &faer::sparse::SparseColMat<usize, f64>| a.as_ref().to_dense();
    let (jm, e, q, r, b) = (
        dense(&lin.j),
        dense(&lin.e),
        dense(&lin.q),
        dense(&lin.r),
        dense(&lin.b),
    );
    let size = jm.nrows();
    let n = size / 2;
    let eq_t = e.transpose() * &q;
    for a in 0..size {
        for c in 0..size {
            assert_eq!(jm[(a, c)], -jm[(c, a)]);
            assert!((eq_t[(a, c)] - eq_t[(c, a)]).abs() <= 1e-9 * eq_t[(a, a)].abs().max(1.0));
            assert_eq!(r[(a, c)], 0.0);
        }
    }
    assert_eq!(b.ncols(), 3);
    assert_eq!(lin.states[n - 1], "q[block].rho_wz");
    // K⁻¹ B on the position coordinates.
    let k = q.submatrix(0, 0, n, n).to_owned();
    let bq = b.submatrix(n, 0, n, 3).to_owned();
    let x = faer::linalg::solvers::Solve::solve(&k.partial_piv_lu(), &bq);
    let kb = phstring::statics::body_stiffness(&sys, &eq, 0, &params).unwrap();
    let compliance = kb.matrix.try_inverse().unwrap();
    let rho = (j / m).sqrt() * 3f64.sqrt();
    let mut worst = 0.0f64;
    for col in 0..3 {
        // Columns: force x, force y, torque z; rows: x, y, turn (ρ w / ρ).
        let got = [x[(n - 3, col)], x[(n - 2, col)], x[(n - 1, col)] / rho];
        for row in 0..3 {
            let want = compliance[(row, col)];
            let scale = compliance.column(col).abs().max();
            worst = worst.max((got[row] - want).abs() / scale);
        }
    }
    eprintln!("static gain against the compliance: {worst:.2e}");
    assert!(worst <= 1e-10, "{worst}");
    // Bᵀ reads the body's velocity and angular velocity: a state whose body coordinates
    // move at (1, 2, 3ρ) m/s gives (1, 2, 3).
    let mut v = faer::Mat::<f64>::zeros(size, 1);
    v[(2 * n - 3, 0)] = 1.0;
    v[(2 * n - 2, 0)] = 2.0;
    v[(2 * n - 1, 0)] = 3.0 * rho;
    let y = b.transpose() * &v;
    for (k, want) in [1.0, 2.0, 3.0].iter().enumerate() {
        assert!((y[(k, 0)] - want).abs() <= 1e-12, "{k}: {}", y[(k, 0)]);
    }
}

/// Runs the compound pendulum (`m` [kg], `j` [kg·m²], `d`, `l` [m], `g` [m/s²]) from string
/// angle `th1` and body angle `th2` [rad] at rest for four periods `period` [s] with `scheme`
/// and step `h` [s]; returns the angular frequency [rad/s] of the string angle measured between
/// its first and last upward zero crossings.
fn swing(
    (m, j, d, l, g): (f64, f64, f64, f64, f64),
    (th1, th2): (f64, f64),
    period: f64,
    scheme: Scheme,
    h: f64,
) -> f64 {
    let (net, end) = compound_pendulum((m, j, d, l, g), (th1, th2));
    let params = StepParams {
        h,
        scheme,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let angle = |sim: &Simulation<2, Material>| {
        let r = sim.state().r[end];
        r.x.atan2(-r.y)
    };
    let (mut last, mut t_last) = (angle(&sim), 0.0);
    let mut ups = Vec::new();
    while sim.time() < 4.0 * period {
        sim.step().unwrap();
        let (a, t) = (angle(&sim), sim.time());
        if last < 0.0 && a >= 0.0 {
            ups.push(t_last + (t - t_last) * (-last) / (a - last));
        }
        (last, t_last) = (a, t);
    }
    let cycles = (ups.len() - 1) as f64;
    2.0 * std::f64::consts::PI * cycles / (ups[ups.len() - 1] - ups[0])
}

/// The wrench port (3D): a force of 2 kN and a torque of 1 kN·m, both turning in time, act
/// on the first box for 1 s (500 steps). The momentum changes by the impulse `Σ h F(t_{n+½})`,
/// the angular momentum by `Σ h (x_{n+½} × F + τ)`, both to 1e-13 of their size, and `Ĥ`
/// by the energy the port supplied, on every step. The port reports its input.
#[test]
fn wrench_port_supplies_its_impulse_and_work() {
    let force = |t: f64| Vector3::new(2e3 * (3.0 * t).cos(), 1e3 * (2.0 * t).sin(), -5e2);
    let torque = |t: f64| Vector3::new(1e3 * t, -5e2, 8e2 * (5.0 * t).sin());
    let wrench = BodyWrench {
        force: std::sync::Arc::new(force),
        torque: std::sync::Arc::new(torque),
    };
    let mut sim = Simulation::new(two_boxes::<3>(Some(wrench)), params()).unwrap();
    let sys_p = |sim: &Simulation<3, Material>| sim.system().linear_momentum(sim.state());
    let sys_l = |sim: &Simulation<3, Material>| sim.system().angular_momentum(sim.state());
    let (p0, l0, h0) = (sys_p(&sim), sys_l(&sim), sim.energies().hamiltonian());
    let (mut impulse, mut moment) = (Vector3::zeros(), Vector3::zeros());
    let mut worst_balance = 0.0f64;
    for _ in 0..500 {
        let (t, x0) = (sim.time(), sim.state().bodies[0].position);
        let rep = sim.step().unwrap();
        let h = rep.h;
        let x_mid = (x0 + sim.state().bodies[0].position) * 0.5;
        let f = force(t + 0.5 * h);
        impulse += f * h;
        moment += (x_mid.cross(&f) + torque(t + 0.5 * h)) * h;
        worst_balance = worst_balance.max(rep.balance_error.abs() / rep.energy_scale);
        let port = sim.body_ports()[0];
        assert_eq!(port.force, f);
    }
    let dp = (sys_p(&sim) - p0 - impulse).norm() / impulse.norm();
    // Relative to the larger of the angular momentum and the moment (rounding is relative to
    // the sums' size).
    let dl = (sys_l(&sim) - l0 - moment).norm() / moment.norm().max(l0.norm());
    let dh = sim.energies().hamiltonian() - h0 - sim.supplied_energy();
    assert!(dp < 1e-13, "momentum against impulse: {dp:e}");
    assert!(dl < 1e-13, "angular momentum against moment: {dl:e}");
    assert!(
        worst_balance < 1e-13,
        "balance error {worst_balance:e} of the energy scale"
    );
    assert!(
        dh.abs() < 1e-12 * sim.supplied_energy().abs().max(h0),
        "Ĥ moved {dh:e} J beyond the supplied {} J",
        sim.supplied_energy()
    );
}

/// A checkpoint taken after 100 steps and restored into a new simulation of the same
/// network continues exactly as the run that was not interrupted (bodies included), and a
/// checkpoint of another network's body count is refused.
#[test]
fn checkpoint_restores_the_bodies_exactly() {
    let mut a = Simulation::new(two_boxes::<3>(None), params()).unwrap();
    for _ in 0..100 {
        a.step().unwrap();
    }
    let cp = a.checkpoint();
    let flat = phstring::simulation::FlatCheckpoint::from(&cp);
    assert_eq!(flat.bodies.len(), 2 * 13);
    let mut b = Simulation::new(two_boxes::<3>(None), params()).unwrap();
    b.restore(flat.into_checkpoint()).unwrap();
    for _ in 0..50 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert_eq!(a.state(), b.state());
    // A checkpoint without the bodies does not fit.
    let mut none = phstring::simulation::FlatCheckpoint::from(&cp);
    none.bodies.clear();
    let err = b.restore(none.into_checkpoint()).unwrap_err().to_string();
    assert!(err.contains("rigid bodies"), "{err}");
}

/// A buoy rising in still water (3D): 1 t, 2 m³ displaced (buoyancy at 0.3 m above its
/// centre), `C_d A` = 1.5 m², `C_a` = 0.5, with a 2 m pennant (1 kg/m, no hydrodynamics)
/// hanging below it. From rest it
/// reaches the closed-form terminal speed `√(2 (ρgV − m g − w_line L)/(ρ C_d A))` (with the
/// drag law's smoothing speed) to 1e-9,
/// upright; every step's balance (with the drag's dissipation and the buoyancy's potential)
/// is exact.
#[test]
fn buoy_rises_at_the_closed_form_terminal_speed() {
    use phstring::{BodyHydro, Water};
    let water = Water::<3>::new(1025.0);
    let g = water.gravity;
    let (m, vol, cda) = (1000.0, 2.0, 1.5);
    let (rho_line, len) = (1.0, 2.0);
    let centre = Vector3::new(0.0, 0.0, -100.0);
    let hydro = BodyHydro {
        volume: vol,
        centre_of_buoyancy: Vector3::new(0.0, 0.0, 0.3),
        cda,
        ca: 0.5,
        ..Default::default()
    };
    let pennant = (rho_line, len, 1.0);
    let net = buoy_on_pennant(water, (m, 400.0), centre, pennant, hydro);
    let mut sim = Simulation::new(net, params()).unwrap();
    let mut worst = 0.0f64;
    let mut dissipated = 0.0;
    let mut z8 = 0.0;
    while sim.time() < 10.0 {
        let rep = sim.step().unwrap();
        worst = worst.max(rep.balance_error.abs() / rep.energy_scale);
        dissipated += rep.water.drag_dissipated;
        if (sim.time() - 8.0).abs() < 1e-9 {
            z8 = sim.state().bodies[0].position.z;
        }
    }
    let net_up = 1025.0 * g * vol - m * g - rho_line * len * g;
    // Terminal speed with the drag law's smoothed speed √(v² + δ²):
    // ½ρC_dA v √(v² + δ²) = F, so v² = (√(δ⁴ + 4 (F/c)²) − δ²)/2 with c = ½ρC_dA.
    let (c, delta) = (0.5 * 1025.0 * cda, phstring::water::DEFAULT_DRAG_SMOOTHING);
    let q = net_up / c;
    let v_t = (((delta.powi(4) + 4.0 * q * q).sqrt() - delta * delta) / 2.0).sqrt();
    let st = sim.state().bodies[0];
    // The mean speed over the last 2 s (the pennant's axial vibration, undamped, makes the
    // velocity state ripple by about 2e-7).
    let speed = (st.position.z - z8) / 2.0;
    assert!(
        (speed / v_t - 1.0).abs() < 1e-9,
        "{speed} m/s against {v_t} m/s"
    );
    assert!(
        st.velocity.xy().norm() < 1e-12 && st.omega.norm() < 1e-12,
        "{st:?}"
    );
    assert!(worst < 1e-13, "balance error {worst:e} of the energy scale");
    // The drag took what the buoyancy gave beyond the weights and the kinetic energy.
    let rise = st.position.z - centre.z;
    let kinetic = sim.energies().kinetic;
    let expected = net_up * rise - kinetic;
    assert!(
        (dissipated / expected - 1.0).abs() < 1e-9,
        "dissipated {dissipated} J, expected {expected} J"
    );
}

/// A prescribed motion (2D): a 50 t "vessel" surges, heaves and pitches (amplitudes 2 m,
/// 0.5 m, 3°, periods 12 s, 8 s and 10 s) on two 60 m chains (EA = 5e8 N, 100 kg/m) to two
/// anchors, in gravity, for 20 s. It follows its path to round-off, every step's balance is
/// exact with the motion's power as supply, and the momentum changes by the impulse of the
/// weights, the anchors' reactions and the motion's reaction force, to the Newton residuals
/// `Σ h ‖R‖` the steps left (and 1e-12 of the impulse for rounding).
#[test]
fn prescribed_body_follows_its_path_with_exact_balance() {
    prescribed_vessel(false);
}

/// The same vessel in water with a current of 0.8 m/s and drag on it (`C_dA` = 20 m²,
/// 5e4 N·s/m): still on its path and with an exact balance on every step, the drag's work in
/// the water's shares and not in the motion's reaction (once counted).
#[test]
fn prescribed_body_in_a_current_keeps_an_exact_balance() {
    prescribed_vessel(true);
}

/// Runs the vessel of [`prescribed_body_follows_its_path_with_exact_balance`], dry or in a
/// current with drag on the vessel, and checks its path, balance and (dry) momentum.
fn prescribed_vessel(wet: bool) {
    use phstring::BodyMotion;
    use std::f64::consts::PI;
    let g = 9.81;
    let (a1, a2, a3) = (2.0, 0.5, 3f64.to_radians());
    let (w1, w2, w3) = (2.0 * PI / 12.0, 2.0 * PI / 8.0, 2.0 * PI / 10.0);
    let pose = move |t: f64| {
        let x = Vector3::new(a1 * (w1 * t).sin(), -2.0 + a2 * (w2 * t).sin(), 0.0);
        (
            x,
            UnitQuaternion::from_euler_angles(0.0, 0.0, a3 * (w3 * t).sin()),
        )
    };
    let twist = move |t: f64| {
        let v = Vector3::new(a1 * w1 * (w1 * t).cos(), a2 * w2 * (w2 * t).cos(), 0.0);
        (v, Vector3::new(0.0, 0.0, a3 * w3 * (w3 * t).cos()))
    };
    let (x0, q0) = pose(0.0);
    let (v0, om0) = twist(0.0);
    let start = BodyState::new(x0, v0, q0, om0);
    let mut nb = NetworkBuilder::<2, Material>::new();
    let fairleads = [
        Vector3::new(-10.0, -3.0, 0.0),
        Vector3::new(10.0, -3.0, 0.0),
    ];
    let mut atts = Vec::new();
    let mut anchors = Vec::new();
    for (k, s) in fairleads.iter().enumerate() {
        let p = start.point(s);
        let f = nb.node(Vector::<2>::new(p.x, p.y));
        let a = nb.node(Vector::<2>::new(if k == 0 { -60.0 } else { 60.0 }, -40.0));
        let spec = StringSpec {
            name: format!("chain{k}"),
            material: Material::tension_only_linear(5e8),
            rho_a: 100.0,
            mass: MassMatrix::Consistent,
            body_force: Vector::<2>::new(0.0, -100.0 * g),
            prestretch: 1.0,
        };
        nb.string(spec, &[a, f], 20).unwrap();
        atts.push(Attachment {
            node: f,
            point: Vector::<2>::new(s.x, s.y),
        });
        anchors.push(a);
    }
    let boundary = Boundary {
        fixed: anchors.iter().map(|&a| phstring::Fixed::node(a)).collect(),
        ..Default::default()
    };
    let mut net = nb.build(boundary, Vec::new()).unwrap();
    for (att, s) in atts.iter().zip(&fairleads) {
        let arm = start.orientation.transform_vector(s);
        let v = start.velocity + start.omega_space().cross(&arm);
        net.initial.v[att.node] = Vector::<2>::new(v.x, v.y);
    }
    let m = 5e4;
    let hydro = wet.then_some(phstring::BodyHydro {
        cda: 20.0,
        linear_drag: 5e4,
        ..Default::default()
    });
    if wet {
        let current = phstring::Current::Uniform(Vector::<2>::new(0.8, 0.0));
        net = net.with_water(phstring::Water::new(1025.0).with_current(current));
    }
    let net = net.with_body(RigidBody {
        name: "vessel".into(),
        mass: m,
        inertia: nalgebra::Matrix3::from_diagonal_element(4e6),
        weight: Vector::<2>::new(0.0, -m * g),
        attachments: atts,
        initial: start,
        wrench: None,
        hydro,
        motion: Some(BodyMotion {
            pose: std::sync::Arc::new(pose),
            twist: std::sync::Arc::new(twist),
        }),
        feedback: None,
    });
    let params = StepParams {
        h: 0.01,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let gravity: Vector<2> =
        sim.system().body_force_vector().iter().sum::<Vector<2>>() + Vector::<2>::new(0.0, -m * g);
    let p0 = sim.system().linear_momentum(sim.state());
    let (mut impulse, mut worst, mut off) = (Vector::<2>::zeros(), 0.0f64, 0.0f64);
    // The momentum balance holds to the Newton residuals left on the free rows.
    let (mut residuals, mut drag) = (0.0, 0.0);
    while sim.time() < 20.0 {
        let rep = sim.step().unwrap();
        residuals += rep.residual * rep.h;
        drag += rep.water.drag_dissipated;
        worst = worst.max(rep.balance_error.abs() / rep.energy_scale);
        let reactions: Vector<2> = sim.ports().iter().map(|p| p.output).sum();
        let f = sim.body_ports()[0].force;
        impulse += (gravity + reactions + Vector::<2>::new(f.x, f.y)) * rep.h;
        let (x, q) = pose(sim.time());
        let st = sim.state().bodies[0];
        off = off.max((st.position - x).norm() + st.orientation.angle_to(&q));
    }
    let dp = (sim.system().linear_momentum(sim.state()) - p0 - impulse).norm();
    assert!(off < 1e-12, "off the path by {off:e}");
    assert!(worst < 1e-13, "balance error {worst:e} of the energy scale");
    if wet {
        assert!(drag > 0.0, "the drag dissipated {drag} J");
        return;
    }
    let bound = residuals + 1e-12 * impulse.norm();
    assert!(
        dp <= bound,
        "momentum against impulse: {dp:e} (bound {bound:e})"
    );
}

/// A floater's waterplane (3D): a 20 t buoy, neutrally buoyant with its waterline point at the
/// surface (`V = m/ρ_w`), waterplane 10 m², `C_a` = 0.3, with a 2 m pennant (1 kg/m) below,
/// released 0.3 m above its equilibrium, heaves at the closed-form frequency
/// `√(ρ_w g A_w / M)`, `M = m + C_a ρ_w V + m_pennant`, to 1e-4 (the pennant's stretch and the
/// scheme's `(hω)²/12`, 4e-5 at 10 ms), about the closed-form equilibrium
/// `−w_pennant L/(ρ_w g A_w)` to 1e-3 of the amplitude, with an exact balance on every step
/// (measured: 3.2e-5 and 1e-6).
#[test]
fn floater_heaves_at_the_closed_form_frequency() {
    use phstring::{BodyHydro, Water};
    let water = Water::<3>::new(1025.0);
    let g = water.gravity;
    let (m, area, ca, rho) = (2e4, 10.0, 0.3, 1025.0);
    let vol = m / rho;
    let (rho_line, len) = (1.0, 2.0);
    let k = rho * g * area;
    let z_eq = -rho_line * len * g / k;
    let lift = 0.3;
    let centre = Vector3::new(0.0, 0.0, lift);
    let hydro = BodyHydro {
        volume: vol,
        ca,
        waterplane_area: area,
        ..Default::default()
    };
    let net = buoy_on_pennant(water, (m, 5e4), centre, (rho_line, len, 2.0), hydro);
    let mut sim = Simulation::new(net, StepParams::default()).unwrap();
    let omega = (k / (m + ca * rho * vol + rho_line * len)).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega;
    let (mut last, mut t_last, mut worst) = (lift - z_eq, 0.0, 0.0f64);
    let (mut ups, mut lo, mut hi) = (Vec::new(), f64::MAX, f64::MIN);
    while sim.time() < 5.0 * period {
        let rep = sim.step().unwrap();
        worst = worst.max(rep.balance_error.abs() / rep.energy_scale);
        let (z, t) = (sim.state().bodies[0].position.z, sim.time());
        let a = z - z_eq;
        if last < 0.0 && a >= 0.0 {
            ups.push(t_last + (t - t_last) * (-last) / (a - last));
        }
        (last, t_last) = (a, t);
        lo = lo.min(z);
        hi = hi.max(z);
    }
    let measured =
        2.0 * std::f64::consts::PI * (ups.len() - 1) as f64 / (ups[ups.len() - 1] - ups[0]);
    assert!(
        (measured / omega - 1.0).abs() < 1e-4,
        "{measured} rad/s against {omega}"
    );
    let centre_of_swing = 0.5 * (lo + hi);
    assert!(
        (centre_of_swing - z_eq).abs() < 1e-3 * lift,
        "swings about {centre_of_swing} m, equilibrium {z_eq} m"
    );
    assert!(worst < 1e-13, "balance error {worst:e} of the energy scale");
}

/// A wrench held from outside (`set_body_wrench`, the co-simulation input) gives the run of
/// the same constant wrench signal bit for bit, and its release the run without it; unknown
/// bodies and non-finite values are refused with nothing changed.
#[test]
fn held_body_wrench_equals_the_constant_signal() {
    let (f, tau) = (
        Vector3::new(500.0, -300.0, 200.0),
        Vector3::new(100.0, 50.0, -80.0),
    );
    let constant = BodyWrench {
        force: std::sync::Arc::new(move |_t| f),
        torque: std::sync::Arc::new(move |_t| tau),
    };
    let mut by_signal = Simulation::new(two_boxes::<3>(Some(constant)), params()).unwrap();
    let mut by_input = Simulation::new(two_boxes::<3>(None), params()).unwrap();
    let mut free = Simulation::new(two_boxes::<3>(None), params()).unwrap();
    assert!(by_input.set_body_wrench(2, f, tau).is_err());
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    let err = by_input
        .set_body_wrench(0, nan, tau)
        .unwrap_err()
        .to_string();
    assert!(err.contains("body 0") && err.contains("NaN"), "{err}");
    by_input.set_body_wrench(0, f, tau).unwrap();
    for _ in 0..50 {
        by_signal.step().unwrap();
        by_input.step().unwrap();
        free.step().unwrap();
    }
    assert_eq!(by_signal.state(), by_input.state());
    assert_eq!(by_signal.supplied_energy(), by_input.supplied_energy());
    // Released: the input's run goes on as the free run would from its state.
    by_input.release_body_wrench(0).unwrap();
    let mut released = Simulation::new(two_boxes::<3>(None), params()).unwrap();
    released.restore(by_input.checkpoint()).unwrap();
    by_input.step().unwrap();
    released.step().unwrap();
    assert_eq!(by_input.state(), released.state());
    assert_ne!(free.state(), by_signal.state());
}

/// With `dg4` the wrench port's sample is the step's `h_k`-weighted mean over its sub-steps:
/// `h · mean_power` summed over the steps is the supplied energy (to 1e-12).
#[test]
fn dg4_body_port_reports_the_steps_mean() {
    let force = |t: f64| Vector3::new(2e3 * (3.0 * t).cos(), 1e3, 0.0);
    let wrench = BodyWrench {
        force: std::sync::Arc::new(force),
        torque: std::sync::Arc::new(|_t| Vector3::new(0.0, 0.0, 500.0)),
    };
    let params = StepParams {
        scheme: Scheme::DiscreteGradient4,
        ..params()
    };
    let mut sim = Simulation::new(two_boxes::<3>(Some(wrench)), params).unwrap();
    let mut port_energy = 0.0;
    for _ in 0..100 {
        let rep = sim.step().unwrap();
        port_energy += sim.body_ports()[0].mean_power * rep.h;
    }
    let supplied = sim.supplied_energy();
    assert!(
        (port_energy - supplied).abs() <= 1e-12 * supplied.abs(),
        "port {port_energy} J against supplied {supplied} J"
    );
}

/// A buoy (`mass` [kg], moment of inertia `inertia` [kg·m²] about every axis) centred at
/// `centre` [m], at rest, in `water`, with `hydro`, and a pennant below it (`rho_line` [kg/m],
/// `len` [m], two elements, no hydrodynamics) hanging from the body point `below` [m] under
/// its centre.
fn buoy_on_pennant(
    water: phstring::Water<3>,
    (mass, inertia): (f64, f64),
    centre: Vector3<f64>,
    (rho_line, len, below): (f64, f64, f64),
    hydro: phstring::BodyHydro,
) -> Network<3, Material> {
    let g = water.gravity;
    let mut nb = NetworkBuilder::<3, Material>::new();
    let top = nb.node(Vector::<3>::new(centre.x, centre.y, centre.z - below));
    let bottom = nb.node(Vector::<3>::new(centre.x, centre.y, centre.z - below - len));
    let spec = StringSpec {
        name: "pennant".into(),
        material: Material::tension_only_linear(1e7),
        rho_a: rho_line,
        mass: MassMatrix::Consistent,
        body_force: Vector::<3>::new(0.0, 0.0, -rho_line * g),
        prestretch: 1.0,
    };
    nb.string(spec, &[top, bottom], 2).unwrap();
    nb.build(Boundary::default(), Vec::new())
        .unwrap()
        .with_water(water)
        .with_body(RigidBody {
            name: "buoy".into(),
            mass,
            inertia: nalgebra::Matrix3::from_diagonal_element(inertia),
            weight: Vector::<3>::new(0.0, 0.0, -mass * g),
            attachments: vec![Attachment {
                node: top,
                point: Vector::<3>::new(0.0, 0.0, -below),
            }],
            initial: BodyState::at_rest(centre, UnitQuaternion::identity()),
            wrench: None,
            hydro: Some(hydro),
            motion: None,
            feedback: None,
        })
}

/// Steps of 2 ms with Newton's default tolerance (`‖R‖ ≤ 1e-12` of the step's force scale,
/// above the residuals' round-off, so that the iterations do not depend on it).
fn default_newton() -> StepParams {
    StepParams {
        h: 2e-3,
        ..Default::default()
    }
}

/// The largest distance between the nodes of two runs and between their bodies' centres and
/// body-frame points 1 m out [m].
fn distance<const D: usize>(a: &Simulation<D, Material>, b: &Simulation<D, Material>) -> f64 {
    let (sa, sb) = (a.state(), b.state());
    let nodes = sa.r.iter().zip(&sb.r).map(|(p, q)| (p - q).norm());
    let bodies = sa.bodies.iter().zip(&sb.bodies).map(|(p, q)| {
        let turn = (p.orientation.to_rotation_matrix().matrix()
            - q.orientation.to_rotation_matrix().matrix())
        .norm();
        (p.position - q.position).norm().max(turn)
    });
    nodes.chain(bodies).fold(0.0, f64::max)
}

/// Runs `net` `steps` steps with the network solver (the bodies' slots in its junction
/// system) and with `reference` (the bordered solve's Schur complement over it); returns the
/// largest distance between the runs over all steps [m], and per run the largest balance
/// error of a step (of the step's energy scale) and the Newton iterations.
fn against_bordered<const D: usize>(
    net: impl Fn() -> Network<D, Material>,
    params: StepParams,
    reference: SolverKind,
    steps: usize,
) -> (f64, [f64; 2], [usize; 2]) {
    let with = |solver| StepParams { solver, ..params };
    let mut junction = Simulation::new(net(), with(SolverKind::Network)).unwrap();
    let mut bordered = Simulation::new(net(), with(reference)).unwrap();
    assert_eq!(junction.solver_name(), "network");
    let (mut dist, mut balance, mut its) = (0.0f64, [0.0f64; 2], [0, 0]);
    for _ in 0..steps {
        for (k, sim) in [&mut junction, &mut bordered].into_iter().enumerate() {
            let rep = sim.step().unwrap();
            balance[k] = balance[k].max(rep.balance_error.abs() / rep.energy_scale);
            its[k] += rep.newton_iterations;
        }
        dist = dist.max(distance(&junction, &bordered));
    }
    (dist, balance, its)
}

/// The bodies as junctions of the network solver against the bordered solve over faer's
/// sparse LU: the two boxes on three ropes (3D) and on two (2D), 50 steps of 2 ms with
/// Newton's default tolerance. The same Newton iterations (measured 150 and 149), the nodes
/// and the bodies' poses the same to 1e-12 m (measured: 3D 2.7e-14 m, 2D 3.7e-14 m, over a
/// 20 m span), every step's balance exact in both (below 1e-13 of the step's energy scale;
/// measured 3.6e-17 and 5.5e-17, the same in both to two digits). Longer runs part further
/// because the motion does: a difference at round-off grows e-fold about every 0.04 s in 2D
/// (to 1.3e-5 m at 1 s) and every 0.1 s in 3D.
#[test]
fn bodies_as_junctions_match_the_bordered_solve() {
    use SolverKind::SparseLu;
    let (d3, b3, i3) = against_bordered(|| two_boxes::<3>(None), default_newton(), SparseLu, 50);
    let (d2, b2, i2) = against_bordered(|| two_boxes::<2>(None), default_newton(), SparseLu, 50);
    println!("3D: {d3:e} m, balance {b3:?}, {i3:?}; 2D: {d2:e} m, balance {b2:?}, {i2:?}");
    assert!(
        i3[0] == i3[1] && i2[0] == i2[1],
        "Newton iterations {i3:?} {i2:?}"
    );
    assert!(d3 < 1e-12 && d2 < 1e-12, "3D {d3:e} m, 2D {d2:e} m");
    for b in b3.iter().chain(&b2) {
        assert!(*b < 1e-13, "balance 3D {b3:?}, 2D {b2:?}");
    }
}

/// A body on a single string whose mesh is a chain: a 2 t box (3D) hangs, moving and
/// spinning, from a support by a 10 m wire rope of ten elements numbered along it. The default
/// solver is now the network solver with the body as a junction; against the bordered
/// block-tridiagonal solve, 200 steps of 2 ms: the same Newton iterations (measured 424),
/// the same positions to 1e-12 m (measured 1.3e-14 m), every step's balance exact in both
/// (measured 2.4e-17 of the step's energy scale).
#[test]
fn body_on_a_chain_matches_the_bordered_chain_solve() {
    let net = || {
        let mut nb = NetworkBuilder::<3, Material>::new();
        let mut prev = nb.node(Vector::<3>::zeros());
        let first = prev;
        for k in 1..=10 {
            let next = nb.node(Vector::<3>::new(0.0, 0.0, -(k as f64)));
            nb.string(rope(&format!("rope{k}")), &[prev, next], 1)
                .unwrap();
            prev = next;
        }
        let boundary = Boundary {
            fixed: vec![phstring::Fixed::node(first)],
            ..Default::default()
        };
        let mut net = nb.build(boundary, Vec::new()).unwrap();
        let s = Vector3::new(0.3, -0.2, 0.25);
        let q = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3);
        let centre = Vector3::new(0.0, 0.0, -10.0) - q.transform_vector(&s);
        let st = BodyState::new(
            centre,
            Vector3::new(0.5, -0.3, 0.0),
            q,
            Vector3::new(0.2, -0.4, 0.6),
        );
        let omega = q.transform_vector(&st.omega);
        net.initial.v[prev] = embed(&(st.velocity + omega.cross(&q.transform_vector(&s))));
        net.with_body(RigidBody {
            name: "box".into(),
            mass: 2000.0,
            inertia: box_inertia(2000.0),
            weight: Vector::<3>::new(0.0, 0.0, -2000.0 * 9.81),
            attachments: vec![Attachment {
                node: prev,
                point: embed(&s),
            }],
            initial: st,
            wrench: None,
            hydro: None,
            motion: None,
            feedback: None,
        })
    };
    assert!(net().mesh.is_chain());
    let auto = Simulation::new(net(), default_newton()).unwrap();
    assert_eq!(auto.solver_name(), "network");
    let (d, b, i) = against_bordered(net, default_newton(), SolverKind::BlockTridiagonal, 200);
    println!("chain: {d:e} m, balance {b:?}, {i:?}");
    assert_eq!(i[0], i[1], "Newton iterations");
    assert!(d < 1e-12, "{d:e} m");
    assert!(b[0] < 1e-13 && b[1] < 1e-13, "balance {b:?}");
}

/// The isotropic added-mass matrix `diag(C_a ρ_w V I, added inertia)` is the scalar `C_a`
/// with the added inertia: the rising buoy of [`buoy_rises_at_the_closed_form_terminal_speed`]
/// (`C_a` 0.5, i.e. 1025 kg, added inertia 50, 60, 70 kg·m², buoyancy off its axis so that
/// it turns) given either way runs the same bit for bit over 300 steps.
#[test]
fn isotropic_added_mass_matrix_is_the_scalar_added_mass() {
    use phstring::{BodyHydro, Mat6, Water};
    let run = |hydro: BodyHydro| {
        let net = buoy_on_pennant(
            Water::<3>::new(1025.0),
            (1000.0, 400.0),
            Vector3::new(0.0, 0.0, -100.0),
            (1.0, 2.0, 1.0),
            hydro,
        );
        let mut sim = Simulation::new(net, params()).unwrap();
        for _ in 0..300 {
            sim.step().unwrap();
        }
        sim.state().clone()
    };
    let base = BodyHydro {
        volume: 2.0,
        centre_of_buoyancy: Vector3::new(0.2, -0.1, 0.3),
        cda: 1.5,
        ..Default::default()
    };
    let scalar = run(BodyHydro {
        ca: 0.5,
        added_inertia: Vector3::new(50.0, 60.0, 70.0),
        ..base
    });
    let matrix = run(BodyHydro {
        added_mass: Some(Mat6::from_diagonal(&nalgebra::Vector6::new(
            1025.0, 1025.0, 1025.0, 50.0, 60.0, 70.0,
        ))),
        ..base
    });
    assert!(
        scalar.bodies[0].omega.norm() > 1e-3,
        "{:?}",
        scalar.bodies[0]
    );
    assert_eq!(scalar, matrix);
}

/// A 20 t buoy (5 m³, inertia 4e4 kg·m²) with a coupled added-mass matrix (surge 1.5e4,
/// sway 2.5e4, heave 4e3 kg, surge–pitch −6e3 and sway–roll 5e3 kg·m, moments 3e4, 2.5e4,
/// 1e4 kg·m²) on a 2 m pennant, its buoyancy off its axis, released from rest, 1000 steps of
/// 2 ms: it rises, drifts and turns, and every step's energy balance (its kinetic energy
/// `½ ξ·𝕄ξ` in `Ĥ`, the drag's dissipation) holds within 1e-13 of the energy scale, as
/// for the buoy with scalar added mass.
#[test]
fn coupled_added_mass_keeps_every_steps_balance() {
    use phstring::{BodyHydro, Mat6, Water};
    let mut a = Mat6::from_diagonal(&nalgebra::Vector6::new(1.5e4, 2.5e4, 4e3, 3e4, 2.5e4, 1e4));
    for (r, c, v) in [(0, 4, -6e3), (1, 3, 5e3)] {
        a[(r, c)] = v;
        a[(c, r)] = v;
    }
    let hydro = BodyHydro {
        volume: 25.0,
        centre_of_buoyancy: Vector3::new(0.3, -0.2, 0.5),
        cda: 3.0,
        added_mass: Some(a),
        ..Default::default()
    };
    let centre = Vector3::new(0.0, 0.0, -100.0);
    let net = buoy_on_pennant(
        Water::<3>::new(1025.0),
        (2e4, 4e4),
        centre,
        (50.0, 2.0, 1.0),
        hydro,
    );
    let mut sim = Simulation::new(net, params()).unwrap();
    let mut worst = 0.0f64;
    for _ in 0..1000 {
        let rep = sim.step().unwrap();
        worst = worst.max(rep.balance_error.abs() / rep.energy_scale);
    }
    let st = sim.state().bodies[0];
    eprintln!("coupled added mass: balance {worst:e} of the energy scale, {st:?}");
    assert!(
        st.position.z - centre.z > 0.5 && st.omega.norm() > 1e-2,
        "{st:?}"
    );
    assert!(worst < 1e-13, "balance error {worst:e} of the energy scale");
}

/// A 10 t body (20 t·m² about its centre) on four horizontal steel wires (EA 1e8 N,
/// 0.01 kg/m, 20 m, 1 % stretched), two from each of its points `(0, ±2 m)`, in the plane,
/// with a diagonal-plus-coupling added mass (surge 4e3 kg, sway 9e3 kg, yaw 6e3 kg·m², and
/// the surge–yaw coupling 3e3 kg·m): its three lowest modes (`modes::modes_with_bodies`)
/// have the frequencies of the rigid body with `𝕄 = M_RB + A` on the springs of its mooring
/// stiffness `K` (`statics::body_stiffness`): the sway `√(K_yy/𝕄_yy)`, and the coupled
/// surge–yaw pair, the roots of the 2-DOF `det(K − ω² 𝕄) = 0`, to 1e-4 (the wires' 0.8 kg
/// that the rigid model leaves out; measured 6.9e-6, 9.2e-6, 2.1e-5). Without the coupling the pair splits into
/// `√(K_xx/𝕄_xx)` and `√(K_θθ/𝕄_θθ)`, which the coupled modes miss by more than 1e-2.
#[test]
fn body_modes_use_the_full_added_mass_matrix() {
    use phstring::{BodyHydro, Mat6, Water};
    let (m, j, d, l) = (1e4, 2e4, 2.0, 20.0);
    let (axx, ayy, att, axt) = (4e3, 9e3, 6e3, 3e3);
    let mut nb = NetworkBuilder::<2, Material>::new();
    let spec = StringSpec {
        name: "wire".into(),
        material: Material::linear_elastic(1e8),
        rho_a: 0.01,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::zeros(),
        prestretch: 1.01,
    };
    let mut fixed = Boundary::default();
    let mut attachments = Vec::new();
    for y in [d, -d] {
        let p = nb.node(Vector::<2>::new(0.0, y));
        attachments.push(Attachment {
            node: p,
            point: Vector::<2>::new(0.0, y),
        });
        for x in [-l, l] {
            let a = nb.node(Vector::<2>::new(x, y));
            fixed.fixed.push(phstring::Fixed::node(a));
            nb.string(spec.clone(), &[a, p], 4).unwrap();
        }
    }
    let mut a = Mat6::zeros();
    for (r, c, v) in [
        (0, 0, axx),
        (1, 1, ayy),
        (5, 5, att),
        (0, 5, axt),
        (5, 0, axt),
    ] {
        a[(r, c)] = v;
    }
    let body = RigidBody {
        name: "block".into(),
        mass: m,
        inertia: nalgebra::Matrix3::from_diagonal_element(j),
        weight: Vector::<2>::zeros(),
        attachments,
        initial: BodyState::at_rest(Vector3::zeros(), UnitQuaternion::identity()),
        wrench: None,
        hydro: Some(BodyHydro {
            added_mass: Some(a),
            ..Default::default()
        }),
        motion: None,
        feedback: None,
    };
    let net = nb
        .build(fixed, Vec::new())
        .unwrap()
        .with_water(Water::<2>::new(1025.0))
        .with_body(body);
    let (sys, start) = phstring::PhSystem::new(net).unwrap();
    let params = phstring::statics::StaticsParams::default();
    let eq = phstring::statics::solve_system(&sys, &start.r, &params, None).unwrap();
    let k = phstring::statics::body_stiffness(&sys, &eq, 0, &params)
        .unwrap()
        .matrix;
    let found =
        phstring::modes::modes_with_bodies(&sys, &eq.state.r, &eq.state.bodies, 3, None).unwrap();
    // Rows and columns (x, y, θ).
    let (kx, ky, kt, kxt) = (k[(0, 0)], k[(1, 1)], k[(2, 2)], k[(0, 2)]);
    assert!(k[(0, 1)].abs() + k[(1, 2)].abs() < 1e-9 * ky, "{k}");
    let (mx, my, mt) = (m + axx, m + ayy, j + att);
    // (M_x M_θ − c²) λ² − (k_x M_θ + k_θ M_x − 2 k_xθ c) λ + (k_x k_θ − k_xθ²) = 0.
    let qa = mx * mt - axt * axt;
    let qb = kx * mt + kt * mx - 2.0 * kxt * axt;
    let qc = kx * kt - kxt * kxt;
    let disc = (qb * qb - 4.0 * qa * qc).sqrt();
    let mut want = [
        (ky / my).sqrt(),
        ((qb - disc) / (2.0 * qa)).sqrt(),
        ((qb + disc) / (2.0 * qa)).sqrt(),
    ];
    want.sort_by(f64::total_cmp);
    for (mode, omega) in found.modes.iter().zip(want) {
        let rel = (mode.omega / omega - 1.0).abs();
        eprintln!(
            "added-mass mode: {} rad/s against {omega}: {rel:.2e}",
            mode.omega
        );
        assert!(rel < 1e-4, "{} rad/s against {omega}", mode.omega);
    }
    let uncoupled = [(kx / mx).sqrt(), (kt / mt).sqrt()];
    for u in uncoupled {
        let nearest = found
            .modes
            .iter()
            .map(|md| (md.omega / u - 1.0).abs())
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest > 1e-2,
            "uncoupled {u} rad/s is a mode ({nearest:.1e})"
        );
    }
}
