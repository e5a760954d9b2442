//! Tests of the MoorDyn deck reader on the example decks and on hand-written variations.

use std::path::Path;

use proptest::prelude::*;

use super::*;

const SPAR_V2: &str = include_str!("../../../../examples/moordyn/spar_oc3_v2.dat");
const CHAIN_V1: &str = include_str!("../../../../examples/moordyn/chain_shallow_v1.dat");

fn deck(text: &str) -> Deck {
    parse(text, "deck.dat").unwrap_or_else(|e| panic!("{e}"))
}

fn err(text: &str) -> String {
    parse(text, "deck.dat")
        .expect_err("the deck should be refused")
        .to_string()
}

/// The line of `text` (1-based) holding `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// A small v2 deck whose sections are titled by the arguments.
fn small_v2(types: &str, points: &str, lines: &str, options: &str, outputs: &str) -> String {
    format!(
        "title\n--- {types} ---\nName Diam MassDen EA BA EI Cd Ca CdAx CaAx\n(-) (m) (kg/m) (N) (Ns) (Nm2) (-) (-) (-) (-)\n\
         wire 0.1 20 1e8 -0.5 0 1.2 1 0.2 0\n--- {points} ---\nID Att X Y Z M V CdA Ca\n(#) (-) (m) (m) (m) (kg) (m3) (m2) (-)\n\
         1 Fixed 100 0 -50 0 0 0 0\n2 Coupled 0 0 -5 0 0 0 0\n--- {lines} ---\nID Type A B L N Out\n(#) (-) (#) (#) (m) (-) (-)\n\
         1 wire 1 2 110 10 -\n--- {options} ---\n0.01 dtM\n50 WtrDpth\n--- {outputs} ---\nFairTen1\n--- END ---\n"
    )
}

#[test]
fn spar_v2_example_is_read_with_its_values() {
    let d = deck(SPAR_V2);
    assert_eq!(d.version, Version::V2);
    assert!(d.title.starts_with("OC3-Hywind-like spar"), "{}", d.title);
    assert_eq!(d.line_types.len(), 1);
    let t = &d.line_types[0];
    assert_eq!(t.name, "spar_line");
    assert_eq!((t.diameter, t.mass_per_length), (0.09, 77.7066));
    assert_eq!(t.ea, LineValue::Number(384.243e6));
    assert_eq!(t.ba, LineValue::Number(-0.8));
    assert_eq!(t.ei, LineValue::Number(0.0));
    assert_eq!((t.cd, t.ca, t.cd_ax, t.ca_ax), (1.6, 1.0, 0.1, 0.0));
    assert!(t.extra.is_empty());
    assert_eq!(t.line, line_of(SPAR_V2, "spar_line 0.09"));
    assert_eq!(d.points.len(), 6);
    let p2 = &d.points[1];
    assert_eq!((p2.id, p2.kind), (2, PointKind::Fixed));
    assert_eq!(p2.position, [-426.935, 739.47, -320.0]);
    assert_eq!(p2.force, None);
    assert_eq!(d.points[5].kind, PointKind::Coupled);
    assert_eq!(d.points[5].position, [-2.6, -4.5033, -70.0]);
    assert_eq!(d.lines.len(), 3);
    let l3 = &d.lines[2];
    assert_eq!(l3.line_type, "spar_line");
    assert_eq!(
        (l3.attach_a, l3.attach_b),
        (Attachment::Point(3), Attachment::Point(6))
    );
    assert_eq!((l3.unstretched_length, l3.segments), (902.2, 20));
    assert_eq!(l3.outputs, "pt");
    let o = &d.options;
    assert_eq!(o.dt_m().unwrap(), Some(0.002));
    assert_eq!(o.water_depth().unwrap(), Some(WaterDepth::Depth(320.0)));
    assert_eq!(o.water_density().unwrap(), Some(1025.0));
    assert_eq!(o.gravity().unwrap(), Some(9.80665));
    assert_eq!(
        (o.k_bot().unwrap(), o.c_bot().unwrap()),
        (Some(3.0e6), Some(3.0e5))
    );
    assert_eq!(o.tmax_ic().unwrap(), Some(100.0));
    assert_eq!(o.thresh_ic().unwrap(), Some(0.001));
    assert_eq!(o.t_scheme(), Some("RK4"));
    assert_eq!(o.friction_coefficient().unwrap(), None);
    let rho = o.get("WtrDnsty").unwrap();
    assert_eq!(
        (rho.key.as_str(), rho.line),
        ("rho", line_of(SPAR_V2, "1025      rho"))
    );
    assert_eq!(rho.remark, "water density (kg/m^3)");
    let names: Vec<&str> = d.outputs.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "FairTen1", "FairTen2", "FairTen3", "AnchTen1", "L1N10T", "L1N20PZ", "Point4FX",
            "Point4FY", "Point4FZ", "Point4T"
        ]
    );
    assert_eq!(d.sections_present.len(), 5);
    assert_eq!(d.unsupported_sections().count(), 0);
    assert!(d.notes.is_empty(), "{:?}", d.notes);
}

#[test]
fn chain_v1_example_is_read_in_the_v1_column_order() {
    let d = deck(CHAIN_V1);
    assert_eq!(d.version, Version::V1);
    assert!(d.title.starts_with("Shallow-water chain spread"));
    let t = &d.line_types[0];
    assert_eq!((t.diameter, t.mass_per_length), (0.252, 390.0));
    assert_eq!(t.ea.number(), Some(1.674e9));
    assert_eq!(t.ba.number(), Some(-1.0));
    // v1 writes Can Cat Cdn Cdt = 1.0 0.5 2.4 1.15; v1 has no EI.
    assert_eq!((t.cd, t.ca, t.cd_ax, t.ca_ax), (2.4, 1.0, 1.15, 0.5));
    assert_eq!(t.ei, LineValue::Number(0.0));
    let p5 = &d.points[4];
    assert_eq!(
        (p5.kind, p5.position),
        (PointKind::Coupled, [-20.0, 34.64, -8.0])
    );
    assert_eq!(p5.force, Some([0.0; 3]));
    let l2 = &d.lines[1];
    // v1: Line LineType UnstrLen NumSegs NodeAnch NodeFair Flags.
    assert_eq!(
        (l2.attach_a, l2.attach_b),
        (Attachment::Point(2), Attachment::Point(5))
    );
    assert_eq!((l2.unstretched_length, l2.segments), (400.0, 40));
    let o = &d.options;
    assert_eq!(o.dt_m().unwrap(), Some(0.0005));
    assert_eq!(o.k_bot().unwrap(), Some(3.0e6));
    assert_eq!(o.get("kBot").unwrap().key, "kb");
    assert_eq!(o.cd_scale_ic().unwrap(), Some(5.0));
    assert_eq!(o.thresh_ic().unwrap(), Some(0.001));
    assert_eq!(o.tmax_ic().unwrap(), Some(60.0));
    assert_eq!(
        o.get("ICDfac").unwrap().remark,
        "- drag scale during initial-condition generation (-)"
    );
    let names: Vec<(&str, usize)> = d
        .outputs
        .iter()
        .map(|c| (c.name.as_str(), c.line))
        .collect();
    let first = line_of(CHAIN_V1, "FairTen1 FairTen2");
    assert_eq!(
        names,
        [
            ("FairTen1", first),
            ("FairTen2", first),
            ("FairTen3", first),
            ("Con4pX", first + 1),
            ("L1N10T", first + 2)
        ]
    );
    assert!(d.notes.is_empty(), "{:?}", d.notes);
}

#[test]
fn every_section_title_synonym_is_recognised_in_any_case() {
    let base = deck(&small_v2(
        "LINE TYPES",
        "POINTS",
        "LINES",
        "OPTIONS",
        "OUTPUTS",
    ));
    for (types, points, lines, options, outputs) in [
        (
            "LINE DICTIONARY",
            "POINT LIST",
            "LINE LIST",
            "SOLVER OPTIONS",
            "OUTPUT",
        ),
        (
            "line types",
            "Point Properties",
            "lines",
            "options",
            "outputs",
        ),
        (
            "Line  Types",
            "CONNECTION PROPERTIES",
            "LINES",
            "Solver Options",
            "OUTPUTS",
        ),
        (
            "LINE TYPES",
            "NODE PROPERTIES",
            "LINE LIST",
            "OPTIONS",
            "OUTPUTS",
        ),
    ] {
        let d = deck(&small_v2(types, points, lines, options, outputs));
        assert_eq!(d.line_types, base.line_types, "{types}");
        assert_eq!(d.points, base.points, "{points}");
        assert_eq!(d.lines, base.lines, "{lines}");
        assert_eq!(d.options.entries, base.options.entries, "{options}");
        assert_eq!(d.outputs, base.outputs, "{outputs}");
        assert_eq!(d.sections_present.len(), 5);
    }
    assert_eq!(base.lines[0].unstretched_length, 110.0);
    assert_eq!(
        base.options.water_depth().unwrap(),
        Some(WaterDepth::Depth(50.0))
    );
}

#[test]
fn version_follows_the_lines_section() {
    // LINE PROPERTIES with v2 columns (AttachA …) is v2, as some v2 decks title it.
    let v2 = small_v2(
        "LINE TYPES",
        "POINTS",
        "LINE PROPERTIES",
        "OPTIONS",
        "OUTPUTS",
    )
    .replace(
        "ID Type A B L N Out",
        "ID LineType AttachA AttachB UnstrLen NumSegs Out",
    );
    assert_eq!(deck(&v2).version, Version::V2);
    assert_eq!(deck(&v2).lines[0].unstretched_length, 110.0);
    // The same title with v1 columns is v1, and the columns are read in v1 order.
    let v1 = "t\n--- LINE TYPES ---\nn d m ea ba can cat cdn cdt\n(-) (m) (kg/m) (N) (-) (-) (-) (-) (-)\n\
         w 0.1 20 1e8 -1 1 0 1.6 0.1\n--- POINT PROPERTIES ---\nN T X Y Z M V CdA Ca\n(-) (-) (m) (m) (m) (kg) (m3) (m2) (-)\n\
         1 Fix 0 0 -50 0 0 0 0\n2 Vessel 80 0 -5 0 0 0 0\n--- LINE PROPERTIES ---\n\
         Line LineType UnstrLen NumSegs NodeAnch NodeFair Flags\n(-) (-) (m) (-) (-) (-) (-)\n1 w 95 12 1 2 -\n";
    let d = deck(v1);
    assert_eq!(d.version, Version::V1);
    let l = &d.lines[0];
    assert_eq!(
        (l.unstretched_length, l.segments, l.attach_b),
        (95.0, 12, Attachment::Point(2))
    );
    assert_eq!((d.line_types[0].cd, d.line_types[0].ca), (1.6, 1.0));
    // Without a lines section, a v1-only title decides.
    assert_eq!(deck("t\n--- NODE PROPERTIES ---\n").version, Version::V1);
    assert_eq!(deck("t\n--- POINTS ---\n").version, Version::V2);
}

#[test]
fn comments_tabs_and_crlf_do_not_change_the_deck() {
    let base = deck(SPAR_V2);
    let crlf = SPAR_V2.replace('\n', "\r\n");
    assert_eq!(deck(&crlf), base);
    let tabs = SPAR_V2.replace("  ", "\t");
    assert_eq!(deck(&tabs), base);
    let commented = SPAR_V2
        .replace(
            "1   spar_line  1",
            "# a comment line between rows\n  # indented too\n1   spar_line  1",
        )
        .replace(
            "---------------------- POINTS",
            "# ---- RODS ---- (commented out: not a header)\n---------------------- POINTS",
        );
    let c = deck(&commented);
    assert_eq!(c.lines.len(), 3);
    assert_eq!(c.lines[0].unstretched_length, 902.2);
    assert_eq!(c.sections_present.len(), 5);
    // Text after `#` on a data row is dropped.
    let trailing = SPAR_V2.replace(
        "902.2     20       pt",
        "902.2     20       pt   # fairlead 3",
    );
    assert_eq!(deck(&trailing).lines, base.lines);
    // The byte-order mark of some editors is skipped.
    assert_eq!(deck(&format!("\u{feff}{SPAR_V2}")), base);
}

#[test]
fn a_missing_end_line_is_accepted_with_a_note() {
    let cut = &SPAR_V2[..SPAR_V2.find("---------------------- END").unwrap()];
    let d = deck(cut);
    assert_eq!(d.outputs.len(), 10);
    assert_eq!(d.notes.len(), 1);
    assert_eq!(d.notes[0].line, line_of(SPAR_V2, "Point4FX"));
    assert!(d.notes[0].text.contains("no closing dashed line"));
    assert!(deck(SPAR_V2).notes.is_empty());
    // A bare dashed divider between sections is neither a section nor the end.
    let divided = SPAR_V2.replace(
        "---------------------- LINES",
        "--------------------------------\n---------------------- LINES",
    );
    let d = deck(&divided);
    assert_eq!(d.sections_present.len(), 5);
    assert_eq!(d.unsupported_sections().count(), 0);
    assert!(d.notes.is_empty());
    // The same lines, one file line further down.
    let shifted: Vec<Line> = deck(SPAR_V2)
        .lines
        .into_iter()
        .map(|l| Line {
            line: l.line + 1,
            ..l
        })
        .collect();
    assert_eq!(d.lines, shifted);
}

#[test]
fn options_are_read_in_any_order_and_any_case() {
    let text = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS").replace(
        "0.01 dtM\n50 WtrDpth\n",
        "1e-3 DTM  a remark\n0.5 frictioncoefficient\nbathy.txt WTRDPTH\n9.81 Gravity\n2e-3 dt later line wins\n1000 rhoW\n",
    );
    let d = deck(&text);
    let o = &d.options;
    assert_eq!(o.entries.len(), 6);
    assert_eq!(o.dt_m().unwrap(), Some(2e-3));
    assert_eq!(o.get("dtm").unwrap().remark, "later line wins");
    assert_eq!(o.friction_coefficient().unwrap(), Some(0.5));
    assert_eq!(
        o.water_depth().unwrap(),
        Some(WaterDepth::File("bathy.txt".into()))
    );
    assert_eq!(o.gravity().unwrap(), Some(9.81));
    assert_eq!(o.water_density().unwrap(), Some(1000.0));
    assert_eq!(
        o.get("Gravity").unwrap().line,
        line_of(&text, "9.81 Gravity")
    );
}

#[test]
fn bad_options_are_refused_with_their_line() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let reversed = base.replace("0.01 dtM", "dtM 0.01");
    let line = line_of(&reversed, "dtM 0.01");
    assert_eq!(
        err(&reversed),
        format!(
            "deck.dat:{line}: option `dtM 0.01` is written name first; MoorDyn reads the value first (`0.001 dtM`)"
        )
    );
    let lone = base.replace("0.01 dtM", "0.01");
    assert!(err(&lone).starts_with(&format!("deck.dat:{line}: option `0.01` needs a value")));
    // A value that is not a number is kept raw; its getter names the line.
    let d = deck(
        &base
            .replace("0.01 dtM", "0.0x1 dtM")
            .replace("50 WtrDpth", "5O0 WtrDpth"),
    );
    assert_eq!(d.options.get("dtM").unwrap().value, "0.0x1");
    assert_eq!(
        d.options.dt_m().unwrap_err().to_string(),
        format!("deck.dat:{line}: option dtM `0.0x1` is not a number")
    );
    // `5O0` (letter O) starts like a number: a typo, not a bathymetry file.
    assert!(d.options.water_depth().is_err());
    // A file name may start with a digit when it has an extension.
    let d = deck(&base.replace("50 WtrDpth", "2019_site.bth WtrDpth"));
    assert_eq!(
        d.options.water_depth().unwrap(),
        Some(WaterDepth::File("2019_site.bth".into()))
    );
}

#[test]
fn point_types_and_their_synonyms() {
    let row = |kind: &str| {
        small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS")
            .replace("2 Coupled 0 0 -5", &format!("2 {kind} 0 0 -5"))
    };
    for (word, kind) in [
        ("Fixed", PointKind::Fixed),
        ("fix", PointKind::Fixed),
        ("ANCHOR", PointKind::Fixed),
        ("Vessel", PointKind::Coupled),
        ("Vessel1", PointKind::Coupled),
        ("coupled", PointKind::Coupled),
        ("Fairlead", PointKind::Coupled),
        ("Ves", PointKind::Coupled),
        ("Cpld", PointKind::Coupled),
        ("Free", PointKind::Free),
        ("Connect", PointKind::Free),
        ("Con", PointKind::Free),
        ("point", PointKind::Free),
        ("Body2", PointKind::Body(2)),
        ("Turbine3", PointKind::Turbine(3)),
    ] {
        let d = deck(&row(word));
        assert_eq!(d.points[1].kind, kind, "{word}");
        assert_eq!(d.points[1].kind_text, word);
    }
    for bad in ["Floating", "Body", "Body0", "Fixed2x", "Turbine"] {
        let text = row(bad);
        let line = line_of(&text, &format!("2 {bad} "));
        assert!(
            err(&text).starts_with(&format!(
                "deck.dat:{line}: point type `{bad}` is not one of"
            )),
            "{bad}"
        );
    }
}

#[test]
fn line_ends_name_points_or_rod_ends() {
    let with_ends = |a: &str, b: &str| {
        small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS")
            .replace("1 wire 1 2 110", &format!("1 wire {a} {b} 110"))
    };
    let d = deck(&with_ends("P1", "point2"));
    assert_eq!(
        (d.lines[0].attach_a, d.lines[0].attach_b),
        (Attachment::Point(1), Attachment::Point(2))
    );
    let d = deck(&with_ends("R1A", "Rod2b"));
    assert_eq!(
        (d.lines[0].attach_a, d.lines[0].attach_b),
        (Attachment::Rod(1, RodEnd::A), Attachment::Rod(2, RodEnd::B))
    );
    let text = with_ends("1", "7");
    let line = line_of(&text, "1 wire 1 7");
    assert_eq!(
        err(&text),
        format!("deck.dat:{line}: AttachB refers to point 7, but the deck defines 2 point(s)")
    );
    assert!(err(&with_ends("X1", "2")).contains("AttachA `X1` names neither a point"));
    assert!(err(&with_ends("R1", "2")).contains("AttachA `R1` names neither"));
    assert!(err(&with_ends("0", "2")).contains("AttachA `0` names neither"));
}

#[test]
fn malformed_rows_are_refused_with_their_line_and_field() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let row = line_of(&base, "wire 0.1 20");
    assert_eq!(
        err(&base.replace("wire 0.1 20", "wire 0.1 abc")),
        format!("deck.dat:{row}: MassDen `abc` is not a number")
    );
    assert_eq!(
        err(&base.replace("wire 0.1 20", "wire nan 20")),
        format!("deck.dat:{row}: Diam `nan` is not a number")
    );
    assert_eq!(
        err(&base.replace("1.2 1 0.2 0", "1.2 1 0.2")),
        format!(
            "deck.dat:{row}: a LINE TYPES row needs at least 10 (Name Diam MassDen EA BA/-zeta EI Cd Ca CdAx CaAx) fields, this one has 9"
        )
    );
    // A mistyped EA is an error, not a curve file name.
    assert_eq!(
        err(&base.replace("1e8", "1e8.5")),
        format!("deck.dat:{row}: EA `1e8.5` is not a number")
    );
    assert_eq!(
        err(&base.replace("1e8", "300kN")),
        format!("deck.dat:{row}: EA `300kN` is not a number")
    );
    let p = line_of(&base, "1 Fixed 100");
    assert_eq!(
        err(&base.replace("1 Fixed 100 0 -50", "1 Fixed 100 0 -5O")),
        format!("deck.dat:{p}: Z `-5O` is not a number")
    );
    assert!(
        err(&base.replace("1 Fixed 100 0 -50 0 0 0 0", "1 Fixed 100 0 -50 0 0 0"))
            .starts_with(&format!("deck.dat:{p}: a POINTS row needs 9 "))
    );
    assert_eq!(
        err(&base.replace("2 Coupled", "3 Coupled")),
        format!(
            "deck.dat:{}: POINTS id 3 is out of sequence (MoorDyn numbers them 1, 2, 3, …; expected 2)",
            p + 1
        )
    );
    let l = line_of(&base, "1 wire 1 2");
    assert_eq!(
        err(&base.replace("1 wire 1 2 110 10", "1 wire 1 2 110 0")),
        format!("deck.dat:{l}: NumSegs `0` is not a whole number of at least 1")
    );
    assert_eq!(
        err(&base.replace("1 wire 1 2 110 10", "1 wire 1 2 110 2.5")),
        format!("deck.dat:{l}: NumSegs `2.5` is not a whole number of at least 1")
    );
    assert_eq!(
        err(&base.replace("1 wire 1 2", "1 Wire 1 2")),
        format!("deck.dat:{l}: line type `Wire` is not defined in the LINE TYPES section")
    );
    assert!(
        err(&base.replace("110 10 -", "110 10"))
            .starts_with(&format!("deck.dat:{l}: a LINES row needs 7 "))
    );
}

#[test]
fn tables_need_their_two_header_rows() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let no_units = base.replace("(#) (-) (m) (m) (m) (kg) (m3) (m2) (-)\n", "");
    let line = line_of(&no_units, "1 Fixed 100");
    assert_eq!(
        err(&no_units),
        format!(
            "deck.dat:{line}: section `POINTS` needs two header rows (column names, then units) before its data; found `1 Fixed 100 0 -50 0 0 0 0`"
        )
    );
    // An empty table (no rows at all) is an empty list.
    let d = deck("t\n--- LINE TYPES ---\n--- POINTS ---\n--- LINES ---\n--- END ---\n");
    assert!(d.line_types.is_empty() && d.points.is_empty() && d.lines.is_empty());
    let dup = base.replace("--- OUTPUTS ---", "--- POINTS ---");
    assert!(
        err(&dup).contains("section `POINTS` appears a second time (first at line 6)"),
        "{}",
        err(&dup)
    );
    assert_eq!(
        err("no sections here\n1 2 3\n"),
        "deck.dat: no MoorDyn section header (a dashed line such as `---- LINE TYPES ----`) was found"
    );
}

#[test]
fn unsupported_sections_are_listed_with_their_lines() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let extra = "--- ROD TYPES ---\nName Diam Mass Cd Ca CdEnd CaEnd\n(-) (m) (kg/m) (-) (-) (-) (-)\nCan 10 1e3 0.6 1 1.2 1\n\
                 --- BODIES ---\nID Att\n(#) (-)\n1 coupled 0 0 0 0 0 0 0 0 0 0 0 0\n--- RODS ---\n--- FAILURE ---\n1 5 1 0 1e6\n\
                 --- CONTROL ---\n--- EXTERNAL LOADS ---\n--- SYROPE IC ---\n--- Wave Kinematics ---\n0 0 0\n";
    let text = base.replace("--- OPTIONS ---", &format!("{extra}--- OPTIONS ---"));
    let d = deck(&text);
    let listed: Vec<(SectionKind, &str, usize)> = d
        .unsupported_sections()
        .map(|s| (s.kind, s.title.as_str(), s.line))
        .collect();
    let at = |t: &str| line_of(&text, t);
    assert_eq!(
        listed,
        [
            (SectionKind::RodTypes, "ROD TYPES", at("--- ROD TYPES")),
            (SectionKind::Rods, "RODS", at("--- RODS")),
            (SectionKind::Failure, "FAILURE", at("--- FAILURE")),
            (SectionKind::Control, "CONTROL", at("--- CONTROL")),
            (
                SectionKind::ExternalLoads,
                "EXTERNAL LOADS",
                at("--- EXTERNAL LOADS")
            ),
            (SectionKind::SyropeIc, "SYROPE IC", at("--- SYROPE IC")),
            (
                SectionKind::Unknown,
                "Wave Kinematics",
                at("--- Wave Kinematics")
            ),
        ]
    );
    // The rest of the deck is read as usual, the BODIES section with it (one coupled body).
    assert_eq!(d.lines.len(), 1);
    assert_eq!(
        d.sections_present
            .iter()
            .filter(|s| s.kind.is_read())
            .count(),
        6
    );
    assert_eq!(d.bodies.len(), 1);
    assert_eq!(d.bodies[0].kind, BodyKind::Coupled);
}

#[test]
fn extra_columns_curve_files_and_fortran_numbers() {
    let text = "t\n--- LINE TYPES ---\nName Diam Mass EA BA EI Cd Ca CdAx CaAx Cl dF\n(-) (m) (kg/m) (N) (Ns) (Nm2) (-) (-) (-) (-) (-) (-)\n\
                poly 0.2 30 ea_curve.txt 1e5|2e5 0 1.2 1 0.2 0 0.8 0.08 0.18\nsteel 0.05 1.5D1 2.1d8 -1 bend.dat 1.2 1 0.2 0\n--- END ---\n";
    let d = deck(text);
    let p = &d.line_types[0];
    assert_eq!(p.ea, LineValue::CurveFile("ea_curve.txt".into()));
    assert_eq!(p.ba, LineValue::Parts(vec!["1e5".into(), "2e5".into()]));
    assert_eq!(p.ea.number(), None);
    assert_eq!(
        p.extra,
        [
            ("Cl".to_string(), "0.8".to_string()),
            ("dF".into(), "0.08".into()),
            ("column13".into(), "0.18".into())
        ]
    );
    let s = &d.line_types[1];
    assert_eq!((s.mass_per_length, s.ea.number()), (15.0, Some(2.1e8)));
    assert_eq!(s.ei, LineValue::CurveFile("bend.dat".into()));
    let dup = text.replace("steel 0.05", "poly 0.05");
    assert_eq!(
        err(&dup),
        "deck.dat:6: line type `poly` is defined twice (first at line 5)"
    );
}

/// v1 decks whose LINE DICTIONARY has more columns than MoorDyn v1's nine (an `EI`
/// column, a viscoelastic `viscoE` column between the others) are read by their header
/// names, not by position.
#[test]
fn v1_line_dictionary_columns_are_found_by_their_header_names() {
    let row = |header: &str, units: &str, values: &str| {
        CHAIN_V1
            .replace(
                "LineType  Diam    MassDenInAir  EA        BA/-zeta  Can   Cat   Cdn   Cdt",
                header,
            )
            .replace(
                "(-)       (m)     (kg/m)        (N)       (Pa-s/-)  (-)   (-)   (-)   (-)",
                units,
            )
            .replace(
                "chain     0.252   390.0         1.674e9   -1.0      1.0   0.5   2.4   1.15",
                values,
            )
    };
    let with_visco = row(
        "LineType Diam MassDenInAir EA viscoE BA/-zeta EI Can Cat Cdn Cdt",
        "(-) (m) (kg/m) (N) (-) (Pa-s/-) (Nm2) (-) (-) (-) (-)",
        "chain 0.252 390.0 1.674e9 0.3 -1.0 0 1.0 0.5 2.4 1.15",
    );
    let d = deck(&with_visco);
    assert_eq!(d.version, Version::V1);
    let t = &d.line_types[0];
    assert_eq!(t.ea, LineValue::Number(1.674e9));
    assert_eq!(t.ba, LineValue::Number(-1.0));
    assert_eq!(t.ei, LineValue::Number(0.0));
    assert_eq!((t.ca, t.ca_ax, t.cd, t.cd_ax), (1.0, 0.5, 2.4, 1.15));
    assert_eq!(t.extra, [("viscoE".to_string(), "0.3".to_string())]);
    // The plain v1 header reads as before, and so does a header without names (positional).
    let plain = &deck(CHAIN_V1).line_types[0];
    assert_eq!(
        (plain.ca, plain.ca_ax, plain.cd, plain.cd_ax),
        (1.0, 0.5, 2.4, 1.15)
    );
    let unnamed = row(
        "a b c d e f g h i",
        "(-) (m) (kg/m) (N) (-) (-) (-) (-) (-)",
        "chain 0.252 390.0 1.674e9 -1.0 1.0 0.5 2.4 1.15",
    );
    assert_eq!(deck(&unnamed).line_types[0], *plain);
    let short = row(
        "LineType Diam MassDenInAir EA viscoE BA/-zeta EI Can Cat Cdn Cdt",
        "(-) (m) (kg/m) (N) (-) (Pa-s/-) (Nm2) (-) (-) (-) (-)",
        "chain 0.252 390.0 1.674e9 0.3 -1.0 0 1.0 0.5 2.4",
    );
    assert_eq!(
        err(&short),
        format!(
            "deck.dat:{}: a LINE TYPES row needs at least 11 (up to the last column the header names) fields, this one has 10",
            line_of(&short, "chain 0.252")
        )
    );
}

#[test]
fn moordyn_f_v1_count_lines_are_checked_and_skipped() {
    let text = "t\nFalse Echo - echo\n--- LINE TYPES ---\n1 NTypes - number of types\nName Diam Mass EA BA Can Cat Cdn Cdt\n(-) (m) (kg/m) (N) (-) (-) (-) (-) (-)\n\
                w 0.1 20 1e8 -1 1 0 1.6 0.1\n--- CONNECTION PROPERTIES ---\n2 NConnects\nNode Type X Y Z M V FX FY FZ CdA CA\n(-) (-) (m) (m) (m) (kg) (m3) (N) (N) (N) (m2) (-)\n\
                1 Fixed 0 0 -50 0 0 0 0 0 0 0\n2 Vessel 80 0 -5 0 0 0 0 -10 0 0\n--- LINE PROPERTIES ---\n1 NLines\nLine LineType UnstrLen NumSegs NodeAnch NodeFair Flags\n(-) (-) (m) (-) (-) (-) (-)\n\
                1 w 95 12 1 2 -\n--- OUTPUTS ---\nFairTen1\nEND\n--- END ---\n";
    let d = deck(text);
    assert_eq!(d.version, Version::V1);
    assert_eq!(d.points[1].force, Some([0.0, 0.0, -10.0]));
    assert_eq!(d.lines[0].attach_a, Attachment::Point(1));
    assert_eq!(
        err(&text.replace("2 NConnects", "3 NConnects")),
        "deck.dat:9: `NConnects` declares 3 row(s), but the table has 2"
    );
    assert_eq!(
        err(&text.replace("FairTen1\nEND\n", "FairTen1\nEND\nFairTen2\n")),
        "deck.dat:22: `FairTen2` follows the END of the OUTPUTS list"
    );
}

#[test]
fn recognition_is_by_content_and_never_takes_toml_for_a_deck() {
    assert!(looks_like_moordyn(SPAR_V2));
    assert!(looks_like_moordyn(CHAIN_V1));
    assert!(looks_like_moordyn(&SPAR_V2.replace('\n', "\r\n")));
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut tomls = 0;
    for entry in std::fs::read_dir(examples).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(!looks_like_moordyn(&text), "{}", path.display());
            tomls += 1;
        }
    }
    assert!(tomls >= 5);
    // A scenario that mentions the titles in comments and in a string.
    let toml = "# ---- LINE TYPES ----\n# ---- LINES ----\n[run]\nnote = \"\"\"\n---- LINE TYPES ----\n---- LINES ----\n\"\"\"\nend = 1.0\n";
    assert!(!looks_like_moordyn(toml));
    // Only one of the two sections, or none.
    assert!(!looks_like_moordyn("t\n--- LINE TYPES ---\n"));
    assert!(!looks_like_moordyn("t\n--- OPTIONS ---\n--- OUTPUTS ---\n"));
    // An OpenFAST module file with an OUTPUT section is no deck.
    assert!(!looks_like_moordyn(
        "ElastoDyn\n--- SIMULATION CONTROL ---\nFalse Echo\n--- OUTPUT ---\n\"TipDxc1\"\nEND\n"
    ));
    // A deck of rods only is a deck (that the mapping will refuse).
    assert!(looks_like_moordyn(
        "t\n--- ROD TYPES ---\n--- RODS ---\n--- OPTIONS ---\n"
    ));
    assert!(!looks_like_moordyn("just some text\n"));
    assert!(!looks_like_moordyn(""));
}

#[test]
fn load_reads_files_and_names_them() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/moordyn/chain_shallow_v1.dat");
    let d = load(&path).unwrap();
    assert_eq!(d.file, path.display().to_string());
    assert_eq!(d.lines.len(), 3);
    let dir = crate::test_util::temp_dir("moordyn", "load");
    let missing = dir.join("missing.dat");
    assert!(
        load(&missing)
            .unwrap_err()
            .to_string()
            .starts_with("cannot read MoorDyn deck")
    );
    let binary = dir.join("binary.dat");
    std::fs::write(&binary, b"title\n\xff\xfe--- LINES ---\n").unwrap();
    assert_eq!(
        load(&binary).unwrap_err().to_string(),
        format!(
            "MoorDyn deck {} is not UTF-8 text (byte 6, on line 2, is invalid)",
            binary.display()
        )
    );
    let bad = dir.join("bad.dat");
    std::fs::write(&bad, CHAIN_V1.replace("390.0", "39O.0")).unwrap();
    let line = line_of(CHAIN_V1, "chain     0.252");
    assert_eq!(
        load(&bad).unwrap_err().to_string(),
        format!("{}:{line}: MassDen `39O.0` is not a number", bad.display())
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Pieces of decks to garble: headers, rows, options and noise.
fn piece() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("---- LINE TYPES ----".to_string()),
        Just("---- POINTS ----".to_string()),
        Just("---- LINES ----".to_string()),
        Just("---- LINE PROPERTIES ----".to_string()),
        Just("---- OPTIONS ----".to_string()),
        Just("---- OUTPUTS ----".to_string()),
        Just("---- END ----".to_string()),
        Just("Name Diam MassDen EA BA EI Cd Ca CdAx CaAx".to_string()),
        Just("(-) (m) (kg/m) (N) (-) (-) (-) (-) (-) (-)".to_string()),
        Just("w 0.1 20 1e8 -1 0 1 1 0.1 0".to_string()),
        Just("1 Fixed 0 0 -50 0 0 0 0".to_string()),
        Just("2 Body4294967295 0 0 -5 0 0 0 0".to_string()),
        Just("1 w 1 2 100 4294967296 -".to_string()),
        Just("1 w R1A P2 100 10 p".to_string()),
        Just("3 NLines".to_string()),
        Just("0.01 dtM".to_string()),
        Just("END".to_string()),
        "[ -~\t#|]{0,40}",
        "[0-9a-zA-Z .eED+-]{0,30}",
        "\\PC{0,12}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]
    #[test]
    fn garbled_decks_never_panic(pieces in prop::collection::vec(piece(), 0..30), crlf in any::<bool>()) {
        let sep = if crlf { "\r\n" } else { "\n" };
        let text = pieces.join(sep);
        let _ = looks_like_moordyn(&text);
        match parse(&text, "g.dat") {
            Ok(d) => {
                let o = &d.options;
                let _ = (o.dt_m(), o.water_depth(), o.k_bot(), o.t_scheme());
                prop_assert_eq!(d.lines.iter().map(|l| l.id).collect::<Vec<_>>(), (1..=d.lines.len() as u32).collect::<Vec<_>>());
            }
            Err(e) => prop_assert!(e.to_string().starts_with("g.dat"), "{}", e),
        }
    }

    #[test]
    fn mutated_examples_never_panic(cut in 0usize..4000, insert in "\\PC{0,8}", which in any::<bool>()) {
        let base = if which { SPAR_V2 } else { CHAIN_V1 };
        let at = base.floor_char_boundary(cut.min(base.len()));
        let text = format!("{}{}{}", &base[..at], insert, &base[at..]);
        let _ = looks_like_moordyn(&text);
        if let Err(e) = parse(&text, "m.dat") {
            prop_assert!(e.to_string().starts_with("m.dat"), "{}", e);
        }
    }
}

/// The BODIES rows: the attachment words (any case, a number after `Vessel` ignored,
/// the pinned forms), the pose, and the starred columns with one or several `|`-separated
/// values kept as written; a row of the wrong width, a starred column with a value count
/// MoorDyn does not take, an unknown word and an id out of sequence are refused at their
/// line.
#[test]
fn bodies_are_read_with_their_starred_columns() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let with = |rows: &str| {
        base.replace(
            "--- OPTIONS ---",
            &format!("--- BODIES ---\nID Att X0 Y0 Z0 r0 p0 y0 M CG I V CdA Ca\n(#) (-) (m) (m) (m) (deg) (deg) (deg) (kg) (m) (kgm2) (m3) (m2) (-)\n{rows}\n--- OPTIONS ---"),
        )
    };
    let text = with(
        "1 free 1 2 -30 0 5 90 2e5 0.5|0|1 1e6|2e6|3e6 400 20|0 0\n2 Vessel1 0 0 0 0 0 0 0 0 0 0 0 0\n3 FIX 0 0 -50 0 0 0 0 -2 1e3 0 1|2|3|4|5|6 0|0|0\n4 CoupledPinned 0 0 0 0 0 0 0 0 0 0 0 0",
    );
    let d = deck(&text);
    assert_eq!(d.bodies.len(), 4);
    let b = &d.bodies[0];
    assert_eq!(
        (b.id, b.kind, b.kind_text.as_str()),
        (1, BodyKind::Free, "free")
    );
    assert_eq!(b.pose, [1.0, 2.0, -30.0, 0.0, 5.0, 90.0]);
    assert_eq!((b.mass, b.volume), (2e5, 400.0));
    assert_eq!(b.cg, vec![0.5, 0.0, 1.0]);
    assert_eq!(b.inertia, vec![1e6, 2e6, 3e6]);
    assert_eq!((b.cda.clone(), b.ca.clone()), (vec![20.0, 0.0], vec![0.0]));
    assert_eq!(b.line, line_of(&text, "1 free"));
    assert_eq!(d.bodies[1].kind, BodyKind::Coupled);
    assert_eq!(d.bodies[2].kind, BodyKind::Fixed);
    assert_eq!(d.bodies[2].cg, vec![-2.0]);
    assert_eq!(d.bodies[2].cda, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(d.bodies[3].kind, BodyKind::Pinned);
    let cases = [
        (
            "1 free 0 0 0 0 0 0 1 0 1 0 0",
            "a BODIES row needs 14 (ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG I Volume CdA Ca) fields, this one has 13",
        ),
        ("1 free 0 0 0 0 0 0 1 0|1 1 0 0 0", "CG `0|1`"),
        ("1 free 0 0 0 0 0 0 1 0 1 0 1|2|3|4 0", "CdA `1|2|3|4`"),
        (
            "1 floating 0 0 0 0 0 0 1 0 1 0 0 0",
            "body type `floating` is not one of",
        ),
        (
            "2 free 0 0 0 0 0 0 1 0 1 0 0 0",
            "BODIES id 2 is out of sequence",
        ),
    ];
    for (row, says) in cases {
        let text = with(row);
        let e = err(&text);
        let line = line_of(&text, row);
        assert!(
            e.starts_with(&format!("deck.dat:{line}: ")) && e.contains(says),
            "{row}: {e}"
        );
    }
}

/// A `---` in the remark of an option or data row does not make the row a section header
/// (MoorDyn's test is any `---` on the line): a row that starts with a number, or an
/// option row whose second field is an option name, is data and the remark is dropped.
#[test]
fn a_dashed_remark_on_a_data_row_is_not_a_header() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS")
        .replace("50 WtrDpth\n", "50 WtrDpth\n1025 rho\n");
    let dashed = base
        .replace("50 WtrDpth\n", "50 WtrDpth --- water depth (m)\n")
        .replace(
            "1 Fixed 100 0 -50 0 0 0 0\n",
            "1 Fixed 100 0 -50 0 0 0 0 --- anchor\n",
        )
        .replace("0.01 dtM\n", "0.01 dtM\nRK4 tScheme ---- time scheme\n");
    let d = deck(&dashed);
    assert_eq!(d.sections_present.len(), 5, "{:?}", d.sections_present);
    assert_eq!(d.unsupported_sections().count(), 0);
    assert_eq!(
        d.options.water_depth().unwrap(),
        Some(WaterDepth::Depth(50.0))
    );
    assert_eq!(d.options.water_density().unwrap(), Some(1025.0));
    assert_eq!(d.options.t_scheme(), Some("RK4"));
    let wtr = d.options.get("WtrDpth").unwrap();
    assert_eq!(
        (wtr.line, wtr.remark.as_str()),
        (line_of(&dashed, "50 WtrDpth"), "")
    );
    assert_eq!(d.points, deck(&base).points);
    // Lines that are headers stay headers, numbers in the title or not.
    let titled = base.replace("--- LINES ---", "--- LINES 3 of them ---");
    assert_eq!(deck(&titled).lines, deck(&base).lines);
}

/// Decks exported on Windows: Latin-1 (`°`, `²` as single bytes) and UTF-16 with its
/// byte-order mark are read as the same deck, with a note saying how; a file that is
/// neither a deck nor UTF-8 is refused naming the line of the bad byte.
#[test]
fn latin1_and_utf16_decks_are_read_with_a_note() {
    let dir = crate::test_util::temp_dir("moordyn", "encodings");
    let text = CHAIN_V1.replacen('\n', " at 20 \u{b0}C, EA in N/m\u{b2}\n", 1);
    let utf8 = dir.join("utf8.dat");
    std::fs::write(&utf8, &text).unwrap();
    let want = load(&utf8).unwrap();
    assert!(want.notes.is_empty(), "{:?}", want.notes);
    let latin1: Vec<u8> = text
        .chars()
        .map(|c| u8::try_from(c as u32).unwrap())
        .collect();
    let path = dir.join("latin1.dat");
    std::fs::write(&path, &latin1).unwrap();
    let d = load(&path).unwrap();
    assert_eq!(
        (&d.title, &d.lines, &d.options.entries),
        (&want.title, &want.lines, &want.options.entries)
    );
    assert_eq!(d.notes.len(), 1, "{:?}", d.notes);
    assert_eq!(
        d.notes[0].line, 1,
        "the first byte that is not UTF-8 is on line 1"
    );
    assert!(
        d.notes[0].text.contains("read as Latin-1"),
        "{}",
        d.notes[0].text
    );
    for (name, big) in [("le", false), ("be", true)] {
        let mut bytes = if big {
            vec![0xfe, 0xff]
        } else {
            vec![0xff, 0xfe]
        };
        for u in text.encode_utf16() {
            bytes.extend(if big {
                u.to_be_bytes()
            } else {
                u.to_le_bytes()
            });
        }
        let path = dir.join(format!("utf16{name}.dat"));
        std::fs::write(&path, &bytes).unwrap();
        let d = load(&path).unwrap();
        assert_eq!(
            (&d.title, &d.lines, &d.options.entries),
            (&want.title, &want.lines, &want.options.entries)
        );
        assert_eq!(d.notes.len(), 1, "{:?}", d.notes);
        assert!(
            d.notes[0].text.contains("read as UTF-16"),
            "{}",
            d.notes[0].text
        );
    }
    // Not UTF-8 and not a deck: refused with the line of the bad byte.
    let binary = dir.join("binary.dat");
    std::fs::write(&binary, b"title\nnotes\n\xb0 --- LINES ---\n").unwrap();
    assert_eq!(
        load(&binary).unwrap_err().to_string(),
        format!(
            "MoorDyn deck {} is not UTF-8 text (byte 12, on line 3, is invalid)",
            binary.display()
        )
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// OUTPUTS written OpenFAST-style: channel names separated by commas, or in double quotes.
#[test]
fn outputs_take_commas_and_quotes() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let text = base.replace(
        "FairTen1\n",
        "FairTen1, AnchTen1,L1N10T\n\"Point2PX\" \"Point2PZ\",\"L1N3T\"\n",
    );
    let d = deck(&text);
    let names: Vec<&str> = d.outputs.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "FairTen1", "AnchTen1", "L1N10T", "Point2PX", "Point2PZ", "L1N3T"
        ]
    );
    let second = line_of(&text, "Point2PX");
    assert_eq!(d.outputs[3].line, second);
    assert_eq!(d.outputs[0].line, second - 1);
}

/// An option given twice (under the same name or another of its names): the later line
/// counts, and a note names both lines and the value used.
#[test]
fn a_repeated_option_is_noted_with_both_lines() {
    let base = small_v2("LINE TYPES", "POINTS", "LINES", "OPTIONS", "OUTPUTS");
    let text = base.replace(
        "50 WtrDpth\n",
        "2000 WtrDnsty\n50 WtrDpth\n60 wtrdpth depth\n1025 rho\n70 WtrDpth\n",
    );
    let d = deck(&text);
    assert_eq!(d.options.water_density().unwrap(), Some(1025.0));
    assert_eq!(
        d.options.water_depth().unwrap(),
        Some(WaterDepth::Depth(70.0))
    );
    let (dens, rho) = (line_of(&text, "2000 WtrDnsty"), line_of(&text, "1025 rho"));
    let (d50, d60, d70) = (
        line_of(&text, "50 WtrDpth"),
        line_of(&text, "60 wtrdpth"),
        line_of(&text, "70 WtrDpth"),
    );
    let texts: Vec<(usize, &str)> = d.notes.iter().map(|n| (n.line, n.text.as_str())).collect();
    assert_eq!(
        texts,
        [
            (
                rho,
                &*format!(
                    "option WtrDnsty is given twice, on line {dens} (`2000 WtrDnsty`) and line {rho} (`1025 rho`): the later, 1025, is used"
                )
            ),
            (
                d70,
                &*format!(
                    "option WtrDpth is given 3 times, on line {d50} (`50 WtrDpth`), line {d60} (`60 wtrdpth`) and line {d70} (`70 WtrDpth`): the last, 70, is used"
                )
            ),
        ]
    );
    assert!(deck(&base).notes.is_empty());
}
