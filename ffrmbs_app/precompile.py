"""Compile the default scene's numba kernels in a second process while the job preprocesses.

A cold first ``ffrmbs run`` spends most of its time compiling numba kernels (about 40 CPU
s on a 2-core machine) and preprocessing the beam (its modes, some 5 s). Both are
single-threaded, so on two cores they can run side by side: :func:`start` launches
:mod:`ffrmbs_app.precompile_child` with the job's settings (:func:`child_command`, from
the copy of ffrmbs the job runs), which builds the default scene on the 25 mm mesh
(:data:`~ffrmbs_app.scenes.point_mass_beam.TET10_COARSE`, the job's mesh check, cached
for it) and runs its warm-up, which compiles every kernel the scene calls with the
argument types of the 12.5 mm mesh's scene (the same arrays, other sizes) into numba's
disk cache (``cache=True``; :mod:`ffrmbs.caches`, the directory inherited). The job preprocesses the
12.5 mm beam meanwhile and :meth:`Precompiler.wait`\\ s for the child before it calls a
kernel, then loads them from the cache; nothing is compiled twice and nothing depends on
the child: if it fails, the job compiles what it needs itself.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from dataclasses import asdict
from pathlib import Path

CHILD = "ffrmbs_app.precompile_child"     # the module the second process runs


class Precompiler:
    """A running child process compiling the default scene's kernels (module docstring)."""

    def __init__(self, process):
        self.process = process
        self.started = time.perf_counter()

    def wait(self, log) -> float:
        """Wait for the child; say how long it took (wall seconds since its start, which
        ran beside the preprocessing) and return it; a failed child is named in one line."""
        code = self.process.wait()
        seconds = time.perf_counter() - self.started
        if code == 0:
            log(f"kernels compiled in a second process beside the preprocessing: {seconds:.2f} s "
                "(cached on disk for the next run; not counted in the cost)")
        else:
            log(f"compiling the kernels in a second process failed (exit {code}); the run compiles them itself")
        return seconds

    def stop(self) -> None:
        """End the child (the job stopped before it needed the kernels)."""
        self.process.kill()
        self.process.wait()


def start(settings, log) -> Precompiler:
    """Launch the child for the default scene's ``settings`` (a
    :class:`~ffrmbs_app.main_job.JobSettings`); its output is discarded."""
    log("compiling numba kernels in a second process while preprocessing (first run; cached on disk for the "
        "next) ...")
    process = subprocess.Popen(child_command(settings), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    return Precompiler(process)


def child_command(settings) -> list:
    """The child's command line: :data:`CHILD` run as ``__main__`` from the copy of ffrmbs
    this process imported (its directory first on ``sys.path``). ``python -m CHILD`` would
    put the working directory first, and from a clone after ``pip install .`` import the
    clone's source while the job runs the installed copy: numba keys its disk cache by the
    source's directory, so the job would compile every kernel again."""
    root = str(Path(__file__).resolve().parents[1])
    code = f"import runpy, sys; sys.path.insert(0, {root!r}); runpy.run_module({CHILD!r}, run_name='__main__')"
    return [sys.executable, "-c", code, json.dumps(asdict(settings))]
