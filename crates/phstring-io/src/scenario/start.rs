//! Starting from a validated scenario, for every front end: the problem built once into a
//! system ([`Setup`], from [`ScenarioFile::setup`](super::ScenarioFile::setup)), its static
//! equilibrium ([`Setup::equilibrium`]), and the running simulation ([`Setup::start`]), with
//! the starting equilibrium of `initial.equilibrium` and `[initial]`'s fields on it.
//!
//! A checkpoint resume starts without the equilibrium (its state comes from the checkpoint,
//! which the run driver restores on the started simulation).

use std::sync::atomic::AtomicBool;

use phstring::statics::{self, Equilibrium, StaticsError, StaticsParams};
use phstring::{ByDim, Material, Network, PhSystem, SetupError, Simulation, State};

use super::{ScenarioError, Validated};

/// Why the starting state of a scenario could not be set up.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StartError {
    /// The scenario is invalid (its initial displacement or velocity on the equilibrium).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The starting equilibrium (`initial.equilibrium`) was not found.
    #[error("initial.equilibrium: {0}")]
    Statics(StaticsError),
    /// The simulation could not start from the starting state.
    #[error("setup failed: {0}")]
    Setup(SetupError),
}

/// A problem built once: the system and its initial state (the one `[initial]` gives on the
/// geometry's shape; with `initial.equilibrium`, the shape at rest that the equilibrium
/// solve starts from).
pub struct Built<const D: usize> {
    /// The system.
    pub system: PhSystem<D, Material>,
    /// The initial state.
    pub state: State<D>,
}

impl<const D: usize> Built<D> {
    /// Builds `problem` ([`PhSystem::new`]).
    pub fn new(problem: Network<D, Material>) -> Result<Self, SetupError> {
        let (system, state) = PhSystem::new(problem)?;
        Ok(Self { system, state })
    }
}

/// A scenario validated once, with its system built once.
pub type Setup<const D: usize> = Validated<D, Built<D>>;

/// A [`Setup`] of the scenario's own dimension.
pub type AnySetup = ByDim<Setup<1>, Setup<2>, Setup<3>>;

/// A started scenario: the running simulation with the scenario's settings and components.
pub type Running<const D: usize> = Validated<D, Simulation<D, Material>>;

/// A [`Running`] scenario of its own dimension.
pub type AnyRunning = ByDim<Running<1>, Running<2>, Running<3>>;

impl<const D: usize> Setup<D> {
    /// The static equilibrium of the scenario (loads at `t = 0`) from its initial positions,
    /// with its Newton settings and linear solver; with `open_loop`, feedback laws are left
    /// out unchecked (the linear model and modes). `stop` ends the solve early (Ctrl-C).
    pub fn equilibrium(
        &self,
        open_loop: bool,
        stop: Option<&AtomicBool>,
    ) -> Result<Equilibrium<D>, StaticsError> {
        let Built { system, state } = &self.problem;
        statics::solve_system(system, &state.r, &self.statics_params(open_loop), stop)
    }

    /// The statics' settings of [`Self::equilibrium`]: the scenario's Newton settings (with
    /// the statics' iteration limit) and linear solver.
    pub fn statics_params(&self, open_loop: bool) -> StaticsParams {
        StaticsParams {
            newton: phstring::NewtonParams {
                max_iter: StaticsParams::default().newton.max_iter,
                ..self.settings.step.newton
            },
            solver: self.settings.step.solver,
            open_loop,
            ..Default::default()
        }
    }

    /// Refuses a start from the equilibrium (at rest) when a rigid body is given a velocity
    /// or an angular velocity, which that start would drop.
    fn bodies_at_rest(&self) -> Result<(), ScenarioError> {
        let Built { system, state } = &self.problem;
        for (i, ((name, _), b)) in system.bodies().iter().zip(&state.bodies).enumerate() {
            if b.velocity.norm() > 0.0 || b.omega.norm() > 0.0 {
                let reason = if system.body_has_motion(i) {
                    format!(
                        "= true starts every body at rest, but the prescribed motion of body \"{name}\" moves at t = 0: start its motion at rest (zero rates at t = 0), or start from the given positions"
                    )
                } else {
                    format!(
                        "= true starts every body at rest at its rest pose, but body \"{name}\" is given a velocity or angular velocity: remove them, or start from the given positions"
                    )
                };
                return Err(ScenarioError::Invalid {
                    key: "initial.equilibrium".into(),
                    origin: super::Origin::Scenario(self.initial.path().to_path_buf()),
                    reason,
                });
            }
        }
        Ok(())
    }

    /// Starts the simulation at `t = 0`. With `initial.equilibrium` and `from_equilibrium`,
    /// from the static equilibrium with `[initial]`'s displacement and velocity applied on
    /// it; the second value then says how the equilibrium was found (for reports). A
    /// checkpoint resume passes `from_equilibrium = false`. `stop` ends the equilibrium
    /// solve early.
    pub fn start(
        self,
        from_equilibrium: bool,
        stop: Option<&AtomicBool>,
    ) -> Result<(Running<D>, Option<String>), StartError> {
        let mut report = None;
        let mut start_state = None;
        if from_equilibrium && self.initial.equilibrium {
            self.bodies_at_rest()?;
            let eq = self.equilibrium(false, stop).map_err(StartError::Statics)?;
            let mut state = self.initial.apply(&self.problem.system, &eq.state.r)?;
            // The rigid bodies start at their rest poses.
            state.bodies.clone_from(&eq.state.bodies);
            start_state = Some(state);
            report = Some(format!(
                "{} ({} steps, {} Newton iterations), residual {:.3e} N, {}",
                eq.path.name(),
                eq.path.steps(),
                eq.iterations,
                eq.residual,
                if eq.stable { "stable" } else { "not stable" }
            ));
        }
        let params = self.settings.step;
        let running = self.map_problem(|built| {
            let state = start_state.unwrap_or(built.state);
            Simulation::from_system(built.system, state, params).map_err(StartError::Setup)
        })?;
        Ok((running, report))
    }
}
