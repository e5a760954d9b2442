"""MoorDyn 2.7.2 as a peer of phstring on the example decks of examples/moordyn: the static
fairlead and anchor tensions of both codes against each other and against the elastic
catenary with a grounded length, and the fairlead tension histories of both under the
deck's platform motion table.

Optional: skipped when the `moordyn` package (`pip install moordyn==2.7.2`) is not
importable or `PHSTRING_BIN` (the phstring binary) is not set. Both codes are driven by
python/benches/moordyn_peer.py (the same motion interpolant and rotation convention as
phstring's `--motion`; its docstring says how).

What is compared, and why the tolerances are what they are:

* phstring's tension at a line end is the magnitude of the force of the line on its end
  node (end_tensions.csv, or at rest the support's reaction in equilibrium.csv); MoorDyn's
  is `|Fnet|` of the end node (`GetLineNodeForce`, what its `.out` channels FAIRTEN and
  ANCHTEN write). Both are the end segment's tension plus the node's share of the wet weight
  (half a segment), which at rest is the tension of the continuous line at its end: the
  closed form. MoorDyn's `GetLineFairTen`, the end segment's tension alone, is short of it
  by about half a segment's weight (asserted below, so the two definitions stay apart).
* MoorDyn's lines after `Init` are not at rest (its initial-condition search ends on its
  own criterion): the lines settle for `SETTLE` s with the vessel held before anything is
  read or the motion starts.
"""

import math
import os
import pathlib
import sys

import numpy as np
import pytest

moordyn = pytest.importorskip("moordyn")

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python" / "benches"))

import moordyn_peer as peer  # noqa: E402

pytestmark = pytest.mark.skipif(not os.environ.get("PHSTRING_BIN"), reason="PHSTRING_BIN is not set")

RHO_W, G = 1025.0, 9.80665
SETTLE = 60.0  # s with the vessel held before MoorDyn's lines are read or moved
STRETCH = 40.0  # s of the motion compared

# Per deck: unstretched length [m], mass per length [kg/m], diameter [m], EA [N], the first
# line's anchor and fairlead [m] (the deck's positions; the other lines are alike), depth [m].
LINES = {
    "chain_shallow_50m": (350.0, 200.1, 0.1801, 8.5606e8, (358.0, 0.0, -50.0), (20.0, 0.0, -8.0), 50.0),
    "chain_intermediate_150m": (473.3, 130.4, 0.0809, 5.89e8, (422.5, 0.0, -150.0), (20.0, 0.0, -4.0), 150.0),
    "chain_deep_320m": (1100.0, 685.0, 0.333, 3.27e9, (1000.0, 0.0, -320.0), (35.0, 0.0, -14.0), 320.0),
    "semi_oc4": (835.5, 113.35, 0.0766, 7.536e8, (418.8, 725.383, -200.0), (20.434, 35.393, -14.0), 200.0),
    "spar_oc3": (902.2, 77.7066, 0.09, 384.243e6, (853.87, 0.0, -320.0), (5.2, 0.0, -70.0), 320.0),
}


def catenary_on_seabed(length, w, ea, x, hv):
    """The elastic catenary of a line of unstretched `length` [m], wet weight `w` [N/m] and
    axial stiffness `ea` [N] from an anchor on a rigid frictionless seabed to a fairlead `x`
    away and `hv` above the seabed, with a grounded part: `(H, V_F, L_b)` [N, N, m] from

        x  = L_b + (H/w) asinh(V_F/H) + H L/EA,
        hv = (H/w) (sqrt(1 + (V_F/H)^2) - 1) + w L_s^2/(2 EA),   V_F = w L_s, L_s = L - L_b.
    """

    def bisect(f, lo, hi):
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if f(mid) < 0.0 else (lo, mid)
        return 0.5 * (lo + hi)

    def suspended(h):
        return bisect(lambda ls: (h / w) * (math.sqrt(1.0 + (w * ls / h) ** 2) - 1.0) + w * ls * ls / (2.0 * ea) - hv,
                      0.0, length)

    def span(h):
        ls = suspended(h)
        return length - ls + (h / w) * math.asinh(w * ls / h) + h * length / ea - x

    h = bisect(span, 1.0, 1e9)
    ls = suspended(h)
    return h, w * ls, length - ls


def closed_form(name):
    """`(T_fairlead, T_anchor, w, segment)` [N, N, N/m, m] of deck `name`'s lines at rest."""
    length, mass, d, ea, anchor, fair, depth = LINES[name]
    w = (mass - RHO_W * math.pi / 4.0 * d * d) * G
    x = math.hypot(fair[0] - anchor[0], fair[1] - anchor[1])
    h, v, _ = catenary_on_seabed(length, w, ea, x, fair[2] + depth)
    segs = next(int(float(line.split()[5])) for line in peer.deck_path(name).read_text().splitlines()
                if line.split()[:1] == ["1"] and len(line.split()) == 7)
    return math.hypot(h, v), h, w, length / segs


@pytest.fixture(scope="module", params=list(LINES))
def deck(request):
    return request.param


def test_static_tensions_agree_with_moordyn_and_the_closed_form(deck, tmp_path):
    """At rest both codes solve the same lumped-mass model on the same mesh: phstring's
    statics by Newton, MoorDyn's by settling in time. Fairlead and anchor tensions of the
    two agree to 0.2 % (measured: at most 0.04 % at the fairleads, 0.1 % at the deep chain's
    anchor; MoorDyn's settling is not finished after its search and SETTLE s: the three
    lines of the symmetric semi differ by 0.085 % between themselves), and each is within
    0.5 % of the closed form (the mesh's O(l²) error: phstring's largest is the shallow
    chain's 0.32 %, MoorDyn's the same deck's 0.36 %)."""
    t_fair, t_anch, w, seg = closed_form(deck)
    ph_fair, ph_anch = peer.phstring_statics(deck, tmp_path / "statics", os.environ["PHSTRING_BIN"])
    md = peer.moordyn_run(deck, 0.0, settle=SETTLE)
    md_fair, md_anch, md_segment = md["fair"][0], md["anch"][0], md["fairten"][0]
    print(f"{deck}: closed form fairlead {t_fair:.0f} N, anchor {t_anch:.0f} N")
    print(f"  phstring fairlead {ph_fair}, anchor {ph_anch}")
    print(f"  MoorDyn  fairlead {md_fair}, anchor {md_anch}, GetLineFairTen {md_segment}")
    for ph, md_, cf in [(ph_fair, md_fair, t_fair), (ph_anch, md_anch, t_anch)]:
        assert np.all(np.abs(ph - md_) <= 2e-3 * cf), (ph, md_)
        assert np.all(np.abs(ph - cf) <= 5e-3 * cf), (ph, cf)
        assert np.all(np.abs(md_ - cf) <= 5e-3 * cf), (md_, cf)
    # GetLineFairTen is the end segment's tension: short of |Fnet| by about the vertical
    # half-segment weight's share, w (l/2) V/T, to a tenth of it.
    share = w * seg / 2.0 * np.sqrt(np.maximum(md_fair**2 - t_anch**2, 0.0)) / md_fair
    assert np.all(np.abs((md_fair - md_segment) - share) <= 0.1 * share), (md_fair - md_segment, share)


def test_fairlead_tension_histories_agree_under_the_motion(deck, tmp_path):
    """The first STRETCH s of the deck's motion table in both codes, each at the deck's dtM,
    sampled every 0.1 s: the fairlead tensions agree to 1 % of the largest in the RMS over
    the stretch and to 5 % at every sample (measured, RMS and largest: shallow chain 0.79 %
    and 3.9 %, intermediate 0.19 % and 0.71 %, deep 0.60 % and 1.9 %, semi 0.15 % and
    0.81 %, spar 0.072 % and 0.52 %). What is left is not phstring's time step (its run at
    four times this step differs from this one by 3e-4 of the tension on the shallow chain)
    but the two models' differences, largest in the short, near-taut shallow chain whose
    tension moves fastest: the internal damping (phstring's Kelvin–Voigt `2η ν² ν̇` equals
    MoorDyn's `BA ε̇` at small strain only), the damping and drag forces on the end node, in
    MoorDyn's `Fnet` but not in phstring's end force, and the vessel's velocity, which
    MoorDyn holds over each coupling interval."""
    ph = peer.phstring_run(deck, STRETCH, tmp_path / "run", bin_path=os.environ["PHSTRING_BIN"])
    md = peer.moordyn_run(deck, STRETCH, settle=SETTLE)
    mine = peer.on_times(ph["t"], ph["fair"], md["t"])
    scale = np.max(md["fair"])
    diff = np.abs(mine - md["fair"]) / scale
    largest, rms = np.max(diff), np.sqrt(np.mean(diff**2))
    swing = (np.max(md["fair"]) - np.min(md["fair"])) / scale
    print(f"{deck}: fairlead tension difference RMS {rms:.2e}, largest {largest:.2e} of the largest "
          f"{scale:.0f} N (the motion swings it by {swing:.2e})")
    assert swing > 0.05, "the motion moves the tension"
    assert rms <= 1e-2, rms
    assert largest <= 5e-2, largest
