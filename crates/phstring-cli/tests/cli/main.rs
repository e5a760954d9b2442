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

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A fresh temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("phstring-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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
