//! A winch's payout from a table file (`payout_table`, docs/scenario.md "Winches"): the
//! crane's hoist sampled into a table runs as its expression does, and tables that cannot
//! drive a winch are refused naming the key and the file's row.

use std::path::Path;

use crate::{numeric_rows, phstring, run_with, temp_dir, workspace_root};

const CRANE: &str = "examples/crane_hoisting_2d.toml";

/// The crane's payout expression [m]: 15 m hauled in over 30 s, a smooth step.
fn hoist(t: f64) -> f64 {
    let x = (t / 30.0).min(1.0);
    -15.0 * (3.0 * x * x - 2.0 * x * x * x)
}

/// The crane scenario with its `payout` replaced by `table_line`, and the table `rows` as
/// `hoist.csv`, in `dir`; returns the scenario's path.
fn crane_with_table(dir: &Path, table_line: &str, rows: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(workspace_root().join(CRANE)).unwrap();
    let payout = text
        .lines()
        .find(|l| l.starts_with("payout = "))
        .unwrap()
        .to_string();
    std::fs::write(dir.join("hoist.csv"), rows).unwrap();
    let path = dir.join("crane_table.toml");
    std::fs::write(&path, text.replace(&payout, table_line)).unwrap();
    path
}

/// The crane's hoist sampled every 0.25 s into `hoist.csv` and given as `payout_table`: the
/// winch's payout (`winches.csv`) follows the expression's run within 1 mm, the bound of the
/// table's C¹ interpolant at the smooth step's ends, where the payout's acceleration jumps
/// by 0.1 m/s² (`Δp'' dt²/8` = 0.8 mm); the hooks within 2 mm (that and the rope's axial
/// ringing, which the expression's jumps of acceleration excite more than the table's smooth
/// ones: 1.5 kN of drum tension, 0.4 mm of stretch), and `check` names the table.
#[test]
fn a_payout_table_drives_the_winch_as_its_expression_does() {
    let dir = temp_dir("winch-table");
    let mut rows = String::from("t,payout\n");
    for k in 0..=180 {
        let t = 0.25 * k as f64;
        rows.push_str(&format!("{t},{:.12}\n", hoist(t)));
    }
    let scenario = crane_with_table(&dir, "payout_table = \"hoist.csv\"", &rows);
    let fast = [
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
    ];
    let (a, b) = (dir.join("expression"), dir.join("table"));
    let o = run_with(CRANE, &a, &fast, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run_with(scenario.to_str().unwrap(), &b, &fast, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // winches.csv: t, winch, payout, length, speed, tension, … (the name column skipped).
    let read = |dir: &Path| -> Vec<Vec<f64>> {
        let text = std::fs::read_to_string(dir.join("winches.csv")).unwrap();
        text.lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .enumerate()
                    .filter(|(i, _)| *i != 1)
                    .map(|(_, x)| x.parse().unwrap())
                    .collect()
            })
            .collect()
    };
    let (ra, rb) = (read(&a), read(&b));
    assert_eq!(ra.len(), rb.len());
    let payout = ra
        .iter()
        .zip(&rb)
        .map(|(x, y)| (x[1] - y[1]).abs())
        .fold(0.0, f64::max);
    // The hook (node 1): positions.csv rows `t, node, x, y`.
    let hook = |dir: &Path| -> Vec<[f64; 2]> {
        numeric_rows(&dir.join("positions.csv"))
            .into_iter()
            .filter(|r| r[1] == 1.0)
            .map(|r| [r[2], r[3]])
            .collect()
    };
    let (ha, hb) = (hook(&a), hook(&b));
    assert_eq!(ha.len(), hb.len());
    let apart = ha
        .iter()
        .zip(&hb)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max);
    eprintln!("payout table: payouts {payout:.2e} m apart, hooks {apart:.2e} m apart");
    assert!(payout < 1e-3, "payouts {payout} m apart");
    assert!(apart < 2e-3, "hooks {apart} m apart");
    let last = rb.last().unwrap();
    assert!(
        (last[1] + 15.0).abs() < 1e-9,
        "payout at the end {}",
        last[1]
    );
    let o = phstring(&["check", scenario.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("payout [m] from the table hoist.csv"), "{out}");
}

/// A payout table beside `payout`, one not at 0 at `t = 0`, or with a second value column
/// is refused by key, naming the file's row; one 1e-12 m off 0 at `t = 0` (rounding) is
/// taken.
#[test]
fn payout_tables_that_cannot_drive_a_winch_are_refused() {
    let dir = temp_dir("winch-table-refused");
    let rounded = crane_with_table(
        &dir,
        "payout_table = \"hoist.csv\"",
        "t,payout\n0,1e-12\n10,-1\n45,-2\n",
    );
    let o = phstring(&["check", rounded.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ok_rows = "t,payout\n0,0\n10,-1\n45,-2\n";
    let cases = [
        (
            "payout_table = \"hoist.csv\"\npayout = \"-t\"",
            ok_rows,
            "`winch.0.payout_table` and `payout` both drive the payout",
        ),
        (
            "payout_table = \"hoist.csv\"",
            "t,payout\n0,0.5\n10,-1\n45,-2\n",
            "the payout is 0.5 m at t = 0",
        ),
        (
            "payout_table = \"hoist.csv\"",
            "t,payout,x\n0,0,1\n10,-1,1\n45,-2,1\n",
            "columns",
        ),
    ];
    for (k, (line, rows, expected)) in cases.iter().enumerate() {
        let sub = dir.join(format!("case{k}"));
        std::fs::create_dir_all(&sub).unwrap();
        let scenario = crane_with_table(&sub, line, rows);
        let o = phstring(&["check", scenario.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "case {k} was taken");
        assert!(
            err.contains("winch.0.payout_table") && err.contains(expected),
            "case {k}: {err}"
        );
    }
}

/// A resume reads the scenario's tables again: a run of the crane with its payout table,
/// started with paths relative to its folder and stopped after 200 steps, resumes from
/// another working directory (the checkpoint holds the scenario's absolute path) and writes
/// `energy.csv` and `winches.csv` as the uninterrupted run does, byte for byte, and after the
/// whole folder was renamed, from the path it was given, and from a checkpoint without the
/// fingerprints (as written before them); a table
/// edited after the checkpoint (15 m hauled in becoming 10 m) is refused by the resume,
/// naming the key and the file, instead of a run that jumped at the resume.
#[test]
fn a_resume_finds_its_tables_from_anywhere_and_refuses_a_changed_one() {
    let dir = temp_dir("winch-table-resume");
    let table = |scale: f64| {
        let mut rows = String::from("t,payout\n");
        for k in 0..=180 {
            let t = 0.25 * k as f64;
            rows.push_str(&format!("{t},{:.12}\n", scale * hoist(t)));
        }
        rows
    };
    crane_with_table(&dir, "payout_table = \"hoist.csv\"", &table(1.0));
    let in_dir = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_phstring"))
            .args(args)
            .current_dir(&dir)
            .env_remove("RUST_BACKTRACE")
            .output()
            .unwrap()
    };
    let run = |out: &str, extra: &[&str]| {
        let mut args = vec!["run", "crane_table.toml", "--out", out, "-q"];
        for s in [
            "output.plots=false",
            "output.animation=false",
            "output.vtk=false",
            "time.end=4",
        ] {
            args.extend(["--set", s]);
        }
        args.extend_from_slice(extra);
        in_dir(&args)
    };
    let o = run("whole", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for part in ["part", "edited", "moved", "old"] {
        let o = run(part, &["--stop-after-steps", "200"]);
        assert_eq!(
            o.status.code(),
            Some(130),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // From the workspace root.
    let cp = dir.join("part").join("checkpoint.json");
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["energy.csv", "winches.csv"] {
        let read = |d: &str| std::fs::read(dir.join(d).join(f)).unwrap();
        assert!(
            read("whole") == read("part"),
            "{f} differs after the resume"
        );
    }
    // A checkpoint as written before the fingerprints: the scenario path as given, no data
    // files; resumed from the folder it was given in, as then.
    let cp = dir.join("old").join("checkpoint.json");
    let mut c = phstring_io::checkpoint::CheckpointFile::read(&cp).unwrap();
    assert_eq!(c.data_files.len(), 1);
    c.scenario_path = c.scenario_path_given.clone();
    c.scenario_path_given = std::path::PathBuf::new();
    c.data_files.clear();
    c.write(&cp).unwrap();
    let text = std::fs::read_to_string(&cp).unwrap();
    assert!(!text.contains("data_files") && !text.contains("scenario_path_given"));
    let o = in_dir(&["run", "--resume", "old/checkpoint.json", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |d: &str| std::fs::read(dir.join(d).join("energy.csv")).unwrap();
    assert!(
        read("whole") == read("old"),
        "energy.csv differs after the old resume"
    );
    // The whole project moved (a renamed folder): the checkpoint's absolute path is gone,
    // the path the run was given, from the new folder, finds the same files.
    let moved = dir.with_extension("moved");
    std::fs::rename(&dir, &moved).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(["run", "--resume", "moved/checkpoint.json", "-q"])
        .current_dir(&moved)
        .env_remove("RUST_BACKTRACE")
        .output()
        .unwrap();
    std::fs::rename(&moved, &dir).unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |d: &str| std::fs::read(dir.join(d).join("energy.csv")).unwrap();
    assert!(
        read("whole") == read("moved"),
        "energy.csv differs after the move"
    );
    std::fs::write(dir.join("hoist.csv"), table(2.0 / 3.0)).unwrap();
    let cp = dir.join("edited").join("checkpoint.json");
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("`winch.0.payout_table`")
            && err.contains("hoist.csv has changed since the checkpoint was written"),
        "{err}"
    );
}
