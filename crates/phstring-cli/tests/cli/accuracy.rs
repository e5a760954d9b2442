//! `time.scheme = "dg4"` and error control (`time.rtol`, `time.atol`) from the command line:
//! they run with exact balance, resume bit for bit, and bad values name the key.

use std::path::Path;

use crate::{phstring, temp_dir};

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

fn run(out: &Path, sets: &[&str], extra: &[&str]) -> std::process::Output {
    crate::run_with("examples/paper_pendulum.toml", out, sets, extra)
}

/// The summary of the paper pendulum run into `out` with `sets` (case `name`), after checking
/// that it completed with its energy balance at round-off (≤ 1e-11 J on every step).
fn run_completed(out: &Path, sets: &[&str], name: &str) -> serde_json::Value {
    let o = run(out, sets, &[]);
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(out);
    assert_eq!(s["status"], "completed", "{name}");
    assert!(
        s["max_balance_error"].as_f64().unwrap() <= 1e-11,
        "{name}: {s}"
    );
    s
}

/// The paper pendulum with `dg4` and with error control: completed, the balance at
/// round-off, and error control takes more steps than `time.h` alone where the tolerance
/// asks for it.
#[test]
fn dg4_and_error_control_run_with_exact_balance() {
    let dir = temp_dir("dg4-run");
    for (name, sets) in [
        ("dg4", vec!["time.scheme=\"dg4\""]),
        ("dg-tol", vec!["time.rtol=1e-6", "time.atol=1e-6"]),
        (
            "dg4-tol",
            vec!["time.scheme=\"dg4\"", "time.rtol=1e-6", "time.atol=1e-6"],
        ),
    ] {
        let s = run_completed(&dir.join(name), &sets, name);
        let steps = s["steps"].as_u64().unwrap();
        if name.ends_with("tol") {
            assert!(steps > 1000, "{name}: {steps} steps");
        } else {
            assert_eq!(steps, 100, "{name}");
        }
    }
}

/// `time.error_per_step = true` from the command line: the paper pendulum with error control
/// at 1e-6 completes with its balance at round-off in fewer steps than with the error per
/// unit step, and summary.json's scenario records the key.
#[test]
fn error_per_step_runs_with_exact_balance_in_fewer_steps() {
    let dir = temp_dir("per-step");
    let mut steps = Vec::new();
    for (name, per_step) in [("unit", "false"), ("step", "true")] {
        let set = format!("time.error_per_step={per_step}");
        let sets: [&str; 3] = ["time.rtol=1e-6", "time.atol=1e-6", &set];
        let s = run_completed(&dir.join(name), &sets, name);
        assert_eq!(
            s["scenario"]["time"]["error_per_step"].as_bool(),
            Some(per_step == "true"),
            "{name}"
        );
        steps.push(s["steps"].as_u64().unwrap());
    }
    assert!(
        steps[1] < steps[0],
        "per step {} vs per unit step {}",
        steps[1],
        steps[0]
    );
}

/// An error-controlled run interrupted after 700 steps and resumed writes the same
/// `energy.csv` as an uninterrupted one (the controller's history is in the checkpoint).
#[test]
fn error_control_resumes_bit_for_bit() {
    let dir = temp_dir("tol-resume");
    let sets = ["time.rtol=1e-6", "time.atol=1e-6"];
    let scenario = "examples/paper_pendulum.toml";
    let (whole, parts) = crate::run_whole_and_resumed(scenario, &dir, &sets, 700);
    let read = |d: &Path| std::fs::read_to_string(d.join("energy.csv")).unwrap();
    assert_eq!(read(&whole), read(&parts));
}

/// Bad `time.scheme`, `time.rtol` and `time.atol` are refused with their key, and
/// `time.error_per_step` without error control or not a boolean with the reason.
#[test]
fn bad_accuracy_keys_name_the_key() {
    let dir = temp_dir("bad-accuracy");
    for (set, key) in [
        ("time.scheme=\"rk4\"", "time.scheme"),
        ("time.rtol=-1e-3", "time.rtol"),
        ("time.atol=nan", "time.atol"),
        ("time.error_per_step=true", "needs error control"),
        ("time.error_per_step=1", "expected a boolean"),
    ] {
        let o = run(&dir.join("out"), &[set], &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{set} accepted");
        assert!(err.contains(key), "{set}: {err}");
    }
}

/// A tolerance no step can meet (`time.rtol = time.atol = 1e-300`): every step is accepted
/// at the step-size floor `time.h/2^time.max_halvings`, and the run says so, in
/// `summary.json` (`steps_over_tolerance`, a warning) and on stderr; the count survives an
/// interruption and resume. A tolerance the steps meet gives neither.
#[test]
fn steps_accepted_over_the_tolerance_are_reported() {
    let dir = temp_dir("tol-floor");
    // 0.1 s at h = 0.01 s / 2^3: 80 steps, each at the floor.
    let sets = [
        "time.rtol=1e-300",
        "time.atol=1e-300",
        "time.max_halvings=3",
        "time.end=0.1",
    ];
    let whole = dir.join("whole");
    let o = run(&whole, &sets, &[]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    let s = summary(&whole);
    assert_eq!(s["steps"], 80, "{s}");
    assert_eq!(s["steps_over_tolerance"], 80, "{s}");
    let warning = "80 of 80 steps missed the error tolerance (time.rtol = 1e-300, time.atol = 1e-300): error control accepted them at its smallest step size time.h/2^time.max_halvings = 0.00125 s whatever their error estimate";
    let warnings = s["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().starts_with(warning)),
        "{s}"
    );
    assert!(err.contains(&format!("warning: {warning}")), "{err}");
    // Interrupted after 30 steps and resumed: the same count.
    let parts = dir.join("parts");
    let first = run(&parts, &sets, &["--stop-after-steps", "30"]);
    assert_eq!(first.status.code(), Some(130));
    assert_eq!(summary(&parts)["steps_over_tolerance"], 30);
    let cp = parts.join("checkpoint.json");
    let second = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(second.status.success());
    assert_eq!(summary(&parts)["steps_over_tolerance"], 80);
    // A tolerance the steps meet: no step over it, no warning.
    let met = dir.join("met");
    let o = run(
        &met,
        &["time.rtol=1e-3", "time.atol=1e-3", "time.end=0.1"],
        &[],
    );
    assert!(o.status.success());
    let s = summary(&met);
    assert_eq!(s["steps_over_tolerance"], 0, "{s}");
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("missed the error tolerance"),
        "{s}"
    );
}
