"""numba kernel of a fused detection (:mod:`mbs.run.fused_detection`): the contour stage
and the detection stage of one contact in one call, composed of the kernels of the
contours (:mod:`contours.neutral._kernels`), the contact search and kinematics
(:mod:`contact._detection_kernels`) and the bodies (:func:`mbs.bodies._kernels.point_jacobian_T`).

:func:`centre_on_neutral_2s` serves a point or a sphere (its frame's state written here
from the global q, u on a point mass, by its contour's update otherwise) against a
neutral 2s contour of a floating-frame body (FFR or rigid; the frame's R, A, v, ω̄ are in
the contour's state: constant on a frame at rest, written by the contour's update
otherwise), :func:`centre_on_offset` the same
against an offset contour (band, cylinder: :mod:`contours.derived`) of such a body (a
:class:`~contact.kinematics.ContactKinematicsPointContour2s` or
:class:`~contact.kinematics.ContactKinematicsSphereContour2s` with its compiled
:class:`~contact.search.Contact2sSearch`), :func:`centre_on_neutral_1s` against a neutral
1s contour (:class:`~contact.kinematics.ContactKinematicsPointContour1s`,
``ContactKinematicsSphereContour1s`` with a compiled :class:`~contact.search.Contact1sSearch`).
All three share the states and broad phase (:func:`_begin`), C2's Jacobians
(:func:`_jacobian`) and the gap, the sphere's point and the frame's pieces (:func:`_finish`);
:func:`centre_on_plane` and :func:`sphere_on_sphere` serve the analytic pairs. Their reference is the Python path they replace —
``contour.update`` of both contours, then :meth:`contact.Contact.locate` (bounding boxes, ``search.solve`` warm-started,
``contour.evaluate``, :func:`~contact._detection_kernels.normal_gap`,
:func:`~contact._detection_kernels.frame_rates_jacobians`) — which
``tests/unit/contact/test_fused_detection.py`` compares them against.

The kernel takes each object's arrays as the one vector their views share
(:attr:`contours.base.ContourPoint.buffer`, :attr:`contact.kinematics.ContactKinematics.buffer`,
the frame contour's ``state``), the surface's ``kernel_data`` (knots … span cache), the
constants of the pair as one int table ``itab`` and one float table ``ftab`` (layouts
below, written by :mod:`mbs.run.fused_detection`), a small work vector, and the work arrays the
search's Newton (``newton_work``) and the contour's evaluation (``contour_work``) use on the
Python path.

Constant arguments of nested kernel calls are passed as typed values (``np.int64(0)``,
``np.bool_(True)``): numba compiles a callee apart for every literal argument, once more
beside the runtime-typed version the other callers use (``tests/qa/test_compile_once.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from contact._detection_kernels import (boxes_overlap, edge_frame, frame_rates_jacobians, newton_1s, newton_2s,
                                       newton_offset, normal_gap)
from contact.kinematics import ACTIVE_AT, G_N_AT, GD_N_AT
from contact.search import LAST_ITERATIONS, NEWTON_ITERATIONS, NEWTON_SOLVES
from contours import rigid
from contours._offset_kernels import evaluate_offset, offsets
from contours.fitting._kernels import in_material
from contours._rigid_kernels import frame_point, plane_coordinates, plane_point, sphere_point
from contours.rigid import sphere_angles
from contours.base import DERIVS_AT, ETA_AT, FRAME_AT, J_AT, V_AT, XI_AT
from contours.neutral._kernels import (A_AT, Q_AT, STAMP_AT, bounding_box, contract_surface, evaluate_1s, frame_2s,
                                      point_velocity)
from contours.neutral._kernels import R_AT as STATE_R_AT, V_AT as STATE_V_AT, W_AT as STATE_W_AT  # (beside the
# ContourPoint buffer's V_AT)

from mbs.bodies._kernels import point_jacobian_T, quat_matrix_into

APART, LOCATED, FALLBACK, NO_POINT = 0, 1, 2, 3   # outcomes of a fused detection (NO_POINT: no contact
                                                 # point exists, the kinematics turn inactive)

# itab: the point's rows of q and u, the body's q_f and q̇_f rows, n_f, nu of the two
# bodies, velocity wanted (0/1), broad phase on (0/1), Newton iterations, an offset
# contour's offset law (contours._offset_kernels.offsets) and whether its ξ is closed,
# whether the surface's body has a free frame (0/1), whether a curve is a sharp edge (0/1:
# the normal from the curve to the centre), the first rows of q and u of a free quaternion
# frame whose state the kernel writes (−1: its contour's update writes it, or it is at
# rest), the offsets of the kinematics buffer (contact.kinematics.buffer_layout, 8). The
# surface's own kernel data (knots, ints, floats, control points, state, span cache) are
# arguments.
QP, UP, QF, UF, NF, NU1, NU2, VELOCITY, BOX, MAX_ITER, LAW, XI_CLOSED, FREE, EDGE, FRAME_Q, FRAME_U, KIN_AT = range(17)
NODE_Q, NODE_U, NODE_NF, NODE_FREE, NODE_AT = range(KIN_AT + 8, KIN_AT + 13)
# ^ side 1 at a node of a flexible body whose frame the kernel writes (_node_frame): the
#   body's first rows of q and u (−1: not so), its n_f, free quaternion frame (1) or at
#   rest (0), and where in ftab its R₀ (3), A₀ (9, row-major; at rest) and the node's mode
#   rows Φ (3, n_f) lie; the node's ū0 is side 1's offset (ftab[OFFSET_AT:])
ITAB_SIZE = NODE_AT + 1
Q2, U2 = QF, UF     # the analytic pairs (plane, sphere–sphere): side 2's point-mass rows (−1: not a point mass)
# ftab: margin [m], tol2 [m²] (NaN until the search knows its length scale), the largest
# Newton steps in η and ξ, the normal's sign (2s), edge2 [m²] (contact.search: how far
# beyond the domain's boundary a point still projects onto it, squared), the point frame's
# offset ū0 (3) [m], an offset contour's law size [m], ξ domain (2) and reach (the largest
# offset [m], which grows the neutral curve's box), the sphere's radius ρ [m] (0: a point),
# the map T (3, 3) of a free frame's ω̄ = T u_r at this step (row-major), then the
# undeformed control points' box (lo (3), hi (3)) [m] and the bound of P_Φ (3, n_f) [m]
# (contours.neutral._kernels.bounding_box)
MARGIN, TOL2, MAX_STEP_E, MAX_STEP_X, SIGN, EDGE2 = range(6)
OFFSET_AT, FLOATS_AT, RADIUS, FRAME_T_AT, BOX_AT = 6, 9, 13, 14, 23
SIZE, XI_A, XI_B, REACH = FLOATS_AT, FLOATS_AT + 1, FLOATS_AT + 2, FLOATS_AT + 3
N_REF_AT = FLOATS_AT    # a 1s contour's: its body-frame reference normal n̄_ref (3,)
OFFSET2_AT, RADIUS2 = FLOATS_AT, FLOATS_AT + 3    # the analytic pairs: side 2's frame offset ū0 (3) [m], radius [m]


WORK_SIZE = 15     # the work vector: two boxes (2, 3) and the direction −n (3,); Newton and the
                   # contour's evaluation work in the search's and the contour's own work arrays


@njit(cache=True)
def _begin(q, u, itab, ftab, reach, state, frame1, point1, centre, axes1, start, work):
    """Steps 1–3 of a fused detection (:func:`centre_on_neutral_2s`): the contours'
    states, the broad phase against the surface's box (in ``ftab`` from BOX_AT: its
    undeformed control points' lo (3), hi (3) and the bound of P_Φ (3, n_f); grown by
    ``reach`` [m]), the centre, a point's C1 or a sphere's axes. Returns APART when the
    boxes are apart, FALLBACK without a warm start ``start`` or a Newton tolerance,
    else LOCATED (ready for Newton)."""
    n_f = itab[NF]
    box0 = ftab[BOX_AT:BOX_AT + 6 + 3 * n_f]
    radius = ftab[RADIUS]
    qf, uf = itab[QF], itab[UF]
    _mass_frame(q, u, itab[QP], itab[UP], ftab[OFFSET_AT:OFFSET_AT + 3], frame1)
    _node_frame(q, u, itab, ftab, frame1)
    _free_frame(q, u, itab[FRAME_Q], itab[FRAME_U], state)
    for k in range(n_f):
        state[Q_AT + k] = q[qf + k]
        state[Q_AT + n_f + k] = u[uf + k]
    state[STAMP_AT] += 1.0
    if itab[BOX] != 0:
        box1, box2 = work[0:6].reshape(2, 3), work[6:12].reshape(2, 3)
        _sphere_box(frame1, radius, box1)
        bounding_box(box0[0:3], box0[3:6], box0[6:6 + 3 * n_f].reshape(3, n_f), state, box2)
        for c in range(3):
            box2[0, c] -= reach
            box2[1, c] += reach
        if not boxes_overlap(box1, box2, ftab[MARGIN]):
            return APART
    _centre(frame1, radius, itab[VELOCITY] != 0, point1, centre, axes1)
    if np.isnan(start[0]) or np.isnan(ftab[TOL2]):
        return FALLBACK
    return LOCATED


@njit(cache=True)
def _mass_frame(q, u, q_at, u_at, offset, frame):
    """A point-mass frame contour's state at the global (q, u): r = q_P + ū0 and ṙ = u_P
    (:mod:`contours.rigid`'s shortcut: its orientation and Jacobians are constant);
    nothing for ``q_at`` < 0 (a ground frame, or a frame whose contour's update wrote it)."""
    if q_at < 0:
        return
    for c in range(3):
        frame[rigid.R_AT + c] = q[q_at + c] + offset[c]
        frame[rigid.V_AT + c] = u[u_at + c]


@njit(cache=True)
def _node_frame(q, u, itab, ftab, frame):
    """Side 1's frame contour at a node of a flexible body on a free quaternion frame or
    a frame at rest, into ``frame`` (its state) at the global (q, u), as the contour's
    update gives it (:meth:`mbs.bodies.floating_frame.FloatingFrameBody.point_kinematics`,
    ``point_velocity``): with ū = ū0 + Φ q_f, r = R + A ū, A, ṙ = v + A (ω̄ × ū + Φ q̇_f),
    ω = A ω̄, J_T = [1, −A ũ, A Φ] and J_R = [0, A, 0] on a free frame (T = 1), J_T = A Φ
    and J_R = 0 at rest (R₀, A₀ constant). Nothing when itab[NODE_Q] < 0."""
    qb = itab[NODE_Q]
    if qb < 0:
        return
    ub, n_f, free, at = itab[NODE_U], itab[NODE_NF], itab[NODE_FREE] != 0, itab[NODE_AT]
    nu = itab[NU1]
    A = frame[rigid.A_AT:rigid.A_AT + 9].reshape(3, 3)
    phi = ftab[at + 12:at + 12 + 3 * n_f].reshape(3, n_f)
    qf, uf = (qb + 7, ub + 6) if free else (qb, ub)
    if free:
        quat_matrix_into(q, qb + 3, A)
    else:
        for k in range(9):
            A[k // 3, k % 3] = ftab[at + 3 + k]
    ub0, ub1, ub2 = ftab[OFFSET_AT], ftab[OFFSET_AT + 1], ftab[OFFSET_AT + 2]   # ū = ū0 + Φ q_f
    r0 = r1 = r2 = 0.0                                                          # Φ q̇_f (+ ω̄ × ū)
    for k in range(n_f):
        ub0 += phi[0, k] * q[qf + k]
        ub1 += phi[1, k] * q[qf + k]
        ub2 += phi[2, k] * q[qf + k]
        r0 += phi[0, k] * u[uf + k]
        r1 += phi[1, k] * u[uf + k]
        r2 += phi[2, k] * u[uf + k]
    if free:
        w0, w1, w2 = u[ub + 3], u[ub + 4], u[ub + 5]
        r0 += w1 * ub2 - w2 * ub1
        r1 += w2 * ub0 - w0 * ub2
        r2 += w0 * ub1 - w1 * ub0
    J_T = frame[rigid.J_AT:rigid.J_AT + 3 * nu].reshape(3, nu)
    J_R = frame[rigid.J_AT + 3 * nu:rigid.J_AT + 6 * nu].reshape(3, nu)
    f0 = 6 if free else 0
    for c in range(3):
        R = q[qb + c] if free else ftab[at + c]
        v = u[ub + c] if free else 0.0
        frame[rigid.R_AT + c] = R + A[c, 0] * ub0 + A[c, 1] * ub1 + A[c, 2] * ub2
        frame[rigid.V_AT + c] = v + A[c, 0] * r0 + A[c, 1] * r1 + A[c, 2] * r2
        frame[rigid.W_AT + c] = (A[c, 0] * u[ub + 3] + A[c, 1] * u[ub + 4] + A[c, 2] * u[ub + 5]) if free else 0.0
        for j in range(nu):
            J_R[c, j] = 0.0
        if free:
            b0 = -(A[c, 1] * ub2 - A[c, 2] * ub1)
            b1 = -(A[c, 2] * ub0 - A[c, 0] * ub2)
            b2 = -(A[c, 0] * ub1 - A[c, 1] * ub0)
            for j in range(3):
                J_T[c, j] = 1.0 if c == j else 0.0
                J_R[c, 3 + j] = A[c, j]
            J_T[c, 3], J_T[c, 4], J_T[c, 5] = b0, b1, b2
        for k in range(n_f):
            J_T[c, f0 + k] = A[c, 0] * phi[0, k] + A[c, 1] * phi[1, k] + A[c, 2] * phi[2, k]


@njit(cache=True)
def _free_frame(q, u, q_at, u_at, state):
    """A free quaternion frame's R = q[q_at:+3], A of the quaternion q[q_at+3:+7], v =
    u[u_at:+3] and ω̄ = u[u_at+3:+6] (T = 1) into the neutral contour's ``state``, as its
    update's ``frame_state`` gives them; nothing for ``q_at`` < 0."""
    if q_at < 0:
        return
    quat_matrix_into(q, q_at + 3, state[A_AT:A_AT + 9].reshape(3, 3))
    for c in range(3):
        state[STATE_R_AT + c] = q[q_at + c]
        state[STATE_V_AT + c] = u[u_at + c]
        state[STATE_W_AT + c] = u[u_at + 3 + c]


@njit(cache=True)
def _sphere_box(frame, radius, box):
    """The box (2, 3) [m] of a sphere of ``radius`` (0: a point) about the frame's origin."""
    for c in range(3):
        box[0, c] = frame[rigid.R_AT + c] - radius
        box[1, c] = frame[rigid.R_AT + c] + radius


@njit(cache=True)
def _centre(frame1, radius, velocity, point1, centre, axes1):
    """Side 1 at its frame: the centre c into ``centre``; a point's C1 into ``point1`` (the
    frame origin, :func:`~contours._rigid_kernels.frame_point`, ṙ with ``velocity``), a
    sphere's axes into ``axes1``."""
    if radius > 0.0:
        for k in range(9):
            axes1[k // 3, k % 3] = frame1[rigid.A_AT + k]
    else:
        frame_point(frame1, velocity, np.bool_(True), point1)
    for c in range(3):
        centre[c] = frame1[rigid.R_AT + c]


@njit(cache=True)
def _finish(itab, ftab, frame1, point1, point2, kin, centre, axes1, work, eta, xi):
    """Step 6 of a fused detection (:func:`centre_on_neutral_2s`) once C2 is in ``point2``
    at (``eta``, ``xi``): g_N, a sphere's C1, the frame's pieces into ``kin``; the
    kinematics active, g_N, ġ_N (with velocity) and both points' (η, ξ) (a point's C1 at
    (0, 0)) as their update leaves them. Returns g_N [m]."""
    nu1, nu2 = itab[NU1], itab[NU2]
    velocity = itab[VELOCITY] != 0
    radius = ftab[RADIUS]
    D2 = point2[DERIVS_AT:FRAME_AT].reshape(6, 3)
    F2 = point2[FRAME_AT:V_AT].reshape(3, 3)
    g_N = normal_gap(F2, centre, D2, radius)
    eta1 = xi1 = 0.0
    if radius > 0.0:
        m = work[12:15]
        for c in range(3):
            m[c] = -F2[c, 2]
        eta1, xi1 = sphere_angles(axes1, m)
        sphere_point(frame1, radius, eta1, xi1, velocity, np.bool_(True), point1)
    point1[ETA_AT], point1[XI_AT] = eta1, xi1
    point2[ETA_AT], point2[XI_AT] = eta, xi
    ko = KIN_AT
    T = kin[itab[ko + 1]:itab[ko + 2]].reshape(3, 2)
    w_T1 = kin[itab[ko + 5]:itab[ko + 6]].reshape(nu1, 2)
    w_T2 = kin[itab[ko + 6]:itab[ko + 7]].reshape(nu2, 2)
    J1 = point1[J_AT:J_AT + 3 * nu1].reshape(3, nu1)
    J2 = point2[J_AT:J_AT + 3 * nu2].reshape(3, nu2)
    gd_N = frame_rates_jacobians(F2, point1[V_AT:J_AT], point2[V_AT:J_AT], J1, J2, velocity, np.bool_(True),
                                 kin[itab[ko]:itab[ko + 1]], T, kin[itab[ko + 2]:itab[ko + 3]],
                                 kin[itab[ko + 3]:itab[ko + 4]], kin[itab[ko + 4]:itab[ko + 5]], w_T1, w_T2)
    kin[G_N_AT] = g_N
    if velocity:
        kin[GD_N_AT] = gd_N
    kin[ACTIVE_AT] = 1.0
    return g_N


@njit(cache=True)
def _count(counts, k, steps):
    """A converged Newton's counters (as the searches of :mod:`contact.search` keep them)."""
    counts[NEWTON_SOLVES] += 1
    counts[NEWTON_ITERATIONS] += steps
    counts[LAST_ITERATIONS] = k


@njit(cache=True)
def _jacobian(itab, ftab, state, local, phi_point, point2):
    """C2's J_T and J_R into ``point2`` (thesis eq. 2.70, 2.72;
    :func:`mbs.bodies._kernels.point_jacobian_T`): on a free frame (``itab[FREE]``, T in
    ``ftab``) J_T = [1, −A ũ T, A Φ] and J_R = [0, A T, 0], on a prescribed one (at rest or
    moving) J_T = A Φ and J_R = 0."""
    n_f, nu2 = itab[NF], itab[NU2]
    free = itab[FREE] != 0
    A = state[A_AT:A_AT + 9].reshape(3, 3)
    T = ftab[FRAME_T_AT:FRAME_T_AT + 9].reshape(3, 3)
    J2 = point2[J_AT:J_AT + 3 * nu2].reshape(3, nu2)
    point_jacobian_T(A, T, local, phi_point.reshape(3, n_f), free, np.int64(6) if free else np.int64(0), J2)
    JR = point2[J_AT + 3 * nu2:J_AT + 6 * nu2]
    for k in range(3 * nu2):
        JR[k] = 0.0
    if free:
        for c in range(3):
            for j in range(3):
                JR[c * nu2 + 3 + j] = A[c, 0] * T[0, j] + A[c, 1] * T[1, j] + A[c, 2] * T[2, j]


@njit(cache=True)
def centre_on_neutral_2s(q, u, itab, ftab, knots_e, knots_x, ints, floats, ctrl0, phi, state, span, frame1, point1,
                         point2, kin, centre, axes1, start, counts, work, newton_work, contour_work, trim_vertices,
                         trim_starts):
    """Stages 3 and 4 for one contact (module docstring) at the global (q, u) [m, m/s]:

    1. the contours' states: the point r = q_P + ū0, ṙ = u_P into ``frame1`` (the
       frame contour's state); q_f, q̇_f and a new stamp into the neutral contour's
       ``state`` (as :func:`~contours.neutral._kernels.store_state`, ``store_velocity``;
       R, A, v, ω̄ of the frame stay as they are);
    2. broad phase (with ``itab[BOX]``): the point's box (the sphere's, ``ftab[RADIUS]``
       around its centre) and the contour's (:func:`~contours.neutral._kernels.bounding_box`)
       grown by the margin (:func:`~contact._detection_kernels.boxes_overlap`) — apart: APART;
    3. the centre c into ``centre`` (the kinematics' copy; a point's C1 also into ``point1``:
       r, frame, J_T = 1, J_R = 0 of a point-mass frame, ṙ with ``itab[VELOCITY]``;
       a sphere's axes into ``axes1``);
    4. Newton on eq. 3.31–3.32 for c from the warm start ``start`` (η, ξ)
       (:func:`~contact._detection_kernels.newton_2s` on the surface's kernel data, in the
       search's ``newton_work`` = B, ū rows, r rows, g), the search's ``counts`` and
       ``start`` updated — no warm start, no tolerance yet, no root, or a root in a hole
       of a trimmed face (``trim_vertices``, ``trim_starts``: the polygons of
       :func:`contours.fitting._kernels.in_material`; none: no hole): FALLBACK (the caller
       runs the Python path, which searches the coarse grid or keeps the hole);
    5. C2 into ``point2``: r and its derivatives (eq. 3.23, 3.25, 3.26: those of Newton's
       last evaluation, at the root), the frame (eq. 3.27–3.29), ṙ (eq. 2.32)
       with ``itab[VELOCITY]`` — what :func:`~contours.neutral._kernels.evaluate_2s`
       gives at the root, its Φ rows in the third of the contour's ``contour_work`` —,
       J_T and J_R (eq. 2.70, 2.72: :func:`_jacobian`);
    6. g_N = nᵀ (c − r_C2) − ρ (eq. 3.4); a sphere's C1 = c − ρ n into ``point1``
       (:func:`contours._rigid_kernels.sphere_point` at the coordinates of −n); g_N, ġ_N
       (with velocity), active, n, T, ġ_T, w_N1, w_N2, w_T1, w_T2 (eq. 3.8) into ``kin``,
       both points' (η, ξ) into theirs (:func:`_finish`).

    Returns (outcome, g_N [m]; NaN unless LOCATED). NO_POINT leaves the kinematics inactive.
    """
    ready = _begin(q, u, itab, ftab, 0.0, state, frame1, point1, centre, axes1, start, work)
    if ready != LOCATED:
        return ready, np.nan
    B, local, D, g = newton_work
    found, eta, xi, gg, k, steps = newton_2s(centre, start[0], start[1], knots_e, knots_x, ints, floats, ctrl0, phi,
                                             state, span, ftab[MAX_STEP_E], ftab[MAX_STEP_X], ftab[TOL2], ftab[EDGE2],
                                             itab[MAX_ITER], B, local, D, g)
    if not (found and in_material(eta, xi, trim_vertices, trim_starts)):
        return FALLBACK, np.nan
    _count(counts, k, steps)
    start[0], start[1] = eta, xi
    # C2: the r rows of Newton's last evaluation, then the rest of evaluate_2s at the root
    for k in range(18):
        point2[DERIVS_AT + k] = D[k // 3, k % 3]
    frame_2s(point2[DERIVS_AT:FRAME_AT].reshape(6, 3), ftab[SIGN], point2[FRAME_AT:V_AT].reshape(3, 3))
    phi_rows = contour_work[2]
    contract_surface(B[0], int(span[1]), ints[0], B[1], int(span[2]), ints[3], phi, np.int64(1), phi_rows)
    if itab[VELOCITY] != 0:
        point_velocity(state, local[0], phi_rows[0], point2[V_AT:J_AT])
    _jacobian(itab, ftab, state, local[0], phi_rows[0], point2)
    return LOCATED, _finish(itab, ftab, frame1, point1, point2, kin, centre, axes1, work, eta, xi)


@njit(cache=True)
def centre_on_offset(q, u, itab, ftab, knots, ints, floats, ctrl0, phi, state, span, n0, frame1, point1, point2,
                     kin, centre, axes1, start, counts, work, newton_work, contour_work):
    """:func:`centre_on_neutral_2s` against an offset contour (band, cylinder), from its neutral curve's kernel data (knots … span) and reference normal n0:
    the broad phase against the curve's box grown by the reach, Newton on the offset
    surface (:func:`~contact._detection_kernels.newton_offset`, the search's work arrays
    ``newton_work`` = B, local, rows, frame, D, g), C2 by
    :func:`~contours._offset_kernels.evaluate_offset` at the root (the contour's own work
    arrays ``contour_work`` = B, local, rows, frame, Φ rows, Φ_P, as
    :meth:`contours.derived.OffsetContour.evaluate` fills them) with J_T, J_R at Φ_P.
    Returns as :func:`centre_on_neutral_2s`."""
    ready = _begin(q, u, itab, ftab, ftab[REACH], state, frame1, point1, centre, axes1, start, work)
    if ready != LOCATED:
        return ready, np.nan
    B, local, rows, frame, D, g = newton_work
    law, size = itab[LAW], ftab[SIZE]
    found, eta, xi, gg, k, steps = newton_offset(centre, start[0], start[1], knots, ints, floats, ctrl0, phi, state,
                                                 span, n0, law, size, ftab[XI_A], ftab[XI_B], itab[XI_CLOSED] != 0,
                                                 ftab[MAX_STEP_E], ftab[MAX_STEP_X], ftab[TOL2], ftab[EDGE2],
                                                 itab[MAX_ITER], B, local, rows, frame, D, g)
    if not found:
        return FALLBACK, np.nan
    _count(counts, k, steps)
    start[0], start[1] = eta, xi
    B, local, rows, frame, phi_rows, phi_point = contour_work
    al, be, al1, be1, al2, be2 = offsets(law, size, xi)
    evaluate_offset(eta, knots, ints, floats, ctrl0, phi, state, span, n0, al, be, al1, be1, al2, be2,
                    np.bool_(True), itab[VELOCITY] != 0, B, local, rows, frame, phi_rows, phi_point,
                    point2[DERIVS_AT:FRAME_AT].reshape(6, 3), point2[FRAME_AT:V_AT].reshape(3, 3), point2[V_AT:J_AT])
    _jacobian(itab, ftab, state, rows[0], phi_point, point2)
    return LOCATED, _finish(itab, ftab, frame1, point1, point2, kin, centre, axes1, work, eta, xi)


@njit(cache=True)
def centre_on_neutral_1s(q, u, itab, ftab, knots, ints, floats, ctrl0, phi, state, span, n_ref, frame1, point1,
                         point2, kin, centre, axes1, start, counts, work, newton_work, contour_work):
    """:func:`centre_on_neutral_2s` against a neutral 1s contour, from its
    kernel data (knots … span) and its reference normal in world axes ``n_ref`` (A n̄_ref
    of the contour's last update): Newton on t_ηᵀ (c − r(η)) = 0 from the warm start η = ``start[0]``
    (:func:`~contact._detection_kernels.newton_1s`, the search's work arrays
    ``newton_work`` = B, local, D, g), C2 by :func:`~contours.neutral._kernels.evaluate_1s`
    at the root (the contour's work arrays ``contour_work`` = B, ū rows, Φ rows) with
    J_T, J_R; on a sharp edge (``itab[EDGE]``) the frame of
    :func:`~contact._detection_kernels.edge_frame` (NO_POINT when the centre lies on the
    curve). On a free quaternion frame (``itab[FRAME_Q]``) the kernel also writes the
    curve's reference normal ``n_ref`` = A n̄_ref (n̄_ref in ``ftab``), as the curve's
    update does. Returns as :func:`centre_on_neutral_2s` (C2's ξ = 0)."""
    ready = _begin(q, u, itab, ftab, 0.0, state, frame1, point1, centre, axes1, start, work)
    if itab[FRAME_Q] >= 0:
        for c in range(3):
            n_ref[c] = (state[A_AT + 3 * c] * ftab[N_REF_AT] + state[A_AT + 3 * c + 1] * ftab[N_REF_AT + 1]
                        + state[A_AT + 3 * c + 2] * ftab[N_REF_AT + 2])
    if ready != LOCATED:
        return ready, np.nan
    B, local, D, g = newton_work
    found, eta, gg, k, steps = newton_1s(centre, start[0], knots, ints, floats, ctrl0, phi, state, span,
                                         ftab[MAX_STEP_E], ftab[TOL2], ftab[EDGE2], itab[MAX_ITER], B, local, D, g)
    if not found:
        return FALLBACK, np.nan
    _count(counts, k, steps)
    start[0] = eta
    B, local, phi_rows = contour_work
    D2, F2 = point2[DERIVS_AT:FRAME_AT].reshape(6, 3), point2[FRAME_AT:V_AT].reshape(3, 3)
    evaluate_1s(eta, knots, ints, floats, ctrl0, phi, state, span, n_ref, np.bool_(True), itab[VELOCITY] != 0, B,
                local, phi_rows, D2, F2, point2[V_AT:J_AT])
    if itab[EDGE] != 0 and not edge_frame(F2, centre, D2):
        kin[ACTIVE_AT] = 0.0
        return NO_POINT, np.nan
    _jacobian(itab, ftab, state, local[0], phi_rows[0], point2)
    return LOCATED, _finish(itab, ftab, frame1, point1, point2, kin, centre, axes1, work, eta, 0.0)


@njit(cache=True)
def centre_on_plane(q, u, itab, ftab, frame1, plane, point1, point2, kin, centre, axes1, work):
    """Stages 3 and 4 of a point or a sphere against a plane (analytic, no search) at the
    global (q, u) [m, m/s]: each side's frame state on a point mass (``itab[QP]``,
    ``itab[Q2]`` >= 0; else its contour's update wrote it, or it is the ground's);
    side 1's centre c (a point's C1); C2 the foot of c on the plane, (η, ξ) = (a_x,
    a_y)ᵀ (c − r_O) (:func:`~contours._rigid_kernels.plane_point`, with J_T, J_R); then
    g_N, a sphere's C1 and the frame's pieces as :func:`centre_on_neutral_2s` step 6.
    The plane is unbounded: no broad phase. Returns as :func:`centre_on_neutral_2s`."""
    velocity = itab[VELOCITY] != 0
    _mass_frame(q, u, itab[QP], itab[UP], ftab[OFFSET_AT:OFFSET_AT + 3], frame1)
    _node_frame(q, u, itab, ftab, frame1)
    _mass_frame(q, u, itab[Q2], itab[U2], ftab[OFFSET2_AT:OFFSET2_AT + 3], plane)
    _centre(frame1, ftab[RADIUS], velocity, point1, centre, axes1)
    eta, xi = plane_coordinates(plane, centre)
    plane_point(plane, eta, xi, velocity, np.bool_(True), point2)
    return LOCATED, _finish(itab, ftab, frame1, point1, point2, kin, centre, axes1, work, eta, xi)


@njit(cache=True)
def sphere_on_sphere(q, u, itab, ftab, frame1, frame2, point1, point2, kin, centre, axes1, axes2, work):
    """Stages 3 and 4 of a sphere (or a point: ρ1 = 0) against a sphere (analytic) at the
    global (q, u): the frame states as
    :func:`centre_on_plane`; broad phase (with ``itab[BOX]``) on the spheres' boxes;
    n = (c1 − c2)/|c1 − c2|, C2 = c2 + ρ2 n at sphere 2's coordinates of n
    (:func:`~contours._rigid_kernels.sphere_point`, its axes into ``axes2``), then g_N,
    C1 = c1 − ρ1 n and the frame's pieces as :func:`centre_on_neutral_2s` step 6.
    NO_POINT when the centres coincide. Returns as :func:`centre_on_neutral_2s`."""
    velocity = itab[VELOCITY] != 0
    radius1, radius2 = ftab[RADIUS], ftab[RADIUS2]
    _mass_frame(q, u, itab[QP], itab[UP], ftab[OFFSET_AT:OFFSET_AT + 3], frame1)
    _node_frame(q, u, itab, ftab, frame1)
    _mass_frame(q, u, itab[Q2], itab[U2], ftab[OFFSET2_AT:OFFSET2_AT + 3], frame2)
    if itab[BOX] != 0:
        box1, box2 = work[0:6].reshape(2, 3), work[6:12].reshape(2, 3)
        _sphere_box(frame1, radius1, box1)
        _sphere_box(frame2, radius2, box2)
        if not boxes_overlap(box1, box2, ftab[MARGIN]):
            return APART, np.nan
    _centre(frame1, radius1, velocity, point1, centre, axes1)
    for k in range(9):
        axes2[k // 3, k % 3] = frame2[rigid.A_AT + k]
    m = work[12:15]
    dist2 = 0.0
    for c in range(3):
        m[c] = centre[c] - frame2[rigid.R_AT + c]
        dist2 += m[c] * m[c]
    dist = np.sqrt(dist2)
    if dist == 0.0:
        kin[ACTIVE_AT] = 0.0
        return NO_POINT, np.nan
    for c in range(3):
        m[c] /= dist
    eta, xi = sphere_angles(axes2, m)
    sphere_point(frame2, radius2, eta, xi, velocity, np.bool_(True), point2)
    return LOCATED, _finish(itab, ftab, frame1, point1, point2, kin, centre, axes1, work, eta, xi)


@njit(cache=True)
def normal_plane_offset(itab, kin, point1, point2):
    """t2ᵀ (r_C1 − r_C2) [m]: a point kept on a curve's offset along the curve frame's t2
    (:class:`~contact.kinematics.PointOnCurveConstraint`), from the located kinematics."""
    T = kin[itab[KIN_AT + 1]:itab[KIN_AT + 2]]           # T (3, 2) row-major: t2 is column 1
    return (T[1] * (point1[DERIVS_AT] - point2[DERIVS_AT]) + T[3] * (point1[DERIVS_AT + 1] - point2[DERIVS_AT + 1])
            + T[5] * (point1[DERIVS_AT + 2] - point2[DERIVS_AT + 2]))
