//! Fuzz target: scenario parsing, `--set` overrides, validation and expression evaluation
//! must never panic, whatever the bytes.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use phstring_io::scenario::{self, Expr};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // The first line doubles as a `--set` option and as an expression.
    let first = text.lines().next().unwrap_or("");
    for sets in [&[][..], &[first.to_string()][..]] {
        if let Ok(file) = scenario::parse(text, Path::new("fuzz.toml"), sets) {
            // Validation builds the mesh: skip sizes that only test the allocator.
            let big = file.scenario.mesh.elements.as_ref().is_some_and(|n| *n.get_ref() > 100_000)
                || file.scenario.geometry.nodes.as_ref().is_some_and(|n| n.get_ref().len() > 100_000);
            if !big {
                let _ = file.check();
            }
        }
    }
    if let Ok(e) = Expr::new(first, 0.005) {
        for t in [0.0, 1e-300, 0.2, -1.0, 1e300, f64::NAN] {
            let _ = e.eval(t);
        }
    }
});
