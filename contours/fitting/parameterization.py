"""Parameters (η, ξ) of a surface patch's nodes on the unit square: a mean-value map
with a square boundary (Floater 2003), periodic in η for a closed band.

A face with holes (:meth:`.patch.SurfacePatch.topology` "holes") is mapped as the disk
it becomes when each hole is filled by a fan of triangles from one added node at the
mean of the hole loop's nodes: its outer loop goes onto the square's boundary, the hole
loops inside; the added nodes are no data (:mod:`.trim`: the fit is trimmed to the
material). Mean-value weights reproduce linear functions on a planar star, so on a flat
face whose outer loop is a rectangle (corners at its corners) and whose holes are star-
shaped about their nodes' mean, the map is affine, as without holes.

A disk patch (:class:`.patch.SurfacePatch` with one boundary loop) has its boundary
mapped onto the square's edges by arc length, between four corner nodes: the four
boundary nodes where the boundary turns most, when they turn by at least
:data:`CORNER_TURN` (the corners of a rectangular face), else four nodes at equal arc
length (a smooth boundary such as a disk's circle). Interior nodes follow from the
mean-value weights of Floater, w_ij = (tan(α_ij/2) + tan(β_ij/2)) / |x_j − x_i| with α,
β the angles at x_i beside the edge ij: x_i = Σ_j w_ij x_j / Σ_j w_ij, one sparse solve
per coordinate. All weights are positive, so the map of a square boundary is one-to-one
(Floater's theorem for convex boundaries; cotangent weights, which turn negative on obtuse
triangles, are not).

An annulus (two loops, e.g. a cylinder's lateral surface) is cut open along the shortest
edge path from loop 0 to loop 1; the cut patch is a disk whose boundary is loop 0, one side
of the cut, loop 1, the other side, mapped onto the square's bottom, right, top and left
edges. The two sides of the cut land at η = 1 and η = 0, the same point of a direction
periodic in η; each node keeps its parameters from the side η = 0.

Neither map projects onto a plane or a cylinder: both follow the patch's own triangles,
so a curved face (a channel, a cap) is parameterized like a flat one. A smooth boundary
(a cap's circle) gets its four corners where the boundary does not turn; the map is
singular there and the fitted surface's normal is unreliable near those four points.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.sparse.linalg import splu

from ffrmbs.errors import ModelError

from .patch import SurfacePatch

#: a disk patch's boundary node is a corner when its turning angle is at least this [rad]
CORNER_TURN = np.radians(30.0)


def parameterize(patch: SurfacePatch):
    """(params (k, 2) in [0, 1]², closed (bool, bool)) of ``patch``'s nodes: η along the
    first, ξ along the second direction; closed = (True, False) for an annulus."""
    kind = patch.topology()
    if kind == "disk":
        uv = _square_map(patch.points, patch.linear, patch.loops[0], _corners(patch.points, patch.loops[0]))
        return uv, (False, False)
    if kind == "holes":
        return _holed_map(patch), (False, False)
    return _band_map(patch), (True, False)


def unwrap_seam(t) -> np.ndarray:
    """Triangle corner parameters ``t`` (T, c, 2) of a band, η shifted by ±1 where a corner
    lies across the seam η = 0 ≡ 1 from the triangle's first corner (in place; returned)."""
    d = t[..., 0] - t[..., :1, 0]
    t[..., 0] += np.where(d > 0.5, -1.0, 0.0) + np.where(d < -0.5, 1.0, 0.0)
    return t


def _corners(points, loop) -> np.ndarray:
    """Four positions in ``loop`` (indices into it, increasing) of the square's corners."""
    if len(loop) < 4:
        raise ModelError(f"a patch boundary of {len(loop)} nodes cannot be mapped to a square (at least 4)")
    x = points[loop]
    a, b = x - np.roll(x, 1, axis=0), np.roll(x, -1, axis=0) - x
    cos = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
    turn = np.arccos(np.clip(cos, -1.0, 1.0))
    order = np.argsort(-turn, kind="stable")
    if turn[order[3]] >= CORNER_TURN:
        return np.sort(order[:4])
    start = int(order[0])
    s = _arc_length(np.roll(x, -start, axis=0), closed=True)
    steps = [int(np.argmin(np.abs(s[:-1] - q * s[-1] / 4))) for q in (1, 2, 3)]
    corners = np.unique((start + np.array([0] + steps)) % len(loop))
    if len(corners) != 4:
        raise ModelError(f"cannot place four corners on a patch boundary of {len(loop)} nodes")
    return corners


def _arc_length(x, closed=False) -> np.ndarray:
    """Cumulative arc length along the points x (m, 3), from 0; closed: m + 1 values."""
    if closed:
        x = np.vstack([x, x[:1]])
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))])


def _square_boundary(points, loop, corners) -> np.ndarray:
    """(m, 2) positions of the loop's nodes on the unit square's boundary, counter-
    clockwise from corner 0 at (0, 0): the four sides by arc length."""
    m = len(loop)
    uv = np.zeros((m, 2))
    starts = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    ends = starts[1:] + starts[:1]
    for side in range(4):
        a, b = int(corners[side]), int(corners[(side + 1) % 4])
        idx = np.arange(a, b + (m if b <= a else 0) + 1) % m
        s = _arc_length(points[loop[idx]])
        if s[-1] <= 0:
            raise ModelError("a side of the patch boundary has zero length")
        t = (s / s[-1])[:, None]
        uv[idx] = (1 - t) * np.array(starts[side]) + t * np.array(ends[side])
    return uv


def mean_value_weights(points, triangles) -> csr_matrix:
    """(k, k) sparse W, W_ij = Σ over the triangles at the edge ij of tan(θ_i/2)/|x_j − x_i|,
    θ_i the triangle's angle at x_i (Floater's mean-value weights, positive)."""
    x = points[triangles]                                  # (T, 3 corners, 3)
    rows, cols, vals = [], [], []
    for c in range(3):
        i, j, l = triangles[:, c], triangles[:, (c + 1) % 3], triangles[:, (c + 2) % 3]
        e1, e2 = x[:, (c + 1) % 3] - x[:, c], x[:, (c + 2) % 3] - x[:, c]
        n1, n2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
        if not (n1 > 0).all() or not (n2 > 0).all():
            raise ModelError("the patch has a degenerate triangle (two coincident nodes)")
        cos = np.clip(np.einsum("ij,ij->i", e1, e2) / (n1 * n2), -1.0, 1.0)
        half = np.tan(0.5 * np.arccos(cos))
        rows += [i, i]
        cols += [j, l]
        vals += [half / n1, half / n2]
    k = len(points)
    return coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(k, k)).tocsr()


def _square_map(points, triangles, loop, corners) -> np.ndarray:
    """(k, 2) parameters: ``loop`` on the square's boundary, the rest by mean-value weights."""
    k = len(points)
    uv = np.zeros((k, 2))
    uv[loop] = _square_boundary(points, loop, corners)
    W = mean_value_weights(points, triangles)
    inner = np.setdiff1d(np.arange(k), loop)
    if inner.size:
        L = (coo_matrix((np.asarray(W.sum(axis=1)).ravel(), (np.arange(k), np.arange(k))), shape=(k, k))
             - W).tocsr()
        A = L[inner][:, inner].tocsc()
        rhs = -(L[inner][:, loop] @ uv[loop])
        uv[inner] = splu(A).solve(np.ascontiguousarray(rhs))
    return np.clip(uv, 0.0, 1.0)


def _holed_map(patch: SurfacePatch) -> np.ndarray:
    """(k, 2) parameters of a face with holes: each hole filled by a fan of triangles to
    a node at its nodes' mean, then the square map of the filled disk (module docstring)."""
    outer, holes = patch.outer_and_holes()
    k = patch.k
    points, triangles = [patch.points], [patch.linear]
    for i, loop in enumerate(holes):
        points.append(patch.points[loop].mean(axis=0)[None, :])
        # the hole lies right of its loop: the fan's edges run against it (same orientation)
        triangles.append(np.column_stack([np.roll(loop, -1), loop, np.full(len(loop), k + i)]))
    uv = _square_map(np.concatenate(points), np.concatenate(triangles), outer, _corners(patch.points, outer))
    return uv[:k]


def _band_map(patch: SurfacePatch) -> np.ndarray:
    """(k, 2) periodic-in-η parameters of an annulus patch (see the module docstring)."""
    k, tri = patch.k, patch.linear
    cut = _cut_path(patch)
    left = _left_corners(patch, cut)                     # (T, 3) index into cut, or -1
    cut_tri = np.where(left >= 0, k + left, tri)         # left-side copies are nodes k + i
    points = np.concatenate([patch.points, patch.points[cut]])
    edges = np.stack([cut_tri, np.roll(cut_tri, -1, axis=1)], axis=2).reshape(-1, 2)
    n = k + len(cut)
    boundary = edges[~np.isin(edges[:, 0] * n + edges[:, 1], edges[:, 1] * n + edges[:, 0])]
    nxt = np.full(n, -1, dtype=np.int64)
    nxt[boundary[:, 0]] = boundary[:, 1]
    loop = [int(cut[0]) if nxt[cut[0]] >= 0 else k]
    while nxt[loop[-1]] != loop[0]:
        loop.append(int(nxt[loop[-1]]))
        if loop[-1] < 0 or len(loop) > len(boundary):
            raise ModelError(f"{patch.name}: cannot cut the band open along nodes {cut[0]}..{cut[-1]}")
    loop = np.array(loop)
    corners = np.flatnonzero(np.isin(loop, [cut[0], k, cut[-1], k + len(cut) - 1]))
    after = loop[(corners + 1) % len(loop)]               # the node after each corner
    first = np.flatnonzero((after < k) & np.isin(after, patch.loops[0]) & ~np.isin(after, cut))
    if len(corners) != 4 or len(first) != 1:
        raise ModelError(f"{patch.name}: cannot cut the band open (the cut does not join its two boundaries)")
    first = int(first[0])
    loop = np.roll(loop, -int(corners[first]))
    corners = np.sort((corners - corners[first]) % len(loop))
    uv = _square_map(points, cut_tri, loop, corners)
    params = uv[:k].copy()
    at_zero = uv[k:, 0] < uv[cut, 0]                     # each cut node keeps its copy at η = 0
    params[cut[at_zero]] = uv[k:][at_zero]
    params[params[:, 0] >= 1.0, 0] = 0.0
    return params


def _cut_path(patch: SurfacePatch) -> np.ndarray:
    """Nodes of the shortest edge path from the smallest node of loop 0 to loop 1 whose
    inner nodes are off the boundary (local indices, loop 0 first)."""
    k = patch.k
    loop0, loop1 = patch.loops
    on0, on1 = np.isin(np.arange(k), loop0), np.isin(np.arange(k), loop1)
    start = int(loop0.min())
    e = np.unique(np.sort(patch.directed_edges(), axis=1), axis=0)
    allowed = ~(on0 | on1)
    allowed[start] = True
    ok0, ok1 = allowed[e[:, 0]] | on1[e[:, 0]], allowed[e[:, 1]] | on1[e[:, 1]]
    e = e[ok0 & ok1 & ~(on1[e[:, 0]] & on1[e[:, 1]])]
    length = np.linalg.norm(patch.points[e[:, 0]] - patch.points[e[:, 1]], axis=1)
    graph = coo_matrix((length, (e[:, 0], e[:, 1])), shape=(k, k)).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=start, return_predecessors=True)
    targets = loop1[np.isfinite(dist[loop1])]
    if not targets.size:
        raise ModelError(f"{patch.name}: no path of inner nodes joins the band's two boundaries")
    path = [int(targets[np.argmin(dist[targets])])]
    while path[-1] != start:
        path.append(int(pred[path[-1]]))
    return np.array(path[::-1], dtype=np.int64)


def _left_corners(patch: SurfacePatch, cut) -> np.ndarray:
    """(T, 3): for each corner of the linear triangles at a cut node on the left of the
    cut (seen from outside, walking from loop 0 to loop 1) its index in ``cut``, else -1.

    The corners at one node are grouped by joining, across every inner edge that is not
    on the cut, the corners of the two triangles at the edge's nodes; the group holding
    the triangle that has a cut edge p_i -> p_(i+1) in its own orientation is the left."""
    tri = patch.linear
    T = len(tri)
    d = np.stack([tri, np.roll(tri, -1, axis=1)], axis=2).reshape(-1, 2)    # edge c: corner c -> c+1
    k = patch.k
    key = d[:, 0] * k + d[:, 1]
    order = np.argsort(key)
    rkey = d[:, 1] * k + d[:, 0]
    pos = np.searchsorted(key[order], rkey)
    pos = np.minimum(pos, len(key) - 1)
    twin = np.where(key[order][pos] == rkey, order[pos], -1)                 # the reverse edge's index
    cut_keys = set((cut[:-1] * k + cut[1:]).tolist()) | set((cut[1:] * k + cut[:-1]).tolist())
    on_cut = np.isin(key, list(cut_keys))
    inner = (twin >= 0) & ~on_cut
    e = np.flatnonzero(inner)
    t1, c1 = e // 3, e % 3
    t2, c2 = twin[e] // 3, twin[e] % 3
    # edge (t1, c1) runs a -> b = corners c1, c1+1 of t1; its twin (t2, c2) runs b -> a
    a1, b1 = 3 * t1 + c1, 3 * t1 + (c1 + 1) % 3
    b2, a2 = 3 * t2 + c2, 3 * t2 + (c2 + 1) % 3
    n = 3 * T
    graph = coo_matrix((np.ones(2 * e.size), (np.concatenate([a1, b1]), np.concatenate([a2, b2]))), shape=(n, n))
    _, group = connected_components(graph, directed=False)
    forward = np.isin(key, (cut[:-1] * k + cut[1:]).tolist())
    left_groups = set()
    for edge in np.flatnonzero(forward):
        t, c = edge // 3, edge % 3
        left_groups.update((group[3 * t + c], group[3 * t + (c + 1) % 3]))
    where = np.full(k, -1, dtype=np.int64)
    where[cut] = np.arange(len(cut))
    corner_node = tri.ravel()
    is_left = np.isin(group, list(left_groups)) & (where[corner_node] >= 0)
    return np.where(is_left, where[corner_node], -1).reshape(T, 3)
