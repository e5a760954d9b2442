//! Network scenarios: the examples run, `summary.json` lists their
//! components, the energy balance stays at round-off, `check` prints the components, and
//! invalid network files are refused with the key and its `line:column`.

use std::path::Path;

use crate::{phstring, temp_dir};

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `example` for `end` seconds into a fresh folder; returns the folder.
fn run_briefly(example: &str, end: &str) -> crate::TestDir {
    let out = temp_dir(&format!("network-{example}")).inside("out");
    let o = phstring(&[
        "run",
        &format!("examples/{example}.toml"),
        "--set",
        &format!("time.end={end}"),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{example}: {}", stderr(&o));
    out
}

/// The largest `|balance_error|` of `energy.csv` relative to the energy scale of the run
/// (the largest `|T̂| + |V̂|` of any row).
fn relative_balance_error(dir: &Path) -> f64 {
    let mut r = csv::Reader::from_path(dir.join("energy.csv")).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (kin, pot, bal) = (col("kinetic"), col("potential"), col("balance_error"));
    let (mut worst, mut scale) = (0.0_f64, 0.0_f64);
    for row in r.records() {
        let row = row.unwrap();
        let x = |i: usize| row[i].parse::<f64>().unwrap();
        scale = scale.max(x(kin).abs() + x(pot).abs());
        worst = worst.max(x(bal).abs());
    }
    assert!(scale > 0.0);
    worst / scale
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(&dir.join("summary.json"))).unwrap()
}

#[test]
fn platform_example_runs_lists_its_components_and_balances_energy() {
    let out = run_briefly("platform_3d", "0.1");
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["steps"], 50);
    assert_eq!(s["elements"], 50);
    let c = &s["components"];
    let strings = c["strings"].as_array().unwrap();
    let names: Vec<&str> = strings
        .iter()
        .map(|x| x["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["cable0", "cable1", "cable2", "cable3"]);
    assert_eq!(strings[1]["elements"], serde_json::json!([12, 24]));
    assert_eq!(strings[1]["nodes"], 13);
    assert_eq!(strings[1]["path_nodes"], serde_json::json!([2, 0]));
    assert_eq!(strings[1]["law"], "tension_only_linear");
    assert_eq!(strings[1]["material"], "steel");
    assert_eq!(strings[1]["ea"], 5e7);
    assert_eq!(strings[1]["rho_a"], 2.0);
    let springs = c["springs"].as_array().unwrap();
    assert_eq!(springs[0]["name"], "link");
    // cable0:6 and cable1:6: the 6th nodes along the cables (interior nodes from 5 and 16).
    assert_eq!(springs[0]["nodes"], serde_json::json!([10, 21]));
    assert_eq!(springs[1]["name"], "tie");
    assert_eq!(springs[1]["to_point"], serde_json::json!([0.8, -0.2, 0.0]));
    assert_eq!(c["point_masses"][0]["node"], 0);
    assert_eq!(c["point_masses"][0]["kg"], 1500.0);
    assert_eq!(c["motions"][0]["node"], 1);
    assert_eq!(c["motions"][0]["component"], "z");
    // Corners 0 (x, y) … 3 and the fixed end of the tie.
    let supports: Vec<u64> = c["supports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["node"].as_u64().unwrap())
        .collect();
    assert_eq!(supports, [1, 2, 3, 4, 49]);
    assert_eq!(c["supports"][0]["fixed"], serde_json::json!(["x", "y"]));
    assert_eq!(c["nodes"][0]["name"], "platform");
    // The scenario as run keeps the network tables.
    assert_eq!(s["scenario"]["string"][0]["path"][0], "corner0");
    assert_eq!(s["scenario"]["geometry"], serde_json::Value::Null);
    let rel = relative_balance_error(&out);
    assert!(rel < 1e-13, "balance error {rel:e} of the energy");
}

#[test]
fn net_example_runs_lists_its_components_and_balances_energy() {
    let out = run_briefly("net_3d", "0.04");
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["steps"], 20);
    let c = &s["components"];
    assert_eq!(c["strings"].as_array().unwrap().len(), 40);
    assert_eq!(c["strings"][0]["name"], "x0");
    assert_eq!(c["strings"][39]["name"], "y19");
    // 21 spans of 2 elements each.
    assert_eq!(c["strings"][0]["elements"], serde_json::json!([0, 42]));
    assert_eq!(c["springs"].as_array().unwrap().len(), 4);
    assert_eq!(c["supports"].as_array().unwrap().len(), 80);
    assert_eq!(c["point_masses"][0]["kg"], 200.0);
    assert_eq!(s["elements"], 40 * 42 + 4);
    let rel = relative_balance_error(&out);
    assert!(rel < 1e-13, "balance error {rel:e} of the energy");
}

#[test]
fn check_prints_the_components_of_a_network() {
    let o = phstring(&["check", "examples/platform_3d.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for expected in [
        "50 elements, 50 nodes: 4 strings, 2 springs, 5 named nodes",
        "node:      node 0 \"platform\" at [0.3, -0.2, 0] m",
        "string:    cable0: 12 elements (1 span of 12), node 1 \"corner0\" to node 0 \"platform\", tension_only_linear (steel)",
        "spring:    link: node 10 \"cable0:6\" to node 21 \"cable1:6\", k = 20000 N/m, rest length 5 m",
        "spring:    tie: node 0 \"platform\" to the fixed point [0.8, -0.2, 0] m",
        "fixed:     node 1 \"corner0\" (x, y)",
        "motion:    node 1 \"corner0\" z = 10 + 0.15*(1 - cos(2*pi*t/5)) m",
        "mass:      node 0 \"platform\": 1500 kg, weight [0, 0, -14715] N",
    ] {
        assert!(text.contains(expected), "missing {expected:?} in\n{text}");
    }
    // A long list is cut: the net has 80 fixed anchors.
    let o = phstring(&["check", "examples/net_3d.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("and 60 more fixed nodes"), "{text}");
    assert!(text.contains("and 20 more strings"), "{text}");
}

/// `line:column` of the first `needle` in `text` (1-based).
fn pos(text: &str, needle: &str) -> String {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in the text"));
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap().chars().count() + 1;
    format!("{line}:{column}")
}

/// The platform example with `from` replaced by `to` (once).
fn platform_with(from: &str, to: &str) -> String {
    let text = read(&crate::workspace_root().join("examples/platform_3d.toml"));
    assert!(text.contains(from), "{from:?}");
    text.replacen(from, to, 1)
}

/// Invalid networks are refused by `check` and `run` with the key and the position of the
/// value (the file's `line:column`).
#[test]
fn invalid_networks_are_refused_with_key_and_position() {
    let dir = temp_dir("network-broken");
    // (name, text, the value's text to locate, key, message part)
    let cases = [
        (
            "typo",
            platform_with(
                "path = [\"corner0\", \"platform\"]",
                "path = [\"corner0\", \"platfrom\"]",
            ),
            "\"platfrom\"",
            "string.0.path.1",
            "names node \"platfrom\", which is not a [[node]] (known: platform, ",
        ),
        (
            "no_string",
            platform_with("between = [\"cable0:6\"", "between = [\"cabel0:6\""),
            "\"cabel0:6\"",
            "spring.0.between.0",
            "names string \"cabel0\", which is not a [[string]] (known: cable0, ",
        ),
        (
            "index",
            platform_with("\"cable1:6\"]", "\"cable1:13\"]"),
            "\"cable1:13\"",
            "spring.0.between.1",
            "is out of range: string cable1 has nodes 0..=12 (or -1..=-13 from the end)",
        ),
        (
            "mass",
            platform_with("node = \"platform\"\nkg", "node = \"deck\"\nkg"),
            "\"deck\"",
            "point_mass.0.node",
            "names node \"deck\", which is not a [[node]]",
        ),
        (
            "self_spring",
            platform_with(
                "[\"cable0:6\", \"cable1:6\"]",
                "[\"cable0:6\", \"cable0:6\"]",
            ),
            "\"cable0:6\"]",
            "spring.0.between.1",
            "is the same node as between.0 (\"cable0:6\" (node 10)): a spring joins two different nodes",
        ),
        (
            "motion_force",
            platform_with(
                "node = \"corner1\"\nfixed = true",
                "node = \"corner0\"\nforce = [\"0\", \"0\", \"100\"]",
            ),
            "[\"0\", \"0\", \"100\"]",
            "boundary.1.force",
            "\"corner0\" (node 1) has a prescribed position (boundary.0.position) in component z and cannot also be loaded in it",
        ),
        (
            "motion_start",
            platform_with("\"10 + 0.15*", "\"11 + 0.15*"),
            "\"11 + 0.15*",
            "boundary.0.position.2",
            "component z is at 11 m at t = 0, but \"corner0\" (node 1) starts at 10 m",
        ),
        (
            "duplicate",
            platform_with("name = \"corner3\"", "name = \"corner2\""),
            "\"corner2\"\nposition = [-5.0",
            "node.4.name",
            "= \"corner2\" is already the name of node.3 (line 26); names must differ",
        ),
        (
            "repeat",
            platform_with(
                "path = [\"corner2\", \"platform\"]",
                "path = [\"corner2\", \"corner2\", \"platform\"]",
            ),
            "\"corner2\", \"platform\"]",
            "string.2.path.1",
            "is \"corner2\" (node 3) again: consecutive nodes of a path must differ",
        ),
        (
            "unused",
            platform_with(
                "[materials.steel]",
                "[[node]]\nname = \"spare\"\nposition = [0.0, 0.0, 5.0]\n\n[materials.steel]",
            ),
            "\"spare\"",
            "node.5.name",
            "= \"spare\" is on no string's path and at no spring's end",
        ),
        (
            "mixed",
            platform_with("[time]", "[geometry]\nstart = [0.0, 0.0, 0.0]\n\n[time]"),
            "[geometry]",
            "geometry",
            "belongs to a single-string scenario, but this one has [[string]] tables",
        ),
    ];
    for (name, text, value, key, message) in cases {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, &text).unwrap();
        let expected = format!("{name}.toml:{}: `{key}` ", pos(&text, value));
        let out = dir.join("out");
        for args in [
            vec!["check", path.to_str().unwrap()],
            vec![
                "run",
                path.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        ] {
            let o = phstring(&args);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{name}: {err}");
            assert!(
                err.contains(&expected),
                "{name}: expected {expected:?} in {err}"
            );
            assert!(
                err.contains(message),
                "{name}: expected {message:?} in {err}"
            );
        }
    }
    // Nothing was run.
    assert!(!dir.join("out").join("summary.json").exists());
}

/// A single-string file with a network table names the table.
#[test]
fn single_string_file_with_a_network_table_is_refused() {
    let dir = temp_dir("network-single");
    let text = read(&crate::workspace_root().join("examples/paper_pendulum.toml"))
        + "\n[[spring]]\nname = \"s\"\nbetween = [0, 1]\nk = 1.0\nrest = 0.0\n";
    let path = dir.join("mixed.toml");
    std::fs::write(&path, &text).unwrap();
    let o = phstring(&["check", path.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "mixed.toml:{}: `spring` belongs to a network",
            pos(&text, "[[spring]]")
        )),
        "{err}"
    );
}

/// A network run interrupted and resumed writes what an uninterrupted run writes, and a
/// sweep varies a network's keys.
#[test]
fn network_runs_resume_bit_identically_and_sweep() {
    let dir = temp_dir("network-resume");
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "run",
            "examples/platform_3d.toml",
            "--set",
            "time.end=0.04",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        phstring(&args)
    };
    let o = run(&whole, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(&parts, &["--stop-after-steps", "7"]);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let cp = parts.join("checkpoint.json");
    let o = phstring(&["run", "--resume", cp.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["energy.csv", "positions.csv", "ports.csv"] {
        assert_eq!(read(&whole.join(f)), read(&parts.join(f)), "{f}");
    }
    let sweep = dir.join("sweep");
    let o = phstring(&[
        "sweep",
        "examples/platform_3d.toml",
        "--set",
        "time.end=0.01",
        "--vary",
        "materials.steel.ea=5e7,1e8",
        "--vary",
        "point_mass.0.kg=1000,2000",
        "--jobs",
        "2",
        "--out",
        sweep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = read(&sweep.join("sweep.csv"));
    assert_eq!(table.lines().count(), 5, "{table}");
    let s = summary(&sweep.join("run_003"));
    assert_eq!(s["components"]["strings"][0]["ea"], 1e8);
    assert_eq!(s["components"]["point_masses"][0]["kg"], 2000.0);
}

/// A string 1e-12 m long 1 m from the origin (elements of 2.5e-14 m, which coordinates of
/// 1 m hold to 2.2e-16 m): `check` accepts it with a warning, and `run` prints the warning
/// once, before stepping, and keeps it in `summary.json`.
#[test]
fn elements_below_the_rounding_of_their_coordinates_are_warned_about() {
    let sets = [
        "--set",
        "geometry.start=[1.0, 0.0]",
        "--set",
        "geometry.end=[1.000000000001, 0.0]",
        "--set",
        "time.end=0.02",
    ];
    let warning = "warning: the string: 40 of its 40 elements are shorter than 1e8 times the rounding of their coordinates; element ";
    let mut args = vec!["check", "examples/taut_string.toml"];
    args.extend(sets);
    let o = phstring(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches(warning).count(), 1, "{}", stderr(&o));
    let out = temp_dir("short-elements").inside("out");
    let mut args = vec![
        "run",
        "examples/taut_string.toml",
        "-q",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(sets);
    let o = phstring(&args);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert_eq!(err.matches(warning).count(), 1, "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&read(&out.join("summary.json"))).unwrap();
    let warnings = summary["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{summary}");
    let kept = warnings[0].as_str().unwrap();
    assert!(err.contains(&format!("warning: {kept}\n")), "{kept}\n{err}");
    // The example as it is: no warning.
    let o = phstring(&["check", "examples/taut_string.toml"]);
    assert!(!stderr(&o).contains("rounding"), "{}", stderr(&o));
}
