//! Acceptance 1, 2 and 7 (iteration counts): the paper's benchmark (METHOD §4).

use phstring::Scheme;
use phstring::benchmarks::{PAPER_H0, PAPER_H1_DG, PAPER_H1_MP};

use crate::common::run_paper;

#[test]
fn paper_benchmark_values() {
    for (scheme, h1) in [
        (Scheme::DiscreteGradient, PAPER_H1_DG),
        (Scheme::Midpoint, PAPER_H1_MP),
    ] {
        let (sim, h0, reports) = run_paper(scheme);
        let end = sim.energies().hamiltonian();
        let max_inc_after = reports
            .iter()
            .filter(|r| r.t > 0.2 + 1e-9)
            .map(|r| (r.after.hamiltonian() - r.before.hamiltonian()).abs())
            .fold(0.0, f64::max);
        let iters: Vec<usize> = reports.iter().map(|r| r.newton_iterations).collect();
        eprintln!(
            "{scheme:?}: H(0) = {h0:.9}, H(1) = {end:.9}, max |dH| after loading = {max_inc_after:.3e}, iterations = {:?}",
            iters
        );
        assert!((h0 - PAPER_H0).abs() <= 1e-6, "H(0) = {h0}");
        assert!(
            (end - h1).abs() <= 1e-6,
            "{scheme:?}: H(1) = {end}, paper {h1}"
        );
    }
}
