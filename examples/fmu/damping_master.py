"""Closes a damping-injection loop around the hoist-rope FMU with FMPy as the master.

The FMU (examples/fmu/hoist.toml) takes the force on the payload as its input and gives the
payload's mid-step velocity as its output. At every communication point this master reads
the velocity v of the last step and sets the force u = -K_d v for the next communication
step (zero-order hold). The swing dies out; the FMU's energy balance
Ĥ(t) - Ĥ(0) - supplied = balance_error stays at rounding level, whatever the master does,
because the FMU accounts for the power of the force it held.

The same law inside the scenario (examples/damping_injection.toml, `control = { kd }`) is
evaluated implicitly at the mid-step; the coupled loop uses the velocity one communication
step old. The plot compares the kinetic energy of both.

    cargo build -p phstring-cli          # builds phstring and the FMU's library
    python3 examples/fmu/damping_master.py [--phstring target/debug/phstring] [--out DIR]

Needs fmpy, numpy and matplotlib (pip install fmpy numpy matplotlib).
"""

import argparse
import csv
import os
import pathlib
import shutil
import subprocess
import tempfile

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]


def build_fmu(phstring, scenario, out):
    """Runs `phstring fmu scenario -o out` and returns the path of the FMU."""
    subprocess.run([str(phstring), "fmu", str(scenario), "-o", str(out), "--quiet"], check=True)
    return pathlib.Path(out)


def closed_loop(fmu, kd=300.0, comm_step=0.01, t_end=20.0, h=None):
    """Runs the FMU `fmu` with u = -kd * v at the payload, communication step `comm_step`
    [s], up to `t_end` [s]; `h` [s] sets the FMU's internal step (default: the scenario's).
    Returns a dict of NumPy arrays: t, T, H, supplied, balance_error, u (force x), v (x)."""
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(str(fmu))
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipped,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="hoist",
    )
    try:
        slave.instantiate()
        if h is not None:
            slave.setReal([vr["h"]], [h])
        slave.setupExperiment(startTime=0.0, stopTime=t_end)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        outputs = [vr[n] for n in ("load0.v.x", "load0.v.y", "T", "H", "supplied", "balance_error")]
        inputs = [vr["load0.F.x"], vr["load0.F.y"]]
        steps = int(round(t_end / comm_step))
        rows = []
        v = np.zeros(2)
        u = np.zeros(2)
        vx, vy, T, H, supplied, balance = slave.getReal(outputs)
        rows.append((0.0, T, H, supplied, balance, 0.0, 0.0))
        for n in range(steps):
            t = n * comm_step
            u = -kd * v
            slave.setReal(inputs, list(u))
            slave.doStep(currentCommunicationPoint=t, communicationStepSize=comm_step)
            vx, vy, T, H, supplied, balance = slave.getReal(outputs)
            v = np.array([vx, vy])
            rows.append(((n + 1) * comm_step, T, H, supplied, balance, u[0], vx))
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    a = np.array(rows)
    names = ("t", "T", "H", "supplied", "balance_error", "u", "v")
    return {k: a[:, i] for i, k in enumerate(names)}


def monolithic(phstring, out, t_end=20.0):
    """`phstring run examples/damping_injection.toml` up to `t_end` (no settling stop);
    returns t and the kinetic energy from its energy.csv."""
    subprocess.run(
        [str(phstring), "run", str(ROOT / "examples" / "damping_injection.toml"), "--out", str(out),
         "--force", "--quiet", "--set", f"time.end={t_end}", "--set", "time.settle.kinetic=1e300",
         "--set", "output.vtk=false", "--set", "output.plots=false", "--set", "output.animation=false",
         "--set", "output.positions=false"],
        check=True,
    )
    with open(pathlib.Path(out) / "energy.csv") as f:
        rows = list(csv.DictReader(f))
    return np.array([float(r["t"]) for r in rows]), np.array([float(r["kinetic"]) for r in rows])


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--phstring", default=os.environ.get("PHSTRING_BIN", ROOT / "target" / "debug" / "phstring"))
    p.add_argument("--out", default=HERE, type=pathlib.Path, help="folder for coupled_run.png")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu(args.phstring, HERE / "hoist.toml", pathlib.Path(tmp) / "hoist.fmu")
        runs = {H: closed_loop(fmu, comm_step=H) for H in (0.01, 0.05)}
        t_mono, T_mono = monolithic(args.phstring, pathlib.Path(tmp) / "mono")
    for H, r in runs.items():
        print(
            f"H = {H:.2f} s: T(20 s) = {r['T'][-1]:.3e} J, supplied {r['supplied'][-1]:.1f} J, "
            f"Ĥ change {r['H'][-1] - r['H'][0]:.1f} J, max |balance_error| {np.abs(r['balance_error']).max():.1e} J"
        )
    print(f"monolithic (implicit law): T(20 s) = {T_mono[-1]:.3e} J")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    ax1.semilogy(t_mono, np.maximum(T_mono, 1e-12), "k-", lw=2, label="law inside the scenario (implicit)")
    for H, style in ((0.01, "C0--"), (0.05, "C1:")):
        r = runs[H]
        ax1.semilogy(r["t"], np.maximum(r["T"], 1e-12), style, label=f"FMU + FMPy master, H = {H} s")
    ax1.set_ylabel("kinetic energy T̂ [J]")
    ax1.legend()
    ax1.set_title("Damping injection u = −300 v at the payload")
    for H, style in ((0.01, "C0-"), (0.05, "C1-")):
        r = runs[H]
        ax2.plot(r["t"], np.abs(r["balance_error"]), style, label=f"|balance error|, H = {H} s")
    ax2.set_yscale("log")
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("|Ĥ(t) − Ĥ(0) − supplied| [J]")
    ax2.legend()
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out / "coupled_run.png", dpi=90)
    print(f"wrote {args.out / 'coupled_run.png'}")


if __name__ == "__main__":
    main()
