"""The side-by-side peer benchmarks (Exudyn free flight, Akantu case study): the selection
rule on made-up rows, and tiny runs when the peer is installed (no timing assertions)."""

import json

import numpy as np
import pytest

from validation.bench import akantu_case_study, exudyn_free_flight
from validation.bench.common import write_json


def _row(cpu, traj, elas, dt=1e-3):
    return {"integrator": "moreau", "dt": dt, "options": {"theta": 0.5}, "cpu_s": cpu,
            "trajectory_error": traj, "elastic_error": elas}


def test_select_takes_the_fastest_candidate_with_both_errors_no_larger():
    peer = _row(1.0, 1e-4, 0.5)
    fast_but_inaccurate, slow, medium = _row(0.1, 2e-4, 0.1), _row(0.9, 1e-5, 0.5), _row(0.3, 1e-4, 0.4)
    assert exudyn_free_flight.select([fast_but_inaccurate, slow, medium], peer) is medium
    assert exudyn_free_flight.select([fast_but_inaccurate, _row(0.2, 1e-5, 0.6)], peer) is None


def test_exudyn_side_by_side_tiny(monkeypatch, tmp_path):
    pytest.importorskip("exudyn", reason="exudyn is an optional peer (pip install '.[peers]')")
    monkeypatch.setattr(exudyn_free_flight, "CANDIDATES", (("generalized-alpha", 1e-3, {"plan": True}),
                                                           ("moreau", 1e-3, {"theta": 0.5})))
    doc = exudyn_free_flight.benchmark(modes=(4,), exudyn_steps=(1e-3,), repeats=1, reference_dt=2.5e-4,
                                       log=lambda msg: None)
    saved = json.loads(open(write_json(doc, str(tmp_path), "exudyn_free_flight")).read())
    assert [(r["code"], r["integrator"], r["dt"]) for r in saved["rows"]] == [
        ("ffrmbs", "generalized-alpha", 1e-3), ("ffrmbs", "moreau", 1e-3), ("exudyn", "generalized-alpha", 1e-3)]
    for r in saved["rows"]:
        assert r["n_modes"] == 4 and r["cpu_s"] > 0 and r["us_per_step"] > 0
        assert np.isfinite(r["trajectory_error"]) and np.isfinite(r["elastic_error"])
    (c,) = saved["comparisons"]
    assert c["n_modes"] == 4 and c["exudyn_dt"] == 1e-3
    assert (c["ratio"] is None) == (c["ours"] is None)
    assert len(saved["verdicts"]) == 1 and saved["verdicts"][0].endswith("met")
    assert "| exudyn | 4 | generalized-alpha |" in saved["table"]


def test_akantu_side_by_side_tiny(monkeypatch, tmp_path):
    pytest.importorskip("akantu", reason="akantu is an optional peer (pip install '.[peers]')")
    monkeypatch.setattr(akantu_case_study, "OURS", (("rkmk4", 10, 1e-2),))
    doc = akantu_case_study.benchmark(0.02, log=lambda msg: None)
    saved = json.loads(open(write_json(doc, str(tmp_path), "akantu_case_study")).read())
    (r,) = saved["rows"]
    assert r["n_modes"] == 10 and r["cpu_s"] > 0 and r["akantu_cpu_s"] > r["akantu_loop_cpu_s"] > 0
    assert r["ratio"] == pytest.approx(r["akantu_cpu_s"] / r["cpu_s"]) and 0 <= r["rms_error"] < 1
    assert len(saved["verdicts"]) == 1 and "SimpleRB rkmk4 10 modes" in saved["verdicts"][0]
