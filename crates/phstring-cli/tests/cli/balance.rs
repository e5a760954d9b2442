//! The energy balance as the acceptance test: a control gain or an initial velocity far beyond
//! the structure's own forces ends with a balance at round-off, a refusal at validation or a
//! failure that names the balance, never with "completed" and a broken balance.

use crate::{phstring, summary, temp_dir};

/// What a run of the scan came to.
#[derive(Debug, PartialEq)]
enum Outcome {
    /// Completed, with the largest relative balance error of a step.
    Completed(f64),
    /// Refused before the first step (the gain cannot be resolved).
    Refused,
    /// Failed at a step whose balance (or solve) could not be resolved.
    Failed,
}

/// Runs `scenario` with `sets`; checks that a completed run kept every step's balance within
/// the bound and that a refusal or failure says why.
fn outcome(scenario: &str, name: &str, sets: &[String]) -> Outcome {
    let out = temp_dir(name);
    let mut args = vec!["run", scenario, "--out", out.to_str().unwrap(), "-q"];
    for s in sets {
        args.extend(["--set", s.as_str()]);
    }
    let o = phstring(&args);
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    if o.status.success() {
        let s = summary(&out);
        let (rel, bound) = (
            s["max_relative_balance_error"].as_f64().unwrap(),
            s["balance_bound"].as_f64().unwrap(),
        );
        assert_eq!(bound, 1e-11);
        assert!(
            rel <= bound,
            "{name}: completed with a step's balance error {rel:e} of its energy scale (bound {bound:e})"
        );
        return Outcome::Completed(rel);
    }
    if stderr.contains("beyond what double precision") || stderr.contains("feedback port at node") {
        assert!(
            !out.join("energy.csv").exists(),
            "{name}: refused, but wrote energy.csv"
        );
        return Outcome::Refused;
    }
    assert!(
        stderr.contains("energy balance of the step is off by")
            || stderr.contains("step-size floor"),
        "{name}: failed without naming the cause: {stderr}"
    );
    Outcome::Failed
}

/// `kp` from 1e13 to 1e30 N/m on the damping-injection payload (EA = 1e7 N, 0.5 m elements,
/// 200 kg): a gain the rope can resolve runs with its balance at round-off; beyond
/// `(EA/l)/ε ≈ 9e22 N/m` it is refused before the run; in between, a run may fail, naming the
/// balance, but never completes with it broken.
#[test]
fn absurd_gains_end_in_a_balance_at_roundoff_or_a_clear_refusal() {
    let mut seen = Vec::new();
    for kp in [1e13, 1e15, 1e17, 1e20, 1e25, 1e30] {
        let sets = [
            "time.end=2".to_string(),
            format!(
                "boundary.1.control={{ kp = {kp:e}, kd = {kp:e}, reference = [\"3.42\", \"-9.39\"] }}"
            ),
        ];
        let o = outcome(
            "examples/damping_injection.toml",
            &format!("kp{kp:e}"),
            &sets,
        );
        eprintln!("kp = kd = {kp:e}: {o:?}");
        seen.push(o);
    }
    assert!(
        matches!(seen[0], Outcome::Completed(_)),
        "kp = 1e13 must run: {:?}",
        seen[0]
    );
    assert_eq!(seen[4], Outcome::Refused, "kp = 1e25 must be refused");
    assert_eq!(seen[5], Outcome::Refused, "kp = 1e30 must be refused");
}

/// Initial velocities from 1e4 to 1e10 m/s on the taut string: every run completes with each
/// step's balance at round-off or fails naming the balance.
#[test]
fn absurd_initial_velocities_end_in_a_balance_at_roundoff_or_a_clear_failure() {
    let mut seen = Vec::new();
    for v in [1e4, 1e6, 1e8, 1e10] {
        let sets = [
            "time.end=0.1".to_string(),
            format!("initial.velocity=[\"0\", \"{v:e}*sin(pi*s/L)\"]"),
        ];
        let o = outcome("examples/taut_string.toml", &format!("v{v:e}"), &sets);
        eprintln!("v = {v:e} m/s: {o:?}");
        assert_ne!(o, Outcome::Refused);
        seen.push(o);
    }
    assert!(
        matches!(seen[0], Outcome::Completed(_)),
        "1e4 m/s must run: {:?}",
        seen[0]
    );
}
