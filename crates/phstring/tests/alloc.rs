//! The step loop does not allocate: a counting global allocator around 50 steps of
//! the paper's benchmark, after one warm-up step, for both linear solvers.
//!
//! Allocations are counted per thread (a global counter would also count the test harness's
//! allocations on other threads and fail on a busy machine), so only the allocations of the
//! thread that runs the steps are measured.

use phstring::benchmarks::{paper_params, paper_pendulum};
use phstring::testing::{CountingAllocator, allocations, live_bytes};
use phstring::{Scheme, Simulation, SolverKind, StepControl, StepParams};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// The counting allocator sees allocations of the calling thread only, so another thread
/// allocating at the same time (as the test harness does on a busy machine) is not counted.
#[test]
fn allocation_counter_ignores_other_threads() {
    let before = allocations();
    let other = std::thread::spawn(|| {
        let v: Vec<Vec<u8>> = (0..1000).map(|i| vec![0; i + 1]).collect();
        v.len()
    });
    assert_eq!(other.join().unwrap(), 1000);
    // Spawning and joining allocate on this thread too; the 1000 vectors must not show.
    let here = allocations() - before;
    assert!(here < 100, "{here} allocations counted on this thread");
    let before = allocations();
    let v = vec![1u8; 10];
    assert_eq!(allocations() - before, 1);
    drop(v);
}

/// `check` refuses runs that cannot fit in memory, from `phstring::estimated_memory_bytes`.
/// The estimate must be what a simulation really holds: the heap bytes of a set-up
/// simulation (with its problem's state moved in) and after ten steps, against the estimate,
/// in 1D, 2D and 3D.
#[test]
fn memory_estimate_matches_the_allocator() {
    fn measure<const D: usize>(n_el: usize) -> (isize, isize) {
        let before = live_bytes();
        let mesh = phstring::Mesh::uniform_chain(n_el, 10.0).unwrap();
        let mut end = phstring::Vector::<D>::zeros();
        end[0] = 10.0;
        let initial = phstring::State::straight(&mesh, phstring::Vector::zeros(), end);
        let problem = phstring::Problem {
            point_masses: Vec::new(),
            mesh,
            material: phstring::Material::hyperelastic(1e6),
            rho_a: 1.0,
            body_force: phstring::Vector::zeros(),
            mass: phstring::MassMatrix::Consistent,
            boundary: phstring::Boundary {
                motions: vec![],
                feedback: vec![],
                fixed: vec![phstring::Fixed::node(0)],
                loads: vec![],
            },
            initial,
        };
        let mut sim = Simulation::new(problem, StepParams::default()).unwrap();
        let setup = live_bytes() - before;
        for _ in 0..10 {
            sim.step().unwrap();
        }
        let stepping = live_bytes() - before;
        drop(sim);
        (setup, stepping)
    }
    let n_el = 100_000;
    for (d, (setup, stepping)) in [
        (1, measure::<1>(n_el)),
        (2, measure::<2>(n_el)),
        (3, measure::<3>(n_el)),
    ] {
        let estimate = phstring::estimated_memory_bytes(d, n_el) as f64;
        eprintln!(
            "d = {d}: estimate {:.1} MB, set up {:.1} MB, after 10 steps {:.1} MB ({:.0} bytes per element)",
            estimate / 1e6,
            setup as f64 / 1e6,
            stepping as f64 / 1e6,
            stepping as f64 / n_el as f64
        );
        for measured in [setup, stepping] {
            let ratio = measured as f64 / estimate;
            assert!(
                (0.95..=1.05).contains(&ratio),
                "d = {d}: measured {measured} bytes, estimate {estimate}"
            );
        }
    }
}

#[test]
fn step_loop_does_not_allocate() {
    for solver in [SolverKind::BlockTridiagonal, SolverKind::SparseLu] {
        for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
            let params = StepParams {
                scheme,
                solver,
                ..paper_params()
            };
            let mut sim = Simulation::new(paper_pendulum(30), params).unwrap();
            sim.step().unwrap(); // warm-up: lets a backend size internal buffers once
            let before = allocations();
            let mut iters = 0;
            for _ in 0..50 {
                iters += sim.step().unwrap().newton_iterations;
            }
            let n = allocations() - before;
            eprintln!(
                "{solver:?} {scheme:?}: {n} allocations in 50 steps ({iters} Newton iterations)"
            );
            assert_eq!(
                n, 0,
                "{solver:?} {scheme:?}: the step loop allocated {n} times"
            );
        }
    }
    // Nonlinear elimination and step-size control on a fine mesh: adaptive steps with local
    // solves and rejected attempts.
    let mut problem = paper_pendulum(1000);
    problem.material = phstring::Material::tension_only_linear(20.0);
    let mut sim = Simulation::new(problem, StepParams::default()).unwrap();
    sim.step().unwrap();
    let before = allocations();
    let (mut local, mut rejected) = (0, 0);
    for _ in 0..40 {
        let r = sim.step().unwrap();
        local += r.local_iterations;
        rejected += r.rejected;
    }
    let n = allocations() - before;
    eprintln!(
        "elimination: {n} allocations in 40 steps ({local} local iterations, {rejected} rejected)"
    );
    assert!(local > 0, "elimination never ran");
    assert_eq!(
        n, 0,
        "the adaptive step loop with elimination allocated {n} times"
    );
}

/// A network (three strings at a junction, a spring, a spring to a fixed point, a point mass, a
/// moving support) steps without allocating, with each solver for general meshes.
#[test]
fn network_step_loop_does_not_allocate() {
    use phstring::{
        Boundary, Fixed, MassMatrix, Material, Motion, NetworkBuilder, PointMass, StringSpec,
        Vector,
    };
    let solvers: Vec<SolverKind> = [SolverKind::SparseLu, SolverKind::Auto].into();
    for solver in solvers {
        let g = Vector::<3>::new(0.0, 0.0, -9.81);
        let mut b = NetworkBuilder::<3, Material>::new();
        let hub = b.node(Vector::<3>::new(0.0, 0.0, 0.0));
        let tops: Vec<usize> = [(-10.0, 0.0), (5.0, 8.0), (5.0, -8.0)]
            .iter()
            .map(|&(x, y)| b.node(Vector::<3>::new(x, y, 10.0)))
            .collect();
        for (k, &top) in tops.iter().enumerate() {
            let spec = StringSpec {
                name: format!("leg{k}"),
                material: Material::tension_only_linear(2e7),
                rho_a: 1.5,
                mass: MassMatrix::Consistent,
                body_force: g * 1.5,
                prestretch: 1.0,
            };
            b.string(spec, &[top, hub], 20).unwrap();
        }
        let (m0, m1) = (b.group_nodes(0).unwrap()[10], b.group_nodes(1).unwrap()[10]);
        let gap = (b.position(m1).unwrap() - b.position(m0).unwrap()).norm();
        b.spring("brace", m0, m1, 1e4, gap).unwrap();
        b.spring_to_point("tie", hub, Vector::<3>::new(1.0, 0.0, 0.0), 1e3, 1.0)
            .unwrap();
        let z0 = 10.0;
        let net = b
            .build(
                Boundary {
                    fixed: vec![
                        Fixed {
                            node: tops[0],
                            components: [true, true, false],
                        },
                        Fixed::node(tops[1]),
                        Fixed::node(tops[2]),
                    ],
                    loads: vec![],
                    motions: vec![Motion::new(tops[0], 2, move |t| z0 + 0.1 * t * t)],
                    feedback: vec![],
                },
                vec![PointMass {
                    node: hub,
                    mass: 800.0,
                    weight: g * 800.0,
                }],
            )
            .unwrap();
        let params = StepParams {
            h: 2e-3,
            solver,
            ..StepParams::default()
        };
        let mut sim = Simulation::new(net, params).unwrap();
        sim.step().unwrap();
        let before = allocations();
        let mut iters = 0;
        for _ in 0..50 {
            iters += sim.step().unwrap().newton_iterations;
        }
        let n = allocations() - before;
        eprintln!(
            "network, {}: {n} allocations in 50 steps ({iters} Newton iterations)",
            sim.solver_name()
        );
        assert_eq!(
            n,
            0,
            "{}: the network step loop allocated {n} times",
            sim.solver_name()
        );
    }
}

/// The network solver with the bodies' slots in its junction system (a star of three
/// 30-element strings, two bodies linked to three nodes, 3D) solves without allocating once
/// built, factoring (`solve`) and with the kept factors (`solve_again`).
#[test]
fn network_solve_with_border_does_not_allocate() {
    use phstring::linsolve::{
        Block, BlockJacobian, BorderPattern, JunctionLu, LinearSolver, NetworkSolver,
    };
    use phstring::mesh::Mesh;
    let mut els = Vec::new();
    for arm in 0..3 {
        let mut prev = 0;
        for k in 0..30 {
            let next = 1 + arm * 30 + k;
            els.push([prev, next]);
            prev = next;
        }
    }
    let n = 91;
    let mesh = Mesh::new(n, els, vec![2.0; 90]).unwrap();
    let pattern = BorderPattern {
        slots: 4,
        links: vec![[29, 0], [29, 1], [59, 0], [59, 1], [15, 2], [15, 3]],
        pairs: vec![[0, 1], [2, 3]],
    };
    let mut solver = NetworkSolver::<3>::with_border(&mesh, &pattern, JunctionLu::Block).unwrap();
    solver.keep_factors();
    let mut jac = BlockJacobian::<3>::with_slots(&mesh, 4);
    // A mass-dominated matrix: 2 m/h² of 1e6 N/m on the diagonal, EA/l of 1e5 N/m between
    // neighbours, the bodies' 1e8 N/m.
    for d in &mut jac.diag {
        *d = Block::identity() * 1.2e6;
    }
    for off in &mut jac.off {
        *off = [Block::identity() * -1e5; 2];
    }
    for s in 0..4 {
        jac.border.own[s * 4 + s] = Block::identity() * 1e8;
    }
    let fill = |jac: &mut BlockJacobian<3>| {
        jac.border.links.clear();
        for &[node, slot] in &pattern.links {
            let b = Block::identity() * -1e5;
            jac.border.links.push((node, slot, b, b));
        }
    };
    fill(&mut jac);
    let rhs0: Vec<_> = (0..n + 4)
        .map(|i| phstring::Vector::<3>::from_element((i as f64).sin()))
        .collect();
    let mut x = rhs0.clone();
    solver.solve(&jac, &mut x).unwrap();
    let before = allocations();
    for _ in 0..20 {
        fill(&mut jac);
        x.copy_from_slice(&rhs0);
        solver.solve(&jac, &mut x).unwrap();
        x.copy_from_slice(&rhs0);
        solver.solve_again(&jac, &mut x).unwrap();
    }
    let count = allocations() - before;
    assert_eq!(
        count, 0,
        "the bordered network solve allocated {count} times"
    );
}

/// A 2D hoist for the winch allocation tests: a 5 t payload on `n_el` elements of 1 m of
/// 32 mm steel wire rope (EA = 4.3e7 N, 4.1 kg/m) hanging straight below a drum at the
/// origin, `reserve` more elements on the drum, the winch paying out `payout(t)` (or, with
/// `dynamics`, moved by the drum's dynamics).
fn winch_hoist(
    n_el: usize,
    reserve: usize,
    payout: impl Fn(f64) -> f64 + Send + Sync + 'static,
    dynamics: Option<phstring::WinchDrum>,
) -> phstring::Network<2, phstring::Material> {
    use phstring::{
        Boundary, MassMatrix, Material, NetworkBuilder, PointMass, StringSpec, Vector, Winch,
    };
    let (g, ea, rho_a, payload) = (9.81, 4.3e7, 4.1, 5000.0);
    let mut b = NetworkBuilder::<2, Material>::new();
    let drum = b.node(Vector::<2>::zeros());
    // The hook where the rope's static stretch puts it.
    let a = n_el as f64;
    let hook = b.node(Vector::<2>::new(
        0.0,
        -(a + g * (payload + 0.5 * rho_a * a) * a / ea),
    ));
    let spec = StringSpec {
        name: "rope".into(),
        material: Material::tension_only_linear(ea),
        rho_a,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -rho_a * g),
        prestretch: 1.0,
    };
    let group = b
        .string_on_drum(spec, &[drum, hook], n_el, reserve)
        .unwrap();
    let masses = vec![PointMass {
        node: hook,
        mass: payload,
        weight: Vector::<2>::new(0.0, -payload * g),
    }];
    b.build(Boundary::default(), masses)
        .unwrap()
        .with_winch(Winch {
            name: "hoist".into(),
            group,
            reserve,
            payout: std::sync::Arc::new(payout),
            drum_motion: None,
            drum: dynamics,
        })
}

/// Steps `sim` for `steps` steps and counts the allocations of the steps that end with a
/// cut (the winch string's group range changes: an element came off or went onto the
/// drum) and of the others: `(cuts, allocations in cut steps, allocations in the others)`.
fn count_winch_allocations<M: phstring::StoredEnergy>(
    sim: &mut Simulation<2, M>,
    group: usize,
    steps: usize,
) -> (usize, usize, usize) {
    let (mut cuts, mut at_cuts, mut between) = (0, 0, 0);
    for _ in 0..steps {
        let start = sim.system().groups()[group].elements.start;
        let before = allocations();
        sim.step().unwrap();
        let n = allocations() - before;
        if sim.system().groups()[group].elements.start != start {
            cuts += 1;
            at_cuts += n;
        } else {
            between += n;
        }
    }
    (cuts, at_cuts, between)
}

/// Steps `net` with `params` (one warm-up step, then `steps`) and counts the allocations as
/// [`count_winch_allocations`] does, printing them and the rejected steps under `label`.
fn winch_run_allocations(
    net: phstring::Network<2, phstring::Material>,
    group: usize,
    steps: usize,
    params: StepParams,
    label: &str,
) -> (usize, usize, usize) {
    let mut sim = Simulation::new(net, params).unwrap();
    sim.step().unwrap();
    let (cuts, at_cuts, between) = count_winch_allocations(&mut sim, group, steps);
    eprintln!(
        "{label}: {cuts} cut steps with {at_cuts} allocations, {between} allocations in the other steps, {} rejected",
        sim.rejected_steps()
    );
    (cuts, at_cuts, between)
}

/// The step parameters of the winch allocation tests: `h` = 0.01 s, the defaults otherwise.
fn at_10_ms() -> StepParams {
    StepParams {
        h: 0.01,
        ..StepParams::default()
    }
}

/// A winch run steps without allocating, the steps that cut included: 20 m of rope under a
/// 5 t payload, 3 m paid out in a smooth move of 3 s and hauled back in the same way,
/// elements of 1 m coming off and going onto the drum (step-size control on); with `dg`,
/// with `dg4` (three sub-steps, the cut after them, the winch port's means) and with `dg4`
/// under error control (the saved state, the embedded `dg` step, rejected attempts put
/// back).
#[test]
fn winch_step_loop_does_not_allocate() {
    // Smooth 0 → 1 over [0, 1], at rest at both ends.
    let smooth = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    let runs = [
        ("dg", Scheme::DiscreteGradient, StepControl::default()),
        ("dg4", Scheme::DiscreteGradient4, StepControl::default()),
        (
            "dg4 with error control",
            Scheme::DiscreteGradient4,
            StepControl::with_tolerance(1e-3, 1e-3),
        ),
    ];
    for (name, scheme, control) in runs {
        // 3 m out over 3 s (at up to 1.5 m/s) and back in over t = 4…7 s.
        let payout = move |t: f64| 3.0 * (smooth(t / 3.0) - smooth((t - 4.0) / 3.0));
        let net = winch_hoist(20, 10, payout, None);
        let group = net.groups.len() - 1;
        let params = StepParams {
            h: 0.01,
            scheme,
            control,
            ..StepParams::default()
        };
        let label = format!("winch, {name}");
        let (cuts, at_cuts, between) = winch_run_allocations(net, group, 799, params, &label);
        // Two elements come off the drum (the first, at p = 0+, in the warm-up step) and two
        // go back on (the last stays off at p = 0, on the edge of its band: docs/method.md
        // §23).
        assert!(cuts >= 4, "{name}: {cuts} cuts");
        assert_eq!(
            between, 0,
            "{name}: steps between cuts allocated {between} times"
        );
        assert_eq!(
            at_cuts, 0,
            "{name}: {cuts} cut steps allocated {at_cuts} times"
        );
    }
}

/// The same winch run in water (buoyancy, drag and added mass on the rope, 32 mm, drag
/// coefficient 1.2) steps without allocating, its cuts included: a cut lumps the water again
/// at the nodes between the old and the new drum node, in lists with room for every node
/// and element (docs/method.md §23, "The cost of a cut").
#[test]
fn winch_step_loop_in_water_does_not_allocate() {
    let smooth = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    let payout = move |t: f64| 3.0 * (smooth(t / 3.0) - smooth((t - 4.0) / 3.0));
    let net = winch_hoist(20, 10, payout, None);
    let group = net.groups.len() - 1;
    let net = net
        .with_water(phstring::Water::new(1025.0))
        .with_line_hydro(
            group,
            phstring::LineHydro {
                diameter: 0.032,
                cd: 1.2,
                ..Default::default()
            },
        );
    let (cuts, at_cuts, between) =
        winch_run_allocations(net, group, 799, at_10_ms(), "winch in water");
    assert!(cuts >= 4, "{cuts} cuts");
    assert_eq!(between, 0, "steps between cuts allocated {between} times");
    assert_eq!(at_cuts, 0, "{cuts} cut steps allocated {at_cuts} times");
}

/// A winch with a drum with dynamics steps without allocating, its cuts included: the same
/// hoist, its 2 t drum paying out against a tension controller (target 40 kN, damping
/// 2e4 N·s/m) under the 5 t payload's 50 kN, at about (50 − 40) kN / 2e4 N·s/m = 0.5 m/s.
/// The drum's payout is a Newton unknown, solved by the bordered solve's Schur complement
/// in buffers sized once.
#[test]
fn drum_step_loop_does_not_allocate() {
    let drum = phstring::WinchDrum {
        derivative_time: 0.0,
        inertia: 2000.0,
        force: std::sync::Arc::new(|_| 40.0e3),
        damping: 2.0e4,
        brake: None,
    };
    let net = winch_hoist(20, 10, |_| 0.0, Some(drum));
    let group = net.groups.len() - 1;
    let (cuts, at_cuts, between) = winch_run_allocations(net, group, 599, at_10_ms(), "drum");
    // About 3 m paid out in 6 s: elements of 1 m come off the drum.
    assert!(cuts >= 2, "{cuts} cuts");
    assert_eq!(between, 0, "steps between cuts allocated {between} times");
    assert_eq!(at_cuts, 0, "{cuts} cut steps allocated {at_cuts} times");
}

/// The hoist of [`winch_hoist`], 3 m paid out and hauled back in (smooth moves of 3 s each),
/// with a rigid body of `mass` [kg] (isotropic inertia `inertia` [kg·m²], in gravity) holding
/// node `node` at its point `point` [m], starting in `initial`, moving as `motion` or free.
fn hoist_with_body(
    node: usize,
    (mass, inertia): (f64, f64),
    point: phstring::Vector<2>,
    initial: phstring::BodyState,
    motion: Option<phstring::BodyMotion>,
) -> phstring::Network<2, phstring::Material> {
    use phstring::{Attachment, RigidBody, Vector};
    let smooth = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    let out_and_in = move |t: f64| 3.0 * (smooth(t / 3.0) - smooth(t / 3.0 - 1.0));
    winch_hoist(20, 10, out_and_in, None).with_body(RigidBody {
        name: "body".into(),
        mass,
        inertia: nalgebra::Matrix3::from_diagonal_element(inertia),
        weight: Vector::<2>::new(0.0, -mass * 9.81),
        attachments: vec![Attachment { node, point }],
        initial,
        wrench: None,
        hydro: None,
        motion,
        feedback: None,
    })
}

/// Steps the winch run `net` (its winch's string the last group) for 600 steps of 10 ms and
/// asserts at least 4 cuts and no allocation, cut steps included.
fn assert_winch_run_does_not_allocate(net: phstring::Network<2, phstring::Material>, label: &str) {
    let group = net.groups.len() - 1;
    let (cuts, at_cuts, between) = winch_run_allocations(net, group, 599, at_10_ms(), label);
    assert!(cuts >= 4, "{cuts} cuts");
    assert_eq!(between, 0, "steps between cuts allocated {between} times");
    assert_eq!(at_cuts, 0, "{cuts} cut steps allocated {at_cuts} times");
}

/// A winch whose drum is on a rigid body steps without allocating, the cuts (which move the
/// body's attachment to the new drum node and relink it) included: the hoist of
/// [`hoist_with_body`] with its drum (node 0) on a 50 t vessel that heaves 0.5 m and rolls 2°
/// from rest.
#[test]
fn body_drum_step_loop_does_not_allocate() {
    use nalgebra::{UnitQuaternion, Vector3};
    use phstring::{BodyMotion, BodyState, Vector};
    let w = std::f64::consts::TAU / 8.0;
    let pose = move |t: f64| {
        let c = 1.0 - (w * t).cos();
        (
            Vector3::new(0.0, -2.0 + 0.5 * c, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 2f64.to_radians() * c),
        )
    };
    let twist = move |t: f64| {
        let s = w * (w * t).sin();
        (
            Vector3::new(0.0, 0.5 * s, 0.0),
            Vector3::new(0.0, 0.0, 2f64.to_radians() * s),
        )
    };
    let (x0, q0) = pose(0.0);
    let motion = BodyMotion {
        pose: std::sync::Arc::new(pose),
        twist: std::sync::Arc::new(twist),
    };
    let start = BodyState::new(x0, Vector3::zeros(), q0, Vector3::zeros());
    let net = hoist_with_body(
        0,
        (5e4, 4e6),
        Vector::<2>::new(0.0, 2.0),
        start,
        Some(motion),
    );
    assert_winch_run_does_not_allocate(net, "body drum");
}

/// A free rigid body steps without allocating (its rows' buffers are kept between
/// evaluations): the hoist of [`hoist_with_body`] with a free 1 t block hanging from the hook
/// (node 1) by a point 0.5 m above its centre, started turning.
#[test]
fn free_body_step_loop_does_not_allocate() {
    use nalgebra::{UnitQuaternion, Vector3};
    use phstring::{BodyState, Vector};
    // The hook where the rope's static stretch under the 5 t payload puts it.
    let (ea, rho_a, payload, a) = (4.3e7, 4.1, 5000.0, 20.0);
    let y_hook = -(a + 9.81 * (payload + 0.5 * rho_a * a) * a / ea);
    let omega = Vector3::new(0.0, 0.0, 0.2);
    let arm = Vector3::new(0.0, 0.5, 0.0);
    let start = BodyState::new(
        Vector3::new(0.0, y_hook - 0.5, 0.0),
        Vector3::zeros(),
        UnitQuaternion::identity(),
        omega,
    );
    let mut net = hoist_with_body(1, (1000.0, 200.0), Vector::<2>::new(0.0, 0.5), start, None);
    let v_hook = omega.cross(&arm);
    net.initial.v[1] = Vector::<2>::new(v_hook.x, v_hook.y);
    assert_winch_run_does_not_allocate(net, "free body");
}
