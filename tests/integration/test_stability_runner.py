"""The stability runner with a fake registry: a crashing case gives a FAILED row, a
SimulationError a graceful row with time, step and cause; the JSON and the report are
written either way; a case that did not pass is an FfrmbsError naming it (exit status 2
on the command line)."""

import json
import math
import os

import numpy as np
import pytest

from ffrmbs_app.cli import main
from ffrmbs.errors import FfrmbsError, SimulationError
from validation.stability import runner
from validation.stability.core import StabilityCase, StabilityRow


def good(quick):
    return StabilityRow("good", finished=True, stable=True, energy_drift=1e-9, max_penetration=None,
                        error=2.5e-4, reference="analytic", run_time_s=0.01, passed=True, outcome="passed",
                        note="a | pipe", details={"quick": quick, "array": np.arange(3), "nan": float("nan"),
                                                  "np_float": np.float64(1.5)})


def crash(quick):
    raise ValueError("boom")


def diverge(quick):
    err = SimulationError(0.125, 42, "the state became NaN or infinite")
    err.result = None
    raise err


def registry(*fns, names=None):
    names = names or [fn.__name__ for fn in fns]
    return {name: StabilityCase(name, f"the {name} case", fn) for name, fn in zip(names, fns)}


def test_a_crash_and_a_simulation_error_become_rows_and_the_files_are_written(tmp_path):
    out = tmp_path / "out"
    lines = []
    with pytest.raises(FfrmbsError) as info:
        runner.run_stability(str(out), quick=True, progress=lines.append, cases=registry(good, crash, diverge))
    message = str(info.value)
    assert "crash" in message and "diverge" in message and "good" not in message.split("(see")[0]
    doc = json.loads((out / "stability.json").read_text())
    rows = {r["case"]: r for r in doc["rows"]}
    assert list(rows) == ["good", "crash", "diverge"]
    assert rows["good"]["passed"] and rows["good"]["details"] == {"quick": True, "array": [0, 1, 2], "nan": None,
                                                                   "np_float": 1.5}
    assert rows["crash"]["outcome"] == "FAILED: ValueError: boom" and rows["crash"]["passed"] is False
    assert rows["crash"]["finished"] is False and "test_stability_runner.py" in rows["crash"]["note"]
    d = rows["diverge"]
    assert d["passed"] is False
    assert d["outcome"].startswith("failed gracefully: simulation stopped at t = 0.125 s (step 42)")
    assert d["details"]["t"] == 0.125 and d["details"]["step"] == 42
    assert d["details"]["cause"] == "the state became NaN or infinite"
    assert "machine" in doc and doc["quick"] is True
    report = (out / "report.md").read_text()
    assert ("| case | finished | stable | energy drift | max penetration [m] | error (reference) | run time [s] "
            "| outcome |") in report
    assert "0.00025 (analytic)" in report and "FAILED: ValueError: boom" in report and "t = 0.125 s (step 42)" in report
    assert "a \\| pipe" not in report.split("## Notes")[0] and "a | pipe" in report.split("## Notes")[1]
    table = [line for line in report.splitlines() if line.startswith("| good")][0]
    assert table.count("|") == len(runner.COLUMNS) + 1          # one cell per column
    assert "| case |" in "\n".join(lines)                        # the table went to progress too
    assert sorted(os.listdir(out)) == ["report.md", "stability.json"]   # no temporary files left


def test_all_passing_returns_the_rows_and_overwrites_the_files(tmp_path):
    (tmp_path / "stability.json").write_text("old")
    rows = runner.run_stability(str(tmp_path), progress=lambda s: None, cases=registry(good))
    assert [r.case for r in rows] == ["good"] and rows[0].passed
    assert json.loads((tmp_path / "stability.json").read_text())["rows"][0]["case"] == "good"


def test_only_selects_names_and_groups_and_rejects_unknown_ones(tmp_path):
    cases = registry(good, good, crash, names=["stiff/a", "stiff/b", "other"])
    rows = runner.run_stability(str(tmp_path), only=["stiff"], progress=lambda s: None, cases=cases)
    assert [r.case for r in rows] == ["good", "good"]       # the fake case names its row "good"
    with pytest.raises(FfrmbsError, match="unknown stability case.*nope.*known: stiff/a, stiff/b, other"):
        runner.run_stability(str(tmp_path), only=["nope"], progress=lambda s: None, cases=cases)


def test_a_case_returning_no_row_is_a_failure(tmp_path):
    with pytest.raises(FfrmbsError, match="none_row"):
        runner.run_stability(str(tmp_path), progress=lambda s: None,
                             cases=registry(lambda quick: None, names=["none_row"]))
    row = json.loads((tmp_path / "stability.json").read_text())["rows"][0]
    assert row["outcome"].startswith("FAILED: TypeError") and not row["passed"]


def test_cli_exit_status(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(runner, "CASES", registry(good, crash))
    assert main(["validate", "--stability", "--quick", "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("ffrmbs: error: stability case(s) failed: crash")
    assert (tmp_path / "a" / "report.md").exists()
    assert main(["validate", "--stability", "--only", "good", "--out", str(tmp_path / "b")]) == 0
    doc = json.loads((tmp_path / "b" / "stability.json").read_text())
    assert [r["case"] for r in doc["rows"]] == ["good"] and doc["quick"] is False
    assert math.isclose(doc["rows"][0]["error"], 2.5e-4)
