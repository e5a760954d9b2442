//! Static equilibrium (docs/method.md §15) against closed forms: the discrete hanging chain
//! (exact), the continuum hanging length and the elastic catenary (O(h²)).

use phstring::statics::{self, FirstGuess, StaticsError, StaticsParams, StaticsPath};
use phstring::testing::{between_supports, hanging_chain};
use phstring::{Material, Problem, Simulation, StepParams, Vector};

const G: f64 = 9.81;

/// Stretch `λ = |r'|` at which the law carries the tension `t = S λ` [N].
fn stretch(material: &Material, t: f64) -> f64 {
    let ea = material.ea();
    match material {
        Material::Hyperelastic(_) => {
            // EA/2 (λ − 1/λ) = t.
            let a = t / ea;
            a + (a * a + 1.0).sqrt()
        }
        Material::LinearElastic(_) => 1.0 + t / ea,
        Material::StVenantKirchhoff(_) => {
            // EA/2 (λ³ − λ) = t, by Newton from λ = 1 + t/EA.
            let mut l = 1.0 + t / ea;
            for _ in 0..60 {
                let f = 0.5 * (l * l * l - l) - t / ea;
                l -= f / (0.5 * (3.0 * l * l - 1.0));
            }
            l
        }
        _ => unreachable!("the three smooth laws"),
    }
}

/// The exact discrete tip depth of the hanging chain: element `e` carries the weight of the
/// nodes below it, `w l (n − e − ½) + P`.
fn discrete_tip(material: &Material, n: usize, len: f64, rho_a: f64, tip: f64) -> f64 {
    let l = len / n as f64;
    let w = rho_a * G;
    (0..n)
        .map(|e| l * stretch(material, w * l * (n as f64 - e as f64 - 0.5) + G * tip))
        .sum()
}

/// The continuum hanging length `∫₀ᴸ λ(w (L − s) + P) ds` by composite Gauss–Legendre.
fn continuum_tip(material: &Material, len: f64, rho_a: f64, tip: f64) -> f64 {
    let (x, wq) = gauss5();
    let parts = 2000;
    let h = len / parts as f64;
    let w = rho_a * G;
    let mut sum = 0.0;
    for p in 0..parts {
        for (xi, wi) in x.iter().zip(&wq) {
            let s = h * (p as f64 + 0.5 * (1.0 + xi));
            sum += 0.5 * h * wi * stretch(material, w * (len - s) + G * tip);
        }
    }
    sum
}

fn gauss5() -> ([f64; 5], [f64; 5]) {
    let a = (5.0f64 - 2.0 * (10.0f64 / 7.0).sqrt()).sqrt() / 3.0;
    let b = (5.0f64 + 2.0 * (10.0f64 / 7.0).sqrt()).sqrt() / 3.0;
    let wa = (322.0 + 13.0 * 70f64.sqrt()) / 900.0;
    let wb = (322.0 - 13.0 * 70f64.sqrt()) / 900.0;
    ([-b, -a, 0.0, a, b], [wb, wa, 128.0 / 225.0, wa, wb])
}

fn laws(ea: f64) -> [Material; 3] {
    [
        Material::hyperelastic(ea),
        Material::linear_elastic(ea),
        Material::st_venant_kirchhoff(ea),
    ]
}

/// A 100 m rope of 1 kg/m with a 500 kg payload, for a steel (EA = 1e8 N) and a nylon
/// (EA = 1e5 N, 5 % strain at the top) rope: the tip depth equals the exact discrete
/// solution to 1e-10, and the horizontal reaction is zero, the vertical one the weight.
#[test]
fn hanging_chain_matches_the_discrete_closed_form() {
    for ea in [1e8, 1e5] {
        for material in laws(ea) {
            let (n, len, rho_a, tip) = (50, 100.0, 1.0, 500.0);
            let p = hanging_chain(n, len, material, rho_a, tip, Vector::<2>::new(0.0, -1.0));
            let eq = statics::solve(p, &StaticsParams::default(), None).unwrap();
            let exact = discrete_tip(&material, n, len, rho_a, tip);
            let got = -eq.state.r[n][1];
            let rel = (got - exact).abs() / exact;
            assert!(
                rel <= 1e-10,
                "{} EA {ea}: tip {got} vs {exact}, rel {rel:e}",
                material.name()
            );
            assert!(eq.state.r[n][0].abs() <= 1e-12 * len);
            let weight = G * (rho_a * len + tip);
            let ry = eq.reactions[0][1];
            assert!(
                (ry - weight).abs() <= 1e-10 * weight,
                "reaction {ry} vs {weight}"
            );
            assert!(
                eq.residual <= 1e-11 * eq.force_scale
                    && (eq.residual <= eq.tolerance || eq.at_roundoff),
                "residual {:e}, tolerance {:e}, scale {:e}, roundoff {}",
                eq.residual,
                eq.tolerance,
                eq.force_scale,
                eq.at_roundoff
            );
            assert_eq!(eq.path, StaticsPath::Newton, "{}", material.name());
            assert!(eq.stable);
        }
    }
}

/// Starting from a horizontal line, a tension-only rope (slack everywhere at first: no
/// stiffness) swings down to the same hanging equilibrium through the pseudo-transient path.
#[test]
fn slack_start_reaches_the_hanging_equilibrium() {
    let (n, len, rho_a, tip) = (40, 100.0, 1.0, 500.0);
    for material in [
        Material::tension_only_linear(1e8),
        Material::tension_only_hyperelastic(1e8),
    ] {
        let p = hanging_chain(n, len, material, rho_a, tip, Vector::<2>::new(1.0, 0.0));
        let eq = statics::solve(p, &StaticsParams::default(), None).unwrap();
        let smooth = match material {
            Material::TensionOnlyLinear(_) => Material::linear_elastic(1e8),
            _ => Material::hyperelastic(1e8),
        };
        let exact = discrete_tip(&smooth, n, len, rho_a, tip);
        let got = -eq.state.r[n][1];
        assert!(
            (got - exact).abs() <= 1e-9 * exact,
            "{}: tip {got} vs {exact} ({:?})",
            material.name(),
            eq.path
        );
        assert!(
            matches!(eq.path, StaticsPath::PseudoTransient { .. }),
            "{:?}",
            eq.path
        );
    }
}

/// The discrete hanging length converges to the continuum one at second order (the
/// linear law's is exact: the midpoint rule integrates its linear stretch exactly).
#[test]
fn hanging_length_converges_at_second_order() {
    let (len, rho_a, tip) = (100.0, 1.0, 0.0);
    for material in [
        Material::hyperelastic(1e4),
        Material::st_venant_kirchhoff(1e4),
    ] {
        let exact = continuum_tip(&material, len, rho_a, tip);
        let errs: Vec<f64> = [10, 20, 40]
            .iter()
            .map(|&n| {
                let p = hanging_chain(n, len, material, rho_a, tip, Vector::<2>::new(0.0, -1.0));
                let eq = statics::solve(p, &StaticsParams::default(), None).unwrap();
                (-eq.state.r[n][1] - exact).abs()
            })
            .collect();
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!(
                (1.95..2.05).contains(&order),
                "{}: errors {errs:?}",
                material.name()
            );
        }
    }
    let lin = Material::linear_elastic(1e4);
    let exact = len + rho_a * G * len * len / (2.0 * 1e4);
    let p = hanging_chain(7, len, lin, rho_a, 0.0, Vector::<2>::new(0.0, -1.0));
    let eq = statics::solve(p, &StaticsParams::default(), None).unwrap();
    assert!((-eq.state.r[7][1] - exact).abs() <= 1e-12 * exact);
}

/// Irvine's elastic catenary: the unstretched length `l0`, weight `w` per unstretched metre,
/// supports at (0, 0) and (`span`, `dh`). Returns `(H, V)`: the horizontal tension and the
/// vertical force of the left support on the cable (up).
fn irvine(ea: f64, w: f64, l0: f64, span: f64, dh: f64) -> (f64, f64) {
    let end = |h: f64, v: f64| {
        let s = l0;
        let x = h * s / ea + h / w * (((w * s - v) / h).asinh() + (v / h).asinh());
        let y = (w * s * s / 2.0 - v * s) / ea
            + ((h * h + (w * s - v).powi(2)).sqrt() - (h * h + v * v).sqrt()) / w;
        (x - span, y - dh)
    };
    let (mut h, mut v) = (w * l0, 0.5 * w * l0);
    for _ in 0..100 {
        let (fx, fy) = end(h, v);
        let (eh, ev) = (1e-7 * h, 1e-7 * w * l0);
        let (a, c) = end(h + eh, v);
        let (b, d) = end(h, v + ev);
        let (j11, j21, j12, j22) = ((a - fx) / eh, (c - fy) / eh, (b - fx) / ev, (d - fy) / ev);
        let det = j11 * j22 - j12 * j21;
        h -= (j22 * fx - j12 * fy) / det;
        v -= (-j21 * fx + j11 * fy) / det;
    }
    (h, v)
}

/// The point at unstretched arc length `s` of the elastic catenary with forces `H`, `V`.
fn irvine_point(ea: f64, w: f64, h: f64, v: f64, s: f64) -> (f64, f64) {
    let x = h * s / ea + h / w * (((w * s - v) / h).asinh() + (v / h).asinh());
    let y = (w * s * s / 2.0 - v * s) / ea
        + ((h * h + (w * s - v).powi(2)).sqrt() - (h * h + v * v).sqrt()) / w;
    (x, y)
}

/// A catenary of `n` elements: a 120 m linear elastic cable (EA = 1e6 N, 2 kg/m) between
/// supports 100 m apart, `dh` higher at the right, started straight (compressed) between them.
fn catenary(n: usize, dh: f64) -> Problem<2, Material> {
    let (l0, span, rho_a) = (120.0, 100.0, 2.0);
    between_supports(
        n,
        l0,
        Vector::<2>::new(span, dh),
        Material::linear_elastic(1e6),
        rho_a,
        Vector::<2>::new(0.0, -G * rho_a),
    )
}

/// Support reactions and the mid-span point (sag) against the elastic catenary, at equal and
/// different heights: second-order convergence in the element length.
#[test]
fn elastic_catenary_converges_at_second_order() {
    for dh in [0.0, 30.0] {
        let (h, v) = irvine(1e6, 2.0 * G, 120.0, 100.0, dh);
        let mut errs = Vec::new();
        for n in [16, 32, 64] {
            let eq = statics::solve(catenary(n, dh), &StaticsParams::default(), None).unwrap();
            let ra = eq.reactions[0];
            let rb = eq.reactions[n];
            // Left support pulls left and up; right support right and up.
            let err_h = ((-ra[0] - h).abs()).max((rb[0] - h).abs()) / h;
            let err_v = ((ra[1] - v).abs()).max((rb[1] - (2.0 * G * 120.0 - v)).abs()) / h;
            // The mid-span node against the catenary's point at s = l0/2.
            let (xs, ys) = irvine_point(1e6, 2.0 * G, h, v, 60.0);
            let mid = eq.state.r[n / 2];
            let err_x = ((mid[0] - xs).abs()).max((mid[1] - ys).abs()) / 100.0;
            errs.push(err_h.max(err_v).max(err_x));
        }
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!((1.9..2.1).contains(&order), "dh {dh}: errors {errs:?}");
        }
        assert!(errs[2] < 1e-3, "dh {dh}: {errs:?}");
    }
}

/// A dynamic run started at the equilibrium stays there: drift ≤ 1e-12 m over 1000 steps.
#[test]
fn a_run_started_at_equilibrium_stays_at_rest() {
    let p = hanging_chain(
        40,
        100.0,
        Material::hyperelastic(1e8),
        1.0,
        500.0,
        Vector::<2>::new(0.0, -1.0),
    );
    let eq = statics::solve(p.clone(), &StaticsParams::default(), None).unwrap();
    let start = eq.state.r.clone();
    let mut p = p;
    p.initial = eq.state;
    let mut sim = Simulation::new(
        p,
        StepParams {
            h: 1e-3,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..1000 {
        sim.step().unwrap();
    }
    let drift = sim
        .state()
        .r
        .iter()
        .zip(&start)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(drift <= 1e-12, "drift {drift:e} m");
}

/// A free string under gravity has no equilibrium: the error names the free translation.
#[test]
fn under_constrained_structure_is_named() {
    let mut p = hanging_chain(
        10,
        10.0,
        Material::hyperelastic(1e6),
        1.0,
        0.0,
        Vector::<2>::new(0.0, -1.0),
    );
    p.boundary.fixed[0].components = [true, false];
    let err = statics::solve(p, &StaticsParams::default(), None).unwrap_err();
    assert!(
        matches!(err, StaticsError::UnderConstrained { axis: "y", .. }),
        "{err}"
    );
    assert!(err.to_string().contains("translate along y"), "{err}");
}

/// With too few pseudo-time steps, a slack start finds no equilibrium; the message names
/// the load step where the continuation failed and the pseudo-transient count.
#[test]
fn failure_names_the_continuation_step() {
    let p = hanging_chain(
        20,
        100.0,
        Material::tension_only_linear(1e8),
        1.0,
        0.0,
        Vector::<2>::new(1.0, 0.0),
    );
    let params = StaticsParams {
        max_pseudo_steps: 2,
        ..Default::default()
    };
    let err = statics::solve(p, &params, None).unwrap_err();
    let msg = err.to_string();
    match err {
        StaticsError::NotFound(nf) => {
            let (load_step, pseudo_steps) = (nf.load_step, nf.pseudo_steps);
            assert_eq!(load_step, 1, "{msg}");
            // Two pseudo-transient runs (compression released, then as is), 2 steps each.
            assert!(pseudo_steps <= 4, "{msg}");
        }
        _ => panic!("{msg}"),
    }
    assert!(msg.contains("load step 1"), "{msg}");
}

/// A law that raises a stop flag at its `at`-th evaluation, as a Ctrl-C in the middle of a
/// solve would, and counts the evaluations made after it.
#[derive(Debug)]
struct Tripwire {
    law: Material,
    calls: std::sync::atomic::AtomicUsize,
    at: usize,
    flag: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Tripwire {
    fn tick(&self) {
        use std::sync::atomic::Ordering;
        if self.calls.fetch_add(1, Ordering::Relaxed) + 1 == self.at {
            self.flag.store(true, Ordering::Relaxed);
        }
    }
}

impl phstring::StoredEnergy for Tripwire {
    fn w(&self, c: f64) -> f64 {
        self.tick();
        self.law.w(c)
    }
    fn dw(&self, c: f64) -> f64 {
        self.tick();
        self.law.dw(c)
    }
    fn d2w(&self, c: f64) -> f64 {
        self.tick();
        self.law.d2w(c)
    }
    fn admissible(&self, c: f64) -> bool {
        self.law.admissible(c)
    }
}

/// A stop request in the middle of the equilibrium solve of a slack start (Newton at the
/// full load fails, the load continuation fails, the pseudo-transient continuation finds
/// it) ends the solve with `Interrupted` within a small part of the work, wherever it lands.
#[test]
fn stop_request_ends_the_continuation_promptly() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let (n, len, rho_a) = (40, 100.0, 1.0);
    let problem = |at: usize, flag: &Arc<AtomicBool>| {
        let p = hanging_chain(
            n,
            len,
            Material::tension_only_linear(1e8),
            rho_a,
            500.0,
            Vector::<2>::new(1.0, 0.0),
        );
        Problem {
            mesh: p.mesh,
            initial: p.initial,
            material: Tripwire {
                law: p.material,
                calls: AtomicUsize::new(0),
                at,
                flag: flag.clone(),
            },
            rho_a: p.rho_a,
            body_force: p.body_force,
            mass: p.mass,
            boundary: p.boundary,
            point_masses: p.point_masses,
        }
    };
    // Without a stop: the law's evaluations of the whole solve.
    let flag = Arc::new(AtomicBool::new(false));
    let (sys, initial) = phstring::PhSystem::new(problem(usize::MAX, &flag)).unwrap();
    let eq =
        statics::solve_system(&sys, &initial.r, &StaticsParams::default(), Some(&flag)).unwrap();
    assert!(
        matches!(eq.path, StaticsPath::PseudoTransient { .. }),
        "{:?}",
        eq.path
    );
    let law = |sys: &phstring::PhSystem<2, Tripwire>| match &sys.groups()[0].law {
        phstring::Law::String(m) => m.calls.load(Ordering::Relaxed),
        phstring::Law::Spring(_) => unreachable!("a string"),
    };
    let total = law(&sys);
    assert!(total > 10_000, "{total}");
    for part in [0.05, 0.3, 0.6, 0.9] {
        let at = (part * total as f64) as usize;
        let flag = Arc::new(AtomicBool::new(false));
        let (sys, initial) = phstring::PhSystem::new(problem(at, &flag)).unwrap();
        let e = statics::solve_system(&sys, &initial.r, &StaticsParams::default(), Some(&flag))
            .unwrap_err();
        assert_eq!(e, StaticsError::Interrupted, "stop at {part} of the work");
        let after = law(&sys) - at;
        eprintln!("stop at {at} of {total} law evaluations: {after} after it");
        assert!(
            after < total / 500,
            "stop at {part} of the work: {after} evaluations after it (of {total})"
        );
    }
}

/// The catenary first guess of a linear elastic cable between two supports (120 m, 2 kg/m,
/// EA = 1e6 N, 64 elements, supports 100 m apart and 30 m different in height) is the
/// discrete equilibrium itself: Newton from it needs at most one iteration (measured 0),
/// and it is the equilibrium the other paths find from the straight compressed start
/// (support reactions to 1e-9).
#[test]
fn catenary_guess_of_a_cable_between_supports_is_its_discrete_equilibrium() {
    let n = 64;
    let eq = statics::solve(catenary(n, 30.0), &StaticsParams::default(), None).unwrap();
    assert_eq!(eq.path, StaticsPath::CatenaryGuess);
    assert_eq!(eq.guess, FirstGuess::Used);
    assert!(eq.iterations <= 1, "{} iterations", eq.iterations);
    let without = StaticsParams {
        first_guess: false,
        ..Default::default()
    };
    let old = statics::solve(catenary(n, 30.0), &without, None).unwrap();
    assert!(
        matches!(old.path, StaticsPath::PseudoTransient { .. }),
        "{:?}",
        old.path
    );
    for i in [0, n] {
        let e = (eq.reactions[i] - old.reactions[i]).norm() / old.reactions[i].norm();
        assert!(e <= 1e-9, "support {i}: {e:e}");
    }
}

/// A chain hanging from one support has a free end: the guess does not apply, says why, and
/// Newton from the start finds the equilibrium as before.
#[test]
fn catenary_guess_needs_two_supports() {
    let p = hanging_chain(
        20,
        100.0,
        Material::linear_elastic(1e8),
        10.0,
        500.0,
        Vector::<2>::new(0.0, -1.0),
    );
    let eq = statics::solve(p, &StaticsParams::default(), None).unwrap();
    assert_eq!(eq.path, StaticsPath::Newton);
    match &eq.guess {
        FirstGuess::NotApplicable(why) => assert!(why.contains("not a support"), "{why}"),
        other => panic!("{other:?}"),
    }
}
