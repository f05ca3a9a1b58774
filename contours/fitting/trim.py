"""The trim of a surface fitted over a face with holes: the holes' polygons in parameter
space, and the test whether a point (η, ξ) lies on the material.

A face with holes (:meth:`.patch.SurfacePatch.topology` "holes") is parameterized over
its outer loop's square with the holes filled (:mod:`.parameterization`) and fitted on
its material's nodes only; the fitted surface S(η, ξ) spans the holes smoothly (the
thin-plate term of :mod:`.bspline_fit`) and is trimmed to the material: a point whose
(η, ξ) lies inside a hole's polygon — the hole loop's nodes' parameters, in loop order —
is no point of the contour (no contact there). The outer loop is the square's boundary,
the domain's own edge. The test is the crossing number of :mod:`._kernels` (numba; one
call is O(hole vertices)); :func:`in_material_reference` is its numpy reference.
"""

from __future__ import annotations

import numpy as np

from ._kernels import in_material


class Trim:
    """Hole polygons in parameter space.

    Parameters
    ----------
    polygons : list of (m_h, 2) arrays, each a hole's corners (η, ξ) in loop order.

    Attributes
    ----------
    polygons, vertices, starts
        The polygons, their vertices (M, 2) and starts (H + 1,): the packed layout of
        :func:`._kernels.in_material`.
    """

    def __init__(self, polygons):
        self.polygons = [np.ascontiguousarray(p, dtype=float) for p in polygons]
        self.vertices = np.ascontiguousarray(np.concatenate(self.polygons) if self.polygons else np.zeros((0, 2)))
        self.starts = np.concatenate([[0], np.cumsum([len(p) for p in self.polygons])]).astype(np.int64)

    @classmethod
    def of_fit(cls, fit, patch):
        """The trim of a fit (its ``params`` per patch node) on ``patch``: None unless the
        patch is a face with holes."""
        if patch.topology() != "holes":
            return None
        _, holes = patch.outer_and_holes()
        return cls([fit.params[h] for h in holes])

    def contains(self, eta, xi) -> bool:
        """True when (η, ξ) is on the material (inside no hole polygon)."""
        return bool(in_material(float(eta), float(xi), self.vertices, self.starts))

    def contains_many(self, params) -> np.ndarray:
        """(m,) bool, :meth:`contains` at each row of ``params`` (m, 2)."""
        params = np.asarray(params, dtype=float).reshape(-1, 2)
        return np.array([in_material(e, x, self.vertices, self.starts) for e, x in params], dtype=bool)


def in_material_reference(params, polygons) -> np.ndarray:
    """(m,) bool: the points ``params`` (m, 2) inside no polygon of ``polygons`` (numpy,
    crossing number over all edges at once)."""
    params = np.asarray(params, dtype=float).reshape(-1, 2)
    inside = np.zeros(len(params), dtype=bool)
    for p in polygons:
        a, b = np.asarray(p, dtype=float), np.roll(np.asarray(p, dtype=float), 1, axis=0)
        e, x = params[:, :1], params[:, 1:]
        straddle = (a[None, :, 1] > x) != (b[None, :, 1] > x)
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = a[None, :, 0] + (x - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
        inside |= (np.sum(straddle & (e < cross), axis=1) % 2) == 1
    return ~inside
