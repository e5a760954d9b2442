"""MoorDyn 2.7.2 as a peer of phstring on a free body with added mass (a deck's BODIES `Ca`).

Optional: skipped when the `moordyn` package (`pip install moordyn==2.7.2`) is not
importable or `PHSTRING_BIN` (the phstring binary) is not set.

* **The mass matrix.** MoorDyn's body mass matrix about its reference point (`GetBodyM`, in
  space axes; MoorDyn 2.7.2 copies only its first three rows out, the translational ones) with
  `Ca` less the same without `Ca` is its added mass `rho_w V diag(Ca_x, Ca_y, Ca_z)` with no
  coupling to the rotation. phstring's mapping gives the added mass about the centre of mass,
  `A_C = T^T A_O T` with the lever `CG` (`added_mass` in the generated scenario); moved back
  to the reference point with `T^-1` its first three rows must be MoorDyn's, to rounding. The
  body's centre of gravity is off its reference point along all three axes, so the lever's
  couplings are all nonzero in `A_C` and must all cancel.
* **A heave period.** A buoyant body on one vertical tether (a linear spring, no drag or
  damping) started off its equilibrium: the heave periods of both codes, with and without
  `Ca`, against each other and the closed form `2 pi sqrt((m + A_z + m_n)/k)`. Both schemes'
  period errors at the 5 ms step are below 1e-4; the test asks for 1e-3.
* **Six `Ca` values** are refused by both codes (MoorDyn reads 1 or 3).
* **Three or six `CdA` values**: MoorDyn reads the first as 0 (a sinking body turned so
  that its x axis is vertical meets no drag), and phstring's mapping reads them so.
"""

import math
import os
import pathlib
import subprocess
import tomllib

import numpy as np
import pytest

moordyn = pytest.importorskip("moordyn")

pytestmark = pytest.mark.skipif(not os.environ.get("PHSTRING_BIN"), reason="PHSTRING_BIN is not set")

RHO_W = 1025.0
MASS, VOLUME = 2.0e5, 400.0  # kg, m^3
EA, LENGTH, TETHER_MASS = 1e8, 50.0, 1.0  # N, m, kg/m

DECK = """--- MoorDyn input ---
tethered buoy
---------------------- LINE TYPES ----------------------
Name    Diam  MassDen  EA   BA/-zeta  EI  Cd  Ca  CdAx  CaAx
(-)     (m)   (kg/m)   (N)  (N-s)     (-) (-) (-) (-)   (-)
tether  0.1   1.0      1e8  0         0   0   0   0     0
---------------------- BODIES ----------------------
ID  Attachment  X0  Y0  Z0     r0  p0  y0  Mass   CG     I    Volume  CdA  Ca
(#) (word)      (m) (m) (m)   (deg)(deg)(deg)(kg) (m)    (kg-m^2) (m^3) (m^2) (-)
1   Free        0   0   -44.5  0   0   0   2.0e5  {cg}  1e6  400     0    {ca}
---------------------- POINTS ----------------------
ID  Attachment  X   Y   Z      Mass  Volume  CdA  Ca
(#) (word)      (m) (m) (m)    (kg)  (m^3)   (m^2) (-)
1   Fixed       0   0   -100   0     0       0    0
2   Body1       0   0   -5     0     0       0    0
---------------------- LINES ----------------------
ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  Outputs
(#) (name)    (#)      (#)      (m)       (-)      (-)
1   tether    1        2        50        1        -
---------------------- OPTIONS ----------------------
0.005    dtM
9.80665  g
1025     rho
200      WtrDpth
0        TmaxIC
---------------------- END ----------------------
"""


def write_deck(tmp_path, name, cg, ca):
    path = tmp_path / f"{name}.dat"
    path.write_text(DECK.format(cg=cg, ca=ca))
    return path


def skew(c):
    return np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])


class MoorDyn:
    """A MoorDyn system of deck `path`, run in the deck's directory (its output files)."""

    def __init__(self, path):
        self.cwd = os.getcwd()
        os.chdir(path.parent)
        self.system = moordyn.Create(str(path))
        moordyn.Init(self.system, [], [])
        self.body = moordyn.GetBody(self.system, 1)
        self.t = 0.0

    def step(self, dt):
        moordyn.Step(self.system, [], [], self.t, dt)
        self.t += dt

    def close(self):
        moordyn.Close(self.system)
        os.chdir(self.cwd)


def moordyn_translational_mass(path):
    """MoorDyn's body mass matrix about the reference point, its first three rows (3 x 6)."""
    md = MoorDyn(path)
    try:
        md.step(0.005)  # the matrix is assembled in the first evaluation of the body's forces
        return np.array(moordyn.GetBodyM(md.body))[:3]
    finally:
        md.close()


def phstring_scenario(path):
    out = subprocess.run([os.environ["PHSTRING_BIN"], "check", str(path), "--print-scenario"],
                         check=True, capture_output=True, text=True).stdout
    return tomllib.loads(out)


def test_added_mass_about_the_reference_point_is_moordyns(tmp_path):
    cg = np.array([0.5, -0.3, 1.0])
    ca = np.array([0.8, 0.6, 0.4])
    with_ca = write_deck(tmp_path, "with_ca", "0.5|-0.3|1.0", "0.8|0.6|0.4")
    without = write_deck(tmp_path, "without", "0.5|-0.3|1.0", "0")
    md = moordyn_translational_mass(with_ca) - moordyn_translational_mass(without)
    a_o = np.zeros((3, 6))
    a_o[:, :3] = np.diag(RHO_W * VOLUME * ca)
    assert np.abs(md - a_o).max() <= 1e-9 * a_o.max(), md

    a_c = np.array(phstring_scenario(with_ca)["bodies"]["body1"]["added_mass"])
    assert np.abs(a_c[:3, 3:]).min() == 0.0 and np.abs(a_c[:3, 3:]).max() > 0.1 * a_o.max()
    t_inv = np.eye(6)
    t_inv[:3, 3:] = -skew(cg)
    back = t_inv.T @ a_c @ t_inv
    print("MoorDyn's added mass rows about the reference point:\n", md)
    print("phstring's, moved back from the centre of mass:\n", back[:3])
    assert np.abs(back[:3] - md).max() <= 1e-9 * a_o.max()


def turning_period(t, v):
    """Twice the mean spacing of the sign changes of `v` (linearly interpolated)."""
    i = np.where(np.sign(v[1:]) != np.sign(v[:-1]))[0]
    turns = t[i] + (t[i + 1] - t[i]) * v[i] / (v[i] - v[i + 1])
    assert len(turns) >= 4, turns
    return 2.0 * (turns[-1] - turns[0]) / (len(turns) - 1)


def moordyn_period(path, t_end=8.0, dt=0.005):
    md = MoorDyn(path)
    try:
        t, v = [], []
        while md.t < t_end - 0.5 * dt:
            md.step(dt)
            t.append(md.t)
            v.append(moordyn.GetBodyVel(md.body)[2])
        return turning_period(np.array(t), np.array(v))
    finally:
        md.close()


def phstring_period(path, out, t_end=8.0):
    subprocess.run([os.environ["PHSTRING_BIN"], "run", str(path), "--out", str(out), "--force", "-q",
                    "--set", "initial.equilibrium=false", "--set", f"time.end={t_end}",
                    "--set", "output.row_stride=1"],
                   check=True, capture_output=True)
    rows = np.genfromtxt(out / "bodies.csv", delimiter=",", names=True)
    return turning_period(rows["t"], rows["vz"])


def test_heave_period_with_added_mass_matches_moordyn(tmp_path):
    k = EA / LENGTH
    m_n = 0.5 * TETHER_MASS * LENGTH
    for ca, a_z in [("0", 0.0), ("0.3|0.6|1.0", RHO_W * VOLUME * 1.0)]:
        deck = write_deck(tmp_path, "heave", "1.0", ca)
        closed = 2.0 * math.pi * math.sqrt((MASS + a_z + m_n) / k)
        md = moordyn_period(deck)
        ph = phstring_period(deck, tmp_path / "run")
        print(f"Ca {ca}: heave period MoorDyn {md:.6f} s, phstring {ph:.6f} s, closed form {closed:.6f} s")
        assert abs(md / closed - 1.0) < 1e-3
        assert abs(ph / closed - 1.0) < 1e-3
        assert abs(ph / md - 1.0) < 1e-3


def test_six_added_mass_coefficients_are_refused_by_both(tmp_path):
    deck = write_deck(tmp_path, "six", "1.0", "1|1|1|1|1|1")
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        with pytest.raises(Exception):
            moordyn.Create(str(deck))
    finally:
        os.chdir(cwd)
    r = subprocess.run([os.environ["PHSTRING_BIN"], "check", str(deck)], capture_output=True, text=True)
    assert r.returncode != 0
    assert "MoorDyn reads 1 (all three axes) or 3" in r.stderr, r.stderr


SINKER = """--- MoorDyn input ---
a sinking body
---------------------- LINE TYPES ----------------------
Name    Diam  MassDen  EA   BA/-zeta  EI  Cd  Ca  CdAx  CaAx
(-)     (m)   (kg/m)   (N)  (N-s)     (-) (-) (-) (-)   (-)
chain   0.1   100.0    5e8  0         0   1.2 1   0.4   0
---------------------- BODIES ----------------------
ID  Attachment  X0  Y0  Z0    r0  p0  y0  Mass   CG  I    Volume  CdA  Ca
(#) (word)      (m) (m) (m)  (deg)(deg)(deg)(kg) (m) (kg-m^2) (m^3) (m^2) (-)
1   Free        0   0   -60   0   90  0   2.0e5  0   1e6  100     {cda}  0
---------------------- POINTS ----------------------
ID  Attachment  X   Y   Z      Mass  Volume  CdA  Ca
(#) (word)      (m) (m) (m)    (kg)  (m^3)   (m^2) (-)
1   Fixed       100 0   -100   0     0       0    0
2   Fixed       0   0   -100   0     0       0    0
---------------------- LINES ----------------------
ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  Outputs
(#) (name)    (#)      (#)      (m)       (-)      (-)
1   chain     1        2        100       5        -
---------------------- OPTIONS ----------------------
0.001    dtM
9.80665  g
1025     rho
200      WtrDpth
0        TmaxIC
---------------------- END ----------------------
"""


def test_moordyn_reads_the_first_of_three_or_six_drag_areas_as_zero(tmp_path):
    """A 200 t body of 100 m^3 pitched 90 deg (its x axis vertical) sinks for 3 s: with `CdA`
    = `5|0` it meets drag, with `5|5|5` and `5|5|5|0|0|0` it falls as without any, at
    `a = (rho_w V - m) g / m` (MoorDyn drops the first value, the x area). phstring's mapping
    reads them alike and refuses the unequal areas `[0, 5, 5]`, naming them."""
    a = (RHO_W * 100.0 - 2.0e5) * 9.80665 / 2.0e5
    for cda, dragged in [("5|0", True), ("5|5|5", False), ("5|5|5|0|0|0", False)]:
        path = tmp_path / "sinker.dat"
        path.write_text(SINKER.format(cda=cda))
        md = MoorDyn(path)
        try:
            while md.t < 3.0 - 0.0005:
                md.step(0.01)
            vz = moordyn.GetBodyVel(md.body)[2]
        finally:
            md.close()
        print(f"CdA {cda}: vz {vz:.6f} m/s after 3 s, without drag {a * 3.0:.6f} m/s")
        if dragged:
            assert vz > 0.9 * a * 3.0
        else:
            assert abs(vz / (a * 3.0) - 1.0) < 1e-9
    deck = write_deck(tmp_path, "per_axis", "1.0", "0").read_text().replace(
        "400     0    0", "400     5|5|5|0|0|0    0")
    (tmp_path / "per_axis.dat").write_text(deck)
    r = subprocess.run([os.environ["PHSTRING_BIN"], "check", str(tmp_path / "per_axis.dat")],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "which MoorDyn reads as [0.0, 5.0, 5.0] m² along the body axes" in r.stderr, r.stderr
