//! Static equilibrium of a 1e6-element hanging steel rope (target: ≤ 1 s).
//!
//! `cargo bench -p phstring --bench statics [-- ELEMENTS]`: a 1000 m rope (EA = 1e8 N,
//! ρA = 1 kg/m) with a 2000 kg payload hangs from node 0; it starts straight down and
//! stress-free, in 2D and in 3D. Prints the path, Newton iterations, residual and the wall
//! time of `statics::solve` (best and median of five), and checks the tip depth against the
//! exact discrete solution of the paper's law.

use std::time::Instant;

use phstring::statics::{self, StaticsParams};
use phstring::testing::{down, hanging_chain};
use phstring::{Material, Problem};

const G: f64 = 9.81;

/// The rope of the module doc, `n` elements, straight down from node 0.
fn problem<const D: usize>(n: usize) -> Problem<D, Material> {
    let (len, rho_a, tip) = (1000.0, 1.0, 2000.0);
    hanging_chain(n, len, Material::hyperelastic(1e8), rho_a, tip, down())
}

/// Tip depth of the discrete chain with the paper's law: element `e` carries
/// `w l (n − e − ½) + P`, stretch `λ = t/EA + √((t/EA)² + 1)`.
fn exact_depth(n: usize) -> f64 {
    let (len, ea, w, p) = (1000.0, 1e8, G, G * 2000.0);
    let l = len / n as f64;
    (0..n)
        .map(|e| {
            let a = (w * l * (n as f64 - e as f64 - 0.5) + p) / ea;
            l * (a + (a * a + 1.0).sqrt())
        })
        .sum()
}

fn run<const D: usize>(n: usize) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..5 {
        let p = problem::<D>(n);
        let t0 = Instant::now();
        let eq = statics::solve(p, &StaticsParams::default(), None).expect("equilibrium");
        times.push(t0.elapsed().as_secs_f64());
        last = Some(eq);
    }
    let eq = last.unwrap();
    times.sort_by(f64::total_cmp);
    let depth = -eq.state.r[n][D - 1];
    let exact = exact_depth(n);
    println!(
        "D = {D}, {n} elements: {} ({} steps), {} Newton iterations, residual {:.2e} N (tol {:.2e}), tip error {:.1e} rel; solve best {:.3} s, median {:.3} s",
        eq.path.name(),
        eq.path.steps(),
        eq.iterations,
        eq.residual,
        eq.tolerance,
        (depth - exact).abs() / exact,
        times[0],
        times[2]
    );
}

fn main() {
    let n = std::env::args()
        .skip(1)
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(1_000_000);
    run::<2>(n);
    run::<3>(n);
}
