//! `phstring fmu` (issue 16): the archive's layout and model description, networks'
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
