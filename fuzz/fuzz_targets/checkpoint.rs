//! Fuzz target: reading and restoring checkpoints must never panic, hang or produce
//! non-finite energies, whatever the bytes (a checkpoint with a number removed once made
//! `--resume` panic inside nalgebra).
//!
//! Each input is tried twice: as raw bytes (format, size and checksum checks), and, if it
//! parses as a checkpoint, again with its checksum re-stamped, so that edited values reach
//! the checks against the scenario (lengths, ranges), `restore` and a few steps.
#![no_main]

use std::path::{Path, PathBuf};

use libfuzzer_sys::fuzz_target;
use phstring::{Material, Simulation};
use phstring_io::checkpoint::CheckpointFile;
use phstring_io::scenario::{self, ScenarioFile};

fn temp_file() -> PathBuf {
    std::env::temp_dir().join(format!("phstring-fuzz-checkpoint-{}.json", std::process::id()))
}

/// Meshes above this size only test the allocator.
const MAX_ELEMENTS: usize = 2000;

fn resume<const D: usize>(cp: &CheckpointFile, file: &ScenarioFile) {
    let Ok(v) = file.validate::<D>() else { return };
    if v.problem.mesh.n_elements() > MAX_ELEMENTS {
        return;
    }
    let Ok(mut sim) = Simulation::<D, Material>::new(v.problem, v.settings.step) else {
        return;
    };
    if cp.check_against(&sim, &v.settings).is_err() {
        return;
    }
    sim.restore(cp.sim.to_checkpoint::<D>())
        .expect("a checkpoint that passed check_against restores");
    for _ in 0..3 {
        match sim.step_until(v.settings.t_end) {
            Ok(r) => {
                assert!(r.after.hamiltonian().is_finite(), "non-finite energy accepted");
                assert!(r.balance_error.is_finite(), "non-finite balance error");
            }
            Err(_) => break,
        }
        if sim.time() >= v.settings.t_end {
            break;
        }
    }
}

fn try_file(path: &Path) {
    let Ok(cp) = CheckpointFile::read(path) else { return };
    let Ok(file) = scenario::parse(&cp.scenario_text, Path::new("checkpoint.toml"), &[]) else {
        return;
    };
    match file.dimension() {
        Ok(1) => resume::<1>(&cp, &file),
        Ok(2) => resume::<2>(&cp, &file),
        Ok(3) => resume::<3>(&cp, &file),
        _ => {}
    }
}

fuzz_target!(|data: &[u8]| {
    let path = temp_file();
    if std::fs::write(&path, data).is_err() {
        return;
    }
    try_file(&path);
    // Re-stamp the checksum of a parsable checkpoint so that the edit reaches the checks.
    if let Ok(mut cp) = serde_json::from_slice::<CheckpointFile>(data) {
        cp.checksum = cp.checksum();
        if let Ok(text) = serde_json::to_vec(&cp) {
            if std::fs::write(&path, text).is_ok() {
                try_file(&path);
            }
        }
    }
    let _ = std::fs::remove_file(&path);
});
