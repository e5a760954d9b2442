"""Winches from Python: `winches` and `set_winch_speed` on the gantry crane, against the
winch's own energy bookkeeping and the static line tension times the hauling speed; and
`set_winch_force` on a drum with dynamics."""

import pathlib

import pytest

import phstring

CRANE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "crane_hoisting_2d.toml"


def crane():
    """The crane example with its payout held at 0 and the trolley at rest, 10 s long."""
    text = CRANE.read_text()
    text = text.replace('payout = "-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)"', 'payout = "0"')
    text = text.replace('drum_position = ["6 * (3*min(t/8,1)^2 - 2*min(t/8,1)^3)", "0"]', "")
    return phstring.Simulation(phstring.Scenario.from_toml(text))


def test_a_held_winch_speed_hauls_in_and_its_energy_is_the_hamiltonian_change():
    # Hauling 5 t in at 2 cm/s for 5 s (0.1 m): the winch's power is the line tension times
    # the speed and the rope's stretch, the static tension g (m + ρA ℓ) within the bounce
    # the start excites (±0.3 %), and its energy is the change of Ĥ (its only port).
    sim = crane()
    with pytest.raises(ValueError, match='no winch named "drum": the winches are hoist'):
        sim.set_winch_speed("drum", -0.02)
    h0 = sim.energies["hamiltonian"]
    sim.set_winch_speed("hoist", -0.02)
    powers = []
    while sim.time < 5.0 - 1e-9:
        sim.step()
        w = sim.winches[0]
        if sim.time > 1.0:
            powers.append(w["power"])
    w = sim.winches[0]
    assert w["name"] == "hoist"
    assert w["payout"] == pytest.approx(-0.1, abs=1e-12)
    assert w["length"] == pytest.approx(24.9, abs=1e-9)
    assert w["mass"] == pytest.approx(4.1 * 24.9, rel=1e-12)
    assert w["speed"] == pytest.approx(-0.02, rel=1e-9)
    dh = sim.energies["hamiltonian"] - h0
    assert w["energy"] == pytest.approx(dh, rel=1e-9)
    mean = sum(powers) / len(powers)
    static = 9.81 * (5000.0 + 4.1 * 24.95) * 0.02 * 1.00116
    assert mean == pytest.approx(static, rel=3e-3)


HEAVE = CRANE.parent / "heave_compensated_winch_2d.toml"


def test_a_held_motor_pull_hauls_in_a_drum_and_the_motor_and_damping_close_the_balance():
    # The heave-compensating winch on a still vessel: its controller's target held 1 kN above
    # the 51.06 kN that hang from it hauls the load in (the payout speed is a state of the
    # drum, not an input); the motor's energy is its pull times the rope hauled over the drum,
    # and the change of Ĥ is the winch's energy less what the damping took.
    text = HEAVE.read_text().replace("1.0 * sin(2*pi*t/8) * min(t/8, 1)", "0")
    sim = phstring.Simulation(phstring.Scenario.from_toml(text))
    with pytest.raises(ValueError, match="has a drum with dynamics"):
        sim.set_winch_speed("heave_winch", -0.02)
    with pytest.raises(ValueError, match="must be finite"):
        sim.set_winch_force(0, float("nan"))
    h0 = sim.energies["hamiltonian"]
    pull = 51061.0 + 1000.0
    sim.set_winch_force("heave_winch", pull)
    while sim.time < 10.0 - 1e-9:
        sim.step()
    w = sim.winches[0]
    assert w["payout"] < -0.5 and w["speed"] < 0.0
    # λ = 1 + T/EA ≈ 1.0012: the rope passes over the drum stretched.
    assert w["motor_energy"] == pytest.approx(-pull * w["payout"] * 1.0012, rel=2e-4)
    assert w["drum_dissipated"] > 0.0
    dh = sim.energies["hamiltonian"] - h0
    assert w["energy"] - w["drum_dissipated"] == pytest.approx(dh, rel=1e-9)
    crane_sim = crane()
    with pytest.raises(ValueError, match="has a prescribed payout"):
        crane_sim.set_winch_force("hoist", 1e4)
