"""Least-squares B-spline curves and surfaces through scattered data, factored once.

Given data parameters t_i (a curve) or (η_i, ξ_i) (a surface, from
:mod:`.parameterization`) and uniform knots, the control points P of the B-spline
S(η, ξ) = Σ_ab N_a(η) M_b(ξ) P_ab (unit weights, like the interpolating contours of
:mod:`contours.nurbs`) minimize

    Σ_i |S(η_i, ξ_i) − Q_i|² + λ E(S),   E = ∫∫ |S_ηη|² + 2 |S_ηξ|² + |S_ξξ|² dη dξ,

the thin-plate energy (a curve: E = ∫ |C''|² dt). The normal equations (BᵀB + λ S) P =
Bᵀ Q, with B the collocation matrix B_i,ab = N_a(η_i) M_b(ξ_i) and S the energy's Gram
matrix, are factored once; the fitting matrix F = (BᵀB + λ S)⁻¹ Bᵀ maps any nodal field
linearly to control points — node positions ū0 and every mode shape alike, so
P_ū = F ū0 + (F Φ) q_f exactly as for interpolation (thesis Sec. 3.2.2).

λ = ``smoothing`` · tr(BᵀB) / tr(S): the energy term is scaled to the data term, so the
dimensionless ``smoothing`` means the same on any patch. It makes the system regular
where a knot span holds too few data points and costs nothing on a plane (E = 0 for any
affine S).

The energy is exact: S = G2 ⊗ G0 + 2 G1 ⊗ G1 + G0 ⊗ G2 with the 1-D Gram matrices
G_d,ab = ∫ N_a^(d) N_b^(d) dt by Gauss–Legendre quadrature per knot span.

Knots: clamped uniform (open) or periodic uniform (closed, the first p control points
repeated at the end — "wrapped" — as in :mod:`contours.nurbs.knots`), domain [0, 1].
Each :class:`FitDirection` carries the attributes the contours' parametric space reads
from an :class:`~contours.nurbs.Interpolation1D` (knots, degree, n_ctrl, closed, domain).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix, csc_matrix, kron
from scipy.sparse.linalg import splu

from ffrmbs.errors import ModelError
from contours.nurbs._kernels import ders_basis, find_span

#: default dimensionless smoothing (see the module docstring)
SMOOTHING = 1e-6


class FitDirection:
    """Uniform knots of one parametric direction with ``n`` distinct control points.

    Parameters
    ----------
    n : number of distinct control points (open: n >= p + 1; closed: n >= p + 1).
    degree : p >= 1 (3: C²).
    closed : periodic with period 1 (C^{p-1} across the seam).

    Attributes
    ----------
    knots, degree, closed
        The knot vector, the degree and whether the direction is closed.
    domain : (0.0, 1.0)
    n_ctrl : int
        n (open) or n + p (closed).
    n_unique : int
        n.
    """

    def __init__(self, n, degree=3, closed=False):
        p = int(degree)
        n = int(n)
        if p < 1:
            raise ModelError(f"the degree must be an integer >= 1, got {degree}")
        if n < p + 1:
            raise ModelError(f"a degree-{p} fit needs at least {p + 1} control points per direction, got {n}")
        self.degree, self.closed, self.n_unique = p, bool(closed), n
        if self.closed:
            self.knots = (np.arange(n + 2 * p + 1) - p) / n
            self.n_ctrl = n + p
        else:
            self.knots = np.concatenate([np.zeros(p), np.linspace(0.0, 1.0, n - p + 1), np.ones(p)])
            self.n_ctrl = n
        self.knots.flags.writeable = False
        self.domain = (0.0, 1.0)

    def basis(self, t, nd=0):
        """(first (m,), values (nd + 1, m, p + 1)): the p + 1 nonzero basis functions (and
        derivatives up to nd) at the parameters t, for control points first + j (mod
        n_unique when closed)."""
        t = np.asarray(t, dtype=float).ravel()
        p = self.degree
        first = np.empty(t.size, dtype=np.int64)
        values = np.empty((nd + 1, t.size, p + 1))
        row = np.empty((nd + 1, p + 1))
        knots = np.array(self.knots)      # writable: numba compiles a read-only array apart
        for i, ti in enumerate(t):
            ti = ti % 1.0 if self.closed else min(max(ti, 0.0), 1.0)
            span = find_span(knots, p, self.n_ctrl, ti)
            ders_basis(knots, p, span, ti, nd, row)
            first[i] = span - p
            values[:, i] = row
        return first, values

    def collocation(self, t, d=0) -> csc_matrix:
        """(m, n_unique) sparse matrix of the d-th derivative of the basis at t."""
        first, values = self.basis(t, d)
        p, m = self.degree, first.size
        cols = (first[:, None] + np.arange(p + 1)[None, :]) % self.n_unique
        rows = np.repeat(np.arange(m), p + 1)
        return coo_matrix((values[d].ravel(), (rows, cols.ravel())), shape=(m, self.n_unique)).tocsc()

    def gram(self, d) -> csc_matrix:
        """(n_unique, n_unique) G_d,ab = ∫_0^1 N_a^(d) N_b^(d) dt (exact: Gauss–Legendre with
        p + 1 points per knot span)."""
        x, w = np.polynomial.legendre.leggauss(self.degree + 1)
        spans = np.unique(self.knots[(self.knots >= 0.0) & (self.knots <= 1.0)])
        a, b = spans[:-1], spans[1:]
        t = (0.5 * (b - a)[:, None] * (x[None, :] + 1.0) + a[:, None]).ravel()
        weights = (0.5 * (b - a)[:, None] * w[None, :]).ravel()
        D = self.collocation(t, d)
        return (D.T @ D.multiply(weights[:, None])).tocsc()

    def wrap(self, P, axis=0) -> np.ndarray:
        """Control points with the first p repeated at the end along ``axis`` (closed)."""
        if not self.closed:
            return P
        return np.concatenate([P, np.take(P, np.arange(self.degree), axis=axis)], axis=axis)


class _LeastSquares:
    """The factored normal equations of one fit (see the module docstring)."""

    def __init__(self, B, S, smoothing):
        if not np.isfinite(smoothing) or smoothing < 0:
            raise ModelError(f"the smoothing must be a number >= 0, got {smoothing}")
        BtB = (B.T @ B).tocsc()
        scale = BtB.diagonal().sum() / max(S.diagonal().sum(), np.finfo(float).tiny)
        self.B = B.tocsr()
        self.lam = float(smoothing) * scale
        A = (BtB + self.lam * S).tocsc()
        try:
            self._lu = splu(A)
        except RuntimeError:
            raise ModelError("the least-squares fit is singular: too few data points for the control points; "
                             "give fewer control points or a larger smoothing") from None
        if not np.all(np.isfinite(self._lu.U.diagonal())) or np.abs(self._lu.U.diagonal()).min() <= 1e-14 * \
                np.abs(self._lu.U.diagonal()).max():
            raise ModelError("the least-squares fit is singular: too few data points for the control points; "
                             "give fewer control points or a larger smoothing")

    def solve(self, values) -> np.ndarray:
        """(n_unknowns, w) control points of data (k, w)."""
        return self._lu.solve(np.ascontiguousarray(self.B.T @ values))


class SurfaceFit:
    """Least-squares tensor-product B-spline surface through scattered data (module docstring).

    Parameters
    ----------
    params : (k, 2) data parameters (η_i, ξ_i) in [0, 1]² (η in [0, 1) when closed).
    n_ctrl : (n_η, n_ξ) distinct control points per direction.
    degree : int or (p_η, p_ξ).
    closed : (closed_η, closed_ξ).
    smoothing : dimensionless λ factor (>= 0).

    Attributes
    ----------
    eta, xi : FitDirection
        The two directions.
    params
        The parameters.
    n_points : int
        k.
    """

    def __init__(self, params, n_ctrl, degree=3, closed=(False, False), smoothing=SMOOTHING):
        params = np.asarray(params, dtype=float)
        if params.ndim != 2 or params.shape[1] != 2 or not np.isfinite(params).all():
            raise ModelError(f"surface fit parameters must be a finite (k, 2) array, got shape {params.shape}")
        p_eta, p_xi = (degree, degree) if np.isscalar(degree) else degree
        self.eta = FitDirection(n_ctrl[0], p_eta, closed[0])
        self.xi = FitDirection(n_ctrl[1], p_xi, closed[1])
        self.params, self.n_points = params, len(params)
        B = self.collocation(params)
        G = [self.eta.gram(d) for d in range(3)], [self.xi.gram(d) for d in range(3)]
        S = kron(G[0][2], G[1][0]) + 2 * kron(G[0][1], G[1][1]) + kron(G[0][0], G[1][2])
        self._ls = _LeastSquares(B.tocsr(), S.tocsc(), smoothing)

    def collocation(self, params, d_eta=0, d_xi=0):
        """(m, n_η n_ξ) sparse matrix of ∂^(d_η + d_ξ) S / ∂η^d_η ∂ξ^d_ξ at ``params``
        (m, 2) in terms of the distinct control points (η-major)."""
        params = np.asarray(params, dtype=float).reshape(-1, 2)
        m = len(params)
        fe, ve = self.eta.basis(params[:, 0], d_eta)
        fx, vx = self.xi.basis(params[:, 1], d_xi)
        pe, px, nx = self.eta.degree + 1, self.xi.degree + 1, self.xi.n_unique
        ce = (fe[:, None] + np.arange(pe)) % self.eta.n_unique
        cx = (fx[:, None] + np.arange(px)) % nx
        cols = (ce[:, :, None] * nx + cx[:, None, :]).reshape(m, -1)
        vals = (ve[d_eta][:, :, None] * vx[d_xi][:, None, :]).reshape(m, -1)
        rows = np.repeat(np.arange(m), pe * px)
        return coo_matrix((vals.ravel(), (rows, cols.ravel())), shape=(m, self.eta.n_unique * nx)).tocsr()

    def distinct_control_points(self, values) -> np.ndarray:
        """The n_η n_ξ distinct control points (η-major, the columns of :meth:`collocation`)
        of data ``values`` (k, ...): shape (n_η n_ξ, ...), units of ``values``."""
        Q = np.asarray(values, dtype=float)
        if Q.ndim == 0 or Q.shape[0] != self.n_points:
            raise ModelError(f"expected values of shape ({self.n_points}, ...), got {Q.shape}")
        return self._ls.solve(Q.reshape(self.n_points, -1)).reshape((-1,) + Q.shape[1:])

    def control_points(self, values) -> np.ndarray:
        """Control points (eta.n_ctrl, xi.n_ctrl, ...) of data ``values`` (k, ...), wrapped
        along closed directions; units of ``values``."""
        P = self.distinct_control_points(values)
        P = P.reshape((self.eta.n_unique, self.xi.n_unique) + P.shape[1:])
        return np.ascontiguousarray(self.xi.wrap(self.eta.wrap(P, 0), 1))

    def matrix(self) -> np.ndarray:
        """The fitting matrix F (n_η n_ξ, k), distinct control points = F · data."""
        return self._ls.solve(np.eye(self.n_points))


class CurveFit:
    """Least-squares B-spline curve through data at parameters t (k,) in [0, 1] ([0, 1)
    closed), with ``n_ctrl`` distinct control points; see :class:`SurfaceFit`."""

    def __init__(self, params, n_ctrl, degree=3, closed=False, smoothing=SMOOTHING):
        params = np.asarray(params, dtype=float).ravel()
        if not np.isfinite(params).all():
            raise ModelError("curve fit parameters must be finite")
        self.eta = d = FitDirection(n_ctrl, degree, closed)
        # what the parametric space reads from an Interpolation1D
        self.knots, self.degree, self.closed, self.n_ctrl, self.domain = d.knots, d.degree, d.closed, d.n_ctrl, d.domain
        self.params, self.n_points = params, params.size
        self._ls = _LeastSquares(self.eta.collocation(params), self.eta.gram(2), smoothing)

    def control_points(self, values) -> np.ndarray:
        """Control points (n_ctrl, ...) of data (k, ...), wrapped when closed."""
        Q = np.asarray(values, dtype=float)
        if Q.ndim == 0 or Q.shape[0] != self.n_points:
            raise ModelError(f"expected values of shape ({self.n_points}, ...), got {Q.shape}")
        P = self._ls.solve(Q.reshape(self.n_points, -1)).reshape((self.eta.n_unique,) + Q.shape[1:])
        return np.ascontiguousarray(self.eta.wrap(P, 0))
