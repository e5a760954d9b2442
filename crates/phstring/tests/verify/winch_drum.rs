//! Winch drums with dynamics (docs/method.md §23.6): the payout is a state, moved by the
//! rope's pull against the drum's inertia, motor, damping and brake inside the exact step. A
//! 5 t payload on a 32 mm steel wire rope released against a slipping brake, held by a
//! tension controller, and hauled in by a motor torque: each against the rigid-rope law of
//! motion, with the exact balance on every step and each mechanism's share; and the statics
//! at the length a winch has reached.

use phstring::{Material, Network, Simulation, StepReport, WinchDrum};
use std::sync::Arc;

use super::winch::{EA, G, L, PAYLOAD, RHO_A, fixed_step};

/// The rope off the drum at the start [m].
const ROPE: f64 = 20.0;

/// The weight [N] hanging from the drum with `a` metres of rope off it.
fn weight(a: f64) -> f64 {
    G * (PAYLOAD + RHO_A * a)
}

/// A 2D hoist: the drum at the origin, 20 m of rope hanging in its static shape with the
/// payload at its end, 30 elements more on the drum, the drum `drum`.
fn drum_hoist(drum: WinchDrum) -> (Network<2, Material>, usize) {
    let (mut net, hook) = super::winch::hoist((ROPE / L) as usize, 30, |_| 0.0);
    net.winches[0].drum = Some(drum);
    (net, hook)
}

/// The rigid-rope law of motion of the payout `p`: `(m + I + ρA (a₀ + p)) p̈ = g (m + ρA
/// (a₀ + p)) − f(ṗ)` (the rope that comes off the drum joins the motion, as the model's cut
/// books it), by RK4 over `[0, t]` with `n` steps; returns `(p, ṗ)`.
fn rigid_rope(inertia: f64, force: impl Fn(f64) -> f64, t: f64, n: usize) -> (f64, f64) {
    let acc = |p: f64, u: f64| {
        let a = ROPE + p;
        (weight(a) - force(u)) / (PAYLOAD + inertia + RHO_A * a)
    };
    let (mut p, mut u) = (0.0, 0.0);
    let dt = t / n as f64;
    for _ in 0..n {
        let (k1p, k1u) = (u, acc(p, u));
        let (k2p, k2u) = (
            u + 0.5 * dt * k1u,
            acc(p + 0.5 * dt * k1p, u + 0.5 * dt * k1u),
        );
        let (k3p, k3u) = (
            u + 0.5 * dt * k2u,
            acc(p + 0.5 * dt * k2p, u + 0.5 * dt * k2u),
        );
        let (k4p, k4u) = (u + dt * k3u, acc(p + dt * k3p, u + dt * k3u));
        p += dt / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p);
        u += dt / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
    }
    (p, u)
}

/// Runs `sim` to `t_end` (the last step shortened to end there), checking every step's
/// balance `Ĥₙ₊₁ − Ĥₙ = supplied − dissipated` against `1e-12` of its energy scale and that
/// the winch is the only supply; returns the worst relative balance error and the sums of
/// supplied and dissipated energy.
fn run_balanced(sim: &mut Simulation<2, Material>, t_end: f64) -> (f64, f64, f64) {
    let (mut worst, mut supplied, mut dissipated) = (0.0_f64, 0.0, 0.0);
    while sim.time() < t_end - 1e-9 {
        let r: StepReport = sim.step_until(t_end).unwrap_or_else(|e| panic!("{e}"));
        let scale = r.before.magnitude + r.after.magnitude + r.winch.abs() + r.dissipated;
        let balance = r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
        worst = worst.max(balance.abs() / scale);
        assert!(r.supplied == r.winch, "no port but the winch supplies");
        supplied += r.supplied;
        dissipated += r.dissipated;
    }
    assert!(worst < 1e-12, "balance/scale {worst:e}");
    (worst, supplied, dissipated)
}

/// A drum of `inertia` [kg at the rope] held by a brake alone: holding force `hold` [N],
/// slip speed `slip` [m/s], no motor, no damping.
fn brake_drum(inertia: f64, hold: f64, slip: f64) -> WinchDrum {
    WinchDrum {
        inertia,
        force: Arc::new(|_| 0.0),
        damping: 0.0,
        brake: Some((hold, slip)),
    }
}

/// A brake that holds 30 kN lets the 5.08 t that hang from it (49.9 kN) slip: the drum (2 t
/// at the rope) and the payload accelerate at `(W − F_b)/(m + I + ρA a)`, 2.9 m/s², the
/// payout after 2 s is the rigid-rope law's (5.8 m) within the rope's axial vibration (the
/// release drops the tension by 20 kN: ±9 mm on the 2.2 MN/m of 20 m of rope), and the brake
/// dissipates `F_b` times the rope that slid over it (`λ` times the payout), less its slip
/// band.
#[test]
fn a_slipping_brake_lets_the_payload_fall_at_the_rate_of_its_excess_weight() {
    let (hold, slip, inertia) = (3.0e4, 1e-3, 2000.0);
    let (net, _) = drum_hoist(brake_drum(inertia, hold, slip));
    let mut sim = Simulation::new(net, fixed_step(2e-3)).unwrap_or_else(|e| panic!("{e}"));
    let h0 = sim.energies().hamiltonian();
    let (mut supplied, mut dissipated, mut slid) = (0.0, 0.0, 0.0);
    while sim.time() < 2.0 - 1e-9 {
        let ws = sim.checkpoint().winches[0];
        let t = sim.time() + 2e-3;
        let (_, s, d) = run_balanced(&mut sim, t);
        supplied += s;
        dissipated += d;
        slid += ws.stretch * sim.winch_samples()[0].speed * 2e-3;
    }
    let w = sim.winch_samples()[0];
    let brake = |u: f64| hold * u / (u * u + slip * slip).sqrt();
    let (p, u) = rigid_rope(inertia, brake, 2.0, 20000);
    let de = sim.energies().hamiltonian() - h0;
    eprintln!(
        "brake: payout {:.5} m (rigid rope {p:.5} m), speed {:.4} m/s (rigid {u:.4}); dissipated {dissipated:.1} J = brake {:.1} J (F_b λp = {:.1} J); supplied {supplied:.1} J; ΔĤ {de:.1} J",
        w.payout,
        w.speed,
        w.dissipated,
        hold * slid
    );
    assert!(
        (w.payout - p).abs() < 0.012,
        "payout {} m against {p} m",
        w.payout
    );
    assert!((w.dissipated - dissipated).abs() < 1e-9 * dissipated);
    // The brake's force is below `F_b` by its slip band: `F_b (1 − u/√(u² + s²))`, about
    // `F_b s²/(2u²)` once it slips fast, and all of `F_b` at rest.
    let band = hold * slid - w.dissipated;
    assert!(band > 0.0 && band < 1e-4 * hold * slid, "{band} J");
    assert!((de - (supplied - dissipated)).abs() < 1e-9 * dissipated);
}

/// A tension controller (motor pull `T_ref` = 45 kN, damping 1e5 N·s/m, no drum inertia)
/// under 49.9 kN pays out at the speed its tension error asks inside every step, `ṗ_{n+½} =
/// (T_{n+½} − T_ref)/(λ d)` with `T_{n+½}` the drum's reaction along the rope (to round-off),
/// and at the rigid-rope law's speed (0.049 m/s) over 10 s, within what the model hangs from
/// the drum beyond the rigid rope: the cable behind the drum node (at most an element, 40 N)
/// and the stretch `λ` (0.1 %). The motor takes `λ T_ref` times the payout, the damping
/// `λ² d ṗ²` per second.
#[test]
fn a_tension_controlled_drum_pays_out_at_the_speed_its_tension_error_asks() {
    let (target, damping) = (4.5e4, 1.0e5);
    let drum = WinchDrum {
        inertia: 0.0,
        force: Arc::new(move |_| target),
        damping,
        brake: None,
    };
    let (net, _) = drum_hoist(drum);
    let mut sim = Simulation::new(net, fixed_step(1e-2)).unwrap_or_else(|e| panic!("{e}"));
    let (mut worst_law, mut stretched) = (0.0_f64, 0.0);
    let (mut supplied, mut dissipated) = (0.0, 0.0);
    while sim.time() < 10.0 - 1e-9 {
        let ws = sim.checkpoint().winches[0];
        let t = sim.time() + 1e-2;
        let (_, s, d) = run_balanced(&mut sim, t);
        supplied += s;
        dissipated += d;
        let w = sim.winch_samples()[0];
        stretched += ws.stretch * w.speed * 1e-2;
        let y = w.port.2;
        let pull = -(ws.direction[0] * y[0] + ws.direction[1] * y[1]);
        let law = (pull - target) / (ws.stretch * damping);
        worst_law = worst_law.max((w.speed - law).abs() / law);
    }
    let w = sim.winch_samples()[0];
    let (p, u) = rigid_rope(0.0, |u| target + damping * u, 10.0, 20000);
    let motor = -target * stretched;
    eprintln!(
        "tension control: payout {:.5} m (rigid {p:.5} m), speed {:.5} (rigid {u:.5}) m/s, tension {:.1} N; law off by {worst_law:.1e}; motor {:.1} J (−λ T_ref p = {motor:.1} J), winch {supplied:.1} J; damping {dissipated:.1} J",
        w.payout, w.speed, w.tension, w.motor,
    );
    assert!(
        worst_law < 1e-9,
        "speed off the law by {worst_law} (relative)"
    );
    let behind = RHO_A * G * L / damping * 10.0;
    assert!(
        (w.payout - p).abs() < behind + 2e-3 * p,
        "payout {} m against {p} m",
        w.payout
    );
    // The winch's supply is the motor's and what the cuts booked (an element's energy each).
    assert!(
        (w.motor - motor).abs() < 1e-9 * motor.abs(),
        "motor {} J",
        w.motor
    );
    assert!((w.energy - supplied).abs() < 1e-9 * motor.abs());
    assert!((w.dissipated - dissipated).abs() < 1e-9 * dissipated);
}

/// A motor pulling 60 kN at the rope through a drum of 3 t at the rope hauls the 5.08 t
/// payload in at `(f − W)/(m + I + ρA a)`, 1.2 m/s², against the rigid-rope law over 2 s (2.3 m
/// hauled in, three elements onto the drum); the drum's kinetic energy is in `Ĥ`, and the
/// motor supplies `f` times the haul.
#[test]
fn a_motor_torque_hauls_in_against_the_drums_inertia() {
    let (pull, inertia) = (6.0e4, 3000.0);
    let drum = WinchDrum {
        inertia,
        force: Arc::new(move |_| pull),
        damping: 0.0,
        brake: None,
    };
    let (net, _) = drum_hoist(drum);
    let mut sim = Simulation::new(net, fixed_step(2e-3)).unwrap_or_else(|e| panic!("{e}"));
    let (_, supplied, dissipated) = run_balanced(&mut sim, 2.0);
    let w = sim.winch_samples()[0];
    let (p, u) = rigid_rope(inertia, |_| pull, 2.0, 20000);
    let ws = sim.checkpoint().winches[0];
    let drum_energy = 0.5 * inertia * (ws.stretch * ws.speed).powi(2);
    eprintln!(
        "motor: payout {:.5} m (rigid {p:.5} m), speed {:.5} (rigid {u:.5}) m/s; drum energy {drum_energy:.1} J; supplied {supplied:.1} J (f |p| = {:.1} J)",
        w.payout,
        ws.speed,
        -pull * w.payout
    );
    assert_eq!(dissipated, 0.0);
    assert!(
        (w.payout - p).abs() < 0.01,
        "payout {} m against {p} m",
        w.payout
    );
    assert!(
        (ws.speed - u).abs() < 0.05 * u.abs(),
        "speed {} against {u}",
        ws.speed
    );
    assert!(sim.energies().kinetic > drum_energy && drum_energy > 0.0);
    assert!((supplied + pull * w.payout).abs() < 2e-3 * (pull * w.payout).abs());
}

/// After the motor has hauled in 2.5 m, the system holds the winch's current mesh: its static
/// equilibrium from the run's state hangs the payload below the drum node by the closed-form
/// static length of the rope between them, `n L + g((m + ρA n L) n L − ρA (n L)²/2)/EA` with
/// `n` elements off the drum node, to 1e-9 m, and the drum node's reaction carries the
/// payload and that rope, `g (m + ρA n L)`.
#[test]
fn statics_at_the_length_a_winch_has_reached_hangs_the_closed_form_rope() {
    let drum = WinchDrum {
        inertia: 3000.0,
        force: Arc::new(|_| 6.0e4),
        damping: 0.0,
        brake: None,
    };
    let (net, hook) = drum_hoist(drum);
    let mut sim = Simulation::new(net, fixed_step(2e-3)).unwrap_or_else(|e| panic!("{e}"));
    sim.run_until(2.0, &mut ())
        .unwrap_or_else(|e| panic!("{e}"));
    let cp = sim.checkpoint();
    let (drum_node, drum_element) = sim.system().winch_layout(&cp.winches)[0];
    let g = sim.system().winches()[0].1;
    let n = sim.system().group_span(g).end - drum_element;
    let eq = phstring::statics::solve_from(
        sim.system(),
        sim.state(),
        &phstring::statics::StaticsParams::default(),
        None,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let a = n as f64 * L;
    let hang = a + G * ((PAYLOAD + RHO_A * a) * a - 0.5 * RHO_A * a * a) / EA;
    let r = &eq.state.r;
    let drop = r[drum_node][1] - r[hook][1];
    let lift = eq.reactions[drum_node][1];
    eprintln!(
        "statics at {n} elements off the drum node: payload {drop:.9} m below it (closed form {hang:.9} m), drum reaction {lift:.3} N (weight {:.3} N)",
        weight(a)
    );
    assert!(cp.winches[0].payout < -2.0, "hauled in");
    assert!((drop - hang).abs() < 1e-9, "{drop} against {hang}");
    assert!((lift - weight(a)).abs() < 1e-9 * weight(a), "{lift} N");
    assert!((r[drum_node][0] - r[hook][0]).abs() < 1e-12);
}

/// A tension controller with inertia under `dg4` (motor pull `T_ref` = 45 kN, damping
/// 1e4 N·s/m, a drum of 500 kg at the rope, `h` = 0.02 s): under 49.9 kN it pays out at up to
/// 0.49 m/s, 2.6 m in 6 s (two elements off the drum). Guards the drum's unknown `Δp` in each
/// sub-step, the backward one with its negative step and anti-damping: every step's balance
/// within 1e-12 of its energy scale with the drum's shares summed over the sub-steps (the
/// step's dissipation may be negative, the run's is not), the payout against the rigid-rope
/// law within the model's cable behind the drum node (`ρA g L · 6 s/d`) and 0.2 % (the
/// stretch `λ`), and the damping's total `Σ λ² d ṗ² h` against the run's dissipation.
#[test]
fn a_tension_controlled_drum_under_dg4_keeps_every_step_balanced() {
    let (target, damping, inertia, h) = (4.5e4, 1.0e4, 500.0, 0.02);
    let drum = WinchDrum {
        inertia,
        force: Arc::new(move |_| target),
        damping,
        brake: None,
    };
    let (net, _) = drum_hoist(drum);
    let params = phstring::StepParams {
        scheme: phstring::Scheme::DiscreteGradient4,
        ..fixed_step(h)
    };
    let mut sim = Simulation::new(net, params).unwrap_or_else(|e| panic!("{e}"));
    let h0 = sim.energies().hamiltonian();
    let (worst, supplied, dissipated) = run_balanced(&mut sim, 6.0);
    let w = sim.winch_samples()[0];
    let (p, u) = rigid_rope(inertia, |u| target + damping * u, 6.0, 20000);
    let de = sim.energies().hamiltonian() - h0;
    eprintln!(
        "dg4 tension control: balance/scale {worst:.1e}; payout {:.5} m (rigid {p:.5} m), speed {:.5} m/s (rigid {u:.5}); supplied {supplied:.1} J, dissipated {dissipated:.1} J (drum {:.1} J), ΔĤ {de:.1} J",
        w.payout, w.speed, w.dissipated
    );
    let behind = RHO_A * G * L / damping * 6.0;
    assert!(
        (w.payout - p).abs() < behind + 2e-3 * p,
        "payout {} m against {p} m",
        w.payout
    );
    assert!(w.payout > 2.0, "two elements off the drum");
    assert!(dissipated > 0.0 && (w.dissipated - dissipated).abs() < 1e-9 * dissipated);
    assert!((de - (supplied - dissipated)).abs() < 1e-9 * supplied.abs());
}

/// The slipping brake of the test above (30 kN, slip speed 1 mm/s, a drum of 2 t at the rope)
/// under `dg4` at `h` = 2 ms: the backward sub-step runs the brake backward (it gives energy
/// back there, the damping exception of docs/method.md §19), every step's balance within
/// 1e-12 of its energy scale, the brake's total dissipation the run's, and the payout at 2 s
/// the rigid-rope law's within the rope's axial vibration (12 mm, as with `dg`).
#[test]
fn a_slipping_brake_under_dg4_keeps_every_step_balanced() {
    let (hold, slip, inertia, h) = (3.0e4, 1e-3, 2000.0, 2e-3);
    let (net, _) = drum_hoist(brake_drum(inertia, hold, slip));
    let params = phstring::StepParams {
        scheme: phstring::Scheme::DiscreteGradient4,
        ..fixed_step(h)
    };
    let mut sim = Simulation::new(net, params).unwrap_or_else(|e| panic!("{e}"));
    let (worst, _, dissipated) = run_balanced(&mut sim, 2.0);
    let w = sim.winch_samples()[0];
    let brake = |u: f64| hold * u / (u * u + slip * slip).sqrt();
    let (p, _) = rigid_rope(inertia, brake, 2.0, 20000);
    eprintln!(
        "dg4 brake: balance/scale {worst:.1e}; payout {:.5} m (rigid rope {p:.5} m); dissipated {dissipated:.1} J; {} rejected",
        w.payout,
        sim.rejected_steps()
    );
    assert!(
        (w.payout - p).abs() < 0.012,
        "payout {} m against {p} m",
        w.payout
    );
    assert!((w.dissipated - dissipated).abs() < 1e-9 * dissipated);
}

/// The tension controller of the `dg4` test above under error control (`rtol = atol =
/// 1e-4`, `time.h` = 0.05 s), with `dg` and with `dg4` (whose embedded `dg` step has the
/// drum's row from its state before the step, and compares the drum's payout and speed):
/// each run completes with every accepted step's balance within 1e-12 of its energy scale,
/// the drum's dissipation the run's, and the payout at 3 s (1.2 m, two cuts) within the
/// tolerance asked, `atol + rtol |p|`, of `dg4` at a fixed 2.5 ms.
#[test]
fn a_tension_controlled_drum_under_error_control_keeps_its_tolerance() {
    let (target, damping, inertia, tol) = (4.5e4, 1.0e4, 500.0, 1e-4);
    let drum = || WinchDrum {
        inertia,
        force: Arc::new(move |_| target),
        damping,
        brake: None,
    };
    let dg4 = phstring::Scheme::DiscreteGradient4;
    let reference = {
        let (net, _) = drum_hoist(drum());
        let params = phstring::StepParams {
            scheme: dg4,
            ..fixed_step(2.5e-3)
        };
        let mut sim = Simulation::new(net, params).unwrap_or_else(|e| panic!("{e}"));
        run_balanced(&mut sim, 3.0);
        sim.winch_samples()[0].payout
    };
    for scheme in [phstring::Scheme::DiscreteGradient, dg4] {
        let (net, _) = drum_hoist(drum());
        let params = phstring::StepParams {
            h: 0.05,
            scheme,
            control: phstring::StepControl::with_tolerance(tol, tol),
            ..phstring::StepParams::default()
        };
        let mut sim = Simulation::new(net, params).unwrap_or_else(|e| panic!("{e}"));
        let (worst, _, dissipated) = run_balanced(&mut sim, 3.0);
        let w = sim.winch_samples()[0];
        let allowed = tol * (1.0 + reference.abs());
        eprintln!(
            "{scheme:?} tension control with tol {tol:e}: {} steps, {} rejected; balance/scale {worst:.1e}; payout {:.6} m against {reference:.6} m (allowed {allowed:.1e})",
            sim.steps(),
            sim.rejected_steps(),
            w.payout
        );
        assert!((w.dissipated - dissipated).abs() < 1e-9 * dissipated);
        assert!(
            (w.payout - reference).abs() < allowed,
            "{scheme:?}: payout {} m",
            w.payout
        );
    }
}
