//! The outputs of a run in water (docs/method.md §21): energy.csv's water columns close the
//! balance mechanism by mechanism, summary.json's `water` object, the ParaView contact arrays,
//! the plot of where the energy went, a resume that writes what an uninterrupted run does;
//! and a dry run's files are those it always wrote.

use std::path::Path;

use crate::{phstring, run_with, summary, temp_dir};

/// A mooring line anchored on a seabed 60 m deep, heaved at its fairlead 5 m below the
/// surface, in a 0.3 m/s current. 160 m long: with 180 m (a straight start 48 m slack) the
/// starting equilibrium of the tension-only line fails (a singular Newton matrix at the
/// slack start, and the pseudo-transient continuation needs more than its 2000 steps).
const WET_LINE: &str = r#"title = "wet line"
dimension = 2
[geometry]
start = [0.0, -60.0]
end = [120.0, -5.0]
length = 160.0
[mesh]
elements = 90
[material]
law = "tension_only_linear"
ea = 5.0e8
rho_a = 25.0
diameter = 0.076
cd = 1.2
cd_axial = 0.008
ca = 1.0
[water]
depth = 60.0
current = [0.3, 0.0]
[seabed]
stiffness = 3.0e6
damping = 3.0e5
friction = 0.5
[body_force]
gravity = [0.0, -9.81]
[[boundary]]
node = 0
fixed = true
[[boundary]]
node = -1
position = ["120", "-5 + 1.0 * sin(2*pi*t/10) * (1 - exp(-(t/2)^2))"]
[initial]
equilibrium = true
[time]
scheme = "dg"
h = 0.01
end = 2.0
"#;

const DRY_HEADER: &str = "t,kinetic,potential,hamiltonian,supplied_energy,balance_error,newton_iterations,newton_residual,h,dissipated_energy";

/// The header and the rows (as numbers) of the CSV file at `p`, the columns by name.
fn table(p: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut r = csv::Reader::from_path(p).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| {
            x.unwrap()
                .iter()
                .map(|f| f.parse().unwrap_or(0.0))
                .collect()
        })
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header.iter().position(|h| h == name).unwrap()
}

/// Runs the wet line into `out` with `extra` arguments.
fn run_wet(dir: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let scenario = dir.join("wet.toml");
    std::fs::write(&scenario, WET_LINE).unwrap();
    run_with(scenario.to_str().unwrap(), out, &[], extra)
}

/// energy.csv of the wet line: the dry columns, then the water's; at every row
/// `Ĥ(t) − Ĥ(0) − supplied + dissipated` within 1e-9 of the row's energy scale
/// `|T̂| + |V̂| + |Ĥ(0)| + |supplied| + |dissipated|`; the water's dissipations are all of the
/// dissipated energy (no material damping) to 1e-12 of it, never decrease, and the energy
/// supplied besides the current's is the boundary ports' `Σ h û·ŷ` of ports.csv to 1e-9.
fn check_energy(out: &Path) {
    let (h, rows) = table(&out.join("energy.csv"));
    assert_eq!(
        h.join(","),
        format!(
            "{DRY_HEADER},buoyancy,seabed,drag_dissipated,current_supplied,seabed_dissipated,friction_dissipated"
        )
    );
    assert_eq!(rows.len(), 201);
    let c = |n: &str| column(&h, n);
    let (kin, pot, ham) = (c("kinetic"), c("potential"), c("hamiltonian"));
    let (sup, dis) = (c("supplied_energy"), c("dissipated_energy"));
    let (drag, cur, bed, fric) = (
        c("drag_dissipated"),
        c("current_supplied"),
        c("seabed_dissipated"),
        c("friction_dissipated"),
    );
    let h0 = rows[0][ham];
    let mut worst = 0.0f64;
    for (k, r) in rows.iter().enumerate() {
        let scale = r[kin].abs() + r[pot].abs() + h0.abs() + r[sup].abs() + r[dis].abs();
        let closure = (r[ham] - h0 - r[sup] + r[dis]).abs() / scale;
        worst = worst.max(closure);
        let water = r[drag] + r[bed] + r[fric];
        assert!((water - r[dis]).abs() <= 1e-12 * r[dis], "row {k}: {r:?}");
        assert!(r[c("seabed")] >= 0.0, "row {k}");
        if k > 0 {
            for j in [drag, bed, fric] {
                assert!(r[j] >= rows[k - 1][j], "row {k}: {} decreased", h[j]);
            }
        }
    }
    eprintln!("wet line: worst balance closure {worst:.2e} of the energy scale");
    assert!(worst <= 1e-9, "{worst:e}");
    let last = rows.last().unwrap();
    let (ph, prow) = table(&out.join("ports.csv"));
    let step = rows[1][c("h")];
    let ports: f64 = prow.iter().map(|r| step * r[column(&ph, "power")]).sum();
    let boundary = last[sup] - last[cur];
    assert!(
        (ports - boundary).abs() <= 1e-9 * last[sup].abs(),
        "{ports} vs {boundary}"
    );
    assert!(last[drag] > 100.0 && last[cur] > 100.0 && last[bed] > 0.0 && last[fric] > 0.0);
}

/// The grounded length [m] of the wet line's last frame from positions.csv: nodes below the
/// seabed (`y < −60 m`), each element `l_e = 160/90 m` counted half per grounded node.
fn grounded_from_positions(out: &Path) -> f64 {
    let (_, rows) = table(&out.join("positions.csv"));
    let last = &rows[rows.len() - 91..];
    let below: Vec<bool> = last.iter().map(|r| r[3] < -60.0).collect();
    below
        .windows(2)
        .map(|w| 0.5 * f64::from(u8::from(w[0]) + u8::from(w[1])) * 160.0 / 90.0)
        .sum()
}

#[test]
fn a_wet_run_reports_the_water_mechanism_by_mechanism() {
    let dir = temp_dir("water-outputs");
    let out = dir.join("wet");
    let o = run_wet(&dir, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    check_energy(&out);
    let s = summary(&out);
    let w = &s["water"];
    let (_, rows) = table(&out.join("energy.csv"));
    let last = rows.last().unwrap();
    // The totals are energy.csv's last row, to the last digit.
    for (k, name) in [
        (10, "buoyancy_final"),
        (11, "seabed_final"),
        (12, "drag_dissipated"),
        (13, "current_supplied"),
        (14, "seabed_dissipated"),
        (15, "friction_dissipated"),
    ] {
        assert_eq!(w[name].as_f64().unwrap(), last[k], "{name}");
    }
    let g = &w["strings"][0];
    let (end, min) = (
        g["grounded_length_final"].as_f64().unwrap(),
        g["grounded_length_min"].as_f64().unwrap(),
    );
    let expected = grounded_from_positions(&out);
    eprintln!("wet line: grounded {end} m at the end (positions.csv: {expected} m), least {min} m");
    assert!(
        (end - expected).abs() <= 1e-9 * expected,
        "{end} vs {expected}"
    );
    assert!(end > 50.0 && min > 50.0 && min <= end, "{g}");
    // The largest contact force is about a grounded node's wet weight per node,
    // (ρA − ρ_w π d²/4) g l_e = 20.35 · 9.81 · 1.78 = 355 N, within 10 %.
    let f = w["max_contact_force"].as_f64().unwrap();
    eprintln!("wet line: largest contact force {f} N");
    assert!((f / 355.0 - 1.0).abs() < 0.1, "{f}");
    assert!(w["max_contact_force_node"].as_u64().unwrap() < 91);
    let plots: Vec<&str> = s["plots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap())
        .collect();
    assert!(plots.contains(&"energy_split"), "{plots:?}");
    assert!(plots.contains(&"fairlead_tension"), "{plots:?}");
    // The configuration has the water surface and the seabed behind it, the nodes on the
    // seabed marked, and the grounded length at the last snapshot (the end) in the legend.
    let svg = std::fs::read_to_string(out.join("configuration.svg")).unwrap();
    assert!(svg.contains("water surface") && svg.contains("seabed"));
    assert!(svg.contains("on the seabed"));
    assert!(svg.contains(&format!("{end:.1} m")), "{end}");
    // end_tensions.csv: a row at t = 0 and per step, each tension positive.
    let (h, rows) = table(&out.join("end_tensions.csv"));
    assert_eq!(h.join(","), "t,FairTen1,AnchTen1");
    assert_eq!(rows.len(), table(&out.join("energy.csv")).1.len());
    assert!(rows.iter().all(|r| r[1] > 0.0 && r[2] > 0.0));
    for f in ["energy_split.svg", "energy_split.png"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 1000, "{f}");
    }
    let frame = std::fs::read_to_string(out.join("paraview/frame_000200.vtp")).unwrap();
    assert!(frame.contains("Name=\"grounded\"") && frame.contains("Name=\"contact_force\""));

    // Interrupted after 120 steps and resumed: the files of the uninterrupted run.
    let part = dir.join("part");
    let o = run_wet(&dir, &part, &["--stop-after-steps", "120"]);
    assert!(!o.status.success());
    let cp = part.join("checkpoint.json");
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "energy.csv",
        "positions.csv",
        "end_tensions.csv",
        "paraview/frame_000200.vtp",
        // The nodes on the seabed at the snapshots before the checkpoint are in it.
        "configuration.svg",
    ] {
        assert!(
            std::fs::read(out.join(f)).unwrap() == std::fs::read(part.join(f)).unwrap(),
            "{f} differs after a resume"
        );
    }
    assert_eq!(summary(&part)["water"], s["water"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_dry_run_writes_no_water_outputs() {
    let dir = temp_dir("water-dry");
    let out = dir.join("dry");
    let sets = ["time.end=0.05"];
    let o = run_with("examples/slack_wire.toml", &out, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (h, _) = table(&out.join("energy.csv"));
    assert_eq!(h.join(","), DRY_HEADER);
    let s = summary(&out);
    assert!(s.get("water").is_none(), "{s}");
    assert!(!out.join("energy_split.png").exists());
    let svg = std::fs::read_to_string(out.join("configuration.svg")).unwrap();
    assert!(!svg.contains("water surface") && !svg.contains("seabed"));
    let frame = std::fs::read_to_string(out.join("paraview/frame_000000.vtp")).unwrap();
    assert!(!frame.contains("grounded") && !frame.contains("contact_force"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The trace of a MatrixMarket coordinate file (`linearize`'s `FORM/NAME.mtx`).
fn mtx_trace(p: &Path) -> f64 {
    let text = std::fs::read_to_string(p).unwrap();
    let mut rows = text.lines().filter(|l| !l.starts_with('%')).skip(1);
    let mut trace = 0.0;
    for line in rows.by_ref() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() == 3 && f[0] == f[1] {
            trace += f[2].parse::<f64>().unwrap();
        }
    }
    trace
}

/// `water.linear_drag_amplitude = V` adds Lorentz's equivalent linear drag to `linearize`'s
/// damping matrix: on the mooring line (2D, every element under water, anchor and fairlead
/// held), the trace of the reduced `R` grows by `(8/3π) V (½ρ Cd d + ½ρ CdAx π d)` times a
/// quarter of the free element ends' lengths, `(2L − l_anchor − l_fairlead)/4` (to 1e-9).
#[test]
fn linearize_adds_the_equivalent_linear_drag() {
    let dir = temp_dir("linearize-drag");
    let lin = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["linearize", "examples/mooring_line.toml", "--out"];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        let o = phstring(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        mtx_trace(&out.join("reduced/R.mtx"))
    };
    let v = 0.5;
    let plain = lin("plain", &[]);
    let amplitude = format!("water.linear_drag_amplitude={v}");
    let with = lin("with", &["--set", &amplitude]);
    let (rho, d, cd, cda) = (1025.0, 0.076, 1.2, 0.008);
    let (l1, l2) = (114.583333, (35.416667f64).hypot(55.0));
    let free_ends = 2.0 * (l1 + l2) - l1 / 90.0 - l2 / 90.0;
    let per_length = 0.5 * rho * cd * d + 0.5 * rho * cda * std::f64::consts::PI * d;
    let expected = 8.0 / (3.0 * std::f64::consts::PI) * v * per_length * free_ends / 4.0;
    assert!(
        (with - plain - expected).abs() <= 1e-9 * expected,
        "trace of R grew by {} N·s/m, expected {expected}",
        with - plain
    );
}
