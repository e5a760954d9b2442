"""phstring: port-Hamiltonian strings and cables with exact energy behaviour, from Python.

Units are SI (m, s, kg, N, J). `Scenario`, `Simulation` (stepping, inputs, ports,
checkpoints), `run`, `statics`, `modes`, `linearize` (scipy.sparse matrices) and
`campaign` (a MoorDyn deck over many vessel motions).
"""

# Helpers are imported under private names: the package's namespace (`dir(phstring)`) is
# its API and nothing else.
import csv as _csv
import io as _io
import json as _json
import os as _os
from typing import Any as _Any
from typing import Dict as _Dict
from typing import Optional as _Optional
from typing import Sequence as _Sequence

import numpy as _np

from ._phstring import Checkpoint, Scenario, ScenarioError, Simulation, StepError
from ._phstring import __version__
from ._phstring import campaign_raw as _campaign_raw
from ._phstring import linearize_raw as _linearize_raw
from ._phstring import modes, statics
from ._phstring import run as _run_in_process
from ._phstring import run_to_folder as _run_to_folder

__all__ = [
    "Checkpoint",
    "Result",
    "Scenario",
    "ScenarioError",
    "Simulation",
    "StepError",
    "campaign",
    "campaign_table",
    "linearize",
    "modes",
    "run",
    "statics",
    "__version__",
]

_ENERGY = {
    "t": "t",
    "kinetic": "kinetic",
    "potential": "potential",
    "hamiltonian": "hamiltonian",
    "supplied": "supplied_energy",
    "dissipated": "dissipated_energy",
    "balance_error": "balance_error",
    "h": "h",
    "newton_iterations": "newton_iterations",
}


class Result:
    """What `run` returns. One entry per step from t = 0 (NumPy arrays): `t` [s],
    `kinetic`, `potential`, `hamiltonian`, `supplied`, `dissipated`, `balance_error` [J],
    `h` [s], `newton_iterations`; `positions` [m] of shape (frames, nodes, d) at the times
    `t_positions` [s] (every `output.stride` steps and the last); `summary`: `summary.json`
    as a dict when the run wrote a folder, else None."""

    def __init__(self, arrays: _Dict[str, _Any], summary: _Optional[dict]):
        for key, value in arrays.items():
            setattr(self, key, value)
        self.summary = summary

    def __repr__(self) -> str:
        return f"Result(steps={len(self.t) - 1}, t_end={self.t[-1]})"


def run(scenario: Scenario, out: _Optional[str] = None, progress: bool = False) -> Result:
    """Runs `scenario` to its end time and returns a `Result`. With `out`, it runs exactly as
    `phstring run` into that folder (all outputs, plots, ParaView) and reads the arrays back
    from it; without, in-process, writing nothing. Either way the values are those of the
    CLI's `energy.csv`, bit for bit. Ctrl-C raises KeyboardInterrupt after the current step
    (with `out`, the folder then holds a checkpoint to resume from). With `progress`, a
    one-line progress display on standard error."""
    if out is None:
        return Result(_run_in_process(scenario, progress), None)
    summary = _json.loads(_run_to_folder(scenario, _os.fspath(out), progress))
    energy = _np.genfromtxt(_os.path.join(out, "energy.csv"), delimiter=",", names=True)
    arrays: _Dict[str, _Any] = {key: _np.asarray(energy[col]) for key, col in _ENERGY.items()}
    arrays["newton_iterations"] = arrays["newton_iterations"].astype(_np.int64)
    pos_file = _os.path.join(out, "positions.csv")
    if _os.path.exists(pos_file):
        pos = _np.loadtxt(pos_file, delimiter=",", skiprows=1, ndmin=2)
        nodes = int(pos[:, 1].max()) + 1
        frames = pos.shape[0] // nodes
        arrays["t_positions"] = pos[::nodes, 0]
        arrays["positions"] = pos[:, 2:].reshape(frames, nodes, -1)
    return Result(arrays, summary)


def linearize(scenario: Scenario, form: str = "reduced") -> _Dict[str, _Any]:
    """The linear port-Hamiltonian model `E x' = (J - R) Q x + B u`, `y = B^T Q x` about the
    static equilibrium (docs/method.md §16), form "reduced" (x = (q, v)) or "full"
    (x = (r, v, C)): a dict with `E`, `J`, `R`, `Q`, `B` as scipy.sparse CSC matrices,
    `states` (names) and `inputs` ((node, component) of each force port). Needs scipy.
    For pyMOR: `PHLTIModel.from_matrices(m["J"], m["R"], m["B"], E=m["E"], Q=m["Q"])`."""
    import scipy.sparse

    raw = _linearize_raw(scenario, form)
    out: _Dict[str, _Any] = {"states": raw["states"], "inputs": raw["inputs"]}
    for name in "EJRQB":
        m = raw[name]
        out[name] = scipy.sparse.csc_matrix((m["data"], m["indices"], m["indptr"]), shape=m["shape"])
    return out


# The columns of campaign.csv that are text, integers (-1 where empty) and booleans; the
# others are numbers (NaN where empty).
_CAMPAIGN_TEXT = ("dir", "case", "name", "status", "error")
_CAMPAIGN_INT = ("run", "line", "slack_steps")


def campaign_table(text: str) -> _Dict[str, _Any]:
    """The campaign table `campaign.csv` (its text) as a dict of NumPy arrays, one entry per
    column and one element per row (a row per case and line): `run`, `line`, `slack_steps`
    as integers (-1 where empty: a failed case), `slack` as booleans, `dir`, `case`, `name`,
    `status`, `error` and other varied keys as text, the extremes as floats [N, s, m]
    (NaN where empty). docs/moordyn.md, "Campaigns", lists the columns."""
    rows = list(_csv.reader(_io.StringIO(text)))
    header, body = rows[0], rows[1:]
    known = set(_CAMPAIGN_TEXT) | set(_CAMPAIGN_INT) | {"slack"}
    first_value = header.index("status") + 1
    table: _Dict[str, _Any] = {}
    for k, name in enumerate(header):
        col = [r[k] for r in body]
        if name in _CAMPAIGN_INT:
            table[name] = _np.array([int(v) if v else -1 for v in col], dtype=_np.int64)
        elif name == "slack":
            table[name] = _np.array([v == "true" for v in col], dtype=bool)
        elif name in known or k < first_value:
            table[name] = _np.array(col, dtype=str)
        else:
            table[name] = _np.array([float(v) if v else _np.nan for v in col], dtype=_np.float64)
    return table


def campaign(
    deck: str,
    motions: _Sequence[str],
    out: str,
    jobs: _Optional[int] = None,
    set: _Optional[_Sequence[str]] = None,
    ignore: _Optional[_Sequence[str]] = None,
) -> _Dict[str, _Any]:
    """Runs the MoorDyn deck `deck` once per vessel motion table in `motions` (columns
    `t, x, y, z, roll, pitch, yaw` [s, m, rad]), as `phstring sweep DECK --vary
    motion=a.csv,b.csv --out OUT`: each case exactly as `phstring run DECK --motion a.csv`,
    `jobs` at a time (default: the number of cores), into `out/run_NNN_STEM/`, with `set`
    overrides and `ignore` words as the CLI takes them. Returns the campaign table
    (`campaign_table`): per case and line the largest and smallest fairlead and anchor
    tensions [N], the time of the largest fairlead tension [s], the smallest grounded length
    [m] and whether the line went slack. A case that fails is a row with `status` "failed"
    and its reason in `error`. Ctrl-C stops the runs and raises KeyboardInterrupt."""
    text = _campaign_raw(
        _os.fspath(deck),
        [_os.fspath(m) for m in motions],
        _os.fspath(out),
        jobs,
        None if set is None else list(set),
        None if ignore is None else list(ignore),
    )
    return campaign_table(text)
