//! The 10 lowest natural modes of a 1e5-element taut string (target: ≤ 2 s).
//!
//! `cargo bench -p phstring --bench modes_lanczos [-- ELEMENTS]`: a 1000 m steel wire
//! (linear elastic, EA = 1e8 N, ρA = 1 kg/m) stretched 0.1 % between two supports, in 2D and
//! 3D. Prints the method, the linear solves, the wall time of `modes::modes` (best and median
//! of five) and the largest relative error against the discrete closed form
//! `ω² = 6k/(ρA l²)(1 − cos θ)/(2 + cos θ)`, `θ = jπ/n` (`1 − cos θ` as `2 sin²(θ/2)`: at
//! `θ = π/1e5` the difference loses 7 digits), with `k = S = EA(1 − 1/λ)`
//! (transverse, a pair in 3D) or `k = EA` (longitudinal).

use std::f64::consts::PI;
use std::time::Instant;

use phstring::testing::between_supports;
use phstring::{Material, PhSystem, SolverKind, Vector, modes};

fn run<const D: usize>(n: usize) {
    let (len, stretch, ea, rho_a) = (1000.0, 1.001, 1e8, 1.0);
    let mut end = Vector::<D>::zeros();
    end[0] = len * stretch;
    let p = between_supports(
        n,
        len,
        end,
        Material::linear_elastic(ea),
        rho_a,
        Vector::zeros(),
    );
    let (sys, st) = PhSystem::new(p).unwrap();
    let l = len / n as f64;
    let omega = |k: f64, j: usize| {
        let th = j as f64 * PI / n as f64;
        (6.0 * k / (rho_a * l * l) * (2.0 * (th / 2.0).sin().powi(2)) / (2.0 + th.cos())).sqrt()
    };
    let s = ea * (1.0 - 1.0 / stretch);
    let mut want: Vec<f64> = (1..n)
        .flat_map(|j| std::iter::repeat_n(omega(s, j), D - 1).chain([omega(ea, j)]))
        .take(40)
        .collect();
    want.sort_by(f64::total_cmp);
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..5 {
        let t0 = Instant::now();
        let m = modes::modes(&sys, &st.r, 10, SolverKind::Auto, None).unwrap();
        times.push(t0.elapsed().as_secs_f64());
        last = Some(m);
    }
    let m = last.unwrap();
    times.sort_by(f64::total_cmp);
    let err = m
        .modes
        .iter()
        .zip(&want)
        .map(|(a, w)| (a.omega - w).abs() / w)
        .fold(0.0, f64::max);
    println!(
        "D = {D}, {n} elements, 10 lowest modes: {} ({} solves), max rel. error {err:.1e}; best {:.3} s, median {:.3} s",
        m.method, m.solves, times[0], times[2]
    );
}

fn main() {
    let n = std::env::args()
        .skip(1)
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(100_000);
    run::<2>(n);
    run::<3>(n);
}
