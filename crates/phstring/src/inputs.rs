//! Inputs set from outside a run: a controller, a co-simulation master (the FMU) or a script
//! sets the input of a port between steps and the simulation holds it.
//!
//! * A **held force** on a load port ([`Simulation::set_load_force`]): the load's force is
//!   the value set [N], constant over the following steps until it is set again or released
//!   (zero-order hold). The stepper samples it at the mid-step like any load, so the port's
//!   power `û·ŷ` and the energy balance are those of a load with that constant force.
//! * A **position target** on a moving support ([`Simulation::set_motion_target`]): the
//!   support moves on a straight [`PositionRamp`] from where it is now to the target [m],
//!   reached at a given time [s] and held after it. The support's velocity state follows
//!   [`Motion::velocity`] of the ramp (its slope, from the left) and the energy it supplies is
//!   accounted as for any prescribed motion (docs/method.md §14).
//!
//! * A **payout speed** of a winch ([`Simulation::set_winch_speed`]): from the current time
//!   on the winch pays out at that speed [m/s] (negative: hauls in), its payout continuing
//!   from where it is (zero-order hold of the speed). Its energy is booked as for any payout
//!   (docs/method.md §23).
//!
//! Before a run, [`NodalLoad::hold`] and [`Motion::hold`] hold the same inputs on the
//! boundary conditions of a problem, e.g. to find a starting equilibrium under them, and
//! [`PhSystem::hold_body_wrench`] a rigid body's wrench on a built system.
//!
//! Loads are numbered in the order of [`Boundary::loads`](crate::Boundary::loads) (load `k`
//! is port `k` of [`Simulation::ports`]), motions in the order of
//! [`Boundary::motions`](crate::Boundary::motions). Held inputs are not part of a
//! [`Checkpoint`](crate::Checkpoint): a caller that restores one sets its inputs again.

use std::sync::Arc;

use thiserror::Error;

use crate::boundary::{HeldForce, HeldMotion, Motion, NodalLoad, PositionRamp};
use crate::error::Num;
use crate::material::StoredEnergy;
use crate::simulation::Simulation;
use crate::system::{PhSystem, Vector};

/// A refused input: nothing was changed.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum InputError {
    /// The load index is not one of the problem's loads.
    #[error("load port {load} does not exist: the problem has {count} loads{}", range(*count))]
    NoSuchLoad {
        /// The index given.
        load: usize,
        /// Number of loads.
        count: usize,
    },
    /// The motion index is not one of the problem's prescribed motions.
    #[error("motion {motion} does not exist: the problem has {count} prescribed motions{}", range(*count))]
    NoSuchMotion {
        /// The index given.
        motion: usize,
        /// Number of motions.
        count: usize,
    },
    /// A component of a held force is not finite.
    #[error("the force of load port {load} must be finite, got {} in component {component}", Num(*value))]
    ForceNotFinite {
        /// Load index.
        load: usize,
        /// Component (0 = x).
        component: usize,
        /// The value given [N].
        value: f64,
    },
    /// A position target, the time it is to be reached at, or a ramp's end point is not
    /// finite.
    #[error("the {what} of motion {motion} must be finite, got {}", Num(*value))]
    MotionNotFinite {
        /// Motion index.
        motion: usize,
        /// Which value (`position target`, `target time`, …).
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// The winch index is not one of the problem's winches.
    #[error("winch {winch} does not exist: the problem has {count} winches{}", range(*count))]
    NoSuchWinch {
        /// The index given.
        winch: usize,
        /// Number of winches.
        count: usize,
    },
    /// A winch's held speed is not finite.
    #[error("the payout speed of winch {winch} must be finite, got {} m/s", Num(*value))]
    WinchSpeedNotFinite {
        /// Winch index.
        winch: usize,
        /// The value given [m/s].
        value: f64,
    },
    /// A winch input that does not fit its drive: a held payout speed for a drum with
    /// dynamics (its payout is a state), or a motor pull for a prescribed payout.
    #[error("winch {winch} {why}")]
    WinchDrive {
        /// Winch index.
        winch: usize,
        /// What does not fit.
        why: &'static str,
    },
    /// A winch's held motor pull is not finite.
    #[error("the motor pull of winch {winch} must be finite, got {} N", Num(*value))]
    WinchForceNotFinite {
        /// Winch index.
        winch: usize,
        /// The value given [N].
        value: f64,
    },
    /// The body index is not one of the problem's rigid bodies.
    #[error("body {body} does not exist: the problem has {count} rigid bodies{}", range(*count))]
    NoSuchBody {
        /// The index given.
        body: usize,
        /// Number of bodies.
        count: usize,
    },
    /// A body's held wrench is not finite, or the body's motion is prescribed (its port is
    /// the motion).
    #[error("the wrench of body {body} cannot be held: {why}")]
    BodyWrench {
        /// Body index.
        body: usize,
        /// Why, with the value.
        why: String,
    },
    /// A ramp ends before it starts.
    #[error("the ramp of motion {motion} ends at t = {} s, before it starts at t = {} s", Num(*t1), Num(*t0))]
    RampBackwards {
        /// Motion index.
        motion: usize,
        /// Start [s].
        t0: f64,
        /// End [s].
        t1: f64,
    },
}

/// ` (0 … n−1)` for `n > 0`.
fn range(count: usize) -> String {
    match count {
        0 => String::new(),
        n => format!(" (0 … {})", n - 1),
    }
}

/// Why `ramp` cannot be followed by motion `motion`, if it cannot.
fn check_ramp(ramp: &PositionRamp, motion: usize) -> Result<(), InputError> {
    for (what, value) in [
        ("ramp start time", ramp.t0),
        ("ramp end time", ramp.t1),
        ("ramp start position", ramp.from),
        ("position target", ramp.to),
    ] {
        if !value.is_finite() {
            return Err(InputError::MotionNotFinite {
                motion,
                what,
                value,
            });
        }
    }
    if ramp.t1 < ramp.t0 {
        return Err(InputError::RampBackwards {
            motion,
            t0: ramp.t0,
            t1: ramp.t1,
        });
    }
    Ok(())
}

impl<const D: usize> NodalLoad<D> {
    /// Holds the force at `force` [N] at all times: the load's signal becomes that constant.
    pub fn hold(&mut self, force: Vector<D>) {
        self.force = Arc::new(move |_t| force);
    }
}

impl Motion {
    /// Makes the motion follow `ramp`: its position signal becomes [`PositionRamp::position`]
    /// (its velocity the backward difference of the ramp, which is exact on it).
    pub fn hold(&mut self, ramp: PositionRamp) {
        self.position = Arc::new(move |t| ramp.position(t));
        self.rate = None;
    }
}

impl<const D: usize, M> PhSystem<D, M> {
    /// Holds the force of load `load` at `force` [N] before a simulation starts (a starting
    /// equilibrium under an input): [`NodalLoad::hold`] on the built system. A simulation
    /// started from it registers the input with [`Simulation::set_load_force`]. Refused
    /// (nothing changes) for an unknown load or a non-finite component.
    pub fn hold_load_force(&mut self, load: usize, force: Vector<D>) -> Result<(), InputError> {
        let count = self.boundary.loads.len();
        if load >= count {
            return Err(InputError::NoSuchLoad { load, count });
        }
        check_force(&force, load)?;
        self.boundary.loads[load].hold(force);
        Ok(())
    }

    /// Holds support `motion` on `ramp` before a simulation starts: [`Motion::hold`] on the
    /// built system. A simulation started from it registers the ramp with
    /// [`Simulation::set_motion_ramp`]. Refused (nothing changes) for an unknown motion, a
    /// non-finite ramp or one that ends before it starts.
    pub fn hold_motion(&mut self, motion: usize, ramp: PositionRamp) -> Result<(), InputError> {
        let count = self.boundary.motions.len();
        if motion >= count {
            return Err(InputError::NoSuchMotion { motion, count });
        }
        check_ramp(&ramp, motion)?;
        self.boundary.motions[motion].hold(ramp);
        Ok(())
    }

    /// Holds body `body`'s wrench port at `force` [N] and `torque` [N·m] (space axes, at the
    /// centre of mass) before a simulation starts (a starting equilibrium under an input: the
    /// statics take the port's wrench at `t = 0`); a body without a wrench port gets one. A
    /// simulation started from it registers the input with [`Simulation::set_body_wrench`]
    /// (whose release then returns to this held wrench, not to the scenario's). Refused
    /// (nothing changes) for an unknown body, a body whose motion is prescribed, or a
    /// non-finite component.
    pub fn hold_body_wrench(
        &mut self,
        body: usize,
        force: crate::body::Vec3,
        torque: crate::body::Vec3,
    ) -> Result<(), InputError> {
        let model = wrench_target(&mut self.bodies, body, &force, &torque)?;
        model.wrench = Some(crate::body::BodyWrench {
            force: Arc::new(move |_t| force),
            torque: Arc::new(move |_t| torque),
        });
        Ok(())
    }
}

/// Refuses a force with a non-finite component (load `load`).
fn check_force<const D: usize>(force: &Vector<D>, load: usize) -> Result<(), InputError> {
    match force.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        Some((component, &value)) => Err(InputError::ForceNotFinite {
            load,
            component,
            value,
        }),
        None => Ok(()),
    }
}

impl<const D: usize, M: StoredEnergy> Simulation<D, M> {
    /// Index check of load `load`.
    fn load_index(&self, load: usize) -> Result<usize, InputError> {
        let count = self.system().boundary().loads.len();
        if load < count {
            Ok(load)
        } else {
            Err(InputError::NoSuchLoad { load, count })
        }
    }

    /// Index check of motion `motion`.
    fn motion_index(&self, motion: usize) -> Result<usize, InputError> {
        let count = self.system().boundary().motions.len();
        if motion < count {
            Ok(motion)
        } else {
            Err(InputError::NoSuchMotion { motion, count })
        }
    }

    /// Holds the force of load `load` (port `load`) at `force` [N] from the next step on,
    /// until it is set again or released (zero-order hold). The step samples it at the
    /// mid-step like the load's own signal, so a held force gives the step of a constant
    /// force signal bit for bit, and its power enters the supplied energy the same way.
    /// Refused (nothing changes) for an unknown load or a non-finite component.
    pub fn set_load_force(&mut self, load: usize, force: Vector<D>) -> Result<(), InputError> {
        let load = self.load_index(load)?;
        check_force(&force, load)?;
        let (inputs, boundary) = self.inputs_and_boundary();
        let nodal = &mut boundary.loads[load];
        let slots = grow(&mut inputs.loads, load);
        let signal = match slots[load].take() {
            Some(held) => held.signal,
            None => nodal.force.clone(),
        };
        nodal.hold(force);
        slots[load] = Some(HeldForce { force, signal });
        Ok(())
    }

    /// Returns load `load` to the signal it had before [`Self::set_load_force`] from the
    /// next step on (nothing to do if it is not held). Refused for an unknown load.
    pub fn release_load_force(&mut self, load: usize) -> Result<(), InputError> {
        let load = self.load_index(load)?;
        let (inputs, boundary) = self.inputs_and_boundary();
        if let Some(held) = inputs.loads.get_mut(load).and_then(Option::take) {
            boundary.loads[load].force = held.signal;
        }
        Ok(())
    }

    /// The force [N] load `load` is held at, if it is held.
    pub fn held_load_force(&self, load: usize) -> Option<Vector<D>> {
        self.held_inputs()
            .loads
            .get(load)
            .and_then(|h| h.as_ref().map(|h| h.force))
    }

    /// Moves support `motion` on a straight ramp from where it is now (its position signal
    /// at [`Self::time`]) to `target` [m], reached at time `t_target` [s] and held from then
    /// on: the co-simulation semantics of a position input over the next communication
    /// interval. The support's velocity state follows the ramp's slope (from the left, see
    /// [`Motion::velocity`]) and its supplied energy enters the balance as for any motion.
    /// Returns the ramp. Refused (nothing changes) for an unknown motion, a non-finite
    /// target or time, or `t_target` before the current time.
    pub fn set_motion_target(
        &mut self,
        motion: usize,
        target: f64,
        t_target: f64,
    ) -> Result<PositionRamp, InputError> {
        let motion = self.motion_index(motion)?;
        let now = self.time();
        let here = (self.system().boundary().motions[motion].position)(now);
        let ramp = PositionRamp {
            t0: now,
            t1: t_target,
            from: here,
            to: target,
        };
        self.set_motion_ramp(motion, ramp)?;
        Ok(ramp)
    }

    /// Makes support `motion` follow `ramp` from the next step on (to put back a ramp saved
    /// with [`Self::motion_ramp`], or to register one held before the run with
    /// [`Motion::hold`]). Refused (nothing changes) for an unknown motion, a non-finite
    /// ramp or one that ends before it starts.
    pub fn set_motion_ramp(&mut self, motion: usize, ramp: PositionRamp) -> Result<(), InputError> {
        let motion = self.motion_index(motion)?;
        check_ramp(&ramp, motion)?;
        let (inputs, boundary) = self.inputs_and_boundary();
        let m = &mut boundary.motions[motion];
        let slots = grow(&mut inputs.motions, motion);
        let (signal, rate) = match slots[motion].take() {
            Some(held) => (held.signal, held.rate),
            None => (m.position.clone(), m.rate.clone()),
        };
        m.hold(ramp);
        slots[motion] = Some(HeldMotion { ramp, signal, rate });
        Ok(())
    }

    /// The ramp support `motion` follows, if one was set on this simulation.
    pub fn motion_ramp(&self, motion: usize) -> Option<PositionRamp> {
        self.held_inputs()
            .motions
            .get(motion)
            .and_then(|h| h.as_ref().map(|h| h.ramp))
    }

    /// Returns support `motion` to the position signal it had before its first ramp was
    /// set (nothing to do if it has none). The signal should continue where the ramp is, or
    /// the next step jumps. Refused for an unknown motion.
    pub fn release_motion(&mut self, motion: usize) -> Result<(), InputError> {
        let motion = self.motion_index(motion)?;
        let (inputs, boundary) = self.inputs_and_boundary();
        if let Some(held) = inputs.motions.get_mut(motion).and_then(Option::take) {
            boundary.motions[motion].position = held.signal;
            boundary.motions[motion].rate = held.rate;
        }
        Ok(())
    }
}

/// `slots` with at least `i + 1` entries (new ones `None`).
fn grow<T>(slots: &mut Vec<Option<T>>, i: usize) -> &mut Vec<Option<T>> {
    if slots.len() <= i {
        slots.resize_with(i + 1, || None);
    }
    slots
}

impl<const D: usize, M: StoredEnergy> Simulation<D, M> {
    /// Holds body `body`'s wrench port at `force` [N] and `torque` [N·m] (space axes) from the
    /// next step on, until it is set again or released (zero-order hold); a body without a
    /// wrench port gets one. The step samples it like a signal, so a held wrench gives the
    /// step of a constant wrench bit for bit, and its work enters the supplied energy the
    /// same way. Refused (nothing changes) for an unknown body, a body whose motion is
    /// prescribed, or a non-finite component.
    pub fn set_body_wrench(
        &mut self,
        body: usize,
        force: crate::body::Vec3,
        torque: crate::body::Vec3,
    ) -> Result<(), InputError> {
        let (models, held) = self.bodies_and_held();
        let count = models.len();
        let model = wrench_target(models, body, &force, &torque)?;
        if held.len() < count {
            held.resize(count, None);
        }
        let original = match held[body].take() {
            Some(original) => original,
            None => model.wrench.clone(),
        };
        model.wrench = Some(crate::body::BodyWrench {
            force: Arc::new(move |_t| force),
            torque: Arc::new(move |_t| torque),
        });
        held[body] = Some(original);
        Ok(())
    }

    /// Returns body `body`'s wrench port to what it had before [`Self::set_body_wrench`]
    /// from the next step on (nothing to do if it is not held). Refused for an unknown body.
    pub fn release_body_wrench(&mut self, body: usize) -> Result<(), InputError> {
        let (models, held) = self.bodies_and_held();
        let count = models.len();
        if body >= count {
            return Err(InputError::NoSuchBody { body, count });
        }
        if let Some(original) = held.get_mut(body).and_then(Option::take) {
            models[body].wrench = original;
        }
        Ok(())
    }
}

/// Body `body` of `models`, if a wrench `(force, torque)` may be held on it: it exists, its
/// motion is not prescribed, and every component is finite.
fn wrench_target<'a>(
    models: &'a mut [crate::body::BodyModel],
    body: usize,
    force: &crate::body::Vec3,
    torque: &crate::body::Vec3,
) -> Result<&'a mut crate::body::BodyModel, InputError> {
    let count = models.len();
    let model = models
        .get_mut(body)
        .ok_or(InputError::NoSuchBody { body, count })?;
    if model.motion.is_some() {
        return Err(InputError::BodyWrench {
            body,
            why: "its motion is prescribed".into(),
        });
    }
    if let Some(x) = force.iter().chain(torque).find(|x| !x.is_finite()) {
        return Err(InputError::BodyWrench {
            body,
            why: format!("a component is {}", Num(*x)),
        });
    }
    Ok(model)
}

impl<const D: usize, M: StoredEnergy> Simulation<D, M> {
    /// Holds winch `winch`'s payout speed at `speed` [m/s] (negative: hauling in) from the
    /// current time on: its payout becomes `p_now + speed (t − t_now)`, continuing from the
    /// payout it has reached, until set again; the scenario's payout does not come back.
    /// Refused (nothing changes) for an unknown winch, a speed that is not finite, or a
    /// winch whose drum has dynamics (its payout is a state: hold its motor pull,
    /// [`Self::set_winch_force`]).
    pub fn set_winch_speed(&mut self, winch: usize, speed: f64) -> Result<(), InputError> {
        let count = self.winch_count();
        let p0 = self
            .winch_payout(winch)
            .ok_or(InputError::NoSuchWinch { winch, count })?;
        if self.winch_has_drum(winch) {
            return Err(InputError::WinchDrive {
                winch,
                why: "has a drum with dynamics: its payout is a state, not an input (hold its motor pull instead)",
            });
        }
        let t0 = self.time();
        if !speed.is_finite() {
            return Err(InputError::WinchSpeedNotFinite {
                winch,
                value: speed,
            });
        }
        self.set_winch_payout(winch, Arc::new(move |t| p0 + speed * (t - t0)));
        Ok(())
    }

    /// Holds the motor pull of winch `winch`'s drum at `force` [N] at the rope (hauling in
    /// positive; a tension controller's target tension) from the current time on, until set
    /// again; the scenario's pull does not come back. Refused (nothing changes) for an
    /// unknown winch, a pull that is not finite, or a winch without a drum with dynamics.
    pub fn set_winch_force(&mut self, winch: usize, force: f64) -> Result<(), InputError> {
        let count = self.winch_count();
        if winch >= count {
            return Err(InputError::NoSuchWinch { winch, count });
        }
        if !self.winch_has_drum(winch) {
            return Err(InputError::WinchDrive {
                winch,
                why: "has a prescribed payout, no drum with dynamics: hold its payout speed instead",
            });
        }
        if !force.is_finite() {
            return Err(InputError::WinchForceNotFinite {
                winch,
                value: force,
            });
        }
        self.set_winch_drum_force(winch, Arc::new(move |_| force));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type V = Vector<2>;
    use crate::{Boundary, Fixed, MassMatrix, Material, Mesh, Problem, State, StepParams};

    /// A hanging 2D chain of `n` elements, fixed at node 0, loaded at its end by `force`,
    /// its node 0 moved in x by `motion` if given.
    fn chain(
        force: impl Fn(f64) -> Vector<2> + Send + Sync + 'static,
        motion: Option<Motion>,
    ) -> Simulation<2, Material> {
        let n = 8;
        let mesh = Mesh::uniform_chain(n, 2.0).unwrap();
        let initial = State::straight(&mesh, Vector::zeros(), V::new(1.2, -1.6));
        let fixed = match motion {
            // The moving support's other component stays fixed.
            Some(_) => Fixed {
                node: 0,
                components: [false, true],
            },
            None => Fixed::node(0),
        };
        let problem = Problem {
            mesh,
            initial,
            material: Material::hyperelastic(50.0),
            rho_a: 0.3,
            body_force: V::new(0.0, -9.81 * 0.3),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                fixed: vec![fixed],
                loads: vec![NodalLoad::new(n, force)],
                motions: motion.into_iter().collect(),
                feedback: vec![],
            },
            point_masses: vec![],
        };
        let params = StepParams {
            h: 0.01,
            ..Default::default()
        };
        Simulation::new(problem, params).unwrap()
    }

    fn bits<const D: usize>(s: &Simulation<D, Material>) -> Vec<u64> {
        let st = s.state();
        let e = s.energies();
        st.r.iter()
            .chain(&st.v)
            .flat_map(|x| x.iter().map(|c| c.to_bits()).collect::<Vec<_>>())
            .chain(st.c.iter().map(|c| c.to_bits()))
            .chain([
                e.hamiltonian().to_bits(),
                s.supplied_energy().to_bits(),
                s.dissipated_energy().to_bits(),
            ])
            .collect()
    }

    #[test]
    fn a_held_force_steps_as_a_constant_force_signal_bit_for_bit() {
        let u = V::new(0.3, -0.7);
        let mut constant = chain(move |_| u, None);
        let mut held = chain(|t| V::new(t.sin(), 1.0), None);
        held.set_load_force(0, u).unwrap();
        assert_eq!(held.held_load_force(0), Some(u));
        for _ in 0..20 {
            let (a, b) = (constant.step().unwrap(), held.step().unwrap());
            assert_eq!(a.balance_error.to_bits(), b.balance_error.to_bits());
            assert_eq!(bits(&constant), bits(&held));
            assert_eq!(constant.ports()[0], held.ports()[0]);
        }
        assert!(held.supplied_energy() != 0.0);
    }

    #[test]
    fn a_released_force_follows_its_signal_again() {
        let signal = |t: f64| V::new(0.2 * t, -0.1);
        let mut free = chain(signal, None);
        let mut held = chain(signal, None);
        held.set_load_force(0, V::new(5.0, 5.0)).unwrap();
        held.set_load_force(0, V::new(0.0, 1.0)).unwrap();
        held.release_load_force(0).unwrap();
        assert_eq!(held.held_load_force(0), None);
        for _ in 0..5 {
            free.step().unwrap();
            held.step().unwrap();
        }
        assert_eq!(bits(&free), bits(&held));
    }

    #[test]
    fn a_position_target_ramps_and_the_balance_stays_exact() {
        let mut sim = chain(|_| Vector::zeros(), Some(Motion::new(0, 0, |_| 0.0)));
        let h0 = sim.energies().hamiltonian();
        let ramp = sim.set_motion_target(0, 0.05, 0.1).unwrap();
        assert_eq!(
            ramp,
            PositionRamp {
                t0: 0.0,
                t1: 0.1,
                from: 0.0,
                to: 0.05
            }
        );
        assert_eq!(sim.motion_ramp(0), Some(ramp));
        let mut worst = 0.0f64;
        for _ in 0..10 {
            let r = sim.step_until(0.1).unwrap();
            worst = worst.max(r.balance_error.abs() / r.after.hamiltonian().abs().max(1.0));
            let x = sim.state().r[0][0];
            assert_eq!(x.to_bits(), ramp.position(sim.time()).to_bits());
        }
        assert_eq!(sim.state().r[0][0], 0.05);
        // The ramp's slope, 0.5 m/s, was the support's velocity on the way.
        assert!(sim.supplied_energy() != 0.0);
        // The whole run's balance, as well as each step's.
        let total =
            sim.energies().hamiltonian() - h0 - sim.supplied_energy() + sim.dissipated_energy();
        assert!(worst < 1e-9, "step balance {worst}");
        assert!(total.abs() < 1e-9 * h0.abs().max(1.0), "balance {total}");
        // The next target starts where the support is.
        let next = sim.set_motion_target(0, 0.0, 0.2).unwrap();
        assert_eq!((next.t0, next.from), (sim.time(), 0.05));
        sim.step_until(0.2).unwrap();
        assert!(sim.state().v[0][0] < 0.0);
    }

    #[test]
    fn a_ramp_set_on_the_simulation_matches_the_same_ramp_as_a_signal() {
        let ramp = PositionRamp {
            t0: 0.0,
            t1: 0.07,
            from: 0.0,
            to: -0.02,
        };
        let mut signal = Motion::new(0, 0, |_| 0.0);
        signal.hold(ramp);
        let mut as_signal = chain(|_| Vector::zeros(), Some(signal));
        let mut held = chain(|_| Vector::zeros(), Some(Motion::new(0, 0, |_| 0.0)));
        held.set_motion_ramp(0, ramp).unwrap();
        for _ in 0..6 {
            as_signal.step().unwrap();
            held.step().unwrap();
        }
        // Not the first step: its velocity at t = 0 was set up from each problem's own signal.
        held.release_motion(0).unwrap();
        assert_eq!(held.motion_ramp(0), None);
        assert_eq!(
            held.state().r[0][0].to_bits(),
            as_signal.state().r[0][0].to_bits()
        );
    }

    #[test]
    fn bad_ports_and_values_are_refused_by_name_and_change_nothing() {
        let mut sim = chain(|_| V::new(0.0, -1.0), Some(Motion::new(0, 0, |_| 0.0)));
        let before = bits(&sim);
        let e = sim.set_load_force(3, Vector::zeros()).unwrap_err();
        assert_eq!(e, InputError::NoSuchLoad { load: 3, count: 1 });
        assert_eq!(
            e.to_string(),
            "load port 3 does not exist: the problem has 1 loads (0 … 0)"
        );
        let e = sim.set_load_force(0, V::new(1.0, f64::NAN)).unwrap_err();
        assert!(e.to_string().contains("load port 0") && e.to_string().contains("NaN"));
        assert!(matches!(e, InputError::ForceNotFinite { component: 1, .. }));
        assert_eq!(sim.held_load_force(0), None);
        assert!(sim.release_load_force(1).is_err());
        let e = sim.set_motion_target(2, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("motion 2 does not exist"), "{e}");
        let e = sim.set_motion_target(0, f64::INFINITY, 1.0).unwrap_err();
        assert!(
            e.to_string()
                .contains("position target of motion 0 must be finite, got inf"),
            "{e}"
        );
        let e = sim.set_motion_target(0, 0.1, f64::NAN).unwrap_err();
        assert!(e.to_string().contains("ramp end time"), "{e}");
        let e = sim.set_motion_target(0, 0.1, -1.0).unwrap_err();
        assert!(
            matches!(e, InputError::RampBackwards { motion: 0, .. }),
            "{e}"
        );
        assert_eq!(sim.motion_ramp(0), None);
        assert!(sim.release_motion(1).is_err());
        sim.step().unwrap();
        let mut fresh = chain(|_| V::new(0.0, -1.0), Some(Motion::new(0, 0, |_| 0.0)));
        assert_eq!(before, bits(&fresh));
        fresh.step().unwrap();
        assert_eq!(bits(&sim), bits(&fresh));
    }
}
