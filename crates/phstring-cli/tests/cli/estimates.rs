//! Resources are estimated before they are spent: `check` counts the parse of a large
//! scenario and the bookkeeping of its components in its memory estimate (on which `run`'s
//! refusal against the memory available relies), prices a step with what it really
//! evaluates, and estimates the size and number of the output files, warning above 5 GB or
//! 1e5 files. `summary.json` of a large network stays small.

use std::path::Path;
use std::process::Command;

use super::{phstring, temp_dir};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A network of `n` one-element strings between `n + 1` named nodes in a row, both ends
/// fixed, with its outputs off but `summary.json` (about 155 bytes of TOML per string).
fn many_strings(dir: &Path, n: usize) -> std::path::PathBuf {
    use std::fmt::Write as _;
    let mut t = String::from(
        "title = \"many strings\"\ndimension = 2\n[materials.rope]\nlaw = \"tension_only_linear\"\nea = 1.0e8\nrho_a = 1.0\n[body_force]\ngravity = [0.0, -9.81]\n",
    );
    for k in 0..=n {
        let _ = writeln!(t, "[[node]]\nname = \"n{k}\"\nposition = [{k}.0, 0.0]");
    }
    for k in 0..n {
        let _ = writeln!(
            t,
            "[[string]]\nname = \"s{k}\"\npath = [\"n{k}\", \"n{}\"]\nelements = 1\nmaterial = \"rope\"\nprestretch = 1.001",
            k + 1
        );
    }
    let _ = write!(
        t,
        "[[boundary]]\nnode = \"n0\"\nfixed = true\n[[boundary]]\nnode = \"n{n}\"\nfixed = true\n[time]\nh = 0.01\nend = 0.02\n[output]\npositions = false\nvtk = false\nplots = false\nanimation = false\n"
    );
    let path = dir.join("many.toml");
    std::fs::write(&path, t).unwrap();
    path
}

/// The memory estimate `check` prints [bytes].
fn estimated_memory(check: &str) -> f64 {
    let line = check
        .lines()
        .find(|l| l.contains("estimate:"))
        .unwrap_or_else(|| panic!("{check}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let value: f64 = words[1].parse().unwrap();
    value
        * match words[2] {
            "GB" => 1e9,
            "MB" => 1e6,
            unit => panic!("{unit} in {line}"),
        }
}

/// Peak resident memory [bytes] of `phstring args` by `/usr/bin/time -v`, with its output;
/// `None` where `/usr/bin/time` is not installed.
fn peak_memory(args: &[&str]) -> Option<(f64, std::process::Output)> {
    if !Path::new("/usr/bin/time").exists() {
        eprintln!("skipped: no /usr/bin/time");
        return None;
    }
    let o = Command::new("/usr/bin/time")
        .arg("-v")
        .arg(env!("CARGO_BIN_EXE_phstring"))
        .args(args)
        .current_dir(super::workspace_root())
        .output()
        .unwrap();
    let kib: f64 = stderr(&o)
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("Maximum resident set size (kbytes): ")
        })
        .unwrap()
        .parse()
        .unwrap();
    Some((kib * 1024.0, o))
}

/// 99 999 one-element strings: the parse of the 15.5 MB file (about 40 bytes per byte of
/// TOML) is the peak of `check` and `run`; it was left out of the estimate (78 MB for a
/// 573 MB peak), and `summary.json` listed every component (99 MB).
#[test]
fn many_strings_estimate_covers_the_parse_and_summary_stays_small() {
    let dir = temp_dir("many-strings");
    let path = many_strings(&dir, 99_999);
    let p = path.to_str().unwrap();
    let o = phstring(&["check", p]);
    assert!(o.status.success(), "{}", stderr(&o));
    let estimate = estimated_memory(&stdout(&o));
    if let Some((peak, o)) = peak_memory(&["check", p]) {
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            estimate >= peak && estimate <= 1.3 * peak,
            "estimate {estimate:.3e} B, peak of check {peak:.3e} B"
        );
    }
    let out = dir.join("out");
    if let Some((peak, o)) = peak_memory(&["run", p, "--out", out.to_str().unwrap(), "-q"]) {
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            estimate >= peak && estimate <= 1.3 * peak,
            "estimate {estimate:.3e} B, peak of run {peak:.3e} B"
        );
    } else {
        let o = phstring(&["run", p, "--out", out.to_str().unwrap(), "-q"]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    // The summary counts the components; components.json and scenario.json hold them.
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.len() < 20_000, "{} bytes", summary.len());
    let s: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert_eq!(s["components"]["file"], "components.json");
    assert_eq!(s["components"]["strings"], 99_999);
    assert_eq!(s["components"]["nodes"], 100_000);
    assert_eq!(s["scenario"], serde_json::json!({"file": "scenario.json"}));
    // The lines' extremes are counted too.
    assert_eq!(s["lines"], serde_json::json!({"count": 99_999}));
    let c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("components.json")).unwrap())
            .unwrap();
    assert_eq!(c["strings"].as_array().unwrap().len(), 99_999);
    assert_eq!(c["strings"][99_998]["name"], "s99998");
    let scenario: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("scenario.json")).unwrap()).unwrap();
    assert_eq!(scenario["string"].as_array().unwrap().len(), 99_999);

    // With too little memory for the parse, the file is refused before it is parsed: the
    // refusal itself takes a few MB, not the parse's hundreds.
    let refused = dir.join("refused");
    let args = ["run", p, "--out", refused.to_str().unwrap()];
    let o = Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(args)
        .env("PHSTRING_MEMORY_AVAILABLE", "3e8")
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "scenario file {p} has 16 MB of text, and reading it needs about 684 MB"
        )) && err.contains("but only 300 MB is available on this machine"),
        "{err}"
    );
    assert!(!refused.exists());
}

/// A small network of the same kind lists its components in `summary.json` itself.
#[test]
fn small_network_lists_its_components_in_the_summary() {
    let dir = temp_dir("few-strings");
    let path = many_strings(&dir, 300);
    let out = dir.join("out");
    let o = phstring(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["components"]["strings"].as_array().unwrap().len(), 300);
    assert_eq!(s["scenario"]["string"].as_array().unwrap().len(), 300);
    assert!(!out.join("components.json").exists());
    assert!(!out.join("scenario.json").exists());
}

/// A 2000 s pendulum at h = 1e-3 with the default outputs (every step, ParaView on) would
/// write about 14.7 GB in 2e6 files (end_tensions.csv: 2e6 rows of three numbers of about
/// 17 bytes, 102 MB, counted with energy.csv and ports.csv): `check` says so and warns; `run` warns before it starts.
/// The estimate matches what a 2 s run writes.
#[test]
fn check_estimates_the_outputs_and_warns_about_huge_ones() {
    let o = phstring(&[
        "check",
        "examples/paper_pendulum.toml",
        "--set",
        "time.h=0.001",
        "--set",
        "time.end=2000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("  output:    about 14.7 GB in 2.0e6 files (energy.csv, ports.csv and end_tensions.csv 688 MB, positions.csv 2.8 GB, 2.0e6 ParaView frames 11.3 GB)"),
        "{out}"
    );
    assert!(
        stderr(&o).contains("warning: the run would write about 14.7 GB in 2.0e6 files"),
        "{}",
        stderr(&o)
    );
    // Every 1000th step and no ParaView: below the thresholds.
    let o = phstring(&[
        "check",
        "examples/paper_pendulum.toml",
        "--set",
        "time.h=0.001",
        "--set",
        "time.end=2000",
        "--set",
        "output.stride=1000",
        "--set",
        "output.vtk=false",
    ]);
    assert!(!stderr(&o).contains("would write"), "{}", stderr(&o));
    assert!(stdout(&o).contains("in 17 files"), "{}", stdout(&o));

    // The 2 s run: the estimate within 10 % of the files written.
    let dir = temp_dir("output-size").inside("o");
    let args = [
        "examples/paper_pendulum.toml",
        "--set",
        "time.h=0.001",
        "--set",
        "time.end=2",
    ];
    let o = phstring(&[&["check"][..], &args[..]].concat());
    let line = stdout(&o)
        .lines()
        .find(|l| l.contains("output:"))
        .unwrap()
        .to_string();
    assert!(line.contains("about 15 MB in 2018 files"), "{line}");
    let o = phstring(
        &[
            &["run"][..],
            &args[..],
            &["--out", dir.to_str().unwrap(), "-q"],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    fn size(p: &Path) -> (f64, usize) {
        if p.is_dir() {
            std::fs::read_dir(p)
                .unwrap()
                .flatten()
                .fold((0.0, 0), |(b, n), e| {
                    let (b2, n2) = size(&e.path());
                    (b + b2, n + n2)
                })
        } else {
            (std::fs::metadata(p).unwrap().len() as f64, 1)
        }
    }
    let (bytes, files) = size(&dir);
    assert!((bytes / 15e6 - 1.0).abs() < 0.1, "{bytes} bytes written");
    // The 2018 files estimated, and the lock: 2001 frames, string.pvd, energy.csv,
    // positions.csv, ports.csv, end_tensions.csv, elements.csv, the run id, summary.json,
    // eight plot files, animation.gif.
    assert_eq!(files, 2018 + 1);
}

/// A step costs its iterations and what it evaluates besides them: for a 1e6-element rope
/// in 3D, 1e6 × (100 ns + 4 × 180 ns) (the estimate was 400 ms at 1e7 element-iterations
/// per second; steps of 2 iterations took 0.43 s of CPU time here, 1.1 s wall time on a
/// loaded machine).
#[test]
fn check_prices_a_step_with_what_it_evaluates() {
    let o = phstring(&[
        "check",
        "examples/hoist_3d.toml",
        "--set",
        "mesh.elements=1000000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("~820 ms per step"), "{}", stdout(&o));
}

/// `output.row_stride = 7` over 20 steps writes the rows of steps 0, 7, 14 and the last
/// (20) in `energy.csv`, `ports.csv` and `end_tensions.csv`, each equal to the row of the
/// same step of a run that writes every step; `check` estimates the thinner files.
#[test]
fn a_row_stride_thins_the_per_step_files_to_the_same_rows() {
    let dir = temp_dir("row-stride");
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "run",
            "examples/paper_pendulum.toml",
            "--out",
            out.to_str().unwrap(),
            "-q",
            "--set",
            "time.end=0.2",
            "--set",
            "output.plots=false",
            "--set",
            "output.animation=false",
        ];
        args.extend_from_slice(extra);
        let o = phstring(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let every = run("every", &[]);
    let thin = run("thin", &["--set", "output.row_stride=7"]);
    let lines = |dir: &Path, file: &str| -> Vec<String> {
        std::fs::read_to_string(dir.join(file))
            .unwrap()
            .lines()
            .map(String::from)
            .collect()
    };
    for file in ["energy.csv", "end_tensions.csv"] {
        let (all, some) = (lines(&every, file), lines(&thin, file));
        // Header, then steps 0, 7, 14, 20.
        let expected: Vec<String> = [0, 1, 8, 15, 21].iter().map(|&i| all[i].clone()).collect();
        assert_eq!(some, expected, "{file}");
    }
    // ports.csv has one row per port and step (no t = 0 row): steps 7, 14 and 20.
    let (all, some) = (lines(&every, "ports.csv"), lines(&thin, "ports.csv"));
    let per_step = (all.len() - 1) / 20;
    let mut expected = vec![all[0].clone()];
    for step in [7, 14, 20] {
        expected.extend_from_slice(&all[1 + (step - 1) * per_step..1 + step * per_step]);
    }
    assert_eq!(some, expected);
    let o = phstring(&[
        "check",
        "examples/paper_pendulum.toml",
        "--set",
        "output.row_stride=0",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("output.row_stride` must be at least 1, got 0"),
        "{}",
        stderr(&o)
    );
}
