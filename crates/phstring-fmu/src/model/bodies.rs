//! The FMU's variables of rigid bodies (docs/method.md §20, §22): the wrench ports marked
//! `external = true` as inputs, and per body its state and its port sample as outputs.

use phstring_io::scenario::{ScenarioError, ScenarioFile, Setup};

use super::{AXES, BodyValue, Causality, Quantity, Variable};

/// The input variables of the wrench ports with `external = true` of `v`: per body the
/// force [N] (`d` components) and the torque [N·m] (3 in 3D, `z` in 2D), held over each
/// communication step, starting at the wrench's expressions at `t = 0` (which must be
/// finite: an error points at the body's `wrench` key).
pub(super) fn wrench_inputs<const D: usize>(
    file: &ScenarioFile,
    v: &Setup<D>,
) -> Result<Vec<Variable>, ScenarioError> {
    let sys = &v.problem.system;
    let mut vars = Vec::new();
    for (b, body) in v.components.bodies.iter().enumerate() {
        if !body.wrench_external {
            continue;
        }
        let (force, torque) = sys.body_wrench_at(b, 0.0).unwrap_or_default();
        let name = &body.name;
        let inputs = (0..D)
            .map(|i| (format!("F.{}", AXES[i]), "N", "force", force[i], i, false))
            .chain(torque_components(D).map(|i| {
                let n = format!("M.{}", AXES[i]);
                (n, "N.m", "torque", torque[i], i, true)
            }));
        for (var, unit, what, start, i, turn) in inputs {
            if !start.is_finite() {
                let key = format!("bodies.{name}.wrench");
                let span = file
                    .scenario
                    .bodies
                    .get(name)
                    .and_then(|s| s.get_ref().wrench.as_ref())
                    .map_or(0..0, |w| w.span());
                return Err(ScenarioError::Invalid {
                    origin: file.origin(&key, span),
                    key,
                    reason: format!(
                        "the {what} is {start} in {} at t = 0, the start value of the FMU input body{b}.{var}: an input starts at a finite value",
                        AXES[i]
                    ),
                });
            }
            vars.push(Variable {
                name: format!("body{b}.{var}"),
                causality: Causality::Input,
                unit,
                description: format!(
                    "{what} on rigid body {b} (\"{name}\") in {}, space axes{} (held over each communication step)",
                    AXES[i],
                    if turn { ", about its centre of mass" } else { ", at its centre of mass" },
                ),
                start: Some(start),
                quantity: match turn {
                    false => Quantity::BodyForce { body: b, component: i },
                    true => Quantity::BodyTorque { body: b, component: i },
                },
            });
        }
    }
    Ok(vars)
}

/// The components (0 = x) of a turn in `d` dimensions: `x, y, z` in 3D, `z` in 2D.
fn torque_components(d: usize) -> std::ops::Range<usize> {
    if d == 3 { 0..3 } else { 2..3 }
}

/// The output variables of the rigid bodies of `v`, per body: position [m], orientation
/// (3D: quaternion `w, x, y, z`; 2D: angle [rad]), velocity [m/s] and angular velocity
/// [rad/s, space axes]; for a wrench port its mid-step velocity and angular velocity of the
/// last internal step, for a prescribed motion its reaction force [N] and torque [N·m].
pub(super) fn outputs<const D: usize>(v: &Setup<D>) -> Vec<Variable> {
    use BodyValue::*;
    let sys = &v.problem.system;
    let mut vars = Vec::new();
    for (b, body) in v.components.bodies.iter().enumerate() {
        let label = format!("rigid body {b} (\"{}\")", body.name);
        let mut add = |var: String, unit: &'static str, what: String, value, component| {
            vars.push(Variable {
                name: format!("body{b}.{var}"),
                causality: Causality::Output,
                unit,
                description: format!("{what} of {label}"),
                start: None,
                quantity: Quantity::Body {
                    body: b,
                    what: value,
                    component,
                },
            });
        };
        let step = "over the last internal step";
        for i in 0..D {
            let a = AXES[i];
            add(
                format!("r.{a}"),
                "m",
                format!("position of the centre of mass in {a}"),
                Position,
                i,
            );
        }
        if D == 3 {
            for (i, c) in ["w", "x", "y", "z"].into_iter().enumerate() {
                let what = format!("orientation quaternion (body axes to space), component {c},");
                add(format!("q.{c}"), "1", what, Orientation, i);
            }
        } else {
            add(
                "theta".into(),
                "rad",
                "angle about z in (−π, π]".into(),
                Angle,
                2,
            );
        }
        for i in 0..D {
            let a = AXES[i];
            add(
                format!("v.{a}"),
                "m/s",
                format!("velocity of the centre of mass in {a}"),
                Velocity,
                i,
            );
        }
        for i in torque_components(D) {
            let a = AXES[i];
            add(
                format!("w.{a}"),
                "rad/s",
                format!("angular velocity in {a} (space axes)"),
                AngularVelocity,
                i,
            );
        }
        if sys.body_has_wrench(b) {
            for i in 0..D {
                let a = AXES[i];
                let what = format!("wrench port's output, the mid-step velocity {step} in {a},");
                add(format!("vmid.{a}"), "m/s", what, MidVelocity, i);
            }
            for i in torque_components(D) {
                let a = AXES[i];
                let what = format!(
                    "wrench port's output, the mid-step angular velocity {step} in {a} (space axes),"
                );
                add(format!("wmid.{a}"), "rad/s", what, MidAngularVelocity, i);
            }
        }
        if sys.body_has_motion(b) {
            for i in 0..D {
                let a = AXES[i];
                let what = format!(
                    "force its prescribed motion exerts {step} in {a}, at the centre of mass,"
                );
                add(format!("RF.{a}"), "N", what, ReactionForce, i);
            }
            for i in torque_components(D) {
                let a = AXES[i];
                let what =
                    format!("torque its prescribed motion exerts {step} about {a} (space axes),");
                add(format!("RM.{a}"), "N.m", what, ReactionTorque, i);
            }
        }
    }
    vars
}
