"""Rigid bodies from Python: `body_ports`, `set_body_wrench` and `release_body_wrench`
against the momentum and energy balances of a pushed body."""

import numpy as np
import pytest

import phstring

# A 2 t block (a 2 m × 1 m × 0.5 m box) in zero gravity, free: its two points hold only a
# massless spring between them at its rest length, whose forces on the block cancel, so the
# port's wrench is the only force and torque on it. A network needs a string: a 100 m rope
# between two fixed points beside it, unstretched, which stays at rest.
FREE_BLOCK = """
title = "A free 2 t block in zero gravity beside a rope at rest"
dimension = 3

[[node]]
name = "a"
position = [0.0, 0.0, 0.0]

[[node]]
name = "b"
position = [100.0, 0.0, 0.0]

[materials.rope]
law = "linear_elastic"
ea = 1.0e8
rho_a = 2.3

[[string]]
name = "rope"
path = ["a", "b"]
elements = 4
material = "rope"

[[boundary]]
node = "a"
fixed = true

[[boundary]]
node = "b"
fixed = true

[bodies.block]
mass = 2000.0
inertia = [208.3, 708.3, 833.3]
position = [50.0, 20.0, 0.0]
points = { fore = [1.0, 0.0, 0.0], aft = [-1.0, 0.0, 0.0] }

[[spring]]
name = "inner"
between = ["block.fore", "block.aft"]
k = 1.0e6
rest = 2.0

[time]
h = 0.01
end = 10.0
"""

BLOCK_KG = 2000.0
INERTIA = np.diag([208.3, 708.3, 833.3])


def rotation(q):
    """The rotation matrix of the unit quaternion `(w, x, y, z)`."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def spin(port):
    """Angular momentum about the centre of mass [kg·m²/s], `R J Rᵀ ω` (space axes)."""
    r = rotation(port["orientation"])
    return r @ INERTIA @ r.T @ port["angular_velocity"]


def test_a_held_wrench_gives_the_impulse_and_its_work_is_the_energy_change():
    """A force F = (1500, −800, 300) N and a torque τ = (0, 50, 200) N·m held for T = 2 s
    (200 steps): the block's momentum is F·T and its angular momentum about its centre τ·T,
    the port's work Σ power·h is the supplied energy and the change of Ĥ, all to 1e-10
    relative; released, both stay."""
    sim = phstring.Simulation(phstring.Scenario.from_toml(FREE_BLOCK))
    force, torque = [1500.0, -800.0, 300.0], [0.0, 50.0, 200.0]
    sim.set_body_wrench("block", force, torque)
    h0 = sim.energies["hamiltonian"]
    work = 0.0
    for _ in range(200):
        r = sim.step()
        work += sim.body_ports[0]["power"] * r["h"]
    assert sim.time == pytest.approx(2.0, rel=1e-14)
    port = sim.body_ports[0]
    assert port["name"] == "block"
    assert np.array_equal(port["force"], force) and np.array_equal(port["torque"], torque)
    impulse = np.array(force) * sim.time
    p = BLOCK_KG * port["velocity"]
    assert np.linalg.norm(p - impulse) <= 1e-10 * np.linalg.norm(impulse), p - impulse
    angular = np.array(torque) * sim.time
    s = spin(port)
    assert np.linalg.norm(s - angular) <= 1e-10 * np.linalg.norm(angular), s - angular
    # The block turned (the torque's work is part of the port's).
    assert np.linalg.norm(port["angular_velocity"]) > 0.1
    e = sim.energies
    assert abs(work - e["supplied"]) <= 1e-10 * abs(work)
    assert abs((e["hamiltonian"] - h0) - work) <= 1e-10 * abs(work)
    assert work > 1e3
    q = port["orientation"]
    assert abs(np.dot(q, q) - 1.0) < 1e-14
    # Released (by index): no port force from the next step on, the momentum stays.
    sim.release_body_wrench(0)
    for _ in range(10):
        sim.step()
    port = sim.body_ports[0]
    assert np.array_equal(port["force"], [0.0, 0.0, 0.0])
    assert np.linalg.norm(BLOCK_KG * port["velocity"] - p) <= 1e-10 * np.linalg.norm(impulse)
    assert np.linalg.norm(spin(port) - s) <= 1e-10 * np.linalg.norm(angular)


def test_set_body_wrench_refuses_bad_bodies_and_values():
    sim = phstring.Simulation(phstring.Scenario.from_toml(FREE_BLOCK))
    with pytest.raises(ValueError, match=r'no rigid body named "hook": the bodies are block'):
        sim.set_body_wrench("hook", [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="no rigid body 1: the bodies are block"):
        sim.release_body_wrench(1)
    with pytest.raises(ValueError, match="the force of body 0 needs 3 components, got 2"):
        sim.set_body_wrench(0, [1.0, 2.0])
    with pytest.raises(ValueError, match="the torque of body 0 must be finite, got NaN"):
        sim.set_body_wrench(0, [1.0, 2.0, 3.0], [0.0, float("nan"), 0.0])
    # Before the first step the port is zero, the pose the scenario's.
    port = sim.body_ports[0]
    assert np.array_equal(port["position"], [50.0, 20.0, 0.0])
    assert np.array_equal(port["orientation"], [1.0, 0.0, 0.0, 0.0])
    assert port["power"] == 0.0
