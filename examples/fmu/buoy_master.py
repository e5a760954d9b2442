"""A buoy moored by the string FMU, two-way coupled, against the same buoy inside the step.

The mooring line of examples/fmu/buoy_line.toml (160 m of steel wire rope, EA = 5e8 N, from
its static equilibrium) becomes an FMU whose fairlead position is an input (`external =
true`) and whose fairlead reaction is an output. This master integrates a 20 t buoy in surge
and heave,

    m x'' = F_drift            - c x' - R_x(t)
    m z'' = rho g (V - A_w z) - m g + k eta(t) - c z' - R_y(t),

with the waterplane's hydrostatic stiffness k = rho g A_w, a linear damping c, a regular
wave eta(t), a constant drift force F_drift and the line's pull on the buoy -R (R is the
force the buoy exerts on the line, the FMU's `support*.R`). The buoy's numbers come from
examples/fmu/buoy_monolithic.toml, where the same buoy is a rigid body attached to the same
line, integrated in the same exact step as the line (`phstring run`): the exact run the
co-simulation is compared with.

At every communication point the master advances the buoy with the line force of the last
step (explicit coupling), sets the fairlead to the buoy's new position (the FMU moves it
there at constant speed over the step) and reads the new reaction. The FMU keeps its own
energy balance exactly (balance_error); the coupling does not: the buoy used the line force
of the step before, so the work it did on the line, the sum of R_old . dr, differs from what
the line received (the FMU's `supplied`). The script prints that defect and how far the
coupled buoy drifts from the monolithic one.

    cargo build -p phstring-cli
    python3 examples/fmu/buoy_master.py [--phstring target/debug/phstring] [--out DIR]
"""

import argparse
import csv
import os
import pathlib
import shutil
import subprocess
import tempfile
import tomllib

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
LINE = HERE / "buoy_line.toml"
MONOLITHIC = HERE / "buoy_monolithic.toml"

WAVE = (0.5, 6.0)  # m, s: amplitude and period of the regular wave


def buoy_parameters():
    """The buoy of buoy_monolithic.toml: mass [kg], volume [m³], waterplane area [m²],
    linear drag [N·s/m], drift force [N], water density [kg/m³], gravity [m/s²]."""
    s = tomllib.loads(MONOLITHIC.read_text())
    b = s["bodies"]["buoy"]
    force = b["wrench"]["force"]
    k = s["water"]["density"] * -s["body_force"]["gravity"][1] * b["waterplane_area"]
    # The scenario's heave force must be the wave this master applies: k eta(t).
    assert force[1].replace(" ", "") == f"{k}*{WAVE[0]}*sin(2*pi*t/{WAVE[1]:g})", force[1]
    return dict(mass=b["mass"], volume=b["volume"], area=b["waterplane_area"],
                drag=b["linear_drag"], drift=float(force[0]), rho=s["water"]["density"],
                g=-s["body_force"]["gravity"][1])


def build_fmu(phstring, out):
    """The mooring line's FMU with the fairlead as its input and its reaction as an output."""
    subprocess.run(
        [str(phstring), "fmu", str(LINE), "-o", str(out), "--quiet",
         "--set", "boundary.1.external=true", "--set", "fmu.nodes=[80]"],
        check=True,
        capture_output=True,
    )
    return pathlib.Path(out)


def coupled(fmu, t_end=30.0, comm_step=0.01):
    """Runs the buoy and the line together up to `t_end` [s] with communication step
    `comm_step` [s]. Returns a dict of NumPy arrays: t, x and z (the buoy's position [m]),
    eta (wave [m]), Rx and Ry (fairlead reaction [N]), supplied (FMU) and work_buoy (the
    buoy's work on the line with the force it used [J]), balance_error [J], H [J]."""
    p = buoy_parameters()
    m, c = p["mass"], p["drag"]
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    # The fairlead is node 1 (the named nodes come first, in file order).
    reaction = ["support1.R.x", "support1.R.y"]
    unzipped = extract(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="mooring")
    try:
        slave.instantiate()
        slave.setupExperiment(startTime=0.0, stopTime=t_end)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        out = [vr[n] for n in reaction + ["supplied", "balance_error", "H"]]
        inputs = [vr["motion0.x"], vr["motion1.y"]]
        r = np.array(slave.getReal(inputs))
        v = np.zeros(2)
        # The line's pull at rest: the FMU reports port outputs after a step, so take one
        # step standing still.
        slave.setReal(inputs, list(r))
        slave.doStep(0.0, comm_step)
        Rx, Ry, supplied, balance, H = slave.getReal(out)
        R = np.array([Rx, Ry])
        work = 0.0
        rows = [(comm_step, *r, 0.0, *R, supplied, work, balance, H)]
        steps = int(round(t_end / comm_step))
        k = p["rho"] * p["g"] * p["area"]
        for n in range(1, steps):
            t = n * comm_step
            eta = WAVE[0] * np.sin(2 * np.pi * t / WAVE[1])
            force = np.array([
                p["drift"],
                p["rho"] * p["g"] * (p["volume"] - p["area"] * r[1]) - m * p["g"] + k * eta,
            ]) - c * v - R
            v = v + comm_step * force / m
            r_new = r + comm_step * v
            slave.setReal(inputs, list(r_new))
            slave.doStep(t, comm_step)
            work += R @ (r_new - r)  # the force the buoy used, over its displacement
            Rx, Ry, supplied, balance, H = slave.getReal(out)
            R = np.array([Rx, Ry])
            r = r_new
            rows.append((t + comm_step, *r, eta, *R, supplied, work, balance, H))
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    a = np.array(rows)
    names = ("t", "x", "z", "eta", "Rx", "Ry", "supplied", "work_buoy", "balance_error", "H")
    return {k: a[:, i] for i, k in enumerate(names)}


def monolithic(phstring, out, t_end=30.0):
    """`phstring run buoy_monolithic.toml` up to `t_end` [s] into folder `out`. Returns a dict
    of NumPy arrays: t, x and z (the buoy's centre [m]), fairlead (the line's tension at the
    buoy [N]) and energy.csv's columns at the same times (energies [J])."""
    subprocess.run(
        [str(phstring), "run", str(MONOLITHIC), "--out", str(out), "--quiet", "--force",
         "--set", f"time.end={t_end}"],
        check=True,
        capture_output=True,
    )
    with open(pathlib.Path(out) / "bodies.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["body"] in ("buoy", "0")]
    with open(pathlib.Path(out) / "energy.csv") as f:
        energy = list(csv.DictReader(f))
    with open(pathlib.Path(out) / "end_tensions.csv") as f:
        ends = {float(r["t"]): float(r["FairTen1"]) for r in csv.DictReader(f)}
    t = np.array([float(r["t"]) for r in rows])
    e = {float(r["t"]): r for r in energy}
    res = {"t": t, "x": np.array([float(r["x"]) for r in rows]),
           "z": np.array([float(r["y"]) for r in rows]),
           "fairlead": np.array([ends.get(ti, np.nan) for ti in t])}
    for key in energy[0]:
        if key != "t":
            res[key] = np.array([float(e[ti][key]) if ti in e else np.nan for ti in t])
    return res


def compare(c, m):
    """The coupled run `c` against the monolithic run `m` at the coupled run's times: the
    largest differences of the buoy's surge and heave [m]."""
    dx = np.interp(c["t"], m["t"], m["x"]) - c["x"]
    dz = np.interp(c["t"], m["t"], m["z"]) - c["z"]
    return np.abs(dx).max(), np.abs(dz).max()


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--phstring", default=os.environ.get("PHSTRING_BIN", ROOT / "target" / "debug" / "phstring"))
    p.add_argument("--out", default=HERE, type=pathlib.Path, help="folder for buoy_run.png")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        fmu = build_fmu(args.phstring, tmp / "mooring.fmu")
        runs = {H: coupled(fmu, comm_step=H) for H in (0.01, 0.02)}
        mono = monolithic(args.phstring, tmp / "monolithic")
    m0 = mono
    print(f"monolithic: supplied {m0['supplied_energy'][-1]:.1f} J, "
          f"dissipated {m0['dissipated_energy'][-1]:.1f} J, "
          f"max |balance_error| {np.nanmax(np.abs(m0['balance_error'])):.1e} J")
    for H, r in runs.items():
        dx, dz = compare(r, mono)
        print(f"H = {H} s: heave {r['z'].min():+.3f} … {r['z'].max():+.3f} m, "
              f"work on the line: FMU {r['supplied'][-1]:.1f} J, buoy's side {r['work_buoy'][-1]:.1f} J "
              f"(explicit coupling defect {r['work_buoy'][-1] - r['supplied'][-1]:+.1f} J); "
              f"off the monolithic run by {dx * 1e3:.1f} mm in surge, {dz * 1e3:.1f} mm in heave; "
              f"FMU max |balance_error| {np.abs(r['balance_error']).max():.1e} J")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = runs[0.01]
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    a1.plot(r["t"], r["eta"], "C7--", label="wave η")
    a1.plot(mono["t"], mono["z"], "C2-", lw=2.5, alpha=0.5, label="heave, monolithic")
    a1.plot(r["t"], r["z"], "C0-", label="heave, FMU-coupled")
    a1.set_ylabel("[m]")
    a1.legend(loc="upper right")
    a1.set_title("A 20 t buoy on the mooring-line FMU (FMPy master, H = 0.01 s)")
    a2.plot(r["t"], np.hypot(r["Rx"], r["Ry"]) / 1e3, "C3-", lw=0.6, label="FMU-coupled")
    a2.plot(mono["t"], mono["fairlead"] / 1e3, "C2-", lw=1.5, label="monolithic")
    a2.set_ylabel("fairlead pull |R| [kN]")
    a2.legend(loc="upper right")
    a3.plot(r["t"], r["supplied"] / 1e3, "C0-", label="received by the line (FMU)")
    a3.plot(r["t"], r["work_buoy"] / 1e3, "C1--", label="done by the buoy (lagged force)")
    a3.set_ylabel("work [kJ]")
    a3.set_xlabel("t [s]")
    a3.legend(loc="upper left")
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out / "buoy_run.png", dpi=90)
    print(f"wrote {args.out / 'buoy_run.png'}")


if __name__ == "__main__":
    main()
