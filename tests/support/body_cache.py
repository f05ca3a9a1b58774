"""The tests' body cache: :func:`preprocess.build_body` computed once per recipe and kept on disk.

A recipe is everything the body data follows from: the mesh (points, tets, node groups,
source), the material, the number of modes and every option of ``build_body`` (clamp,
units, params, limits check, geometric stiffness, mass kind), together with the source of
the ``preprocess`` package and the numpy and scipy versions, so an entry is never read for
code or inputs it was not made from. Its key is the SHA-256 of those, pickled.

Entries are pickled :class:`preprocess.BodyData` (bit-exact: arrays, CSR index order,
dtypes and params come back as they were built), one file per key in the cache directory,
written under a temporary name and moved into place with ``os.replace``, so a reader sees
the whole file or none. A lock file per key lets one process (of several xdist workers)
build while the others wait and then read. Warnings raised while building are stored with
the entry and raised again on every read, as a build would.

A call that watches the building (``log=`` or ``progress=`` given) builds every time.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy

import paths


def _source_digest() -> str:
    """SHA-256 of the ``preprocess`` package's source files (names and contents)."""
    h = hashlib.sha256()
    for path in sorted((paths.REPO / "preprocess").rglob("*.py")):
        h.update(str(path.relative_to(paths.REPO)).encode())
        h.update(path.read_bytes())
    h.update(f"numpy {np.__version__} scipy {scipy.__version__}".encode())
    return h.hexdigest()


class BodyCache:
    """``build_body`` of :mod:`preprocess` with its results kept in ``directory``."""

    def __init__(self, directory, build_body):
        self.directory = Path(directory)
        self.build_body = build_body
        self.source = _source_digest()
        self.built = self.read = 0

    def key(self, mesh, material, n_modes, options) -> str:
        """The entry name of one recipe (module docstring)."""
        recipe = (self.source, mesh.points, mesh.tets, sorted(mesh.node_groups.items()), mesh.source,
                  material, n_modes, sorted(options.items()))
        return hashlib.sha256(pickle.dumps(recipe, protocol=5)).hexdigest()

    def __call__(self, mesh, material, n_modes, clamp=None, log=None, progress=None, **options):
        """:func:`preprocess.build_body` (same arguments), read from the cache when built before."""
        if log is not None or progress is not None:
            return self.build_body(mesh, material, n_modes, clamp, log=log, progress=progress, **options)
        options["clamp"] = clamp
        path = self.directory / f"{self.key(mesh, material, n_modes, options)}.pkl"
        with self._lock(path):
            if not path.exists():
                self._write(path, *self._build(mesh, material, n_modes, options))
                self.built += 1
            else:
                self.read += 1
            body, caught = pickle.loads(path.read_bytes())
        for message in caught:
            warnings.warn(message, stacklevel=2)
        return body

    def _build(self, mesh, material, n_modes, options):
        """(body data, the warnings its building raised)."""
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            body = self.build_body(mesh, material, n_modes, **options)
        return body, [w.message for w in caught]

    def _write(self, path: Path, body, caught) -> None:
        """Pickle (body, warnings) to ``path`` through a temporary file and ``os.replace``."""
        temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        temporary.write_bytes(pickle.dumps((body, caught), protocol=5))
        os.replace(temporary, path)

    @contextmanager
    def _lock(self, path: Path):
        """Hold the exclusive lock of ``path``'s entry (a ``.lock`` file beside it)."""
        self.directory.mkdir(parents=True, exist_ok=True)
        with open(path.with_suffix(".lock"), "a") as handle:
            fcntl.flock(handle, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(handle, fcntl.LOCK_UN)
