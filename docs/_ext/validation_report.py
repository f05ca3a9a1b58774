"""The validation report pages, generated from committed validation output when the docs build.

``docs/validation/_data/<run>/`` holds what one ``ffrmbs validate`` run wrote (results.json,
the work-precision PNGs and the cases' extra figures) or what ``ffrmbs validate --stability``
wrote (stability.json). At ``builder-inited`` this extension writes one MyST page per run,
``docs/validation/generated/<run>.md``: the run's date, mode and machine, a summary table,
and per case its description, status, a table of its rows (code, config, error, CPU time,
reference, extra columns), its figures and notes. Every figure on the pages comes from those
files; the cells are formatted by :func:`validation.report.cell` and the stability table by
:func:`validation.stability.runner.markdown_table`, as in ``report.md``.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

from validation.harness import ROW_KEYS
from validation.report import cell
from validation.stability.core import StabilityRow
from validation.stability.runner import markdown_table

DATA = "_data"
GENERATED = "generated"


def _file_stem(name: str) -> str:
    """The report's file name of a case (``run_validation``: unsafe characters as ``_``)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def _seconds(value) -> str:
    return "n/a" if value is None else f"{value:.3g}"


def _error(value) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.3e}"


def _rows_table(rows: list[dict]) -> list[str]:
    extra = list(dict.fromkeys(k for row in rows for k in row if k not in ROW_KEYS))
    header = ["code", "config", "error", "error kind", "CPU [s]", "reference"] + extra
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        cells = [cell(row["code"]), cell(row["config"]), _error(row["error"]), cell(row["error_kind"]),
                 cell(row["cpu_s"]), cell(row["reference"])] + [cell(row.get(k, "")) for k in extra]
        lines.append("| " + " | ".join(c.replace("*", r"\*") for c in cells) + " |")
    return lines + [""]


def _figures(data_dir: Path, name: str) -> list[Path]:
    """The case's work-precision plot first, then its extra figures ``<case>_<title>.png``."""
    stem = _file_stem(name)
    main = [data_dir / f"{stem}.png"] if (data_dir / f"{stem}.png").exists() else []
    return main + sorted(p for p in data_dir.glob(f"{stem}_*.png"))


def _machine(machine: dict) -> str:
    return (f"{machine.get('platform', '?')}; Python {machine.get('python', '?')}; "
            f"numpy {machine.get('numpy', '?')}; {machine.get('cpu_count', '?')} CPUs")


def validation_page(data_dir: Path, rel: str, command: str) -> str:
    """The MyST page of one ``ffrmbs validate`` run; ``rel``: the data directory as seen
    from the generated page."""
    doc = json.loads((data_dir / "results.json").read_text())
    cases = doc["cases"]
    rows_of = {name: [r for r in doc["rows"] if r["case"] == name] for name in cases}
    mode = "quick" if doc["quick"] else "full"
    lines = [f"# Validation cases ({mode} sweeps)", "",
             f"Generated from `{rel}/results.json`, written by `{command}` on {doc['date']} "
             f"(machine: {_machine(doc['machine'])}). CPU times are CPU seconds of the case's "
             "process, numba compilation left out.", "",
             "| case | rows | status | CPU [s] |", "|---|---|---|---|"]
    for name, case in cases.items():
        status = "FAILED" if case["failure"] else case["status"]
        lines.append(f"| [{name}](#{name}) | {len(rows_of[name])} | {cell(status)} | {_seconds(case['cpu_s'])} |")
    lines.append("")
    for name, case in cases.items():
        lines += [f"## {name}", "", case["description"] or "", "",
                  f"Status: {case['status']}.", ""]
        if case["failure"]:
            lines += [f"FAILED: {cell(case['failure'])}", ""]
        if rows_of[name]:
            lines += _rows_table(rows_of[name])
        for png in _figures(data_dir, name):
            lines += [f"![{name}: {png.stem}]({rel}/{png.name})", ""]
        lines += [note + "\n" for note in case["notes"]]
        if case["skipped"]:
            lines += ["Skipped:", ""] + [f"- {cell(s)}" for s in case["skipped"]] + [""]
    return "\n".join(lines)


def stability_page(data_dir: Path, rel: str, command: str) -> str:
    """The MyST page of one ``ffrmbs validate --stability`` run."""
    doc = json.loads((data_dir / "stability.json").read_text())
    rows = [StabilityRow(**r) for r in doc["rows"]]
    passed = sum(r.passed for r in rows)
    lines = ["# Stability suite", "",
             f"Generated from `{rel}/stability.json`, written by `{command}` on {doc['created']} "
             f"(machine: {_machine(doc['machine'])}). {passed} of {len(rows)} cases passed"
             f"{' (quick settings)' if doc['quick'] else ''}. A case passes when its outcome is the one "
             "it predicts: most finish stable within their bound; some must stop with a clear "
             "`SimulationError` naming the time, the step and the cause. Run times are wall seconds "
             "of the simulations and depend on the machine's load when the data was written.", "",
             markdown_table(rows).replace("*", r"\*"), "", "## Notes", ""]
    lines += [f"- **{r.case}** ({'passed' if r.passed else 'not passed'}): {cell(r.note or '—')}" for r in rows]
    return "\n".join(lines) + "\n"


def _command(data_dir: Path) -> str:
    """The command that wrote a run, from its COMMAND file (one line)."""
    return (data_dir / "COMMAND").read_text().strip()


def write_pages(app):
    """``builder-inited``: write the generated page of every run under ``validation/_data``."""
    root = Path(app.srcdir) / "validation"
    out = root / GENERATED
    out.mkdir(exist_ok=True)
    for data_dir in sorted(p for p in (root / DATA).iterdir() if p.is_dir()):
        rel = f"../{DATA}/{data_dir.name}"
        if (data_dir / "results.json").exists():
            text = validation_page(data_dir, rel, _command(data_dir))
        elif (data_dir / "stability.json").exists():
            text = stability_page(data_dir, rel, _command(data_dir))
        else:
            continue
        page = out / f"{data_dir.name}.md"
        if not page.exists() or page.read_text() != text:      # unchanged pages are not rebuilt
            page.write_text(text)


def setup(app):
    app.connect("builder-inited", write_pages)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
