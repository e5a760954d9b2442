//! Dissipation and feedback control from the command line: the examples
//! `damped_pendulum`, `damping_injection` and `pd_tip_tracking` run, and what each claims in
//! its header comment is checked on its output files; bad damping and control keys are
//! refused with the key and its line.

use std::collections::BTreeMap;
use std::path::Path;

use crate::{phstring, temp_dir};

/// Runs `example` into a fresh folder and returns it.
fn run_example(example: &str, name: &str) -> crate::TestDir {
    let out = temp_dir(name);
    let o = crate::run_with(&format!("examples/{example}"), &out, &[], &["--force"]);
    assert!(
        o.status.success(),
        "{example}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// The columns of a CSV file by header name.
fn columns(p: &Path) -> BTreeMap<String, Vec<String>> {
    let mut r = csv::Reader::from_path(p).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let mut cols: BTreeMap<String, Vec<String>> =
        header.iter().map(|h| (h.clone(), Vec::new())).collect();
    for rec in r.records() {
        for (h, x) in header.iter().zip(rec.unwrap().iter()) {
            cols.get_mut(h).unwrap().push(x.to_string());
        }
    }
    cols
}

fn floats(c: &BTreeMap<String, Vec<String>>, name: &str) -> Vec<f64> {
    c[name].iter().map(|x| x.parse().unwrap()).collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// `damped_pendulum.toml`: after the pulse (t > 0.2 s) `Ĥ` never increases; the dissipated
/// energy grows on every step (`D_n ≥ 0`); the balance stays at round-off (≤ 1e-11 J); and
/// `Ĥ(T) − Ĥ(0) = supplied − dissipated` closes to round-off over the whole run.
#[test]
fn damped_pendulum_loses_exactly_what_it_dissipates() {
    let dir = run_example("damped_pendulum.toml", "damped-pendulum");
    let e = columns(&dir.join("energy.csv"));
    let (t, h, d) = (
        floats(&e, "t"),
        floats(&e, "hamiltonian"),
        floats(&e, "dissipated_energy"),
    );
    let (supplied, bal) = (floats(&e, "supplied_energy"), floats(&e, "balance_error"));
    for n in 0..t.len() - 1 {
        assert!(d[n + 1] >= d[n], "D_n < 0 at step {}", n + 1);
        assert!(
            bal[n + 1].abs() <= 1e-11,
            "step {}: {:e}",
            n + 1,
            bal[n + 1]
        );
        if t[n] >= 0.2 - 1e-9 {
            assert!(h[n + 1] <= h[n] + 1e-12, "Ĥ rose at step {}", n + 1);
        }
    }
    let last = t.len() - 1;
    let closure = h[last] - h[0] - supplied[last] + d[last];
    assert!(closure.abs() <= 1e-10, "{closure:e}");
    // The damping is doing something: most of the energy above the hanging rest is gone.
    assert!(d[last] > 1.0, "dissipated {}", d[last]);
    let s = summary(&dir);
    assert_eq!(s["dissipated_energy"].as_f64().unwrap(), d[last]);
    assert_eq!(s["components"]["strings"][0]["kelvin_voigt"], 0.2);
}

/// `damping_injection.toml`: the controller's port supplies `h u·y ≤ 0` on every step, `Ĥ`
/// never increases, and the run settles (time.settle) before `time.end`, reporting when and
/// where.
#[test]
fn damping_injection_is_passive_and_settles() {
    let dir = run_example("damping_injection.toml", "damping-injection");
    let e = columns(&dir.join("energy.csv"));
    let (h, dt) = (floats(&e, "hamiltonian"), floats(&e, "h"));
    let p = columns(&dir.join("ports.csv"));
    let (kind, power) = (&p["kind"], floats(&p, "power"));
    let mut control_steps = 0;
    for (k, pw) in kind.iter().zip(&power) {
        if k == "force" {
            assert!(*pw <= 0.0, "the controller supplied power {pw:e} W");
            control_steps += 1;
        }
    }
    assert_eq!(control_steps, h.len() - 1, "one control sample per step");
    for n in 0..h.len() - 1 {
        assert!(
            h[n + 1] <= h[n] + 1e-15 * h[n].abs(),
            "Ĥ rose at step {}: {} → {}",
            n + 1,
            h[n],
            h[n + 1]
        );
        assert!(dt[n + 1] > 0.0);
    }
    let s = summary(&dir);
    let settled = &s["settled"];
    assert_eq!(settled["settled"], true, "{s}");
    let t = settled["t"].as_f64().unwrap();
    assert!(t < 60.0 && t > 2.0, "settled at {t}");
    assert!(settled["kinetic"].as_f64().unwrap() < 1.0);
    assert_eq!(s["t_reached"].as_f64().unwrap(), t);
    assert_eq!(s["status"], "completed");
    // The swing's energy went out through the controller: Ĥ fell by what it took.
    let taken = -floats(&e, "supplied_energy").last().unwrap();
    assert!((h[0] - h.last().unwrap() - taken).abs() <= 1e-9 * h[0].abs());
    assert!(taken > 1000.0, "{taken}");
}

/// `pd_tip_tracking.toml`: the hook's distance from the reference path shrinks from 0.5 m
/// to below 1 cm over the last half of the run, and the cumulative supplied energy of
/// energy.csv is the sum over steps of `h Σ_ports u·y` from ports.csv.
#[test]
fn pd_tracking_converges_and_the_supplied_energy_is_the_port_power() {
    let dir = run_example("pd_tip_tracking.toml", "pd-tracking");
    let pos = columns(&dir.join("positions.csv"));
    let (t, node, x, y) = (
        floats(&pos, "t"),
        &pos["node"],
        floats(&pos, "x"),
        floats(&pos, "y"),
    );
    let hook = node
        .iter()
        .map(|n| n.parse::<usize>().unwrap())
        .max()
        .unwrap();
    let reference = |t: f64| {
        let x = 0.5 + 0.5 * (0.5 * t).sin();
        (x, -(25.0 - x * x).sqrt())
    };
    let mut errors = Vec::new();
    for k in 0..t.len() {
        if node[k].parse::<usize>().unwrap() == hook {
            let (xr, yr) = reference(t[k]);
            errors.push((t[k], (x[k] - xr).hypot(y[k] - yr)));
        }
    }
    let first = errors[0].1;
    assert!((first - 0.5).abs() < 1e-3, "starts 0.5 m off: {first}");
    let late = errors
        .iter()
        .filter(|(t, _)| *t >= 6.0)
        .map(|e| e.1)
        .fold(0.0, f64::max);
    assert!(late < 0.01, "tracking error after 6 s: {late}");
    // Supplied energy = Σ_n h_n Σ_ports u·y.
    let e = columns(&dir.join("energy.csv"));
    let (h, supplied) = (floats(&e, "h"), floats(&e, "supplied_energy"));
    let p = columns(&dir.join("ports.csv"));
    let (t_mid, power) = (floats(&p, "t_mid"), floats(&p, "power"));
    let mut sum = 0.0;
    let mut k = 0;
    for n in 1..h.len() {
        let mut step_power = 0.0;
        let tm = t_mid[k];
        while k < t_mid.len() && t_mid[k] == tm {
            step_power += power[k];
            k += 1;
        }
        sum += h[n] * step_power;
    }
    assert_eq!(k, t_mid.len());
    let last = *supplied.last().unwrap();
    assert!(
        (sum - last).abs() <= 1e-9 * last.abs().max(1.0),
        "{sum} vs {last}"
    );
    let bal = floats(&e, "balance_error");
    assert!(bal.iter().all(|b| b.abs() <= 1e-10), "balance");
}

/// Bad damping and control keys are refused before anything runs, naming the key and its
/// line.
#[test]
fn bad_damping_and_control_keys_name_the_key() {
    let dir = temp_dir("bad-control");
    let base =
        std::fs::read_to_string(crate::workspace_root().join("examples/pd_tip_tracking.toml"))
            .unwrap();
    let cases = [
        (
            base.replace("rho_a = 0.15", "rho_a = 0.15\nkelvin_voigt = -1.0"),
            "material.kelvin_voigt",
        ),
        (
            base.replace("kp = 2000.0, kd = 250.0, ", "kp = 2000.0, kd = -5.0, "),
            "boundary.1.control.kd",
        ),
        (
            base.replace(
                "kp = 2000.0, kd = 250.0, reference = [",
                "kp = 2000.0, kd = 250.0, reference_velocity = [",
            ),
            "boundary.1.control.kp",
        ),
        (
            base.replace("kp = 2000.0, kd = 250.0, ", "kp = 0.0, kd = 0.0, "),
            "boundary.1.control",
        ),
        (
            base.replace("node = -1\ncontrol", "node = 0\ncontrol"),
            "boundary.1.control",
        ),
    ];
    for (k, (text, key)) in cases.iter().enumerate() {
        let f = dir.join(format!("case{k}.toml"));
        std::fs::write(&f, text).unwrap();
        let o = phstring(&["check", f.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "case {k} accepted");
        assert!(err.contains(key), "case {k}: no `{key}` in: {err}");
        assert!(
            err.contains(&format!("case{k}.toml:")),
            "case {k}: no line in: {err}"
        );
    }
}

/// Statics leave feedback laws out: a PD law that pulls at rest at the equilibrium found
/// without it is refused with its port, node and force (the pd_tip_tracking reference starts
/// 0.5 m beside the hanging hook), while damping injection, which is zero at rest, passes;
/// `linearize` takes the open-loop plant, whose feedback port is an input.
#[test]
fn statics_refuse_a_feedback_law_that_pushes_at_rest() {
    let dir = temp_dir("statics-feedback");
    let o = phstring(&[
        "statics",
        "examples/pd_tip_tracking.toml",
        "--out",
        dir.join("pd").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("feedback port 0 (the 1st control) at node 25 pushes with"),
        "{err}"
    );
    let o = phstring(&[
        "statics",
        "examples/damping_injection.toml",
        "--out",
        dir.join("di").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = phstring(&[
        "linearize",
        "examples/pd_tip_tracking.toml",
        "--out",
        dir.join("lin").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("lin/manifest.json")).unwrap())
            .unwrap();
    assert_eq!(m["inputs"].as_array().unwrap().len(), 2, "{}", m["inputs"]);
}

/// `time.settle` survives an interruption: a run stopped after 500 steps (t = 5 s: armed,
/// and within the hold, below the threshold since about 4.2 s) and resumed settles at the
/// same step and time as the uninterrupted run, with identical `energy.csv`.
#[test]
fn settling_survives_a_resume() {
    let whole = run_example("damping_injection.toml", "settle-whole");
    let dir = temp_dir("settle-resume");
    let out = dir.join("run");
    let first = phstring(&[
        "run",
        "examples/damping_injection.toml",
        "--out",
        out.to_str().unwrap(),
        "-q",
        "--stop-after-steps",
        "500",
    ]);
    assert_eq!(
        first.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let cp = out.join("checkpoint.json");
    let second = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    let (a, b) = (summary(&whole), summary(&out));
    assert_eq!(a["settled"], b["settled"]);
    assert_eq!(a["settled"]["settled"], true);
    let read = |d: &Path| std::fs::read_to_string(d.join("energy.csv")).unwrap();
    assert_eq!(read(&whole), read(&out));
}

/// A control reference that fails during the run (here `sqrt(0.5 - t)` after t = 0.5 s)
/// stops the run at once with the key, the expression and the time, not by step halving.
#[test]
fn a_failing_control_reference_is_named() {
    let dir = temp_dir("control-expr");
    let text =
        std::fs::read_to_string(crate::workspace_root().join("examples/pd_tip_tracking.toml"))
            .unwrap()
            .replace("\"0.5 + 0.5*sin(0.5*t)\",", "\"0.5*sqrt(0.5 - t)\",");
    let f = dir.join("bad.toml");
    std::fs::write(&f, text).unwrap();
    let o = phstring(&[
        "run",
        f.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
        "-q",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("boundary.1.control.reference"), "{err}");
    assert!(err.contains("sqrt(0.5 - t)"), "{err}");
    let s = summary(&dir.join("out"));
    assert_eq!(s["status"], "failed");
    assert!(s["t_reached"].as_f64().unwrap() <= 0.5 + 1e-9);
    assert_eq!(s["rejected_steps"], 0, "no halving on a failing expression");
}
