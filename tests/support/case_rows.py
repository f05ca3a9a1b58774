"""Shared by the tests of validation cases: one quick harness run grouped by case (with
or without the report files), and row selection by config."""

from validation.harness import run_case
from validation.report import run_validation


def quick_rows_by_case(out, cases):
    """{case name: rows} of one quick harness run of ``cases`` into ``out``; the run must
    have written results.json and report.md."""
    all_rows = run_validation(out, quick=True, cases=cases, progress=None)
    assert (out / "results.json").exists() and (out / "report.md").exists()
    by_case = {}
    for row in all_rows:
        by_case.setdefault(row["case"], []).append(row)
    return by_case


def quick_rows_without_files(cases):
    """{case name: rows} of each of ``cases`` run in quick mode as the harness runs it
    (:func:`validation.harness.run_case`: warnings caught, the result checked), without
    the plots and report (tests/integration/test_harness.py covers those); a case must not
    fail."""
    registry = {case.NAME: case for case in cases}
    by_case = {}
    for name in registry:
        outcome = run_case(registry, name, True)
        assert outcome.failure is None, outcome.traceback
        by_case[name] = outcome.result.rows
    return by_case


def select(rows, **config):
    """The rows whose config (or row) matches every key of ``config``."""
    return [r for r in rows if all(r["config"].get(k, r.get(k)) == v for k, v in config.items())]
