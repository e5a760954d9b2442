//! `phstring fmu`: the archive's layout and model description, networks'
//! parameters, and refusals that name what is wrong and leave no file behind.

use std::io::Read as _;
use std::path::Path;

use crate::{phstring, temp_dir, workspace_root};

/// The entries of the zip archive at `p`: (name, content).
fn entries(p: &Path) -> Vec<(String, Vec<u8>)> {
    let mut z = zip::ZipArchive::new(std::fs::File::open(p).unwrap()).unwrap();
    (0..z.len())
        .map(|i| {
            let mut f = z.by_index(i).unwrap();
            let mut bytes = Vec::new();
            f.read_to_end(&mut bytes).unwrap();
            (f.name().unwrap().to_string(), bytes)
        })
        .collect()
}

fn fmu(args: &[&str]) -> std::process::Output {
    let mut all = vec!["fmu"];
    all.extend_from_slice(args);
    phstring(&all)
}

#[test]
fn the_pendulum_fmu_holds_description_library_and_scenario() {
    let dir = temp_dir("fmu-pendulum");
    let out = dir.join("pendulum.fmu");
    let o = fmu(&["examples/fmu/pendulum.toml", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("2 inputs, 12 outputs, 3 parameters"),
        "{said}"
    );
    let e = entries(&out);
    let names: Vec<&str> = e.iter().map(|(n, _)| n.as_str()).collect();
    let lib = format!(
        "binaries/{}/pendulum.{}",
        phstring_fmu::package::platform().unwrap().0,
        phstring_fmu::package::platform().unwrap().1
    );
    assert_eq!(
        names,
        [
            "modelDescription.xml",
            lib.as_str(),
            "resources/scenario.toml"
        ]
    );
    let scenario = std::fs::read(workspace_root().join("examples/fmu/pendulum.toml")).unwrap();
    assert_eq!(e[2].1, scenario, "the scenario is packaged as it is");
    // The library is a shared object of this build, with the FMI functions.
    let so = &e[1].1;
    assert!(so.len() > 100_000);
    for f in [
        "fmi2Instantiate",
        "fmi2DoStep",
        "fmi2GetFMUstate",
        "fmi2SerializeFMUstate",
    ] {
        assert!(
            so.windows(f.len()).any(|w| w == f.as_bytes()),
            "{f} is not in the library"
        );
    }
    let xml = String::from_utf8(e[0].1.clone()).unwrap();
    for needle in [
        "fmiVersion=\"2.0\"",
        "modelIdentifier=\"pendulum\"",
        "name=\"load0.F.x\" valueReference=\"3\"",
        "causality=\"input\"",
        "name=\"node30.r.y\"",
        "<DefaultExperiment startTime=\"0\" stopTime=\"1.0\" stepSize=\"0.01\"/>",
    ] {
        assert!(xml.contains(needle), "{needle} not in\n{xml}");
    }
}

#[test]
fn a_network_has_parameters_per_material() {
    let dir = temp_dir("fmu-network");
    let out = dir.join("platform.fmu");
    let o = fmu(&["examples/platform_3d.toml", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("EA.steel") && said.contains("rhoA.steel"),
        "{said}"
    );
    assert!(said.contains("no inputs: mark a [[boundary]]"), "{said}");
}

#[test]
fn refusals_name_the_problem_and_write_nothing() {
    let dir = temp_dir("fmu-refusals");
    let cases: [(Vec<String>, &str); 6] = [
        (
            vec!["-o".into(), dir.join("2d-crane.fmu").display().to_string()],
            "must be a C identifier",
        ),
        (
            vec!["-o".into(), dir.join("crane.zip").display().to_string()],
            "ends in .fmu",
        ),
        (
            vec![
                "-o".into(),
                dir.join("crane.fmu").display().to_string(),
                "--library".into(),
                dir.join("missing.so").display().to_string(),
            ],
            "missing.so",
        ),
        (
            vec![
                "-o".into(),
                dir.join("crane.fmu").display().to_string(),
                "--set".into(),
                "boundary.0.external=true".into(),
            ],
            "boundary.0.external",
        ),
        (
            vec![
                "-o".into(),
                dir.join("crane.fmu").display().to_string(),
                "--set".into(),
                "fmu.nodes=[3, -28]".into(),
            ],
            "fmu.nodes.1",
        ),
        (
            vec![
                "-o".into(),
                dir.join("crane.fmu").display().to_string(),
                "--set".into(),
                "boundary.1.force=[\"1/t\", \"0\"]".into(),
            ],
            "the start value of the FMU input load0.F.x",
        ),
    ];
    for (args, needle) in cases {
        let mut all = vec!["examples/fmu/pendulum.toml"];
        all.extend(args.iter().map(String::as_str));
        let o = fmu(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

#[test]
fn fmi_3_puts_the_library_under_the_platform_tuple() {
    let dir = temp_dir("fmu-fmi3");
    let out = dir.join("pendulum.fmu");
    let o = fmu(&[
        "examples/fmu/pendulum.toml",
        "-o",
        out.to_str().unwrap(),
        "--fmi-version",
        "3",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e = entries(&out);
    let lib = format!(
        "binaries/{}/pendulum.{}",
        phstring_fmu::package::platform_fmi3().unwrap(),
        phstring_fmu::package::platform().unwrap().1
    );
    assert_eq!(e[1].0, lib);
    let xml = String::from_utf8(e[0].1.clone()).unwrap();
    assert!(xml.contains("fmiVersion=\"3.0\""));
    assert!(xml.contains("causality=\"independent\""));
    let o = fmu(&[
        "examples/fmu/pendulum.toml",
        "-o",
        out.to_str().unwrap(),
        "--fmi-version",
        "4",
    ]);
    assert!(!o.status.success());
}

#[test]
fn an_existing_fmu_is_replaced_only_with_force() {
    let dir = temp_dir("fmu-force");
    let out = dir.join("exists.fmu");
    std::fs::write(&out, "mine").unwrap();
    let o = fmu(&["examples/fmu/pendulum.toml", "-o", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("exists.fmu") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine");
    let o = fmu(&[
        "examples/fmu/pendulum.toml",
        "-o",
        out.to_str().unwrap(),
        "--force",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(entries(&out)[0].0, "modelDescription.xml");
}

#[test]
fn c_keywords_and_fmi_names_are_refused_as_model_identifiers() {
    let dir = temp_dir("fmu-identifiers");
    for (name, why) in [
        ("int", "C keyword"),
        ("fmi2Instantiate", "FMI's namespace"),
        ("fmi3DoStep", "FMI's namespace"),
    ] {
        let out = dir.join(format!("{name}.fmu"));
        let o = fmu(&["examples/fmu/pendulum.toml", "-o", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name} accepted");
        assert!(err.contains(name) && err.contains(why), "{name}: {err}");
    }
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none());
}

/// The library built with this `phstring` (the one `phstring fmu` packages by default).
fn built_library() -> std::path::PathBuf {
    phstring_fmu::package::library_candidates(Path::new(env!("CARGO_BIN_EXE_phstring")))
        .into_iter()
        .find(|p| p.is_file())
        .expect("the FMU library is built with the phstring binary")
}

/// Runs `phstring fmu` on the pendulum with `PHSTRING_FMU_LIBRARY` set to `library`.
fn fmu_with_library_env(out: &Path, library: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_phstring"))
        .args(["fmu", "examples/fmu/pendulum.toml", "-o"])
        .arg(out)
        .env("PHSTRING_FMU_LIBRARY", library)
        .current_dir(workspace_root())
        .output()
        .unwrap()
}

#[test]
fn a_library_that_is_not_an_fmu_library_is_refused() {
    let dir = temp_dir("fmu-library");
    let lib_dir = temp_dir("fmu-library-files");
    let out = dir.join("crane.fmu");
    // A text file (an account list), given by option and by environment.
    let text = lib_dir.join("passwd");
    std::fs::write(&text, "root:x:0:0:root:/root:/bin/sh\n").unwrap();
    let o = fmu(&[
        "examples/fmu/pendulum.toml",
        "-o",
        out.to_str().unwrap(),
        "--library",
        text.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains(text.to_str().unwrap()) && err.contains("not a shared library"),
        "{err}"
    );
    let o = fmu_with_library_env(&out, &text);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("not a shared library"), "{err}");
    // A shared object of the platform that is not an FMU library: a program (PIE).
    if cfg!(target_os = "linux") && Path::new("/bin/ls").is_file() {
        let o = fmu(&[
            "examples/fmu/pendulum.toml",
            "-o",
            out.to_str().unwrap(),
            "--library",
            "/bin/ls",
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(
            err.contains("/bin/ls") && err.contains("does not export fmi2Instantiate"),
            "{err}"
        );
    }
    // The real library with its ELF machine changed to AArch64 (183): another platform's.
    if cfg!(all(target_os = "linux", target_arch = "x86_64")) {
        let mut bytes = std::fs::read(built_library()).unwrap();
        bytes[18..20].copy_from_slice(&183u16.to_le_bytes());
        let arm = lib_dir.join("libarm.so");
        std::fs::write(&arm, &bytes).unwrap();
        let o = fmu_with_library_env(&out, &arm);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(
            err.contains("libarm.so") && err.contains("Aarch64") && err.contains("X86_64"),
            "{err}"
        );
    }
    assert!(
        std::fs::read_dir(&dir).unwrap().next().is_none(),
        "nothing is written"
    );
    // The library itself passes for both versions.
    for v in ["2", "3"] {
        let lib = built_library();
        let o = fmu(&[
            "examples/fmu/pendulum.toml",
            "-o",
            out.to_str().unwrap(),
            "--library",
            lib.to_str().unwrap(),
            "--fmi-version",
            v,
            "--force",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
}

/// A write that fails (here the file-size limit, as a full disk would) names the cause,
/// without the zip crate's internals, and leaves no partial file.
#[cfg(target_os = "linux")]
#[test]
fn a_failing_write_names_the_cause_and_leaves_nothing() {
    let dir = temp_dir("fmu-full");
    let out = dir.join("crane.fmu");
    // `ulimit -f 64`: files up to 32 kB (the library alone is far larger); SIGXFSZ ignored
    // so that the write fails with EFBIG instead of killing the process.
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 64; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_phstring"))
        .args(["fmu", "examples/fmu/pendulum.toml", "-o"])
        .arg(&out)
        .current_dir(workspace_root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("cannot write") && err.contains("File too large"),
        "{err}"
    );
    assert!(!err.contains("ZipWriter") && !err.contains("Os {"), "{err}");
    assert!(
        std::fs::read_dir(&dir).unwrap().next().is_none(),
        "a partial file is left"
    );
}

/// An FMU carries the data files its scenario reads: the platform table of
/// `examples/spread_mooring_platform.toml` is packed under `resources/tables/` and the
/// packed scenario names it there, so the FMU unpacked anywhere else still finds it.
#[test]
fn an_fmu_packs_the_tables_its_scenario_reads() {
    let dir = temp_dir("fmu-tables");
    let out = dir.join("platform.fmu");
    let o = fmu(&[
        "examples/spread_mooring_platform.toml",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e = entries(&out);
    let table = e
        .iter()
        .find(|(n, _)| n == "resources/tables/0-oc4_platform.csv")
        .unwrap_or_else(|| panic!("{:?}", e.iter().map(|x| &x.0).collect::<Vec<_>>()));
    let source = std::fs::read(workspace_root().join("examples/tables/oc4_platform.csv")).unwrap();
    assert_eq!(table.1, source);
    let (_, scenario) = e
        .iter()
        .find(|(n, _)| n == "resources/scenario.toml")
        .unwrap();
    let scenario = String::from_utf8(scenario.clone()).unwrap();
    assert!(
        scenario.contains(r#"motion_table = "tables/0-oc4_platform.csv""#),
        "{scenario}"
    );
    // Unpacked elsewhere, the scenario checks: it finds its table beside it.
    let unpacked = dir.join("unpacked");
    for (name, bytes) in &e {
        if let Some(rest) = name.strip_prefix("resources/") {
            let path = unpacked.join(rest);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, bytes).unwrap();
        }
    }
    let o = phstring(&["check", unpacked.join("scenario.toml").to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
