//! Broken scenarios: one clear message naming the key and its line, non-zero exit, no panic,
//! no output written.

use crate::{phstring, temp_dir};

/// Runs `check` and `run` on `content`; both must fail with a message containing every
/// string in `expect`, and `run` must leave no outputs.
fn rejects(name: &str, content: &[u8], expect: &[&str]) {
    let tmp = temp_dir(&format!("broken-{name}"));
    let file = tmp.join(format!("{name}.toml"));
    std::fs::write(&file, content).unwrap();
    let out = tmp.join("out");
    for args in [
        vec!["check", file.to_str().unwrap()],
        vec![
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let o = phstring(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name}: {args:?} succeeded");
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(err.starts_with("error: "), "{name}: {err}");
        for e in expect {
            assert!(err.contains(e), "{name}: expected {e:?} in\n{err}");
        }
    }
    assert!(
        !out.join("energy.csv").exists(),
        "{name}: a partial run was written"
    );
}

const GOOD: &str = r#"dimension = 2
[geometry]
start = [0.0, 0.0]
end = [1.0, 0.0]
[mesh]
elements = 4
[material]
ea = 20.0
rho_a = 1.0
[[boundary]]
node = 0
fixed = true
[[boundary]]
node = -1
force = ["0", "sin(t)"]
[time]
h = 0.01
end = 0.05
"#;

fn with(from: &str, to: &str) -> Vec<u8> {
    assert!(GOOD.contains(from), "{from}");
    GOOD.replacen(from, to, 1).into_bytes()
}

#[test]
fn the_good_scenario_passes() {
    let tmp = temp_dir("good");
    let file = tmp.join("good.toml");
    std::fs::write(&file, GOOD).unwrap();
    let o = phstring(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        tmp.join("o").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn toml_syntax_error() {
    rejects(
        "syntax",
        &with("ea = 20.0", "ea = = 20.0"),
        &["syntax.toml:8:"],
    );
}

#[test]
fn empty_file() {
    rejects("empty", b"", &["missing field `dimension`"]);
}

#[test]
fn binary_garbage() {
    rejects(
        "garbage",
        &[0x00, 0xff, 0xfe, 0x13, 0x37, 0x80, 0x81],
        &["not UTF-8 text"],
    );
}

#[test]
fn missing_file() {
    let o = phstring(&["check", "/nonexistent/nothing.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("cannot read scenario file /nonexistent/nothing.toml"),
        "{err}"
    );
    assert!(!err.contains("panicked"));
}

#[test]
fn unknown_key() {
    rejects(
        "unknown",
        &with("rho_a = 1.0", "rho_a = 1.0\nyoung = 3.0"),
        &["unknown.toml:10:", "unknown field `young`"],
    );
}

#[test]
fn wrong_type() {
    rejects(
        "type",
        &with("elements = 4", "elements = \"four\""),
        &["type.toml:6:", "invalid type"],
    );
}

#[test]
fn negative_ea() {
    rejects(
        "ea",
        &with("ea = 20.0", "ea = -20.0"),
        &["ea.toml:8:", "`material.ea`", "-20"],
    );
}

#[test]
fn non_positive_h() {
    rejects(
        "h0",
        &with("h = 0.01", "h = 0.0"),
        &["h0.toml:17:", "`time.h`"],
    );
    rejects(
        "hneg",
        &with("h = 0.01", "h = -0.01"),
        &["hneg.toml:17:", "`time.h`"],
    );
}

#[test]
fn node_index_out_of_range() {
    rejects(
        "node",
        &with("node = -1", "node = 7"),
        &["node.toml:14:", "`boundary.1.node`", "0..=4"],
    );
}

#[test]
fn expression_that_does_not_parse() {
    rejects(
        "expr",
        &with("\"sin(t)\"", "\"sin(t\""),
        &["expr.toml:15:", "`boundary.1.force`", "\"sin(t\""],
    );
    rejects(
        "expr2",
        &with("\"sin(t)\"", "\"foo(t)\""),
        &["expr2.toml:15:", "\"foo(t)\""],
    );
}

#[test]
fn node_fixed_and_loaded_in_the_same_component() {
    let both = with("node = -1\n", "node = -1\nfixed = [\"y\"]\n");
    rejects(
        "fixload",
        &both,
        &["`boundary.1.force`", "fixed in component y"],
    );
    // Fixed in y, loaded in x only: allowed.
    let tmp = temp_dir("fixload-ok");
    let file = tmp.join("ok.toml");
    let ok = String::from_utf8(both)
        .unwrap()
        .replace("[\"0\", \"sin(t)\"]", "[\"sin(t)\", \"0\"]");
    std::fs::write(&file, ok).unwrap();
    let o = phstring(&["check", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn expression_checked_at_first_use_not_at_t0() {
    // 1/t is undefined at t = 0 but the load is first evaluated at t = h/2.
    let tmp = temp_dir("one-over-t");
    let file = tmp.join("ok.toml");
    std::fs::write(&file, with("\"sin(t)\"", "\"0.001/t\"")).unwrap();
    let o = phstring(&["check", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn set_on_a_boundary_key_is_named_as_set() {
    let o = phstring(&[
        "check",
        "examples/paper_pendulum.toml",
        "--set",
        "boundary.1.node=99",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--set boundary.1.node=99") && err.contains("`boundary.1.node`"),
        "{err}"
    );
}

#[test]
fn bad_set_option() {
    let o = phstring(&[
        "check",
        "examples/paper_pendulum.toml",
        "--set",
        "material.ea=-1",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("--set material.ea=-1") && err.contains("`material.ea`"),
        "{err}"
    );
    let o = phstring(&["check", "examples/paper_pendulum.toml", "--set", "nonsense"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected key=value"));
}

#[test]
fn non_positive_rho_a() {
    rejects(
        "rhoa",
        &with("rho_a = 1.0", "rho_a = 0.0"),
        &["rhoa.toml:9:", "`material.rho_a`"],
    );
}

#[test]
fn non_positive_end_time() {
    rejects(
        "end",
        &with("end = 0.05", "end = -1.0"),
        &["end.toml:18:", "`time.end`"],
    );
}

#[test]
fn zero_elements() {
    rejects(
        "el0",
        &with("elements = 4", "elements = 0"),
        &["el0.toml:6:", "`mesh.elements`"],
    );
}

#[test]
fn vector_length_must_match_dimension() {
    rejects(
        "veclen",
        &with("end = [1.0, 0.0]", "end = [1.0, 0.0, 0.0]"),
        &["veclen.toml:4:", "`geometry.end`", "2 components"],
    );
    rejects(
        "forcelen",
        &with("[\"0\", \"sin(t)\"]", "[\"0\"]"),
        &["forcelen.toml:15:", "`boundary.1.force`", "2 expressions"],
    );
}

#[test]
fn bad_dimension_and_law() {
    rejects(
        "dim",
        &with("dimension = 2", "dimension = 4"),
        &["dim.toml:1:", "`dimension`", "1, 2 or 3"],
    );
    rejects(
        "law",
        &with("ea = 20.0", "law = \"rubber\"\nea = 20.0"),
        &["law.toml:8:", "`material.law`", "\"rubber\""],
    );
}

#[test]
fn step_that_does_not_divide_end_time() {
    rejects(
        "div",
        &with("h = 0.01", "h = 0.03"),
        &["div.toml:17:", "`time.h`", "whole number of steps"],
    );
}
