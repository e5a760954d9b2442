//! Writing the `.fmu` archive: `modelDescription.xml`, the shared library under
//! `binaries/<platform>/<modelIdentifier>.<ext>`, the scenario under
//! `resources/scenario.toml`.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use phstring_io::scenario::ScenarioFile;

use crate::model::ModelSpec;

/// The FMI platform folder and shared-library extension of this build's target, if FMI 2.0
/// names one.
pub fn platform() -> Option<(&'static str, &'static str)> {
    let bits64 = cfg!(target_pointer_width = "64");
    if cfg!(target_os = "linux") {
        Some((if bits64 { "linux64" } else { "linux32" }, "so"))
    } else if cfg!(target_os = "macos") {
        Some(("darwin64", "dylib"))
    } else if cfg!(target_os = "windows") {
        Some((if bits64 { "win64" } else { "win32" }, "dll"))
    } else {
        None
    }
}

/// The FMI 3.0 platform tuple (`x86_64-linux`, …) of this build's target, if FMI 3.0 names
/// one.
pub fn platform_fmi3() -> Option<&'static str> {
    let arch = match std::env::consts::ARCH {
        "x86_64" => "x86_64",
        "aarch64" => "aarch64",
        "x86" => "x86",
        _ => return None,
    };
    let os = match std::env::consts::OS {
        "linux" => "linux",
        "macos" => "darwin",
        "windows" => "windows",
        _ => return None,
    };
    // Only the tuples the standard lists.
    Some(match (arch, os) {
        ("x86_64", "linux") => "x86_64-linux",
        ("aarch64", "linux") => "aarch64-linux",
        ("x86", "linux") => "x86-linux",
        ("x86_64", "darwin") => "x86_64-darwin",
        ("aarch64", "darwin") => "aarch64-darwin",
        ("x86_64", "windows") => "x86_64-windows",
        ("x86", "windows") => "x86-windows",
        _ => return None,
    })
}

/// The FMI version of an FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FmiVersion {
    /// FMI 2.0 (the default: the version most tools import).
    V2,
    /// FMI 3.0.
    V3,
}

/// File name of this crate's shared library as Cargo builds it (`libphstring_fmu.so`, …).
pub fn library_file_name() -> String {
    format!(
        "{}phstring_fmu{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    )
}

/// Where Cargo puts the shared library when it builds the `phstring` executable at `exe`:
/// in its `deps/` folder (built with the executable, as a dependency of the CLI), or next to
/// it (`cargo build -p phstring-fmu`, or an installation that copied it there).
pub fn library_candidates(exe: &Path) -> Vec<PathBuf> {
    let name = library_file_name();
    exe.parent()
        .map(|dir| vec![dir.join("deps").join(&name), dir.join(&name)])
        .unwrap_or_default()
}

/// The model identifier for an FMU file named `stem` (`crane.fmu` → `crane`): a C
/// identifier, since FMI tools use it in file and function names.
pub fn model_identifier(stem: &str) -> Result<String, String> {
    let ok = stem
        .chars()
        .enumerate()
        .all(|(i, c)| c == '_' || c.is_ascii_alphabetic() || (i > 0 && c.is_ascii_digit()));
    if stem.is_empty() || !ok {
        return Err(format!(
            "the FMU's file name {stem:?} must be a C identifier (letters, digits and _, not starting with a digit): FMI tools name the model's shared library after it"
        ));
    }
    Ok(stem.to_string())
}

/// A failure to write the archive.
#[derive(Debug)]
pub struct PackageError(pub String);

impl std::fmt::Display for PackageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PackageError {}

/// Writes the FMU (FMI `version`) of `file` (variables `spec`) with the shared library
/// `library` to `out`. The archive is written to a temporary file next to `out` and renamed
/// into place, so `out` is either the complete FMU or untouched.
pub fn write_fmu(
    file: &ScenarioFile,
    spec: &ModelSpec,
    identifier: &str,
    library: &Path,
    out: &Path,
    version: FmiVersion,
) -> Result<(), PackageError> {
    let no_platform = || {
        PackageError(format!(
            "FMI {} names no binaries folder for this platform",
            if version == FmiVersion::V2 {
                "2.0"
            } else {
                "3.0"
            }
        ))
    };
    let (folder2, ext) = platform().ok_or_else(no_platform)?;
    let folder = match version {
        FmiVersion::V2 => folder2,
        FmiVersion::V3 => platform_fmi3().ok_or_else(no_platform)?,
    };
    let lib = std::fs::read(library).map_err(|e| {
        PackageError(format!(
            "cannot read the FMU library {}: {e}",
            library.display()
        ))
    })?;
    let description = match version {
        FmiVersion::V2 => spec.model_description(identifier),
        FmiVersion::V3 => spec.model_description_fmi3(identifier),
    };
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let tmp = dir.join(format!(
        ".{}.partial-{}",
        out.file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        std::process::id()
    ));
    let result = write_archive(
        &tmp,
        &[
            ("modelDescription.xml".to_string(), description.as_bytes()),
            (format!("binaries/{folder}/{identifier}.{ext}"), &lib),
            (
                "resources/scenario.toml".to_string(),
                file.text().as_bytes(),
            ),
        ],
    )
    .and_then(|()| std::fs::rename(&tmp, out));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(PackageError(format!("cannot write {}: {e}", out.display())));
    }
    Ok(())
}

/// A zip archive at `path` with `entries` (name, bytes), deflated.
fn write_archive(path: &Path, entries: &[(String, &[u8])]) -> std::io::Result<()> {
    let f = std::fs::File::create(path)?;
    let mut zip = zip::ZipWriter::new(std::io::BufWriter::new(f));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    for (name, bytes) in entries {
        zip.start_file(name.as_str(), options)
            .map_err(std::io::Error::other)?;
        zip.write_all(bytes)?;
    }
    let mut w = zip.finish().map_err(std::io::Error::other)?;
    w.flush()?;
    w.into_inner().map_err(|e| e.into_error())?.sync_all()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_identifiers_are_c_identifiers() {
        assert_eq!(model_identifier("crane_2d").unwrap(), "crane_2d");
        for bad in ["", "2d", "my-crane", "a b", "kran\u{e4}"] {
            assert!(model_identifier(bad).is_err(), "{bad:?}");
        }
    }
}
