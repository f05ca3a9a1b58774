"""Run the stability suite: every registered case, one row each, a JSON file and a
markdown report (``ffrmbs validate --stability --out DIR``).

A case never takes the runner down: a :class:`~ffrmbs.errors.SimulationError` escaping a
case becomes a graceful row (the case did not expect that stop, so it does not pass) and
any other exception a ``FAILED: <type>: <message>`` row. After writing
``DIR/stability.json`` and ``DIR/report.md`` (atomically: a temporary file renamed over
the old one) the runner raises :class:`~ffrmbs.errors.FfrmbsError` naming the cases that
did not pass, which the command line turns into exit status 2 with one line.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import time
import traceback

from ffrmbs.errors import FfrmbsError, SimulationError
from validation.bench.common import machine
from validation.report import cell, json_safe, write_atomic
from validation.stability import body_cases, contact_cases  # noqa: F401  (they register their cases in CASES)
from validation.stability.core import CASES, StabilityCase, StabilityRow, graceful_row

COLUMNS = ("case", "finished", "stable", "energy drift", "max penetration [m]", "error (reference)", "run time [s]",
           "outcome")


def select_cases(cases: dict, only) -> list[StabilityCase]:
    """The cases of ``cases`` named in ``only`` (None: all, in registration order). A name
    selects the case of that name, or the group of cases named ``name/...``; an unknown
    name is an FfrmbsError listing the known ones."""
    if not only:
        return list(cases.values())
    chosen, unknown = [], []
    for name in only:
        hits = [c for key, c in cases.items() if key == name or key.startswith(name + "/")]
        if not hits:
            unknown.append(name)
        chosen.extend(c for c in hits if c not in chosen)
    if unknown:
        raise FfrmbsError(f"unknown stability case(s) {', '.join(unknown)}; known: {', '.join(cases)}")
    return chosen


def run_case(case: StabilityCase, quick: bool) -> StabilityRow:
    """Run one case; whatever it raises becomes a row (see module docstring)."""
    t0 = time.perf_counter()
    try:
        row = case.run(quick)
        if not isinstance(row, StabilityRow):
            raise TypeError(f"the case returned {type(row).__name__}, not a StabilityRow")
        return row
    except SimulationError as err:
        return graceful_row(case.name, err, time.perf_counter() - t0, reference=case.title, expected=False,
                            note="the case did not expect this stop")
    except Exception as exc:            # a crash: recorded, never raised out of the runner
        where = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
        note = f"raised at {where.filename}:{where.lineno} ({where.name})" if where else ""
        return StabilityRow(case.name, finished=False, stable=False, energy_drift=None, max_penetration=None,
                            error=None, reference=case.title, run_time_s=time.perf_counter() - t0, passed=False,
                            outcome=f"FAILED: {type(exc).__name__}: {exc}", note=note)


def run_stability(out_dir, quick=False, only=None, progress=print, cases=None) -> list[StabilityRow]:
    """Run the stability cases (``cases``: a {name: StabilityCase} registry, default the
    registered :data:`~validation.stability.core.CASES`; ``only``: names or group
    prefixes), write ``out_dir/stability.json`` (rows as dicts plus the machine) and
    ``out_dir/report.md`` (the table, then each row's note), print the table with
    ``progress``, return the rows; raise FfrmbsError naming the cases that did not pass."""
    if cases is None:
        cases = CASES
    selected = select_cases(cases, only)
    rows = []
    for case in selected:
        progress(f"stability case {case.name}: {case.title} ...")
        row = run_case(case, quick)
        rows.append(row)
        progress(f"stability case {case.name}: {row.outcome} ({row.run_time_s:.2f} s)")
    os.makedirs(out_dir, exist_ok=True)
    doc = {"suite": "stability", "quick": bool(quick), "only": list(only) if only else None,
           "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "machine": machine(), "rows": [json_safe(r.as_dict()) for r in rows]}
    json_path = os.path.join(out_dir, "stability.json")
    _write_text(json_path, json.dumps(doc, indent=1, allow_nan=False) + "\n")
    table = markdown_table(rows)
    _write_text(os.path.join(out_dir, "report.md"), report_markdown(rows, quick, doc["machine"]))
    progress(table)
    failed = [r.case for r in rows if not r.passed]
    if failed:
        raise FfrmbsError(f"stability case(s) failed: {', '.join(failed)} (see {json_path})")
    return rows


def markdown_table(rows) -> str:
    """The table of rows, one line each (columns: :data:`COLUMNS`)."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for r in rows:
        error = "—" if r.error is None else f"{_num(r.error)} ({r.reference})"
        cells = (r.case, _yes(r.finished), _yes(r.stable), _num(r.energy_drift), _num(r.max_penetration), error,
                 f"{r.run_time_s:.2f}", r.outcome)
        lines.append("| " + " | ".join(cell(c) for c in cells) + " |")
    return "\n".join(lines)


def report_markdown(rows, quick, machine) -> str:
    passed = sum(r.passed for r in rows)
    head = (f"# Stability suite\n\n{passed} of {len(rows)} cases passed"
            f"{' (quick settings)' if quick else ''}. Machine: {machine.get('platform', '?')}, "
            f"Python {machine.get('python', '?')}, {machine.get('cpu_count', '?')} cores.\n\n")
    notes = "\n".join(f"- **{r.case}** ({'passed' if r.passed else 'not passed'}): {r.note or '—'}" for r in rows)
    return head + markdown_table(rows) + "\n\n## Notes\n\n" + notes + "\n"


def _yes(flag) -> str:
    return "yes" if flag else "no"


def _num(x) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{x:.3g}"


def _write_text(path, text):
    """Write ``text`` (UTF-8) to ``path`` atomically (:func:`validation.report.write_atomic`)."""
    write_atomic(path, lambda f: f.write(text.encode("utf-8")))
