//! The prescribed motion of a rigid body (`motion` or `motion_table` of `[bodies.NAME]`,
//! docs/scenario.md "Rigid bodies"): its absolute pose as expressions of `t` (position [m],
//! roll, pitch, yaw [deg]) or as a `[[platform]]` table (`t, x, y, z, roll, pitch, yaw` [s,
//! m, rad]), made into the library's [`BodyMotion`] (pose and its rate, docs/method.md §22).
//! Expressions' rates are the backward differences of a moving support's (`Motion::velocity`),
//! a table's are its interpolant's exact ones.

use std::sync::{Arc, Mutex};

use nalgebra::{Rotation3, UnitQuaternion};
use phstring::body::{BodyMotion, Vec3};
use phstring::signal::rotation;
use phstring::{Motion, PlatformPath};

use super::expr::{Expr, eval_or_record_at};
use super::spec::BodySpec;
use super::{ScenarioError, ScenarioFile};
use crate::text::{clip, num, nums};

/// Where a body's prescribed motion comes from (validated).
#[derive(Clone)]
pub(super) enum MotionSource {
    /// Expressions at `key` (`bodies.NAME.motion`): the position's `d` components [m] and the
    /// angles [deg] (roll, pitch, yaw in 3D; the angle about `z` in 2D), or, without
    /// orientation expressions, the constant angles `fixed` [deg] (roll, pitch, yaw).
    Exprs {
        key: String,
        position: Vec<Expr>,
        angles: Vec<Expr>,
        fixed: Vec3,
    },
    /// A platform table `file` and its path.
    Table {
        file: String,
        path: Arc<PlatformPath>,
    },
}

impl MotionSource {
    /// What `summary.json` and `phstring check` say the motion is: the expressions
    /// (position, then angles), or `["table FILE"]`.
    pub(super) fn texts(&self) -> Vec<String> {
        match self {
            Self::Exprs {
                position, angles, ..
            } => position
                .iter()
                .chain(angles)
                .map(|e| e.text().to_string())
                .collect(),
            Self::Table { file, .. } => vec![format!("table {}", clip(file))],
        }
    }

    /// The library's motion of a body in dimension `D`; an expression that fails (or is not
    /// finite) during the run gives NaN and is recorded in `slot`.
    pub(super) fn motion<const D: usize>(&self, slot: &Arc<Mutex<Option<String>>>) -> BodyMotion {
        match self {
            Self::Table { path, .. } => {
                let (p, v) = (path.clone(), path.clone());
                BodyMotion {
                    pose: Arc::new(move |t| {
                        let (x, rot) = p.pose(t);
                        (x, quaternion(&rot))
                    }),
                    twist: Arc::new(move |t| {
                        let s = v.state(t);
                        let w = s.rotation_rate * s.rotation.transpose();
                        (s.velocity, Vec3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]))
                    }),
                }
            }
            Self::Exprs {
                key,
                position,
                angles,
                fixed,
            } => {
                let channels = Arc::new(expr_channels::<D>(key, position, angles, fixed, slot));
                let c = channels.clone();
                BodyMotion {
                    pose: Arc::new(move |t| {
                        let a = |i: usize| (c[i].position)(t);
                        let rot = rotation(a(3), a(4), a(5));
                        (Vec3::new(a(0), a(1), a(2)), quaternion(&rot))
                    }),
                    twist: Arc::new(move |t| {
                        let rate = |i: usize| channels[i].velocity(t);
                        let a = |i: usize| (channels[i].position)(t);
                        let rx = rotation(a(3), 0.0, 0.0);
                        let rxy = rotation(a(3), a(4), 0.0);
                        // R = Rx Ry Rz: ω = φ̇ x + θ̇ Rx y + ψ̇ Rx Ry z (space axes).
                        let omega = Vec3::x() * rate(3)
                            + rx * Vec3::y() * rate(4)
                            + rxy * Vec3::z() * rate(5);
                        (Vec3::new(rate(0), rate(1), rate(2)), omega)
                    }),
                }
            }
        }
    }
}

/// The unit quaternion of the rotation matrix `rot`.
fn quaternion(rot: &nalgebra::Matrix3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rot))
}

/// The six channels `x, y, z` [m], `roll, pitch, yaw` [rad] of a motion's expressions (the
/// position's `D` components, angles [deg] or the constant `fixed` [deg]), as moving-support
/// signals whose velocity is their backward difference.
fn expr_channels<const D: usize>(
    key: &str,
    position: &[Expr],
    angles: &[Expr],
    fixed: &Vec3,
    slot: &Arc<Mutex<Option<String>>>,
) -> Vec<Motion> {
    let deg = std::f64::consts::PI / 180.0;
    let mut out = Vec::with_capacity(6);
    for c in 0..3 {
        match position.get(c) {
            Some(e) => {
                let (e, slot, what) = (e.clone(), slot.clone(), format!("{key}.position"));
                out.push(Motion::new(0, c, move |t| {
                    eval_or_record_at(&e, &slot, &what, c, t)
                }));
            }
            None => out.push(Motion::new(0, c, |_| 0.0)),
        }
    }
    // In 2D the one angle is about z (yaw).
    let first = if D == 2 { 2 } else { 0 };
    for c in 0..3usize {
        let expr = c.checked_sub(first).and_then(|i| angles.get(i));
        match expr {
            Some(e) => {
                let (e, slot, what) = (e.clone(), slot.clone(), format!("{key}.orientation"));
                out.push(Motion::new(0, 3 + c, move |t| {
                    eval_or_record_at(&e, &slot, &what, c, t) * deg
                }));
            }
            None => {
                let a = fixed[c] * deg;
                out.push(Motion::new(0, 3 + c, move |_| a));
            }
        }
    }
    out
}

impl ScenarioFile {
    /// The prescribed motion of the body at `key` (`spec`): `None` without `motion` and
    /// `motion_table`. Expressions are checked at `t_check` [s] and at `t = 0`; a table needs
    /// dimension 3. A body with a motion takes no wrench, `velocity` or `angular_velocity`.
    pub(super) fn body_motion_source<const D: usize>(
        &self,
        key: &str,
        spec: &BodySpec,
        t_check: f64,
    ) -> Result<Option<MotionSource>, ScenarioError> {
        let k = |f: &str| format!("{key}.{f}");
        let source = match (&spec.motion, &spec.motion_table) {
            (None, None) => return Ok(None),
            (Some(_), Some(t)) => {
                return Err(self.invalid(
                    &k("motion_table"),
                    t.span(),
                    "and `motion` both prescribe the body's motion: give one of them",
                ));
            }
            (None, Some(file)) => {
                if D != 3 {
                    return Err(self.invalid(
                        &k("motion_table"),
                        file.span(),
                        format!("is a platform table (x, y, z, roll, pitch, yaw), which needs dimension 3, but dimension = {D}: use `motion` expressions"),
                    ));
                }
                let table = self.scenario_table(&k("motion_table"), file, 7)?;
                let path = table
                    .platform()
                    .unwrap_or_else(|| unreachable!("read with 7 columns"));
                MotionSource::Table {
                    file: file.get_ref().clone(),
                    path: Arc::new(path),
                }
            }
            (Some(m), None) => {
                let m = m.get_ref();
                let mkey = k("motion");
                let position =
                    self.motion_exprs(&format!("{mkey}.position"), &m.position, D, t_check)?;
                let turns = if D == 2 { 1 } else { 3 };
                let angles = match &m.orientation {
                    Some(o) => {
                        self.motion_exprs(&format!("{mkey}.orientation"), o, turns, t_check)?
                    }
                    None => Vec::new(),
                };
                let fixed =
                    self.turn_vector(&k("orientation"), spec.orientation.as_ref(), turns)?;
                MotionSource::Exprs {
                    key: mkey,
                    position,
                    angles,
                    fixed,
                }
            }
        };
        let excluded = [
            (
                "wrench",
                spec.wrench.as_ref().map(|w| w.span()),
                "a wrench port (its port is the motion: the reaction wrench is its output)",
            ),
            (
                "velocity",
                spec.velocity.as_ref().map(|v| v.span()),
                "a velocity (the motion gives it)",
            ),
            (
                "angular_velocity",
                spec.angular_velocity.as_ref().map(|v| v.span()),
                "an angular velocity (the motion gives it)",
            ),
        ];
        if let Some((f, Some(span), what)) = excluded.into_iter().find(|(_, s, _)| s.is_some()) {
            return Err(self.invalid(
                &k(f),
                span,
                format!("is given, but the body has a prescribed motion, which takes no {what}: remove `{f}`"),
            ));
        }
        Ok(Some(source))
    }

    /// `n` expressions of `t` at `key`, each valid at `t_check` and at `t = 0` [s].
    fn motion_exprs(
        &self,
        key: &str,
        list: &toml::Spanned<Vec<toml::Spanned<String>>>,
        n: usize,
        t_check: f64,
    ) -> Result<Vec<Expr>, ScenarioError> {
        if list.get_ref().len() != n {
            return Err(self.invalid(
                key,
                list.span(),
                format!("must have {n} expressions, got {}", list.get_ref().len()),
            ));
        }
        let mut out = Vec::with_capacity(n);
        for (i, e) in list.get_ref().iter().enumerate() {
            let ekey = format!("{key}.{i}");
            let expr =
                Expr::new(e.get_ref(), t_check).map_err(|m| self.invalid(&ekey, e.span(), m))?;
            match expr.eval(0.0) {
                Ok(x) if x.is_finite() => {}
                Ok(x) => {
                    return Err(self.invalid(
                        &ekey,
                        e.span(),
                        format!("= \"{}\" is {} at t = 0", clip(e.get_ref()), num(x)),
                    ));
                }
                Err(m) => {
                    return Err(self.invalid(
                        &ekey,
                        e.span(),
                        format!("= \"{}\" fails at t = 0: {m}", clip(e.get_ref())),
                    ));
                }
            }
            out.push(expr);
        }
        Ok(out)
    }

    /// The start of the body at `key` with the motion `source`: its pose and rates at
    /// `t = 0`, `(position [m], orientation, velocity [m/s], angular velocity [rad/s] in space
    /// axes)`. The body's `position` must be the motion's at `t = 0` (to
    /// `1e-9·max(1, |x|)` m per component, the tolerance of a moving support), and its
    /// `orientation`, when given, the motion's (to 1e-9 rad).
    pub(super) fn motion_start<const D: usize>(
        &self,
        key: &str,
        spec: &BodySpec,
        source: &MotionSource,
        position: &Vec3,
        orientation: &UnitQuaternion<f64>,
    ) -> Result<(Vec3, UnitQuaternion<f64>, Vec3, Vec3), ScenarioError> {
        let slot = Arc::new(Mutex::new(None));
        let motion = source.motion::<D>(&slot);
        let ((x, q), (v, w)) = ((motion.pose)(0.0), (motion.twist)(0.0));
        let mkey = match source {
            MotionSource::Exprs { .. } => format!("{key}.motion"),
            MotionSource::Table { .. } => format!("{key}.motion_table"),
        };
        let mspan = spec
            .motion
            .as_ref()
            .map(|m| m.span())
            .or(spec.motion_table.as_ref().map(|m| m.span()))
            .unwrap_or(0..0);
        let finite = x
            .iter()
            .chain(v.iter())
            .chain(w.iter())
            .all(|c| c.is_finite());
        if !finite {
            let why = slot.lock().ok().and_then(|s| s.clone()).unwrap_or_default();
            return Err(self.invalid(
                &mkey,
                mspan,
                format!("has no finite pose and rate at t = 0: {why}"),
            ));
        }
        let scale = x.norm().max(1.0);
        if (x - position).amax() > super::tables::START_TOLERANCE * scale {
            return Err(self.invalid(
                &format!("{key}.position"),
                spec.position.span(),
                format!(
                    "= {} m, but the body's prescribed motion (`{mkey}`) starts at {} m: write the motion's position at t = 0 into `position`",
                    nums(&position.as_slice()[..D]),
                    nums(&x.as_slice()[..D])
                ),
            ));
        }
        if let Some(o) = &spec.orientation {
            let off = q.angle_to(orientation);
            if off > 1e-9 {
                return Err(self.invalid(
                    &format!("{key}.orientation"),
                    o.span(),
                    format!(
                        "= {} deg is {} rad from the orientation at t = 0 of the body's prescribed motion (`{mkey}`): write the motion's angles at t = 0 (in degrees) or leave `orientation` out",
                        nums(o.get_ref()),
                        num(off)
                    ),
                ));
            }
        }
        Ok((x, q, v, w))
    }
}
