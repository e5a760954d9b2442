//! Throughput of the time stepper: element-Newton-iterations per second.
//!
//! `cargo bench -p phstring --bench throughput [-- max_n]` prints one row per mesh size,
//! dimension and linear solver. The problem is a taut string (both ends fixed, prestretched
//! to C = 1.44, gravity on) with a sinusoidal transverse initial velocity, DG scheme, with
//! a step size small enough that every mesh converges in a few iterations. Nonlinear
//! elimination is off, so that every iteration counted is a full one. The wet rows run the
//! same string lying on a seabed 10 m down in a current, with buoyancy, drag, added mass,
//! seabed damping and friction (docs/method.md §21), and without the friction, against the
//! dry string. Times are this thread's CPU time where Linux reports it (the wall clock
//! otherwise, as for the paper's loop), so that a busy machine does not slow the rates.

use std::time::Instant;

use phstring::{
    Boundary, Current, Fixed, Friction, LineHydro, MassMatrix, Material, Mesh, Network,
    NetworkBuilder, Problem, Scheme, Seabed, Simulation, SolverKind, State, StepParams, StringSpec,
    Vector, Water,
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
            feedback: vec![],
            fixed: vec![Fixed::node(0), Fixed::node(n_el)],
            loads: vec![],
        },
    }
}

/// The taut string of [`problem`] 10 m under water, resting on a flat seabed there, in a
/// 0.3 m/s current, with buoyancy, drag, added mass, seabed damping and (with `friction`)
/// friction. The friction's Coulomb level per node (about 5e-4 N on 1.2e-4 m elements) over
/// its slope (100 N·s/m) is a regularization speed of 5 µm/s, far below the string's speeds:
/// nearly discontinuous, the law makes Newton backtrack. Its weight
/// acts along the water's vertical (`z` in 3D), so that it presses on the seabed (in 3D the
/// dry string's gravity along `y` would leave it floating just off it).
fn wet<const D: usize>(n_el: usize, friction: bool) -> Network<D, Material> {
    let mut p = problem::<D>(n_el);
    for r in &mut p.initial.r {
        r[D - 1] -= 10.0;
    }
    p.body_force = Vector::<D>::zeros();
    p.body_force[D - 1] = -9.81;
    let mut u = Vector::<D>::zeros();
    u[0] = 0.3;
    let mut seabed = Seabed::flat(10.0, 3.0e6, 3.0e5);
    if friction {
        seabed = seabed.with_friction(Friction::new(0.5, 100.0));
    }
    let water = Water::new(1025.0)
        .with_gravity(9.81)
        .with_current(Current::Uniform(u))
        .with_seabed(seabed);
    let hydro = LineHydro {
        diameter: 0.02,
        cd: 1.2,
        cd_axial: 0.008,
        ca: 1.0,
        ca_axial: 1.0,
    };
    Network::from(p).with_water(water).with_line_hydro(0, hydro)
}

fn measure<const D: usize>(n_el: usize, solver: SolverKind) -> (f64, f64, usize) {
    let (rate, per, iters, _) = measure_problem::<D>(problem::<D>(n_el).into(), n_el, solver);
    (rate, per, iters)
}

fn measure_problem<const D: usize>(
    net: Network<D, Material>,
    n_el: usize,
    solver: SolverKind,
) -> (f64, f64, usize, usize) {
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
    let mut sim = Simulation::new(net, params).unwrap();
    sim.step().unwrap(); // warm-up
    let target = if n_el >= 100_000 {
        3
    } else {
        (3_000_000 / n_el).clamp(3, 2000)
    };
    let mut iters = 0;
    let mut backtracks = 0;
    let t0 = Clock::start();
    let mut steps = 0;
    while steps < target || t0.seconds() < MIN_MEASURED {
        let report = sim.step().unwrap();
        iters += report.newton_iterations;
        backtracks += report.backtracks;
        steps += 1;
    }
    let dt = t0.seconds();
    let rate = (iters * n_el) as f64 / dt;
    (rate, dt / iters as f64, iters, backtracks)
}

/// The time a measurement takes: this thread's CPU time where Linux reports it
/// (`/proc/thread-self/schedstat`), so that other jobs on a busy machine do not count,
/// else the wall clock.
enum Clock {
    Cpu(f64),
    Wall(Instant),
}

impl Clock {
    fn cpu() -> Option<f64> {
        let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
        let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
        Some(ns * 1e-9)
    }
    fn start() -> Self {
        Self::cpu().map_or_else(|| Clock::Wall(Instant::now()), Clock::Cpu)
    }
    /// Seconds since [`Clock::start`].
    fn seconds(&self) -> f64 {
        match self {
            Clock::Cpu(t0) => Self::cpu().unwrap_or(*t0) - t0,
            Clock::Wall(t0) => t0.elapsed().as_secs_f64(),
        }
    }
    fn name() -> &'static str {
        if Self::cpu().is_some() {
            "this thread's CPU time"
        } else {
            "wall clock"
        }
    }
}

/// A net of `2k` strings (`k` along x, `k` along y) crossing at a `k × k` grid of shared
/// junction nodes, `span` elements between crossings and from the border crossings to the
/// fixed border anchors: each string has `(k + 1) · span` elements. Prestretched (λ = 1.2),
/// gravity on, a transverse initial velocity: the chain benchmark's problem, as a net.
fn net<const D: usize>(k: usize, span: usize) -> Network<D, Material> {
    assert!(D >= 2);
    let spacing = 1.2 / (k + 1) as f64;
    let mut b = NetworkBuilder::<D, Material>::new();
    let at = |i: f64, j: f64| {
        let mut x = Vector::<D>::zeros();
        x[0] = i * spacing;
        x[1] = j * spacing;
        x
    };
    let cross: Vec<usize> = (0..k * k)
        .map(|n| b.node(at((n % k + 1) as f64, (n / k + 1) as f64)))
        .collect();
    let mut g = Vector::<D>::zeros();
    g[D - 1] = -9.81;
    let spec = |name: String| StringSpec {
        name,
        material: Material::hyperelastic(20.0),
        rho_a: 1.0,
        mass: MassMatrix::Consistent,
        body_force: g,
        prestretch: 1.2,
    };
    let mut anchors = Vec::new();
    for dir in 0..2 {
        for j in 0..k {
            let edge = |b: &mut NetworkBuilder<D, Material>, i: f64| {
                b.node(if dir == 0 {
                    at(i, (j + 1) as f64)
                } else {
                    at((j + 1) as f64, i)
                })
            };
            let first = edge(&mut b, 0.0);
            let last = edge(&mut b, (k + 1) as f64);
            anchors.extend([first, last]);
            let mut path = vec![first];
            path.extend((0..k).map(|i| {
                if dir == 0 {
                    cross[j * k + i]
                } else {
                    cross[i * k + j]
                }
            }));
            path.push(last);
            b.string(spec(format!("s{dir}_{j}")), &path, span).unwrap();
        }
    }
    let fixed = anchors.iter().map(|&a| Fixed::node(a)).collect();
    let mut network = b
        .build(
            Boundary {
                fixed,
                loads: vec![],
                motions: vec![],
                feedback: vec![],
            },
            vec![],
        )
        .unwrap();
    let pi = std::f64::consts::PI;
    for (r, v) in network.initial.r.iter().zip(&mut network.initial.v) {
        v[D - 1] = (pi * r[0] / 1.2).sin() * (pi * r[1] / 1.2).sin();
    }
    network
}

/// Element-Newton-iterations per second of the net (see [`net`]) with `solver`, as
/// [`measure`] does for a chain: `(rate, seconds per iteration, iterations, elements)`.
fn measure_net<const D: usize>(
    k: usize,
    span: usize,
    solver: SolverKind,
) -> (f64, f64, usize, usize) {
    let network = net::<D>(k, span);
    let n_el = network.mesh.n_elements();
    let mut params = StepParams {
        h: 1e-3,
        scheme: Scheme::DiscreteGradient,
        solver,
        ..Default::default()
    };
    params.newton.tol = 1e-11 * (n_el as f64 / 30.0).sqrt().max(1.0);
    params.newton.rtol = 0.0;
    params.newton.elimination = false;
    let mut sim = Simulation::new(network, params).unwrap();
    sim.step().unwrap(); // warm-up
    let mut iters = 0;
    let t0 = Clock::start();
    // At least 3 steps and MIN_MEASURED s (see MIN_MEASURED).
    let mut steps = 0;
    while steps < 3 || t0.seconds() < MIN_MEASURED {
        iters += sim.step().unwrap().newton_iterations;
        steps += 1;
    }
    let dt = t0.seconds();
    ((iters * n_el) as f64 / dt, dt / iters as f64, iters, n_el)
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
    println!("rates per second of {}", Clock::name());
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
    println!(
        "in water (on the seabed, in a current): ratio = wet rate / dry rate; the line search's \
         extra evaluations (backtracks) count in the wet rows' iterations"
    );
    for &n in &[1_000usize, 10_000, 100_000] {
        if n > max_n {
            break;
        }
        let (dry, _, _) = measure::<3>(n, SolverKind::BlockTridiagonal);
        for (label, friction) in [("wet BlockTridiagonal", true), ("wet, no friction", false)] {
            let (r3, s3, i3, b3) =
                measure_problem::<3>(wet::<3>(n, friction), n, SolverKind::BlockTridiagonal);
            println!(
                "{n:>9} {:>2} {:>18} {:>22.3e} {:>16.3e} {:>6}   ratio {:.2}, {b3} backtracks",
                3,
                label,
                r3,
                s3,
                i3,
                r3 / dry
            );
        }
    }
    // The net: 50 + 50 strings of 1020 elements crossing at a 50 × 50 grid of junctions,
    // against the chain of (about) the same size.
    let (k, span) = if max_n >= 100_000 { (50, 20) } else { (10, 20) };
    let (chain2, _, _) = measure::<2>(2 * k * (k + 1) * span, SolverKind::BlockTridiagonal);
    let (chain3, _, _) = measure::<3>(2 * k * (k + 1) * span, SolverKind::BlockTridiagonal);
    println!(
        "net of {} strings × {} elements ({} junctions); ratio = net rate / chain rate at the same size",
        2 * k,
        (k + 1) * span,
        k * k
    );
    for solver in NET_SOLVERS {
        let (r2, s2, i2, n2) = measure_net::<2>(k, span, solver);
        println!(
            "{n2:>9} {:>2} {:>18} {:>22.3e} {:>16.3e} {:>6}   ratio {:.2}",
            2,
            format!("net {solver:?}"),
            r2,
            s2,
            i2,
            r2 / chain2
        );
        let (r3, s3, i3, n3) = measure_net::<3>(k, span, solver);
        println!(
            "{n3:>9} {:>2} {:>18} {:>22.3e} {:>16.3e} {:>6}   ratio {:.2}",
            3,
            format!("net {solver:?}"),
            r3,
            s3,
            i3,
            r3 / chain3
        );
    }
}

/// The shortest time [s] a rate is measured over: the CPU-time clock advances in ticks of a
/// few ms, which a small problem's few steps can fall within (a rate of inf).
const MIN_MEASURED: f64 = 0.3;

/// Solvers measured on the net.
const NET_SOLVERS: [SolverKind; 2] = [SolverKind::SparseLu, SolverKind::Network];
