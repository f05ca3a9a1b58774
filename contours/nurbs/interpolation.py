"""Global B-spline interpolation of curves and surfaces (thesis eq. 3.18, 3.22, 3.23).

The contours interpolate with unit weights: a NURBS with all w_i = 1 (eq. 3.15–3.17) is
the B-spline C(η) = sum_i N_{i,p}(η) P_i, so the homogeneous system C^w = N P^w of
eq. 3.18 reduces to N P = Q. The collocation matrix N_{ij} = N_{j,p}(t_i) depends only on
the parameters t_i, the degree and the knot vector; it is factored once
(:class:`Interpolation1D`) and reused for every right-hand side — node positions and every
mode shape alike, since P depends linearly on Q (NURBS Book A9.1).

Surfaces follow the three steps after eq. 3.23 (NURBS Book A9.4): interpolate along η
for each column of the grid, then the resulting control points along ξ.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lu_factor, lu_solve

from ffrmbs.errors import ModelError

from ._kernels import ders_basis, find_span
from .knots import averaged_knots, parameters, periodic_knots, surface_parameters


def _frozen(a):
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


class Interpolation1D:
    """Global interpolation along one parametric direction; factored once, reused.

    Parameters
    ----------
    params : (k,) parameters t_i of the data, from :func:`~contours.nurbs.knots.parameters`;
        open: 0 = t_0 < … < t_{k-1} = 1; closed: 0 = t_0 < … < t_{k-1} < 1 (period 1).
    degree : p >= 1 (3 gives a C² curve); k >= p + 1.
    closed : periodic interpolation (C^{p-1} across the seam).

    Attributes
    ----------
    degree, closed
        As given.
    params : (k,)
        The parameters.
    n_points : int
        k.
    knots : (n_ctrl + p + 1,) knot vector for evaluation — clamped, NURBS Book eq. 9.8
        (open), or periodic (closed), see :mod:`contours.nurbs.knots`.
    n_ctrl : k (open) or k + p (closed: the k control points with the first p repeated
        at the end, "wrapped").
    domain : (a, b) = (knots[p], knots[n_ctrl]) = (0.0, 1.0).
    matrix : (k, k) collocation matrix N_{ij} = N_{j,p}(t_i) of eq. 3.18; for closed
        curves the cyclic one, N_{ij} = sum of the basis functions of P_j and its copy.
    """

    def __init__(self, params, degree=3, closed=False):
        closed = bool(closed)
        knots = periodic_knots(params, degree) if closed else averaged_knots(params, degree)
        self.degree = int(degree)
        self.closed = closed
        self.params = _frozen(params)
        self.n_points = self.params.size
        self.knots = _frozen(knots)
        self.n_ctrl = self.n_points + (self.degree if closed else 0)
        self.domain = (float(self.knots[self.degree]), float(self.knots[self.n_ctrl]))
        self.matrix = _frozen(self._collocation())
        self._lu = lu_factor(self.matrix, check_finite=False)
        if np.any(np.diag(self._lu[0]) == 0.0):
            raise ModelError("singular interpolation matrix (parameters do not fit the knots)")

    def _collocation(self):
        p, k = self.degree, self.n_points
        N = np.zeros((k, k))
        row = np.empty((1, p + 1))
        knots = np.array(self.knots)      # writable: numba compiles a read-only array apart
        for r, t in enumerate(self.params):
            span = find_span(knots, p, self.n_ctrl, t)
            ders_basis(knots, p, span, t, 0, row)
            for j in range(p + 1):
                N[r, (span - p + j) % k] += row[0, j]
        return N

    def control_points(self, values):
        """Control points P with N P = Q (eq. 3.22, unit weights).

        - values : (k, ...) data at the parameters, any trailing shape (e.g. (k, 3) node
          positions [m] or (k, 3, n_f) mode shapes).

        Returns (n_ctrl, ...) in the units of ``values``; for closed curves the last p rows
        repeat the first p.
        """
        Q = np.asarray(values, dtype=float)
        if Q.ndim == 0 or Q.shape[0] != self.n_points:
            raise ModelError(f"expected values of shape ({self.n_points}, ...), got {Q.shape}")
        P = lu_solve(self._lu, Q.reshape(self.n_points, -1), check_finite=False)
        if self.closed:
            P = np.vstack([P, P[: self.degree]])
        return P.reshape((self.n_ctrl,) + Q.shape[1:])

    @classmethod
    def from_points(cls, points, degree=3, closed=False, method="chord"):
        """Interpolation with the parameters of ``points`` (k, d) by ``method`` (eq. 3.19–3.21)."""
        return cls(parameters(points, method, closed), degree, closed)


class SurfaceInterpolation:
    """Tensor-product global interpolation of a (k_η, k_ξ) grid (steps after eq. 3.23).

    Parameters
    ----------
    eta, xi : :class:`Interpolation1D` along the first (η) and second (ξ) grid index.
    """

    def __init__(self, eta, xi):
        self.eta = eta
        self.xi = xi

    @classmethod
    def from_grid(cls, grid, degree=(3, 3), closed=(False, False), method="chord"):
        """Interpolation with the averaged parameters of ``grid`` (k_η, k_ξ, 3) (NURBS Book A9.3).

        degree : int or (p_η, p_ξ); closed : (closed_η, closed_ξ).
        """
        p_eta, p_xi = (degree, degree) if np.isscalar(degree) else degree
        t_eta, t_xi = surface_parameters(grid, method, closed)
        return cls(Interpolation1D(t_eta, p_eta, closed[0]), Interpolation1D(t_xi, p_xi, closed[1]))

    def control_points(self, values):
        """Control points P_ij of the surface through ``values`` (k_η, k_ξ, ...).

        Step 1 interpolates each column along η, step 2 the result along ξ.
        Returns (eta.n_ctrl, xi.n_ctrl, ...), wrapped along closed directions.
        """
        Q = np.asarray(values, dtype=float)
        if Q.ndim < 2 or Q.shape[:2] != (self.eta.n_points, self.xi.n_points):
            raise ModelError(f"expected values of shape ({self.eta.n_points}, {self.xi.n_points}, ...), "
                             f"got {Q.shape}")
        R = self.eta.control_points(Q)
        return np.ascontiguousarray(np.moveaxis(self.xi.control_points(np.moveaxis(R, 1, 0)), 0, 1))
