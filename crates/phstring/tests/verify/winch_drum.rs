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
        derivative_time: 0.0,
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
        derivative_time: 0.0,
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
        derivative_time: 0.0,
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
        derivative_time: 0.0,
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
        derivative_time: 0.0,
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
        derivative_time: 0.0,
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

/// A tension controller with a derivative part: target `T_ref`, damping `d`, derivative time
/// `tau` [s], no drum inertia.
fn pd_drum(target: impl Fn(f64) -> f64 + Send + Sync + 'static, d: f64, tau: f64) -> WinchDrum {
    WinchDrum {
        inertia: 0.0,
        force: Arc::new(target),
        damping: d,
        brake: None,
        derivative_time: tau,
    }
}

/// The rope's pull at the drum over the last step of `sim`, `T_{n+½} = −t̂·R_d` [N] (the
/// winch port's reaction along the path of `ws`, the winch's state before the step: a cut
/// after the step starts a new path).
fn drum_pull(sim: &Simulation<2, Material>, ws: &phstring::WinchState) -> f64 {
    let y = sim.winch_samples()[0].port.2;
    -(ws.direction[0] * y[0] + ws.direction[1] * y[1])
}

/// A PD tension controller (target 45 kN, `d` = 1e5 N·s/m, derivative time 0.3 s, no drum
/// inertia) under the 49.9 kN of the hoist, over 3 s at `h` = 10 ms: on every step the
/// mid-step speed is the law's, `λ d ṗ_{n+½} = (T_{n+½} − T_ref) + τ (T_{n+½} − T_{n−½})/h`
/// (on the first step, with no previous pull, `τ`'s part is off), to 1e-9 of the larger of
/// the law's speed and the proportional law's at rest (`ΔT/(λ d)`, 0.049 m/s); each step's
/// balance within 1e-12 of its energy scale; the pull the state records is the port's; the
/// motor's energy is `−λ Σ (T_ref − τ (T_{n+½} − T_{n−½})/h) Δp` to 1e-9, the derivative part
/// booked with the motor.
#[test]
fn a_pd_tension_controller_pays_out_at_the_speed_its_law_asks() {
    let (target, damping, tau, h) = (4.5e4, 1.0e5, 0.3, 1e-2);
    let (net, _) = drum_hoist(pd_drum(move |_| target, damping, tau));
    let mut sim = Simulation::new(net, fixed_step(h)).unwrap_or_else(|e| panic!("{e}"));
    let (mut worst_law, mut worst_record, mut motor) = (0.0_f64, 0.0_f64, 0.0);
    let mut worst_balance = 0.0_f64;
    while sim.time() < 3.0 - 1e-9 {
        let before = sim.checkpoint().winches[0];
        let t = sim.time() + h;
        let (worst, _, _) = run_balanced(&mut sim, t);
        worst_balance = worst_balance.max(worst);
        let (ws, w) = (sim.checkpoint().winches[0], sim.winch_samples()[0]);
        let pull = drum_pull(&sim, &before);
        let rate = if before.pull_step > 0.0 {
            assert_eq!(before.pull_step, h, "the previous step's size");
            (pull - before.pull) / h
        } else {
            assert_eq!(
                sim.steps(),
                1,
                "no previous pull only before the first step"
            );
            0.0
        };
        let law = ((pull - target) + tau * rate) / (before.stretch * damping);
        let at_rest = (weight(ROPE) - target) / (before.stretch * damping);
        worst_law = worst_law.max((w.speed - law).abs() / law.abs().max(at_rest));
        worst_record = worst_record.max((ws.pull - pull).abs() / pull);
        assert_eq!(ws.pull_step, h);
        motor -= before.stretch * (target - tau * rate) * w.speed * h;
    }
    let w = sim.winch_samples()[0];
    eprintln!(
        "PD tension control: law off by {worst_law:.1e}, recorded pull by {worst_record:.1e}, balance/scale {worst_balance:.1e}; motor {:.3} J against {motor:.3} J; payout {:.4} m",
        w.motor, w.payout
    );
    assert!(worst_law < 1e-9, "speed off the law by {worst_law:e}");
    assert!(
        worst_record < 1e-12,
        "recorded pull off by {worst_record:e}"
    );
    assert!(
        (w.motor - motor).abs() < 1e-9 * motor.abs(),
        "motor {} J against {motor} J",
        w.motor
    );
}

/// The rigid-rope closed form of a tension controller without drum inertia after a step of
/// its target to `T_r` at `s = 0` from rest: the moving mass `m` [kg] (payload and rope
/// below the drum node), its weight `g m`, the rope's pull `T(0) = g m − θ₀` [N], stretch
/// `λ`, damping `d` [N·s/m] and derivative time `tau` [s]. With `λ m v̇ = g m − T` and the law
/// `λ d v = (T − T_r) + τ Ṫ`, the payout speed obeys `τ m v̈ + m v̇ + d v = F/λ`, `F = g m −
/// T_r`, from `v(0) = 0`, `λ m v̇(0) = θ₀` (underdamped for `τ > m/(4d)`); without `τ`,
/// `m v̇ + d v = F/λ` and the pull is `T_r + λ d v` at once. Returns the speed [m/s] and the
/// pull [N] at `s` [s].
fn pd_closed_form(
    (m, theta0, stretch): (f64, f64, f64),
    (target, d, tau): (f64, f64, f64),
    s: f64,
) -> (f64, f64) {
    let weight = G * m;
    let steady = (weight - target) / (stretch * d);
    if tau == 0.0 {
        let v = steady * (1.0 - (-d * s / m).exp());
        return (v, target + stretch * d * v);
    }
    let w0 = (d / (tau * m)).sqrt();
    let zeta = 1.0 / (2.0 * w0 * tau);
    assert!(zeta < 1.0, "underdamped");
    let wd = w0 * (1.0 - zeta * zeta).sqrt();
    let a = -steady;
    let b = (theta0 / (stretch * m) + zeta * w0 * a) / wd;
    let (decay, (sin, cos)) = ((-zeta * w0 * s).exp(), (wd * s).sin_cos());
    let v = steady + decay * (a * cos + b * sin);
    let dv = decay * ((wd * b - zeta * w0 * a) * cos - (zeta * w0 * b + wd * a) * sin);
    (v, weight - stretch * m * dv)
}

/// The hoist's drum as a tension controller (`d` = 1e4 N·s/m, no drum inertia) held at the
/// rope's weight, its target raised by 2.5 kN at 0.05 s, with and without a derivative time
/// of 0.5 s, over 3 s at `h` = 2 ms: it hauls in 0.63 m, less than an element, so no cut
/// happens and the load below the drum node stays the 5 t payload and 20 m of rope. Each
/// run's payout speed and pull against [`pd_closed_form`], the rigid rope's closed form, with
/// every step's balance within 1e-12. Guards what the D part does: the P law raises the pull
/// to the new target at once (in the elastic rope within a few `d/k` ≈ 5 ms, 0.7 MN/s) and
/// hauls in with the time constant `m/d` = 0.51 s; with `τ` the pull is a lag of time
/// constant `τ` (`τ Ṫ = λ d v − (T − T_r)`), rising at most at `ΔT/τ` = 5 kN/s (asserted
/// within 5 %, and the P law's at least 20 times faster), and the speed rings (`ζ` = 0.50,
/// `ω₀` = 1.98 rad/s) 16 % over its steady value. Tolerances: the rigid rope leaves out the
/// rope's compliance `1/k`, `k = EA/ℓ` = 2.15 MN/m: in series with the drum's spring `d/τ` it
/// lowers the ringing's frequency by `(d/τ)/(2k)` = 0.5 %, and raising the pull at `ΔT/τ`
/// takes a drum speed `ΔT/(τ k)` = 0.9 % of the steady speed that the rigid rope has not
/// (twice that while the rope's step response overshoots at the start); the D part's
/// difference lags the law by `h/2` (`ω₀ h/2` = 0.2 %). So with `τ` the speed is held to
/// 2.5 % of the steady speed from the step on and the pull to 1 % of the step; without `τ`
/// both to 1 % from 0.5 s after the step on (one `m/d`: the P law's hard start rings the rope,
/// its speed 1.3 % off at 0.25 s).
#[test]
fn a_pd_tension_controller_follows_its_closed_loop_closed_form() {
    let (step, damping, h, t0, t_end) = (2.5e3, 1.0e4, 2e-3, 0.05, 3.05);
    let before = weight(ROPE);
    let target = move |t: f64| if t < t0 { before } else { before + step };
    let mut fastest = [0.0_f64; 2];
    for (k, tau) in [0.0, 0.5].into_iter().enumerate() {
        let (net, _) = drum_hoist(pd_drum(target, damping, tau));
        let mut sim = Simulation::new(net, fixed_step(h)).unwrap_or_else(|e| panic!("{e}"));
        let stretch = sim.checkpoint().winches[0].stretch;
        let m = PAYLOAD + RHO_A * ROPE;
        let (mut worst_v, mut worst_t, mut last) = (0.0_f64, 0.0_f64, before);
        let steady = (target(t0) - G * m) / (stretch * damping);
        while sim.time() < t_end - 1e-9 {
            let ws = sim.checkpoint().winches[0];
            let t = sim.time() + h;
            run_balanced(&mut sim, t);
            let pull = drum_pull(&sim, &ws);
            let s = t - 0.5 * h - t0;
            if s > 0.0 {
                fastest[k] = fastest[k].max((pull - last) / h);
            }
            last = pull;
            if s < if tau > 0.0 { 0.0 } else { 0.5 } {
                continue;
            }
            let (v, pull_cf) = pd_closed_form((m, 0.0, stretch), (target(t0), damping, tau), s);
            worst_v = worst_v.max((sim.winch_samples()[0].speed - v).abs() / steady.abs());
            worst_t = worst_t.max((pull - pull_cf).abs() / step);
        }
        let w = sim.winch_samples()[0];
        eprintln!(
            "τ = {tau} s: payout {:.4} m, speed off the closed form by {worst_v:.2e} of {steady:.4} m/s, pull by {worst_t:.2e} of {step} N; fastest rise {:.0} N/s",
            w.payout, fastest[k]
        );
        let tol_v = if tau > 0.0 { 2.5e-2 } else { 1e-2 };
        assert!(worst_v < tol_v, "τ = {tau}: speed off by {worst_v:e}");
        assert!(worst_t < 1e-2, "τ = {tau}: pull off by {worst_t:e}");
        assert!(w.payout > -L, "no cut");
    }
    // The D part: the pull rises at most at ΔT/τ (the lag's rate at the step), where the P
    // law raises it within a few `d/k`.
    assert!(fastest[1] < 1.05 * step / 0.5, "{} N/s", fastest[1]);
    assert!(fastest[0] > 20.0 * step / 0.5, "{} N/s", fastest[0]);
}

/// A run of the PD tension controller of
/// [`a_pd_tension_controller_pays_out_at_the_speed_its_law_asks`] continued from a checkpoint
/// taken after 1 s (the previous pull known, elements brought off the drum) steps exactly as
/// the run that was not interrupted: after 0.5 s more the states, winch states and energies
/// agree bit for bit, restored from the record and from its flat form (the checkpoint
/// file's); and the same scenario under `dg4` is refused naming the winch's derivative time.
#[test]
fn a_pd_tension_controller_resumes_from_a_checkpoint_bit_for_bit() {
    let (target, damping, tau, h) = (4.5e4, 1.0e5, 0.3, 1e-2);
    let run = || {
        let (net, _) = drum_hoist(pd_drum(move |_| target, damping, tau));
        Simulation::new(net, fixed_step(h)).unwrap_or_else(|e| panic!("{e}"))
    };
    let mut sim = run();
    for _ in 0..100 {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
    }
    let cp = sim.checkpoint();
    assert!(cp.winches[0].pull_step == h && cp.winches[0].pull > target);
    for _ in 0..50 {
        sim.step().unwrap_or_else(|e| panic!("{e}"));
    }
    for from_flat in [false, true] {
        let mut again = run();
        let record = if from_flat {
            phstring::simulation::FlatCheckpoint::from(&cp).into_checkpoint()
        } else {
            cp.clone()
        };
        again.restore(record).unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..50 {
            again.step().unwrap_or_else(|e| panic!("{e}"));
        }
        assert_eq!(again.state(), sim.state());
        assert_eq!(again.checkpoint().winches, sim.checkpoint().winches);
        assert_eq!(again.energies().hamiltonian(), sim.energies().hamiltonian());
    }
    let (net, _) = drum_hoist(pd_drum(move |_| target, damping, tau));
    let params = phstring::StepParams {
        scheme: phstring::Scheme::DiscreteGradient4,
        ..fixed_step(h)
    };
    let err = Simulation::new(net, params)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("'hoist'") && err.contains("derivative_time 0.3 s") && err.contains("dg4"),
        "{err}"
    );
}

/// The PD tension controller of [`a_pd_tension_controller_pays_out_at_the_speed_its_law_asks`]
/// under error control (`dg`, `rtol = atol = 1e-4`, `time.h` = 0.05 s) over 1.5 s: steps
/// of varying size, some rejected. On every accepted step the law holds with the time
/// between the mid times, `Δt = (h_{n−1} + h_n)/2`, and the previous pull of the last
/// accepted step (a rejected attempt leaves no trace of its pull: the saved record is put
/// back), to 1e-9 of the speed as with fixed steps or, where more, to the step's Newton residual
/// over `λ² d` (the residual bounds the drum's row, `λ (λ d u − (T − T_ref) − τ Ṫ)`, and
/// Newton's tolerance grows with the derivative part's pulls `(τ/Δt) λ T`, 2e5 times the pull
/// at the smallest steps), plus the rounding of the rate recomputed here from the port's
/// reaction, `8 ε T τ/Δt` over `λ d`; each step's balance within 1e-12.
#[test]
fn a_pd_tension_controller_under_error_control_takes_its_rate_from_accepted_steps() {
    let (target, damping, tau, tol) = (4.5e4, 1.0e5, 0.3, 1e-4);
    let (net, _) = drum_hoist(pd_drum(move |_| target, damping, tau));
    let params = phstring::StepParams {
        h: 0.05,
        control: phstring::StepControl::with_tolerance(tol, tol),
        ..phstring::StepParams::default()
    };
    let mut sim = Simulation::new(net, params).unwrap_or_else(|e| panic!("{e}"));
    let (mut worst_law, mut sizes) = (0.0_f64, std::collections::BTreeSet::new());
    while sim.time() < 1.5 - 1e-9 {
        let before = sim.checkpoint().winches[0];
        let r = sim.step_until(1.5).unwrap_or_else(|e| panic!("{e}"));
        let scale = r.before.magnitude + r.after.magnitude + r.winch.abs() + r.dissipated;
        let balance = r.after.hamiltonian() - r.before.hamiltonian() - r.supplied + r.dissipated;
        assert!(balance.abs() < 1e-12 * scale, "balance {balance:e} J");
        let (ws, w) = (sim.checkpoint().winches[0], sim.winch_samples()[0]);
        assert_eq!(ws.pull_step, r.h, "the accepted step's size");
        sizes.insert(r.h.to_bits());
        let pull = drum_pull(&sim, &before);
        let dt = 0.5 * (before.pull_step + r.h);
        let rate = if before.pull_step > 0.0 {
            (pull - before.pull) / dt
        } else {
            0.0
        };
        let law = ((pull - target) + tau * rate) / (before.stretch * damping);
        let at_rest = (weight(ROPE) - target) / (before.stretch * damping);
        let newton = r.residual / (before.stretch * before.stretch * damping);
        let rounding = 8.0 * f64::EPSILON * pull * tau / dt / (before.stretch * damping);
        let allowed = (1e-9 * law.abs().max(at_rest)).max(newton) + rounding;
        worst_law = worst_law.max((w.speed - law).abs() / allowed);
    }
    eprintln!(
        "PD tension control under error control: {} steps ({} sizes), {} rejected; law off by {worst_law:.2} of its tolerance",
        sim.steps(),
        sizes.len(),
        sim.rejected_steps()
    );
    assert!(sim.rejected_steps() > 0, "error control rejected steps");
    assert!(sizes.len() > 2, "steps of several sizes");
    assert!(
        worst_law <= 1.0,
        "speed off the law by {worst_law} of its tolerance"
    );
}
