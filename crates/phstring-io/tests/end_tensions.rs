//! `end_tensions.csv` of a run: the mooring line of `examples/mooring_line.toml` (180 m of
//! wire rope, 25 kg/m in air, d = 76 mm, from an anchor on a seabed 60 m down to a fairlead
//! 5 m below the surface and 150 m away) starts from its static equilibrium, so its
//! fairlead and anchor tensions are those of the catenary with a grounded part; with its
//! fairlead held (no heave) they stay.

use std::path::Path;

use phstring_io::drive::run::{RunOptions, run};
use phstring_io::scenario;

/// Horizontal tension `H` [N] of an inextensible catenary of length `l` [m] and wet weight
/// `w` [N/m] from a frictionless flat seabed (anchor on it) to a fairlead `h` [m] above it
/// and `x` [m] away: the suspended length is `√(h² + 2 h H / w)` and the span
/// `l − l_s + (H/w) asinh(w l_s / H) = x` (bisection on `H`).
fn catenary_horizontal_tension(l: f64, w: f64, h: f64, x: f64) -> f64 {
    let span = |t: f64| {
        let ls = (h * h + 2.0 * h * t / w).sqrt();
        l - ls + t / w * (w * ls / t).asinh()
    };
    let (mut lo, mut hi) = (1.0, 1e7);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if span(mid) < x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn a_mooring_at_rest_has_the_catenary_end_tensions() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/mooring_line.toml");
    // The fairlead held where it starts (no heave): the line stays at rest.
    let text = std::fs::read_to_string(&path).unwrap();
    let heave = text
        .lines()
        .find(|l| l.starts_with("position = [\"150\""))
        .unwrap();
    let text = text.replace(heave, "fixed = true");
    let sets: Vec<String> = [
        "time.end=0.2",
        "output.plots=false",
        "output.vtk=false",
        "output.positions=false",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let file = scenario::parse(&text, &path, &sets).unwrap();
    let out = std::env::temp_dir().join(format!("phstring-end-tensions-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    run(&file, &out, &mut (), RunOptions::default()).unwrap();
    let text = std::fs::read_to_string(out.join("end_tensions.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,FairTen1,AnchTen1"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    // One row at t = 0 and one per step (h = 0.01 s).
    assert_eq!(rows.len(), 21);
    assert_eq!(rows[0][0], 0.0);
    // Wet weight: (25 kg/m − 1025 kg/m³ · π (0.076 m)²/4) · 9.81 m/s².
    let w = (25.0 - 1025.0 * std::f64::consts::PI * 0.076 * 0.076 / 4.0) * 9.81;
    let big_h = catenary_horizontal_tension(180.0, w, 55.0, 150.0);
    let fair = big_h + w * 55.0;
    let (fair_run, anchor_run) = (rows[0][1], rows[0][2]);
    println!("H = {big_h} N, fairlead {fair} N; run: fairlead {fair_run} N, anchor {anchor_run} N");
    // The closed form is inextensible and continuous; the run's line stretches by
    // T/EA ≈ 3e-5 and lumps its weight on 1.3 m elements (measured: 7.4e-6 apart).
    assert!((fair_run / fair - 1.0).abs() < 1e-4, "{fair_run} vs {fair}");
    // The anchor lies on the seabed unpressed (no contact force), so the anchor end also
    // carries half the weight of its element (114.58 m / 90 long) across H: between H and
    // √(H² + (w l/2)²) = H + 1.6 N (measured: H + 1.28 N).
    let half = 0.5 * w * 114.583333 / 90.0;
    let top = (big_h * big_h + half * half).sqrt();
    assert!(
        anchor_run > big_h * (1.0 - 1e-4) && anchor_run < top * (1.0 + 1e-4),
        "{anchor_run} vs {big_h}..{top}"
    );
    // At rest it stays (measured: to 4e-14).
    for r in &rows {
        assert!((r[1] / fair_run - 1.0).abs() < 1e-9, "{r:?}");
        assert!((r[2] / anchor_run - 1.0).abs() < 1e-9, "{r:?}");
    }
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"completed\""), "{summary}");
    let _ = std::fs::remove_dir_all(&out);
}
