"""The on-disk cache of the peers' reference runs: one ``.npz`` per run, keyed by its recipe.

A run is named ``<name>-<first 16 hex of sha256(JSON recipe)>.npz`` in
:func:`ffrmbs_app.scenes.cache.cache_dir`, holds its recipe (as JSON text) beside its
arrays, is written atomically (a temporary file beside it, then a rename) and read
without pickle; a file whose recipe differs from the one asked for is not a hit.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from ffrmbs_app.scenes.cache import cache_dir


def cache_path(name: str, key: dict) -> Path:
    """``cache_dir() / <name>-<first 16 hex of sha256(JSON key)>.npz``."""
    digest = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]
    return cache_dir() / f"{name}-{digest}.npz"


def store(path: Path, key: dict, arrays: dict) -> None:
    """Write ``arrays`` (name -> array) and the recipe ``key`` to ``path`` atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, recipe=np.array(json.dumps(key, sort_keys=True)), **arrays)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def load(path: Path, key: dict) -> dict | None:
    """The arrays cached at ``path`` (name -> array, the recipe left out) if the file
    exists and holds ``key``, else None."""
    if not path.exists():
        return None
    with np.load(path, allow_pickle=False) as z:
        if json.loads(str(z["recipe"])) != json.loads(json.dumps(key)):
            return None
        return {name: z[name] for name in z.files if name != "recipe"}
