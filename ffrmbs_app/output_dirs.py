"""Output directories and temporary files that leave nothing behind: directories created
for a write removed again when it fails (:func:`new_directories`), the temporary files
and directories of a writer that was killed removed by the next writer of the same output
(:func:`remove_stale`; their names carry the writer's pid, :func:`temporary_name`), and
SIGTERM turned into an interruption for a block that cleans up after itself
(:func:`terminate_interrupts`)."""

from __future__ import annotations

import os
import shutil
import signal
import threading
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def new_directories(path):
    """Create the directory ``path`` and its missing ancestors for the block; if the block
    raises, remove the ones it created (innermost first, if empty) and re-raise.

    Yields the directories created (outermost first)."""
    missing = []
    p = Path(path)
    while not p.exists():
        missing.append(p)
        p = p.parent
    missing.reverse()
    created = []
    try:
        for d in missing:
            d.mkdir()
            created.append(d)
        yield created
    except BaseException:
        for d in reversed(created):
            try:
                d.rmdir()
            except OSError:
                pass
        raise


def shown(path) -> str:
    """``path`` as a command prints it: relative to the current directory when it lies
    under it ("out/bounce.h5"), else absolute ("/data/runs/bounce.h5"), so every path a
    command prints reads one way, whichever way it was made."""
    p = Path(path).absolute()
    try:
        return str(p.relative_to(Path.cwd()))
    except ValueError:
        return str(p)


def temporary_name(prefix) -> str:
    """``<prefix><pid>-`` : the start of the name of a temporary file or directory of this
    process (``tempfile.mkdtemp(prefix=…)`` adds a random tail), which
    :func:`remove_stale` recognizes once the process is gone."""
    return f"{prefix}{os.getpid()}-"


def remove_stale(directory, prefix) -> list:
    """Remove the entries of ``directory`` named ``<prefix><pid>`` or ``<prefix><pid>-…``
    whose process ``pid`` has ended: what a writer killed mid-write (kill -9, a power
    cut) left behind. Entries of running processes (this one included) are kept.
    Returns the paths removed."""
    directory = Path(directory)
    removed = []
    try:
        entries = list(directory.iterdir())
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(prefix):
            continue
        pid = entry.name[len(prefix):].split("-", 1)[0]
        if not pid.isdigit() or _running(int(pid)):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
        removed.append(entry)
    return removed


def _running(pid) -> bool:
    """Whether a process ``pid`` exists (signal 0 checks without sending anything)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:         # another user's process
        return True
    return True


@contextmanager
def terminate_interrupts():
    """In the block, SIGTERM raises KeyboardInterrupt as Ctrl-C does, so that the block's
    own cleanup (a temporary directory removed) runs before the process ends; outside
    the main thread (where Python takes no signals) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(signal.Signals(signum).name)

    old = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)
