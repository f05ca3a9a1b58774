"""Checked reading of a result file (the HDF5 layout of :mod:`mbs.results.result_file`) for the
ParaView export (:mod:`ffrmbs_app.export`) and the plots (:mod:`ffrmbs_app.plot`): the
file opened when it holds samples, each dataset and group fetched, and its shape checked,
with one :class:`~ffrmbs.errors.InputFileError` naming the file and the object at fault.
"""

from __future__ import annotations

from contextlib import contextmanager

import h5py

from ffrmbs.errors import InputFileError
from mbs.results.result_file import attribute, open_result_file


@contextmanager
def open_result(path):
    """Open an ffrmbs result file read-only (:func:`mbs.results.result_file.open_result_file`: a
    regular HDF5 file of the result format and version, reading faults as
    InputFileError) that holds samples: a one-dimensional ``/t``. Yields the ``h5py.File``."""
    with open_result_file(path) as f:
        if "t" not in f and attribute(f, "status") == "running":
            raise InputFileError(path, None, "no samples written yet (the run has just started)")
        t = dataset(f, "t", path)
        if t.ndim != 1:
            raise InputFileError(path, None, f"/t must be one-dimensional, has shape {t.shape}")
        yield f


def _child(parent, name, path, cls, kind):
    """``parent[name]`` as an h5py ``cls`` (Dataset or Group), or InputFileError naming it."""
    obj = parent.get(name)
    if not isinstance(obj, cls):
        where = f"{parent.name.rstrip('/')}/{name}"
        raise InputFileError(path, None, f"missing {kind} {where}" if obj is None else f"{where} is not a {kind}")
    return obj


def dataset(parent, name, path):
    """``parent[name]`` (``parent`` an h5py Group or File) as an h5py Dataset, or an
    InputFileError naming ``path`` (the result file) and the dataset that is missing or
    not a dataset."""
    return _child(parent, name, path, h5py.Dataset, "dataset")


def group(parent, name, path):
    """``parent[name]`` (``parent`` an h5py Group or File) as an h5py Group, or an
    InputFileError naming ``path`` (the result file) and the group that is missing or not
    a group."""
    return _child(parent, name, path, h5py.Group, "group")


def check_shape(ds, shape, path):
    """An InputFileError naming ``path`` and the dataset unless ``ds.shape`` matches
    ``shape`` (a tuple of lengths; None = any length on that axis)."""
    if len(ds.shape) != len(shape) or any(s is not None and s != d for s, d in zip(shape, ds.shape)):
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise InputFileError(path, None, f"{ds.name} has shape {ds.shape}, expected {want}")
