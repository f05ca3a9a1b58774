"""Checked access to the tables of a scene file: each value's type, range and unit against
its :class:`~ffrmbs_app.scene_file.schema.Key`, every fault an
:class:`~ffrmbs.errors.InputFileError` naming the file, the line, the entry and the key."""

from __future__ import annotations

import math

import numpy as np

from ffrmbs.errors import ModelError, quote

from .reading import Document
from .schema import MAX_MAGNITUDE, ORTHONORMAL_TOL, REQUIRED, Key


def describe(value) -> str:
    """The TOML type and value, for messages: "a string ('heavy')"."""
    if isinstance(value, bool):
        return f"a boolean ({str(value).lower()})"
    if isinstance(value, int):
        return f"an integer ({value})"
    if isinstance(value, float):
        return f"a float ({value!r})"
    if isinstance(value, str):
        return f"a string ({quote(value, 40)})"
    if isinstance(value, list):
        return f"an array of {len(value)}"
    if isinstance(value, dict):
        return "a table"
    return f"a {type(value).__name__} ({value})"


def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def is_int(value) -> bool:
    """An integer within 64 bits (tomllib reads larger ones too)."""
    return isinstance(value, int) and not isinstance(value, bool) and -2 ** 63 <= value < 2 ** 63


def in_unit(unit: str) -> str:
    """" [unit]" for messages, or "" for none."""
    return f" [{unit}]" if unit else ""


def _too_large(key, unit, value) -> str:
    return (f"{key!r}: {float(value)!r}{in_unit(unit)} is beyond the bound |x| <= {MAX_MAGNITUDE:g} "
            "(SI units) of any number of a scene")


_OWN_DEFAULT = object()       # Table.get: take the Key's default


def run(doc: Document, keypath, label, make):
    """``make()``, with a ModelError of the API reported at ``keypath`` after ``label``."""
    try:
        return make()
    except ModelError as exc:
        doc.fail(keypath, f"{label}: {exc}")


class Table:
    """One table of the scene file with its key path, its label ("body 'beam'") and its
    schema ({key: Key}). Unknown keys are rejected when it is opened (unless ``schema``
    is None: a head table read before its kind is known). :meth:`get` reads a key as
    its schema says; the typed getters check type and range and name the key in any
    fault."""

    def __init__(self, doc: Document, data, keypath: tuple, label: str, schema: dict | None):
        self.doc, self.data, self.keypath, self.label = doc, data, tuple(keypath), label
        self.schema = schema or {}
        if not isinstance(data, dict):
            doc.fail(self.keypath, f"{label}: expected a table, got {describe(data)}")
        if schema is not None:
            self.allow(tuple(schema))

    def allow(self, allowed, why=""):
        """Fault on the first key not in ``allowed`` (``why`` says whose keys they are)."""
        for key in self.data:
            if key not in allowed:
                self.fail(key, f"unknown key {key!r}{why} (allowed: {', '.join(allowed)})")

    def fail(self, key, fault):
        self.doc.fail(self.keypath + ((key,) if key is not None else ()), f"{self.label}: {fault}")

    def has(self, key) -> bool:
        return key in self.data

    def get(self, key, default=_OWN_DEFAULT, spec: Key | None = None):
        """The value of ``key`` read as its Key in the schema (or ``spec``) says, with that
        Key's default unless ``default`` is given."""
        spec = spec or self.schema[key]
        if default is _OWN_DEFAULT:
            default = spec.default
        if spec.type == "number":
            return self.number(key, default, spec.unit, spec.low, spec.strict, spec.high)
        if spec.type == "integer":
            return self.integer(key, default, spec.low, spec.high)
        if spec.type == "boolean":
            return self.boolean(key, default)
        if spec.type == "string":
            return self.string(key, default)
        if spec.type == "choice":
            return self.choice(key, tuple(spec.choices), default)
        if spec.type == "numbers":
            return self.numbers(key, spec.size, default, spec.unit, spec.low)
        if spec.type == "matrix3":
            return self.matrix3(key, default, spec.unit)
        raise TypeError(f"key {key!r} of type {spec.type!r} is read by the builder")

    def _raw(self, key, default):
        if key in self.data:
            return True, self.data[key]
        if default is REQUIRED:
            self.fail(None, f"missing required key {key!r}")
        return False, default

    def number(self, key, default=REQUIRED, unit="", low=None, strict=False, high=None) -> float:
        """A finite number [unit] >= low (> low when ``strict``) and <= high."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not is_number(value):
            self.fail(key, f"{key!r} must be a number{in_unit(unit)}, got {describe(value)}")
        value = float(value)
        if not math.isfinite(value):
            self.fail(key, f"{key!r} must be finite, got {value!r}")
        if abs(value) > MAX_MAGNITUDE:
            self.fail(key, _too_large(key, unit, value))
        if low is not None and (value <= low if strict else value < low):
            self.fail(key, f"{key!r} must be {'>' if strict else '>='} {low:g}{in_unit(unit)}, got {value!r}")
        if high is not None and value > high:
            self.fail(key, f"{key!r} must be <= {high:g}{in_unit(unit)}, got {value!r}")
        return value

    def integer(self, key, default=REQUIRED, low=None, high=None) -> int:
        """A 64-bit integer in low..high."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not is_int(value):
            self.fail(key, f"{key!r} must be an integer (64 bits), got {describe(value)}")
        if (low is not None and value < low) or (high is not None and value > high):
            bounds = f"in {low}..{high}" if high is not None else f">= {low}"
            self.fail(key, f"{key!r} must be {bounds}, got {value}")
        return value

    def boolean(self, key, default=REQUIRED) -> bool:
        given, value = self._raw(key, default)
        if given and not isinstance(value, bool):
            self.fail(key, f"{key!r} must be true or false, got {describe(value)}")
        return value

    def string(self, key, default=REQUIRED) -> str:
        given, value = self._raw(key, default)
        if given and not isinstance(value, str):
            self.fail(key, f"{key!r} must be a string, got {describe(value)}")
        return value

    def choice(self, key, options, default=REQUIRED) -> str:
        given, value = self._raw(key, default)
        if given and (not isinstance(value, str) or value not in options):
            self.fail(key, f"{key!r} must be one of {', '.join(repr(o) for o in options)}, "
                           f"got {describe(value)}")
        return value

    def numbers(self, key, n=None, default=REQUIRED, unit="", low=None) -> np.ndarray | None:
        """An array of n finite numbers (any length >= 1 if n is None), each >= low."""
        given, value = self._raw(key, default)
        if not given:
            return None if value is None else np.array(value, dtype=float)
        size = f"{n} numbers" if n else "numbers"
        if not isinstance(value, list) or (n is not None and len(value) != n) or not value:
            self.fail(key, f"{key!r} must be an array of {size}{in_unit(unit)}, got {describe(value)}"
                      + (f": {value!r}" if isinstance(value, list) and len(repr(value)) < 80 else ""))
        bad = [i for i, v in enumerate(value) if not is_number(v)]
        if bad:
            self.fail(key, f"{key!r} must be an array of {size}{in_unit(unit)}: entry {bad[0] + 1} is "
                           f"{describe(value[bad[0]])}")
        array = np.array(value, dtype=float)
        if not np.isfinite(array).all():
            self.fail(key, f"{key!r} must hold finite numbers, got {quote(value, 60)}")
        if (np.abs(array) > MAX_MAGNITUDE).any():
            self.fail(key, _too_large(key, unit, array[np.abs(array) > MAX_MAGNITUDE][0]))
        if low is not None and (array < low).any():
            self.fail(key, f"{key!r} must hold numbers >= {low:g}{in_unit(unit)}, got {quote(value, 60)}")
        return array

    def rows(self, key, n_rows, what, default=REQUIRED) -> np.ndarray | None:
        """An (n_rows, 3) array given as a list of rows of three finite numbers (any
        number of rows >= 1 if n_rows is None). ``what`` describes it in a fault."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not (isinstance(value, list) and value and (n_rows is None or len(value) == n_rows) and all(
                isinstance(row, list) and len(row) == 3 and all(is_number(v) for v in row) for row in value)):
            self.fail(key, f"{key!r} must be {what}, got {describe(value)}")
        array = np.array(value, dtype=float)
        if not np.isfinite(array).all():
            self.fail(key, f"{key!r} must hold finite numbers")
        if (np.abs(array) > MAX_MAGNITUDE).any():
            self.fail(key, _too_large(key, "", array[np.abs(array) > MAX_MAGNITUDE][0]))
        return array

    def matrix3(self, key, default=REQUIRED, unit="") -> np.ndarray | None:
        """A 3 x 3 matrix given as a list of three rows of three numbers."""
        return self.rows(key, 3, f"a 3 x 3 matrix{in_unit(unit)} (three rows of three numbers)", default)

    def rotation(self, key) -> np.ndarray | None:
        """A rotation matrix (orthonormal, det +1 within ORTHONORMAL_TOL) or None."""
        A = self.matrix3(key, None)
        if A is not None and (np.abs(A.T @ A - np.eye(3)).max() > ORTHONORMAL_TOL or np.linalg.det(A) < 0):
            self.fail(key, f"{key!r} must be a rotation matrix (orthonormal rows, determinant +1)")
        return A

    def indices(self, key, n_nodes, default=REQUIRED) -> np.ndarray:
        """A non-empty list of 0-based node indices < n_nodes."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not (isinstance(value, list) and value and all(is_int(v) for v in value)):
            self.fail(key, f"{key!r} must be a non-empty array of 0-based node indices, got {describe(value)}")
        bad = [v for v in value if not 0 <= v < n_nodes]
        if bad:
            self.fail(key, f"{key!r}: node {bad[0]} outside 0..{n_nodes - 1}")
        return np.array(value, dtype=np.int64)

    def table(self, key, label, schema, default=REQUIRED):
        """The sub-table ``key`` as a Table (``schema`` as for the constructor)."""
        given, value = self._raw(key, default)
        if not given:
            return value
        return Table(self.doc, value, self.keypath + (key,), f"{self.label}: {label}", schema)

    def model(self, key, make):
        """``make()``, with a ModelError of the API reported at ``key``."""
        return run(self.doc, self.keypath + (key,), self.label, make)
