"""A piece of a job run in a second process beside the rest of it.

The job (:mod:`ffrmbs_app.job`) writes the plot and the ParaView export of a result file
while it runs the accuracy checks: both are single-threaded and independent (the checks
write nothing, plot and export only read the closed result file), so on two cores they
take the time of the longer instead of the sum. :func:`start` forks a child that calls
``task()``; :meth:`SideProcess.join` waits for it and says whether it succeeded.

Nothing depends on the child: :func:`start` returns None where a second process does not
pay or cannot be had — one CPU available to this process, no ``fork`` (the child
inherits the loaded modules and the job's state, so it starts in milliseconds; a spawned
one would import everything again), a thread other than the main one (signals reach
only the main thread), a daemonic process (a worker of a process pool may have no
children) — and a child that fails exits quietly with a non-zero code (its traceback
would be the half of an error: the caller does the work again in its own process, where
the error is raised and reported as usual). The child leaves by ``os._exit``: the
parent's exit handlers are the parent's.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import threading

STOP_WAIT = 10.0        # seconds a child has to end after SIGTERM before it is killed


def cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:          # no sched_getaffinity (macOS, Windows)
        return os.cpu_count() or 1


def available() -> bool:
    """Whether a forked second process can run beside this one (module docstring)."""
    return (cpus() >= 2 and "fork" in multiprocessing.get_all_start_methods()
            and threading.current_thread() is threading.main_thread()
            and not multiprocessing.current_process().daemon)


class SideProcess:
    """A forked child running ``task()`` (module docstring)."""

    def __init__(self, task):
        for stream in (sys.stdout, sys.stderr):     # nothing buffered is written twice
            stream.flush()
        self.process = multiprocessing.get_context("fork").Process(target=_child, args=(task,), daemon=True)
        self.process.start()

    def join(self) -> bool:
        """Wait for the child; True when ``task()`` returned."""
        self.process.join()
        return self.process.exitcode == 0

    def stop(self) -> None:
        """End the child (SIGTERM; killed after :data:`STOP_WAIT` seconds) and wait for it."""
        if self.process.is_alive():
            self.process.terminate()
            self.process.join(STOP_WAIT)
            if self.process.is_alive():
                self.process.kill()
        self.process.join()


def start(task) -> SideProcess | None:
    """``task()`` started in a second process, or None where none is available (the
    caller then does the work itself)."""
    return SideProcess(task) if available() else None


def _child(task) -> None:
    try:
        task()
    except BaseException:       # the caller does the work again and reports the error
        os._exit(1)
    os._exit(0)
