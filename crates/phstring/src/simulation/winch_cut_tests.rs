//! A winch's cut in place (docs/method.md §23, "The cost of a cut") against a placement
//! of the whole system: after every cut the system's data are those a restore builds from
//! scratch (group ranges, held flags, body forces, constrained sets, the lumped water, bit
//! for bit), and the energies updated in place are those of an evaluation of the state; a
//! checkpoint taken at a cut resumes bit for bit.

use super::Simulation;
use super::test_support::fixed_steps;
use crate::network::{NetworkBuilder, StringSpec};
use crate::system::{MassMatrix, PointMass, Vector};
use crate::water::{LineHydro, PointHydro, Seabed, Water};
use crate::winch::{Winch, WinchDrum};
use crate::{Boundary, Material};
use std::sync::Arc;

/// 76 mm studless chain (EA = 5e8 N, 115 kg/m, elements of 1 m) from a drum 5 m above the
/// water, 14 elements off the drum and 8 on it, a 2 t clump (0.3 m³) at its end, hanging
/// into 10 m of water over a flat seabed (kBot 3e6 Pa/m, cBot 1e5 Pa·s/m), drag on the chain
/// (Cd 2.4, CdAx 1.15, Ca 1): paid out 5 m over 5 s and hauled back in the same way, so that
/// the clump lands on the seabed and lifts off again; or with `drum`, a drum with dynamics.
fn chain_over_water(drum: Option<WinchDrum>) -> Simulation<2, Material> {
    Simulation::new(chain_network(drum), fixed_steps(0.01)).unwrap()
}

/// The 76 mm studless chain: EA = 5e8 N, 115 kg/m, in gravity.
fn chain_spec() -> StringSpec<2, Material> {
    let rho_a = 115.0;
    StringSpec {
        name: "chain".into(),
        material: Material::tension_only_linear(5.0e8),
        rho_a,
        mass: MassMatrix::Consistent,
        body_force: Vector::<2>::new(0.0, -rho_a * 9.81),
        prestretch: 1.0,
    }
}

/// The network of [`chain_over_water`].
fn chain_network(drum: Option<WinchDrum>) -> crate::Network<2, Material> {
    let (g, clump, time) = (9.81, 2000.0, 5.0);
    let mut b = NetworkBuilder::<2, Material>::new();
    let top = b.node(Vector::<2>::new(0.0, 5.0));
    let end = b.node(Vector::<2>::new(2.0, -8.857));
    let group = b.string_on_drum(chain_spec(), &[top, end], 14, 8).unwrap();
    let masses = vec![PointMass {
        node: end,
        mass: clump,
        weight: Vector::<2>::new(0.0, -clump * g),
    }];
    b.build(Boundary::default(), masses)
        .unwrap()
        .with_water(Water::new(1025.0).with_seabed(Seabed::flat(10.0, 3e6, 1e5)))
        .with_line_hydro(
            group,
            LineHydro {
                diameter: 0.136,
                cd: 2.4,
                cd_axial: 1.15,
                ca: 1.0,
                ca_axial: 0.0,
            },
        )
        .with_point_hydro(PointHydro {
            node: end,
            volume: 0.3,
            cda: 0.5,
            ca: 1.0,
        })
        .with_winch(Winch {
            name: "drum".into(),
            group,
            reserve: 8,
            payout: Arc::new(move |t| 5.0 * (smooth(t / time) - smooth(t / time - 1.2))),
            drum_motion: None,
            drum,
        })
}

/// `C¹` step from 0 to 1 over `x ∈ [0, 1]` (the payouts' ramps).
fn smooth(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Steps `sim` and its `twin` (the same problem) for `steps` steps; after every step that
/// cut, restores the twin from `sim`'s checkpoint (a placement of the whole system and the
/// water lumped from scratch) and checks that both systems hold the same data and that
/// `sim`'s energies, updated in place, are those of its state (every term within 1e-13 of
/// the energies' magnitude). Returns the cuts and the largest energy difference over the
/// energies' magnitude.
fn compare_cuts(
    sim: Simulation<2, Material>,
    twin: Simulation<2, Material>,
    steps: usize,
) -> (usize, f64) {
    let (cuts, worst, _) = compare_all_cuts(sim, twin, steps);
    (cuts, worst)
}

/// [`compare_cuts`] over every winch of `sim`: a step cuts when any winch's drum element
/// changes. Also returns the most elements any winch crossed in one step.
fn compare_all_cuts(
    mut sim: Simulation<2, Material>,
    mut twin: Simulation<2, Material>,
    steps: usize,
) -> (usize, f64, usize) {
    let (mut cuts, mut worst, mut widest) = (0, 0.0_f64, 0);
    let drums = |s: &Simulation<2, Material>| s.run.winches.iter().map(|w| w.drum).collect();
    for _ in 0..steps {
        let from: Vec<usize> = drums(&sim);
        sim.step().unwrap();
        let to: Vec<usize> = drums(&sim);
        if to == from {
            continue;
        }
        for (a, b) in from.iter().zip(&to) {
            widest = widest.max(a.abs_diff(*b));
        }
        cuts += 1;
        twin.restore(sim.checkpoint()).unwrap();
        let (a, b) = (&sim.sys, &twin.sys);
        let ranges = |s: &crate::PhSystem<2, Material>| {
            s.groups
                .iter()
                .map(|g| g.elements.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(ranges(a), ranges(b), "group ranges");
        assert_eq!(a.free, b.free, "held flags");
        assert_eq!(a.f_body, b.f_body, "body forces");
        assert_eq!(a.constrained, b.constrained, "constrained nodes");
        assert_eq!(a.constrained_elements, b.constrained_elements);
        assert_eq!(a.water, b.water, "the lumped water");
        assert_eq!(a.attached, b.attached, "the nodes held by bodies");
        assert_eq!(a.body_links, b.body_links, "the bodies' links");
        let points = |s: &crate::PhSystem<2, Material>| {
            let at = |m: &crate::body::BodyModel| m.attachments.clone();
            s.bodies.iter().map(at).collect::<Vec<_>>()
        };
        assert_eq!(points(a), points(b), "the bodies' attachments");
        let e = sim.with_drums(sim.sys.energies(&sim.run.state), false);
        let h = sim.energies;
        let parts = |x: &crate::Energies| [x.kinetic, x.internal, x.external, x.buoyancy, x.seabed];
        for (p, q) in parts(&h).iter().zip(parts(&e)) {
            worst = worst.max((p - q).abs() / e.magnitude);
        }
        assert!((h.magnitude - e.magnitude).abs() <= 1e-12 * e.magnitude);
    }
    assert!(
        worst <= 1e-13,
        "energies off by {worst:e} of their magnitude"
    );
    (cuts, worst, widest)
}

/// A chain paid out into water onto the seabed and hauled back: every cut in place leaves
/// the system as a placement from scratch does, and its energies within 1e-13 of their
/// magnitude of an evaluation (the parts summed in another order).
#[test]
fn a_cut_in_place_leaves_the_system_as_a_placement_from_scratch() {
    let sim = chain_over_water(None);
    let grounded = |s: &Simulation<2, Material>| s.sys.water.as_ref().unwrap().nodes.len();
    let wet_nodes = grounded(&sim);
    let (cuts, worst) = compare_cuts(sim, chain_over_water(None), 1150);
    eprintln!("{cuts} cuts, {wet_nodes} wet nodes at the start; energies off by {worst:.2e}");
    // 5 m out and back, elements of 1 m: 5 off the drum and 5 back on (the last one may
    // stay off on the edge of its band).
    assert!(cuts >= 9, "{cuts} cuts");
}

/// The same with a drum with dynamics (1.5 t at the chain, a 20 kN pull, damping 4e4
/// N·s/m): its kinetic energy changes at a cut with the path's stretch and is part of the
/// energies updated in place.
#[test]
fn a_cut_in_place_keeps_a_drums_kinetic_energy() {
    let drum = || WinchDrum {
        inertia: 1500.0,
        force: Arc::new(|t| 2.0e4 + 1e3 * t),
        damping: 4.0e4,
        brake: None,
        derivative_time: 0.0,
    };
    let sim = chain_over_water(Some(drum()));
    let (cuts, worst) = compare_cuts(sim, chain_over_water(Some(drum())), 600);
    eprintln!("{cuts} cuts; energies off by {worst:.2e}");
    assert!(cuts >= 2, "{cuts} cuts");
}

/// A run resumed from a checkpoint taken on a step that cut (its record in the flat form a
/// checkpoint file and an FMU state store) reports the energies an uninterrupted run
/// reports, bit for bit: the checkpoint carries the energies updated in place, which an
/// evaluation of the state gives only to rounding (here the internal energy differs in its
/// last bit).
#[test]
fn a_checkpoint_taken_at_a_cut_resumes_bit_for_bit() {
    let mut sim = chain_over_water(None);
    while sim.run.winches[0].drum == 8 {
        sim.step().unwrap();
    }
    let held = sim.checkpoint().energies.expect("the run's energies");
    let evaluated = sim.with_drums(sim.sys.energies(&sim.run.state), false);
    eprintln!("at the cut: held {held:?}\n evaluated {evaluated:?}");
    assert_ne!(
        held, evaluated,
        "the test needs energies that differ by rounding"
    );
    let flat = sim.flat_checkpoint();
    let mut resumed = chain_over_water(None);
    resumed.restore(flat.into_checkpoint()).unwrap();
    assert_eq!(resumed.energies, sim.energies);
    for _ in 0..300 {
        let (a, b) = (sim.step().unwrap(), resumed.step().unwrap());
        assert_eq!((a.before, a.after), (b.before, b.after), "at t = {} s", a.t);
    }
    assert_eq!(resumed.checkpoint(), sim.checkpoint());
}

/// A water point (a buoy's volume, drag and added mass) on a winch string's node other
/// than its last is refused naming the node, as a point mass there is: the node goes onto
/// the drum.
#[test]
fn a_water_point_on_a_winch_strings_inner_node_is_refused() {
    let mut b = NetworkBuilder::<2, Material>::new();
    let top = b.node(Vector::<2>::new(0.0, 5.0));
    let end = b.node(Vector::<2>::new(0.0, -9.0));
    let group = b.string_on_drum(chain_spec(), &[top, end], 14, 8).unwrap();
    let inner = b.group_nodes(group).unwrap()[10];
    let net = b
        .build(Boundary::default(), Vec::new())
        .unwrap()
        .with_water(Water::new(1025.0))
        .with_point_hydro(PointHydro {
            node: inner,
            volume: 0.2,
            cda: 0.3,
            ca: 1.0,
        })
        .with_winch(Winch {
            name: "drum".into(),
            group,
            reserve: 8,
            payout: Arc::new(|_| 0.0),
            drum_motion: None,
            drum: None,
        });
    let Err(err) = Simulation::new(net, fixed_steps(0.01)) else {
        panic!("a water point on the drum's string was accepted");
    };
    let err = err.to_string();
    assert!(
        err.contains(&format!("mesh node {inner}")) && err.contains("water point"),
        "{err}"
    );
}

/// The chain's drum on a 40 t vessel that heaves 0.6 m and rolls 3° at a 6 s period: every
/// cut in place leaves the system, the vessel's attachment and links included, as a
/// placement from scratch does.
#[test]
fn cuts_of_a_drum_on_a_vessel_leave_the_system_as_a_placement_from_scratch() {
    use crate::body::{Attachment, BodyMotion, BodyState, RigidBody};
    use nalgebra::{UnitQuaternion, Vector3};
    let w = std::f64::consts::TAU / 6.0;
    let pose = move |t: f64| {
        let c = 1.0 - (w * t).cos();
        (
            Vector3::new(0.0, 3.0 + 0.3 * c, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 1.5f64.to_radians() * c),
        )
    };
    let twist = move |t: f64| {
        let s = w * (w * t).sin();
        (
            Vector3::new(0.0, 0.3 * s, 0.0),
            Vector3::new(0.0, 0.0, 1.5f64.to_radians() * s),
        )
    };
    let on_vessel = || {
        let (x0, q0) = pose(0.0);
        let net = chain_network(None);
        let top = net.mesh.elements()[net.groups[0].elements.start][0];
        let net = net.with_body(RigidBody {
            name: "vessel".into(),
            mass: 4e4,
            inertia: nalgebra::Matrix3::from_diagonal_element(3e6),
            weight: Vector::<2>::new(0.0, -4e4 * 9.81),
            attachments: vec![Attachment {
                node: top,
                point: Vector::<2>::new(0.0, 2.0),
            }],
            initial: BodyState::new(x0, Vector3::zeros(), q0, Vector3::zeros()),
            wrench: None,
            hydro: None,
            motion: Some(BodyMotion {
                pose: Arc::new(pose),
                twist: Arc::new(twist),
            }),
            feedback: None,
        });
        Simulation::new(net, fixed_steps(0.01)).unwrap()
    };
    let (cuts, worst) = compare_cuts(on_vessel(), on_vessel(), 1150);
    eprintln!("{cuts} cuts; energies off by {worst:.2e}");
    assert!(cuts >= 9, "{cuts} cuts");
}

/// With `dg4`, the damped seabed contacts that set how many triple jumps a step takes
/// (docs/method.md §19) follow the cuts: after every cut of the chain paid out onto the
/// seabed and hauled back, they are those of the system as placed, so that a node the cut
/// lumps anew (the drum element's length changes its mass and contact) is not split by
/// stale numbers.
#[test]
fn dg4_damped_contacts_follow_the_cuts() {
    let mut params = fixed_steps(0.01);
    params.scheme = crate::integrator::Scheme::DiscreteGradient4;
    let mut sim = Simulation::new(chain_network(None), params).unwrap();
    let (mut cuts, mut changed) = (0, 0);
    let start = sim.contacts.clone();
    for _ in 0..1150 {
        let from = sim.run.winches[0].drum;
        sim.step().unwrap();
        if sim.run.winches[0].drum == from {
            continue;
        }
        cuts += 1;
        let placed = crate::integrator::damped_contacts(&sim.sys);
        changed += usize::from(placed != start);
        assert_eq!(sim.contacts, placed, "after cut {cuts}");
    }
    eprintln!("{cuts} cuts, {changed} with contacts other than the start's");
    assert!(cuts >= 9 && changed >= 1, "{cuts} cuts, {changed} changed");
}

/// A winch's hold after every step (its drum node's velocity set to the payout rate) books
/// the change of the energy of the elements at the drum node alone: after every step of
/// the chain paid out onto the seabed and hauled back (prescribed, and a drum with
/// dynamics; with `dg`, and with `dg4`, whose sub-steps hold too), the run's energies are
/// those of an evaluation of the state, every term within 1e-13 of their magnitude, and
/// holds changed them on at least 100 steps.
#[test]
fn a_hold_updates_the_energies_in_place() {
    let drum = WinchDrum {
        inertia: 1500.0,
        force: Arc::new(|t| 2.0e4 + 1e3 * t),
        damping: 4.0e4,
        brake: None,
        derivative_time: 0.0,
    };
    let dg4 = || {
        let mut p = fixed_steps(0.01);
        p.scheme = crate::integrator::Scheme::DiscreteGradient4;
        p
    };
    let cases = [
        ("prescribed", None, fixed_steps(0.01), 1150),
        ("drum", Some(drum), fixed_steps(0.01), 600),
        ("prescribed, dg4", None, dg4(), 1150),
    ];
    for (label, drum, params, steps) in cases {
        let mut sim = Simulation::new(chain_network(drum), params).unwrap();
        let (mut worst, mut moved) = (0.0_f64, 0);
        for _ in 0..steps {
            let report = sim.step().unwrap();
            let e = sim.with_drums(sim.sys.energies(&sim.run.state), false);
            let (h, f) = (sim.energies.to_array(), e.to_array());
            for (p, q) in h.iter().zip(f) {
                worst = worst.max((p - q).abs() / e.magnitude);
            }
            // The holds' energy: the winch's supply beyond its reaction's work.
            moved += usize::from(report.winch != sim.winch_work.iter().sum::<f64>());
        }
        eprintln!("{label}: {moved} of {steps} holds changed the energies; worst {worst:.2e}");
        assert!(worst <= 1e-13, "{label}: off by {worst:e} of the magnitude");
        // Measured 1003 of 1150 (prescribed) and 149 of 600 (the drum's own speed is
        // mostly its path's already): the test is not vacuous.
        assert!(moved >= 100, "{label}: {moved} holds changed the energies");
    }
}

/// Two winches over 10 m of water with a seabed: 36 mm wire ropes (EA = 1e8 N, 6 kg/m,
/// 0.1 m elements, the linear law, prestretched) from drums 5 m above the water, each with
/// a 500 kg hook 3 m down, drag and added mass on the ropes; one paid out 2 m and the other
/// 5 m over 2.5 s and hauled back, in steps of 0.05 s, so that the fast drum element moves by up to two elements in one
/// step. Every cut in place, of one winch or of both at once, leaves the system as a
/// placement from scratch does; and the nodes that come off the drum together predict the
/// next step from their new velocity (with the zero mid-step velocity of the step they were
/// parked through, Newton started 0.13 m off and failed the step after the first cut of two
/// elements). Measured: 84 cuts, two elements at most, energies within 3.8e-16.
#[test]
fn two_winches_and_cuts_of_several_elements_match_a_placement_from_scratch() {
    let two = || {
        let mut b = NetworkBuilder::<2, Material>::new();
        let rope = |name: &str| StringSpec {
            name: name.into(),
            // The linear law without the tension-only kink, on which Newton needs smaller
            // steps than these while the hook's axial oscillation (period 0.04 s) goes slack.
            material: Material::linear_elastic(1.0e8),
            rho_a: 6.0,
            mass: MassMatrix::Consistent,
            body_force: Vector::<2>::new(0.0, -6.0 * 9.81),
            // About the hook's static stretch (5e-5).
            prestretch: 1.00005,
        };
        let mut groups = Vec::new();
        let mut masses = Vec::new();
        for (k, name) in ["slow", "fast"].into_iter().enumerate() {
            let x = 6.0 * k as f64;
            let top = b.node(Vector::<2>::new(x, 5.0));
            let hook = b.node(Vector::<2>::new(x, -3.0));
            groups.push(b.string_on_drum(rope(name), &[top, hook], 80, 60).unwrap());
            masses.push(PointMass {
                node: hook,
                mass: 500.0,
                weight: Vector::<2>::new(0.0, -500.0 * 9.81),
            });
        }
        let hydro = LineHydro {
            diameter: 0.036,
            cd: 1.2,
            cd_axial: 0.008,
            ca: 1.0,
            ca_axial: 0.0,
        };
        let mut net = b
            .build(Boundary::default(), masses)
            .unwrap()
            .with_water(Water::new(1025.0).with_seabed(Seabed::flat(10.0, 3e6, 1e5)));
        for (g, out) in groups.into_iter().zip([2.0, 5.0]) {
            net = net.with_line_hydro(g, hydro).with_winch(Winch {
                name: format!("winch {g}"),
                group: g,
                reserve: 60,
                payout: Arc::new(move |t| out * (smooth(t / 2.5) - smooth(t / 2.5 - 1.5))),
                drum_motion: None,
                drum: None,
            });
        }
        net
    };
    let sim = || Simulation::new(two(), fixed_steps(0.05)).unwrap();
    let (cuts, worst, widest) = compare_all_cuts(sim(), sim(), 140);
    eprintln!("{cuts} cuts, at most {widest} elements in one step; energies off by {worst:.2e}");
    assert!(widest >= 2 && cuts >= 40, "{cuts} cuts, widest {widest}");
}
