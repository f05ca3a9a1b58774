"""A patch of an FE body's surface: the surface triangles of a node group, their linear
subdivision, and the patch's boundary loops.

The surface triangles are the body file's (``BodyData.surface_triangles``): (T, 3)
corners of tet4 faces or (T, 6) tet10 faces (corners c0, c1, c2, then the mid-edge nodes
of (c0, c1), (c1, c2), (c2, c0)), counter-clockwise seen from outside. A triangle belongs
to the patch when all its nodes are in the group. A 6-node triangle is split into four
linear ones (corner, mid, mid and the middle one), so mid-edge nodes are data points and
vertices of the patch's triangulation like the corners.

The patch must be a connected, manifold surface: a topological disk (one boundary loop;
mapped onto the unit square), a face with holes (an outer loop and one or more hole
loops) or a closed band (two loops, e.g. a cylinder's lateral surface; mapped
periodically in one direction), see :mod:`.parameterization`. A face with holes and a
band differ in their normals: the flatness |Σ A_T n_T| / Σ A_T of a band that closes
around an axis is small (0 for a cylinder, sin α for a cone of half-angle α), that of a
face is not (1 for a flat one, 2/π for a half cylinder, 1/2 for a hemisphere); a patch
with several loops whose flatness is at least :data:`FACE_FLATNESS` is a face with holes.

On a face with holes the loops, projected onto the plane normal to the area-weighted mean
normal m = Σ A_T n_T / |Σ A_T n_T|, run
counter-clockwise seen along −m (the patch on their left) for the outer loop — a
positive signed area — and clockwise for the holes: the outer loop is the one loop of
positive signed area.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ffrmbs.errors import ModelError

#: a patch with several boundary loops is a face with holes from this flatness on (module docstring)
FACE_FLATNESS = 0.25

#: the four linear triangles of a 6-node triangle (local node numbers 0..5)
SUBTRIANGLES = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])


class SurfacePatch:
    """The surface triangles of a node group of one body.

    Parameters
    ----------
    points : (N, 3) undeformed node positions ū0 of the body [m].
    surface_triangles : (T, 3) or (T, 6) the body's surface triangles.
    group : (n,) node indices (a node group, any order).
    name : str, for error messages.

    Attributes
    ----------
    nodes : (k,) sorted global node indices of the patch (the data points).
    triangles : (T_p, 3|6) the patch's surface triangles in local indices (into ``nodes``).
    linear : (T_l, 3) its linear triangles (local indices), counter-clockwise from outside.
    loops : list of (m,) int arrays, the boundary loops (local indices) in the direction
        of the triangles' orientation (the patch on the left, seen from outside).
    points : (k, 3) [m] the patch nodes' positions.
    edge_length : float [m], the mean length of the linear triangles' edges.
    """

    def __init__(self, points, surface_triangles, group, name="patch"):
        self.name = name
        if surface_triangles is None:
            raise ModelError(f"{name}: the body file has no surface triangles; re-run the preprocessing")
        group = np.unique(np.asarray(group, dtype=np.int64))
        tri = np.asarray(surface_triangles, dtype=np.int64)
        inside = np.zeros(len(points), dtype=bool)
        inside[group] = True
        tri = tri[inside[tri].all(axis=1)]
        if not len(tri):
            raise ModelError(f"{name}: no surface triangle has all its nodes in the group "
                             f"({group.size} nodes): not a face group of the surface")
        self.nodes = np.unique(tri)
        off = np.setdiff1d(group, self.nodes)
        if off.size:
            raise ModelError(f"{name}: {off.size} of the group's {group.size} nodes (e.g. node {off[0]}) are "
                             f"on no surface triangle of the group: the group is not a surface patch")
        local = np.full(len(points), -1, dtype=np.int64)
        local[self.nodes] = np.arange(self.nodes.size)
        self.triangles = local[tri]
        self.order = 1 if tri.shape[1] == 3 else 2
        self.linear = self.triangles if self.order == 1 else self.triangles[:, SUBTRIANGLES].reshape(-1, 3)
        self.points = np.asarray(points, dtype=float)[self.nodes]
        self._check_connected()
        self.loops = self._boundary_loops()
        e = self.points[self.linear]
        self.edge_length = float(np.linalg.norm(e - np.roll(e, 1, axis=1), axis=2).mean())

    @property
    def k(self) -> int:
        """Number of patch nodes."""
        return self.nodes.size

    def _check_connected(self):
        t = self.linear
        graph = coo_matrix((np.ones(t.size), (np.repeat(t[:, 0], 3), t.ravel())), shape=(self.k, self.k))
        n, _ = connected_components(graph, directed=False)
        if n != 1:
            raise ModelError(f"{self.name}: the patch falls into {n} separate pieces; give one connected "
                             f"face group per contour")

    def directed_edges(self) -> np.ndarray:
        """(3 T_l, 2) the linear triangles' edges a -> b in their orientation."""
        t = self.linear
        return np.stack([t, np.roll(t, -1, axis=1)], axis=2).reshape(-1, 2)

    def _boundary_loops(self) -> list:
        """Boundary loops: directed edges whose reverse is no edge, chained head to tail."""
        d = self.directed_edges()
        key = d[:, 0] * self.k + d[:, 1]
        rkey = d[:, 1] * self.k + d[:, 0]
        if np.unique(key).size != key.size:
            raise ModelError(f"{self.name}: the patch is not a manifold surface (an edge is used twice in the "
                             f"same direction: inconsistent orientation or overlapping triangles)")
        boundary = d[~np.isin(key, rkey)]
        nxt = np.full(self.k, -1, dtype=np.int64)
        if np.unique(boundary[:, 0]).size != len(boundary):
            raise ModelError(f"{self.name}: the patch's boundary touches itself at a node (two faces meeting "
                             f"at a single node); split the group")
        nxt[boundary[:, 0]] = boundary[:, 1]
        loops, seen = [], np.zeros(self.k, dtype=bool)
        for start in boundary[:, 0]:
            if seen[start]:
                continue
            loop = [start]
            seen[start] = True
            node = nxt[start]
            while node != start:
                if node < 0 or seen[node]:
                    raise ModelError(f"{self.name}: the patch's boundary is not a set of closed loops")
                loop.append(node)
                seen[node] = True
                node = nxt[node]
            loops.append(np.array(loop, dtype=np.int64))
        return sorted(loops, key=lambda l: int(l.min()))

    def topology(self) -> str:
        """"disk" (one boundary loop), "holes" (a face with holes: an outer loop and
        len(loops) − 1 hole loops, flatness >= FACE_FLATNESS) or "annulus" (a closed band:
        two loops, a smaller flatness), else a ModelError (module docstring)."""
        n = len(self.loops)
        edges = np.unique(np.sort(self.directed_edges(), axis=1), axis=0)
        euler = self.k - len(edges) + len(self.linear)
        if n == 1 and euler == 1:
            return "disk"
        flat = self.flatness() >= FACE_FLATNESS
        if n >= 2 and euler == 2 - n and flat:
            return "holes"
        if n == 2 and euler == 0:
            return "annulus"
        if n == 0:
            raise ModelError(f"{self.name}: the patch is a closed surface (no boundary); a contour needs a "
                             f"patch with one boundary (a face), a face with holes or a closed band")
        raise ModelError(f"{self.name}: the patch has {n} boundary loops and Euler characteristic {euler}"
                         f"{'' if flat else ' and closes around an axis'}: a contour needs a face (1 loop, or an "
                         f"outer loop and holes) or a closed band (2 loops): split the group")

    def _area_normals(self) -> np.ndarray:
        """(T_l, 3) 2 A_T n_T of the linear triangles (outward, from their orientation)."""
        x = self.points[self.linear]
        return np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])

    def flatness(self) -> float:
        """|Σ A_T n_T| / Σ A_T in [0, 1] (module docstring)."""
        n = self._area_normals()
        return float(np.linalg.norm(n.sum(axis=0)) / np.linalg.norm(n, axis=1).sum())

    def mean_normal(self):
        """(3,) the unit area-weighted mean outward normal m = Σ A_T n_T / |Σ A_T n_T|, or
        None when the sum vanishes (a closed band around an axis)."""
        n = self._area_normals()
        total = n.sum(axis=0)
        size = np.linalg.norm(total)
        if size <= 1e-12 * np.linalg.norm(n, axis=1).sum():
            return None
        return total / size

    def outer_and_holes(self) -> tuple:
        """(outer loop, [hole loops]) of a face with holes (:meth:`topology` "holes"):
        the outer loop has a positive signed area in the plane normal to the mean normal
        (module docstring); ModelError if not exactly one has."""
        m = self.mean_normal()
        e1 = np.cross(m, [1.0, 0.0, 0.0] if abs(m[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(m, e1)
        areas = []
        for loop in self.loops:
            x = self.points[loop]
            a, b = x @ e1, x @ e2
            areas.append(0.5 * float(np.sum(a * np.roll(b, -1) - np.roll(a, -1) * b)))
        positive = [i for i, area in enumerate(areas) if area > 0]
        if len(positive) != 1:
            raise ModelError(f"{self.name}: cannot tell the outer boundary of the face from its holes "
                             f"({len(positive)} of its {len(areas)} boundary loops run counter-clockwise)")
        outer = positive[0]
        return self.loops[outer], [loop for i, loop in enumerate(self.loops) if i != outer]
