//! Property tests of the scenario validator: for any values of the keys, validation
//! returns a problem or an error that names a key with its position — never a panic; and
//! every physically valid choice is accepted.

use std::path::Path;

use phstring_io::scenario;
use proptest::prelude::*;

#[allow(clippy::too_many_arguments)] // one argument per scenario key under test
fn scenario_text(
    dim: i64,
    elements: i64,
    ea: f64,
    rho_a: f64,
    h: f64,
    end: f64,
    node: i64,
    expr: &str,
) -> String {
    let zeros = |d: i64| vec!["0.0"; d.clamp(0, 5) as usize].join(", ");
    let ones = |d: i64| {
        let mut v = vec!["0.0"; d.clamp(0, 5) as usize];
        if let Some(x) = v.first_mut() {
            *x = "1.0";
        }
        v.join(", ")
    };
    let force = vec![format!("\"{}\"", expr.replace('"', "")); dim.clamp(0, 5) as usize].join(", ");
    format!(
        "dimension = {dim}\n[geometry]\nstart = [{}]\nend = [{}]\n[mesh]\nelements = {elements}\n\
         [material]\nea = {ea:?}\nrho_a = {rho_a:?}\n[[boundary]]\nnode = 0\nfixed = true\n\
         [[boundary]]\nnode = {node}\nforce = [{force}]\n[time]\nh = {h:?}\nend = {end:?}\n",
        zeros(dim),
        ones(dim)
    )
}

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1e3..1e3f64,
        Just(0.0),
        Just(-0.0),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(f64::NAN),
        Just(1e-300),
        Just(1e300),
    ]
}

fn any_expr() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("sin(pi*t/0.2) * (t <= 0.2)".to_string()),
        Just("1/t".to_string()),
        Just("sqrt(-1)".to_string()),
        Just("foo(t)".to_string()),
        Just("(((".to_string()),
        Just("".to_string()),
        "[a-z0-9+*/().<= -]{0,20}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn validation_never_panics_and_errors_name_a_key(
        dim in -1i64..5, elements in -3i64..40, ea in any_f64(), rho_a in any_f64(),
        h in any_f64(), end in any_f64(), node in -50i64..50, expr in any_expr(),
    ) {
        let text = scenario_text(dim, elements, ea, rho_a, h, end, node, &expr);
        match scenario::parse(&text, Path::new("p.toml"), &[]) {
            Err(e) => prop_assert!(e.to_string().starts_with("p.toml:"), "{e}"),
            Ok(file) => {
                if let Err(e) = file.check() {
                    let m = e.to_string();
                    prop_assert!(m.starts_with("p.toml"), "{m}");
                    prop_assert!(m.contains('`'), "error names no key: {m}");
                }
            }
        }
    }

    #[test]
    fn valid_scenarios_are_accepted(
        dim in 1i64..4, elements in 1i64..200, ea in 1e-3..1e6f64, rho_a in 1e-3..1e3f64,
        steps in 1u32..500, node in 1i64..200,
    ) {
        let h = 0.001;
        let end = f64::from(steps) * h;
        let node = node.min(elements).max(1);
        let text = scenario_text(dim, elements, ea, rho_a, h, end, node, "sin(t)");
        let file = scenario::parse(&text, Path::new("v.toml"), &[]).unwrap();
        prop_assert!(file.check().is_ok(), "{:?}", file.check().err().map(|e| e.to_string()));
    }
}

/// The paper example, for `--set` properties.
fn paper_text() -> String {
    scenario_text(2, 30, 20.0, 1.0, 0.01, 1.0, -1, "sin(t)")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any `--set` option (keys of any depth, values with line breaks, quotes,
    /// brackets) gives a scenario or an error that names the option, clipped to a bounded
    /// length, and never a panic.
    #[test]
    fn set_options_never_panic_and_errors_are_bounded(
        key in "[a-z0-9._ -]{0,40}|(boundary|geometry|time)\\.-?[0-9]{1,2}\\.[a-z]{1,6}",
        value in "[a-z0-9\\[\\]{}\"'=,.\\n -]{0,60}",
        long in 0usize..2,
    ) {
        let value = if long == 1 { value.repeat(2000) } else { value };
        let option = format!("{key}={value}");
        match scenario::parse(&paper_text(), Path::new("p.toml"), std::slice::from_ref(&option)) {
            Ok(file) => { let _ = file.check(); }
            Err(e) => {
                let m = e.to_string();
                prop_assert!(m.len() < 1500, "{} bytes: {}", m.len(), &m[..300]);
                prop_assert!(!m.chars().any(|c| c.is_control() && c != '\n'), "{m:?}");
            }
        }
    }

    /// `--set` options on a network's tables: a network or an error of bounded length that
    /// names a key, never a panic.
    #[test]
    fn network_set_options_never_panic_and_errors_are_bounded(
        key in "(string|spring|node|point_mass|boundary)\\.-?[0-9]\\.(name|path|between|to_point|elements|material|prestretch|k|rest|node|kg|position|fixed|force)|materials\\.(steel|[a-z]{1,6})\\.(law|ea|rho_a|mass)",
        value in "[a-z0-9\\[\\]\":=,.-]{0,40}",
        long in 0usize..2,
    ) {
        let value = if long == 1 { value.repeat(2000) } else { value };
        let option = format!("{key}={value}");
        let result = scenario::parse(NET, Path::new("n.toml"), std::slice::from_ref(&option))
            .and_then(|f| f.check());
        if let Err(e) = result {
            let m = e.to_string();
            prop_assert!(m.len() < 1500, "{} bytes: {}", m.len(), &m[..300]);
            prop_assert!(!m.chars().any(|c| c.is_control() && c != '\n'), "{m:?}");
        }
    }

    /// `--vary` splitting: values joined by commas split back into the same
    /// values, whatever quotes, escapes and brackets they hold.
    #[test]
    fn vary_values_split_back(values in proptest::collection::vec(vary_value(), 1..5)) {
        let option = format!("title={}", values.join(","));
        let v = phstring_io::drive::sweep::Vary::parse(&option).unwrap();
        prop_assert_eq!(v.values, values);
    }

    /// Any `--vary` text gives values or an error, never a panic.
    #[test]
    fn vary_parsing_never_panics(text in "[a-z=,\"'\\\\\\[\\]{} ]{0,40}") {
        let _ = phstring_io::drive::sweep::Vary::parse(&text);
    }
}

/// A `--vary` value: a number, a word, a basic string with escapes, a literal string or
/// an array of them.
fn vary_value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        "[0-9]{1,4}".prop_map(|s| s),
        "[a-z]{1,6}".prop_map(|s| s),
        "([a-z,]|\\\\\"|\\\\\\\\){0,6}".prop_map(|s| format!("\"{s}\"")),
        "[a-z,\"]{0,6}".prop_map(|s| format!("'{s}'")),
    ];
    prop_oneof![
        leaf.clone(),
        proptest::collection::vec(leaf, 0..3).prop_map(|v| format!("[{}]", v.join(", "))),
    ]
}

/// Bounded inputs: a `--set` key of 4,000 segments is refused at once by its length;
/// 32 segments are the most.
#[test]
fn deep_set_keys_are_capped() {
    let deep = format!("{}=1", vec!["a"; 4000].join("."));
    let e = scenario::parse(&paper_text(), Path::new("p.toml"), &[deep])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the key is 7999 bytes long"),
        "{}",
        &e[..300.min(e.len())]
    );
    assert!(e.len() < 600);
    let deep = format!("{}=1", vec!["a"; 33].join("."));
    let e = scenario::parse(&paper_text(), Path::new("p.toml"), &[deep])
        .unwrap_err()
        .to_string();
    assert!(e.contains("33 segments"), "{e}");
    // 32 segments: a new nested table costs one header line, not one per level.
    let deep = format!("{}=1", vec!["a"; 32].join("."));
    let e = scenario::parse(&paper_text(), Path::new("p.toml"), &[deep])
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field `a`"), "{e}");
}

/// A `--set` value with a line break is refused when the break would end it (the text after
/// it is never silently dropped), and accepted as one value inside brackets.
#[test]
fn set_with_a_line_break_is_one_value_or_refused() {
    let e = scenario::parse(
        &paper_text(),
        Path::new("p.toml"),
        &["time.h=0.01\ntime.end=5".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("the value has a line break"), "{e}");
    let file = scenario::parse(
        &paper_text(),
        Path::new("p.toml"),
        &["geometry.end=[\n1.0,\n 2.0]".to_string()],
    )
    .unwrap();
    assert_eq!(
        file.scenario
            .geometry
            .as_ref()
            .unwrap()
            .get_ref()
            .end
            .as_ref()
            .unwrap()
            .get_ref(),
        &vec![1.0, 2.0]
    );
}

/// Bounded inputs: a scenario file is read up to 16 MiB; an endless one is refused as too
/// large.
#[test]
fn scenario_file_size_is_capped() {
    let e = scenario::load(Path::new("/dev/zero"), &[]).unwrap_err();
    assert!(matches!(e, scenario::ScenarioError::TooLarge { .. }), "{e}");
}

/// Point masses (`[[point_mass]]`): the node counts from the end like a boundary's, the
/// weight is `kg · g`, and a bad mass or node names its key and position.
#[test]
fn point_masses_are_validated_with_their_weight() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper_pendulum.toml"),
    )
    .unwrap()
        + "\n[[point_mass]]\nnode = -1\nkg = 2.5\n";
    let file = scenario::parse(&text, Path::new("pm.toml"), &[]).unwrap();
    let v = file.validate::<2>().unwrap();
    let pm = &v.problem.point_masses;
    assert_eq!(pm.len(), 1);
    assert_eq!((pm[0].node, pm[0].mass), (30, 2.5));
    assert_eq!(pm[0].weight, phstring::Vector::<2>::new(0.0, -9.81 * 2.5));
    for (set, key) in [
        ("point_mass.0.kg=0", "`point_mass.0.kg` must be positive"),
        ("point_mass.0.kg=-1.0", "`point_mass.0.kg` must be positive"),
        (
            "point_mass.0.node=31",
            "`point_mass.0.node` = 31 is out of range",
        ),
        ("point_mass.0.kg=1e308", "`point_mass.0.kg`"),
        // A weight whose square overflows the force residual: named, not NaN or infinite.
        (
            "point_mass.0.kg=1e300",
            "`point_mass.0.kg` = 1e300: its weight under body_force.gravity at node 30 is 9.810000000000001e300 N, above 1e150 N",
        ),
        (
            "material.drag=1e300",
            "`material.drag` = 1e300 N·s/m² gives the elements of the string, of reference length up to 0.033333333333333375 m, the drag coefficient 3.3333333333333377e298 N·s/m each, above 1e150 N·s/m",
        ),
        (
            "material.rho_a=1e300",
            "`material.rho_a` = 1e300 gives the elements of the string the weight 3.2700000000000042e299 N each",
        ),
    ] {
        let err = scenario::parse(&text, Path::new("pm.toml"), &[set.to_string()])
            .and_then(|f| f.check())
            .err()
            .unwrap_or_else(|| panic!("{set} accepted"))
            .to_string();
        assert!(err.contains(key), "{set}: {err}");
    }
}

/// Prescribed motion (`position` in a boundary entry): absolute positions that must start at
/// the node; a component cannot be both fixed and moved; `""` leaves a component free.
#[test]
fn prescribed_positions_are_validated() {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/crane_2d.toml"),
    )
    .unwrap();
    let file = scenario::parse(&base, Path::new("crane.toml"), &[]).unwrap();
    let v = file.validate::<2>().unwrap();
    let m = &v.problem.boundary.motions;
    assert_eq!(m.len(), 1);
    assert_eq!((m[0].node, m[0].component), (0, 0));
    // Accelerating at 0.5 m/s² for 2 s (1 m), then 1 m/s.
    assert_eq!((m[0].position)(2.0), 1.0);
    assert_eq!((m[0].position)(4.0), 3.0);
    for (set, key, expected) in [
        (
            r#"boundary.0.position=["1 + t", ""]"#,
            "boundary.0.position.0",
            "component x is at 1 m at t = 0, but node 0 starts at 0 m",
        ),
        (
            r#"boundary.0.position=["t", "t"]"#,
            "boundary.0.position.1",
            "node 0 is also fixed in component y",
        ),
        (
            r#"boundary.0.position=["t"]"#,
            "boundary.0.position",
            "must have 2 expressions",
        ),
    ] {
        let err = scenario::parse(&base, Path::new("crane.toml"), &[set.to_string()])
            .and_then(|f| f.check())
            .err()
            .unwrap_or_else(|| panic!("{set} accepted"))
            .to_string();
        assert!(err.contains(&format!("`{key}`")), "{set}: {err}");
        assert!(err.contains(expected), "{set}: {err}");
    }
}

/// Found by `set_options_never_panic_and_errors_are_bounded` in a fresh clone (bounded
/// inputs): malformed inline tables make the TOML parser recurse once per `{`, and a
/// 1 MB scenario file (or a long `--set` value) overflowed the stack and aborted. Texts with
/// more than `MAX_BRACES` `{` are refused before parsing.
#[test]
fn many_braces_are_refused_not_overflowing_the_stack() {
    let junk = "{,[\n] b].]'{}\"z']9,bb".repeat(50_000);
    let text = format!("title = \"x\"\ndimension = 2\n[mesh]\nelements = {junk}\n");
    let err = scenario::parse(&text, Path::new("junk.toml"), &[])
        .expect_err("refused")
        .to_string();
    assert!(err.contains("junk.toml has 100000 `{` characters"), "{err}");
    let set = format!("mesh.elements={}", "{,[\n] b].]'{}\"z']9,bb".repeat(2000));
    let err = scenario::parse(&paper_text(), Path::new("p.toml"), &[set])
        .expect_err("refused")
        .to_string();
    assert!(err.contains("4000 `{` characters"), "{err}");
}

/// A small 2D network: three named nodes, string `s0` from `a` to `b`, string `s1` from
/// the middle of `s0` to `c`, a spring from `b` to `c`, a point mass at `c`, `a` fixed and
/// `b` moved along x.
const NET: &str = r#"dimension = 2

[[node]]
name = "a"
position = [0.0, 0.0]

[[node]]
name = "b"
position = [1.0, 0.0]

[[node]]
name = "c"
position = [1.0, -1.0]

[materials.steel]
law = "tension_only_linear"
ea = 1.0e5
rho_a = 1.0

[[string]]
name = "s0"
path = ["a", "b"]
elements = 4
material = "steel"

[[string]]
name = "s1"
path = ["s0:2", "c"]
elements = 3
material = "steel"
prestretch = 1.01

[[spring]]
name = "k0"
between = ["b", "c"]
k = 100.0
rest = 1.0

[[point_mass]]
node = "c"
kg = 2.0

[body_force]
gravity = [0.0, -9.81]

[[boundary]]
node = "a"
fixed = true

[[boundary]]
node = "b"
fixed = ["y"]
position = ["1 + 0.1*t", ""]

[time]
h = 0.01
end = 0.1
"#;

/// `line:column` of the first `needle` in `text`; a `|` in `needle` marks the position
/// meant (after some context that makes it unique).
fn pos(text: &str, needle: &str) -> String {
    let (before, after) = needle.split_once('|').unwrap_or(("", needle));
    let at = text
        .find(&format!("{before}{after}"))
        .unwrap_or_else(|| panic!("{needle:?} not in {text}"))
        + before.len();
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap().chars().count() + 1;
    format!("{line}:{column}")
}

/// The network builds as the builder numbers it, with references along strings resolved.
#[test]
fn network_scenario_resolves_names_and_string_nodes() {
    let file = scenario::parse(NET, Path::new("net.toml"), &[]).unwrap();
    file.check().unwrap_or_else(|e| panic!("{e}"));
    let v = file.validate::<2>().unwrap();
    assert!(v.network);
    let p = &v.problem;
    // Nodes: a, b, c; s0's interior 3, 4, 5; s1's interior 6, 7.
    assert_eq!(p.mesh.n_nodes(), 8);
    assert_eq!(p.mesh.n_elements(), 4 + 3 + 1);
    let groups: Vec<(&str, std::ops::Range<usize>)> = p
        .groups
        .iter()
        .map(|g| (g.name.as_str(), g.elements.clone()))
        .collect();
    assert_eq!(groups, [("s0", 0..4), ("s1", 4..7), ("k0", 7..8)]);
    // s1 starts at s0:2, the 2nd node along s0: node 4, at (0.5, 0).
    assert_eq!(p.mesh.elements()[4], [4, 6]);
    assert_eq!(p.initial.r[4], phstring::Vector::<2>::new(0.5, 0.0));
    assert_eq!(p.mesh.elements()[7], [1, 2]);
    // Prestretch 1.01: l = |Δr| / 3 / 1.01.
    let l = (1.25f64).sqrt() / 3.0 / 1.01;
    assert!((p.mesh.lengths()[4] - l).abs() < 1e-15);
    // Body force ρA g on the strings, none on the spring.
    assert_eq!(
        p.groups[0].body_force,
        phstring::Vector::<2>::new(0.0, -9.81)
    );
    assert_eq!(p.groups[2].body_force, phstring::Vector::<2>::zeros());
    assert_eq!((p.point_masses[0].node, p.point_masses[0].mass), (2, 2.0));
    assert_eq!(p.boundary.motions[0].node, 1);
    let c = &v.components;
    assert_eq!(c.strings[1].path_nodes, [4, 2]);
    assert_eq!(c.strings[1].interior_nodes, [6, 8]);
    assert_eq!(c.node_label(4), "node 4 \"s0:2\"");
    assert_eq!(c.node_label(2), "node 2 \"c\"");
    assert!((c.strings[1].reference_length - 3.0 * l).abs() < 1e-15);
    // Every kind of reference: an index, a name, along a string from either end.
    for (r, node) in [
        ("3", 3),
        ("-1", 7),
        ("\"b\"", 1),
        ("\"s0:0\"", 0),
        ("\"s0:-1\"", 1),
        ("\"s0:1\"", 3),
        ("\"s1:-2\"", 7),
        ("\"s1:1\"", 6),
    ] {
        let f = scenario::parse(
            NET,
            Path::new("net.toml"),
            &[format!("point_mass.0.node={r}")],
        )
        .unwrap();
        let v = f.validate::<2>().unwrap_or_else(|e| panic!("{r}: {e}"));
        assert_eq!(v.problem.point_masses[0].node, node, "{r}");
    }
}

/// Every single-string example is still one chain group, solved block-tridiagonally.
#[test]
fn single_string_examples_stay_chains() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let file = scenario::load(&path, &[]).unwrap();
        if !file.scenario.string.is_empty() {
            continue;
        }
        seen += 1;
        macro_rules! check {
            ($d:literal) => {{
                let v = file.validate::<$d>().unwrap();
                assert!(!v.network);
                assert_eq!(v.problem.groups.len(), 1);
                assert_eq!(v.problem.groups[0].name, "string");
                assert!(v.problem.mesh.is_chain(), "{}", path.display());
                let sim = phstring::Simulation::new(v.problem, v.settings.step).unwrap();
                assert_eq!(sim.solver_name(), "block_tridiagonal", "{}", path.display());
            }};
        }
        match file.dimension().unwrap() {
            1 => check!(1),
            2 => check!(2),
            _ => check!(3),
        }
    }
    assert!(seen >= 6);
}

/// The platform example is the network of the library's verification test
/// (`phstring::testing::platform`, built with `NetworkBuilder` by hand): the same mesh,
/// groups, conditions and initial state.
#[test]
fn platform_example_is_the_hand_built_network() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/platform_3d.toml");
    let file = scenario::load(&path, &[]).unwrap();
    let v = file.validate::<3>().unwrap();
    let (net, _) = phstring::testing::platform();
    let s = &v.problem;
    assert_eq!(s.mesh, net.mesh);
    assert_eq!(s.groups, net.groups);
    assert_eq!(s.initial, net.initial);
    assert_eq!(s.point_masses, net.point_masses);
    let mut fixed: Vec<(usize, [bool; 3])> = s
        .boundary
        .fixed
        .iter()
        .map(|f| (f.node, f.components))
        .collect();
    fixed.sort_by_key(|f| f.0);
    assert_eq!(
        fixed,
        [
            (1, [true, true, false]),
            (2, [true; 3]),
            (3, [true; 3]),
            (4, [true; 3]),
            (49, [true; 3])
        ]
    );
    let m = &s.boundary.motions;
    assert_eq!((m.len(), m[0].node, m[0].component), (1, 1, 2));
    assert!(((m[0].position)(2.5) - 10.3).abs() < 1e-12);
}

/// Each error of a network names its key and the position of the value.
#[test]
fn network_errors_name_the_key_and_position() {
    // (replace, by, the value to locate in the new text, key, message part)
    let cases: &[(&str, &str, &str, &str, &str)] = &[
        (
            r#"path = ["a", "b"]"#,
            r#"path = ["a", "bb"]"#,
            r#""bb""#,
            "string.0.path.1",
            r#"names node "bb", which is not a [[node]] (known: b, a, c)"#,
        ),
        (
            r#"path = ["s0:2", "c"]"#,
            r#"path = ["s2:2", "c"]"#,
            r#""s2:2""#,
            "string.1.path.0",
            r#"names string "s2", which is not a [[string]] (known: s0, s1)"#,
        ),
        (
            r#"path = ["a", "b"]"#,
            r#"path = ["a", "s1:1"]"#,
            r#""s1:1""#,
            "string.0.path.1",
            r#"names string "s1", which is not defined above this one"#,
        ),
        (
            r#"path = ["s0:2", "c"]"#,
            r#"path = ["s0:5", "c"]"#,
            r#""s0:5""#,
            "string.1.path.0",
            "is out of range: string s0 has nodes 0..=4 (or -1..=-5 from the end)",
        ),
        (
            r#"path = ["s0:2", "c"]"#,
            r#"path = ["s0:x", "c"]"#,
            r#""s0:x""#,
            "string.1.path.0",
            r#"after the ':' comes a node index along the string, e.g. "s0:3""#,
        ),
        (
            r#"path = ["s0:2", "c"]"#,
            r#"path = ["s0:+2", "c"]"#,
            r#""s0:+2""#,
            "string.1.path.0",
            r#"= "s0:+2": after the ':' comes a node index along the string, e.g. "s0:3" or "s0:-1" (digits with an optional leading '-', no blanks or '+')"#,
        ),
        (
            r#"path = ["s0:2", "c"]"#,
            r#"path = ["s0: 2", "c"]"#,
            r#""s0: 2""#,
            "string.1.path.0",
            r#"= "s0: 2": after the ':' comes a node index along the string"#,
        ),
        (
            "[[point_mass]]\nnode = \"c\"",
            "[[point_mass]]\nnode = \"s1:+1\"",
            r#""s1:+1""#,
            "point_mass.0.node",
            r#"= "s1:+1": after the ':' comes a node index along the string"#,
        ),
        (
            r#"path = ["s0:2", "c"]"#,
            r#"path = [9, "c"]"#,
            "9, ",
            "string.1.path.0",
            "= 9 is out of range: the mesh has nodes 0..=5 so far",
        ),
        (
            r#"path = ["a", "b"]"#,
            r#"path = ["a", "a", "b"]"#,
            r#""a", "b"]"#,
            "string.0.path.1",
            r#"is "a" (node 0) again: consecutive nodes of a path must differ"#,
        ),
        (
            "position = [1.0, -1.0]",
            "position = [0.5, 0.0]",
            r#""c"]"#,
            "string.1.path.1",
            "the span between them has zero length",
        ),
        (
            r#"path = ["a", "b"]"#,
            r#"path = ["a"]"#,
            r#"["a"]"#,
            "string.0.path",
            "has 1 nodes; a string's path has 2 to 100000",
        ),
        (
            "elements = 4",
            "elements = 0",
            "elements = |0",
            "string.0.elements",
            "must be at least 1 (elements per span), got 0",
        ),
        (
            "elements = 4",
            "elements = 60000000",
            "60000000",
            "string.0.elements",
            "at most 5e7 elements in all",
        ),
        (
            "material = \"steel\"\n\n[[string]]",
            "material = \"steal\"\n\n[[string]]",
            r#""steal""#,
            "string.0.material",
            r#"names material "steal", which is not a [materials.NAME] table (known: steel)"#,
        ),
        (
            "prestretch = 1.01",
            "prestretch = -1.0",
            "prestretch = |-1.0",
            "string.1.prestretch",
            "must be positive and finite, got -1",
        ),
        (
            r#"name = "s1""#,
            r#"name = "s0""#,
            r#""s0"
path = ["s0"#,
            "string.1.name",
            r#"= "s0" is already the name of string.0 (line 21)"#,
        ),
        (
            r#"name = "k0""#,
            r#"name = "s1""#,
            r#""s1"
between"#,
            "spring.0.name",
            r#"= "s1" is already the name of string.1"#,
        ),
        (
            r#"name = "c""#,
            r#"name = "c:1""#,
            r#""c:1""#,
            "node.2.name",
            r#"= "c:1" is not a valid name"#,
        ),
        (
            r#"between = ["b", "c"]"#,
            r#"between = ["c", "c"]"#,
            r#""c", |"c"]"#,
            "spring.0.between.1",
            r#"is the same node as between.0 ("c" (node 2))"#,
        ),
        (
            r#"between = ["b", "c"]"#,
            r#"between = ["b"]"#,
            r#"["b"]"#,
            "spring.0.between",
            "names one node: give a second one, or `to_point`",
        ),
        (
            "rest = 1.0",
            "rest = 1.0\nto_point = [2.0, 2.0]",
            "[2.0, 2.0]",
            "spring.0.to_point",
            "must not be given with two nodes in `between`",
        ),
        (
            "rest = 1.0",
            "rest = -1.0",
            "rest = |-1.0",
            "spring.0.rest",
            "must be at least 0 and finite, got -1",
        ),
        (
            "k = 100.0",
            "k = 0.0",
            "k = |0.0",
            "spring.0.k",
            "= 0: a spring of stiffness 0 does nothing; give `damping` [N s/m] for a pure dashpot",
        ),
        (
            r#"between = ["b", "c"]"#,
            "between = [\"b\"]\nto_point = [1.0, 0.0]",
            "rest = |1.0",
            "spring.0.rest",
            "but the spring's ends start at the same point",
        ),
        (
            "[[point_mass]]\nnode = \"c\"",
            "[[point_mass]]\nnode = 8",
            "node = |8",
            "point_mass.0.node",
            "= 8 is out of range: the mesh has nodes 0..=7 (or -1..=-8 from the end)",
        ),
        (
            "[[point_mass]]\nnode = \"c\"",
            "[[point_mass]]\nnode = \"s3:1\"",
            r#""s3:1""#,
            "point_mass.0.node",
            r#"names string "s3", which is not a [[string]]"#,
        ),
        (
            r#"position = ["1 + 0.1*t", ""]"#,
            r#"position = ["0.1*t", ""]"#,
            r#""0.1*t""#,
            "boundary.1.position.0",
            r#"component x is at 0 m at t = 0, but "b" (node 1) starts at 1 m"#,
        ),
        (
            "node = \"a\"\nfixed = true",
            "node = \"b\"\nposition = [\"1 - t\", \"\"]",
            r#""1 + 0.1*t""#,
            "boundary.1.position.0",
            r#""b" (node 1) already follows boundary.0.position in component x"#,
        ),
        (
            "node = \"a\"\nfixed = true",
            "node = \"b\"\nforce = [\"sin(t)\", \"0\"]",
            r#"["sin(t)", "0"]"#,
            "boundary.0.force",
            r#""b" (node 1) has a prescribed position (boundary.1.position) in component x and cannot also be loaded in it (give "0" there)"#,
        ),
        (
            "[[spring]]\nname = \"k0\"\nbetween = [\"b\", \"c\"]",
            "[[node]]\nname = \"d\"\nposition = [2.0, 0.0]\n\n[[spring]]\nname = \"k0\"\nbetween = [\"b\", \"d\"]",
            r#""b", |"d"]"#,
            "spring.0.between.1",
            r#"is "d" (node 3), which only springs hold: springs are massless, so give the node a [[point_mass]] or fix it"#,
        ),
        (
            "[[point_mass]]",
            "[[node]]\nname = \"d\"\nposition = [3.0, 3.0]\n\n[[point_mass]]",
            r#""d""#,
            "node.3.name",
            r#"= "d" is on no string's path and at no spring's end"#,
        ),
        (
            "[time]",
            "[material]\nea = 1.0\nrho_a = 1.0\n\n[time]",
            "[material]",
            "material",
            "belongs to a single-string scenario, but this one has [[string]] tables",
        ),
        (
            "[materials.steel]",
            "[materials.\"st eel\"]",
            "[materials.\"st eel\"]",
            "materials.st eel",
            r#"= "st eel" is not a valid name"#,
        ),
        (
            "[time]",
            "[newton]\nsolver = \"block_tridiagonal\"\n\n[time]",
            "solver = |\"block_tridiagonal\"",
            "newton.solver",
            "= block_tridiagonal solves chains (element e joining nodes e and e+1, as one string) only",
        ),
        (
            "ea = 1.0e5",
            "ea = -1.0e5",
            "ea = |-1.0e5",
            "materials.steel.ea",
            "must be positive and finite",
        ),
        (
            r#"position = ["1 + 0.1*t", ""]"#,
            r#"position = ["", " "]"#,
            r#"["", " "]"#,
            "boundary.1.position",
            r#"prescribes nothing: every expression is "" (free); give the position of at least one component"#,
        ),
        (
            r#"position = ["1 + 0.1*t", ""]"#,
            "position = []",
            "position = |[]",
            "boundary.1.position",
            r#"must have 2 expressions (dimension = 2; "" for a free component), got 0"#,
        ),
        (
            "prestretch = 1.01",
            "prestretch = 1e-300",
            "prestretch = |1e-300",
            "string.1.prestretch",
            r#"= 1e-300 gives the elements of string "s1" (string.1) the weight 3.6559711432121563e300 N each: the body force 9.81 N/m (materials.steel.rho_a = 1 kg/m times body_force.gravity, plus body_force.per_length) times the reference element length 3.7267799624996496e299 m (span 1 of its path / elements / prestretch), above 1e150 N: nodal forces this large overflow the force residual, which squares them"#,
        ),
        (
            "rho_a = 1.0",
            "rho_a = 1e300",
            "rho_a = |1e300",
            "materials.steel.rho_a",
            r#"= 1e300 gives the elements of string "s0" (string.0) the weight 2.4525000000000003e300 N each: the body force 9.810000000000001e300 N/m (materials.steel.rho_a = 1e300 kg/m times body_force.gravity, plus body_force.per_length) times the reference element length 0.25 m (span 1 of its path / elements / prestretch), above 1e150 N"#,
        ),
        (
            "rho_a = 1.0",
            "rho_a = 1.0\ndrag = 1e300",
            "drag = |1e300",
            "materials.steel.drag",
            r#"= 1e300 N·s/m² gives the elements of string "s0" (string.0), of reference length up to 0.25 m, the drag coefficient 2.5e299 N·s/m each, above 1e150 N·s/m"#,
        ),
        (
            "kg = 2.0",
            "kg = 1e300",
            "kg = |1e300",
            "point_mass.0.kg",
            r#"= 1e300: its weight under body_force.gravity at "c" (node 2) is 9.810000000000001e300 N, above 1e150 N"#,
        ),
        (
            "position = [1.0, -1.0]",
            "position = [0.5, 1e-300]",
            r#""c"]"#,
            "string.1.path.1",
            r#"is "c" (node 2), 1e-300 m from the path's previous node: the span's elements (3 of 3.3333333333333334e-301 m) are too short for floating point, their squared length (in the strain C) underflows below 2.2e-308 m²; elements must be longer than 1.5e-154 m"#,
        ),
    ];
    for (from, to, value, key, message) in cases {
        assert!(NET.contains(from), "{from:?}");
        let text = NET.replacen(from, to, 1);
        let err = scenario::parse(&text, Path::new("net.toml"), &[])
            .and_then(|f| f.check())
            .err()
            .unwrap_or_else(|| panic!("{to:?} accepted"))
            .to_string();
        let expected = format!("net.toml:{}: `{key}` ", pos(&text, value));
        assert!(
            err.contains(&expected),
            "{to:?}: expected {expected:?} in {err}"
        );
        assert!(
            err.contains(message),
            "{to:?}: expected {message:?} in {err}"
        );
    }
}

/// A single-string file with a network table, and a file with neither, name the key.
#[test]
fn layout_errors_name_the_table() {
    let paper = paper_text();
    for (extra, key) in [
        ("[[node]]\nname = \"a\"\nposition = [0.0, 0.0]\n", "node"),
        ("[materials.steel]\nea = 1.0\nrho_a = 1.0\n", "materials"),
    ] {
        let text = format!("{paper}{extra}");
        let err = scenario::parse(&text, Path::new("p.toml"), &[])
            .and_then(|f| f.check())
            .expect_err("refused")
            .to_string();
        let header = extra.lines().next().unwrap();
        assert!(
            err.contains(&format!(
                "p.toml:{}: `{key}` belongs to a network",
                pos(&text, header)
            )),
            "{err}"
        );
    }
    let err = scenario::parse(
        "dimension = 2\n[time]\nh = 0.1\nend = 1.0\n",
        Path::new("e.toml"),
        &[],
    )
    .and_then(|f| f.check())
    .expect_err("refused")
    .to_string();
    assert!(err.starts_with("e.toml: `geometry` is required"), "{err}");
}

/// A value set with `--set` is reported as the option, also for an element of an array.
#[test]
fn network_set_errors_name_the_option() {
    let err = scenario::parse(
        NET,
        Path::new("net.toml"),
        &[r#"string.1.path=["s0:2", "cc"]"#.to_string()],
    )
    .and_then(|f| f.check())
    .expect_err("refused")
    .to_string();
    assert!(
        err.starts_with(r#"--set string.1.path=["s0:2", "cc"]: `string.1.path.1` names node "cc""#),
        "{err}"
    );
    let file = scenario::parse(
        NET,
        Path::new("net.toml"),
        &["materials.steel.ea=2e5".into()],
    )
    .unwrap();
    let v = file.validate::<2>().unwrap();
    assert_eq!(v.components.strings[0].ea, 2e5);
    assert_eq!(file.element_count(), 4 + 3 + 1);
}

/// A network scenario with random values and references, for the property tests.
#[allow(clippy::too_many_arguments)] // one argument per key under test
fn network_text(
    dim: i64,
    elements: i64,
    refs: &[String],
    coords: &[f64],
    k: f64,
    rest: f64,
    prestretch: f64,
    kg: f64,
    to_point: bool,
) -> String {
    let d = dim.clamp(0, 4) as usize;
    let vec = |i: usize| {
        let v: Vec<String> = (0..d)
            .map(|j| format!("{:?}", coords[(i * 3 + j) % coords.len()]))
            .collect();
        format!("[{}]", v.join(", "))
    };
    let r = |i: usize| refs[i % refs.len()].clone();
    let mut t = format!("dimension = {dim}\n");
    for (i, name) in ["a", "b", "c"].iter().enumerate() {
        t += &format!("[[node]]\nname = \"{name}\"\nposition = {}\n", vec(i));
    }
    t += "[materials.m]\nlaw = \"hyperelastic\"\nea = 100.0\nrho_a = 1.0\n";
    t += &format!(
        "[[string]]\nname = \"s0\"\npath = [\"a\", {}]\nelements = {elements}\nmaterial = \"m\"\nprestretch = {prestretch:?}\n",
        r(0)
    );
    t += &format!(
        "[[string]]\nname = \"s1\"\npath = [{}, {}, \"c\"]\nelements = 2\nmaterial = \"m\"\n",
        r(1),
        r(2)
    );
    if to_point {
        t += &format!(
            "[[spring]]\nname = \"k\"\nbetween = [{}]\nto_point = {}\nk = {k:?}\nrest = {rest:?}\n",
            r(3),
            vec(3)
        );
    } else {
        t += &format!(
            "[[spring]]\nname = \"k\"\nbetween = [{}, {}]\nk = {k:?}\nrest = {rest:?}\n",
            r(3),
            r(4)
        );
    }
    t += &format!("[[point_mass]]\nnode = {}\nkg = {kg:?}\n", r(5));
    t += &format!("[[boundary]]\nnode = {}\nfixed = true\n", r(6));
    t += "[body_force]\n";
    t += &format!("gravity = {}\n", vec(4));
    t += "[time]\nh = 0.01\nend = 0.02\n";
    t
}

fn any_ref() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("\"a\"".to_string()),
        Just("\"b\"".to_string()),
        Just("\"c\"".to_string()),
        Just("\"x\"".to_string()),
        (-12i64..12).prop_map(|i| format!("\"s0:{i}\"")),
        (-8i64..8).prop_map(|i| format!("\"s1:{i}\"")),
        (-3i64..3).prop_map(|i| format!("\"s9:{i}\"")),
        (-20i64..20).prop_map(|i| i.to_string()),
        "\"[a-z0-9:-]{0,6}\"",
        Just("1.5".to_string()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Networks: any values and references give a network or an error that
    /// names a key (or, for what only the assembled system shows, the setup), never a
    /// panic.
    #[test]
    fn network_validation_never_panics_and_errors_name_a_key(
        dim in 0i64..5, elements in -2i64..6,
        refs in proptest::collection::vec(any_ref(), 7),
        coords in proptest::collection::vec(prop_oneof![3 => -5.0..5.0f64, 1 => any_f64()], 15),
        k in any_f64(), rest in any_f64(), prestretch in any_f64(), kg in any_f64(),
        to_point in any::<bool>(),
    ) {
        let text = network_text(dim, elements, &refs, &coords, k, rest, prestretch, kg, to_point);
        match scenario::parse(&text, Path::new("n.toml"), &[]) {
            Err(e) => prop_assert!(e.to_string().starts_with("n.toml:"), "{e}"),
            Ok(file) => {
                if let Err(e) = file.check() {
                    let m = e.to_string();
                    prop_assert!(m.starts_with("n.toml"), "{m}");
                    let setup = matches!(e, scenario::ScenarioError::Setup { .. });
                    prop_assert!(setup || m.contains('`'), "error names no key: {m}");
                }
            }
        }
    }

    /// Valid networks are accepted: nodes apart, references along the strings in range.
    #[test]
    fn valid_networks_are_accepted(
        elements in 1i64..6, i0 in 1i64..5, i1 in -5i64..0, k in 1.0..1e4f64,
        rest in 0.0..2.0f64, prestretch in 0.9..1.1f64, kg in 0.1..100.0f64,
        to_point in any::<bool>(),
    ) {
        let i0 = i0.min(elements);
        let refs = vec![
            "\"b\"".to_string(),
            format!("\"s0:{i0}\""),
            format!("\"s0:{}\"", i1.max(-elements - 1)),
            "\"c\"".to_string(),
            "\"s1:1\"".to_string(),
            "\"s1:-1\"".to_string(),
            "\"a\"".to_string(),
        ];
        let coords = [0.0, 0.0, 0.0, 2.0, 0.5, 0.0, 1.0, -2.0, 0.0, 3.0, 3.0, 0.0, 0.0, -9.81, 0.0];
        // s1 from s0:i0 to s0:i1 must not be one node: shift the second when they meet.
        let text = network_text(2, elements, &refs, &coords, k, rest, prestretch, kg, to_point);
        let file = scenario::parse(&text, Path::new("v.toml"), &[]).unwrap();
        match file.check() {
            Ok(()) => {}
            Err(e) => {
                let m = e.to_string();
                // s0:i0 and s0:i1 can be the same node (a span of zero length).
                prop_assert!(m.contains("again: consecutive nodes"), "{m}");
            }
        }
    }
}

/// The annotated examples of docs/scenario.md (one string, a network) are valid scenarios.
#[test]
fn documented_examples_are_valid() {
    let doc = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scenario.md"),
    )
    .unwrap();
    for section in ["## Complete annotated example", "## Networks"] {
        let at = doc.find(section).unwrap_or_else(|| panic!("{section}"));
        let start = doc[at..].find("```toml\n").unwrap() + at + "```toml\n".len();
        let end = doc[start..].find("```").unwrap() + start;
        let file = scenario::parse(&doc[start..end], Path::new("doc.toml"), &[])
            .unwrap_or_else(|e| panic!("{section}: {e}"));
        file.check().unwrap_or_else(|e| panic!("{section}: {e}"));
    }
}

/// A spring with `to_point` ends at a new node, fixed in every component, after the
/// strings' nodes; another spring may use that node by its index.
#[test]
fn springs_to_points_make_fixed_nodes() {
    let text = NET.replacen(
        "between = [\"b\", \"c\"]",
        "between = [\"c\"]\nto_point = [2.0, -1.0]",
        1,
    );
    let file = scenario::parse(&text, Path::new("net.toml"), &[]).unwrap();
    file.check().unwrap_or_else(|e| panic!("{e}"));
    let v = file.validate::<2>().unwrap();
    assert_eq!(v.problem.mesh.n_nodes(), 9);
    assert_eq!(v.components.springs[0].nodes, [2, 8]);
    let s = v.components.supports.iter().find(|s| s.node == 8).unwrap();
    assert_eq!(s.fixed, ["x", "y"]);
    assert_eq!(
        v.problem.initial.r[8],
        phstring::Vector::<2>::new(2.0, -1.0)
    );
    // The fixed point is held in every component: nothing can be attached to it.
    for extra in [
        "\n[[boundary]]\nnode = 8\nforce = [\"0\", \"100\"]\n",
        "\n[[boundary]]\nnode = -1\nposition = [\"2 + 0.1*sin(t)\", \"\"]\n",
        "\n[[point_mass]]\nnode = -1\nkg = 5.0\n",
    ] {
        let err = scenario::parse(&(text.clone() + extra), Path::new("net.toml"), &[])
            .and_then(|f| f.check())
            .expect_err(extra)
            .to_string();
        assert!(
            err.contains("the fixed point of spring \"k0\""),
            "{extra}: {err}"
        );
    }
    // In a spring's `between`, indices count in the strings' nodes: -1 is the last interior
    // node of s1 (node 7), not the fixed point of k0, and 8 is out of range.
    let more = "\n[[spring]]\nname = \"k1\"\nbetween = [-1, \"b\"]\nk = 10.0\nrest = 0.5\n";
    let v = scenario::parse(&(text.clone() + more), Path::new("net.toml"), &[])
        .unwrap()
        .validate::<2>()
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(v.components.springs[1].nodes, [7, 1]);
    let bad = "\n[[spring]]\nname = \"k1\"\nbetween = [8, \"b\"]\nk = 10.0\nrest = 0.0\n";
    let err = scenario::parse(&(text + bad), Path::new("net.toml"), &[])
        .and_then(|f| f.check())
        .expect_err("index of a fixed point")
        .to_string();
    assert!(err.contains("spring.1.between.0"), "{err}");
}

/// A string whose elements are far shorter than the rounding of their coordinates allows
/// (3.3e-13 m at 0.5 m from the origin, which holds positions to 1.1e-16 m) is valid, but
/// warned about; the same string 1e-5 m long is not, nor is the network as written.
#[test]
fn elements_below_the_rounding_of_their_coordinates_are_warned_about() {
    let warnings = |text: &str| {
        scenario::parse(text, Path::new("net.toml"), &[])
            .unwrap()
            .check_with_warnings()
            .unwrap()
    };
    assert_eq!(warnings(NET), Vec::<String>::new());
    let at = |y: &str| {
        NET.replacen(
            "position = [1.0, -1.0]",
            &format!("position = [0.5, {y}]"),
            1,
        )
    };
    assert_eq!(warnings(&at("1e-5")), Vec::<String>::new());
    let w = warnings(&at("1e-12"));
    assert_eq!(w.len(), 1, "{w:?}");
    let expected = "string \"s1\": 3 of its 3 elements are shorter than 1e8 times the rounding of their coordinates; element ";
    assert!(w[0].starts_with(expected), "{w:?}");
    assert!(
        w[0].contains("at coordinates of 0.5 m, which floating point holds to about 1.1102230246251565e-16 m, so its strain carries a relative rounding error of about 0.000666133814775094 and Newton may fail at the first step"),
        "{w:?}"
    );
}
