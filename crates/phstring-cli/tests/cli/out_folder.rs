//! Every command reads and checks its inputs before it touches its output folder, and
//! refuses an output folder that holds one of its inputs (the scenario file, a checkpoint),
//! so that `--force` can never remove what the command reads.

use std::path::{Path, PathBuf};

use super::{phstring, temp_dir, workspace_root};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The relative paths of every file under `dir`, sorted, with their contents.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_path_buf();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// A folder `case/` holding a copy of `example` as `scenario.toml` and a previous output
/// (`energy.csv`), so that `--force` would clear it; returns the folder and the scenario.
fn case_folder(name: &str, example: &str) -> (crate::TestDir, PathBuf) {
    let case = temp_dir(name).inside("case");
    std::fs::create_dir_all(&case).unwrap();
    let scenario = case.join("scenario.toml");
    std::fs::copy(workspace_root().join(example), &scenario).unwrap();
    std::fs::write(case.join("energy.csv"), "t\n0\n").unwrap();
    (case, scenario)
}

/// Runs `args`, expects the refusal that names the folder and the input, and that the
/// folder is exactly as it was.
fn assert_refused_untouched(args: &[&str], case: &Path, input: &Path) {
    let before = snapshot(case);
    let o = phstring(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(
        err.contains(&format!(
            "output folder {} holds the input file",
            case.display()
        )),
        "{args:?}: {err}"
    );
    assert!(
        err.contains(&input.display().to_string()),
        "{args:?}: {err}"
    );
    assert_eq!(snapshot(case), before, "{args:?} changed the folder");
}

#[test]
fn run_refuses_out_folder_holding_its_scenario() {
    let (case, scenario) = case_folder("holds-run", "examples/axial_rod_1d.toml");
    let (c, s) = (case.to_str().unwrap(), scenario.to_str().unwrap());
    assert_refused_untouched(&["run", s, "--out", c, "--force", "-q"], &case, &scenario);
    // A sub-folder of the output folder is inside it too.
    let parent = case.parent().unwrap();
    let o = phstring(&["run", s, "--out", parent.to_str().unwrap(), "--force", "-q"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("holds the input file"),
        "{}",
        stderr(&o)
    );
    assert!(scenario.exists());
    // Next to the scenario, not above it: runs.
    let out = parent.join("out");
    let o = phstring(&["run", s, "--out", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("summary.json").exists());
}

#[test]
fn sweep_refuses_out_folder_holding_its_scenario() {
    let (case, scenario) = case_folder("holds-sweep", "examples/axial_rod_1d.toml");
    let (c, s) = (case.to_str().unwrap(), scenario.to_str().unwrap());
    assert_refused_untouched(
        &[
            "sweep",
            s,
            "--vary",
            "time.h=0.001,0.002",
            "--out",
            c,
            "--force",
            "-q",
        ],
        &case,
        &scenario,
    );
}

#[test]
fn statics_refuses_out_folder_holding_its_scenario() {
    let (case, scenario) = case_folder("holds-statics", "examples/taut_string.toml");
    let (c, s) = (case.to_str().unwrap(), scenario.to_str().unwrap());
    assert_refused_untouched(&["statics", s, "--out", c, "--force"], &case, &scenario);
}

#[test]
fn modes_refuses_out_folder_holding_its_scenario() {
    let (case, scenario) = case_folder("holds-modes", "examples/taut_string.toml");
    let (c, s) = (case.to_str().unwrap(), scenario.to_str().unwrap());
    assert_refused_untouched(
        &["modes", s, "--count", "3", "--out", c, "--force"],
        &case,
        &scenario,
    );
}

/// `linearize --at DIR/checkpoint.json --out DIR --force` cleared DIR (the checkpoint and
/// the interrupted run with it) before reading the checkpoint, then failed on it.
#[test]
fn linearize_refuses_out_folder_holding_its_checkpoint() {
    let tmp = temp_dir("holds-linearize");
    let x = tmp.join("x");
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--out",
        x.to_str().unwrap(),
        "--stop-after-steps",
        "40",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let cp = x.join("checkpoint.json");
    assert_refused_untouched(
        &[
            "linearize",
            "examples/paper_pendulum.toml",
            "--at",
            cp.to_str().unwrap(),
            "--out",
            x.to_str().unwrap(),
            "--force",
        ],
        &x,
        &cp,
    );
    // The interrupted run is whole: it resumes and completes.
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));

    // A missing checkpoint, and one of another scenario's mesh, are refused before a
    // non-empty folder is cleared with --force.
    let other = tmp.join("other");
    let o = phstring(&[
        "run",
        "examples/taut_string.toml",
        "--out",
        other.to_str().unwrap(),
        "--stop-after-steps",
        "2",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let other_cp = other.join("checkpoint.json");
    let before = snapshot(&x);
    for (at, expect) in [
        (tmp.join("missing.json"), "No such file".to_string()),
        (
            other_cp.clone(),
            format!(
                "{} holds 82 position values, but the scenario has 31 nodes in 2D (62 values)",
                other_cp.display()
            ),
        ),
    ] {
        let o = phstring(&[
            "linearize",
            "examples/paper_pendulum.toml",
            "--at",
            at.to_str().unwrap(),
            "--out",
            x.to_str().unwrap(),
            "--force",
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(&expect), "{}", stderr(&o));
        assert_eq!(snapshot(&x), before, "{at:?}: the folder was touched");
    }
    // A checkpoint of the right scenario, outside the output folder: linearized at it.
    let lin = tmp.join("lin");
    let again = tmp.join("again");
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--out",
        again.to_str().unwrap(),
        "--stop-after-steps",
        "40",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let o = phstring(&[
        "linearize",
        "examples/paper_pendulum.toml",
        "--at",
        again.join("checkpoint.json").to_str().unwrap(),
        "--out",
        lin.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(lin.join("manifest.json")).unwrap()).unwrap();
    let t = manifest["time"].as_f64().unwrap();
    assert!((t - 0.4).abs() < 1e-12, "{manifest}");
}
