//! A seabed given as a bathymetry grid (docs/method.md §21): the step's balance stays exact
//! with the nonlinear gap (its exact discrete gradient), every dissipation ≥ 0; and on a
//! grid that is an incline, statics put a grounded chain at the vertical penetration
//! `w cos²α/(k d)` and change its tension along the incline by `w sin α` per metre.
//! Real values: chain `EA = 1e9 N`, `ρA = 150 kg/m`, `d = 0.15 m`, about 50 m of water.

use phstring::statics::{StaticsParams, solve};
use phstring::water::STANDARD_GRAVITY as G;
use phstring::{
    Bathymetry, Current, Friction, LineHydro, Seabed, Simulation, StepParams, Vector, Water,
};
use std::f64::consts::PI;

use crate::common::chain;

const RHO_W: f64 = 1025.0;

/// A bumpy seabed about 50 m deep: ±2 m waves along x, a cross slope along y, on a grid of
/// 20 m (uneven at one end).
fn bumpy_depth(x: f64, y: f64) -> f64 {
    50.0 + 2.0 * (x / 25.0).sin() - 0.03 * x + 0.02 * y
}

/// A 3D chain dropped from 0.3 m above a bumpy grid seabed (stiffness, damping, friction),
/// its far end free, in a current that drags it sideways over the bumps: every step's
/// balance is exact to 1e-12 of its energy scale, every dissipation ≥ 0, and the chain
/// touches the seabed and slides on it.
#[test]
fn balance_is_exact_on_a_bathymetry_grid() {
    let (n, l, d) = (30, 5.0, 0.15);
    let xs: Vec<f64> = (-1..=8).map(|i| 20.0 * i as f64).chain([175.0]).collect();
    let ys: Vec<f64> = vec![-40.0, -20.0, 0.0, 20.0, 40.0];
    let depths = ys
        .iter()
        .flat_map(|&y| xs.iter().map(move |&x| bumpy_depth(x, y)))
        .collect();
    let grid = Bathymetry::grid(xs, ys, depths).unwrap();
    let r: Vec<Vector<3>> = (0..=n)
        .map(|i| {
            let x = l * i as f64;
            Vector::<3>::new(x, 0.0, 0.3 - grid.depth_at(x, 0.0))
        })
        .collect();
    let seabed = Seabed::grid(grid, 3e6, 3e5).with_friction(Friction::new(0.5, 200.0));
    let net = chain(r, l, 1e9, 150.0, &[0])
        .with_water(
            Water::new(RHO_W)
                .with_current(Current::Uniform(Vector::<3>::new(0.3, 1.5, 0.0)))
                .with_seabed(seabed),
        )
        .with_line_hydro(
            0,
            LineHydro {
                diameter: d,
                cd: 1.2,
                cd_axial: 0.4,
                ca: 1.0,
                ca_axial: 0.5,
            },
        );
    let params = StepParams {
        h: 0.01,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let (mut worst, mut grounded_seen) = (0.0f64, 0usize);
    for _ in 0..300 {
        let r = sim.step().unwrap();
        worst = worst.max(r.relative_balance_error());
        let w = r.water;
        for x in [
            w.drag_dissipated,
            w.seabed_dissipated,
            w.friction_dissipated,
        ] {
            assert!(x >= 0.0, "step {}: dissipation {x:e} < 0", r.step);
        }
        grounded_seen = grounded_seen.max(
            sim.system()
                .seabed_contacts(&sim.state().r)
                .iter()
                .filter(|c| c.grounded)
                .count(),
        );
    }
    let total = sim.water_work();
    assert!(grounded_seen >= 25, "{grounded_seen} grounded nodes");
    assert!(
        total.seabed_dissipated > 0.0 && total.friction_dissipated > 0.0,
        "{total:?}"
    );
    // The current pushed the chain sideways (y) over the seabed.
    let tip = sim.state().r[n];
    assert!(tip[1] > 0.05, "tip at {tip}");
    assert!(worst <= 1e-12, "relative balance error {worst:e}");
    println!("bathymetry balance: worst {worst:e}, {grounded_seen} grounded, {total:?}");
}

/// A 2D chain on a grid profile that is an incline rising at `α` (depth 120 m at x = 0,
/// `tan α = 0.06`), held at its upper end and free at its lower end, on a frictionless seabed:
/// statics put its nodes (away from the held end) at the vertical penetration `w cos²α/(k d)` (the normal contact force
/// `k d p/cos α` carries the normal weight `w cos α`), to 1e-6; the held end pulls up the
/// incline with the weight along it, `w sin α L`, to 1e-6, and holds its own node's normal
/// weight plus the last element's tilt, `w cos α l/2 + T p/l`, to 1e-4.
#[test]
fn statics_on_a_grid_incline() {
    let (n, l, d, rho_a, k) = (40, 2.5, 0.15, 150.0, 3e6);
    let slope: f64 = 0.06;
    let depth = |x: f64| 120.0 - slope * x;
    let xs: Vec<f64> = vec![-50.0, 0.0, 30.0, 70.0, 100.0, 160.0];
    let ds = xs.iter().map(|&x| depth(x)).collect();
    let grid = Bathymetry::profile(xs, ds).unwrap();
    let (c, s) = (
        1.0 / (1.0 + slope * slope).sqrt(),
        slope / (1.0 + slope * slope).sqrt(),
    );
    // Along the incline from x = 0 to x = L cos α, on its surface.
    let r: Vec<Vector<2>> = (0..=n)
        .map(|i| {
            let x = l * i as f64 * c;
            Vector::<2>::new(x, -depth(x))
        })
        .collect();
    let hydro = LineHydro {
        diameter: d,
        cd: 1.2,
        cd_axial: 0.4,
        ca: 1.0,
        ca_axial: 0.5,
    };
    let net = chain(r, l, 1e9, rho_a, &[n])
        .with_water(Water::new(RHO_W).with_seabed(Seabed::grid(grid, k, 0.0)))
        .with_line_hydro(0, hydro);
    let out = solve(net, &StaticsParams::default(), None).unwrap();
    let w = (rho_a - RHO_W * PI * d * d / 4.0) * G;
    let expected = w * c * c / (k * d);
    let r = &out.state.r;
    // Away from the held end (it sits on the surface, so its element tilts by p/l and the
    // tension presses the node next to it by T p/l more).
    for i in [1, n / 4, n / 2, 3 * n / 4] {
        let p = -depth(r[i][0]) - r[i][1];
        assert!(
            (p - expected).abs() <= 1e-6 * expected,
            "node {i}: penetration {p:e} vs w cos²α/(kd) = {expected:e}"
        );
    }
    // The support pulls up the incline with the whole weight along it, and holds the
    // normal weight of its own node's half element.
    let (t, nrm) = (Vector::<2>::new(c, s), Vector::<2>::new(-s, c));
    let reaction = out.reactions[n];
    let (along, normal) = (reaction.dot(&t), reaction.dot(&nrm));
    let want = w * s * l * n as f64;
    assert!(
        (along - want).abs() <= 1e-6 * want,
        "held end pulls {along} N along the incline, w sin α L = {want} N"
    );
    // Normal to it: its own node's half element, and the last element's tension turned by
    // the tilt p/l (the tension there is w sin α L to one element's share, ~1 %).
    let own = w * c * 0.5 * l + want * expected / l;
    assert!(
        (normal - own).abs() <= 1e-4 * own,
        "held end's normal force {normal} N vs w cos α l/2 + T p/l = {own} N"
    );
}
