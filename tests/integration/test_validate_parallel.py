"""``ffrmbs validate --workers N``: the cases as Dask tasks give the same rows, report
and results.json as the serial run; a failing case is a failed outcome, not the end."""

import json
import math

import pytest

from ffrmbs.errors import FfrmbsError
from validation import run_validation
from validation.cases import wobble_shear, wobble_step

import failing_case

CHEAP = {"wobble_shear": wobble_shear, "wobble_step": wobble_step}


def comparable(rows):
    """The rows without their CPU times and spreads (measured, so they differ run to run)."""
    out = []
    for row in rows:
        row = {k: v for k, v in row.items() if not k.startswith("cpu")}
        out.append({k: ("nan" if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()})
    return out


@pytest.mark.slow
def test_cases_on_dask_give_the_serial_rows_and_report(dask_client, tmp_path):
    serial = run_validation(tmp_path / "serial", quick=True, cases=CHEAP, progress=None)
    lines = []
    parallel = run_validation(tmp_path / "dask", quick=True, cases=CHEAP, progress=lines.append, client=dask_client)
    assert comparable(parallel) == comparable(serial)
    assert any("Dask workers" in line for line in lines) and sum("rows" in line for line in lines) == 2
    docs = [json.loads((tmp_path / d / "results.json").read_text()) for d in ("serial", "dask")]
    assert list(docs[0]["cases"]) == list(docs[1]["cases"])
    assert [c["status"] for c in docs[0]["cases"].values()] == [c["status"] for c in docs[1]["cases"].values()]
    assert all(row["cpu_s"] > 0 for row in parallel)
    assert (tmp_path / "dask" / "report.md").read_text().count("## ") == \
        (tmp_path / "serial" / "report.md").read_text().count("## ")


@pytest.mark.slow
def test_a_failing_case_on_a_worker_is_reported_and_the_others_run(dask_client, tmp_path):
    cases = {"wobble_shear": wobble_shear, "failing_case": failing_case}
    with pytest.raises(FfrmbsError, match=r"validation case\(s\) failed: failing_case"):
        run_validation(tmp_path, quick=True, cases=cases, progress=None, client=dask_client)
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["cases"]["wobble_shear"]["status"] == "ok" and doc["cases"]["failing_case"]["status"] == "failed"
    assert "deliberate failure" in doc["cases"]["failing_case"]["failure"]


def test_case_times_are_kept_per_mode_and_merged(tmp_path, monkeypatch):
    from validation.parallel import case_times, record_case_times

    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path))
    assert case_times(True) == {}
    record_case_times(True, {"a": 2.0, "b": 1.0})
    record_case_times(True, {"b": 3.0})
    record_case_times(False, {"a": 9.0})
    assert case_times(True) == {"a": 2.0, "b": 3.0} and case_times(False) == {"a": 9.0}
    (tmp_path / "case-times.json").write_text("not json")
    assert case_times(True) == {}


def test_without_dask_workers_are_one_clear_error(monkeypatch, tmp_path):
    import sys

    monkeypatch.setitem(sys.modules, "distributed", None)          # as if not installed
    with pytest.raises(FfrmbsError, match=r"Dask, which is not installed: pip install '\.\[sweep\]'"):
        run_validation(tmp_path, quick=True, cases=CHEAP, progress=None, workers=2)
