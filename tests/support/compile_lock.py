"""One process at a time compiles a given numba kernel, so the xdist workers share each
compilation through numba's disk cache instead of both doing it.

numba compiles a kernel in :meth:`numba.core.dispatcher.Dispatcher.compile`: it loads the
signature from the disk cache if it is there, else compiles and saves it. Two workers that
need the same kernel at the same time both miss the cache and both compile (tens of CPU
seconds for the contact solver's kernels). :func:`install` wraps that method in an
exclusive ``flock`` on a file per kernel (module and qualified name) for kernels with a
disk cache: the second worker waits, then loads what the first saved. Kernels call
kernels, never themselves, so the locks a process holds follow one call chain and two
processes cannot wait on each other.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
from pathlib import Path

from numba.core.caching import NullCache
from numba.core.dispatcher import Dispatcher


def lock_file(directory, kernel) -> Path:
    """The file in ``directory`` that ``kernel``'s (a numba dispatcher's) compilations lock."""
    name = f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}"
    return Path(directory) / hashlib.sha1(name.encode()).hexdigest()


def install(directory) -> None:
    """Lock each compilation of a disk-cached kernel on its :func:`lock_file` in ``directory``."""
    Path(directory).mkdir(parents=True, exist_ok=True)
    compile_ = Dispatcher.compile

    @functools.wraps(compile_)
    def compile_locked(self, sig):
        if isinstance(self._cache, NullCache):
            return compile_(self, sig)
        with open(lock_file(directory, self), "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            return compile_(self, sig)

    Dispatcher.compile = compile_locked
