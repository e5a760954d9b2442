//! Expressions of time in `force` and `position` (nanoexpr), and their evaluation during a
//! run, where a failure becomes NaN (the step fails) and is recorded for the message. The
//! expressions of `[initial]` (of `s`, `L`, `x`, `y`, `z`) are in `initial.rs`.

use nanoexpr::Math;

use crate::text::{clip, num};

/// The value of `expr` at `t`, component `component` of `boundary.{k}.{key}`; a failure or a
/// non-finite value gives NaN (the step then fails) and is kept in `slot` for the message,
/// the first one only (later ones are consequences).
pub(super) fn eval_or_record(
    expr: &Expr,
    slot: &std::sync::Mutex<Option<String>>,
    key: &str,
    k: usize,
    component: usize,
    t: f64,
) -> f64 {
    match expr.eval(t) {
        Ok(x) if x.is_finite() => x,
        failed => record(
            failed,
            expr,
            slot,
            &format!("boundary.{k}.{key}"),
            component,
            t,
        ),
    }
}

/// [`eval_or_record`] of an expression at the full dotted `key` (e.g.
/// `bodies.hook.wrench.force`).
pub(super) fn eval_or_record_at(
    expr: &Expr,
    slot: &std::sync::Mutex<Option<String>>,
    key: &str,
    component: usize,
    t: f64,
) -> f64 {
    match expr.eval(t) {
        Ok(x) if x.is_finite() => x,
        failed => record(failed, expr, slot, key, component, t),
    }
}

/// Keeps the first failure (`failed`: an error or a non-finite value) of `expr` at `key`
/// in `slot`; NaN.
fn record(
    failed: Result<f64, String>,
    expr: &Expr,
    slot: &std::sync::Mutex<Option<String>>,
    key: &str,
    component: usize,
    t: f64,
) -> f64 {
    let what = match failed {
        Ok(x) => format!("value {}", num(x)),
        Err(m) => m,
    };
    if let Ok(mut s) = slot.lock()
        && s.is_none()
    {
        *s = Some(format!(
            "`{key}` component {} \"{}\" at t = {} s: {what}",
            ["x", "y", "z"][component.min(2)],
            clip(expr.text()),
            num(t)
        ));
    }
    f64::NAN
}

/// The error `e` of expression `text` for a message: its kind and the part of the text it
/// concerns, e.g. `division by zero (at "1/s", characters 0..3)`.
pub(super) fn describe(text: &str, e: &nanoexpr::Error) -> String {
    let s = e.span;
    let part = text.get(s.start..s.end).unwrap_or("");
    format!(
        "{} (at \"{}\", characters {}..{})",
        e.kind,
        clip(part),
        s.start,
        s.end
    )
}

/// Whether a force expression is the literal zero (`"0"`, `"0.0"`, …).
pub(super) fn is_zero(text: &str) -> bool {
    text.trim().parse::<f64>() == Ok(0.0)
}

/// A force expression `t ↦ f(t)` [N].
#[derive(Debug, Clone)]
pub struct Expr {
    text: String,
}

impl Expr {
    /// Parses `text` and checks it by evaluating it at `t_check` [s] (the first time it will
    /// be used: the mid time of the first step).
    pub fn new(text: &str, t_check: f64) -> Result<Self, String> {
        let e = Self {
            text: text.to_string(),
        };
        e.eval(t_check)
            .map_err(|m| format!("expression \"{}\" is invalid: {m}", clip(text)))?;
        Ok(e)
    }
    /// Evaluates at time `t` [s].
    pub fn eval(&self, t: f64) -> Result<f64, String> {
        let ctx = ([("t", t)], Math);
        nanoexpr::evaluate_with::<f64, _>(&self.text, &ctx).map_err(|e| describe(&self.text, &e))
    }
    /// The expression text.
    pub fn text(&self) -> &str {
        &self.text
    }
}
