"""Where ffrmbs keeps what it reuses between runs: :func:`cache_dir` (``$FFRMBS_CACHE`` or
``~/.cache/ffrmbs``) holds the built-in scenes' bodies and, in ``numba/``, the compiled
kernels — unless ``$NUMBA_CACHE_DIR`` says otherwise.

By default numba writes its cache files beside the modules. For an installed ffrmbs those
are in ``site-packages``, and ``pip uninstall`` leaves the files it did not install behind:
the directories ``mbs/``, ``contact/`` … that remain then shadow a later editable install
of ffrmbs as empty namespace packages, and the first import fails with "cannot import
name … (unknown location)". :func:`configure_numba` sets numba's cache directory
(``numba.core.config.CACHE_DIR``, and ``$NUMBA_CACHE_DIR`` for the processes this one
starts) when the user has not. numba picks a kernel's cache directory when the kernel is
defined, so every package that defines kernels calls it first, in its ``__init__``.
"""

from __future__ import annotations

import os
from pathlib import Path

NUMBA_ENV = "NUMBA_CACHE_DIR"


def cache_dir() -> Path:
    """``$FFRMBS_CACHE`` or ``~/.cache/ffrmbs``."""
    return Path(os.environ.get("FFRMBS_CACHE") or Path.home() / ".cache" / "ffrmbs")


def configure_numba() -> str:
    """Set numba's cache directory to ``<cache_dir()>/numba`` unless ``$NUMBA_CACHE_DIR``
    (or numba's configuration) names one; return the directory in use."""
    from numba.core import config

    chosen = os.environ.get(NUMBA_ENV) or config.CACHE_DIR
    if not chosen:
        chosen = str(cache_dir() / "numba")
        os.environ[NUMBA_ENV] = chosen
    config.CACHE_DIR = chosen
    return chosen
