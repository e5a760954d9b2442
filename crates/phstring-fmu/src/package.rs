//! Writing the `.fmu` archive: `modelDescription.xml`, the shared library under
//! `binaries/<platform>/<modelIdentifier>.<ext>`, the scenario under
//! `resources/scenario.toml`.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use phstring_io::scenario::ScenarioFile;

pub use crate::error::PackageError;
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

/// The keywords of C (C89 to C23): not usable as identifiers.
const C_KEYWORDS: &[&str] = &[
    "alignas",
    "alignof",
    "auto",
    "bool",
    "break",
    "case",
    "char",
    "const",
    "constexpr",
    "continue",
    "default",
    "do",
    "double",
    "else",
    "enum",
    "extern",
    "false",
    "float",
    "for",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "nullptr",
    "register",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "static_assert",
    "struct",
    "switch",
    "thread_local",
    "true",
    "typedef",
    "typeof",
    "typeof_unqual",
    "union",
    "unsigned",
    "void",
    "volatile",
    "while",
    "_Alignas",
    "_Alignof",
    "_Atomic",
    "_BitInt",
    "_Bool",
    "_Complex",
    "_Decimal128",
    "_Decimal32",
    "_Decimal64",
    "_Generic",
    "_Imaginary",
    "_Noreturn",
    "_Static_assert",
    "_Thread_local",
];

/// The model identifier for an FMU file named `stem` (`crane.fmu` → `crane`): a C
/// identifier, since FMI tools use it in file and function names (a source-code or
/// statically linked FMU prefixes its functions with it). Refused as well: C keywords,
/// names in FMI's own namespace (`fmi2…`, `fmi3…`: the functions, types and macros of the
/// FMI headers) and names C reserves (`_` followed by a capital or another `_`).
pub fn model_identifier(stem: &str) -> Result<String, PackageError> {
    let ok = stem
        .chars()
        .enumerate()
        .all(|(i, c)| c == '_' || c.is_ascii_alphabetic() || (i > 0 && c.is_ascii_digit()));
    if stem.is_empty() || !ok {
        return Err(PackageError::NotCIdentifier { stem: stem.into() });
    }
    let why = if C_KEYWORDS.contains(&stem) {
        Some("is a C keyword")
    } else if stem.starts_with("fmi2") || stem.starts_with("fmi3") {
        Some("is in FMI's namespace (fmi2…, fmi3…: the names of the FMI functions and types)")
    } else if stem.starts_with("__")
        || (stem.starts_with('_') && stem[1..].starts_with(|c: char| c.is_ascii_uppercase()))
    {
        Some("is reserved in C (a leading _ followed by a capital or _)")
    } else {
        None
    };
    match why {
        Some(why) => Err(PackageError::ReservedIdentifier {
            stem: stem.into(),
            why,
        }),
        None => Ok(stem.to_string()),
    }
}

/// The FMI function whose export marks a shared library as an FMU library of `version`.
fn entry_point(version: FmiVersion) -> &'static str {
    match version {
        FmiVersion::V2 => "fmi2Instantiate",
        FmiVersion::V3 => "fmi3InstantiateCoSimulation",
    }
}

/// Checks that `bytes` (the file `path`) is a shared library that the binaries folder
/// `folder` of this build's platform can hold: the platform's format (ELF on Linux, Mach-O
/// on macOS, PE on Windows), a shared object (not an executable or object file), this
/// build's architecture (x86_64 for `linux64` and `x86_64-linux`), and exporting the FMI
/// entry point of `version` (`fmi2Instantiate`, `fmi3InstantiateCoSimulation`). The error
/// names the file and what is wrong.
pub fn check_library(
    bytes: &[u8],
    path: &Path,
    folder: &str,
    version: FmiVersion,
) -> Result<(), PackageError> {
    use object::{Architecture, BinaryFormat, Object as _, ObjectKind};
    let bad = |what: String| PackageError::Library {
        path: path.to_path_buf(),
        what,
    };
    let expected_format = if cfg!(target_os = "macos") {
        BinaryFormat::MachO
    } else if cfg!(target_os = "windows") {
        BinaryFormat::Pe
    } else {
        BinaryFormat::Elf
    };
    let name = |f: BinaryFormat| match f {
        BinaryFormat::Elf => "ELF".to_string(),
        BinaryFormat::MachO => "Mach-O".to_string(),
        BinaryFormat::Pe => "PE".to_string(),
        other => format!("{other:?}"),
    };
    let file = object::File::parse(bytes).map_err(|e| {
        bad(format!(
            "is not a shared library (expected format {}: {e})",
            name(expected_format)
        ))
    })?;
    if file.format() != expected_format {
        return Err(bad(format!(
            "is in the {} format, binaries/{folder} needs a shared library in the {} format",
            name(file.format()),
            name(expected_format)
        )));
    }
    if file.kind() != ObjectKind::Dynamic {
        return Err(bad(format!(
            "is not a shared library but a file of kind {:?}",
            file.kind()
        )));
    }
    let arch = match std::env::consts::ARCH {
        "x86_64" => Architecture::X86_64,
        "aarch64" => Architecture::Aarch64,
        "x86" => Architecture::I386,
        _ => Architecture::Unknown,
    };
    if arch != Architecture::Unknown && file.architecture() != arch {
        return Err(bad(format!(
            "is built for {:?}, binaries/{folder} needs {arch:?}",
            file.architecture()
        )));
    }
    let entry = entry_point(version);
    let mut exported = file
        .exports()
        .map_err(|e| bad(format!("has no readable table of exported functions ({e})")))?;
    // Mach-O prefixes C names with `_`.
    let found = exported.any(|e| {
        e.is_ok_and(|e| {
            e.name().name().is_some_and(|name| {
                name == entry.as_bytes() || name.strip_prefix(b"_") == Some(entry.as_bytes())
            })
        })
    });
    if !found {
        return Err(bad(format!(
            "does not export {entry}: it is not an FMU library of FMI {}",
            if version == FmiVersion::V2 {
                "2.0"
            } else {
                "3.0"
            }
        )));
    }
    Ok(())
}

/// A data file packed into the FMU: its name under `resources/` and its bytes.
type DataFile = (String, Vec<u8>);

/// The scenario text of the FMU and the data files it reads (tables, bathymetry), each
/// under `tables/K-NAME` of the FMU's resources, where the text now names them: the FMU
/// carries everything it reads, wherever it is unpacked.
fn pack_data_files(file: &ScenarioFile) -> Result<(String, Vec<DataFile>), PackageError> {
    let files = file.data_files();
    if files.is_empty() {
        return Ok((file.text().to_string(), Vec::new()));
    }
    let mut data = Vec::with_capacity(files.len());
    let mut sets = Vec::with_capacity(files.len());
    for (k, (key, path)) in files.into_iter().enumerate() {
        let bytes = std::fs::read(&path).map_err(|cause| PackageError::DataFile {
            key: key.clone(),
            path: path.clone(),
            cause,
        })?;
        let base: String = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || ".-_".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let name = format!("tables/{k}-{base}");
        // `name` holds letters, digits, `.`, `-`, `_` and `/` only: a TOML string as it is.
        sets.push(format!("{key}=\"{name}\""));
        data.push((name, bytes));
    }
    let packed = phstring_io::scenario::parse(file.text(), &file.path, &sets)
        .map_err(|e| PackageError::Rename(e.to_string()))?;
    Ok((packed.text().to_string(), data))
}

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
    let no_platform = || PackageError::NoPlatform {
        version: if version == FmiVersion::V2 {
            "2.0"
        } else {
            "3.0"
        },
    };
    let (folder2, ext) = platform().ok_or_else(no_platform)?;
    let folder = match version {
        FmiVersion::V2 => folder2,
        FmiVersion::V3 => platform_fmi3().ok_or_else(no_platform)?,
    };
    let lib = std::fs::read(library).map_err(|cause| PackageError::ReadLibrary {
        path: library.to_path_buf(),
        cause,
    })?;
    check_library(&lib, library, folder, version)?;
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
    let (text, data) = pack_data_files(file)?;
    let mut entries: Vec<(String, &[u8])> = vec![
        ("modelDescription.xml".to_string(), description.as_bytes()),
        (format!("binaries/{folder}/{identifier}.{ext}"), &lib),
        ("resources/scenario.toml".to_string(), text.as_bytes()),
    ];
    for (name, bytes) in &data {
        entries.push((format!("resources/{name}"), bytes));
    }
    let archive = archive(&entries).map_err(|cause| PackageError::Archive {
        out: out.to_path_buf(),
        cause,
    })?;
    let result = std::fs::File::create(&tmp)
        .and_then(|mut f| write_synced(&mut f, &archive, |f| f.sync_all()))
        .and_then(|()| std::fs::rename(&tmp, out));
    if let Err(cause) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(PackageError::Write {
            out: out.to_path_buf(),
            cause,
        });
    }
    Ok(())
}

/// The zip archive of `entries` (name, bytes), deflated, in memory: so that a failing disk
/// fails a plain write of its bytes (whose error names the cause, "No space left on
/// device"), never the zip writer's finalization.
fn archive(entries: &[(String, &[u8])]) -> std::io::Result<Vec<u8>> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    for (name, bytes) in entries {
        zip.start_file(name.as_str(), options)
            .map_err(std::io::Error::other)?;
        zip.write_all(bytes)?;
    }
    Ok(zip.finish().map_err(std::io::Error::other)?.into_inner())
}

/// Writes `bytes` to `w`, then `sync` (the file's `sync_all`), each error as it is.
fn write_synced<W: std::io::Write>(
    w: &mut W,
    bytes: &[u8],
    sync: impl FnOnce(&mut W) -> std::io::Result<()>,
) -> std::io::Result<()> {
    w.write_all(bytes)?;
    w.flush()?;
    sync(w)
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

    #[test]
    fn c_keywords_and_fmi_names_are_refused_as_model_identifiers() {
        for (bad, why) in [
            ("int", "C keyword"),
            ("while", "C keyword"),
            ("_Bool", "C keyword"),
            ("fmi2Instantiate", "FMI's namespace"),
            ("fmi3DoStep", "FMI's namespace"),
            ("fmi2", "FMI's namespace"),
            ("_Crane", "reserved"),
            ("__crane", "reserved"),
        ] {
            let e = model_identifier(bad)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_else(|| panic!("{bad} accepted"));
            assert!(e.contains(why) && e.contains(bad), "{bad}: {e}");
        }
        for good in ["integer", "fmi", "fmi_crane", "my_fmi2", "_crane", "Int"] {
            assert_eq!(model_identifier(good).unwrap(), good);
        }
    }

    /// A writer whose device is full.
    struct Full;

    impl std::io::Write for Full {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::Error::from_raw_os_error(28))
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_full_disk_is_named_as_the_cause() {
        let zip = archive(&[("a.txt".to_string(), b"x".repeat(100_000).as_slice())]).unwrap();
        // The archive is complete in memory (readable, the entry whole).
        let mut read = zip::ZipArchive::new(std::io::Cursor::new(&zip)).unwrap();
        assert_eq!(read.by_name("a.txt").unwrap().size(), 100_000);
        let e = write_synced(&mut Full, &zip, |_| Ok(())).unwrap_err();
        let said = e.to_string();
        assert!(said.contains("No space left on device"), "{said}");
        assert!(!said.contains("Zip"), "{said}");
    }

    /// This build's platform folder.
    fn folder() -> &'static str {
        platform().unwrap().0
    }

    #[test]
    fn a_file_that_is_not_an_fmu_library_is_refused() {
        let path = Path::new("/x/passwd");
        let e = check_library(
            b"root:x:0:0:root:/root:/bin/sh\n",
            path,
            folder(),
            FmiVersion::V2,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("/x/passwd") && e.contains("not a shared library"),
            "{e}"
        );
        // An executable (this test) is not a shared library, or does not export the entry.
        let exe = std::env::current_exe().unwrap();
        let e = check_library(
            &std::fs::read(&exe).unwrap(),
            &exe,
            folder(),
            FmiVersion::V2,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("not a shared library") || e.contains("does not export fmi2Instantiate"),
            "{e}"
        );
    }
}
