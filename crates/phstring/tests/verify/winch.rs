//! Winches (docs/method.md §23): a payload hoisted and lowered on a steel wire rope paid out
//! from or hauled onto a drum, against the exact discrete balance, the mass off the drum,
//! and the static energies of the hanging rope before and after.

use phstring::{
    Boundary, MassMatrix, Material, Network, NetworkBuilder, PointMass, Simulation, State,
    StepControl, StepParams, StringSpec, Vector, Winch,
};
use std::sync::Arc;

pub(super) const G: f64 = 9.81;
/// A 32 mm six-strand steel wire rope: axial stiffness [N] and mass per metre [kg/m].
pub(super) const EA: f64 = 4.3e7;
pub(super) const RHO_A: f64 = 4.1;
/// The payload [kg] and the element length [m].
pub(super) const PAYLOAD: f64 = 5000.0;
pub(super) const L: f64 = 1.0;

/// Height below the drum [m] of the point at unstretched distance `s` [m] from the drum of
/// a vertical rope of unstretched length `a` [m] hanging with the payload at its end, at
/// rest: `y(s) = −(s + g((m + ρA a) s − ρA s²/2)/EA)`.
fn hanging(s: f64, a: f64) -> f64 {
    -(s + G * ((PAYLOAD + RHO_A * a) * s - 0.5 * RHO_A * s * s) / EA)
}

/// The static energy [J] of that rope and payload: the weight's potential and the strain
/// energy `∫ T²/(2 EA) ds` with `T(s) = g (m + ρA (a − s))`.
fn static_energy(a: f64) -> f64 {
    let n = 20000;
    let ds = a / n as f64;
    let mut e = PAYLOAD * G * hanging(a, a);
    for k in 0..n {
        let s = (k as f64 + 0.5) * ds;
        let t = G * (PAYLOAD + RHO_A * (a - s));
        e += RHO_A * G * hanging(s, a) * ds + t * t / (2.0 * EA) * ds;
    }
    e
}

/// The change of the static energy [J] from `a0` to `a` metres of rope off the drum as the
/// model holds it at the end of a run of `sim`, with what it adds: the cable between the
/// drum node and the drum point (`behind`, at most one element, drawn straight above the
/// drum: its weight's potential and strain energy at the drum's tension are in `Ĥ`), and
/// the drum node's offset from where that cable's static stretch puts it (its last cut put
/// it on the string's stretch at that moment, which the payload's bounce sets; the string
/// below hangs from there). Returns the change, `behind` [m], the cable's energy [J] and the
/// offset [m].
fn static_change(sim: &Simulation<2, Material>, a: f64, a0: f64) -> (f64, f64, f64, f64) {
    let cp = sim.checkpoint();
    let behind = cp.winches[0].behind(cp.winches[0].payout);
    let top = G * (PAYLOAD + RHO_A * a);
    let stretch = 1.0 + top / EA;
    let virtual_part =
        RHO_A * G * stretch * behind * behind / 2.0 + top * top / (2.0 * EA) * behind;
    let (drum_node, _) = sim.system().winch_layout(&cp.winches)[0];
    let offset = sim.state().r[drum_node][1] - stretch * behind;
    let change = static_energy(a) + virtual_part + top * offset - static_energy(a0);
    (change, behind, virtual_part, offset)
}

/// A 2D hoist: a drum at the origin, `n_el` elements of 1 m hanging below it with the
/// payload at the end, `reserve` more on the drum, at rest in its static shape; the winch
/// pays out `payout(t)`.
pub(super) fn hoist(
    n_el: usize,
    reserve: usize,
    payout: impl Fn(f64) -> f64 + Send + Sync + 'static,
) -> (Network<2, Material>, usize) {
    let zero = Vector::<2>::zeros();
    let (net, g, _, hook) = rope_below(zero, zero, n_el, reserve);
    let net = net.with_winch(Winch {
        name: "hoist".into(),
        group: g,
        reserve,
        payout: Arc::new(payout),
        drum_motion: None,
        drum: None,
    });
    (net, hook)
}

/// The rope of [`hoist`] without its winch: `n_el` elements of 1 m with the payload at their
/// end and `reserve` elements on the drum, hanging in their static shape below the drum point
/// `top` [m], moving at `v0` [m/s] (the drum point's velocity at `t = 0`: the nodes on the
/// drum and the drum node move with it). Returns the network, the rope's group, its first
/// path node (the drum) and the hook.
pub(super) fn rope_below(
    top: Vector<2>,
    v0: Vector<2>,
    n_el: usize,
    reserve: usize,
) -> (Network<2, Material>, usize, usize, usize) {
    let a = n_el as f64 * L;
    let mut b = NetworkBuilder::<2, Material>::new();
    let drum = b.node(top);
    let hook = b.node(top + Vector::<2>::new(0.0, -a));
    let spec = StringSpec {
        name: "rope".into(),
        material: Material::tension_only_linear(EA),
        rho_a: RHO_A,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -RHO_A * G),
        prestretch: 1.0,
    };
    let g = b
        .string_on_drum(spec, &[drum, hook], n_el, reserve)
        .unwrap();
    let nodes = b.group_nodes(g).unwrap().to_vec();
    let masses = vec![PointMass {
        node: hook,
        mass: PAYLOAD,
        weight: Vector::<2>::new(0.0, -PAYLOAD * G),
    }];
    let mut net = b.build(Boundary::default(), masses).unwrap();
    let mut r = net.initial.r.clone();
    for (j, &i) in nodes[reserve..].iter().enumerate() {
        r[i] = top + Vector::<2>::new(0.0, hanging(j as f64 * L, a));
    }
    net.initial = State::at_rest(&net.mesh, r);
    for &i in &nodes[..=reserve] {
        net.initial.v[i] = v0;
    }
    (net, g, drum, hook)
}

pub(super) fn fixed_step(h: f64) -> StepParams {
    StepParams {
        h,
        control: StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..StepParams::default()
    }
}

/// Smooth 0 → 1 over `[0, 1]`, at rest at both ends.
pub(super) fn smooth(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Hoisting 5 t by 15 m in 30 s on 25 m of rope: every step's balance
/// `Ĥₙ₊₁ − Ĥₙ = winch supply` holds to round-off through the fifteen elements that go onto
/// the drum; the mass off the drum ends at `ρA · 10 m`; the payload ends at the static
/// height of 10 m of rope; and what the winch supplied is the change of the static
/// energy (payload and rope raised, stretch released) within the rope's and payload's
/// kinetic scale.
#[test]
fn hoisting_a_payload_books_every_joule_through_the_drum() {
    hoist_and_check(25, 5, 15.0);
}

/// Lowering the same payload by 15 m from 10 m of rope: fifteen elements come off the drum,
/// and the same checks hold with the winch taking the energy.
#[test]
fn lowering_a_payload_books_every_joule_through_the_drum() {
    hoist_and_check(10, 20, -15.0);
}

/// Runs `n_el` elements with `reserve` on the drum through a smooth hoist of `lift` [m]
/// (negative: lowering) in 30 s and 2 s after, and makes the checks of the hoisting test.
fn hoist_and_check(n_el: usize, reserve: usize, lift: f64) {
    let time = 30.0;
    let (net, hook) = hoist(n_el, reserve, move |t| -lift * smooth(t / time));
    let h = 0.01;
    let mut sim = Simulation::new(net, fixed_step(h)).unwrap_or_else(|e| panic!("{e}"));
    let h0 = sim.energies().hamiltonian();
    let (mut worst, mut winch_total, mut bounce) = (0.0_f64, 0.0, 0.0_f64);
    let steps = (time / h).round() as usize + 200;
    for _ in 0..steps {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let scale = r.before.magnitude + r.after.magnitude + r.winch.abs();
        let balance = r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
        worst = worst.max(balance.abs() / scale);
        winch_total += r.winch;
        if r.t > time {
            // After the move, the payload's axial bounce trades kinetic and strain energy:
            // its largest kinetic energy is the energy of the bounce.
            bounce = bounce.max(r.after.kinetic);
        }
        assert!(r.supplied == r.winch, "no port but the winch supplies");
    }
    let w = sim.winch_samples()[0];
    let a = n_el as f64 * L - lift;
    let y = sim.state().r[hook][1];
    let de = sim.energies().hamiltonian() - h0;
    let (de_static, behind, virtual_part, offset) = static_change(&sim, a, n_el as f64 * L);
    eprintln!(
        "balance/scale {worst:.1e}; behind the drum {behind:.4} m ({virtual_part:.2} J), drum node {offset:.2e} m off; payout {:.6} m, off the drum {:.6} m, mass {:.3} kg; hook at {y:.5} m (static {:.5}); winch {winch_total:.1} J = ΔĤ {de:.1} J, static ΔE {de_static:.1} J, kinetic now {:.2e} J",
        w.payout,
        w.length,
        w.mass,
        hanging(a, a),
        sim.energies().kinetic
    );
    eprintln!("bounce energy {bounce:.3} J");
    assert!(worst < 1e-12, "balance/scale {worst:e}");
    assert!((w.payout + lift).abs() < 1e-12 && (w.length - a).abs() < 1e-9);
    assert!((w.mass - RHO_A * a).abs() < 1e-9 * RHO_A * a);
    assert!((w.energy - winch_total).abs() < 1e-9 * winch_total.abs());
    assert!((de - winch_total).abs() < 1e-9 * winch_total.abs());
    assert!(
        lift * winch_total > 0.0,
        "the winch supplies hoisting and takes lowering"
    );
    // What stays beyond the static change is the payload's axial bounce after the move (a
    // few tenths of a millimetre, below a joule): at most its amplitude `√(2 E/k)` on the
    // rope's axial stiffness `k = EA/a`, and 0.05 mm for the static shape's rounding.
    let amplitude = (2.0 * bounce / (EA / a)).sqrt();
    assert!(
        (y - hanging(a, a)).abs() < amplitude + 5e-5,
        "hook at {y}, bounce amplitude {amplitude}"
    );
    assert!(
        (winch_total - de_static).abs() < 1.5 * bounce + 0.1,
        "winch {winch_total} J against the static change {de_static} J"
    );
}

/// A winch asked to pay out more than its drum holds stops the run with an error that
/// names it, its payout and its capacity, at the first step that would need more, and
/// without retrying smaller steps; the state stays the last good one.
#[test]
fn a_winch_that_runs_out_of_cable_stops_the_run_by_name() {
    let (net, _) = hoist(10, 2, |t| 0.5 * t);
    let mut sim = Simulation::new(
        net,
        StepParams {
            h: 0.1,
            ..StepParams::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let e = loop {
        match sim.step() {
            Ok(_) => continue,
            Err(e) => break e,
        }
    };
    let msg = e.to_string();
    eprintln!("{msg}");
    // Two parked elements of 1 m: 2 m paid out at 0.5 m/s take 4 s.
    assert!(matches!(e, phstring::StepError::Winch { .. }), "{msg}");
    assert!(
        msg.contains("winch 'hoist'") && msg.contains("more than the drum holds (2 m"),
        "{msg}"
    );
    assert!(
        (sim.time() - 4.0).abs() < 1e-9,
        "stopped at t = {}",
        sim.time()
    );
    assert_eq!(sim.rejected_steps(), 0);
}

/// A gantry crane hoists 5 t by 15 m in 30 s while its trolley (the drum) travels 6 m in
/// 8 s. The balance holds to round-off on every step with the drum moving, and after both
/// moves the payload swings as a pendulum from the drum node: period `2π √(ℓ/g)` with `ℓ`
/// the rope below the drum node (10 m off the drum and the cable the model keeps behind the
/// drum point), within the rope's mass and the swing's amplitude (0.5 %).
#[test]
fn a_moving_drum_hoists_and_the_payload_swings_from_the_drum_node() {
    let (n_el, reserve, lift, time, travel) = (25, 5, 15.0, 30.0, 6.0);
    let (mut net, hook) = hoist(n_el, reserve, move |t| -lift * smooth(t / time));
    net.winches[0].drum_motion = Some(Arc::new(move |t| [travel * smooth(t / 8.0), 0.0, 0.0]));
    let h = 0.01;
    let mut sim = Simulation::new(net, fixed_step(h)).unwrap_or_else(|e| panic!("{e}"));
    let mut worst = 0.0_f64;
    let mut crossings: Vec<f64> = Vec::new();
    let mut prev = 0.0;
    while sim.time() < 60.0 - 1e-9 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let scale = r.before.magnitude + r.after.magnitude + r.winch.abs();
        let balance = r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
        worst = worst.max(balance.abs() / scale);
        let sway = sim.state().r[hook][0] - travel;
        if r.t > time + 1.0 && prev < 0.0 && sway >= 0.0 {
            // Upward zero crossing, interpolated within the step.
            crossings.push(r.t - h * sway / (sway - prev));
        }
        prev = sway;
    }
    let cp = sim.checkpoint();
    let w = sim.winch_samples()[0];
    let behind = cp.winches[0].behind(w.payout);
    let a = n_el as f64 * L - lift;
    let stretch = 1.0 + G * (PAYLOAD + RHO_A * a) / EA;
    let pendulum = 2.0 * std::f64::consts::PI * (stretch * (a + behind) / G).sqrt();
    let periods: Vec<f64> = crossings.windows(2).map(|p| p[1] - p[0]).collect();
    let mean = periods.iter().sum::<f64>() / periods.len() as f64;
    eprintln!(
        "balance/scale {worst:.1e}; {} swings after the hoist, period {mean:.4} s against {pendulum:.4} s ({behind:.3} m behind the drum point); winch {:.1} J",
        periods.len(),
        w.energy
    );
    assert!(worst < 1e-12, "balance/scale {worst:e}");
    assert!(periods.len() >= 3, "{crossings:?}");
    assert!(
        (mean / pendulum - 1.0).abs() < 5e-3,
        "{mean} against {pendulum}"
    );
}

/// A payout speed held from outside (a controller, the FMU, a script): hauling in at
/// 5 cm/s from t = 1 s and stopping at t = 3 s hauls in 0.1 m, continuing from the payout
/// reached, with the balance exact on every step; the winch's energy is the static energy
/// change of the 0.1 m lift within the payload's bounce after the two jerks.
#[test]
fn a_held_payout_speed_hauls_in_from_where_the_winch_is() {
    let (net, _) = hoist(25, 0, |_| 0.0);
    let mut sim = Simulation::new(net, fixed_step(0.01)).unwrap_or_else(|e| panic!("{e}"));
    let h0 = sim.energies().hamiltonian();
    let (mut worst, mut bounce) = (0.0_f64, 0.0_f64);
    let mut run_to = |sim: &mut Simulation<2, Material>, t: f64, watch: bool| {
        while sim.time() < t - 1e-9 {
            let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
            let scale = r.before.magnitude + r.after.magnitude + r.winch.abs();
            let balance =
                r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
            worst = worst.max(balance.abs() / scale);
            if watch {
                bounce = bounce.max(r.after.kinetic);
            }
        }
    };
    run_to(&mut sim, 1.0, false);
    assert!(matches!(
        sim.set_winch_speed(1, -0.05),
        Err(phstring::InputError::NoSuchWinch { winch: 1, count: 1 })
    ));
    sim.set_winch_speed(0, -0.05).unwrap();
    run_to(&mut sim, 3.0, false);
    sim.set_winch_speed(0, 0.0).unwrap();
    run_to(&mut sim, 5.0, true);
    let w = sim.winch_samples()[0];
    let de = sim.energies().hamiltonian() - h0;
    let a = 25.0 - 0.1;
    let (de_static, ..) = static_change(&sim, a, 25.0);
    eprintln!(
        "payout {:.9} m, balance/scale {worst:.1e}, winch {:.2} J = ΔĤ {de:.2} J, static {de_static:.2} J, bounce {bounce:.2} J",
        w.payout, w.energy
    );
    assert!((w.payout + 0.1).abs() < 1e-12);
    assert!(worst < 1e-12);
    assert!((w.energy - de).abs() < 1e-9 * de.abs());
    assert!(
        (de - de_static).abs() < 1.5 * bounce + 0.1,
        "{de} against {de_static}"
    );
}

/// The anchor-handling line: a vessel's drum 5 m above 50 m of water, 76 mm studless chain
/// (115 kg/m, EA = 5e8 N, drag, a seabed with damping) laid straight down 65 m and 130 m
/// along the seabed to an anchor, five 5 m elements on the drum, paying out 20 m over 20 s.
/// Returns the network and the chain's group.
fn anchor_line() -> (Network<2, Material>, usize) {
    let (per_span, depth) = (13, 50.0);
    let mut b = NetworkBuilder::<2, Material>::new();
    let drum = b.node(Vector::<2>::new(0.0, 5.0));
    let x0 = (65.0f64 * 65.0 - 55.0 * 55.0).sqrt();
    let mut path = vec![drum];
    for k in 0..4 {
        path.push(b.node(Vector::<2>::new(x0 + 65.0 * k as f64, -depth)));
    }
    let rho_a = 115.0;
    let spec = StringSpec {
        name: "chain".into(),
        material: Material::tension_only_linear(5e8),
        rho_a,
        mass: MassMatrix::Lumped,
        body_force: Vector::<2>::new(0.0, -rho_a * G),
        prestretch: 1.0,
    };
    let g = b.string_on_drum(spec, &path, per_span, 5).unwrap();
    let anchor = path[4];
    let boundary = Boundary {
        fixed: vec![phstring::Fixed::node(anchor)],
        ..Boundary::default()
    };
    let net = b
        .build(boundary, Vec::new())
        .unwrap()
        .with_water(
            phstring::Water::new(1025.0).with_seabed(phstring::Seabed::flat(depth, 3e6, 1e5)),
        )
        .with_line_hydro(
            g,
            phstring::LineHydro {
                diameter: 0.137,
                cd: 2.4,
                ..Default::default()
            },
        )
        .with_winch(Winch {
            name: "anchor handling".into(),
            group: g,
            reserve: 5,
            payout: Arc::new(|t| 20.0 * smooth(t / 20.0)),
            drum_motion: None,
            drum: None,
        });
    (net, g)
}

/// Anchor handling: a vessel's winch 5 m above the water pays out 20 m of 76 mm studless
/// chain (115 kg/m, EA = 5e8 N) that runs down 5 m of air and 50 m of water to a flat
/// seabed and along it to an anchor, with drag and seabed damping; it starts from its
/// straight layout and swings and snaps into its catenary meanwhile (the drum tension
/// ranges 0–0.2 MN, the drag takes 0.27 MJ). The water is lumped again over the elements
/// that come off the drum, and every step's balance (winch, drag, current, seabed damping)
/// holds to round-off; the chain paid out after it has settled (t = 2 s) lands on the seabed
/// (the grounded length grows by more than half of it), and lowering it, the winch takes
/// energy.
#[test]
fn anchor_handling_pays_chain_out_onto_the_seabed_with_every_joule_booked() {
    let (net, g) = anchor_line();
    let mut sim = Simulation::new(net, fixed_step(0.01)).unwrap_or_else(|e| panic!("{e}"));
    let mut grounded0 = 0.0;
    let (mut worst, mut drag, mut seabed) = (0.0_f64, 0.0, 0.0);
    while sim.time() < 30.0 - 1e-9 {
        if (sim.time() - 2.0).abs() < 1e-9 {
            // Settled onto the seabed, 0.56 m paid out.
            grounded0 = sim.system().grounded_length(g, &sim.state().r);
        }
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let balance = r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
        let scale = r.before.magnitude + r.after.magnitude + r.winch.abs() + r.water.magnitude();
        worst = worst.max(balance.abs() / scale);
        drag += r.water.drag_dissipated;
        seabed += r.water.seabed_dissipated;
    }
    let w = sim.winch_samples()[0];
    let grounded = sim.system().grounded_length(g, &sim.state().r);
    eprintln!(
        "balance/scale {worst:.1e}; payout {:.3} m, grounded {grounded0:.1} → {grounded:.1} m, winch {:.0} J, drag {drag:.0} J, seabed damping {seabed:.0} J, tension at the drum {:.0} N",
        w.payout, w.energy, w.tension
    );
    assert!(worst < 1e-11, "balance/scale {worst:e}");
    assert!((w.payout - 20.0).abs() < 1e-12);
    assert!(grounded - grounded0 > 10.0, "{grounded0} → {grounded}");
    assert!(w.energy < 0.0 && drag > 0.0 && seabed > 0.0);
}

/// A run from the static equilibrium of the anchor line (a catenary leaving the drum at its
/// own angle) starts its drum node's path along that catenary: paying out 1 mm/s (an
/// element comes off the drum in the first step), the tension at the drum changes over the
/// first 0.5 s by less than twice the weight of a 5 m element (11.3 kN): the element that
/// comes off hangs its weight on the drum node at once, a step load whose response
/// overshoots up to twice it (measured 7.0 kN). Along the layout's straight direction
/// instead, the first element kinked the chain at the drum (measured: the tension doubled).
#[test]
fn a_winch_run_from_an_equilibrium_continues_the_catenary_at_the_drum() {
    let (mut net, _) = anchor_line();
    net.winches[0].payout = Arc::new(|t| 0.001 * t);
    let (sys, init) = phstring::PhSystem::new(net).unwrap();
    let eq = phstring::statics::solve_system(&sys, &init.r, &Default::default(), None)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut sim =
        Simulation::from_system(sys, eq.state, fixed_step(0.01)).unwrap_or_else(|e| panic!("{e}"));
    let t0 = sim.winch_samples()[0].tension;
    let mut worst = 0.0_f64;
    while sim.time() < 0.5 - 1e-9 {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
        worst = worst.max((sim.winch_samples()[0].tension - t0).abs());
    }
    let element = 115.0 * G * 5.0;
    eprintln!(
        "tension at the drum {t0:.0} N at rest, off by at most {worst:.0} N over 0.5 s (an element weighs {element:.0} N)"
    );
    assert!(t0 > 5e4 && worst < 2.0 * element, "{t0} N, {worst} N");
}
