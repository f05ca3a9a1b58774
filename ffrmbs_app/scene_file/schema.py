"""The schema of scene files: one simulation job written in TOML — its documentation
(this docstring) and its data (the tables below: each key's type, unit, default and
bounds; the kinds come from the library's registries).

``read_scene(path)`` (:mod:`ffrmbs_app.scene_file`) reads a scene file and returns a
:class:`ffrmbs_app.scene.Scene`: the :class:`mbs.System` with its initial state set, and
how to integrate it and what to record. ``ffrmbs_app.scene_loader.load_scene`` calls it for ``.toml`` files. Every entry maps
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
    default): see :mod:`mbs.run.plan`. ``gravity`` ([0, 0, 0]) [m/s²].

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
  directory. ``"builtin:point_mass_beam"`` (tet4, 275 nodes, all 750 modes),
  ``"builtin:point_mass_beam_tet10"`` (tet10 of 12.5 mm, 3321 nodes, 40 modes: the main
  job's beam) and ``"builtin:sliding_ball"`` are the cached thesis beams of
  :mod:`ffrmbs_app.scenes`.
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
  ``geometric_stiffening`` (false): true adds the stiffening of the body by the inertia
  loads of its spinning frame (:mod:`mbs.bodies.geometric_stiffening`); the body file must hold
  the geometric stiffness (``ffrmbs preprocess ... --geometric-stiffness``).
- "rigid": :class:`mbs.RigidBody`. ``mass`` *req.* [kg] > 0. ``inertia`` *req.*
  [kg m²] about the centre of mass in body axes: a 3 x 3 matrix, or 3 principal
  values. ``com`` ([0, 0, 0]) [m] in the body frame. ``rotation``, ``position``,
  ``orientation``, ``velocity`` and ``angular_velocity`` as for a free flexible body.
- "point_mass": :class:`mbs.PointMass`. ``mass`` *req.* [kg] > 0. ``position`` and
  ``velocity`` (both [0, 0, 0]) [m], [m/s].

Every body takes ``initial`` ("given"): "static" starts the body at rest in static
equilibrium under gravity and the loads at t = 0 (:meth:`mbs.System.static_equilibrium`),
held by its fixed frame, joints, springs and the contacts it rests on (closed at the
given state: with the impact law frictionless, with the Coulomb law sticking within its
friction cone); the bodies with "given" keep
their state. A clamped flexible body (``frame = "fixed"``) then starts from its static
deflection K_ff q_f = Q_f (exact in its modes) instead of ringing about it. The given
``position`` and ``orientation`` of a free body are the start of the search; such a body
takes no ``velocity``, ``angular_velocity``, ``q_f`` or ``modal_velocities``. A body
nothing holds (free fall), a contact that would have to pull, one the deflection would
close, or a resting contact with a penalty law or residual flexibility are errors naming
the body or the contact.

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
``contour1`` *req.*: ``{ kind = "point" | "sphere", <frame>, radius, residual_flexibility = false }``;
at a ``node`` of a flexible body, ``residual_flexibility = true`` gives the node the static
compliance of the modes its body leaves out (:class:`contours.residual.NodeCompliance`): a
part pressed on another through points at its nodes deflects there as the full model does.
Or a face: ``contour1`` a "2s" or "1s" contour of a flexible body (the keys of
``contour2`` below) makes a face contact (:class:`contact.FaceContact`), a point contact at
each of its nodes against ``contour2`` with the contact's law, named "<name> node <j>", each
with its node's residual flexibility when the face has ``residual_flexibility = true``.
Either contour may be on the ground, not both: points on the ground
(``body = "ground"``) against a surface on a body model a part landing on a rigid
support, the part's own surface (and its residual flexibility) taking the contact.
``contour2`` *req.* is one of:

- ``{ kind = "2s", body, nodes, extra_rows = 0, degree = 3, closed = false,
  method = "chord", outward }``: :class:`contours.Contour2sNeutralFFR` on a flexible
  body. ``nodes`` is a node-group name or the node matrix O as a list of rows. A
  group that is a planar structured grid is interpolated exactly; any other face
  group of a tet4/tet10 surface (e.g. a gmsh physical surface) is fitted by least
  squares (:mod:`contours.fitting`; a closed band such as a cylinder's lateral
  surface periodically), with ``control_points`` (one count or a pair [η, ξ];
  default: knot spans of about two node spacings — given, the group is fitted even if
  it is a grid) and ``smoothing`` (1e-6, a dimensionless thin-plate weight).
  ``ffrmbs contour BODY GROUP`` reports how well a group is fitted. ``degree`` and
  ``closed`` take one value or a pair (η, ξ) (``closed``, ``extra_rows`` and
  ``method`` concern grids only). ``outward`` is +1 or -1. Omitted, it is found from
  the body.
- ``{ kind = "1s" | "band" | "cylinder", body, start, direction, nodes, normal,
  degree = 3, closed, method = "chord", width, offset = 0, radius }``: a
  :class:`contours.Contour1sNeutralFFR`. It runs through the nodes on the line
  through ``start`` [m] along ``direction`` (within ``nodes``, a group or a list,
  if given). Without ``start`` and ``direction``, ``nodes`` is a node group that
  forms an edge of surface nodes on any tet4/tet10 mesh (e.g. a gmsh physical
  curve: a box edge, a pulley rim), ordered by walking the body's surface edges
  (:func:`contours.node_grid.node_path`), or the ordered list of nodes.
  ``closed`` follows the walk when absent (a loop gives a closed curve; given, it
  must agree); for a list or a line it defaults to false. The curve interpolates
  the ordered nodes; with ``control_points`` (a count >= 2) it is a least-squares
  fit to them instead (``smoothing``, 1e-6). ``normal`` *req.* is the
  reference normal in the body frame. "band" (a
  :class:`contours.FlexibleBand`) takes ``width`` *req.* [m] and ``offset`` [m].
  "cylinder" (a :class:`contours.FlexibleCylinder`) takes ``radius`` *req.* [m].
  "edge" (a :class:`contours.Contour1sEdgeFFR`, same keys as "1s") is a sharp edge
  that a sphere touches (the normal from the edge to the ball's centre), e.g. a hole's
  rim given as a gmsh physical curve; a 2s face with holes is trimmed to its material,
  so a ball over a hole falls through and meets the rim's edge.
- Each of these flexible contours takes ``residual_flexibility`` (false): true makes
  its contacts act through the static compliance of the modes the body leaves out
  (:mod:`contours.residual`; a set-valued law is needed), accurate impacts with few
  modes; the compliance is computed once and cached with the scenes' body data.
- ``{ kind = "plane", <frame>, normal = [0, 0, 1], size = 1 }``: a
  :class:`contours.PlaneContour` through the frame's point, with that normal in
  the frame's axes. The default frame is the ground origin.
- ``{ kind = "sphere", <frame>, radius }``: a :class:`contours.SphereContour`.

``law`` *req.* is a name of :data:`contact.LAWS`; its parameters are the law class's
fields of type float (units from its ``units``), required where the class has no
default. The registered laws:

- "impact": :class:`contact.UnilateralNewtonImpact`, with ``e`` (0).
- "coulomb": :class:`contact.UnilateralCoulombContact`, with ``e`` (0), ``mu``
  *req.* and ``e_T`` (0).
- "penalty": :class:`contact.LinearRegularizedUnilateralConstraint`, with ``k``
  *req.* [N/m] and ``d`` (0) [N s/m].
- "bilateral": a point kept on a 1s curve (:class:`contact.CurveConstraint`).

A single-valued law (such as "penalty") takes optional friction
(:class:`contact.RegularizedCoulombFriction`): ``mu`` and ``v_eps`` [m/s], both or
neither.

The kinematics follow from the contour kinds (:data:`contact.PAIR_KINEMATICS`, for
"bilateral" :data:`contact.BILATERAL_KINEMATICS`): point or sphere against 2s, band,
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

import dataclasses
import inspect
from dataclasses import dataclass

from contact import LAWS, SOLVERS, RegularizedCoulombFriction
from contours.fitting import SMOOTHING
from mbs import BODIES, INTEGRATORS, JOINTS, LOADS, ROTATIONS, Tabulated
from mbs.integrators import MoreauTimeStepping
from mbs.links.joints import AXIS_KINDS
from ffrmbs.registry import Registry
from preprocess.units import UNIT_SYSTEMS

GROUND = "ground"                   # the inertial frame's body name
BUILTIN = "builtin:"                # prefix of a built-in body source
ORTHONORMAL_TOL = 1e-9              # max |AᵀA − 1| of an orientation matrix
MAX_MAGNITUDE = 1e12                # |x| of any number of a scene [SI units]: larger ones are no physical input


class _Required:
    def __repr__(self):
        return "required"


REQUIRED = _Required()              # the default of a required key


@dataclass(frozen=True)
class Key:
    """One key of a table.

    type: "number" (a finite float [unit] in the bounds low/high, low exclusive when
    ``strict``), "integer" (64 bits, in low..high), "boolean", "string", "choice" (one of
    ``choices``: a tuple, or a registry whose names when the file is read are the choices), "numbers" (an array of ``size`` finite numbers, any length >= 1 if
    None, each >= low), "matrix3" (3 rows of 3 numbers [unit]), "table" (a sub-table),
    or "special" (a form read by the builder, described in ``doc``). default: the value
    when the key is absent, or :data:`REQUIRED`.
    """

    type: str
    default: object = REQUIRED
    unit: str = ""
    low: float | None = None
    strict: bool = False
    high: float | None = None
    choices: tuple | Registry = ()
    size: int | None = None
    doc: str = ""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


def _length(default=REQUIRED, low=0.0, strict=False):
    return Key("number", default, "m", low, strict)


def _vector(default=None, unit="", doc=""):
    return Key("numbers", default, unit, size=3, doc=doc)


# --- [scene] ------------------------------------------------------------------------------------

SCENE = {
    "name": Key("string", None, doc="the file's stem when absent"),
    "description": Key("string", ""),
    "t_end": Key("number", unit="s", low=0.0, strict=True),
    "dt": Key("number", unit="s", low=0.0, strict=True),
    "integrator": Key("choice", "moreau", choices=INTEGRATORS),
    "n_out": Key("integer", 101, low=2),
    "energies": Key("boolean", True),
    "plan": Key("boolean", True),
    "tolerance": Key("number", None, unit="m", low=0.0, strict=True),
    "gravity": _vector((0.0, 0.0, 0.0), "m/s²"),
    "options": Key("table", {}, doc="the integrator's keyword options (option_keys)"),
}
TOP_LEVEL = ("scene", "body", "spring", "joint", "load", "contact", "outputs")


def option_keys(integrator: str) -> dict:
    """{option: Key} of the keyword options of integrator ``integrator`` (for
    "moreau-adaptive" also Moreau's), typed by their defaults in the signature: a bool
    a boolean, an int an integer >= 0, ``solver`` one of :data:`contact.SOLVERS`, another
    str a string, a tuple that many numbers, anything else a number."""
    params = dict(inspect.signature(INTEGRATORS[integrator].__init__).parameters)
    if integrator == "moreau-adaptive":
        params.update(inspect.signature(MoreauTimeStepping.__init__).parameters)
    keys = {}
    for name, p in params.items():
        if name in ("self", "system") or p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL):
            continue
        default = p.default
        if isinstance(default, bool):
            keys[name] = Key("boolean")
        elif isinstance(default, int):
            keys[name] = Key("integer", low=0)
        elif isinstance(default, str):
            keys[name] = Key("choice", choices=SOLVERS) if name == "solver" else Key("string")
        elif isinstance(default, (tuple, list)):
            keys[name] = Key("numbers", size=len(default))
        else:                       # float or None (an optional number)
            keys[name] = Key("number")
    return keys


# --- [[body]] -----------------------------------------------------------------------------------

BODY_HEAD = {"name": Key("string"), "kind": Key("choice", choices=BODIES)}
_INITIAL = {"initial": Key("choice", "given", choices=("given", "static"))}
STATIC_REFUSES = ("velocity", "angular_velocity", "q_f", "modal_velocities")     # what initial = "static" computes
_FREE_FRAME = {
    "rotation": Key("choice", "quaternion", choices=ROTATIONS),
    "position": _vector(unit="m"),
    "orientation": Key("special", None, doc="a rotation matrix: three rows of three numbers"),
    "velocity": _vector(unit="m/s"),
    "angular_velocity": _vector(unit="rad/s"),
}
BODY = {
    "flexible": {
        **BODY_HEAD,
        "source": Key("string", doc="a body directory or .h5 file, or builtin:<name>"),
        "units": Key("choice", "si", choices=tuple(UNIT_SYSTEMS)),
        "modes": Key("special", None, doc="a number of modes, a list of 0-based mode indices or \"all\""),
        "frame": Key("choice", "free", choices=("free", "fixed")),
        **_FREE_FRAME,
        "q_f": Key("special", None, doc="one value per selected mode"),
        "modal_velocities": Key("special", None, unit="1/s", doc="one value per selected mode"),
        "rayleigh": Key("numbers", None, low=0.0, size=2, doc="[α [1/s], β [s]]"),
        "modal_damping": Key("special", None, doc="ζ >= 0: one value or one per selected mode"),
        "geometric_stiffening": Key("boolean", False, doc="stiffening by the frame's inertia loads "
                                                          "(body file preprocessed with --geometric-stiffness)"),
        **_INITIAL,
    },
    "rigid": {
        **BODY_HEAD,
        "mass": Key("number", unit="kg", low=0.0, strict=True),
        "inertia": Key("special", unit="kg m²", doc="a 3 x 3 matrix or 3 principal values"),
        "com": _vector((0.0, 0.0, 0.0), "m"),
        **_FREE_FRAME,
        **_INITIAL,
    },
    "point_mass": {
        **BODY_HEAD,
        "mass": Key("number", unit="kg", low=0.0, strict=True),
        "position": _vector((0.0, 0.0, 0.0), "m"),
        "velocity": _vector((0.0, 0.0, 0.0), "m/s"),
        **_INITIAL,
    },
}
FIXED_FRAME_REFUSES = ("velocity", "angular_velocity", "rotation")     # keys of free frames only

# --- frames, links, loads ---------------------------------------------------------------------

FRAME = {
    "body": Key("string", doc='a body name or "ground"'),
    "node": Key("integer", low=0, doc="0-based node of a flexible body"),
    "at": _vector(REQUIRED, "m"),
    "point": _vector(None, "m"),
}
SPRING = {
    "frame1": Key("table"), "frame2": Key("table"),
    "stiffness": Key("number", unit="N/m", low=0.0),
    "damping": Key("number", 0.0, unit="N s/m", low=0.0),
    "free_length": Key("number", unit="m", low=0.0),
}
JOINT = {
    "kind": Key("choice", choices=JOINTS),
    "frame1": Key("table"), "frame2": Key("table"),
    "axis": _vector(REQUIRED, doc=f"[-] in frame1's axes, for {' and '.join(AXIS_KINDS)} joints only"),
}
_TIME_FUNCTION = "a constant [x, y, z] or a table {times, values, kind, hold_first}"
LOAD = {
    "force": {"kind": Key("choice", choices=LOADS), **FRAME,
              "force": Key("special", unit="N", doc=_TIME_FUNCTION), "frame_fixed": Key("boolean", False)},
    "torque": {"kind": Key("choice", choices=LOADS), **FRAME,
               "torque": Key("special", unit="N m", doc=_TIME_FUNCTION), "frame_fixed": Key("boolean", False)},
    "distributed": {"kind": Key("choice", choices=LOADS), "body": FRAME["body"],
                    "nodes": Key("special", doc="a node-group name or a list of node indices"),
                    "weights": Key("numbers", None), "force": Key("special", unit="N", doc=_TIME_FUNCTION),
                    "frame_fixed": Key("boolean", True)},
    "nodal": {"kind": Key("choice", choices=LOADS), "body": FRAME["body"],
              "file": Key("string", doc="a force file, relative to the scene file"),
              "blocked": Key("special", None, doc="a node group or a list of nodes"),
              "frame_fixed": Key("boolean", True)},
}
TABULATED = {
    "times": Key("numbers", unit="s"),
    "values": Key("special", doc="an array of [x, y, z] rows, one per time"),
    "kind": Key("choice", "step", choices=Tabulated.KINDS),
    "hold_first": Key("boolean", False),
}

# --- [[contact]] --------------------------------------------------------------------------------

CONTACT = {
    "name": Key("string", None, doc='"contact <i>" when absent; unique'),
    "contour1": Key("table"), "contour2": Key("table"),
    "law": Key("choice", choices=LAWS),
    "margin": Key("special", "auto", unit="m", doc='a length >= 0, "auto" or "off"'),
}
_KIND = Key("choice", choices=())      # the kind of a contour: checked against CONTOUR1_KINDS or CONTOUR2_KINDS
_NEUTRAL = {"degree": Key("integer", 3, low=1),
            "method": Key("choice", "chord", choices=("chord", "centripetal"))}
_CURVE = {"kind": _KIND, "body": FRAME["body"], "start": _vector(REQUIRED, "m"),
          "direction": _vector(REQUIRED),
          "nodes": Key("special", None, doc="a node group (an edge of surface nodes, or with start and direction "
                                            "any group) or the ordered list of nodes"),
          "normal": _vector(REQUIRED), **_NEUTRAL,
          "closed": Key("boolean", None, doc="from the walk of an edge group when absent, else false"),
          "control_points": Key("integer", None, low=2, doc="absent: interpolate the nodes; a count: fit them "
                                                            "by least squares"),
          "smoothing": Key("number", SMOOTHING, low=0.0, doc="the fit's weight of the curvature energy"),
          "residual_flexibility": Key("boolean", False, doc="contacts see the dropped modes' static compliance")}
CONTOUR = {
    "point": {"kind": _KIND, **FRAME,
              "residual_flexibility": Key("boolean", False, doc="at a 'node' of a flexible body: contacts see the "
                                                                 "dropped modes' static compliance of the node")},
    "sphere": {"kind": _KIND, **FRAME, "radius": _length(low=0.0, strict=True),
               "residual_flexibility": Key("boolean", False, doc="as for a point")},
    "plane": {"kind": _KIND, **FRAME, "normal": _vector((0.0, 0.0, 1.0)),
              "size": _length(1.0, strict=True)},
    "2s": {"kind": _KIND, "body": FRAME["body"],
           "nodes": Key("special", doc="a node-group name or the node matrix O"),
           "extra_rows": Key("integer", 0, low=0),
           "degree": Key("special", 3, doc="an integer >= 1 or a pair [eta, xi]"),
           "closed": Key("special", False, doc="true/false or a pair [eta, xi]"),
           "method": _NEUTRAL["method"],
           "outward": Key("special", None, doc="+1 or -1; found from the body when absent"),
           "control_points": Key("special", None, doc="an integer >= 2 or a pair [eta, xi]: a fitted patch's "
                                                      "distinct control points"),
           "smoothing": Key("number", SMOOTHING, low=0.0, doc="a fitted patch's thin-plate weight"),
           "residual_flexibility": _CURVE["residual_flexibility"]},
    "1s": _CURVE,
    "band": {**_CURVE, "width": _length(low=0.0, strict=True), "offset": _length(0.0, low=None)},
    "cylinder": {**_CURVE, "radius": _length(low=0.0, strict=True)},
    "edge": _CURVE,
}
FACE_KINDS = ("2s", "1s")      # contour1 kinds that make a face contact (contact.face.FaceContact)
CONTOUR1_KINDS = ("point", "sphere") + FACE_KINDS
CONTOUR2_KINDS = ("2s", "1s", "band", "cylinder", "edge", "plane", "sphere")
LAW_DEFAULTS = {"coulomb": {"e": 0.0}}                   # scene defaults where the law class has none


def law_keys(name: str) -> dict:
    """{parameter: Key} of the law registered as ``name``: its dataclass fields of type
    float, with the class's ``units`` and its defaults (or :data:`LAW_DEFAULTS`)."""
    return _parameter_keys(LAWS[name], LAW_DEFAULTS.get(name, {}))


def friction_keys(name: str) -> dict:
    """{parameter: Key} of the optional friction of law ``name``: those of
    :class:`contact.RegularizedCoulombFriction` for a single-valued law, else none."""
    if getattr(LAWS[name], "kind", None) != "single-valued":
        return {}
    return _parameter_keys(RegularizedCoulombFriction, {})


def _parameter_keys(cls, defaults: dict) -> dict:
    units = getattr(cls, "units", {})
    keys = {}
    for f in dataclasses.fields(cls):
        if f.init and f.type in ("float", float):
            default = f.default if f.default is not dataclasses.MISSING else REQUIRED
            keys[f.name] = Key("number", defaults.get(f.name, default), units.get(f.name, ""))
    return keys


# --- [outputs] ----------------------------------------------------------------------------------

QUANTITIES = ("position", "velocity", "displacement", "angular_velocity", "q_f")
QUANTITY_UNITS = {"position": "m", "velocity": "m/s", "displacement": "m", "angular_velocity": "rad/s"}
BODY_QUANTITIES = ("angular_velocity", "q_f")          # of the body: no node or point
FLEXIBLE_QUANTITIES = ("displacement", "q_f")
COMPONENTS = ("x", "y", "z")
OUTPUT = {**FRAME, "quantity": Key("choice", "position", choices=QUANTITIES),
          "component": Key("choice", choices=COMPONENTS)}
