//! The physics of the example scenarios (issue 11, item 9), run in-process from the files in
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
    assert!(rel.abs() < 3e-3, "swing period {measured} s vs {predicted} s");
    assert!(worst <= 1e-13, "energy balance error {worst:e} of the energy scale");
    // The trolley is the only port that moves: its work is all the energy supplied.
    assert!(
        (drive_work - supplied).abs() <= 1e-9 * supplied.abs().max(1.0),
        "drive work {drive_work} J vs supplied {supplied} J"
    );
}
