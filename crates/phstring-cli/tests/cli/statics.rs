//! `phstring statics` and `phstring linearize`, and a run that starts from the equilibrium
//! (`initial.equilibrium = true`), on the slack-wire and mooring-line examples.

use super::{phstring, temp_dir};

fn summary(p: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p.join("summary.json")).unwrap()).unwrap()
}

fn csv_rows(p: &std::path::Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|x| x.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// The slack wire rope (a mooring line's geometry in air) reaches a stable equilibrium from
/// the catenary first guess, which for a linear elastic rope in air is its discrete
/// equilibrium (at most one Newton iteration, measured 0); the support reactions carry the
/// line's weight (20 kg/m × 160 m × g) to 1e-9, every element is in tension, and the outputs
/// are complete.
#[test]
fn statics_of_the_slack_wire_balances_its_weight() {
    let out = temp_dir("statics-mooring");
    let o = phstring(&[
        "statics",
        "examples/slack_wire.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["stable"], true);
    assert_eq!(s["path"], "catenary_guess", "{}", s["first_guess"]);
    assert_eq!(s["first_guess"], "used");
    assert!(s["newton_iterations"].as_u64().unwrap() <= 1, "{s}");
    let weight = 20.0 * 160.0 * 9.81;
    let total_y = s["total_reaction"][1].as_f64().unwrap();
    assert!(
        (total_y - weight).abs() <= 1e-9 * weight,
        "{total_y} vs {weight}"
    );
    assert!(s["total_reaction"][0].as_f64().unwrap().abs() <= 1e-9 * weight);
    assert!(s["min_tension"].as_f64().unwrap() > 0.0);
    let tension = csv_rows(&out.join("tension.csv"));
    assert_eq!(tension.len(), 160);
    for f in [
        "equilibrium.csv",
        "equilibrium.vtp",
        "equilibrium.png",
        "equilibrium.svg",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
}

/// `initial.equilibrium = true`: the run's first positions are the statics positions, bit for
/// bit, and its summary says how they were found.
#[test]
fn a_run_starts_from_the_statics_equilibrium() {
    let st = temp_dir("statics-for-run");
    let o = phstring(&[
        "statics",
        "examples/slack_wire.toml",
        "--out",
        st.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run = temp_dir("run-from-equilibrium");
    let o = phstring(&[
        "run",
        "examples/slack_wire.toml",
        "--out",
        run.to_str().unwrap(),
        "--set",
        "time.end=0.2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let eq = csv_rows(&st.join("equilibrium.csv"));
    let first: Vec<Vec<f64>> = csv_rows(&run.join("positions.csv"))
        .into_iter()
        .filter(|r| r[0] == 0.0)
        .collect();
    assert_eq!(first.len(), eq.len());
    for (a, b) in first.iter().zip(&eq) {
        assert_eq!(&a[2..4], &b[1..3], "node {}", b[0]);
    }
    let s = summary(&run);
    assert!(
        s["initial_equilibrium"]
            .as_str()
            .unwrap()
            .starts_with("catenary_guess")
    );
    let err = s["max_balance_error"].as_f64().unwrap();
    let h0 = s["hamiltonian_initial"].as_f64().unwrap().abs();
    assert!(err <= 1e-13 * h0, "balance {err} of {h0}");
}

/// A string held in x only, under gravity in y: no equilibrium, and the message says why.
#[test]
fn statics_names_a_free_translation() {
    let dir = temp_dir("statics-free");
    let file = dir.join("free.toml");
    std::fs::write(
        &file,
        r#"dimension = 2
[geometry]
start = [0.0, 0.0]
end = [10.0, 0.0]
[mesh]
elements = 10
[material]
law = "linear_elastic"
ea = 1e6
rho_a = 1.0
[body_force]
gravity = [0.0, -9.81]
[[boundary]]
node = 0
fixed = [true, false]
[time]
h = 0.01
end = 0.1
"#,
    )
    .unwrap();
    let o = phstring(&[
        "statics",
        file.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("free to translate along y"), "{e}");
    assert!(e.contains("-9.81"), "the net load is named: {e}");
}

/// `phstring linearize` writes both forms and the manifest (the Python tests read them).
#[test]
fn linearize_writes_both_forms_and_a_manifest() {
    let out = temp_dir("linearize");
    let o = phstring(&[
        "linearize",
        "examples/paper_pendulum.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["inputs"].as_array().unwrap().len(), 2);
    assert_eq!(
        m["forms"]["reduced"]["states"].as_array().unwrap().len(),
        120
    );
    assert_eq!(m["forms"]["full"]["states"].as_array().unwrap().len(), 150);
    for form in ["full", "reduced"] {
        for name in ["E", "J", "R", "Q", "B"] {
            let mtx = std::fs::read_to_string(out.join(form).join(format!("{name}.mtx"))).unwrap();
            assert!(mtx.starts_with("%%MatrixMarket matrix coordinate real general"));
            let npz = std::fs::read(out.join(form).join(format!("{name}.npz"))).unwrap();
            assert_eq!(&npz[..2], b"PK");
        }
    }
}

/// `--at checkpoint.json`: the model about a state of an interrupted run, whose time and
/// (nonzero, off equilibrium) static residual the manifest states.
#[test]
fn linearize_at_a_checkpoint() {
    let run = temp_dir("linearize-at-run");
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--out",
        run.to_str().unwrap(),
        "--stop-after-steps",
        "10",
    ]);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let cp = run.join("checkpoint.json");
    let out = temp_dir("linearize-at");
    let o = phstring(&[
        "linearize",
        "examples/paper_pendulum.toml",
        "--at",
        cp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert!(
        m["linearized_at"]
            .as_str()
            .unwrap()
            .ends_with("checkpoint.json")
    );
    assert!(
        (m["time"].as_f64().unwrap() - 0.1).abs() < 1e-12,
        "{}",
        m["time"]
    );
    assert!(
        m["static_residual"].as_f64().unwrap() > 1e-3,
        "the swinging pendulum is not at rest"
    );
    // A checkpoint of another scenario is refused with a message.
    let o = phstring(&[
        "linearize",
        "examples/taut_string.toml",
        "--at",
        cp.to_str().unwrap(),
        "--out",
        temp_dir("linearize-at-wrong").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("position values"));
}

/// `phstring modes` on the taut-string example (St. Venant–Kirchhoff, EA = 50 N, ρA =
/// 0.5 kg/m, L = 1 m stretched to 1.2 m, 40 elements): `S = EA/2 (C − 1) = 11 N` with
/// `C = 1.44`; transverse stiffness `S`, longitudinal `S + 4W''C = S + EA·C = 83 N`;
/// `ω_j² = 6k/(ρA l²) · 2 sin²(θ/2)/(2 + cos θ)`, `θ = jπ/40`. The four lowest: transverse
/// j = 1, 2, longitudinal j = 1, transverse j = 3, to 1e-9.
#[test]
fn modes_of_the_taut_string_example_match_the_closed_form() {
    let out = temp_dir("modes-taut");
    let o = phstring(&[
        "modes",
        "examples/taut_string.toml",
        "--count",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let w = |k: f64, j: f64| {
        let (l, th) = (1.0 / 40.0, j * std::f64::consts::PI / 40.0);
        (6.0 * k / (0.5 * l * l) * 2.0 * (th / 2.0).sin().powi(2) / (2.0 + th.cos())).sqrt()
    };
    let want = [
        (w(11.0, 1.0), "transverse"),
        (w(11.0, 2.0), "transverse"),
        (w(83.0, 1.0), "longitudinal"),
        (w(11.0, 3.0), "transverse"),
    ];
    let text = std::fs::read_to_string(out.join("modes.csv")).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 4);
    for (row, (omega, character)) in rows.iter().zip(want) {
        let got: f64 = row[1].parse().unwrap();
        assert!((got - omega).abs() <= 1e-9 * omega, "{got} vs {omega}");
        assert_eq!(row[4], character);
    }
    for f in [
        "modes.pvd",
        "mode_001.vtp",
        "mode_004.vtp",
        "modes.png",
        "summary.json",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
}

/// `modes --count` and `linearize --modes` above the number of modes the model has (one
/// per free position component) give all of them, and say so on stderr and in the output
/// summary instead of silently giving fewer.
#[test]
fn more_modes_than_exist_are_named_not_silently_dropped() {
    let tmp = temp_dir("modes-count");
    // The taut string: 40 elements, both ends fixed, 2D: 39 × 2 = 78 free components.
    let out = tmp.join("modes");
    let o = phstring(&[
        "modes",
        "examples/taut_string.toml",
        "--count",
        "1000000",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let note = "--count 1000000: the model has 78 free position components, so only 78 modes exist; 78 are given";
    assert!(err.contains(&format!("warning: {note}")), "{err}");
    let s = summary(&out);
    assert_eq!(s["requested"], 1_000_000);
    assert_eq!(s["warnings"], serde_json::json!([note]));
    assert_eq!(s["modes"].as_array().unwrap().len(), 78);
    assert_eq!(csv_rows(&out.join("modes.csv")).len(), 78);
    // As many as exist: no warning.
    let out = tmp.join("modes78");
    let o = phstring(&[
        "modes",
        "examples/taut_string.toml",
        "--count",
        "78",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    assert_eq!(summary(&out)["warnings"], serde_json::json!([]));

    // The paper's pendulum: 30 elements, node 0 fixed, 2D: 60 free components.
    let out = tmp.join("linear");
    let o = phstring(&[
        "linearize",
        "examples/paper_pendulum.toml",
        "--modes",
        "100000",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let note = "--modes 100000: the model has 60 free position components, so only 60 modes exist; 60 are given";
    assert!(err.contains(&format!("warning: {note}")), "{err}");
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["requested_modes"], 100_000);
    assert_eq!(m["warnings"], serde_json::json!([note]));
    // The modal form's state: 60 modal coordinates and their 60 rates.
    assert_eq!(m["forms"]["modal"]["states"].as_array().unwrap().len(), 120);
}

/// The mooring line in water rests on the seabed: where it lies (away from the touchdown and
/// the anchor) its penetration is its weight in water over the contact stiffness,
/// `w/(k d)` with `w = (ρA − ρ_w π d²/4) g`, to 1e-3; the fairlead carries the weight in
/// water of the suspended part (the line beyond the last grounded node) to one element's
/// weight; every element is in tension (the frictionless seabed transmits the horizontal
/// pull to the anchor).
#[test]
fn statics_of_the_mooring_line_in_water_lies_on_the_seabed() {
    let out = temp_dir("statics-wet-mooring");
    let o = phstring(&[
        "statics",
        "examples/mooring_line.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["stable"], true);
    assert!(s["min_tension"].as_f64().unwrap() > 0.0);
    let (rho_a, d, rho_w, g, k, depth) = (25.0, 0.076, 1025.0, 9.81, 3.0e6, 60.0);
    let w = (rho_a - rho_w * std::f64::consts::PI * d * d / 4.0) * g;
    // node, x, y, reaction_x, reaction_y; the string's nodes in path order are the named
    // nodes 0 (anchor), 1 (touchdown), 2 (fairlead) and the spans' interior nodes.
    let rows = csv_rows(&out.join("equilibrium.csv"));
    let mut along: Vec<&Vec<f64>> = rows.iter().collect();
    along.sort_by(|a, b| a[1].total_cmp(&b[1]));
    let grounded: Vec<&&Vec<f64>> = along.iter().filter(|r| r[2] < -depth).collect();
    let expected = w / (k * d);
    let middle = grounded[grounded.len() / 2];
    let penetration = -depth - middle[2];
    assert!(
        (penetration - expected).abs() <= 1e-3 * expected,
        "penetration {penetration} m vs w/(kd) = {expected} m"
    );
    // Reference element length: 90 per span, spans of 114.58 m and 65.42 m.
    let last_grounded_x = grounded.last().unwrap()[1];
    assert!(
        (90.0..=115.0).contains(&last_grounded_x),
        "grounded to x = {last_grounded_x} m"
    );
    let l_ground = 114.583333 / 90.0;
    let (suspended_ref, element_weight) = {
        // The grounded part is nearly unstretched: its reference length is its x extent.
        let suspended = 180.0 - last_grounded_x;
        (suspended, w * l_ground)
    };
    let fairlead = rows.iter().find(|r| r[0] == 2.0).unwrap();
    let v = fairlead[4];
    assert!(
        (v - w * suspended_ref).abs() <= 2.0 * element_weight,
        "fairlead carries {v} N, the suspended {suspended_ref} m weigh {} N",
        w * suspended_ref
    );
}

/// `phstring check` states each wet string's weight in water, `(ρA − ρ_w π d²/4) g`, and the
/// seabed.
#[test]
fn check_states_the_weight_in_water() {
    let o = phstring(&["check", "examples/mooring_line.toml"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let w = (25.0 - 1025.0 * std::f64::consts::PI * 0.076 * 0.076 / 4.0) * 9.81;
    let line = text
        .lines()
        .find(|l| l.contains("weight in water"))
        .expect("a line with the weight in water");
    let stated: f64 = line
        .rsplit("weight in water ")
        .next()
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .expect("a number");
    assert!((stated - w).abs() <= 1e-9 * w, "{stated} vs {w}");
    assert!(text.contains("seabed:    flat at −60 m"), "{text}");
}

/// The three chains of the spread mooring, 120° apart, pull their anchors equally: the three
/// anchor reactions have the same magnitude (to 1e-6) and add up to no horizontal force (to
/// 1e-6 of one), each chain lies partly on the seabed, and the equilibrium is stable.
#[test]
fn statics_of_the_spread_mooring_is_symmetric() {
    let out = temp_dir("statics-spread");
    let o = phstring(&[
        "statics",
        "examples/spread_mooring_3d.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary(&out)["stable"], true);
    // node, x, y, z, reaction_x, reaction_y, reaction_z; anchors are named nodes 0, 3, 6.
    let rows = csv_rows(&out.join("equilibrium.csv"));
    let anchors: Vec<&Vec<f64>> = [0.0, 3.0, 6.0]
        .iter()
        .map(|k| rows.iter().find(|r| r[0] == *k).unwrap())
        .collect();
    let norm = |r: &Vec<f64>| (r[4] * r[4] + r[5] * r[5] + r[6] * r[6]).sqrt();
    let m0 = norm(anchors[0]);
    assert!(m0 > 1e5, "anchor pull {m0} N");
    for a in &anchors[1..] {
        assert!((norm(a) - m0).abs() <= 1e-6 * m0, "{} vs {m0}", norm(a));
    }
    for k in [4, 5] {
        let sum: f64 = anchors.iter().map(|a| a[k]).sum();
        assert!(sum.abs() <= 1e-6 * m0, "horizontal sum {sum} N");
    }
    let grounded = rows.iter().filter(|r| r[3] < -200.0).count();
    assert!(
        (30..=120).contains(&grounded),
        "{grounded} nodes lie on the seabed"
    );
}

/// Bisection for the root of `f` in `[lo, hi]` (a sign change there).
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let f_lo = f(lo);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (f(mid) > 0.0) == (f_lo > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The chain on the slope (`examples/chain_on_slope_2d.toml`, a bathymetry profile rising at
/// `tan α = 0.035`) against the elastic catenary with a grounded length on a frictionless
/// incline: the grounded part (unstretched `L_b`) runs up the slope from the anchor with the
/// tension `T(s) = T_a + w sin α s` and sinks vertically by `p = w cos²α/(k d)`; from the
/// touchdown the suspended part (`L − L_b`) leaves tangent to the slope with
/// `H = T_td cos α`, `V₀ = T_td sin α` and reaches the fairlead (345, −10) as the elastic
/// catenary (21.8). Solved for `T_a` and `L_b` by bisection: `H` and the fairlead's `V`
/// within 5e-4 (measured 8e-5, 4e-5: the mesh of 2.6 m elements), the anchor's pull within
/// 5e-4 (measured 3e-5), the last grounded node within one element of the touchdown, and
/// the penetration of the grounded chain within 1e-4 of `p` (measured 6e-6).
#[test]
fn statics_of_the_chain_on_the_slope_match_the_inclined_catenary() {
    let out = temp_dir("statics-slope");
    let o = phstring(&[
        "statics",
        "examples/chain_on_slope_2d.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary(&out)["stable"], true);
    let (rho_a, d, ea, k, len, g) = (113.0, 0.1368, 6.0e8, 3.0e6, 420.0, 9.81);
    let w = (rho_a - 1025.0 * std::f64::consts::PI * d * d / 4.0) * g;
    let tan_a: f64 = 0.035;
    let (c, s) = (1.0 / tan_a.hypot(1.0), tan_a / tan_a.hypot(1.0));
    let p = w * c * c / (k * d);
    // The fairlead's (x, z, H, V) for the anchor tension `ta` and grounded length `lb`.
    let fairlead = |ta: f64, lb: f64| {
        let stretched = lb + (ta * lb + w * s * lb * lb / 2.0) / ea;
        let (xt, zt) = (c * stretched, -180.0 + s * stretched - p);
        let t_td = ta + w * s * lb;
        let (h, v0, ls) = (t_td * c, t_td * s, len - lb);
        let v1 = v0 + w * ls;
        let x = xt + h / w * ((v1 / h).asinh() - (v0 / h).asinh()) + h * ls / ea;
        let z = zt
            + h / w * ((v1 / h).hypot(1.0) - (v0 / h).hypot(1.0))
            + (v0 * ls + w * ls * ls / 2.0) / ea;
        (x, z, h, v1, xt)
    };
    let anchor_tension = |lb: f64| bisect(|ta| fairlead(ta, lb).1 + 10.0, 1.0, 5e6);
    let lb = bisect(|lb| fairlead(anchor_tension(lb), lb).0 - 345.0, 50.0, 300.0);
    let ta = anchor_tension(lb);
    let (_, _, h, v, x_td) = fairlead(ta, lb);
    // node, x, y, reaction_x, reaction_y; named nodes 0 (anchor), 2 (fairlead).
    let rows = csv_rows(&out.join("equilibrium.csv"));
    let node = |k: f64| rows.iter().find(|r| r[0] == k).unwrap();
    let (fl, an) = (node(2.0), node(0.0));
    let rel = |a: f64, b: f64| (a - b).abs() / b;
    println!(
        "slope: H {} vs {h} ({:.1e}), V {} vs {v} ({:.1e}), anchor {} vs {ta} ({:.1e}), L_b {lb} m",
        fl[3],
        rel(fl[3], h),
        fl[4],
        rel(fl[4], v),
        an[3].hypot(an[4]),
        rel(an[3].hypot(an[4]), ta)
    );
    assert!(rel(fl[3], h) <= 5e-4, "H {} vs {h}", fl[3]);
    assert!(rel(fl[4], v) <= 5e-4, "V {} vs {v}", fl[4]);
    assert!(rel(an[3].hypot(an[4]), ta) <= 5e-4, "anchor {an:?} vs {ta}");
    let seabed = |x: f64| -180.0 + tan_a * x;
    let grounded: Vec<&Vec<f64>> = rows.iter().filter(|r| r[2] < seabed(r[1])).collect();
    let last = grounded.iter().map(|r| r[1]).fold(f64::MIN, f64::max);
    let element = 2.57;
    assert!(
        (last - x_td).abs() <= element,
        "grounded to x = {last} m, touchdown at {x_td} m"
    );
    let mid = grounded
        .iter()
        .find(|r| (r[1] - 80.0).abs() < element)
        .unwrap();
    let pen = seabed(mid[1]) - mid[2];
    assert!(
        rel(pen, p) <= 1e-4,
        "penetration {pen} m vs w cos²α/(kd) = {p} m"
    );
}

/// `statics --at` the checkpoint of a run without winches is the equilibrium at the
/// checkpoint's time: a 1 t hook on 20 m of steel wire (EA = 1e8 N, 6.5 kg/m) hangs from a
/// trolley moving at 0.5 m/s and is pulled down by `1000 t` N; at the checkpoint of `t` = 4 s
/// the trolley is held where the run had it (x = 2 m, to 1e-12 m), the hook hangs straight
/// below it (to 1e-9 m), the supports carry the weight plus the pull at 4 s, 4000 N (to
/// `√(free components)` × the statics' tolerance), and the hook hangs the closed-form static
/// length `ℓ + g((m + ρA ℓ)ℓ − ρA ℓ²/2)/EA + F ℓ/EA` below the trolley (to 1e-9 m).
#[test]
fn statics_at_a_checkpoint_takes_the_supports_and_loads_at_its_time() {
    let dir = temp_dir("statics-at-time");
    let scenario = dir.join("trolley.toml");
    std::fs::write(
        &scenario,
        r#"
title = "A 1 t hook on a travelling trolley, pulled down more and more"
dimension = 2

[[node]]
name = "trolley"
position = [0.0, 0.0]

[[node]]
name = "hook"
position = [0.0, -20.01]

[materials.wire]
law = "tension_only_linear"
ea = 1.0e8
rho_a = 6.5

[[string]]
name = "wire"
path = ["trolley", "hook"]
elements = 20
material = "wire"
prestretch = 1.0005

[[boundary]]
node = "trolley"
position = ["0.5*t", "0"]

[[boundary]]
node = "hook"
force = ["0", "-1000*t"]

[[point_mass]]
node = "hook"
kg = 1000.0

[body_force]
gravity = [0.0, -9.81]

[time]
h = 0.01
end = 10.0

[output]
plots = false
animation = false
"#,
    )
    .unwrap();
    let run = dir.join("run");
    let o = phstring(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
        "-q",
        "--stop-after-steps",
        "400",
    ]);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = dir.join("statics");
    let cp = run.join("checkpoint.json");
    let o = phstring(&[
        "statics",
        scenario.to_str().unwrap(),
        "--at",
        cp.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = super::summary(&out);
    let t = s["started_from"]["time"].as_f64().unwrap();
    assert!((t - 4.0).abs() < 1e-9, "{t}");
    assert!(s["started_from"]["winches"].as_array().unwrap().is_empty());
    let rows = super::numeric_rows(&out.join("equilibrium.csv"));
    let (trolley, hook) = (&rows[0], &rows[1]);
    assert!((trolley[1] - 0.5 * t).abs() < 1e-12, "{trolley:?}");
    assert!((hook[1] - trolley[1]).abs() < 1e-9, "{hook:?}");
    let (g, m, rho_a, ea, ell) = (9.81, 1000.0, 6.5, 1.0e8, 20.0);
    let pull = 1000.0 * t;
    let load = g * (m + rho_a * ell) + pull;
    let tol = (2.0 * ell).sqrt() * s["tolerance"].as_f64().unwrap();
    let lift = s["total_reaction"][1].as_f64().unwrap();
    let hang = ell + g * ((m + rho_a * ell) * ell - 0.5 * rho_a * ell * ell) / ea + pull * ell / ea;
    let drop = trolley[2] - hook[2];
    eprintln!(
        "statics at t = {t} s: supports {lift:.6} N against {load:.6} N, hook {drop:.9} m below the trolley against {hang:.9} m"
    );
    assert!((lift - load).abs() <= tol + 1e-12 * load, "{lift}");
    assert!((drop - hang).abs() < 1e-9, "{drop} against {hang}");
    let _ = std::fs::remove_dir_all(&dir);
}
