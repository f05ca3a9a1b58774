"""The one exception hierarchy of ffrmbs.

Every error a user can cause by their input or their model derives from
:class:`FfrmbsError`; the command line prints its message and exits non-zero
without a traceback. :func:`quote` shows file content in such a message safely.
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


class OutputFileError(FfrmbsError):
    """A file ffrmbs writes (result file, checkpoint, plot, ParaView export) that cannot
    be written: a full disk, a missing directory, no permission.

    Parameters
    ----------
    path : str or os.PathLike
        The file that could not be written.
    fault : str
        What failed and the system's reason (e.g. "No space left on device").
    """

    def __init__(self, path, fault):
        self.path = str(path)
        self.fault = fault
        super().__init__(f"{self.path}: {fault}")


def first_line(exc: Exception, limit: int = 200) -> str:
    """The first line of ``exc``'s message (its class name when empty), at most ``limit``
    characters: a library's multi-line message in a one-line error."""
    return (str(exc).splitlines() or [type(exc).__name__])[0][:limit]


def os_reason(exc: OSError) -> str:
    """The system's reason of an OSError in a few words (e.g. "No space left on device"):
    its strerror, else :func:`first_line` of its message."""
    return exc.strerror or first_line(exc)


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


def quote(text: str, limit: int = 20) -> str:
    """``text`` quoted for an error message: at most ``limit`` characters, in single
    quotes, every non-printable character (control codes, escapes) shown as ``?`` and a
    cut marked with ``…`` — so a message never echoes more than a short, harmless
    prefix of a file's content."""
    text = str(text)
    shown = "".join(c if c.isprintable() else "?" for c in text[:limit])
    return f"'{shown}{'…' if len(text) > limit else ''}'"
