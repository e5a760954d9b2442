//! Validation of the parts shared by every scenario that are not components: `[body_force]`,
//! `[time]`, `[newton]` and `[output]`.

use phstring::{NewtonParams, Predictor, Scheme, SolverKind, StepControl, StepParams, Vector};

use super::{RunSettings, ScenarioError, ScenarioFile};
use crate::text::{clip, num};

/// Most planned steps (`time.end / time.h`) of a run: 1e10 steps take days even on the
/// smallest mesh.
pub const MAX_STEPS: f64 = 1e10;

/// The validated `[body_force]`.
#[derive(Debug, Clone, Copy)]
pub(super) struct BodyForce<const D: usize> {
    /// `body_force.gravity` [m/s²], if given.
    pub gravity: Option<Vector<D>>,
    /// `body_force.per_length` [N/m], if given.
    pub per_length: Option<Vector<D>>,
}

impl<const D: usize> BodyForce<D> {
    /// Gravity [m/s²] (zero if not given).
    pub fn g(&self) -> Vector<D> {
        self.gravity.unwrap_or_else(Vector::zeros)
    }
    /// The body force per unit reference length of a string of mass per length `rho_a`
    /// [kg/m]: `rho_a · gravity + per_length` [N/m] (added in this order to zero, as the
    /// single-string validation always did, so that results stay bit-identical).
    pub fn on_string(&self, rho_a: f64) -> Vector<D> {
        let mut body = Vector::<D>::zeros();
        if let Some(g) = self.gravity {
            body += g * rho_a;
        }
        if let Some(pl) = self.per_length {
            body += pl;
        }
        body
    }
}

/// The validated `[time]` table.
struct Time {
    h: f64,
    t_end: f64,
    scheme: Scheme,
    max_halvings: u32,
}

/// The validated `[newton]` table.
struct Newton {
    params: NewtonParams,
    solver: SolverKind,
    predictor: Predictor,
}

impl ScenarioFile {
    /// `[body_force]`: vectors of `dimension` finite components.
    pub(super) fn body_force<const D: usize>(&self) -> Result<BodyForce<D>, ScenarioError> {
        let b = &self.scenario.body_force;
        let gravity = match &b.gravity {
            Some(g) => Some(self.vector::<D>("body_force.gravity", g)?),
            None => None,
        };
        let per_length = match &b.per_length {
            Some(p) => Some(self.vector::<D>("body_force.per_length", p)?),
            None => None,
        };
        Ok(BodyForce {
            gravity,
            per_length,
        })
    }

    /// The time at which expressions are first evaluated: the mid time `h/2` of the first
    /// step (0 if `time.h` is invalid; that error is reported by [`Self::run_settings`]).
    pub(super) fn first_mid_time(&self) -> f64 {
        match *self.scenario.time.h.get_ref() {
            h if h > 0.0 && h.is_finite() => 0.5 * h,
            _ => 0.0,
        }
    }

    /// `[time]`: positive `h` and `end`, a whole number of steps (at most [`MAX_STEPS`]).
    fn time(&self) -> Result<Time, ScenarioError> {
        let s = &self.scenario.time;
        let h = self.positive("time.h", &s.h)?;
        let t_end = self.positive("time.end", &s.end)?;
        let steps = (t_end / h).round();
        if steps > MAX_STEPS {
            return Err(self.invalid(
                "time.h",
                s.h.span(),
                format!(
                    "= {} gives {} steps up to time.end = {}; at most {MAX_STEPS:.0e} are allowed (use a larger time.h or a shorter time.end)",
                    num(h),
                    if steps.is_finite() {
                        format!("{steps:.2e}")
                    } else {
                        "too many".to_string()
                    },
                    num(t_end)
                ),
            ));
        }
        if steps < 1.0 || ((steps * h) - t_end).abs() > 1e-9 * t_end {
            return Err(self.invalid(
                "time.h",
                s.h.span(),
                format!(
                    "= {} does not divide time.end = {} into a whole number of steps",
                    num(h),
                    num(t_end)
                ),
            ));
        }
        let scheme = match s.scheme.get_ref().as_str() {
            "dg" => Scheme::DiscreteGradient,
            "mp" => Scheme::Midpoint,
            "dg4" => Scheme::DiscreteGradient4,
            other => {
                return Err(self.invalid(
                    "time.scheme",
                    s.scheme.span(),
                    format!("must be dg, mp or dg4, got \"{}\"", clip(other)),
                ));
            }
        };
        let mh = *s.max_halvings.get_ref();
        if !(0..=40).contains(&mh) {
            return Err(self.invalid(
                "time.max_halvings",
                s.max_halvings.span(),
                format!("must be between 0 and 40, got {mh}"),
            ));
        }
        Ok(Time {
            h,
            t_end,
            scheme,
            max_halvings: mh as u32,
        })
    }

    /// `time.error_per_step` for the step control `control` (its tolerances read): given
    /// `true`, error control must be on.
    fn error_per_step(&self, control: &StepControl) -> Result<bool, ScenarioError> {
        let Some(e) = &self.scenario.time.error_per_step else {
            return Ok(false);
        };
        if *e.get_ref() && !control.error_control() {
            return Err(self.invalid(
                "time.error_per_step",
                e.span(),
                "= true needs error control: give time.atol (and/or time.rtol) > 0".to_string(),
            ));
        }
        Ok(*e.get_ref())
    }

    /// `[newton]`: tolerances, iteration limit, solver and predictor names.
    fn newton(&self) -> Result<Newton, ScenarioError> {
        let s = &self.scenario.newton;
        let tol = match &s.tol {
            Some(t) => Some(self.positive("newton.tol", t)?),
            None => None,
        };
        let rtol = match &s.rtol {
            Some(r) => {
                let x = *r.get_ref();
                if !(0.0..1.0).contains(&x) {
                    return Err(self.invalid(
                        "newton.rtol",
                        r.span(),
                        format!("must be at least 0 and below 1, got {}", phstring::Num(x)),
                    ));
                }
                Some(x)
            }
            None => None,
        };
        // `tol` alone: absolute test; otherwise relative with `tol` (or the default) as floor.
        let (tol, rtol) = match (tol, rtol) {
            (Some(t), None) => (t, 0.0),
            (t, r) => (
                t.unwrap_or(phstring::newton::DEFAULT_ATOL),
                r.unwrap_or(phstring::newton::DEFAULT_RTOL),
            ),
        };
        let max_iter = *s.max_iter.get_ref();
        if !(1..=10_000).contains(&max_iter) {
            return Err(self.invalid(
                "newton.max_iter",
                s.max_iter.span(),
                format!("must be between 1 and 10000, got {max_iter}"),
            ));
        }
        let solver = match s.solver.get_ref().as_str() {
            "auto" => SolverKind::Auto,
            "block_tridiagonal" => SolverKind::BlockTridiagonal,
            "sparse_lu" => SolverKind::SparseLu,
            "network" => SolverKind::Network,
            other => {
                return Err(self.invalid(
                    "newton.solver",
                    s.solver.span(),
                    format!(
                        "must be auto, block_tridiagonal, sparse_lu or network, got \"{}\"",
                        clip(other)
                    ),
                ));
            }
        };
        let predictor = match s.predictor.get_ref().as_str() {
            "velocity" => Predictor::Velocity,
            "acceleration" => Predictor::Acceleration,
            "midpoint_velocity" => Predictor::MidpointVelocity,
            other => {
                return Err(self.invalid(
                    "newton.predictor",
                    s.predictor.span(),
                    format!(
                        "must be velocity, acceleration or midpoint_velocity, got \"{}\"",
                        clip(other)
                    ),
                ));
            }
        };
        Ok(Newton {
            params: NewtonParams {
                tol,
                rtol,
                max_iter: max_iter as usize,
                progress_extension: NewtonParams::default().progress_extension,
                line_search: s.line_search,
                elimination: s.elimination,
            },
            solver,
            predictor,
        })
    }

    /// `[output]`: the stride (the switches need no check).
    fn output_stride(&self) -> Result<usize, ScenarioError> {
        let stride = &self.scenario.output.stride;
        match *stride.get_ref() {
            n if n >= 1 => Ok(n as usize),
            n => Err(self.invalid(
                "output.stride",
                stride.span(),
                format!("must be at least 1, got {n}"),
            )),
        }
    }

    /// `output.channels` and `output.channels_file`: every channel name reads (see
    /// [`crate::channels`]) as a quantity that is written, and the file is a plain name.
    /// Whether the lines and points they name exist is checked when the run starts.
    fn output_channels(&self) -> Result<(), ScenarioError> {
        let out = &self.scenario.output;
        for (i, c) in out.channels.iter().enumerate() {
            let key = format!("output.channels.{i}");
            match crate::channels::parse(c.get_ref()) {
                Err(reason) => return Err(self.invalid(&key, c.span(), reason)),
                Ok(ch) => {
                    if let crate::channels::Quantity::NotWritten(why) = ch.quantity {
                        return Err(self.invalid(
                            &key,
                            c.span(),
                            format!("= {:?}: not written: {why}", ch.name),
                        ));
                    }
                }
            }
        }
        if let Some(f) = &out.channels_file {
            let name = f.get_ref();
            if !crate::files::is_channel_table(name) {
                return Err(self.invalid(
                    "output.channels_file",
                    f.span(),
                    format!("= {name:?} must be a plain file name ending in .out (no folder), as MoorDyn's tables"),
                ));
            }
        }
        Ok(())
    }

    /// The run settings: `[time]`, `[newton]` and `[output]`; `chain`: whether the mesh is a
    /// chain (element `e` joins nodes `e` and `e+1`: a single string, or a network numbered
    /// like one), which `newton.solver = "block_tridiagonal"` needs.
    pub(super) fn run_settings(&self, chain: bool) -> Result<RunSettings, ScenarioError> {
        let time = self.time()?;
        let newton = self.newton()?;
        if !chain && newton.solver == SolverKind::BlockTridiagonal {
            return Err(self.invalid(
                "newton.solver",
                self.scenario.newton.solver.span(),
                "= block_tridiagonal solves chains (element e joining nodes e and e+1, as one string) only: use auto, network or sparse_lu for this network",
            ));
        }
        let stride = self.output_stride()?;
        let row_stride = match &self.scenario.output.row_stride {
            None => 1,
            Some(r) => match *r.get_ref() {
                n if n >= 1 => usize::try_from(n).unwrap_or(usize::MAX),
                n => {
                    return Err(self.invalid(
                        "output.row_stride",
                        r.span(),
                        format!("must be at least 1, got {n}"),
                    ));
                }
            },
        };
        self.output_channels()?;
        let output = self.scenario.output.clone();
        let mut control = StepControl {
            adaptive: self.scenario.time.adaptive,
            max_halvings: time.max_halvings,
            rtol: self.non_negative("time.rtol", self.scenario.time.rtol.as_ref())?,
            atol: self.non_negative("time.atol", self.scenario.time.atol.as_ref())?,
            ..Default::default()
        };
        control.error_per_step = self.error_per_step(&control)?;
        Ok(RunSettings {
            step: StepParams {
                h: time.h,
                scheme: time.scheme,
                newton: newton.params,
                solver: newton.solver,
                predictor: newton.predictor,
                control,
            },
            t_end: time.t_end,
            settle: match &self.scenario.time.settle {
                None => None,
                Some(s) => {
                    let s = s.get_ref();
                    Some(phstring::Settle {
                        kinetic: self.positive("time.settle.kinetic", &s.kinetic)?,
                        hold: self.non_negative("time.settle.hold", s.hold.as_ref())?,
                    })
                }
            },
            stride,
            row_stride,
            animation: output.animation,
            output,
        })
    }
}
