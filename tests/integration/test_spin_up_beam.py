"""The spin-up beam (examples/spin_up.py, validation case spin_up_beam) against the
geometrically exact beam of validation/peers/spin_up_beam.py: the stiffened FFR solid
follows it within the issue's 0.5 % RMS of the peak, linear FFR diverges after the spin
passes the first bending frequency."""

import importlib.util
import io

import h5py
import numpy as np
import pytest

from validation.cases import spin_up_beam as case
from validation.peers import spin_up_beam as peer

import paths

EXAMPLE = paths.EXAMPLES / "spin_up.py"


@pytest.fixture(scope="module")
def reference():
    return peer.reference()


def load_example():
    spec = importlib.util.spec_from_file_location("spin_up_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_example_writes_v_tip_every_50_ms_and_follows_the_reference(tmp_path, reference):
    out = io.StringIO()
    load_example().main(["--out", str(tmp_path / "run")], out=out)
    with h5py.File(tmp_path / "run" / "spin_up.h5", "r") as f:
        assert f.attrs["status"] == "complete"
        t, v = f["t"][()], f["outputs/v_tip"][()]
    assert t.shape == v.shape == (401,)
    assert np.diff(t) == pytest.approx(0.05) and t[-1] == pytest.approx(20.0)
    t_ref, v_ref = reference
    error = np.sqrt(np.mean((v - np.interp(t, t_ref, v_ref)) ** 2)) / np.abs(v_ref).max()
    assert error <= 5e-3
    assert "largest tip displacement" in out.getvalue()


@pytest.mark.slow
def test_quick_case_meets_the_target_and_shows_the_linear_model_diverge(reference):
    rows = case.run(quick=True).rows
    stiffened = [r for r in rows if r["config"]["geometric_stiffening"]]
    linear = [r for r in rows if not r["config"]["geometric_stiffening"]]
    assert stiffened and linear
    assert max(r["error"] for r in stiffened if r["config"]["modes"] >= 10) <= 5e-3
    assert all(r["diverged_at_s"] is None for r in stiffened)
    # ω1 = 3.80 rad/s is passed at t ≈ 8.5 s; the linear model grows without bound after it
    for r in linear:
        assert 8.5 < r["diverged_at_s"] < 20.0
        assert not r["error"] <= 1.0


def test_compare_flags_divergence_and_measures_against_the_peak():
    t = np.linspace(0.0, 2.0, 5)
    error, peak, diverged = case.compare(t, np.array([0.0, 0.1, 0.5, 30.0, np.inf]), t, np.array([0, 0.1, 0.5, 1, 1.0]))
    assert diverged == 1.5 and peak == np.inf and not np.isfinite(error)
    error, _, diverged = case.compare(t, np.full(5, 0.2), t, np.zeros(4).tolist() + [0.4])
    assert diverged is None and error == pytest.approx(np.sqrt((4 * 0.04 + 0.04) / 5) / 0.4)
