"""A PD controller written in Python closes the loop around the paper's pendulum through
`set_input`: every step it reads the tip's position and mid-step velocity and holds a force
that pulls the tip towards a target point below the support.

Prints the distance of the tip from the target at the start and at the end [m]."""

import pathlib

import numpy as np

import phstring

ROOT = pathlib.Path(__file__).resolve().parents[2]
# A controller in Python acts on the last step's output (a sampled-data loop, explicit in
# time), so its gains are limited by h·KD/m < 2 with m the tip's share of the mass (about
# 1/90 kg here); a scenario's `control` is evaluated inside the step and has no such limit.
KP, KD = 8.0, 0.6                         # N/m, N·s/m
TARGET = np.array([0.3, -0.9])            # m

# The paper's pendulum without its pulse (the controller's force replaces it), for 3 s.
scenario = phstring.Scenario.from_file(
    str(ROOT / "examples" / "paper_pendulum.toml"),
    set=['boundary.1.force=["0", "0"]', "time.end=3.0"])
sim = phstring.Simulation(scenario)
tip = sim.r.shape[0] - 1
velocity = np.zeros(2)
start = np.linalg.norm(sim.r[tip] - TARGET)
while sim.time < sim.t_end - 1e-12:
    sim.set_input(0, list(KP * (TARGET - sim.r[tip]) - KD * velocity))
    sim.step()
    velocity = sim.ports[0]["y"]          # the port output: the tip's mid-step velocity
end = np.linalg.norm(sim.r[tip] - TARGET)
print(f"distance from the target [m]: {start:.4f} {end:.4f}")
