"""phstring: port-Hamiltonian strings and cables with exact energy behaviour.

Work in progress (issue 15): `Scenario`, `Simulation` and `run` exist; outputs to a folder,
statics, modes, linear models, checkpoints, progress and Ctrl-C handling do not yet.
"""

from ._phstring import Scenario, ScenarioError, Simulation, StepError, run

__all__ = ["Scenario", "ScenarioError", "Simulation", "StepError", "run"]
