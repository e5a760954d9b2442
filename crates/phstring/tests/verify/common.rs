//! Shared helpers.

use phstring::benchmarks::{paper_params, paper_pendulum};
use phstring::{Energies, Material, Scheme, Simulation, StepParams, StepReport};

/// Runs the paper benchmark with `scheme`, returning the simulation, `Ĥ(0)` and all reports.
pub fn run_paper(scheme: Scheme) -> (Simulation<2, Material>, f64, Vec<StepReport>) {
    let params = StepParams {
        scheme,
        ..paper_params()
    };
    let mut sim = Simulation::new(paper_pendulum(30), params).expect("valid problem");
    let h0 = sim.energies().hamiltonian();
    let mut reports = Vec::new();
    for _ in 0..100 {
        reports.push(sim.step().expect("step converges"));
    }
    (sim, h0, reports)
}

/// The energy scale of a state [J]: the largest magnitude of its kinetic, internal and
/// external potential energy (balance errors are judged relative to it).
pub fn energy_scale(e: &Energies) -> f64 {
    e.kinetic.abs().max(e.internal.abs()).max(e.external.abs())
}
