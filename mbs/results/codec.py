"""Values of a run as named arrays and back: the encoding of a checkpoint's entries
(:mod:`mbs.results.checkpoint`).

:func:`put` turns a value into an array under its name and records its kind; :func:`take`
turns it back, written into the array the fresh run holds there (arrays other arrays view
stay shared), its shape and dtype checked. A value may be

- a numpy array: saved as is, restored in place (``current[...] = saved``);
- a float, int or bool (numpy scalars included): a 0-d array, restored as the Python
  type;
- a tuple of numbers: a float array, restored as a tuple;
- None: no array, its kind "none".

The kind of each entry ("array", "float", "int", "bool", "tuple", "none") goes into
``kinds`` (kept in the checkpoint's JSON header), so reading needs no code from the file.
"""

from __future__ import annotations

import numbers

import numpy as np

SCALARS = {"float": (float, np.float64), "int": (int, np.int64), "bool": (bool, np.bool_)}


class StateMismatch(ValueError):
    """A saved state that does not fit the run it is restored into (the message names
    the entry and the mismatch)."""


def put(key, value, arrays: dict, kinds: dict) -> None:
    """Add ``value`` (module docstring) under ``key`` to ``arrays`` and its kind to ``kinds``."""
    if value is None:
        kinds[key] = "none"
    elif isinstance(value, np.ndarray):
        arrays[key], kinds[key] = value, "array"
    elif isinstance(value, (bool, np.bool_)):
        arrays[key], kinds[key] = np.array(value, dtype=np.bool_), "bool"
    elif isinstance(value, numbers.Integral):
        arrays[key], kinds[key] = np.array(value, dtype=np.int64), "int"
    elif isinstance(value, numbers.Real):
        arrays[key], kinds[key] = np.array(value, dtype=np.float64), "float"
    elif isinstance(value, tuple) and all(isinstance(v, numbers.Real) for v in value):
        arrays[key], kinds[key] = np.array(value, dtype=np.float64), "tuple"
    else:
        raise TypeError(f"{key}: {type(value).__name__} is not run state that a checkpoint can hold")


def take(key, current, arrays, kinds):
    """The value saved under ``key`` for a place now holding ``current`` (arrays are
    written into ``current`` and returned); StateMismatch if it is missing or does not fit."""
    kind = kinds.get(key)
    if kind is None or (kind != "none" and key not in arrays):
        raise StateMismatch(f"{key} is missing")
    if kind == "none":
        return None
    saved = arrays[key]
    if kind == "array":
        if isinstance(current, np.ndarray):
            if current.shape != saved.shape or current.dtype != saved.dtype:
                raise StateMismatch(f"{key} has shape {saved.shape} {saved.dtype}, this run's {current.shape} "
                                    f"{current.dtype}")
            current[...] = saved
            return current
        return np.array(saved)
    if kind == "tuple":
        if saved.ndim != 1 or saved.dtype != np.float64:
            raise StateMismatch(f"{key} is not a tuple of numbers")
        return tuple(float(v) for v in saved)
    if kind not in SCALARS:
        raise StateMismatch(f"{key} has an unknown kind {kind!r}")
    python, dtype = SCALARS[kind]
    if saved.shape != () or saved.dtype != dtype:
        raise StateMismatch(f"{key} is not a {kind} (shape {saved.shape}, {saved.dtype})")
    return python(saved[()])
