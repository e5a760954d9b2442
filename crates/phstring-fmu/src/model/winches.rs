//! The FMU's variables of winches (docs/method.md §20, §23): the payout speed of a winch
//! marked `external = true` as an input, and per winch its payout, length off the drum,
//! speed, drum tension, power and energy as outputs.

use phstring_io::scenario::Setup;

use super::{Causality, Quantity, Variable, WinchValue};

/// The input variables of the winches with `external = true` of `v`: per winch its payout
/// speed [m/s] (`winch.NAME.speed`, negative hauls in), held over each communication step
/// from the payout reached, starting at 0.
pub(super) fn speed_inputs<const D: usize>(v: &Setup<D>) -> Vec<Variable> {
    let winches = v.components.winches.iter().enumerate();
    winches
        .filter(|(_, w)| w.external)
        .map(|(k, w)| Variable {
            name: format!("winch.{}.speed", w.name),
            causality: Causality::Input,
            unit: "m/s",
            description: format!(
                "payout speed of winch {k} (\"{}\"), negative hauling in (held over each communication step from the payout reached)",
                w.name
            ),
            start: Some(0.0),
            quantity: Quantity::WinchSpeed { winch: k },
        })
        .collect()
}

/// The output variables of the winches of `v`, per winch: the length paid out since
/// `t = 0` [m], the reference length off the drum [m], the mean payout speed [m/s] and power
/// [W] over the last internal step, the tension at the drum [N] and the energy supplied
/// since `t = 0` [J].
pub(super) fn outputs<const D: usize>(v: &Setup<D>) -> Vec<Variable> {
    use WinchValue::*;
    let last = "over the last internal step";
    let values = [
        (
            "payout",
            "m",
            Payout,
            "length paid out since t = 0 (negative: hauled in)".to_string(),
        ),
        (
            "length",
            "m",
            Length,
            "unstretched length of string off the drum, beyond the drum point".into(),
        ),
        (
            "vmid",
            "m/s",
            Speed,
            format!("mean payout speed {last} (the payout's increment over the step)"),
        ),
        (
            "tension",
            "N",
            Tension,
            "tension of the element at the drum".into(),
        ),
        (
            "power",
            "W",
            Power,
            format!("mean power the winch supplied {last} (negative: taken)"),
        ),
        (
            "energy",
            "J",
            Energy,
            "energy the winch supplied since t = 0 (part of supplied)".into(),
        ),
    ];
    let mut vars = Vec::new();
    for (k, w) in v.components.winches.iter().enumerate() {
        for (var, unit, what, text) in &values {
            vars.push(Variable {
                name: format!("winch.{}.{var}", w.name),
                causality: Causality::Output,
                unit,
                description: format!("{text}, of winch {k} (\"{}\")", w.name),
                start: None,
                quantity: Quantity::Winch {
                    winch: k,
                    what: *what,
                },
            });
        }
    }
    vars
}
