//! A full disk loses nothing that was written: CSV files end on a whole row, no partial
//! ParaView frame is left, the failure names the cause, and `summary.json` records it with
//! the files left incomplete. Run on a small tmpfs; skipped where mounting one is not
//! permitted (not root, no mount namespace).

use std::path::Path;
use std::process::Command;

use super::{phstring, temp_dir};

/// A tmpfs of `size` mounted on a fresh folder, unmounted when dropped.
struct Tmpfs(crate::TestDir);

impl Tmpfs {
    /// `None` (with a note on stderr) where mounting is not permitted.
    fn mount(name: &str, size: &str) -> Option<Self> {
        let dir = temp_dir(name).inside("mnt");
        std::fs::create_dir_all(&dir).unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&*dir)
            .output()
            .is_ok_and(|o| o.status.success());
        if !ok {
            eprintln!("skipped: cannot mount a tmpfs on {}", dir.display());
            return None;
        }
        Some(Self(dir))
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&*self.0).status();
    }
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The rows of a CSV file after its header, checking that it ends on a whole row and that
/// every row has `fields` numbers (columns `skip` are text).
fn whole_rows(path: &Path, fields: usize, text_columns: &[usize]) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.ends_with('\n'), "{} ends mid-row", path.display());
    text.lines()
        .skip(1)
        .map(|l| {
            let row: Vec<String> = l.split(',').map(str::to_string).collect();
            assert_eq!(row.len(), fields, "{}: row {l:?}", path.display());
            for (k, x) in row.iter().enumerate() {
                if !text_columns.contains(&k) {
                    assert!(
                        x.parse::<f64>().is_ok(),
                        "{}: {x:?} in {l:?}",
                        path.display()
                    );
                }
            }
            row
        })
        .collect()
}

/// Every `.vtp` in `dir` is a whole file (ends with its closing tag, so none is empty).
fn whole_frames(dir: &Path) -> Vec<String> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".vtp") {
            let text = std::fs::read_to_string(e.path()).unwrap();
            assert!(text.trim_end().ends_with("</VTKFile>"), "{name} is partial");
            names.push(name);
        }
    }
    names.sort();
    names
}

/// The files a ParaView collection lists, checking that it is whole.
fn listed(pvd: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(pvd).unwrap();
    assert!(text.ends_with("</Collection>\n</VTKFile>\n"), "{text}");
    let mut files: Vec<String> = text
        .lines()
        .filter_map(|l| l.split(" file=\"").nth(1))
        .map(|f| f.trim_end_matches("\"/>").to_string())
        .collect();
    files.sort();
    files
}

#[test]
fn run_on_a_full_disk_keeps_whole_rows_and_records_the_failure() {
    let Some(fs) = Tmpfs::mount("full-run", "2m") else {
        return;
    };
    let out = fs.0.join("x");
    // About 10 kB per step (a ParaView frame, 31 rows of positions): 2 MB last ~200 steps.
    let o = phstring(&[
        "run",
        "examples/paper_pendulum.toml",
        "--set",
        "time.h=0.001",
        "--set",
        "time.end=20",
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("No space left on device"), "{err}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        err.contains("summary.json records the failure"),
        "{err}\n{s}"
    );
    assert_eq!(s["status"], "failed");
    assert!(
        s["error"]
            .as_str()
            .unwrap()
            .contains("No space left on device"),
        "{s}"
    );
    let incomplete: Vec<&str> = s["incomplete_files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert!(!incomplete.is_empty(), "{s}");
    for f in &incomplete {
        assert!(out.join(f).is_file(), "{f}");
        assert!(err.contains(f), "{f} not named in {err}");
    }
    // Every row whole; positions.csv in whole frames of 31 nodes.
    let energy = whole_rows(&out.join("energy.csv"), 10, &[]);
    let positions = whole_rows(&out.join("positions.csv"), 4, &[]);
    assert!(energy.len() > 10, "{} rows", energy.len());
    assert!(!positions.is_empty());
    assert_eq!(positions.len() % 31, 0, "{} rows", positions.len());
    assert_eq!(positions.last().unwrap()[1], "30");
    whole_rows(&out.join("ports.csv"), 9, &[3]);
    // The collection lists exactly the frames on disk, each whole.
    let frames = whole_frames(&out.join("paraview"));
    assert!(!frames.is_empty());
    assert_eq!(listed(&out.join("paraview/string.pvd")), frames);
}

#[test]
fn modes_on_a_full_disk_names_the_cause_and_leaves_no_partial_frame() {
    let Some(fs) = Tmpfs::mount("full-modes", "2m") else {
        return;
    };
    // Leave about 200 kB: modes.csv fits, not the 20 frames of about 25 kB each.
    std::fs::write(fs.0.join("filler"), vec![0u8; 1_900_000]).unwrap();
    let out = fs.0.join("m");
    let o = phstring(&[
        "modes",
        "examples/taut_string.toml",
        "--set",
        "mesh.elements=400",
        "--count",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("No space left on device"), "{err}");
    assert!(!err.contains("XML error"), "{err}");
    let frames = whole_frames(&out);
    assert!(frames.len() < 20, "{frames:?}");
    assert!(out.join("modes.csv").exists());
}
