"""Akantu (EPFL LSMS, ``pip install akantu``) as a peer FE assembler; optional.

:func:`assemble` hands a tet4 / tet10 mesh to Akantu and returns Akantu's OWN
stiffness matrix and lumped node masses, renumbered to our conventions:

* node order: the caller's ``points`` rows; tet10 element order VTK/meshio
  (corners 0..3, then mid-edge nodes of edges (0,1), (1,2), (0,2), (0,3), (1,3),
  (2,3), as :data:`preprocess.mesh.TET10_EDGES`);
* DOF ``3*node + direction``.

Route: the mesh is written as a gmsh 2.2 ``.msh`` file with meshio (which converts
the tet10 node order to gmsh's) and a material file
``material elastic [ name = steel  rho = ..  E = ..  nu = .. ]`` into a temporary
directory; ``akantu.parseInput`` reads the material, ``akantu.Mesh(3).read`` the
mesh, and a ``SolidMechanicsModel`` initialized for a static analysis assembles
``K`` (``assembleStiffnessMatrix``, converted with ``akantu.AkantuSparseMatrix``,
which mirrors Akantu's stored upper triangle) and the lumped mass
(``assembleMassLumped``; ``getMass()`` is (N, 3) with equal columns).

Akantu's lumping is not ours for tet10: Akantu gives each element's corners 1/32
and mid-edge nodes 7/48 of the element mass (1/8 and 7/8 in total), our HRZ gives
1/36 and 4/27 (1/9 and 8/9). For tet4 both give ρV/4 per corner.

Checks made on every call (a failure raises :class:`RuntimeError`, since it would
mean the adapter, not the caller, is wrong): Akantu read the same nodes (matched
by coordinates if it renumbered them) and the same elements; K is symmetric; the
six rigid-body motions lie in K's null space (this also checks the DOF
numbering); the three mass columns agree and the masses sum to ρV.

The mesh and material hand-over and these node and mass checks live in
:func:`build_model`, shared with :mod:`validation.peers.akantu_dynamics` (explicit
dynamics on the same Akantu model).

Akantu keeps its parsed input in a process-wide parser; each model is built right
after parsing its own material file, so calls with different materials do not
interfere. Not thread-safe.

Lifetimes (found with akantu 5.0.7): a ``SolidMechanicsModel`` does not keep its
``Mesh`` alive (using or deleting the model after the mesh is gone crashes the
process), so :func:`build_model` ties the mesh's lifetime to the model's; the
arrays ``getDisplacement()``, ``getMass()``, ... are numpy views of the model's
memory that do not keep the model alive: copy what must outlive it.
"""

from __future__ import annotations

import tempfile
import weakref
from pathlib import Path
from typing import NamedTuple

import numpy as np

from preprocess.modes import rigid_body_modes

__all__ = ["available", "assemble", "check_mesh", "build_model", "AkantuModel"]

_TET_TYPES = {4: ("tetra", "_tetrahedron_4"), 10: ("tetra10", "_tetrahedron_10")}


def available() -> bool:
    """True when ``import akantu`` works on this machine."""
    try:
        import akantu  # noqa: F401
    except Exception:  # ImportError, or a broken shared library / init failure
        return False
    return True


def _volume(points, tets):
    """Volume of the (possibly curved) tet4/tet10 mesh, by a rule exact for det J."""
    from preprocess.fe import shape_functions, tet_quadrature

    order = 1 if tets.shape[1] == 4 else 2
    pts, w = tet_quadrature(3 * (order - 1))
    _, dN = shape_functions(order, pts)
    J = np.einsum("eni,qnj->eqij", points[tets], dN)
    return float(np.einsum("q,eq->", w, np.linalg.det(J)))


def _node_map(aka_nodes, points):
    """``perm`` with ``aka_nodes[perm[i]] == points[i]`` (identity when Akantu kept the order)."""
    scale = max(float(np.ptp(points, axis=0).max()), 1.0e-300)
    tol = 1.0e-9 * scale
    if aka_nodes.shape == points.shape and np.abs(aka_nodes - points).max() <= tol:
        return np.arange(len(points))
    if aka_nodes.shape != points.shape:
        raise RuntimeError(f"Akantu read {len(aka_nodes)} nodes, the mesh has {len(points)}")
    from scipy.spatial import cKDTree

    dist, perm = cKDTree(aka_nodes).query(points)
    if dist.max() > tol or len(np.unique(perm)) != len(points):
        raise RuntimeError("cannot match Akantu's nodes to the mesh's nodes by coordinates")
    return perm


def check_mesh(points, tets, density, young, poisson):
    """Validated copies ``(points (N, 3) float, tets (E, 4|10) int64)`` of a mesh and material.

    Raises ValueError on malformed input: wrong shapes, node indices outside
    ``points``, or a material outside ρ > 0, E > 0, -1 < ν < 0.5.
    """
    points = np.ascontiguousarray(points, dtype=float)
    tets = np.ascontiguousarray(tets, dtype=np.int64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), not {points.shape}")
    if not np.all(np.isfinite(points)):
        raise ValueError("points must be finite")
    if tets.ndim != 2 or tets.shape[1] not in _TET_TYPES or len(tets) == 0:
        raise ValueError(f"tets must have shape (E, 4) or (E, 10) with E > 0, not {tets.shape}")
    if tets.min() < 0 or tets.max() >= len(points):
        raise ValueError("tets refer to nodes outside points")
    if not (density > 0 and young > 0 and -1.0 < poisson < 0.5):
        raise ValueError(f"need ρ > 0, E > 0, -1 < ν < 0.5; got {density}, {young}, {poisson}")
    return points, tets


class AkantuModel(NamedTuple):
    """An initialized Akantu model of a caller's mesh (see :func:`build_model`)."""

    model: object
    """``akantu.SolidMechanicsModel``; its node arrays are in Akantu's node order."""
    perm: np.ndarray
    """(N,) int: the caller's node ``i`` is Akantu's node ``perm[i]``."""
    masses: np.ndarray
    """(N,) lumped node masses [kg for SI input] in the CALLER's node order."""


def _keep_alive(mesh):
    """Weakref-finalizer callback holding ``mesh`` until its model is destroyed."""


def build_model(points, tets, density, young, poisson, analysis_method):
    """An Akantu ``SolidMechanicsModel`` of a tet mesh, initialized for ``analysis_method``.

    The route of the module docstring: gmsh 2.2 mesh and material file into a
    temporary directory, ``akantu.parseInput``, ``Mesh(3).read``, then
    ``SolidMechanicsModel(mesh).initFull(_analysis_method=analysis_method)`` and
    ``assembleMassLumped``. The mesh stays alive as long as the model.

    Parameters
    ----------
    points, tets, density, young, poisson : as :func:`assemble` (checked with
        :func:`check_mesh`).
    analysis_method : an Akantu analysis method, e.g. ``akantu._static`` or
        ``akantu._explicit_lumped_mass``.

    Returns
    -------
    :class:`AkantuModel` ``(model, perm, masses)``.

    Raises ImportError when akantu is not installed, ValueError on malformed input,
    RuntimeError when Akantu read other nodes or elements than given, or its lumped
    masses are not equal per direction or do not sum to ρV.
    """
    import akantu as aka
    import meshio

    points, tets = check_mesh(points, tets, density, young, poisson)
    meshio_type, aka_type_name = _TET_TYPES[tets.shape[1]]
    aka_type = getattr(aka, aka_type_name)
    n = len(points)

    with tempfile.TemporaryDirectory(prefix="akantu_fe_") as tmp:
        msh = Path(tmp) / "mesh.msh"
        material = Path(tmp) / "material.dat"
        ones = np.ones(len(tets), dtype=np.int32)
        meshio.write(
            str(msh),
            meshio.Mesh(points, [(meshio_type, tets)],
                        cell_data={"gmsh:physical": [ones], "gmsh:geometrical": [ones]}),
            file_format="gmsh22", binary=False, float_fmt=".17g")
        material.write_text(
            "material elastic [\n"
            "    name = steel\n"
            f"    rho = {float(density):.17g}\n"
            f"    E = {float(young):.17g}\n"
            f"    nu = {float(poisson):.17g}\n"
            "]\n")
        aka.parseInput(str(material))
        mesh = aka.Mesh(3)
        mesh.read(str(msh))

    if mesh.getNbElement(type=aka_type) != len(tets):
        raise RuntimeError(f"Akantu read {mesh.getNbElement(type=aka_type)} elements, "
                           f"the mesh has {len(tets)}")
    perm = _node_map(np.array(mesh.getNodes(), dtype=float), points)
    inv = np.empty(n, dtype=np.int64)
    inv[perm] = np.arange(n)
    conn = inv[np.array(mesh.getConnectivity(aka_type), dtype=np.int64)]
    ours, theirs = np.sort(tets, axis=1), np.sort(conn, axis=1)
    if not np.array_equal(ours[np.lexsort(ours.T[::-1])], theirs[np.lexsort(theirs.T[::-1])]):
        raise RuntimeError("Akantu's elements are not the mesh's elements")

    model = aka.SolidMechanicsModel(mesh)
    weakref.finalize(model, _keep_alive, mesh).atexit = False
    model.initFull(_analysis_method=analysis_method)
    model.assembleMassLumped()
    mass3 = np.array(model.getMass(), dtype=float)
    if mass3.shape != (n, 3):
        raise RuntimeError(f"Akantu returned masses {mass3.shape} for {n} nodes")
    if np.abs(mass3 - mass3[:, :1]).max() > 1e-12 * np.abs(mass3).max():
        raise RuntimeError("Akantu's lumped masses differ between directions")
    masses = mass3[perm, 0].copy()
    total = density * _volume(points, tets)
    if abs(masses.sum() - total) > 1e-10 * total:
        raise RuntimeError(f"Akantu's masses sum to {masses.sum()}, not ρV = {total}")
    return AkantuModel(model, perm, masses)


def assemble(points, tets, density, young, poisson):
    """Akantu's stiffness K (CSR, (3N, 3N)) and lumped node masses (N,) of a tet mesh.

    Parameters
    ----------
    points : (N, 3) float array of node coordinates.
    tets : (E, 4) tet4 or (E, 10) tet10 connectivity, 0-based, VTK/meshio node order
        (the order of :mod:`preprocess.mesh`), positively oriented.
    density, young, poisson : ρ, E, ν of a linear elastic isotropic material (any
        consistent units; SI gives N/m and kg).

    Returns
    -------
    (K, masses): ``scipy.sparse.csr_matrix`` (3N, 3N) with DOF ``3*node + direction``
    in the caller's node numbering, and ``numpy`` array (N,) of lumped masses.

    Raises ImportError when akantu is not installed, ValueError on malformed input,
    RuntimeError when a consistency check on Akantu's result fails.
    """
    import akantu as aka

    points, tets = check_mesh(points, tets, density, young, poisson)
    n = len(points)
    model, perm, masses = build_model(points, tets, density, young, poisson, aka._static)
    model.assembleStiffnessMatrix()
    K_aka = aka.AkantuSparseMatrix(model.getDOFManager().getMatrix("K")).tocsr()
    del model

    if K_aka.shape != (3 * n, 3 * n):
        raise RuntimeError(f"Akantu returned K {K_aka.shape} for {n} nodes")
    dof = (3 * perm[:, None] + np.arange(3)).ravel()  # our DOF i is Akantu's DOF dof[i]
    K = K_aka[dof][:, dof].tocsr()
    K.sum_duplicates()
    K.sort_indices()

    kmax = abs(K).max()
    if abs(K - K.T).max() > 1e-12 * kmax:
        raise RuntimeError("Akantu's stiffness matrix is not symmetric")
    R = rigid_body_modes(points, np.ones(len(points)))
    if np.abs(K @ R).max() > 1e-8 * kmax * np.abs(R).max():
        raise RuntimeError("rigid-body motions are not in the null space of Akantu's K "
                           "(node or DOF numbering mismatch)")
    return K, masses
