//! The cost of a rigid body in the step (docs/method.md §22): a cable robot of 8 cables
//! (tension-only, EA = 1e6 N, 0.05 kg/m) from the corners of a 4 × 4 × 3 m frame to a 50 kg
//! platform, in gravity, 2000 steps of 1 ms, once with the platform a rigid body (8 attached
//! cable ends, a bordered solve) and once as a point mass where the 8 cables meet (a junction
//! of the network solver). `cargo bench -p phstring --bench bodies` prints, per mesh (10 to
//! 800 elements per cable), the time per step and per Newton iteration of both and the
//! body's extra cost per iteration in elements of the junction model (the extra time over the
//! junction model's time per element).

use nalgebra::{UnitQuaternion, Vector3};
use phstring::{
    Attachment, BodyState, Boundary, Fixed, MassMatrix, Material, NetworkBuilder, PointMass,
    RigidBody, Simulation, StepParams, StringSpec, Vector,
};
use std::time::Instant;

/// Seconds per step and per Newton iteration of the cable robot with `n_el` elements per
/// cable, the platform a body (`with_body`) or a point mass at a junction.
fn run(n_el: usize, with_body: bool) -> (f64, f64) {
    let anchors = [
        (-2.0, -2.0, 3.0),
        (2.0, -2.0, 3.0),
        (2.0, 2.0, 3.0),
        (-2.0, 2.0, 3.0),
        (-2.0, -2.0, 0.0),
        (2.0, -2.0, 0.0),
        (2.0, 2.0, 0.0),
        (-2.0, 2.0, 0.0),
    ];
    let pts = [
        (-0.3, -0.3, 0.15),
        (0.3, -0.3, 0.15),
        (0.3, 0.3, 0.15),
        (-0.3, 0.3, 0.15),
        (-0.3, -0.3, -0.15),
        (0.3, -0.3, -0.15),
        (0.3, 0.3, -0.15),
        (-0.3, 0.3, -0.15),
    ];
    let centre = Vector3::new(0.0, 0.0, 1.5);
    let mut nb = NetworkBuilder::<3, Material>::new();
    let spec = StringSpec {
        name: "cable".into(),
        material: Material::tension_only_linear(1e6),
        rho_a: 0.05,
        mass: MassMatrix::Consistent,
        body_force: Vector::<3>::new(0.0, 0.0, -0.05 * 9.81),
        prestretch: 1.002,
    };
    let mut atts = Vec::new();
    let junction = if with_body {
        None
    } else {
        Some(nb.node(centre))
    };
    let mut fixed = Vec::new();
    for (a, p) in anchors.iter().zip(&pts) {
        let an = nb.node(Vector::<3>::new(a.0, a.1, a.2));
        fixed.push(Fixed::node(an));
        let s = Vector3::new(p.0, p.1, p.2);
        let end = match junction {
            Some(j) => j,
            None => nb.node(centre + s),
        };
        nb.string(spec.clone(), &[an, end], n_el).unwrap();
        atts.push(Attachment {
            node: end,
            point: s,
        });
    }
    let boundary = Boundary {
        fixed,
        ..Default::default()
    };
    let pm = match junction {
        Some(j) => vec![PointMass {
            node: j,
            mass: 50.0,
            weight: Vector::<3>::new(0.0, 0.0, -50.0 * 9.81),
        }],
        None => vec![],
    };
    let mut net = nb.build(boundary, pm).unwrap();
    if with_body {
        let inertia = nalgebra::Matrix3::from_diagonal(&Vector3::new(1.9, 1.9, 3.0));
        net = net.with_body(RigidBody {
            name: "platform".into(),
            mass: 50.0,
            inertia,
            weight: Vector::<3>::new(0.0, 0.0, -50.0 * 9.81),
            attachments: atts,
            initial: BodyState::at_rest(centre, UnitQuaternion::identity()),
            wrench: None,
            hydro: None,
            motion: None,
            feedback: None,
        });
    }
    let params = StepParams {
        h: 1e-3,
        ..Default::default()
    };
    let mut sim = Simulation::new(net, params).unwrap();
    let steps = 2000;
    let t0 = Instant::now();
    let mut its = 0;
    for _ in 0..steps {
        its += sim.step().unwrap().newton_iterations;
    }
    let dt = t0.elapsed().as_secs_f64();
    (dt / steps as f64, dt / its as f64)
}

fn main() {
    println!(
        "elements  body ms/step  µs/it   junction ms/step  µs/it   body's extra cost [elements]"
    );
    for n_el in [10, 50, 200, 800] {
        // Alternate, best of three each.
        let (mut b, mut j) = ((f64::MAX, f64::MAX), (f64::MAX, f64::MAX));
        for _ in 0..3 {
            let rb = run(n_el, true);
            let rj = run(n_el, false);
            b = (b.0.min(rb.0), b.1.min(rb.1));
            j = (j.0.min(rj.0), j.1.min(rj.1));
        }
        let elements = 8 * n_el;
        let extra = (b.1 - j.1) / (j.1 / elements as f64);
        println!(
            "{elements:>8}  {:>12.3}  {:>6.1}  {:>16.3}  {:>6.1}   {extra:>8.0}",
            b.0 * 1e3,
            b.1 * 1e6,
            j.0 * 1e3,
            j.1 * 1e6
        );
    }
}
