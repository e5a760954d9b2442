//! `[initial]`: equilibrium flag, displacement and velocity fields of the reference arc
//! length `s`, per-node lists, and their checks. A 100 m steel rope (EA = 1e8 N,
//! ρA = 1 kg/m) in 50 elements of 2 m serves as the single string.

use std::path::Path;

use phstring::{State, Vector};
use phstring_io::scenario::{self, ScenarioFile, Validated};

/// The rope from (0, 0) to (100, 0), both ends fixed unless `fix` is empty, with `initial`
/// appended (a TOML table or nothing).
fn rope(fix: &str, initial: &str) -> String {
    format!(
        r#"title = "steel rope"
dimension = 2

[geometry]
start = [0.0, 0.0]
end = [100.0, 0.0]

[mesh]
elements = 50

[material]
law = "linear_elastic"
ea = 1.0e8
rho_a = 1.0

[body_force]
gravity = [0.0, -9.81]
{fix}
[time]
h = 0.001
end = 0.01
{initial}"#
    )
}

const BOTH_ENDS: &str = "
[[boundary]]
node = 0
fixed = true

[[boundary]]
node = -1
fixed = true
";

fn parse(text: &str, sets: &[&str]) -> ScenarioFile {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    scenario::parse(text, Path::new("t.toml"), &sets).unwrap_or_else(|e| panic!("{e}"))
}

fn valid<const D: usize>(text: &str) -> Validated<D> {
    let file = parse(text, &[]);
    file.check().unwrap_or_else(|e| panic!("{e}"));
    file.validate::<D>().unwrap_or_else(|e| panic!("{e}"))
}

/// The validation error of `text` (it must fail).
fn error(text: &str, sets: &[&str]) -> String {
    match parse(text, sets).validate::<2>() {
        Ok(_) => panic!("validated:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// `line:column` of the first `needle` in `text`.
fn pos(text: &str, needle: &str) -> String {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in {text}"));
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap().chars().count() + 1;
    format!("{line}:{column}")
}

/// Reference arc length of each node of a chain, summed plainly.
fn arc(v: &Validated<2>) -> (Vec<f64>, f64) {
    let mut s = vec![0.0];
    for &l in v.problem.mesh.lengths() {
        s.push(s.last().unwrap() + l);
    }
    let total = *s.last().unwrap();
    (s, total)
}

/// Without `[initial]` (or with one that changes nothing) the initial state is the straight
/// rope at rest, exactly as before.
#[test]
fn no_initial_table_is_the_state_of_before() {
    let plain = valid::<2>(&rope(BOTH_ENDS, ""));
    assert!(!plain.initial.equilibrium);
    assert!(!plain.initial.changes_base());
    let straight = State::at_rest(
        &plain.problem.mesh,
        (0..=50)
            .map(|i| Vector::<2>::new(0.0, 0.0) + Vector::<2>::new(100.0, 0.0) * (i as f64 / 50.0))
            .collect(),
    );
    assert_eq!(plain.problem.initial, straight);
    let empty = valid::<2>(&rope(BOTH_ENDS, "[initial]\nequilibrium = false\n"));
    assert_eq!(empty.problem.initial, plain.problem.initial);
    // The scenario as run (summary.json) has no `initial` without the table.
    let json = serde_json::to_value(&parse(&rope(BOTH_ENDS, ""), &[]).scenario).unwrap();
    assert!(json.get("initial").is_none());
    let json = serde_json::to_value(
        &parse(
            &rope(BOTH_ENDS, "[initial]\ndisplacement = [\"0\", \"0\"]\n"),
            &[],
        )
        .scenario,
    )
    .unwrap();
    assert_eq!(json["initial"]["displacement"][1], "0");
    assert_eq!(json["initial"]["equilibrium"], false);
}

/// Every example still validates, at rest (but for the points of a moving rigid body);
/// only the hanging lines (`mooring_line.toml`,
/// `slack_wire.toml`, `spread_mooring_3d.toml`, `spread_mooring_platform.toml`,
/// `chain_on_slope_2d.toml`, `anchor_handling_2d.toml`) and the bodies held by lines (`cable_robot_3d.toml`,
/// `cable_robot_winches_3d.toml`, `spar_buoy_3d.toml`) ask for the equilibrium start (and
/// no displacement or velocity).
#[test]
fn examples_start_at_rest() {
    fn at_rest<const D: usize>(file: &ScenarioFile) {
        let v = file.validate::<D>().unwrap();
        let mooring = [
            "mooring_line.toml",
            "slack_wire.toml",
            "spread_mooring_3d.toml",
            "spread_mooring_platform.toml",
            "chain_on_slope_2d.toml",
            "cable_robot_3d.toml",
            "cable_robot_winches_3d.toml",
            "spar_buoy_3d.toml",
            "anchor_handling_2d.toml",
        ]
        .iter()
        .any(|name| file.path.ends_with(name));
        assert!(!v.initial.changes_base() && v.initial.equilibrium == mooring);
        // A rigid body's points move with it (`hook_block_3d.toml`'s beam starts turning).
        let body_points: Vec<usize> = v
            .components
            .bodies
            .iter()
            .flat_map(|b| b.points.iter().map(|p| p.node))
            .collect();
        assert!(
            v.problem
                .initial
                .v
                .iter()
                .enumerate()
                .all(|(i, v)| body_points.contains(&i) || v.iter().all(|&x| x == 0.0))
        );
        assert_eq!(v.problem.initial.kinematic_defect(&v.problem.mesh), 0.0);
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut count = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let file = scenario::load(&path, &[]).unwrap();
            file.check().unwrap_or_else(|e| panic!("{e}"));
            match file.dimension().unwrap() {
                1 => at_rest::<1>(&file),
                2 => at_rest::<2>(&file),
                _ => at_rest::<3>(&file),
            }
            count += 1;
        }
    }
    assert!(count >= 5);
}

/// A plucked rope: straight + 0.01 sin(π s/L) in y, strains consistent, the fixed ends
/// exactly where they were (sin(π) ≈ 1e-16 is no displacement).
#[test]
fn plucked_rope_follows_the_expression() {
    let v = valid::<2>(&rope(
        BOTH_ENDS,
        "[initial]\ndisplacement = [\"0\", \"0.01*sin(pi*s/L)\"]\n",
    ));
    let (s, total) = arc(&v);
    assert!((total - 100.0).abs() < 1e-12);
    let r = &v.problem.initial.r;
    for (i, ri) in r.iter().enumerate() {
        let x = 100.0 * (i as f64 / 50.0);
        let y = if i == 0 || i == 50 {
            0.0
        } else {
            0.01 * (std::f64::consts::PI * s[i] / total).sin()
        };
        assert!((ri[0] - x).abs() <= 1e-15 * x.abs(), "node {i}: {ri}");
        assert!(
            (ri[1] - y).abs() <= 1e-15 * y.abs(),
            "node {i}: {} vs {y}",
            ri[1]
        );
    }
    assert_eq!(r[0], Vector::<2>::zeros());
    assert_eq!(r[50], Vector::<2>::new(100.0, 0.0));
    assert!((r[25][1] - 0.01).abs() < 1e-15);
    assert!(v.problem.initial.kinematic_defect(&v.problem.mesh) <= 1e-15);
    assert!(
        v.problem
            .initial
            .v
            .iter()
            .all(|v| v == &Vector::<2>::zeros())
    );
    // The stretch of the plucked shape: C > 1 in every element.
    assert!(v.problem.initial.c.iter().all(|&c| c > 1.0));
}

/// A free string spinning at ω = 2 rad/s about the origin: v = ω × r at every node,
/// exactly; in 3D too.
#[test]
fn rigid_rotation_of_a_free_string() {
    let text = rope("", "[initial]\nvelocity = [\"-2*y\", \"2*x\"]\n")
        .replace("start = [0.0, 0.0]", "start = [-30.0, -40.0]")
        .replace("end = [100.0, 0.0]", "end = [30.0, 40.0]");
    let v = valid::<2>(&text);
    let st = &v.problem.initial;
    for (r, u) in st.r.iter().zip(&st.v) {
        assert_eq!(*u, Vector::<2>::new(-2.0 * r[1], 2.0 * r[0]));
    }
    assert_eq!(st.v[0], Vector::<2>::new(80.0, -60.0));
    // The positions are those of the straight string: no displacement.
    assert_eq!(st.r[25], Vector::<2>::zeros());
    let text3 = text
        .replace("dimension = 2", "dimension = 3")
        .replace("[-30.0, -40.0]", "[-30.0, -40.0, 10.0]")
        .replace("[30.0, 40.0]", "[30.0, 40.0, -10.0]")
        .replace("[0.0, -9.81]", "[0.0, 0.0, -9.81]")
        // ω = (1, 0, 2): ω × r = (-2y, 2x - z, y).
        .replace("[\"-2*y\", \"2*x\"]", "[\"-2*y\", \"2*x - z\", \"y\"]");
    let v = valid::<3>(&text3);
    let st = &v.problem.initial;
    let omega = Vector::<3>::new(1.0, 0.0, 2.0);
    for (r, u) in st.r.iter().zip(&st.v) {
        assert_eq!(*u, omega.cross(r));
    }
}

/// `positions` and `velocities` are taken as given, one entry per node.
#[test]
fn per_node_lists_are_taken_exactly() {
    let base = rope(BOTH_ENDS, "").replace("elements = 50", "elements = 4");
    let positions = [
        [0.0, 0.0],
        [24.0, -3.0],
        [50.5, -4.25],
        [75.0, -2.0],
        [100.0, 0.0],
    ];
    let velocities = [
        [0.0, 0.0],
        [0.1, 0.2],
        [-0.3, 0.4],
        [1e-3, -5.0],
        [0.0, 0.0],
    ];
    let list = |xs: &[[f64; 2]]| {
        let e: Vec<String> = xs
            .iter()
            .map(|p| format!("[{:?}, {:?}]", p[0], p[1]))
            .collect();
        format!("[{}]", e.join(", "))
    };
    let text = format!(
        "{base}[initial]\npositions = {}\nvelocities = {}\n",
        list(&positions),
        list(&velocities)
    );
    let v = valid::<2>(&text);
    let st = &v.problem.initial;
    for i in 0..5 {
        assert_eq!(st.r[i], Vector::<2>::from(positions[i]));
        assert_eq!(st.v[i], Vector::<2>::from(velocities[i]));
    }
    assert_eq!(st.kinematic_defect(&v.problem.mesh), 0.0);
    assert_eq!(
        st.c[0],
        (Vector::<2>::new(24.0, -3.0).norm() / 25.0).powi(2)
    );

    // Wrong count: the error names it, the node count and the numbering.
    let short = format!("{base}[initial]\npositions = {}\n", list(&positions[..4]));
    let m = error(&short, &[]);
    assert!(
        m.starts_with(&format!("t.toml:{}:", pos(&short, "[[0.0, 0.0]"))),
        "{m}"
    );
    assert!(
        m.contains("`initial.positions` has 4 entries, but the mesh has 5 nodes"),
        "{m}"
    );
    assert!(m.contains("nodes 0..=4 in mesh order"), "{m}");
    let bad = format!(
        "{base}[initial]\nvelocities = [[0.0, 0.0], [1.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]\n"
    );
    let m = error(&bad, &[]);
    assert!(
        m.starts_with(&format!(
            "t.toml:{}: `initial.velocities.1` (node 1) must have 2 finite components",
            pos(&bad, "[1.0]")
        )),
        "{m}"
    );

    // Conflicting keys.
    let both = format!(
        "{base}[initial]\npositions = {}\ndisplacement = [\"0\", \"0\"]\n",
        list(&positions)
    );
    let m = error(&both, &[]);
    assert!(
        m.contains("`initial.displacement` cannot be combined with `initial.positions`"),
        "{m}"
    );
    assert!(
        m.starts_with(&format!("t.toml:{}:", pos(&both, "[\"0\", \"0\"]"))),
        "{m}"
    );
    let eq = format!(
        "{base}[initial]\nequilibrium = true\npositions = {}\n",
        list(&positions)
    );
    let m = error(&eq, &[]);
    assert!(m.contains("`initial.positions` gives the initial shape, so it cannot be combined with `initial.equilibrium = true`"), "{m}");
    let vv = format!(
        "{base}[initial]\nvelocities = {}\nvelocity = [\"0\", \"0\"]\n",
        list(&velocities)
    );
    let m = error(&vv, &[]);
    assert!(
        m.contains("`initial.velocity` cannot be combined with `initial.velocities`"),
        "{m}"
    );

    // A listed position or velocity at a fixed node.
    let mut moved = positions;
    moved[4][1] = 0.5;
    let m = error(
        &format!("{base}[initial]\npositions = {}\n", list(&moved)),
        &[],
    );
    assert!(m.contains("`initial.positions.4` = [100, 0.5] puts node 4 at 0.5 m in component y, but the node is fixed there and starts at 0 m"), "{m}");
    let mut spinning = velocities;
    spinning[0][0] = 2.0;
    let m = error(
        &format!("{base}[initial]\nvelocities = {}\n", list(&spinning)),
        &[],
    );
    assert!(m.contains("`initial.velocities.0` = [2, 0] gives node 0 the velocity 2 m/s in component x, but the node is fixed there"), "{m}");
}

/// Expressions that fail or give ∞ at some node name the key, the node and its `s`, at the
/// position of the expression.
#[test]
fn expression_errors_name_key_node_and_s() {
    let text = rope(BOTH_ENDS, "[initial]\ndisplacement = [\"0\", \"0.01*q\"]\n");
    let m = error(&text, &[]);
    assert!(m.starts_with(&format!("t.toml:{}: `initial.displacement.1` \"0.01*q\" at node 0 (s = 0 m, L = 100 m): unknown variable", pos(&text, "\"0.01*q\""))), "{m}");
    // Division by zero where s = 0.
    let text = rope(BOTH_ENDS, "[initial]\nvelocity = [\"1/s\", \"0\"]\n");
    let m = error(&text, &[]);
    assert!(
        m.contains("`initial.velocity.0` \"1/s\" at node 0 (s = 0 m, L = 100 m): division by zero"),
        "{m}"
    );
    // Overflow further along: exp(s*10) is finite up to s ≈ 70.9 m.
    let text = rope(BOTH_ENDS, "[initial]\nvelocity = [\"0\", \"exp(s*10)\"]\n");
    let m = error(&text, &[]);
    assert!(
        m.contains("`initial.velocity.1` \"exp(s*10)\" at node 36 (s = 72 m, L = 100 m)"),
        "{m}"
    );
    // A variable of a higher dimension, and a wrong count of expressions.
    let m = error(
        &rope(BOTH_ENDS, "[initial]\nvelocity = [\"z\", \"0\"]\n"),
        &[],
    );
    assert!(m.contains("unknown variable"), "{m}");
    let m = error(&rope(BOTH_ENDS, "[initial]\nvelocity = [\"0\"]\n"), &[]);
    assert!(
        m.contains("`initial.velocity` must have 2 expressions (dimension = 2)"),
        "{m}"
    );
    // A displacement that folds an element onto itself: C = 0 is outside linear_elastic.
    let text = rope("", "[initial]\ndisplacement = [\"-s + 50\", \"0\"]\n");
    let m = error(&text, &[]);
    assert!(m.contains("`initial.displacement` gives element 0 (nodes 0 and 1) the initial strain C = 0, outside the domain of linear_elastic"), "{m}");
    // From --set, the option is named.
    let m = error(
        &rope(BOTH_ENDS, ""),
        &["initial.displacement=[\"0\", \"1/(s-s)\"]"],
    );
    assert!(m.starts_with("--set initial.displacement=[\"0\", \"1/(s-s)\"]: `initial.displacement.1` \"1/(s-s)\" at node 0"), "{m}");
}

/// Supports cannot be displaced or set moving.
#[test]
fn fixed_nodes_keep_their_place_and_rest() {
    let text = rope(
        BOTH_ENDS,
        "[initial]\ndisplacement = [\"0\", \"0.01*s/L\"]\n",
    );
    let m = error(&text, &[]);
    assert!(m.starts_with(&format!("t.toml:{}: `initial.displacement.1` \"0.01*s/L\" is 0.01 m at node 50 (s = 100 m): the node is fixed in component y, and a support cannot be displaced", pos(&text, "\"0.01*s/L\""))), "{m}");
    // Fixed in y only: a displacement along x is allowed at the first node.
    let roller = BOTH_ENDS.replacen("fixed = true", "fixed = [\"y\"]", 1);
    let v = valid::<2>(&rope(
        &roller,
        "[initial]\ndisplacement = [\"0.5 - 0.005*s\", \"0\"]\n",
    ));
    assert_eq!(v.problem.initial.r[0], Vector::<2>::new(0.5, 0.0));
    assert_eq!(v.problem.initial.r[50], Vector::<2>::new(100.0, 0.0));
    let m = error(
        &rope(BOTH_ENDS, "[initial]\nvelocity = [\"1\", \"0\"]\n"),
        &[],
    );
    assert!(m.contains("`initial.velocity.0` \"1\" is 1 m/s at node 0 (s = 0 m): the node is fixed in component x, so its initial velocity must be 0 there"), "{m}");
    // A moved component is not displaced either; its velocity is free.
    let crane = rope(
        "\n[[boundary]]\nnode = 0\nfixed = [\"y\"]\nposition = [\"0.1*t\", \"\"]\n",
        "[initial]\ndisplacement = [\"0.01*(1 - s/L)\", \"0\"]\n",
    );
    let m = error(&crane, &[]);
    assert!(m.contains("`initial.displacement.0` \"0.01*(1 - s/L)\" is 0.01 m at node 0 (s = 0 m): its component x follows a prescribed `position`"), "{m}");
    let crane = crane.replace(
        "displacement = [\"0.01*(1 - s/L)\", \"0\"]",
        "velocity = [\"0.1\", \"0\"]",
    );
    let v = valid::<2>(&crane);
    assert_eq!(v.problem.initial.v[0], Vector::<2>::new(0.1, 0.0));
}

/// `equilibrium` is read (also from --set); the problem then starts from the straight shape
/// at rest, and `initial_state` applies the fields to any base shape, with `x`, `y` of that
/// base.
#[test]
fn equilibrium_keeps_the_base_and_applies_later() {
    let text = rope(
        BOTH_ENDS,
        "[initial]\ndisplacement = [\"0\", \"0.01*sin(pi*s/L)\"]\nvelocity = [\"0\", \"y\"]\n",
    );
    let plain = valid::<2>(&text);
    assert!(!plain.initial.equilibrium);
    let file = parse(&text, &["initial.equilibrium=true"]);
    file.check().unwrap();
    let v = file.validate::<2>().unwrap();
    assert!(v.initial.equilibrium && v.initial.changes_base());
    let straight = valid::<2>(&rope(BOTH_ENDS, "")).problem.initial;
    assert_eq!(v.problem.initial, straight);
    // A sagged base (a stand-in for the equilibrium): the displacement is added to it, the
    // velocity uses its y.
    let base: Vec<Vector<2>> = straight
        .r
        .iter()
        .map(|r| Vector::<2>::new(r[0], -1e-3 * r[0] * (100.0 - r[0])))
        .collect();
    let st = v.initial_state(&base).unwrap();
    let (s, total) = arc(&v);
    for i in 1..50 {
        let y = base[i][1] + 0.01 * (std::f64::consts::PI * s[i] / total).sin();
        assert!((st.r[i][1] - y).abs() <= 1e-15 * y.abs(), "node {i}");
        assert_eq!(st.v[i], Vector::<2>::new(0.0, base[i][1]));
    }
    assert_eq!(st.r[0], base[0]);
    assert!(st.kinematic_defect(&v.problem.mesh) <= 1e-15);
    // Without equilibrium, the displaced state is the problem's.
    assert_eq!(
        plain.initial_state(&straight.r).unwrap(),
        plain.problem.initial
    );
    // A base of the wrong size is refused.
    let m = v.initial_state(&base[1..]).unwrap_err().to_string();
    assert!(
        m.contains("`initial` cannot be applied to a base shape of 50 nodes: the mesh has 51"),
        "{m}"
    );
    // `--set` creates the table.
    let file = parse(&rope(BOTH_ENDS, ""), &["initial.equilibrium=true"]);
    assert!(
        file.text().contains("[initial]\nequilibrium = true"),
        "{}",
        file.text()
    );
    assert!(file.validate::<2>().unwrap().initial.equilibrium);
    let m = scenario::parse(
        &rope(BOTH_ENDS, ""),
        Path::new("t.toml"),
        &["initial.equilibrium=1".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        m.contains("invalid type: integer `1`, expected a boolean"),
        "{m}"
    );
}

/// In a network, `s` runs along each string from its first path node; a node shared by
/// two strings takes its value from the first.
#[test]
fn network_arc_length_runs_along_each_string() {
    let text = r#"dimension = 2

[[node]]
name = "a"
position = [0.0, 0.0]

[[node]]
name = "b"
position = [10.0, 0.0]

[[node]]
name = "c"
position = [10.0, 10.0]

[materials.steel]
law = "linear_elastic"
ea = 1.0e8
rho_a = 1.0

[[string]]
name = "low"
path = ["a", "b"]
elements = 5
material = "steel"

[[string]]
name = "up"
path = ["b", "c"]
elements = 5
material = "steel"
prestretch = 1.25

[[boundary]]
node = "a"
fixed = true

[time]
h = 0.001
end = 0.01

[initial]
displacement = ["0.001*s", "0.0002*s*L"]
"#;
    let v = valid::<2>(text);
    let r = &v.problem.initial.r;
    // Nodes: a = 0, b = 1, c = 2; low's interior 3..=6, up's 7..=10.
    assert_eq!(r.len(), 11);
    // low: s = 2 m at its node 1 (mesh node 3), L = 10 m; a is fixed at s = 0.
    assert_eq!(r[0], Vector::<2>::zeros());
    let close = |got: Vector<2>, want: [f64; 2]| {
        assert!(
            (got - Vector::<2>::from(want)).norm() <= 2e-15 * got.norm(),
            "{got} vs {want:?}"
        );
    };
    close(r[3], [2.002, 0.004]);
    // b (low's end, up's start) takes low's s = 10 m, L = 10 m.
    close(r[1], [10.01, 0.02]);
    // up: reference lengths 2 m / 1.25 = 1.6 m, L = 8 m; its node 2 (mesh node 8) at
    // s = 3.2 m, its end c at s = 8 m.
    close(r[8], [10.0032, 4.00512]);
    close(r[2], [10.008, 10.0128]);
    let st = &v.problem.initial;
    assert!(st.kinematic_defect(&v.problem.mesh) <= 1e-15);
    // Errors name the string and the node along it.
    let bad = text.replace("\"0.0002*s*L\"", "\"1/(s - 1.6)\"");
    let m = match parse(&bad, &[]).validate::<2>() {
        Ok(_) => panic!("validated"),
        Err(e) => e.to_string(),
    };
    assert!(m.contains("\"1/(s - 1.6)\" at node 7 (s = 1.6 m, L = 8 m along string \"up\", its node 1): division by zero"), "{m}");
    // The node count of a network names its numbering.
    let m = match parse(
        &text.replace(
            "displacement = [\"0.001*s\", \"0.0002*s*L\"]",
            "positions = [[0.0, 0.0]]",
        ),
        &[],
    )
    .validate::<2>()
    {
        Ok(_) => panic!("validated"),
        Err(e) => e.to_string(),
    };
    assert!(
        m.contains("has 1 entries, but the mesh has 11 nodes")
            && m.contains("the [[node]]s in file order"),
        "{m}"
    );
}

/// The example of docs/scenario.md's `[initial]` section is valid on the rope.
#[test]
fn documented_example_is_valid() {
    let doc = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scenario.md"),
    )
    .unwrap();
    let at = doc.find("## Initial state: `[initial]`").unwrap();
    let start = doc[at..].find("```toml\n").unwrap() + at + "```toml\n".len();
    let end = doc[start..].find("```").unwrap() + start;
    let v = valid::<2>(&rope(BOTH_ENDS, &doc[start..end]));
    let st = &v.problem.initial;
    assert!((st.r[25][1] - 0.01).abs() < 1e-15);
    assert!((st.v[12][1] - 0.5).abs() < 1e-3);
    assert_eq!(st.v[50], Vector::<2>::zeros());
}
