//! Hostile input on the command line: output folders (`--force`,
//! symbolic links, locks), signals, unbounded inputs, memory and step budgets, and messages.
//! Each test is named after what it guards. No test depends on timing: waits are for outcomes,
//! with generous limits only as guards against a hang.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::{phstring, temp_dir, wait_or_kill, workspace_root};

const PAPER: &str = "examples/paper_pendulum.toml";

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The binary, not yet started, in the workspace root.
fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_phstring"));
    c.args(args)
        .current_dir(workspace_root())
        .env_remove("RUST_BACKTRACE")
        .env_remove("PHSTRING_MEMORY_AVAILABLE");
    c
}

/// Polls `cond` until it holds (guard: 120 s).
fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    let start = Instant::now();
    while !cond() {
        assert!(start.elapsed() < Duration::from_secs(120), "{what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A run of the paper example into `out` with `extra` arguments.
fn run(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["run", PAPER, "--out", s(out), "-q"];
    args.extend(extra);
    phstring(&args)
}

/// Runs of many small steps (about 2 s in all), long enough to be under way when a signal
/// or a kill comes.
const LONG: &[&str] = &[
    "--set",
    "mesh.elements=4000",
    "--set",
    "time.h=0.0001",
    "--set",
    "time.end=0.3",
    "--set",
    "output.vtk=false",
    "--set",
    "output.positions=false",
];

/// A run that cannot end before a signal comes, however fast the machine (1e7 steps); the
/// tests stop it.
const ENDLESS: &[&str] = &[
    "--set",
    "mesh.elements=4000",
    "--set",
    "time.h=0.0001",
    "--set",
    "time.end=1000",
    "--set",
    "output.vtk=false",
    "--set",
    "output.positions=false",
];

fn energy_rows(out: &Path) -> usize {
    std::fs::read_to_string(out.join("energy.csv")).map_or(0, |s| s.lines().count())
}

fn kill(sig: &str, child: &Child) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

// ---- Output folders ---------------------------------------------------------------------

/// `--force` keeps the user's files: only the exact names phstring writes go
/// (`figure1.png`, `run_1/`, `run_/`, `notes.txt` stay), and the outputs of the earlier run
/// are replaced.
#[test]
fn force_deletes_only_exact_output_names() {
    let out = temp_dir("force-exact").inside("o");
    assert!(run(&out, &["--set", "time.end=0.05"]).status.success());
    let user = [
        "figure1.png",
        "fig9.svg",
        "notes.txt",
        "run_1/energy.csv",
        "run_/energy.csv",
        "run_0001/summary.json",
        "paraview/frame_1.vtp",
        "paraview/mine.vtp",
        "figures/fig2_mine.png",
    ];
    for f in user {
        let p = out.join(f);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, "user data").unwrap();
    }
    // An earlier sweep's run folder and paper figure: phstring's, so they go.
    std::fs::create_dir_all(out.join("run_007/paraview")).unwrap();
    std::fs::write(out.join("run_007/energy.csv"), "old").unwrap();
    std::fs::write(out.join("run_007/paraview/frame_000000.vtp"), "old").unwrap();
    std::fs::create_dir_all(out.join("figures")).unwrap();
    std::fs::write(out.join("figures/fig2_configurations.png"), "old").unwrap();
    let o = run(&out, &["--force", "--set", "time.end=0.02"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in user {
        assert_eq!(
            std::fs::read_to_string(out.join(f)).unwrap(),
            "user data",
            "{f} was touched"
        );
    }
    assert!(!out.join("run_007").exists(), "an emptied run folder goes");
    assert!(!out.join("figures/fig2_configurations.png").exists());
    assert!(out.join("figures/fig2_mine.png").exists());
    // The new run's outputs, not the old ones: 2 steps.
    assert_eq!(energy_rows(&out), 4);
    assert!(!out.join("paraview/frame_000005.vtp").exists());
}

/// `--force` does not follow a symlinked `paraview/` (or `energy.csv`) out of the folder: the
/// link itself is removed, its target is neither cleared nor written to.
#[test]
fn force_does_not_follow_a_symlinked_paraview() {
    let tmp = temp_dir("force-symlink");
    let (out, target) = (tmp.join("o"), tmp.join("elsewhere"));
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&target).unwrap();
    for f in ["string.pvd", "frame_000000.vtp", "energy.csv"] {
        std::fs::write(target.join(f), "precious").unwrap();
    }
    std::os::unix::fs::symlink(&target, out.join("paraview")).unwrap();
    std::os::unix::fs::symlink(target.join("energy.csv"), out.join("energy.csv")).unwrap();
    let o = run(&out, &["--force", "--set", "time.end=0.02"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["string.pvd", "frame_000000.vtp", "energy.csv"] {
        assert_eq!(
            std::fs::read_to_string(target.join(f)).unwrap(),
            "precious",
            "{f}"
        );
    }
    assert_eq!(std::fs::read_dir(&target).unwrap().count(), 3);
    let meta = std::fs::symlink_metadata(out.join("paraview")).unwrap();
    assert!(meta.is_dir() && !meta.file_type().is_symlink());
    assert!(out.join("paraview/frame_000002.vtp").exists());
    assert_eq!(energy_rows(&out), 4);
}

/// Without `--force` either: a resume refuses to write through a link among the
/// run's outputs.
#[test]
fn resume_refuses_to_write_through_a_symlink() {
    let tmp = temp_dir("resume-symlink");
    let (out, target) = (tmp.join("o"), tmp.join("elsewhere"));
    let o = run(&out, &["--stop-after-steps", "3"]);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    std::fs::create_dir_all(&target).unwrap();
    std::fs::remove_dir_all(out.join("paraview")).unwrap();
    std::os::unix::fs::symlink(&target, out.join("paraview")).unwrap();
    let o = phstring(&["run", "--resume", s(&out.join("checkpoint.json")), "-q"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("paraview is a symbolic link"), "{err}");
    assert_eq!(std::fs::read_dir(&target).unwrap().count(), 0);
}

/// `sweep --force` validates the new values before it deletes anything: a bad value is
/// refused and the previous sweep stays as it was.
#[test]
fn sweep_force_validates_before_deleting() {
    let out = temp_dir("sweep-validate").inside("o");
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        "mesh.elements=10,20",
        "--set",
        "time.end=0.02",
        "--out",
        s(&out),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        "mesh.elements=10,abc",
        "--out",
        s(&out),
        "--force",
        "-q",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("invalid type: string \"abc\""), "{err}");
    assert_eq!(
        std::fs::read_to_string(out.join("sweep.csv")).unwrap(),
        table
    );
    assert!(out.join("run_001/energy.csv").exists());
}

/// Concurrent runs cannot write into one folder: a folder whose lock is
/// held (here by the test itself) is refused with a message naming it, and nothing is
/// written; once the lock is free, the leftover lock file blocks nothing.
#[test]
fn concurrent_runs_into_one_folder_are_refused() {
    let out = temp_dir("lock").inside("o");
    std::fs::create_dir_all(&out).unwrap();
    let lock = std::fs::File::create(out.join(".phstring.lock")).unwrap();
    lock.try_lock().unwrap();
    for extra in [&[][..], &["--force"][..]] {
        let o = run(&out, extra);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(&format!(
                "output folder {} is in use by another phstring run",
                out.display()
            )),
            "{err}"
        );
    }
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        "mesh.elements=10",
        "--out",
        s(&out),
        "-q",
    ]);
    assert!(stderr(&o).contains("in use by another phstring run"));
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        1,
        "nothing written"
    );
    drop(lock);
    let o = run(&out, &["--set", "time.end=0.02"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The lock dies with the process, so a killed run does not block the next.
#[test]
fn lock_of_a_killed_run_does_not_block() {
    let out = temp_dir("lock-kill").inside("o");
    let mut args = vec!["run", PAPER, "-q", "--out", s(&out)];
    args.extend(LONG);
    let mut guard = Guard(Some(command(&args).stderr(Stdio::null()).spawn().unwrap()));
    wait_until("the run starts", || energy_rows(&out) > 3);
    kill("-KILL", guard.child());
    wait_or_kill(
        guard.0.take().unwrap(),
        Duration::from_secs(60),
        "killed run",
    );
    let o = run(&out, &["--force", "--set", "time.end=0.02"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

// ---- Signals ----------------------------------------------------------------------------

/// Kills the child when dropped (a failed test leaves no process behind).
struct Guard(Option<Child>);

impl Guard {
    fn child(&mut self) -> &mut Child {
        self.0.as_mut().unwrap()
    }
}

impl Drop for Guard {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// A second signal forces an exit: the first SIGTERM asks the
/// run to stop (here it is blocked reading its scenario from a FIFO, so it cannot), the
/// second exits at once with code 130.
#[test]
fn second_signal_exits_at_once() {
    use std::io::Read;
    let tmp = temp_dir("second-signal");
    let fifo = tmp.join("scenario.toml");
    let ok = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(ok.success());
    // Held open for writing (read-write does not block on Linux), so that the run's open
    // succeeds and its read then waits for data that never comes.
    let _writer = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&fifo)
        .unwrap();
    let mut guard = Guard(Some(
        command(&["run", s(&fifo), "-q", "--out", s(&tmp.join("o"))])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    ));
    // The handler is installed before the scenario is read: once the run holds the FIFO
    // open, it is blocked in the read. Then the first signal.
    let fd_dir = PathBuf::from(format!("/proc/{}/fd", guard.child().id()));
    wait_until("the scenario is opened", || {
        std::fs::read_dir(&fd_dir).is_ok_and(|d| {
            d.flatten()
                .any(|e| std::fs::read_link(e.path()).is_ok_and(|t| t == fifo))
        })
    });
    kill("-TERM", guard.child());
    // The first signal is handled (the note is printed) and the process goes on waiting.
    let mut err = guard.child().stderr.take().unwrap();
    let mut seen = Vec::new();
    let note = b"stopping at the end of the current step";
    wait_until("the first signal is handled", || {
        let mut buf = [0u8; 256];
        let n = err.read(&mut buf).unwrap_or(0);
        seen.extend_from_slice(&buf[..n]);
        seen.windows(note.len()).any(|w| w == note)
    });
    assert!(guard.child().try_wait().unwrap().is_none(), "still blocked");
    kill("-TERM", guard.child());
    let o = wait_or_kill(
        guard.0.take().unwrap(),
        Duration::from_secs(60),
        "second signal",
    );
    assert_eq!(o.status.code(), Some(130));
    err.read_to_end(&mut seen).unwrap();
    let seen = String::from_utf8_lossy(&seen);
    assert!(seen.contains("second interrupt: exiting at once"), "{seen}");
}

/// SIGTERM stops a run like Ctrl-C, with a checkpoint and code 130.
#[test]
fn sigterm_stops_a_run_cleanly() {
    let out = temp_dir("sigterm").inside("o");
    let mut args = vec!["run", PAPER, "-q", "--out", s(&out)];
    args.extend(ENDLESS);
    let mut guard = Guard(Some(command(&args).stderr(Stdio::piped()).spawn().unwrap()));
    wait_until("the run starts", || energy_rows(&out) > 3);
    kill("-TERM", guard.child());
    let o = wait_or_kill(guard.0.take().unwrap(), Duration::from_secs(120), "SIGTERM");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted at t ="), "{err}");
    assert!(out.join("checkpoint.json").exists());
}

// ---- Unbounded inputs -------------------------------------------------------------------

/// `phstring check /dev/zero` is refused as larger than 16 MiB instead of read forever.
#[test]
fn scenario_from_dev_zero_is_refused() {
    let child = command(&["check", "/dev/zero"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let o = wait_or_kill(child, Duration::from_secs(120), "check /dev/zero");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("scenario file /dev/zero is larger than 16 MiB"),
        "{err}"
    );
}

/// Deep `--set` keys cannot cost quadratic time and memory: a key of 4000 segments is
/// refused by its length (clipped in the message), one of 40 by its depth (at most 32), and
/// within the caps a new nested table costs one header line.
#[test]
fn deep_set_key_is_refused() {
    let key = vec!["a"; 4000].join(".");
    let o = phstring(&["check", PAPER, "--set", &format!("{key}=1")]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("the key is 7999 bytes long"), "{err}");
    assert!(err.len() < 600, "the key is clipped: {err}");
    let key = vec!["a"; 40].join(".");
    let o = phstring(&["check", PAPER, "--set", &format!("{key}=1")]);
    assert!(stderr(&o).contains("the key has 40 segments; scenario keys have at most 32"));
    // Within the caps a new nested table costs one header line, not one per level.
    let key = vec!["a"; 30].join(".");
    let o = phstring(&["check", PAPER, "--set", &format!("{key}=1")]);
    let err = stderr(&o);
    assert!(err.contains("unknown field `a`"), "{err}");
}

/// A sweep of 6.55e12 runs is refused with its count, before any combination is made (making
/// them all first would abort on allocation).
#[test]
fn huge_sweep_is_refused_with_its_count() {
    let values = (0..40).map(|i| i.to_string()).collect::<Vec<_>>().join(",");
    let mut args = vec!["sweep".to_string(), PAPER.to_string()];
    for k in 0..8 {
        args.push("--vary".into());
        args.push(format!("title{k}={values}"));
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = phstring(&args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("the sweep has 6.55e12 runs") && err.contains("at most 100000"),
        "{err}"
    );
}

/// `--jobs` is capped, so that `--jobs 100000` cannot spawn threads until the machine stalls.
#[test]
fn jobs_are_capped() {
    let out = temp_dir("jobs").inside("o");
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        "mesh.elements=10",
        "--jobs",
        "100000",
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--jobs 100000: at most"), "{err}");
    assert!(!out.exists());
}

// ---- Memory and steps -------------------------------------------------------------------

/// A run that does not fit in memory is refused: `check` shows the
/// estimate and warns, `run` refuses before it allocates anything; a sweep counts its
/// parallel runs. The machine's memory is set with PHSTRING_MEMORY_AVAILABLE.
#[test]
fn run_that_does_not_fit_in_memory_is_refused() {
    let out = temp_dir("memory").inside("o");
    let o = command(&["check", PAPER, "--set", "mesh.elements=1000000"])
        .env("PHSTRING_MEMORY_AVAILABLE", "1e8")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // About 1.1 GB (the library's estimate plus the outputs' measured share).
    let out_text = stdout(&o);
    assert!(
        out_text.contains("estimate:  1.1 GB of memory"),
        "{out_text}"
    );
    let err = stderr(&o);
    assert!(
        err.contains("warning: 1000000 elements in 2D need about ")
            && err.contains("of memory, but only 100 MB is available on this machine"),
        "{err}"
    );
    let o = command(&[
        "run",
        PAPER,
        "--set",
        "mesh.elements=1000000",
        "--out",
        s(&out),
    ])
    .env("PHSTRING_MEMORY_AVAILABLE", "1e8")
    .output()
    .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("use fewer elements"), "{}", stderr(&o));
    assert!(!out.exists());
    // Two runs of 1e5 elements (about 0.1 GB each) fit alone, not both at once.
    let o = command(&[
        "sweep",
        PAPER,
        "--vary",
        "time.scheme=dg,mp",
        "--set",
        "mesh.elements=100000",
        "--jobs",
        "2",
        "--out",
        s(&out),
    ])
    .env("PHSTRING_MEMORY_AVAILABLE", "1.5e8")
    .output()
    .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("run 0 of the sweep"), "{err}");
    assert!(
        err.contains("(2 runs at once; fewer --jobs also help)"),
        "{err}"
    );
    assert!(!out.exists());
}

/// Runs of too many steps: `check` warns above 1e9 planned
/// steps, and validation (so `run` and `check`) refuses more than 1e10.
#[test]
fn runs_of_too_many_steps_are_warned_about_and_refused() {
    let o = phstring(&["check", PAPER, "--set", "time.h=1e-10"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: 1.00e10 planned steps"),
        "{}",
        stderr(&o)
    );
    let o = phstring(&["check", PAPER, "--set", "time.h=1e-9"]);
    assert!(!stderr(&o).contains("planned steps"), "{}", stderr(&o));
    let o = phstring(&["check", PAPER, "--set", "time.h=1e-12"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("gives 1.00e12 steps"), "{err}");
    assert!(
        err.contains("use a larger time.h or a shorter time.end"),
        "{err}"
    );
}

// ---- Messages and options ---------------------------------------------------------------

/// A full stderr or stdout (`2>/dev/full`) does not make phstring panic (`eprintln!` would,
/// with exit code 101): the exit code stays the command's own.
#[test]
fn full_stderr_does_not_panic() {
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let o = command(&["check", "missing.toml"])
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let o = command(&["check", PAPER, "--set", "time.h=1e-10"])
        .stdout(full())
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let out = temp_dir("full").inside("o");
    let o = command(&["run", PAPER, "--out", s(&out), "--set", "time.end=0.02"])
        .stdout(full())
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
}

/// An error's cause is printed once, also for a missing checkpoint and an output folder that
/// cannot be made.
#[test]
fn error_causes_are_printed_once() {
    let o = phstring(&["check", "missing.toml"]);
    let err = stderr(&o);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    // CheckpointError::Io both prints and chains its cause: still once.
    let o = phstring(&["run", "--resume", "/nonexistent/checkpoint.json"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    let o = phstring(&["run", PAPER, "--out", "/dev/null/o"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

/// Floats in messages are short (never printed with `{}`, which shows 300-digit decimals).
#[test]
fn floats_in_messages_are_short() {
    for set in ["time.h=5e-324", "material.ea=-5e-324", "time.end=1e300"] {
        let o = phstring(&["check", PAPER, "--set", set]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.len() < 300, "{err}");
    }
    let o = phstring(&["check", PAPER, "--set", "time.h=5e-324"]);
    assert!(stderr(&o).contains("`time.h` = 5e-324 gives too many steps"));
    let o = phstring(&["check", PAPER, "--set", "geometry.length=1e300"]);
    let text = stdout(&o) + &stderr(&o);
    assert!(text.lines().all(|l| l.len() < 300), "{text}");
}

/// Error messages do not echo 10 MB expressions: user text in messages is cut at about
/// 200 bytes with its length.
#[test]
fn long_user_text_is_clipped_in_messages() {
    let tmp = temp_dir("clip");
    let long = format!("t + {}", "1 +".repeat(1_000_000));
    let text = std::fs::read_to_string(workspace_root().join(PAPER))
        .unwrap()
        .replace(
            "force = [\"sin(pi*t/0.2) * (t <= 0.2)\", \"sin(pi*t/0.2) * (t <= 0.2)\"]",
            &format!("force = [\"{long}\", \"0\"]"),
        );
    assert!(text.contains(&long));
    let file = tmp.join("long.toml");
    std::fs::write(&file, text).unwrap();
    let o = phstring(&["check", s(&file)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{}", &err[..err.len().min(2000)]);
    assert!(err.len() < 2000, "{} bytes of error", err.len());
    assert!(err.contains("… (3000004 bytes)"), "{err}");
    // A long `--set` value (the longest argument Linux passes is 128 KiB).
    let value = "x".repeat(100_000);
    let o = phstring(&["check", PAPER, "--set", &format!("material.law={value}")]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.len() < 2000, "{} bytes of error", err.len());
}

/// A `--set` value with a line break that would end it is refused (the text after it is never
/// silently dropped); one TOML value over several lines is accepted.
#[test]
fn set_value_with_a_newline_is_refused() {
    let o = phstring(&["check", PAPER, "--set", "time.h=0.01\ntime.end=5"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--set time.h=0.01\\ntime.end=5: the value has a line break"),
        "{err}"
    );
    // One TOML value over several lines is fine.
    let o = phstring(&[
        "check",
        PAPER,
        "--set",
        "body_force.gravity=[\n  0.0,\n  -1.62,\n]",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("body force: [0, -1.62] N/m"));
}

/// `--vary` keeps `\"` inside quoted values, refuses an unbalanced quote with its position,
/// and refuses a key varied twice or also given with `--set` (no duplicate columns).
#[test]
fn vary_quotes_escapes_and_duplicate_keys() {
    let out = temp_dir("vary").inside("o");
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        r#"title="a \",b","c""#,
        "--set",
        "time.end=0.02",
        "--out",
        s(&out),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(table.lines().count(), 3, "{table}");
    assert!(table.contains(r#","""a \"",b""","#), "{table}");
    let o = phstring(&["sweep", PAPER, "--vary", r#"title="a,b"#]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("the quote \" at character 7 is not closed"),
        "{err}"
    );
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        "mesh.elements=10,20",
        "--vary",
        "mesh.elements=30",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("the key is varied twice"), "{err}");
    let o = phstring(&[
        "sweep",
        PAPER,
        "--vary",
        "mesh.elements=10,20",
        "--set",
        "mesh.elements=30",
    ]);
    assert!(stderr(&o).contains("also given with --set mesh.elements=30"));
}

/// Control characters in titles are escaped on the terminal.
#[test]
fn control_characters_in_titles_are_escaped_on_the_terminal() {
    let tmp = temp_dir("control");
    let text = std::fs::read_to_string(workspace_root().join(PAPER))
        .unwrap()
        .replace(
            "title = \"String pendulum (paper, Section 4)\"",
            "title = \"a\\u001b[2J\\u0007b\\u0000c\\r\\nd\"",
        );
    assert!(text.contains("\\u001b"));
    let file = tmp.join("t.toml");
    std::fs::write(&file, text).unwrap();
    let o = phstring(&["check", s(&file)]);
    let out = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !out.bytes().any(|b| b < 0x20 && b != b'\n'),
        "control bytes in {out:?}"
    );
    assert!(
        out.contains(r"title:     a\u{1b}[2J\u{7}b\u{0}c\r\nd"),
        "{out}"
    );
    let o = phstring(&["check", s(&file), "--set", "material.law=\u{1b}[31mred"]);
    let err = stderr(&o);
    assert!(!err.contains('\u{1b}'), "{err:?}");
}

/// An overflowing length is reported as such, not as coinciding nodes.
#[test]
fn overflowing_length_is_not_reported_as_coinciding_nodes() {
    let o = phstring(&[
        "check",
        PAPER,
        "--set",
        "geometry.start=[-1e308, 0.0]",
        "--set",
        "geometry.end=[1e308, 0.0]",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("coincide"), "{err}");
    assert!(
        err.contains("the distance from start to end overflows"),
        "{err}"
    );
    // Finite nodes whose distance overflows.
    let tmp = temp_dir("overflow");
    let file = tmp.join("n.toml");
    let text = std::fs::read_to_string(workspace_root().join(PAPER))
        .unwrap()
        .replace(
            "start = [0.0, 0.0]\nend = [0.7071067811865476, -0.7071067811865476]",
            "nodes = [[0.0, 0.0], [1.7e308, 0.0], [-1.7e308, 0.0]]",
        )
        .replace("[mesh]\nelements = 30\n", "");
    assert!(text.contains("nodes = "));
    std::fs::write(&file, text).unwrap();
    let o = phstring(&["check", s(&file)]);
    let err = stderr(&o);
    // Element 0 is 1.7e308 m long (its squared length overflows, but it is measured without
    // squaring); element 1 spans 3.4e308 m, which overflows.
    assert!(
        err.contains("the length of element 1 (nodes 1 to 2) overflows"),
        "{err}"
    );
}

/// Boundary entries are addressed by index in `--set`: negative indices count from the end,
/// and a non-index says how entries are named (not that `boundary` is not a table).
#[test]
fn boundary_entries_are_addressed_by_index() {
    let o = phstring(&["check", PAPER, "--set", "boundary.-1.node=5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("force:     node 5:"), "{}", stdout(&o));
    let o = phstring(&["check", PAPER, "--set", "boundary.-1.node=99"]);
    assert!(
        stderr(&o).contains("--set boundary.-1.node=99: `boundary.1.node` = 99 is out of range"),
        "{}",
        stderr(&o)
    );
    let o = phstring(&["check", PAPER, "--set", "boundary.last.node=5"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("`boundary` is an array of tables: address an entry by its 0-based index, e.g. boundary.0.node"),
        "{err}"
    );
    let o = phstring(&["check", PAPER, "--set", "boundary.-3.node=5"]);
    assert!(stderr(&o).contains("index -3 out of range (2 entries)"));
}

/// Options that would do nothing (`--checkpoint-every 0`, `--jobs 0`, `--resume` with
/// `--force`) are refused, not accepted silently.
#[test]
fn no_op_options_are_refused() {
    for args in [
        &["run", PAPER, "--checkpoint-every", "0"][..],
        &["sweep", PAPER, "--vary", "mesh.elements=10", "--jobs", "0"][..],
        &["run", "--resume", "x/checkpoint.json", "--force"][..],
    ] {
        let o = phstring(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("must be at least 1") || err.contains("cannot be used with"),
            "{err}"
        );
    }
}
