"""The tests' compile lock (tests/support/compile_lock.py), installed in every test process
by tests/conftest.py: a disk-cached kernel waits for its lock file before it compiles, and
once it may, it loads what the holder saved instead of compiling it again."""

import fcntl
import importlib
import sys
import threading
import time

import numpy as np
from numba import typeof
from numba.core.dispatcher import Dispatcher

import compile_lock
from conftest import CACHE

KERNEL = """
from numba import njit

@njit(cache=True)
def kernel(x):
    return x.sum() + 1.0
"""


def test_a_kernel_waits_for_its_lock_and_then_loads_from_the_cache(tmp_path, monkeypatch):
    (tmp_path / "locked_kernel.py").write_text(KERNEL)
    monkeypatch.syspath_prepend(str(tmp_path))
    holder = importlib.import_module("locked_kernel").kernel
    waiter = {}
    with open(compile_lock.lock_file(CACHE / "numba-locks", holder), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)                 # another worker compiling it
        thread = threading.Thread(target=lambda: waiter.setdefault("sum", holder(np.ones(3))))
        thread.start()
        time.sleep(1.0)
        assert thread.is_alive() and "sum" not in waiter  # waiting, not compiling
        Dispatcher.compile.__wrapped__(holder, (typeof(np.ones(3)),))   # the holder compiles, saves
    thread.join(60)
    assert waiter["sum"] == 4.0
    sys.modules.pop("locked_kernel")
    again = importlib.import_module("locked_kernel").kernel  # a second process's view
    assert again(np.ones(3)) == 4.0
    assert sum(again._cache_hits.values()) == 1 and sum(again._cache_misses.values()) == 0
