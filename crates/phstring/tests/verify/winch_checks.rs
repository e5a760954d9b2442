//! Further checks of the winches (docs/method.md §23, "Verification").

use super::winch::{EA, RHO_A, fixed_step};
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Network, NetworkBuilder, Simulation, StringSpec, Vector,
    Winch,
};
use std::sync::Arc;

/// The taut rope's reference length [m] and pretension [N].
const SPAN: f64 = 100.0;
const T0: f64 = 5000.0;

/// A taut 2D rope without gravity: the drum at the origin, `n_el` elements of `SPAN / n_el`
/// (reference) to a fixed end at `x = λ₀ SPAN` (`λ₀ = 1 + T0/EA`), `reserve` more on the
/// drum, at rest; the winch pays out `payout(t)`.
fn taut_rope(
    n_el: usize,
    reserve: usize,
    payout: impl Fn(f64) -> f64 + Send + Sync + 'static,
) -> Network<2, Material> {
    let stretch = 1.0 + T0 / EA;
    let mut b = NetworkBuilder::<2, Material>::new();
    let drum = b.node(Vector::<2>::zeros());
    let end = b.node(Vector::<2>::new(stretch * SPAN, 0.0));
    let spec = StringSpec {
        name: "rope".into(),
        material: Material::tension_only_linear(EA),
        rho_a: RHO_A,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::zeros(),
        prestretch: stretch,
    };
    let g = b.string_on_drum(spec, &[drum, end], n_el, reserve).unwrap();
    let boundary = Boundary {
        fixed: vec![Fixed::node(end)],
        ..Boundary::default()
    };
    b.build(boundary, Vec::new()).unwrap().with_winch(Winch {
        name: "drum".into(),
        group: g,
        reserve,
        payout: Arc::new(payout),
        drum_motion: None,
        drum: None,
    })
}

/// Runs the taut rope with `n_el` elements at the constant payout speed `speed` [m/s] from
/// `t = 0` with the Courant number `courant` (`h = courant · l / c`) to twice the echo
/// time `2 SPAN / c`; returns the mean change of the drum tension from `T0` [N], counted
/// positive toward the jump (a rise hauling in, a drop paying out), over the middle halves
/// of the first and second echo intervals, when that change first crosses the middle
/// between the two plateaus [s], and the stretch of the drum node's path at the end [–].
fn sudden_start(n_el: usize, speed: f64, courant: f64) -> (f64, f64, f64, f64) {
    let c = (EA / RHO_A).sqrt();
    let echo = 2.0 * SPAN / c;
    let l = SPAN / n_el as f64;
    let h = courant * l / c;
    let net = taut_rope(n_el, 2, move |t| speed * t);
    let mut sim = Simulation::new(net, fixed_step(h)).unwrap_or_else(|e| panic!("{e}"));
    let t0 = sim.winch_samples()[0].tension;
    assert!((t0 - T0).abs() < 1e-6 * T0, "pretension {t0} N");
    let jump = (1.0 + T0 / EA) * speed.abs() * (EA * RHO_A).sqrt();
    let (mut first, mut second) = ((0.0, 0), (0.0, 0));
    let mut crossing = f64::NAN;
    let mut prev = (0.0, 0.0);
    let steps = (2.0 * echo / h).ceil() as usize;
    for _ in 0..steps {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let dt = (sim.winch_samples()[0].tension - T0) * -speed.signum();
        let x = r.t / echo;
        if (0.25..0.75).contains(&x) {
            first = (first.0 + dt, first.1 + 1);
        }
        if (1.25..1.75).contains(&x) {
            second = (second.0 + dt, second.1 + 1);
        }
        if crossing.is_nan() && x > 0.5 && dt >= 2.0 * jump {
            crossing = prev.0 + (r.t - prev.0) * (2.0 * jump - prev.1) / (dt - prev.1);
        }
        prev = (r.t, dt);
    }
    let stretch = sim.checkpoint().winches[0].stretch;
    (
        first.0 / first.1 as f64,
        second.0 / second.1 as f64,
        crossing,
        stretch,
    )
}

/// The St-Venant wave of a sudden start: a taut 100 m steel rope (EA = 4.3e7 N, 4.1 kg/m,
/// 5 kN pretension, no gravity, the far end fixed) hauled in at 0.5 m/s, or paid out at
/// 0.1 m/s, from t = 0 without a ramp (the drum node moves at the payout speed from the first
/// step on), `h` = 0.5 `l/c`. The tension at the drum jumps by `ΔT = λ |v| √(EA ρA)` (the
/// particle speed at the drum `λ|v|` times the rope's impedance; exact for the linear law,
/// whose axial waves are linear) and holds until the echo from the fixed end returns at
/// `2L/c`, `c = √(EA/ρA)`, after which it is `3ΔT`. Physically `λ` is the stretch behind
/// the front, `λ₀ ± ΔT/EA`; the model moves the drum node with the stretch of its path,
/// taken at the last cut (hauling in: the start's `λ₀`; paying out: after the first step,
/// when the first element comes off the drum, between the two). Guards:
/// * the model's jump (with the path's stretch), as the mean tension over the middle half
///   of the first echo interval, converges to the closed form at least at first order per
///   mesh refinement (25, 100, 400 elements) and is within 1e-7 on the finest mesh; the
///   second plateau `3ΔT` within 1e-5 there;
/// * the path's stretch lies between `λ₀` and `λ₀ ± ΔT/EA`, so the model's jump is within
///   `|v|/c` (1.5e-4 at 0.5 m/s) of the physical one;
/// * the echo, as the tension crossing `2ΔT`, arrives at `2L/c` within an offset that
///   shrinks at least as `l^½` (a dispersive front widens as `l^⅔ t^⅓`).
#[test]
fn a_sudden_start_sends_the_st_venant_wave_down_the_rope() {
    let c = (EA / RHO_A).sqrt();
    let z = (EA * RHO_A).sqrt();
    let echo = 2.0 * SPAN / c;
    let stretch0 = 1.0 + T0 / EA;
    for speed in [-0.5_f64, 0.1] {
        let physical = stretch0 * speed.abs() * z / (1.0 + speed / c);
        let mut errors = Vec::new();
        for n_el in [25, 100, 400] {
            let (first, second, crossing, stretch) = sudden_start(n_el, speed, 0.5);
            let model = stretch * speed.abs() * z;
            let (e1, e2) = (first / model - 1.0, second / (3.0 * model) - 1.0);
            eprintln!(
                "v = {speed} m/s, {n_el} elements: jump {first:.4} N (model {model:.4} N: {e1:.2e}; physical {physical:.4} N: {:.2e}; v√(EAρA) {:.4} N), second plateau {e2:.2e}, echo {:.3e} s late; path stretch − 1 = {:.4e}",
                first / physical - 1.0,
                speed.abs() * z,
                crossing - echo,
                stretch - 1.0
            );
            // The stretch behind the front: lower paying out, higher hauling in.
            let behind_front = stretch0 * (1.0 - speed * z / EA);
            let (lo, hi) = (stretch0.min(behind_front), stretch0.max(behind_front));
            assert!(
                (lo - 1e-12..=hi + 1e-12).contains(&stretch),
                "path stretch {stretch} outside [{lo}, {hi}]"
            );
            assert!((model / physical - 1.0).abs() <= speed.abs() / c * (1.0 + 1e-9));
            errors.push((e1.abs(), e2.abs(), (crossing - echo).abs()));
        }
        for w in errors.windows(2) {
            assert!(w[1].0 <= w[0].0 / 4.0, "{errors:?}");
            assert!(w[1].2 <= w[0].2 / 2.0, "{errors:?}");
        }
        let finest = errors[errors.len() - 1];
        assert!(finest.0 < 1e-7 && finest.1 < 1e-5, "{errors:?}");
    }
}

/// The step's balance error relative to its energy scale (the winch tests' measure): the
/// energies' magnitudes at both ends and the winch's supply.
fn relative_balance(r: &phstring::StepReport) -> f64 {
    let scale = r.before.magnitude + r.after.magnitude + r.winch.abs();
    (r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated).abs() / scale
}

/// The winch's drum element index within its string and the distance `b` [m] behind the
/// drum point (the model's cable still on the drum).
fn drum_state(sim: &Simulation<2, Material>) -> (usize, f64) {
    let ws = sim.checkpoint().winches[0];
    (ws.drum, ws.behind(ws.payout))
}

/// Paying out 12.5 m of rope under the 5 t payload and hauling the same 12.5 m back in
/// (smooth moves of 10 s each, 2 s apart, `h` = 0.01 s, 13 elements off the drum and 13 back
/// on). Guards the mass off the drum and the reversal:
/// * on every step the length off the drum is the start's 20 m plus the payout (1e-12 m:
///   sums of a few tens of metres with one rounding per cut), `WinchSample::mass` is `ρA`
///   times it (1e-15 relative), and the mass of the elements in the string's group,
///   summed from the mesh, is `ρA` times it plus the cable the model keeps behind the drum
///   point, `ρA b`, `0 ≤ b ≤ L` (1e-14 relative);
/// * at the end the mesh is the start's: the drum element and the group's range are the
///   start's with the drum node at the drum point (`b` = 0 within 1e-12 m: the cut band is
///   `[−ε, L − ε]` with `ε = 1e-9 L`, so the payout brought back to 0 puts the last element
///   back even where rounding leaves `b` a little below `L`), the reference lengths are the
///   start's, the parked nodes are at the drum point at rest, and the start's drum node is
///   within `n_cuts · L · ΔT / EA` of the drum point: each cut starts the drum node's path
///   on the stretch of its element then, which the payload's bounce and the rope's weight
///   change by at most the range `ΔT` of the drum tension over the run.
#[test]
fn paying_out_and_hauling_back_keeps_the_mass_and_returns_the_mesh() {
    use super::winch::{L, hoist, smooth};
    let (n_el, reserve, amount) = (20, 15, 12.5);
    let p = move |t: f64| amount * (smooth(t / 10.0) - smooth((t - 12.0) / 10.0));
    let (net, _) = hoist(n_el, reserve, p);
    let mut sim = Simulation::new(net, fixed_step(0.01)).unwrap_or_else(|e| panic!("{e}"));
    let g = sim.system().groups().len() - 1;
    let start_range = sim.system().groups()[g].elements.clone();
    let start_lengths = sim.system().mesh().lengths().to_vec();
    let start_layout = sim.system().winch_layout(&sim.checkpoint().winches);
    let drum_point = sim.state().r[start_layout[0].0];
    let a0 = n_el as f64 * L;
    let (mut worst_len, mut worst_mass, mut worst_group, mut worst_balance) =
        (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    let (mut t_min, mut t_max, mut cuts) = (f64::MAX, f64::MIN, 0);
    let mut drum_prev = reserve;
    while sim.time() < 23.0 - 1e-9 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        worst_balance = worst_balance.max(relative_balance(&r));
        let w = sim.winch_samples()[0];
        let (drum, behind) = drum_state(&sim);
        cuts += drum.abs_diff(drum_prev);
        drum_prev = drum;
        worst_len = worst_len.max((w.length - (a0 + p(r.t))).abs());
        worst_mass = worst_mass.max((w.mass - RHO_A * w.length).abs() / w.mass);
        let grp = &sim.system().groups()[g];
        assert_eq!(grp.elements.start, start_range.start + drum - reserve);
        assert_eq!(grp.elements.end, start_range.end);
        let group_mass: f64 = sim.system().mesh().lengths()[grp.elements.clone()]
            .iter()
            .map(|l| grp.rho_a * l)
            .sum();
        assert!(
            (-1e-9 * L - 1e-12..=L).contains(&behind),
            "{behind} m behind the drum point at t = {}",
            r.t
        );
        worst_group =
            worst_group.max((group_mass - RHO_A * (w.length + behind)).abs() / group_mass);
        t_min = t_min.min(w.tension);
        t_max = t_max.max(w.tension);
    }
    let cp = sim.checkpoint();
    let (drum, behind) = drum_state(&sim);
    let layout = sim.system().winch_layout(&cp.winches);
    let grp = &sim.system().groups()[g];
    // The string's nodes from the drum point, parked ones included.
    let nodes = sim.system().mesh().elements()[start_range.start - reserve..start_range.end]
        .iter()
        .map(|e| e[0])
        .collect::<Vec<_>>();
    let start_node = sim.state().r[start_layout[0].0];
    let off = (start_node - drum_point).norm();
    let bound = cuts as f64 * L * (t_max - t_min) / EA;
    eprintln!(
        "{cuts} cuts; length off the drum − (20 m + payout) ≤ {worst_len:.1e} m, mass {worst_mass:.1e}, group mass − ρA(length + b) {worst_group:.1e}; balance/scale {worst_balance:.1e}; end: drum element {drum} (start {reserve}), {behind:.3e} m behind the drum point, the start's drum node {off:.2e} m off it (bound {bound:.2e} m, tension {t_min:.0}–{t_max:.0} N)"
    );
    assert!(worst_len < 1e-12, "{worst_len}");
    assert!(worst_mass < 1e-15, "{worst_mass}");
    assert!(worst_group < 1e-14, "{worst_group}");
    assert!(worst_balance < 1e-12, "{worst_balance}");
    assert!(
        drum == reserve && behind.abs() < 1e-12,
        "drum element {drum} with {behind} m behind the drum point"
    );
    assert_eq!(cuts, 26, "13 elements off the drum and back");
    assert_eq!(layout[0].1, start_layout[0].1 + drum - reserve);
    assert_eq!(grp.elements.start, start_range.start + drum - reserve);
    assert_eq!(grp.elements.end, start_range.end);
    assert_eq!(sim.system().mesh().lengths(), &start_lengths[..]);
    for &i in &nodes[..drum] {
        assert_eq!(sim.state().r[i], drum_point, "parked node {i}");
        assert_eq!(sim.state().v[i], Vector::<2>::zeros(), "parked node {i}");
    }
    assert!(
        off <= bound,
        "the start's drum node {off} m off, bound {bound} m"
    );
}

/// A payout speed held from outside across cuts: 0.2 m/s out for 12.5 s (2.5 m, three
/// elements off the drum), then 0.2 m/s in for 12.5 s (three back on), then held still,
/// from 10 m of rope under the 5 t payload. Guards the exact balance on every step,
/// the cut steps included (1e-12 of the energy scale, as everywhere), and the payout
/// continuing from where it is at each change of speed (back to 0 within 1e-12 m).
#[test]
fn a_held_payout_speed_pays_out_and_hauls_in_across_cuts_with_the_balance_exact() {
    use super::winch::hoist;
    let (net, _) = hoist(10, 10, |_| 0.0);
    let mut sim = Simulation::new(net, fixed_step(0.01)).unwrap_or_else(|e| panic!("{e}"));
    let (mut worst, mut worst_cut, mut out, mut back) = (0.0_f64, 0.0_f64, 0, 0);
    let mut drum_prev = drum_state(&sim).0;
    let mut energy = 0.0;
    for (until, speed) in [(0.5, 0.0), (13.0, 0.2), (25.5, -0.2), (27.0, 0.0)] {
        sim.set_winch_speed(0, speed).unwrap();
        while sim.time() < until - 1e-9 {
            let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
            let e = relative_balance(&r);
            worst = worst.max(e);
            energy += r.winch;
            let drum = drum_state(&sim).0;
            if drum != drum_prev {
                worst_cut = worst_cut.max(e);
                if drum < drum_prev {
                    out += 1;
                } else {
                    back += 1;
                }
            }
            drum_prev = drum;
        }
    }
    let w = sim.winch_samples()[0];
    eprintln!(
        "{out} cuts out, {back} back; balance/scale {worst:.1e} (cut steps {worst_cut:.1e}); payout at the end {:.1e} m; winch {:.3} J",
        w.payout, w.energy
    );
    assert!(out == 3 && back == 3, "{out} out, {back} back");
    assert!(worst < 1e-12 && worst_cut < 1e-12, "{worst} {worst_cut}");
    assert!(w.payout.abs() < 1e-12, "{}", w.payout);
    assert!((w.energy - energy).abs() <= 1e-9 * energy.abs());
}
