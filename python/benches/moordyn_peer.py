"""phstring against MoorDyn 2.7.2 on the example decks of examples/moordyn, each under its
platform motion table: wall time per simulated second and the error of each code against
its own converged small-step reference, as a markdown table.

    python3 python/benches/moordyn_peer.py [--bin path/to/phstring] [--repeat 3] [--decks a,b]

The binary is `--bin`, else `$PHSTRING_BIN`, else `target/release/phstring`. MoorDyn is the
`moordyn` Python package (`pip install moordyn==2.7.2`).

How each code is run and measured (the same for every deck):

* **The motion.** Both codes move the deck's coupled points rigidly with the same platform
  table `t, x, y, z, roll, pitch, yaw`, interpolated the same way (each column by the C¹
  cubic Hermite polynomial with three-point slopes, held outside the table; `R = Rx Ry Rz`;
  docs/moordyn.md, docs/scenario.md "Motion and force tables"). phstring reads the table
  (`run DECK --motion TABLE`); MoorDyn gets, every coupling interval `DT_COUPLING`, the
  points' positions and velocities from this module's copy of that interpolant (it holds
  the velocity over the interval, as a coupled program does).
* **Time.** phstring: `time_loop_s` of summary.json (the steps alone: not the writing of
  the rows that follows each step, nor the start-up statics). MoorDyn: the loop of `moordyn.Step` calls (not `Init`, whose dynamic
  relaxation is MoorDyn's start-up). Each divided by the simulated time. The two codes run
  alternately, in the order phstring, MoorDyn then MoorDyn, phstring, `--repeat` times; the
  table gives the fastest run of each (the least disturbed by the other jobs of a shared
  machine).
* **Error.** The fairlead tension histories (MoorDyn: `|Fnet|` of the line's fairlead node,
  what its `.out` channel FAIRTEN writes; phstring: end_tensions.csv's FairTen) over the
  first ERROR_WINDOW s of the motion, against the same code's run on the same mesh at an
  eighth of the deck's `dtM` (REF_FACTOR): the largest difference over the lines and the
  sample times, relative to the largest reference tension. Both codes are sampled at the
  same times, every SAMPLE s (the coupling interval, at which MoorDyn's values exist); a
  phstring run whose steps do not land on a sample time is interpolated linearly there.
* **phstring's runs.** Fixed steps at multiples of `dtM` (PH_STEPS), and error control
  (`time.rtol = 0`, `time.atol` from PH_TOLERANCES, `time.h` a multiple of `dtM` from
  PH_CAPS as the largest step), also with the error per step (`time.error_per_step`, `time.atol`
  from PH_TOLERANCES_PER_STEP); the fixed steps and the runs with the error per step also
  with a looser Newton tolerance from a better start (FAST_NEWTON). The table names the
  fastest run whose error is no larger than MoorDyn's at the deck's `dtM`; every run is
  printed above it.
* **Start.** MoorDyn's `Init` can end with the lines still moving; its lines settle for
  SETTLE s with the vessel held (not timed) before the motion starts. phstring starts from
  its static equilibrium.
* **Outputs.** phstring writes energy.csv, ports.csv and end_tensions.csv every step
  (`output.row_stride` thins them), outside the time measured; positions, plots and
  ParaView files are off. MoorDyn writes nothing (its values are read through its API every SAMPLE s).
"""

import argparse
import json
import math
import os
import pathlib
import shutil
import subprocess
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
DECKS = ROOT / "examples" / "moordyn"

# The decks and their tables (examples/moordyn/NAME_v2.dat, NAME_motion.csv).
EXAMPLES = ["chain_shallow_50m", "chain_intermediate_150m", "chain_deep_320m", "semi_oc4", "spar_oc3"]

# Coupling interval of the MoorDyn driver [s]: OpenFAST's usual 0.0125 s or less.
DT_COUPLING = 0.01
# Seconds MoorDyn's lines settle with the vessel held after Init, before the motion starts:
# after 60 s the semi's three lines still differ by 0.085 %, which shows as 1.6e-3 of
# "error" between two step sizes; after 200 s, 0.013 %, and the step's own error shows.
SETTLE = 200.0
# The errors are measured over the first ERROR_WINDOW s of the motion (the references at
# small steps are costly), the times over the whole table.
ERROR_WINDOW = 60.0
# Both codes' tensions are compared every SAMPLE s [s]. Sampled every 0.1 s, MoorDyn's error
# on the shallow chain reads 4.3e-4; every 0.01 s, 1.1e-3: its largest deviations fall
# between the coarser samples, as phstring's do.
SAMPLE = DT_COUPLING
# Each code's reference runs at its deck's dtM / REF_FACTOR.
REF_FACTOR = 8
# phstring's steps, in multiples of the deck's dtM (its reference runs at dtM / REF_FACTOR); each
# divides the tables' 300 s and 600 s into whole steps at the decks' dtM of 0.5, 1 and
# 2 ms, as a fixed-step run needs (phstring refuses a step that does not).
PH_STEPS = (4, 5, 6, 8, 10, 12, 15, 16, 20, 24, 25, 30, 40, 50, 100)
# phstring with error control: the absolute tolerances of its positions [m] (`time.atol`,
# with `time.rtol = 0`) and the largest steps (`time.h`, in multiples of dtM) tried.
PH_TOLERANCES = (2e-7, 4e-7, 7e-7, 1e-6, 2e-6, 4e-6, 7e-6, 1e-5, 2e-5, 4e-5, 7e-5, 1e-4, 1.5e-4, 2e-4, 3e-4)
PH_CAPS = (10, 20)
# The same with `time.error_per_step = true` (the tolerance bounds each step's local error,
# not its error per unit step): tighter tolerances give the same error.
PH_TOLERANCES_PER_STEP = (
    1e-7, 2e-7, 4e-7, 7e-7, 1e-6, 2e-6, 4e-6, 1e-5, 1.5e-5, 2e-5, 2.5e-5, 3e-5, 5e-5, 1e-4,
)
# The fixed steps and the runs with the error per step again, with Newton stopped at 1e-10
# of the force scale (default 1e-12) from the acceleration predictor: on these decks the
# first iteration from that predictor mostly reaches 1e-10, so a step takes one iteration
# instead of two. The energy balance stays exact to about 1e-14 of the energies (each row
# prints its largest relative balance error).
FAST_NEWTON = ("newton.predictor=acceleration", "newton.rtol=1e-10")
FAST_LABEL = ", Newton 1e-10 from acceleration"


def deck_path(name):
    return DECKS / f"{name}_v2.dat"


def table_path(name):
    return DECKS / f"{name}_motion.csv"


# ---------------------------------------------------------------- the platform motion


def three_point_slopes(t, x):
    """The slope at each sample of the parabola through it and its neighbours (one-sided
    three-point parabolas at the ends; the chord with two samples)."""
    n = len(t)
    h = np.diff(t)
    d = np.diff(x) / h
    if n == 2:
        return np.array([d[0], d[0]])
    m = np.empty(n)
    m[0] = ((2.0 * h[0] + h[1]) * d[0] - h[0] * d[1]) / (h[0] + h[1])
    m[1:-1] = (h[1:] * d[:-1] + h[:-1] * d[1:]) / (h[:-1] + h[1:])
    a, b = h[-1], h[-2]
    m[-1] = ((2.0 * a + b) * d[-1] - a * d[-2]) / (a + b)
    return m


class Sampled:
    """A column of a table: the C¹ cubic Hermite interpolant with three-point slopes, held
    at its end values (zero rate) outside the table."""

    def __init__(self, t, x):
        self.t = np.asarray(t, float)
        self.x = np.asarray(x, float)
        self.m = three_point_slopes(self.t, self.x)

    def _piece(self, t):
        if t < self.t[0] or t > self.t[-1]:
            return None
        i = int(np.searchsorted(self.t, t, side="right")) - 1
        return min(max(i, 0), len(self.t) - 2)

    def value(self, t):
        i = self._piece(t)
        if i is None:
            return self.x[0] if t < self.t[0] else self.x[-1]
        h = self.t[i + 1] - self.t[i]
        s = (t - self.t[i]) / h
        h01 = 3 * s * s - 2 * s**3
        h10 = s**3 - 2 * s * s + s
        h11 = s**3 - s * s
        return self.x[i] + h01 * (self.x[i + 1] - self.x[i]) + h * (h10 * self.m[i] + h11 * self.m[i + 1])

    def rate(self, t):
        i = self._piece(t)
        if i is None:
            return 0.0
        h = self.t[i + 1] - self.t[i]
        s = (t - self.t[i]) / h
        d01 = 6 * (s - s * s)
        d10 = 3 * s * s - 4 * s + 1
        d11 = 3 * s * s - 2 * s
        return d01 * (self.x[i + 1] - self.x[i]) / h + d10 * self.m[i] + d11 * self.m[i + 1]


def _axes(roll, pitch, yaw):
    (sf, cf), (st, ct), (sp, cp) = [(math.sin(a), math.cos(a)) for a in (roll, pitch, yaw)]
    r = [
        np.array([[1, 0, 0], [0, cf, -sf], [0, sf, cf]]),
        np.array([[ct, 0, st], [0, 1, 0], [-st, 0, ct]]),
        np.array([[cp, -sp, 0], [sp, cp, 0], [0, 0, 1]]),
    ]
    dr = [
        np.array([[0, 0, 0], [0, -sf, -cf], [0, cf, -sf]]),
        np.array([[-st, 0, ct], [0, 0, 0], [-ct, 0, -st]]),
        np.array([[-sp, -cp, 0], [cp, -sp, 0], [0, 0, 0]]),
    ]
    return r, dr


class Platform:
    """A platform table `t, x, y, z, roll, pitch, yaw` [s, m, m, m, rad, rad, rad]: a body
    point `b` [m] is at `p(t) + R(t) b`, `R = Rx(roll) Ry(pitch) Rz(yaw)`, and moves at
    `ṗ + Ṙ b`."""

    def __init__(self, path):
        rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        self.end = rows[-1, 0]
        self.channels = [Sampled(rows[:, 0], rows[:, k]) for k in range(1, 7)]

    def point(self, t, b):
        c = [ch.value(t) for ch in self.channels]
        (rx, ry, rz), _ = _axes(*c[3:])
        return np.array(c[:3]) + rx @ ry @ rz @ b

    def velocity(self, t, b):
        c = [ch.value(t) for ch in self.channels]
        rate = [ch.rate(t) for ch in self.channels]
        (rx, ry, rz), (dx, dy, dz) = _axes(*c[3:])
        r_dot = dx @ ry @ rz * rate[3] + rx @ dy @ rz * rate[4] + rx @ ry @ dz * rate[5]
        return np.array(rate[:3]) + r_dot @ b


# ---------------------------------------------------------------- MoorDyn


def deck_with_dtm(src, dst, factor):
    """Copies the deck `src` to `dst` with its `dtM` divided by `factor`; returns the new dtM."""
    lines = src.read_text().splitlines()
    dtm = None
    for i, line in enumerate(lines):
        f = line.split()
        if len(f) >= 2 and f[1].lower() == "dtm":
            dtm = float(f[0]) / factor
            lines[i] = f"{dtm:.6g}  dtM  " + " ".join(f[2:])
    dst.write_text("\n".join(lines) + "\n")
    return dtm


class _Quiet:
    """Sends the C library's standard output (MoorDyn prints every step) to /dev/null."""

    def __enter__(self):
        import sys

        sys.stdout.flush()
        self.saved = os.dup(1)
        self.null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self.null, 1)

    def __exit__(self, *exc):
        os.dup2(self.saved, 1)
        os.close(self.saved)
        os.close(self.null)


def moordyn_run(name, t_end, dtm_factor=1.0, settle=0.0, sample=0.1):
    """Runs deck `name` in MoorDyn under its motion table to `t_end` [s] (dtM divided by
    `dtm_factor`), after `settle` s with the vessel held at its start pose (MoorDyn's own
    initial-condition search can end before the lines are at rest; the motion then starts at
    its t = 0). Returns a dict: `t` (every `sample` s from 0), `fair` and `anch` (|Fnet| of
    each line's fairlead and anchor node, N, one column per line), `fairten`
    (GetLineFairTen: the end segment's tension), `loop_s` (wall time of the Step calls of
    the motion)."""
    import moordyn

    platform = Platform(table_path(name))
    work = pathlib.Path(tempfile.mkdtemp(prefix="md-peer-"))
    try:
        with _Quiet():
            return _moordyn_run(moordyn, platform, work, name, t_end, dtm_factor, settle, sample)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _moordyn_run(moordyn, platform, work, name, t_end, dtm_factor, settle, sample):
    deck = work / "deck.dat"
    deck_with_dtm(deck_path(name), deck, dtm_factor)
    system = moordyn.Create(str(deck))
    body = []
    for i in range(moordyn.GetNumberPoints(system)):
        p = moordyn.GetPoint(system, i + 1)
        if moordyn.GetPointType(p) == moordyn.POINT_TYPE_COUPLED:
            body.append(np.array(moordyn.GetPointPos(p)))
    steps = round(t_end / DT_COUPLING)
    # The coupled points' positions and velocities at every coupling time, computed before
    # the timed loop (as a coupled program has them from its own solution).
    xs, vs = [], []
    for k in range(steps + 1):
        t = k * DT_COUPLING
        xs.append([float(c) for b in body for c in platform.point(t, b)])
        vs.append([float(c) for b in body for c in platform.velocity(t, b)])
    moordyn.Init(system, xs[0], vs[0])
    lines = [moordyn.GetLine(system, i + 1) for i in range(moordyn.GetNumberLines(system))]
    ends = [moordyn.GetLineN(ln) for ln in lines]
    rest = [0.0] * len(vs[0])
    n_settle = round(settle / DT_COUPLING)
    for k in range(n_settle):
        moordyn.Step(system, xs[0], rest, k * DT_COUPLING - settle, DT_COUPLING)
    out = {"t": [], "fair": [], "anch": [], "fairten": []}

    def record(t):
        out["fair"].append([np.linalg.norm(moordyn.GetLineNodeForce(ln, n)) for ln, n in zip(lines, ends)])
        out["anch"].append([np.linalg.norm(moordyn.GetLineNodeForce(ln, 0)) for ln in lines])
        out["fairten"].append([moordyn.GetLineFairTen(ln) for ln in lines])
        out["t"].append(t)

    record(0.0)
    every = round(sample / DT_COUPLING)
    loop = 0.0
    for k in range(steps):
        start = time.perf_counter()
        moordyn.Step(system, xs[k], vs[k], k * DT_COUPLING, DT_COUPLING)
        loop += time.perf_counter() - start
        if (k + 1) % every == 0:
            record((k + 1) * DT_COUPLING)
    moordyn.Close(system)
    out = {key: np.array(v) for key, v in out.items()}
    out["loop_s"] = loop
    return out


# ---------------------------------------------------------------- phstring


def binary():
    return os.environ.get("PHSTRING_BIN", str(ROOT / "target" / "release" / "phstring"))


QUIET = ["output.vtk=false", "output.plots=false", "output.animation=false", "output.positions=false"]


def phstring_run(name, t_end, out, h=None, bin_path=None, sets=()):
    """`phstring run` of deck `name` with `--motion` its table to `t_end` [s] (time.h = `h`
    when given, and the `--set` assignments `sets`) into `out`, which is removed once read.
    Returns a dict: `t`, `fair`, `anch` (end_tensions.csv's FairTen and AnchTen columns, N),
    `loop_s` (summary.json's time_loop_s), `h`, `steps`."""
    sets = QUIET + [f"time.end={t_end}"] + list(sets)
    if h is not None:
        sets.append(f"time.h={h}")
    args = [bin_path or binary(), "run", str(deck_path(name)), "--motion", str(table_path(name)),
            "--out", str(out), "--force", "-q"]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, capture_output=True)
    rows = np.loadtxt(out / "end_tensions.csv", delimiter=",", skiprows=1, ndmin=2)
    header = (out / "end_tensions.csv").read_text().splitlines()[0].split(",")
    fair = [i for i, c in enumerate(header) if c.startswith("FairTen")]
    anch = [i for i, c in enumerate(header) if c.startswith("AnchTen")]
    summary = json.loads((out / "summary.json").read_text())
    shutil.rmtree(out, ignore_errors=True)  # a run at a small step writes tens of MB
    return {
        "t": rows[:, 0],
        "fair": rows[:, fair],
        "anch": rows[:, anch],
        "loop_s": summary["time_loop_s"],
        "h": summary["scenario"]["time"]["h"],
        "steps": summary["steps"],
        "balance": summary["max_relative_balance_error"],
    }


def phstring_statics(name, out, bin_path=None):
    """`phstring statics` of deck `name` into `out`, which is removed once read. Returns
    `(fair, anch)`: the magnitudes of the support reactions [N] at each line's fairlead and
    anchor (the deck's anchors are its first points, its fairleads the next ones, one per
    line, as in the example decks)."""
    args = [bin_path or binary(), "statics", str(deck_path(name)), "--out", str(out), "--force", "-q"]
    subprocess.run(args, check=True, capture_output=True)
    rows = np.loadtxt(out / "equilibrium.csv", delimiter=",", skiprows=1, ndmin=2)
    reaction = np.linalg.norm(rows[:, 4:7], axis=1)
    shutil.rmtree(out, ignore_errors=True)
    lines = sum(1 for line in deck_path(name).read_text().splitlines() if " Vessel " in f" {line} ")
    return reaction[lines : 2 * lines], reaction[:lines]


def on_times(t_src, values, t):
    """`values` (rows at times `t_src`) linearly interpolated at times `t`, column by column."""
    return np.column_stack([np.interp(t, t_src, values[:, k]) for k in range(values.shape[1])])


def relative_error(run, ref):
    """Largest |T − T_ref| over the reference's sample times and the lines, relative to the
    largest reference tension."""
    mine = on_times(run["t"], run["fair"], ref["t"])
    return float(np.max(np.abs(mine - ref["fair"])) / np.max(np.abs(ref["fair"])))


# ---------------------------------------------------------------- the bench


def deck_dtm(name):
    """The deck's dtM [s]."""
    for line in deck_path(name).read_text().splitlines():
        f = line.split()
        if len(f) >= 2 and f[1].lower() == "dtm":
            return float(f[0])
    raise ValueError(f"{deck_path(name)} has no dtM")


def ph_configs(dtm):
    """phstring's runs of a deck with step `dtm` [s]: `(label, h, sets)`, the fixed steps of
    PH_STEPS, then error control at each cap of PH_CAPS and tolerance of PH_TOLERANCES (error
    per unit step) and of PH_TOLERANCES_PER_STEP (error per step)."""
    runs, fast = [], []
    for f in PH_STEPS:
        label = f"h = {f * dtm * 1e3:g} ms"
        runs.append((label, f * dtm, ()))
        fast.append((label + FAST_LABEL, f * dtm, FAST_NEWTON))
    for cap in PH_CAPS:
        for atol in PH_TOLERANCES:
            label = f"atol {atol:g} m, h ≤ {cap * dtm * 1e3:g} ms"
            runs.append((label, cap * dtm, ("time.rtol=0", f"time.atol={atol}")))
        for atol in PH_TOLERANCES_PER_STEP:
            label = f"atol {atol:g} m per step, h ≤ {cap * dtm * 1e3:g} ms"
            sets = ("time.rtol=0", f"time.atol={atol}", "time.error_per_step=true")
            runs.append((label, cap * dtm, sets))
            fast.append((label + FAST_LABEL, cap * dtm, sets + FAST_NEWTON))
    return runs + fast


def bench(name, repeat):
    """Times both codes over the deck's whole table and measures their errors over its first
    ERROR_WINDOW s (see the module's docstring)."""
    t_end = float(Platform(table_path(name)).end)
    window = min(ERROR_WINDOW, t_end)
    dtm = deck_dtm(name)
    work = pathlib.Path(tempfile.mkdtemp(prefix="ph-peer-"))
    try:
        md_ref = moordyn_run(name, window, dtm_factor=REF_FACTOR, settle=SETTLE, sample=SAMPLE)
        h_ref = dtm / REF_FACTOR
        per_sample = round(SAMPLE / h_ref)
        # The reference's rows must fall on the sample times (every REF_FACTOR · SAMPLE / dtM
        # steps): a dtM that does not divide REF_FACTOR · SAMPLE would shift them.
        assert abs(per_sample * h_ref - SAMPLE) <= 1e-9 * SAMPLE, f"{name}: dtM {dtm} s"
        stride = f"output.row_stride={per_sample}"
        ph_ref = phstring_run(name, window, work / "ref", h=h_ref, sets=[stride])
        configs = ph_configs(dtm)
        md_times, md_err = [], None
        ph_times = {label: [] for label, _, _ in configs}
        # Per run, its error and step count: the same in every repeat (the runs are
        # deterministic), so taken from the first.
        ph_err = {}
        for k in range(repeat):
            for who in ("ph", "md") if k % 2 == 0 else ("md", "ph"):
                if who == "md":
                    md = moordyn_run(name, t_end, settle=SETTLE, sample=SAMPLE)
                    md_times.append(md["loop_s"])
                    md_err = relative_error(md, md_ref)
                    continue
                for label, h, sets in configs:
                    try:
                        r = phstring_run(name, t_end, work / "run", h=h, sets=sets)
                    except subprocess.CalledProcessError:
                        continue
                    finally:
                        shutil.rmtree(work / "run", ignore_errors=True)
                    ph_times[label].append(r["loop_s"])
                    if label not in ph_err:
                        ph_err[label] = (relative_error(r, ph_ref), r["steps"], r["balance"])
        rows = [(label, min(ts) / t_end, *ph_err[label]) for label, ts in ph_times.items() if ts]
        ok = [r for r in rows if r[2] <= md_err]
        return {
            "name": name, "t_end": t_end, "dtm": dtm,
            "md_per_s": min(md_times) / t_end, "md_err": md_err,
            "ph_rows": rows, "best": min(ok, key=lambda r: r[1]) if ok else None,
        }
    finally:
        shutil.rmtree(work, ignore_errors=True)


def table(results):
    out = [
        "| deck | simulated | MoorDyn dtM | MoorDyn wall/sim s | MoorDyn error "
        "| phstring run | phstring wall/sim s | phstring error | speed-up |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        b = r["best"]
        if b is None:
            label, per, err, _, _ = min(r["ph_rows"], key=lambda row: row[2])
            speed = "none at MoorDyn's error"
        else:
            label, per, err, _, _ = b
            speed = f"{r['md_per_s'] / per:.1f}×"
        out.append(
            f"| {r['name']} | {r['t_end']:.0f} s | {r['dtm'] * 1e3:g} ms | {r['md_per_s'] * 1e3:.2f} ms "
            f"| {r['md_err']:.1e} | {label} | {per * 1e3:.2f} ms | {err:.1e} | {speed} |"
        )
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", help="the phstring binary (default $PHSTRING_BIN, else target/release/phstring)")
    ap.add_argument("--repeat", type=int, default=3, help="alternating runs of each code (default 3)")
    ap.add_argument("--decks", default=",".join(EXAMPLES), help="comma-separated deck names")
    a = ap.parse_args()
    if a.bin:
        os.environ["PHSTRING_BIN"] = a.bin
    results = []
    for name in a.decks.split(","):
        r = bench(name, a.repeat)
        for label, per, err, steps, balance in r["ph_rows"]:
            print(f"# {name}: phstring {label}: {per * 1e3:.3f} ms per simulated s, {steps} steps, "
                  f"error {err:.2e}, relative balance error {balance:.1e}", flush=True)
        print(f"# {name}: MoorDyn dtM = {r['dtm']:g} s: {r['md_per_s'] * 1e3:.3f} ms per simulated s, "
              f"error {r['md_err']:.2e}", flush=True)
        results.append(r)
    print(table(results))


if __name__ == "__main__":
    main()
