"""Tetrahedral meshes: canonical node order, surface, connectivity.

A :class:`Mesh` holds linear (tet4) or quadratic (tet10) tetrahedra in one
canonical local order — the VTK/meshio order, which is also Abaqus C3D10's::

    vertices 0, 1, 2, 3 (positive volume), then mid-edge nodes of the edges
    (0,1), (1,2), (0,2), (0,3), (1,3), (2,3)

Input orderings differ between tools (gmsh swaps the last two mid-edge nodes,
:data:`GMSH_TET10`). Elements meshed or read by gmsh are brought into this order by
that known permutation, so mid-edge nodes placed on a curved surface (gmsh's
second-order meshing, :mod:`preprocess.geometry`) keep their edges however far they
lie from the straight edge's midpoint; tet10 elements from other tools are sorted
geometrically: each mid-edge node is matched to the edge whose midpoint it lies
closest to. This accepts any tool's convention and catches corrupt connectivity.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ffrmbs.errors import InputFileError

#: mid-edge node k (local index 4 + k) sits on edge TET10_EDGES[k]
TET10_EDGES = np.array([(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)])

#: gmsh's tet10 (element type 11) -> canonical order: gmsh's mid-edge nodes 8 and 9 sit
#: on the edges (2,3) and (1,3), the canonical ones on (1,3) and (2,3)
GMSH_TET10 = np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8])

#: canonical tet10 with corners 1 and 2 swapped (orientation reversed), still canonical:
#: the mid-edge nodes of (0,1) <-> (0,2) and (1,3) <-> (2,3) swap with them
_TET10_FLIP = np.array([0, 2, 1, 3, 6, 5, 4, 7, 9, 8])

#: outward faces (corner triples) of a positively oriented tetrahedron, face i opposite vertex i
TET_FACES = np.array([(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)])


def _edge_slot(a, b):
    """Local mid-node index (4..9) of the edge between local corners a and b."""
    for k, (i, j) in enumerate(TET10_EDGES):
        if {i, j} == {a, b}:
            return 4 + k
    raise ValueError((a, b))


#: outward quadratic faces: corners, then mid-nodes of edges (c0,c1), (c1,c2), (c2,c0)
TET10_FACES = np.array([
    [*f, _edge_slot(f[0], f[1]), _edge_slot(f[1], f[2]), _edge_slot(f[2], f[0])]
    for f in TET_FACES
])


@dataclass
class Mesh:
    """A tetrahedral mesh in canonical order.

    Attributes
    ----------
    points : (N, 3) float array, node coordinates (units of the source; SI after
        :meth:`scaled`).
    tets : (E, 4) or (E, 10) int64 array, 0-based, canonical order (module docstring).
    node_groups : dict name -> sorted int64 node indices.
    source : str, where the mesh came from (for messages).
    """

    points: np.ndarray
    tets: np.ndarray
    node_groups: dict = field(default_factory=dict)
    source: str = "<memory>"

    @property
    def order(self) -> int:
        """Element order: 1 for tet4, 2 for tet10."""
        return 1 if self.tets.shape[1] == 4 else 2

    @property
    def n_nodes(self) -> int:
        return self.points.shape[0]

    @property
    def n_elements(self) -> int:
        return self.tets.shape[0]

    def scaled(self, factor: float) -> "Mesh":
        """A copy with coordinates multiplied by ``factor`` (unit conversion)."""
        return Mesh(self.points * factor, self.tets, dict(self.node_groups), self.source)

    def group(self, name: str) -> np.ndarray:
        """Node indices of group ``name``; InputFileError naming the known groups if absent."""
        try:
            return self.node_groups[name]
        except KeyError:
            known = ", ".join(sorted(self.node_groups)) or "none"
            raise InputFileError(self.source, None,
                                 f"unknown node group {name!r}; known groups: {known}") from None

    def surface_triangles(self) -> np.ndarray:
        """Outward surface faces: faces that belong to exactly one element.

        Returns (T, 3) corner triples for tet4, (T, 6) for tet10 (corners, then the
        mid-edge nodes of edges (c0,c1), (c1,c2), (c2,c0)), counter-clockwise seen
        from outside.
        """
        faces = TET_FACES if self.order == 1 else TET10_FACES
        all_faces = self.tets[:, faces].reshape(-1, faces.shape[1])
        key = np.sort(all_faces[:, :3], axis=1)
        _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        return all_faces[counts[inverse.ravel()] == 1]

    def surface_nodes(self) -> np.ndarray:
        """Sorted indices of all nodes on the surface."""
        return np.unique(self.surface_triangles())

    def parts(self) -> tuple[int, np.ndarray]:
        """Connected parts: (number of parts, part label (N,) of every node, 0-based).

        Two nodes are in one part when a chain of elements, each sharing a node with
        the next, joins them.
        """
        n_per = self.tets.shape[1]
        graph = sp.coo_matrix((np.ones(self.tets.size), (np.repeat(self.tets[:, 0], n_per), self.tets.ravel())),
                              shape=(self.n_nodes, self.n_nodes))
        return connected_components(graph, directed=False)

    def element_volumes(self) -> np.ndarray:
        """Volumes of the straight-sided tetrahedra spanned by the corners, shape (E,)."""
        p = self.points[self.tets[:, :4]]
        return np.linalg.det(p[:, 1:] - p[:, :1]) / 6.0


def canonical_mesh(points, tets, node_groups, source, mid_nodes_in_order=False) -> Mesh:
    """Build a :class:`Mesh` from raw arrays in any tet4/tet10 node convention.

    Drops nodes not used by any tetrahedron (renumbering groups accordingly),
    orients every element positively and sorts tet10 mid-edge nodes into the
    canonical order — geometrically, or, with ``mid_nodes_in_order``, taking them as
    already in the canonical order (e.g. gmsh's permuted by :data:`GMSH_TET10`).
    Raises InputFileError for degenerate elements or tet10 connectivity whose mid-edge
    nodes do not match the edges (geometric sorting only).
    """
    points = np.asarray(points, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)
    if tets.ndim != 2 or tets.shape[1] not in (4, 10) or len(tets) == 0:
        raise InputFileError(source, None, "no tetrahedra (tet4 or tet10) in the mesh")
    if not np.all(np.isfinite(points)):
        raise InputFileError(source, None, "node coordinates contain NaN or inf")
    used = np.unique(tets)
    new_index = -np.ones(len(points), dtype=np.int64)
    new_index[used] = np.arange(len(used))
    tets = new_index[tets]
    points = points[used]
    groups = {}
    for name, nodes in node_groups.items():
        mapped = new_index[np.asarray(nodes, dtype=np.int64)]
        groups[name] = np.unique(mapped[mapped >= 0])

    corners = points[tets[:, :4]]
    vol6 = np.linalg.det(corners[:, 1:] - corners[:, :1])
    scale = np.ptp(points, axis=0).max() ** 3
    if np.any(np.abs(vol6) <= 1e-14 * scale):
        bad = int(np.argmax(np.abs(vol6) <= 1e-14 * scale))
        raise InputFileError(source, None, f"degenerate tetrahedron (zero volume), element {bad + 1}")
    flip = vol6 < 0
    if tets.shape[1] == 10 and mid_nodes_in_order:
        tets[flip] = tets[flip][:, _TET10_FLIP]
    else:
        tets[flip, 1], tets[flip, 2] = tets[flip, 2].copy(), tets[flip, 1].copy()
        if tets.shape[1] == 10:
            tets = _sort_mid_nodes(points, tets, source)
    return Mesh(points, tets, groups, str(source))


def _sort_mid_nodes(points, tets, source):
    """Put the six mid-edge nodes of each tet10 on their edges (canonical order)."""
    corners = points[tets[:, :4]]
    edge_mid = 0.5 * (corners[:, TET10_EDGES[:, 0]] + corners[:, TET10_EDGES[:, 1]])  # (E,6,3)
    mids = points[tets[:, 4:]]  # (E,6,3)
    dist = np.linalg.norm(mids[:, :, None, :] - edge_mid[:, None, :, :], axis=-1)  # node x edge
    slot = np.argmin(dist, axis=2)  # edge of each given mid node
    ok = np.all(np.sort(slot, axis=1) == np.arange(6), axis=1)
    if not np.all(ok):
        bad = int(np.argmin(ok))
        raise InputFileError(source, None, f"tet10 element {bad + 1}: mid-edge nodes do not lie on distinct edges")
    out = tets.copy()
    rows = np.arange(len(tets))[:, None]
    out[rows, 4 + slot] = tets[:, 4:]
    return out
