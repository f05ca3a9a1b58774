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

from ffrmbs.errors import ModelError
from preprocess import fe, geometry, modes, units as unitsys
from preprocess.body import BodyData
from preprocess.mesh import Mesh, read_mesh

BUILTINS = ("box:LX,LY,LZ", "stepped-beam")


@dataclass
class Material:
    """Linear elastic isotropic material in the units of its source.

    density [kg/m³ or t/mm³], young [Pa or N/mm²], poisson [-].
    """

    density: float
    young: float
    poisson: float

    def to_si(self, units: str) -> "Material":
        f = unitsys.unit_system(units)
        return Material(self.density * f.density, self.young * f.stress, self.poisson)


def mesh_source(spec: str, order=2, mesh_size=None) -> Mesh:
    """The mesh named by ``spec``: a file path, ``box:LX,LY,LZ`` or ``stepped-beam``.

    Built-in sizes and ``mesh_size`` are in the units of the run (m for SI, mm for SI(mm)).
    """
    if spec.startswith("box:"):
        try:
            lx, ly, lz = (float(v) for v in spec[4:].split(","))
        except ValueError:
            raise ModelError(f"built-in box needs three lengths, e.g. box:1,1,5 — got {spec!r}") from None
        return geometry.box(lx, ly, lz, mesh_size if mesh_size else min(lx, ly, lz) / 2, order)
    if spec == "stepped-beam":
        return geometry.stepped_beam(mesh_size if mesh_size else 5.0, order)
    return read_mesh(Path(spec), order, mesh_size)


def build_body(mesh: Mesh, material: Material, n_modes: int, clamp: str | None = None,
               units: str = "si", params: dict | None = None, log=None, progress=None) -> BodyData:
    """Assemble K and the lumped masses, compute ``n_modes`` modes, return SI body data.

    ``clamp`` names a node group to clamp (thesis Sec. 2.4.4 (a)); None gives
    free-free modes with the rigid-body modes removed (b). ``log(msg)`` receives
    progress lines with timings; ``progress(label)`` is called as each long step begins
    ("assembling K", "computing modes"), e.g. a stage bar's ``stage`` (ffrmbs.progress).
    """
    log = log or (lambda msg: None)
    progress = progress or (lambda label: None)
    if n_modes < 1:
        raise ModelError(f"the number of modes must be at least 1, not {n_modes}")
    f = unitsys.unit_system(units)
    mesh_si = mesh.scaled(f.length)
    mat = material.to_si(units)
    clamped = mesh.group(clamp) if clamp is not None else None

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


def mesh_statistics(mesh: Mesh) -> str:
    """Report Table 1 style line: nodes, surface nodes, elements, element type, order."""
    ext = np.ptp(mesh.points, axis=0)
    return ("nodes  surface nodes  elements  element type  dimensions  order\n"
            f"{mesh.n_nodes:5d}  {len(mesh.surface_nodes()):13d}  {mesh.n_elements:8d}  "
            f"{'tet4' if mesh.order == 1 else 'tet10':>12}  "
            f"{'x'.join(f'{v:g}' for v in ext):>10}  {mesh.order:5d}")
