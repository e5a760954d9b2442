"""A load-case campaign fanned out with Dask: the OC3-like spar deck driven by three surge
motions (2, 5 and 10 m at a 100 s period), one task per case, gathering the campaign table
that `phstring.campaign` returns for all cases at once (the same columns and values).

Usage: python3 dask_campaign.py OUT_DIR [T_END_S]   (default T_END_S = 300)

The local cluster here stands in for a real one: to use a cluster, replace the
`LocalCluster(...)` line by `Client("tcp://scheduler:8786")`; OUT_DIR must then be a folder
every worker can reach (a shared file system), as the deck and tables are."""

import math
import pathlib
import sys

import numpy as np
from dask.distributed import Client, LocalCluster

ROOT = pathlib.Path(__file__).resolve().parents[2]
DECK = str(ROOT / "examples" / "moordyn" / "spar_oc3_v2.dat")
AMPLITUDES = [2.0, 5.0, 10.0]


def surge_table(path: pathlib.Path, amplitude: float, t_end: float, period: float = 100.0) -> str:
    """Writes a platform table `t, x, y, z, roll, pitch, yaw` of surge
    `x = A sin(2πt/T) (1 − exp(−(t/30 s)²))` [m] (from rest), every 0.5 s up to `t_end`."""
    with open(path, "w") as f:
        f.write("t, x, y, z, roll, pitch, yaw\n")
        for i in range(int(round(t_end / 0.5)) + 1):
            t = 0.5 * i
            x = amplitude * math.sin(2 * math.pi * t / period) * (1 - math.exp(-((t / 30.0) ** 2)))
            f.write(f"{t}, {x!r}, 0, 0, 0, 0, 0\n")
    return str(path)


def one_case(deck: str, motion: str, out: str) -> dict:
    """One case on a worker: a campaign of one table, in a folder of its own."""
    import phstring  # imported on the worker

    return phstring.campaign(deck, [motion], out=out, jobs=1)


def gather(tables: list) -> dict:
    """The tables of single cases as one, in case order, with `run` the case's index."""
    table = {key: np.concatenate([t[key] for t in tables]) for key in tables[0]}
    table["run"] = np.concatenate([np.full(len(t["run"]), k) for k, t in enumerate(tables)])
    return table


def campaign_on(client: Client, deck: str, motions: list, out: pathlib.Path) -> dict:
    """The campaign of `deck` over `motions`, one Dask task per case."""
    outs = [str(out / f"case_{k:03}") for k in range(len(motions))]
    futures = client.map(one_case, [deck] * len(motions), motions, outs)
    return gather(client.gather(futures))


if __name__ == "__main__":
    out = pathlib.Path(sys.argv[1]).resolve()
    t_end = float(sys.argv[2]) if len(sys.argv) > 2 else 300.0
    out.mkdir(parents=True, exist_ok=True)
    motions = [surge_table(out / f"surge{a:g}.csv", a, t_end) for a in AMPLITUDES]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        table = campaign_on(client, DECK, motions, out)
    columns = ["case", "line", "status", "fair_ten_max", "fair_ten_max_t", "fair_ten_min",
               "anch_ten_max", "anch_ten_min", "grounded_length_min", "slack"]
    print(",".join(columns))
    for k in range(len(table["run"])):
        values = [table[c][k] for c in columns]
        values[0] = pathlib.Path(values[0]).name
        print(",".join(repr(float(v)) if isinstance(v, np.floating) else str(v) for v in values))
