"""Time spent compiling numba kernels, measured apart from the run it interrupts.

Every kernel of ffrmbs is compiled with ``cache=True``: the first run of a kind of scene
compiles its kernels and stores them on disk (``~/.cache/ffrmbs/numba`` or
``$NUMBA_CACHE_DIR``, :mod:`ffrmbs.caches`), later runs load them. Compilation happens lazily, at a kernel's
first call, so it falls inside whatever is being timed. :class:`CompileClock` listens to
numba's ``numba:compiler_lock`` event — numba holds that lock while it compiles a kernel
or loads it from the cache, and nested compilations are counted once — and to
``numba:compile`` (a real compilation, not a cache load), so a job can

- tell the user when compilation starts, on its own line (``log``), once;
- report the seconds spent compiling or loading, and how many kernels were compiled;
- subtract those wall seconds from the run's wall time and those CPU seconds from its CPU
  time, so that a reported per-step cost never contains compilation.
"""

from __future__ import annotations

import time
from contextlib import ExitStack

from numba.core import event


class _Listener(event.Listener):
    """Wall and CPU time between the outermost start and end of one event kind; counts
    starts."""

    def __init__(self, on_first=None):
        self.seconds = self.cpu_seconds = 0.0
        self.count = 0
        self._depth = 0
        self._t0 = self._c0 = 0.0
        self._on_first = on_first

    def on_start(self, ev):
        if self._depth == 0:
            if self.count == 0 and self._on_first is not None:
                self._on_first()
            self._t0, self._c0 = time.perf_counter(), time.process_time()
            self.count += 1
        self._depth += 1

    def on_end(self, ev):
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._t0
            self.cpu_seconds += time.process_time() - self._c0


class CompileClock:
    """A context manager measuring numba compilation inside its ``with`` block.

    Attributes after (or during) the block: ``seconds`` — wall seconds [s] spent
    compiling kernels or loading them from numba's disk cache; ``cpu_seconds`` — the CPU
    seconds [s] of this process in that time; ``compiled`` — kernel
    signatures compiled (0 when everything came from the cache). ``log(msg)`` is called
    once, when the first real compilation starts.
    """

    def __init__(self, log=None):
        self._lock = _Listener()
        self._compile = _Listener(on_first=None if log is None else lambda: log(
            "compiling numba kernels (first run of this kind of scene; cached on disk for the next) ..."))
        self._stack = ExitStack()

    @property
    def seconds(self) -> float:
        return self._lock.seconds

    @property
    def cpu_seconds(self) -> float:
        return self._lock.cpu_seconds

    @property
    def compiled(self) -> int:
        return self._compile.count

    def __enter__(self):
        self._stack.enter_context(event.install_listener("numba:compiler_lock", self._lock))
        self._stack.enter_context(event.install_listener("numba:compile", self._compile))
        return self

    def __exit__(self, *exc):
        self._stack.close()
        return False

    def describe(self) -> str:
        """One line for the job's report."""
        if self.compiled:
            return (f"kernels: {self.compiled} compiled in {self.seconds:.2f} s (cached on disk for the next run; "
                    f"not counted in the cost)")
        if self.seconds == 0.0:
            return "kernels: already loaded in this process"
        return f"kernels: loaded from numba's disk cache in {self.seconds:.2f} s (not counted in the cost)"
