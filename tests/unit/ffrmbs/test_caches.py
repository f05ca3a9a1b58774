"""Where the compiled kernels go (:mod:`ffrmbs.caches`): without ``$NUMBA_CACHE_DIR`` into
``$FFRMBS_CACHE/numba`` — not beside the modules, where an uninstalled copy would leave
them to shadow the next install — and into ``$NUMBA_CACHE_DIR`` when it is set. Each case
runs in a fresh interpreter: numba picks a kernel's cache directory when it is defined."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

PROBE = """
import numpy as np
import contours
from contours._rigid_kernels import sphere_angles
sphere_angles(np.eye(3), np.array([1.0, 0.0, 0.0]))
import os
print(os.environ["NUMBA_CACHE_DIR"])
"""


def _run(env):
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def _kernel_files(root):
    return [p for p in root.rglob("*") if p.suffix in (".nbi", ".nbc")]


@pytest.mark.parametrize("given", [False, True])
def test_kernels_are_cached_in_the_ffrmbs_cache_or_numba_s_own_directory(tmp_path, given):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["FFRMBS_CACHE"] = str(tmp_path / "ffrmbs")
    if given:
        env["NUMBA_CACHE_DIR"] = str(tmp_path / "mine")
    where = tmp_path / ("mine" if given else "ffrmbs/numba")
    assert _run(env) == str(where)          # what the processes it starts inherit
    assert any("_rigid_kernels" in p.name for p in _kernel_files(where))
    if not given:
        assert not (tmp_path / "mine").exists()
