"""numba kernels of contact detection (stage 4 of a step, DESIGN.md): the broad-phase box
test, Newton on eq. 3.6 over a neutral contour evaluated span-locally, and the contact
frame, relative velocity and Jacobian pieces of eq. 3.4–3.8.

The Newton kernels read the contour from its ``kernel_data`` (knots, degrees, domains,
P_ū0, P_Φ, the state vector and the span cache of :mod:`contours.neutral._kernels`) and
evaluate it by :func:`~contours.neutral._kernels.fields_1s` /
:func:`~contours.neutral._kernels.fields_2s` (an offset contour — band, cylinder — by
:func:`~contours._offset_kernels.offset_fields` over its neutral curve's) — no Python
per iteration. Their reference
is the Python Newton of :mod:`contact.search` (``compiled=False``) over
``contour.evaluate``; the others have their numpy formulas in the docstrings.
``tests/unit/contact/test_compiled_contact.py`` compares them.
"""

from __future__ import annotations

from numba import njit

from contours._offset_kernels import offset_fields, offsets
from contours.neutral._kernels import fields_1s, fields_2s

SINGULAR = 1e-10  # det H ≤ this × |t_η|² |t_ξ|² (1s: |H| ≤ this × |t_η|²): not definite


@njit(cache=True)
def boxes_overlap(box1, box2, margin):
    """True if the boxes (2, 3) [m] (rows min, max), each grown by ``margin`` [m], overlap:
    lo1 − 2m ≤ hi2 and lo2 − 2m ≤ hi1 on every axis (infinite bounds allowed)."""
    m = 2.0 * margin
    for c in range(3):
        if not (box1[0, c] - m <= box2[1, c] and box2[0, c] - m <= box1[1, c]):
            return False
    return True


@njit(cache=True)
def _wrap(t, a, b, closed):
    """(t in [a, b], True if an open direction had to clip t); a closed one wraps t."""
    if closed:
        return a + (t - a) % (b - a), False
    if t < a:
        return a, True
    if t > b:
        return b, True
    return t, False


@njit(cache=True)
def _step(t, dt, a, b, closed, max_step):
    """t + dt with |dt| capped at ``max_step``, wrapped or clipped by :func:`_wrap`."""
    return _wrap(t + min(max(dt, -max_step), max_step), a, b, closed)


@njit(cache=True)
def _dot(x, y):
    """xᵀ y of two 3-vectors."""
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]


@njit(cache=True)
def _gap(r_point, D, g):
    """g = r_P − r (3,) [m] from row 0 of D; returns |g|²."""
    for c in range(3):
        g[c] = r_point[c] - D[0, c]
    return _dot(g, g)


@njit(cache=True)
def side(t, a, b, closed):
    """+1 when t is on the upper bound b of an open direction, −1 on its lower bound a,
    else 0."""
    if closed:
        return 0
    if t >= b:
        return 1
    if t <= a:
        return -1
    return 0


@njit(cache=True)
def stationary(f, a, tol2, edge2, at):
    """Whether the tangent projection f = tᵀ g [m²] (a = tᵀ t) of an iterate is solved:
    f² ≤ tol2 · a, or the iterate is on a bound (``at`` = ±1, :func:`side`) and the point
    lies beyond it (f has the sign of ``at``) by at most √edge2 [m] (f² ≤ edge2 · a): the
    closest point of the domain is on its boundary, and a point on the boundary is on
    the contour (the projection clamped to the domain, with the tolerance √edge2)."""
    return f * f <= tol2 * a or (at * f > 0.0 and f * f <= edge2 * a)


@njit(cache=True)
def _newton_2s_direction(r_point, D, g, tol2, edge2, at_e, at_x):
    """One Newton iteration's test and step on eq. 3.31–3.32 from the fields D (6, 3) at
    the iterate (g = r_P − r into g; ``at_e``, ``at_x``: the iterate's bounds, :func:`side`):
    returns (|g|² [m²], converged (:func:`stationary`), minimum, Δη, Δξ, degenerate).
    ``minimum``: H negative definite (a distance minimum); the step is Newton's there,
    else Gauss–Newton's; ``degenerate``: the Gauss–Newton matrix is singular (no step,
    Δη = Δξ = 0)."""
    gg = _gap(r_point, D, g)
    f0, f1 = _dot(D[1], g), _dot(D[2], g)
    a, b, c = _dot(D[1], D[1]), _dot(D[1], D[2]), _dot(D[2], D[2])
    h11, h12, h22 = _dot(D[3], g) - a, _dot(D[4], g) - b, _dot(D[5], g) - c
    det = h11 * h22 - h12 * h12
    minimum = h11 < 0.0 and det > SINGULAR * a * c
    converged = stationary(f0, a, tol2, edge2, at_e) and stationary(f1, c, tol2, edge2, at_x)
    if not minimum:  # Gauss–Newton: a descent direction of |g|²
        h11, h12, h22, det = -a, -b, -c, a * c - b * b
        if det <= SINGULAR * a * c:
            return gg, converged, minimum, 0.0, 0.0, True   # degenerate parametrization
    return gg, converged, minimum, (h12 * f1 - h22 * f0) / det, (h12 * f0 - h11 * f1) / det, False


@njit(cache=True)
def newton_2s(r_point, eta, xi, knots_e, knots_x, ints, floats, ctrl0, phi, state, span, max_step_e, max_step_x,
              tol2, edge2, max_iter, B, local, D, g):
    """Newton on g_η = t_ηᵀ g = 0, g_ξ = t_ξᵀ g = 0 (thesis eq. 3.31–3.32), g = r_P − r(η, ξ),
    from (η, ξ) on a neutral 2s contour (the algorithm of
    :meth:`contact.search.Contact2sSearch._newton_reference`, see :mod:`contact.search`).

    ``max_step_*`` cap a step per coordinate, ``tol2`` = (tol · length scale)² [m²],
    ``edge2`` [m²] the square of how far beyond a bound a point may lie and still project
    onto it (:func:`stationary`); B, local, D (6, 3), g (3,) are work arrays. Returns (found, η, ξ, |g|² [m²],
    iterations of the converged start, Newton steps taken); found is False when Newton
    failed or stopped at a maximum or saddle of the distance.
    """
    ae, be, ax, bx = floats[0], floats[1], floats[2], floats[3]
    ce, cx = ints[2] != 0, ints[5] != 0
    eta = _wrap(eta, ae, be, ce)[0]
    xi = _wrap(xi, ax, bx, cx)[0]
    clipped = 0
    steps = 0
    for k in range(max_iter + 1):
        fields_2s(eta, xi, knots_e, knots_x, ints, floats, ctrl0, phi, state, span, B, local, D)
        gg, converged, minimum, d_eta, d_xi, degenerate = _newton_2s_direction(
            r_point, D, g, tol2, edge2, side(eta, ae, be, ce), side(xi, ax, bx, cx))
        if converged:
            return minimum, eta, xi, gg, k, steps
        if k == max_iter:
            break
        steps += 1
        if degenerate:
            break
        eta, out_e = _step(eta, d_eta, ae, be, ce, max_step_e)
        xi, out_x = _step(xi, d_xi, ax, bx, cx, max_step_x)
        clipped = clipped + 1 if (out_e or out_x) else 0
        if clipped == 2:
            break        # the root lies outside the contour
    return False, eta, xi, 0.0, max_iter, steps


@njit(cache=True)
def newton_offset(r_point, eta, xi, knots, ints, floats, ctrl0, phi, state, span, n0, law, size, ax, bx, cx,
                  max_step_e, max_step_x, tol2, edge2, max_iter, B, local, rows, frame, D, g):
    """:func:`newton_2s` on an offset contour (band, cylinder: :mod:`contours.derived`):
    the fields from :func:`~contours._offset_kernels.offset_fields` over the neutral
    curve's ``kernel_data`` (knots … span) and body-frame reference normal n0, the offsets
    at ξ from the law (``law``, ``size``) of :func:`~contours._offset_kernels.offsets`;
    ξ ∈ [ax, bx], closed if ``cx``. B, local, rows, frame, D, g are the work arrays of
    ``contour.kernel_workspace()`` and g (3,). Returns as :func:`newton_2s`."""
    ae, be, ce = floats[0], floats[1], ints[2] != 0
    eta = _wrap(eta, ae, be, ce)[0]
    xi = _wrap(xi, ax, bx, cx)[0]
    clipped = 0
    steps = 0
    for k in range(max_iter + 1):
        al, bt, al1, bt1, al2, bt2 = offsets(law, size, xi)
        offset_fields(eta, knots, ints, floats, ctrl0, phi, state, span, n0, al, bt, al1, bt1, al2, bt2, B, local,
                      rows, frame, D)
        gg, converged, minimum, d_eta, d_xi, degenerate = _newton_2s_direction(
            r_point, D, g, tol2, edge2, side(eta, ae, be, ce), side(xi, ax, bx, cx))
        if converged:
            return minimum, eta, xi, gg, k, steps
        if k == max_iter:
            break
        steps += 1
        if degenerate:
            break
        eta, out_e = _step(eta, d_eta, ae, be, ce, max_step_e)
        xi, out_x = _step(xi, d_xi, ax, bx, cx, max_step_x)
        clipped = clipped + 1 if (out_e or out_x) else 0
        if clipped == 2:
            break        # the root lies outside the contour
    return False, eta, xi, 0.0, max_iter, steps


@njit(cache=True)
def newton_1s(r_point, eta, knots, ints, floats, ctrl0, phi, state, span, max_step, tol2, edge2, max_iter, B,
              local, D, g):
    """Newton on g_η = t_ηᵀ (r_P − r(η)) = 0 (eq. 3.6 on a curve) from η on a neutral 1s
    contour (the algorithm of :meth:`contact.search.Contact1sSearch._newton_reference`).
    Arguments as for :func:`newton_2s`; returns (found, η, |g|² [m²], iterations of the
    converged start, Newton steps taken)."""
    a_, b_, closed = floats[0], floats[1], ints[2] != 0
    eta = _wrap(eta, a_, b_, closed)[0]
    clipped = 0
    steps = 0
    for k in range(max_iter + 1):
        fields_1s(eta, knots, ints, floats, ctrl0, phi, state, span, B, local, D)
        gg = _gap(r_point, D, g)
        f, a = _dot(D[1], g), _dot(D[1], D[1])
        h = _dot(D[3], g) - a
        minimum = h < -SINGULAR * a
        if stationary(f, a, tol2, edge2, side(eta, a_, b_, closed)):
            return minimum, eta, gg, k, steps
        if k == max_iter or a == 0.0:
            break
        steps += 1
        eta, out = _step(eta, -f / (h if minimum else -a), a_, b_, closed, max_step)  # else Gauss–Newton
        clipped = clipped + 1 if out else 0
        if clipped == 2:
            break
    return False, eta, 0.0, max_iter, steps


@njit(cache=True)
def edge_frame(F, centre, D):
    """The frame of a sphere's centre c against an edge (a curve) at its closest point
    r_C2 = D[0]: n = (c − r_C2)/|c − r_C2| (from the edge to the centre), t1 the curve's
    unit tangent F[:, 0] made perpendicular to n, t2 = n × t1, into the columns of F
    (3, 3). False (F unchanged) when c lies on the curve or n is along the tangent."""
    d0, d1, d2 = centre[0] - D[0, 0], centre[1] - D[0, 1], centre[2] - D[0, 2]
    dist = (d0 * d0 + d1 * d1 + d2 * d2) ** 0.5
    if dist == 0.0:
        return False
    n0, n1, n2 = d0 / dist, d1 / dist, d2 / dist
    s = F[0, 0] * n0 + F[1, 0] * n1 + F[2, 0] * n2
    t0, t1, t2 = F[0, 0] - s * n0, F[1, 0] - s * n1, F[2, 0] - s * n2
    size = (t0 * t0 + t1 * t1 + t2 * t2) ** 0.5
    if size <= 1e-12:
        return False
    F[0, 0], F[1, 0], F[2, 0] = t0 / size, t1 / size, t2 / size
    F[0, 2], F[1, 2], F[2, 2] = n0, n1, n2
    F[0, 1] = n1 * F[2, 0] - n2 * F[1, 0]
    F[1, 1] = n2 * F[0, 0] - n0 * F[2, 0]
    F[2, 1] = n0 * F[1, 0] - n1 * F[0, 0]
    return True


@njit(cache=True)
def normal_gap(F, centre, D, radius):
    """g_N = nᵀ (c − r_C2) − ρ [m] (thesis eq. 3.4) with n = F[:, 2] and r_C2 = D[0]."""
    s = 0.0
    for c in range(3):
        s += F[c, 2] * (centre[c] - D[0, c])
    return s - radius


@njit(cache=True)
def frame_rates_jacobians(F, v1, v2, J1, J2, velocity, jacobians, n, T, gd_T, w_N1, w_N2, w_T1, w_T2):
    """Contact frame and the pieces of eq. 3.8 from contour 2's frame F (3, 3) (columns
    t1, t2, n): n = F[:, 2], T = F[:, :2]; with ``velocity`` ġ_T = Tᵀ (v1 − v2) into gd_T
    and the return value ġ_N = nᵀ (v1 − v2) [m/s] (else 0); with ``jacobians``
    w_N1 = J1ᵀ n, w_N2 = −J2ᵀ n, w_T1 = J1ᵀ T, w_T2 = −J2ᵀ T (J1 (3, nu1), J2 (3, nu2))."""
    for c in range(3):
        n[c] = F[c, 2]
        T[c, 0] = F[c, 0]
        T[c, 1] = F[c, 1]
    gd_N = 0.0
    if velocity:
        gd_T[0] = gd_T[1] = 0.0
        for c in range(3):
            dv = v1[c] - v2[c]
            gd_N += n[c] * dv
            gd_T[0] += T[c, 0] * dv
            gd_T[1] += T[c, 1] * dv
    if jacobians:
        _project(J1, n, T, 1.0, w_N1, w_T1)
        _project(J2, n, T, -1.0, w_N2, w_T2)
    return gd_N


@njit(cache=True)
def _project(J, n, T, sign, w_N, w_T):
    """w_N = sign · Jᵀ n, w_T = sign · Jᵀ T."""
    for j in range(J.shape[1]):
        a = J[0, j] * n[0] + J[1, j] * n[1] + J[2, j] * n[2]
        b = J[0, j] * T[0, 0] + J[1, j] * T[1, 0] + J[2, j] * T[2, 0]
        c = J[0, j] * T[0, 1] + J[1, j] * T[1, 1] + J[2, j] * T[2, 1]
        w_N[j] = sign * a
        w_T[j, 0] = sign * b
        w_T[j, 1] = sign * c


@njit(cache=True)
def assemble_W(out, col, dim, start1, w_N1, w_T1, start2, w_N2, w_T2):
    """W = [W_N] (dim 1) or [W_N, W_T] (dim 3) (eq. 3.8) into the columns col..col + dim of
    ``out`` (nu_total, ≥ col + dim) from the bodies' pieces: zero, then the pieces added at
    rows start_i.. (start_i < 0: the ground, no rows); both contours may sit on one body.
    ``out`` is the whole array (not a column slice), so the kernel sees one layout."""
    for i in range(out.shape[0]):
        for k in range(dim):
            out[i, col + k] = 0.0
    _add_block(out, col, dim, start1, w_N1, w_T1)
    _add_block(out, col, dim, start2, w_N2, w_T2)


@njit(cache=True)
def _add_block(out, col, dim, start, w_N, w_T):
    """out[start + j, col..] += (w_N[j], w_T[j]) (the W_T columns only when dim is 3)."""
    if start < 0:
        return
    for j in range(w_N.shape[0]):
        out[start + j, col] += w_N[j]
        if dim == 3:
            out[start + j, col + 1] += w_T[j, 0]
            out[start + j, col + 2] += w_T[j, 1]
