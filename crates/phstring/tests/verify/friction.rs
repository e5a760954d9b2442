//! Seabed friction with axial and transverse coefficients and a static peak
//! (docs/method.md §21 (21.5a), (21.5b)): steady sliding resistance against the closed form,
//! the break-away load of a rising pull, and the exact balance with both.

use std::f64::consts::PI;

use phstring::water::{STANDARD_GRAVITY as G, STATIC_PEAK_SLIP};
use phstring::{
    Friction, LineHydro, Motion, NodalLoad, PortKind, Seabed, Simulation, StepParams, Vector, Water,
};

use crate::common::chain;

const RHO_W: f64 = 1025.0;

/// Wet weight per length [N/m] of a line of `rho_a` [kg/m] and diameter `d` [m].
fn wet_weight(rho_a: f64, d: f64) -> f64 {
    (rho_a - RHO_W * PI * d * d / 4.0) * G
}

/// The regularized law's force over `μN` at the normalized slip `x` with static scale `s`
/// (21.5), (21.5b): `x/√(1 + x²) (1 + (s − 1) exp(−(x/x_S)⁴))`.
fn law(x: f64, s: f64) -> f64 {
    x / (1.0 + x * x).sqrt() * (1.0 + (s - 1.0) * (-(x / STATIC_PEAK_SLIP).powi(4)).exp())
}

/// Its maximum over the slip, by a fine scan (the closed form's regularized peak).
fn law_peak(s: f64) -> f64 {
    (1..=200_000)
        .map(|k| law(k as f64 * 1e-3, s))
        .fold(0.0, f64::max)
}

/// A 3D chain of `n` elements of `l` [m] along x on a flat seabed 60 m deep, with the
/// friction `friction`; `mass` [kg/m], diameter 0.1 m, kBot 3e6 Pa/m, cBot 3e5 Pa·s/m.
fn grounded_chain(
    n: usize,
    l: f64,
    rho_a: f64,
    friction: Friction,
) -> phstring::Network<3, phstring::Material> {
    let r: Vec<Vector<3>> = (0..=n)
        .map(|i| Vector::<3>::new(l * i as f64, 0.0, -60.0))
        .collect();
    chain(r, l, 1e9, rho_a, &[])
        .with_water(
            Water::new(RHO_W).with_seabed(Seabed::flat(60.0, 3e6, 3e5).with_friction(friction)),
        )
        .with_line_hydro(
            0,
            LineHydro {
                diameter: 0.1,
                ..Default::default()
            },
        )
}

/// The sum of the regularized law over the nodes of a chain of `n` elements of `l` sliding
/// at `v` with coefficient `mu`, slope `c` per node, static scale `s`, `N_i = w L_i`.
fn chain_law(n: usize, l: f64, w: f64, mu: f64, c: f64, v: f64, s: f64) -> f64 {
    (0..=n)
        .map(|i| {
            let li = if i == 0 || i == n { 0.5 * l } else { l };
            let a = mu * w * li;
            a * law(c * v / a, s)
        })
        .sum()
}

/// A chain lying on the seabed with axial friction μ_a = 0.3 and transverse μ_t = 0.6: pulled
/// along its axis by its end at 0.1 m/s, the pull is the axial law `Σ μ_a N_i σ(c_a v/(μ_a N_i))`
/// (to 1e-4) and Coulomb's `μ_a w L` (to 5e-3); dragged sideways at 0.1 m/s (every node's y
/// prescribed), the nodes' reactions sum to the transverse law and `μ_t w L`.
#[test]
fn axial_and_transverse_sliding_resistance() {
    let (n, l, rho_a, v) = (25, 2.0, 100.0, 0.1);
    let (mu_t, mu_a, fric_damp) = (0.6, 0.3, 2e5);
    let friction = Friction::new(mu_t, mu_t * fric_damp).with_axial(mu_a, mu_a * fric_damp);
    let w = wet_weight(rho_a, 0.1);
    let ramp = move |t: f64| v * (t - 1.0 + (-t).exp());
    let params = StepParams {
        h: 0.01,
        ..Default::default()
    };
    // Along the axis: the end pulled along x.
    let mut net = grounded_chain(n, l, rho_a, friction);
    let x0 = l * n as f64;
    net.boundary
        .motions
        .push(Motion::new(n, 0, move |t: f64| x0 + ramp(t)));
    let mut sim = Simulation::new(net, params).unwrap();
    sim.run_until(15.0, &mut ()).unwrap();
    // The reaction [N] along axis k of the prescribed node i.
    let port = |sim: &Simulation<3, phstring::Material>, i: usize, k: usize| {
        sim.ports()
            .iter()
            .find(|p| p.kind == PortKind::Velocity && p.node == i)
            .unwrap()
            .output[k]
    };
    let axial = port(&sim, n, 0);
    // Across the axis: every node dragged along y.
    let mut net = grounded_chain(n, l, rho_a, friction);
    for i in 0..=n {
        net.boundary.motions.push(Motion::new(i, 1, ramp));
    }
    let mut sim = Simulation::new(net, params).unwrap();
    sim.run_until(15.0, &mut ()).unwrap();
    let transverse: f64 = (0..=n).map(|i| port(&sim, i, 1)).sum();
    let length = l * n as f64;
    let (law_a, law_t) = (
        chain_law(n, l, w, mu_a, mu_a * fric_damp, v, 1.0),
        chain_law(n, l, w, mu_t, mu_t * fric_damp, v, 1.0),
    );
    println!(
        "axial pull {axial:.3} N (law {law_a:.3}, μ_a w L {:.3}); transverse {transverse:.3} N (law {law_t:.3}, μ_t w L {:.3})",
        mu_a * w * length,
        mu_t * w * length
    );
    for (got, law, mu) in [(axial, law_a, mu_a), (transverse, law_t, mu_t)] {
        assert!(
            (got - law).abs() <= 1e-4 * law,
            "{got} N against the law's {law} N"
        );
        let coulomb = mu * w * length;
        assert!(
            (got - coulomb).abs() <= 5e-3 * coulomb,
            "{got} N against {coulomb} N"
        );
    }
}

/// A chain on the seabed under a horizontal pull rising at 0.05 μ_k N per second on every
/// node (so that every node has the same load over its friction): with the static scale
/// s = 2 it creeps (below half the peak's slip speed up to 95 % of the peak) until the pull
/// passes the regularized peak `max ψ · μ_k W` (1.7 % below `s μ_k W`), and then slides; the
/// pull at break-away (the mean slip speed passing twice the peak's) is the peak to 1 % and
/// `s μ_k W` to 3 %.
#[test]
fn static_peak_holds_until_the_pull_exceeds_mu_s_w() {
    let (n, l, rho_a) = (4, 2.0, 100.0);
    let (mu, c, s) = (0.5, 1e5, 2.0);
    let w = wet_weight(rho_a, 0.1);
    let mut net = grounded_chain(n, l, rho_a, Friction::new(mu, c).with_static_scale(s));
    let rate = 0.05;
    let mut per_node = Vec::new();
    for i in 0..=n {
        let li = if i == 0 || i == n { 0.5 * l } else { l };
        let a = mu * w * li;
        per_node.push(a);
        net.boundary.loads.push(NodalLoad::new(i, move |t: f64| {
            Vector::<3>::new(rate * a * t, 0.0, 0.0)
        }));
    }
    let coulomb: f64 = per_node.iter().sum();
    // The slip speed at the peak of the law (x ≈ 6.5 for s = 2) at the middle nodes.
    let peak_speed = 6.5 * per_node[1] / c;
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.01,
            ..Default::default()
        },
    )
    .unwrap();
    let peak = law_peak(s) * coulomb;
    let mut breakaway = None;
    // The fastest mean slip while the pull is below 95 % of the peak: a creep.
    let mut creep = 0.0f64;
    while sim.time() < 60.0 {
        sim.step().unwrap();
        let vx = sim.state().v.iter().map(|v| v[0]).sum::<f64>() / (n + 1) as f64;
        let pull = rate * coulomb * sim.time();
        if vx > 2.0 * peak_speed {
            breakaway = Some(pull);
            break;
        }
        if pull <= 0.95 * peak {
            creep = creep.max(vx);
        }
    }
    let pull = breakaway.expect("the chain breaks away within 60 s");
    println!(
        "break-away pull {pull:.2} N: regularized peak {peak:.2} N, s μ W {:.2} N; creep ≤ {creep:.4} m/s up to 95 % of the peak (peak's slip speed {peak_speed:.4} m/s)",
        s * coulomb
    );
    assert!(creep <= 0.5 * peak_speed, "creep {creep} m/s");
    assert!(
        (pull - peak).abs() <= 1e-2 * peak,
        "{pull} N against {peak} N"
    );
    assert!((pull - s * coulomb).abs() <= 3e-2 * s * coulomb);
    // Well above the kinetic level μ W that the sliding chain then meets.
    assert!(pull > 1.9 * coulomb);
}

/// The 3D mooring line of the water tests (anchor on a seabed 50 m deep, fairlead 5 m above
/// the surface, 80 m of it grounded along x), pushed sideways by a 4 m/s current whose drag
/// exceeds the static friction, with axial and transverse friction (μ_a = 0.4, μ_t = 0.8) and
/// a static peak (s = 1.3), FricDamp 2e5 N·s/m: the grounded nodes break away, their
/// normalized slip `c_f |v|/(μN)` passing the peak (≈ 6.5) into its decay; every step's
/// balance is exact to 1e-12 of its energy scale (as with the isotropic law), every step's
/// friction dissipation ≥ 0, and the run's totals close.
#[test]
fn balance_is_exact_with_axial_friction_and_static_peak() {
    let (n, l, d) = (30, 5.0, 0.15);
    let fairlead = Vector::<3>::new(110.0, 10.0, 5.0);
    // 80 m grounded along x, then straight to the fairlead (≈ 150 m of the 150 m line).
    let grounded = 80.0;
    let r: Vec<Vector<3>> = (0..=n)
        .map(|i| {
            let s = l * i as f64;
            let touch = Vector::<3>::new(grounded, 0.0, -50.0);
            if s <= grounded {
                Vector::<3>::new(s, 0.0, -50.0)
            } else {
                let u = (fairlead - touch).normalize();
                touch + u * (s - grounded)
            }
        })
        .collect();
    let fd = 2e5;
    let friction = Friction::new(0.8, 0.8 * fd)
        .with_axial(0.4, 0.4 * fd)
        .with_static_scale(1.3);
    let current = phstring::Current::Uniform(Vector::<3>::new(0.0, 4.0, 0.0));
    let hydro = LineHydro {
        diameter: d,
        cd: 1.2,
        cd_axial: 0.4,
        ca: 1.0,
        ca_axial: 0.5,
    };
    let net = chain(r, l, 1e9, 150.0, &[0, n])
        .with_water(
            Water::new(RHO_W)
                .with_current(current)
                .with_seabed(Seabed::flat(50.0, 3e6, 3e5).with_friction(friction)),
        )
        .with_line_hydro(0, hydro);
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.01,
            ..Default::default()
        },
    )
    .unwrap();
    let h0 = sim.energies().hamiltonian();
    let (mut worst, mut scale_sum, mut friction_total, mut max_slip) = (0.0f64, 0.0, 0.0, 0.0f64);
    for _ in 0..300 {
        let r = sim.step().unwrap();
        worst = worst.max(r.relative_balance_error());
        scale_sum += r.energy_scale;
        let f = r.water.friction_dissipated;
        assert!(f >= 0.0, "step {}: friction dissipation {f:e}", r.step);
        friction_total += f;
        // The fastest slip of a grounded node, in units of μN/c_f (N = w l).
        let slip = sim.state().v[1..10]
            .iter()
            .map(|v| v.xy().norm())
            .fold(0.0, f64::max);
        max_slip = max_slip.max(slip * fd / (wet_weight(150.0, d) * l));
    }
    let closed =
        sim.energies().hamiltonian() - h0 - sim.supplied_energy() + sim.dissipated_energy();
    println!(
        "worst relative balance error {worst:e}, friction dissipated {friction_total:.4e} J, run balance {closed:e} J, largest normalized slip {max_slip:.1}"
    );
    assert!(friction_total > 0.0 && max_slip > 10.0, "slip {max_slip}");
    assert!(worst <= 1e-12, "relative balance error {worst:e}");
    assert!(closed.abs() <= 1e-12 * scale_sum, "run balance {closed:e}");
}
