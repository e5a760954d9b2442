//! Tests of the mapping of decks onto scenarios: what the example decks become, value by
//! value, and a refusal naming the deck line for every feature the mapping does not model.

use std::path::Path;

use super::*;
use crate::scenario::{self, Scenario, ScenarioFile};

const SPAR_V2: &str = include_str!("../../../../examples/moordyn/spar_oc3_v2.dat");
const CHAIN_V1: &str = include_str!("../../../../examples/moordyn/chain_shallow_v1.dat");

/// The mapping of deck `text` (named `deck.dat`) and the scenario it parses into.
fn mapped(text: &str, ignore: &[Feature]) -> (Mapping, ScenarioFile) {
    let deck = parse(text, "deck.dat").unwrap_or_else(|e| panic!("{e}"));
    let m = map(&deck, ignore).unwrap_or_else(|e| panic!("{e}"));
    let file = scenario::parse(&m.scenario, Path::new("deck.dat (generated scenario)"), &[])
        .unwrap_or_else(|e| panic!("{e}\n{}", m.scenario));
    (m, file)
}

/// The names of the output channels a generated scenario writes.
fn channel_names(s: &crate::scenario::Scenario) -> Vec<&str> {
    s.output
        .channels
        .iter()
        .map(|c| c.get_ref().as_str())
        .collect()
}

/// The refusal of deck `text`.
fn refused(text: &str) -> String {
    let deck = parse(text, "deck.dat").unwrap_or_else(|e| panic!("{e}"));
    map(&deck, &[])
        .expect_err("the deck should be refused")
        .to_string()
}

/// The line of `text` (1-based) holding `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

fn material<'a>(s: &'a Scenario, name: &str) -> &'a crate::scenario::MaterialSpec {
    s.materials[name].get_ref()
}

fn opt(x: &Option<toml::Spanned<f64>>) -> Option<f64> {
    x.as_ref().map(|v| *v.get_ref())
}

/// The v1 chain deck: three lines of 40 elements of 10 m, six supports, the damping ratio
/// converted per line, and the options as settings.
#[test]
fn the_chain_deck_maps_value_by_value() {
    let (m, file) = mapped(CHAIN_V1, &[]);
    let s = &file.scenario;
    assert_eq!(*s.dimension.get_ref(), 3);
    assert_eq!(s.string.len(), 3);
    // 6 points and 3 × 39 interior nodes.
    assert_eq!(s.node.len(), 6 + 3 * 39);
    for (k, st) in s.string.iter().enumerate() {
        let st = st.get_ref();
        assert_eq!(st.name.get_ref(), &format!("line{}", k + 1));
        assert_eq!(st.path.get_ref().len(), 41);
        assert_eq!(*st.elements.get_ref(), 1);
        assert!(st.prestretch.is_none(), "slack lines start stress-free");
        let mat = material(s, st.material.get_ref());
        assert_eq!(mat.law.get_ref(), "tension_only_linear");
        assert_eq!(mat.mass.get_ref(), "lumped");
        assert_eq!((*mat.ea.get_ref(), *mat.rho_a.get_ref()), (1.674e9, 390.0));
        assert_eq!(opt(&mat.diameter), Some(0.252));
        // v1 columns Can Cat Cdn Cdt = 1.0 0.5 2.4 1.15.
        assert_eq!(
            (
                opt(&mat.cd),
                opt(&mat.ca),
                opt(&mat.cd_axial),
                opt(&mat.ca_axial)
            ),
            (Some(2.4), Some(1.0), Some(1.15), Some(0.5))
        );
        // BA = ζ l_seg √(EA ρA) with ζ = 1, l_seg = 10 m; η = BA/2.
        let eta = 0.5 * 10.0 * (1.674e9_f64 * 390.0).sqrt();
        let kv = opt(&mat.kelvin_voigt).unwrap();
        assert!((kv - eta).abs() <= 1e-12 * eta, "{kv} vs {eta}");
    }
    // Every element 10 m: the chords of each string's path.
    let pos: std::collections::HashMap<&str, Vec<f64>> = s
        .node
        .iter()
        .map(|n| {
            (
                n.get_ref().name.get_ref().as_str(),
                n.get_ref().position.get_ref().clone(),
            )
        })
        .collect();
    for st in &s.string {
        let names: Vec<String> = st
            .get_ref()
            .path
            .get_ref()
            .iter()
            .map(|r| r.get_ref().to_string())
            .collect();
        for w in names.windows(2) {
            let (a, b) = (&pos[w[0].trim_matches('"')], &pos[w[1].trim_matches('"')]);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!((d - 10.0).abs() <= 1e-9, "{w:?}: {d}");
        }
    }
    // Six supports: anchors and the vessel's fairleads, held.
    assert_eq!(s.boundary.len(), 6);
    assert!(
        m.record
            .converted
            .iter()
            .filter(|c| c.contains("(Vessel) is held"))
            .count()
            == 3
    );
    // Options: dtM, WtrDpth, kb, cb; g and density by default; 60 s; a frame every 0.1 s.
    assert_eq!(*s.time.h.get_ref(), 0.0005);
    assert_eq!(*s.time.end.get_ref(), 60.0);
    assert_eq!(*s.output.stride.get_ref(), 200);
    assert_eq!(
        s.body_force.gravity.as_ref().unwrap().get_ref(),
        &vec![0.0, 0.0, -9.80665]
    );
    let w = s.water.as_ref().unwrap().get_ref();
    assert_eq!((opt(&w.density), opt(&w.depth)), (Some(1025.0), Some(50.0)));
    let b = s.seabed.as_ref().unwrap().get_ref();
    assert_eq!(*b.stiffness.get_ref(), 3.0e6);
    assert_eq!(
        (opt(&b.damping), opt(&b.friction), opt(&b.friction_damping)),
        (Some(3.0e5), Some(0.0), Some(200.0))
    );
    assert!(*s.initial.as_ref().unwrap().equilibrium.get_ref());
    // Not needed, with reasons; recorded in [deck].
    let d = s.deck.as_ref().unwrap();
    assert_eq!(d, &m.record);
    assert_eq!((d.path.as_str(), d.version.as_str()), ("deck.dat", "v1"));
    let keys: Vec<&str> = d.not_needed.keys().map(String::as_str).collect();
    assert_eq!(keys, ["CdScaleIC", "TmaxIC", "threshIC"]);
    // The OUTPUTS channels become columns of deck.out, MoorDyn's main output file.
    let channels = channel_names(s);
    assert_eq!(
        channels,
        ["FairTen1", "FairTen2", "FairTen3", "Con4pX", "L1N10T"]
    );
    assert_eq!(
        s.output
            .channels_file
            .as_ref()
            .map(|f| f.get_ref().as_str()),
        Some("deck.out")
    );
    // The rows of `check`: one per type, point, line, option and output channel, in deck
    // order.
    let lines: Vec<usize> = m.rows.iter().map(|r| r.line).collect();
    assert_eq!(
        lines,
        [
            6, 10, 11, 12, 13, 14, 15, 19, 20, 21, 23, 24, 25, 26, 27, 28, 29, 31, 31, 31, 32, 33,
            0, 0
        ]
    );
    file.setup().unwrap_or_else(|e| panic!("{e}"));
}

/// The v2 spar deck: 20 elements of 45.11 m per line, `rho` as the density, `g`, and the
/// options not needed.
#[test]
fn the_spar_deck_maps_value_by_value() {
    let (m, file) = mapped(SPAR_V2, &[]);
    let s = &file.scenario;
    assert_eq!(s.string.len(), 3);
    assert_eq!(s.node.len(), 6 + 3 * 19);
    let mat = material(s, "spar_line_line3");
    assert_eq!(
        (*mat.ea.get_ref(), *mat.rho_a.get_ref()),
        (384.243e6, 77.7066)
    );
    assert_eq!(
        (
            opt(&mat.cd),
            opt(&mat.ca),
            opt(&mat.cd_axial),
            opt(&mat.ca_axial)
        ),
        (Some(1.6), Some(1.0), Some(0.1), Some(0.0))
    );
    let eta = 0.5 * 0.8 * (902.2 / 20.0) * (384.243e6_f64 * 77.7066).sqrt();
    let kv = opt(&mat.kelvin_voigt).unwrap();
    assert!((kv - eta).abs() <= 1e-12 * eta, "{kv} vs {eta}");
    assert_eq!((*s.time.h.get_ref(), *s.time.end.get_ref()), (0.002, 60.0));
    assert_eq!(*s.output.stride.get_ref(), 50);
    assert_eq!(
        s.body_force.gravity.as_ref().unwrap().get_ref(),
        &vec![0.0, 0.0, -9.80665]
    );
    let w = s.water.as_ref().unwrap().get_ref();
    assert_eq!(
        (opt(&w.density), opt(&w.depth)),
        (Some(1025.0), Some(320.0))
    );
    let keys: Vec<&str> = m.record.not_needed.keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "CdScaleIC",
            "TmaxIC",
            "dtIC",
            "line output flags",
            "tScheme",
            "threshIC"
        ]
    );
    let row = m
        .rows
        .iter()
        .find(|r| r.entry.starts_with("line 1 "))
        .unwrap();
    assert_eq!(row.line, line_of(SPAR_V2, "1   spar_line"));
    assert!(
        row.became
            .starts_with("string line1: 20 elements of 45.11 m from point1 to point4"),
        "{}",
        row.became
    );
}

/// Taut and negative-length lines, free points with and without mass, BA ≥ 0, dtOut and
/// friction.
#[test]
fn taut_lines_free_points_and_positive_ba() {
    let text = "t\n--- LINE TYPES ---\nName Diam MassDen EA BA EI Cd Ca CdAx CaAx\n(-) (m) (kg/m) (N) (Ns) (Nm2) (-) (-) (-) (-)\n\
                wire 0.1 20 1e8 4e5 0 1.2 1 0.2 0\n--- POINTS ---\nID Att X Y Z M V CdA Ca\n(#) (-) (m) (m) (m) (kg) (m3) (m2) (-)\n\
                1 Fixed 100 0 -50 0 0 0 0\n2 Free 50 0 -30 2000 1.5 0.8 1.0\n3 Vessel 0 0 -5 0 0 0 0\n4 Connect 60 10 -20 0 0 0 0\n5 Fixed 90 20 -50 0 0 0 0\n\
                --- LINES ---\nID Type A B L N Out\n(#) (-) (#) (#) (m) (-) (-)\n1 wire 1 2 60 6 -\n2 wire 2 3 -1.2 5 -\n3 wire 4 5 40 4 -\n4 wire 2 4 14 2 -\n\
                --- OPTIONS ---\n0.01 dtM\n50 WtrDpth\n0.5 dtOut\n0.4 FrictionCoefficient\n150 FricDamp\n1.5 StatDynFricScale\n--- END ---\n";
    let (m, file) = mapped(text, &[]);
    let s = &file.scenario;
    let mat = material(s, "wire");
    assert_eq!(opt(&mat.kelvin_voigt), Some(2e5));
    // Line 1 runs 53.85 m < 60 m (slack): stress-free. Line 2: 1.2 × its 55.2 m span,
    // slack. Line 3: 41.23 m > 40 m: straight, stretched 41.23/40.
    let st = |k: usize| s.string[k].get_ref();
    assert!(st(0).prestretch.is_none());
    let span3 = (30.0_f64.powi(2) + 10.0_f64.powi(2) + 30.0_f64.powi(2)).sqrt();
    let p3 = *st(2).prestretch.as_ref().unwrap().get_ref();
    assert!((p3 - span3 / 40.0).abs() <= 1e-15, "{p3}");
    assert!(
        m.record
            .converted
            .iter()
            .any(|c| c.contains("UnstrLen = -1.2 of line 2"))
    );
    // A free point with mass is a point mass; one without is a junction.
    assert_eq!(s.point_mass.len(), 1);
    let pm = &s.point_mass[0];
    assert_eq!(pm.node.get_ref().to_string(), "\"point2\"");
    assert_eq!(*pm.kg.get_ref(), 2000.0);
    assert_eq!(
        (opt(&pm.volume), opt(&pm.cda), opt(&pm.ca)),
        (Some(1.5), Some(0.8), Some(1.0))
    );
    assert_eq!(s.boundary.len(), 3);
    assert_eq!(*s.output.stride.get_ref(), 50);
    let b = s.seabed.as_ref().unwrap().get_ref();
    assert_eq!(
        (
            opt(&b.friction),
            opt(&b.friction_damping),
            opt(&b.friction_static_scale),
            opt(&b.friction_axial)
        ),
        (Some(0.4), Some(150.0), Some(1.5), None)
    );
    // StatDynFricScale is mapped, not converted with a warning.
    assert!(
        !m.record
            .converted
            .iter()
            .any(|c| c.contains("StatDynFricScale"))
    );
    assert!(m.rows.iter().any(|r| r.entry.contains("StatDynFricScale")
        && r.became == "seabed.friction_static_scale = 1.5"));
    assert!(m.record.converted.iter().any(|c| {
        c.contains("BA = 400000 N·s of line type wire → kelvin_voigt η = BA/2 = 200000 N·s")
    }));
    file.setup().unwrap_or_else(|e| panic!("{e}"));
}

/// Every feature the mapping does not model is refused naming its deck line (and the
/// `--ignore` word where it can be dropped); with the word, the deck maps and the record
/// lists what was dropped.
#[test]
fn unsupported_features_are_refused_with_their_line() {
    let base = SPAR_V2.to_string();
    let types_row = "spar_line 0.09   77.7066   384.243e6   -0.8      0     1.6   1.0   0.1   0.0";
    let with_row = |old: &str, new: &str| base.replace(old, new);
    let section = |title: &str| {
        base.replace(
            "---------------------- OPTIONS",
            &format!("--- {title} ---\nName X\n(-) (-)\na 1\n---------------------- OPTIONS"),
        )
    };
    let option = |o: &str| base.replace("0.002     dtM", &format!("{o}\n0.002     dtM"));
    let cases: Vec<(String, &str, Option<Feature>, &str)> = vec![
        (
            with_row(
                types_row,
                &types_row.replace("-0.8      0  ", "-0.8      2e4"),
            ),
            "spar_line 0.09",
            Some(Feature::BendingStiffness),
            "bending stiffness EI = 20000",
        ),
        (
            with_row(types_row, &types_row.replace("384.243e6", "ea.txt")),
            "spar_line 0.09",
            None,
            "EA from the curve file `ea.txt`",
        ),
        (
            with_row(types_row, &types_row.replace("384.243e6", "3e8|4e8")),
            "spar_line 0.09",
            None,
            "viscoelastic EA `3e8|4e8`",
        ),
        (
            with_row(types_row, &types_row.replace("-0.8  ", "ba.txt")),
            "spar_line 0.09",
            None,
            "BA from the curve file `ba.txt`",
        ),
        (
            section("ROD TYPES"),
            "ROD TYPES",
            Some(Feature::Rods),
            "section `ROD TYPES`",
        ),
        (
            section("RODS"),
            "--- RODS",
            Some(Feature::Rods),
            "section `RODS`",
        ),
        (
            section("FAILURE"),
            "FAILURE",
            Some(Feature::Failure),
            "section `FAILURE`",
        ),
        (
            section("CONTROL"),
            "CONTROL",
            Some(Feature::Control),
            "section `CONTROL`",
        ),
        (
            section("EXTERNAL LOADS"),
            "EXTERNAL LOADS",
            Some(Feature::ExternalLoads),
            "section `EXTERNAL LOADS`",
        ),
        (
            section("SYROPE IC"),
            "SYROPE IC",
            Some(Feature::SyropeIc),
            "section `SYROPE IC`",
        ),
        (
            section("MYSTERY"),
            "MYSTERY",
            Some(Feature::UnknownSections),
            "section `MYSTERY`",
        ),
        (
            option("1 WaveKin"),
            "1 WaveKin",
            Some(Feature::Waves),
            "option WaveKin = 1 (WaveKin from files)",
        ),
        (
            option("2 Currents"),
            "2 Currents",
            Some(Feature::Currents),
            "option Currents = 2 (Currents from files)",
        ),
        (
            option("bathy.txt SeafloorFile"),
            "SeafloorFile",
            None,
            "a bathymetry file",
        ),
        (
            base.replace("320       WtrDpth", "bathy.txt WtrDpth"),
            "WtrDpth",
            None,
            "WtrDpth `bathy.txt` (a bathymetry file",
        ),
        (
            option("3 WaterKinematicsMode"),
            "WaterKinematicsMode",
            Some(Feature::UnknownOptions),
            "option `WaterKinematicsMode`",
        ),
        (
            with_row("4   Vessel      5.2", "4   Turbine2    5.2"),
            "4   Turbine2",
            None,
            "attached to turbine 2",
        ),
        (
            with_row("3   spar_line  3        6", "3   spar_line  3        R1B"),
            "3   spar_line",
            None,
            "line 3 attached to end B of rod 1",
        ),
        (
            with_row(
                "4   Vessel      5.2       0.0       -70.0   0     0",
                "4   Free        5.2       0.0       -70.0   0     3",
            ),
            "4   Free",
            None,
            "point 4 with Volume, CdA or Ca but no Mass",
        ),
    ];
    for (text, needle, feature, what) in &cases {
        let line = line_of(text, needle);
        let e = refused(text);
        assert!(
            e.starts_with(&format!("deck.dat:{line}: ")),
            "{needle}: {e}"
        );
        assert!(e.contains(what), "{needle}: {e}");
        assert!(e.contains("is not supported by phstring"), "{e}");
        match feature {
            Some(f) => {
                assert!(e.contains(&format!("`--ignore {}`", f.word())), "{e}");
                let (m, _) = mapped(text, &[*f]);
                assert_eq!(m.record.ignored.len(), 1, "{needle}");
                assert!(m.record.ignored[0].starts_with(&format!("deck.dat:{line}: ")));
                assert!(m.scenario.contains(&format!("(--ignore {})", f.word())));
            }
            None => assert!(!e.contains("--ignore"), "{e}"),
        }
    }
}

/// The VIV columns, other extra columns and point forces (v1 decks' FX FY FZ).
#[test]
fn viv_extra_columns_and_point_forces_are_refused() {
    let v2 = SPAR_V2
        .replace(
            "EI    Cd    Ca    CdAx  CaAx",
            "EI    Cd    Ca    CdAx  CaAx Cl dF cF",
        )
        .replace("0.1   0.0\n", "0.1   0.0  0.8 0.1 0.2\n");
    let line = line_of(&v2, "spar_line 0.09");
    let e = refused(&v2);
    assert!(
        e.starts_with(&format!(
            "deck.dat:{line}: vortex-induced vibration (Cl = 0.8)"
        )),
        "{e}"
    );
    // Zero VIV coefficients are VIV switched off: mapped.
    mapped(&v2.replace("0.8 0.1 0.2", "0 0 0"), &[]);
    let other = v2
        .replace("Cl dF cF", "Xx dF cF")
        .replace("0.8 0.1 0.2", "0.8 0 0");
    assert!(refused(&other).contains("line type column `Xx` = 0.8"));
    let forced = CHAIN_V1.replace(
        "4     Vessel   40.0     0.0       -8.0   0    0    0    0    0",
        "4     Vessel   40.0     0.0       -8.0   0    0    0    0    -5",
    );
    let e = refused(&forced);
    assert!(
        e.starts_with(&format!(
            "deck.dat:{}: the steady force FX FY FZ = [0.0, 0.0, -5.0] on point 4 (Vessel)",
            line_of(&forced, "4     Vessel")
        )),
        "{e}"
    );
    assert!(Feature::from_word("eI").is_ok());
    assert_eq!(
        Feature::from_word("wind").unwrap_err().to_string(),
        "--ignore wind: not a feature that can be dropped (one of: EI, rods, bodies, failure, control, external_loads, waves, currents, viv, point_forces, syrope, unknown_sections, extra_columns, unknown_options)"
    );
}

/// Decks that cannot become a scenario as written.
#[test]
fn unmappable_decks_say_why() {
    let no_lines = SPAR_V2.replace("1   spar_line  1        4        902.2     20       -\n2   spar_line  2        5        902.2     20       -\n3   spar_line  3        6        902.2     20       pt\n", "");
    assert_eq!(
        refused(&no_lines),
        "deck.dat:1: the deck has no lines: there is nothing to simulate"
    );
    let deep = SPAR_V2.replace("-426.935   739.47    -320.0", "-426.935   739.47    -321.0");
    assert_eq!(
        refused(&deep),
        format!(
            "deck.dat:{}: point 2 (Fixed) at z = -321 m lies below the seabed at WtrDpth = 320 m",
            line_of(&deep, "-321.0")
        )
    );
    let no_step = SPAR_V2.replace("0.002     dtM", "0     dtM");
    assert_eq!(
        refused(&no_step),
        format!(
            "deck.dat:{}: option dtM = 0 must be positive",
            line_of(&no_step, "0     dtM")
        )
    );
    let to_itself = SPAR_V2.replace("3   spar_line  3        6", "3   spar_line  3        3");
    assert_eq!(
        refused(&to_itself),
        format!(
            "deck.dat:{}: line 3 runs from point 3 to itself",
            line_of(&to_itself, "3   spar_line")
        )
    );
}

/// `load_scenario` tells decks from scenario files by content, applies `--set` to the
/// generated scenario, and refuses `--ignore` for a scenario file.
#[test]
fn load_scenario_reads_decks_and_scenarios() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let deck = root.join("moordyn/spar_oc3_v2.dat");
    let l = load_scenario(&deck, &["time.end=0.2".into()], &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(*l.file.scenario.time.end.get_ref(), 0.2);
    assert_eq!(l.file.path, generated_name(&deck));
    assert!(l.mapping.is_some());
    let toml = root.join("taut_string.toml");
    assert!(load_scenario(&toml, &[], &[]).unwrap().mapping.is_none());
    let e = load_scenario(&toml, &[], &["EI".into()])
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.starts_with("--ignore EI: ")
            && e.ends_with(
                "is a scenario file, not a MoorDyn deck; --ignore applies to decks only"
            ),
        "{e}"
    );
    // Validation errors of the generated scenario name the option that caused them.
    let l = load_scenario(&deck, &["time.end=-1".into()], &[]).unwrap();
    let e = l.file.setup().err().unwrap().to_string();
    assert!(e.starts_with("--set time.end=-1: "), "{e}");
}

/// A deck of one 40 m wire from point 1 (fixed) to point 2 (vessel), 4 segments, with the
/// OUTPUTS section `outputs` (point 3 has no line).
fn deck_with_outputs(outputs: &str) -> String {
    format!(
        "t\n--- LINE TYPES ---\nName Diam MassDen EA BA EI Cd Ca CdAx CaAx\n(-) (m) (kg/m) (N) (Ns) (Nm2) (-) (-) (-) (-)\n\
         wire 0.1 20 1e8 0 0 1.2 1 0.2 0\n--- POINTS ---\nID Att X Y Z M V CdA Ca\n(#) (-) (m) (m) (m) (kg) (m3) (m2) (-)\n\
         1 Fixed 30 0 -50 0 0 0 0\n2 Vessel 0 0 -20 0 0 0 0\n3 Fixed 0 30 -50 0 0 0 0\n\
         --- LINES ---\nID Type A B L N Out\n(#) (-) (#) (#) (m) (-) (-)\n1 wire 1 2 45 4 -\n\
         --- OPTIONS ---\n0.01 dtM\n50 WtrDpth\n--- OUTPUTS ---\n{outputs}\n--- END ---\n"
    )
}

/// The OUTPUTS channels: those written become `output.channels` with MoorDyn's file name;
/// those phstring does not write are dropped with a warning at their line (which the run
/// prints); a channel naming a line, node or point the deck lacks is refused at its line,
/// as MoorDyn refuses it.
#[test]
fn output_channels_are_written_dropped_with_a_warning_or_refused() {
    let text = deck_with_outputs("FairTen1 L1N2T L1N4PZ\nL1N2AX L1N2FX Point3PZ\nPoint2FZ L1NAFX");
    let (m, file) = mapped(&text, &[]);
    let channels = channel_names(&file.scenario);
    assert_eq!(
        channels,
        ["FairTen1", "L1N2T", "L1N4PZ", "Point2FZ", "L1NAFX"]
    );
    let out_line = line_of(&text, "L1N2AX");
    let notes: Vec<&String> = m
        .record
        .warnings
        .iter()
        .filter(|c| c.starts_with(&format!("deck.dat:{out_line}: channel")))
        .collect();
    assert_eq!(notes.len(), 3, "{:?}", m.record.warnings);
    // The generated scenario carries them, and its validation makes them the run's warnings.
    let deck_record = file.scenario.deck.as_ref().unwrap();
    assert_eq!(deck_record.warnings, m.record.warnings);
    let run_warnings = file.check_with_warnings().unwrap();
    for n in &notes {
        assert!(run_warnings.contains(n), "{n} not in {run_warnings:?}");
    }
    assert!(notes[0].contains("L1N2AX is not written: accelerations"));
    assert!(notes[1].contains("L1N2FX is not written: the net force on an interior node"));
    assert!(notes[2].contains("Point3PZ is not written: point 3 has no line"));
    for (outputs, says) in [
        ("FairTen2", "reads line 2, but the deck has 1 lines"),
        ("L1N5T", "reads node 5 of line 1, which has nodes 0 to 4"),
        ("Point4PZ", "reads point 4, but the deck has 3 points"),
    ] {
        let text = deck_with_outputs(outputs);
        let e = refused(&text);
        let line = line_of(&text, outputs);
        assert!(
            e.contains(&format!("deck.dat:{line}")) && e.contains(says),
            "{outputs}: {e}"
        );
    }
}

/// MoorDyn-F's friction options: `mu_kT` and `mu_kA` become the transverse and axial
/// coefficients, `MC` (StatDynFricScale's other name) the static scale and `CV` (FricDamp's)
/// the damping; the scenario builds a seabed with axial friction of slope `mu_kA · CV`.
/// `mu_kT` next to `FrictionCoefficient` is refused, naming its line.
#[test]
fn moordyn_f_friction_options_map_to_axial_friction_and_static_scale() {
    let deck = |extra: &str| {
        format!(
            "t\n--- LINE TYPES ---\nName Diam MassDen EA BA EI Cd Ca CdAx CaAx\n(-) (m) (kg/m) (N) (Ns) (Nm2) (-) (-) (-) (-)\n\
             chain 0.1 100 1e9 -1 0 1.2 1 0.2 0\n--- POINTS ---\nID Att X Y Z M V CdA Ca\n(#) (-) (m) (m) (m) (kg) (m3) (m2) (-)\n\
             1 Fixed 200 0 -100 0 0 0 0\n2 Vessel 0 0 -5 0 0 0 0\n--- LINES ---\nID Type A B L N Out\n(#) (-) (#) (#) (m) (-) (-)\n1 chain 1 2 250 25 -\n\
             --- OPTIONS ---\n0.01 dtM\n100 WtrDpth\n{extra}--- END ---\n"
        )
    };
    let (m, file) = mapped(&deck("0.8 mu_kT\n0.4 mu_kA\n1.3 MC\n150 CV\n"), &[]);
    let b = file.scenario.seabed.as_ref().unwrap().get_ref();
    assert_eq!(
        (
            opt(&b.friction),
            opt(&b.friction_axial),
            opt(&b.friction_static_scale),
            opt(&b.friction_damping)
        ),
        (Some(0.8), Some(0.4), Some(1.3), Some(150.0))
    );
    for (entry, became) in [
        ("mu_kT", "seabed.friction = 0.8 (transverse)"),
        ("mu_kA", "seabed.friction_axial = 0.4"),
        ("MC", "seabed.friction_static_scale = 1.3"),
    ] {
        assert!(
            m.rows
                .iter()
                .any(|r| r.entry.contains(entry) && r.became == became),
            "{entry}: {:?}",
            m.rows
        );
    }
    let v = file.validate::<3>().unwrap_or_else(|e| panic!("{e}"));
    let water = v.problem.water.as_ref().unwrap();
    let friction = water.seabed.as_ref().unwrap().friction.unwrap();
    assert_eq!((friction.coefficient, friction.slope), (0.8, 0.8 * 150.0));
    let axial = friction.axial.unwrap();
    assert_eq!((axial.coefficient, axial.slope), (0.4, 0.4 * 150.0));
    assert_eq!(friction.static_scale, 1.3);
    let message = refused(&deck("0.5 FrictionCoefficient\n0.8 mu_kT\n"));
    assert!(
        message.contains("deck.dat:19") && message.contains("both FrictionCoefficient and mu_kT"),
        "{message}"
    );
}

/// The spar deck with its three fairleads on a free body: a 200 t buoy (400 m³, drag area
/// 20 m² in translation only) 60 m down, its centre of gravity 1 m above its reference point.
fn buoy_deck(body_row: &str) -> String {
    SPAR_V2
        .replace(
            "4   Vessel      5.2       0.0       -70.0",
            "4   Body1       5.2       0.0       -10.0",
        )
        .replace(
            "5   Vessel     -2.6       4.5033    -70.0",
            "5   Body1      -2.6       4.5033    -10.0",
        )
        .replace(
            "6   Vessel     -2.6      -4.5033    -70.0",
            "6   Body1      -2.6      -4.5033    -10.0",
        )
        .replace(
            "---------------------- LINES",
            &format!(
                "---------------------- BODIES ----------------------\n\
                 ID  Attachment  X0   Y0   Z0    r0  p0  y0  Mass   CG   I             Volume  CdA   Ca\n\
                 (#) (word)      (m)  (m)  (m)  (deg)(deg)(deg)(kg) (m)  (kg-m^2)      (m^3)   (m^2) (-)\n\
                 {body_row}\n---------------------- LINES"
            ),
        )
}

const FREE_BUOY: &str =
    "1   Free        0    0    -60   0   0   90  2.0e5  1.0  1e6|1e6|5e5   400     20|0  0";

/// A free body maps onto `[bodies.body1]`: its mass and inertia, its centre at
/// `X0 + R CG` (the CG 1 m up the body's z, which the yaw of 90° keeps vertical), the
/// orientation in degrees, its points relative to the centre (`p − CG`), the volume and the
/// translational drag area (a conversion with its caveat); the lines end at the body's
/// points, placed at `X0 + R p` (point 4 at (5.2, 0, −10) in body axes turned 90° about z:
/// (0, 5.2, −70)); `check` rows say what the body and its points became, and the scenario
/// validates.
#[test]
fn a_free_body_maps_onto_a_rigid_body() {
    let text = buoy_deck(FREE_BUOY);
    let (m, file) = mapped(&text, &[]);
    let s = &file.scenario;
    let b = s.bodies["body1"].get_ref();
    assert_eq!(*b.mass.get_ref(), 2.0e5);
    assert_eq!(b.inertia.get_ref(), &vec![1e6, 1e6, 5e5]);
    assert_eq!(b.position.get_ref(), &vec![0.0, 0.0, -59.0]);
    assert_eq!(
        b.orientation.as_ref().unwrap().get_ref(),
        &vec![0.0, 0.0, 90.0]
    );
    let p4 = b.points.get_ref()["p4"].get_ref();
    assert_eq!(p4, &vec![5.2, 0.0, -11.0]);
    assert_eq!(opt(&b.volume), Some(400.0));
    assert_eq!(opt(&b.cda), Some(20.0));
    assert!(b.ca.is_none() && b.motion.is_none());
    let line1 = s.string[0].get_ref().path.get_ref();
    assert_eq!(
        line1.last().unwrap().get_ref(),
        &scenario::NodeRef::Name("body1.p4".into())
    );
    // The last interior node of line 1 lies between the anchor and (0, 5.2, −70).
    let fair = [0.0, 5.2, -70.0];
    let anchor = [853.87, 0.0, -320.0];
    let last_interior = s
        .node
        .iter()
        .find(|n| n.get_ref().name.get_ref() == "line1_19")
        .unwrap()
        .get_ref()
        .position
        .get_ref()
        .clone();
    let chord = |a: &[f64], b: &[f64]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    assert!(chord(&last_interior, &fair) < chord(&last_interior, &anchor));
    assert!((chord(&last_interior, &fair) - 902.2 / 20.0).abs() < 1e-6 * 902.2);
    assert!(
        m.record
            .converted
            .iter()
            .any(|c| c.contains("CdA = 20 m² of body 1"))
    );
    let row = |needle: &str| {
        m.rows
            .iter()
            .find(|r| r.entry.contains(needle))
            .unwrap_or_else(|| panic!("no row {needle}"))
            .became
            .clone()
    };
    assert!(row("body 1 (Free)").starts_with("[bodies.body1]: a free rigid body of 200000 kg"));
    assert_eq!(
        row("point 4 (Body1)"),
        "body point body1.p4 of [bodies.body1]"
    );
    file.setup().unwrap_or_else(|e| panic!("{e}"));
}

/// A coupled body without `--motion` is a prescribed body held at its deck pose (constant
/// motion expressions, 1 kg and 1 kg·m², listed as conversions); a fixed body's points are
/// fixed supports at `X0 + R p`.
#[test]
fn coupled_and_fixed_bodies_map_onto_a_held_body_and_supports() {
    let coupled = buoy_deck(
        "1   Coupled     0    0    -60   0   0   0   0      0    0             0       0     0",
    );
    let (m, file) = mapped(&coupled, &[]);
    let b = file.scenario.bodies["body1"].get_ref();
    let motion = b.motion.as_ref().unwrap().get_ref();
    let texts: Vec<&str> = motion
        .position
        .get_ref()
        .iter()
        .map(|e| e.get_ref().as_str())
        .collect();
    assert_eq!(texts, ["0.0", "0.0", "-60.0"]);
    assert_eq!(*b.mass.get_ref(), 1.0);
    assert_eq!(
        b.points.get_ref()["p5"].get_ref(),
        &vec![-2.6, 4.5033, -10.0]
    );
    assert!(
        m.record
            .converted
            .iter()
            .any(|c| c.contains("coupled body 1 is held at its deck pose"))
    );
    file.setup().unwrap_or_else(|e| panic!("{e}"));
    let fixed = buoy_deck(
        "1   Fixed       0    0    -60   0   0   0   0      0    0             0       0     0",
    );
    let (m, file) = mapped(&fixed, &[]);
    assert!(file.scenario.bodies.is_empty());
    let p4 = file
        .scenario
        .node
        .iter()
        .find(|n| n.get_ref().name.get_ref() == "point4")
        .unwrap();
    assert_eq!(p4.get_ref().position.get_ref(), &vec![5.2, 0.0, -70.0]);
    assert!(
        m.rows
            .iter()
            .any(|r| r.entry == "body 1 (Fixed)" && r.became.contains("fixed supports"))
    );
    file.setup().unwrap_or_else(|e| panic!("{e}"));
}

/// What the body model does not take is refused at the body's (or point's) line, saying why:
/// one drag area for all six degrees of freedom (rotational drag, which phstring's body
/// lacks), six per-degree-of-freedom drag areas whose first MoorDyn reads as 0 (per-axis
/// drag), a pinned body (no `--ignore`: phstring cannot prescribe the translation alone),
/// six `Ca` values (MoorDyn refuses them) or a negative one, a point on a body the deck
/// lacks, a free body without mass; with `--ignore bodies` the drag is dropped and listed.
#[test]
fn body_features_the_model_lacks_are_refused_with_their_line() {
    let cases: Vec<(String, &str, Option<Feature>, &str)> = vec![
        (
            buoy_deck(&FREE_BUOY.replace("20|0", "20")),
            "1   Free",
            Some(Feature::Bodies),
            "the rotational drag of body 1 (CdA = 20, which MoorDyn reads as the rotational drag areas [20.0, 20.0, 20.0]",
        ),
        (
            buoy_deck(&FREE_BUOY.replace("20|0", "20|20|20|0|0|0")),
            "1   Free",
            Some(Feature::Bodies),
            "which MoorDyn reads as [0.0, 20.0, 20.0] m² along the body axes; MoorDyn 2.7.2 reads the first of 6 CdA values as 0",
        ),
        (
            buoy_deck(&FREE_BUOY.replace("Free    ", "Pinned  ")),
            "1   Pinned",
            None,
            "body 1 (Pinned), coupled in translation and free to turn",
        ),
        (
            buoy_deck(&FREE_BUOY.replace("20|0  0", "20|0  1|1|1|1|1|1")),
            "1   Free",
            None,
            "body 1 has 6 added-mass coefficients Ca = 1|1|1|1|1|1: MoorDyn reads 1 (all three axes) or 3",
        ),
        (
            buoy_deck(&FREE_BUOY.replace("20|0  0", "20|0  0.8|-0.5|0.8")),
            "1   Free",
            None,
            "body 1 has a negative added-mass coefficient Ca = 0.8|-0.5|0.8",
        ),
    ];
    for (text, needle, feature, what) in &cases {
        let line = line_of(text, needle);
        let e = refused(text);
        assert!(
            e.starts_with(&format!("deck.dat:{line}: ")),
            "{needle}: {e}"
        );
        assert!(e.contains(what), "{needle}: {e}");
        match feature {
            Some(f) => {
                assert!(e.contains(&format!("`--ignore {}`", f.word())), "{e}");
                let (m, file) = mapped(text, &[*f]);
                assert_eq!(m.record.ignored.len(), 1, "{needle}");
                file.setup().unwrap_or_else(|e| panic!("{e}"));
            }
            None => assert!(!e.contains("--ignore"), "{e}"),
        }
    }
    let rotational = refused(&buoy_deck(&FREE_BUOY.replace("20|0", "20")));
    assert!(
        rotational.contains("phstring's body has no rotational quadratic drag"),
        "{rotational}"
    );
    let pinned = refused(&buoy_deck(&FREE_BUOY.replace("Free    ", "Pinned  ")));
    assert!(
        pinned.contains("cannot hold the translation and leave the rotation free"),
        "{pinned}"
    );
    let missing = buoy_deck(FREE_BUOY).replace("6   Body1", "6   Body2");
    let e = refused(&missing);
    let line = line_of(&missing, "6   Body2");
    assert!(
        e.starts_with(&format!("deck.dat:{line}: "))
            && e.contains("point 6 (Body2) is attached to body 2, but the deck has 1 bodies"),
        "{e}"
    );
    let massless = buoy_deck(&FREE_BUOY.replace("2.0e5", "0    "));
    let e = refused(&massless);
    assert!(
        e.contains("free body 1 has Mass 0 kg: phstring's bodies need a positive mass"),
        "{e}"
    );
}

/// The buoy with its centre of gravity off the reference point along all three axes and a
/// `Ca` per axis.
const CA_BUOY: &str = "1   Free        0    0    -60   0   0   90  2.0e5  0.5|-0.3|1.0  1e6|1e6|5e5   400     20|0  0.8|0.6|0.4";

/// A body's `Ca` becomes MoorDyn's added mass `ρ_w V Ca_i` along the body axes at the
/// reference point, moved to the centre of mass with the lever `CG` = (0.5, −0.3, 1.0) m:
/// the blocks `[[a, a ĉ], [ĉᵀ a, ĉᵀ a ĉ]]`, here entry by entry as worked by hand
/// (`ρ_w` = 1025 kg/m³, V = 400 m³); `check` says what it became and lists the conversion.
/// With one `Ca` and the CG at the reference point it is the scalar `ca`. The deck then runs:
/// 50 steps from its layout move and turn the body and keep the energy balance to rounding.
#[test]
fn a_body_added_mass_maps_about_the_centre_of_mass_and_runs() {
    let (m, file) = mapped(&buoy_deck(CA_BUOY), &[]);
    let b = file.scenario.bodies["body1"].get_ref();
    assert!(b.ca.is_none());
    let a = b.added_mass.as_ref().expect("a 6×6 added mass").get_ref();
    let (a1, a2, a3) = (
        1025.0 * 400.0 * 0.8,
        1025.0 * 400.0 * 0.6,
        1025.0 * 400.0 * 0.4,
    );
    let hand = [
        [a1, 0.0, 0.0, 0.0, -a1, -0.3 * a1],
        [0.0, a2, 0.0, a2, 0.0, -0.5 * a2],
        [0.0, 0.0, a3, 0.3 * a3, 0.5 * a3, 0.0],
        [0.0, a2, 0.3 * a3, a2 + 0.09 * a3, 0.15 * a3, -0.5 * a2],
        [-a1, 0.0, 0.5 * a3, 0.15 * a3, a1 + 0.25 * a3, 0.3 * a1],
        [
            -0.3 * a1,
            -0.5 * a2,
            0.0,
            -0.5 * a2,
            0.3 * a1,
            0.09 * a1 + 0.25 * a2,
        ],
    ];
    assert_eq!(a.len(), 6);
    for (r, (row, want)) in a.iter().zip(hand).enumerate() {
        for (c, (x, y)) in row.iter().zip(want).enumerate() {
            assert!((x - y).abs() <= 1e-12 * a1, "({r}, {c}): {x} vs {y} kg");
        }
    }
    let row = m
        .rows
        .iter()
        .find(|r| r.entry == "body 1 (Free)")
        .unwrap()
        .became
        .clone();
    assert!(
        row.contains("added mass ρ_w V Ca = [328000.0, 246000.0, 164000.0] kg along the body axes at the reference point, moved to the centre of mass (added_mass, 6×6, with the lever CG = [0.5, -0.3, 1.0] m)"),
        "{row}"
    );
    assert!(
        m.record
            .converted
            .iter()
            .any(|c| c.contains("Ca = 0.8|0.6|0.4 of body 1: MoorDyn's added mass")),
        "{:?}",
        m.record.converted
    );
    // One Ca, the CG at the reference point: the scalar key.
    let scalar = CA_BUOY
        .replace("0.5|-0.3|1.0", "0")
        .replace("0.8|0.6|0.4", "0.8");
    let (_, iso) = mapped(&buoy_deck(&scalar), &[]);
    let b = iso.scenario.bodies["body1"].get_ref();
    assert_eq!(opt(&b.ca), Some(0.8));
    assert!(b.added_mass.is_none());

    let setup = file.setup().unwrap_or_else(|e| panic!("{e}"));
    let phstring::ByDim::D3(setup) = setup else {
        panic!("a deck is 3D")
    };
    // From the deck's layout (not its equilibrium), so that the lines pull the body off
    // its pose and turn it (the CG is off its points' centre).
    let (mut run, _) = setup.start(false, None).unwrap_or_else(|e| panic!("{e}"));
    let sim = &mut run.problem;
    let x0 = sim.state().bodies[0].position;
    let h0 = sim.energies().hamiltonian();
    let mut scale: f64 = 0.0;
    for _ in 0..50 {
        let r = sim.step().unwrap_or_else(|e| panic!("{e}"));
        scale = scale.max(r.energy_scale);
    }
    // Ĥ_n − Ĥ_0 + Σ D − Σ S = 0 to rounding: 50 steps' errors of ε times the energy scale.
    let drift = sim.energies().hamiltonian() - h0 + sim.dissipated_energy() - sim.supplied_energy();
    let moved = (sim.state().bodies[0].position - x0).norm();
    let turned = sim.state().bodies[0].omega.norm();
    println!(
        "body moved {moved:e} m, turns at {turned:e} rad/s; balance drift {drift:e} J of {scale:e} J"
    );
    assert!(
        moved > 1e-4 && turned > 1e-6,
        "{moved:e} m, {turned:e} rad/s"
    );
    assert!(drift.abs() < 1e-10 * scale, "{drift:e} J of {scale:e} J");
}

/// A buoyant 200 t body (400 m³) held down by one vertical tether of 50 m with EA = 1e8 N
/// (one segment, 1 kg/m, no drag or damping: a linear spring `k = EA/L` = 2e6 N/m, taut
/// throughout), its centre of gravity 1 m above its reference point and the tether 5 m
/// below it. Started 0.53 m below its equilibrium, it heaves undamped with the period
/// `2π √((m + A_z + m_n)/k)` (`m_n` = 25 kg, the tether's lumped half on the body point;
/// `A_z = ρ_w V Ca_z`): with `Ca` = 0 and with `0.3|0.6|1.0` (the z value counts; the CG
/// offset along z couples no rotation into heave), each within 1e-3 of the closed form and
/// their ratio within 1e-3 of `√((m + A_z + m_n)/(m + m_n))` — 1.75, the added mass's doing.
/// (The scheme's period error at `h` = 5 ms is `(ωh)²/12` ≈ 2e-5; the turning points are
/// interpolated linearly between steps.)
#[test]
fn the_heave_period_of_a_tethered_body_grows_with_its_added_mass() {
    let deck = |ca: &str| {
        format!(
            "--- MoorDyn input ---\ntethered buoy\n\
             ---------------------- LINE TYPES ----------------------\n\
             Name    Diam  MassDen  EA   BA/-zeta  EI  Cd  Ca  CdAx  CaAx\n\
             (-)     (m)   (kg/m)   (N)  (N-s)     (-) (-) (-) (-)   (-)\n\
             tether  0.1   1.0      1e8  0         0   0   0   0     0\n\
             ---------------------- BODIES ----------------------\n\
             ID  Attachment  X0  Y0  Z0     r0  p0  y0  Mass   CG   I    Volume  CdA  Ca\n\
             (#) (word)      (m) (m) (m)   (deg)(deg)(deg)(kg) (m)  (kg-m^2) (m^3) (m^2) (-)\n\
             1   Free        0   0   -44.5  0   0   0   2.0e5  1.0  1e6  400     0    {ca}\n\
             ---------------------- POINTS ----------------------\n\
             ID  Attachment  X   Y   Z      Mass  Volume  CdA  Ca\n\
             (#) (word)      (m) (m) (m)    (kg)  (m^3)   (m^2) (-)\n\
             1   Fixed       0   0   -100   0     0       0    0\n\
             2   Body1       0   0   -5     0     0       0    0\n\
             ---------------------- LINES ----------------------\n\
             ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  Outputs\n\
             (#) (name)    (#)      (#)      (m)       (-)      (-)\n\
             1   tether    1        2        50        1        -\n\
             ---------------------- OPTIONS ----------------------\n\
             0.005    dtM\n9.80665  g\n1025     rho\n200      WtrDpth\n\
             ---------------------- END ----------------------\n"
        )
    };
    let (m, k, m_n) = (2.0e5, 1e8 / 50.0, 25.0);
    let period = |ca: &str| -> f64 {
        let (_, file) = mapped(&deck(ca), &[]);
        let setup = file.setup().unwrap_or_else(|e| panic!("{e}"));
        let phstring::ByDim::D3(setup) = setup else {
            panic!("a deck is 3D")
        };
        // From the deck's pose (the tether 1 % stretched), not from the equilibrium.
        let (mut run, _) = setup.start(false, None).unwrap_or_else(|e| panic!("{e}"));
        let sim = &mut run.problem;
        let mut turns = Vec::new();
        let (mut t0, mut v0) = (0.0, 0.0);
        while sim.time() < 8.0 {
            sim.step().unwrap_or_else(|e| panic!("{e}"));
            let (t1, v1) = (sim.time(), sim.state().bodies[0].velocity.z);
            if v0 > 0.0 && v1 <= 0.0 || v0 < 0.0 && v1 >= 0.0 {
                turns.push(t0 + (t1 - t0) * v0 / (v0 - v1));
            }
            (t0, v0) = (t1, v1);
            let turned = sim.state().bodies[0].omega.norm();
            assert!(turned < 1e-9, "heave turned the body: {turned:e} rad/s");
        }
        assert!(turns.len() >= 4, "{turns:?}");
        2.0 * (turns[turns.len() - 1] - turns[0]) / (turns.len() - 1) as f64
    };
    let still = period("0");
    let added = period("0.3|0.6|1.0");
    let a_z = 1025.0 * 400.0 * 1.0;
    let closed = |a: f64| 2.0 * std::f64::consts::PI * ((m + a + m_n) / k).sqrt();
    println!(
        "heave period {still} s without added mass (closed form {}), {added} s with (closed form {}), ratio {}",
        closed(0.0),
        closed(a_z),
        added / still
    );
    assert!((still / closed(0.0) - 1.0).abs() < 1e-3, "{still} s");
    assert!((added / closed(a_z) - 1.0).abs() < 1e-3, "{added} s");
    let ratio = ((m + a_z + m_n) / (m + m_n)).sqrt();
    assert!(
        (added / still / ratio - 1.0).abs() < 1e-3,
        "{}",
        added / still
    );
}

/// A body channel on a deck whose free body is mapped is not refused nor said to be: it is
/// not written, with a warning saying so.
#[test]
fn a_body_channel_is_a_warning_that_body_channels_are_not_written() {
    let text = "--- MoorDyn input ---\ntethered buoy\n\
         --- LINE TYPES ---\nName Diam MassDen EA BA/-zeta EI Cd Ca CdAx CaAx\n\
         (-) (m) (kg/m) (N) (N-s) (-) (-) (-) (-) (-)\ntether 0.1 1.0 1e8 0 0 0 0 0 0\n\
         --- BODIES ---\nID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG I Volume CdA Ca\n\
         (#) (word) (m) (m) (m) (deg) (deg) (deg) (kg) (m) (kg-m^2) (m^3) (m^2) (-)\n\
         1 Free 0 0 -44.5 0 0 0 2.0e5 1.0 1e6 400 0 0\n\
         --- POINTS ---\nID Attachment X Y Z Mass Volume CdA Ca\n(#) (word) (m) (m) (m) (kg) (m^3) (m^2) (-)\n\
         1 Fixed 0 0 -100 0 0 0 0\n2 Body1 0 0 -5 0 0 0 0\n\
         --- LINES ---\nID LineType AttachA AttachB UnstrLen NumSegs Outputs\n(#) (name) (#) (#) (m) (-) (-)\n\
         1 tether 1 2 50 1 -\n\
         --- OPTIONS ---\n0.005 dtM\n200 WtrDpth\n--- OUTPUTS ---\nAnchTen1\nBody1PX\n--- END ---\n";
    let (m, file) = mapped(text, &[]);
    let line = line_of(text, "Body1PX");
    assert_eq!(
        m.record.warnings,
        [format!(
            "deck.dat:{line}: channel Body1PX is not written: `Body1PX` reads a body; phstring does not write body channels yet"
        )]
    );
    let channels = channel_names(&file.scenario);
    assert_eq!(channels, ["AnchTen1"]);
}
