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
* :func:`check_node_matrix` — validate an explicitly given O.

All positions are undeformed body-frame node positions ``u0`` of shape (N, 3) in m;
node indices are 0-based rows of ``u0``.

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
from scipy.spatial import cKDTree

from ffrmbs.errors import ModelError

__all__ = ["node_matrix", "node_line", "check_node_matrix"]


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
