"""Shared by the tests of validation cases: one quick harness run grouped by case, and
row selection by config."""

from validation.harness import run_validation


def quick_rows_by_case(out, cases):
    """{case name: rows} of one quick harness run of ``cases`` into ``out``; the run must
    have written results.json and report.md."""
    all_rows = run_validation(out, quick=True, cases=cases, progress=None)
    assert (out / "results.json").exists() and (out / "report.md").exists()
    by_case = {}
    for row in all_rows:
        by_case.setdefault(row["case"], []).append(row)
    return by_case


def select(rows, **config):
    """The rows whose config (or row) matches every key of ``config``."""
    return [r for r in rows if all(r["config"].get(k, r.get(k)) == v for k, v in config.items())]
