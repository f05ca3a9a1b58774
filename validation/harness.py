"""The validation harness: run cases, write results.json, report.md and work-precision plots.

Protocol (DESIGN.md, "Validation protocol"). A case is a module ``validation/cases/<name>.py``
listed in ``CASE_MODULES`` of ``validation/cases/__init__.py``; it defines

- ``NAME: str`` -- equal to its module name ``<name>``,
- ``DESCRIPTION: str`` -- one line,
- ``run(quick: bool) -> CaseResult``.

Each row of a result is a dict ``{case, code, config, cpu_s, error, error_kind, reference}``
(build it with :func:`make_row`): ``code`` is ``"ffrmbs"`` or a peer's name, ``config`` the
swept parameters, ``cpu_s`` CPU seconds, ``error`` a float (relative unless ``error_kind``
says otherwise; NaN when the row has no error), ``reference`` what the error is measured
against. Extra keys are kept in results.json and shown as extra table columns.

A case's status (report.md's summary table, results.json) is "ok", "failed", or
"skipped (<reason>)" when it returns no rows and says why in its ``skipped`` lines
(e.g. a peer code that is not installed).
"""

from __future__ import annotations

import datetime
import importlib
import json
import logging
import math
import numbers
import os
import platform
import re
import tempfile
import time
import traceback
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ffrmbs_app.compile_clock import CompileClock
from ffrmbs_app.ticks import label_log_axis, series_label
from ffrmbs.errors import FfrmbsError, ModelError

ROW_KEYS = ("case", "code", "config", "cpu_s", "error", "error_kind", "reference")
DEFAULT_PLOT_GROUPS = ("code", "error_kind", "reference")
_MARKERS = "osD^v<>pPX*h"


@dataclass
class CaseResult:
    """What a case's ``run(quick)`` returns.

    rows : list of dict
        The rows, see :func:`make_row`.
    skipped : list of str
        One line per part not run and why, e.g. ``"akantu: skipped: akantu not installed"``.
    notes : list of str
        Markdown paragraphs printed under the case's table (e.g. extra comparison tables).
    plot_groups : sequence of str or None
        Keys whose values define one marker series of the work-precision plot; a key is
        looked up in the row, then in its ``config``. None: ``DEFAULT_PLOT_GROUPS``,
        i.e. one series per (code, error_kind, reference).
    figures : dict name -> callable(path)
        Extra figures (e.g. the report's Fig. 9 plot): each callable writes a PNG to the
        path it is given; the harness names it ``<case>_<name>.png`` and shows it in the report.
    """

    rows: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    plot_groups: tuple | list | None = None
    figures: dict = field(default_factory=dict)


def make_row(case, config, cpu_s, error, error_kind, reference, code="ffrmbs", **extra):
    """One result row: ``{case, code, config, cpu_s, error, error_kind, reference, **extra}``.

    ``cpu_s`` [s] and ``error`` are stored as floats (``error=None`` becomes NaN: a row
    without an error); ``config`` is copied into a plain dict. Extra keywords (e.g.
    ``value=203.0``) are kept in results.json and shown as extra columns of the report table.
    """
    row = {"case": case, "code": code, "config": dict(config), "cpu_s": float(cpu_s),
           "error": math.nan if error is None else float(error),
           "error_kind": error_kind, "reference": reference}
    row.update(extra)
    return row


def timed(fn, *args, **kw):
    """Call ``fn(*args, **kw)``; return ``(result, cpu_s)``.

    ``cpu_s`` [s] is the CPU time of this process (``time.process_time``: user + system,
    summed over all its threads, so a multi-threaded BLAS counts every core it uses;
    sleeping and waiting are not counted), less the time numba spent compiling kernels
    or loading them from its cache during the call (:class:`ffrmbs_app.compile_clock.CompileClock`):
    compilation is never run time.
    """
    with CompileClock() as clock:
        start = time.process_time()
        result = fn(*args, **kw)
        cpu = time.process_time() - start
    return result, max(cpu - clock.cpu_seconds, 0.0)


class CpuTiming(NamedTuple):
    """CPU time per call of a function: ``samples`` (repeats,) [s], each the mean over a
    batch of ``loops`` calls; ``result`` the last call's return value."""

    result: object
    samples: np.ndarray
    loops: int

    @property
    def median(self) -> float:
        """Median of the samples [s]."""
        return float(np.median(self.samples))

    @property
    def std(self) -> float:
        """Sample standard deviation [s] (NaN for one sample)."""
        return float(np.std(self.samples, ddof=1)) if self.samples.size > 1 else float("nan")

    @property
    def robust_std(self) -> float:
        """1.4826 × the median absolute deviation [s]: the standard deviation of normal
        scatter, insensitive to a batch slowed by the machine's other load."""
        return float(1.4826 * np.median(np.abs(self.samples - self.median)))


def cpu_samples(fns, repeats=5, min_batch_s=0.02):
    """A :class:`CpuTiming` of each function of ``fns``.

    Like ``timeit``: after one untimed warm-up call (compiled kernels load on first use),
    each of ``repeats`` samples times a batch of ``loops`` calls (enough for
    ``min_batch_s`` CPU seconds, from one calibration call) and divides by ``loops``.
    The batches of the functions alternate, so a slow drift of the machine's load
    affects them alike.
    """
    for fn in fns:
        fn()
    calibrations = [timed(fn) for fn in fns]
    results = [result for result, _ in calibrations]
    loops = [max(1, int(np.ceil(min_batch_s / max(cpu, 1e-6)))) for _, cpu in calibrations]
    samples = [[] for _ in fns]
    for _ in range(repeats):
        for j, fn in enumerate(fns):
            batch, cpu = timed(lambda: [fn() for _ in range(loops[j])])
            results[j] = batch[-1]
            samples[j].append(cpu / loops[j])
    return [CpuTiming(results[j], np.array(samples[j]), loops[j]) for j in range(len(fns))]


def cpu_per_call(fn, repeats=5, min_batch_s=0.02) -> CpuTiming:
    """The :class:`CpuTiming` of ``fn()`` (see :func:`cpu_samples`)."""
    return cpu_samples([fn], repeats, min_batch_s)[0]


def _check_case_module(name, module):
    """Raise ModelError unless ``module`` follows the case protocol under ``name``."""
    missing = [attr for attr in ("NAME", "DESCRIPTION", "run") if not hasattr(module, attr)]
    if missing:
        raise ModelError(f"validation case {name!r} lacks {', '.join(missing)}")
    if module.NAME != name:
        raise ModelError(f"validation case {name!r} has NAME = {module.NAME!r}; they must agree")


class _CaseRegistry(Mapping):
    """Case name -> case module, for the names in ``validation.cases.CASE_MODULES``.

    The list is read on every access and a module is imported only when asked for, so a
    listed but missing or broken module is an error (ModelError) for that case alone.
    """

    def _names(self):
        return list(getattr(importlib.import_module("validation.cases"), "CASE_MODULES", []))

    def __iter__(self):
        return iter(self._names())

    def __len__(self):
        return len(self._names())

    def __getitem__(self, name):
        if name not in self._names():
            raise KeyError(name)
        try:
            module = importlib.import_module(f"validation.cases.{name}")
        except ImportError as exc:
            raise ModelError(f"validation case {name!r} is listed in validation/cases/__init__.py "
                             f"but cannot be imported: {exc}") from exc
        _check_case_module(name, module)
        return module


CASES = _CaseRegistry()


def available_cases():
    """Names of the registered validation cases, in the order of ``CASE_MODULES``."""
    return list(CASES)


@dataclass
class _Outcome:
    """One case's run: its result or its failure."""

    name: str
    description: str = ""
    result: CaseResult | None = None
    failure: str | None = None
    traceback: str | None = None
    cpu_s: float = math.nan
    warnings: list = field(default_factory=list)


def _check_result(result):
    """Raise ModelError unless ``result`` is a CaseResult whose rows carry ROW_KEYS.

    ``config`` must be a dict, ``cpu_s`` a real number, ``error`` a real number or None.
    """
    if not isinstance(result, CaseResult):
        raise ModelError(f"run() returned {type(result).__name__}, expected CaseResult")
    for i, row in enumerate(result.rows):
        if not isinstance(row, dict):
            raise ModelError(f"row {i} is a {type(row).__name__}, expected dict")
        missing = [key for key in ROW_KEYS if key not in row]
        if missing:
            raise ModelError(f"row {i} lacks {', '.join(missing)}")
        if not isinstance(row["config"], dict):
            raise ModelError(f"row {i}: config is a {type(row['config']).__name__}, expected dict")
        if not isinstance(row["cpu_s"], numbers.Real):
            raise ModelError(f"row {i}: cpu_s = {row['cpu_s']!r} is not a number")
        if not (row["error"] is None or isinstance(row["error"], numbers.Real)):
            raise ModelError(f"row {i}: error = {row['error']!r} is neither a number nor None")


QUIET_CATEGORIES = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


class _Collector(logging.Handler):
    """A logging handler keeping the messages of WARNING and above."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


class CaseWarnings:
    """The warnings a case raises while it runs (``warnings.warn``, and the "ffrmbs"
    loggers' warnings, which repeat them), kept for its report instead of printed: they
    are about our own validation scenes, which the user cannot change. :attr:`lines`:
    each distinct message once, with its count ("… (3 times)"); deprecation, import and
    resource warnings are left to Python's filters."""

    def __enter__(self):
        self._catch = warnings.catch_warnings(record=True)
        self._seen = self._catch.__enter__()
        warnings.simplefilter("always")
        for category in QUIET_CATEGORIES:
            warnings.simplefilter("ignore", category)
        self._handler = _Collector()
        self._logger = logging.getLogger("ffrmbs")
        self._logger.addHandler(self._handler)
        return self

    def __exit__(self, *exc):
        self._logger.removeHandler(self._handler)
        self._catch.__exit__(*exc)
        counts = {}
        for message in [str(w.message) for w in self._seen]:
            counts[message] = counts.get(message, 0) + 1
        for message in self._handler.messages:              # logged only, not also warned
            counts.setdefault(message, 1)
        self.lines = [m if n == 1 else f"{m} ({n} times)" for m, n in counts.items()]
        return False


def run_case(registry, name, quick):
    """Load and run one case; an exception becomes a failed outcome, the warnings it
    raises go to the outcome (:class:`CaseWarnings`)."""
    outcome = _Outcome(name)
    start = time.process_time()
    with CaseWarnings() as caught:
        try:
            module = registry[name]
            outcome.description = str(module.DESCRIPTION)
            result = module.run(quick)
            _check_result(result)
            outcome.result = result
        except Exception as exc:  # noqa: BLE001 -- a failing case must not stop the others
            outcome.failure = f"{type(exc).__name__}: {exc}"
            outcome.traceback = traceback.format_exc()
    outcome.cpu_s = time.process_time() - start
    outcome.warnings = caught.lines
    return outcome


def outcome_line(outcome) -> str:
    """One progress line of a case's outcome: its rows and CPU time, skipped or FAILED."""
    if outcome.failure is not None:
        return f"{outcome.name}: FAILED: {outcome.failure}"
    if not outcome.result.rows and outcome.result.skipped:
        return f"{outcome.name}: {_status(outcome)}"
    warned = f", {len(outcome.warnings)} warning(s) in the report" if outcome.warnings else ""
    return f"{outcome.name}: {len(outcome.result.rows)} rows, {outcome.cpu_s:.3g} s CPU{warned}"


def _as_registry(cases):
    """A mapping name -> module from a mapping or from an iterable of case modules."""
    if isinstance(cases, Mapping):
        registry = dict(cases)
    else:
        registry = {module.NAME: module for module in cases}
    for name, module in registry.items():
        _check_case_module(name, module)
    return registry


def _select(registry, only):
    """The case names to run: all, or ``only`` (a name or a list of names)."""
    known = list(registry)
    if only is None:
        return known
    wanted = [only] if isinstance(only, str) else list(only)
    unknown = [name for name in wanted if name not in known]
    if unknown:
        raise ModelError(f"unknown validation case(s) {', '.join(map(repr, unknown))}; "
                         f"known: {', '.join(known) or '(none)'}")
    return wanted


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


_SKIP_REASON = re.compile(r"skipped: (?P<reason>.*?)(?: \([^()]*\))?\s*$")


def _status(outcome) -> str:
    """A case's status: "failed", "ok", or "skipped (<reason>)" when it has no rows and
    says why (its ``skipped`` lines, e.g. "akantu: skipped: akantu not installed (pip
    install ...)" gives "skipped (akantu not installed)"; distinct reasons joined by "; ")."""
    if outcome.failure is not None:
        return "failed"
    result = outcome.result
    if result.rows or not result.skipped:
        return "ok"
    reasons = []
    for line in result.skipped:
        match = _SKIP_REASON.search(line)
        reason = match["reason"] if match else line
        if reason not in reasons:
            reasons.append(reason)
    return f"skipped ({'; '.join(reasons)})"


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
        lines += [f"Not run: {_status(outcome)}.", ""]
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
        status = "FAILED" if o.failure is not None else _status(o)
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
                         "status": _status(o),
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
    registry = CASES if cases is None else _as_registry(cases)
    names = _select(registry, only)
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    if workers is None and scheduler is None and client is None:
        from validation.parallel import record_case_times

        outcomes = []
        for i, name in enumerate(names, 1):
            say(f"[{i}/{len(names)}] {name} ...")
            outcomes.append(run_case(registry, name, quick))
            say(f"[{i}/{len(names)}] {outcome_line(outcomes[-1])}")
        record_case_times(quick, {o.name: o.cpu_s for o in outcomes})
    else:
        from validation.parallel import run_cases

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
