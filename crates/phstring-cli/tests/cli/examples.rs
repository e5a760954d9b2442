//! Every example runs and writes complete, parseable outputs; the paper example matches
//! `phstring paper` to the last digit.

use std::path::Path;

use crate::{phstring, temp_dir, workspace_root};

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Parses a CSV file into its header and numeric-or-text rows.
fn csv_rows(p: &Path) -> (Vec<String>, Vec<csv::StringRecord>) {
    let mut r = csv::Reader::from_path(p).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r.records().map(|x| x.unwrap()).collect();
    (header, rows)
}

fn check_outputs(dir: &Path, dim: usize, steps: usize, stride: usize, n_nodes: usize) {
    let (h, rows) = csv_rows(&dir.join("energy.csv"));
    // A run in water adds its six columns after the ten of every run.
    let dry = "t,kinetic,potential,hamiltonian,supplied_energy,balance_error,newton_iterations,newton_residual,h,dissipated_energy";
    let wet = format!(
        "{dry},buoyancy,seabed,drag_dissipated,current_supplied,seabed_dissipated,friction_dissipated"
    );
    // A run with winches adds two columns per winch after those.
    let winches = h.iter().filter(|c| c.starts_with("winch")).count() / 2;
    let tail: String = (0..winches)
        .map(|k| format!(",winch{k}_supplied,winch{k}_dissipated"))
        .collect();
    let header = h.join(",");
    assert!(
        header == format!("{dry}{tail}") || header == format!("{wet}{tail}"),
        "{header}"
    );
    assert_eq!(winches > 0, dir.join("winches.csv").is_file());
    assert_eq!(rows.len(), steps + 1, "{}", dir.display());
    for row in &rows {
        for f in row.iter() {
            let x: f64 = f.parse().unwrap();
            assert!(x.is_finite());
        }
    }
    // Every number in its shortest round-trip form: the significant digits of Rust's
    // shortest scientific form of the value read back.
    let digits = |f: &str| {
        let m = f.split('e').next().unwrap().replace(['-', '.'], "");
        m.trim_start_matches('0').trim_end_matches('0').to_string()
    };
    for f in &rows[1] {
        let x: f64 = f.parse().unwrap();
        assert_eq!(digits(f), digits(&format!("{x:e}")), "{f}");
    }
    let (h, rows) = csv_rows(&dir.join("positions.csv"));
    assert_eq!(h.len(), 2 + dim);
    // Every `stride` steps from t = 0, and the last step if it falls between.
    let frames = steps / stride + 1 + usize::from(!steps.is_multiple_of(stride));
    assert_eq!(rows.len(), frames * n_nodes);
    let (h, rows) = csv_rows(&dir.join("ports.csv"));
    assert_eq!(h.len(), 5 + 2 * dim);
    assert!(!rows.is_empty());
    let summary: serde_json::Value =
        serde_json::from_str(&read(&dir.join("summary.json"))).unwrap();
    assert_eq!(summary["status"], "completed");
    assert_eq!(summary["steps"], steps);
    assert!(summary["time_loop_s"].as_f64().unwrap() > 0.0);
    assert!(summary["scenario"]["time"]["h"].as_f64().unwrap() > 0.0);
    let pvd = read(&dir.join("paraview/string.pvd"));
    assert_eq!(pvd.matches("<DataSet").count(), frames);
    let last = format!("frame_{steps:06}.vtp");
    assert!(read(&dir.join("paraview").join(&last)).contains("PolyData"));
    let mut plots = vec!["energy", "increments"];
    if dim >= 2 {
        plots.push("configuration");
    }
    if dir.join("winches.csv").is_file() {
        plots.extend(["winch_length", "winch_tension"]);
    }
    if dim >= 2 {
        let gif = std::fs::read(dir.join("animation.gif")).unwrap();
        assert_eq!(&gif[..6], b"GIF89a", "animation.gif");
    }
    let elements = read(&dir.join("elements.csv"));
    assert!(
        elements.starts_with("element,node_a,node_b,group,kind"),
        "elements.csv"
    );
    for stem in plots {
        assert!(
            read(&dir.join(format!("{stem}.svg"))).contains("<svg"),
            "{stem}.svg"
        );
        let png = std::fs::read(dir.join(format!("{stem}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{stem}.png");
    }
}

#[test]
fn every_example_runs_and_writes_complete_outputs() {
    let tmp = temp_dir("examples");
    // (file, dimension, steps, stride, nodes)
    let cases = [
        ("paper_pendulum", 2, 100, 1, 31),
        ("anchor_handling_2d", 2, 4500, 20, 84),
        ("taut_string", 2, 500, 5, 41),
        ("hoist_3d", 3, 400, 4, 21),
        ("axial_rod_1d", 1, 500, 10, 51),
        ("steel_hoist", 2, 400, 10, 101),
        ("crane_2d", 2, 3600, 10, 41),
        ("crane_hoisting_2d", 2, 4500, 10, 26),
        ("heave_compensated_winch_2d", 2, 6400, 10, 81),
        ("crane_vessel_heave_compensation_2d", 2, 6000, 10, 81),
        ("platform_3d", 3, 1500, 10, 50),
        ("net_3d", 3, 1000, 10, 1321),
        ("slack_wire", 2, 2000, 20, 161),
        ("mooring_line", 2, 2000, 20, 181),
        ("spread_mooring_3d", 3, 1200, 20, 153),
        ("spread_mooring_platform", 3, 600, 20, 153),
        ("chain_on_slope_2d", 2, 1500, 20, 161),
        // Ends early: it settles (time.settle) at step 2078.
        ("riser_in_current", 2, 2078, 10, 51),
        ("damped_pendulum", 2, 300, 1, 31),
        // Ends early: it settles (time.settle) at step 622.
        ("damping_injection", 2, 622, 10, 21),
        ("pd_tip_tracking", 2, 1200, 5, 26),
        ("hook_block_3d", 3, 2000, 50, 21),
        ("hook_block_antisway_3d", 3, 2000, 50, 21),
        ("cable_robot_3d", 3, 2000, 25, 40),
        ("cable_robot_winches_3d", 3, 2000, 25, 56),
        ("spar_buoy_3d", 3, 1600, 10, 123),
    ];
    let mut files: Vec<String> = std::fs::read_dir(workspace_root().join("examples"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    files.sort();
    let mut listed: Vec<String> = cases.iter().map(|c| format!("{}.toml", c.0)).collect();
    listed.sort();
    assert_eq!(files, listed, "every example must be covered here");
    for (name, dim, steps, stride, nodes) in cases {
        let out = tmp.join(name);
        let o = phstring(&[
            "run",
            &format!("examples/{name}.toml"),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        check_outputs(&out, dim, steps, stride, nodes);
    }
}

#[test]
fn paper_example_matches_paper_command_to_the_last_digit() {
    let tmp = temp_dir("paper");
    let o = phstring(&["paper", "--out", tmp.join("paper").to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("-3.4683588")
            && table.contains("-3.4037616")
            && table.contains("-3.3984740"),
        "{table}"
    );
    for fig in [
        "fig2_configurations",
        "fig3_energies",
        "fig4_hamiltonian",
        "fig5_increments",
    ] {
        for ext in ["svg", "png"] {
            assert!(
                tmp.join("paper/figures")
                    .join(format!("{fig}.{ext}"))
                    .is_file(),
                "{fig}.{ext}"
            );
        }
    }
    let run = tmp.join("run");
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["energy.csv", "positions.csv", "ports.csv"] {
        assert_eq!(
            read(&tmp.join("paper/dg").join(f)),
            read(&run.join(f)),
            "{f} differs"
        );
    }
    // And the published values, from the CSV: H(0) and H(1) within 1e-6.
    let (_, dg) = csv_rows(&run.join("energy.csv"));
    let h = |rows: &Vec<csv::StringRecord>, i: usize| rows[i][3].parse::<f64>().unwrap();
    assert!((h(&dg, 0) - (-3.468359)).abs() < 1e-6);
    assert!((h(&dg, 100) - (-3.403762)).abs() < 1e-6);
    let (_, mp) = csv_rows(&tmp.join("paper/mp/energy.csv"));
    assert!((h(&mp, 100) - (-3.398474)).abs() < 1e-6);
}

#[test]
fn set_overrides_a_key_and_check_describes_the_run() {
    let tmp = temp_dir("set");
    let o = phstring(&[
        "check",
        "examples/paper_pendulum.toml",
        "--set",
        "mesh.elements=60",
        "--set",
        "time.scheme=mp",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("60 elements, 61 nodes"), "{text}");
    assert!(text.contains("mp scheme"), "{text}");
    assert!(text.contains("fixed:     node 0 (x, y)"), "{text}");
    let out = tmp.join("o");
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--set",
        "mesh.elements=10",
        "--set",
        "time.end=0.1",
        "--set",
        "output.stride=3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    assert_eq!(summary["elements"], 10);
    assert_eq!(summary["steps"], 10);
    assert_eq!(summary["scenario"]["mesh"]["elements"], 10);
    // Stride 3 over 10 steps: frames at steps 0, 3, 6, 9 and the final state at 10.
    assert_eq!(
        read(&out.join("paraview/string.pvd"))
            .matches("<DataSet")
            .count(),
        5
    );
    assert!(out.join("paraview/frame_000010.vtp").is_file());
    assert_eq!(csv_rows(&out.join("positions.csv")).1.len(), 5 * 11);
    // A second run into the same folder needs --force.
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--force"));
}

/// `phstring sweep`: one folder per combination, a summary table, and results that do not
/// depend on the number of threads.
#[test]
fn sweep_runs_all_combinations_independently_of_threads() {
    let tmp = temp_dir("sweep");
    let mut outputs = Vec::new();
    for jobs in ["1", "2"] {
        let out = tmp.join(format!("j{jobs}"));
        let o = phstring(&[
            "sweep",
            "examples/paper_pendulum.toml",
            "--vary",
            "mesh.elements=8,16",
            "--vary",
            "material.law=hyperelastic,tension_only_linear",
            "--set",
            "time.end=0.3",
            "--set",
            "output.vtk=false",
            "--set",
            "output.plots=false",
            "--jobs",
            jobs,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (h, rows) = csv_rows(&out.join("sweep.csv"));
        assert_eq!(
            h[2..4],
            ["mesh.elements".to_string(), "material.law".to_string()]
        );
        assert_eq!(rows.len(), 4);
        assert!(rows.iter().all(|r| &r[4] == "completed"));
        assert_eq!(&rows[3][2], "16");
        assert_eq!(&rows[3][3], "tension_only_linear");
        outputs.push(out);
    }
    for i in 0..4 {
        let f = format!("run_{i:03}/energy.csv");
        assert_eq!(
            read(&outputs[0].join(&f)),
            read(&outputs[1].join(&f)),
            "{f}"
        );
    }
}

/// The step-to-step changes of the fairlead reaction's magnitude [N] in the `ports.csv` of
/// the slack-wire run in `dir` (node 160), sorted.
fn fairlead_changes(dir: &Path) -> Vec<f64> {
    let (header, rows) = csv_rows(&dir.join("ports.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (node, yx, yy) = (col("node"), col("y_x"), col("y_y"));
    let pull: Vec<f64> = rows
        .iter()
        .filter(|r| &r[node] == "160")
        .map(|r| r[yx].parse::<f64>().unwrap().hypot(r[yy].parse().unwrap()))
        .collect();
    let mut d: Vec<f64> = pull.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    d.sort_by(f64::total_cmp);
    d
}

/// The slack-wire example's fairlead tension (25 kN mean) is smooth: its heave is built up
/// from rest, so no axial wave strikes the undamped rope, and the tension changes by about
/// 6 N per step (measured median 6.1 N, largest 33 N). The same heave started abruptly
/// (`sin(2πt/10)` alone, 0.63 m/s at t = 0) changes it by about 5 kN per step: the reason
/// the example has its build-up.
#[test]
fn the_slack_wire_examples_fairlead_tension_is_smooth() {
    let tmp = temp_dir("mooring-smooth");
    let quiet = [
        "output.plots=false",
        "output.vtk=false",
        "output.animation=false",
    ];
    let built_up = tmp.join("built_up");
    let o = crate::run_with("examples/slack_wire.toml", &built_up, &quiet, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = fairlead_changes(&built_up);
    let (median, largest) = (d[d.len() / 2], d[d.len() - 1]);
    assert!(median < 20.0 && largest < 100.0, "{median} N, {largest} N");
    let abrupt = tmp.join("abrupt");
    let sine = r#"boundary.1.position=["120", "60 + 1.0 * sin(2*pi*t/10)"]"#;
    let sets = [quiet[0], quiet[1], quiet[2], sine];
    let o = crate::run_with("examples/slack_wire.toml", &abrupt, &sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = fairlead_changes(&abrupt);
    assert!(d[d.len() / 2] > 1000.0, "{} N", d[d.len() / 2]);
}
