"""Tests of the validation harness with small fake case modules."""

import json
import math
import sys
import types

import numpy as np
import pytest

from ffrmbs.errors import FfrmbsError, ModelError
from validation import CaseResult, available_cases, make_row, run_validation, timed
from validation.harness import CASES, ROW_KEYS

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def fake_case(name, run, description="A fake case."):
    """A case module built in memory: NAME, DESCRIPTION, run(quick)."""
    module = types.ModuleType(f"fake_{name}")
    module.NAME = name
    module.DESCRIPTION = description
    module.run = run
    return module


def demo_run(quick):
    """Three ffrmbs rows (a NaN error among them), one peer row, a note and a skip."""
    rows = [make_row("demo", {"modes": m, "dt": np.float64(1e-3)}, cpu_s=0.01 * m,
                     error=np.float64(10.0 ** -m), error_kind="rel. first frequency",
                     reference="Euler-Bernoulli", value=np.float32(203.0))
            for m in (1, 2) if not quick or m == 1]
    rows.append(make_row("demo", {"modes": 3}, cpu_s=0.05, error=math.nan,
                         error_kind="rel. first frequency", reference="Euler-Bernoulli"))
    rows.append(make_row("demo", {"mesh": "coarse"}, cpu_s=0.2, error=3e-2,
                         error_kind="rel. first frequency", reference="Euler-Bernoulli", code="exudyn"))
    return CaseResult(rows=rows, skipped=["akantu: skipped: akantu not installed"],
                      notes=["| extra | table |\n|---|---|\n| 1 | 2 |"])


def failing_run(quick):
    raise RuntimeError("boom in case")


def no_rows_run(quick):
    return CaseResult()


@pytest.fixture
def demo():
    return fake_case("demo", demo_run)


def read_outputs(out):
    return json.loads((out / "results.json").read_text()), (out / "report.md").read_text()


def test_make_row_and_timed():
    row = make_row("c", {"n": 1}, 0.5, None, "abs. tip deflection [m]", "beam theory", value=1.0)
    assert list(row)[:7] == list(ROW_KEYS)
    assert row["code"] == "ffrmbs" and math.isnan(row["error"]) and row["value"] == 1.0
    result, cpu = timed(sum, range(100000))
    assert result == sum(range(100000)) and cpu >= 0.0


def test_results_json(tmp_path, demo):
    rows = run_validation(tmp_path, cases=[demo], progress=None)
    assert len(rows) == 4
    doc, _ = read_outputs(tmp_path)
    assert set(doc) >= {"date", "quick", "machine", "rows", "cases"}
    assert doc["quick"] is False and doc["machine"]["cpu_count"] >= 1
    assert len(doc["rows"]) == 4
    for row in doc["rows"]:
        assert set(ROW_KEYS) <= set(row)
    first = doc["rows"][0]
    assert first == {"case": "demo", "code": "ffrmbs", "config": {"modes": 1, "dt": 1e-3},
                     "cpu_s": 0.01, "error": 0.1, "error_kind": "rel. first frequency",
                     "reference": "Euler-Bernoulli", "value": 203.0}
    assert doc["rows"][2]["error"] is None  # NaN -> null
    assert doc["rows"][3]["code"] == "exudyn"
    case = doc["cases"]["demo"]
    assert case["status"] == "ok" and case["failure"] is None
    assert case["skipped"] == ["akantu: skipped: akantu not installed"]
    assert case["notes"][0].startswith("| extra |")


def test_quick_is_passed(tmp_path, demo):
    rows = run_validation(tmp_path, quick=True, cases={"demo": demo}, progress=None)
    assert len(rows) == 3
    assert read_outputs(tmp_path)[0]["quick"] is True


def test_report_table(tmp_path, demo):
    run_validation(tmp_path, cases=[demo], progress=None)
    _, report = read_outputs(tmp_path)
    lines = report.splitlines()
    assert lines[0] == "# ffrmbs validation report"
    assert any("numpy" in line and "CPUs" in line for line in lines)
    assert "## demo" in lines and "A fake case." in lines
    assert ("| code | config | cpu [s] | error | error kind | reference | value |") in lines
    assert ("| ffrmbs | modes=1, dt=0.001 | 0.01 | 1.000e-01 | rel. first frequency "
            "| Euler-Bernoulli | 203 |") in lines
    assert "| ffrmbs | modes=3 | 0.05 | n/a | rel. first frequency | Euler-Bernoulli |  |" in lines
    assert "| exudyn | mesh=coarse | 0.2 | 3.000e-02 | rel. first frequency | Euler-Bernoulli |  |" in lines
    assert "1 of 4 rows not plotted: error NaN or zero, or cpu time not positive." in lines
    assert "| 1 | 2 |" in lines
    assert "Skipped:" in lines and "- akantu: skipped: akantu not installed" in lines
    assert "![demo: work-precision](demo.png)" in lines


def test_png_written(tmp_path, demo):
    run_validation(tmp_path, cases=[demo], progress=None)
    assert (tmp_path / "demo.png").read_bytes()[:8] == PNG_SIGNATURE
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp-")]


def test_case_without_plottable_rows(tmp_path):
    def run(quick):
        return CaseResult(rows=[make_row("flat", {}, 0.0, 0.0, "abs.", "exact"),
                                make_row("flat", {}, 1.0, None, "abs.", "exact")])

    run_validation(tmp_path, cases=[fake_case("flat", run)], progress=None)
    _, report = read_outputs(tmp_path)
    assert not (tmp_path / "flat.png").exists()
    assert "2 of 2 rows not plotted: error NaN or zero, or cpu time not positive." in report


def test_failing_case(tmp_path, demo):
    lines = []
    cases = [fake_case("broken", failing_run), demo, fake_case("empty", no_rows_run)]
    with pytest.raises(FfrmbsError, match="broken") as info:
        run_validation(tmp_path, cases=cases, progress=lines.append)
    assert "demo" not in str(info.value) and "empty" not in str(info.value)
    doc, report = read_outputs(tmp_path)
    assert doc["cases"]["broken"]["status"] == "failed"
    assert doc["cases"]["broken"]["failure"] == "RuntimeError: boom in case"
    assert "boom in case" in doc["cases"]["broken"]["traceback"]
    assert doc["cases"]["demo"]["status"] == "ok" and len(doc["rows"]) == 4
    assert "FAILED: RuntimeError: boom in case" in report
    assert "| broken | 0 | FAILED |" in report and "| demo | 4 | ok |" in report
    assert (tmp_path / "demo.png").exists()
    assert any("broken: FAILED" in line for line in lines)


def test_malformed_rows_fail_the_case(tmp_path):
    def run(quick):
        return CaseResult(rows=[{"case": "bad", "code": "ffrmbs"}])

    with pytest.raises(FfrmbsError, match="bad"):
        run_validation(tmp_path, cases=[fake_case("bad", run)], progress=None)
    doc, _ = read_outputs(tmp_path)
    assert "row 0 lacks config, cpu_s, error, error_kind, reference" in doc["cases"]["bad"]["failure"]


def test_unknown_only(tmp_path, demo):
    with pytest.raises(ModelError, match="'nope'.*known: demo"):
        run_validation(tmp_path, only="nope", cases=[demo], progress=None)
    assert not (tmp_path / "results.json").exists()


def test_only_selects(tmp_path, demo):
    other = fake_case("other", failing_run)
    rows = run_validation(tmp_path, only=["demo"], cases=[demo, other], progress=None)
    assert {row["case"] for row in rows} == {"demo"}
    assert list(read_outputs(tmp_path)[0]["cases"]) == ["demo"]


def test_registry_imports_listed_modules_lazily(tmp_path, demo, monkeypatch):
    package = types.ModuleType("validation.cases")
    package.CASE_MODULES = ["demo", "missing"]
    monkeypatch.setitem(sys.modules, "validation.cases", package)
    monkeypatch.setitem(sys.modules, "validation.cases.demo", demo)
    assert available_cases() == ["demo", "missing"]
    assert CASES["demo"] is demo
    with pytest.raises(KeyError):
        CASES["no such case"]
    with pytest.raises(ModelError, match="'missing' is listed .* cannot be imported"):
        CASES["missing"]
    assert len(run_validation(tmp_path, only="demo", progress=None)) == 4
    with pytest.raises(FfrmbsError, match="failed: missing"):
        run_validation(tmp_path, progress=None)
    doc, _ = read_outputs(tmp_path)
    assert doc["cases"]["demo"]["status"] == "ok"
    assert doc["cases"]["missing"]["failure"].startswith("ModelError: validation case 'missing'")


def test_case_figures_are_written_and_shown(tmp_path):
    """A case's extra figure goes to <case>_<name>.png and is linked from the report."""
    def run(quick):
        result = CaseResult(rows=[make_row("fig", {}, 0.1, 0.5, "rel.", "ref")])

        def draw(path):
            with open(path, "wb") as f:
                f.write(b"\x89PNG fake")

        result.figures["boundaries"] = draw
        return result

    run_validation(tmp_path, cases=[fake_case("fig", run)], progress=None)
    assert (tmp_path / "fig_boundaries.png").read_bytes() == b"\x89PNG fake"
    _, report = read_outputs(tmp_path)
    assert "![fig: boundaries](fig_boundaries.png)" in report
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("tmp")]


@pytest.mark.parametrize("name", ["wobble_complex", "wobble_case_study"])
def test_a_case_without_its_peer_says_skipped_and_why(tmp_path, monkeypatch, name):
    """The Akantu cases, Akantu absent: status "skipped (akantu not installed)" in report.md
    and results.json, not "ok" with "No rows."."""
    from validation.peers import akantu_dynamics

    monkeypatch.setattr(akantu_dynamics, "available", lambda: False)
    lines = []
    run_validation(tmp_path, quick=True, only=name, progress=lines.append)
    assert f"[1/1] {name}: skipped (akantu not installed)" in lines
    doc, report = read_outputs(tmp_path)
    assert doc["cases"][name]["status"] == "skipped (akantu not installed)"
    assert f"| {name} | 0 | skipped (akantu not installed) |" in report
    assert "Not run: skipped (akantu not installed)." in report and "No rows." not in report


def test_a_case_with_rows_and_a_skipped_part_is_ok(tmp_path, demo):
    run_validation(tmp_path, cases=[demo, fake_case("empty", no_rows_run)], progress=None)
    doc, report = read_outputs(tmp_path)
    assert doc["cases"]["demo"]["status"] == "ok" and doc["cases"]["empty"]["status"] == "ok"
    assert "| demo | 4 | ok |" in report and "| empty | 0 | ok |" in report


def warning_run(quick):
    """A case whose scene warns three times (a fit warning) and logs a validity warning."""
    import logging
    import warnings

    for _ in range(3):
        warnings.warn("contour top: fit deviation 1.2 mm at the nodes")
    logging.getLogger("ffrmbs.validity").warning("body 'beam' spins at 5 rad/s")
    return CaseResult(rows=[make_row("warns", {"n": 1}, 0.1, 1e-3, "rel.", "r")])


def test_a_case_s_warnings_go_to_its_report_not_to_the_terminal(tmp_path, capfd):
    lines = []
    with __import__("warnings").catch_warnings():
        __import__("warnings").simplefilter("error")            # a warning that escaped would raise here
        run_validation(tmp_path, cases=[fake_case("warns", warning_run)], progress=lines.append)
    out, err = capfd.readouterr()
    assert "fit deviation" not in out + err and "spins" not in out + err
    assert "warns: 1 rows" in lines[1] and "2 warning(s) in the report" in lines[1]
    doc, report = read_outputs(tmp_path)
    assert doc["cases"]["warns"]["warnings"] == ["contour top: fit deviation 1.2 mm at the nodes (3 times)",
                                                 "body 'beam' spins at 5 rad/s"]
    assert "- contour top: fit deviation 1.2 mm at the nodes (3 times)" in report
