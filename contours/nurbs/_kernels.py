"""numba kernels for B-spline evaluation (unit weights, thesis eq. 3.9–3.17 with w_i = 1).

Pure functions on float64 arrays; none allocates when its ``out``/``work`` arrays are
given. Plain-numpy references are in :mod:`contours.nurbs.basis`, and the tests compare
the two.

Conventions: a knot vector ``knots`` of length ``n_ctrl + p + 1`` for ``n_ctrl`` control
points of degree ``p``; the domain is ``[knots[p], knots[n_ctrl]]``. Open curves use a
clamped vector on [0, 1]; closed (periodic) curves an unclamped one whose domain is
[0, 1], with the first ``p`` control points repeated at the end ("wrapped"), so that the
same evaluation code serves both (see :mod:`contours.nurbs.knots`).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def find_span(knots, p, n_ctrl, t):
    """Knot span index s with ``knots[s] <= t < knots[s+1]``, ``p <= s <= n_ctrl - 1``.

    NURBS Book A2.1 (binary search). ``t`` at (or beyond) the right end of the domain,
    ``knots[n_ctrl]``, goes to the last span ``n_ctrl - 1``; ``t`` left of the domain to
    the first span ``p``.
    """
    if t >= knots[n_ctrl]:
        return n_ctrl - 1
    if t <= knots[p]:
        return p
    low = p
    high = n_ctrl
    mid = (low + high) // 2
    while t < knots[mid] or t >= knots[mid + 1]:
        if t < knots[mid]:
            high = mid
        else:
            low = mid
        mid = (low + high) // 2
    return mid


@njit(cache=True)
def wrap_parameter(t, a, b, closed):
    """Map a parameter into the domain [a, b].

    closed: ``a + (t - a) mod (b - a)`` (period ``b - a``); open: ``t`` clipped to [a, b].
    """
    if closed:
        period = b - a
        return a + (t - a) - math.floor((t - a) / period) * period
    return min(max(t, a), b)


@njit(cache=True)
def ders_basis(knots, p, span, t, nd, out):
    """Derivatives 0..nd of the p + 1 nonzero basis functions N_{span-p..span, p}(t).

    Fills ``out`` (nd + 1, p + 1): ``out[k, j] = d^k N_{span-p+j, p} / dt^k`` (1/[t]^k).
    Same result as NURBS Book A2.3, computed in place without scratch arrays:

    1. the Cox–de Boor recursion (thesis eq. 3.11–3.13, NURBS Book A2.2) raises the
       degree from 0 to p in one row; when it reaches degree p - k (k = nd..1), that row
       is copied into ``out[k]``;
    2. each ``out[k]`` is then differentiated k times by NURBS Book eq. 2.9,
       N'_{i,q} = q N_{i,q-1} / (u_{i+q} - u_i) - q N_{i+1,q-1} / (u_{i+q+1} - u_{i+1}),
       with 0/0 := 0 for repeated knots.

    Rows k > p are zero. ``span`` must come from :func:`find_span`.
    """
    for k in range(nd + 1):
        for j in range(p + 1):
            out[k, j] = 0.0
    # step 1: basis functions of degree q = 0..p in out[0, :q+1], N_{span-q..span, q}
    out[0, 0] = 1.0
    if 1 <= p <= nd:
        out[p, 0] = 1.0
    for q in range(1, p + 1):
        saved = 0.0
        for r in range(q):
            right = knots[span + r + 1] - t
            left = t - knots[span + 1 - q + r]
            temp = out[0, r] / (right + left)
            out[0, r] = saved + right * temp
            saved = left * temp
        out[0, q] = saved
        k = p - q
        if 1 <= k <= nd:
            for j in range(q + 1):
                out[k, j] = out[0, j]
    # step 2: differentiate row k (degree p - k values) k times, raising q = p-k+1..p
    for k in range(1, min(nd, p) + 1):
        for q in range(p - k + 1, p + 1):
            # row holds values for i = span-q+1..span at positions 0..q-1; the result
            # for i = span-q..span goes to positions 0..q (downward, in place)
            for r in range(q, -1, -1):
                i = span - q + r
                val = 0.0
                if r >= 1:
                    d = knots[i + q] - knots[i]
                    if d > 0.0:
                        val += out[k, r - 1] / d
                if r <= q - 1:
                    d = knots[i + q + 1] - knots[i + 1]
                    if d > 0.0:
                        val -= out[k, r] / d
                out[k, r] = q * val
    return out


@njit(cache=True)
def curve_derivs(knots, p, ctrl, t, nd, closed, work, out):
    """Curve point and derivatives C^(k)(t), k = 0..nd (thesis eq. 3.9 with w_i = 1).

    NURBS Book A3.2. ``ctrl`` (n_ctrl, m) control points (wrapped for closed curves);
    ``work`` (nd + 1, p + 1) scratch for the basis derivatives; ``out`` (nd + 1, m):
    ``out[k] = d^k C / dt^k`` in [ctrl]/[t]^k. ``t`` is wrapped (closed) or clipped (open)
    into the domain ``[knots[p], knots[n_ctrl]]`` first.
    """
    n_ctrl = ctrl.shape[0]
    m = ctrl.shape[1]
    t = wrap_parameter(t, knots[p], knots[n_ctrl], closed)
    span = find_span(knots, p, n_ctrl, t)
    ders_basis(knots, p, span, t, nd, work)
    for k in range(nd + 1):
        for c in range(m):
            acc = 0.0
            for j in range(p + 1):
                acc += work[k, j] * ctrl[span - p + j, c]
            out[k, c] = acc
    return out


@njit(cache=True)
def surface_derivs(knots_eta, p_eta, knots_xi, p_xi, ctrl, eta, xi, nd, closed_eta, closed_xi,
                   work_eta, work_xi, out):
    """Surface point and partial derivatives (thesis eq. 3.23 with w_ij = 1).

    NURBS Book A3.6. ``ctrl`` (n_eta, n_xi, m) control points (wrapped along closed
    directions); ``work_eta`` (nd + 1, p_eta + 1) and ``work_xi`` (nd + 1, p_xi + 1)
    scratch; ``out`` (nd + 1, nd + 1, m): ``out[a, b] = ∂^{a+b} S / ∂η^a ∂ξ^b`` for
    a + b <= nd, zero otherwise. (η, ξ) are wrapped or clipped into the domain first.
    """
    n_eta = ctrl.shape[0]
    n_xi = ctrl.shape[1]
    m = ctrl.shape[2]
    eta = wrap_parameter(eta, knots_eta[p_eta], knots_eta[n_eta], closed_eta)
    xi = wrap_parameter(xi, knots_xi[p_xi], knots_xi[n_xi], closed_xi)
    s_eta = find_span(knots_eta, p_eta, n_eta, eta)
    s_xi = find_span(knots_xi, p_xi, n_xi, xi)
    ders_basis(knots_eta, p_eta, s_eta, eta, nd, work_eta)
    ders_basis(knots_xi, p_xi, s_xi, xi, nd, work_xi)
    for a in range(nd + 1):
        for b in range(nd + 1):
            for c in range(m):
                out[a, b, c] = 0.0
    for a in range(nd + 1):
        for i in range(p_eta + 1):
            na = work_eta[a, i]
            row = s_eta - p_eta + i
            for b in range(nd - a + 1):
                for j in range(p_xi + 1):
                    w = na * work_xi[b, j]
                    col = s_xi - p_xi + j
                    for c in range(m):
                        out[a, b, c] += w * ctrl[row, col, c]
    return out
