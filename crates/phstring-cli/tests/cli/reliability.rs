//! Runtime failures stop with a precise reason and intact outputs; checkpoints,
//! resume and interrupts; determinism; output safety.

use std::path::Path;
use std::process::Command;

use crate::{phstring, temp_dir, workspace_root};

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(&dir.join("summary.json"))).unwrap()
}

/// Runs the paper example with `sets` into a fresh folder; returns (exit code, stderr, dir).
fn run_paper(name: &str, sets: &[&str]) -> (Option<i32>, String, crate::TestDir) {
    let out = temp_dir(name).inside("out");
    let o = crate::run_with("examples/paper_pendulum.toml", &out, sets, &[]);
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
        out,
    )
}

/// A failed run: exit 1, one clear message, `summary.json` says failed with the reason, and
/// `energy.csv` holds every step up to the last good one, each row complete.
fn assert_failed_cleanly(code: Option<i32>, err: &str, out: &Path, expect: &[&str]) -> usize {
    assert_eq!(code, Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expect {
        assert!(err.contains(e), "expected {e:?} in\n{err}");
    }
    let s = summary(out);
    assert_eq!(s["status"], "failed");
    let reason = s["error"].as_str().unwrap();
    for e in expect {
        assert!(
            reason.contains(e),
            "expected {e:?} in summary error {reason}"
        );
    }
    let energy = read(&out.join("energy.csv"));
    let rows: Vec<&str> = energy.lines().skip(1).collect();
    assert_eq!(rows.len(), s["steps"].as_u64().unwrap() as usize + 1);
    for r in &rows {
        assert_eq!(r.split(',').count(), 10, "incomplete row {r}");
        for f in r.split(',') {
            assert!(f.parse::<f64>().unwrap().is_finite(), "{r}");
        }
    }
    rows.len() - 1
}

#[test]
fn coinciding_nodes_are_rejected_before_running() {
    let tmp = temp_dir("coincide");
    let file = tmp.join("c.toml");
    let text = read(&workspace_root().join("examples/paper_pendulum.toml")).replace(
        "[geometry]\nstart = [0.0, 0.0]\nend = [0.7071067811865476, -0.7071067811865476]   # s (√2/2)(1, −1), L = 1 m, C₀ = 1",
        "[geometry]\nnodes = [[0.0, 0.0], [0.5, 0.0], [0.5, 0.0], [1.0, 0.0]]",
    ).replace("[mesh]\nelements = 30\n", "");
    assert!(text.contains("nodes = "));
    std::fs::write(&file, text).unwrap();
    let o = phstring(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        tmp.join("o").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("element 1 has zero initial length (nodes 1 and 2 coincide)"),
        "{err}"
    );
    assert!(!tmp.join("o").join("energy.csv").exists());
}

#[test]
fn load_expression_failure_is_quoted() {
    let (code, err, out) = run_paper("loadexpr", &["boundary.1.force=[\"sqrt(0.1 - t)\", \"0\"]"]);
    let steps = assert_failed_cleanly(
        code,
        &err,
        &out,
        &[
            "\"sqrt(0.1 - t)\"",
            "boundary.1.force",
            "non-finite value in the load",
        ],
    );
    assert_eq!(
        steps, 10,
        "the load fails in the step whose mid time passes 0.1 s"
    );
}

#[test]
fn non_finite_residual_is_reported_with_node() {
    let (code, err, out) = run_paper("inf", &["boundary.1.force=[\"1e300\", \"1e300\"]"]);
    assert_failed_cleanly(
        code,
        &err,
        &out,
        // Finite entries of 1e300 N whose norm overflows, at the loaded end (node 30).
        &["residual's norm (it overflows", "at node 30"],
    );
}

#[test]
fn newton_failure_with_fixed_steps_names_step_time_node_residual() {
    let (code, err, out) = run_paper(
        "newton",
        &[
            "mesh.elements=1000",
            // Without elimination, plain globalized Newton fails on this mesh at h = 0.01.
            "newton.elimination=false",
            "time.adaptive=false",
            "time.end=0.1",
            "output.vtk=false",
        ],
    );
    let steps = assert_failed_cleanly(
        code,
        &err,
        &out,
        &["in step 1 (t = 0 s → 0.01 s)", "residual", "at node"],
    );
    assert_eq!(steps, 0);
}

#[test]
fn exhausted_step_size_control_is_an_error() {
    let (code, err, out) = run_paper(
        "halvings",
        &[
            "mesh.elements=3000",
            "newton.elimination=false",
            "time.max_halvings=1",
            "time.end=0.1",
            "output.vtk=false",
        ],
    );
    assert_failed_cleanly(
        code,
        &err,
        &out,
        &["the step-size floor h = 5.000e-3 s (time.h / 2^1) was reached without convergence"],
    );
}

/// Stop after 137 steps, resume: all outputs equal the uninterrupted run's byte for byte.
/// Then a crash after a checkpoint (files longer than recorded) resumes equally well.
#[test]
fn checkpoint_resume_is_bit_identical() {
    let tmp = temp_dir("resume");
    let (a, b) = (tmp.join("a"), tmp.join("b"));
    let ex = "examples/taut_string.toml";
    let o = phstring(&["run", ex, "--out", a.to_str().unwrap(), "-q"]);
    assert!(o.status.success());
    let o = phstring(&[
        "run",
        ex,
        "--out",
        b.to_str().unwrap(),
        "-q",
        "--stop-after-steps",
        "137",
        "--checkpoint-every",
        "50",
    ]);
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(summary(&b)["status"], "interrupted");
    let cp = b.join("checkpoint.json");
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let files = [
        "energy.csv",
        "positions.csv",
        "ports.csv",
        "paraview/string.pvd",
        "paraview/frame_000250.vtp",
        "paraview/frame_000500.vtp",
        "energy.svg",
        "configuration.svg",
    ];
    for f in files {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
    assert!(!cp.exists(), "a completed run removes its checkpoint");
    assert_eq!(summary(&b)["resumed"], true);
    // Crash simulation: keep the checkpoint of step 200, run on to step 260, then resume
    // from step 200 (the files are longer than the checkpoint recorded).
    let c = tmp.join("c");
    let o = phstring(&[
        "run",
        ex,
        "--out",
        c.to_str().unwrap(),
        "-q",
        "--stop-after-steps",
        "200",
    ]);
    assert_eq!(o.status.code(), Some(130));
    let cp200 = tmp.join("cp200.json");
    std::fs::copy(c.join("checkpoint.json"), &cp200).unwrap();
    let o = phstring(&[
        "run",
        "--resume",
        c.join("checkpoint.json").to_str().unwrap(),
        "-q",
        "--stop-after-steps",
        "260",
    ]);
    assert_eq!(o.status.code(), Some(130));
    std::fs::copy(&cp200, c.join("checkpoint.json")).unwrap();
    let o = phstring(&[
        "run",
        "--resume",
        c.join("checkpoint.json").to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in files {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(c.join(f)).unwrap(),
            "{f}"
        );
    }
}

/// Ctrl-C (SIGINT) stops at the end of a step with outputs flushed and status
/// "interrupted"; the run resumes to the same result as an uninterrupted one.
///
/// The run signals itself after step 40 (hidden `--signal-self-after-step`, which sends a
/// real SIGINT with `kill` and waits until the handler has seen it), so the interruption
/// lands at a known step however fast or busy the machine is (no test depends on wall-clock
/// time).
#[test]
fn interrupt_stops_cleanly_and_resumes() {
    let tmp = temp_dir("sigint");
    let (a, b) = (tmp.join("a"), tmp.join("b"));
    let sets = [
        "--set",
        "mesh.elements=400",
        "--set",
        "time.h=0.001",
        "--set",
        "time.end=0.3",
        "--set",
        "output.vtk=false",
        "--set",
        "output.positions=false",
    ];
    let mut args = vec!["run", "examples/paper_pendulum.toml", "-q", "--out"];
    let o = Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(args.iter().chain([&b.to_str().unwrap()]).chain(sets.iter()))
        .args(["--signal-self-after-step", "40"])
        .current_dir(workspace_root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted at t ="), "{err}");
    let s = summary(&b);
    assert_eq!(s["status"], "interrupted");
    let steps = s["steps"].as_u64().unwrap() as usize;
    assert_eq!(steps, 40);
    assert_eq!(read(&b.join("energy.csv")).lines().count(), steps + 2);
    // Resume, and compare with an uninterrupted run.
    let o = phstring(&[
        "run",
        "--resume",
        b.join("checkpoint.json").to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    args.push(a.to_str().unwrap());
    args.extend(sets);
    let o = phstring(&args);
    assert!(o.status.success());
    for f in ["energy.csv", "ports.csv"] {
        assert_eq!(read(&a.join(f)), read(&b.join(f)), "{f}");
    }
}

/// Same scenario, same bits: two runs give identical outputs (timing aside).
#[test]
fn runs_are_deterministic() {
    let tmp = temp_dir("determinism");
    let mut dirs = Vec::new();
    for k in 0..2 {
        let out = tmp.join(format!("r{k}"));
        let o = phstring(&[
            "run",
            "examples/hoist_3d.toml",
            "--out",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert!(o.status.success());
        dirs.push(out);
    }
    for f in [
        "energy.csv",
        "positions.csv",
        "ports.csv",
        "paraview/string.pvd",
        "paraview/frame_000400.vtp",
        "energy.svg",
        "energy.png",
    ] {
        assert_eq!(
            std::fs::read(dirs[0].join(f)).unwrap(),
            std::fs::read(dirs[1].join(f)).unwrap(),
            "{f}"
        );
    }
}

/// Nothing is written outside `--out`.
#[test]
fn nothing_is_written_outside_out() {
    let tmp = temp_dir("confined");
    let cwd = tmp.join("cwd");
    std::fs::create_dir_all(&cwd).unwrap();
    let scenario = workspace_root().join("examples/axial_rod_1d.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(["run", scenario.to_str().unwrap(), "--out", "inside", "-q"])
        .current_dir(&cwd)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let entries: Vec<String> = std::fs::read_dir(&cwd)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(entries, vec!["inside".to_string()]);
}

/// `--force` removes an earlier run's checkpoint, so that a later `--resume` cannot mix two
/// runs.
#[test]
fn force_removes_a_stale_checkpoint() {
    let out = temp_dir("stale-cp").inside("o");
    let o = phstring(&[
        "run",
        "examples/taut_string.toml",
        "--out",
        out.to_str().unwrap(),
        "-q",
        "--stop-after-steps",
        "5",
    ]);
    assert_eq!(o.status.code(), Some(130));
    assert!(out.join("checkpoint.json").exists());
    // A new run into the same folder that fails at once.
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--out",
        out.to_str().unwrap(),
        "-q",
        "--force",
        "--set",
        "boundary.1.force=[\"1e300\", \"0\"]",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!out.join("checkpoint.json").exists());
}
