"""numba kernel of a fused detection (:mod:`mbs.fused_detection`): the contour stage
and the detection stage of one contact in one call, composed of the kernels of the
contours (:mod:`contours.neutral._kernels`), the contact search and kinematics
(:mod:`contact._detection_kernels`) and the bodies (:func:`mbs._kernels.point_jacobian_T`).

:func:`centre_on_neutral_2s` serves a point or a sphere on a point mass against a
neutral 2s contour of a body on a frame fixed in space (a
:class:`~contact.kinematics.ContactKinematicsPointContour2s` or
:class:`~contact.kinematics.ContactKinematicsSphereContour2s` with its compiled
:class:`~contact.search.Contact2sSearch`). Its reference is the
Python path it replaces — ``contour.update`` of both contours, then
:meth:`contact.Contact.locate` (bounding boxes, ``search.solve`` warm-started,
``contour.evaluate``, :func:`~contact._detection_kernels.normal_gap`,
:func:`~contact._detection_kernels.frame_rates_jacobians`) — which
``tests/unit/contact/test_fused_detection.py`` compares it against.

The kernel takes each object's arrays as the one vector their views share
(:attr:`contours.base.ContourPoint.buffer`, :attr:`contact.kinematics.ContactKinematics.buffer`,
the frame contour's ``state``, the neutral contour's state and span cache), the
constants of the pair as one int table ``itab`` and one float table ``ftab`` (layouts
below, written by :class:`mbs.fused_detection.CentreOnNeutral2s`) and a work vector.

Constant arguments of nested kernel calls are passed as typed values (``np.int64(0)``,
``np.bool_(True)``): numba compiles a callee apart for every literal argument, once more
beside the runtime-typed version the other callers use (``tests/qa/test_compile_once.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from contact._detection_kernels import boxes_overlap, frame_rates_jacobians, newton_2s, normal_gap
from contact.search import LAST_ITERATIONS, NEWTON_ITERATIONS, NEWTON_SOLVES
from contours import rigid
from contours.rigid import sphere_angles
from contours._rigid_kernels import sphere_point
from contours.base import DERIVS_AT, FRAME_AT, J_AT, V_AT
from contours.neutral._kernels import A_AT, Q_AT, STAMP_AT, bounding_box, contract_surface, frame_2s, point_velocity

from ._kernels import point_jacobian_T

APART, LOCATED, FALLBACK = 0, 1, 2          # outcomes of a fused detection

# itab: the point's rows of q and u, the body's q_f and q̇_f rows, n_f, nu of the two
# bodies, velocity wanted (0/1), broad phase on (0/1), Newton iterations, the neutral
# contour's ints (6: p, n_ctrl, closed per direction), the knot vectors' lengths, the
# offsets of the kinematics buffer (contact.kinematics.buffer_layout, 8)
QP, UP, QF, UF, NF, NU1, NU2, VELOCITY, BOX, MAX_ITER = range(10)
GEOM_AT, KNOTS_E_N, KNOTS_X_N, KIN_AT = 10, 16, 17, 18
ITAB_SIZE = KIN_AT + 8
# ftab: margin [m], tol2 [m²] (NaN until the search knows its length scale), the largest
# Newton steps in η and ξ, the normal's sign, edge2 [m²] (contact.search: how far beyond
# the domain's boundary a point still projects onto it, squared), the point frame's offset ū0 (3) [m], the
# domain (4), the sphere's radius ρ [m] (0: a point), then the knots in η and ξ, the undeformed control points' box (lo (3),
# hi (3)) [m] and the bound of P_Φ (3, n_f) [m] (contours.neutral._kernels.bounding_box)
MARGIN, TOL2, MAX_STEP_E, MAX_STEP_X, SIGN, EDGE2 = range(6)
OFFSET_AT, FLOATS_AT, RADIUS, KNOTS_AT = 6, 9, 13, 14


MAX_DEGREE = 7
# the work vector: basis tables (2, 3, p_max + 1), ū rows (6, 3), r rows (6, 3), g (3,), then
# from WORK_AT the Φ rows (6, 3 n_f), two boxes (2, 3) and the direction −n (3,)
WORK_AT = 6 * (MAX_DEGREE + 1) + 39


def work_size(n_f):
    """Length of the work vector of a contour with n_f modes (degrees up to 7)."""
    return WORK_AT + 18 * n_f + 15


@njit(cache=True)
def centre_on_neutral_2s(q, u, itab, ftab, ctrl0, phi, state, span, frame1, point1, point2, kin, centre, axes1,
                         start, counts, work):
    """Stages 3 and 4 for one contact (module docstring) at the global (q, u) [m, m/s]:

    1. the contours' states: the point r = q_P + ū0, ṙ = u_P into ``frame1`` (the
       frame contour's state); q_f, q̇_f and a new stamp into the neutral contour's
       ``state`` (as :func:`~contours.neutral._kernels.store_state`, ``store_velocity``;
       R, A, v, ω̄ of the frame at rest stay);
    2. broad phase (with ``itab[BOX]``): the point's box (the sphere's, ``ftab[RADIUS]``
       around its centre) and the contour's (:func:`~contours.neutral._kernels.bounding_box`)
       grown by the margin (:func:`~contact._detection_kernels.boxes_overlap`) — apart: APART;
    3. the centre c into ``centre`` (the kinematics' copy; a point's C1 also into ``point1``:
       r, frame, J_T = 1, J_R = 0 of a point-mass frame, ṙ with ``itab[VELOCITY]``;
       a sphere's axes into ``axes1``);
    4. Newton on eq. 3.31–3.32 for c from the warm start ``start`` (η, ξ)
       (:func:`~contact._detection_kernels.newton_2s`), the search's ``counts`` and
       ``start`` updated — no warm start, no tolerance yet or no root: FALLBACK (the
       caller runs the Python path, which searches the coarse grid);
    5. C2 into ``point2``: r and its derivatives (eq. 3.23, 3.25, 3.26: those of Newton's
       last evaluation, at the root), the frame (eq. 3.27–3.29), ṙ (eq. 2.32)
       with ``itab[VELOCITY]`` — what :func:`~contours.neutral._kernels.evaluate_2s`
       gives at the root —, J_T = A Φ (eq. 2.70 on a prescribed frame,
       :func:`mbs._kernels.point_jacobian_T`), J_R = 0;
    6. g_N = nᵀ (c − r_C2) − ρ (eq. 3.4); a sphere's C1 = c − ρ n into ``point1``
       (:func:`contours._rigid_kernels.sphere_point` at the coordinates of −n); n, T, ġ_T,
       w_N1, w_N2, w_T1, w_T2 (eq. 3.8) into ``kin``.

    Returns (outcome, g_N [m], ġ_N [m/s] (NaN without velocity), C2's η, ξ, a sphere's
    C1 η, ξ [rad] (NaN for a point)).
    """
    nan = np.nan
    n_f, nu1, nu2 = itab[NF], itab[NU1], itab[NU2]
    velocity = itab[VELOCITY] != 0
    radius = ftab[RADIUS]

    # 1. the contours' states (store_state, store_velocity of the neutral contour)
    qp, up, qf, uf = itab[QP], itab[UP], itab[QF], itab[UF]
    for c in range(3):
        frame1[rigid.R_AT + c] = q[qp + c] + ftab[OFFSET_AT + c]
        frame1[rigid.V_AT + c] = u[up + c]
    for k in range(n_f):
        state[Q_AT + k] = q[qf + k]
        state[Q_AT + n_f + k] = u[uf + k]
    state[STAMP_AT] += 1.0

    # 2. broad phase
    o = KNOTS_AT + itab[KNOTS_E_N] + itab[KNOTS_X_N]
    work_at = WORK_AT + 18 * n_f
    if itab[BOX] != 0:
        box1, box2 = work[work_at:work_at + 6].reshape(2, 3), work[work_at + 6:work_at + 12].reshape(2, 3)
        for c in range(3):
            box1[0, c] = frame1[rigid.R_AT + c] - radius
            box1[1, c] = frame1[rigid.R_AT + c] + radius
        bounding_box(ftab[o:o + 3], ftab[o + 3:o + 6], ftab[o + 6:o + 6 + 3 * n_f].reshape(3, n_f), state, box2)
        if not boxes_overlap(box1, box2, ftab[MARGIN]):
            return APART, nan, nan, nan, nan, nan, nan

    # 3. the centre; a point's C1 (PointContour.evaluate), a sphere's axes
    sphere = radius > 0.0
    if sphere:
        for k in range(9):
            axes1[k // 3, k % 3] = frame1[rigid.A_AT + k]
    else:
        for k in range(V_AT - DERIVS_AT):
            point1[DERIVS_AT + k] = 0.0
        for c in range(3):
            point1[DERIVS_AT + c] = frame1[rigid.R_AT + c]
        for k in range(9):
            point1[FRAME_AT + k] = frame1[rigid.A_AT + k]
        for k in range(6 * nu1):
            point1[J_AT + k] = frame1[rigid.J_AT + k]
        if velocity:
            for c in range(3):
                point1[V_AT + c] = frame1[rigid.V_AT + c]
    for c in range(3):
        centre[c] = frame1[rigid.R_AT + c]

    # 4. warm-started Newton; its last evaluation, at the root, is C2's r rows
    if np.isnan(start[0]) or np.isnan(ftab[TOL2]):
        return FALLBACK, nan, nan, nan, nan, nan, nan
    ints = itab[GEOM_AT:GEOM_AT + 6]
    pm = max(ints[0], ints[3]) + 1
    B = work[:6 * pm].reshape(2, 3, pm)
    local = work[6 * pm:6 * pm + 18].reshape(6, 3)
    D = work[6 * pm + 18:6 * pm + 36].reshape(6, 3)
    g = work[6 * pm + 36:6 * pm + 39]
    knots_e = ftab[KNOTS_AT:KNOTS_AT + itab[KNOTS_E_N]]
    knots_x = ftab[KNOTS_AT + itab[KNOTS_E_N]:o]
    found, eta, xi, gg, k, steps = newton_2s(centre, start[0], start[1], knots_e, knots_x, ints,
                                             ftab[FLOATS_AT:FLOATS_AT + 4], ctrl0, phi, state, span, ftab[MAX_STEP_E],
                                             ftab[MAX_STEP_X], ftab[TOL2], ftab[EDGE2], itab[MAX_ITER], B, local,
                                             D, g)
    if not found:
        return FALLBACK, nan, nan, nan, nan, nan, nan
    counts[NEWTON_SOLVES] += 1
    counts[NEWTON_ITERATIONS] += steps
    counts[LAST_ITERATIONS] = k
    start[0], start[1] = eta, xi

    # 5. the point C2 (the r rows of Newton's last evaluation, then the rest of evaluate_2s
    # at the root: frame, Φ rows, ṙ; J_T, J_R)
    for k in range(18):
        point2[DERIVS_AT + k] = work[6 * pm + 18 + k]
    D2 = point2[DERIVS_AT:FRAME_AT].reshape(6, 3)
    F2 = point2[FRAME_AT:V_AT].reshape(3, 3)
    v2 = point2[V_AT:J_AT]
    J2 = point2[J_AT:J_AT + 3 * nu2].reshape(3, nu2)
    frame_2s(D2, ftab[SIGN], F2)
    phi_rows = work[WORK_AT:WORK_AT + 18 * n_f].reshape(6, 3 * n_f)
    contract_surface(B[0], int(span[1]), ints[0], B[1], int(span[2]), ints[3], phi, np.int64(1), phi_rows)
    if velocity:
        point_velocity(state, local[0], phi_rows[0], v2)
    A = state[A_AT:A_AT + 9].reshape(3, 3)
    point_jacobian_T(A, A, local[0], phi_rows[0].reshape(3, n_f), np.bool_(False), np.int64(0), J2)   # prescribed frame: A Φ
    for k in range(3 * nu2):
        point2[J_AT + 3 * nu2 + k] = 0.0

    # 6. gap, a sphere's C1, frame, relative velocity, Jacobian pieces
    g_N = normal_gap(F2, centre, D2, radius)
    eta1 = xi1 = nan
    if sphere:
        m = work[work_at + 12:work_at + 15]
        for c in range(3):
            m[c] = -F2[c, 2]
        eta1, xi1 = sphere_angles(axes1, m)
        sphere_point(frame1, radius, eta1, xi1, velocity, np.bool_(True), point1)
    ko = KIN_AT
    T = kin[itab[ko + 1]:itab[ko + 2]].reshape(3, 2)
    w_T1 = kin[itab[ko + 5]:itab[ko + 6]].reshape(nu1, 2)
    w_T2 = kin[itab[ko + 6]:itab[ko + 7]].reshape(nu2, 2)
    J1 = point1[J_AT:J_AT + 3 * nu1].reshape(3, nu1)
    gd_N = frame_rates_jacobians(F2, point1[V_AT:J_AT], v2, J1, J2, velocity, np.bool_(True), kin[itab[ko]:itab[ko + 1]], T,
                                 kin[itab[ko + 2]:itab[ko + 3]], kin[itab[ko + 3]:itab[ko + 4]],
                                 kin[itab[ko + 4]:itab[ko + 5]], w_T1, w_T2)
    return LOCATED, g_N, gd_N if velocity else nan, eta, xi, eta1, xi1
