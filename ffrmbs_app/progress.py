"""Progress bars (tqdm) that stay silent when nobody watches.

A bar draws on ``sys.stderr`` only when it is a terminal, so logs, pipes, CI and the tests
see nothing. The environment variable ``FFRMBS_PROGRESS`` overrides the check:

* ``FFRMBS_PROGRESS=1`` (or ``true``, ``yes``, ``on``): always draw (e.g. under ``tee``);
* ``FFRMBS_PROGRESS=0`` (or ``false``, ``no``, ``off``): never draw;
* unset or anything else: draw when ``sys.stderr.isatty()``.

Three uses:

* :func:`progress_bar` — a bar over a known total, as a context manager::

      with progress_bar(t_end, "simulating", unit="s") as bar:
          ...
          bar.update_to(t)            # absolute value, e.g. the simulated time [s]

* :class:`ProgressCallback` — what a time-stepping loop calls as ``progress(t)`` after each
  accepted step (cheap: one subtraction and tqdm's own rate limit when shown, a no-op
  when silent)::

      with ProgressCallback(t_end) as progress:
          integrator.run(..., progress=progress)

* stage bars — ``bar.stage(label)`` closes the previous stage and shows ``label`` while
  the next runs (the preprocessing pipeline: meshing, assembling K, modes, writing).

:func:`write` prints a log line without tearing a bar that is being drawn.
"""

from __future__ import annotations

import os
import sys

from tqdm import tqdm

ENV_VAR = "FFRMBS_PROGRESS"
_ON = {"1", "true", "yes", "on"}
_OFF = {"0", "false", "no", "off"}

_BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| {n:.4g}/{total:.4g} {unit} [{elapsed}<{remaining}]"
_STAGE_FORMAT = "{desc}: {n:.0f}/{total:.0f} {unit}s |{bar}| [{elapsed}]{postfix}"

_active = []   # bars being drawn (for write())


def progress_enabled(stream=None) -> bool:
    """Whether bars are drawn on ``stream`` (default ``sys.stderr``): ``FFRMBS_PROGRESS``
    when it says on or off, otherwise whether the stream is a terminal."""
    env = os.environ.get(ENV_VAR, "").strip().lower()
    if env in _ON:
        return True
    if env in _OFF:
        return False
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream is not None and stream.isatty())
    except (AttributeError, ValueError):      # no isatty, or a closed stream
        return False


class ProgressBar:
    """A bar from 0 to ``total`` (in ``unit``) on ``sys.stderr``, drawn only when
    :func:`progress_enabled`; when silent every method is a no-op.

    Parameters
    ----------
    total : float
        The value at completion (e.g. t_end [s], a number of files or stages).
    desc : str
        The label before the bar.
    unit : str
        Unit of ``total`` shown after the numbers ("s", "file", "stage", ...).
    stages : bool
        Format for a count of stages with the running stage's label (see :meth:`stage`).
    enabled : bool or None
        Force on or off; None asks :func:`progress_enabled`.
    """

    def __init__(self, total, desc, unit="s", stages=False, enabled=None):
        self.total = float(total)
        self.enabled = progress_enabled() if enabled is None else bool(enabled)
        self._bar = None
        self._stage_open = False
        if self.enabled:
            self._bar = tqdm(total=self.total, desc=desc, unit=unit, file=sys.stderr, leave=True,
                             dynamic_ncols=True, mininterval=0.2,
                             bar_format=_STAGE_FORMAT if stages else _BAR_FORMAT)
            _active.append(self)

    @property
    def n(self) -> float:
        """The value reached so far (0 when silent)."""
        return float(self._bar.n) if self._bar is not None else 0.0

    def update(self, step=1.0):
        """Advance by ``step`` (in ``unit``)."""
        if self._bar is not None:
            self._bar.update(step)

    def update_to(self, value):
        """Advance to the absolute ``value`` (clipped to [n, total]; never goes back)."""
        bar = self._bar
        if bar is not None:
            step = min(value, self.total) - bar.n
            if step > 0:
                bar.update(step)

    __call__ = update_to

    def stage(self, label):
        """Count the previous stage as done (if one is running) and show ``label``."""
        if self._bar is None:
            return
        if self._stage_open:
            self._bar.update(1)
        self._stage_open = True
        self._bar.set_postfix_str(str(label), refresh=True)

    def postfix(self, text):
        """Show ``text`` after the bar (e.g. counts of running and failed tasks)."""
        if self._bar is not None:
            self._bar.set_postfix_str(str(text), refresh=False)

    def write(self, msg, file=None):
        """Print ``msg`` on ``file`` (default stderr) without tearing the bar."""
        write(msg, file)

    def close(self, complete=False):
        """Stop drawing (idempotent); ``complete`` first fills the bar (a finished run)."""
        if self._bar is None:
            return
        if complete:
            if self._stage_open:
                self._bar.update(1)
                self._stage_open = False
                self._bar.set_postfix_str("done", refresh=False)
            self.update_to(self.total)
        self._bar.close()
        self._bar = None
        if self in _active:
            _active.remove(self)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.close(complete=exc_type is None)
        return False


def progress_bar(total, desc, unit="s", enabled=None) -> ProgressBar:
    """A :class:`ProgressBar` from 0 to ``total`` [``unit``], silent unless on a terminal
    (or ``FFRMBS_PROGRESS=1``); use it as a context manager and call ``update_to(value)``."""
    return ProgressBar(total, desc, unit=unit, enabled=enabled)


def stage_bar(n_stages, desc, enabled=None) -> ProgressBar:
    """A bar over ``n_stages`` named stages: call ``stage(label)`` as each begins; leaving
    the ``with`` block without an error completes the last one."""
    return ProgressBar(n_stages, desc, unit="stage", stages=True, enabled=enabled)


class ProgressCallback(ProgressBar):
    """The adapter a time-stepping loop calls as ``progress(t)`` with the simulated time
    ``t`` [s] after each accepted step; the bar runs from ``t_start`` to ``t_end`` [s].

    Silent (a no-op call) unless :func:`progress_enabled`. Close it (or use ``with``) when
    the run ends; a run that stops early leaves the bar where it stopped.
    """

    def __init__(self, t_end, desc="simulating", t_start=0.0, enabled=None):
        self.t_start = float(t_start)
        super().__init__(float(t_end) - self.t_start, desc, unit="s", enabled=enabled)

    def __call__(self, t):
        if self._bar is not None:
            self.update_to(t - self.t_start)


def write(msg, file=None):
    """Print a log line on ``file`` (default ``sys.stderr``), flushed; while a bar is drawn
    it goes through ``tqdm.write`` so the bar is redrawn below it, not torn."""
    file = sys.stderr if file is None else file
    if _active:
        tqdm.write(str(msg), file=file)
        file.flush()
    else:
        print(msg, file=file, flush=True)
