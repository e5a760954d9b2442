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
