"""One run at a time per result file: an exclusive lock on ``OUT/<scene>.lock`` held while
the job runs.

The lock is ``fcntl.flock`` on the lock file, which holds the pid of its owner. The
kernel drops it when its owner ends, even by kill -9, so a stale lock file never blocks
a later run. A second run for the same result file is refused at once with the owner's
pid (:class:`~ffrmbs.errors.FfrmbsError`).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from pathlib import Path

from ffrmbs.errors import FfrmbsError


def in_use(result_path, pid=None) -> FfrmbsError:
    """The error of a result file that another run (with ``pid``, if known) is writing."""
    return FfrmbsError(f"{result_path} is in use by another run" + (f" (pid {pid})" if pid else "")
                       + "; wait for it to end or choose another --out")


@contextlib.contextmanager
def output_lock(result_path):
    """Hold the lock of ``result_path`` (``<stem>.lock`` beside it; its directory is
    created) for the ``with`` block; refuse if another process holds it. The lock file is
    removed on leaving."""
    result_path = Path(result_path)
    path = result_path.with_suffix(".lock")
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        f = open(path, "a+")
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            pid = f.read(20).strip()
            f.close()
            raise in_use(result_path, pid=pid if pid.isdigit() else None) from None
        try:                         # the file locked is still the one at ``path`` (not removed meanwhile)
            if os.stat(path).st_ino == os.fstat(f.fileno()).st_ino:
                break
        except FileNotFoundError:
            pass
        f.close()
    try:
        f.truncate(0)
        f.write(str(os.getpid()))
        f.flush()
        yield
    finally:
        path.unlink(missing_ok=True)
        f.close()
