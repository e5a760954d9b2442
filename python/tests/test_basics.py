"""The Python package against the command line: the paper's run from
Python is the CLI's, bit for bit; errors map to ScenarioError and StepError."""

import csv
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import phstring

ROOT = pathlib.Path(__file__).resolve().parents[2]
PAPER = ROOT / "examples" / "paper_pendulum.toml"
BIN = os.environ.get("PHSTRING_BIN", str(ROOT / "target" / "debug" / "phstring"))


def cli_energy(tmp_path, *sets):
    args = [BIN, "run", str(PAPER), "--out", str(tmp_path / "out"), "-q"]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, capture_output=True)
    with open(tmp_path / "out" / "energy.csv") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


@pytest.mark.skipif(not pathlib.Path(BIN).exists(), reason="the CLI binary is not built")
def test_paper_run_is_the_cli_run_bit_for_bit(tmp_path):
    sc = phstring.Scenario.from_file(str(PAPER))
    res = phstring.run(sc)
    folder = phstring.run(sc, out=str(tmp_path / "py"))
    cli = cli_energy(tmp_path)
    for key, col in [("t", "t"), ("hamiltonian", "hamiltonian"), ("kinetic", "kinetic"),
                     ("supplied", "supplied_energy"), ("balance_error", "balance_error"), ("h", "h")]:
        assert np.array_equal(getattr(res, key), cli[col]), key
        assert np.array_equal(getattr(folder, key), cli[col]), key
    assert np.array_equal(res.positions, folder.positions)
    assert res.positions.shape == (101, 31, 2)
    assert folder.summary["status"] == "completed" and folder.summary["steps"] == 100
    # The paper's published values.
    assert abs(res.hamiltonian[0] - (-3.468359)) < 1e-6
    assert abs(res.hamiltonian[-1] - (-3.403762)) < 1e-6


def test_simulation_steps_and_state():
    sim = phstring.Simulation(phstring.Scenario.from_file(str(PAPER), set=["mesh.elements=10"]))
    assert sim.r.shape == (11, 2)
    h0 = sim.energies["hamiltonian"]
    rep = sim.step()
    assert rep["step"] == 1 and abs(rep["t"] - 0.01) < 1e-15
    assert abs(rep["balance_error"]) < 1e-12
    e = sim.energies
    assert abs(e["hamiltonian"] - h0 - e["supplied"] + e["dissipated"]) < 1e-12
    while sim.time < sim.t_end - 1e-12:
        sim.step()
    assert sim.steps == 100
    assert sim.v.shape == (11, 2) and sim.c.shape == (10,)
    # The kinematic relation C = |r'|² holds for the state (docs/method.md §7).
    rp = np.diff(sim.r, axis=0) / 0.1
    assert np.allclose(sim.c, (rp ** 2).sum(axis=1), rtol=1e-12)
    # A copy: it does not change when the simulation moves on.
    r = sim.r
    r[0, 0] = 99.0
    assert sim.r[0, 0] == 0.0


def test_scenario_from_dict_and_toml():
    text = PAPER.read_text()
    a = phstring.Scenario.from_toml(text, set=["time.end=0.05"])
    assert a.dimension == 2
    import tomllib
    b = phstring.Scenario.from_json(json.dumps(tomllib.loads(text)), set=["time.end=0.05"])
    ra, rb = phstring.run(a), phstring.run(b)
    assert np.array_equal(ra.hamiltonian, rb.hamiltonian)


def test_errors_are_mapped():
    with pytest.raises(phstring.ScenarioError, match="mesh.elements"):
        phstring.Scenario.from_file(str(PAPER), set=["mesh.elements=-3"])
    with pytest.raises(phstring.ScenarioError):
        phstring.Scenario.from_toml("dimension = 2\n[time]\nh = 0.1\n")
    # A load that stops being defined after t = 0.02 s fails the third step.
    sc = phstring.Scenario.from_file(str(PAPER), set=['boundary.1.force=["sqrt(0.02 - t)", "0"]'])
    sim = phstring.Simulation(sc)
    sim.step()
    sim.step()
    with pytest.raises(phstring.StepError, match="step 3"):
        sim.step()
    assert sim.steps == 2


def test_constant_set_input_equals_the_scenario_force():
    """`set_input` with a constant force gives the run of the scenario with that force, bit
    for bit (the load is sampled at the mid-step either way)."""
    steps = 30
    with_force = phstring.Simulation(
        phstring.Scenario.from_file(str(PAPER), set=['boundary.1.force=["0.3", "-0.1"]']))
    held = phstring.Simulation(
        phstring.Scenario.from_file(str(PAPER), set=['boundary.1.force=["0", "0"]']))
    held.set_input(0, [0.3, -0.1])
    for _ in range(steps):
        a, b = with_force.step(), held.step()
        assert a["hamiltonian"] == b["hamiltonian"] and a["supplied"] == b["supplied"]
    assert np.array_equal(with_force.r, held.r)
    port = held.ports[0]
    assert port["kind"] == "force" and port["node"] == 30
    assert np.array_equal(port["u"], [0.3, -0.1])
    assert port["power"] == pytest.approx(float(port["u"] @ port["y"]), rel=0, abs=0)
    # Back to the scenario's expression.
    held.set_input(0, None)
    held.step()
    assert np.array_equal(held.ports[0]["u"], [0.0, 0.0])


def test_set_input_refuses_bad_values():
    sim = phstring.Simulation(phstring.Scenario.from_file(str(PAPER)))
    with pytest.raises(ValueError, match="port 3 is not a load"):
        sim.set_input(3, [0.0, 0.0])
    with pytest.raises(ValueError, match="needs 2 components"):
        sim.set_input(0, [1.0])
    with pytest.raises(ValueError, match="finite"):
        sim.set_input(0, [float("nan"), 0.0])


def test_pd_control_example_tracks_the_point():
    out = subprocess.run(
        ["python3", str(ROOT / "python" / "examples" / "pd_control.py")],
        check=True, capture_output=True, text=True)
    first, last = (float(x) for x in out.stdout.split()[-2:])
    assert first > 0.1 and last < 0.2 * first, out.stdout


def test_checkpoint_and_restore_continue_bit_for_bit():
    sc = phstring.Scenario.from_file(str(PAPER))
    a = phstring.Simulation(sc)
    for _ in range(40):
        a.step()
    cp = a.checkpoint()
    rest_a = [a.step()["hamiltonian"] for _ in range(30)]
    b = phstring.Simulation(sc)
    b.restore(cp)
    assert b.steps == 40
    rest_b = [b.step()["hamiltonian"] for _ in range(30)]
    assert rest_a == rest_b
    three = phstring.Simulation(phstring.Scenario.from_file(str(ROOT / "examples" / "hoist_3d.toml")))
    with pytest.raises(ValueError, match="dimension"):
        three.restore(cp)


def test_ctrl_c_stops_a_run_after_the_current_step(tmp_path):
    """An OS signal during a run (here SIGALRM after 0.3 s, whose handler raises
    KeyboardInterrupt as Ctrl-C's does) stops it after the current step, in-process and into
    a folder (which then holds a checkpoint)."""
    import signal

    def interrupt(*_):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, interrupt)
    try:
        # 1e7 steps: the run cannot end before the signal.
        sc = phstring.Scenario.from_file(str(PAPER), set=["mesh.elements=300", "time.end=1e5"])
        for out in [None, str(tmp_path / "run")]:
            signal.setitimer(signal.ITIMER_REAL, 0.3)
            with pytest.raises(KeyboardInterrupt):
                phstring.run(sc, out=out)
        summary = json.loads((tmp_path / "run" / "summary.json").read_text())
        assert summary["status"] == "interrupted"
        assert (tmp_path / "run" / "checkpoint.json").exists()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def test_no_memory_growth_over_1e5_steps():
    import resource
    sim = phstring.Simulation(phstring.Scenario.from_file(
        str(PAPER), set=["mesh.elements=4", "time.end=2000.0"]))
    for _ in range(10000):
        sim.step()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    for _ in range(100000):
        sim.step()
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    # ru_maxrss is in KiB on Linux: less than 1 MiB more after 1e5 steps.
    assert after - before < 1024, (before, after)


def test_paper_figures_example(tmp_path):
    out = subprocess.run(
        ["python3", str(ROOT / "python" / "examples" / "paper_figures.py"), str(tmp_path)],
        check=True, capture_output=True, text=True)
    assert "H(0) = -3.468359 J, H(1) = -3.403762 J (dg)" in out.stdout
    for name in ["paper_energy.png", "paper_configuration.png"]:
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_dask_sweep_example():
    pytest.importorskip("distributed")
    out = subprocess.run(
        ["python3", str(ROOT / "python" / "examples" / "dask_sweep.py")],
        check=True, capture_output=True, text=True)
    rows = [line.split(",") for line in out.stdout.strip().splitlines()[1:]]
    assert [int(r[0]) for r in rows] == [10, 20, 30, 60, 120]
    # The N = 30 row is the paper's value; every run keeps its energy balance.
    assert abs(float(rows[2][1]) - (-3.403762)) < 1e-6
    assert all(float(r[2]) < 1e-11 for r in rows)


def test_every_error_kind_is_mapped(tmp_path):
    """Each kind of failure reaches Python as its own exception, with the message."""
    # A missing file and a bad value: ScenarioError, naming the file or the key.
    with pytest.raises(phstring.ScenarioError, match="no_such.toml"):
        phstring.Scenario.from_file(str(tmp_path / "no_such.toml"))
    with pytest.raises(phstring.ScenarioError, match="time.h"):
        phstring.Scenario.from_file(str(PAPER), set=["time.h=-1"])
    with pytest.raises(phstring.ScenarioError):
        phstring.Scenario.from_json("[1, 2]")
    # A failing step, in-process and into a folder: StepError with step and time.
    bad = phstring.Scenario.from_file(str(PAPER), set=['boundary.1.force=["sqrt(0.02 - t)", "0"]'])
    with pytest.raises(phstring.StepError, match="step 3"):
        phstring.run(bad)
    with pytest.raises(phstring.StepError, match="boundary.1.force"):
        phstring.run(bad, out=str(tmp_path / "failed"))
    # An output folder that cannot be made: OSError.
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OSError):
        phstring.run(phstring.Scenario.from_file(str(PAPER)), out=str(blocker / "sub"))


def test_statics_modes_and_linear_model():
    """Statics, modes and the linear model from Python agree with each other: the taut
    string's lowest frequencies solve the linear model's pencil, `R = 0` without damping and
    `R` positive semidefinite with it."""
    import scipy.linalg
    taut = phstring.Scenario.from_file(str(ROOT / "examples" / "taut_string.toml"))
    eq = phstring.statics(taut)
    assert eq["stable"] and eq["residual"] <= eq["tolerance"]
    m = phstring.modes(taut, 4)
    assert m["shapes"].shape == (4, eq["positions"].shape[0], 2)
    lin = phstring.linearize(taut)
    n = lin["E"].shape[0] // 2
    K = lin["Q"].toarray()[:n, :n]
    M = lin["E"].toarray()[n:, n:]
    w2 = scipy.linalg.eigh(K, M, eigvals_only=True)[:4]
    assert np.allclose(np.sqrt(w2), m["omega"], rtol=1e-9)
    assert lin["R"].nnz == 0
    damped = phstring.linearize(phstring.Scenario.from_file(str(ROOT / "examples" / "damped_pendulum.toml")))
    R = damped["R"].toarray()
    assert np.array_equal(R, R.T) and np.linalg.eigvalsh(R).min() >= -1e-12 * np.abs(R).max()
    with pytest.raises(phstring.StepError, match="statics"):
        phstring.statics(phstring.Scenario.from_file(str(ROOT / "examples" / "pd_tip_tracking.toml")))


def test_progress_only_when_asked(tmp_path):
    code = "import phstring, sys; sc = phstring.Scenario.from_file(sys.argv[1]); phstring.run(sc, progress=sys.argv[2] == '1')"
    quiet = subprocess.run(["python3", "-c", code, str(PAPER), "0"], check=True, capture_output=True, text=True)
    shown = subprocess.run(["python3", "-c", code, str(PAPER), "1"], check=True, capture_output=True, text=True)
    assert quiet.stderr == ""
    assert "100 %" in shown.stderr


def test_simulation_starts_at_the_equilibrium_when_asked():
    """`initial.equilibrium = true` (the mooring line): `Simulation` starts where
    `phstring run` does, at the static equilibrium, at rest but for the fairlead, which
    starts at its heave's velocity d/dt (60 + sin(2πt/10)) = 2π/10 m/s (the heave without the
    example's build-up)."""
    sine = 'boundary.1.position=["120", "60 + 1.0 * sin(2*pi*t/10)"]'
    sc = phstring.Scenario.from_file(str(ROOT / "examples" / "slack_wire.toml"), set=["mesh.elements=40", sine])
    eq = phstring.statics(sc)
    sim = phstring.Simulation(sc)
    assert np.array_equal(sim.r, eq["positions"])
    v = np.array(sim.v)
    assert np.all(v[:-1] == 0.0) and v[-1, 0] == 0.0
    assert abs(v[-1, 1] - 0.2 * np.pi) < 1e-9
    assert sim.energies["kinetic"] > 0.0
    # The straight line between anchor and fairlead would be 134 m; the line sags.
    assert sim.r[:, 1].min() < -1.0


def test_water_energies_are_reported_per_mechanism():
    """The mooring line in water (examples/mooring_line.toml, 2 s): the energies name the
    buoyancy and seabed potentials and the water's shares; they are inside the totals, the
    drag and seabed damping dissipate (≥ 0) and the balance closes to round-off."""
    sc = phstring.Scenario.from_file(str(ROOT / "examples" / "mooring_line.toml"), set=["time.end=2.0"])
    sim = phstring.Simulation(sc)
    h0 = sim.energies["hamiltonian"]
    dry = phstring.Simulation(phstring.Scenario.from_file(str(PAPER)))
    assert "buoyancy" not in dry.energies
    while sim.time < 2.0 - 1e-9:
        sim.step()
    e = sim.energies
    # The buoyancy potential −ρ_w g V z is positive below the surface (z < 0).
    assert e["buoyancy"] > 0.0 and e["seabed"] > 0.0
    assert e["drag_dissipated"] > 0.0 and e["seabed_dissipated"] >= 0.0
    assert e["drag_dissipated"] + e["seabed_dissipated"] + e["friction_dissipated"] <= e["dissipated"] * (1 + 1e-12)
    assert e["current_supplied"] == 0.0  # still water
    scale = abs(h0) + abs(e["hamiltonian"])
    assert abs(e["hamiltonian"] - h0 - e["supplied"] + e["dissipated"]) <= 1e-12 * scale


def test_version_and_a_namespace_of_the_api_only():
    """`phstring.__version__` is the package's version (pyproject.toml), and the package's
    public names are exactly `__all__`: no helper modules (`os`, `json`, `np`) or typing
    names leak into `dir(phstring)`."""
    import re

    text = (ROOT / "python" / "pyproject.toml").read_text()
    declared = re.search(r'^version\s*=\s*"([^"]+)"', text, re.M).group(1)
    assert phstring.__version__ == declared
    names = set(dir(phstring))
    for helper in ["os", "json", "np", "numpy", "Any", "Dict", "Optional", "annotations"]:
        assert helper not in names, helper
    public = {n for n in names if not n.startswith("_")}
    assert public == set(phstring.__all__) - {"__version__"}
