"""Contours sampled to :class:`trimesh.Trimesh` (visualization; trimesh's bounds)."""

from __future__ import annotations

import numpy as np
import trimesh


def surface_mesh(grid, closed_eta=False, closed_xi=False) -> trimesh.Trimesh:
    """Two triangles per cell of a point grid (n_eta, n_xi, 3) [m]; closed directions
    connect their last row back to the first."""
    ne, nx = grid.shape[:2]
    idx = np.arange(ne * nx).reshape(ne, nx)
    if closed_eta:
        idx = np.vstack([idx, idx[:1]])
    if closed_xi:
        idx = np.hstack([idx, idx[:, :1]])
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return trimesh.Trimesh(grid.reshape(-1, 3), faces, process=False)


def tube_mesh(contour, n_eta, n_ring, radius=None) -> trimesh.Trimesh:
    """A tube of ``radius`` [m] around a 1s contour (default 1 % of its box diagonal),
    ``n_ring`` vertices per ring in the contour's (n, t2) plane."""
    curve = contour.sample(n_eta)
    if radius is None:
        radius = 0.01 * np.linalg.norm(np.ptp(curve, axis=0))
    point = contour.new_point()
    etas = np.linspace(*contour.domain, n_eta, endpoint=not contour.closed[0])
    phis = np.linspace(0.0, 2.0 * np.pi, n_ring, endpoint=False)
    ring = np.stack([np.cos(phis), np.sin(phis)], 1)
    grid = np.empty((n_eta, n_ring, 3))
    for i, eta in enumerate(etas):
        contour.evaluate(point, eta)
        grid[i] = point.r + radius * ring @ np.stack([point.n, point.t2])
    return surface_mesh(grid, contour.closed[0], True)
