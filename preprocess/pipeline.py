"""The preprocessing pipeline: mesh -> FE model -> modes -> :class:`BodyData`.

``build_body`` turns a mesh (in the units of its source) and a material into the
body data of thesis Sec. 4.2.1 in SI units; ``mesh_source`` resolves the INPUT of
``ffrmbs preprocess``: a mesh file or a built-in geometry (``box:LX,LY,LZ``,
``stepped-beam``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, ModelError
from preprocess import fe, geometry, limits, modes, units as unitsys
from preprocess.body import BodyData
from preprocess.inputfiles import regular_file
from preprocess.mesh import Mesh, check_meshing_options, read_mesh

BUILTINS = ("box:LX,LY,LZ", "stepped-beam")


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


def check_mesh_options(spec: str, order=None, mesh_size=None):
    """The checks of :func:`mesh_source` on its options, before anything is read or
    meshed: a ModelError for a ``mesh_size`` that is not positive and finite, and for an
    ``order`` or a ``mesh_size`` given for a mesh file
    (:func:`~preprocess.mesh.check_meshing_options`); an InputFileError for a file that
    is missing or not a regular file (:func:`~preprocess.inputfiles.regular_file`)."""
    if mesh_size is not None:
        fe.check_positive("mesh size", mesh_size)
    if not (spec.startswith("box:") or spec == "stepped-beam"):
        check_meshing_options(regular_file(spec), order, mesh_size)


def mesh_source(spec: str, order=None, mesh_size=None, check_limits=True, announce=None) -> Mesh:
    """The mesh named by ``spec``: a file path, ``box:LX,LY,LZ`` or ``stepped-beam``.

    Built-in sizes and ``mesh_size`` are in the units of the run (m for SI, mm for SI(mm));
    ``mesh_size`` must be positive and finite (ModelError) or None (a default), and None
    for a mesh file. ``order``: 1 (tet4) or 2 (tet10) for a built-in geometry or a
    ``.geo`` file, None meaning 2; None for a mesh file, which keeps its own order
    (:func:`~preprocess.mesh.read_mesh`). ``check_limits``: a mesh estimated over the
    limits of :mod:`preprocess.limits` is a ModelError before meshing. ``announce``: called
    (no arguments) once the options pass :func:`check_mesh_options`, before anything is
    read or meshed, so a caller reporting progress says nothing for a refused option.
    """
    check_mesh_options(spec, order, mesh_size)
    if announce is not None:
        announce()
    if spec.startswith("box:"):
        try:
            lx, ly, lz = (float(v) for v in spec[4:].split(","))
        except ValueError:
            raise ModelError(f"built-in box needs three lengths, e.g. box:1,1,5 — got {spec!r}") from None
        return geometry.box(lx, ly, lz, min(lx, ly, lz) / 2 if mesh_size is None else mesh_size,
                            2 if order is None else order, check_limits=check_limits)
    if spec == "stepped-beam":
        return geometry.stepped_beam(5.0 if mesh_size is None else mesh_size, 2 if order is None else order,
                                     check_limits=check_limits)
    return read_mesh(Path(spec), order, mesh_size, check_limits)


def build_body(mesh: Mesh, material: Material, n_modes: int, clamp: str | None = None,
               units: str = "si", params: dict | None = None, log=None, progress=None,
               check_limits: bool = True) -> BodyData:
    """Assemble K and the lumped masses, compute ``n_modes`` modes, return SI body data.

    ``clamp`` names a node group to clamp (thesis Sec. 2.4.4 (a)); None gives
    free-free modes with the rigid-body modes removed (b). ``log(msg)`` receives
    progress lines with timings; ``progress(label)`` is called as each long step begins
    ("assembling K", "computing modes"), e.g. a stage bar's ``stage`` (ffrmbs_app.progress).
    ``check_limits``: a mesh whose assembly and modes are estimated over the limits of
    :mod:`preprocess.limits` is a ModelError before assembly.
    """
    log = log or (lambda msg: None)
    progress = progress or (lambda label: None)
    check_n_modes(n_modes)
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
    log(f"assembled K ({K.nnz} nonzeros) and lumped masses in {time.perf_counter() - t0:.2f} s")

    progress("computing modes")
    t0 = time.perf_counter()
    if clamped is not None:
        eig, phi = modes.clamped_modes(K, masses, n_modes, clamped)
    else:
        eig, phi = modes.free_modes(K, masses, mesh_si.points, n_modes)
    log(f"computed {len(eig)} {'clamped' if clamped is not None else 'free-free'} modes "
        f"in {time.perf_counter() - t0:.2f} s")

    all_params = dict(params or {})
    all_params.update(n_modes=int(n_modes), clamp=clamp, free=clamp is None, units_in=units,
                      element_order=mesh.order, n_elements=mesh.n_elements)
    return BodyData(
        u0=mesh_si.points, phi=phi, masses=masses, stiffness=K, eigenvalues=eig,
        node_groups={k: np.asarray(v, dtype=np.int64) for k, v in mesh.node_groups.items()},
        surface_triangles=mesh.surface_triangles(),
        material=dict(density=mat.density, young=mat.young, poisson=mat.poisson),
        params=all_params,
    )


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
