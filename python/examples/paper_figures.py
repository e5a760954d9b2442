"""The paper's figures from Python (docs/method.md §12): the energies of the string pendulum
with the discrete gradient (DG) and the implicit midpoint rule (MP), and its configuration
at a few times. Writes paper_energy.png and paper_configuration.png into the folder given
as the first argument (default: the current one)."""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import phstring  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)
paper = str(ROOT / "examples" / "paper_pendulum.toml")

fig, ax = plt.subplots(figsize=(7, 4))
for scheme in ["dg", "mp"]:
    res = phstring.run(phstring.Scenario.from_file(paper, set=[f'time.scheme="{scheme}"']))
    ax.plot(res.t, res.hamiltonian, label=f"H ({scheme})")
    if scheme == "dg":
        ax.plot(res.t, res.kinetic, "--", label="T (dg)")
        ax.plot(res.t, res.potential, ":", label="V (dg)")
        dg = res
ax.set_xlabel("t [s]")
ax.set_ylabel("energy [J]")
ax.legend()
fig.tight_layout()
fig.savefig(out / "paper_energy.png", dpi=120)

fig, ax = plt.subplots(figsize=(5, 5))
for k in range(0, len(dg.t_positions), 20):
    r = dg.positions[k]
    ax.plot(r[:, 0], r[:, 1], "-", label=f"t = {dg.t_positions[k]:.1f} s")
ax.set_aspect("equal")
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out / "paper_configuration.png", dpi=120)
print(f"H(0) = {dg.hamiltonian[0]:.6f} J, H(1) = {dg.hamiltonian[-1]:.6f} J (dg)")
