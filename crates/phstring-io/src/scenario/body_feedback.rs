//! The feedback law of a rigid body (`feedback` of `[bodies.NAME]`, docs/scenario.md "Rigid
//! bodies"): PD on the body's pose with damping (gains per space axis), the reference pose
//! as expressions of `t` (position [m], roll, pitch, yaw [deg]; default: the body's initial
//! pose), made into the library's [`BodyFeedback`] (docs/method.md §22). The reference's
//! rates are the expressions' backward differences, as a body motion's.

use std::sync::{Arc, Mutex};

use phstring::BodyFeedback;
use phstring::body::Vec3;

use super::body_motion::MotionSource;
use super::expr::Expr;
use super::spec::{BodyFeedbackSpec, GainSpec};
use super::{ScenarioError, ScenarioFile};
use crate::text::num;

/// A validated body feedback: its gains and its reference (expressions).
#[derive(Clone)]
pub(super) struct FeedbackSource {
    /// `(kp [N/m], kd [N·s/m], kp_turn [N·m/rad], kd_turn [N·m·s/rad])` per space axis.
    gains: [Vec3; 4],
    /// The reference pose (expressions, or constants).
    reference: MotionSource,
}

impl FeedbackSource {
    /// The library's law; a reference expression that fails during the run gives NaN and is
    /// recorded in `slot` (the step then fails on a non-finite reference).
    pub(super) fn law<const D: usize>(&self, slot: &Arc<Mutex<Option<String>>>) -> BodyFeedback {
        let motion = self.reference.motion::<D>(slot);
        let [kp, kd, kp_turn, kd_turn] = self.gains;
        BodyFeedback {
            kp,
            kd,
            kp_turn,
            kd_turn,
            reference: motion.pose,
            reference_rate: motion.twist,
        }
    }

    /// What `check` and `summary.json` say: the gains, then the reference position [m] and
    /// orientation [deg] (expressions, or the constant angles).
    pub(super) fn texts(&self) -> Vec<String> {
        let names = [
            "kp [N/m]",
            "kd [N·s/m]",
            "kp_turn [N·m/rad]",
            "kd_turn [N·m·s/rad]",
        ];
        let mut out: Vec<String> = names
            .iter()
            .zip(&self.gains)
            .map(|(n, g)| format!("{n} = [{}, {}, {}]", num(g.x), num(g.y), num(g.z)))
            .collect();
        if let MotionSource::Exprs {
            position,
            angles,
            fixed,
            ..
        } = &self.reference
        {
            let list = |l: &[Expr]| l.iter().map(|e| e.text().to_string()).collect::<Vec<_>>();
            let angles = if angles.is_empty() {
                fixed.iter().map(|a| num(*a).to_string()).collect()
            } else {
                list(angles)
            };
            out.push(format!(
                "reference position [{}] m",
                list(position).join(", ")
            ));
            out.push(format!("orientation [{}] deg", angles.join(", ")));
        }
        out
    }
}

impl ScenarioFile {
    /// The feedback of the body at `key` (`spec`, `None` without one), whose initial pose is
    /// `position` [m] and `angles` [deg] (roll, pitch, yaw; the reference's default).
    /// Expressions are checked at `t_check` [s].
    pub(super) fn body_feedback_source<const D: usize>(
        &self,
        key: &str,
        spec: &toml::Spanned<BodyFeedbackSpec>,
        (position, angles): (&Vec3, &Vec3),
        t_check: f64,
    ) -> Result<FeedbackSource, ScenarioError> {
        let fkey = format!("{key}.feedback");
        let f = spec.get_ref();
        let turns = if D == 2 { 1 } else { 3 };
        let gains = [
            self.body_gain::<D>(&fkey, "kp", f.kp.as_ref(), D)?,
            self.body_gain::<D>(&fkey, "kd", f.kd.as_ref(), D)?,
            self.body_gain::<D>(&fkey, "kp_turn", f.kp_turn.as_ref(), turns)?,
            self.body_gain::<D>(&fkey, "kd_turn", f.kd_turn.as_ref(), turns)?,
        ];
        if gains.iter().all(|g| *g == Vec3::zeros()) {
            return Err(self.invalid(
                &fkey,
                spec.span(),
                "has all gains 0 (or none): give kp, kd, kp_turn or kd_turn",
            ));
        }
        let constant = |x: f64| {
            // Rust prints a float in plain decimal digits, which the expressions read back.
            Expr::new(&format!("{x}"), t_check).unwrap_or_else(|_| unreachable!("a number"))
        };
        let position = match &f.position {
            Some(p) => self.wrench_exprs(&format!("{fkey}.position"), Some(p), D, t_check)?,
            None => (0..D).map(|k| constant(position[k])).collect(),
        };
        let angle_exprs = match &f.orientation {
            Some(o) => {
                self.wrench_exprs(&format!("{fkey}.orientation"), Some(o), turns, t_check)?
            }
            None => Vec::new(),
        };
        Ok(FeedbackSource {
            gains,
            reference: MotionSource::Exprs {
                key: fkey,
                position,
                angles: angle_exprs,
                fixed: *angles,
            },
        })
    }

    /// The gain `name` of `[bodies.NAME] feedback` (`fkey`): one number for every axis, or
    /// `n` numbers (the space axes; in 2D `x`, `y` for a translation and the one about `z`
    /// for a turn); ≥ 0 and finite; default 0.
    fn body_gain<const D: usize>(
        &self,
        fkey: &str,
        name: &str,
        gain: Option<&toml::Spanned<GainSpec>>,
        n: usize,
    ) -> Result<Vec3, ScenarioError> {
        let Some(g) = gain else {
            return Ok(Vec3::zeros());
        };
        let key = format!("{fkey}.{name}");
        let list: Vec<f64> = match g.get_ref() {
            GainSpec::One(x) => vec![*x; n],
            GainSpec::Each(list) if list.len() == n => list.clone(),
            GainSpec::Each(list) => {
                return Err(self.invalid(
                    &key,
                    g.span(),
                    format!(
                        "must be one number or {n} (dimension = {D}), got {}",
                        list.len()
                    ),
                ));
            }
        };
        if let Some(x) = list.iter().find(|x| !(**x >= 0.0 && x.is_finite())) {
            return Err(self.invalid(
                &key,
                g.span(),
                format!("must be at least 0 and finite, got {}", num(*x)),
            ));
        }
        // A turn's one gain in 2D is about z.
        let first = if n == 1 && D == 2 { 2 } else { 0 };
        let mut out = Vec3::zeros();
        for (k, x) in list.iter().enumerate() {
            out[first + k] = *x;
        }
        Ok(out)
    }
}
