//! MoorDyn decks through the commands: `check` prints the mapping, `statics` of the example
//! decks against the elastic catenary with a grounded length, a short `run` whose energy
//! balance holds, and `--ignore`.

use std::path::Path;

use phstring::testing::catenary_on_seabed;

use crate::{phstring, run_with, summary, temp_dir, workspace_root};

const CHAIN: &str = "examples/moordyn/chain_shallow_v1.dat";
const SPAR: &str = "examples/moordyn/spar_oc3_v2.dat";

/// Sea water [kg/m³] and gravity [m/s²], the decks' values (MoorDyn's defaults for the
/// chain deck, which gives neither).
const RHO_W: f64 = 1025.0;
const G: f64 = 9.80665;

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}
fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The rows of `equilibrium.csv` in `dir`: position and reaction of every node.
fn equilibrium(dir: &Path) -> Vec<[f64; 6]> {
    let mut r = csv::Reader::from_path(dir.join("equilibrium.csv")).unwrap();
    r.records()
        .map(|x| {
            let x = x.unwrap();
            std::array::from_fn(|k| x[k + 1].parse().unwrap())
        })
        .collect()
}

/// The columns of `energy.csv` in `out` by name, its rows, and the worst closure of the
/// balance `Ĥ − Ĥ(0) − supplied + dissipated` over its rows, relative to each row's scale.
fn energy_closure(out: &Path) -> (Vec<String>, Vec<Vec<f64>>, f64) {
    let mut r = csv::Reader::from_path(out.join("energy.csv")).unwrap();
    let h: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let c = |n: &str| h.iter().position(|x| x == n).unwrap();
    let rows: Vec<Vec<f64>> = r
        .records()
        .map(|x| x.unwrap().iter().map(|f| f.parse().unwrap()).collect())
        .collect();
    let (kin, pot, ham, sup, dis) = (
        c("kinetic"),
        c("potential"),
        c("hamiltonian"),
        c("supplied_energy"),
        c("dissipated_energy"),
    );
    let h0 = rows[0][ham];
    let mut worst = 0.0f64;
    for row in &rows {
        let scale = row[kin].abs() + row[pot].abs() + h0.abs() + row[sup].abs() + row[dis].abs();
        worst = worst.max((row[ham] - h0 - row[sup] + row[dis]).abs() / scale);
    }
    (h, rows, worst)
}

/// The lines of a deck, all alike: unstretched length [m], wet weight per length [N/m], EA
/// [N], the first line's anchor [m], the node of the first fairlead, the water depth [m],
/// and how many lines (line `k` runs from node `k` to node `fairlead + k`).
struct Line {
    length: f64,
    wet_weight: f64,
    ea: f64,
    anchor: [f64; 3],
    fairlead: usize,
    depth: f64,
    count: usize,
}

/// Every deck's lines hang between an anchor and a vessel point: statics start from the
/// catenary first guess and Newton converges from it in at most 4 iterations (measured 3 on
/// the decks' meshes and with 4 elements per segment, 4 for the semi on 4x).
fn assert_catenary_start(s: &serde_json::Value, name: &str) {
    assert_eq!(s["path"], "catenary_guess", "{name}: {}", s["first_guess"]);
    assert_eq!(s["first_guess"], "used", "{name}");
    let iterations = s["newton_iterations"].as_u64().unwrap();
    assert!(iterations <= 4, "{name}: {iterations} Newton iterations");
}

/// Runs `phstring statics DECK` with `sets` and compares the fairleads' tensions (their
/// reactions; node `i` is the deck's point `i + 1`) with the closed form; returns the
/// largest relative error of the horizontal tension and of the fairlead tension.
fn fairlead_errors(deck: &str, name: &str, line: &Line, sets: &[&str]) -> (f64, f64) {
    let out = temp_dir(name);
    let mut args = vec!["statics", deck, "--out", out.to_str().unwrap(), "--force"];
    for s in sets {
        args.extend(["--set", s]);
    }
    let o = phstring(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = equilibrium(&out);
    let s = summary(&out);
    assert_eq!(s["deck"]["path"], deck);
    assert_catenary_start(&s, name);
    let mut worst = (0.0f64, 0.0f64);
    for k in 0..line.count {
        let f = rows[line.fairlead + k];
        let a = rows[k];
        let x = ((f[0] - a[0]).powi(2) + (f[1] - a[1]).powi(2)).sqrt();
        let hv = f[2] + line.depth;
        if k == 0 {
            assert_eq!(a[..3], line.anchor);
        }
        let (h, v, _) = catenary_on_seabed(line.length, line.wet_weight, line.ea, x, hv);
        let (hf, vf) = ((f[3].powi(2) + f[4].powi(2)).sqrt(), f[5]);
        let e_h = (hf - h) / h;
        let e_t = (hf.hypot(vf) - h.hypot(v)) / h.hypot(v);
        eprintln!(
            "{name}: fairlead {k}: H {hf:.1} N (closed form {h:.1}), V {vf:.1} N ({v:.1}); errors H {e_h:.2e}, tension {e_t:.2e}"
        );
        worst = (worst.0.max(e_h.abs()), worst.1.max(e_t.abs()));
    }
    worst
}

/// `phstring statics` of both example decks: the fairlead tension against the elastic
/// catenary with a grounded length on a rigid frictionless seabed (the decks have no
/// friction; the penalty seabed's penetration w/(k d), 4 mm and 0.3 mm, shifts the height by
/// 1e-4 and 1e-6 of it). The spar's 20 segments of 45 m resolve its 770 m suspended span:
/// within 0.5 % (measured 0.13 %). The chain's 10 m segments leave about 6 of them to its 65 m
/// suspended span (H/w = 29 m): the deck's own mesh is 1.0 % off (measured 1.04 %), and two
/// and four elements per segment (`--set string.K.elements`) bring it to 0.18 % and 0.034 %.
#[test]
fn statics_of_the_example_decks_match_the_elastic_catenary() {
    let area = |d: f64| std::f64::consts::PI / 4.0 * d * d;
    let spar = Line {
        length: 902.2,
        wet_weight: (77.7066 - RHO_W * area(0.09)) * G,
        ea: 384.243e6,
        anchor: [853.87, 0.0, -320.0],
        fairlead: 3,
        depth: 320.0,
        count: 3,
    };
    let (e_h, e_t) = fairlead_errors(SPAR, "deck-spar", &spar, &[]);
    assert!(e_h <= 5e-3 && e_t <= 5e-3, "{e_h:e} {e_t:e}");
    let chain = Line {
        length: 400.0,
        wet_weight: (390.0 - RHO_W * area(0.252)) * G,
        ea: 1.674e9,
        anchor: [420.0, 0.0, -50.0],
        fairlead: 3,
        depth: 50.0,
        count: 3,
    };
    let (_, coarse) = fairlead_errors(CHAIN, "deck-chain", &chain, &[]);
    assert!(coarse <= 1.5e-2, "{coarse:e}");
    let fine = [
        "string.0.elements=4",
        "string.1.elements=4",
        "string.2.elements=4",
    ];
    let (_, refined) = fairlead_errors(CHAIN, "deck-chain4", &chain, &fine);
    assert!(
        refined <= 1e-3 && refined < coarse / 10.0,
        "{refined:e} {coarse:e}"
    );
}

/// The v2 example decks written from public numbers (examples/moordyn), each with its
/// platform motion table `NAME_motion.csv`, and their lines for the closed form.
fn v2_examples() -> Vec<(&'static str, Line)> {
    let area = |d: f64| std::f64::consts::PI / 4.0 * d * d;
    let line = |length, mass: f64, diameter, ea, anchor, depth, count| Line {
        length,
        wet_weight: (mass - RHO_W * area(diameter)) * G,
        ea,
        anchor,
        fairlead: count,
        depth,
        count,
    };
    vec![
        (
            "chain_shallow_50m",
            line(350.0, 200.1, 0.1801, 8.5606e8, [358.0, 0.0, -50.0], 50.0, 1),
        ),
        (
            "chain_intermediate_150m",
            line(473.3, 130.4, 0.0809, 5.89e8, [422.5, 0.0, -150.0], 150.0, 1),
        ),
        (
            "chain_deep_320m",
            line(
                1100.0,
                685.0,
                0.333,
                3.27e9,
                [1000.0, 0.0, -320.0],
                320.0,
                1,
            ),
        ),
        (
            "semi_oc4",
            line(
                835.5,
                113.35,
                0.0766,
                7.536e8,
                [418.8, 725.383, -200.0],
                200.0,
                3,
            ),
        ),
    ]
}

/// `phstring statics` of the v2 example decks against the elastic catenary with a grounded
/// length on a rigid frictionless seabed (as above): the fairlead tension within 0.5 % on
/// the deck's own mesh and within 0.05 % with four elements per segment
/// (`--set string.K.elements=4`), where the lumped-mass error, O(l²) in the segment length
/// l, is about 16 times smaller. Measured on the deck's mesh and on 4×: shallow chain (10 m
/// segments, H/w = 100 m) 0.32 % and 0.013 %, intermediate (11.8 m, H/w = 96 m) 0.028 % and
/// 0.0023 %, deep (22 m, H/w = 258 m) 0.028 % and 0.0016 %, semi (41.8 m, H/w = 845 m)
/// 0.17 % and 0.014 %.
#[test]
fn statics_of_the_v2_example_decks_match_the_elastic_catenary() {
    for (name, line) in v2_examples() {
        let deck = format!("examples/moordyn/{name}_v2.dat");
        let (_, own) = fairlead_errors(&deck, name, &line, &[]);
        let fine: Vec<String> = (0..line.count)
            .map(|k| format!("string.{k}.elements=4"))
            .collect();
        let fine: Vec<&str> = fine.iter().map(String::as_str).collect();
        let (_, refined) = fairlead_errors(&deck, &format!("{name}4"), &line, &fine);
        eprintln!(
            "{name}: fairlead tension error {own:.2e} on the deck's mesh, {refined:.2e} on 4x"
        );
        assert!(own <= 5e-3, "{name}: {own:e}");
        assert!(refined <= 5e-4, "{name}: {refined:e}");
    }
}

/// Every deck in examples/moordyn is listed here; each v2 example runs through `check`,
/// `statics` and a short stretch (2 s) of `run --motion` with its table: both start from the
/// catenary first guess ([`assert_catenary_start`]), the run completes,
/// its end_tensions.csv (`t`, then `FairTen<i>, AnchTen<i>` for each line) starts at the
/// static fairlead tension of `statics` (to 1e-6) and
/// its energy balance closes to 1e-9 of its scale.
#[test]
fn every_example_deck_runs_check_statics_and_its_motion() {
    let mut files: Vec<String> =
        std::fs::read_dir(crate::workspace_root().join("examples/moordyn"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".dat"))
            .collect();
    files.sort();
    let mut listed: Vec<String> = v2_examples()
        .iter()
        .map(|(n, _)| format!("{n}_v2.dat"))
        .chain(["chain_shallow_v1.dat".into(), "spar_oc3_v2.dat".into()])
        .collect();
    listed.sort();
    assert_eq!(files, listed, "every example deck must be covered here");
    let dir = temp_dir("deck-examples");
    let names = v2_examples()
        .into_iter()
        .map(|(n, _)| n)
        .chain(["spar_oc3"]);
    for name in names {
        let deck = format!("examples/moordyn/{name}_v2.dat");
        let table = format!("examples/moordyn/{name}_motion.csv");
        let o = phstring(&["check", &deck, "--motion", &table]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let st = dir.join(format!("{name}-statics"));
        let o = phstring(&["statics", &deck, "--out", st.to_str().unwrap(), "-q"]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        assert_catenary_start(&summary(&st), name);
        let out = dir.join(name);
        let o = run_with(
            &deck,
            &out,
            &[
                "time.end=2.0",
                "output.plots=false",
                "output.vtk=false",
                "output.animation=false",
            ],
            &["--motion", &table],
        );
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let s = summary(&out);
        assert_eq!(s["status"], "completed", "{name}");
        let start = s["initial_equilibrium"].as_str().unwrap();
        assert!(start.starts_with("catenary_guess"), "{name}: {start}");
        let (_, _, worst) = energy_closure(&out);
        assert!(worst <= 1e-9, "{name}: balance closure {worst:e}");
        let mut r = csv::Reader::from_path(out.join("end_tensions.csv")).unwrap();
        let rows: Vec<Vec<f64>> = r
            .records()
            .map(|x| x.unwrap().iter().map(|f| f.parse().unwrap()).collect())
            .collect();
        assert!((rows.last().unwrap()[0] - 2.0).abs() < 1e-9, "{name}");
        let reactions = equilibrium(&st);
        let lines = (rows[0].len() - 1) / 2;
        for k in 0..lines {
            let f = reactions[lines + k];
            let statics = (f[3] * f[3] + f[4] * f[4] + f[5] * f[5]).sqrt();
            let start = rows[0][1 + 2 * k];
            assert!(
                (start - statics).abs() <= 1e-6 * statics,
                "{name}: line {k}: FairTen at t = 0 is {start} N, statics {statics} N"
            );
        }
    }
}

/// `phstring run DECK --set time.end=…`: from the static equilibrium, the lines given an
/// upward velocity `0.2 sin(π s/L)` m/s swing back with drag, seabed damping and the
/// Kelvin–Voigt damping converted from the deck's damping ratio; energy.csv's balance
/// `Ĥ − Ĥ(0) − supplied + dissipated` closes to 1e-9 of the energy scale at every row, and
/// summary.json records the deck.
#[test]
fn a_short_run_of_a_deck_keeps_the_energy_balance() {
    let dir = temp_dir("deck-run");
    let out = dir.join("chain");
    let o = run_with(
        CHAIN,
        &out,
        &[
            "time.end=0.05",
            r#"initial.velocity=["0", "0", "0.2*sin(pi*s/L)"]"#,
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (h, rows, worst) = energy_closure(&out);
    let c = |n: &str| h.iter().position(|x| x == n).unwrap();
    let (kin, dis) = (c("kinetic"), c("dissipated_energy"));
    assert_eq!(rows.len(), 101);
    assert!(
        rows[0][kin] > 1e3,
        "the lines start moving: {}",
        rows[0][kin]
    );
    eprintln!("deck run: worst balance closure {worst:.2e}");
    assert!(worst <= 1e-9, "{worst:e}");
    let last = rows.last().unwrap();
    assert!(last[dis] > 0.0 && last[c("drag_dissipated")] > 0.0);
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["deck"]["path"], CHAIN);
    assert_eq!(s["deck"]["version"], "v1");
    assert!(s["deck"]["not_needed"]["TmaxIC"].is_string());
    assert_eq!(s["deck"]["converted"].as_array().unwrap().len(), 6);
    assert!(s["deck"].get("ignored").is_none());
}

/// `check DECK` prints the table of what each deck entry became, then the scenario as
/// `check` always does; `--print-scenario` prints the generated TOML.
#[test]
fn check_prints_the_mapping_of_a_deck() {
    let o = phstring(&["check", SPAR]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for expected in [
        "examples/moordyn/spar_oc3_v2.dat is a MoorDyn v2 deck; it maps onto a phstring scenario as follows:",
        "line type spar_line",
        "materials spar_line_lineN, one per line: tension_only_linear, EA = 384243000 N, rho_a = 77.7066 kg/m (in air)",
        "node point4, a support held at its deck position (no vessel motion)",
        "string line1: 20 elements of 45.11 m from point1 to point4, material spar_line_line1",
        "option dtM = 0.002",
        "time.h = 0.002 s (the largest step)",
        "option rho = 1025",
        "water.density = 1025 kg/m³",
        "not needed: TmaxIC: phstring solves the static equilibrium directly",
        "time.end = 60 s: phstring's default for decks",
        "converted: examples/moordyn/spar_oc3_v2.dat:20: BA/-zeta = -0.8 of line type spar_line on line 1",
        "the scenario generated from examples/moordyn/spar_oc3_v2.dat is valid:",
        "mesh:      60 elements, 63 nodes: 3 strings, 0 springs, 63 named nodes",
    ] {
        assert!(text.contains(expected), "missing {expected:?} in\n{text}");
    }
    let o = phstring(&["check", SPAR, "--print-scenario", "--set", "time.end=2.0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let t: toml::Table = stdout(&o).parse().unwrap();
    assert_eq!(t["string"].as_array().unwrap().len(), 3);
    assert_eq!(t["time"]["end"].as_float(), Some(2.0));
    assert_eq!(t["deck"]["path"].as_str(), Some(SPAR));
    // A bad override of the generated scenario names the option.
    let o = phstring(&["check", SPAR, "--set", "time.h=-1"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).starts_with("error: --set time.h=-1: "),
        "{}",
        stderr(&o)
    );
}

/// A deck with bending stiffness is refused naming its line; `--ignore EI` drops it and
/// the summary records it; `--ignore` of a scenario file is refused.
#[test]
fn ignore_drops_a_refused_feature_on_purpose() {
    let dir = temp_dir("deck-ignore");
    let deck = dir.join("stiff.dat");
    let text = std::fs::read_to_string(crate::workspace_root().join(SPAR))
        .unwrap()
        .replace("-0.8      0     1.6", "-0.8      2.5e4 1.6");
    std::fs::write(&deck, &text).unwrap();
    let deck = deck.to_str().unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with("spar_line"))
        .unwrap()
        + 1;
    let o = phstring(&["check", deck]);
    assert!(!o.status.success());
    assert_eq!(
        stderr(&o).trim_end(),
        format!(
            "error: {deck}:{line}: bending stiffness EI = 25000 N·m² of line type spar_line is not supported by phstring (give `--ignore EI` to drop it on purpose)"
        )
    );
    let out = dir.join("st");
    let o = phstring(&[
        "statics",
        deck,
        "--ignore",
        "EI",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    let ignored = s["deck"]["ignored"].as_array().unwrap();
    assert_eq!(ignored.len(), 1);
    assert!(
        ignored[0]
            .as_str()
            .unwrap()
            .starts_with(&format!("{deck}:{line}: bending stiffness EI")),
        "{ignored:?}"
    );
    let o = phstring(&["check", "examples/taut_string.toml", "--ignore", "EI"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--ignore applies to decks only"),
        "{}",
        stderr(&o)
    );
}

/// `--motion FILE` moves a deck's coupled points rigidly by a platform table `t, x, y, z,
/// roll, pitch, yaw`: the spar's fairleads (deck positions = body coordinates) surge by
/// `2 sin(2πt/10)(1 − e^{−t²})` m under a constant yaw of 0.05 rad, so point 4 (node 3,
/// `b = (5.2, 0, −70)`) is at `p(t) + Rz(0.05) b` on every frame (the table's rows; to 1e-9
/// m); the run ends at the table's last time, 2.5 s; the energy balance closes to 1e-9 of
/// its scale; the summary records the motion; a scenario file with `--motion` is refused.
#[test]
fn a_vessel_motion_table_moves_the_coupled_points() {
    let dir = temp_dir("deck-motion");
    let surge =
        |t: f64| 2.0 * (2.0 * std::f64::consts::PI * t / 10.0).sin() * (1.0 - (-t * t).exp());
    let yaw: f64 = 0.05;
    let mut table = String::from("t, x, y, z, roll, pitch, yaw\n");
    for i in 0..=50 {
        let t = 0.05 * i as f64;
        table.push_str(&format!("{t}, {}, 0, 0, 0, 0, {yaw}\n", surge(t)));
    }
    let table_path = dir.join("vessel.csv");
    std::fs::write(&table_path, table).unwrap();
    let out = dir.join("spar");
    let o = run_with(
        SPAR,
        &out,
        &["output.plots=false", "output.animation=false"],
        &["--motion", table_path.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let mut r = csv::Reader::from_path(out.join("positions.csv")).unwrap();
    let mut frames = 0;
    let mut last_t = 0.0f64;
    for rec in r.records() {
        let rec = rec.unwrap();
        if &rec[1] != "3" {
            continue;
        }
        let t: f64 = rec[0].parse().unwrap();
        let x: [f64; 3] = std::array::from_fn(|k| rec[k + 2].parse().unwrap());
        let expected = [surge(t) + 5.2 * yaw.cos(), 5.2 * yaw.sin(), -70.0];
        for k in 0..3 {
            assert!(
                (x[k] - expected[k]).abs() <= 1e-9,
                "t = {t}: point 4 at {x:?}, the table puts it at {expected:?}"
            );
        }
        frames += 1;
        last_t = t;
    }
    assert!(frames >= 26, "{frames} frames");
    assert!((last_t - 2.5).abs() <= 1e-12, "the run ends at {last_t} s");
    let (h, rows, worst) = energy_closure(&out);
    let sup = h.iter().position(|x| x == "supplied_energy").unwrap();
    assert!(worst <= 1e-9, "balance closure {worst:e}");
    assert!(
        rows.last().unwrap()[sup].abs() > 1.0,
        "the vessel supplies work"
    );
    let s = summary(&out);
    let converted = s["deck"]["converted"].to_string();
    assert!(converted.contains("--motion"), "{converted}");
    let o = phstring(&[
        "check",
        "examples/mooring_line.toml",
        "--motion",
        table_path.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("is a scenario file, not a MoorDyn deck"),
        "{}",
        stderr(&o)
    );
}

/// A platform table of `steps` rows 0.05 s apart: a 2 m surge at a 10 s period, ramped in.
fn surge_table(dir: &Path, steps: usize) -> std::path::PathBuf {
    let surge =
        |t: f64| 2.0 * (2.0 * std::f64::consts::PI * t / 10.0).sin() * (1.0 - (-t * t).exp());
    let mut table = String::from("t, x, y, z, roll, pitch, yaw\n");
    for i in 0..=steps {
        let t = 0.05 * i as f64;
        table.push_str(&format!("{t}, {}, 0, 0, 0, 0, 0\n", surge(t)));
    }
    let path = dir.join("surge.csv");
    std::fs::write(&path, table).unwrap();
    path
}

/// The title row, the units row and the value rows of a MoorDyn-style `.out` table.
fn read_out(path: &Path) -> (Vec<String>, Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let words = |l: &str| l.split_whitespace().map(String::from).collect::<Vec<_>>();
    let names = words(lines.next().unwrap());
    let units = words(lines.next().unwrap());
    let rows = lines
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect();
    (names, units, rows)
}

/// The OUTPUTS section of a deck becomes a table in MoorDyn's `.out` layout, named after
/// the deck, at the times of `positions.csv`: fairlead and anchor tensions equal those of
/// `end_tensions.csv` (to the table's 8 significant digits), the point's force is the
/// force of its one line, the fairlead node follows the vessel; an interrupted run resumed
/// writes the same table as an uninterrupted one.
#[test]
fn the_outputs_section_writes_a_moordyn_style_table() {
    let dir = temp_dir("deck-out");
    let table = surge_table(&dir, 20);
    let out = dir.join("spar");
    let args = ["--motion", table.to_str().unwrap()];
    let sets = ["output.plots=false", "output.animation=false"];
    let o = run_with(SPAR, &out, &sets, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let (names, units, rows) = read_out(&out.join("spar_oc3_v2.out"));
    assert_eq!(
        names,
        [
            "Time", "FairTen1", "FairTen2", "FairTen3", "AnchTen1", "L1N10T", "L1N20PZ",
            "Point4FX", "Point4FY", "Point4FZ", "Point4T"
        ]
    );
    assert_eq!(
        units,
        ["(s)", "N", "N", "N", "N", "N", "m", "N", "N", "N", "N"]
    );
    // Every 50 steps of 0.002 s (the deck's dtM, no dtOut) from 0 to 1 s.
    let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(times.len(), 11, "{times:?}");
    let mut ends = csv::Reader::from_path(out.join("end_tensions.csv")).unwrap();
    let ends: Vec<Vec<f64>> = ends
        .records()
        .map(|r| r.unwrap().iter().map(|x| x.parse().unwrap()).collect())
        .collect();
    let close = |a: f64, b: f64| (a - b).abs() <= 5e-8 * b.abs().max(1.0);
    for row in &rows {
        let e = ends
            .iter()
            .find(|e| (e[0] - row[0]).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no end_tensions row at t = {}", row[0]));
        // end_tensions.csv: t, FairTen1, AnchTen1, FairTen2, AnchTen2, FairTen3, AnchTen3.
        for (col, ecol) in [(1, 1), (2, 3), (3, 5), (4, 2)] {
            assert!(close(row[col], e[ecol]), "t = {}: {row:?} vs {e:?}", row[0]);
        }
        let f = (row[7].powi(2) + row[8].powi(2) + row[9].powi(2)).sqrt();
        assert!(close(f, row[10]) && close(row[10], row[1]), "{row:?}");
        // The tension grows from the anchor to the fairlead along a hanging line.
        assert!(row[4] < row[5] && row[5] < row[1], "{row:?}");
        // The fairlead node is on the vessel: a surge leaves its depth unchanged.
        assert!((row[6] + 70.0).abs() <= 1e-6, "{row:?}");
    }
    // The surge (+x) moves the fairleads toward anchor 1 (at +x) and away from anchors 2
    // and 3: line 1 slackens, lines 2 and 3 tighten.
    let (a, b) = (&rows[0], &rows[10]);
    assert!(b[1] < a[1] - 1e4 && b[2] > a[2] + 1e4, "{a:?} {b:?}");
    // Stopped after 130 steps and resumed: the same table, byte for byte.
    let split = dir.join("split");
    let mut first_args = args.to_vec();
    first_args.extend(["--stop-after-steps", "130"]);
    let o = run_with(SPAR, &split, &sets, &first_args);
    assert!(!o.status.success());
    let cp = split.join("checkpoint.json");
    let o = phstring(&["run", "--resume", cp.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(split.join("spar_oc3_v2.out")).unwrap(),
        std::fs::read(out.join("spar_oc3_v2.out")).unwrap()
    );
}

/// `output.channels` in a TOML scenario: node `j` of line 1 is the `j`-th node along the
/// first string (here 180 elements, nodes 0 to 180), the table is `channels.out`, and a
/// channel naming what the run lacks is refused at its entry before anything runs long.
#[test]
fn output_channels_of_a_scenario_name_its_strings_and_nodes() {
    let dir = temp_dir("scenario-channels");
    let out = dir.join("mooring");
    let sets = [
        "time.end=0.02",
        "output.plots=false",
        "output.animation=false",
        r#"output.channels=["FairTen1", "AnchTen1", "L1N90T", "L1N180PY", "L1N0PX"]"#,
    ];
    let o = run_with("examples/mooring_line.toml", &out, &sets, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (names, _, rows) = read_out(&out.join("channels.out"));
    assert_eq!(names.len(), 6);
    let first = &rows[0];
    // The fairlead of examples/mooring_line.toml is at (150, −5) m, the anchor at x = 0.
    assert!(
        (first[4] + 5.0).abs() < 1e-6 && first[5].abs() < 1e-6,
        "{first:?}"
    );
    assert!(first[2] < first[3] && first[3] < first[1], "{first:?}");
    for (channel, says) in [
        ("L2N1T", "reads line 2, but there are 1 lines"),
        (
            "L1N181T",
            "reads node 181 of line 1, which has nodes 0 to 180",
        ),
        ("Point1PZ", "reads point 1, which is not in the run"),
        ("L1N3AX", "not written: accelerations"),
        ("L1N3Q", "unknown quantity `Q`"),
    ] {
        let set = format!(r#"output.channels=["FairTen1", "{channel}"]"#);
        let o = run_with(
            "examples/mooring_line.toml",
            &dir.join("bad"),
            &[&set],
            &["--force"],
        );
        let e = stderr(&o);
        assert!(!o.status.success(), "{channel}");
        assert!(
            e.contains("output.channels.1") && e.contains(says),
            "{channel}: {e}"
        );
    }
}

/// `--motion` with three columns per coupled point (MoorDyn's per-point form): each point
/// follows its own columns as absolute positions (point 4 surges 3 m, points 5 and 6 stay
/// where the table puts them, 1 m off their deck positions); a table of another width is
/// refused with both forms' widths.
#[test]
fn a_per_point_motion_table_moves_each_coupled_point() {
    let dir = temp_dir("deck-motion-points");
    let surge = |t: f64| 3.0 * (1.0 - (-t * t).exp());
    let mut table = String::from("t x4 y4 z4 x5 y5 z5 x6 y6 z6\n");
    for i in 0..=20 {
        let t = 0.05 * i as f64;
        table.push_str(&format!(
            "{t} {} 0 -70 -2.6 4.5033 -69 -2.6 -4.5033 -69\n",
            5.2 + surge(t)
        ));
    }
    let path = dir.join("points.txt");
    std::fs::write(&path, table).unwrap();
    let out = dir.join("spar");
    let sets = ["output.plots=false", "output.animation=false"];
    let o = run_with(SPAR, &out, &sets, &["--motion", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Points 4, 5, 6 are nodes 3, 4, 5 (the deck's points in order, fixed ones first).
    let mut r = csv::Reader::from_path(out.join("positions.csv")).unwrap();
    let mut checked = 0;
    for rec in r.records() {
        let rec = rec.unwrap();
        let t: f64 = rec[0].parse().unwrap();
        let x: [f64; 3] = std::array::from_fn(|k| rec[k + 2].parse().unwrap());
        let expected = match &rec[1] {
            "3" => [5.2 + surge(t), 0.0, -70.0],
            "4" => [-2.6, 4.5033, -69.0],
            "5" => [-2.6, -4.5033, -69.0],
            _ => continue,
        };
        for k in 0..3 {
            assert!(
                (x[k] - expected[k]).abs() <= 1e-9,
                "t = {t}: {x:?} vs {expected:?}"
            );
        }
        checked += 1;
    }
    assert!(checked >= 33, "{checked} rows checked");
    let s = summary(&out);
    assert!(
        s["deck"]["converted"]
            .to_string()
            .contains("its three columns")
    );
    // `check` names each point's own columns (point 5: the file's columns 5, 6, 7).
    let o = phstring(&["check", SPAR, "--motion", path.to_str().unwrap()]);
    let listed = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        listed.contains("\"point5\" x = table ")
            && listed.contains("points.txt column 5 (x)")
            && listed.contains("points.txt column 10 (z)"),
        "{listed}"
    );
    // Five columns fit neither form for three coupled points.
    std::fs::write(&path, "t x y z w\n0 1 2 3 4\n1 1 2 3 4\n").unwrap();
    let o = phstring(&["check", SPAR, "--motion", path.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        stderr(&o)
            .contains("has 5 columns; the deck's 3 coupled point(s) take a platform table of 7")
            && stderr(&o).contains("per-point table of 10"),
        "{}",
        stderr(&o)
    );
}

/// The spar deck with its three fairleads on a free body (BODIES): a 200 t buoy of 400 m³
/// 60 m down, held down by the lines. `check` prints what the body and its points became;
/// `statics` finds the rest state, where the lines carry the buoy's net buoyancy: the
/// forces the body exerts on its three points (the last nodes of `equilibrium.csv`) add up
/// to `ρ_w g V − m g = 2 059 396.5 N` upwards to 1e-6 of it, and to zero across.
#[test]
fn a_deck_with_a_free_body_maps_and_finds_its_equilibrium() {
    let dir = temp_dir("deck-body");
    let deck = std::fs::read_to_string(workspace_root().join(SPAR))
        .unwrap()
        .replace("4   Vessel      5.2       0.0       -70.0", "4   Body1       5.2       0.0       -10.0")
        .replace("5   Vessel     -2.6       4.5033    -70.0", "5   Body1      -2.6       4.5033    -10.0")
        .replace("6   Vessel     -2.6      -4.5033    -70.0", "6   Body1      -2.6      -4.5033    -10.0")
        .replace(
            "---------------------- LINES",
            "---------------------- BODIES ----------------------\n\
             ID  Attachment  X0   Y0   Z0    r0  p0  y0  Mass   CG   I             Volume  CdA   Ca\n\
             (#) (word)      (m)  (m)  (m)  (deg)(deg)(deg)(kg) (m)  (kg-m^2)      (m^3)   (m^2) (-)\n\
             1   Free        0    0    -60   0   0   0   2.0e5  0    1e6|1e6|5e5   400     20|0  0\n\
             ---------------------- LINES",
        );
    let path = dir.join("buoy.dat");
    std::fs::write(&path, deck).unwrap();
    let p = path.to_str().unwrap();
    let o = phstring(&["check", p]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for expected in [
        "[bodies.body1]: a free rigid body of 200000 kg",
        "body point body1.p4 of [bodies.body1]",
        "body:      body1: 200000 kg",
        "in water:  body body1: volume 400 m³",
    ] {
        assert!(text.contains(expected), "missing {expected:?} in\n{text}");
    }
    let st = dir.join("statics");
    let o = phstring(&["statics", p, "--out", st.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = equilibrium(&st);
    assert_eq!(rows.len(), 3 + 3 * 19 + 3);
    let pull: [f64; 3] =
        std::array::from_fn(|k| rows[rows.len() - 3..].iter().map(|r| r[3 + k]).sum());
    let net = RHO_W * G * 400.0 - 2.0e5 * G;
    println!("the body's pull on its points {pull:?} N, net buoyancy {net} N");
    assert!((pull[2] - net).abs() <= 1e-6 * net, "{pull:?} vs {net}");
    assert!(
        pull[0].abs() <= 1e-6 * net && pull[1].abs() <= 1e-6 * net,
        "{pull:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `--motion` table read as the user meant or flagged: with two coupled points (the spar
/// deck without its third line) a 7-column table is a per-point table unless its header
/// names the roll, as `roll` or OpenFAST's `PtfmRoll`: so a table with OpenFAST's platform
/// column names moves the fairleads rigidly from their deck positions (the first starts at
/// (5.2, 0, −70)), while the same rows without a header are absolute positions, which put
/// both fairleads at the origin: the run warns (summary.json too), naming the point, its
/// offset and the platform form. A 4-column table whose header names surge, sway and heave
/// is refused, naming them. A water depth given by `--set` that puts the seabed above an
/// anchor is refused as in the deck, naming `water.depth` and the node.
#[test]
fn motion_tables_read_as_meant_or_flagged() {
    let dir = temp_dir("deck-motion-meant");
    let text = std::fs::read_to_string(workspace_root().join(SPAR)).unwrap();
    // Without point 3 (an anchor), point 6 (a fairlead) and line 3; points 4 and 5 become
    // 3 and 4 (MoorDyn numbers them in sequence).
    let two: String = text
        .lines()
        .filter(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            !(w.first() == Some(&"3") || w.first() == Some(&"6") || l.starts_with("FairTen3"))
        })
        .map(|l| {
            let l = l
                .replace("4   Vessel", "3   Vessel")
                .replace("5   Vessel", "4   Vessel")
                .replace("1        4 ", "1        3 ")
                .replace("2        5 ", "2        4 ");
            format!("{l}\n")
        })
        .collect();
    let deck = dir.join("two.dat");
    std::fs::write(&deck, two).unwrap();
    let deck = deck.to_str().unwrap();
    let rows = "0,0,0,0,0,0,0\n1,0.5,0,0,0,0,0\n2,1.0,0,0,0,0,0\n";
    let table = |name: &str, header: &str| {
        let p = dir.join(name);
        std::fs::write(&p, format!("{header}{rows}")).unwrap();
        p.to_str().unwrap().to_string()
    };
    let openfast = table(
        "openfast.csv",
        "Time,PtfmSurge,PtfmSway,PtfmHeave,PtfmRoll,PtfmPitch,PtfmYaw\n",
    );
    let bare = table("bare.csv", "");
    let sets = [
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
    ];
    let start_of_point4 = |out: &Path| {
        let mut r = csv::Reader::from_path(out.join("positions.csv")).unwrap();
        let rec = r
            .records()
            .map(|r| r.unwrap())
            .find(|r| &r[1] == "2")
            .unwrap();
        [2, 3, 4].map(|k| rec[k].parse::<f64>().unwrap())
    };
    let out = dir.join("openfast");
    let o = run_with(deck, &out, &sets, &["--motion", &openfast]);
    assert!(o.status.success(), "{}", stderr(&o));
    let p = start_of_point4(&out);
    assert!(
        (p[0] - 5.2).abs() < 1e-9 && p[1].abs() < 1e-9 && (p[2] + 70.0).abs() < 1e-9,
        "{p:?}"
    );
    assert_eq!(summary(&out)["warnings"].as_array().unwrap().len(), 0);
    let out = dir.join("bare");
    let o = run_with(deck, &out, &sets, &["--motion", &bare]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(start_of_point4(&out).iter().all(|x| x.abs() < 1e-9));
    let warnings = summary(&out)["warnings"].to_string();
    assert!(
        warnings.contains(
            "puts point 3 at (0, 0, 0) m at t = 0, 70.2 m from its deck position (5.2, 0, -70)"
        ) && warnings.contains("point 4")
            && stderr(&o).contains("warning: --motion"),
        "{warnings}\n{}",
        stderr(&o)
    );
    let surge = dir.join("surge.csv");
    std::fs::write(&surge, "t,surge,sway,heave\n0,0,0,0\n1,1,0,0\n").unwrap();
    let o = phstring(&["check", CHAIN_DEEP, "--motion", surge.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        stderr(&o)
            .contains("has 4 columns and its header names platform motions (surge, sway, heave)"),
        "{}",
        stderr(&o)
    );
    let o = phstring(&["check", CHAIN_DEEP, "--set", "water.depth=100"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--set water.depth=100: `water.depth` = 100 m puts the seabed at z = -100 m, above the support at mesh node 0 (z = -320 m)"),
        "{}",
        stderr(&o)
    );
}

/// The deep-water chain deck.
const CHAIN_DEEP: &str = "examples/moordyn/chain_deep_320m_v2.dat";

/// A line longer than its ends' horizontal plus vertical distance (the shallow chain made
/// 400 m long for 338 m + 42 m) has extra length lying slack on the frictionless seabed,
/// where its rest state is not unique: `statics` warns before it fails, naming the deck line
/// and the way to run it, and the run from the layout that the warning names completes with
/// its energy balance.
#[test]
fn a_line_longer_than_its_path_warns_and_runs_from_its_layout() {
    let dir = temp_dir("deck-slack-extra");
    let text = std::fs::read_to_string(workspace_root().join(SHALLOW)).unwrap();
    assert!(text.contains("350.0     35 "));
    let deck = dir.join("long.dat");
    std::fs::write(&deck, text.replace("350.0     35 ", "400.0     35 ")).unwrap();
    let deck = deck.to_str().unwrap();
    let line = text
        .lines()
        .position(|l| l.contains("350.0     35 "))
        .unwrap()
        + 1;
    let out = dir.join("statics");
    let o = phstring(&["statics", deck, "--out", out.to_str().unwrap()]);
    assert!(
        !o.status.success(),
        "the statics of the slack line were found"
    );
    assert!(
        stderr(&o).contains(&format!(
            "warning: {deck}:{line}: line 1 (400 m) is longer than its ends' horizontal plus vertical distance (380.0 m)"
        )) && stderr(&o).contains("--set initial.equilibrium=false"),
        "{}",
        stderr(&o)
    );
    // The same line from an anchor 20 m above the seabed hangs in the water: no warning.
    let hanging = dir.join("hanging.dat");
    let raised = text
        .replace("350.0     35 ", "400.0     35 ")
        .replace("358.0   0.0   -50.0", "358.0   0.0   -30.0");
    assert_ne!(raised, text.replace("350.0     35 ", "400.0     35 "));
    std::fs::write(&hanging, raised).unwrap();
    let o = phstring(&["check", hanging.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let out = dir.join("run");
    let sets = [
        "initial.equilibrium=false",
        "time.end=1",
        "output.plots=false",
        "output.animation=false",
        "output.vtk=false",
    ];
    let o = run_with(deck, &out, &sets, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    let balance = s["max_balance_error"].as_f64().unwrap();
    let scale = s["hamiltonian_initial"].as_f64().unwrap().abs();
    assert!(balance <= 1e-12 * scale, "balance {balance} J of {scale} J");
}

/// The shallow-water chain deck.
const SHALLOW: &str = "examples/moordyn/chain_shallow_50m_v2.dat";

/// A line whose UnstrLen is far below the distance between its ends (the shallow chain made
/// 170 m long for 340.6 m: a typing error) starts stretched by 100 %: `check` warns, naming
/// the deck line and the stretch, where the example's 350 m gives no warning.
#[test]
fn a_line_far_shorter_than_its_ends_apart_warns() {
    let dir = temp_dir("deck-overstretch");
    let text = std::fs::read_to_string(workspace_root().join(SHALLOW)).unwrap();
    let deck = dir.join("short.dat");
    std::fs::write(&deck, text.replace("350.0     35 ", "170.0     35 ")).unwrap();
    let o = phstring(&["check", deck.to_str().unwrap()]);
    let line = text
        .lines()
        .position(|l| l.contains("350.0     35 "))
        .unwrap()
        + 1;
    assert!(
        stderr(&o).contains(&format!(
            "short.dat:{line}: line 1 (170 m) starts stretched by 100.4 % to reach its ends 340.6 m apart"
        )),
        "{}",
        stderr(&o)
    );
    let o = phstring(&["check", SHALLOW]);
    assert!(o.status.success());
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// A motion table that ends before `time.end` while still moving holds its last row from
/// there, so the platform stops at once: `check` warns, naming the key, the table's end and
/// the end time; at the table's own end (a deck's default) it says nothing.
#[test]
fn a_table_that_ends_moving_before_the_run_warns() {
    let table = "examples/moordyn/chain_deep_320m_motion.csv";
    let o = phstring(&[
        "check",
        CHAIN_DEEP,
        "--motion",
        table,
        "--set",
        "time.end=400",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("`platform.0.motion_table`: table ")
            && stderr(&o).contains("table chain_deep_320m_motion.csv ends at t = 300 s with its column 6 still changing")
            && stderr(&o).contains("from there to time.end = 400 s it holds its last row"),
        "{}",
        stderr(&o)
    );
    let o = phstring(&["check", CHAIN_DEEP, "--motion", table]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// The chain deck in 320 m of water, edited: `edit` applied to its text, written to `dir`
/// as `name` in the bytes `encode` makes of it.
fn edited_deep(
    dir: &Path,
    name: &str,
    edit: impl Fn(String) -> String,
    encode: impl Fn(&str) -> Vec<u8>,
) -> String {
    let text = std::fs::read_to_string(workspace_root().join(CHAIN_DEEP)).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, encode(&edit(text))).unwrap();
    path.to_str().unwrap().to_string()
}

/// A deck as written on Windows by hand, checked: Latin-1 bytes (`°` in the title), a `---`
/// in the remark of WtrDpth and the water density given twice. The deck is read (no
/// unknown section), WtrDpth and every option after it count (the seabed at 320 m), and
/// `check` prints how the file was read and which density is used.
#[test]
fn check_reads_a_latin1_deck_with_dashed_remarks_and_a_repeated_option() {
    let dir = temp_dir("deck-latin1");
    let deck = edited_deep(
        &dir,
        "deep.dat",
        |t| {
            t.replace(
                "(the OC3-Hywind depth)",
                "(the OC3-Hywind depth, 10 \u{b0}C)",
            )
            .replace(
                "320       WtrDpth    water depth (m)",
                "320       WtrDpth    --- water depth (m)",
            )
            .replace(
                "1025      rho",
                "2000      WtrDnsty   first try\n1025      rho",
            )
        },
        |t| t.chars().map(|c| u8::try_from(c as u32).unwrap()).collect(),
    );
    let o = phstring(&["check", &deck]);
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(o.status.success(), "{err}");
    for expected in [
        "deck.dat:2: the file is not UTF-8 (byte 0xB0, offset 138, is the first that is not); read as Latin-1",
        "deck.dat:23: option WtrDnsty is given twice, on line 22 (`2000 WtrDnsty`) and line 23 (`1025 rho`): the later, 1025, is used",
        "option WtrDpth = 320",
        "seabed:    flat at −320 m, stiffness 3000000 Pa/m",
    ] {
        let expected = expected.replace("deck.dat", &deck);
        assert!(out.contains(&expected), "missing {expected:?} in\n{out}");
    }
    assert!(
        !out.contains("no WtrDpth") && !err.contains("section"),
        "{out}\n{err}"
    );
}

/// OUTPUTS written OpenFAST-style (commas, quotes) with names longer than the `.out`
/// column: every channel written, the header and each row with as many whitespace-separated
/// fields; a channel that is not written (an acceleration) is a warning that `run` prints
/// and summary.json lists.
#[test]
fn openfast_style_outputs_with_long_names_run_and_the_rest_warn() {
    let dir = temp_dir("deck-outputs");
    let deck = edited_deep(
        &dir,
        "deep.dat",
        |t| {
            t.replace(
                "FairTen1\nAnchTen1\n",
                "FairTen000000000000000001, \"Point0000000000000002PX\",AnchTen1\nL1N10AX\n",
            )
        },
        |t| t.as_bytes().to_vec(),
    );
    let out = dir.join("run");
    let sets = [
        "time.end=0.005",
        "output.plots=false",
        "output.animation=false",
    ];
    let o = phstring(&[
        "run",
        &deck,
        "--out",
        out.to_str().unwrap(),
        "--set",
        sets[0],
        "--set",
        sets[1],
        "--set",
        sets[2],
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let warning = format!("{deck}:32: channel L1N10AX is not written: accelerations");
    assert!(err.contains(&format!("warning: {warning}")), "{err}");
    let s = summary(&out);
    let listed = s["warnings"].as_array().unwrap();
    assert!(
        listed
            .iter()
            .any(|w| w.as_str().unwrap().starts_with(&warning)),
        "{listed:?}"
    );
    let text = std::fs::read_to_string(out.join("deep.out")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let fields = |l: &str| l.split_whitespace().count();
    assert_eq!(
        lines[0].split_whitespace().collect::<Vec<_>>(),
        [
            "Time",
            "FairTen000000000000000001",
            "Point0000000000000002PX",
            "AnchTen1"
        ]
    );
    assert_eq!(fields(lines[1]), 4, "{}", lines[1]);
    assert!(lines.len() > 3, "{text}");
    for row in &lines[2..] {
        assert_eq!(fields(row), 4, "{row}");
    }
    // The fairlead's x, the second channel, is the vessel point's 35 m.
    let x: f64 = lines[2].split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((x - 35.0).abs() < 1e-9, "{x}");
}
