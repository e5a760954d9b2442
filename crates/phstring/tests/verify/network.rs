//! Networks: several strings joined at shared nodes, springs, point
//! masses and a moving support in one system. Checks: the discrete energy balance of the
//! whole network on every step, momentum and angular momentum of a free network, and the
//! momentum balance through the support ports.

use crate::common::energy_scale;
use phstring::testing::platform;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, NetworkBuilder, PointMass, SetupError, Simulation,
    StepParams, StringSpec, Vector,
};

/// Energy balance of every step to round-off of the energy scale; momentum change equals the
/// impulse of gravity and of the support reactions to the Newton tolerance.
#[test]
fn platform_network_balances_energy_and_momentum_through_its_ports() {
    let (net, platform_node) = platform();
    let n_nodes = net.mesh.n_nodes();
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 2e-3,
            ..StepParams::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sim.system().groups().len(), 6);
    let f_body: Vector<3> = sim.system().body_force_vector().iter().sum();
    let p0 = sim.system().linear_momentum(sim.state());
    let (mut impulse, mut slack, mut worst, mut supplied) =
        (Vector::<3>::zeros(), 0.0, 0.0_f64, 0.0);
    let mut z_min = f64::INFINITY;
    for _ in 0..750 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let reactions: Vector<3> = sim.ports().iter().map(|p| p.output).sum();
        impulse += (f_body + reactions) * r.h;
        // Each free node's residual is at most ‖R‖: the momentum balance holds to that.
        slack += r.h * r.residual * (n_nodes as f64).sqrt();
        let scale = energy_scale(&r.before).max(energy_scale(&r.after));
        worst = worst.max(r.balance_error.abs() / scale);
        supplied += r.supplied;
        z_min = z_min.min(sim.state().r[platform_node][2]);
    }
    // The platform fell and was caught by the cables: their vertical stiffness
    // 4 EA cos²θ / L ≈ 9.5e6 N/m under 14.7 kN gives 1.5 mm static, twice that dynamic.
    println!("platform: lowest z {z_min:.4e} m");
    assert!(
        z_min < -0.002 && z_min > -0.004,
        "lowest platform z {z_min}"
    );
    assert!(
        worst <= 1e-13,
        "energy balance error {worst:e} of the energy scale"
    );
    assert!(
        supplied.abs() > 1.0,
        "the heaving corner supplies work: {supplied} J"
    );
    let dp = sim.system().linear_momentum(sim.state()) - p0;
    let err = (dp - impulse).norm();
    let p_scale = impulse.norm().max(f_body.norm() * sim.time());
    println!(
        "platform: energy balance {worst:.2e} of scale, momentum error {err:.3e} N·s \
         (Newton bound {slack:.3e}, impulse scale {p_scale:.3e}), supplied {supplied:.3} J"
    );
    assert!(
        err <= slack + 1e-12 * p_scale,
        "momentum balance: |Δp − impulse| = {err:e} N·s, bound {slack:e}"
    );
}

/// A free network (no supports, no gravity): a triangle of three strings of different laws
/// joined at its corners, a spring across it, a point mass, spinning and flying. Linear and
/// angular momentum are conserved to round-off.
#[test]
fn free_network_conserves_linear_and_angular_momentum() {
    let mut b = NetworkBuilder::<3, Material>::new();
    let c: Vec<usize> = [(0.0, 0.0, 0.0), (30.0, 0.0, 5.0), (10.0, 25.0, -3.0)]
        .iter()
        .map(|&(x, y, z)| b.node(Vector::<3>::new(x, y, z)))
        .collect();
    let laws = [
        Material::linear_elastic(1e6),
        Material::hyperelastic(5e5),
        Material::st_venant_kirchhoff(2e6),
    ];
    for (k, law) in laws.into_iter().enumerate() {
        b.string(
            StringSpec {
                name: format!("side{k}"),
                material: law,
                rho_a: 0.5 + k as f64,
                mass: if k == 1 {
                    MassMatrix::Lumped
                } else {
                    MassMatrix::Consistent
                },
                body_force: Vector::zeros(),
                prestretch: 1.01,
            },
            &[c[k], c[(k + 1) % 3]],
            9,
        )
        .unwrap();
    }
    let mid = b.group_nodes(0).unwrap()[4];
    b.spring("brace", mid, c[2], 1e4, 20.0).unwrap();
    let mut net = b
        .build(
            Boundary::default(),
            vec![PointMass {
                node: c[1],
                mass: 40.0,
                weight: Vector::zeros(),
            }],
        )
        .unwrap();
    // Spin about an axis through (10, 8, 0) plus a drift, and a transverse wiggle.
    let omega = Vector::<3>::new(0.1, -0.2, 0.5);
    for (i, (r, v)) in net.initial.r.iter().zip(&mut net.initial.v).enumerate() {
        *v = omega.cross(&(r - Vector::<3>::new(10.0, 8.0, 0.0)))
            + Vector::<3>::new(1.0, 0.5, -0.2)
            + Vector::<3>::new(0.0, 0.0, (i as f64 * 0.7).sin());
    }
    let mut sim = Simulation::new(net, {
        let mut p = StepParams {
            h: 5e-3,
            ..StepParams::default()
        };
        // The drifts are bounded by the Newton residual, h Σ|R| per step: with the default
        // rtol = 1e-12 this fast spin shows 1.8e-13 (angular momentum) and 2.8e-12 (energy);
        // 1e-14 shows the conservation of the scheme itself.
        p.newton.rtol = 1e-14;
        p
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let (p0, l0) = (
        sim.system().linear_momentum(sim.state()),
        sim.system().angular_momentum(sim.state()),
    );
    let (mut dp, mut dl, mut de) = (0.0_f64, 0.0_f64, 0.0_f64);
    for _ in 0..400 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let (p, l) = (
            sim.system().linear_momentum(sim.state()),
            sim.system().angular_momentum(sim.state()),
        );
        dp = dp.max((p - p0).norm() / p0.norm());
        dl = dl.max((l - l0).norm() / l0.norm());
        de = de.max(r.balance_error.abs() / energy_scale(&r.after));
    }
    println!("free network: momentum {dp:.2e}, angular momentum {dl:.2e}, energy {de:.2e}");
    assert!(dp <= 1e-13, "linear momentum drift {dp:e}");
    assert!(dl <= 1e-13, "angular momentum drift {dl:e}");
    assert!(de <= 1e-13, "energy balance {de:e}");
}

/// Setup errors name what is wrong: a free node with only springs, groups that do not
/// cover the elements, a massive spring.
#[test]
fn network_setup_errors_name_the_cause() {
    let mut b = NetworkBuilder::<2, Material>::new();
    let a = b.node(Vector::<2>::new(0.0, 0.0));
    let c = b.node(Vector::<2>::new(1.0, 0.0));
    b.spring("s", a, c, 10.0, 0.0).unwrap();
    let net = b
        .clone()
        .build(
            Boundary {
                fixed: vec![Fixed::node(a)],
                ..Boundary::default()
            },
            vec![],
        )
        .unwrap();
    let err = Simulation::new(net, StepParams::default()).err().unwrap();
    assert_eq!(err, SetupError::MasslessNode { node: c });
    let mut net = b.clone().build(Boundary::default(), vec![]).unwrap();
    net.groups[0].rho_a = 1.0;
    assert!(matches!(
        Simulation::new(net, StepParams::default()).err().unwrap(),
        SetupError::MassiveSpring { group: 0, .. }
    ));
    let mut net = b.build(Boundary::default(), vec![]).unwrap();
    net.groups.clear();
    assert!(matches!(
        Simulation::new(net, StepParams::default()).err().unwrap(),
        SetupError::GroupCoverage { expected: 0, .. }
    ));
    let mut b = NetworkBuilder::<2, Material>::new();
    let a = b.node(Vector::<2>::new(0.0, 0.0));
    assert!(matches!(
        b.spring("self", a, a, 1.0, 0.0),
        Err(SetupError::DegenerateElement { .. })
    ));
}

/// The network solver and the general sparse LU give the same trajectory of the platform
/// network (the linear solves differ only by round-off, so the Newton iterates agree to the
/// tolerance).
#[test]
fn network_solver_and_sparse_lu_give_the_same_trajectory() {
    use phstring::SolverKind;
    let run = |solver: SolverKind| {
        let (net, _) = platform();
        let mut sim = Simulation::new(
            net,
            StepParams {
                h: 2e-3,
                solver,
                ..StepParams::default()
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let mut its = 0;
        for _ in 0..100 {
            its += sim
                .step()
                .unwrap_or_else(|e| panic!("{e}"))
                .newton_iterations;
        }
        (sim.solver_name(), sim.state().clone(), its)
    };
    let (name_a, a, its_a) = run(SolverKind::Auto);
    let (name_b, b, its_b) = run(SolverKind::SparseLu);
    assert_eq!((name_a, name_b), ("network", "sparse_lu"));
    let dr =
        a.r.iter()
            .zip(&b.r)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, f64::max);
    let dv =
        a.v.iter()
            .zip(&b.v)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, f64::max);
    println!(
        "network vs sparse LU: max |Δr| {dr:.2e} m, |Δv| {dv:.2e} m/s, iterations {its_a} vs {its_b}"
    );
    assert!(
        dr <= 1e-11 && dv <= 1e-8,
        "trajectories differ: {dr:e} m, {dv:e} m/s"
    );
}

/// A refused string leaves the builder as it was; a zero-rest-length spring whose ends start
/// at the same point runs with the midpoint rule too (its `W''` is 0, not 0/0).
#[test]
fn refused_strings_leave_the_builder_alone_and_zero_length_springs_step() {
    use phstring::Scheme;
    let spec = |name: &str| StringSpec {
        name: name.into(),
        material: Material::tension_only_linear(1e6),
        rho_a: 1.0,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -9.81),
        prestretch: 1.0,
    };
    let mut b = NetworkBuilder::<2, Material>::new();
    let n0 = b.node(Vector::<2>::new(0.0, 0.0));
    let n1 = b.node(Vector::<2>::new(0.0, -5.0));
    let n2 = b.node(Vector::<2>::new(0.0, -5.0));
    for bad in [&[n0, n1, n1][..], &[n0, n1, n2][..]] {
        assert!(b.clone().string(spec("bad"), bad, 2).is_err());
        let mut probe = b.clone();
        assert!(probe.string(spec("bad"), bad, 2).is_err());
        assert_eq!(probe.n_nodes(), 3, "a refused string added nodes");
    }
    b.string(spec("rope"), &[n0, n1], 10).unwrap();
    // n2 coincides with the rope's end: a zero-length spring at rest length 0 ties them.
    b.spring("tie", n1, n2, 1e5, 0.0).unwrap();
    let net = b
        .build(
            Boundary {
                fixed: vec![Fixed::node(n0)],
                ..Boundary::default()
            },
            vec![PointMass {
                node: n2,
                mass: 100.0,
                weight: Vector::<2>::new(0.0, -981.0),
            }],
        )
        .unwrap();
    for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
        let mut sim = Simulation::new(
            net.clone(),
            StepParams {
                h: 1e-3,
                scheme,
                ..StepParams::default()
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..50 {
            sim.step().unwrap_or_else(|e| panic!("{scheme:?}: {e}"));
        }
        // The mass hangs on the spring below the rope's end: 981 N / 1e5 N/m ≈ 1 cm at rest.
        let gap = (sim.state().r[n2] - sim.state().r[n1]).norm();
        assert!(gap > 1e-4 && gap < 0.03, "{scheme:?}: spring length {gap}");
    }
}

/// A spring so stiff that the residual's norm overflows (its entries are finite) fails with a
/// message that says so and names the node with the largest residual, not node 0.
#[test]
fn overflowing_residual_norm_names_its_node() {
    let mut b = NetworkBuilder::<2, Material>::new();
    let top = b.node(Vector::<2>::new(0.0, 0.0));
    let end = b.node(Vector::<2>::new(0.0, -10.0));
    b.string(
        StringSpec {
            name: "rope".into(),
            material: Material::tension_only_linear(1e7),
            rho_a: 1.0,
            mass: MassMatrix::Consistent,
            body_force: Vector::<2>::new(0.0, -9.81),
            prestretch: 1.0,
        },
        &[top, end],
        4,
    )
    .unwrap();
    b.spring_to_point("stiff", end, Vector::<2>::new(1.0, -10.0), 1e160, 0.5)
        .unwrap();
    let net = b
        .build(
            Boundary {
                fixed: vec![Fixed::node(top)],
                ..Boundary::default()
            },
            vec![],
        )
        .unwrap();
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 1e-3,
            ..StepParams::default()
        },
    )
    .unwrap();
    let err = sim.step().unwrap_err().to_string();
    println!("{err}");
    assert!(
        err.contains("overflows") && err.contains(&format!("node {end}")),
        "{err}"
    );
}
