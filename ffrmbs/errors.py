"""The one exception hierarchy of ffrmbs.

Every error a user can cause by their input or their model derives from
:class:`FfrmbsError`; the command line prints its message and exits non-zero
without a traceback.
"""

from __future__ import annotations


class FfrmbsError(Exception):
    """Base class of all errors ffrmbs raises on purpose."""


class InputFileError(FfrmbsError):
    """A malformed or inconsistent input file.

    Parameters
    ----------
    path : str or os.PathLike
        The file at fault.
    line : int or None
        1-based line number of the fault, or None when the fault concerns the
        whole file (e.g. it is empty, or two files disagree).
    fault : str
        What is wrong, in words.
    """

    def __init__(self, path, line, fault):
        self.path = str(path)
        self.line = line
        self.fault = fault
        where = f"{self.path}, line {line}" if line is not None else self.path
        super().__init__(f"{where}: {fault}")


class ModelError(FfrmbsError):
    """An inconsistent model: unknown node group, bad parameter, missing data."""


class SimulationError(FfrmbsError):
    """A simulation that cannot go on (NaN, no convergence, ...).

    Carries the time ``t`` [s], the step index ``step`` and the ``cause``.
    """

    def __init__(self, t, step, cause):
        self.t = t
        self.step = step
        self.cause = cause
        super().__init__(f"simulation stopped at t = {t:.6g} s (step {step}): {cause}")


class RunInterrupted(FfrmbsError):
    """A run stopped on request (SIGINT, SIGTERM) after a complete step.

    Carries the time ``t`` [s], the step index ``step``, the ``reason`` and, like
    :class:`SimulationError`, the results so far in ``result``.
    """

    def __init__(self, t, step, reason):
        self.t = t
        self.step = step
        self.reason = reason
        self.result = None
        super().__init__(f"run interrupted at t = {t:.6g} s (step {step}): {reason}")


def quote(text, limit: int = 20) -> str:
    """``text`` as a short, printable quotation for an error message: at most ``limit``
    characters of it, non-printable ones as '?', cut ones marked by '…'."""
    s = "".join(c if c.isprintable() else "?" for c in str(text)[:limit])
    return f"'{s}…'" if len(str(text)) > limit else f"'{s}'"
