//! Throughput of the time stepper: element-Newton-iterations per second (issue 4).
//!
//! `cargo bench -p phstring --bench throughput [-- max_n]` prints one row per mesh size,
//! dimension and linear solver. The problem is a taut string (both ends fixed, prestretched
//! to C = 1.44, gravity on) with a sinusoidal transverse initial velocity, DG scheme, with
//! a step size small enough that every mesh converges in a few iterations. Nonlinear
//! elimination is off, so that every iteration counted is a full one.

use std::time::Instant;

use phstring::{
    Boundary, Fixed, MassMatrix, Material, Mesh, Problem, Scheme, Simulation, SolverKind, State,
    StepParams, Vector,
};

fn problem<const D: usize>(n_el: usize) -> Problem<D, Material> {
    let mesh = Mesh::uniform_chain(n_el, 1.0).unwrap();
    let r: Vec<Vector<D>> = (0..=n_el)
        .map(|i| {
            let mut x = Vector::<D>::zeros();
            x[0] = 1.2 * i as f64 / n_el as f64;
            x
        })
        .collect();
    let v: Vec<Vector<D>> = (0..=n_el)
        .map(|i| {
            let mut x = Vector::<D>::zeros();
            x[1] = (std::f64::consts::PI * i as f64 / n_el as f64).sin();
            x
        })
        .collect();
    let mut g = Vector::<D>::zeros();
    g[1] = -9.81;
    Problem {
        point_masses: Vec::new(),
        initial: State::consistent(&mesh, r, v),
        mesh,
        material: Material::hyperelastic(20.0),
        rho_a: 1.0,
        body_force: g,
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            motions: vec![],
            fixed: vec![Fixed::node(0), Fixed::node(n_el)],
            loads: vec![],
        },
    }
}

fn measure<const D: usize>(n_el: usize, solver: SolverKind) -> (f64, f64, usize) {
    let params = StepParams {
        h: 1e-3,
        scheme: Scheme::DiscreteGradient,
        solver,
        ..Default::default()
    };
    // Tolerance relative to the problem size: the residual floor grows like sqrt(N).
    let mut params = params;
    params.newton.tol = 1e-11 * (n_el as f64 / 30.0).sqrt().max(1.0);
    params.newton.rtol = 0.0;
    // The cost of a full Newton iteration: no local solves in between.
    params.newton.elimination = false;
    let mut sim = Simulation::new(problem::<D>(n_el), params).unwrap();
    sim.step().unwrap(); // warm-up
    let target = if n_el >= 100_000 {
        3
    } else {
        (3_000_000 / n_el).clamp(3, 2000)
    };
    let mut iters = 0;
    let t0 = Instant::now();
    for _ in 0..target {
        iters += sim.step().unwrap().newton_iterations;
    }
    let dt = t0.elapsed().as_secs_f64();
    let rate = (iters * n_el) as f64 / dt;
    (rate, dt / iters as f64, iters)
}

/// The paper's benchmark time loop (100 steps, 30 elements), best of 20 runs [s].
fn paper_loop() -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut iters = 0;
    for _ in 0..20 {
        let mut sim = Simulation::new(
            phstring::benchmarks::paper_pendulum(30),
            phstring::benchmarks::paper_params(),
        )
        .unwrap();
        let t0 = Instant::now();
        iters = 0;
        for _ in 0..100 {
            iters += sim.step().unwrap().newton_iterations;
        }
        best = best.min(t0.elapsed().as_secs_f64());
    }
    (best, iters)
}

fn main() {
    let (t, it) = paper_loop();
    println!(
        "paper benchmark time loop (DG, 30 elements, 100 steps): {:.3} ms, {it} Newton iterations (best of 20)",
        t * 1e3
    );
    let max_n: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    println!(
        "{:>9} {:>2} {:>18} {:>22} {:>16} {:>6}",
        "elements", "d", "solver", "element-iter/s", "s per iteration", "iters"
    );
    for &n in &[100usize, 1_000, 10_000, 100_000, 1_000_000] {
        if n > max_n {
            break;
        }
        for solver in [SolverKind::BlockTridiagonal, SolverKind::SparseLu] {
            if solver == SolverKind::SparseLu && n > 100_000 && max_n < 10_000_000 {
                // faer's symbolic analysis at 1e6 blocks takes seconds; include with max_n ≥ 1e7.
                println!(
                    "{n:>9}  - {:>18} {:>22}",
                    "sparse-lu", "(skipped: pass 10000000)"
                );
                continue;
            }
            let (r2, s2, i2) = measure::<2>(n, solver);
            println!(
                "{n:>9} {:>2} {:>18} {:>22.3e} {:>16.3e} {:>6}",
                2,
                format!("{solver:?}"),
                r2,
                s2,
                i2
            );
            let (r3, s3, i3) = measure::<3>(n, solver);
            println!(
                "{n:>9} {:>2} {:>18} {:>22.3e} {:>16.3e} {:>6}",
                3,
                format!("{solver:?}"),
                r3,
                s3,
                i3
            );
        }
    }
}
