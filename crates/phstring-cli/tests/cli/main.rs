//! End-to-end tests of the `phstring` binary.

mod accuracy;
mod balance;
mod bodies;
mod body_feedback;
mod broken;
mod campaign;
mod control;
mod estimates;
mod examples;
mod fmu;
mod full_disk;
mod hardening_cli;
mod hardening_io;
mod interrupt;
mod moordyn;
mod mooring;
mod network;
mod out_folder;
mod reliability;
mod riser;
mod statics;
mod water;
mod winch;
mod winch_body;
mod winch_table;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A test's temporary folder, or a path inside it ([`TestDir::inside`]): the folder is
/// removed when the test passes (the guard dropped without a panic) and kept for
/// inspection when it fails. Dereferences to its path.
pub struct TestDir {
    path: PathBuf,
    root: PathBuf,
}

impl TestDir {
    /// The path `name` inside this folder (not created), with the guard of the folder.
    pub fn inside(self, name: &str) -> TestDir {
        let mut me = std::mem::ManuallyDrop::new(self);
        TestDir {
            path: std::mem::take(&mut me.path).join(name),
            root: std::mem::take(&mut me.root),
        }
    }
}

impl std::ops::Deref for TestDir {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.path
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.root);
        }
    }
}

/// A fresh temporary folder for one test (see [`TestDir`]).
pub fn temp_dir(name: &str) -> TestDir {
    let d = std::env::temp_dir().join(format!("phstring-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    TestDir {
        path: d.clone(),
        root: d,
    }
}

/// Runs the binary with `args` in the workspace root.
pub fn phstring(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(args)
        .current_dir(workspace_root())
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("binary runs")
}

/// Runs `phstring run SCENARIO --out OUT -q` with `--set` for each of `sets`, then `extra`.
pub fn run_with(scenario: &str, out: &Path, sets: &[&str], extra: &[&str]) -> Output {
    let mut args = vec!["run", scenario, "--out", out.to_str().unwrap(), "-q"];
    for s in sets {
        args.push("--set");
        args.push(s);
    }
    args.extend_from_slice(extra);
    phstring(&args)
}

/// Runs `scenario` with `sets` twice under `dir`: whole into `dir/whole`, and into
/// `dir/parts` stopped after `steps` steps (exit code 130) and resumed from its checkpoint.
/// Returns the two folders.
pub fn run_whole_and_resumed(
    scenario: &str,
    dir: &Path,
    sets: &[&str],
    steps: usize,
) -> (PathBuf, PathBuf) {
    let whole = dir.join("whole");
    let o = run_with(scenario, &whole, sets, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let parts = dir.join("parts");
    let stop = steps.to_string();
    let first = run_with(scenario, &parts, sets, &["--stop-after-steps", &stop]);
    let err = String::from_utf8_lossy(&first.stderr);
    assert_eq!(first.status.code(), Some(130), "{err}");
    let cp = parts.join("checkpoint.json");
    let second = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    (whole, parts)
}

/// The rows of the CSV file `path` after its header, each field as a number (NaN where it
/// is not one, e.g. a name).
pub fn numeric_rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// The `summary.json` of the run in `dir`.
pub fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The workspace root (where `examples/` is).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// Waits for `child`; kills it and fails if it has not ended after `limit` (a hang guard,
/// far above the expected time).
pub fn wait_or_kill(mut child: std::process::Child, limit: Duration, what: &str) -> Output {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}
