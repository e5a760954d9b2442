"""Load-case campaigns from Python: `phstring.campaign` runs a MoorDyn deck over several
vessel motion tables and returns the campaign table; the Dask example gathers the same
table case by case."""

import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import phstring

ROOT = pathlib.Path(__file__).resolve().parents[2]
SPAR = ROOT / "examples" / "moordyn" / "spar_oc3_v2.dat"

# A three-line spar after the OC3 example deck with 10 segments per line and a 0.01 s step.
DECK = """\
---------------------- MoorDyn v2 deck (campaign test) ------------------------
three catenary lines 120 degrees apart in 320 m of water, coarse
---------------------- LINE TYPES ----------------------------------------------
TypeName  Diam   Mass/m    EA          BA/-zeta  EI    Cd    Ca    CdAx  CaAx
(name)    (m)    (kg/m)    (N)         (N-s/-)   (N-m^2) (-) (-)   (-)   (-)
spar_line 0.09   77.7066   384.243e6   -0.8      0     1.6   1.0   0.1   0.0
---------------------- POINTS --------------------------------------------------
ID  Attachment  X         Y         Z       Mass  Volume  CdA  Ca
(#) (word)      (m)       (m)       (m)     (kg)  (m^3)   (m^2) (-)
1   Fixed       853.87    0.0       -320.0  0     0       0    0
2   Fixed      -426.935   739.47    -320.0  0     0       0    0
3   Fixed      -426.935  -739.47    -320.0  0     0       0    0
4   Vessel      5.2       0.0       -70.0   0     0       0    0
5   Vessel     -2.6       4.5033    -70.0   0     0       0    0
6   Vessel     -2.6      -4.5033    -70.0   0     0       0    0
---------------------- LINES ---------------------------------------------------
ID  LineType   AttachA  AttachB  UnstrLen  NumSegs  Outputs
(#) (name)     (#)      (#)      (m)       (-)      (-)
1   spar_line  1        4        902.2     10       -
2   spar_line  2        5        902.2     10       -
3   spar_line  3        6        902.2     10       -
---------------------- OPTIONS -------------------------------------------------
0.01      dtM        mooring time step (s)
320       WtrDpth    water depth (m)
1025      rho        water density (kg/m^3)
9.80665   g          gravity (m/s^2)
---------------------- END -----------------------------------------------------
"""


def table(path, amplitude):
    """2 s of surge x = -A (1 - cos(2 pi t / 4 s)) / 2 (away from line 1's anchor) [m]."""
    rows = ["t, x, y, z, roll, pitch, yaw"]
    for i in range(41):
        t = 0.05 * i
        x = -amplitude * (1 - math.cos(2 * math.pi * t / 4)) / 2
        rows.append(f"{t!r}, {x!r}, 0, 0, 0, 0, 0")
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def test_campaign_returns_the_extremes_of_each_case_and_a_failed_row(tmp_path):
    deck = tmp_path / "spar.dat"
    deck.write_text(DECK)
    small, large = table(tmp_path / "small.csv", 1.0), table(tmp_path / "large.csv", 4.0)
    bad = tmp_path / "bad.csv"
    lines = pathlib.Path(small).read_text().splitlines()
    lines[5] = "0.2, 1e, 0, 0, 0, 0, 0"
    bad.write_text("\n".join(lines) + "\n")
    out = tmp_path / "campaign"
    t = phstring.campaign(str(deck), [small, large, str(bad)], out=str(out), jobs=2,
                          set=["output.plots=false"])
    assert list(t["status"]) == ["completed"] * 6 + ["failed"]
    assert list(t["run"]) == [0, 0, 0, 1, 1, 1, 2]
    assert list(t["line"]) == [1, 2, 3, 1, 2, 3, -1]
    assert list(t["dir"][:4:3]) == ["run_000_small", "run_001_large"]
    assert "bad.csv:6" in t["error"][6] and np.isnan(t["fair_ten_max"][6])
    for run, folder in [(0, "run_000_small"), (1, "run_001_large")]:
        ends = np.genfromtxt(out / folder / "end_tensions.csv", delimiter=",", names=True)
        rows = t["run"] == run
        for line in (1, 2, 3):
            fair, anch = ends[f"FairTen{line}"], ends[f"AnchTen{line}"]
            k = np.flatnonzero(rows & (t["line"] == line))[0]
            assert t["fair_ten_max"][k] == fair.max()
            assert t["fair_ten_max_t"][k] == ends["t"][np.argmax(fair)]
            assert t["fair_ten_min"][k] == fair.min()
            assert t["anch_ten_max"][k] == anch.max() and t["anch_ten_min"][k] == anch.min()
            assert 0.0 < t["grounded_length_min"][k] < 902.2
    # Line 1 is pulled harder by the larger surge (measured 1.09 MN and 1.69 MN).
    assert t["fair_ten_max"][3] > 1.3 * t["fair_ten_max"][0] > 1.3e6


def test_dask_campaign_example_gives_the_campaign_table(tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "dask"
    done = subprocess.run(
        [sys.executable, str(ROOT / "python" / "examples" / "dask_campaign.py"), str(out), "20"],
        check=True, capture_output=True, text=True)
    printed = [line.split(",") for line in done.stdout.strip().splitlines()]
    header, rows = printed[0], printed[1:]
    assert len(rows) == 9 and all(r[header.index("status")] == "completed" for r in rows)
    motions = [str(out / f"surge{a}.csv") for a in (2, 5, 10)]
    direct = phstring.campaign(str(SPAR), motions, out=str(tmp_path / "direct"), jobs=2)
    for k, row in enumerate(rows):
        assert row[0] == pathlib.Path(direct["case"][k]).name
        assert int(row[1]) == direct["line"][k]
        for name in ["fair_ten_max", "fair_ten_max_t", "fair_ten_min", "anch_ten_max",
                     "anch_ten_min", "grounded_length_min"]:
            assert float(row[header.index(name)]) == direct[name][k], (k, name)
    # The surge (positive over the first 20 s, towards line 1's anchor) pulls lines 2 and 3
    # harder the larger it is.
    assert direct["fair_ten_max"][1] < direct["fair_ten_max"][4] < direct["fair_ten_max"][7]


def test_ctrl_c_stops_a_campaign_with_its_runs_resumable(tmp_path):
    """An OS signal during a campaign (SIGALRM after 0.5 s, whose handler raises
    KeyboardInterrupt as Ctrl-C's does) stops every run under way with a checkpoint and
    raises KeyboardInterrupt; the table marks the runs interrupted."""
    import csv
    import signal

    def interrupt(*_):
        raise KeyboardInterrupt

    deck = tmp_path / "spar.dat"
    deck.write_text(DECK)
    motions = [table(tmp_path / "a.csv", 1.0), table(tmp_path / "b.csv", 2.0)]
    out = tmp_path / "campaign"
    old = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        with pytest.raises(KeyboardInterrupt):
            # 1e5 steps per case: the runs cannot end before the signal.
            phstring.campaign(str(deck), motions, out=str(out), jobs=2, set=["time.end=1000"])
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    with open(out / "campaign.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["status"] for r in rows] == ["interrupted", "interrupted"]
    for folder in ["run_000_a", "run_001_b"]:
        assert (out / folder / "checkpoint.json").exists()
