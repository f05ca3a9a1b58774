"""Resource estimates of preprocessing, checked before meshing and before assembly.

A mesh size far below the body's size would make gmsh build ~10¹² elements and exhaust
memory; a mesh file may be too large to assemble and factor. :func:`from_mesh_size`
estimates a mesh from the body's volume and the mesh size, :func:`from_elements` from
a number of tetrahedra, :func:`from_mesh` from the counts of a mesh read; :func:`check`
refuses an estimate over the limits (MAX_NODES nodes, or MEMORY_SHARE of the physical
memory) with one line giving the numbers.

The constants were measured on gmsh 4.15 meshes (Delaunay, ``Mesh.MeshSizeMax`` = h)
of a unit cube, a 1 x 0.2 x 5 slab and the stepped beam, 5 000 to 180 000 tetrahedra:

* tetrahedra per volume: 4.6 to 5.3 · V / h³, 5.9 for the slab at h = 0.1 (two elements
  thick) — TETS_PER_H3 = 6; fewer when the size at the geometry's points exceeds h;
* nodes per tetrahedron: 0.18 to 0.24 (tet4), 1.63 to 1.84 (tet10; the most for the
  thin slab); taken as 0.21 and 1.85, which with TETS_PER_H3 bounds the counted nodes;
* nonzeros of K per node: 113 to 130 (tet4), 224 to 230 (tet10);
* peak memory of assembly (the element matrices as COO triplets, then the CSR copy):
  7.5 kB per tet4, 48 kB per tet10, i.e. ≈ 2.2 · (3n)² · 24 B for n nodes per element;
* the shift-invert factor of K − σM (SuperLU, COLAMD order, as ARPACK's eigsh uses) has
  about FACTOR_FRONT · (3N) · (3W) nonzeros, W = N s / L the nodes of one layer across the
  body's longest extent L, s = (V/N)^⅓ the node spacing — a banded profile; measured
  1.3 to 2.3 times 9 N W (cube, 1 200 to 14 000 nodes, tet4 and tet10: 1.3 to 1.55;
  stepped beam, 16 000 and 18 000 nodes: 2.0 and 2.3), at 11 to 17 B per nonzero
  (value, index, SuperLU's overhead): FACTOR_BYTES = 16.

The memory estimate is the larger of assembly and eigen solve (K, its CSC copy and the
factor). It is rough — a factor of two either way — and meant to catch sizes that
cannot run, not to plan runs.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from ffrmbs.errors import ModelError

TETS_PER_H3 = 6.0                      # tetrahedra per h³ of volume
NODES_PER_TET = {1: 0.21, 2: 1.85}      # by element order
K_NONZEROS_PER_NODE = {1: 130, 2: 230}  # by element order
NODES_PER_ELEMENT = {1: 4, 2: 10}
ASSEMBLY_BYTES = 2.2 * 24              # per entry of the element matrices, (3n)² per element
FACTOR_FRONT = 2.0                     # factor nonzeros per (3N)(3W), see above
FACTOR_BYTES = 16                      # per factor nonzero
K_BYTES = 2 * 12                       # per K nonzero: CSR and its CSC copy (8 B value, 4 B index)

MAX_NODES = 5_000_000
MEMORY_SHARE = 0.5                     # of the physical memory


def lift(python: str) -> str:
    """The advice that ends a refusal over a limit: the command-line flag and ``python``,
    the Python argument lifting the same limits. One wording for every limit."""
    return f"pass --no-limits ({python} from Python) to run it anyway"


LIFT = lift("check_limits=False")


@dataclass(frozen=True)
class Estimate:
    """An estimated mesh: ``n_elements`` tetrahedra of ``order`` (1 tet4, 2 tet10),
    ``n_nodes`` nodes, ``memory`` [bytes] to assemble K and compute the modes."""

    n_elements: float
    n_nodes: float
    order: int
    memory: float


def memory_bytes(n_nodes: float, n_elements: float, order: int, volume: float, extent: float) -> float:
    """Peak memory [bytes] of assembly or eigen solve, whichever is larger, for a body of
    ``volume`` whose longest extent is ``extent`` (any one length unit; module docstring)."""
    assembly = n_elements * (3 * NODES_PER_ELEMENT[order]) ** 2 * ASSEMBLY_BYTES
    spacing = (volume / n_nodes) ** (1 / 3) if n_nodes > 0 else 0.0
    layer = n_nodes * spacing / extent if extent > 0 else 0.0
    factor = FACTOR_FRONT * (3 * n_nodes) * (3 * layer)
    return max(assembly, K_NONZEROS_PER_NODE[order] * n_nodes * K_BYTES + factor * FACTOR_BYTES)


def from_mesh(n_nodes: float, n_elements: float, order: int, volume: float, extent: float) -> Estimate:
    """The estimate for a mesh whose counts are known, of ``volume`` and longest ``extent``."""
    return Estimate(n_elements, n_nodes, order, memory_bytes(n_nodes, n_elements, order, volume, extent))


def from_elements(n_elements: float, order: int, volume: float, extent: float) -> Estimate:
    """The estimate for a mesh of ``n_elements`` tetrahedra (NODES_PER_TET nodes each)."""
    return from_mesh(NODES_PER_TET[order] * n_elements, n_elements, order, volume, extent)


def from_mesh_size(volume: float, extent: float, mesh_size: float, order: int) -> Estimate:
    """The estimate for meshing ``volume`` (longest ``extent``) with element size
    ``mesh_size`` (one length unit): TETS_PER_H3 · V / h³ tetrahedra (none for no
    volume, infinitely many for no size)."""
    n_elements = 0.0 if volume <= 0 else TETS_PER_H3 * volume / mesh_size ** 3 if mesh_size > 0 else math.inf
    return from_elements(n_elements, order, volume, extent)


def physical_memory() -> float | None:
    """The machine's physical memory [bytes], or None where the system does not say."""
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def check(estimate: Estimate, what: str) -> None:
    """ModelError if ``estimate`` has more than MAX_NODES nodes or needs more than
    MEMORY_SHARE of the physical memory; ``what`` names the mesh and how it was estimated
    ("<builtin box> meshed at element size 0.001 (volume 1)"). The message gives the estimate, the limit and how to lift it."""
    memory = physical_memory()
    over_memory = memory is not None and estimate.memory > MEMORY_SHARE * memory
    if estimate.n_nodes <= MAX_NODES and not over_memory:
        return
    element = "tet4" if estimate.order == 1 else "tet10"
    limit = f"{MAX_NODES:.0e} nodes" + (
        f", {MEMORY_SHARE:.0%} of the {memory / 1e9:.3g} GB of physical memory" if memory is not None else "")
    raise ModelError(f"{what}: about {estimate.n_elements:.2g} {element} elements, {estimate.n_nodes:.2g} nodes "
                     f"and {estimate.memory / 1e9:.2g} GB of memory to assemble K and compute the modes, over "
                     f"the limit ({limit}); {LIFT}")
