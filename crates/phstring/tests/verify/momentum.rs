//! Momentum maps of a free–free string (docs/method.md §5, eq. (5.9)).

use phstring::{
    Boundary, MassMatrix, Material, Mesh, NewtonParams, Problem, Scheme, Simulation, State,
    StepParams, Vector,
};

/// A free string of reference length 1, stretched by 1.3, spinning about the z axis
/// (and, in 3D, tumbling), with a radial stretching velocity.
fn spinning<const D: usize>(scheme: Scheme) -> Simulation<D, Material> {
    let n_el = 12;
    let mesh = Mesh::uniform_chain(n_el, 1.0).unwrap();
    let mut r = Vec::new();
    let mut v = Vec::new();
    for i in 0..=n_el {
        let s = i as f64 / n_el as f64 - 0.5;
        let mut ri = Vector::<D>::zeros();
        ri[0] = 1.3 * s;
        let mut vi = Vector::<D>::zeros();
        vi[0] = -2.5 * s; // stretching
        vi[1] = 8.0 * ri[0]; // spin about z: ω × r
        if D == 3 {
            vi[2] = 1.0 * s + 0.2; // tumbling + drift
        }
        r.push(ri);
        v.push(vi);
    }
    let problem = Problem {
        point_masses: Vec::new(),
        initial: State::consistent(&mesh, r, v),
        mesh,
        material: Material::hyperelastic(20.0),
        rho_a: 1.0,
        body_force: Vector::zeros(),
        mass: MassMatrix::Consistent,
        boundary: Boundary::default(),
    };
    let params = StepParams {
        h: 0.01,
        scheme,
        newton: NewtonParams {
            tol: 1e-12,
            rtol: 0.0,
            max_iter: 25,
            ..Default::default()
        },
        ..Default::default()
    };
    Simulation::new(problem, params).unwrap()
}

fn stretch_range<const D: usize>(sim: &Simulation<D, Material>, range: &mut (f64, f64)) {
    for &c in &sim.state().c {
        range.0 = range.0.min(c.sqrt());
        range.1 = range.1.max(c.sqrt());
    }
}

/// 200 steps of each scheme: linear momentum ≤ 1e-13, angular momentum ≤ 1e-12 relative,
/// a stretch range of about 0.8 … 1.9, DG energy ≤ 1e-10 relative and MP's ≥ 1000× larger.
/// `angular` gives the angular momentum's components (one in 2D, three in 3D).
fn check_momentum_maps<const D: usize>(angular: impl Fn(&Simulation<D, Material>) -> Vec<f64>) {
    let mut energy_err = [0.0; 2];
    for (k, scheme) in [Scheme::DiscreteGradient, Scheme::Midpoint]
        .into_iter()
        .enumerate()
    {
        let mut sim = spinning::<D>(scheme);
        let p0 = sim.system().linear_momentum(sim.state());
        let l0 = angular(&sim);
        let l0_norm = l0.iter().map(|x| x * x).sum::<f64>().sqrt();
        let h0 = sim.energies().hamiltonian();
        let mut range = (f64::INFINITY, 0.0);
        let (mut dp, mut dl, mut de) = (0.0_f64, 0.0_f64, 0.0_f64);
        for _ in 0..200 {
            sim.step().unwrap();
            stretch_range(&sim, &mut range);
            dp = dp.max((sim.system().linear_momentum(sim.state()) - p0).norm());
            let l = angular(&sim);
            let d = l
                .iter()
                .zip(&l0)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            dl = dl.max(d / l0_norm);
            de = de.max((sim.energies().hamiltonian() - h0).abs() / h0.abs());
        }
        eprintln!(
            "{D}D {scheme:?}: stretch {range:?}, |Δp| {dp:e}, |ΔL|/|L| {dl:e}, |ΔH|/H {de:e}"
        );
        assert!(range.0 < 0.85 && range.1 > 1.8, "stretch range {range:?}");
        assert!(dp <= 1e-13, "linear momentum drift {dp:e}");
        assert!(dl <= 1e-12, "angular momentum drift {dl:e}");
        energy_err[k] = de;
    }
    assert!(
        energy_err[0] <= 1e-10,
        "DG energy error {:e}",
        energy_err[0]
    );
    assert!(
        energy_err[1] >= 1e3 * energy_err[0].max(1e-16),
        "MP energy error {:e}",
        energy_err[1]
    );
}

#[test]
fn momentum_maps_2d() {
    check_momentum_maps::<2>(|sim| vec![sim.system().angular_momentum(sim.state())]);
}

#[test]
fn momentum_maps_3d() {
    check_momentum_maps::<3>(|sim| {
        sim.system()
            .angular_momentum(sim.state())
            .iter()
            .copied()
            .collect()
    });
}
