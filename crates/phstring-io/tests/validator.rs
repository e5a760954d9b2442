//! Property tests of the scenario validator (issue 5): for any values of the keys, validation
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

    /// Issue 10: any `--set` option (keys of any depth, values with line breaks, quotes,
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

    /// Issue 10 (`--vary` splitting): values joined by commas split back into the same
    /// values, whatever quotes, escapes and brackets they hold.
    #[test]
    fn vary_values_split_back(values in proptest::collection::vec(vary_value(), 1..5)) {
        let option = format!("title={}", values.join(","));
        let v = phstring_io::sweep::Vary::parse(&option).unwrap();
        prop_assert_eq!(v.values, values);
    }

    /// Any `--vary` text gives values or an error, never a panic.
    #[test]
    fn vary_parsing_never_panics(text in "[a-z=,\"'\\\\\\[\\]{} ]{0,40}") {
        let _ = phstring_io::sweep::Vary::parse(&text);
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

/// Issue 10 (unbounded inputs): a key of 4,000 segments is refused at once by its length;
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

/// Issue 10 (`--set` silently drops the text after a newline).
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

/// Issue 10 (unbounded inputs): a scenario file is read up to 16 MiB.
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

/// Found by `set_options_never_panic_and_errors_are_bounded` in a fresh clone (issue 10,
/// unbounded inputs): malformed inline tables make the TOML parser recurse once per `{`, and a
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
