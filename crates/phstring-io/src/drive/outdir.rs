//! The output folder: the names phstring writes (in one place), clearing them for `--force`,
//! a lock against concurrent runs, and the refusal to write through symbolic links.
//!
//! Layout (every command may find any of these, as a folder may be reused by another
//! command with `--force`):
//!
//! ```text
//! DIR/  RUN_FILES, paraview/ (string.pvd, frame_NNNNNN.vtp,    a run
//!       bodies.pvd, bodies_NNNNNN.vtp)
//!       dg/, mp/ (each a run folder), figures/ (PAPER_FIGURES)  phstring paper
//!       sweep.csv, run_NNN/ (each a run folder)                 phstring sweep
//!       .phstring.lock                                          the lock (never removed)
//! ```

use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};

use crate::files::{
    BODIES_PVD_FILE, CAMPAIGN_TABLE, FIGURES_DIR, LOCK_FILE, PAPER_FIGURES, PAPER_RUN_DIRS,
    PARAVIEW_DIR, PVD_FILE, RUN_FILES, RUN_ID_FILE, SWEEP_TABLE, body_frame_name, case_dir_name,
    frame_name, is_channel_table, is_own_temp_file,
};

/// Whether `name` is exactly a name that [`frame_name`] or [`body_frame_name`] gives.
fn is_frame_name(name: &str) -> bool {
    [
        ("frame_", frame_name as fn(usize) -> String),
        ("bodies_", body_frame_name),
    ]
    .iter()
    .any(|(prefix, named)| {
        name.strip_prefix(prefix)
            .and_then(|s| s.strip_suffix(".vtp"))
            .filter(|d| d.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|d| d.parse::<usize>().ok())
            .is_some_and(|n| named(n) == name)
    })
}

/// Whether `name` is exactly a name that [`run_dir_name`] or [`case_dir_name`] gives.
fn is_run_dir_name(name: &str) -> bool {
    let Some(rest) = name.strip_prefix("run_") else {
        return false;
    };
    let (digits, label) = rest.split_once('_').unwrap_or((rest, ""));
    digits.bytes().all(|b| b.is_ascii_digit())
        && digits
            .parse::<usize>()
            .is_ok_and(|n| case_dir_name(n, label) == name)
}

/// What an entry of a folder is to phstring.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Entry {
    /// One of phstring's files.
    File,
    /// One of phstring's folders, holding entries of this kind.
    Dir(Folder),
}

/// Kinds of folders phstring writes.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Folder {
    /// The `--out` folder (any command).
    Top,
    /// A run folder (`dg/`, `mp/`, `run_NNN/`).
    Run,
    /// `paraview/`.
    Paraview,
    /// `figures/`.
    Figures,
}

fn classify(folder: Folder, name: &str) -> Option<Entry> {
    let run = |name: &str| {
        if RUN_FILES.contains(&name) || is_own_temp_file(name) || is_channel_table(name) {
            Some(Entry::File)
        } else if name == PARAVIEW_DIR {
            Some(Entry::Dir(Folder::Paraview))
        } else {
            None
        }
    };
    match folder {
        Folder::Top => run(name).or_else(|| {
            if name == SWEEP_TABLE || name == CAMPAIGN_TABLE {
                Some(Entry::File)
            } else if PAPER_RUN_DIRS.contains(&name) || is_run_dir_name(name) {
                Some(Entry::Dir(Folder::Run))
            } else if name == FIGURES_DIR {
                Some(Entry::Dir(Folder::Figures))
            } else {
                None
            }
        }),
        Folder::Run => run(name),
        Folder::Paraview => (name == PVD_FILE
            || name == BODIES_PVD_FILE
            || is_own_temp_file(name)
            || is_frame_name(name))
        .then_some(Entry::File),
        Folder::Figures => PAPER_FIGURES.contains(&name).then_some(Entry::File),
    }
}

/// Whether `name` is a file phstring keeps for itself in an output folder (the lock, the run
/// id, a temporary file left by a kill): such files alone do not make a folder non-empty.
pub fn is_bookkeeping(name: &str) -> bool {
    name == LOCK_FILE || name == RUN_ID_FILE || is_own_temp_file(name)
}

/// Errors preparing an output folder.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutDirError {
    /// The path exists and is not a folder.
    #[error("output path {} exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    /// The folder holds files and `--force` was not given.
    #[error(
        "output folder {} is not empty; pass --force to overwrite it, or choose another with --out",
        .0.display()
    )]
    NotEmpty(PathBuf),
    /// Another phstring process holds the folder's lock.
    #[error(
        "output folder {} is in use by another phstring run (it holds {}); wait for it to finish or choose another folder with --out",
        .0.display(),
        LOCK_FILE
    )]
    Busy(PathBuf),
    /// One of phstring's output names is a symbolic link.
    #[error(
        "{} is a symbolic link, and phstring does not write through links: remove the link (for a new run, --force removes it)",
        .0.display()
    )]
    Symlink(PathBuf),
    /// The output folder holds one of the command's input files (the scenario, a
    /// checkpoint it reads), which preparing the folder could remove or overwrite.
    #[error(
        "output folder {} holds the input file {}, which preparing the folder could remove or overwrite; choose another folder with --out",
        out.display(),
        input.display()
    )]
    HoldsInput {
        /// The output folder, as given.
        out: PathBuf,
        /// The input file, as given.
        input: PathBuf,
    },
    /// A file operation failed.
    #[error("cannot {action} {}: {cause}", path.display())]
    Io {
        /// What was being done (`read`, `remove`, `create`, `lock`).
        action: &'static str,
        /// The path.
        path: PathBuf,
        /// The operating system's reason (part of the message, not a separate source).
        cause: io::Error,
    },
}

fn io_err(action: &'static str, path: &Path) -> impl FnOnce(io::Error) -> OutDirError + use<> {
    let path = path.to_path_buf();
    move |cause| OutDirError::Io {
        action,
        path,
        cause,
    }
}

/// An advisory lock on an output folder, held while the value lives (and released by the
/// operating system when the process ends, also when it is killed).
#[derive(Debug)]
pub struct OutLock {
    _file: File,
    dir: PathBuf,
}

impl OutLock {
    /// Locks `dir` (which must exist) through `dir/.phstring.lock`; a folder locked by
    /// another process is refused with [`OutDirError::Busy`].
    pub fn acquire(dir: &Path) -> Result<Self, OutDirError> {
        let path = dir.join(LOCK_FILE);
        if std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(OutDirError::Symlink(path));
        }
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(io_err("create", &path))?;
        match file.try_lock() {
            Ok(()) => Ok(Self {
                _file: file,
                dir: dir.to_path_buf(),
            }),
            Err(std::fs::TryLockError::WouldBlock) => Err(OutDirError::Busy(dir.to_path_buf())),
            Err(std::fs::TryLockError::Error(cause)) => Err(OutDirError::Io {
                action: "lock",
                path,
                cause,
            }),
        }
    }

    /// The locked folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// Prepares `dir` for a new run (or paper, or sweep): refuses a non-empty folder unless
/// `force`, creates it, locks it (refusing one that another run holds), removes the outputs
/// of an earlier run with `force` ([`clear`]), and refuses symbolic links among phstring's
/// names ([`refuse_symlinks`]). Bookkeeping files alone ([`is_bookkeeping`]) do not make a
/// folder non-empty.
pub fn prepare(dir: &Path, force: bool) -> Result<OutLock, OutDirError> {
    let mut lock = None;
    match std::fs::metadata(dir) {
        Ok(m) if !m.is_dir() => return Err(OutDirError::NotAFolder(dir.to_path_buf())),
        Ok(_) => {
            // A folder in use is reported as such, with or without --force.
            if std::fs::symlink_metadata(dir.join(LOCK_FILE)).is_ok() {
                lock = Some(OutLock::acquire(dir)?);
            }
            let non_empty = std::fs::read_dir(dir)
                .map_err(io_err("read", dir))?
                .flatten()
                .any(|e| !is_bookkeeping(&e.file_name().to_string_lossy()));
            if non_empty && !force {
                return Err(OutDirError::NotEmpty(dir.to_path_buf()));
            }
        }
        Err(_) => {}
    }
    std::fs::create_dir_all(dir).map_err(io_err("create", dir))?;
    let lock = match lock {
        Some(l) => l,
        None => OutLock::acquire(dir)?,
    };
    if force {
        clear(dir)?;
    }
    refuse_symlinks(dir)?;
    Ok(lock)
}

/// Refuses an output folder `out` that holds, at any depth, one of the command's `inputs`
/// (the scenario file, a checkpoint it reads): preparing the folder (with `--force`) could
/// remove them before or while they are used, and a run would write over the run it reads.
/// Paths are compared after resolving links and `..`; an `out` that does not exist yet
/// holds nothing, and an input that cannot be resolved (a pipe such as `/dev/stdin`) is
/// not a file in a folder.
pub fn refuse_inputs_inside(out: &Path, inputs: &[&Path]) -> Result<(), OutDirError> {
    let Ok(dir) = std::fs::canonicalize(out) else {
        return Ok(());
    };
    for &input in inputs {
        if std::fs::canonicalize(input).is_ok_and(|p| p.starts_with(&dir)) {
            return Err(OutDirError::HoldsInput {
                out: out.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Prepares the folder of a run to be resumed: locks it (refusing one that another run
/// holds) and refuses symbolic links among phstring's names. Nothing is removed.
pub fn prepare_resume(dir: &Path) -> Result<OutLock, OutDirError> {
    if !dir.is_dir() {
        return Err(OutDirError::Io {
            action: "resume in",
            path: dir.to_path_buf(),
            cause: io::Error::new(io::ErrorKind::NotFound, "no such folder"),
        });
    }
    let lock = OutLock::acquire(dir)?;
    refuse_symlinks(dir)?;
    Ok(lock)
}

/// Removes the outputs phstring writes (exactly the names of the layout above) from `dir`,
/// and the folders among them that are then empty. Symbolic links are never followed: a
/// link with one of phstring's names is removed itself, its target is left alone. Other
/// files and folders stay.
pub fn clear(dir: &Path) -> Result<(), OutDirError> {
    clear_folder(dir, Folder::Top)
}

fn clear_folder(dir: &Path, folder: Folder) -> Result<(), OutDirError> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_err("read", dir)(e)),
    };
    for entry in entries {
        let entry = entry.map_err(io_err("read", dir))?;
        let name = entry.file_name();
        let Some(kind) = name.to_str().and_then(|n| classify(folder, n)) else {
            continue;
        };
        let path = entry.path();
        // `DirEntry::file_type` does not follow links.
        let ty = entry.file_type().map_err(io_err("read", &path))?;
        match kind {
            _ if ty.is_symlink() => remove_link(&path)?,
            Entry::File if !ty.is_dir() => {
                std::fs::remove_file(&path).map_err(io_err("remove", &path))?;
            }
            Entry::Dir(sub) if ty.is_dir() => {
                clear_folder(&path, sub)?;
                // Only an emptied folder goes; one holding other files stays.
                let _ = std::fs::remove_dir(&path);
            }
            // A folder where phstring writes a file, or a file where it makes a folder:
            // not phstring's, left alone.
            _ => {}
        }
    }
    Ok(())
}

fn remove_link(path: &Path) -> Result<(), OutDirError> {
    // On Unix `remove_file` removes the link itself, also a link to a folder; on Windows a
    // link to a folder is a directory link.
    std::fs::remove_file(path)
        .or_else(|_| std::fs::remove_dir(path))
        .map_err(io_err("remove", path))
}

/// Refuses a symbolic link at any of phstring's names in `dir` (recursively in phstring's
/// folders), so that no output is written through a link to somewhere else.
pub fn refuse_symlinks(dir: &Path) -> Result<(), OutDirError> {
    find_symlink(dir, Folder::Top).map_or(Ok(()), |p| Err(OutDirError::Symlink(p)))
}

fn find_symlink(dir: &Path, folder: Folder) -> Option<PathBuf> {
    for entry in std::fs::read_dir(dir).ok()?.flatten() {
        let name = entry.file_name();
        let Some(kind) = name.to_str().and_then(|n| classify(folder, n)) else {
            continue;
        };
        let path = entry.path();
        let Ok(ty) = entry.file_type() else { continue };
        if ty.is_symlink() {
            return Some(path);
        }
        if let (Entry::Dir(sub), true) = (kind, ty.is_dir())
            && let Some(p) = find_symlink(&path, sub)
        {
            return Some(p);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_names_only() {
        assert!(is_frame_name("frame_000000.vtp"));
        assert!(is_frame_name("frame_1234567.vtp"));
        assert!(!is_frame_name("frame_00001.vtp"));
        assert!(!is_frame_name("frame_0000001.vtp"));
        assert!(!is_frame_name("frame_.vtp"));
        assert!(!is_frame_name("frame_+00001.vtp"));
        assert!(is_frame_name("bodies_000040.vtp"));
        assert!(!is_frame_name("bodies_40.vtp"));
        assert!(!is_frame_name("bodies.vtp"));
        assert!(is_run_dir_name("run_000"));
        assert!(is_run_dir_name("run_1234"));
        assert!(!is_run_dir_name("run_"));
        assert!(!is_run_dir_name("run_1"));
        assert!(!is_run_dir_name("run_0001"));
        assert!(!is_run_dir_name("run_+12"));
        // A campaign's folders carry their motion table's stem.
        assert_eq!(case_dir_name(7, "surge 5m"), "run_007_surge_5m");
        assert_eq!(case_dir_name(7, ""), "run_007");
        assert!(is_run_dir_name("run_007_surge_5m"));
        assert!(is_run_dir_name("run_012_sea.state-3"));
        assert!(!is_run_dir_name("run_007_"));
        assert!(!is_run_dir_name("run_07_surge"));
        assert!(!is_run_dir_name("run_007_surge 5m"));
        assert!(!is_run_dir_name(&format!("run_007_{}", "a".repeat(41))));
        assert_eq!(classify(Folder::Top, CAMPAIGN_TABLE), Some(Entry::File));
        assert_eq!(classify(Folder::Top, "figure1.png"), None);
        assert_eq!(classify(Folder::Top, "fig2_configurations.png"), None);
        assert_eq!(
            classify(Folder::Figures, "fig2_configurations.png"),
            Some(Entry::File)
        );
        assert_eq!(classify(Folder::Figures, "fig9.png"), None);
        assert_eq!(classify(Folder::Top, LOCK_FILE), None);
    }

    #[test]
    fn out_folder_holding_an_input_is_refused() {
        let dir = crate::test_util::temp_dir("outdir", "inputs");
        let run = dir.join("run");
        std::fs::create_dir_all(run.join("sub")).unwrap();
        let cp = run.join("sub").join("checkpoint.json");
        std::fs::write(&cp, "{}").unwrap();
        let outside = dir.join("scenario.toml");
        std::fs::write(&outside, "").unwrap();
        // Deep inside, and named through `..`.
        let e = refuse_inputs_inside(&run, &[&outside, &cp]).unwrap_err();
        assert!(matches!(e, OutDirError::HoldsInput { .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains(&run.display().to_string()), "{text}");
        assert!(text.contains(&cp.display().to_string()), "{text}");
        let dotted = dir.join("run/sub/../sub/checkpoint.json");
        assert!(refuse_inputs_inside(&dir.join("run/sub/.."), &[&dotted]).is_err());
        // The folder the input is in, through a link to it.
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&run, dir.join("link")).unwrap();
            assert!(refuse_inputs_inside(&dir.join("link"), &[&cp]).is_err());
        }
        // A sibling folder, a folder not created yet, a name that only shares a prefix.
        std::fs::create_dir_all(run.join("sub2")).unwrap();
        assert!(refuse_inputs_inside(&run.join("sub2"), &[&cp]).is_ok());
        assert!(refuse_inputs_inside(&dir.join("new"), &[&cp, &outside]).is_ok());
        std::fs::create_dir_all(dir.join("ru")).unwrap();
        assert!(refuse_inputs_inside(&dir.join("ru"), &[&cp]).is_ok());
        assert!(refuse_inputs_inside(&run, &[&outside]).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
