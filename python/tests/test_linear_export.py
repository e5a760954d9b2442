"""The linear port-Hamiltonian export of `phstring linearize`, read back with scipy (and
pyMOR when it is installed): the matrices are what manifest.json says they are."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
import scipy.io
import scipy.linalg
import scipy.sparse

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = os.environ.get("PHSTRING_BIN", str(ROOT / "target" / "debug" / "phstring"))


def linearize(tmp_path, example, *sets, modes=None):
    out = tmp_path / example
    args = [BIN, "linearize", str(ROOT / "examples" / f"{example}.toml"), "--out", str(out), "--quiet"]
    if modes is not None:
        args += ["--modes", str(modes)]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, capture_output=True)
    return out, json.loads((out / "manifest.json").read_text())


def load(out, entry):
    a = scipy.io.mmread(out / entry["mtx"]).tocsc()
    b = scipy.sparse.load_npz(out / entry["npz"]).tocsc()
    assert a.shape == tuple(entry["shape"]) == b.shape
    # MatrixMarket text round-trips exactly (shortest representation).
    assert (a != b).nnz == 0
    return b


def forms(out, manifest):
    for name, form in manifest["forms"].items():
        yield name, form, {k: load(out, v) for k, v in form["matrices"].items()}


@pytest.mark.parametrize("example", ["paper_pendulum", "steel_hoist", "damped_pendulum", "pd_tip_tracking"])
def test_structure(tmp_path, example):
    out, m = linearize(tmp_path, example)
    assert m["stable"]
    for name, form, mats in forms(out, m):
        n = len(form["states"])
        assert len(form["state_units"]) == n
        E, J, R, Q, B = (mats[k].toarray() for k in "EJRQB")
        assert E.shape == J.shape == R.shape == Q.shape == (n, n)
        assert B.shape == (n, len(m["inputs"])) and len(m["outputs"]) == len(m["inputs"])
        assert np.array_equal(J, -J.T), name
        assert np.array_equal(R, R.T)
        # R = 0 without damping; with it positive semidefinite (eigvalsh rounds: a relative
        # 1e-12 below zero is a zero eigenvalue).
        assert np.linalg.eigvalsh(R).min() >= -1e-12 * max(np.abs(R).max(), 1e-300), name
        assert (np.abs(R).max() > 0) == (example == "damped_pendulum"), name
        EQ = E.T @ Q
        scale = np.abs(EQ).max()
        assert np.abs(EQ - EQ.T).max() <= 1e-12 * scale, name
        assert np.abs(Q - Q.T).max() <= 1e-12 * np.abs(Q).max(), name
        # Positive semidefinite at the stable equilibrium: the hanging string is in tension.
        assert np.linalg.eigvalsh(0.5 * (EQ + EQ.T)).min() >= -1e-10 * scale, name
        assert np.linalg.eigvalsh(Q).min() >= -1e-10 * np.abs(Q).max(), name


def transfer(mats, s):
    E, J, R, Q, B = (mats[k].toarray() for k in "EJRQB")
    A = (J - R) @ Q
    return B.T @ Q @ np.linalg.solve(s * E - A, B)


@pytest.mark.parametrize("example", ["paper_pendulum", "damped_pendulum"])
def test_full_and_reduced_forms_have_one_transfer_function(tmp_path, example):
    out, m = linearize(tmp_path, example)
    f = dict((name, mats) for name, _, mats in forms(out, m))
    for w in [0.3, 1.0, 7.0, 50.0]:
        gf = transfer(f["full"], 1j * w)
        gr = transfer(f["reduced"], 1j * w)
        assert np.abs(gf - gr).max() <= 1e-8 * np.abs(gr).max(), w


def test_pymor_phltimodel(tmp_path):
    pymor = pytest.importorskip("pymor.models.iosys")
    out, m = linearize(tmp_path, "paper_pendulum")
    for name, _, mats in forms(out, m):
        fom = pymor.PHLTIModel.from_matrices(mats["J"], mats["R"], mats["B"], E=mats["E"], Q=mats["Q"])
        assert fom.dim_input == len(m["inputs"]) and fom.dim_output == len(m["outputs"])
        for w in [0.5, 5.0]:
            got = fom.transfer_function.eval_tf(1j * w)
            want = transfer(mats, 1j * w)
            assert np.abs(got - want).max() <= 1e-8 * np.abs(want).max(), (name, w)


def test_modal_truncation(tmp_path):
    """All 60 modes of the pendulum: the modal form has the reduced form's transfer function."""
    out, m = linearize(tmp_path, "paper_pendulum", modes=60)
    f = dict((name, mats) for name, _, mats in forms(out, m))
    Q = f["modal"]["Q"].toarray()
    assert np.all(np.diag(Q) >= 0.0) and np.array_equal(Q, np.diag(np.diag(Q)))
    for w in [0.3, 1.0, 7.0]:
        gm = transfer(f["modal"], 1j * w)
        gr = transfer(f["reduced"], 1j * w)
        assert np.abs(gm - gr).max() <= 1e-7 * np.abs(gr).max(), w
    # Fewer modes: still port-Hamiltonian, and the low-frequency error shrinks as modes are
    # added (measured 2.6 % of |G| at 0.3 rad/s with 10 modes).
    errs = []
    for k in [10, 20, 40]:
        out, m = linearize(tmp_path / f"k{k}", "paper_pendulum", modes=k)
        f = dict((name, mats) for name, _, mats in forms(out, m))
        assert len(m["forms"]["modal"]["states"]) == 2 * k
        gm = transfer(f["modal"], 0.3j)
        gr = transfer(f["reduced"], 0.3j)
        errs.append(np.abs(gm - gr).max() / np.abs(gr).max())
    assert errs[0] > errs[1] > errs[2], errs
