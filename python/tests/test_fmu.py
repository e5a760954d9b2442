"""The FMU of `phstring fmu` in FMPy, the real client: it validates, reproduces `phstring run`
bit for bit, closes a damping-injection loop, and fails clearly (bad parameter, diverging
step) without hanging the master."""

import csv
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave, fmi2Discard
from fmpy.validation import validate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = os.environ.get("PHSTRING_BIN", str(ROOT / "target" / "debug" / "phstring"))
sys.path.insert(0, str(ROOT / "examples" / "fmu"))

import buoy_master  # noqa: E402  (the examples' masters, tested here)
import damping_master  # noqa: E402

H = 0.01  # s, the pendulum's time.h


def unzip_dir(fmu):
    """A fresh folder next to `fmu` (in pytest's temporary folders) to extract it into, so
    that no extraction is left in the system's temporary folder."""
    import tempfile

    return tempfile.mkdtemp(dir=fmu.parent, prefix=f"{fmu.stem}_")


def build(tmp_path, scenario, name, *sets, version="2"):
    """`phstring fmu` of examples/fmu/SCENARIO (or of a path) with `--set` for each of `sets`."""
    out = tmp_path / f"{name}.fmu"
    path = scenario if isinstance(scenario, pathlib.Path) else ROOT / "examples" / "fmu" / scenario
    args = [BIN, "fmu", str(path), "-o", str(out), "--quiet", "--fmi-version", version]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, capture_output=True)
    return out


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    return build(tmp_path_factory.mktemp("fmu"), "pendulum.toml", "pendulum")


@pytest.fixture(scope="module", params=["2", "3"])
def pendulum_any(request, tmp_path_factory):
    """The pendulum's FMU in FMI 2.0 and in FMI 3.0 (one shared library serves both)."""
    v = request.param
    path = build(tmp_path_factory.mktemp(f"fmi{v}"), "pendulum.toml", f"pendulum{v}", version=v)
    assert read_model_description(str(path)).fmiVersion == f"{v}.0"
    return path


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "pendulum"
    subprocess.run(
        [BIN, "run", str(ROOT / "examples" / "fmu" / "pendulum.toml"), "--out", str(out), "--quiet",
         "--set", "output.vtk=false", "--set", "output.plots=false", "--set", "output.animation=false"],
        check=True,
        capture_output=True,
    )
    return out


def columns(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k not in ("kind",)}


class Log:
    """Collects the FMU's log messages (FMPy logger callback; FMI 3.0's has no instance
    name)."""

    def __init__(self, fmi="fmi2"):
        self.messages = []
        self.fmi = fmi

    def __call__(self, *args):
        status, message = (args[1], args[3]) if self.fmi == "fmi3" else (args[2], args[4])
        self.messages.append((status, message.decode()))


def test_validates_and_describes_its_variables(pendulum_any):
    assert validate_fmu(str(pendulum_any)) == []
    md = read_model_description(str(pendulum_any))
    assert md.fmiVersion in ("2.0", "3.0")
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    v = {x.name: x for x in md.modelVariables}
    if md.fmiVersion == "3.0":
        assert (v["time"].causality, v["time"].type) == ("independent", "Float64")
    assert (v["EA"].causality, v["EA"].unit, float(v["EA"].start)) == ("parameter", "N", 20.0)
    assert (v["rhoA"].unit, v["h"].unit, float(v["h"].start)) == ("kg/m", "s", 0.01)
    assert (v["load0.F.x"].causality, v["load0.F.x"].unit) == ("input", "N")
    assert (v["load0.v.y"].causality, v["load0.v.y"].unit) == ("output", "m/s")
    assert (v["support0.R.x"].unit, v["H"].unit, v["node30.r.x"].unit) == ("N", "J", "m")
    assert md.defaultExperiment.stopTime == "1.0"


def signal(t, fx, fy):
    return np.array(list(zip(t, fx, fy)), dtype=[("time", np.float64), ("load0.F.x", np.float64),
                                                   ("load0.F.y", np.float64)])


def test_same_energy_as_phstring_run_bit_for_bit(pendulum_any, run_dir):
    """H = h and, as the input, the tip force the run applied in step n (its pulse at the
    mid-step t_n + h/2, from ports.csv), set at the communication point t_n: the run samples
    loads at the mid-step, the FMU holds the value set at t_n over [t_n, t_n + H]."""
    ports = columns(run_dir / "ports.csv")
    tip = ports["port"] == 0
    ux, uy = ports["u_x"][tip], ports["u_y"][tip]
    t = np.arange(0.0, 1.0 + H / 2, H)
    res = simulate_fmu(str(pendulum_any), stop_time=1.0, output_interval=H,
                       input=signal(t, np.append(ux, 0.0), np.append(uy, 0.0)),
                       output=["H", "T", "supplied", "balance_error"])
    energy = columns(run_dir / "energy.csv")
    assert len(res) == len(energy["t"]) == 101
    assert np.array_equal(res["time"], energy["t"])
    assert np.array_equal(res["H"], energy["hamiltonian"])
    assert np.array_equal(res["T"], energy["kinetic"])
    assert np.array_equal(res["supplied"], energy["supplied_energy"])
    assert np.abs(res["balance_error"]).max() <= 1e-13
    # The pulse computed here in NumPy differs from phstring's expression evaluator in the
    # last bit at some steps (3e-16 N); the energies then agree to rounding, not bit for bit.
    tm = t + H / 2
    pulse = np.where(tm <= 0.2, np.sin(np.pi * tm / 0.2), 0.0)
    res2 = simulate_fmu(str(pendulum_any), stop_time=1.0, output_interval=H, input=signal(t, pulse, pulse),
                        output=["H"])
    assert np.abs(res2["H"] - energy["hamiltonian"]).max() <= 1e-13


def test_closed_loop_damping_injection_comes_to_rest(tmp_path):
    """The example's master: u = -300 v at the payload from the FMU's velocity output."""
    fmu = build(tmp_path, "hoist.toml", "hoist")
    r = damping_master.closed_loop(fmu, kd=300.0, comm_step=0.01, t_end=20.0)
    peak = r["T"].max()
    assert peak > 100.0  # J: the swing
    # The swing dies out: what is left (0.02 % of the peak) are the rope's own vibrations.
    assert r["T"][-1] < 2e-3 * peak, r["T"][-1]
    assert np.abs(r["v"][-200:]).max() < 0.05  # m/s: the payload is at rest
    # The controller only took energy out, and the FMU accounts for every joule of it.
    assert r["supplied"][-1] < -1000.0
    assert np.abs(r["balance_error"]).max() <= 1e-12 * np.abs(r["H"]).max()
    assert abs((r["H"][-1] - r["H"][0]) - r["supplied"][-1]) <= 1e-12 * np.abs(r["H"]).max()


def test_a_bad_parameter_is_refused_with_its_name(pendulum_any):
    fmi = "fmi3" if read_model_description(str(pendulum_any)).fmiVersion == "3.0" else "fmi2"
    log = Log(fmi)
    setter = "fmi3SetFloat64" if fmi == "fmi3" else "fmi2SetReal"
    # Extracted here: simulate_fmu leaves its own extraction behind when it raises.
    from fmpy import extract

    unzipped = extract(str(pendulum_any), unzipdir=unzip_dir(pendulum_any))
    with pytest.raises(Exception, match=setter):
        simulate_fmu(unzipped, stop_time=0.1, start_values={"EA": -1.0}, logger=log)
    assert any(s == 3 and "EA = -1" in m for s, m in log.messages), log.messages
    # Positive, but it does not fit the scenario: refused when the simulation is set up.
    log = Log(fmi)
    with pytest.raises(Exception, match=f"{fmi}ExitInitializationMode"):
        simulate_fmu(unzipped, stop_time=0.1, start_values={"h": 1e-300}, logger=log)
    assert any(s == 3 and "time.h" in m for s, m in log.messages), log.messages


def slave_of(fmu, log):
    md = read_model_description(str(fmu))
    from fmpy import extract

    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), unzipdir=unzip_dir(fmu)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    s.instantiate(callbacks=callbacks)
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    return s, {v.name: v.valueReference for v in md.modelVariables}, callbacks


def test_a_diverging_step_is_discarded_and_the_master_can_go_back(pendulum):
    log = Log()
    s, vr, _keep = slave_of(pendulum, log)
    s.doStep(0.0, 0.05)
    state = s.getFMUState()
    s.setReal([vr["load0.F.x"]], [1e160])
    with pytest.raises(Exception) as e:
        s.doStep(0.05, 0.01)
    assert getattr(e.value, "status", None) == fmi2Discard
    from fmpy.fmi2 import fmi2LastSuccessfulTime, fmi2Terminated

    assert s.getRealStatus(fmi2LastSuccessfulTime) == pytest.approx(0.05, abs=1e-15)
    assert s.getBooleanStatus(fmi2Terminated)
    status, message = log.messages[-1]
    assert status == 2 and "step 6" in message and "t = 0.05" in message, message
    # Back to the saved state, with a sane force: it goes on.
    s.setFMUState(state)
    s.setReal([vr["load0.F.x"]], [0.1])
    s.doStep(0.05, 0.01)
    assert s.getReal([vr["balance_error"]])[0] == pytest.approx(0.0, abs=1e-12)
    s.freeFMUState(state)
    s.terminate()
    s.freeInstance()
    # simulate_fmu stops at the last step completed instead of retrying forever.
    log = Log()
    t = np.array([0.0, 1.0])
    res = simulate_fmu(str(pendulum), stop_time=1.0, output_interval=H, logger=log,
                       input=signal(t, np.full(2, 1e160), np.zeros(2)), output=["H"])
    assert res["time"][-1] == 0.0
    assert any(s == 2 for s, _ in log.messages)


def test_serialized_states_continue_bit_for_bit(pendulum):
    log = Log()
    a, vr, _ka = slave_of(pendulum, log)
    for n in range(10):
        a.setReal([vr["load0.F.x"], vr["load0.F.y"]], [0.3, 0.2])
        a.doStep(n * H, H)
    state = a.getFMUState()
    blob = a.serializeFMUstate(state)
    a.freeFMUState(state)
    first = []
    for n in range(10, 30):
        a.doStep(n * H, H)
        first.append(a.getReal([vr["H"]])[0])
    b, _, _kb = slave_of(pendulum, log)
    b.setFMUState(b.deSerializeFMUstate(blob))
    again = []
    for n in range(10, 30):
        b.doStep(n * H, H)
        again.append(b.getReal([vr["H"]])[0])
    assert again == first
    for s in (a, b):
        s.terminate()
        s.freeInstance()


def test_fmi3_a_diverging_step_is_discarded_and_the_master_can_go_back(tmp_path):
    """FMI 3.0: a diverging step is discarded (FMPy raises with the status), the master
    restores a saved state and goes on; doStep's out-arguments of a completed step."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    fmu = build(tmp_path, "pendulum.toml", "pendulum3", version="3")
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu), unzipdir=unzip_dir(fmu)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t3")
    s.instantiate()
    s.enterInitializationMode(startTime=0.0)
    s.exitInitializationMode()
    s.setFloat64([vr["load0.F.x"]], [0.2])
    s.doStep(0.0, 0.05)
    assert s.getFloat64([vr["time"]])[0] == 0.05
    state = s.getFMUState()
    s.setFloat64([vr["load0.F.x"]], [1e160])
    with pytest.raises(Exception) as e:
        s.doStep(0.05, 0.01)
    assert getattr(e.value, "status", None) == 2
    s.setFMUState(state)
    s.setFloat64([vr["load0.F.x"]], [0.2])
    event, terminate, early, last = s.doStep(0.05, 0.01)
    assert (event, terminate, early) == (False, False, False)
    assert last == pytest.approx(0.06, abs=1e-15)
    assert abs(s.getFloat64([vr["balance_error"]])[0]) <= 1e-12
    s.freeFMUState(state)
    s.terminate()
    s.freeInstance()


def test_a_moving_support_from_the_master_follows_its_inputs_with_an_exact_balance(tmp_path):
    """The mooring line from its equilibrium, the fairlead's heave as the FMU's position
    inputs: set at t_n to where `phstring run` has the fairlead at t_n + h (positions.csv),
    the FMU moves the fairlead there exactly, keeps its balance, and receives the work of the
    reaction over the fairlead's path. Between communication points the FMU's fairlead moves
    on straight ramps at the ramp's speed while the run's follows the sine at the sine's
    speed, so the two agree as the same physics, not bit for bit (the FMU is the library
    driven by the same ramps bit for bit: crates/phstring-fmu/tests/fmu.rs)."""
    h = 0.005  # s: at 0.01 s the run halves a step, and a half step samples the heave's sine
    # The heave without the example's build-up, so that it moves from the start.
    sine = 'boundary.1.position=["120", "60 + 1.0 * sin(2*pi*t/10)"]'
    sets = ["boundary.1.external=true", sine, f"time.h={h}", "time.end=0.5", "fmu.nodes=[160]"]
    fmu = build(tmp_path, ROOT / "examples" / "slack_wire.toml", "mooring", *sets)
    out = tmp_path / "run"
    args = [BIN, "run", str(ROOT / "examples" / "slack_wire.toml"), "--out", str(out), "--quiet",
            "--set", "output.stride=1", "--set", "output.vtk=false", "--set", "output.plots=false",
            "--set", "output.animation=false"]
    for s_ in sets:
        args += ["--set", s_]
    subprocess.run(args, check=True, capture_output=True)
    pos = columns(out / "positions.csv")
    fair = pos["node"] == 160
    x, y = pos["x"][fair], pos["y"][fair]
    assert len(x) == 101
    t = np.arange(0.0, 0.5 + h / 2, h)
    sig = np.array(list(zip(t, np.append(x[1:], x[-1]), np.append(y[1:], y[-1]))),
                   dtype=[("time", np.float64), ("motion0.x", np.float64), ("motion1.y", np.float64)])
    res = simulate_fmu(str(fmu), stop_time=0.5, output_interval=h, input=sig,
                       output=["H", "supplied", "support160.R.x", "support160.R.y", "balance_error",
                               "node160.r.x", "node160.r.y"])
    energy = columns(out / "energy.csv")
    assert np.all(energy["h"][1:] == h), "the run took a halved step"
    assert np.array_equal(res["node160.r.x"], x) and np.array_equal(res["node160.r.y"], y)
    assert np.abs(res["balance_error"]).max() <= 1e-12 * np.abs(res["H"]).max()
    # The work of the reaction over the path; the rest of the supply is the kinetic energy the
    # held velocity imposes beyond its impulse's work at each change of the ramps' slope, of
    # order ½ m |Δs|² with the fairlead's mass m ≤ ρA l = 20 kg (most of it at the start,
    # where the fairlead jumps from rest to the sine's 0.63 m/s: 1.3 J).
    work = np.sum(res["support160.R.x"][1:] * np.diff(x) + res["support160.R.y"][1:] * np.diff(y))
    slopes = np.concatenate([[[0.0, 0.0]], np.column_stack([np.diff(x), np.diff(y)]) / h])
    jumps = np.sum(np.diff(slopes, axis=0) ** 2)
    assert abs(work - res["supplied"][-1]) <= 20.0 * jumps
    assert 1.0 < abs(work - res["supplied"][-1])
    assert abs(work) > 1e3  # J: 0.3 m up in 0.5 s against ~1e5 N
    # The same physics as the run: Ĥ within 1e-3 of it (the ramps' speed is not the sine's).
    assert np.abs(res["H"] - energy["hamiltonian"]).max() < 1e-3 * np.abs(energy["hamiltonian"]).max()
    assert res["support160.R.y"][1] > 5e4  # N: the line pulls the fairlead down with ~75 kN


def test_a_3d_network_with_a_moving_fairlead(tmp_path):
    """examples/platform_3d.toml (four steel wires, a point mass, FMI 3.0): the heaving
    fairlead's z is an input; raising it 1 cm over 0.02 s lifts the node by exactly that and
    keeps the balance."""
    fmu = build(tmp_path, ROOT / "examples" / "platform_3d.toml", "platform",
                "boundary.0.external=true", "fmu.nodes=[\"corner0\"]", version="3")
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    names = [v.name for v in md.modelVariables]
    # corner0 is mesh node 1 (named nodes are numbered first; node 0 is the platform).
    assert "motion0.z" in names and "EA.steel" in names and "support1.R.z" in names
    z0 = float(next(v.start for v in md.modelVariables if v.name == "motion0.z"))
    t = np.array([0.0, 0.02, 0.04])
    sig = np.array(list(zip(t, [z0 + 0.01] * 3)), dtype=[("time", np.float64), ("motion0.z", np.float64)])
    res = simulate_fmu(str(fmu), stop_time=0.04, output_interval=0.02, input=sig,
                       output=["node1.r.z", "supplied", "balance_error", "H"])
    assert res["node1.r.z"][0] == z0
    assert res["node1.r.z"][1] == z0 + 0.01
    assert res["node1.r.z"][2] == z0 + 0.01
    assert res["supplied"][-1] != 0.0
    assert np.abs(res["balance_error"]).max() <= 1e-12 * np.abs(res["H"]).max()


def test_a_buoy_on_the_mooring_line_coupled_against_the_same_buoy_in_one_step(tmp_path):
    """examples/fmu/buoy_master.py: the buoy sets the fairlead, the line's pull acts on the
    buoy one communication step late, against examples/fmu/buoy_monolithic.toml, the same buoy
    as a rigid body in the line's exact step. Both balances hold to rounding; the line
    receives sum(R_new . dr) (up to the held velocity's impact energies at the ramps'
    corners); the coupled buoy follows the monolithic one to a few mm at H = 0.01 s and moves
    away from it as H grows, and the explicit coupling's energy defect (the buoy used R_old)
    grows with H."""
    fmu = buoy_master.build_fmu(BIN, tmp_path / "mooring.fmu")
    exact = buoy_master.monolithic(BIN, tmp_path / "monolithic", t_end=10.0)
    assert np.nanmax(np.abs(exact["balance_error"])) <= 1e-13 * np.abs(exact["hamiltonian"]).max()
    assert 0.3 < np.abs(exact["z"]).max() < 1.5  # m: driven by a 0.5 m wave near resonance
    runs = {H: buoy_master.coupled(fmu, t_end=10.0, comm_step=H) for H in (0.01, 0.02)}
    r = runs[0.01]
    assert np.abs(r["balance_error"]).max() <= 1e-12 * np.abs(r["H"]).max()
    pull = np.hypot(r["Rx"], r["Ry"])
    assert 1e4 < pull.min() and pull.max() < 4e4  # N: the line pulls, never goes slack
    received = np.sum(r["Rx"][1:] * np.diff(r["x"]) + r["Ry"][1:] * np.diff(r["z"]))
    # The work of the pull over the fairlead's path, up to the kinetic energy the held
    # velocity imposes beyond its impulse's work where the ramps' slope changes (of order
    # ½ m |Δs|², m ≤ ρA l = 20 kg the fairlead's mass).
    kinks = sum(np.sum(np.diff(np.concatenate([[0.0], np.diff(r[k]) / 0.01])) ** 2) for k in ("x", "z"))
    assert abs(received - r["supplied"][-1]) <= 20.0 * kinks
    off = {H: buoy_master.compare(c, exact) for H, c in runs.items()}
    assert off[0.01][1] < 5e-3  # m of heave, against a 0.76 m amplitude
    assert off[0.02][1] > 2.0 * off[0.01][1]  # the coupling's error shrinks with H
    defect = {H: abs(c["work_buoy"][-1] - c["supplied"][-1]) for H, c in runs.items()}
    exchanged = np.abs(r["supplied"]).max()
    assert defect[0.01] < 0.02 * exchanged
    assert defect[0.02] > defect[0.01]


def test_a_hook_block_driven_through_its_wrench_settles_at_the_static_equilibrium(tmp_path):
    """examples/fmu/hook_block.toml (a 2 t hook block on two 5.9 m slings, FMI 2.0 and the
    wrench port as input): the master ramps a force F0 = (4 kN, -1 kN) onto the block over
    2 s and damps the swing with -c v and the turn with -c_r w from the block's velocity
    outputs (c = 4 kN·s/m, about 0.7 of critical for the ~1.4 rad/s swing; c_r = 300
    N·m·s). After 20 s the block rests where `phstring statics` puts it under F0 (the same
    scenario with F0 as the wrench's expressions): its sling points within 1e-6 m (1e-7 m
    measured; without the turn's damping a swing-turn mode is left at 3e-5 m/s). The
    supports' reactions, averaged over the last second against the slings' remaining
    vibrations, carry the load: sum R_x = -F0_x and sum R_y = (m + slings) g - F0_y (closed
    form; the statics gives it to 3e-8 N); the balance holds to round-off."""
    fmu = build(tmp_path, "hook_block.toml", "hook_block")
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    v = {x.name: x for x in md.modelVariables}
    assert (v["body0.F.x"].causality, v["body0.F.x"].unit) == ("input", "N")
    assert (v["body0.M.z"].causality, v["body0.M.z"].unit) == ("input", "N.m")
    assert (v["body0.theta"].unit, v["body0.w.z"].unit, v["body0.vmid.x"].unit) == ("rad", "rad/s", "m/s")
    assert '"hook"' in v["body0.F.x"].description
    # The block's sling points, listed in [fmu] nodes: their node numbers from the descriptions.
    points = {p: next(int(n.split(".")[0][4:]) for n, x in v.items()
                      if n.startswith("node") and f'("hook.{p}")' in x.description) for p in ("left", "right")}

    f0 = np.array([4000.0, -1000.0])  # N
    c, c_r = 4000.0, 300.0  # N·s/m, N·m·s
    log = Log()
    s, vr, _keep = slave_of(fmu, log)
    get = lambda *names: np.array(s.getReal([vr[n] for n in names]))  # noqa: E731
    H_comm = 0.01
    start = {p: get(f"node{k}.r.x", f"node{k}.r.y") for p, k in points.items()}
    energies, reactions = [], []
    for n in range(2000):
        t = n * H_comm
        vel, w = get("body0.v.x", "body0.v.y"), get("body0.w.z")[0]
        force = f0 * min(t / 2.0, 1.0) - c * vel
        s.setReal([vr["body0.F.x"], vr["body0.F.y"], vr["body0.M.z"]], [force[0], force[1], -c_r * w])
        s.doStep(t, H_comm)
        energies.append(get("H", "balance_error"))
        reactions.append(get("support0.R.x", "support0.R.y") + get("support1.R.x", "support1.R.y"))
    energies = np.array(energies)
    assert np.abs(energies[:, 1]).max() <= 1e-12 * np.abs(energies[:, 0]).max()
    assert np.abs(get("body0.v.x", "body0.v.y")).max() < 1e-5  # m/s: at rest
    at = {p: get(f"node{k}.r.x", f"node{k}.r.y") for p, k in points.items()}
    reactions = np.mean(reactions[-100:], axis=0)
    s.terminate()
    s.freeInstance()

    # The statics of the same scenario with F0 as the wrench's expressions.
    text = (ROOT / "examples" / "fmu" / "hook_block.toml").read_text()
    text = text.replace('force = ["0", "0"]', f'force = ["{f0[0]}", "{f0[1]}"]')
    scenario = tmp_path / "hook_block_f0.toml"
    scenario.write_text(text.replace("external = true", "external = false"))
    out = tmp_path / "statics"
    subprocess.run([BIN, "statics", str(scenario), "--out", str(out), "--quiet"], check=True,
                   capture_output=True)
    eq = columns(out / "equilibrium.csv")
    for p, k in points.items():
        row = eq["node"] == k
        expected = np.array([eq["x"][row][0], eq["y"][row][0]])
        assert np.abs(at[p] - expected).max() < 1e-6, (p, at[p], expected)
    # F0 moved the block: the slings' V holds it sideways, so its points move by ~3 cm (the
    # right sling, pulled straighter, takes the force), 3e4 times the tolerance above.
    assert 0.02 < at["left"][0] - start["left"][0] < 0.05
    assert 0.02 < at["right"][0] - start["right"][0] < 0.05
    # Closed form of the supports' load: the block, the slings (2 kg/m over their reference
    # lengths, the 5.86 m chords over the prestretch 1.00011) and F0.
    slings = 2 * 2.0 * np.hypot(2.7, 5.2) / 1.00011
    weight = (2000.0 + slings) * 9.81
    assert abs(reactions[0] + f0[0]) <= 2e-5 * weight, reactions
    assert abs(reactions[1] - (weight - f0[1])) <= 2e-5 * weight, reactions


def test_fmi3_hook_block_states_with_the_body_continue_bit_for_bit(tmp_path):
    """FMI 3.0: the hook block's FMU validates, and a serialized state (the block's pose and
    velocities in the checkpoint, its port sample with it) continues bit for bit in another
    instance, the wrench input set again at each step."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    fmu = build(tmp_path, "hook_block.toml", "hook_block3", version="3")
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(str(fmu), unzipdir=unzip_dir(fmu))

    def slave(name):
        s = FMU3Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        s.instantiate()
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        return s

    outputs = [vr[n] for n in ("H", "body0.r.x", "body0.theta", "body0.wmid.z", "balance_error")]

    def run(s, first, last):
        rows = []
        for n in range(first, last):
            t = n * 0.02
            s.setFloat64([vr["body0.F.x"], vr["body0.M.z"]], [3000.0 * np.sin(1.3 * t), 200.0])
            s.doStep(t, 0.02)
            rows.append(s.getFloat64(outputs))
        return rows

    a = slave("a")
    run(a, 0, 10)
    state = a.getFMUState()
    blob = a.serializeFMUState(state)
    a.freeFMUState(state)
    first = run(a, 10, 30)
    assert abs(first[-1][1] - first[0][1]) > 1e-4  # m: the block moves
    b = slave("b")
    b.setFMUState(b.deserializeFMUState(blob))
    assert run(b, 10, 30) == first
    for s in (a, b):
        s.terminate()
        s.freeInstance()


def crane_fmu(tmp_path, version="2"):
    """examples/crane_hoisting_2d.toml with the trolley at rest and the winch's payout speed
    an FMU input (`external = true` instead of `payout`)."""
    text = (ROOT / "examples" / "crane_hoisting_2d.toml").read_text()
    payout = 'payout = "-15 * (3*min(t/30,1)^2 - 2*min(t/30,1)^3)"'
    drum = 'drum_position = ["6 * (3*min(t/8,1)^2 - 2*min(t/8,1)^3)", "0"]'
    assert payout in text and drum in text
    scenario = tmp_path / "crane_external.toml"
    scenario.write_text(text.replace(payout, "external = true").replace(drum, ""))
    return build(tmp_path, scenario, f"crane{version}", version=version)


@pytest.mark.parametrize("version", ["2", "3"])
def test_a_winch_speed_input_and_its_outputs_are_described(tmp_path, version):
    fmu = crane_fmu(tmp_path, version)
    assert validate_fmu(str(fmu)) == []
    v = {x.name: x for x in read_model_description(str(fmu)).modelVariables}
    assert (v["winch.hoist.speed"].causality, v["winch.hoist.speed"].unit) == ("input", "m/s")
    assert float(v["winch.hoist.speed"].start) == 0.0
    units = {n: v[f"winch.hoist.{n}"].unit for n in ("payout", "length", "vmid", "tension", "power", "energy")}
    assert units == {"payout": "m", "length": "m", "vmid": "m/s", "tension": "N", "power": "W", "energy": "J"}
    assert all(v[f"winch.hoist.{n}"].causality == "output" for n in units)


def test_the_crane_hauls_in_at_the_masters_speed_with_the_static_power(tmp_path):
    """The master hauls the 5 t payload in through the winch's speed input: a smooth ramp to
    0.3 m/s over 2 s (six periods of the payload's bounce on the rope, 0.34 s, so that it
    starts nearly quasi-statically), then 0.3 m/s to t = 6 s, one element going onto the drum
    at t = 4.33 s. The paid-out length is the master's sum of speed x H; over the constant
    phase -0.3 m/s x the time since its start. The power is the tension times the speed and
    the rope's stretch (the drum's reaction works on the drum node, which moves lambda per
    metre paid out): per step against the FMU's own tension output, and, averaged over the
    constant phase, against the static line tension g (m + rhoA l); at the cut the winch takes
    back the element's strain energy T^2 L / (2 EA) and the weight's potential rhoA g L^2 / 2
    of its upper node lifted L above the drum. The winch is the model's only port: its energy
    is `supplied` and the change of H, and the balance stays at rounding."""
    fmu = crane_fmu(tmp_path)
    log = Log()
    s, vr, _keep = slave_of(fmu, log)
    get = lambda *names: np.array(s.getReal([vr[n] for n in names]))  # noqa: E731
    w = lambda n: f"winch.hoist.{n}"  # noqa: E731
    h_comm, ramp, v0 = 0.01, 2.0, -0.3  # s, s, m/s
    ea, rho_a, m, g, el = 4.3e7, 4.1, 5000.0, 9.81, 1.0  # N, kg/m, kg, m/s^2, m
    h0 = get("H")[0]
    rows, paid = [], 0.0
    for n in range(600):
        t = n * h_comm
        x = min((t + h_comm / 2) / ramp, 1.0)
        speed = v0 * (3 * x**2 - 2 * x**3)
        s.setReal([vr[w("speed")]], [speed])
        s.doStep(t, h_comm)
        paid += speed * h_comm
        rows.append([t + h_comm, speed, paid, *get(w("payout"), w("length"), w("vmid"), w("tension"), w("power"),
                                               w("energy"), "H", "supplied", "balance_error")])
    s.terminate()
    s.freeInstance()
    r = np.array(rows)
    t, speed, paid, payout, length, vmid, tension, power, energy, H, supplied, balance = r.T
    # The payout is the held speeds' sum: 600 steps of rounding on at most 1.5 m.
    assert np.abs(payout - paid).max() <= 1e-12
    const = t > ramp + h_comm / 2
    assert np.abs(payout[const] - payout[const][0] - v0 * (t[const] - t[const][0])).max() <= 1e-12
    assert payout[-1] == pytest.approx(v0 * (6.0 - ramp / 2), abs=1e-12)  # the ramp pays half its time
    assert np.abs(length - (25.0 + payout)).max() <= 1e-12
    assert np.abs(vmid - speed).max() <= 1e-12
    # The step where an element went onto the drum: the length off it fell below 24 m.
    cut = np.flatnonzero(np.diff(np.floor(length)) < 0) + 1
    assert len(cut) == 1 and t[cut[0]] == pytest.approx(4.34, abs=1e-9)
    plain = const.copy()
    plain[cut] = False
    # Per step: power = -tension x stretch x speed, the stretch 1 + T/EA of the drum element.
    # The tension is the element's at the step's end, the power the step's mean: they differ
    # by the change of the tension over a step (the rope's vibrations left by the ramp), which
    # bounds the difference, with the weight of the drum element's half (rhoA g L / 2 x speed).
    quasi = -tension * (1.0 + tension / ea) * vmid
    jump = np.abs(np.diff(tension))[plain[1:]].max()  # N per step
    gap = np.abs(power - quasi)[plain]
    print(f"tension jumps up to {jump:.1f} N per step; power - tension x speed up to {gap.max():.1f} W")
    assert gap.max() <= (jump + rho_a * g * el / 2) * abs(v0)
    # At the cut the winch takes back the element's energy.
    k = cut[0]
    taken = (quasi[k] - power[k]) * h_comm
    element = tension[k] ** 2 * el / (2 * ea) + rho_a * g * el**2 / 2
    print(f"at the cut the winch took {taken:.3f} J, the element's strain and weight {element:.3f} J")
    assert abs(taken - element) <= (jump + rho_a * g * el / 2) * abs(v0) * h_comm + 1e-3 * element
    # Averaged over the constant phase (the cut aside) against the static line tension: the
    # vibrations' mean is the difference (the payload does not accelerate at constant speed).
    weight = g * (m + rho_a * length[plain])
    static = weight * (1.0 + weight / ea) * -v0
    print(f"mean power {power[plain].mean():.2f} W against the static {static.mean():.2f} W")
    assert power[plain].mean() == pytest.approx(static.mean(), rel=1e-3)
    # The winch is the only port.
    assert np.abs(energy - supplied).max() <= 1e-9 * np.abs(energy).max()
    assert np.abs(H - h0 - energy).max() <= 1e-9 * np.abs(energy).max()
    assert np.abs(balance).max() <= 1e-12 * np.abs(H).max()
    print(f"winch energy {energy[-1]:.2f} J, max |balance_error| {np.abs(balance).max():.3e} J of H {np.abs(H).max():.4e} J")
