"""numba kernels of the neutral contours: basis tables at a point, contractions of
control-point arrays with them, control-point updates and the contour frame.

Plain-numpy references: :func:`contours.nurbs.basis.curve_point` /
:func:`~contours.nurbs.basis.surface_point` for the contractions and the formulas in
the docstrings for the rest; ``tests/test_neutral_contours.py`` compares them.
"""

import numba
import numpy as np

from contours.nurbs._kernels import ders_basis, find_span, wrap_parameter


@numba.njit(cache=True)
def locate(knots, p, n_ctrl, closed, a, b, t, B):
    """Basis functions N_{s-p..s} and their first two derivatives at t into B (3, p+1);
    returns the span s. Closed directions wrap t into [a, b); open ones clip it."""
    t = wrap_parameter(t, a, b, closed)
    s = find_span(knots, p, n_ctrl, t)
    nd = min(2, p)
    ders_basis(knots, p, s, t, nd, B[: nd + 1])
    for k in range(nd + 1, 3):
        B[k, :] = 0.0
    return s


@numba.njit(cache=True)
def contract_curve(B, s, p, ctrl, nrows, out):
    """Rows of out (6, m) from a curve's control points ctrl (n_ctrl, m): row 0 = C,
    row 1 = C', row 3 = C'' (rows 2, 4, 5 zero); only the first ``nrows`` rows (1, 3 or 6)
    are written."""
    m = ctrl.shape[1]
    for r in range(nrows):
        for k in range(m):
            out[r, k] = 0.0
    for a in range(p + 1):
        i = s - p + a
        for k in range(m):
            c = ctrl[i, k]
            out[0, k] += B[0, a] * c
            if nrows > 1:
                out[1, k] += B[1, a] * c
            if nrows > 3:
                out[3, k] += B[2, a] * c


@numba.njit(cache=True)
def contract_surface(Be, se, pe, Bx, sx, px, ctrl, nrows, out):
    """Rows of out (6, m) from a surface's control points ctrl (n_eta, n_xi, m):
    S, S_η, S_ξ, S_ηη, S_ηξ, S_ξξ (thesis eq. 3.23, 3.25, 3.26); the first ``nrows`` rows."""
    m = ctrl.shape[2]
    for r in range(nrows):
        for k in range(m):
            out[r, k] = 0.0
    for a in range(pe + 1):
        i = se - pe + a
        for b in range(px + 1):
            j = sx - px + b
            c0 = Be[0, a] * Bx[0, b]
            c1 = Be[1, a] * Bx[0, b]
            c2 = Be[0, a] * Bx[1, b]
            c3 = Be[2, a] * Bx[0, b]
            c4 = Be[1, a] * Bx[1, b]
            c5 = Be[0, a] * Bx[2, b]
            for k in range(m):
                c = ctrl[i, j, k]
                out[0, k] += c0 * c
                if nrows > 1:
                    out[1, k] += c1 * c
                    out[2, k] += c2 * c
                if nrows > 3:
                    out[3, k] += c3 * c
                    out[4, k] += c4 * c
                    out[5, k] += c5 * c


@numba.njit(cache=True)
def position_ctrl(R, A, local, out):
    """Control points of r = R + A ū from those of ū (rows of (n, 3)): B-splines are
    affinely invariant (partition of unity), so this equals interpolating the nodal
    positions of thesis eq. 2.24."""
    for i in range(local.shape[0]):
        for c in range(3):
            out[i, c] = R[c] + A[c, 0] * local[i, 0] + A[c, 1] * local[i, 1] + A[c, 2] * local[i, 2]


@numba.njit(cache=True)
def velocity_ctrl(v, A, w, local, modal, out):
    """Control points of ṙ = v + A (ω̄ × ū + Φ q̇_f) (thesis eq. 2.32) from those of ū
    (n, 3) and of Φ q̇_f (n, 3) (``modal``); exact by linearity of the interpolation."""
    rel = np.empty(3)
    for i in range(local.shape[0]):
        rel[0] = w[1] * local[i, 2] - w[2] * local[i, 1] + modal[i, 0]
        rel[1] = w[2] * local[i, 0] - w[0] * local[i, 2] + modal[i, 1]
        rel[2] = w[0] * local[i, 1] - w[1] * local[i, 0] + modal[i, 2]
        for c in range(3):
            out[i, c] = v[c] + A[c, 0] * rel[0] + A[c, 1] * rel[1] + A[c, 2] * rel[2]


@numba.njit(cache=True)
def frame_2s(D, sign, F):
    """Columns of F (3, 3): t1 = t_η/|t_η| (eq. 3.28), t2 = n × t1 (eq. 3.29),
    n = sign · t_η × t_ξ / |t_η × t_ξ| (eq. 3.27) from D rows 1 (t_η) and 2 (t_ξ)."""
    te, tx = D[1], D[2]
    nx = te[1] * tx[2] - te[2] * tx[1]
    ny = te[2] * tx[0] - te[0] * tx[2]
    nz = te[0] * tx[1] - te[1] * tx[0]
    s = sign / np.sqrt(nx * nx + ny * ny + nz * nz)
    F[0, 2], F[1, 2], F[2, 2] = s * nx, s * ny, s * nz
    _complete(te, F)


@numba.njit(cache=True)
def frame_1s(D, n_ref, F):
    """Columns of F (3, 3) on a curve: t1 = t_η/|t_η|, n = the reference direction n_ref
    made perpendicular to t1 and normalized, t2 = n × t1."""
    te = D[1]
    inv = 1.0 / np.sqrt(te[0] ** 2 + te[1] ** 2 + te[2] ** 2)
    d = (n_ref[0] * te[0] + n_ref[1] * te[1] + n_ref[2] * te[2]) * inv * inv
    for c in range(3):
        F[c, 2] = n_ref[c] - d * te[c]
    s = 1.0 / np.sqrt(F[0, 2] ** 2 + F[1, 2] ** 2 + F[2, 2] ** 2)
    for c in range(3):
        F[c, 2] *= s
    _complete(te, F)


@numba.njit(cache=True)
def _complete(te, F):
    inv = 1.0 / np.sqrt(te[0] ** 2 + te[1] ** 2 + te[2] ** 2)
    for c in range(3):
        F[c, 0] = te[c] * inv
    F[0, 1] = F[1, 2] * F[2, 0] - F[2, 2] * F[1, 0]
    F[1, 1] = F[2, 2] * F[0, 0] - F[0, 2] * F[2, 0]
    F[2, 1] = F[0, 2] * F[1, 0] - F[1, 2] * F[0, 0]
