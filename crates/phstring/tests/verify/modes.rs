//! Natural modes (docs/method.md §17) against closed forms: the taut string's discrete and
//! continuum spectra, the inextensible hanging chain (Bessel), and a dynamic run started
//! from a mode shape.

use phstring::modes::{self, Character};
use phstring::statics::{self, StaticsParams};
use phstring::testing::{between_supports, hanging_chain};
use phstring::{
    Material, PhSystem, Problem, Scheme, Simulation, SolverKind, State, StepParams, Vector,
};
use std::f64::consts::PI;

/// A 100 m steel wire (EA = 1e7 N, 1.2 kg/m) stretched 0.5 % between two supports, `n`
/// elements, in 2D.
fn taut(n: usize) -> (Problem<2, Material>, f64, f64) {
    let (len, stretch, ea, rho_a) = (100.0, 1.005, 1e7, 1.2);
    let p = between_supports(
        n,
        len,
        Vector::<2>::new(len * stretch, 0.0),
        Material::linear_elastic(ea),
        rho_a,
        Vector::<2>::zeros(),
    );
    // S = 2W'(C) = EA (1 − 1/λ); the longitudinal stiffness S + 4W''C = EA.
    (p, ea * (1.0 - 1.0 / stretch), ea)
}

/// `ω_k² = 6k/(ρA l²) (1 − cos θ)/(2 + cos θ)`, θ = kπ/n: the discrete spectrum of a fixed
/// chain with element stiffness `k/l` and consistent mass.
fn discrete(stiff: f64, rho_a: f64, l: f64, n: usize, k: usize) -> f64 {
    let th = k as f64 * PI / n as f64;
    (6.0 * stiff / (rho_a * l * l) * (1.0 - th.cos()) / (2.0 + th.cos())).sqrt()
}

/// Dense (n = 40) and Lanczos (n = 4000) against the discrete closed form to 1e-10, both
/// families; and the characters.
#[test]
fn taut_string_matches_the_discrete_spectrum() {
    for (n, count) in [(40usize, 79usize), (4000, 12)] {
        let (p, s, ea) = taut(n);
        let (sys, st) = PhSystem::new(p).unwrap();
        let m = modes::modes(&sys, &st.r, count, SolverKind::Auto, None).unwrap();
        assert_eq!(m.method, if n == 40 { "dense" } else { "lanczos" });
        let l = 100.0 / n as f64;
        let mut want: Vec<(f64, Character)> = (1..n)
            .flat_map(|k| {
                [
                    (discrete(s, 1.2, l, n, k), Character::Transverse),
                    (discrete(ea, 1.2, l, n, k), Character::Longitudinal),
                ]
            })
            .collect();
        want.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (got, (w, c)) in m.modes.iter().zip(&want) {
            let rel = (got.omega - w).abs() / w;
            assert!(rel <= 1e-10, "n {n}: ω {} vs {w}, rel {rel:e}", got.omega);
            assert_eq!(got.character, *c, "n {n}: ω {w}");
        }
    }
}

/// The transverse frequencies converge to the continuum `kπ/L √(S/ρA)` at second order.
#[test]
fn taut_string_converges_to_the_continuum() {
    let errs: Vec<f64> = [20, 40, 80]
        .iter()
        .map(|&n| {
            let (p, s, _) = taut(n);
            let (sys, st) = PhSystem::new(p).unwrap();
            let m = modes::modes(&sys, &st.r, 3, SolverKind::Auto, None).unwrap();
            let exact = 3.0 * PI / 100.0 * (s / 1.2).sqrt();
            let third = m
                .modes
                .iter()
                .filter(|x| x.character == Character::Transverse)
                .nth(2)
                .unwrap();
            (third.omega - exact).abs() / exact
        })
        .collect();
    for w in errs.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!((1.95..2.05).contains(&order), "{errs:?}");
    }
}

/// A nearly inextensible hanging chain (EA = 1e9 N, 10 m, 1 kg/m): its lowest frequencies
/// approach `α_k/2 √(g/L)` with α_k the zeros of J₀, at second order in the mesh.
#[test]
fn hanging_chain_tends_to_the_bessel_limit() {
    let alpha = [
        2.404_825_557_695_773,
        5.520_078_110_286_311,
        8.653_727_912_911_013,
    ];
    let (len, g) = (10.0, 9.81);
    let mut errs = Vec::new();
    for n in [25, 50, 100, 200] {
        let p = hanging_chain(
            n,
            len,
            Material::hyperelastic(1e9),
            1.0,
            0.0,
            Vector::<2>::new(0.0, -1.0),
        );
        let eq = statics::solve(p.clone(), &StaticsParams::default(), None).unwrap();
        let (sys, _) = PhSystem::new(p).unwrap();
        let m = modes::modes(&sys, &eq.state.r, 3, SolverKind::Auto, None).unwrap();
        let err: Vec<f64> = m
            .modes
            .iter()
            .zip(alpha)
            .map(|(x, a)| {
                assert_eq!(x.character, Character::Transverse);
                let w = a / 2.0 * (g / len).sqrt();
                (x.omega - w) / w
            })
            .collect();
        errs.push(err);
    }
    // Second order in the element length, for each of the three modes…
    for k in 0..3 {
        for w in errs.windows(2) {
            let order = (w[0][k] / w[1][k]).log2();
            assert!((1.9..2.1).contains(&order), "mode {k}: {errs:?}");
        }
        // …towards the inextensible limit: the Richardson extrapolation of the two finest
        // meshes is within 1e-5 of it (what is left is O(h⁴) and the stretch, ~1e-7).
        let rich = (4.0 * errs[3][k] - errs[2][k]) / 3.0;
        assert!(
            rich.abs() < 1e-5,
            "mode {k}: extrapolated {rich:e}, {errs:?}"
        );
    }
}

/// Started from a small first transverse mode, the discrete-gradient run oscillates at
/// `ω̃ = (2/h) atan(ωh/2)`: the implicit midpoint rule's frequency on a linear oscillator
/// (the DG step on a quadratic energy), measured from 20 periods of the middle node.
#[test]
fn a_run_from_a_mode_shape_oscillates_at_its_frequency() {
    let n = 20;
    let (p, _, _) = taut(n);
    let (sys, st) = PhSystem::new(p.clone()).unwrap();
    let m = modes::modes(&sys, &st.r, 1, SolverKind::Auto, None).unwrap();
    let mode = &m.modes[0];
    assert_eq!(mode.character, Character::Transverse);
    let w = mode.omega;
    let h = 2.0 * PI / w / 50.0;
    let amp = 1e-4 / mode.shape[n / 2].norm();
    let mut p = p;
    let r: Vec<Vector<2>> =
        st.r.iter()
            .zip(&mode.shape)
            .map(|(r, f)| r + f * amp)
            .collect();
    p.initial = State::at_rest(&sys.mesh().clone(), r);
    let params = StepParams {
        h,
        scheme: Scheme::DiscreteGradient,
        ..Default::default()
    };
    let mut sim = Simulation::new(p, params).unwrap();
    let mut crossings = Vec::new();
    let mut prev = sim.state().r[n / 2][1];
    for _ in 0..(50 * 21) {
        sim.step().unwrap();
        let y = sim.state().r[n / 2][1];
        if prev < 0.0 && y >= 0.0 {
            crossings.push(sim.time() - h * y / (y - prev));
        }
        prev = y;
    }
    let periods = (crossings.len() - 1) as f64;
    let measured = 2.0 * PI * periods / (crossings.last().unwrap() - crossings[0]);
    let expected = 2.0 / h * (w * h / 2.0).atan();
    assert!(
        (measured - expected).abs() <= 1e-4 * w,
        "{measured} vs {expected} (ω {w})"
    );
    assert!(
        (measured - w).abs() >= 5e-4 * w,
        "the scheme's shift is visible"
    );
}

/// An unstable state (a compressed straight string) is refused.
#[test]
fn unstable_state_is_refused() {
    let (mut p, _, _) = taut(10);
    p.initial = State::straight(&p.mesh, Vector::<2>::zeros(), Vector::<2>::new(90.0, 0.0));
    let (sys, st) = PhSystem::new(p).unwrap();
    let e = modes::modes(&sys, &st.r, 3, SolverKind::Auto, None).unwrap_err();
    assert!(e.to_string().contains("not positive definite"), "{e}");
}
