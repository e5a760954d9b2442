"""Overheads of the Python package, printed as a table:
1. the paper benchmark run from Python (`phstring.run`, in-process) against the CLI's time
   loop (`time_loop_s` of `phstring run`, the stepping alone), best of 5;
2. the per-step overhead of `Simulation.step()` from Python: a Python loop over `step()`
   against the same steps inside `phstring.run` (the Rust loop), on a 4-element pendulum
   (so that the step itself is short), per step, best of 5.

    python3 python/benches/overhead.py [path/to/phstring]
"""

import json
import pathlib
import subprocess
import sys
import tempfile
import time

import phstring

ROOT = pathlib.Path(__file__).resolve().parents[2]
PAPER = str(ROOT / "examples" / "paper_pendulum.toml")
BIN = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target" / "release" / "phstring")


def best(f, n=5):
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return min(out)


for label, sets in [("paper, N = 30", []), ("paper, N = 3000", ["mesh.elements=3000"])]:
    sc = phstring.Scenario.from_file(PAPER, set=sets)
    py = best(lambda: phstring.run(sc))
    cli = []
    for _ in range(5):
        with tempfile.TemporaryDirectory() as d:
            args = [BIN, "run", PAPER, "--out", d, "-q"]
            for s in sets:
                args += ["--set", s]
            subprocess.run(args, check=True, capture_output=True)
            cli.append(json.loads((pathlib.Path(d) / "summary.json").read_text())["time_loop_s"])
    print(f"{label}: phstring.run {py * 1e3:.3f} ms, CLI time loop {min(cli) * 1e3:.3f} ms, ratio {py / min(cli):.2f}")

steps = 20000
small = phstring.Scenario.from_file(PAPER, set=["mesh.elements=4", f"time.end={steps * 0.01}"])


def python_loop():
    sim = phstring.Simulation(small)
    for _ in range(steps):
        sim.step()


loop = best(python_loop)
rust = best(lambda: phstring.run(small))
print(f"Simulation.step() from Python: {loop / steps * 1e6:.2f} us/step, Rust loop {rust / steps * 1e6:.2f} us/step, overhead {(loop - rust) / steps * 1e6:.2f} us/step")
