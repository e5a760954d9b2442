//! The paper's benchmark (docs/method.md §12).

use phstring::benchmarks::{PAPER_H0, PAPER_H1_DG, PAPER_H1_MP, paper_params, paper_pendulum};
use phstring::{Scheme, Simulation, SolverKind, StepParams};

use crate::common::run_paper;

const END_OF_LOADING: f64 = 0.2;

#[test]
fn paper_dg_values_energy_balance_and_kinematics() {
    let (sim, h0, reports) = run_paper(Scheme::DiscreteGradient);
    let h1 = sim.energies().hamiltonian();
    assert!((h0 - PAPER_H0).abs() <= 1e-6, "H(0) = {h0}");
    assert!(
        (h1 - PAPER_H1_DG).abs() <= 1e-6,
        "H(1) = {h1}, paper {PAPER_H1_DG}"
    );
    let mut max_inc = 0.0_f64;
    let mut max_balance = 0.0_f64;
    for r in &reports {
        let inc = r.after.hamiltonian() - r.before.hamiltonian();
        if r.t > END_OF_LOADING + 1e-9 {
            max_inc = max_inc.max(inc.abs());
            assert!(
                inc.abs() <= 1e-11,
                "step {}: |ΔH| = {:e}",
                r.step,
                inc.abs()
            );
        } else {
            max_balance = max_balance.max(r.balance_error.abs());
            assert!(
                r.balance_error.abs() <= 1e-11,
                "step {}: balance {:e}",
                r.step,
                r.balance_error
            );
        }
    }
    eprintln!(
        "DG: H(0) = {h0:.9}, H(1) = {h1:.9}, max |ΔH| after loading {max_inc:.2e}, max balance error during loading {max_balance:.2e}"
    );
}

#[test]
fn paper_mp_values_and_energy_drift() {
    let (sim, h0, reports) = run_paper(Scheme::Midpoint);
    let h1 = sim.energies().hamiltonian();
    assert!((h0 - PAPER_H0).abs() <= 1e-6, "H(0) = {h0}");
    assert!(
        (h1 - PAPER_H1_MP).abs() <= 1e-6,
        "H(1) = {h1}, paper {PAPER_H1_MP}"
    );
    let incs: Vec<f64> = reports
        .iter()
        .filter(|r| r.t > END_OF_LOADING + 1e-9)
        .map(|r| (r.after.hamiltonian() - r.before.hamiltonian()).abs())
        .collect();
    let min = incs.iter().copied().fold(f64::INFINITY, f64::min);
    let max = incs.iter().copied().fold(0.0, f64::max);
    eprintln!("MP: H(1) = {h1:.9}, increments after loading in [{min:.2e}, {max:.2e}]");
    assert!(min >= 1e-8, "smallest MP increment after loading {min:e}");
}

#[test]
fn remark5_kinematic_relation_holds_over_the_run() {
    for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
        let params = StepParams {
            scheme,
            ..paper_params()
        };
        let mut sim = Simulation::new(paper_pendulum(30), params).unwrap();
        let mut worst = sim.state().kinematic_defect(sim.system().mesh());
        for _ in 0..100 {
            sim.step().unwrap();
            worst = worst.max(sim.state().kinematic_defect(sim.system().mesh()));
        }
        eprintln!("{scheme:?}: max |C − |r'|²| = {worst:.2e}");
        assert!(worst <= 1e-12, "{scheme:?}: kinematic defect {worst:e}");
    }
}

/// Newton work is part of the contract: 3–4 iterations per step with the `h v_n` predictor,
/// 3–5 with the default mid-step-velocity one; exact totals pinned so that a change that
/// silently adds iterations fails.
#[test]
fn paper_newton_iteration_counts() {
    use phstring::Predictor::{MidpointVelocity, Velocity};
    for (predictor, scheme, total, most) in [
        (Velocity, Scheme::DiscreteGradient, 347, 4),
        (Velocity, Scheme::Midpoint, 338, 4),
        (MidpointVelocity, Scheme::DiscreteGradient, 380, 5),
        (MidpointVelocity, Scheme::Midpoint, 374, 5),
    ] {
        let params = StepParams {
            scheme,
            predictor,
            ..paper_params()
        };
        let mut sim = Simulation::new(paper_pendulum(30), params).unwrap();
        for _ in 0..100 {
            let r = sim.step().unwrap();
            assert!(
                (3..=most).contains(&r.newton_iterations),
                "{predictor:?}, {scheme:?}: {} iterations in step {}",
                r.newton_iterations,
                r.step
            );
        }
        assert_eq!(
            sim.total_newton_iterations(),
            total,
            "{predictor:?}, {scheme:?}"
        );
    }
}

/// The sparse LU path gives the same trajectory as the block-tridiagonal one.
#[test]
fn paper_sparse_lu_matches_block_tridiagonal() {
    let mut sims: Vec<_> = [SolverKind::BlockTridiagonal, SolverKind::SparseLu]
        .into_iter()
        .map(|solver| {
            let params = StepParams {
                solver,
                ..paper_params()
            };
            Simulation::new(paper_pendulum(30), params).unwrap()
        })
        .collect();
    assert_eq!(sims[0].solver_name(), "block_tridiagonal");
    assert_eq!(sims[1].solver_name(), "sparse_lu");
    let mut worst = 0.0_f64;
    for _ in 0..100 {
        for sim in &mut sims {
            sim.step().unwrap();
        }
        for (a, b) in sims[0].state().r.iter().zip(&sims[1].state().r) {
            worst = worst.max((a - b).norm());
        }
    }
    assert!(worst <= 1e-12, "positions differ by {worst:e}");
    let (h_a, h_b) = (
        sims[0].energies().hamiltonian(),
        sims[1].energies().hamiltonian(),
    );
    assert!((h_a - h_b).abs() <= 1e-12, "{h_a} vs {h_b}");
}

/// The port outputs close the momentum balance: over each step,
/// `Σ M_ρ (v_{n+1} − v_n)/h = Σ F_b + F_N(t_{n+½}) + reaction`, where the reaction is the
/// output of the support's velocity port and `F_N` the input of the load port.
#[test]
fn port_outputs_close_the_momentum_balance() {
    let mut sim = Simulation::new(paper_pendulum(30), paper_params()).unwrap();
    let fb: phstring::Vector<2> = sim.system().body_force_vector().iter().sum();
    let mut worst = 0.0_f64;
    for _ in 0..100 {
        let p0 = sim.system().linear_momentum(sim.state());
        sim.step().unwrap();
        let p1 = sim.system().linear_momentum(sim.state());
        let ports = sim.ports();
        assert_eq!(ports.len(), 2);
        assert_eq!(
            (ports[0].kind, ports[0].node),
            (phstring::PortKind::Force, 30)
        );
        assert_eq!(
            (ports[1].kind, ports[1].node),
            (phstring::PortKind::Velocity, 0)
        );
        assert_eq!(ports[1].input, phstring::Vector::<2>::zeros()); // fixed support
        let rhs = fb + ports[0].input + ports[1].output;
        worst = worst.max(((p1 - p0) / 0.01 - rhs).norm());
    }
    // Residual tolerance 1e-11 N per step, plus round-off.
    assert!(worst <= 1e-10, "momentum balance off by {worst:e} N");
}

/// A run restored from a checkpoint continues bit for bit like the uninterrupted run, also
/// with step-size control and the mid-step predictor carrying state across the checkpoint.
#[test]
fn checkpoint_restore_is_bit_identical() {
    for predictor in [
        phstring::Predictor::Velocity,
        phstring::Predictor::MidpointVelocity,
    ] {
        let params = StepParams {
            predictor,
            ..paper_params()
        };
        let mut a = Simulation::new(paper_pendulum(30), params).unwrap();
        for _ in 0..37 {
            a.step().unwrap();
        }
        let cp = a.checkpoint();
        let mut b = Simulation::new(paper_pendulum(30), params).unwrap();
        b.restore(cp).unwrap();
        for _ in 37..100 {
            let (ra, rb) = (a.step().unwrap(), b.step().unwrap());
            assert_eq!(ra, rb);
        }
        assert_eq!(a.checkpoint(), b.checkpoint());
        assert_eq!(a.time().to_bits(), b.time().to_bits());
    }
}

/// A material with a bounded domain (limited extensibility, `C < 1.2`): stretching past it is
/// a step error naming the element, the strain, the step and the time — with plain Newton
/// and fixed steps; with the line search and step-size control the run still stops with a
/// clear error once no step size helps.
#[test]
fn strain_outside_a_bounded_domain_is_reported() {
    #[derive(Debug)]
    struct Limited;
    impl phstring::StoredEnergy for Limited {
        fn w(&self, c: f64) -> f64 {
            -5.0 * (1.0 - (c - 1.0) / 0.2).ln() - 25.0 * (c - 1.0)
        }
        fn dw(&self, c: f64) -> f64 {
            25.0 / (1.0 - (c - 1.0) / 0.2) - 25.0
        }
        fn d2w(&self, c: f64) -> f64 {
            125.0 / (1.0 - (c - 1.0) / 0.2).powi(2)
        }
        fn admissible(&self, c: f64) -> bool {
            c.is_finite() && c < 1.2
        }
    }
    let base = paper_pendulum(10);
    let mut loads = base.boundary.clone();
    loads.loads = vec![phstring::NodalLoad::new(10, |_| {
        phstring::Vector::<2>::new(500.0, -500.0)
    })];
    let problem = phstring::Problem {
        point_masses: Vec::new(),
        mesh: base.mesh,
        material: Limited,
        rho_a: 1.0,
        body_force: phstring::Vector::zeros(),
        mass: phstring::MassMatrix::Consistent,
        boundary: loads,
        initial: base.initial,
    };
    let params = StepParams {
        h: 0.01,
        newton: phstring::NewtonParams {
            line_search: false,
            ..phstring::NewtonParams::absolute(1e-11)
        },
        control: phstring::StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut sim = Simulation::new(problem, params).unwrap();
    let err = (0..100)
        .find_map(|_| sim.step().err())
        .expect("the limit is reached");
    let msg = err.to_string();
    assert!(
        matches!(err, phstring::StepError::InvalidStrain { c, .. } if c >= 1.2)
            && msg.contains("element")
            && msg.contains("outside the material's domain"),
        "{msg}"
    );
}

/// `Eᵀ ẑ = ∇Ĥ` (docs/method.md eqs. (4.9)–(4.10)): the efforts against finite differences of `Ĥ` in
/// `r`, `v` and `C`, on a state of the paper's run.
#[test]
fn efforts_are_the_gradient_of_the_hamiltonian() {
    let mut sim = Simulation::new(paper_pendulum(30), StepParams::default()).unwrap();
    for _ in 0..30 {
        sim.step().unwrap();
    }
    let sys = sim.system();
    let state = sim.state().clone();
    let (dr, v, half_s) = sys.efforts(&state);
    let h = |s: &phstring::State<2>| sys.energies(s).hamiltonian();
    let eps = 1e-6;
    let mut mv = vec![phstring::Vector::<2>::zeros(); v.len()];
    sys.mass_mul(&v, &mut mv);
    for i in [0, 7, 30] {
        for k in 0..2 {
            let (mut p, mut m) = (state.clone(), state.clone());
            p.r[i][k] += eps;
            m.r[i][k] -= eps;
            assert!(((h(&p) - h(&m)) / (2.0 * eps) - dr[i][k]).abs() < 1e-8);
            let (mut p, mut m) = (state.clone(), state.clone());
            p.v[i][k] += eps;
            m.v[i][k] -= eps;
            assert!(
                ((h(&p) - h(&m)) / (2.0 * eps) - mv[i][k]).abs() < 1e-8,
                "M v"
            );
        }
    }
    for e in [0, 13, 29] {
        let (mut p, mut m) = (state.clone(), state.clone());
        p.c[e] += eps;
        m.c[e] -= eps;
        let fd = (h(&p) - h(&m)) / (2.0 * eps);
        assert!((fd - sys.m_s()[e] * half_s[e]).abs() < 1e-8, "M_S ½S");
    }
}
