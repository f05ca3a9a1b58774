"""Contour definition from FE nodes: the ordered node matrix O (thesis Sec. 3.2.2, eq. 3.24).

A 2D NURBS contour interpolates the nodes of a rectangular surface area A' of an FFR
body; "all the indices of nodes in A have to be ordered according to their position
[...] and stored in a matrix O row by row" (thesis eq. 3.24), and, "if possible, some
additional nodes outside the boundary" make the interpolated tangents more accurate
near the edge (thesis Sec. 3.2.2, Fig. 3.4). A 1D contour (e.g. a neutral axis) is a
sorted line of nodes.

* :func:`node_matrix` — detect the structured grid of a planar node patch (e.g. a face
  group ``'y1'`` of :func:`preprocess.geometry.box` meshed with ``divisions``) and
  return O, optionally extended by rows of nodes beyond the boundary.
* :func:`node_line` — the nodes on a straight line, sorted along it.
* :func:`node_path` — the nodes of a feature edge or any line of surface nodes of an
  unstructured mesh (a gmsh physical curve: a box edge, a cylinder's rim), ordered by
  walking the edges of the body's surface triangles; open or closed.
* :func:`check_node_matrix` — validate an explicitly given O.

All positions are undeformed body-frame node positions ``u0`` of shape (N, 3) in m;
node indices are 0-based rows of ``u0``.

Walking convention of :func:`node_path` (deterministic): a closed walk starts at the
smallest node index and goes first to the smaller of its two neighbours; an open walk
starts at the end nearer the body-frame origin (given ``u0``; distances equal within
1e-12 x the largest coordinate, or no ``u0``: the end with the smaller index).

Orientation convention of O (deterministic; a right-handed frame is not guaranteed):
the grid's two in-plane line directions t_eta, t_xi are unit vectors, each signed so
that its largest-magnitude global component (the first one on a tie) is positive;
t_eta is the direction along which the patch is longer (equal lengths within tol: the
one whose largest component has the lower global axis index x < y < z). ``O[i, j]`` is
the node at the i-th level along t_eta and the j-th along t_xi, levels in increasing
coordinate. For the x-z face ``'y1'`` of a box longer in x: rows i follow x, columns j
follow z, both increasing.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ffrmbs.errors import ModelError

__all__ = ["node_matrix", "node_line", "node_path", "check_node_matrix"]


def _positions(u0):
    u0 = np.asarray(u0, dtype=float)
    if u0.ndim != 2 or u0.shape[1] != 3:
        raise ModelError(f"node positions u0 must have shape (N, 3), not {u0.shape}")
    return u0


def _indices(idx, n_nodes, what):
    idx = np.asarray(idx)
    if idx.ndim != 1:
        idx = idx.reshape(-1)
    if idx.size and not np.issubdtype(idx.dtype, np.integer):
        raise ModelError(f"{what} must be integer node indices, got dtype {idx.dtype}")
    idx = idx.astype(np.int64)
    bad = idx[(idx < 0) | (idx >= n_nodes)]
    if bad.size:
        raise ModelError(f"{what}: node index {int(bad[0])} out of range 0..{n_nodes - 1}")
    return np.unique(idx)


def _levels(x, tol):
    """Cluster 1D coordinates into levels separated by gaps > tol.

    Returns (labels (n,) int, centres (n_levels,), max spread of a level)."""
    order = np.argsort(x, kind="stable")
    xs = x[order]
    new = np.concatenate([[True], np.diff(xs) > tol])
    lab_sorted = np.cumsum(new) - 1
    labels = np.empty(len(x), dtype=np.int64)
    labels[order] = lab_sorted
    n = int(lab_sorted[-1]) + 1 if len(x) else 0
    centres = np.bincount(labels, weights=x, minlength=n) / np.maximum(np.bincount(labels, minlength=n), 1)
    lo = np.full(n, np.inf)
    hi = np.full(n, -np.inf)
    np.minimum.at(lo, labels, x)
    np.maximum.at(hi, labels, x)
    spread = float(np.max(hi - lo)) if n else 0.0
    return labels, centres, spread


def _sign_fix(t):
    """Sign a direction so that its largest-magnitude component (first on a tie) is positive."""
    k = int(np.argmax(np.abs(t) > np.abs(t).max() * (1 - 1e-9)))
    return t if t[k] > 0 else -t


def _grid_axes(p, tol):
    """Plane normal and two in-plane grid-line directions of centred points p (n, 3)."""
    _, sv, vt = np.linalg.svd(p, full_matrices=False)
    normal = vt[2]
    off = np.abs(p @ normal)
    if off.max() > tol:
        raise ModelError(
            f"node patch is not planar: its {len(p)} nodes deviate up to {off.max():.3g} m from "
            f"their best-fit plane (tol {tol:.3g} m); node_matrix needs a flat structured patch — "
            f"pass the node matrix O explicitly (check_node_matrix)")
    if sv[1] <= tol:
        raise ModelError(f"node patch of {len(p)} nodes is a line, not a surface; use node_line")
    e1, e2 = vt[0], vt[1]  # principal axes of the patch
    a, b = p @ e1, p @ e2
    # snap to the grid lines: nearest-neighbour directions, averaged modulo pi/2
    ab = np.column_stack([a, b])
    _, nn = cKDTree(ab).query(ab, k=2)
    d = ab[nn[:, 1]] - ab
    theta = np.arctan2(d[:, 1], d[:, 0])
    phi = np.angle(np.exp(4j * theta).sum()) / 4.0
    t1 = np.cos(phi) * e1 + np.sin(phi) * e2
    t2 = -np.sin(phi) * e1 + np.cos(phi) * e2
    return normal, _sign_fix(t1), _sign_fix(t2)


def node_matrix(u0, nodes, extra_rows=0, candidates=None, tol=None) -> np.ndarray:
    """The ordered node matrix O of a planar structured node patch (thesis Sec. 3.2.2, eq. 3.24).

    Parameters
    ----------
    u0 : (N, 3) undeformed node positions [m] in the body frame.
    nodes : node indices of the patch A' (e.g. a box face group ``mesh.group('y1')``).
    extra_rows : int >= 0; extend the grid by up to that many rows / columns beyond each
        of its four boundaries with nodes from ``candidates`` (thesis: additional nodes
        outside the boundary improve the interpolated tangents near the edge). A side is
        extended by one row at a time, at the nearest coordinate level beyond it that holds
        a complete row (one node on each grid line of the other direction, including rows
        added before); it stops at the first level that is incomplete. Sides are treated
        in the order eta-low, eta-high, xi-low, xi-high.
    candidates : node indices eligible for the extension (default: all nodes of u0).
    tol : length tolerance [m] for planarity and for nodes sharing a level
        (default 1e-6 x the patch's bounding-box diagonal).

    Returns
    -------
    O : int64 array (n_eta, n_xi) of 0-based node indices; ``O[i, j]`` is the node at the
        i-th level along t_eta and the j-th along t_xi (see the module docstring for the
        orientation convention: eta along the longer side, coordinates increasing).

    Detection: the best-fit plane of the patch (SVD) must hold all nodes within tol; the
    in-plane axes are the patch's principal axes rotated onto the grid lines (the mean
    nearest-neighbour direction modulo 90 degrees), so only rectangular (orthogonal)
    grids are recognized; along them the coordinates must cluster into n_eta and n_xi
    levels with exactly one node in every (level_eta, level_xi) cell.

    Raises ModelError when the patch is not planar or not a structured grid.
    """
    u0 = _positions(u0)
    nodes = _indices(nodes, len(u0), "nodes")
    if len(nodes) < 4:
        raise ModelError(f"node patch has {len(nodes)} nodes; a grid needs at least 2 x 2")
    if not (isinstance(extra_rows, (int, np.integer)) and extra_rows >= 0):
        raise ModelError(f"extra_rows must be an integer >= 0, not {extra_rows!r}")
    p_all = u0[nodes]
    c = p_all.mean(axis=0)
    p = p_all - c
    diam = float(np.linalg.norm(np.ptp(p_all, axis=0)))
    if diam == 0.0:
        raise ModelError(f"node patch of {len(nodes)} nodes has all nodes at one point")
    tol = 1e-6 * diam if tol is None else float(tol)
    if not tol > 0:
        raise ModelError(f"tol must be positive, not {tol}")

    normal, t1, t2 = _grid_axes(p, tol)
    s1, s2 = p @ t1, p @ t2
    ext1, ext2 = np.ptp(s1), np.ptp(s2)
    dom1, dom2 = int(np.argmax(np.abs(t1))), int(np.argmax(np.abs(t2)))
    swap = ext2 > ext1 + tol or (abs(ext2 - ext1) <= tol and dom2 < dom1)
    if swap:
        t1, t2, s1, s2 = t2, t1, s2, s1
    lab1, lev1, spread1 = _levels(s1, tol)
    lab2, lev2, spread2 = _levels(s2, tol)
    n1, n2 = len(lev1), len(lev2)
    if n1 * n2 != len(nodes):
        fault = "not one node per cell"
    else:
        cells, counts = np.unique(lab1 * n2 + lab2, return_counts=True)
        fault = None
        if len(cells) != n1 * n2:
            fault = f"{n1 * n2 - len(cells)} cells empty, {int(np.sum(counts > 1))} with several nodes"
        elif n1 < 2 or n2 < 2:
            fault = "a grid needs at least 2 levels each way"
        elif max(spread1, spread2) > 2 * tol:
            fault = f"levels spread over up to {max(spread1, spread2):.3g} m"
    if fault is not None:
        raise ModelError(
            f"node patch is not a structured grid: its {len(nodes)} nodes take {n1} distinct "
            f"levels along t_eta and {n2} along t_xi ({n1} x {n2} = {n1 * n2} cells, {fault}; "
            f"tol {tol:.3g} m); pass the node matrix O explicitly (check_node_matrix)")
    O = np.empty((n1, n2), dtype=np.int64)
    O[lab1, lab2] = nodes
    if extra_rows == 0:
        return O

    # extension by rows beyond the boundary (thesis Sec. 3.2.2, Fig. 3.4)
    cand = np.arange(len(u0)) if candidates is None else _indices(candidates, len(u0), "candidates")
    cand = np.setdiff1d(cand, nodes)
    q = u0[cand] - c
    on_plane = np.abs(q @ normal) <= tol
    cand, q = cand[on_plane], q[on_plane]
    cs = [q @ t1, q @ t2]
    levels = [list(lev1), list(lev2)]
    for axis, side in ((0, -1), (0, 1), (1, -1), (1, 1)):
        other = 1 - axis
        for _ in range(extra_rows):
            row = _next_row(cs[axis], cs[other], levels[axis], levels[other], side, tol)
            if row is None:
                break
            level, picks = row
            new = cand[picks]
            if axis == 0:
                O = np.vstack([new[None, :], O] if side < 0 else [O, new[None, :]])
            else:
                O = np.hstack([new[:, None], O] if side < 0 else [O, new[:, None]])
            if side < 0:
                levels[axis].insert(0, level)
            else:
                levels[axis].append(level)
    return O


def _next_row(s, r, levels_s, levels_r, side, tol):
    """Nearest complete row of candidates beyond the boundary level on ``side``.

    s, r: candidate coordinates along the extended axis and the other axis; returns
    (level, candidate positions ordered like levels_r) or None."""
    levels_r = np.asarray(levels_r)
    bound = levels_s[0] if side < 0 else levels_s[-1]
    beyond = (s < bound - tol) if side < 0 else (s > bound + tol)
    # candidates on the grid lines of the other direction
    k = np.searchsorted(levels_r, r)
    k_lo = np.clip(k - 1, 0, len(levels_r) - 1)
    k_hi = np.clip(k, 0, len(levels_r) - 1)
    d_lo, d_hi = np.abs(r - levels_r[k_lo]), np.abs(r - levels_r[k_hi])
    line = np.where(d_lo <= d_hi, k_lo, k_hi)
    on_line = np.minimum(d_lo, d_hi) <= tol
    ok = np.flatnonzero(beyond & on_line)
    if ok.size == 0:
        return None
    nearest = ok[np.argmin(np.abs(s[ok] - bound))]
    row = ok[np.abs(s[ok] - s[nearest]) <= tol]
    if len(row) != len(levels_r) or len(np.unique(line[row])) != len(levels_r):
        return None
    picks = np.empty(len(levels_r), dtype=np.int64)
    picks[line[row]] = row
    return float(s[row].mean()), picks


def node_line(u0, start, direction, nodes=None, tol=None) -> np.ndarray:
    """Nodes on a straight line, for 1D contours (e.g. a neutral axis; thesis Sec. 3.2.2).

    Parameters
    ----------
    u0 : (N, 3) undeformed node positions [m].
    start : (3,) a point of the line [m].
    direction : (3,) direction of the line (any length > 0).
    nodes : node indices to choose from (default: all).
    tol : distance [m] from the line within which a node counts as on it
        (default 1e-6 x the body's bounding-box diagonal, all of u0).

    Returns
    -------
    int64 array (n,) of node indices sorted by their coordinate (p - start) . direction.
    Raises ModelError if fewer than 2 nodes lie on the line.
    """
    u0 = _positions(u0)
    start = np.asarray(start, dtype=float).reshape(-1)
    d = np.asarray(direction, dtype=float).reshape(-1)
    if start.shape != (3,) or d.shape != (3,):
        raise ModelError("node_line: start and direction must be 3-vectors")
    norm = np.linalg.norm(d)
    if not norm > 0:
        raise ModelError("node_line: direction must be nonzero")
    d = d / norm
    idx = np.arange(len(u0)) if nodes is None else _indices(nodes, len(u0), "nodes")
    if tol is None:
        tol = 1e-6 * float(np.linalg.norm(np.ptp(u0, axis=0)))
    rel = u0[idx] - start
    t = rel @ d
    dist = np.linalg.norm(rel - t[:, None] * d, axis=1)
    on = dist <= tol
    if np.count_nonzero(on) < 2:
        raise ModelError(
            f"node_line: {np.count_nonzero(on)} node(s) within {tol:.3g} m of the line through "
            f"{start.tolist()} along {d.tolist()}; need at least 2")
    idx, t = idx[on], t[on]
    return idx[np.argsort(t, kind="stable")]


def _half_edges(surface_triangles) -> np.ndarray:
    """The edges of the surface triangles as node pairs (E, 2), each as often as it occurs.

    ``surface_triangles`` is (T, 3) for tet4 (corners c0, c1, c2) or (T, 6) for tet10
    (corners, then the mid-edge nodes m01, m12, m20 of (c0, c1), (c1, c2), (c2, c0)); a
    tet10 edge is split at its mid-edge node into the half-edges c–m and m–c, so the
    mid-edge nodes are nodes of the graph like the corners.
    """
    tri = np.asarray(surface_triangles)
    if tri.ndim != 2 or tri.shape[1] not in (3, 6) or not np.issubdtype(tri.dtype, np.integer):
        raise ModelError(f"surface triangles must be an integer array (T, 3) or (T, 6), not {tri.dtype} {tri.shape}")
    if tri.shape[1] == 3:
        pairs = ((0, 1), (1, 2), (2, 0))
    else:
        pairs = ((0, 3), (3, 1), (1, 4), (4, 2), (2, 5), (5, 0))
    return np.concatenate([tri[:, [a, b]] for a, b in pairs]).astype(np.int64)


def node_path(surface_triangles, nodes, u0=None, name="node group") -> tuple[np.ndarray, bool]:
    """Order the nodes of a feature edge (or any line of surface nodes) of an unstructured
    mesh by walking the edges of the surface triangles; for 1D contours (thesis Sec. 3.2.2,
    whose node lines are ordered by hand).

    Parameters
    ----------
    surface_triangles : (T, 3) tet4 or (T, 6) tet10 surface triangles of the body
        (e.g. ``body.data.surface_triangles``; tet10 edges are walked
        corner – mid-edge node – corner).
    nodes : node indices of the group (any order; duplicates are ignored).
    u0 : (N, 3) undeformed node positions [m], optional: picks the start of an open walk.
    name : how the group is named in error messages (e.g. ``"node group 'rim0'"``).

    Returns
    -------
    (path, closed): path is an int64 array (k,) holding every node of the group once, in
    walking order; closed is True when the group is a cycle (the last node joins the
    first) and False for an open path. Start and direction follow the module docstring:
    closed — the smallest index first, then the smaller of its two neighbours; open —
    the end nearer the origin of the body frame (ties, or no u0: the smaller index).

    The graph is the surface edges (tet10: half-edges) whose two ends are both in the
    group. It must be a simple path (two nodes with one neighbour in the group, the
    others with two) or a simple cycle (every node with two neighbours); anything else
    — fewer than 2 nodes, a node not on the surface, a node with no or with 3 or more
    neighbours, several disconnected pieces — is a ModelError naming the fault.
    """
    edges = _half_edges(surface_triangles)
    group = np.unique(np.asarray(nodes, dtype=np.int64).reshape(-1))
    if len(group) < 2:
        raise ModelError(f"{name} is not a line of surface nodes: it has {len(group)} node(s), a line needs at least 2")
    if group[0] < 0:
        raise ModelError(f"{name}: node index {int(group[0])} is negative")
    n = int(max(edges.max(initial=-1), group[-1])) + 1
    on_surface = np.zeros(n, dtype=bool)
    on_surface[edges[:, 0]] = True
    off = group[~on_surface[group]]
    if off.size:
        raise ModelError(f"{name} is not a line of surface nodes: {off.size} of its {len(group)} nodes are not on "
                         f"the body's surface (e.g. node {int(off[0])})")
    local = -np.ones(n, dtype=np.int64)
    local[group] = np.arange(len(group))
    links = local[edges]
    links = links[(links >= 0).all(axis=1)]                      # surface edges inside the group
    k = len(group)
    adjacency = sp.coo_matrix((np.ones(len(links)), (links[:, 0], links[:, 1])), shape=(k, k)).tocsr()
    adjacency = ((adjacency + adjacency.T) > 0).tocsr()          # undirected, each edge once
    degree = np.diff(adjacency.indptr)
    if degree.max() > 2:
        i = int(np.argmax(degree > 2))
        raise ModelError(f"{name} is not a line of surface nodes: node {int(group[i])} has {int(degree[i])} "
                         f"neighbours in the group along surface edges (a branching or a face, not an edge)")
    if degree.min() == 0:
        i = int(np.argmin(degree))
        raise ModelError(f"{name} is not a line of surface nodes: node {int(group[i])} has no neighbour in the "
                         f"group along surface edges (an isolated node)")
    n_pieces, _ = connected_components(adjacency, directed=False)
    if n_pieces > 1:
        raise ModelError(f"{name} is not a line of surface nodes: it falls into {n_pieces} disconnected pieces "
                         f"(give one connected edge)")
    closed = bool(degree.min() == 2)
    current = 0 if closed else _open_start(np.flatnonzero(degree == 1), group, u0)
    previous = -1
    path = np.empty(k, dtype=np.int64)
    for step in range(k):
        path[step] = current
        around = adjacency.indices[adjacency.indptr[current]:adjacency.indptr[current + 1]]
        if closed and step == 0:
            following = int(around.min())            # the smaller neighbour (local order = index order)
        else:
            following = int(around[0] if around[0] != previous else around[-1])
        previous, current = current, following
    return group[path], closed


def _open_start(ends, group, u0):
    """Local index of the start of an open walk: of the two ``ends`` (local indices into
    ``group``) the one nearer the origin; ties (within 1e-12 x the largest coordinate
    of u0) or no u0: the one with the smaller node index."""
    if u0 is None:
        return int(ends[0])
    u0 = _positions(u0)
    distance = np.linalg.norm(u0[group[ends]], axis=1)
    size = float(np.abs(u0).max())
    if abs(distance[0] - distance[1]) <= 1e-12 * size:
        return int(ends[0])
    return int(ends[np.argmin(distance)])


def check_node_matrix(O, n_nodes) -> np.ndarray:
    """Validate an explicitly given node matrix O (thesis eq. 3.24).

    O : 2D array of integer node indices (0-based, each in 0..n_nodes-1, no duplicates).
    Returns O as an int64 array of the same shape; raises ModelError otherwise.
    """
    A = np.asarray(O)
    if A.ndim != 2 or A.size == 0:
        raise ModelError(f"node matrix O must be a non-empty 2D array, got shape {A.shape}")
    if not np.issubdtype(A.dtype, np.integer):
        raise ModelError(f"node matrix O must hold integer node indices, got dtype {A.dtype}")
    A = A.astype(np.int64)
    bad = np.argwhere((A < 0) | (A >= n_nodes))
    if bad.size:
        i, j = bad[0]
        raise ModelError(f"node matrix O[{i}, {j}] = {A[i, j]} is out of range 0..{n_nodes - 1}")
    vals, counts = np.unique(A, return_counts=True)
    if np.any(counts > 1):
        dup = int(vals[np.argmax(counts > 1)])
        where = [tuple(int(x) for x in w) for w in np.argwhere(A == dup)]
        raise ModelError(f"node matrix O lists node {dup} more than once, at {where}")
    return A
