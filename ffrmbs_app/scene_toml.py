"""Scene files: one simulation job written in TOML.

``read_scene(path)`` reads a scene file and returns a :class:`ffrmbs_app.scene.Scene`:
the :class:`mbs.System` with its initial state set, and how to integrate it and what
to record. ``ffrmbs_app.scene.load_scene`` calls it for ``.toml`` files. Every entry maps
onto the Python API (:mod:`mbs`, :mod:`contours`, :mod:`contact`). The physics is
not implemented here. SI units throughout: m, kg, s, N, rad.

Example: the thesis's point mass dropped on the clamped beam (Sec. 5.2, setup A;
``examples/scenes/point_mass_beam.toml``)::

    [scene]
    name = "point_mass_beam"
    t_end = 0.1                       # [s]
    dt = 1e-5                         # [s]
    integrator = "moreau"
    n_out = 1001

    [scene.options]                   # passed to System.simulate
    theta = 0.5
    trace = true

    [[body]]
    name = "beam"
    kind = "flexible"
    source = "builtin:point_mass_beam"
    modes = 20
    frame = "fixed"

    [[body]]
    name = "point mass"
    kind = "point_mass"
    mass = 0.5                        # [kg]
    position = [0.235, 0.052, 0.025]  # [m]
    velocity = [0.0, -0.2, 0.0]       # [m/s]

    [[contact]]
    name = "impact"
    contour1 = { kind = "point", body = "point mass" }
    contour2 = { kind = "2s", body = "beam", nodes = "y1" }
    law = "impact"
    e = 0.0

    [outputs]
    y = { body = "point mass", quantity = "position", component = "y" }
    vy = { body = "point mass", quantity = "velocity", component = "y" }
    node19 = { body = "beam", at = [0.25, 0.05, 0.025] }

Reference
=========

Top level: the tables ``[scene]`` (required) and ``[outputs]``, and the arrays of
tables ``[[body]]`` (at least one), ``[[spring]]``, ``[[joint]]``, ``[[load]]``,
``[[contact]]``. Bodies are added to the System in file order, then springs, joints,
loads and contacts. Any other key is an error. Keys marked *req.* are required. The
other keys take the default shown.

``[scene]``
    ``name`` (the file's stem): names the result file and its companions in the output
    directory, so it is a plain file stem: 1 to 100 of the characters A-Z a-z 0-9 . _ -,
    not starting with ".". ``description`` (""): one line.
    ``t_end`` *req.* [s] > 0. ``dt`` *req.* [s] > 0: the step, or the largest step
    for "moreau-adaptive". ``integrator`` ("moreau"): one of "moreau",
    "moreau-adaptive", "generalized-alpha", "rk4". ``n_out`` (101) >= 2: output
    samples, equally spaced on [0, t_end]. ``energies`` (true): record the kinetic
    and potential energy. ``plan`` (true) and ``tolerance`` [m] > 0 (the planner's
    default): see :mod:`mbs.plan`. ``gravity`` ([0, 0, 0]) [m/s²].

``[scene.options]``
    The keyword options of the chosen integrator (see ``System.simulate``):

    - moreau: ``theta``, ``solver`` ("gauss-seidel", "jacobi" or "newton"), ``tol``,
      ``max_iter``, ``trace``, ``penetration_bound`` [m];
    - moreau-adaptive: the same, plus ``atol`` [m], ``rtol``, ``dt_min`` [s] and
      ``gap_tol`` [m];
    - generalized-alpha: ``rho_inf``, ``tol``, ``max_iter``;
    - rk4: ``baumgarte`` ([a, b] [1/s]), ``project``, ``projection_tol`` and
      ``projection_iter``.

    The type of each option is that of its default. The integrator checks the ranges
    while the file is read.

``[[body]]``: ``name`` *req.* (unique, not "ground"). ``kind`` *req.*:

- "flexible": an FFR body (:class:`mbs.FlexibleBodyFFR`).
  ``source`` *req.* is a body directory (the thesis's text files, or ``body.h5``) or
  an ``.h5``/``.hdf5`` file. A relative path is taken from the scene file's
  directory. ``"builtin:point_mass_beam"`` and ``"builtin:sliding_ball"`` are the
  cached thesis beams of :mod:`ffrmbs_app.scenes`.
  ``units`` ("si"): the unit system of text files (``"si-mm"``).
  ``modes``: a number n (the first n), a list of 0-based mode indices, or "all".
  Omitted, the body keeps all modes and the planner may drop some.
  ``frame`` ("free"): "free" or "fixed". A fixed frame stays at ``position`` and
  ``orientation``.
  ``rotation`` ("quaternion"): "quaternion" or "cardan" (free frames only).
  ``position`` ([0, 0, 0]): the frame origin R [m].
  ``orientation`` (identity): the frame orientation A, a 3 x 3 rotation matrix given
  as a list of rows.
  ``velocity`` [m/s] and ``angular_velocity`` [rad/s] (inertial components, both
  ([0, 0, 0])): the frame's initial velocities (free frames only).
  ``q_f`` [-] and ``modal_velocities`` [1/s] (zeros, one value per selected mode):
  the initial elastic coordinates and their rates.
  ``rayleigh`` ([α [1/s], β [s]]) and ``modal_damping`` (ζ, one value or one per
  mode): the damping. Both are off by default.
- "rigid": :class:`mbs.RigidBody`. ``mass`` *req.* [kg] > 0. ``inertia`` *req.*
  [kg m²] about the centre of mass in body axes: a 3 x 3 matrix, or 3 principal
  values. ``com`` ([0, 0, 0]) [m] in the body frame. ``rotation``, ``position``,
  ``orientation``, ``velocity`` and ``angular_velocity`` as for a free flexible body.
- "point_mass": :class:`mbs.PointMass`. ``mass`` *req.* [kg] > 0. ``position`` and
  ``velocity`` (both [0, 0, 0]) [m], [m/s].

Frames. Links, loads, contours and outputs name a point by ``body`` plus at most one of:

- ``node = j``: the 0-based FE node of a flexible body. It follows the deformation.
- ``at = [x, y, z]``: the node at that undeformed body-frame position [m], found
  within 1e-9 m.
- ``point = [x, y, z]``: a point fixed to the body frame [m]. It is an offset for a
  point mass, and an inertial position for ``body = "ground"``.

With none of these the point is the body frame's origin, or the point mass itself.
``body = "ground"`` is the inertial frame.

``[[spring]]`` (:class:`mbs.SpringDamper`): ``frame1`` and ``frame2`` *req.*, each a
frame table (``{ body = ..., node = ... }``). ``stiffness`` *req.* [N/m] >= 0.
``damping`` (0) [N s/m] >= 0. ``free_length`` *req.* [m] >= 0.

``[[joint]]`` (:class:`mbs.Joint`): ``kind`` *req.*: "fixed", "spherical",
"revolute" or "prismatic". ``frame1`` and ``frame2`` *req.*: frame tables. ``axis``
[-] in frame1's axes: required for revolute and prismatic joints, refused for the
others.

``[[load]]``: ``kind`` *req.*:

- "force" (:class:`mbs.Force`): a frame (``body`` *req.* and ``node``, ``at`` or
  ``point``), ``force`` *req.* [N], ``frame_fixed`` (false: inertial components;
  true: the frame's axes).
- "torque" (:class:`mbs.Torque`): a frame as for "force", ``torque`` *req.* [N m],
  ``frame_fixed`` (false).
- "distributed" (:class:`mbs.DistributedForce`): ``body`` *req.* (a flexible body),
  ``nodes`` *req.*: a node-group name or a list of node indices. ``weights``:
  equal by default, and they must sum to 1. ``force`` *req.* [N]: the resultant.
  ``frame_fixed`` (true).
- "nodal" (:class:`mbs.NodalForces`): ``body`` *req.* (flexible) and ``file`` *req.*,
  a force file (report Appendix A, :func:`mbs.read_force_file`) relative to the
  scene file. ``blocked``: a node group or a list of nodes whose three DOFs the file
  leaves out. ``frame_fixed`` (true).

A ``force`` or ``torque`` is a constant ``[x, y, z]``, or a table
``{ times = [t0, t1, ...], values = [[x, y, z], ...], kind = "step", hold_first = false }``
(:class:`mbs.Tabulated`). ``kind`` is "step" (report eq. 9) or "linear".
Gravity is ``[scene] gravity``.

``[[contact]]`` (:class:`contact.Contact`). ``name`` ("contact <i>", unique).
``contour1`` *req.*: ``{ kind = "point" | "sphere", <frame>, radius }``.
``contour2`` *req.* is one of:

- ``{ kind = "2s", body, nodes, extra_rows = 0, degree = 3, closed = false,
  method = "chord", outward }``: :class:`contours.Contour2sNeutralFFR` on a flexible
  body. ``nodes`` is a node-group name (a planar structured patch), or the node
  matrix O as a list of rows. ``degree`` and ``closed`` take one value or a pair
  (η, ξ). ``outward`` is +1 or -1. Omitted, it is found from the body.
- ``{ kind = "1s" | "band" | "cylinder", body, start, direction, nodes, normal,
  degree = 3, closed = false, method = "chord", width, offset = 0, radius }``: a
  :class:`contours.Contour1sNeutralFFR`. It runs through the nodes on the line
  through ``start`` [m] along ``direction`` (within ``nodes``, a group or a list,
  if given). Without ``start`` and ``direction``, ``nodes`` is the ordered list of
  nodes. ``normal`` *req.* is the reference normal in the body frame. "band" (a
  :class:`contours.FlexibleBand`) takes ``width`` *req.* [m] and ``offset`` [m].
  "cylinder" (a :class:`contours.FlexibleCylinder`) takes ``radius`` *req.* [m].
- ``{ kind = "plane", <frame>, normal = [0, 0, 1], size = 1 }``: a
  :class:`contours.PlaneContour` through the frame's point, with that normal in
  the frame's axes. The default frame is the ground origin.
- ``{ kind = "sphere", <frame>, radius }``: a :class:`contours.SphereContour`.

``law`` *req.* is one of:

- "impact": :class:`contact.UnilateralNewtonImpact`, with ``e`` (0).
- "coulomb": :class:`contact.UnilateralCoulombContact`, with ``e`` (0), ``mu``
  *req.* and ``e_T`` (0).
- "penalty": :class:`contact.LinearRegularizedUnilateralConstraint`, with ``k``
  *req.* [N/m] and ``d`` (0) [N s/m]. Optional friction
  (:class:`contact.RegularizedCoulombFriction`) takes ``mu`` and ``v_eps`` [m/s].
- "bilateral": a point kept on a 1s curve (:class:`contact.CurveConstraint`).

The kinematics follow from the contour kinds: point or sphere against 2s, band,
cylinder, 1s, plane or sphere. ``margin`` [m] >= 0 sets the broad phase's margin.
It can also be "auto" (the default) or "off".

``[outputs]``: ``name = { body, <frame>, quantity = "position", component }`` per
output. The quantities are:

- "position" [m]: of the frame.
- "velocity" [m/s]: of the frame.
- "displacement" [m]: the elastic displacement Φ q_f of a flexible body's node, in
  body-frame components.
- "angular_velocity" [rad/s]: of the body.
- "q_f" [-]: the body's modal coordinates.

``component`` ("x", "y" or "z") picks one component of a 3-vector. The unit of the
quantity (q_f: "SI", its unit depends on the modes' normalization) is written with the
output into the result file and onto plot axes. Contacts are recorded by the result file
itself.

Errors
======
Any fault raises :class:`ffrmbs.errors.InputFileError` naming the scene file, the
line when it can be found, the entry, and the key. Faults include:

- a syntax error;
- an unknown key (the allowed ones are listed);
- a missing key;
- a wrong type;
- a value out of range (and any number beyond |x| <= 1e12, SI units);
- an unknown enum value (the allowed values are listed);
- an unknown body;
- a node, group or mode the body does not have;
- a body file that is not found (both files are named).

A fault inside a body or force file names that file and its line, and says which
scene entry read it. The whole file is checked before the System is built. An error
therefore leaves nothing half-built.
"""

from __future__ import annotations

import inspect
import json
import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:   # pragma: no cover - Python 3.10
    import tomli as tomllib

from ffrmbs.errors import FfrmbsError, InputFileError, ModelError, os_reason, quote
from ffrmbs_app.scene import Scene, name_fault
from preprocess.inputfiles import regular_file

GROUND = "ground"
BUILTIN = "builtin:"
INTEGRATORS = ("moreau", "moreau-adaptive", "generalized-alpha", "rk4")
BODY_KINDS = ("flexible", "rigid", "point_mass")
JOINT_KINDS = ("fixed", "spherical", "revolute", "prismatic")
LOAD_KINDS = ("force", "torque", "distributed", "nodal")
CONTOUR1_KINDS = ("point", "sphere")
CONTOUR2_KINDS = ("2s", "1s", "band", "cylinder", "plane", "sphere")
LAWS = ("impact", "coulomb", "penalty", "bilateral")
QUANTITIES = ("position", "velocity", "displacement", "angular_velocity", "q_f")
QUANTITY_UNITS = {"position": "m", "velocity": "m/s", "displacement": "m", "angular_velocity": "rad/s"}
COMPONENTS = ("x", "y", "z")
ORTHONORMAL_TOL = 1e-9      # max |AᵀA − 1| of an orientation matrix
MAX_MAGNITUDE = 1e12        # |x| of any number of a scene [SI units]: larger ones are no physical input
TOP_LEVEL = ("scene", "body", "spring", "joint", "load", "contact", "outputs")
FRAME_KEYS = ("body", "node", "at", "point")

_REQUIRED = object()


# --- locating keys in the text -----------------------------------------------------------

_KEY = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')"""
_DOTTED = rf"{_KEY}(?:[ \t]*\.[ \t]*{_KEY})*"
_ARRAY_HEADER = re.compile(rf"[ \t]*\[\[[ \t]*({_DOTTED})[ \t]*\]\]")
_TABLE_HEADER = re.compile(rf"[ \t]*\[[ \t]*({_DOTTED})[ \t]*\]")
_KEY_VALUE = re.compile(rf"[ \t]*({_DOTTED})[ \t]*=[ \t]*(.*)")


def _key_parts(dotted: str) -> tuple:
    parts = []
    for part in re.findall(_KEY, dotted):
        if part.startswith('"'):
            try:
                part = json.loads(part)
            except ValueError:
                part = part[1:-1]
        elif part.startswith("'"):
            part = part[1:-1]
        parts.append(part)
    return tuple(parts)


class _LineIndex:
    """1-based line numbers of the tables and keys of a TOML text. The keys are paths
    such as ("body", 0, "modes"), where array-of-tables entries are counted from 0.
    This is a line scanner, not a parser. It runs only on text that tomllib accepted.
    It knows table headers and ``key = value`` lines. A key inside an inline table or
    a multi-line array takes the line of its enclosing key."""

    def __init__(self, text: str):
        self.lines: dict = {}
        arrays: dict = {}           # path of an array of tables -> index of its last entry
        current: tuple = ()
        closing = None              # delimiter of an open multi-line string
        for lineno, line in enumerate(text.split("\n"), start=1):     # tomllib counts "\n" only
            if closing is not None:
                if closing in line:
                    closing = None
                continue
            header = _ARRAY_HEADER.match(line)
            if header:
                path = self._resolve(_key_parts(header[1]), arrays)
                self.lines.setdefault(path, lineno)
                arrays[path] = arrays.get(path, -1) + 1
                current = path + (arrays[path],)
                self.lines.setdefault(current, lineno)
                continue
            header = _TABLE_HEADER.match(line)
            if header:
                current = self._resolve(_key_parts(header[1]), arrays)
                self.lines.setdefault(current, lineno)
                continue
            pair = _KEY_VALUE.match(line)
            if pair:
                self.lines.setdefault(current + _key_parts(pair[1]), lineno)
                for delimiter in ('"""', "'''"):
                    rest = pair[2]
                    if rest.startswith(delimiter) and rest.count(delimiter) == 1:
                        closing = delimiter

    @staticmethod
    def _resolve(parts, arrays) -> tuple:
        path: tuple = ()
        for i, part in enumerate(parts):
            path += (part,)
            if path in arrays and i < len(parts) - 1:
                path += (arrays[path],)
        return path

    def find(self, path) -> int | None:
        """The line of ``path``, or of its longest prefix that has one (None if none)."""
        path = tuple(path)
        for k in range(len(path), 0, -1):
            if path[:k] in self.lines:
                return self.lines[path[:k]]
        return None


# --- checked access to tables ---------------------------------------------------------------

def _describe(value) -> str:
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


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_int(value) -> bool:
    """An integer within 64 bits (tomllib reads larger ones too)."""
    return isinstance(value, int) and not isinstance(value, bool) and -2 ** 63 <= value < 2 ** 63


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def _too_large(key, unit, value) -> str:
    return (f"{key!r}: {float(value)!r}{_unit(unit)} is beyond the bound |x| <= {MAX_MAGNITUDE:g} "
            "(SI units) of any number of a scene")


class _Reader:
    """Faults of one scene file: InputFileError with the line of a key path."""

    def __init__(self, path: Path, text: str):
        self.path = path
        self.index = _LineIndex(text)

    def fail(self, keypath, fault):
        raise InputFileError(self.path, self.index.find(keypath), fault)

    def run(self, keypath, label, make):
        """``make()``, with a ModelError of the API reported at ``keypath`` after ``label``."""
        try:
            return make()
        except ModelError as exc:
            self.fail(keypath, f"{label}: {exc}")


class _Table:
    """One table of the scene file with its key path and label ("body 'beam'").
    It rejects unknown keys when it is opened. Its getters check the type and range
    and name the key in any fault."""

    def __init__(self, reader: _Reader, data, keypath: tuple, label: str, allowed):
        self.r, self.data, self.keypath, self.label = reader, data, tuple(keypath), label
        if not isinstance(data, dict):
            reader.fail(self.keypath, f"{label}: expected a table, got {_describe(data)}")
        self.allow(allowed)

    def allow(self, allowed, why=""):
        """Fault on the first key not in ``allowed`` (``why`` says whose keys they are)."""
        for key in self.data:
            if key not in allowed:
                self.fail(key, f"unknown key {key!r}{why} (allowed: {', '.join(allowed)})")

    def fail(self, key, fault):
        self.r.fail(self.keypath + ((key,) if key is not None else ()), f"{self.label}: {fault}")

    def has(self, key) -> bool:
        return key in self.data

    def _raw(self, key, default):
        if key in self.data:
            return True, self.data[key]
        if default is _REQUIRED:
            self.fail(None, f"missing required key {key!r}")
        return False, default

    def number(self, key, default=_REQUIRED, unit="", low=None, strict=False, high=None) -> float:
        """A finite number [unit] >= low (> low when ``strict``) and <= high."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not _is_number(value):
            self.fail(key, f"{key!r} must be a number{_unit(unit)}, got {_describe(value)}")
        value = float(value)
        if not math.isfinite(value):
            self.fail(key, f"{key!r} must be finite, got {value!r}")
        if abs(value) > MAX_MAGNITUDE:
            self.fail(key, _too_large(key, unit, value))
        if low is not None and (value <= low if strict else value < low):
            self.fail(key, f"{key!r} must be {'>' if strict else '>='} {low:g}{_unit(unit)}, got {value!r}")
        if high is not None and value > high:
            self.fail(key, f"{key!r} must be <= {high:g}{_unit(unit)}, got {value!r}")
        return value

    def integer(self, key, default=_REQUIRED, low=None, high=None) -> int:
        given, value = self._raw(key, default)
        if not given:
            return value
        if not _is_int(value):
            self.fail(key, f"{key!r} must be an integer (64 bits), got {_describe(value)}")
        if (low is not None and value < low) or (high is not None and value > high):
            bounds = f"in {low}..{high}" if high is not None else f">= {low}"
            self.fail(key, f"{key!r} must be {bounds}, got {value}")
        return value

    def boolean(self, key, default=_REQUIRED) -> bool:
        given, value = self._raw(key, default)
        if given and not isinstance(value, bool):
            self.fail(key, f"{key!r} must be true or false, got {_describe(value)}")
        return value

    def string(self, key, default=_REQUIRED) -> str:
        given, value = self._raw(key, default)
        if given and not isinstance(value, str):
            self.fail(key, f"{key!r} must be a string, got {_describe(value)}")
        return value

    def choice(self, key, options, default=_REQUIRED) -> str:
        given, value = self._raw(key, default)
        if given and (not isinstance(value, str) or value not in options):
            self.fail(key, f"{key!r} must be one of {', '.join(repr(o) for o in options)}, "
                           f"got {_describe(value)}")
        return value

    def numbers(self, key, n=None, default=_REQUIRED, unit="", low=None) -> np.ndarray | None:
        """An array of n finite numbers (any length >= 1 if n is None), each >= low."""
        given, value = self._raw(key, default)
        if not given:
            return None if value is None else np.array(value, dtype=float)
        size = f"{n} numbers" if n else "numbers"
        if not isinstance(value, list) or (n is not None and len(value) != n) or not value:
            self.fail(key, f"{key!r} must be an array of {size}{_unit(unit)}, got {_describe(value)}"
                      + (f": {value!r}" if isinstance(value, list) and len(repr(value)) < 80 else ""))
        bad = [i for i, v in enumerate(value) if not _is_number(v)]
        if bad:
            self.fail(key, f"{key!r} must be an array of {size}{_unit(unit)}: entry {bad[0] + 1} is "
                           f"{_describe(value[bad[0]])}")
        array = np.array(value, dtype=float)
        if not np.isfinite(array).all():
            self.fail(key, f"{key!r} must hold finite numbers, got {quote(value, 60)}")
        if (np.abs(array) > MAX_MAGNITUDE).any():
            self.fail(key, _too_large(key, unit, array[np.abs(array) > MAX_MAGNITUDE][0]))
        if low is not None and (array < low).any():
            self.fail(key, f"{key!r} must hold numbers >= {low:g}{_unit(unit)}, got {quote(value, 60)}")
        return array

    def rows(self, key, n_rows, what, default=_REQUIRED) -> np.ndarray | None:
        """An (n_rows, 3) array given as a list of rows of three finite numbers (any
        number of rows >= 1 if n_rows is None). ``what`` describes it in a fault."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not (isinstance(value, list) and value and (n_rows is None or len(value) == n_rows) and all(
                isinstance(row, list) and len(row) == 3 and all(_is_number(v) for v in row) for row in value)):
            self.fail(key, f"{key!r} must be {what}, got {_describe(value)}")
        array = np.array(value, dtype=float)
        if not np.isfinite(array).all():
            self.fail(key, f"{key!r} must hold finite numbers")
        if (np.abs(array) > MAX_MAGNITUDE).any():
            self.fail(key, _too_large(key, "", array[np.abs(array) > MAX_MAGNITUDE][0]))
        return array

    def matrix3(self, key, default=_REQUIRED, unit="") -> np.ndarray | None:
        """A 3 x 3 matrix given as a list of three rows of three numbers."""
        return self.rows(key, 3, f"a 3 x 3 matrix{_unit(unit)} (three rows of three numbers)", default)

    def indices(self, key, n_nodes, default=_REQUIRED) -> np.ndarray:
        """A non-empty list of 0-based node indices < n_nodes."""
        given, value = self._raw(key, default)
        if not given:
            return value
        if not (isinstance(value, list) and value and all(_is_int(v) for v in value)):
            self.fail(key, f"{key!r} must be a non-empty array of 0-based node indices, got {_describe(value)}")
        bad = [v for v in value if not 0 <= v < n_nodes]
        if bad:
            self.fail(key, f"{key!r}: node {bad[0]} outside 0..{n_nodes - 1}")
        return np.array(value, dtype=np.int64)

    def table(self, key, label, allowed, default=_REQUIRED):
        given, value = self._raw(key, default)
        if not given:
            return value
        return _Table(self.r, value, self.keypath + (key,), f"{self.label}: {label}", allowed)

    def model(self, key, make):
        """``make()``, with a ModelError of the API reported at ``key``."""
        return self.r.run(self.keypath + (key,), self.label, make)


# --- validated entries -----------------------------------------------------------------------

@dataclass
class _Body:
    """A validated [[body]] entry. ``make()`` builds the body."""

    name: str
    kind: str
    keypath: tuple
    make: object
    data: object = None         # BodyData of a flexible body


@dataclass(eq=False)
class _FrameRef:
    """A validated frame reference (see "Frames" in the module docstring)."""

    body: str
    node: int | None = None
    point: np.ndarray | None = None

    def same(self, other) -> bool:
        """Whether both name the same point."""
        return (self.body, self.node) == (other.body, other.node) and (
            (self.point is None and other.point is None)
            or (self.point is not None and other.point is not None and np.array_equal(self.point, other.point)))

    def resolve(self, env, orientation=None, name=None):
        """The :class:`mbs.Frame` in the built System ``env``."""
        from mbs import PointMass, ground_frame
        from mbs.body import Frame

        point = np.zeros(3) if self.point is None else self.point
        if self.body == GROUND:
            return ground_frame(point, orientation, name or GROUND)
        body = env.bodies[self.body]
        if self.node is not None:
            return body.node(self.node, orientation)
        if isinstance(body, PointMass):
            if self.point is None and orientation is None:
                return body.point
            return Frame(body, point, orientation=orientation, name=name or body.name)
        if self.point is None and orientation is None:
            return body.origin
        return body.frame_at(point, orientation, name)


@dataclass
class _Env:
    """The System being built and its bodies by name."""

    system: object
    bodies: dict = field(default_factory=dict)


def _orientation(tab: _Table, key) -> np.ndarray | None:
    """A rotation matrix (orthonormal, det +1 within ORTHONORMAL_TOL) or None."""
    A = tab.matrix3(key, None)
    if A is not None and (np.abs(A.T @ A - np.eye(3)).max() > ORTHONORMAL_TOL or np.linalg.det(A) < 0):
        tab.fail(key, f"{key!r} must be a rotation matrix (orthonormal rows, determinant +1)")
    return A


def _axes_with_normal(normal) -> np.ndarray:
    """A rotation matrix whose third column is the unit ``normal`` (the first column is
    perpendicular to it, built from the coordinate axis least aligned with it)."""
    z = normal / np.linalg.norm(normal)
    x = np.cross(np.eye(3)[int(np.argmin(np.abs(z)))], z)
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))


class _SceneReader:
    """Pass 1 checks the whole file and collects one builder per entry. Pass 2
    (:meth:`build`) runs the builders on a new System."""

    def __init__(self, path: Path, text: str, doc: dict):
        self.path, self.doc = path, doc
        self.r = _Reader(path, text)
        _Table(self.r, doc, (), "scene file", TOP_LEVEL)          # rejects unknown top-level keys
        self.bodies: dict[str, _Body] = {}
        self.steps: list = []               # (keypath, label, build(env)) after the bodies
        self.outputs: dict = {}             # name -> (keypath, label, make(env))
        self.units: dict = {}               # name -> unit of the output's quantity
        self.inputs: dict = {"scene file": str(path)}
        self._sources: dict = {}            # resolved source -> BodyData (read once)

    # --- entry lists ---------------------------------------------------------------------
    def _entries(self, key, what):
        """The tables of the array of tables ``key`` as (index, data)."""
        value = self.doc.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            self.r.fail((key,), f"'{key}' must be an array of tables: write each {what} as [[{key}]]")
        return list(enumerate(value))

    # --- scene settings ------------------------------------------------------------------------
    def settings(self) -> dict:
        if "scene" not in self.doc:
            self.r.fail((), "missing required table 'scene' (write [scene] with t_end and dt)")
        if not isinstance(self.doc["scene"], dict):
            self.r.fail(("scene",), f"'scene' must be a table ([scene] with t_end and dt), "
                                    f"got {_describe(self.doc['scene'])}")
        s = _Table(self.r, self.doc["scene"], ("scene",), "[scene]",
                   ("name", "description", "t_end", "dt", "integrator", "n_out", "energies", "plan",
                    "tolerance", "gravity", "options"))
        name = s.string("name", self.path.stem)
        fault = name_fault(name)
        if fault:
            s.fail("name" if s.has("name") else None,
                   fault + ("" if s.has("name") else " (taken from the file name; set 'name')"))
        out = {"name": name, "description": s.string("description", ""),
               "t_end": s.number("t_end", unit="s", low=0.0, strict=True),
               "dt": s.number("dt", unit="s", low=0.0, strict=True),
               "integrator": s.choice("integrator", INTEGRATORS, "moreau"),
               "n_out": s.integer("n_out", 101, low=2), "energies": s.boolean("energies", True),
               "plan": s.boolean("plan", True),
               "tolerance": s.number("tolerance", None, unit="m", low=0.0, strict=True),
               "gravity": s.numbers("gravity", 3, (0.0, 0.0, 0.0), unit="m/s²")}
        out["options"] = self._options(s, out["integrator"])
        return out

    def _options(self, s: _Table, integrator: str) -> dict:
        from contact.solver import METHODS
        from mbs import System
        from mbs.integrators import MoreauTimeStepping, integrator_class

        cls = integrator_class(integrator)
        params = dict(inspect.signature(cls.__init__).parameters)
        if integrator == "moreau-adaptive":
            params.update(inspect.signature(MoreauTimeStepping.__init__).parameters)
        params = {k: p for k, p in params.items()
                  if k not in ("self", "system") and p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
        o = s.table("options", f"options of integrator {integrator!r}", tuple(params), {})
        if not isinstance(o, _Table):
            return {}
        options = {}
        for key in o.data:
            default = params[key].default
            if isinstance(default, bool):
                options[key] = o.boolean(key)
            elif isinstance(default, int):
                options[key] = o.integer(key, low=0)
            elif isinstance(default, str):
                options[key] = o.choice(key, METHODS) if key == "solver" else o.string(key)
            elif isinstance(default, (tuple, list)):
                options[key] = tuple(o.numbers(key, len(default)))
            else:                      # float or None (an optional number)
                options[key] = o.number(key)
        try:                            # the integrator checks its ranges
            cls(System(), **options)
        except ModelError as exc:
            named = [key for key in options if re.search(rf"\b{re.escape(key)}\b", str(exc))]
            o.fail(named[0] if named else None, str(exc))
        return options

    # --- bodies -----------------------------------------------------------------------------------
    def read_bodies(self):
        entries = self._entries("body", "body")
        if not entries:
            self.r.fail(("body",), "no bodies: 'body' needs at least one [[body]] table")
        for i, data in entries:
            keypath = ("body", i)
            label = f"body #{i + 1}"
            if isinstance(data.get("name"), str):
                label = f"body {data['name']!r}"
            head = _Table(self.r, data, keypath, label, tuple(data))     # no key check yet
            name = head.string("name")
            if name == GROUND:
                head.fail("name", f"the name {GROUND!r} is reserved for the inertial frame")
            if name in self.bodies:
                head.fail("name", f"a second body named {name!r} (body names must be unique)")
            kind = head.choice("kind", BODY_KINDS)
            body = {"flexible": self._flexible, "rigid": self._rigid, "point_mass": self._point_mass}[kind](
                data, keypath, label, name)
            self.bodies[name] = body

    def _flexible(self, data, keypath, label, name) -> _Body:
        from mbs.flexible_body import select_modes
        from mbs.parametrization import PARAMETRIZATIONS

        t = _Table(self.r, data, keypath, label,
                   ("name", "kind", "source", "units", "modes", "frame", "rotation", "position", "orientation",
                    "velocity", "angular_velocity", "q_f", "modal_velocities", "rayleigh", "modal_damping"))
        body_data = self._body_data(t, name)
        modes = t.data.get("modes")
        if modes is None:
            selection = None
        elif modes == "all":
            selection = body_data.n_modes
        elif _is_int(modes):
            selection = modes
        elif isinstance(modes, list) and all(_is_int(m) for m in modes):
            selection = list(modes)
        else:
            t.fail("modes", f"'modes' must be a number of modes, a list of 0-based mode indices or \"all\", "
                            f"got {_describe(modes)}")
        n_modes = len(t.model("modes", lambda: select_modes(body_data.n_modes, selection)))
        frame = t.choice("frame", ("free", "fixed"), "free")
        rotation = t.choice("rotation", tuple(sorted(PARAMETRIZATIONS)), "quaternion")
        if frame == "fixed":
            for key in ("velocity", "angular_velocity", "rotation"):
                if t.has(key):
                    t.fail(key, f"{key!r} applies to a free frame only (this body has frame = \"fixed\")")
        R = t.numbers("position", 3, None, unit="m")
        A = _orientation(t, "orientation")
        v = t.numbers("velocity", 3, None, unit="m/s")
        w = t.numbers("angular_velocity", 3, None, unit="rad/s")
        q_f = self._modal(t, "q_f", n_modes, "")
        qd_f = self._modal(t, "modal_velocities", n_modes, "1/s")
        rayleigh = t.numbers("rayleigh", 2, None, low=0.0)
        zeta = None
        if t.has("modal_damping"):
            value = t.data["modal_damping"]
            zeta = (t.number("modal_damping", low=0.0) if not isinstance(value, list)
                    else self._modal(t, "modal_damping", n_modes, "", low=0.0))

        def make():
            from mbs import FlexibleBodyFFR, PrescribedFrameMotion

            motion = "free"
            if frame == "fixed":
                motion = PrescribedFrameMotion.fixed(*(() if R is None and A is None else
                                                       ((0.0, 0.0, 0.0) if R is None else R, A)))
            body = FlexibleBodyFFR(body_data, modes=selection, frame=motion, rotation=rotation,
                                   rayleigh=None if rayleigh is None else tuple(rayleigh), modal_damping=zeta,
                                   name=name)
            if frame == "free":
                body.set_initial(R=R, A=A, v=v, omega=w)
            return body.set_initial(q_f=q_f, qdot_f=qd_f)

        return _Body(name, "flexible", keypath, make, body_data)

    def _modal(self, t: _Table, key, n_modes, unit, low=None):
        array = t.numbers(key, None, None, unit=unit, low=low)
        if array is not None and array.size != n_modes:
            t.fail(key, f"{key!r} needs one value per selected mode ({n_modes}), got {array.size}")
        return array

    def _body_data(self, t: _Table, name):
        """The BodyData of ``source`` (read once per file), its files added to inputs."""
        from preprocess import read_body
        from preprocess.bodyfiles import body_files
        from preprocess.units import UNIT_SYSTEMS

        source = t.string("source")
        units = t.choice("units", tuple(UNIT_SYSTEMS), "si")
        if source.startswith(BUILTIN):
            return self._builtin(t, name, source[len(BUILTIN):])
        if not source.strip():
            t.fail("source", "'source' is empty: give a body directory or .h5 file")
        path = Path(source).expanduser()
        if not path.is_absolute():
            path = self.path.parent / path
        if not path.exists():
            t.fail("source", f"body file {str(path)!r} not found (source {source!r}, relative to the "
                             f"scene file's directory {str(self.path.parent)!r})")
        key = (str(path.resolve()), units)
        if key not in self._sources:
            try:
                self._sources[key] = read_body(path, units)
            except InputFileError as exc:
                raise InputFileError(exc.path, exc.line, f"{exc.fault} (body {name!r} of scene file "
                                                         f"{self.path})") from None
            except FfrmbsError as exc:
                t.fail("source", f"cannot read body file {str(path)!r}: {exc}")
        files = body_files(path)
        for f in files:
            label = f"body {name!r}" if len(files) == 1 else f"body {name!r} {f.name}"
            self.inputs[label] = str(f)
        return self._sources[key]

    def _builtin(self, t: _Table, name, which):
        from ffrmbs_app.scenes import point_mass_beam, sliding_ball
        from ffrmbs_app.scenes.cache import cached_body_path

        builtins = {"point_mass_beam": point_mass_beam, "sliding_ball": sliding_ball}
        if which not in builtins:
            t.fail("source", f"unknown built-in body {BUILTIN + which!r} (built-in: "
                             f"{', '.join(BUILTIN + b for b in builtins)})")
        module = builtins[which]
        key = (BUILTIN + which, "si")
        if key not in self._sources:
            self._sources[key] = module.default_beam_data()
        h5 = cached_body_path(module.recipe())
        if h5.exists():
            self.inputs[f"body {name!r}"] = str(h5)
        return self._sources[key]

    def _rigid(self, data, keypath, label, name) -> _Body:
        from mbs.parametrization import PARAMETRIZATIONS

        t = _Table(self.r, data, keypath, label,
                   ("name", "kind", "mass", "inertia", "com", "rotation", "position", "orientation", "velocity",
                    "angular_velocity"))
        mass = t.number("mass", unit="kg", low=0.0, strict=True)
        if isinstance(t.data.get("inertia"), list) and t.data["inertia"] \
                and not isinstance(t.data["inertia"][0], list):
            inertia = np.diag(t.numbers("inertia", 3, unit="kg m²", low=0.0))
        else:
            inertia = t.matrix3("inertia", unit="kg m²")
        com = t.numbers("com", 3, (0.0, 0.0, 0.0), unit="m")
        rotation = t.choice("rotation", tuple(sorted(PARAMETRIZATIONS)), "quaternion")
        R = t.numbers("position", 3, None, unit="m")
        A = _orientation(t, "orientation")
        v = t.numbers("velocity", 3, None, unit="m/s")
        w = t.numbers("angular_velocity", 3, None, unit="rad/s")

        if not np.allclose(inertia, inertia.T):
            t.fail("inertia", "'inertia' must be symmetric")
        if np.linalg.eigvalsh(inertia).min() < 0:
            t.fail("inertia", "'inertia' must be positive semi-definite (principal values >= 0)")

        def make():
            from mbs import RigidBody
            return RigidBody(mass, inertia, com, rotation, name).set_initial(R=R, A=A, v=v, omega=w)

        return _Body(name, "rigid", keypath, make)

    def _point_mass(self, data, keypath, label, name) -> _Body:
        t = _Table(self.r, data, keypath, label, ("name", "kind", "mass", "position", "velocity"))
        mass = t.number("mass", unit="kg", low=0.0, strict=True)
        position = t.numbers("position", 3, (0.0, 0.0, 0.0), unit="m")
        velocity = t.numbers("velocity", 3, (0.0, 0.0, 0.0), unit="m/s")

        def make():
            from mbs import PointMass
            return PointMass(mass, position=position, velocity=velocity, name=name)

        return _Body(name, "point_mass", keypath, make)

    # --- frames ------------------------------------------------------------------------------------
    def body_of(self, t: _Table, key="body", kinds=None, default=_REQUIRED) -> str:
        """A body name (or "ground") that exists, of one of ``kinds`` if given."""
        name = t.string(key, default)
        if name == GROUND and (kinds is None or GROUND in kinds):
            return name
        if name not in self.bodies:
            known = ", ".join([GROUND, *self.bodies]) if kinds is None or GROUND in kinds else ", ".join(self.bodies)
            t.fail(key, f"unknown body {name!r} (bodies: {known})")
        if kinds is not None and self.bodies[name].kind not in kinds:
            t.fail(key, f"body {name!r} is a {self.bodies[name].kind} body; this needs "
                        f"{' or '.join(k for k in kinds if k != GROUND)}")
        return name

    def frame(self, t: _Table, default_body=_REQUIRED) -> _FrameRef:
        """The frame named by the keys body, node, at, point of ``t``."""
        name = self.body_of(t, default=default_body)
        given = [k for k in ("node", "at", "point") if t.has(k)]
        if len(given) > 1:
            t.fail(given[1], f"give one of 'node', 'at' or 'point', not {' and '.join(map(repr, given))}")
        kind = GROUND if name == GROUND else self.bodies[name].kind
        if given and given[0] in ("node", "at") and kind != "flexible":
            t.fail(given[0], f"{given[0]!r} needs a flexible body; {name!r} is "
                             f"{'the inertial frame' if kind == GROUND else 'a ' + kind + ' body'} "
                             "(use 'point')")
        if t.has("node"):
            data = self.bodies[name].data
            return _FrameRef(name, node=t.integer("node", low=0, high=data.n_nodes - 1))
        if t.has("at"):
            at = t.numbers("at", 3, unit="m")
            return _FrameRef(name, node=t.model("at", lambda: self.bodies[name].data.node_at(at.tolist())))
        return _FrameRef(name, point=t.numbers("point", 3, None, unit="m"))

    def _frame_table(self, t: _Table, key) -> _FrameRef:
        return self.frame(t.table(key, f"{key!r}", FRAME_KEYS))

    def _add(self, t: _Table, build):
        self.steps.append((t.keypath, t.label, build))

    # --- links ------------------------------------------------------------------------------------
    def read_links(self):
        for i, data in self._entries("spring", "spring"):
            t = _Table(self.r, data, ("spring", i), f"spring #{i + 1}",
                       ("frame1", "frame2", "stiffness", "damping", "free_length"))
            f1, f2 = self._frame_table(t, "frame1"), self._frame_table(t, "frame2")
            if f1.body == GROUND and f2.body == GROUND:
                t.fail("frame2", "both frames are on the ground: the spring would act on nothing")
            k = t.number("stiffness", unit="N/m", low=0.0)
            c = t.number("damping", 0.0, unit="N s/m", low=0.0)
            l0 = t.number("free_length", unit="m", low=0.0)

            def build(env, f1=f1, f2=f2, k=k, c=c, l0=l0):
                from mbs import SpringDamper
                env.system.add(SpringDamper(f1.resolve(env), f2.resolve(env), k, c, free_length=l0))

            self._add(t, build)
        for i, data in self._entries("joint", "joint"):
            t = _Table(self.r, data, ("joint", i), f"joint #{i + 1}", ("kind", "frame1", "frame2", "axis"))
            kind = t.choice("kind", JOINT_KINDS)
            f1, f2 = self._frame_table(t, "frame1"), self._frame_table(t, "frame2")
            if f1.same(f2):
                t.fail("frame2", "frame1 and frame2 are the same frame")
            if f1.body == GROUND and f2.body == GROUND:
                t.fail("frame2", "both frames are on the ground: the joint would constrain nothing")
            needs_axis = kind in ("revolute", "prismatic")
            if needs_axis:
                axis = t.numbers("axis", 3)
                if not np.linalg.norm(axis) > 0:
                    t.fail("axis", "'axis' must be a nonzero direction")
            elif t.has("axis"):
                t.fail("axis", f"a {kind} joint takes no 'axis'")
            else:
                axis = None

            def build(env, kind=kind, f1=f1, f2=f2, axis=axis):
                from mbs import Joint
                env.system.add(Joint(f1.resolve(env), f2.resolve(env), kind, axis))

            self._add(t, build)

    # --- loads ---------------------------------------------------------------------------------------
    def _time_function(self, t: _Table, key, unit):
        """A constant (3,) or a :class:`mbs.Tabulated` of 3-vectors."""
        from mbs import Tabulated

        if not isinstance(t.data.get(key), dict):
            return t.numbers(key, 3, unit=unit)
        table = t.table(key, f"{key!r} table", ("times", "values", "kind", "hold_first"))
        times = table.numbers("times", unit="s")
        values = table.rows("values", None, f"an array of [x, y, z] rows{_unit(unit)}")
        if len(values) != times.size:
            table.fail("values", f"{len(values)} rows of 'values' for {times.size} 'times'")
        kind = table.choice("kind", Tabulated.KINDS, "step")
        hold = table.boolean("hold_first", False)
        return table.model("times", lambda: Tabulated(times, values, kind, hold))

    def read_loads(self):
        from mbs import read_force_file
        from preprocess.modes import clamped_dofs

        for i, data in self._entries("load", "load"):
            keypath, label = ("load", i), f"load #{i + 1}"
            head = _Table(self.r, data, keypath, label, tuple(data))
            kind = head.choice("kind", LOAD_KINDS)
            label = f"load #{i + 1} ({kind})"
            if kind in ("force", "torque"):
                t = _Table(self.r, data, keypath, label, ("kind", *FRAME_KEYS, kind, "frame_fixed"))
                frame = self.frame(t)
                if frame.body == GROUND:
                    t.fail("body", f"a {kind} on the ground does nothing: apply it to a body")
                value = self._time_function(t, kind, "N" if kind == "force" else "N m")
                fixed = t.boolean("frame_fixed", False)

                def build(env, kind=kind, frame=frame, value=value, fixed=fixed):
                    from mbs import Force, Torque
                    env.system.add((Force if kind == "force" else Torque)(frame.resolve(env), value, fixed))

            elif kind == "distributed":
                t = _Table(self.r, data, keypath, label, ("kind", "body", "nodes", "weights", "force", "frame_fixed"))
                name = self.body_of(t, kinds=("flexible",))
                nodes = self._nodes(t, "nodes", name)
                weights = t.numbers("weights", None, None)
                n = len(self.bodies[name].data.node_groups[nodes]) if isinstance(nodes, str) else nodes.size
                if weights is None:
                    weights = np.full(n, 1.0 / n)
                elif weights.size != n:
                    t.fail("weights", f"{weights.size} weights for {n} nodes")
                value = self._time_function(t, "force", "N")
                fixed = t.boolean("frame_fixed", True)
                from mbs.loads import WEIGHT_SUM_TOL
                if not abs(weights.sum() - 1.0) <= WEIGHT_SUM_TOL:
                    t.fail("weights", f"the weights sum to {float(weights.sum())!r}, not 1")

                def build(env, name=name, nodes=nodes, weights=weights, value=value, fixed=fixed):
                    from mbs import DistributedForce
                    env.system.add(DistributedForce(env.bodies[name], nodes, weights, value, fixed))

            else:   # nodal
                t = _Table(self.r, data, keypath, label, ("kind", "body", "file", "blocked", "frame_fixed"))
                name = self.body_of(t, kinds=("flexible",))
                body_data = self.bodies[name].data
                file = t.string("file")
                path = Path(file).expanduser()
                path = path if path.is_absolute() else self.path.parent / path
                if not path.is_file():
                    t.fail("file", f"force file {str(path)!r} not found (file {file!r}, relative to the scene "
                                   f"file's directory {str(self.path.parent)!r})")
                blocked = None
                if t.has("blocked"):
                    nodes = self._nodes(t, "blocked", name)
                    nodes = body_data.node_groups[nodes] if isinstance(nodes, str) else nodes
                    blocked = clamped_dofs(3 * body_data.n_nodes, nodes)
                try:
                    times, forces = read_force_file(path, body_data.n_nodes, blocked)
                except InputFileError as exc:
                    raise InputFileError(exc.path, exc.line, f"{exc.fault} ({label} of scene file "
                                                             f"{self.path})") from None
                self.inputs[f"{label} force file"] = str(path)
                fixed = t.boolean("frame_fixed", True)

                def build(env, name=name, times=times, forces=forces, fixed=fixed):
                    from mbs import NodalForces
                    env.system.add(NodalForces(env.bodies[name], times, forces, fixed))

            self._add(t, build)

    def _nodes(self, t: _Table, key, name, required=True):
        """A node-group name of body ``name`` or a list of its node indices."""
        data = self.bodies[name].data
        value = t.data.get(key)
        if isinstance(value, str):
            if value not in data.node_groups:
                t.fail(key, f"body {name!r} has no node group {value!r} (groups: "
                            f"{', '.join(sorted(data.node_groups)) or 'none'})")
            return value
        if value is None and not required:
            return None
        if value is None:
            t.fail(None, f"missing required key {key!r}")
        if not isinstance(value, list):
            t.fail(key, f"{key!r} must be a node-group name or an array of 0-based node indices, "
                        f"got {_describe(value)}")
        return t.indices(key, data.n_nodes)

    # --- contacts -----------------------------------------------------------------------------------
    def read_contacts(self):
        names = set()
        for i, data in self._entries("contact", "contact"):
            keypath = ("contact", i)
            given = data.get("name")
            label = f"contact {given!r}" if isinstance(given, str) else f"contact #{i + 1}"
            t = _Table(self.r, data, keypath, label, tuple(data))      # the keys are checked once the law is known
            name = t.string("name", f"contact {i + 1}")
            if name in names:
                t.fail("name", f"a second contact named {name!r} (contact names must be unique)")
            names.add(name)
            law = t.choice("law", LAWS)
            law_keys = {"impact": ("e",), "coulomb": ("e", "mu", "e_T"), "penalty": ("k", "d", "mu", "v_eps"),
                        "bilateral": ()}[law]
            common = ("name", "contour1", "contour2", "law") + (("margin",) if law != "bilateral" else ())
            t.allow(common + law_keys, f" for law {law!r}")
            c1 = self._contour(t, "contour1", CONTOUR1_KINDS)
            c2 = self._contour(t, "contour2", CONTOUR2_KINDS)
            kinematics = self._kinematics(t, law, c1[0], c2[0])
            force_law, friction = self._law(t, law)
            margin = "auto"
            if t.has("margin"):
                value = t.data["margin"]
                if value == "auto":
                    margin = "auto"
                elif value == "off":
                    margin = None
                elif _is_number(value):
                    margin = t.number("margin", unit="m", low=0.0)
                else:
                    t.fail("margin", f"'margin' must be a length [m] >= 0, \"auto\" or \"off\", got {_describe(value)}")

            def build(env, c1=c1, c2=c2, kinematics=kinematics, law=force_law, friction=friction, margin=margin,
                      name=name):
                from contact import Contact, CurveConstraint
                kin = kinematics(c1[1](env), c2[1](env))
                if law is None:
                    env.system.add(CurveConstraint(kin, name=name))
                else:
                    env.system.add(Contact(kin, law, friction=friction, name=name, margin=margin))

            self._add(t, build)

    def _kinematics(self, t: _Table, law, kind1, kind2):
        import contact as c

        if law == "bilateral":
            if (kind1, kind2) != ("point", "1s"):
                t.fail("law", f"law 'bilateral' keeps a point on a 1s curve: needs contour1 kind 'point' and "
                              f"contour2 kind '1s', got {kind1!r} and {kind2!r}")
            return c.PointOnCurveConstraint
        if kind2 in ("2s", "band", "cylinder") or (kind2 == "sphere" and kind1 == "point"):
            return c.ContactKinematicsPointContour2s if kind1 == "point" else c.ContactKinematicsSphereContour2s
        if kind2 == "1s":
            return c.ContactKinematicsPointContour1s if kind1 == "point" else c.ContactKinematicsSphereContour1s
        if kind2 == "plane":
            return c.ContactKinematicsPointPlane if kind1 == "point" else c.ContactKinematicsSpherePlane
        return c.ContactKinematicsSphereSphere

    def _law(self, t: _Table, law):
        import contact as c

        if law == "bilateral":
            return None, None
        if law == "impact":
            e = t.number("e", 0.0)
            return t.model("e", lambda: c.UnilateralNewtonImpact(e)), None
        if law == "coulomb":
            e, mu, e_T = t.number("e", 0.0), t.number("mu"), t.number("e_T", 0.0)
            return t.model("mu", lambda: c.UnilateralCoulombContact(e, mu, e_T)), None
        k, d = t.number("k", unit="N/m"), t.number("d", 0.0, unit="N s/m")
        normal = t.model("k", lambda: c.LinearRegularizedUnilateralConstraint(k, d))
        friction = None
        if t.has("mu") or t.has("v_eps"):
            mu, v_eps = t.number("mu"), t.number("v_eps", unit="m/s")
            friction = t.model("v_eps", lambda: c.RegularizedCoulombFriction(mu, v_eps))
        return normal, friction

    def _contour(self, t: _Table, key, kinds):
        """(kind, make(env) -> Contour) of the contour table ``key``."""
        raw = t.data.get(key)
        head = t.table(key, f"{key!r}", tuple(raw) if isinstance(raw, dict) else ())     # no key check yet
        kind = head.choice("kind", kinds)
        label = f"{key} ({kind})"
        if kind == "point":
            c = t.table(key, label, ("kind", *FRAME_KEYS))
            frame = self.frame(c)
            if frame.body == GROUND:
                c.fail("body", "a point contour on the ground never moves: put the point on a body "
                               "and the surface on the ground")

            def make(env):
                from contours import PointContour
                return PointContour(frame.resolve(env))

        elif kind == "sphere":
            c = t.table(key, label, ("kind", *FRAME_KEYS, "radius"))
            frame = self.frame(c)
            radius = c.number("radius", unit="m", low=0.0, strict=True)

            def make(env):
                from contours import SphereContour
                return SphereContour(frame.resolve(env), radius)

        elif kind == "plane":
            c = t.table(key, label, ("kind", *FRAME_KEYS, "normal", "size"))
            frame = self.frame(c, GROUND)
            normal = c.numbers("normal", 3, (0.0, 0.0, 1.0))
            if not np.linalg.norm(normal) > 0:
                c.fail("normal", "'normal' must be a nonzero direction")
            size = c.number("size", 1.0, unit="m", low=0.0, strict=True)
            axes = _axes_with_normal(normal)

            def make(env):
                from contours import PlaneContour
                return PlaneContour(frame.resolve(env, orientation=axes, name="plane"), size)

        elif kind == "2s":
            c = t.table(key, label, ("kind", "body", "nodes", "extra_rows", "degree", "closed", "method", "outward"))
            name = self.body_of(c, kinds=("flexible",))
            nodes = self._node_matrix(c, name)
            extra = c.integer("extra_rows", 0, low=0)
            degree = self._pair(c, "degree", 3, int)
            closed = self._pair(c, "closed", False, bool)
            method = c.choice("method", ("chord", "centripetal"), "chord")
            outward = None
            if c.has("outward"):
                outward = c.integer("outward")
                if outward not in (1, -1):
                    c.fail("outward", f"'outward' must be 1 or -1, got {outward}")

            def make(env):
                from contours import Contour2sNeutralFFR
                return Contour2sNeutralFFR(env.bodies[name], nodes, extra, degree, closed, method, outward)

        else:   # 1s, band, cylinder
            extra_keys = {"1s": (), "band": ("width", "offset"), "cylinder": ("radius",)}[kind]
            c = t.table(key, label, ("kind", "body", "start", "direction", "nodes", "normal", "degree", "closed",
                                     "method", *extra_keys))
            name = self.body_of(c, kinds=("flexible",))
            line = c.has("start") or c.has("direction")
            start = c.numbers("start", 3, unit="m") if line else None
            direction = c.numbers("direction", 3) if line else None
            if line and not np.linalg.norm(direction) > 0:
                c.fail("direction", "'direction' must be a nonzero direction")
            nodes = self._nodes(c, "nodes", name, required=not line)
            if not line and isinstance(nodes, str):
                c.fail("nodes", "a node group has no order: give 'start' and 'direction' (the nodes on that "
                                "line), or 'nodes' as the ordered list of node indices")
            normal = c.numbers("normal", 3)
            if not np.linalg.norm(normal) > 0:
                c.fail("normal", "'normal' must be a nonzero direction")
            degree = c.integer("degree", 3, low=1)
            closed = c.boolean("closed", False)
            method = c.choice("method", ("chord", "centripetal"), "chord")
            width = c.number("width", unit="m", low=0.0, strict=True) if kind == "band" else None
            offset = c.number("offset", 0.0, unit="m") if kind == "band" else None
            radius = c.number("radius", unit="m", low=0.0, strict=True) if kind == "cylinder" else None

            def make(env):
                from contours import Contour1sNeutralFFR, FlexibleBand, FlexibleCylinder
                body = env.bodies[name]
                kw = dict(degree=degree, closed=closed, method=method)
                curve = (Contour1sNeutralFFR.along_line(body, start, direction, normal, nodes=nodes, **kw) if line
                         else Contour1sNeutralFFR(body, nodes, normal, **kw))
                if kind == "band":
                    return FlexibleBand(curve, width, offset)
                if kind == "cylinder":
                    return FlexibleCylinder(curve, radius)
                return curve

        keypath, label = t.keypath + (key,), f"{t.label}: {label}"        # a ModelError is reported there
        return kind, lambda env: self.r.run(keypath, label, lambda: make(env))

    def _pair(self, c: _Table, key, default, kind):
        """One value or a pair [η, ξ] of integers (>= 1) or booleans."""
        value = c.data.get(key, default)
        one = (lambda v: isinstance(v, bool)) if kind is bool else (lambda v: _is_int(v) and v >= 1)
        if one(value):
            return value
        if isinstance(value, list) and len(value) == 2 and all(one(v) for v in value):
            return tuple(value)
        what = "true/false" if kind is bool else "an integer >= 1"
        c.fail(key, f"{key!r} must be {what} or a pair of them [eta, xi], got {_describe(value)}")

    def _node_matrix(self, c: _Table, name):
        """A node-group name, or the node matrix O (rows of node indices, equal lengths >= 2)."""
        value = c.data.get("nodes")
        if isinstance(value, str) or value is None:
            return self._nodes(c, "nodes", name)
        n = self.bodies[name].data.n_nodes
        ok = (isinstance(value, list) and len(value) >= 2 and all(isinstance(row, list) for row in value)
              and len({len(row) for row in value}) == 1 and len(value[0]) >= 2
              and all(_is_int(v) for row in value for v in row))
        if not ok:
            c.fail("nodes", "'nodes' must be a node-group name or the node matrix O: rows of equal length "
                            f"(>= 2 x 2) of 0-based node indices, got {_describe(value)}")
        O = np.array(value, dtype=np.int64)
        if O.min() < 0 or O.max() >= n:
            c.fail("nodes", f"'nodes': node indices must lie in 0..{n - 1}")
        return O

    # --- outputs ------------------------------------------------------------------------------------
    def read_outputs(self):
        value = self.doc.get("outputs", {})
        if not isinstance(value, dict):
            self.r.fail(("outputs",), f"'outputs' must be a table [outputs], got {_describe(value)}")
        for name, spec in value.items():
            keypath, label = ("outputs", name), f"output {name!r}"
            if not isinstance(spec, dict):
                self.r.fail(keypath, f"{label}: expected a table such as {{ body = \"...\", quantity = "
                                     f"\"position\" }}, got {_describe(spec)}")
            t = _Table(self.r, spec, keypath, label, (*FRAME_KEYS, "quantity", "component"))
            quantity = t.choice("quantity", QUANTITIES, "position")
            body = self.body_of(t, kinds=("flexible", "rigid", "point_mass"))
            kind = self.bodies[body].kind
            if quantity in ("angular_velocity", "q_f"):
                for key in ("node", "at", "point"):
                    if t.has(key):
                        t.fail(key, f"quantity {quantity!r} is the body's: it takes no {key!r}")
            if quantity in ("displacement", "q_f") and kind != "flexible":
                t.fail("quantity", f"quantity {quantity!r} needs a flexible body; {body!r} is a {kind} body")
            if quantity == "displacement" and not (t.has("node") or t.has("at")):
                t.fail(None, "quantity 'displacement' needs the node: give 'node' or 'at'")
            frame = self.frame(t)
            component = None
            if t.has("component"):
                if quantity == "q_f":
                    t.fail("component", "quantity 'q_f' takes no 'component'")
                component = COMPONENTS.index(t.choice("component", COMPONENTS))
            self.outputs[name] = (keypath, label, self._probe(frame, quantity, component))
            if quantity in QUANTITY_UNITS:
                self.units[name] = QUANTITY_UNITS[quantity]

    @staticmethod
    def _probe(ref: _FrameRef, quantity, component):
        def make(env):
            body = env.bodies[ref.body]
            frame = ref.resolve(env)
            if quantity == "position" and component is None:
                return frame
            pick = (lambda x: x) if component is None else (lambda x: x[component])
            if quantity == "position":
                return lambda t, q, u: pick(frame.position(q[body.q_slice], t))
            if quantity == "velocity":
                return lambda t, q, u: pick(frame.velocity(q[body.q_slice], u[body.u_slice], t))
            if quantity == "displacement":
                return lambda t, q, u: pick(frame.elastic_displacement(q[body.q_slice]))
            if quantity == "angular_velocity":
                return lambda t, q, u: pick(body.angular_velocity(q[body.q_slice], u[body.u_slice], t))
            return lambda t, q, u: body.elastic_coordinates(q[body.q_slice]).copy()
        return make

    # --- pass 2 ------------------------------------------------------------------------------------
    def build(self, settings: dict) -> Scene:
        from mbs import System

        env = _Env(System(gravity=settings["gravity"]))
        for body in self.bodies.values():
            env.bodies[body.name] = self.r.run(body.keypath, f"body {body.name!r}",
                                               lambda body=body: env.system.add(body.make()))
        for keypath, label, build in self.steps:
            self.r.run(keypath, label, lambda: build(env))
        outputs = {name: self.r.run(keypath, label, lambda make=make: make(env))
                   for name, (keypath, label, make) in self.outputs.items()}
        return self.r.run(("scene",), "[scene]", lambda: Scene(
            env.system, settings["t_end"], settings["dt"], settings["integrator"], settings["options"],
            settings["n_out"], outputs, settings["energies"], settings["plan"], settings["tolerance"],
            settings["name"], dict(self.inputs), settings["description"], units=dict(self.units)))


# --- reading -------------------------------------------------------------------------------------------

def _parse(path: Path, raw: bytes) -> tuple[str, dict]:
    """(text, document) of a TOML file; syntax errors as InputFileError with the line."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputFileError(path, raw[:exc.start].count(b"\n") + 1,
                             "not UTF-8 text (a TOML scene file is UTF-8)") from None
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        line, column = getattr(exc, "lineno", None), getattr(exc, "colno", None)
        where = re.search(r"\(at line (\d+), column (\d+)\)", message)
        if line is None and where:
            line, column = int(where[1]), int(where[2])
        elif line is None and "end of document" in message:
            line = text.count("\n") + 1
        fault = getattr(exc, "msg", None) or re.sub(r"\s*\(at (line \d+, column \d+|end of document)\)", "",
                                                    message)
        raise InputFileError(path, line, f"TOML syntax error: {fault}"
                             + (f" (column {column})" if column else "")) from None


def read_scene(path) -> Scene:
    """The :class:`~ffrmbs_app.scene.Scene` of the TOML scene file ``path``. The schema is
    in the module docstring.

    The whole file is checked first: its syntax, every key, its type and range, the
    body names, the node and mode indices, and the body and force files. Only then is
    the System built. Every fault raises :class:`~ffrmbs.errors.InputFileError` naming
    the file and the line, or the body or force file at fault. ``Scene.inputs`` lists
    the scene file and each body and force file read, as label -> path.
    """
    path = regular_file(path)                 # never open a FIFO or a device
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read the scene file: {os_reason(exc)}") from None
    text, doc = _parse(path, raw)
    reader = _SceneReader(path, text, doc)
    settings = reader.settings()
    reader.read_bodies()
    reader.read_links()
    reader.read_loads()
    reader.read_contacts()
    reader.read_outputs()
    return reader.build(settings)
