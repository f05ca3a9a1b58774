"""The preprocessing pipeline: mesh -> FE model -> modes -> :class:`BodyData`.

``build_body`` turns a mesh (in the units of its source) and a material into the
body data of thesis Sec. 4.2.1 in SI units; ``mesh_source`` resolves the INPUT of
``ffrmbs preprocess``: a mesh, ``.geo``, STEP or IGES file or a built-in geometry (:data:`BUILTINS`: ``box``,
``cylinder``, ``spherical-cap``, ``grooved-block`` with their dimensions after a
colon, ``stepped-beam``), the box also structured (``--structured NX,NY,NZ``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, ModelError
from preprocess import fe, geometry, limits, modes, units as unitsys
from preprocess.body import BodyData
from preprocess.geometric import geometric_stiffness as geometric_stiffness_of
from preprocess.inputfiles import regular_file
from preprocess.mesh import Mesh
from preprocess.mesh_files import check_meshing_options, read_mesh

#: built-in geometries with dimensions: name -> (dimension names, mesher of :mod:`preprocess.geometry`,
#: its check of the dimensions beyond each being positive (or None), an example spec)
_SHAPES = {
    "box": (("LX", "LY", "LZ"), geometry.box, None, "box:1,1,5"),
    "cylinder": (("R", "L"), geometry.cylinder, None, "cylinder:0.05,0.3"),
    "spherical-cap": (("R", "H"), geometry.spherical_cap, geometry.check_cap_dimensions, "spherical-cap:0.1,0.03"),
    "grooved-block": (("LX", "LY", "LZ", "R"), geometry.grooved_block, geometry.check_groove_dimensions,
                      "grooved-block:0.06,0.12,0.06,0.04"),
}
#: the built-in geometries ``mesh_source`` takes, as the user types them
BUILTINS = tuple(f"{name}:{','.join(shape[0])}" for name, shape in _SHAPES.items()) + ("stepped-beam",)
_COUNTS = {2: "two", 3: "three", 4: "four"}


@dataclass
class Material:
    """Linear elastic isotropic material in the units of its source.

    density [kg/m³ or t/mm³], young [Pa or N/mm²], poisson [-]; density and young
    positive and finite, poisson in (-1, 0.5), else a ModelError on construction.
    """

    density: float
    young: float
    poisson: float

    def __post_init__(self):
        fe.check_positive("density", self.density)
        fe.lame(self.young, self.poisson)

    def to_si(self, units: str) -> "Material":
        f = unitsys.unit_system(units)
        return Material(self.density * f.density, self.young * f.stress, self.poisson)


def builtin_shape(spec: str):
    """``(mesher, dimensions)`` of a built-in geometry ``NAME:D1,D2,...`` of :data:`BUILTINS`
    (``stepped-beam``: no dimensions), None when ``spec`` names none (a file path). A
    ModelError for a wrong count of dimensions, one that is not a positive finite
    number, or dimensions that make no such body (a cap's height >= 2 radius, a groove's
    radius >= min(ly/2, lz))."""
    if spec == "stepped-beam":
        return geometry.stepped_beam, ()
    name, colon, values = spec.partition(":")
    if not colon or name not in _SHAPES:
        return None
    names, mesher, check, example = _SHAPES[name]
    try:
        dims = tuple(float(v) for v in values.split(","))
    except ValueError:
        dims = ()
    if len(dims) != len(names):
        raise ModelError(f"built-in {name} needs {_COUNTS[len(names)]} lengths {','.join(names)}, "
                         f"e.g. {example} — got {spec!r}")
    for dim, value in zip(names, dims):
        fe.check_positive(f"{name} {dim}", value)
    if check is not None:
        check(*dims)
    return mesher, dims


def structured_divisions(text: str) -> tuple:
    """The divisions (nx, ny, nz) of ``--structured NX,NY,NZ``: three whole numbers >= 1,
    element edges along x, y, z, given as text; a ModelError otherwise."""
    try:
        divisions = tuple(int(v) for v in str(text).split(","))
    except ValueError:
        divisions = ()
    if len(divisions) != 3 or min(divisions) < 1:
        raise ModelError(f"--structured needs three whole numbers >= 1 (element edges along x, y, z), "
                         f"e.g. 10,2,2 — got {text!r}")
    return divisions


def face_boxes(texts) -> dict:
    """{name: (xmin, ymin, zmin, xmax, ymax, zmax)} of ``--group NAME=XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX``
    texts (input units), each naming a node group of the faces inside the box
    (:func:`~preprocess.geometry.mesh_cad_file`); a ModelError for a text not of that
    form, a bound not finite, a minimum above its maximum or a name given twice."""
    boxes = {}
    for text in texts or ():
        name, equals, values = str(text).partition("=")
        name = name.strip()
        try:
            box = tuple(float(v) for v in values.split(","))
        except ValueError:
            box = ()
        if not (equals and name and len(box) == 6 and np.all(np.isfinite(box))):
            raise ModelError(f"--group needs NAME=XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (six finite numbers, input units), "
                             f"e.g. clamp=-1,-1,-1,0.001,1,1 — got {text!r}")
        if any(lo > hi for lo, hi in zip(box[:3], box[3:])):
            raise ModelError(f"--group {name}: each minimum must be at most its maximum, got {text!r}")
        if name in boxes:
            raise ModelError(f"--group {name} is given twice")
        boxes[name] = box
    return boxes


def check_mesh_options(spec: str, order=None, mesh_size=None, structured=None, groups=None):
    """The checks of :func:`mesh_source` on its options, before anything is read or
    meshed: a ModelError for a ``mesh_size`` that is not positive and finite, for a
    built-in geometry's dimensions (:func:`builtin_shape`), for ``structured`` divisions
    that are not three whole numbers >= 1 or given for anything but a ``box:`` or with a
    ``mesh_size``, and for an ``order`` or a ``mesh_size`` given for a mesh file
    (:func:`~preprocess.mesh_files.check_meshing_options`), and for ``groups`` (``--group``
    texts, :func:`face_boxes`) malformed or given for anything but a STEP or IGES file;
    an InputFileError for a file that is missing or not a regular file
    (:func:`~preprocess.inputfiles.regular_file`).
    Returns the divisions (nx, ny, nz), or None."""
    if mesh_size is not None:
        fe.check_positive("mesh size", mesh_size)
    boxes = face_boxes(groups)
    shape = builtin_shape(spec)
    if boxes and shape is not None:
        raise ModelError(f"--group applies to STEP and IGES files, not the built-in {spec}")
    if structured is not None:
        if shape is None or shape[0] is not geometry.box:
            raise ModelError(f"--structured applies to the built-in box:LX,LY,LZ only, not {spec}")
        if mesh_size is not None:
            raise ModelError("--mesh-size does not apply with --structured: the divisions set the elements")
        return structured_divisions(structured)
    if shape is None:
        check_meshing_options(regular_file(spec), order, mesh_size, boxes)
    return None


def mesh_source(spec: str, order=None, mesh_size=None, check_limits=True, announce=None, structured=None,
                units: str = "si", groups=None) -> Mesh:
    """The mesh named by ``spec``: a file path or a built-in geometry of :data:`BUILTINS`
    (``box:LX,LY,LZ``, ``cylinder:R,L``, ``spherical-cap:R,H``, ``grooved-block:LX,LY,LZ,R``,
    ``stepped-beam``; see :mod:`preprocess.geometry`).

    Built-in sizes and ``mesh_size`` are in the units of the run (m for SI, mm for SI(mm));
    ``mesh_size`` must be positive and finite (ModelError) or None — half the smallest
    dimension of a built-in geometry, 5 mm for the stepped beam — and None for a mesh
    file. ``structured`` (text ``"NX,NY,NZ"``, box only, no ``mesh_size``): the
    box meshed structured with that many element edges along x, y, z
    (:func:`~preprocess.geometry.box` ``divisions``), every face a node grid. ``order``:
    1 (tet4) or 2 (tet10) for a built-in geometry or a ``.geo`` file, None meaning 2;
    None for a mesh file, which keeps its own order
    (:func:`~preprocess.mesh_files.read_mesh`). ``check_limits``: a mesh estimated over the
    limits of :mod:`preprocess.limits` is a ModelError before meshing. ``announce``: called
    (no arguments) once the options pass :func:`check_mesh_options`, before anything is
    read or meshed, so a caller reporting progress says nothing for a refused option.
    ``units`` (:mod:`preprocess.units`): a STEP or IGES file is converted from its own
    length unit to the system's (m or mm). ``groups``: ``--group NAME=XMIN,...,ZMAX``
    texts (:func:`face_boxes`, STEP and IGES only), node groups of the faces in each box.
    """
    divisions = check_mesh_options(spec, order, mesh_size, structured, groups)
    length_unit = unitsys.unit_system(units).length_unit
    if announce is not None:
        announce()
    shape = builtin_shape(spec)
    if shape is None:
        return read_mesh(Path(spec), order, mesh_size, check_limits, length_unit, face_boxes(groups))
    mesher, dims = shape
    order = 2 if order is None else order
    if divisions is not None:
        return geometry.box(*dims, None, order, divisions=divisions, check_limits=check_limits)
    if mesher is geometry.stepped_beam:
        return mesher(5.0 if mesh_size is None else mesh_size, order, check_limits=check_limits)
    return mesher(*dims, min(dims) / 2 if mesh_size is None else mesh_size, order, check_limits=check_limits)


def build_body(mesh: Mesh, material: Material, n_modes: int, clamp: str | None = None,
               units: str = "si", params: dict | None = None, log=None, progress=None,
               check_limits: bool = True, geometric_stiffness: bool = False, mass: str = "lumped") -> BodyData:
    """Assemble K and the masses, compute ``n_modes`` modes, return SI body data.

    ``clamp`` names a node group to clamp (thesis Sec. 2.4.4 (a)); None gives
    free-free modes with the rigid-body modes removed (b). ``log(msg)`` receives
    progress lines with timings; ``progress(label)`` is called as each long step begins
    ("assembling K", "computing modes"), e.g. a stage bar's ``stage`` (ffrmbs_app.progress).
    ``check_limits``: a mesh whose assembly and modes are estimated over the limits of
    :mod:`preprocess.limits` is a ModelError before assembly. ``geometric_stiffness``: also
    the modal geometric stiffness of the frame's inertia loads (:mod:`preprocess.geometric`),
    which a rotating body needs for its stiffening.
    ``mass`` (:data:`MASS_KINDS`): "lumped" (default) — the modes and all inertia from the
    lumped node masses; "consistent" — from the consistent mass matrix M_s
    (:func:`preprocess.fe.consistent_mass_matrix`), stored as ``BodyData.mass_matrix`` (the
    lumped masses are kept too); recorded as ``params["mass"]``.
    """
    log = log or (lambda msg: None)
    progress = progress or (lambda label: None)
    check_n_modes(n_modes)
    check_mass_kind(mass)
    if check_limits:
        limits.check(limits.from_mesh(mesh.n_nodes, mesh.n_elements, mesh.order,
                                      float(mesh.element_volumes().sum()), float(np.ptp(mesh.points, axis=0).max())),
                     mesh.source)
    f = unitsys.unit_system(units)
    mesh_si = mesh.scaled(f.length)
    mat = material.to_si(units)
    clamped = mesh.group(clamp) if clamp is not None else None
    check_parts(mesh, clamp)

    progress("assembling K")
    t0 = time.perf_counter()
    K = fe.stiffness_matrix(mesh_si, mat.young, mat.poisson)
    masses = fe.lumped_masses(mesh_si, mat.density)
    M_s = fe.consistent_mass_matrix(mesh_si, mat.density) if mass == "consistent" else None
    log(f"assembled K ({K.nnz} nonzeros) and {mass} masses in {time.perf_counter() - t0:.2f} s")

    progress("computing modes")
    t0 = time.perf_counter()
    if clamped is not None:
        eig, phi = modes.clamped_modes(K, masses if M_s is None else M_s, n_modes, clamped)
    else:
        eig, phi = modes.free_modes(K, masses if M_s is None else M_s, mesh_si.points, n_modes)
    log(f"computed {len(eig)} {'clamped' if clamped is not None else 'free-free'} modes "
        f"in {time.perf_counter() - t0:.2f} s")

    geometric = None
    if geometric_stiffness:
        progress("geometric stiffness")
        geometric = geometric_stiffness_of(mesh_si, K, mat.young, mat.poisson, masses if M_s is None else M_s, phi,
                                           clamped, log=log)

    all_params = dict(params or {})
    all_params.update(n_modes=int(n_modes), clamp=clamp, free=clamp is None, units_in=units,
                      element_order=mesh.order, n_elements=mesh.n_elements, mass=mass)
    return BodyData(
        u0=mesh_si.points, phi=phi, masses=masses, stiffness=K, eigenvalues=eig, mass_matrix=M_s,
        node_groups={k: np.asarray(v, dtype=np.int64) for k, v in mesh.node_groups.items()},
        surface_triangles=mesh.surface_triangles(),
        material=dict(density=mat.density, young=mat.young, poisson=mat.poisson),
        params=all_params, geometric_stiffness=geometric,
    )


#: the masses :func:`build_body` takes
MASS_KINDS = ("lumped", "consistent")


def check_mass_kind(mass) -> None:
    """ModelError unless ``mass`` is one of :data:`MASS_KINDS`."""
    if not (isinstance(mass, str) and mass in MASS_KINDS):
        raise ModelError(f"mass must be 'lumped' or 'consistent', not {mass!r}")


def check_n_modes(n_modes) -> None:
    """ModelError unless ``n_modes`` is a whole number >= 1."""
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ModelError(f"the number of modes must be a whole number >= 1, not {n_modes!r}")


def check_parts(mesh: Mesh, clamp: str | None) -> None:
    """InputFileError naming the mesh's source if a part of it could move as a rigid body.

    Free-free modes need one connected mesh; clamped modes need a node of the clamped
    group ``clamp`` in every part. Checked before K is factored, which would fail as
    "exactly singular" without saying where.
    """
    n_parts, label = mesh.parts()
    if clamp is None:
        if n_parts > 1:
            sizes = np.bincount(label)
            smallest = label == np.argmin(sizes)
            raise InputFileError(mesh.source, None, f"the mesh is not connected: {n_parts} parts; "
                                 f"{_describe_part(mesh, smallest)} shares no node with the largest part "
                                 f"({sizes.max()} nodes), and free-free modes need one body")
        return
    clamped = mesh.group(clamp)
    if clamped.size == 0:
        raise ModelError(f"the clamped node group {clamp!r} is empty")
    loose = np.setdiff1d(np.arange(n_parts), label[clamped])
    if loose.size:
        raise InputFileError(mesh.source, None, f"{_describe_part(mesh, label == loose[0])} holds no node "
                             f"of the clamped group {clamp!r}: it is unconstrained (free to move as a rigid "
                             f"body; the mesh has {n_parts} parts); clamp it too or remove it")


def _describe_part(mesh: Mesh, in_part: np.ndarray, shown: int = 6) -> str:
    """'a part of n nodes (nodes i, j, ..., the first at (x, y, z))', node numbers
    1-based as in u0.dat, the position in the mesh's units."""
    nodes = np.flatnonzero(in_part)
    listed = ", ".join(str(i + 1) for i in nodes[:shown]) + (", …" if nodes.size > shown else "")
    x, y, z = mesh.points[nodes[0]]
    return f"a part of {nodes.size} nodes (nodes {listed}, the first at ({x:g}, {y:g}, {z:g}))"


def mesh_statistics(mesh: Mesh) -> str:
    """Report Table 1 style line: nodes, surface nodes, elements, element type, order."""
    ext = np.ptp(mesh.points, axis=0)
    return ("nodes  surface nodes  elements  element type  dimensions  order\n"
            f"{mesh.n_nodes:5d}  {len(mesh.surface_nodes()):13d}  {mesh.n_elements:8d}  "
            f"{'tet4' if mesh.order == 1 else 'tet10':>12}  "
            f"{'x'.join(f'{v:g}' for v in ext):>10}  {mesh.order:5d}")
