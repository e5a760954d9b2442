//! Water and seabed (docs/method.md §21): the exact balance with every mechanism on and each
//! dissipation ≥ 0, neutral buoyancy, wet weight, the terminal sinking speed of a horizontal
//! cylinder, the elastic catenary with a grounded length on a frictionless seabed (closed
//! form), a chain pulled over the seabed (Coulomb's `μ w L`). Real values: chain
//! `EA = 1e9 N`, `ρA = 100…150 kg/m`, `d = 0.1…0.15 m`, depths 50–100 m.

use phstring::statics::{FirstGuess, StaticsParams, StaticsPath, solve, solve_system};
use phstring::testing::catenary_on_seabed;
use phstring::water::STANDARD_GRAVITY as G;
use phstring::{
    Current, Friction, LineHydro, Material, Motion, Network, PortKind, Seabed, Simulation,
    StepParams, Vector, Water,
};
use std::f64::consts::PI;

use crate::common::chain;

const RHO_W: f64 = 1025.0;

/// Points at arc lengths `0, l, 2l, …, n l` along the polyline `path`.
fn along<const D: usize>(path: &[Vector<D>], l: f64, n: usize) -> Vec<Vector<D>> {
    (0..=n)
        .map(|i| {
            let mut s = l * i as f64;
            for w in path.windows(2) {
                let seg = (w[1] - w[0]).norm();
                if s <= seg {
                    return w[0] + (w[1] - w[0]) * (s / seg);
                }
                s -= seg;
            }
            *path.last().unwrap()
        })
        .collect()
}

fn wet_weight(rho_a: f64, d: f64) -> f64 {
    (rho_a - RHO_W * PI * d * d / 4.0) * G
}

/// A 3D mooring line with every mechanism on: lying partly on a seabed 50 m deep with
/// stiffness, damping and friction, in a sheared current, crossing the surface to a fairlead
/// 5 m above it, with drag and added mass (`Ca ≠ CaAx`). Every step's balance is exact to
/// 1e-12 of its energy scale, every dissipation ≥ 0, and the run's totals close the balance.
#[test]
fn balance_is_exact_with_every_mechanism() {
    let (n, l, d) = (30, 5.0, 0.15);
    let anchor = Vector::<3>::new(0.0, 0.0, -50.0);
    let fairlead = Vector::<3>::new(110.0, 10.0, 5.0);
    // Grounded to x_b, then straight up: a path of length n l.
    let len = |xb: f64| xb + (fairlead - Vector::<3>::new(xb, 0.0, -50.0)).norm();
    let (mut lo, mut hi) = (0.0, 110.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if len(mid) < n as f64 * l {
            lo = mid
        } else {
            hi = mid
        }
    }
    let path = [anchor, Vector::<3>::new(lo, 0.0, -50.0), fairlead];
    let net = chain(along(&path, l, n), l, 1e9, 150.0, &[0, n]);
    let seabed = Seabed::flat(50.0, 3e6, 3e5).with_friction(Friction::new(0.5, 200.0));
    let current = Current::Profile(vec![
        (-50.0, Vector::<3>::new(0.2, 0.1, 0.0)),
        (0.0, Vector::<3>::new(1.0, 0.3, 0.0)),
    ]);
    let hydro = LineHydro {
        diameter: d,
        cd: 1.2,
        cd_axial: 0.4,
        ca: 1.0,
        ca_axial: 0.5,
    };
    let net = net
        .with_water(Water::new(RHO_W).with_current(current).with_seabed(seabed))
        .with_line_hydro(0, hydro);
    let params = StepParams {
        h: 0.01,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let h0 = sim.energies().hamiltonian();
    let (mut worst, mut grounded_seen, mut scale_sum) = (0.0f64, 0usize, 0.0);
    let mut shares = [0.0f64; 4];
    for _ in 0..300 {
        let r = sim.step().unwrap();
        worst = worst.max(r.relative_balance_error());
        scale_sum += r.energy_scale;
        let w = r.water;
        for (k, x) in [
            w.drag_dissipated,
            w.seabed_dissipated,
            w.friction_dissipated,
        ]
        .into_iter()
        .enumerate()
        {
            assert!(x >= 0.0, "step {}: dissipation {k} = {x:e} < 0", r.step);
            shares[k] += x;
        }
        shares[3] += w.current_supplied.abs();
        let sys = sim.system();
        let contacts = sys.seabed_contacts(&sim.state().r);
        // The one-node query gives each node's entry of the list.
        for c in &contacts {
            assert_eq!(sys.seabed_contact(c.node, &sim.state().r), Some(*c));
        }
        grounded_seen = grounded_seen.max(contacts.iter().filter(|c| c.grounded).count());
    }
    let z: Vec<f64> = sim.state().r.iter().map(|r| r[2]).collect();
    assert!(
        z.iter().any(|&z| z > 0.5) && z.iter().any(|&z| z < -0.5),
        "crosses the surface"
    );
    assert!(grounded_seen >= 5, "{grounded_seen} grounded nodes");
    assert!(
        shares.iter().all(|&s| s > 0.0),
        "every mechanism worked: {shares:?}"
    );
    assert!(worst <= 1e-12, "relative balance error {worst:e}");
    // Ca ≠ CaAx: the isotropic added mass's axial excess is reported, a part of T̂.
    let excess = sim.system().added_mass_axial_excess(sim.state());
    assert!(
        excess > 0.0 && excess < sim.energies().kinetic,
        "{excess:e} J"
    );
    // The run's totals: Ĥ(T) − Ĥ(0) = supplied − dissipated, the water's shares included.
    let total = sim.water_work();
    let closed =
        sim.energies().hamiltonian() - h0 - sim.supplied_energy() + sim.dissipated_energy();
    assert!(closed.abs() <= 1e-12 * scale_sum, "run balance {closed:e}");
    assert!(
        (total.dissipated() - sim.dissipated_energy()).abs() <= 1e-12 * sim.dissipated_energy()
    );
    assert!((total.current_supplied - sim.supplied_energy()).abs() <= 1e-12 * scale_sum);
    println!(
        "balance: worst {worst:e}; drag {:.4e} J, seabed {:.4e} J, friction {:.4e} J, current {:.4e} J",
        total.drag_dissipated,
        total.seabed_dissipated,
        total.friction_dissipated,
        total.current_supplied
    );
}

/// The fourth-order composition (docs/method.md §19) in the same water: each sub-step is a
/// DG step, so the step's balance is exact too (the backward sub-step gives some of its
/// dissipation back; only the sum is checked).
#[test]
fn dg4_balance_is_exact_in_water() {
    let (n, l, d) = (20, 5.0, 0.12);
    let r: Vec<Vector<3>> = along(
        &[
            Vector::<3>::new(0.0, 0.0, -40.0),
            Vector::<3>::new(30.0, 0.0, -40.0),
            Vector::<3>::new(80.0, 5.0, 3.0),
        ],
        l,
        n,
    );
    let seabed = Seabed::flat(40.0, 3e6, 3e5).with_friction(Friction::new(0.7, 300.0));
    let net = chain(r, l, 1e9, 120.0, &[0, n])
        .with_water(
            Water::new(RHO_W)
                .with_current(Current::Uniform(Vector::<3>::new(0.7, 0.4, 0.0)))
                .with_seabed(seabed),
        )
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                cd: 2.0,
                cd_axial: 0.4,
                ca: 1.0,
                ca_axial: 0.5,
            },
        );
    let params = StepParams {
        h: 0.02,
        scheme: phstring::Scheme::DiscreteGradient4,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let mut worst = 0.0f64;
    for _ in 0..100 {
        worst = worst.max(sim.step().unwrap().relative_balance_error());
    }
    assert!(worst <= 1e-12, "dg4: relative balance error {worst:e}");
    assert!(sim.water_work().dissipated() > 0.0);
}

/// A fine mooring line (120 elements: nonlinear elimination's local solves on node ranges
/// run, docs/method.md §10) dropped onto the seabed in a current: the balance stays exact.
#[test]
fn balance_is_exact_with_nonlinear_elimination() {
    let (n, l) = (120, 1.0);
    let r: Vec<Vector<3>> = along(
        &[
            Vector::<3>::new(0.0, 0.0, -38.0),
            Vector::<3>::new(50.0, 0.0, -38.0),
            Vector::<3>::new(110.0, 10.0, -2.0),
        ],
        l,
        n,
    );
    let seabed = Seabed::flat(40.0, 3e6, 3e5).with_friction(Friction::new(0.5, 200.0));
    let net = chain(r, l, 1e9, 120.0, &[0])
        .with_water(
            Water::new(RHO_W)
                .with_current(Current::Uniform(Vector::<3>::new(0.6, -0.3, 0.0)))
                .with_seabed(seabed),
        )
        .with_line_hydro(
            0,
            LineHydro {
                diameter: 0.12,
                cd: 2.4,
                cd_axial: 1.15,
                ca: 1.0,
                ca_axial: 0.5,
            },
        );
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.02,
            ..Default::default()
        },
    )
    .unwrap();
    let (mut worst, mut local) = (0.0f64, 0);
    for _ in 0..150 {
        let r = sim.step().unwrap();
        worst = worst.max(r.relative_balance_error());
        local += r.local_iterations;
    }
    assert!(local > 0, "no local solve ran");
    assert!(worst <= 1e-12, "relative balance error {worst:e}");
    let grounded = sim.system().grounded_length(0, &sim.state().r);
    assert!(grounded > 40.0, "grounded length {grounded} m");
}

/// Error control (docs/method.md §19) in water: the adaptive run reaches its end with every
/// accepted step's balance exact, a step rejected by the error estimate undone with the
/// water's running totals.
#[test]
fn error_control_in_water_keeps_the_balance() {
    let (n, l) = (24, 5.0);
    let r: Vec<Vector<3>> = along(
        &[
            Vector::<3>::new(0.0, 0.0, -50.0),
            Vector::<3>::new(30.0, 0.0, -50.0),
            Vector::<3>::new(100.0, 0.0, 4.0),
        ],
        l,
        n,
    );
    let seabed = Seabed::flat(50.0, 3e6, 3e5).with_friction(Friction::new(0.5, 200.0));
    let net = chain(r, l, 1e9, 120.0, &[0, n])
        .with_water(
            Water::new(RHO_W)
                .with_current(Current::Uniform(Vector::<3>::new(0.5, 0.5, 0.0)))
                .with_seabed(seabed),
        )
        .with_line_hydro(
            0,
            LineHydro {
                diameter: 0.12,
                cd: 2.4,
                cd_axial: 1.15,
                ca: 1.0,
                ca_axial: 0.5,
            },
        );
    let params = StepParams {
        h: 0.1,
        control: phstring::StepControl::with_tolerance(1e-3, 1e-3),
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let h0 = sim.energies().hamiltonian();
    let (mut worst, mut scale, mut rejected) = (0.0f64, 0.0, 0);
    let mut shares = phstring::WaterWork::default();
    while !sim.reached(0.5) {
        let r = sim.step_until(0.5).unwrap();
        worst = worst.max(r.relative_balance_error());
        scale += r.energy_scale;
        rejected += r.rejected;
        shares.add(&r.water);
    }
    println!(
        "error control: {} steps, {rejected} rejected, worst {worst:e}",
        sim.steps()
    );
    assert!(worst <= 1e-12, "relative balance error {worst:e}");
    let closed =
        sim.energies().hamiltonian() - h0 - sim.supplied_energy() + sim.dissipated_energy();
    assert!(closed.abs() <= 1e-12 * scale, "{closed:e}");
    // The totals count the accepted steps only.
    let total = sim.water_work();
    assert!((total.dissipated() - shares.dissipated()).abs() <= 1e-12 * scale);
    assert!((total.current_supplied - shares.current_supplied).abs() <= 1e-12 * scale);
    // The checkpoint carries the water's totals: a restore puts back those of its time.
    let cp = sim.checkpoint();
    sim.step_until(1.0).unwrap();
    assert_ne!(sim.water_work(), total);
    sim.restore(cp).unwrap();
    assert_eq!(sim.water_work(), total);
}

/// A line whose weight equals its buoyancy (`ρA = ρ_w π d²/4`), free and fully submerged in
/// still water, stays where it is.
#[test]
fn neutrally_buoyant_line_stays_put() {
    let (n, l, d) = (10, 2.0, 0.12);
    let rho_a = RHO_W * PI * d * d / 4.0;
    let r: Vec<Vector<3>> = (0..=n)
        .map(|i| Vector::<3>::new(l * i as f64, 0.0, -20.0))
        .collect();
    let net = chain(r.clone(), l, 1e9, rho_a, &[])
        .with_water(Water::new(RHO_W))
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                cd: 1.2,
                cd_axial: 0.4,
                ca: 1.0,
                ca_axial: 0.0,
            },
        );
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.02,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..500 {
        sim.step().unwrap();
    }
    let moved = sim
        .state()
        .r
        .iter()
        .zip(&r)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(moved <= 1e-9, "moved {moved:e} m in 10 s");
}

/// A vertical line hanging in water from a fixed top: the top carries the wet weight
/// `(ρA − ρ_w π d²/4) g L`.
#[test]
fn hanging_line_carries_its_wet_weight() {
    let (n, l, d, rho_a) = (25, 2.0, 0.1, 100.0);
    let r: Vec<Vector<2>> = (0..=n)
        .map(|i| Vector::<2>::new(0.0, -5.0 - l * i as f64))
        .collect();
    let net = chain(r, l, 1e9, rho_a, &[0])
        .with_water(Water::new(RHO_W))
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                cd: 1.2,
                ..Default::default()
            },
        );
    let eq = solve(net, &StaticsParams::default(), None).unwrap();
    let expected = wet_weight(rho_a, d) * l * n as f64;
    let got = eq.reactions[0][1];
    // The loads balance the reactions and the residual left at the free components, whose
    // sum is at most √n ‖R‖ (a steel chain's static residual stops at its round-off floor).
    let left = (n as f64).sqrt() * eq.residual + 1e-12 * expected;
    assert!(
        (got - expected).abs() <= left,
        "top {got} N, wet weight {expected} N, residual {:e} N",
        eq.residual
    );
    assert!(eq.reactions[0][0].abs() <= left);
    // In air the same top carries the dry weight ρA g L (the wet one is lighter by the buoyancy).
    let dry = rho_a * G * l * n as f64;
    assert!(expected < dry - 0.08 * dry);
}

/// A horizontal heavy cylinder sinking in still water reaches `v = √(2 w / (ρ_w C_d d))`
/// (with the drag's smoothing `δ`: `v √(v² + δ²) = 2w/(ρ_w C_d d)`).
#[test]
fn terminal_sinking_speed_of_a_horizontal_cylinder() {
    let (n, l, d, rho_a, cd) = (10, 2.0, 0.1, 100.0, 1.2);
    let r: Vec<Vector<3>> = (0..=n)
        .map(|i| Vector::<3>::new(l * i as f64, 0.0, -100.0))
        .collect();
    let water = Water::new(RHO_W);
    let delta = water.drag_smoothing;
    let net = chain(r, l, 1e9, rho_a, &[])
        .with_water(water)
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                cd,
                cd_axial: 0.4,
                ca: 1.0,
                ca_axial: 0.0,
            },
        );
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.01,
            ..Default::default()
        },
    )
    .unwrap();
    sim.run_until(10.0, &mut ()).unwrap();
    let v2 = 2.0 * wet_weight(rho_a, d) / (RHO_W * cd * d);
    let smoothed = (0.5 * (-delta.powi(2) + (delta.powi(4) + 4.0 * v2 * v2).sqrt())).sqrt();
    // Transverse motion: no axial added-mass excess.
    let excess = sim.system().added_mass_axial_excess(sim.state());
    assert!(excess <= 1e-12 * sim.energies().kinetic, "{excess:e} J");
    println!(
        "terminal: v = {} m/s, smoothed law {smoothed} m/s, Morison {} m/s",
        -sim.state().v[0][2],
        v2.sqrt()
    );
    for v in &sim.state().v {
        let vz = -v[2];
        assert!(
            (vz - smoothed).abs() <= 1e-9 * smoothed,
            "v = {vz} m/s, smoothed law {smoothed}"
        );
        assert!(
            (vz - v2.sqrt()).abs() <= 1e-6 * v2.sqrt(),
            "v = {vz} m/s, Morison {}",
            v2.sqrt()
        );
        assert!(v[0].abs() <= 1e-9 && v[1].abs() <= 1e-9);
    }
}

/// The elastic catenary with a grounded length, in statics, on a frictionless seabed 100 m
/// deep with the penalty stiffness `kBot` growing: the fairlead's horizontal and vertical
/// tension and the grounded length converge to the closed form, and where the line lies its
/// penetration is `w/(k d)`.
#[test]
fn catenary_with_grounded_length_matches_the_closed_form() {
    let (n, l, d, rho_a, ea, depth) = (300, 1.0, 0.1, 100.0, 1e9, 100.0);
    let (x, zf) = (250.0, -10.0);
    let w = wet_weight(rho_a, d);
    let (h_cf, v_cf, lb_cf) = catenary_on_seabed(n as f64 * l, w, ea, x, zf + depth);
    let anchor = Vector::<2>::new(0.0, -depth);
    let fairlead = Vector::<2>::new(x, zf);
    let len = |xb: f64| xb + (fairlead - Vector::<2>::new(xb, -depth)).norm();
    let (mut lo, mut hi) = (0.0, x);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if len(mid) < n as f64 * l {
            lo = mid
        } else {
            hi = mid
        }
    }
    let path = [anchor, Vector::<2>::new(lo, -depth), fairlead];
    let mut errors = Vec::new();
    for k in [3e5, 3e6, 3e7] {
        let net = chain(along(&path, l, n), l, ea, rho_a, &[0, n])
            .with_water(Water::new(RHO_W).with_seabed(Seabed::flat(depth, k, 0.0)))
            .with_line_hydro(
                0,
                LineHydro {
                    diameter: d,
                    cd: 1.2,
                    ..Default::default()
                },
            );
        let (sys, init) = phstring::PhSystem::new(net).unwrap();
        let eq = phstring::statics::solve_system(&sys, &init.r, &StaticsParams::default(), None)
            .unwrap();
        let hf = eq.reactions[n][0];
        let ha = -eq.reactions[0][0];
        // The fairlead holds the wet weight of the whole suspended part.
        let vf = eq.reactions[n][1];
        let lb = sys.grounded_length(0, &eq.state.r);
        let p = -(eq.state.r[n / 10][1] + depth);
        let p_expected = w / (k * d);
        assert!(
            (p - p_expected).abs() <= 1e-6 * p_expected,
            "k {k:e}: penetration {p:e} m, w/(kd) {p_expected:e}"
        );
        let e = ((hf - h_cf) / h_cf, (vf - v_cf) / v_cf, lb - lb_cf);
        println!(
            "k = {k:e} Pa/m: H {hf:.3} N (anchor {ha:.3}, closed form {h_cf:.3}), V_F {vf:.3} N ({v_cf:.3}), L_b {lb:.2} m ({lb_cf:.2}), penetration {p:.3e} m; errors {:.2e} {:.2e} {:.2} m",
            e.0, e.1, e.2
        );
        // Frictionless: the anchor carries the horizontal tension.
        assert!((ha - hf).abs() <= 1e-6 * hf);
        errors.push(e);
    }
    // The penetration p = w/(kd) raises the effective height by p: the tensions' errors
    // shrink with it, to the mesh's O(l²) level at the stiffest seabed.
    for pair in errors.windows(2) {
        assert!(pair[1].0.abs() < pair[0].0.abs() && pair[1].1.abs() < pair[0].1.abs());
    }
    let last = errors.last().unwrap();
    // (3e-4 m of penetration over the 90 m height is 3e-6.)
    assert!(last.0.abs() <= 1e-5 && last.1.abs() <= 1e-5, "{last:?}");
    // The grounded length to within the element length and the touchdown's boundary layer.
    assert!(last.2.abs() <= 2.0 * l, "{last:?}");
}

/// A chain lying on the seabed, pulled slowly along it: the pulling force tends to Coulomb's
/// `μ w L`, here the regularized law's `Σ_i μ N_i σ(c_f v/(μ N_i))` with `N_i = w L_i`.
#[test]
fn chain_pulled_over_the_seabed_needs_mu_w_l() {
    let (n, l, d, rho_a, depth, mu, slope, v) = (25, 2.0, 0.1, 100.0, 60.0, 0.5, 1e5, 0.1);
    let r: Vec<Vector<3>> = (0..=n)
        .map(|i| Vector::<3>::new(l * i as f64, 0.0, -depth))
        .collect();
    let mut net = chain(r, l, 1e9, rho_a, &[])
        .with_water(
            Water::new(RHO_W)
                .with_seabed(Seabed::flat(depth, 3e6, 3e5).with_friction(Friction::new(mu, slope))),
        )
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                ..Default::default()
            },
        );
    let x0 = l * n as f64;
    // Pulled along x from rest, the speed building up over τ = 1 s.
    net.boundary.motions.push(Motion::new(n, 0, move |t: f64| {
        x0 + v * (t - 1.0 + (-t).exp())
    }));
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.01,
            ..Default::default()
        },
    )
    .unwrap();
    sim.run_until(15.0, &mut ()).unwrap();
    let port = sim
        .ports()
        .iter()
        .find(|p| p.kind == PortKind::Velocity && p.node == n)
        .unwrap();
    let pull = port.output[0];
    let w = wet_weight(rho_a, d);
    let coulomb = mu * w * l * n as f64;
    let regularized: f64 = (0..=n)
        .map(|i| {
            let li = if i == 0 || i == n { 0.5 * l } else { l };
            let a = mu * w * li;
            let x = slope * v / a;
            a * x / (1.0 + x * x).sqrt()
        })
        .sum();
    println!("pull {pull:.3} N, regularized law {regularized:.3} N, μ w L {coulomb:.3} N");
    assert!(
        (pull - regularized).abs() <= 1e-4 * regularized,
        "pull {pull} N, law {regularized} N"
    );
    assert!((pull - coulomb).abs() <= 5e-3 * coulomb);
}

/// A line hanging from a fixed top in a uniform current, its lower end free, with no axial
/// drag: in statics it is straight at the angle `θ` from the vertical where the normal drag
/// balances the normal part of the wet weight, `w sin θ = ½ ρ_w C_d d U cos θ √(U² cos² θ + δ²)`
/// (the drag at rest, `v_r = −u`).
#[test]
fn line_in_a_current_hangs_at_the_drag_angle() {
    let (n, l, d, rho_a, cd, u) = (20, 2.0, 0.1, 100.0, 1.2, 2.0);
    let r: Vec<Vector<2>> = (0..=n)
        .map(|i| Vector::<2>::new(0.0, -5.0 - l * i as f64))
        .collect();
    let water = Water::new(RHO_W).with_current(Current::Uniform(Vector::<2>::new(u, 0.0)));
    let delta = water.drag_smoothing;
    let net = chain(r, l, 1e9, rho_a, &[0])
        .with_water(water)
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                cd,
                ..Default::default()
            },
        );
    let eq = solve(net, &StaticsParams::default(), None).unwrap();
    let w = wet_weight(rho_a, d);
    let normal = |th: f64| {
        let un = u * th.cos();
        0.5 * RHO_W * cd * d * un * (un * un + delta * delta).sqrt() - w * th.sin()
    };
    let (mut lo, mut hi) = (0.0, 1.5);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if normal(mid) > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let theta = 0.5 * (lo + hi);
    for pair in eq.state.r.windows(2) {
        let dr = pair[1] - pair[0];
        let got = dr[0].atan2(-dr[1]);
        assert!(
            (got - theta).abs() <= 1e-9,
            "angle {got} rad, closed form {theta} rad"
        );
    }
    // The top holds the whole load, weight and normal drag `w sin θ` per length: along the
    // line, `w L cos θ (sin θ, −cos θ)`.
    let f = eq.reactions[0];
    let wl = w * l * n as f64;
    let expected = [-wl * theta.sin() * theta.cos(), wl * theta.cos().powi(2)];
    for k in 0..2 {
        assert!(
            (f[k] - expected[k]).abs() <= 1e-9 * wl,
            "{f:?} vs {expected:?}"
        );
    }
}

/// Water's refusals, each naming the bad value: dimension 1, a negative or non-finite
/// parameter, a profile out of order, hydrodynamics without water or on a spring.
#[test]
fn invalid_water_is_refused_with_the_value() {
    use phstring::{PhSystem, SetupError};
    let line = LineHydro {
        diameter: 0.1,
        cd: 1.2,
        ..Default::default()
    };
    let r1: Vec<Vector<1>> = (0..=2).map(|i| Vector::<1>::new(-(i as f64))).collect();
    let err =
        PhSystem::new(chain(r1, 1.0, 1e6, 10.0, &[0]).with_water(Water::new(RHO_W))).unwrap_err();
    assert_eq!(err, SetupError::WaterDimension { dimension: 1 });
    assert!(err.to_string().contains("D = 1"), "{err}");
    let r: Vec<Vector<2>> = (0..=2)
        .map(|i| Vector::<2>::new(0.0, -(i as f64)))
        .collect();
    let net = || chain(r.clone(), 1.0, 1e6, 10.0, &[0]);
    let refuse = |n: Network<2, Material>| PhSystem::new(n).unwrap_err();
    let bad_cd = LineHydro { cd: -0.5, ..line };
    let e = refuse(
        net()
            .with_water(Water::new(RHO_W))
            .with_line_hydro(0, bad_cd),
    );
    assert!(
        matches!(e, SetupError::WaterParameter { value, index: Some(0), .. } if value == -0.5),
        "{e}"
    );
    assert!(e.to_string().contains("-0.5"), "{e}");
    let e = refuse(net().with_water(Water::new(f64::NAN)));
    assert!(
        matches!(e, SetupError::WaterParameter { value, .. } if value.is_nan()),
        "{e}"
    );
    let e = refuse(net().with_water(Water::new(RHO_W).with_seabed(Seabed::flat(-3.0, 1e6, 0.0))));
    assert!(
        e.to_string().contains("depth") && e.to_string().contains("-3"),
        "{e}"
    );
    let profile = Current::Profile(vec![(0.0, Vector::zeros()), (-10.0, Vector::zeros())]);
    let e = refuse(net().with_water(Water::new(RHO_W).with_current(profile)));
    assert!(
        matches!(e, SetupError::WaterParameter { index: Some(1), value, .. } if value == -10.0),
        "{e}"
    );
    let e = refuse(net().with_line_hydro(0, line));
    assert_eq!(e, SetupError::HydroWithoutWater);
    let e = refuse(net().with_water(Water::new(RHO_W)).with_line_hydro(3, line));
    assert!(e.to_string().contains('3'), "{e}");
    let e = refuse(
        net()
            .with_water(Water::new(RHO_W))
            .with_line_hydro(0, line)
            .with_line_hydro(0, line),
    );
    assert!(matches!(e, SetupError::HydroGroup { group: 0, .. }), "{e}");
}

/// The sum of every block of the damping matrix `R_v` of a line at rest: the resisting force
/// per unit velocity of a rigid translation [N·s/m].
fn total_damping(net: Network<3, Material>) -> phstring::linsolve::Block<3> {
    let (sys, state) = phstring::PhSystem::new(net).unwrap();
    let rv = phstring::linear::damping_blocks(&sys, &state.r);
    let mut sum = rv.diag.iter().sum::<phstring::linsolve::Block<3>>();
    for [a, b] in &rv.off {
        sum += a + b;
    }
    sum
}

/// The linear model's water damping (docs/method.md §21) against closed forms on a 20 m
/// line (d = 0.1 m, Cd = 1.2, CdAx = 0.4) lying along x, 20 m deep: in still water with an
/// equivalent-linear amplitude of 0.5 m/s, Lorentz's `(8/3π) ½ρ C d V L` in each direction;
/// in a transverse current of 1.5 m/s without it, the derivative of `½ρ Cd d |v_r| v_r`,
/// `2 ½ρ Cd d u L` along the current and `½ρ Cd d u L` across it; on the seabed, the seabed
/// damping `cBot d L` normal to it and the friction slope per node within its plane; with
/// axial friction and a static peak `s`, `s c_a` per node along the line and `s c_f` across.
#[test]
fn linear_model_damping_of_the_water_matches_closed_forms() {
    let (n, l, d, cd, cda) = (10, 2.0, 0.1, 1.2, 0.4);
    let total = n as f64 * l;
    let line = |z: f64| -> Network<3, Material> {
        let r = (0..=n)
            .map(|i| Vector::<3>::new(l * i as f64, 0.0, z))
            .collect();
        chain(r, l, 1e9, 20.0, &[])
    };
    let hydro = LineHydro {
        diameter: d,
        cd,
        cd_axial: cda,
        ca: 1.0,
        ca_axial: 1.0,
    };
    let (an, aa) = (
        0.5 * RHO_W * cd * d * total,
        0.5 * RHO_W * cda * PI * d * total,
    );
    let lorentz = 8.0 / (3.0 * PI);
    // Still water, amplitude V.
    let (v, delta) = (0.5, phstring::water::DEFAULT_DRAG_SMOOTHING);
    let mut water = Water::new(RHO_W);
    water.linear_drag_amplitude = v;
    let c = total_damping(line(-20.0).with_water(water).with_line_hydro(0, hydro));
    let expected = [
        aa * (delta + lorentz * v),
        an * (delta + lorentz * v),
        an * (delta + lorentz * v),
    ];
    for k in 0..3 {
        assert!(
            (c[(k, k)] - expected[k]).abs() <= 1e-12 * expected[k],
            "still water, axis {k}: {} vs {}",
            c[(k, k)],
            expected[k]
        );
    }
    // No coupling between the axes of a line along x.
    let off = c - phstring::linsolve::Block::<3>::from_diagonal(&c.diagonal());
    assert!(off.abs().max() <= 1e-12 * expected[0], "{c}");
    // A transverse current along y, no amplitude.
    let u = 1.5;
    let water = Water::new(RHO_W).with_current(Current::Uniform(Vector::<3>::new(0.0, u, 0.0)));
    let c = total_damping(line(-20.0).with_water(water).with_line_hydro(0, hydro));
    let s = (u * u + delta * delta).sqrt();
    let expected = [aa * delta, an * (s + u * u / s), an * s];
    for k in 0..3 {
        assert!(
            (c[(k, k)] - expected[k]).abs() <= 1e-12 * expected[k],
            "current, axis {k}: {} vs {}",
            c[(k, k)],
            expected[k]
        );
    }
    // On a seabed at 20 m, pressed 1 cm in (beyond the 1 mm damping ramp); no drag.
    let (cbot, slope) = (3e5, 200.0);
    let seabed = Seabed::flat(20.0, 3e6, cbot).with_friction(Friction::new(0.5, slope));
    let calm = LineHydro {
        cd: 0.0,
        cd_axial: 0.0,
        ..hydro
    };
    let c = total_damping(
        line(-20.01)
            .with_water(Water::new(RHO_W).with_seabed(seabed))
            .with_line_hydro(0, calm),
    );
    let expected = [
        slope * (n + 1) as f64,
        slope * (n + 1) as f64,
        cbot * d * total,
    ];
    for k in 0..3 {
        assert!(
            (c[(k, k)] - expected[k]).abs() <= 1e-12 * expected[k],
            "seabed, axis {k}: {} vs {}",
            c[(k, k)],
            expected[k]
        );
    }
    // Axial friction (slope 80 N·s/m along the line's axis x, 200 across it) and a static
    // peak s = 1.5: the zero-slip slopes s c_a along x and s c_f along y.
    let seabed = Seabed::flat(20.0, 3e6, cbot).with_friction(
        Friction::new(0.5, slope)
            .with_axial(0.2, 80.0)
            .with_static_scale(1.5),
    );
    let c = total_damping(
        line(-20.01)
            .with_water(Water::new(RHO_W).with_seabed(seabed))
            .with_line_hydro(0, calm),
    );
    let expected = [
        1.5 * 80.0 * (n + 1) as f64,
        1.5 * slope * (n + 1) as f64,
        cbot * d * total,
    ];
    for k in 0..3 {
        assert!(
            (c[(k, k)] - expected[k]).abs() <= 1e-12 * expected[k],
            "axial friction, axis {k}: {} vs {}",
            c[(k, k)],
            expected[k]
        );
    }
    let off = c - phstring::linsolve::Block::<3>::from_diagonal(&c.diagonal());
    assert!(off.abs().max() <= 1e-12 * expected[0], "{c}");
}

/// Lorentz's equivalence behind `linear_drag_amplitude`: over a cycle of `v = V sin ωt`, the
/// quadratic drag `α |v| v` and the linear `(8/3π) α V v` dissipate the same energy (midpoint
/// quadrature of 10⁵ points, to 1e-9).
#[test]
fn equivalent_linear_drag_dissipates_as_the_quadratic_one_over_a_cycle() {
    let (alpha, v) = (61.5, 0.8);
    let m = 100_000;
    let (mut quad, mut lin) = (0.0, 0.0);
    for i in 0..m {
        let s = (2.0 * PI * (i as f64 + 0.5) / m as f64).sin() * v;
        quad += alpha * s.abs() * s * s;
        lin += 8.0 / (3.0 * PI) * alpha * v * s * s;
    }
    assert!((quad - lin).abs() <= 1e-9 * quad, "{quad} vs {lin}");
}

/// The shallow chain of `examples/moordyn/chain_shallow_v1.dat` in 3D: 400 m of studless
/// chain (390 kg/m, d = 0.252 m, EA = 1.674e9 N) in 40 elements from an anchor on a seabed
/// 50 m deep (kBot = 3e6 Pa/m) to a fairlead 380 m away and 8 m below the surface, laid out
/// along the seabed and straight up with its unstretched length; `seabed` replaces the flat
/// seabed if given.
fn shallow_chain(seabed: Option<Seabed<3>>) -> (phstring::PhSystem<3, Material>, Vec<Vector<3>>) {
    let (n, l, d, rho_a, ea, depth) = (40, 10.0, 0.252, 390.0, 1.674e9, 50.0);
    let anchor = Vector::<3>::new(420.0, 0.0, -depth);
    let fairlead = Vector::<3>::new(40.0, 0.0, -8.0);
    // The touchdown of the straight layout: seabed and straight up make 400 m.
    let len = |t: f64| t + (fairlead - Vector::<3>::new(420.0 - t, 0.0, -depth)).norm();
    let (mut lo, mut hi) = (0.0, 380.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if len(mid) < n as f64 * l {
            lo = mid
        } else {
            hi = mid
        }
    }
    let touchdown = Vector::<3>::new(420.0 - lo, 0.0, -depth);
    let seabed = seabed.unwrap_or_else(|| Seabed::flat(depth, 3e6, 0.0));
    let net = chain(
        along(&[anchor, touchdown, fairlead], l, n),
        l,
        ea,
        rho_a,
        &[0, n],
    )
    .with_water(Water::new(RHO_W).with_seabed(seabed))
    .with_line_hydro(
        0,
        LineHydro {
            diameter: d,
            cd: 2.4,
            ..Default::default()
        },
    );
    let (sys, init) = phstring::PhSystem::new(net).unwrap();
    (sys, init.r)
}

/// The catenary first guess of the shallow chain (grounded over about 300 m, 6–7 elements in
/// its suspended span) lies within 6 mm of the equilibrium (measured 4.2 mm) and its
/// fairlead tension within 5e-4 of it (measured 1.4e-4: the touchdown node's share of the
/// seabed's reaction and the penetration there are what the guess leaves out); Newton from
/// it converges in at most 4 iterations (measured 3) to the equilibrium the other paths
/// find without it (pseudo-transient, 31 steps, 423 iterations; fairlead tension to 1e-9,
/// measured 9.5e-12). With one Newton iteration allowed, Newton from the guess fails and
/// the pseudo-transient path still finds that equilibrium.
#[test]
fn catenary_guess_of_a_grounded_chain_starts_newton_next_to_the_equilibrium() {
    let (sys, r0) = shallow_chain(None);
    let n = 40;
    let guess = phstring::statics::catenary_guess(&sys, &r0).unwrap();
    let eq = solve_system(&sys, &r0, &StaticsParams::default(), None).unwrap();
    assert_eq!(eq.path, StaticsPath::CatenaryGuess);
    assert_eq!(eq.guess, FirstGuess::Used);
    assert!(eq.iterations <= 4, "{} iterations", eq.iterations);
    let off = guess
        .iter()
        .zip(&eq.state.r)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    let (_, reactions) = phstring::statics::static_residual(&sys, &guess).unwrap();
    let t_guess = reactions[n].norm();
    let t_eq = eq.reactions[n].norm();
    let e_guess = (t_guess - t_eq).abs() / t_eq;
    println!(
        "guess: {off:.3e} m off, fairlead tension {t_guess:.3} N against {t_eq:.3} N ({e_guess:.2e}); {} Newton iterations",
        eq.iterations
    );
    assert!(off <= 6e-3, "{off:e} m");
    assert!(e_guess <= 5e-4, "{e_guess:e}");
    let without = StaticsParams {
        first_guess: false,
        ..Default::default()
    };
    let old = solve_system(&sys, &r0, &without, None).unwrap();
    assert_ne!(old.path, StaticsPath::CatenaryGuess);
    let e_old = (old.reactions[n].norm() - t_eq).abs() / t_eq;
    println!(
        "without the guess: {:?}, {} iterations, tension {e_old:.2e} off",
        old.path, old.iterations
    );
    assert!(e_old <= 1e-9, "{e_old:e}");
    let mut tight = StaticsParams::default();
    tight.newton.max_iter = 1;
    let fallback = solve_system(&sys, &r0, &tight, None).unwrap();
    assert!(
        matches!(fallback.guess, FirstGuess::Failed(_)),
        "{:?}",
        fallback.guess
    );
    let e_fb = (fallback.reactions[n].norm() - t_eq).abs() / t_eq;
    println!(
        "fallback: {:?} {:?}, tension {e_fb:.2e} off",
        fallback.path, fallback.guess
    );
    assert!(e_fb <= 1e-9, "{e_fb:e}");
}

/// On a seabed falling at 2° from the anchor towards the fairlead the grounded part of a flat guess would lie metres off the
/// seabed: the guess does not apply (the message says where), and the other paths find the
/// equilibrium, with the anchor's pull along the slope.
#[test]
fn catenary_guess_falls_back_on_a_sloped_seabed() {
    let a = 2f64.to_radians();
    let normal = Vector::<3>::new(-a.sin(), 0.0, a.cos());
    let plane = Seabed::plane(Vector::<3>::new(420.0, 0.0, -50.0), normal, 3e6, 0.0);
    let (sys, r0) = shallow_chain(Some(plane));
    let why = phstring::statics::catenary_guess(&sys, &r0).unwrap_err();
    assert!(
        why.contains("not flat") && why.contains("'string'"),
        "{why}"
    );
    let eq = solve_system(&sys, &r0, &StaticsParams::default(), None).unwrap();
    assert_ne!(eq.path, StaticsPath::CatenaryGuess);
    assert!(
        matches!(&eq.guess, FirstGuess::NotApplicable(w) if *w == why),
        "{:?}",
        eq.guess
    );
    assert!(
        eq.stable && eq.reactions[0][0] > 0.0,
        "{:?}",
        eq.reactions[0]
    );
}
