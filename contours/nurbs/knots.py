"""Parameters of data points and knot vectors for global interpolation.

Thesis eq. 3.19–3.21 (chord length) and NURBS Book Sec. 9.2: eq. 9.4–9.5 (chord length),
eq. 9.6 (centripetal), eq. 9.8 (averaged knots), A9.3 (surface parameters, averaged over
the grid rows and columns). Parameters are dimensionless, on [0, 1].

Open curves use the clamped knot vector of eq. 9.8 on [0, 1]. Closed (periodic) curves
through k points use k distinct knots per period 1, extended periodically
(u_{i+k} = u_i + 1), so that the domain [u_p, u_{k+p}] is exactly [0, 1] and the curve is
C^{p-1} everywhere, the seam included.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

_METHODS = ("chord", "centripetal")


def parameters(points, method="chord", closed=False):
    """Parameters t_i of the data points Q_i (thesis eq. 3.19–3.21, NURBS Book eq. 9.4–9.6).

    Parameters
    ----------
    points : (k, d) data points Q_0..Q_{k-1} [m].
    method : "chord" (chord length, eq. 3.19–3.21) or "centripetal" (square roots of the
        chord lengths, NURBS Book eq. 9.6).
    closed : if True the closing chord Q_{k-1} -> Q_0 counts in the total length, and the
        point Q_0 repeats at t = 1.

    Returns
    -------
    (k,) parameters, t_0 = 0; open: t_{k-1} = 1; closed: t_{k-1} < 1.

    Raises
    ------
    ModelError
        on fewer than 2 points, non-finite coordinates, an unknown method, or coincident
        consecutive points (a zero chord, which makes two parameters equal).
    """
    if method not in _METHODS:
        raise ModelError(f"unknown parametrization method {method!r}; use 'chord' or 'centripetal'")
    Q = np.asarray(points, dtype=float)
    if Q.ndim != 2 or Q.shape[0] < 2:
        raise ModelError(f"interpolation needs a (k, d) array of k >= 2 points, got shape {Q.shape}")
    if not np.all(np.isfinite(Q)):
        raise ModelError("interpolation points contain NaN or inf")
    if closed:
        Q = np.vstack([Q, Q[:1]])
    chords = np.linalg.norm(np.diff(Q, axis=0), axis=1)
    zero = np.flatnonzero(chords == 0.0)
    if zero.size:
        i = int(zero[0])
        j = (i + 1) % (Q.shape[0] - 1) if closed else i + 1
        raise ModelError(f"interpolation points {i} and {j} coincide (zero chord length)")
    steps = np.sqrt(chords) if method == "centripetal" else chords
    params = np.concatenate([[0.0], np.cumsum(steps)]) / np.sum(steps)
    if closed:
        return params[:-1]
    params[-1] = 1.0
    return params


def surface_parameters(grid, method="chord", closed=(False, False)):
    """Parameters of a (k_u, k_v) grid of points, averaged over the rows and columns.

    NURBS Book Sec. 9.2.5 / A9.3, as ``geomdl.fitting.compute_params_surface``: the
    parameters along η (first index) are the mean over the k_v columns ``grid[:, j]`` of
    :func:`parameters`, those along ξ (second index) the mean over the k_u rows.

    Parameters
    ----------
    grid : (k_u, k_v, d) points Q_ij [m].
    method : "chord" or "centripetal".
    closed : (closed_eta, closed_xi).

    Returns
    -------
    params_eta (k_u,), params_xi (k_v,).
    """
    Q = np.asarray(grid, dtype=float)
    if Q.ndim != 3:
        raise ModelError(f"surface interpolation needs a (k_u, k_v, d) grid, got shape {Q.shape}")
    eta = np.mean([parameters(Q[:, j], method, closed[0]) for j in range(Q.shape[1])], axis=0)
    xi = np.mean([parameters(Q[i, :], method, closed[1]) for i in range(Q.shape[0])], axis=0)
    return eta, xi


def _check(params, degree, closed):
    """Validated (k,) parameters for interpolation of degree ``degree``."""
    t = np.asarray(params, dtype=float)
    if int(degree) != degree or degree < 1:
        raise ModelError(f"the degree must be an integer >= 1, got {degree}")
    if t.ndim != 1 or t.size < degree + 1:
        raise ModelError(f"degree {degree} interpolation needs at least {degree + 1} points, got {t.size}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
        raise ModelError("interpolation parameters must be finite and strictly increasing")
    if t[0] != 0.0 or (t[-1] >= 1.0 if closed else t[-1] != 1.0):
        raise ModelError("parameters must start at 0 and end at 1 (open) or below 1 (closed)")
    return t


def averaged_knots(params, degree):
    """Clamped knot vector by averaging (NURBS Book eq. 9.8), length k + p + 1.

    u_0 = … = u_p = 0, u_{j+p} = (1/p) sum_{i=j}^{j+p-1} t_i (j = 1..k-p-1),
    u_k = … = u_{k+p} = 1. Every knot span then holds a parameter, so the collocation
    matrix N of eq. 3.18 is nonsingular (Schoenberg–Whitney).
    """
    t = _check(params, degree, closed=False)
    k, p = t.size, int(degree)
    inner = [np.sum(t[j:j + p]) / p for j in range(1, k - p)]
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])


def periodic_knots(params, degree):
    """Unclamped knot vector of a closed curve through k points, period 1, length k + 2p + 1.

    Knots per period, τ_0 = 0 < τ_1 < … < τ_{k-1} < 1:

    * odd degree: the parameters, τ_j = t_j;
    * even degree: the midpoints (t_{j-1} + t_j) / 2, j = 1..k-1, and τ_0 = 0 in place of
      the midpoint across the seam (t_{k-1} + 1) / 2, so that the domain starts at 0.

    Extended periodically, u_{p+j+ik} = τ_j + i, so u_p = 0 and u_{k+p} = 1: the domain
    is [0, 1] for the k + p wrapped control points P_0..P_{k-1}, P_0..P_{p-1}. All knots are
    simple, so the curve is C^{p-1} everywhere. These choices keep the cyclic collocation
    matrix nonsingular (knots at the parameters for even degree would make it singular,
    e.g. uniform parameters with k even).
    """
    t = _check(params, degree, closed=True)
    k, p = t.size, int(degree)
    tau = t.copy() if p % 2 else np.concatenate([[0.0], 0.5 * (t[:-1] + t[1:])])
    i = np.arange(k + 2 * p + 1) - p
    return tau[i % k] + np.floor_divide(i, k)
