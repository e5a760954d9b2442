//! The physics of the example scenarios, run in-process from the files in
//! `examples/`: what each example claims in its header comment is checked here.

use std::path::Path;

use phstring::{PortKind, Simulation};
use phstring_io::scenario;

fn example(name: &str) -> scenario::ScenarioFile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name);
    scenario::load(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `crane_2d.toml`: after the trolley stops (t = 8 s) the payload swings with the period of a
/// pendulum of the rope's length. The period predicted for the loaded rope is that of a rigid
/// pendulum of the stretched length `L (1 + (M + m/2) g / EA)` with the rope's mass `m` spread
/// along it, `T = 2π √(L (M + m/3) / (g (M + m/2)))`; the measured period must agree within
/// 0.3 % (the rope is not rigid: its axial bounce and the tension varying along it are not in
/// the formula). The energy balance holds on every step with the trolley's input power,
/// which is the ports' `u·y`.
#[test]
fn crane_payload_swings_with_the_pendulum_period_and_the_balance_closes() {
    let file = example("crane_2d.toml");
    let v = file.validate::<2>().unwrap_or_else(|e| panic!("{e}"));
    let t_end = v.settings.t_end;
    let mut sim = Simulation::new(v.problem, v.settings.step).unwrap_or_else(|e| panic!("{e}"));
    let payload = sim.state().r.len() - 1;
    let (l0, g, ea, rho_a, m): (f64, f64, f64, f64, f64) = (20.0, 9.81, 3.0e7, 2.4, 5000.0);
    let m_rope = rho_a * l0;
    let stretched = l0 * (1.0 + (m + 0.5 * m_rope) * g / ea);
    let predicted = 2.0
        * std::f64::consts::PI
        * (stretched * (m + m_rope / 3.0) / (g * (m + m_rope / 2.0))).sqrt();
    let (mut worst, mut supplied, mut drive_work) = (0.0_f64, 0.0, 0.0);
    let mut crossings = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    while sim.time() < t_end - 1e-9 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        let scale = r
            .after
            .kinetic
            .abs()
            .max(r.after.internal.abs())
            .max(r.after.external.abs());
        worst = worst.max(r.balance_error.abs() / scale);
        supplied += r.supplied;
        let trolley = sim
            .ports()
            .iter()
            .find(|p| p.kind == PortKind::Velocity && p.node == 0)
            .expect("the trolley is a velocity port");
        drive_work += r.h * trolley.input.dot(&trolley.output);
        // Upward zero crossings of the payload's offset from the stopped trolley (x = 6 m).
        let x = sim.state().r[payload][0] - 6.0;
        if r.t > 8.0 {
            if let Some((t0, x0)) = prev
                && x0 < 0.0
                && x >= 0.0
            {
                crossings.push(t0 + (r.t - t0) * (-x0) / (x - x0));
            }
            prev = Some((r.t, x));
        }
    }
    assert!(crossings.len() >= 3, "crossings {crossings:?}");
    let periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    let measured = periods.iter().sum::<f64>() / periods.len() as f64;
    let rel = (measured - predicted) / predicted;
    println!(
        "crane: swing period {measured:.4} s (each {periods:.4?}), predicted {predicted:.4} s \
         ({:.2} % off), rigid formula 2π√(L/g) = {:.4} s; energy balance {worst:.2e} of the \
         energy scale; drive work {drive_work:.3} J = supplied {supplied:.3} J",
        100.0 * rel,
        2.0 * std::f64::consts::PI * (l0 / g).sqrt()
    );
    assert!(
        rel.abs() < 3e-3,
        "swing period {measured} s vs {predicted} s"
    );
    assert!(
        worst <= 1e-13,
        "energy balance error {worst:e} of the energy scale"
    );
    // The trolley is the only port that moves: its work is all the energy supplied.
    assert!(
        (drive_work - supplied).abs() <= 1e-9 * supplied.abs().max(1.0),
        "drive work {drive_work} J vs supplied {supplied} J"
    );
}

/// Runs `file` to its end (or `t_end`), returning the largest balance error relative to the
/// energy scale, the momentum error `|Δp − impulse|` of (14.4) with its Newton bound, the
/// supplied energy and the number of steps.
fn run_with_balances<const D: usize>(
    file: &str,
    t_end: Option<f64>,
) -> (f64, f64, f64, f64, usize) {
    let v = example(file)
        .validate::<D>()
        .unwrap_or_else(|e| panic!("{file}: {e}"));
    let t_end = t_end.unwrap_or(v.settings.t_end);
    let mut sim = Simulation::new(v.problem, v.settings.step).unwrap_or_else(|e| panic!("{e}"));
    let n_nodes = sim.state().r.len() as f64;
    let f_body: phstring::Vector<D> = sim.system().body_force_vector().iter().sum();
    let p0 = sim.system().linear_momentum(sim.state());
    let mut impulse = phstring::Vector::<D>::zeros();
    let (mut worst, mut slack, mut supplied) = (0.0_f64, 0.0, 0.0);
    while sim.time() < t_end - 1e-9 {
        let r = sim.step().unwrap_or_else(|e| panic!("{file}: {e}"));
        let reactions: phstring::Vector<D> = sim
            .ports()
            .iter()
            .filter(|p| p.kind == PortKind::Velocity)
            .map(|p| p.output)
            .sum();
        let loads: phstring::Vector<D> = sim
            .ports()
            .iter()
            .filter(|p| p.kind == PortKind::Force)
            .map(|p| p.input)
            .sum();
        impulse += (f_body + reactions + loads) * r.h;
        slack += r.h * r.residual * n_nodes.sqrt();
        let scale = r
            .after
            .kinetic
            .abs()
            .max(r.after.internal.abs())
            .max(r.after.external.abs());
        worst = worst.max(r.balance_error.abs() / scale);
        supplied += r.supplied;
    }
    let dp = sim.system().linear_momentum(sim.state()) - p0;
    (worst, (dp - impulse).norm(), slack, supplied, sim.steps())
}

/// `platform_3d.toml`: the exact energy balance with the heaving corner's work, and the
/// momentum balance through the supports (14.4): the change of the network's momentum equals
/// the impulse of gravity and of the support reactions, to the Newton tolerance.
#[test]
fn platform_balances_energy_and_momentum_through_its_supports() {
    let (worst, dp, slack, supplied, steps) = run_with_balances::<3>("platform_3d.toml", None);
    println!(
        "platform_3d: {steps} steps, energy balance {worst:.2e} of the energy scale, momentum \
         error {dp:.3e} N·s (Newton bound {slack:.3e}), supplied {supplied:.1} J"
    );
    assert!(worst <= 1e-13, "energy balance {worst:e}");
    assert!(
        dp <= slack,
        "momentum error {dp:e} N·s above the bound {slack:e}"
    );
    assert!(
        supplied > 100.0,
        "the heaving corner lifts the platform: {supplied} J"
    );
}

/// `net_3d.toml`, its first second: the net catches the sack with the exact energy balance
/// and the momentum balance through its 80 anchors.
#[test]
fn net_catches_the_sack_with_exact_balances() {
    let (worst, dp, slack, supplied, steps) = run_with_balances::<3>("net_3d.toml", Some(1.0));
    println!(
        "net_3d (to 1 s): {steps} steps, energy balance {worst:.2e} of the energy scale, \
         momentum error {dp:.3e} N·s (Newton bound {slack:.3e}), supplied {supplied:.2e} J"
    );
    assert!(worst <= 1e-13, "energy balance {worst:e}");
    assert!(
        dp <= slack,
        "momentum error {dp:e} N·s above the bound {slack:e}"
    );
    assert_eq!(supplied, 0.0, "fixed anchors supply no work");
}
