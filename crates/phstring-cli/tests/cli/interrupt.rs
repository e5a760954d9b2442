//! One Ctrl-C (SIGINT) ends every long phase of every command promptly with the interrupted
//! exit (code 130 and a message that says what was written), and leaves no output that
//! claims to be complete: the equilibrium solve of `statics` and of a run's
//! `initial.equilibrium`, the eigensolver of `modes` and `linearize --modes`, and the runs of
//! a `sweep`. (The time loop of `run` is covered in `reliability.rs`.)
//!
//! Each command signals itself with the hidden `--signal-self-after-ms` (a real SIGINT,
//! sent with `kill` once the command's handler is installed) on a problem whose phase takes
//! minutes without the signal (measured: the statics of the 20000-element slack wire
//! 260 s, the 2000 modes of the 20000-element taut string more than 200 s); wherever the
//! signal lands, the command must end. The limit on the wait is a guard against a hang, far
//! above the tenth of a second the stop takes.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use crate::{temp_dir, wait_or_kill, workspace_root};

/// Runs the binary with `args` plus `--signal-self-after-ms 1500`; fails if it has not ended
/// after `GUARD`.
fn signalled(args: &[&str]) -> Output {
    const GUARD: Duration = Duration::from_secs(60);
    let child = Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(args)
        .args(["-q", "--signal-self-after-ms", "1500"])
        .current_dir(workspace_root())
        .env_remove("RUST_BACKTRACE")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_or_kill(child, GUARD, &format!("{args:?} after a SIGINT"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The entries of `dir` other than the lock file, sorted.
fn written(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != ".phstring.lock")
        .collect();
    names.sort();
    names
}

/// `command` on `example` refined to 20000 elements, with `extra` arguments, into a fresh
/// folder `name`/o, signalled as [`signalled`]: the output and that folder.
fn signalled_large(
    name: &str,
    command: &str,
    example: &str,
    extra: &[&str],
) -> (Output, crate::TestDir) {
    let out = temp_dir(name).inside("o");
    let mut args = vec![command, example, "--set", "mesh.elements=20000"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out.to_str().unwrap()]);
    (signalled(&args), out)
}

/// The interrupted exit: code 130, the handler's note, and `message` after `error: `.
fn assert_interrupted(o: &Output, message: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("stopping at the end of the current step"),
        "{err}"
    );
    assert!(err.contains(&format!("error: {message}")), "{err}");
}

#[test]
fn statics_stops_at_one_signal_and_writes_nothing() {
    let (o, out) = signalled_large(
        "interrupt-statics",
        "statics",
        "examples/slack_wire.toml",
        &[],
    );
    assert_interrupted(
        &o,
        "interrupted before the equilibrium was found; nothing was written",
    );
    assert_eq!(written(&out), Vec::<String>::new());
}

#[test]
fn run_stops_in_its_starting_equilibrium_and_writes_nothing() {
    let (o, out) = signalled_large(
        "interrupt-run-equilibrium",
        "run",
        "examples/slack_wire.toml",
        &[],
    );
    assert_interrupted(
        &o,
        "interrupted while finding the starting equilibrium (initial.equilibrium); no step was run and nothing was written",
    );
    assert_eq!(written(&out), Vec::<String>::new());
}

#[test]
fn modes_stops_in_lanczos_and_writes_no_summary() {
    let (o, out) = signalled_large(
        "interrupt-modes",
        "modes",
        "examples/taut_string.toml",
        &["--count", "2000"],
    );
    assert_interrupted(&o, "interrupted before the modes were written; ");
    assert!(stderr(&o).contains("no modes.csv or summary.json was written to"));
    let names = written(&out);
    assert!(
        !names
            .iter()
            .any(|n| n == "summary.json" || n == "modes.csv" || n == "modes.pvd"),
        "{names:?}"
    );
}

#[test]
fn linearize_stops_in_the_modal_form_and_writes_nothing() {
    let (o, out) = signalled_large(
        "interrupt-linearize",
        "linearize",
        "examples/taut_string.toml",
        &["--modes", "2000"],
    );
    assert_interrupted(
        &o,
        "interrupted before the model was written; nothing was written",
    );
    assert_eq!(written(&out), Vec::<String>::new());
}

/// The runs under way stop with a checkpoint (status `interrupted`, resumable), the others
/// do not start; `sweep.csv` marks every run `interrupted`.
#[test]
fn sweep_stops_its_runs_and_marks_them_interrupted() {
    let out = temp_dir("interrupt-sweep").inside("o");
    let o = signalled(&[
        "sweep",
        "examples/paper_pendulum.toml",
        "--vary",
        "mesh.elements=4000,3000,2000",
        "--set",
        "time.h=0.0001",
        "--set",
        "time.end=1000",
        "--set",
        "output.vtk=false",
        "--set",
        "output.positions=false",
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_interrupted(
        &o,
        "interrupted: 0 of 3 runs completed, 3 interrupted or not started",
    );
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let rows: Vec<&str> = table.lines().skip(1).collect();
    assert_eq!(rows.len(), 3, "{table}");
    for row in &rows {
        assert!(row.contains(",interrupted,"), "{table}");
    }
    // A run that was under way can be resumed; one that had not started has no folder.
    for (k, row) in rows.iter().enumerate() {
        let dir = out.join(format!("run_{k:03}"));
        if row.contains("not started") {
            assert!(!dir.exists(), "{table}");
        } else {
            assert!(dir.join("checkpoint.json").exists(), "{table}");
            let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
            assert!(summary.contains("\"status\": \"interrupted\""), "{summary}");
        }
    }
    assert!(rows.iter().any(|r| !r.contains("not started")), "{table}");
}
