//! Fuzz target: reading a MoorDyn deck, recognising one and the typed option getters must
//! never panic or hang, whatever the bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use phstring_io::moordyn;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = moordyn::looks_like_moordyn(text);
    if let Ok(deck) = moordyn::parse(text, "fuzz.dat") {
        let o = &deck.options;
        let _ = (o.dt_m(), o.gravity(), o.water_density(), o.water_depth());
        let _ = (o.k_bot(), o.c_bot(), o.tmax_ic(), o.t_scheme());
        for name in ["dtM", "kb", "nonsense"] {
            let _ = o.number(name);
        }
        let _ = deck.unsupported_sections().count();
    }
});
