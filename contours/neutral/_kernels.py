"""numba kernels of the neutral contours: basis tables at a point, contractions of
control-point arrays with them, control-point updates, the contour frame, and the
span-local evaluation of a contour from its per-step state.

Plain-numpy references: :func:`contours.nurbs.basis.curve_point` /
:func:`~contours.nurbs.basis.surface_point` for the contractions and the formulas in
the docstrings for the rest; ``tests/unit/contours/test_neutral_contours.py`` compares them. The
span-local evaluation (:func:`evaluate_1s`, :func:`evaluate_2s`, :func:`local_rows_1s`,
:func:`local_rows_2s`, :func:`bounding_box`) has the full control-point route of
:mod:`.products` as its reference (``compiled=False`` on the contour),
compared in ``tests/unit/contact/test_compiled_contact.py``.

Per-step state of a neutral contour (``state``, written by :func:`store_state`): the
frame origin R [m] at ``R_AT``, the orientation A (row-major) at ``A_AT``, the origin
velocity v [m/s] at ``V_AT``, the body-frame angular velocity ω̄ [rad/s] at ``W_AT``, a
stamp counting the updates at ``STAMP_AT``, then q_f (n_f,) and q̇_f (n_f,) from
``Q_AT``. Geometry of a direction: its knots and, in ``ints`` (p, n_ctrl, closed) and
``floats`` (a, b) per direction, the degree, the number of control points, closedness
and the domain [a, b]. ``span`` caches the ū control points of the span last used,
P_ū0 + P_Φ q_f, after its key (stamp, s_η, s_ξ): evaluations in the same span at the
same state (Newton iterations, then the contact point itself) skip the O(n_f) part.

Constant arguments of nested kernel calls are passed as typed values (``np.int64(0)``,
``np.bool_(True)``): numba compiles a callee apart for every literal argument, once more
beside the runtime-typed version the other callers use (``tests/qa/test_compile_once.py``).
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


R_AT, A_AT, V_AT, W_AT, STAMP_AT, Q_AT = 0, 3, 12, 15, 18, 19
SPAN_KEY = 3   # span[:3] = (stamp, s_η, s_ξ), then the control points (3 each)


@numba.njit(cache=True)
def store_state(state, R, A, q_f):
    """R, A, q_f into the state vector and a new stamp (the cached span is stale)."""
    for c in range(3):
        state[R_AT + c] = R[c]
        for d in range(3):
            state[A_AT + 3 * c + d] = A[c, d]
    for k in range(q_f.shape[0]):
        state[Q_AT + k] = q_f[k]
    state[STAMP_AT] += 1.0


@numba.njit(cache=True)
def store_velocity(state, v, w, qdot_f):
    """v, ω̄, q̇_f into the state vector."""
    n_f = qdot_f.shape[0]
    for c in range(3):
        state[V_AT + c] = v[c]
        state[W_AT + c] = w[c]
    for k in range(n_f):
        state[Q_AT + n_f + k] = qdot_f[k]


@numba.njit(cache=True, fastmath={"reassoc"})
def _modal(row, o, state, start, n_f):
    """Σ_k row[o + k] state[start + k]: one component of P_Φ q_f (start ``Q_AT``) or
    Φ q̇_f (start ``Q_AT + n_f``); summed in any order (vectorized)."""
    s = 0.0
    for k in range(n_f):
        s += row[o + k] * state[start + k]
    return s


@numba.njit(cache=True)
def _span_ctrl_1s(s, p, ctrl0, phi, state, span):
    """span[SPAN_KEY:] ← the ū control points s−p..s of a curve, P_ū0 + P_Φ q_f (thesis
    eq. 2.23 by linearity of the interpolation; ctrl0 (n, 3), phi (n, 3 n_f)), unless
    span already holds them for this state."""
    if span[0] == state[STAMP_AT] and span[1] == s:
        return
    n_f = phi.shape[1] // 3
    o = SPAN_KEY
    for a in range(p + 1):
        for c in range(3):
            span[o] = ctrl0[s - p + a, c] + _modal(phi[s - p + a], c * n_f, state, np.int64(Q_AT), n_f)
            o += 1
    span[0], span[1], span[2] = state[STAMP_AT], s, 0.0


@numba.njit(cache=True)
def _span_ctrl_2s(se, pe, sx, px, ctrl0, phi, state, span):
    """span[SPAN_KEY:] ← the (p_η + 1)(p_ξ + 1) ū control points of the span of a surface,
    P_ū0 + P_Φ q_f (ctrl0 (n_η, n_ξ, 3), phi (n_η, n_ξ, 3 n_f)), unless span already
    holds them for this state."""
    if span[0] == state[STAMP_AT] and span[1] == se and span[2] == sx:
        return
    n_f = phi.shape[2] // 3
    o = SPAN_KEY
    for a in range(pe + 1):
        for b in range(px + 1):
            row = phi[se - pe + a, sx - px + b]
            for c in range(3):
                span[o] = ctrl0[se - pe + a, sx - px + b, c] + _modal(row, c * n_f, state, np.int64(Q_AT), n_f)
                o += 1
    span[0], span[1], span[2] = state[STAMP_AT], se, sx


@numba.njit(cache=True)
def local_rows_1s(B, s, p, ctrl0, phi, state, span, nrows, out):
    """Rows of ū (6, 3) [m] of a curve at the point located by B (3, p+1), span s:
    ū, ū_η, ū_ηη in rows 0, 1, 3 (rows 2, 4, 5 zero), the first ``nrows`` (1, 3 or 6)
    rows written. Only the p + 1 control points of the span are formed (and cached in
    ``span``): O((p + 1) n_f), whatever the number of control points."""
    _span_ctrl_1s(s, p, ctrl0, phi, state, span)
    for r in range(nrows):
        for c in range(3):
            out[r, c] = 0.0
    o = SPAN_KEY
    for a in range(p + 1):
        for c in range(3):
            P = span[o]
            o += 1
            out[0, c] += B[0, a] * P
            if nrows > 1:
                out[1, c] += B[1, a] * P
            if nrows > 3:
                out[3, c] += B[2, a] * P


@numba.njit(cache=True)
def local_rows_2s(Be, se, pe, Bx, sx, px, ctrl0, phi, state, span, nrows, out):
    """Rows of ū (6, 3) [m] of a surface at the point located by (Be, se), (Bx, sx):
    ū, ū_η, ū_ξ, ū_ηη, ū_ηξ, ū_ξξ (thesis eq. 3.23, 3.25, 3.26), the first ``nrows``.
    Only the (p_η + 1)(p_ξ + 1) control points of the span are formed (and cached in
    ``span``): O((p_η + 1)(p_ξ + 1) n_f), whatever the number of control points."""
    _span_ctrl_2s(se, pe, sx, px, ctrl0, phi, state, span)
    for r in range(nrows):
        for c in range(3):
            out[r, c] = 0.0
    o = SPAN_KEY
    for a in range(pe + 1):
        for b in range(px + 1):
            w0 = Be[0, a] * Bx[0, b]
            w1 = Be[1, a] * Bx[0, b]
            w2 = Be[0, a] * Bx[1, b]
            w3 = Be[2, a] * Bx[0, b]
            w4 = Be[1, a] * Bx[1, b]
            w5 = Be[0, a] * Bx[2, b]
            for c in range(3):
                P = span[o]
                o += 1
                out[0, c] += w0 * P
                if nrows > 1:
                    out[1, c] += w1 * P
                    out[2, c] += w2 * P
                if nrows > 3:
                    out[3, c] += w3 * P
                    out[4, c] += w4 * P
                    out[5, c] += w5 * P


@numba.njit(cache=True)
def inertial_rows(state, local, nrows, out):
    """r = R + A ū (thesis eq. 2.24) in row 0 and A times the derivative rows 1..nrows-1
    of ``local`` (6, 3) into ``out`` (6, 3) [m]."""
    for r in range(nrows):
        for c in range(3):
            o = A_AT + 3 * c
            s = state[o] * local[r, 0] + state[o + 1] * local[r, 1] + state[o + 2] * local[r, 2]
            out[r, c] = state[R_AT + c] + s if r == 0 else s


@numba.njit(cache=True)
def point_velocity(state, u_bar, phi_value, v):
    """ṙ = v + A (ω̄ × ū + Φ q̇_f) [m/s] (thesis eq. 2.32) into v (3,) from ū (3,) and
    the mode-shape rows Φ (3 n_f,) (row-major (3, n_f)) at the point."""
    n_f = phi_value.shape[0] // 3
    w0, w1, w2 = state[W_AT], state[W_AT + 1], state[W_AT + 2]
    qd = Q_AT + n_f
    rel0 = w1 * u_bar[2] - w2 * u_bar[1] + _modal(phi_value, np.int64(0), state, qd, n_f)
    rel1 = w2 * u_bar[0] - w0 * u_bar[2] + _modal(phi_value, n_f, state, qd, n_f)
    rel2 = w0 * u_bar[1] - w1 * u_bar[0] + _modal(phi_value, 2 * n_f, state, qd, n_f)
    for c in range(3):
        o = A_AT + 3 * c
        v[c] = state[V_AT + c] + state[o] * rel0 + state[o + 1] * rel1 + state[o + 2] * rel2


@numba.njit(cache=True)
def fields_1s(eta, knots, ints, floats, ctrl0, phi, state, span, B, local, D):
    """Locate η (wrapped or clipped into the domain) and fill ``local`` with the rows of
    ū and ``D`` with those of r (rows 0, 1, 3; (6, 3) each) [m]; returns the span."""
    p = ints[0]
    s = locate(knots, p, ints[1], ints[2] != 0, floats[0], floats[1], eta, B)
    local_rows_1s(B, s, p, ctrl0, phi, state, span, np.int64(6), local)
    inertial_rows(state, local, np.int64(6), D)
    return s


@numba.njit(cache=True)
def fields_2s(eta, xi, knots_e, knots_x, ints, floats, ctrl0, phi, state, span, B, local, D):
    """Locate (η, ξ) (wrapped or clipped into the domain; basis tables into B[0], B[1])
    and fill ``local`` with ū, ū_η, ū_ξ, ū_ηη, ū_ηξ, ū_ξξ and ``D`` with the same rows
    of r (6, 3) [m]; returns the spans (s_η, s_ξ)."""
    pe, px = ints[0], ints[3]
    se = locate(knots_e, pe, ints[1], ints[2] != 0, floats[0], floats[1], eta, B[0])
    sx = locate(knots_x, px, ints[4], ints[5] != 0, floats[2], floats[3], xi, B[1])
    local_rows_2s(B[0], se, pe, B[1], sx, px, ctrl0, phi, state, span, np.int64(6), local)
    inertial_rows(state, local, np.int64(6), D)
    return se, sx


@numba.njit(cache=True)
def evaluate_1s(eta, knots, ints, floats, ctrl0, phi, state, span, n_ref, modal, velocity, B, local, phi_rows,
                D, F, v):
    """A curve point from the state, span-local: r, r_η, r_ηη into D (6, 3), the frame
    (t1, t2, n) of :func:`frame_1s` into F; with ``modal`` the mode-shape rows Φ (3 n_f,)
    into phi_rows[0] and with ``velocity`` (needs ``modal``) ṙ into v (eq. 2.32)."""
    s = fields_1s(eta, knots, ints, floats, ctrl0, phi, state, span, B, local, D)
    frame_1s(D, n_ref, F)
    if modal:
        contract_curve(B, s, ints[0], phi, np.int64(1), phi_rows)
    if velocity:
        point_velocity(state, local[0], phi_rows[0], v)


@numba.njit(cache=True)
def evaluate_2s(eta, xi, knots_e, knots_x, ints, floats, ctrl0, phi, state, span, sign, modal, velocity,
                B, local, phi_rows, D, F, v):
    """A surface point from the state, span-local: r and its derivatives into D (6, 3)
    (eq. 3.23, 3.25, 3.26), the frame of :func:`frame_2s` (eq. 3.27–3.29) into F; with
    ``modal`` the mode-shape rows Φ (3 n_f,) into phi_rows[0] and with ``velocity``
    (needs ``modal``) ṙ into v (eq. 2.32)."""
    se, sx = fields_2s(eta, xi, knots_e, knots_x, ints, floats, ctrl0, phi, state, span, B, local, D)
    frame_2s(D, sign, F)
    if modal:
        contract_surface(B[0], se, ints[0], B[1], sx, ints[3], phi, np.int64(1), phi_rows)
    if velocity:
        point_velocity(state, local[0], phi_rows[0], v)


@numba.njit(cache=True)
def _grown(lo0, hi0, phi_bound, state, c):
    """(centre, half edge) [m] along body axis c of the undeformed control points' box
    [lo0, hi0] grown by e_c = Σ_k phi_bound[c, k] |q_f,k|."""
    e = 0.0
    for k in range(phi_bound.shape[1]):
        e += phi_bound[c, k] * abs(state[Q_AT + k])
    return 0.5 * (lo0[c] + hi0[c]), 0.5 * (hi0[c] - lo0[c]) + e


@numba.njit(cache=True)
def bounding_box(lo0, hi0, phi_bound, state, out):
    """A box (2, 3) [m] (rows min, max) around every position control point, O(n_f):
    the body-frame box [lo0, hi0] of the undeformed control points grown by
    e_c = Σ_k phi_bound[c, k] |q_f,k| (phi_bound[c, k] = max_i |P_Φ,i,ck|, so
    |(P_Φ q_f)_ic| <= e_c), then the box of its image under r = R + A ū (eq. 2.24):
    centre R + A m, half edges |A| h. Contains the contour (convex hull property);
    looser than the control points' own box when A rotates or q_f ≠ 0."""
    m0, h0 = _grown(lo0, hi0, phi_bound, state, np.int64(0))
    m1, h1 = _grown(lo0, hi0, phi_bound, state, np.int64(1))
    m2, h2 = _grown(lo0, hi0, phi_bound, state, np.int64(2))
    for c in range(3):
        o = A_AT + 3 * c
        m = state[R_AT + c] + state[o] * m0 + state[o + 1] * m1 + state[o + 2] * m2
        h = abs(state[o]) * h0 + abs(state[o + 1]) * h1 + abs(state[o + 2]) * h2
        out[0, c] = m - h
        out[1, c] = m + h
