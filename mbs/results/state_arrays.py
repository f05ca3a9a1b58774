"""A run object's state as named arrays, and back (the content of a checkpoint,
:mod:`mbs.results.checkpoint`).

Every object that keeps run state outside :class:`~mbs.run.model.Data` — contours, contact
kinematics, searches, contact points, contacts — names it in a class attribute
``run_state``: a tuple of attribute names. :func:`collect` turns those attributes into
arrays under ``prefix/name``; :func:`restore` puts them back into a freshly built object
of the same kind. An attribute may hold

- a numpy array: saved as is, restored in place (``current[...] = saved``: arrays that
  other arrays view — a contour's state vector and its named slices, kernel
  workspaces — stay shared), its shape and dtype checked against the fresh object's;
- a float, int or bool (numpy scalars included): a 0-d array, restored as the Python
  type;
- a tuple of numbers (a search's warm start (η, ξ)): a float array, restored as a tuple;
- None: no array, its kind "none";
- another object with its own ``run_state``: collected under ``prefix/name``.

The kind of each entry ("array", "float", "int", "bool", "tuple", "none") goes into
``kinds`` (kept in the checkpoint's JSON header), so restoring needs no code from the
file. A new piece of run state is one more name in its class's ``run_state``.

:class:`StateCopy` keeps the same state in memory, in buffers made once: a step that
is taken back (the adaptive Moreau step, :mod:`mbs.integrators.moreau`) copies it
before and puts it back after.
"""

from __future__ import annotations

import numbers

import numpy as np

SCALARS = {"float": (float, np.float64), "int": (int, np.int64), "bool": (bool, np.bool_)}


class StateMismatch(ValueError):
    """A saved state that does not fit the object it is restored into (the message names
    the entry and the mismatch)."""


def collect(obj, prefix, arrays: dict, kinds: dict) -> None:
    """Add the run state of ``obj`` (its ``run_state`` names) to ``arrays`` and ``kinds``."""
    for name in type(obj).run_state:
        put(f"{prefix}/{name}", getattr(obj, name), arrays, kinds)


def put(key, value, arrays: dict, kinds: dict) -> None:
    """Add one value (module docstring) under ``key``."""
    if value is None:
        kinds[key] = "none"
    elif hasattr(type(value), "run_state"):
        collect(value, key, arrays, kinds)
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


def restore(obj, prefix, arrays, kinds) -> None:
    """Set the ``run_state`` attributes of ``obj`` from ``arrays``; StateMismatch if an
    entry is missing or does not fit."""
    for name in type(obj).run_state:
        setattr(obj, name, take(f"{prefix}/{name}", getattr(obj, name), arrays, kinds))


def take(key, current, arrays, kinds):
    """The value saved under ``key`` for an attribute now holding ``current`` (arrays are
    written into ``current`` and returned)."""
    kind = kinds.get(key)
    if kind is None and hasattr(type(current), "run_state"):
        restore(current, key, arrays, kinds)
        return current
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


class StateCopy:
    """A copy of run state kept in memory: :meth:`save` copies it into buffers made on
    the first save (no allocation after that while shapes stay), :meth:`restore` puts it
    back — arrays written into the objects' own arrays (views of them stay valid),
    scalars, tuples and None set again, a dict (counters) copied. An attribute still
    holding the very array of the last save is copied without further checks (its
    buffer fits it).

    ``owners``: [(object, names)] — the attributes ``names`` of each object, or its
    ``run_state`` for names None; an attribute holding an object with its own
    ``run_state`` is walked as :func:`collect` walks it."""

    def __init__(self, owners):
        self._slots = []
        for obj, names in owners:
            self._add(obj, type(obj).run_state if names is None else names)
        self._kept = [None] * len(self._slots)
        self._arrays = [None] * len(self._slots)    # the array each slot held at the last save

    def _add(self, obj, names):
        for name in names:
            value = getattr(obj, name)
            if hasattr(type(value), "run_state"):
                self._add(value, type(value).run_state)
            else:
                self._slots.append((obj, name))

    def save(self) -> None:
        """Copy the state as it is now."""
        kept, arrays = self._kept, self._arrays
        for j, (obj, name) in enumerate(self._slots):
            value, array = getattr(obj, name), arrays[j]
            if array is not None and value is array:    # the array of the last save: its buffer fits
                kept[j][...] = value
                continue
            arrays[j] = None
            if isinstance(value, np.ndarray):
                buf = kept[j]
                if isinstance(buf, np.ndarray) and buf.shape == value.shape and buf.dtype == value.dtype:
                    buf[...] = value
                else:
                    kept[j] = value.copy()
                arrays[j] = value
            elif isinstance(value, dict):
                kept[j] = dict(value)
            else:
                kept[j] = value

    def restore(self) -> None:
        """Put back the state of the last :meth:`save`."""
        for (obj, name), value, array in zip(self._slots, self._kept, self._arrays):
            if array is not None:
                current = getattr(obj, name)
                if current is array:        # still the saved array: written back in place
                    current[...] = value
                    continue
            if isinstance(value, np.ndarray):
                current = getattr(obj, name)
                if isinstance(current, np.ndarray) and current.shape == value.shape and current.dtype == value.dtype:
                    current[...] = value
                else:
                    setattr(obj, name, value.copy())
            elif isinstance(value, dict):
                setattr(obj, name, dict(value))
            else:
                setattr(obj, name, value)
