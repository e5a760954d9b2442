//! Load-case campaigns: `phstring sweep DECK --vary motion=a.csv,b.csv` runs the deck once
//! per platform table, exactly as `phstring run DECK --motion a.csv`, and gathers the
//! extremes of every line into `campaign.csv`.

use std::path::Path;
use std::process::{Command, Output};

use crate::{phstring, temp_dir};

/// A three-line spar after the OC3 example deck (same line type, anchors, fairleads and
/// water), with 10 segments of 90 m per line and a 0.01 s step so that a campaign of
/// short tables runs in seconds.
const DECK: &str = "\
---------------------- MoorDyn v2 deck (campaign test) ------------------------
three catenary lines 120 degrees apart in 320 m of water, coarse
---------------------- LINE TYPES ----------------------------------------------
TypeName  Diam   Mass/m    EA          BA/-zeta  EI    Cd    Ca    CdAx  CaAx
(name)    (m)    (kg/m)    (N)         (N-s/-)   (N-m^2) (-) (-)   (-)   (-)
spar_line 0.09   77.7066   384.243e6   -0.8      0     1.6   1.0   0.1   0.0
---------------------- POINTS --------------------------------------------------
ID  Attachment  X         Y         Z       Mass  Volume  CdA  Ca
(#) (word)      (m)       (m)       (m)     (kg)  (m^3)   (m^2) (-)
1   Fixed       853.87    0.0       -320.0  0     0       0    0
2   Fixed      -426.935   739.47    -320.0  0     0       0    0
3   Fixed      -426.935  -739.47    -320.0  0     0       0    0
4   Vessel      5.2       0.0       -70.0   0     0       0    0
5   Vessel     -2.6       4.5033    -70.0   0     0       0    0
6   Vessel     -2.6      -4.5033    -70.0   0     0       0    0
---------------------- LINES ---------------------------------------------------
ID  LineType   AttachA  AttachB  UnstrLen  NumSegs  Outputs
(#) (name)     (#)      (#)      (m)       (-)      (-)
1   spar_line  1        4        902.2     10       -
2   spar_line  2        5        902.2     10       -
3   spar_line  3        6        902.2     10       -
---------------------- OPTIONS -------------------------------------------------
0.01      dtM        mooring time step (s)
320       WtrDpth    water depth (m)
1025      rho        water density (kg/m^3)
9.80665   g          gravity (m/s^2)
---------------------- END -----------------------------------------------------
";

/// A platform table of 2 s: surge `x = −A (1 − cos(2πt/4 s))/2` (away from line 1's
/// anchor, from rest at `t = 0` to `−A` at 2 s) and heave `z = 0.2 A sin(2πt/4 s)` [m].
fn table(amplitude: f64) -> String {
    let mut text = String::from("t, x, y, z, roll, pitch, yaw\n");
    for i in 0..=40 {
        let t = 0.05 * i as f64;
        let w = 2.0 * std::f64::consts::PI * t / 4.0;
        let x = -amplitude * (1.0 - w.cos()) / 2.0;
        let z = 0.2 * amplitude * w.sin();
        text.push_str(&format!("{t}, {x}, 0, {z}, 0, 0, 0\n"));
    }
    text
}

/// The binary with `args`, run in `dir` (so that relative paths are relative to it).
fn phstring_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The header and rows of a CSV file.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (h, rows)
}

/// The column `name` of `rows` under header `h`, as numbers.
fn column(h: &[String], rows: &[Vec<String>], name: &str) -> Vec<f64> {
    let k = h.iter().position(|x| x == name).unwrap();
    rows.iter().map(|r| r[k].parse().unwrap()).collect()
}

/// The campaign's rows of `case`, with the value of `field` parsed, line by line.
fn field(h: &[String], rows: &[Vec<String>], case: &str, name: &str) -> Vec<String> {
    let (c, k) = (
        h.iter().position(|x| x == "case").unwrap(),
        h.iter().position(|x| x == name).unwrap(),
    );
    rows.iter()
        .filter(|r| r[c] == case)
        .map(|r| r[k].clone())
        .collect()
}

/// A campaign over two surge-and-heave tables (1 m and 4 m) and a table with a bad row:
/// the two good cases complete into `run_000_surge1`, `run_001_surge4`; the bad one is a
/// failed row that names the table's line; every value of the campaign table equals the
/// extreme of that case's own `end_tensions.csv` column (exactly: the files hold 17
/// digits), the time of the largest fairlead tension is that of its row, and the smallest
/// grounded length is the summary's; line 1, which the surge pulls away from its anchor,
/// has the larger largest fairlead tension under the larger motion; and each case's outputs
/// are those of `phstring run DECK --motion TABLE`, byte for byte.
#[test]
fn a_campaign_gathers_every_case_and_line_and_equals_run_with_motion() {
    let dir = temp_dir("campaign");
    std::fs::write(dir.join("spar.dat"), DECK).unwrap();
    std::fs::write(dir.join("surge1.csv"), table(1.0)).unwrap();
    std::fs::write(dir.join("surge4.csv"), table(4.0)).unwrap();
    // Line 22 of the file, the row of t = 1 s, with text for its x.
    let mut bad: Vec<String> = table(2.0).lines().map(String::from).collect();
    bad[21] = "1, abc, 0, 0, 0, 0, 0".into();
    let bad = bad.join("\n") + "\n";
    std::fs::write(dir.join("broken.csv"), bad).unwrap();
    let sets = [
        "--set",
        "output.plots=false",
        "--set",
        "output.animation=false",
    ];
    let mut args = vec![
        "sweep",
        "spar.dat",
        "--vary",
        "motion=surge1.csv,surge4.csv,broken.csv",
        "--out",
        "campaign",
        "-q",
        "--jobs",
        "2",
    ];
    args.extend(sets);
    let o = phstring_in(&dir, &args);
    assert!(!o.status.success(), "one case fails, so the sweep exits 1");
    assert!(stderr(&o).contains("1 of 3 runs failed"), "{}", stderr(&o));
    let out = dir.join("campaign");
    let (h, rows) = read_csv(&out.join("campaign.csv"));
    assert_eq!(
        h[..6],
        ["run", "dir", "case", "line", "name", "status"].map(String::from)
    );
    assert_eq!(
        rows.len(),
        7,
        "3 lines of 2 cases and one failed row: {rows:?}"
    );
    let status = field(&h, &rows, "broken.csv", "status");
    assert_eq!(status, ["failed"]);
    let reason = &field(&h, &rows, "broken.csv", "error")[0];
    assert!(reason.contains("broken.csv:22"), "{reason}");
    assert!(reason.contains("abc"), "{reason}");
    let mut largest = Vec::new();
    for (case, folder) in [
        ("surge1.csv", "run_000_surge1"),
        ("surge4.csv", "run_001_surge4"),
    ] {
        let run = out.join(folder);
        let (eh, erows) = read_csv(&run.join("end_tensions.csv"));
        let t = column(&eh, &erows, "t");
        assert!(
            (t.last().unwrap() - 2.0).abs() < 1e-12,
            "ends at the table's end"
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap())
                .unwrap();
        let num = |name: &str| -> Vec<f64> {
            field(&h, &rows, case, name)
                .iter()
                .map(|x| x.parse().unwrap())
                .collect()
        };
        assert_eq!(field(&h, &rows, case, "status"), ["completed"; 3]);
        assert_eq!(field(&h, &rows, case, "name"), ["line1", "line2", "line3"]);
        for line in 1..=3 {
            let k = line - 1;
            let fair = column(&eh, &erows, &format!("FairTen{line}"));
            let anch = column(&eh, &erows, &format!("AnchTen{line}"));
            let max = fair.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let at = t[fair.iter().position(|x| *x == max).unwrap()];
            assert_eq!(num("fair_ten_max")[k], max, "{case} line {line}");
            assert_eq!(num("fair_ten_max_t")[k], at, "{case} line {line}");
            assert_eq!(
                num("fair_ten_min")[k],
                fair.iter().copied().fold(f64::INFINITY, f64::min)
            );
            assert_eq!(
                num("anch_ten_max")[k],
                anch.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            );
            assert_eq!(
                num("anch_ten_min")[k],
                anch.iter().copied().fold(f64::INFINITY, f64::min)
            );
            let grounded = summary["water"]["strings"][k]["grounded_length_min"]
                .as_f64()
                .unwrap();
            assert_eq!(num("grounded_length_min")[k], grounded);
            assert!(
                grounded > 0.0,
                "{case}: line {line} keeps part of its length on the seabed"
            );
            assert_eq!(summary["lines"][k]["fair_ten_max"].as_f64().unwrap(), max);
        }
        largest.push(num("fair_ten_max")[0]);
        eprintln!(
            "{case}: FairTen max {:?} N, min {:?} N, grounded min {:?} m, slack {:?}",
            num("fair_ten_max"),
            num("fair_ten_min"),
            num("grounded_length_min"),
            field(&h, &rows, case, "slack")
        );
        // The same deck driven by the same table with `run`: the same files, byte for byte.
        let alone = dir.join(format!("alone_{folder}"));
        let mut args = vec!["run", "spar.dat", "--motion", case, "--out"];
        let alone_s = alone.to_str().unwrap().to_string();
        args.push(&alone_s);
        args.push("-q");
        args.extend(sets);
        let o = phstring_in(&dir, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        for file in [
            "end_tensions.csv",
            "energy.csv",
            "positions.csv",
            "ports.csv",
        ] {
            let a = std::fs::read(run.join(file)).unwrap();
            let b = std::fs::read(alone.join(file)).unwrap();
            assert!(a == b, "{case}: {file} differs from run --motion");
        }
    }
    assert!(
        largest[1] > largest[0],
        "4 m pulls line 1 harder than 1 m: {largest:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--vary motion=…` over a scenario file is refused with what to vary instead; with
/// `--motion` too, over a deck, it is refused as giving the table twice.
#[test]
fn motion_is_varied_over_decks_only_and_once() {
    let dir = temp_dir("campaign-refused");
    std::fs::write(dir.join("spar.dat"), DECK).unwrap();
    std::fs::write(dir.join("surge1.csv"), table(1.0)).unwrap();
    let o = phstring(&[
        "sweep",
        "examples/mooring_line.toml",
        "--vary",
        "motion=a.csv,b.csv",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("is a scenario file, not a MoorDyn deck"), "{e}");
    assert!(e.contains("platform.0.motion_table"), "{e}");
    assert!(!dir.join("out").exists(), "nothing is written");
    let o = phstring_in(
        &dir,
        &[
            "sweep",
            "spar.dat",
            "--motion",
            "surge1.csv",
            "--vary",
            "motion=surge1.csv",
        ],
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("is driven by --motion, which gives one table for every run"),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run stopped after 100 steps and resumed from its checkpoint reports the lines'
/// extremes over the whole run (the checkpoint carries them): `summary.json`'s `lines` are
/// those of the uninterrupted run, value for value.
#[test]
fn the_line_extremes_survive_a_resume() {
    let dir = temp_dir("campaign-resume");
    std::fs::write(dir.join("spar.dat"), DECK).unwrap();
    std::fs::write(dir.join("surge4.csv"), table(4.0)).unwrap();
    let run = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "run",
            "spar.dat",
            "--motion",
            "surge4.csv",
            "--out",
            out,
            "-q",
        ];
        args.extend([
            "--set",
            "output.plots=false",
            "--set",
            "output.animation=false",
        ]);
        args.extend(extra);
        phstring_in(&dir, &args)
    };
    let o = run("whole", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run("parts", &["--stop-after-steps", "100"]);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let o = phstring_in(&dir, &["run", "--resume", "parts/checkpoint.json", "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines = |folder: &str| {
        let text = std::fs::read_to_string(dir.join(folder).join("summary.json")).unwrap();
        let s: serde_json::Value = serde_json::from_str(&text).unwrap();
        s["lines"].clone()
    };
    let (whole, parts) = (lines("whole"), lines("parts"));
    assert_eq!(whole.as_array().map(Vec::len), Some(3), "{whole}");
    assert_eq!(whole, parts);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sweep over a deck with one `--motion` table for all runs and another varied key: the
/// folders keep their plain names, and `campaign.csv` has the table as `case` and the
/// varied key's column; the run with half the step reaches the same end time.
#[test]
fn a_deck_sweep_with_one_motion_varies_other_keys() {
    let dir = temp_dir("campaign-keys");
    std::fs::write(dir.join("spar.dat"), DECK).unwrap();
    std::fs::write(dir.join("surge1.csv"), table(1.0)).unwrap();
    let o = phstring_in(
        &dir,
        &[
            "sweep",
            "spar.dat",
            "--motion",
            "surge1.csv",
            "--vary",
            "time.h=0.01,0.005",
            "--set",
            "output.plots=false",
            "--out",
            "keys",
            "-q",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (h, rows) = read_csv(&dir.join("keys").join("campaign.csv"));
    assert_eq!(
        h[..5],
        ["run", "dir", "case", "time.h", "line"].map(String::from)
    );
    assert_eq!(rows.len(), 6);
    for (k, r) in rows.iter().enumerate() {
        let dir_name = if k < 3 { "run_000" } else { "run_001" };
        assert_eq!(r[1..4], [dir_name, "surge1.csv", ["0.01", "0.005"][k / 3]]);
    }
    for run in ["run_000", "run_001"] {
        let (eh, erows) = read_csv(&dir.join("keys").join(run).join("end_tensions.csv"));
        let t = column(&eh, &erows, "t");
        assert!(
            (t.last().unwrap() - 2.0).abs() < 1e-12,
            "{run} ends at {t:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
