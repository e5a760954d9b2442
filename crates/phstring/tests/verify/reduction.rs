//! Structure-preserving modal truncation (docs/method.md §17): the modal PH model's port
//! output against the nonlinear run as the load amplitude goes to zero; with dissipation
//! (§18), the linear models' `R` against a damped run.

use nalgebra::{DMatrix, DVector};
use phstring::linear::{ForcePort, LinearPh, modal_model, reduced_model};
use phstring::modes;
use phstring::testing::between_supports;
use phstring::{
    Damping, Material, Network, NodalLoad, PhSystem, PortKind, Problem, Simulation, SolverKind,
    State, StepParams, Vector,
};
use std::f64::consts::PI;

const N: usize = 20;
const NODE: usize = 7;

/// The taut 100 m steel wire of `modes.rs` with a transverse force pulse `a sin²(πt/τ)` [N]
/// (t < τ) at node 7.
fn problem(a: f64, tau: f64) -> Problem<2, Material> {
    let mut p = between_supports(
        N,
        100.0,
        Vector::<2>::new(100.5, 0.0),
        Material::linear_elastic(1e7),
        1.2,
        Vector::<2>::zeros(),
    );
    p.boundary.loads = vec![NodalLoad::new(NODE, move |t: f64| {
        let s = if t < tau { (PI * t / tau).sin() } else { 0.0 };
        Vector::<2>::new(0.0, a * s * s)
    })];
    p
}

fn dense(m: &faer::sparse::SparseColMat<usize, f64>) -> DMatrix<f64> {
    let d = m.as_ref().to_dense();
    DMatrix::from_fn(d.nrows(), d.ncols(), |i, j| d[(i, j)])
}

/// The port outputs `y_{n+½}` of the linear model `E ẋ = (J − R) Q x + B u` under the implicit
/// midpoint rule (the DG step on a quadratic energy), inputs at the mid times.
fn linear_outputs(
    model: &LinearPh,
    h: f64,
    steps: usize,
    u: impl Fn(f64) -> DVector<f64>,
) -> Vec<DVector<f64>> {
    let (e, j, r, q, b) = (
        dense(&model.e),
        dense(&model.j),
        dense(&model.r),
        dense(&model.q),
        dense(&model.b),
    );
    let a = (&j - &r) * &q;
    let lhs = (&e - &a * (0.5 * h)).lu();
    let rhs = &e + &a * (0.5 * h);
    let mut x = DVector::zeros(e.nrows());
    let mut ys = Vec::with_capacity(steps);
    for n in 0..steps {
        let um = u((n as f64 + 0.5) * h);
        let x1 = lhs.solve(&(&rhs * &x + &b * um * h)).unwrap();
        ys.push(b.transpose() * &q * (&x + &x1) * 0.5);
        x = x1;
    }
    ys
}

/// A force pulse on the taut wire: its system and initial state, every mode about it, the
/// step (1/200 of the first period), the pulse length (0.3 periods), the steps (two periods)
/// and the force ports at `NODE`.
struct Pulse {
    sys: PhSystem<2, Material>,
    st: State<2>,
    modes: Vec<modes::Mode<2>>,
    h: f64,
    tau: f64,
    steps: usize,
    ports: [ForcePort; 2],
}

fn pulse(net: Network<2, Material>) -> Pulse {
    let (sys, st) = PhSystem::new(net).unwrap();
    let modes = modes::modes(&sys, &st.r, usize::MAX, SolverKind::Auto, None)
        .unwrap()
        .modes;
    let w1 = modes[0].omega;
    let port = |component| ForcePort {
        node: NODE,
        component,
    };
    Pulse {
        sys,
        st,
        modes,
        h: 2.0 * PI / w1 / 200.0,
        tau: 0.3 * 2.0 * PI / w1,
        steps: 400,
        ports: [port(0), port(1)],
    }
}

/// The nonlinear run's port outputs `y_{n+½}` at `NODE` for `steps` steps of `h`.
fn nonlinear_outputs(net: Network<2, Material>, h: f64, steps: usize) -> Vec<DVector<f64>> {
    let params = StepParams {
        h,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    (0..steps)
        .map(|_| {
            let r = sim.step().unwrap();
            assert!(r.dissipated >= 0.0);
            let p = sim
                .ports()
                .iter()
                .find(|p| p.node == NODE && p.kind == PortKind::Force)
                .unwrap();
            DVector::from_column_slice(p.output.as_slice())
        })
        .collect()
}

/// The input of the pulse of amplitude `a` [N] and length `tau` [s].
fn pulse_input(a: f64, tau: f64) -> impl Fn(f64) -> DVector<f64> {
    move |t: f64| {
        let s = if t < tau { (PI * t / tau).sin() } else { 0.0 };
        DVector::from_vec(vec![0.0, a * s * s])
    }
}

/// The largest difference of two output histories, over `scale`.
fn largest_difference(y: &[DVector<f64>], z: &[DVector<f64>], scale: f64) -> f64 {
    y.iter()
        .zip(z)
        .map(|(a, b)| (a - b).amax())
        .fold(0.0, f64::max)
        / scale
}

/// The largest output magnitude.
fn largest(y: &[DVector<f64>]) -> f64 {
    y.iter().map(|v| v.amax()).fold(0.0, f64::max)
}

#[test]
fn modal_truncation_matches_the_nonlinear_run_at_small_amplitude() {
    let Pulse {
        sys,
        st,
        modes: all,
        h,
        tau,
        steps,
        ports,
    } = pulse(problem(0.0, 1.0).into());
    let mut errs_full = Vec::new();
    let mut errs_trunc = Vec::new();
    for a in [100.0, 10.0, 1.0] {
        let y_nl = nonlinear_outputs(problem(a, tau).into(), h, steps);
        for (k, errs) in [(all.len(), &mut errs_full), (8, &mut errs_trunc)] {
            let model = modal_model(&sys, &st.r, &all[..k], &ports);
            let y = linear_outputs(&model, h, steps, pulse_input(a, tau));
            errs.push(largest_difference(&y, &y_nl, largest(&y)));
        }
    }
    // Every mode kept: the difference is the nonlinearity, and it vanishes with the amplitude.
    // It is linear in the amplitude (the string's quadratic coupling of transverse motion
    // into stretch): a tenth of the load, a tenth of the relative difference (measured
    // 4.4e-4, 4.4e-5, 4.4e-6 for 100, 10, 1 N).
    for w in errs_full.windows(2) {
        let ratio = w[1] / w[0];
        assert!((0.09..0.11).contains(&ratio), "{errs_full:?}");
    }
    // Eight modes: the truncation error remains as the amplitude goes to zero (5.8 %).
    let floor = errs_trunc[2];
    assert!(
        (errs_trunc[1] - floor).abs() < 0.1 * floor,
        "{errs_trunc:?}"
    );
    assert!(floor > errs_full[2] && floor < 0.2, "{errs_trunc:?}");
}

/// The taut wire of [`problem`] with Kelvin–Voigt damping (η = 1e4 N·s) and drag
/// (1 N·s/m², about 6 % of critical on the first transverse mode).
fn damped(a: f64, tau: f64) -> Network<2, Material> {
    let mut net: Network<2, Material> = problem(a, tau).into();
    net.groups[0].damping = Damping {
        kelvin_voigt: 1e4,
        drag: 1.0,
        dashpot: 0.0,
    };
    net
}

/// With damping, the reduced linear model (with its `R`) and the modal model with every mode
/// (with `Φᵀ R_v Φ`) follow the damped nonlinear run to a difference that vanishes linearly
/// with the amplitude, while the same models without `R` are off by the damping's effect.
#[test]
fn linear_models_carry_the_damping() {
    let Pulse {
        sys,
        st,
        modes: all,
        h,
        tau,
        steps,
        ports,
    } = pulse(damped(0.0, 1.0));
    let reduced = reduced_model(&sys, &st.r, &ports);
    let modal = modal_model(&sys, &st.r, &all, &ports);
    let undamped = LinearPh {
        r: faer::sparse::SparseColMat::try_new_from_triplets(
            reduced.r.nrows(),
            reduced.r.ncols(),
            &[],
        )
        .unwrap(),
        ..reduced.clone()
    };
    let mut errs: [Vec<f64>; 3] = Default::default();
    for a in [100.0, 10.0, 1.0] {
        let y_nl = nonlinear_outputs(damped(a, tau), h, steps);
        for (model, errs) in [&reduced, &modal, &undamped]
            .into_iter()
            .zip(errs.iter_mut())
        {
            let y = linear_outputs(model, h, steps, pulse_input(a, tau));
            errs.push(largest_difference(&y, &y_nl, largest(&y_nl)));
        }
    }
    eprintln!(
        "damped: reduced {:?}, modal {:?}, without R {:?}",
        errs[0], errs[1], errs[2]
    );
    for e in &errs[..2] {
        for w in e.windows(2) {
            let ratio = w[1] / w[0];
            assert!((0.09..0.11).contains(&ratio), "{errs:?}");
        }
    }
    // Without R the difference stays at the damping's effect however small the load.
    assert!(errs[2][2] > 100.0 * errs[0][2], "{errs:?}");
}
