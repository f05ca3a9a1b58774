"""The validation harness: the case protocol, CPU timing, the registry of cases and the run of
one case (its outcome, warnings and status). :mod:`validation.report` runs the chosen cases
and writes results.json, report.md and the work-precision plots.

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

import importlib
import logging
import math
import numbers
import re
import time
import traceback
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ffrmbs_app.compile_clock import CompileClock
from ffrmbs.errors import ModelError

ROW_KEYS = ("case", "code", "config", "cpu_s", "error", "error_kind", "reference")
DEFAULT_PLOT_GROUPS = ("code", "error_kind", "reference")


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
        return f"{outcome.name}: {case_status(outcome)}"
    warned = f", {len(outcome.warnings)} warning(s) in the report" if outcome.warnings else ""
    return f"{outcome.name}: {len(outcome.result.rows)} rows, {outcome.cpu_s:.3g} s CPU{warned}"


def as_registry(cases):
    """A mapping name -> module from a mapping or from an iterable of case modules."""
    if isinstance(cases, Mapping):
        registry = dict(cases)
    else:
        registry = {module.NAME: module for module in cases}
    for name, module in registry.items():
        _check_case_module(name, module)
    return registry


def select_cases(registry, only):
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


_SKIP_REASON = re.compile(r"skipped: (?P<reason>.*?)(?: \([^()]*\))?\s*$")


def case_status(outcome) -> str:
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
