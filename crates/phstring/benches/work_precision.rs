//! Work–precision: wall time against the global time-discretization error at
//! T = 1 s, for `dg` at fixed h, `dg` with error control, `dg4` at fixed h and `dg4` with error
//! control, and an explicit RK4 on the same semi-discretization (lumped mass; phstring runs
//! with lumped mass too, so that all solve one ODE). The error is the tip's (pendulum) or the
//! middle node's (taut string) distance at T from a converged run of the same mesh (`dg4`
//! with a small fixed step; its own change when the step is halved is printed).
//!
//! `cargo bench -p phstring --bench work_precision` (a few minutes; `-- quick` skips
//! N = 3000). Plots: `target/work_precision/<case>.svg`. The N = 3000 section compares error
//! control with today's default (consistent mass, `h = 0.01 s`, step halving) at the same
//! accuracy and shows where the controller cuts.

use std::time::Instant;

use phstring::benchmarks::paper_pendulum;
use phstring::{
    Boundary, Fixed, MassMatrix, Material, Mesh, Network, Problem, Scheme, Simulation, State,
    StepControl, StepParams, Vector,
};
use plotters::prelude::*;

const T_END: f64 = 1.0;

#[derive(Clone, Copy)]
enum Case {
    Pendulum(usize),
    Taut,
    /// A 20 m steel wire rope (EA = 3e7 N, 2.4 kg/m, tension only, 40 elements) with a 5 t
    /// payload, released at rest 10° out of the vertical: a stiff real-unit case.
    SteelPendulum,
}

impl Case {
    fn name(self) -> String {
        match self {
            Case::Pendulum(n) => format!("pendulum_n{n}"),
            Case::Taut => "taut_string".into(),
            Case::SteelPendulum => "steel_pendulum".into(),
        }
    }
    /// The problem with `mass`.
    fn network(self, mass: MassMatrix) -> Network<2, Material> {
        let mut net: Network<2, Material> = match self {
            Case::Pendulum(n) => paper_pendulum(n).into(),
            Case::Taut => phstring::benchmarks::taut_string(TAUT_N).into(),
            Case::SteelPendulum => steel().into(),
        };
        net.groups[0].mass = mass;
        net
    }
    /// The node whose position is compared.
    fn node(self) -> usize {
        match self {
            Case::Pendulum(n) => n,
            Case::Taut => TAUT_N / 2,
            Case::SteelPendulum => STEEL_N,
        }
    }
}

const TAUT_N: usize = 40;
const STEEL_N: usize = 40;

fn steel() -> Problem<2, Material> {
    let mesh = Mesh::uniform_chain(STEEL_N, 20.0).unwrap();
    let a = 10f64.to_radians();
    let end = Vector::<2>::new(20.0 * a.sin(), -20.0 * a.cos());
    let initial = State::straight(&mesh, Vector::zeros(), end);
    Problem {
        point_masses: vec![phstring::PointMass {
            node: STEEL_N,
            mass: 5000.0,
            weight: Vector::<2>::new(0.0, -9.81 * 5000.0),
        }],
        initial,
        mesh,
        material: Material::tension_only_linear(3.0e7),
        rho_a: 2.4,
        body_force: Vector::<2>::new(0.0, -9.81 * 2.4),
        mass: MassMatrix::Consistent,
        boundary: Boundary {
            fixed: vec![Fixed::node(0)],
            ..Default::default()
        },
    }
}

/// The compared node's position at T, the steps, and the best wall time of repeated runs
/// (repeated until 0.2 s have passed, at most 5 times).
fn phstring_run(
    case: Case,
    mass: MassMatrix,
    scheme: Scheme,
    h: f64,
    tol: f64,
) -> Option<(Vector<2>, usize, f64)> {
    let mut best = f64::INFINITY;
    let mut out = None;
    let mut spent = 0.0;
    for _ in 0..5 {
        let params = StepParams {
            h,
            scheme,
            control: StepControl::with_tolerance(tol, tol),
            ..Default::default()
        };
        let mut sim = Simulation::new(case.network(mass), params).ok()?;
        let t0 = Instant::now();
        let s = sim.run_until(T_END, &mut ()).ok()?;
        let wall = t0.elapsed().as_secs_f64();
        best = best.min(wall);
        spent += wall;
        out = Some((sim.state().r[case.node()], s.steps));
        if spent > 0.2 {
            break;
        }
    }
    out.map(|(r, n)| (r, n, best))
}

/// Explicit RK4 on `ṙ = v`, `M_L v̇ = F_b + F_N(t) − K(r) S(|r'|²)` (lumped mass, fixed
/// components held), with step `h`: the compared node at T and the best wall time; `None`
/// if the run blows up.
fn rk4_run(case: Case, h: f64) -> Option<(Vector<2>, usize, f64)> {
    let net = case.network(MassMatrix::Lumped);
    let (sys, state) = phstring::PhSystem::new(net).ok()?;
    let n = state.r.len();
    let ones = vec![Vector::<2>::from_element(1.0); n];
    let mut m = vec![Vector::<2>::zeros(); n];
    sys.mass_mul(&ones, &mut m);
    let free = sys.free_components().to_vec();
    let steps = (T_END / h).round() as usize;
    let n_el = sys.mesh().n_elements();
    let accel =
        |r: &[Vector<2>], t: f64, c: &mut Vec<f64>, s: &mut Vec<f64>, a: &mut [Vector<2>]| {
            for (e, (&[i, j], &l)) in sys
                .mesh()
                .elements()
                .iter()
                .zip(sys.mesh().lengths())
                .enumerate()
            {
                c[e] = ((r[j] - r[i]) / l).norm_squared();
            }
            sys.stresses(c, s);
            sys.k_mul(r, s, a);
            for (i, ai) in a.iter_mut().enumerate() {
                *ai = sys.body_force_vector()[i] - *ai;
            }
            for load in &sys.boundary().loads {
                a[load.node] += (load.force)(t);
            }
            for i in 0..n {
                for k in 0..2 {
                    a[i][k] = if free[i][k] { a[i][k] / m[i][k] } else { 0.0 };
                }
            }
        };
    let mut best = f64::INFINITY;
    let mut out = None;
    let mut spent = 0.0;
    for _ in 0..5 {
        let (mut r, mut v) = (state.r.clone(), state.v.clone());
        let (mut c, mut s) = (vec![0.0; n_el], vec![0.0; n_el]);
        let z = vec![Vector::<2>::zeros(); n];
        let (mut k1r, mut k1v, mut k2r, mut k2v) = (z.clone(), z.clone(), z.clone(), z.clone());
        let (mut k3r, mut k3v, mut k4r, mut k4v) = (z.clone(), z.clone(), z.clone(), z.clone());
        let mut tmp = z.clone();
        let t0 = Instant::now();
        for step in 0..steps {
            let t = step as f64 * h;
            k1r.copy_from_slice(&v);
            accel(&r, t, &mut c, &mut s, &mut k1v);
            for i in 0..n {
                tmp[i] = r[i] + k1r[i] * (0.5 * h);
                k2r[i] = v[i] + k1v[i] * (0.5 * h);
            }
            accel(&tmp, t + 0.5 * h, &mut c, &mut s, &mut k2v);
            for i in 0..n {
                tmp[i] = r[i] + k2r[i] * (0.5 * h);
                k3r[i] = v[i] + k2v[i] * (0.5 * h);
            }
            accel(&tmp, t + 0.5 * h, &mut c, &mut s, &mut k3v);
            for i in 0..n {
                tmp[i] = r[i] + k3r[i] * h;
                k4r[i] = v[i] + k3v[i] * h;
            }
            accel(&tmp, t + h, &mut c, &mut s, &mut k4v);
            for i in 0..n {
                r[i] += (k1r[i] + k2r[i] * 2.0 + k3r[i] * 2.0 + k4r[i]) * (h / 6.0);
                v[i] += (k1v[i] + k2v[i] * 2.0 + k3v[i] * 2.0 + k4v[i]) * (h / 6.0);
            }
            // Compression below the hyperelastic law's domain (C ≤ 0) or a blow-up.
            if c.iter().any(|&x| !(x > 0.0 && x < 1e6)) {
                return None;
            }
        }
        let wall = t0.elapsed().as_secs_f64();
        if !r.iter().all(|x| x.iter().all(|y| y.is_finite())) {
            return None;
        }
        best = best.min(wall);
        spent += wall;
        out = Some(r[case.node()]);
        if spent > 0.2 {
            break;
        }
    }
    out.map(|r| (r, steps, best))
}

/// One point of a curve: wall [s], error [m].
struct Point {
    wall: f64,
    err: f64,
}

/// The wall time to reach error `target` on a curve: interpolated log–log between the two
/// points that bracket it (errors falling along the curve), or, where every point is below
/// it (an explicit method at its stability limit), the cheapest point's time; `None` if no
/// point reaches it.
fn time_at(curve: &[Point], target: f64) -> Option<f64> {
    let bracketed = curve.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        let brackets = (a.err >= target && b.err <= target) || (a.err <= target && b.err >= target);
        if !brackets || a.err <= 0.0 || b.err <= 0.0 || a.err == b.err {
            return None;
        }
        let f = (target.ln() - a.err.ln()) / (b.err.ln() - a.err.ln());
        Some((a.wall.ln() + f * (b.wall.ln() - a.wall.ln())).exp())
    });
    bracketed.or_else(|| {
        (!curve.is_empty() && curve.iter().all(|p| p.err <= target))
            .then(|| curve.iter().map(|p| p.wall).fold(f64::INFINITY, f64::min))
    })
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    if std::env::args().any(|a| a == "fine") {
        fine_mesh();
        return;
    }
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/work_precision");
    let _ = std::fs::create_dir_all(&dir);
    let mut targets = Vec::new();
    for case in [
        Case::Pendulum(30),
        Case::Pendulum(300),
        Case::Taut,
        Case::SteelPendulum,
    ] {
        let mass = MassMatrix::Lumped;
        // Reference: dg4 at a small fixed step, and its change when the step is halved.
        let h_ref = match case {
            Case::Pendulum(300) => 5e-5,
            _ => 1e-4,
        };
        let (reference, _, _) =
            phstring_run(case, mass, Scheme::DiscreteGradient4, h_ref, 0.0).expect("reference");
        let (half, _, _) =
            phstring_run(case, mass, Scheme::DiscreteGradient4, h_ref / 2.0, 0.0).expect("ref/2");
        println!(
            "# {} (lumped mass), T = 1 s; reference dg4 h = {h_ref:e} s, changes by {:.1e} m at h/2",
            case.name(),
            (reference - half).norm()
        );
        let mut curves: Vec<(String, Vec<Point>)> = Vec::new();
        let mut add =
            |name: &str, f: &dyn Fn(f64) -> Option<(Vector<2>, usize, f64)>, params: &[f64]| {
                let mut pts = Vec::new();
                for &p in params {
                    if let Some((r, steps, wall)) = f(p) {
                        let err = (r - reference).norm();
                        println!("{name:>16} {p:>10.3e} {steps:>8} {wall:>10.4e} {err:>10.3e}");
                        pts.push(Point { wall, err });
                    } else {
                        println!("{name:>16} {p:>10.3e}   failed or unstable");
                    }
                }
                curves.push((name.to_string(), pts));
            };
        println!(
            "{:>16} {:>10} {:>8} {:>10} {:>10}",
            "method", "h or tol", "steps", "wall [s]", "error [m]"
        );
        let hs: Vec<f64> = (0..9).map(|k| 0.01 / 2f64.powi(k)).collect();
        let tols: Vec<f64> = (3..=9).map(|k| 10f64.powi(-k)).collect();
        add(
            "dg fixed",
            &|h| phstring_run(case, mass, Scheme::DiscreteGradient, h, 0.0),
            &hs,
        );
        add(
            "dg controlled",
            &|t| phstring_run(case, mass, Scheme::DiscreteGradient, 0.01, t),
            &tols,
        );
        let hs4: Vec<f64> = (0..7).map(|k| 0.02 / 2f64.powi(k)).collect();
        add(
            "dg4 fixed",
            &|h| phstring_run(case, mass, Scheme::DiscreteGradient4, h, 0.0),
            &hs4,
        );
        add(
            "dg4 controlled",
            &|t| phstring_run(case, mass, Scheme::DiscreteGradient4, 0.01, t),
            &tols,
        );
        let hr: Vec<f64> = (0..12).map(|k| 0.01 / 2f64.powi(k)).collect();
        add("rk4 (explicit)", &|h| rk4_run(case, h), &hr);
        {
            let target = 1e-5;
            let best = curves
                .iter()
                .filter(|(n, _)| !n.starts_with("rk4"))
                .filter_map(|(n, c)| time_at(c, target).map(|t| (n.clone(), t)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let rk4 = curves
                .iter()
                .find(|(n, _)| n.starts_with("rk4"))
                .and_then(|(_, c)| time_at(c, target));
            println!(
                "at error {target:e} m: best phstring {:?}, rk4 {:?} s, ratio rk4/phstring {:?}",
                best,
                rk4,
                best.as_ref().zip(rk4).map(|(b, r)| r / b.1)
            );
            targets.push((case.name(), target, best, rk4));
        }
        for ext in ["svg", "png"] {
            let path = dir.join(format!("{}.{ext}", case.name()));
            plot(&path, &case.name(), &curves, ext == "png");
        }
        println!();
    }
    println!("# Targets (time at tip error 1e-5 m)");
    for (case, target, best, rk4) in &targets {
        println!("{case}: {target:e} m: phstring {best:?}, rk4 {rk4:?}");
    }
    if !quick {
        fine_mesh();
    }
}

/// N = 3000, consistent mass: today's default (dg, h = 0.01 s, halving on failure) against
/// error control at the same accuracy, and where the controller cuts.
fn fine_mesh() {
    let case = Case::Pendulum(3000);
    let mass = MassMatrix::Consistent;
    println!("# Pendulum N = 3000 (consistent mass), T = 1 s");
    let (reference, _, _) =
        phstring_run(case, mass, Scheme::DiscreteGradient4, 2.5e-4, 0.0).expect("reference");
    let (half, _, _) =
        phstring_run(case, mass, Scheme::DiscreteGradient4, 1.25e-4, 0.0).expect("reference/2");
    println!(
        "reference dg4 h = 2.5e-4 s; changes by {:.1e} m at h/2",
        (reference - half).norm()
    );
    let (r, steps, wall) = phstring_run(case, mass, Scheme::DiscreteGradient, 0.01, 0.0).unwrap();
    let default_err = (r - reference).norm();
    println!("default dg h = 0.01: {steps} steps, {wall:.3} s, tip error {default_err:.3e} m");
    for tol in [1e-1, 1e-2] {
        match phstring_run(case, mass, Scheme::DiscreteGradient, 0.01, tol) {
            Some((r, steps, wall)) => println!(
                "dg controlled tol {tol:e}: {steps} steps, {wall:.3} s, tip error {:.3e} m",
                (r - reference).norm()
            ),
            None => println!("dg controlled tol {tol:e}: failed"),
        }
    }
    // With a small Kelvin–Voigt viscosity (η = 1e-3 N·s, docs/method.md §18) the free end does
    // not crumple at the element scale, and the controller need not resolve it.
    let damped = || {
        let mut n = case.network(mass);
        n.groups[0].damping = phstring::Damping {
            kelvin_voigt: 1e-3,
            ..phstring::Damping::NONE
        };
        n
    };
    for tol in [1e-1, 1e-2] {
        let params = StepParams {
            h: 0.01,
            control: StepControl::with_tolerance(tol, tol),
            ..Default::default()
        };
        let mut sim = Simulation::new(damped(), params).unwrap();
        let t0 = Instant::now();
        let s = sim.run_until(T_END, &mut ()).unwrap();
        println!(
            "η = 1e-3 N·s, dg controlled tol {tol:e}: {} steps, {:.3} s, tip moved {:.3e} m from the undamped reference",
            s.steps,
            t0.elapsed().as_secs_f64(),
            (sim.state().r[case.node()] - reference).norm()
        );
    }
    // Where the controller cuts: the step sizes over time at tol = 1e-2, undamped.
    let params = StepParams {
        h: 0.01,
        control: StepControl::with_tolerance(1e-2, 1e-2),
        ..Default::default()
    };
    let mut sim = Simulation::new(case.network(mass), params).unwrap();
    let mut windows = vec![(f64::INFINITY, 0.0_f64, 0usize, 0usize); 10];
    while sim.time() < T_END - 1e-12 {
        let r = sim.step_until(T_END).unwrap();
        let w = &mut windows[((r.t - 0.5 * r.h) * 10.0).floor().clamp(0.0, 9.0) as usize];
        w.0 = w.0.min(r.h);
        w.1 = w.1.max(r.h);
        w.2 += 1;
        w.3 += r.rejected;
    }
    println!("tol 1e-2, per 0.1 s: smallest h, largest h, steps, rejected");
    for (k, w) in windows.iter().enumerate() {
        println!(
            "  {:.1}-{:.1} s: {:.2e} {:.2e} {:>5} {:>4}",
            k as f64 / 10.0,
            (k + 1) as f64 / 10.0,
            w.0,
            w.1,
            w.2,
            w.3
        );
    }
}

/// Log–log plot of wall time against error, one series per method, as SVG or PNG.
fn plot(path: &std::path::Path, title: &str, curves: &[(String, Vec<Point>)], png: bool) {
    if png {
        draw(
            BitMapBackend::new(path, (800, 600)).into_drawing_area(),
            title,
            curves,
        );
    } else {
        draw(
            SVGBackend::new(path, (800, 600)).into_drawing_area(),
            title,
            curves,
        );
    }
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    curves: &[(String, Vec<Point>)],
) {
    let pts = || {
        curves
            .iter()
            .flat_map(|(_, c)| c.iter())
            .filter(|p| p.err > 0.0 && p.wall > 0.0)
    };
    let (emin, emax) = pts().fold((f64::INFINITY, 0.0_f64), |a, p| {
        (a.0.min(p.err), a.1.max(p.err))
    });
    let (tmin, tmax) = pts().fold((f64::INFINITY, 0.0_f64), |a, p| {
        (a.0.min(p.wall), a.1.max(p.wall))
    });
    if !(emin < emax && tmin < tmax) {
        return;
    }
    let _ = root.fill(&WHITE);
    let chart = ChartBuilder::on(&root)
        .caption(format!("work-precision: {title}"), ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (emin * 0.5..emax * 2.0).log_scale(),
            (tmin * 0.5..tmax * 2.0).log_scale(),
        );
    let Ok(mut chart) = chart else { return };
    let _ = chart
        .configure_mesh()
        .x_desc("global error at T = 1 s [m]")
        .y_desc("wall time [s]")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw();
    let colors = [RED, BLUE, GREEN, MAGENTA, BLACK];
    for ((name, c), color) in curves.iter().zip(colors) {
        let series: Vec<(f64, f64)> = c
            .iter()
            .filter(|p| p.err > 0.0)
            .map(|p| (p.err, p.wall))
            .collect();
        let style = ShapeStyle::from(&color).stroke_width(2);
        if let Ok(s) = chart.draw_series(LineSeries::new(series.clone(), style)) {
            s.label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
        let _ = chart.draw_series(
            series
                .iter()
                .map(|&(x, y)| Circle::new((x, y), 3, color.filled())),
        );
    }
    let _ = chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw();
    let _ = root.present();
}
