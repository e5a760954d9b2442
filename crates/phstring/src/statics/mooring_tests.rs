//! The mooring stiffness of a rigid body against central differences of the statics of the
//! body held at offsets, and against the elastic catenary's closed form summed over the
//! lines; the held statics and the offset curve.

use nalgebra::{DMatrix, UnitQuaternion, Vector3};

use super::*;
use crate::body::{Attachment, BodyHydro, RigidBody};
use crate::catenary::{Catenary, Line};
use crate::network::{NetworkBuilder, StringSpec};
use crate::system::MassMatrix;
use crate::water::{LineHydro, Seabed, Water};
use crate::{Boundary, Fixed, Material};

const G: f64 = 9.80665;
/// Water depth [m], chain length [m], mass [kg/m], diameter [m], EA [N] of the OC3-Hywind
/// spar's moorings (Jonkman 2010), with its anchor radius [m], fairlead radius [m] and
/// fairlead depth [m].
const DEPTH: f64 = 320.0;
const LENGTH: f64 = 902.2;
const RHO_A: f64 = 77.7066;
const DIAMETER: f64 = 0.09;
const EA: f64 = 384.243e6;
const ANCHOR_RADIUS: f64 = 853.87;
const FAIRLEAD_RADIUS: f64 = 5.2;
const FAIRLEAD_DEPTH: f64 = 70.0;
/// The centre of mass below the surface [m] (20 m above the fairleads, so that the uplift
/// at it and the lines pulling down at them hold the spar upright) and the spar's
/// net uplift (buoyancy less weight, acting at the centre) [N].
const CENTRE_DEPTH: f64 = 50.0;
const UPLIFT: f64 = 1.6e6;

/// The wet weight of the chain [N/m].
fn wet_weight() -> f64 {
    RHO_A * G - 1025.0 * G * std::f64::consts::PI * DIAMETER * DIAMETER / 4.0
}

/// A spar (7466 t, the OC3 inertia) on three chains of `n_el` elements each at 0°, 120° and
/// 240°, in 320 m of water on a stiff seabed; the spar's water terms are its net uplift.
fn spar(n_el: usize) -> (PhSystem<3, Material>, State<3>) {
    spar_with(n_el, None)
}

/// [`spar`] with the body's water terms `hydro`.
fn spar_with(n_el: usize, water_terms: Option<BodyHydro>) -> (PhSystem<3, Material>, State<3>) {
    let mut nb = NetworkBuilder::<3, Material>::new();
    let mut atts = Vec::new();
    let mut held = Boundary::default();
    let centre = Vector3::new(0.0, 0.0, -CENTRE_DEPTH);
    for k in 0..3 {
        let psi = 2.0 * std::f64::consts::PI * k as f64 / 3.0;
        let (c, s) = (psi.cos(), psi.sin());
        let anchor = nb.node(Vector::<3>::new(
            ANCHOR_RADIUS * c,
            ANCHOR_RADIUS * s,
            -DEPTH,
        ));
        let point = Vector3::new(
            FAIRLEAD_RADIUS * c,
            FAIRLEAD_RADIUS * s,
            CENTRE_DEPTH - FAIRLEAD_DEPTH,
        );
        let fair = nb.node(centre + point);
        held.fixed.push(Fixed::node(anchor));
        let spec = StringSpec {
            name: format!("line{k}"),
            material: Material::tension_only_linear(EA),
            rho_a: RHO_A,
            mass: MassMatrix::Lumped,
            body_force: Vector::<3>::new(0.0, 0.0, -RHO_A * G),
            prestretch: (centre + point - nb.position(anchor).unwrap()).norm() / LENGTH,
        };
        nb.string(spec, &[anchor, fair], n_el).unwrap();
        atts.push(Attachment { node: fair, point });
    }
    let net = nb.build(held, Vec::new()).unwrap();
    let water = Water::new(1025.0).with_seabed(Seabed::flat(DEPTH, 3e6, 3e5));
    let hydro = LineHydro {
        diameter: DIAMETER,
        cd: 1.2,
        cd_axial: 0.008,
        ca: 1.0,
        ca_axial: 0.0,
    };
    let mut net = net.with_water(water);
    for g in 0..3 {
        net = net.with_line_hydro(g, hydro);
    }
    let mass = 7.466e6;
    let spar = RigidBody {
        name: "spar".into(),
        mass,
        inertia: nalgebra::Matrix3::from_diagonal(&Vector3::new(4.229e9, 4.229e9, 1.642e8)),
        weight: Vector::<3>::new(0.0, 0.0, UPLIFT),
        attachments: atts,
        initial: BodyState::at_rest(centre, UnitQuaternion::identity()),
        wrench: None,
        hydro: water_terms,
        motion: None,
        feedback: None,
    };
    PhSystem::new(net.with_body(spar)).unwrap()
}

/// The spar's equilibrium, found from its straight start.
fn equilibrium(sys: &PhSystem<3, Material>, start: &State<3>) -> Equilibrium<3> {
    let eq = solve_system(sys, &start.r, &StaticsParams::default(), None).unwrap();
    assert!(eq.stable);
    eq
}

/// The strings' restoring force and moment (minus their wrench on the body) as a 6-vector.
fn restoring(p: &OffsetPoint) -> [f64; 6] {
    let (f, m) = (-p.force, -p.moment);
    [f.x, f.y, f.z, m.x, m.y, m.z]
}

/// Every column of the spar's 6 × 6 mooring stiffness equals the central difference of the
/// restoring force and moment of the statics with the spar held at ±1 cm and ±1 mrad, to
/// 1e-5 of the column's size (moments divided by 10 m; measured: 3.2e-7 at most over the six
/// columns). The matrix has the three-line symmetry: `K_xx = K_yy`, surge–pitch and
/// sway–roll couplings of opposite signs and equal size, and no surge–sway coupling; and it
/// is symmetric to 1e-6 (measured: 4.9e-13).
#[test]
fn stiffness_matches_central_differences_of_held_statics() {
    let (sys, start) = spar(30);
    let eq = equilibrium(&sys, &start);
    let params = StaticsParams::default();
    let k = body_stiffness(&sys, &eq, 0, &params).unwrap();
    assert_eq!(k.dofs, ["x", "y", "z", "rx", "ry", "rz"]);
    let mut worst = 0.0f64;
    for j in 0..6 {
        let eps = if j < 3 { 1e-2 } else { 1e-3 };
        let pts = offset_curve(&sys, &eq, (0, j), &[-eps, eps], &params, None).unwrap();
        let (gm, gp) = (restoring(&pts[0]), restoring(&pts[1]));
        let row_scale = |i: usize| if i < 3 { 1.0 } else { 0.1 };
        let fd: Vec<f64> = (0..6)
            .map(|i| (gp[i] - gm[i]) / (2.0 * eps) * row_scale(i))
            .collect();
        let col: Vec<f64> = (0..6).map(|i| k.matrix[(i, j)] * row_scale(i)).collect();
        let size = col.iter().map(|x| x * x).sum::<f64>().sqrt();
        let err = col
            .iter()
            .zip(&fd)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        worst = worst.max(err / size);
        assert!(err <= 1e-5 * size, "column {j}: {col:?} vs {fd:?}");
    }
    eprintln!("worst column difference {worst:.3e}");
    let m = &k.matrix;
    let kxx = m[(0, 0)];
    assert!(kxx > 0.0 && m[(2, 2)] > 0.0 && m[(5, 5)] > 0.0, "{m}");
    assert!((m[(1, 1)] - kxx).abs() <= 1e-9 * kxx, "{m}");
    assert!(m[(0, 1)].abs() <= 1e-9 * kxx, "{m}");
    assert!(
        (m[(0, 4)] + m[(1, 3)]).abs() <= 1e-9 * m[(0, 4)].abs(),
        "{m}"
    );
    // At an equilibrium under the spar's constant uplift at its centre, `K` is the
    // potential's Hessian: symmetric (moments divided by 10 m as above).
    let scaled = DMatrix::from_fn(6, 6, |i, j| {
        m[(i, j)] * if i < 3 { 1.0 } else { 0.1 } * if j < 3 { 1.0 } else { 0.1 }
    });
    let asym = (&scaled - scaled.transpose()).abs().max() / scaled.abs().max();
    eprintln!("asymmetry {asym:.3e}");
    assert!(asym <= 1e-6, "{m}");
}

/// The translational 3 × 3 block of the spar's mooring stiffness against the elastic
/// catenary on a rigid seabed ([`crate::catenary::on_seabed`]) at the equilibrium's anchor–
/// fairlead spans, its end forces differentiated by central differences of 1 cm and summed
/// over the lines: `K = Σ [e (H_X eᵀ + H_Z ẑᵀ) + (H/X)(P − e eᵀ) + ẑ (V_X eᵀ + V_Z ẑᵀ)]` with
/// `e` the line's horizontal direction and `P` the horizontal projection. The meshes differ
/// from the continuum by their lumped weights and the seabed's penalty, and most where the
/// touchdown point falls between nodes: with 30, 60, 120 and 240 elements per line (30 to
/// 3.8 m) the largest difference relative to `K_zz` is measured at 1.6e-1, 3.8e-2, 4.0e-2
/// and 3.3e-3 (not monotone: the grounded nodes lift off one by one); asserted below 5e-2 at
/// 60 elements and 5e-3 at 240.
#[test]
fn translation_block_matches_the_catenary_closed_form() {
    let w = wet_weight();
    let mut errs = Vec::new();
    for n_el in [60, 240] {
        let (sys, start) = spar(n_el);
        let eq = equilibrium(&sys, &start);
        let k = body_stiffness(&sys, &eq, 0, &StaticsParams::default()).unwrap();
        let mut cf = nalgebra::Matrix3::<f64>::zeros();
        let z = Vector3::z();
        for (node, _) in &sys.bodies[0].attachments {
            // The line's anchor: the support in the fairlead's direction.
            let f = eq.state.r[*node];
            let toward = |i: &usize| eq.state.r[*i].xy().dot(&f.xy());
            let anchor = sys
                .support_nodes()
                .max_by(|i, j| toward(i).total_cmp(&toward(j)));
            let a = eq.state.r[anchor.unwrap()];
            let d = f - a;
            let horizontal = Vector3::new(d.x, d.y, 0.0);
            let x = horizontal.norm();
            let e = horizontal / x;
            let hv = f.z + DEPTH;
            let ends = |x: f64, hv: f64| {
                let (h, v, _) = crate::catenary::on_seabed(LENGTH, w, EA, x, hv);
                (h, v)
            };
            let dd = 1e-2;
            let (h, _) = ends(x, hv);
            let (hxp, vxp) = ends(x + dd, hv);
            let (hxm, vxm) = ends(x - dd, hv);
            let (hzp, vzp) = ends(x, hv + dd);
            let (hzm, vzm) = ends(x, hv - dd);
            let (hx, vx) = ((hxp - hxm) / (2.0 * dd), (vxp - vxm) / (2.0 * dd));
            let (hz, vz) = ((hzp - hzm) / (2.0 * dd), (vzp - vzm) / (2.0 * dd));
            let p = nalgebra::Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 0.0));
            cf += e * (e.transpose() * hx + z.transpose() * hz)
                + (p - e * e.transpose()) * (h / x)
                + z * (e.transpose() * vx + z.transpose() * vz);
        }
        let block = k.matrix.fixed_view::<3, 3>(0, 0).into_owned();
        let err = (block - cf).abs().max() / cf[(2, 2)];
        eprintln!("{n_el} elements: K {block} closed form {cf} difference {err:.3e}");
        errs.push(err);
    }
    assert!(errs[0] <= 5e-2 && errs[1] <= 5e-3, "{errs:?}");
}

/// The spar's offset–tension curve in surge (0 to 40 m, 120 elements per line) against the
/// elastic catenary from each anchor to its fairlead at the held pose (on a rigid seabed,
/// or between the two points once the leeward lines lift their anchors' ends): the
/// strings' force on the spar and each fairlead's tension `√(H² + V_F²)` agree to 2e-4 of
/// the largest fairlead tension at the offset (measured: 5.4e-5 at most); the line towards
/// whose anchor the spar moves slackens, the other two tighten, the restoring force grows
/// monotonically; the curve starts at the equilibrium (the restoring force
/// there balances the uplift to the statics' tolerance).
#[test]
fn surge_offset_curve_matches_the_catenary_closed_form() {
    let (sys, start) = spar(120);
    let eq = equilibrium(&sys, &start);
    let offsets = [0.0, 10.0, 20.0, 30.0, 40.0];
    let curve = offset_curve(&sys, &eq, (0, 0), &offsets, &StaticsParams::default(), None).unwrap();
    let w = wet_weight();
    let pose0 = &eq.state.bodies[0];
    let mut worst = 0.0f64;
    for p in &curve {
        let centre = pose0.position + Vector3::new(p.offset, 0.0, 0.0);
        let mut force = Vector3::zeros();
        let mut tensions = Vec::new();
        for (node, s) in &sys.bodies[0].attachments {
            let f = centre + pose0.orientation * s;
            let start_r = eq.state.r[*node];
            let toward = |i: &usize| eq.state.r[*i].xy().dot(&start_r.xy());
            let a = eq.state.r[sys
                .support_nodes()
                .max_by(|i, j| toward(i).total_cmp(&toward(j)))
                .unwrap()];
            let d = f - a;
            let horizontal = Vector3::new(d.x, d.y, 0.0);
            let line = Line {
                length: LENGTH,
                weight: w,
                ea: EA,
            };
            let (x, hv) = (horizontal.norm(), f.z + DEPTH);
            // Grounded, or (past the point where the anchor starts to lift) between points.
            let c = Catenary::on_seabed(line, x, hv)
                .or_else(|| Catenary::between(line, x, hv))
                .unwrap();
            let (h, v) = (c.h, c.v_a + w * (LENGTH - c.grounded));
            force -= horizontal.normalize() * h + Vector3::z() * v;
            tensions.push((h * h + v * v).sqrt());
        }
        let scale = tensions.iter().cloned().fold(0.0, f64::max);
        let err = (p.force - force).norm().max(
            p.tensions
                .iter()
                .zip(&tensions)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max),
        );
        worst = worst.max(err / scale);
        assert!(err <= 2e-4 * scale, "offset {}: {err} of {scale}", p.offset);
    }
    eprintln!("worst {worst:.3e}");
    // Line 0's anchor is at +x.
    let t = |i: usize, k: usize| curve[i].tensions[k];
    assert!(t(4, 0) < t(0, 0) && t(4, 1) > t(0, 1) && t(4, 2) > t(0, 2));
    assert!(
        (curve[0].force.z + UPLIFT).abs() <= 1e-6 * UPLIFT,
        "{:?}",
        curve[0].force
    );
    assert!(curve.windows(2).all(|p| p[1].force.x < p[0].force.x));
}

/// In 2D: a 50 t block hanging from two supports 6 m apart on steel ropes (EA = 1e8 N, 4
/// elements each, splayed; they stretch by about 2.5 cm, so the offsets stay well inside
/// that): its 3 × 3 stiffness (`x, y, rz`) equals the central differences of the held
/// statics at ±0.1 mm and ±0.01 mrad to 1e-5 of each column (measured: 3.3e-10), and is
/// symmetric to 1e-6 of its size, as the stiffness of a body in equilibrium whose own loads
/// do not change with its turn is (measured: 1.7e-15).
#[test]
fn stiffness_in_2d_matches_central_differences() {
    let mut nb = NetworkBuilder::<2, Material>::new();
    let mut atts = Vec::new();
    let mut held = Boundary::default();
    for (top, point) in [(-3.0, -0.8), (3.0, 0.8)] {
        let sup = nb.node(Vector::<2>::new(top, 10.0));
        let p = Vector::<2>::new(point, 0.5);
        let a = nb.node(p);
        held.fixed.push(Fixed::node(sup));
        let spec = StringSpec {
            name: format!("rope{top}"),
            material: Material::tension_only_linear(1e8),
            rho_a: 4.0,
            mass: MassMatrix::Consistent,
            body_force: Vector::<2>::new(0.0, -4.0 * G),
            prestretch: 1.0,
        };
        nb.string(spec, &[sup, a], 4).unwrap();
        atts.push(Attachment {
            node: a,
            point: Vector::<2>::new(point, 0.5),
        });
    }
    let net = nb.build(held, Vec::new()).unwrap();
    let mass = 50e3;
    let block = RigidBody {
        name: "block".into(),
        mass,
        inertia: nalgebra::Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0)) * (mass * 0.4),
        weight: Vector::<2>::new(0.0, -mass * G),
        attachments: atts,
        initial: BodyState::at_rest(Vector3::zeros(), UnitQuaternion::identity()),
        wrench: None,
        hydro: None,
        motion: None,
        feedback: None,
    };
    let (sys, start) = PhSystem::new(net.with_body(block)).unwrap();
    let params = StaticsParams::default();
    let eq = solve_system(&sys, &start.r, &params, None).unwrap();
    let k = body_stiffness(&sys, &eq, 0, &params).unwrap();
    assert_eq!(k.dofs, ["x", "y", "rz"]);
    let mut worst = 0.0f64;
    for j in 0..3 {
        let eps = if j < 2 { 1e-4 } else { 1e-5 };
        let pts = offset_curve(&sys, &eq, (0, j), &[-eps, eps], &params, None).unwrap();
        let g = |p: &OffsetPoint| [-p.force.x, -p.force.y, -p.moment.z];
        let (gm, gp) = (g(&pts[0]), g(&pts[1]));
        let fd: Vec<f64> = (0..3).map(|i| (gp[i] - gm[i]) / (2.0 * eps)).collect();
        let col: Vec<f64> = (0..3).map(|i| k.matrix[(i, j)]).collect();
        let size = col.iter().map(|x| x * x).sum::<f64>().sqrt();
        let err = col
            .iter()
            .zip(&fd)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        worst = worst.max(err / size);
        assert!(err <= 1e-5 * size, "column {j}: {col:?} vs {fd:?}");
    }
    let asym = (&k.matrix - k.matrix.transpose()).abs().max() / k.matrix.abs().max();
    eprintln!("2D: {} worst {worst:.3e}, asymmetry {asym:.3e}", k.matrix);
    assert!(asym <= 1e-6, "{}", k.matrix);
}

/// The spar with a 6.5 m waterplane (33.18 m²) at the surface, with and without its second
/// moments `I = π r⁴/4` about x and y: the roll and pitch stiffness grow by exactly `ρ_w g I`
/// (the waterplane's hydrostatic restoring), heave and the rest do not change (the points
/// carry the area's share at the same height, so the equilibrium is the same).
#[test]
fn waterplane_moments_add_their_hydrostatic_roll_and_pitch_stiffness() {
    let radius: f64 = 3.25;
    let area = std::f64::consts::PI * radius * radius;
    let moment = std::f64::consts::PI * radius.powi(4) / 4.0;
    let stiffness = |moments: [f64; 2]| {
        let hydro = BodyHydro {
            waterplane_area: area,
            waterline: Vector3::new(0.0, 0.0, CENTRE_DEPTH),
            waterplane_moments: moments,
            ..Default::default()
        };
        let (sys, start) = spar_with(30, Some(hydro));
        let eq = equilibrium(&sys, &start);
        body_stiffness(&sys, &eq, 0, &StaticsParams::default())
            .unwrap()
            .matrix
    };
    let plain = stiffness([0.0, 0.0]);
    let with = stiffness([moment, 1.5 * moment]);
    let rho_g = 1025.0 * crate::water::STANDARD_GRAVITY;
    let mut expected = DMatrix::<f64>::zeros(6, 6);
    expected[(3, 3)] = rho_g * moment;
    expected[(4, 4)] = rho_g * 1.5 * moment;
    let scale = plain.abs().max();
    let err = (&with - &plain - &expected).abs().max();
    // Two Schur complements of the same tangent but for the waterplane's rows: rounding of
    // the condensed 1e9-scale entries.
    assert!(err <= 1e-9 * scale, "{err} of {scale}: {}", &with - &plain);
    assert!(expected[(3, 3)] > 1e3 * 1e-9 * scale);
}
