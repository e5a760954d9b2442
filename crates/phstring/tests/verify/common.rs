//! Shared helpers.

use phstring::benchmarks::{paper_params, paper_pendulum};
use phstring::water::STANDARD_GRAVITY as G;
use phstring::{
    Boundary, Energies, Fixed, MassMatrix, Material, Mesh, Network, Problem, Scheme, Simulation,
    State, StepParams, StepReport, Vector,
};

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

/// A chain of `n` elements of reference length `l` with nodes at `r` (at rest), the linear
/// elastic law `ea` [N], mass `rho_a` [kg/m] and its weight (standard gravity along the last
/// axis), lumped mass, the nodes `fixed` held: the mooring line of the water tests.
pub fn chain<const D: usize>(
    r: Vec<Vector<D>>,
    l: f64,
    ea: f64,
    rho_a: f64,
    fixed: &[usize],
) -> Network<D, Material> {
    let n = r.len() - 1;
    let mesh = Mesh::uniform_chain(n, l * n as f64).unwrap();
    let mut b = Vector::<D>::zeros();
    b[D - 1] = -rho_a * G;
    Problem {
        initial: State::at_rest(&mesh, r),
        mesh,
        material: Material::linear_elastic(ea),
        rho_a,
        body_force: b,
        mass: MassMatrix::Lumped,
        boundary: Boundary {
            fixed: fixed.iter().map(|&i| Fixed::node(i)).collect(),
            loads: vec![],
            motions: vec![],
            feedback: vec![],
        },
        point_masses: vec![],
    }
    .into()
}
