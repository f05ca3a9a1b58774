"""Plain-numpy references for B-spline evaluation, used by the tests of the numba kernels.

Written for clarity, not speed: all basis functions of a knot vector from the Cox–de Boor
recursion exactly as thesis eq. 3.11–3.13 state it, and curve and surface points as the
straightforward sums of eq. 3.9 and 3.23 with unit weights (w_i = 1, so R_{i,p} = N_{i,p},
eq. 3.10).
"""

from __future__ import annotations


import numpy as np


def _ratio(num, den):
    """num / den with the convention 0/0 := 0 (a zero knot span kills its term)."""
    return 0.0 if den == 0.0 else num / den


def basis_functions(knots, p, t, nd=0):
    """All basis functions N_{i,p}(t), i = 0..n_ctrl-1, and their derivatives 0..nd.

    Parameters
    ----------
    knots : (n_ctrl + p + 1,) knot vector U, non-decreasing.
    p : degree.
    t : parameter in the domain [knots[p], knots[n_ctrl]].
    nd : highest derivative order.

    Returns
    -------
    (nd + 1, n_ctrl) array; row k holds d^k N_{i,p} / dt^k.

    Degree 0 (eq. 3.11) uses half-open spans u_i <= t < u_{i+1}, except that t at the
    right end of the domain belongs to the last nonempty span (NURBS Book p. 68). Higher
    degrees use eq. 3.12–3.13, derivatives NURBS Book eq. 2.9, both with 0/0 := 0.
    """
    u = np.asarray(knots, dtype=float)
    n_ctrl = len(u) - p - 1
    if t >= u[n_ctrl]:
        span = max(i for i in range(p, n_ctrl) if u[i] < u[i + 1])
    else:
        span = next(i for i in range(len(u) - 1) if u[i] <= t < u[i + 1])
    # N[q][i] = N_{i,q}(t) for i = 0..len(u)-q-2
    N = [[1.0 if i == span else 0.0 for i in range(len(u) - 1)]]
    for q in range(1, p + 1):
        prev = N[-1]
        N.append([_ratio(t - u[i], u[i + q] - u[i]) * prev[i]
                  + _ratio(u[i + q + 1] - t, u[i + q + 1] - u[i + 1]) * prev[i + 1]
                  for i in range(len(u) - q - 1)])
    out = np.zeros((nd + 1, n_ctrl))
    out[0] = N[p][:n_ctrl]
    for k in range(1, min(nd, p) + 1):
        # D[i] = d^k N_{i,q} / dt^k, raised from q = p - k (D = N) to q = p
        D = N[p - k]
        for q in range(p - k + 1, p + 1):
            D = [q * (_ratio(D[i], u[i + q] - u[i]) - _ratio(D[i + 1], u[i + q + 1] - u[i + 1]))
                 for i in range(len(u) - q - 1)]
        out[k] = D[:n_ctrl]
    return out


def curve_point(knots, p, ctrl, t, nd=0):
    """C^(k)(t) = sum_i N^(k)_{i,p}(t) P_i, k = 0..nd (eq. 3.9, w_i = 1) -> (nd + 1, m).

    ``ctrl`` (n_ctrl, m); ``t`` in the domain (no wrapping or clipping here).
    """
    return basis_functions(knots, p, t, nd) @ np.asarray(ctrl, dtype=float)


def surface_point(knots_eta, p_eta, knots_xi, p_xi, ctrl, eta, xi, nd=0):
    """∂^{a+b}S/∂η^a∂ξ^b = sum_ij N^(a)_{i}(η) N^(b)_{j}(ξ) P_ij (eq. 3.23, w_ij = 1).

    ``ctrl`` (n_eta, n_xi, m) -> (nd + 1, nd + 1, m), all a, b <= nd.
    """
    Ne = basis_functions(knots_eta, p_eta, eta, nd)
    Nx = basis_functions(knots_xi, p_xi, xi, nd)
    return np.einsum("ai,bj,ijc->abc", Ne, Nx, np.asarray(ctrl, dtype=float))
