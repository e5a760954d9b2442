//! Starting a simulation from a validated scenario, for every front end (the run driver, the
//! FMU, the Python package): the scenario's equilibrium ([`solve_validated`]) and the
//! starting state at it (`initial.equilibrium`, [`start_at_equilibrium`]).

use std::sync::atomic::AtomicBool;

use phstring::statics::{self, Equilibrium, StaticsError, StaticsParams};
use phstring::{Material, PhSystem};

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
}

/// The equilibrium of a validated scenario with its Newton settings and linear solver; with
/// `open_loop`, feedback laws are left out unchecked (the linear model and modes).
pub fn solve_validated<const D: usize>(
    v: &Validated<D>,
    open_loop: bool,
    stop: Option<&AtomicBool>,
) -> Result<(PhSystem<D, Material>, Equilibrium<D>), StaticsError> {
    let (sys, initial) = PhSystem::new(v.problem.clone())?;
    let params = StaticsParams {
        newton: phstring::NewtonParams {
            max_iter: StaticsParams::default().newton.max_iter,
            ..v.settings.step.newton
        },
        solver: v.settings.step.solver,
        open_loop,
        ..Default::default()
    };
    let eq = statics::solve_system(&sys, &initial.r, &params, stop)?;
    Ok((sys, eq))
}

/// With `initial.equilibrium`: solves for the starting equilibrium and sets the problem's
/// initial state to it, with `[initial]`'s displacement and velocity applied on it; returns
/// how it was found (for reports). Without it, does nothing and returns `None`. `stop`
/// ends the solve early (Ctrl-C).
pub fn start_at_equilibrium<const D: usize>(
    v: &mut Validated<D>,
    stop: Option<&AtomicBool>,
) -> Result<Option<String>, StartError> {
    if !v.initial.equilibrium {
        return Ok(None);
    }
    let (_, eq) = solve_validated(v, false, stop).map_err(StartError::Statics)?;
    v.problem.initial = v.initial_state(&eq.state.r)?;
    Ok(Some(format!(
        "{} ({} steps, {} Newton iterations), residual {:.3e} N, {}",
        eq.path.name(),
        eq.path.steps(),
        eq.iterations,
        eq.residual,
        if eq.stable { "stable" } else { "not stable" }
    )))
}
