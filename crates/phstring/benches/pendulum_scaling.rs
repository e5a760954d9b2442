//! The paper's pendulum on fine meshes: largest fixed step that converges with
//! plain Newton, with the line search, and with line search plus nonlinear elimination; and
//! adaptive runs at N = 3000 for each law, with their step sizes and Newton work.
//!
//! `cargo bench -p phstring --bench pendulum_scaling` (under a minute). Wall times are the
//! best of three runs; the runs are deterministic, so only the wall time varies. With
//! `-- full` the fixed-step table runs N = 30000 to T = 1 s as well (about 45 minutes; without
//! it, to T = 0.05 s), and `-- table` prints only that table. `-- damping` prints only the
//! table of adaptive runs with Kelvin–Voigt damping: does a physically small
//! viscosity remove the crumpling of the compressed free end and let the steps stay large?

use std::collections::BTreeMap;
use std::time::Instant;

use phstring::benchmarks::paper_pendulum;
use phstring::{
    Damping, Material, Network, NewtonParams, Predictor, Simulation, StepControl, StepParams,
};

/// Newton variants of the fixed-step table.
#[derive(Clone, Copy)]
enum Variant {
    Plain,
    LineSearch,
    Elimination,
}

fn newton(v: Variant) -> NewtonParams {
    NewtonParams {
        line_search: !matches!(v, Variant::Plain),
        elimination: matches!(v, Variant::Elimination),
        ..Default::default()
    }
}

/// Runs to `t_end` with fixed steps; `Ok(())` if every step converged.
fn fixed(n_el: usize, h: f64, v: Variant, t_end: f64) -> Result<(), String> {
    let params = StepParams {
        h,
        newton: newton(v),
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

/// What an adaptive run to `T = 1 s` did.
#[derive(Default)]
struct Adaptive {
    wall: f64,
    steps: usize,
    rejected: usize,
    iterations: usize,
    max_iterations: usize,
    rejected_iterations: usize,
    /// Local elimination work in global-iteration equivalents.
    local_work: f64,
    h_min: f64,
    h_max: f64,
    /// Accepted steps per step size (keyed by `−log2(h/0.01)`).
    h_hist: BTreeMap<i32, usize>,
    max_dh: f64,
    /// Smallest element strain met (`C < 1`: compression).
    c_min: f64,
    /// Energy dissipated [J].
    dissipated: f64,
}

fn adaptive(
    n_el: usize,
    law: Material,
    predictor: Predictor,
    elimination: bool,
) -> Result<Adaptive, String> {
    adaptive_damped(n_el, law, predictor, elimination, 0.0)
}

/// [`adaptive`] with Kelvin–Voigt viscosity `eta` [N·s].
fn adaptive_damped(
    n_el: usize,
    law: Material,
    predictor: Predictor,
    elimination: bool,
    eta: f64,
) -> Result<Adaptive, String> {
    let mut problem = paper_pendulum(n_el);
    problem.material = law;
    let mut problem: Network<2, Material> = problem.into();
    problem.groups[0].damping = Damping {
        kelvin_voigt: eta,
        ..Damping::NONE
    };
    let params = StepParams {
        predictor,
        newton: NewtonParams {
            elimination,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut sim = Simulation::new(problem, params).map_err(|e| e.to_string())?;
    let nodes = (n_el + 1) as f64;
    let mut a = Adaptive {
        h_min: f64::INFINITY,
        c_min: f64::INFINITY,
        ..Default::default()
    };
    let t0 = Instant::now();
    while sim.time() < 1.0 - 1e-12 {
        let r = sim.step_until(1.0).map_err(|e| e.to_string())?;
        a.steps += 1;
        a.rejected += r.rejected;
        a.iterations += r.newton_iterations;
        a.max_iterations = a.max_iterations.max(r.newton_iterations);
        a.rejected_iterations += r.rejected_iterations;
        a.local_work += (r.local_node_iterations + r.rejected_local_node_iterations) as f64 / nodes;
        a.h_min = a.h_min.min(r.h);
        a.h_max = a.h_max.max(r.h);
        a.c_min = sim.state().c.iter().copied().fold(a.c_min, f64::min);
        a.dissipated += r.dissipated;
        let level = (0.01 / r.h).log2().round() as i32;
        *a.h_hist.entry(level).or_default() += 1;
        // Loading ends at t = 0.2: from then on the energy changes only by D_n.
        if r.t - r.h >= 0.2 - 1e-12 {
            a.max_dh = a
                .max_dh
                .max((r.after.hamiltonian() - r.before.hamiltonian() + r.dissipated).abs());
        }
    }
    a.wall = t0.elapsed().as_secs_f64();
    Ok(a)
}

/// Best wall time of three identical runs.
fn adaptive_best(
    n_el: usize,
    law: Material,
    predictor: Predictor,
    elimination: bool,
) -> Result<Adaptive, String> {
    let mut best = adaptive(n_el, law, predictor, elimination)?;
    for _ in 0..2 {
        let again = adaptive(n_el, law, predictor, elimination)?;
        best.wall = best.wall.min(again.wall);
    }
    Ok(best)
}

fn laws() -> [Material; 3] {
    [
        Material::hyperelastic(20.0),
        Material::tension_only_hyperelastic(20.0),
        Material::tension_only_linear(20.0),
    ]
}

fn predictor_name(p: Predictor) -> &'static str {
    match p {
        Predictor::Velocity => "velocity",
        Predictor::Acceleration => "acceleration",
        Predictor::MidpointVelocity => "midpoint_velocity",
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let full = args.iter().any(|a| a == "full");
    let table_only = args.iter().any(|a| a == "table");
    if args.iter().any(|a| a == "damping") {
        damping_table();
        return;
    }
    if !table_only {
        adaptive_tables();
        damping_table();
    }
    fixed_table(full);
}

/// Adaptive runs at N = 3000 (hyperelastic, default settings) with Kelvin–Voigt viscosity
/// η from 0 up: wall time, steps, Newton work, smallest strain and dissipated energy.
fn damping_table() {
    println!(
        "# Kelvin-Voigt damping, N = 3000, T = 1 s, hyperelastic, default settings (best wall of 3)"
    );
    println!(
        "{:>9} {:>8} {:>6} {:>5} {:>8} {:>8} {:>9} {:>9} {:>10} {:>7} {:>10}",
        "eta [Ns]",
        "wall [s]",
        "steps",
        "rej",
        "it/step",
        "max it",
        "rej its",
        "h min",
        "max|bal|",
        "C min",
        "D(1 s) [J]"
    );
    for eta in [0.0, 1e-5, 1e-4, 1e-3, 1e-2] {
        let law = Material::hyperelastic(20.0);
        let mut best: Option<Adaptive> = None;
        for _ in 0..3 {
            match adaptive_damped(3000, law, Predictor::MidpointVelocity, true, eta) {
                Ok(a) => {
                    let wall = best.as_ref().map_or(a.wall, |b| b.wall.min(a.wall));
                    best = Some(Adaptive { wall, ..a });
                }
                Err(e) => {
                    println!("{eta:>9.0e} failed: {e}");
                    break;
                }
            }
        }
        if let Some(a) = best {
            println!(
                "{:>9.0e} {:>8.3} {:>6} {:>5} {:>8.2} {:>8} {:>9} {:>9.2e} {:>10.1e} {:>7.4} {:>10.4e}",
                eta,
                a.wall,
                a.steps,
                a.rejected,
                a.iterations as f64 / a.steps as f64,
                a.max_iterations,
                a.rejected_iterations,
                a.h_min,
                a.max_dh,
                a.c_min,
                a.dissipated
            );
        }
    }
    println!();
}

fn adaptive_tables() {
    println!("# Adaptive runs, N = 3000, T = 1 s, h_max = 0.01 s (best wall of 3)");
    println!(
        "{:>26} {:>17} {:>5} {:>8} {:>6} {:>5} {:>8} {:>8} {:>8} {:>9} {:>9} {:>10} {:>6}",
        "law",
        "predictor",
        "elim",
        "wall [s]",
        "steps",
        "rej",
        "it/step",
        "max it",
        "local/st",
        "rej its",
        "h min",
        "max|dH|>.2",
        "C min"
    );
    let mut hists = Vec::new();
    let configs = laws()
        .into_iter()
        .flat_map(|law| {
            [Predictor::MidpointVelocity, Predictor::Velocity]
                .into_iter()
                .map(move |p| (law, p, true))
        })
        .chain([(
            Material::hyperelastic(20.0),
            Predictor::MidpointVelocity,
            false,
        )]);
    for (law, predictor, elimination) in configs {
        match adaptive_best(3000, law, predictor, elimination) {
            Ok(a) => {
                println!(
                    "{:>26} {:>17} {:>5} {:>8.3} {:>6} {:>5} {:>8.2} {:>8} {:>8.2} {:>9} {:>9.2e} {:>10.1e} {:>6.3}",
                    law.name(),
                    predictor_name(predictor),
                    elimination,
                    a.wall,
                    a.steps,
                    a.rejected,
                    a.iterations as f64 / a.steps as f64,
                    a.max_iterations,
                    a.local_work / a.steps as f64,
                    a.rejected_iterations,
                    a.h_min,
                    a.max_dh,
                    a.c_min
                );
                let hist: Vec<String> = a
                    .h_hist
                    .iter()
                    .map(|(k, c)| format!("{:.2e}:{c}", 0.01 / f64::powi(2.0, *k)))
                    .collect();
                hists.push(format!(
                    "{} / {} / elim {}: {}",
                    law.name(),
                    predictor_name(predictor),
                    elimination,
                    hists_join(&hist)
                ));
            }
            Err(e) => println!(
                "{:>26} {:>17} failed: {e}",
                law.name(),
                predictor_name(predictor)
            ),
        }
    }
    println!();
    println!("# Accepted step sizes (h: number of steps)");
    for h in &hists {
        println!("{h}");
    }
    println!();
    println!(
        "# Spread with the mesh: wall [s] of one run, N = 2800 … 3200, default predictor (midpoint velocity)"
    );
    print!("{:>26}", "law");
    let ns = [2800usize, 2850, 2900, 2950, 3000, 3050, 3100, 3150, 3200];
    for n in ns {
        print!(" {n:>7}");
    }
    println!();
    for law in laws() {
        print!("{:>26}", law.name());
        for n in ns {
            match adaptive(n, law, Predictor::MidpointVelocity, true) {
                Ok(a) => print!(" {:>7.3}", a.wall),
                Err(_) => print!(" {:>7}", "failed"),
            }
        }
        println!();
    }
    println!();
}

fn fixed_table(full: bool) {
    println!("# Largest fixed h (0.01·2^-k) at which the pendulum converges to T");
    println!(
        "{:>7} {:>6} {:>14} {:>14} {:>14}",
        "N", "T [s]", "plain Newton", "line search", "LS + elim."
    );
    let t_30000 = if full { 1.0 } else { 0.05 };
    for (n, t_end) in [(300usize, 1.0), (3000, 1.0), (30000, t_30000)] {
        let mut row = Vec::new();
        for v in [Variant::Plain, Variant::LineSearch, Variant::Elimination] {
            let mut found = None;
            for k in 0..12 {
                let h = 0.01 / f64::powi(2.0, k);
                if fixed(n, h, v, t_end).is_ok() {
                    found = Some(h);
                    break;
                }
            }
            row.push(found.map_or("none ≥ 5e-6".to_string(), |h| format!("{h:.3e}")));
        }
        println!(
            "{n:>7} {t_end:>6} {:>14} {:>14} {:>14}",
            row[0], row[1], row[2]
        );
    }
}

fn hists_join(parts: &[String]) -> String {
    parts.join("  ")
}
