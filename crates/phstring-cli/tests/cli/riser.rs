//! `examples/riser_in_current.toml`: a top-tensioned riser (a tensioned cable) in a uniform
//! current bends downstream as the closed form of a tensioned line under a uniform
//! distributed load says, both in statics (the current's drag is part of the static load) and
//! at the end of a run that settles from the straight start.

use std::path::Path;

use crate::{phstring, run_with, summary, temp_dir};

/// `(x, y)` of the nodes in `equilibrium.csv` (statics) or of the last frame of
/// `positions.csv` (a run), from the bottom up.
fn shape(p: &Path) -> Vec<(f64, f64)> {
    let mut r = csv::Reader::from_path(p).unwrap();
    let rows: Vec<Vec<f64>> = r
        .records()
        .map(|x| x.unwrap().iter().map(|f| f.parse().unwrap()).collect())
        .collect();
    let mut pts: Vec<(f64, f64)> = if p.ends_with("equilibrium.csv") {
        rows.iter().map(|r| (r[1], r[2])).collect()
    } else {
        let last = rows.iter().map(|r| r[0]).fold(f64::MIN, f64::max);
        rows.iter()
            .filter(|r| r[0] == last)
            .map(|r| (r[2], r[3]))
            .collect()
    };
    pts.sort_by(|a, b| a.1.total_cmp(&b.1));
    pts
}

/// The largest distance [m] of `pts` from the closed form, relative to its mid-depth
/// deflection, and that deflection. The closed form: `(T y')' = −q` with the drag
/// `q = ½ ρ_w Cd d U²` per length and the tension `T(z) = T_b + w z` growing with the height
/// `z` above the wellhead by the weight in water `w` (`T_b = T_top − w L`, `L` the line's
/// height), `y(0) = y(L) = 0`:
/// `y(z) = (q/w) [L ln(1 + w z/T_b)/ln(1 + w L/T_b) − z]`, which tends to the taut string's
/// `q z (L − z)/(2T)` as `w → 0`.
fn against_closed_form(pts: &[(f64, f64)]) -> (f64, f64) {
    let (d, rho_a, rho_w, g, cd, u, t_top) = (0.273, 145.0, 1025.0, 9.81, 1.0, 1.0, 3.0e5);
    let w = (rho_a - rho_w * std::f64::consts::PI * d * d / 4.0) * g;
    let q = 0.5 * rho_w * cd * d * u * u;
    let bottom = pts[0].1;
    let l = pts[pts.len() - 1].1 - bottom;
    let tb = t_top - w * l;
    let y = |z: f64| q / w * (l * (w * z / tb).ln_1p() / (w * l / tb).ln_1p() - z);
    let mid = y(0.5 * l);
    let worst = pts
        .iter()
        .map(|&(x, h)| (x - y(h - bottom)).abs() / mid)
        .fold(0.0, f64::max);
    let taut = q * l * l / (8.0 * (t_top - 0.5 * w * l));
    println!(
        "riser: mid-depth deflection {mid} m (taut string with the mean tension {taut} m), worst {worst:e} of it"
    );
    (worst, mid)
}

/// Statics with the current, and a run from the straight start that settles (`time.settle`):
/// every node within 2e-3 of the mid-depth deflection (0.68 m) from the closed form
/// (measured 4.1e-4 in both: the drag on the inclined line is `q cos²θ` normal to it, and the
/// mesh's 2 m elements), and the run's end within 1e-4 of the static shape.
#[test]
fn the_riser_bends_in_the_current_as_the_tensioned_line_under_uniform_load() {
    let tmp = temp_dir("riser");
    let st = tmp.join("statics");
    let o = phstring(&[
        "statics",
        "examples/riser_in_current.toml",
        "--out",
        st.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let statics = shape(&st.join("equilibrium.csv"));
    let (worst, mid) = against_closed_form(&statics);
    assert!((0.6..0.75).contains(&mid), "{mid} m");
    assert!(worst <= 2e-3, "statics: {worst:e} of {mid} m");
    let run = tmp.join("run");
    let quiet = [
        "output.plots=false",
        "output.vtk=false",
        "output.animation=false",
    ];
    let o = run_with("examples/riser_in_current.toml", &run, &quiet, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary(&run)["settled"]["settled"], true);
    let settled = shape(&run.join("positions.csv"));
    let (worst, _) = against_closed_form(&settled);
    assert!(worst <= 2e-3, "run: {worst:e} of {mid} m");
    let apart = settled
        .iter()
        .zip(&statics)
        .map(|(a, b)| (a.0 - b.0).hypot(a.1 - b.1))
        .fold(0.0, f64::max);
    assert!(
        apart <= 1e-4 * mid,
        "the run ends {apart} m from the statics"
    );
}
