//! Dissipation and feedback (docs/method.md §18): the exact balance with each dissipation kind,
//! `D_n ≥ 0`, the decay rate of a Kelvin–Voigt string against linear theory, momentum with
//! internal damping, and passivity of damping injection.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use phstring::benchmarks::{paper_load, paper_params, paper_pendulum};
use phstring::{
    Boundary, Damping, FeedbackLoad, Fixed, MassMatrix, Material, Mesh, Network, NetworkBuilder,
    NodalLoad, PdLaw, Problem, Simulation, State, StepParams, StepReport, StoredEnergy, StringSpec,
    Vector,
};

/// Runs `sim` for `steps` steps, returning the reports.
fn run<const D: usize>(sim: &mut Simulation<D, Material>, steps: usize) -> Vec<StepReport> {
    (0..steps)
        .map(|_| sim.step().expect("step converges"))
        .collect()
}

/// The paper pendulum (N = 30, h = 0.01 s, the paper's Newton tolerance) as a network with
/// the damping `damping` on the string.
fn damped_paper(damping: Damping) -> Network<2, Material> {
    let mut net: Network<2, Material> = paper_pendulum(30).into();
    net.groups[0].damping = damping;
    net
}

/// The paper pendulum built as a network with a dashpot (`k = 0`) from its tip to a fixed
/// point and one from its middle to its tip, both `c` [N·s/m].
fn paper_with_dashpots(c: f64) -> Network<2, Material> {
    let mut b = NetworkBuilder::<2, Material>::new();
    let top = b.node(Vector::<2>::zeros());
    let tip = b.node(Vector::<2>::new(FRAC_1_SQRT_2, -FRAC_1_SQRT_2));
    let spec = StringSpec {
        name: "pendulum".into(),
        material: Material::hyperelastic(20.0),
        rho_a: 1.0,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -9.81),
        prestretch: 1.0,
    };
    b.string(spec, &[top, tip], 30).unwrap();
    let middle = b.group_nodes(0).unwrap()[15];
    let dashpot = Damping {
        dashpot: c,
        ..Damping::NONE
    };
    let g = b
        .spring_to_point("ground", tip, Vector::<2>::new(1.0, -1.0), 0.0, 0.0)
        .unwrap();
    b.set_damping(g, dashpot).unwrap();
    let g = b.spring("across", middle, tip, 0.0, 0.0).unwrap();
    b.set_damping(g, dashpot).unwrap();
    let boundary = Boundary {
        fixed: vec![Fixed::node(top)],
        loads: vec![NodalLoad::new(tip, |t| paper_load(1.0, t))],
        motions: vec![],
        feedback: vec![],
    };
    b.build(boundary, vec![]).unwrap()
}

/// Checks every step of `reports`: `|balance| ≤ 1e-11 J`, `D_n ≥ 0`, and `D_n > 0` in most
/// steps (the damping acts). Returns the total dissipated energy.
fn check_balance(what: &str, reports: &[StepReport]) -> f64 {
    let mut positive = 0;
    for r in reports {
        assert!(
            r.balance_error.abs() <= 1e-11,
            "{what}: step {} balance error {:e} J",
            r.step,
            r.balance_error
        );
        assert!(
            r.dissipated >= 0.0,
            "{what}: step {} D_n = {:e} J",
            r.step,
            r.dissipated
        );
        positive += usize::from(r.dissipated > 0.0);
    }
    assert!(
        positive * 10 >= reports.len() * 9,
        "{what}: D_n > 0 in {positive} steps"
    );
    reports.iter().map(|r| r.dissipated).sum()
}

/// The paper benchmark (1 s) with each dissipation kind, and with damping injection at the
/// tip: the balance `Ĥ_{n+1} − Ĥ_n = h û·ŷ − D_n` within 1e-11 J on every step, `D_n ≥ 0`,
/// and the cumulative dissipated energy equal to `Σ D_n`.
#[test]
fn balance_with_each_dissipation_kind() {
    let kinds = [
        (
            "Kelvin-Voigt",
            damped_paper(Damping {
                kelvin_voigt: 0.05,
                ..Damping::NONE
            }),
        ),
        (
            "drag",
            damped_paper(Damping {
                drag: 0.5,
                ..Damping::NONE
            }),
        ),
        ("dashpots", paper_with_dashpots(0.5)),
    ];
    for (what, net) in kinds {
        let mut sim = Simulation::new(net, paper_params()).unwrap();
        let reports = run(&mut sim, 100);
        let total = check_balance(what, &reports);
        assert!(total > 1e-3, "{what}: dissipated only {total:e} J");
        assert_eq!(sim.dissipated_energy(), {
            let mut s = 0.0;
            for r in &reports {
                s += r.dissipated;
            }
            s
        });
    }
}

/// Damping injection `u = −K_d y` at the tip of the paper pendulum: the port's supplied
/// energy `h u·y` is ≤ 0 on every step, after the load `Ĥ` never increases (beyond the
/// balance's round-off), and the balance is exact.
#[test]
fn damping_injection_is_passive_on_every_step() {
    let mut net: Network<2, Material> = paper_pendulum(30).into();
    net.boundary
        .feedback
        .push(FeedbackLoad::new(30, PdLaw::<2>::damping_injection(0.8)));
    let mut sim = Simulation::new(net, paper_params()).unwrap();
    let mut removed = 0.0;
    for _ in 0..300 {
        let before = sim.energies().hamiltonian();
        let r = sim.step().unwrap();
        // Ports: the load first, then the feedback port.
        let port = sim.ports()[1];
        assert_eq!(port.node, 30);
        let supplied = r.h * port.power();
        assert!(
            supplied <= 0.0,
            "step {}: the controller supplied {supplied:e} J",
            r.step
        );
        removed -= supplied;
        assert!(
            r.balance_error.abs() <= 1e-11,
            "step {}: {:e}",
            r.step,
            r.balance_error
        );
        assert_eq!(r.dissipated, 0.0);
        if r.t > 0.2 + 1e-9 {
            let rise = sim.energies().hamiltonian() - before;
            assert!(rise <= 1e-12, "step {}: Ĥ rose by {rise:e} J", r.step);
        }
    }
    assert!(removed > 0.1, "the controller removed only {removed:e} J");
}

/// A 1D taut steel wire (L = 10 m, EA = 1e7 N, ρA = 0.55 kg/m, stretched by 1e-3, fixed at
/// both ends) with Kelvin–Voigt damping, started in its first axial mode at small amplitude.
///
/// Linear theory (docs/method.md §18): about the stretch `λ`, the axial displacement `u`
/// obeys `ρA ü = k u'' + c u̇''` with `k = S₀ + 4λ²W''(λ²)` and `c = 2λ²η`; the discrete
/// system is `M q̈ + c K q̇ + k K q = 0` with the same stiffness pattern `K`, so the first
/// mode decays at `σ_h = c ω_h² / (2k)` (`ω_h` its frequency on the mesh), and the continuum
/// at `σ = c (π/L)² / (2ρA)`. The midpoint form of the step (which the DG step is for a
/// linear system) maps each mode by `z = (1 + hs/2)/(1 − hs/2)`, `s = −σ_h + i√(ω_h² − σ_h²)`:
/// the run decays at `−ln|z| / h`.
///
/// The run's decay rate, from a least-squares fit of the modal coordinate's two-step
/// recurrence `q_{n+1} = a q_n − |z|² q_{n−1}`, matches the fully discrete theory to 1e-6
/// and the continuum to 1 % (the discretization error with 40 elements and 200 steps per
/// period: about 0.2 %).
#[test]
fn kelvin_voigt_decay_rate_matches_linear_theory() {
    let (length, ea, rho_a, eta, n_el) = (10.0, 1.0e7, 0.55, 150.0, 40);
    let stretch: f64 = 1.001;
    let amplitude = 1e-6 * length;
    let law = Material::linear_elastic(ea);
    let mesh = Mesh::uniform_chain(n_el, length).unwrap();
    let l = length / n_el as f64;
    let s_of = |i: usize| i as f64 * l;
    let r: Vec<Vector<1>> = (0..=n_el)
        .map(|i| Vector::<1>::new(stretch * s_of(i) + amplitude * (PI * s_of(i) / length).sin()))
        .collect();
    let initial = State::at_rest(&mesh, r.clone());
    let problem = Problem {
        mesh,
        initial,
        material: law,
        rho_a,
        body_force: Vector::zeros(),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            fixed: vec![Fixed::node(0), Fixed::node(n_el)],
            ..Default::default()
        },
        point_masses: vec![],
    };
    let mut net: Network<1, Material> = problem.into();
    net.groups[0].damping = Damping {
        kelvin_voigt: eta,
        ..Damping::NONE
    };
    // Linear theory.
    let c0 = stretch * stretch;
    let k = 2.0 * law.dw(c0) + 4.0 * c0 * law.d2w(c0);
    let c = 2.0 * c0 * eta;
    let kappa = PI / length;
    let theta = PI / n_el as f64;
    // First eigenvalue of K q = ω² M q/k·ρA for linear elements with consistent mass.
    let omega_h2 = k / rho_a * 6.0 / (l * l) * (1.0 - theta.cos()) / (2.0 + theta.cos());
    let sigma_h = c * omega_h2 / (2.0 * k);
    let sigma_continuum = c * kappa * kappa / (2.0 * rho_a);
    let period = 2.0 * PI / omega_h2.sqrt();
    let h = period / 200.0;
    let s = num_complex(-sigma_h, (omega_h2 - sigma_h * sigma_h).sqrt());
    let z = cdiv(
        cadd((1.0, 0.0), cscale(s, 0.5 * h)),
        cadd((1.0, 0.0), cscale(s, -0.5 * h)),
    );
    let sigma_discrete = -cabs(z).ln() / h;

    let params = StepParams {
        h,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    // Modal coordinate: projection on the sampled sine (the exact discrete mode shape).
    let shape: Vec<f64> = (0..=n_el).map(|i| (PI * s_of(i) / length).sin()).collect();
    let norm2: f64 = shape.iter().map(|x| x * x).sum();
    let modal = |sim: &Simulation<1, Material>| -> f64 {
        (0..=n_el)
            .map(|i| (sim.state().r[i][0] - stretch * s_of(i)) * shape[i])
            .sum::<f64>()
            / norm2
    };
    let mut q = vec![modal(&sim)];
    // Five periods.
    for _ in 0..1000 {
        let rep = sim.step().unwrap();
        assert!(rep.dissipated >= 0.0);
        assert!(rep.balance_error.abs() <= 1e-12 * rep.before.hamiltonian().abs().max(1e-3));
        q.push(modal(&sim));
    }
    // Least squares for (a, b) in q_{n+1} = a q_n + b q_{n−1}; b = −|z|².
    let (mut s11, mut s12, mut s22, mut r1, mut r2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for w in q.windows(3) {
        let (x1, x2, y) = (w[1], w[0], w[2]);
        s11 += x1 * x1;
        s12 += x1 * x2;
        s22 += x2 * x2;
        r1 += x1 * y;
        r2 += x2 * y;
    }
    let det = s11 * s22 - s12 * s12;
    let b = (s11 * r2 - s12 * r1) / det;
    let sigma_run = -(-b).ln() / (2.0 * h);
    let decay_over_run = (-sigma_run * 1000.0 * h).exp();
    eprintln!(
        "Kelvin-Voigt decay: run {sigma_run:.8} 1/s, discrete theory {sigma_discrete:.8} 1/s, semi-discrete {sigma_h:.8} 1/s, continuum {sigma_continuum:.8} 1/s; amplitude after the run {decay_over_run:.4}"
    );
    assert!(
        (0.05..0.9).contains(&decay_over_run),
        "the test should see a clear decay: {decay_over_run}"
    );
    assert!(
        ((sigma_run - sigma_discrete) / sigma_discrete).abs() <= 1e-6,
        "run {sigma_run} vs discrete theory {sigma_discrete}"
    );
    assert!(
        ((sigma_run - sigma_continuum) / sigma_continuum).abs() <= 1e-2,
        "run {sigma_run} vs continuum {sigma_continuum}"
    );
}

// Complex numbers as pairs, for the amplification factor.
fn num_complex(re: f64, im: f64) -> (f64, f64) {
    (re, im)
}
fn cadd(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 + b.0, a.1 + b.1)
}
fn cscale(a: (f64, f64), x: f64) -> (f64, f64) {
    (a.0 * x, a.1 * x)
}
fn cdiv(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}
fn cabs(a: (f64, f64)) -> f64 {
    a.0.hypot(a.1)
}

/// A free string in 3D (no support, no gravity), stretched and spinning, with Kelvin–Voigt
/// damping and two dashpots between its nodes: linear momentum stays at its initial value
/// to round-off (internal forces come in equal and opposite pairs), while energy is
/// dissipated; with Kelvin–Voigt alone (forces along the element), angular momentum too.
#[test]
fn internal_damping_keeps_momentum() {
    for with_dashpots in [false, true] {
        let mut b = NetworkBuilder::<3, Material>::new();
        let a = b.node(Vector::<3>::new(-0.65, 0.0, 0.0));
        let e = b.node(Vector::<3>::new(0.65, 0.0, 0.0));
        let spec = StringSpec {
            name: "free".into(),
            material: Material::hyperelastic(20.0),
            rho_a: 1.0,
            mass: MassMatrix::Consistent,
            body_force: Vector::zeros(),
            prestretch: 1.3,
        };
        let g = b.string(spec, &[a, e], 12).unwrap();
        b.set_damping(
            g,
            Damping {
                kelvin_voigt: 0.3,
                ..Damping::NONE
            },
        )
        .unwrap();
        if with_dashpots {
            let nodes = b.group_nodes(g).unwrap().to_vec();
            let dashpot = Damping {
                dashpot: 2.0,
                ..Damping::NONE
            };
            let d1 = b.spring("d1", nodes[2], nodes[9], 0.0, 0.0).unwrap();
            b.set_damping(d1, dashpot).unwrap();
            let d2 = b.spring("d2", nodes[0], nodes[12], 0.0, 0.0).unwrap();
            b.set_damping(d2, dashpot).unwrap();
        }
        let mut net = b.build(Boundary::default(), vec![]).unwrap();
        for (r, v) in net.initial.r.iter().zip(net.initial.v.iter_mut()) {
            // Spin about z, stretching, tumbling and drift.
            *v = Vector::<3>::new(-2.5 * r[0] - 8.0 * r[1], 8.0 * r[0], 1.0 * r[0] + 0.2);
        }
        let params = StepParams {
            h: 0.01,
            ..Default::default()
        };
        let mut sim = Simulation::new(net, params).unwrap();
        let p0 = sim.system().linear_momentum(sim.state());
        let l0 = sim.system().angular_momentum(sim.state());
        let (mut dp, mut dl, mut dissipated) = (0.0_f64, 0.0_f64, 0.0);
        for _ in 0..200 {
            let r = sim.step().unwrap();
            assert!(r.dissipated >= 0.0);
            assert!(r.balance_error.abs() <= 1e-11, "{:e}", r.balance_error);
            dissipated += r.dissipated;
            dp = dp.max((sim.system().linear_momentum(sim.state()) - p0).norm());
            dl = dl.max((sim.system().angular_momentum(sim.state()) - l0).norm());
        }
        eprintln!(
            "free string, dashpots {with_dashpots}: |Δp| ≤ {dp:.2e}, |ΔL| ≤ {dl:.2e}, dissipated {dissipated:.4} J, |p0| {:.3}, |L0| {:.3}",
            p0.norm(),
            l0.norm()
        );
        assert!(dissipated > 0.1, "{dissipated}");
        assert!(
            dp <= 1e-12 * p0.norm().max(1.0),
            "linear momentum drifts by {dp:e}"
        );
        if !with_dashpots {
            assert!(dl <= 1e-12 * l0.norm(), "angular momentum drifts by {dl:e}");
        }
    }
}
