//! Fuzz target: scenario parsing, `--set` overrides, `--vary` options, validation and
//! expression evaluation must never panic or hang, whatever the bytes.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use phstring_io::scenario::{self, Expr};
use phstring_io::drive::sweep::{self, Vary};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // The first line doubles as a `--set` option, a `--vary` option and an expression; the
    // next three lines are more `--set` options.
    let mut lines = text.lines();
    let first = lines.next().unwrap_or("");
    let more: Vec<String> = lines.take(3).map(str::to_string).collect();
    let all: Vec<String> = std::iter::once(first.to_string()).chain(more.iter().cloned()).collect();
    for sets in [&[][..], &[first.to_string()][..], &all[..]] {
        if let Ok(file) = scenario::parse(text, Path::new("fuzz.toml"), sets) {
            // Validation builds the mesh: skip sizes that only test the allocator.
            if file.element_count() <= 100_000 {
                let _ = file.check();
            }
        }
    }
    let varies: Vec<Vary> = all.iter().filter_map(|l| Vary::parse(l).ok()).collect();
    if let Ok(n) = sweep::run_count(&varies) {
        // Combinations are built lazily: only the first few.
        for i in 0..n.min(4) {
            let _ = sweep::combination(&varies, i);
        }
    }
    if let Ok(e) = Expr::new(first, 0.005) {
        for t in [0.0, 1e-300, 0.2, -1.0, 1e300, f64::NAN] {
            let _ = e.eval(t);
        }
    }
});
