//! Hostile input at the output layer: plots with extreme data, damaged and foreign checkpoints,
//! non-finite values, bounded checkpoints, flushing and stop requests, failed writes,
//! stale temporary files, control characters.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use phstring_io::checkpoint::CheckpointFile;
use phstring_io::drive::run::{self, Progress, RunError, RunOptions};
use phstring_io::files;
use phstring_io::scenario;

use crate::{phstring, temp_dir, workspace_root};

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(&dir.join("summary.json"))).unwrap()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `phstring run ARGS -q --out OUT`.
fn run(out: &Path, args: &[&str]) -> std::process::Output {
    let mut a = vec!["run"];
    a.extend_from_slice(args);
    a.extend_from_slice(&["-q", "--out", out.to_str().unwrap()]);
    phstring(&a)
}

/// An interrupted taut-string run (20 of 500 steps) with its checkpoint.
fn interrupted_run(out: &Path) -> PathBuf {
    let o = run(
        out,
        &["examples/taut_string.toml", "--stop-after-steps", "20"],
    );
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    out.join("checkpoint.json")
}

/// `phstring run --resume CP -q`.
fn resume(cp: &Path) -> std::process::Output {
    phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"])
}

/// Asserts a clean refusal: exit 1, no panic, `expect` in the message.
fn assert_refused(o: &std::process::Output, expect: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(expect), "expected {expect:?} in\n{err}");
}

/// Every file under `dir` (recursively).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files(&p));
        } else {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// No NaN or infinity in any data file of `dir`.
fn assert_no_non_finite(dir: &Path) {
    for f in files(dir) {
        let ext = f.extension().map(|e| e.to_string_lossy().into_owned());
        // (.vtp frames are base64: checked where they are written, in vtk.rs.)
        if matches!(ext.as_deref(), Some("csv" | "pvd")) {
            let text = read(&f).to_lowercase();
            assert!(
                !text.contains("nan") && !text.contains("inf"),
                "{} holds a non-finite value",
                f.display()
            );
        }
    }
}

/// Plot hang: a string at x = 1e308, whose configuration plot would loop forever, is either
/// refused at validation or ends with a summary, the degenerate plot skipped with a warning.
#[test]
fn plot_hang_extreme_geometry_ends_with_a_summary() {
    let out = temp_dir("hang").inside("o");
    let o = run(
        &out,
        &[
            "examples/paper_pendulum.toml",
            "--set",
            "geometry.start=[1e308, 0.0]",
            "--set",
            "geometry.end=[1e308, -1.0]",
        ],
    );
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    if out.join("summary.json").exists() {
        let s = summary(&out);
        let plots: Vec<&str> = s["plots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p.as_str().unwrap())
            .collect();
        assert!(!plots.contains(&"configuration"), "{s}");
        if o.status.success() {
            let warnings = s["warnings"].to_string();
            assert!(warnings.contains("configuration plot skipped"), "{s}");
        }
    } else {
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    }
    assert_no_non_finite(&out);
}

/// Edits `cp`'s JSON with `edit` and writes it back as text (the checksum is not updated).
fn edit_json(cp: &Path, to: &Path, edit: impl Fn(&mut serde_json::Value)) {
    let mut v: serde_json::Value = serde_json::from_str(&read(cp)).unwrap();
    edit(&mut v);
    std::fs::write(to, serde_json::to_string(&v).unwrap()).unwrap();
}

/// Edits `cp` with `edit` and writes it with phstring's own writer, so that its checksum
/// is right: a valid file with wrong content.
fn edit_valid(cp: &Path, to: &Path, edit: impl Fn(&mut CheckpointFile)) {
    let mut c = CheckpointFile::read(cp).unwrap();
    edit(&mut c);
    c.write(to).unwrap();
}

/// A damaged checkpoint is refused, not a panic: with one number removed from `sim.r`,
/// `sim.v`, `sim.acc`, `sim.v_mid` or `sim.c`, the resume is refused by the checksum, and with
/// a right checksum by the lengths checked against the scenario.
#[test]
fn damaged_checkpoint_is_refused_not_panicking() {
    let out = temp_dir("damaged").inside("o");
    let cp = interrupted_run(&out);
    let original = read(&cp);
    let bad = out.join("checkpoint.json");
    for field in ["r", "v", "acc", "v_mid", "c"] {
        // As text: the checksum no longer matches.
        edit_json(&cp, &bad, |v| {
            v["sim"][field].as_array_mut().unwrap().pop();
        });
        assert_refused(&resume(&bad), "checksum mismatch");
        std::fs::write(&cp, &original).unwrap();
        // With a right checksum: the lengths are checked against the scenario.
        edit_valid(&cp, &bad, |c| {
            let a = match field {
                "r" => &mut c.sim.r,
                "v" => &mut c.sim.v,
                "acc" => &mut c.sim.acc,
                "v_mid" => &mut c.sim.v_mid,
                _ => &mut c.sim.c,
            };
            a.pop();
        });
        assert_refused(&resume(&bad), &format!("sim.{field} has"));
        std::fs::write(&cp, &original).unwrap();
    }
    // Not JSON at all, truncated, or empty.
    std::fs::write(&bad, &original[..original.len() / 2]).unwrap();
    assert_refused(&resume(&bad), "not a phstring checkpoint");
    std::fs::write(&bad, "").unwrap();
    assert_refused(&resume(&bad), "not a phstring checkpoint");
    std::fs::write(&cp, &original).unwrap();
    // The untouched checkpoint still resumes: the refusals changed nothing.
    let o = resume(&cp);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(summary(&out)["status"], "completed");
}

/// Edited checkpoint numbers are not accepted silently: `h_cur = 1e300`, a negative
/// `t_base`, huge `steps`, `energy_bytes = 0`, an edited `scenario_text` are refused, both as
/// a text edit (checksum) and as a valid file with wrong content (range checks).
#[test]
fn edited_checkpoint_numbers_are_refused() {
    let out = temp_dir("edited").inside("o");
    let cp = interrupted_run(&out);
    let original = read(&cp);
    let bad = out.join("checkpoint.json");
    type Edit = (
        &'static str,
        fn(&mut serde_json::Value),
        fn(&mut CheckpointFile),
        &'static str,
    );
    let edits: [Edit; 9] = [
        (
            "h_cur",
            |v| v["sim"]["h_cur"] = 1e300.into(),
            |c| c.sim.h_cur = 1e300,
            "sim.h_cur",
        ),
        (
            "t_base",
            |v| v["sim"]["t_base"] = (-1.0).into(),
            |c| c.sim.t_base = -1.0,
            "sim.t_base",
        ),
        (
            "steps",
            |v| v["sim"]["steps"] = 1_000_000_000_000u64.into(),
            |c| {
                c.sim.steps = 1_000_000_000_000;
                c.counters.steps = 1_000_000_000_000;
            },
            "sim.steps",
        ),
        (
            "k",
            |v| v["sim"]["k"] = 1_000_000_000_000u64.into(),
            |c| c.sim.k = 1_000_000_000_000,
            "beyond time.end",
        ),
        (
            "energy_bytes",
            |v| v["outputs"]["energy_bytes"] = 0.into(),
            |c| c.outputs.energy_bytes = 0,
            "outputs.energy_bytes",
        ),
        (
            "energy_bytes mid-row",
            |v| v["outputs"]["energy_bytes"] = 1000.into(),
            |c| c.outputs.energy_bytes = 1000,
            "does not end a row",
        ),
        (
            "scenario_text",
            |v| {
                let t = v["scenario_text"]
                    .as_str()
                    .unwrap()
                    .replace("elements = 40", "elements = 41");
                v["scenario_text"] = t.into();
            },
            |c| c.scenario_text = c.scenario_text.replace("elements = 40", "elements = 41"),
            "sim.r has",
        ),
        (
            "strain",
            |v| v["sim"]["c"][3] = 2.5.into(),
            |c| c.sim.c.truncate(3),
            "sim.c has 3 numbers",
        ),
        (
            "max_balance_error",
            |v| v["counters"]["max_balance_error"] = (-1.0).into(),
            |c| c.counters.max_balance_error = -1.0,
            "counters.max_balance_error",
        ),
    ];
    for (name, text_edit, valid_edit, message) in edits {
        edit_json(&cp, &bad, text_edit);
        let o = resume(&bad);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(
            err.contains("checksum mismatch") || err.contains("not a phstring checkpoint"),
            "{name}: {err}"
        );
        std::fs::write(&cp, &original).unwrap();
        edit_valid(&cp, &bad, valid_edit);
        let o = resume(&bad);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert!(
            err.contains(message),
            "{name}: expected {message:?} in\n{err}"
        );
        std::fs::write(&cp, &original).unwrap();
    }
    // A checkpoint with a non-finite value is never written.
    let mut c = CheckpointFile::read(&cp).unwrap();
    c.sim.v[5] = f64::NAN;
    let e = c.write(&bad).unwrap_err().to_string();
    assert!(e.contains("non-finite"), "{e}");
    assert_eq!(read(&cp), original);
    assert!(resume(&cp).status.success());
    // A strain outside the material's domain (the paper's law needs C > 0).
    let out = temp_dir("edited-domain").inside("o");
    let o = run(
        &out,
        &["examples/paper_pendulum.toml", "--stop-after-steps", "5"],
    );
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let cp = out.join("checkpoint.json");
    edit_valid(&cp.clone(), &cp, |c| c.sim.c[3] = -0.5);
    assert_refused(
        &resume(&cp),
        "sim.c[3] = -5e-1 is outside the material's domain",
    );
}

/// Bounded inputs: `--resume /dev/zero` is refused instead of read forever, and a huge file
/// or a folder is refused before it is read.
#[test]
fn resume_from_dev_zero_or_a_huge_file_is_refused() {
    if Path::new("/dev/zero").exists() {
        assert_refused(
            &phstring(&["run", "--resume", "/dev/zero", "-q"]),
            "not a phstring checkpoint",
        );
    }
    let dir = temp_dir("hugecp");
    let huge = dir.join("checkpoint.json");
    let f = std::fs::File::create(&huge).unwrap();
    // Sparse: no disk space is used.
    f.set_len(phstring_io::checkpoint::MAX_CHECKPOINT_BYTES + 1)
        .unwrap();
    assert_refused(
        &phstring(&["run", "--resume", huge.to_str().unwrap(), "-q"]),
        "more than a checkpoint can be",
    );
    assert_refused(
        &phstring(&["run", "--resume", dir.to_str().unwrap(), "-q"]),
        "checkpoint",
    );
}

/// `--resume A/checkpoint.json --out B` would overwrite another run: it is refused, naming
/// both folders, and B is left as it was.
#[test]
fn resume_into_another_run_folder_is_refused() {
    let tmp = temp_dir("otherrun");
    let (a, b, c) = (tmp.join("a"), tmp.join("b"), tmp.join("c"));
    let cp = interrupted_run(&a);
    let o = run(&b, &["examples/axial_rod_1d.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before: Vec<(PathBuf, Vec<u8>)> = files(&b)
        .into_iter()
        .map(|f| {
            let bytes = std::fs::read(&f).unwrap();
            (f, bytes)
        })
        .collect();
    let o = phstring(&[
        "run",
        "--resume",
        cp.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
        "-q",
    ]);
    assert_refused(&o, "holds another run");
    let err = stderr(&o);
    assert!(err.contains(a.to_str().unwrap()), "{err}");
    assert!(err.contains(b.to_str().unwrap()), "{err}");
    for (f, bytes) in &before {
        assert_eq!(&std::fs::read(f).unwrap(), bytes, "{} changed", f.display());
    }
    assert_eq!(files(&b).len(), before.len());
    // A folder without a run, too.
    std::fs::create_dir_all(&c).unwrap();
    let o = phstring(&[
        "run",
        "--resume",
        cp.to_str().unwrap(),
        "--out",
        c.to_str().unwrap(),
        "-q",
    ]);
    assert_refused(&o, "holds no phstring run");
    // (A lock file may be there: hidden bookkeeping, no output.)
    assert!(
        files(&c)
            .iter()
            .all(|f| f.file_name().unwrap().to_string_lossy().starts_with('.')),
        "{:?}",
        files(&c)
    );
    // The run id is in the folder, in summary.json and in the checkpoint.
    let id = read(&a.join(files::RUN_ID_FILE)).trim().to_string();
    assert_eq!(summary(&a)["run_id"], id.as_str());
    assert_eq!(CheckpointFile::read(&cp).unwrap().run_id, id);
    assert_ne!(read(&b.join(files::RUN_ID_FILE)).trim(), id);
    // The checkpoint's own folder resumes.
    assert!(resume(&cp).status.success());
}

/// Non-finite values are neither written nor reported as completed: with a string at
/// x = 1e308 under gravity, a strain that overflows, or an overflowing gravity, no NaN or
/// infinity reaches a file, and no run with a non-finite energy ends `completed`.
#[test]
fn non_finite_values_never_reach_outputs() {
    let tmp = temp_dir("nonfinite");
    let cases: [&[&str]; 3] = [
        &[
            "--set",
            "geometry.start=[1e308, 0.0]",
            "--set",
            "geometry.end=[1e308, -1.0]",
            "--set",
            "body_force.gravity=[-9.81,-9.81]",
        ],
        &["--set", "geometry.length=1e-154"],
        &["--set", "body_force.gravity=[1e300, 1e300]"],
    ];
    for (k, sets) in cases.iter().enumerate() {
        let out = tmp.join(format!("o{k}"));
        let mut args = vec!["examples/paper_pendulum.toml"];
        args.extend_from_slice(sets);
        let o = run(&out, &args);
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
        assert_no_non_finite(&out);
        if out.join("summary.json").exists() {
            let s = summary(&out);
            if s["status"] == "completed" {
                for key in [
                    "hamiltonian_final",
                    "max_balance_error",
                    "max_newton_residual",
                ] {
                    assert!(s[key].as_f64().is_some_and(f64::is_finite), "{key}: {s}");
                }
            }
        }
    }
}

/// Non-finite values, at validation: `check`
/// and `run` refuse a scenario whose derived quantities overflow, name the quantity, and a
/// refused run creates no output folder.
#[test]
fn non_finite_derived_quantities_are_refused_by_check_and_run() {
    let tmp = temp_dir("nonfinite-check");
    let cases: [(&[&str], &str); 3] = [
        (
            &[
                "--set",
                "geometry.start=[1e308, 0.0]",
                "--set",
                "geometry.end=[1e308, -1.0]",
                "--set",
                "body_force.gravity=[-9.81,-9.81]",
            ],
            "initial external potential energy is not finite",
        ),
        (
            &["--set", "body_force.per_length=[1e308, 1e308]"],
            "`body_force.per_length` gives the elements of the string the weight 4.714045207910323e306 N each",
        ),
        (&["--set", "geometry.length=1e-154"], "not finite"),
    ];
    for (k, (sets, expected)) in cases.iter().enumerate() {
        let mut args = vec!["check", "examples/paper_pendulum.toml"];
        args.extend_from_slice(sets);
        let o = phstring(&args);
        assert_eq!(o.status.code(), Some(1), "check {sets:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(expected),
            "check {sets:?}: {}",
            stderr(&o)
        );
        let out = tmp.join(format!("o{k}"));
        let mut args = vec!["examples/paper_pendulum.toml"];
        args.extend_from_slice(sets);
        let o = run(&out, &args);
        assert_eq!(o.status.code(), Some(1), "run {sets:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(expected),
            "run {sets:?}: {}",
            stderr(&o)
        );
        assert!(!out.exists(), "a refused run created {}", out.display());
    }
}

/// A resume that is refused because one output file does not match its
/// checkpoint must leave every file as it was (it used to cut `positions.csv` back before
/// finding that `ports.csv` was short).
#[test]
fn refused_resume_leaves_every_file_as_it_was() {
    let out = temp_dir("refused-resume").inside("o");
    let cp = interrupted_run(&out);
    // A crash after the checkpoint leaves positions.csv longer than recorded; ports.csv was
    // damaged (shorter than recorded).
    let positions = out.join("positions.csv");
    let mut longer = read(&positions);
    longer += "0.5,0,1,2\n";
    std::fs::write(&positions, &longer).unwrap();
    let ports = out.join("ports.csv");
    let text = read(&ports);
    let cut = text[..text.len() - 1].rfind('\n').unwrap() + 1;
    std::fs::write(&ports, &text[..cut]).unwrap();
    let o = resume(&cp);
    assert_refused(&o, "ports.csv");
    assert_eq!(read(&positions), longer, "positions.csv was changed");
    assert_eq!(read(&ports), text[..cut], "ports.csv was changed");
}

/// Counts the scalar values (leaves) of a JSON document.
fn leaves(v: &serde_json::Value) -> usize {
    match v {
        serde_json::Value::Array(a) => a.iter().map(leaves).sum(),
        serde_json::Value::Object(o) => o.values().map(leaves).sum(),
        _ => 1,
    }
}

/// Memory does not grow with the length of a run: no history goes into a checkpoint, so a
/// checkpoint after 100 and after 1900 steps has the same values (and about the same size:
/// numbers differ in digits only).
#[test]
fn checkpoint_size_does_not_grow_with_steps() {
    let tmp = temp_dir("cpsize");
    let mut sizes = Vec::new();
    for steps in ["100", "1900"] {
        let out = tmp.join(steps);
        let o = run(
            &out,
            &[
                "examples/paper_pendulum.toml",
                "--set",
                "time.end=100",
                "--set",
                "output.stride=50",
                "--stop-after-steps",
                steps,
            ],
        );
        assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
        let text = read(&out.join("checkpoint.json"));
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert!(v["outputs"].get("history").is_none());
        sizes.push((text.len(), leaves(&v)));
    }
    assert_eq!(sizes[0].1, sizes[1].1, "{sizes:?}");
    let (a, b) = (sizes[0].0 as f64, sizes[1].0 as f64);
    assert!((a - b).abs() < 0.05 * a, "{sizes:?}");
}

/// A progress receiver that sets the stop flag after `at` steps (`usize::MAX`: at the end
/// of the time loop, i.e. during the plot phase).
struct StopAt(Arc<AtomicBool>, usize);

impl Progress for StopAt {
    fn step(&mut self, step: usize, _t: f64) {
        if step >= self.1 {
            self.0.store(true, Ordering::SeqCst);
        }
    }
    fn finish(&mut self) {
        if self.1 == usize::MAX {
            self.0.store(true, Ordering::SeqCst);
        }
    }
}

fn taut() -> scenario::ScenarioFile {
    scenario::load(&workspace_root().join("examples/taut_string.toml"), &[]).unwrap()
}

/// A stop request is honoured within a step: the stop flag is passed
/// to the simulation, a stop inside a step ends the run `interrupted` with a checkpoint, and
/// the resumed run equals an uninterrupted one.
#[test]
fn stop_during_a_step_interrupts_with_a_checkpoint() {
    let tmp = temp_dir("stopstep");
    let (a, b) = (tmp.join("a"), tmp.join("b"));
    let file = taut();
    run::run(&file, &a, &mut (), RunOptions::default()).unwrap();
    let flag = Arc::new(AtomicBool::new(false));
    let opts = RunOptions {
        stop: Some(flag.clone()),
        ..Default::default()
    };
    let e = run::run(&file, &b, &mut StopAt(flag.clone(), 30), opts).unwrap_err();
    assert!(matches!(e, RunError::Interrupted { steps: 30, .. }), "{e}");
    let s = summary(&b);
    assert_eq!(s["status"], "interrupted");
    assert_eq!(s["steps"], 30);
    // The plots and the animation of the interrupted run were skipped because of the stop,
    // and say so.
    assert_eq!(s["plots"].as_array().unwrap().len(), 0, "{s}");
    assert_eq!(s["plots_skipped"].as_array().unwrap().len(), 5, "{s}");
    let cp = CheckpointFile::read(&b.join("checkpoint.json")).unwrap();
    let opts = RunOptions {
        stop: Some(Arc::new(AtomicBool::new(false))),
        resume: Some(cp),
        ..Default::default()
    };
    let info = run::run(&file, &b, &mut (), opts).unwrap();
    assert_eq!(info.status, "completed");
    for f in [
        "energy.csv",
        "ports.csv",
        "positions.csv",
        "end_tensions.csv",
        "paraview/string.pvd",
    ] {
        assert_eq!(read(&a.join(f)), read(&b.join(f)), "{f}");
    }
    // The plots read back from energy.csv (info.history) are those of the whole run.
    let rows = read(&a.join("energy.csv")).lines().count() - 1;
    assert_eq!(info.history.t.len(), rows);
    assert_eq!(info.history.increments().0.len(), rows - 1);
}

/// A stop request is honoured in the plot phase: a stop there skips
/// the remaining plots, lists them in summary.json, and the completed run stays completed.
#[test]
fn stop_during_plots_skips_them_and_lists_them() {
    let out = temp_dir("stopplots").inside("o");
    let flag = Arc::new(AtomicBool::new(false));
    let opts = RunOptions {
        stop: Some(flag.clone()),
        ..Default::default()
    };
    let info = run::run(&taut(), &out, &mut StopAt(flag, usize::MAX), opts).unwrap();
    assert_eq!(info.status, "completed");
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["plots"].as_array().unwrap().len(), 0);
    let skipped: Vec<&str> = s["plots_skipped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(
        skipped,
        [
            "energy",
            "configuration",
            "increments",
            "fairlead_tension",
            "animation"
        ]
    );
    assert!(s["warnings"].to_string().contains("stop requested"));
    assert!(!out.join("animation.gif").exists());
    assert!(!out.join("energy.svg").exists());
}

/// On an I/O error summary.json is neither missing nor stale: a run that cannot write an
/// output (a folder in the way, a full disk) replaces a stale summary with
/// `"status": "failed"` and the I/O error.
#[test]
fn failed_write_leaves_a_fresh_failed_summary() {
    let tmp = temp_dir("iofail");
    // A folder where ports.csv should be.
    let out = tmp.join("dir");
    std::fs::create_dir_all(out.join("ports.csv")).unwrap();
    std::fs::write(out.join("summary.json"), "{\"status\": \"completed\"}").unwrap();
    let e = run::run(&taut(), &out, &mut (), RunOptions::default()).unwrap_err();
    assert!(matches!(e, RunError::Output(_)), "{e}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert!(s["error"].as_str().unwrap().contains("ports.csv"), "{s}");
    assert!(!out.join(".summary.json.tmp").exists());
    // A full disk under energy.csv (/dev/full fails every write with ENOSPC).
    if Path::new("/dev/full").exists() {
        let out = tmp.join("full");
        std::fs::create_dir_all(&out).unwrap();
        std::os::unix::fs::symlink("/dev/full", out.join("energy.csv")).unwrap();
        let e = run::run(&taut(), &out, &mut (), RunOptions::default()).unwrap_err();
        let s = summary(&out);
        assert_eq!(s["status"], "failed", "{e}");
        assert!(s["error"].as_str().unwrap().contains("energy.csv"), "{s}");
    }
}

/// Temporary files left behind by a killed run (`checkpoint.json.tmp` and the like) do not
/// block a run without `--force`: phstring's own temporary files do not make a folder
/// non-empty, and the next run removes them.
#[test]
fn stale_checkpoint_tmp_does_not_block_a_run() {
    let out = temp_dir("staletmp").inside("o");
    std::fs::create_dir_all(&out).unwrap();
    for name in [
        "checkpoint.json.tmp",
        ".checkpoint.json.tmp",
        ".summary.json.tmp",
    ] {
        std::fs::write(out.join(name), "partial").unwrap();
    }
    let o = run(&out, &["examples/axial_rod_1d.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in [
        "checkpoint.json.tmp",
        ".checkpoint.json.tmp",
        ".summary.json.tmp",
    ] {
        assert!(!out.join(name).exists(), "{name} left behind");
    }
    // A checkpoint is written under a dot-name and renamed: none is left after a run.
    let o = run(
        &out,
        &[
            "examples/axial_rod_1d.toml",
            "--force",
            "--checkpoint-every",
            "3",
            "--stop-after-steps",
            "10",
        ],
    );
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(out.join("checkpoint.json").exists());
    assert!(
        files(&out)
            .iter()
            .all(|f| !f.to_string_lossy().ends_with(".tmp"))
    );
}

/// Control characters in a title reach neither the plots (NUL would make the SVG invalid)
/// nor the ParaView index.
#[test]
fn control_characters_in_titles_do_not_reach_plots() {
    let out = temp_dir("ctrltitle").inside("o");
    let o = run(
        &out,
        &[
            "examples/taut_string.toml",
            "--set",
            "title=\"bad\\u0000title\\u001b[2J\"",
            "--set",
            "time.end=0.02",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["energy.svg", "increments.svg", "configuration.svg"] {
        let svg = read(&out.join(f));
        assert!(svg.contains("badtitle[2J"), "{f}");
        assert!(
            !svg.chars()
                .any(|c| c.is_control() && !matches!(c, '\n' | '\r' | '\t')),
            "{f}"
        );
    }
    let pvd = read(&out.join("paraview/string.pvd"));
    assert!(!pvd.chars().any(|c| c.is_control() && c != '\n'));
}
