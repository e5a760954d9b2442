"""Writes the platform motion tables of the example decks (`*_motion.csv` here), for
`phstring run DECK --motion TABLE`: columns t, x, y, z, roll, pitch, yaw [s, m, m, m, rad,
rad, rad], one row a second, starting at rest at the deck's pose.

Each table is a wave-frequency oscillation (surge, heave, pitch at the wave period) on a
slow surge drift (and, for the floaters, sway and yaw), built up over the first 30 s by
`(1 - cos(pi t / 30)) / 2`, so that the fairleads start from rest and no wave front runs
down the lines. Amplitudes are those of a moderate sea for each platform: a few metres of
surge, about a metre of heave, one or two degrees of pitch.

    python3 examples/moordyn/make_motions.py
"""

import math
import pathlib

HERE = pathlib.Path(__file__).resolve().parent
RAMP = 30.0  # s, build-up time


def ramp(t):
    return 0.5 * (1.0 - math.cos(math.pi * t / RAMP)) if t < RAMP else 1.0


def wave(a, period, t, phase=0.0):
    return a * math.sin(2.0 * math.pi * t / period + phase)


# name: (duration [s], wave period [s], surge [m], heave [m], pitch [rad],
#        drift period [s], drift surge [m], drift sway [m], yaw [rad])
TABLES = {
    "chain_shallow_50m": (300, 8.0, 1.2, 0.8, 0.02, 90.0, 2.0, 0.0, 0.0),
    "chain_intermediate_150m": (300, 10.0, 1.5, 1.0, 0.03, 100.0, 3.0, 0.0, 0.0),
    "chain_deep_320m": (300, 12.0, 2.0, 1.5, 0.03, 120.0, 5.0, 0.0, 0.0),
    "semi_oc4": (300, 10.0, 2.0, 1.0, 0.035, 110.0, 4.0, 1.0, 0.01),
    "spar_oc3": (600, 12.0, 1.5, 0.8, 0.02, 125.0, 6.0, 1.5, 0.005),
}


def rows(duration, period, surge, heave, pitch, drift_period, drift, sway, yaw):
    for k in range(duration + 1):
        t = float(k)
        r = ramp(t)
        yield (
            t,
            r * (wave(surge, period, t) + wave(drift, drift_period, t)),
            r * wave(sway, 1.3 * drift_period, t),
            r * wave(heave, period, t, 0.5 * math.pi),
            0.0,
            r * wave(pitch, period, t, 1.0),
            r * wave(yaw, 0.7 * drift_period, t),
        )


for name, spec in TABLES.items():
    lines = ["t,x,y,z,roll,pitch,yaw"]
    for t, x, y, z, roll, pitch, yaw in rows(*spec):
        lines.append(f"{t:g},{x:.4f},{y:.4f},{z:.4f},{roll:g},{pitch:.6f},{yaw:.6f}")
    (HERE / f"{name}_motion.csv").write_text("\n".join(lines) + "\n")
