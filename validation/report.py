"""``ffrmbs validate``: run the chosen validation cases — one after another in this process,
or as Dask tasks (:mod:`validation.parallel`) — and write ``results.json``, ``report.md``
and one work-precision plot per case (:func:`run_validation`). The case protocol, the
registry and the run of one case are :mod:`validation.harness`'s.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import re
import tempfile

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ffrmbs.errors import FfrmbsError
from ffrmbs_app.ticks import label_log_axis, series_label
from validation.harness import (CASES, DEFAULT_PLOT_GROUPS, ROW_KEYS, as_registry, case_status, outcome_line,
                                run_case, select_cases)
from validation.parallel import record_case_times, run_cases

_MARKERS = "osD^v<>pPX*h"


def json_safe(value):
    """``value`` with numpy types as Python types, non-finite floats as None, tuples as lists."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, (bool, int, str)):
        return value
    return str(value)


def write_atomic(path, write):
    """Write ``path`` by ``write(binary_file)`` into a temporary file, then os.replace."""
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix=".tmp-")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _machine():
    """Platform, Python and numpy versions and CPU count of this machine."""
    return {"platform": platform.platform(), "python": platform.python_version(),
            "numpy": np.__version__, "cpu_count": os.cpu_count()}


def _plottable(row):
    """True when the row's cpu time and |error| are finite and positive (log-log plot)."""
    return all(v is not None and math.isfinite(v) and v != 0 for v in (row["cpu_s"], row["error"])) \
        and row["cpu_s"] > 0


def _lookup(row, key):
    """``row[key]``, else ``row["config"][key]``, else None."""
    return row[key] if key in row else row["config"].get(key)


def _unit(error_kind) -> str:
    """The unit of an error kind: the "[...]" it ends with ("impact time [s]" -> "s"), else
    "-" (a relative or dimensionless error)."""
    match = re.search(r"\[([^\[\]]+)\]\s*$", error_kind)
    return match[1] if match else "-"


def _series(rows, group_keys):
    """{repr of the values: (values of the varying keys, rows)} of one panel, the group keys
    that vary among its rows (the legend's) and those that do not (the panel's constants).
    Values are told apart by their repr (a mesh may be a list)."""
    keys = [key for key in group_keys if key != "error_kind"]
    varying = [key for key in keys if len({repr(_lookup(row, key)) for row in rows}) > 1]
    constant = [key for key in keys if key not in varying and _lookup(rows[0], key) is not None]
    groups = {}
    for row in rows:
        values = tuple(_lookup(row, key) for key in varying)
        groups.setdefault(repr(values), (values, []))[1].append(row)
    return groups, varying, constant


def _panel(ax, kind, rows, group_keys):
    """One error kind's work-precision panel: a marker series per value of the varying
    group keys, legend right of the axes, the constant keys in the panel title."""
    groups, varying, constant = _series(rows, group_keys)
    for i, (values, members) in enumerate(groups.values()):
        ax.loglog([r["cpu_s"] for r in members], [abs(r["error"]) for r in members],
                  linestyle="-", linewidth=0.8, marker=_MARKERS[i % len(_MARKERS)],
                  label=series_label(varying, values) if varying else None)
    label_log_axis(ax, "x")
    label_log_axis(ax, "y")
    ax.set_xlabel("CPU time [s]")
    ax.set_ylabel(f"|error| [{_unit(kind)}]")
    title = kind if not constant else f"{kind}\n{series_label(constant, [_lookup(rows[0], k) for k in constant])}"
    ax.set_title(title, fontsize="medium")
    ax.grid(True, which="both", alpha=0.3)
    if varying:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)


def work_precision_figure(name, rows, group_keys):
    """The Figure (Agg canvas attached) of a case's work-precision plot: one log-log panel
    (|error| against CPU time) per error kind, so errors in s, m and relative ones never
    share an axis (:func:`_panel`)."""
    panels = {}
    for row in rows:
        panels.setdefault(row["error_kind"], []).append(row)
    series = [len(_series(members, group_keys)[0]) for members in panels.values()]
    heights = [max(3.0, 0.9 + 0.22 * n) for n in series]
    fig = Figure(figsize=(9.5, 0.5 + sum(heights)), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(panels), 1, squeeze=False, gridspec_kw={"height_ratios": heights})[:, 0]
    for ax, (kind, members) in zip(axes, panels.items()):
        _panel(ax, kind, members, group_keys)
    fig.suptitle(f"{name}: work-precision")
    return fig


def _plot(path, name, rows, group_keys):
    """Write the work-precision plot (:func:`work_precision_figure`) of the plottable rows to ``path``."""
    fig = work_precision_figure(name, rows, group_keys)
    write_atomic(path, lambda f: fig.savefig(f, format="png", dpi=110))


def cell(value):
    """A markdown table cell: floats to 6 significant digits, NaN/None as n/a, dicts as k=v."""
    if isinstance(value, dict):
        text = ", ".join(f"{k}={cell(v)}" for k, v in value.items())
    elif isinstance(value, (float, np.floating)):
        text = "n/a" if not math.isfinite(value) else f"{value:.6g}"
    elif value is None:
        text = "n/a"
    else:
        text = str(value)
    return text.replace("|", "\\|").replace("\n", " ")


def _case_report(outcome, png_name, figures=()):
    """Markdown lines of one case: heading, description, table, plots, notes, skipped."""
    lines = [f"## {outcome.name}", ""]
    if outcome.description:
        lines += [outcome.description, ""]
    if outcome.failure is not None:
        return lines + [f"FAILED: {cell(outcome.failure)}", ""]
    result = outcome.result
    rows = result.rows
    if rows:
        extra = list(dict.fromkeys(k for row in rows for k in row if k not in ROW_KEYS))
        header = ["code", "config", "cpu [s]", "error", "error kind", "reference"] + extra
        lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        for row in rows:
            error = row["error"]
            cells = [cell(row["code"]), cell(row["config"]), cell(row["cpu_s"]),
                     "n/a" if error is None or not math.isfinite(error) else f"{error:.3e}",
                     cell(row["error_kind"]), cell(row["reference"])]
            cells += [cell(row.get(k, "")) for k in extra]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    elif result.skipped:
        lines += [f"Not run: {case_status(outcome)}.", ""]
    else:
        lines += ["No rows.", ""]
    n_out = sum(not _plottable(row) for row in rows)
    if png_name is not None:
        lines += [f"![{outcome.name}: work-precision]({png_name})", ""]
    for title, file_name in figures:
        lines += [f"![{outcome.name}: {title}]({file_name})", ""]
    if n_out:
        lines += [f"{n_out} of {len(rows)} rows not plotted: error NaN or zero, or cpu time "
                  "not positive.", ""]
    for note in result.notes:
        lines += [note, ""]
    if result.skipped:
        lines += ["Skipped:", ""] + [f"- {s}" for s in result.skipped] + [""]
    if outcome.warnings:
        lines += ["Warnings raised while the case ran (about its own scenes):", ""] + \
                 [f"- {cell(w)}" for w in outcome.warnings] + [""]
    return lines


def _report(outcomes, pngs, figures, quick, machine, date):
    """The whole report.md text."""
    lines = ["# ffrmbs validation report", "",
             f"- date: {date}",
             f"- mode: {'quick' if quick else 'full'}",
             f"- machine: {machine['platform']}; Python {machine['python']}; "
             f"numpy {machine['numpy']}; {machine['cpu_count']} CPUs",
             "- cpu [s]: CPU time of this process (all threads), time.process_time", "",
             "| case | rows | status |", "|---|---|---|"]
    for o in outcomes:
        status = "FAILED" if o.failure is not None else case_status(o)
        lines.append(f"| {o.name} | {len(o.result.rows) if o.result else 0} | {status} |")
    lines.append("")
    for o in outcomes:
        lines += _case_report(o, pngs.get(o.name), figures.get(o.name, ()))
    return "\n".join(lines)


def _write_figures(out_dir, outcome):
    """Write a case's extra figures atomically; [(title, file name)] of those written."""
    written = []
    for title, draw in outcome.result.figures.items():
        name = re.sub(r"[^A-Za-z0-9_.-]", "_", f"{outcome.name}_{title}") + ".png"
        fd, tmp = tempfile.mkstemp(dir=out_dir, suffix=".png")
        os.close(fd)
        try:
            draw(tmp)
            os.replace(tmp, os.path.join(out_dir, name))
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
        written.append((title, name))
    return written


def _results_json(outcomes, quick, machine, date):
    """The results.json document: rows of all cases plus per-case status, skipped, notes."""
    cases = {}
    for o in outcomes:
        r = o.result
        cases[o.name] = {"description": o.description,
                         "status": case_status(o),
                         "failure": o.failure, "traceback": o.traceback, "cpu_s": o.cpu_s,
                         "warnings": list(o.warnings),
                         "skipped": list(r.skipped) if r else [], "notes": list(r.notes) if r else []}
    rows = [row for o in outcomes if o.result for row in o.result.rows]
    return json_safe({"date": date, "quick": quick, "machine": machine, "rows": rows, "cases": cases})


def run_validation(out_dir, quick=False, only=None, cases=None, progress=print, workers=None, scheduler=None,
                   client=None):
    """Run validation cases and write ``out_dir/results.json``, ``report.md``, ``<case>.png``.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output directory, created if missing. Files are written atomically.
    quick : bool
        Passed to each case's ``run``: a short sweep for smoke tests.
    only : str or list of str or None
        Case name(s) to run; None runs all. An unknown name raises ModelError.
    cases : mapping name -> module, or iterable of case modules, or None
        The cases to choose from; None: the registry :data:`CASES`.
    progress : callable or None
        Called with one line of text per step; None for silence.
    workers, scheduler, client :
        Run the cases as Dask tasks (:mod:`validation.parallel`): on the given
        ``client``, on a running scheduler at the address ``scheduler``, or on a
        LocalCluster of ``workers`` single-threaded processes. All None: one after
        another in this process. The report and results.json are the same either way;
        each case's CPU time is measured inside its task.

    Notes
    -----
    Returns the rows of all cases. A case that raises is recorded as ``FAILED: <message>``
    and the others still run; after writing the files, FfrmbsError names the failed cases.
    Rows whose error is NaN or zero, or whose cpu time is not positive, are left out of the plots; signed errors are plotted as |error|.
    """
    say = progress or (lambda line: None)
    registry = CASES if cases is None else as_registry(cases)
    names = select_cases(registry, only)
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    if workers is None and scheduler is None and client is None:
        outcomes = []
        for i, name in enumerate(names, 1):
            say(f"[{i}/{len(names)}] {name} ...")
            outcomes.append(run_case(registry, name, quick))
            say(f"[{i}/{len(names)}] {outcome_line(outcomes[-1])}")
        record_case_times(quick, {o.name: o.cpu_s for o in outcomes})
    else:
        outcomes = run_cases(registry, names, quick, say, client=client, scheduler=scheduler, workers=workers)
    pngs = {}
    for o in outcomes:
        plotted = [row for row in o.result.rows if _plottable(row)] if o.result else []
        if plotted:
            pngs[o.name] = re.sub(r"[^A-Za-z0-9_.-]", "_", o.name) + ".png"
            _plot(os.path.join(out_dir, pngs[o.name]), o.name, plotted,
                  o.result.plot_groups or DEFAULT_PLOT_GROUPS)
    figures = {o.name: _write_figures(out_dir, o) for o in outcomes if o.result and o.result.figures}
    machine = _machine()
    date = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    doc = _results_json(outcomes, quick, machine, date)
    write_atomic(os.path.join(out_dir, "results.json"),
                  lambda f: f.write(json.dumps(doc, indent=1, allow_nan=False).encode()))
    report_path = os.path.join(out_dir, "report.md")
    write_atomic(report_path, lambda f: f.write(_report(outcomes, pngs, figures, quick, machine, date).encode()))
    say(f"wrote {report_path}")
    failed = [o.name for o in outcomes if o.failure is not None]
    if failed:
        raise FfrmbsError(f"validation case(s) failed: {', '.join(failed)}; see {report_path}")
    return [row for o in outcomes for row in o.result.rows]
