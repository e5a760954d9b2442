//! The paper's pendulum on fine meshes (issue 4): largest fixed step that converges with
//! plain and with globalized Newton, and adaptive runs at N = 3000 for each law.
//!
//! `cargo bench -p phstring --bench pendulum_scaling` (several minutes).

use std::time::Instant;

use phstring::benchmarks::paper_pendulum;
use phstring::{Material, NewtonParams, Simulation, StepControl, StepParams};

/// Runs to `t_end` with fixed steps; `Ok(())` if every step converged.
fn fixed(n_el: usize, h: f64, line_search: bool, t_end: f64) -> Result<(), String> {
    let params = StepParams {
        h,
        newton: NewtonParams {
            line_search,
            ..Default::default()
        },
        control: StepControl {
            adaptive: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut sim = Simulation::new(paper_pendulum(n_el), params).map_err(|e| e.to_string())?;
    sim.run_until(t_end, &mut ())
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn main() {
    println!("# Largest fixed h (0.01·2^-k) at which the pendulum converges to T");
    println!(
        "{:>7} {:>6} {:>14} {:>14}",
        "N", "T [s]", "plain Newton", "line search"
    );
    for (n, t_end) in [(300usize, 1.0), (3000, 1.0), (30000, 0.05)] {
        let mut row = Vec::new();
        for ls in [false, true] {
            let mut found = None;
            for k in 0..12 {
                let h = 0.01 / f64::powi(2.0, k);
                if fixed(n, h, ls, t_end).is_ok() {
                    found = Some(h);
                    break;
                }
            }
            row.push(found.map_or("none ≥ 5e-6".to_string(), |h| format!("{h:.3e}")));
        }
        println!("{n:>7} {t_end:>6} {:>14} {:>14}", row[0], row[1]);
    }
    println!();
    println!("# Adaptive runs, N = 3000, T = 1 s, h_max = 0.01, line search");
    println!(
        "{:>26} {:>8} {:>6} {:>9} {:>9} {:>9} {:>9} {:>12}",
        "law", "wall [s]", "steps", "rejected", "it/step", "h min", "h max", "max|dH| >0.2"
    );
    for law in [
        Material::hyperelastic(20.0),
        Material::tension_only_hyperelastic(20.0),
        Material::tension_only_linear(20.0),
    ] {
        let mut problem = paper_pendulum(3000);
        problem.material = law;
        let mut sim = Simulation::new(problem, StepParams::default()).unwrap();
        let (mut steps, mut iters, mut hmax, mut dh) = (0, 0, 0.0_f64, 0.0_f64);
        let t0 = Instant::now();
        let mut ok = true;
        while sim.time() < 1.0 - 1e-12 {
            match sim.step_until(1.0) {
                Ok(r) => {
                    steps += 1;
                    iters += r.newton_iterations;
                    hmax = hmax.max(r.h);
                    if r.t > 0.2 + 1e-9 && r.t - r.h >= 0.2 - 1e-12 {
                        dh = dh.max((r.after.hamiltonian() - r.before.hamiltonian()).abs());
                    }
                }
                Err(e) => {
                    println!("{:>26} failed: {e}", law.name());
                    ok = false;
                    break;
                }
            }
        }
        if ok {
            println!(
                "{:>26} {:>8.3} {:>6} {:>9} {:>9.2} {:>9.2e} {:>9.2e} {:>12.2e}",
                law.name(),
                t0.elapsed().as_secs_f64(),
                steps,
                sim.rejected_steps(),
                iters as f64 / steps as f64,
                sim.smallest_step_size(),
                hmax,
                dh
            );
        }
    }
}
