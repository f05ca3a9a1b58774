"""Builders of the files a fault-audit case plants (:mod:`qa.fault_cases`): each is a function
``build(path, shared)`` writing one file or directory at ``path`` of a case directory, from
a literal content or from the audit's valid inputs in ``shared``. Among them the planted
checkpoints whose loading would run code (:func:`planted_pickle`, :func:`planted_object_array`).
"""

from __future__ import annotations

import os
import pickle
import shlex
import shutil

import h5py
import numpy as np

PICKLED_HEADER = b"ffrmbs-checkpoint-2\n" + b"0" * 64 + b"\n"   # the older pickled format's, a forged signature


def text(content: str):
    return lambda path, shared: path.write_text(content)


def scene_file(content: str):
    """A scene file; ``@CASE@`` in ``content`` stands for the case directory."""
    return lambda path, shared: path.write_text(content.replace("@CASE@", str(path.parent)))


def raw(content: bytes):
    return lambda path, shared: path.write_bytes(content)


def fifo():
    return lambda path, shared: os.mkfifo(path)


def folder():
    return lambda path, shared: path.mkdir()


def copy(rel: str):
    """A copy of ``shared/rel`` (a file or a directory)."""
    def build(path, shared):
        src = shared / rel
        if src.is_dir():
            shutil.copytree(src, path)
        else:
            shutil.copyfile(src, path)
    return build


def lines_edited(rel: str, edit):
    """``shared/rel`` (a text file) with its lines passed through ``edit(lines) -> lines``."""
    def build(path, shared):
        path.write_text("\n".join(edit((shared / rel).read_text().splitlines())) + "\n")
    return build


def h5_edited(rel: str, edit):
    """A copy of the HDF5 file ``shared/rel`` changed in place by ``edit(h5py.File)``."""
    def build(path, shared):
        shutil.copyfile(shared / rel, path)
        with h5py.File(path, "r+") as f:
            edit(f)
    return build


def truncated(rel: str, n_bytes: int):
    return lambda path, shared: path.write_bytes((shared / rel).read_bytes()[:n_bytes])


class _Planted:
    """An object whose unpickling runs ``touch marker`` (what an attacker plants)."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {shlex.quote(str(self.marker))}",)


def planted_pickle(header: bytes, marker: str):
    """A checkpoint made of ``header`` and a pickle that creates the file ``marker`` beside
    the checkpoint when loaded."""
    return lambda path, shared: path.write_bytes(header + pickle.dumps(_Planted(path.parent / marker)))


def planted_object_array(marker: str):
    """A checkpoint in the current format (an .npz) with a header and an object array
    whose pickle creates the file ``marker`` beside the checkpoint when loaded."""
    def build(path, shared):
        with open(path, "wb") as f:
            np.savez(f, header=np.frombuffer(b'{"format": "ffrmbs-checkpoint", "format_version": 3}', dtype=np.uint8),
                     plant=np.array([_Planted(path.parent / marker)], dtype=object))
    return build
