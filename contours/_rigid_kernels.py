"""numba kernels of the rigid contours (:mod:`contours.rigid`): the frame origin as a
contour point, a plane's point at given coordinates and the coordinates of a point's
foot on it, a sphere's surface coordinates of a direction and its point at given
coordinates — the one implementation that the contours' ``evaluate``, the contact
kinematics of planes and spheres (:mod:`contact.kinematics`) and the compiled detection
(:mod:`mbs.run._fused_detection_kernels`) share. The frame contour's ``state`` and the
point's ``buffer`` are the flat vectors their arrays are views of (layouts below and
:data:`contours.base.ETA_AT` …: η, ξ, then the derivatives, frame, velocity and
Jacobians; the kernels leave η, ξ to their callers).

numba's disk cache keeps the imported layout's values with the compiled kernels and
checks only this file's stamp: a change of the layout in :mod:`contours.base` must come
with a change of this file.
"""

from __future__ import annotations

import math

from numba import njit

from .base import DERIVS_AT, FRAME_AT, J_AT as POINT_J_AT, V_AT as POINT_V_AT

# layout of a frame contour's state: r, A (row-major), v, ω, J_T (3, nu), J_R (3, nu)
R_AT, A_AT, V_AT, W_AT, J_AT = 0, 3, 12, 15, 18


@njit(cache=True)
def sphere_angles(A, m):
    """Surface coordinates (η, ξ) [rad] of a sphere with axes A (3, 3) at the point in the
    unit direction m (3,) from its centre: (x, y, z) = Aᵀ m, η = atan2(y, x) mod 2π,
    ξ = asin(z) (z clipped to [−1, 1])."""
    x = A[0, 0] * m[0] + A[1, 0] * m[1] + A[2, 0] * m[2]
    y = A[0, 1] * m[0] + A[1, 1] * m[1] + A[2, 1] * m[2]
    z = A[0, 2] * m[0] + A[1, 2] * m[1] + A[2, 2] * m[2]
    return math.atan2(y, x) % (2.0 * math.pi), math.asin(min(1.0, max(-1.0, z)))


@njit(cache=True)
def sphere_point(state, radius, eta, xi, velocity, jacobians, point):
    """The point of a sphere of ``radius`` [m] about its frame's origin at (η, ξ) [rad] into
    ``point`` (a ContourPoint's buffer), from the frame's ``state`` (r, A, v, ω, J_T, J_R):
    with n = A (cos ξ cos η, cos ξ sin η, sin ξ) the outward normal, r_C = r + ρ n and its
    derivatives in η and ξ (rows VALUE … D_XI_XI), the frame (t_η/|t_η|, n × t_η/|t_η|, n);
    with ``velocity`` ṙ_C = v + ω × ρn, with ``jacobians`` J_T = J_T,O − ρñ J_R,O and
    J_R = J_R,O (thesis eq. 2.70, 2.72)."""
    ce, se, cx, sx = math.cos(eta), math.sin(eta), math.cos(xi), math.sin(xi)
    local = ((cx * ce, cx * se, sx), (-cx * se, cx * ce, 0.0), (-sx * ce, -sx * se, cx),
             (-cx * ce, -cx * se, 0.0), (sx * se, -sx * ce, 0.0), (-se, ce, 0.0))
    n = (0.0, 0.0, 0.0)
    t = (0.0, 0.0, 0.0)
    for row in range(6):                      # A times each local direction
        a, b, c = local[row]
        w0 = state[A_AT + 0] * a + state[A_AT + 1] * b + state[A_AT + 2] * c
        w1 = state[A_AT + 3] * a + state[A_AT + 4] * b + state[A_AT + 5] * c
        w2 = state[A_AT + 6] * a + state[A_AT + 7] * b + state[A_AT + 8] * c
        if row == 0:
            n = (w0, w1, w2)
        elif row == 5:
            t = (w0, w1, w2)
        else:
            point[DERIVS_AT + 3 * row] = radius * w0
            point[DERIVS_AT + 3 * row + 1] = radius * w1
            point[DERIVS_AT + 3 * row + 2] = radius * w2
    d = (radius * n[0], radius * n[1], radius * n[2])        # the point's offset from the centre
    for c in range(3):
        point[DERIVS_AT + c] = state[R_AT + c] + d[c]
        point[DERIVS_AT + 15 + c] = -d[c]                    # r_ξξ = −ρ n
        point[FRAME_AT + 3 * c + 2] = n[c]
        point[FRAME_AT + 3 * c] = t[c]
    point[FRAME_AT + 1] = n[1] * t[2] - n[2] * t[1]         # n × t_η/|t_η|
    point[FRAME_AT + 4] = n[2] * t[0] - n[0] * t[2]
    point[FRAME_AT + 7] = n[0] * t[1] - n[1] * t[0]
    _offset_rates(state, d, velocity, jacobians, point)


@njit(cache=True)
def _offset_rates(state, d, velocity, jacobians, point):
    """ṙ = v + ω × d (with ``velocity``) and J_T = J_T,O − d̃ J_R,O, J_R = J_R,O (with
    ``jacobians``) of the body point at the inertial offset d (3,) [m] from the frame
    origin into ``point`` (thesis eq. 2.70, 2.72)."""
    nu = (state.size - J_AT) // 6
    if velocity:
        w = state[W_AT:J_AT]
        point[POINT_V_AT] = state[V_AT] + (w[1] * d[2] - w[2] * d[1])
        point[POINT_V_AT + 1] = state[V_AT + 1] + (w[2] * d[0] - w[0] * d[2])
        point[POINT_V_AT + 2] = state[V_AT + 2] + (w[0] * d[1] - w[1] * d[0])
    if jacobians:
        JT = state[J_AT:J_AT + 3 * nu]
        JR = state[J_AT + 3 * nu:J_AT + 6 * nu]
        for k in range(nu):                   # J_T,O − d × J_R,O column by column
            r0, r1, r2 = JR[k], JR[nu + k], JR[2 * nu + k]
            point[POINT_J_AT + k] = JT[k] - (d[1] * r2 - d[2] * r1)
            point[POINT_J_AT + nu + k] = JT[nu + k] - (d[2] * r0 - d[0] * r2)
            point[POINT_J_AT + 2 * nu + k] = JT[2 * nu + k] - (d[0] * r1 - d[1] * r0)
        for k in range(3 * nu):
            point[POINT_J_AT + 3 * nu + k] = JR[k]


@njit(cache=True)
def frame_point(state, velocity, jacobians, point):
    """The frame origin as a contour point into ``point``: r (the derivative rows zero),
    the frame's orientation as its frame, with ``velocity`` ṙ = v, with ``jacobians``
    J_T = J_T,O and J_R = J_R,O of the frame."""
    for k in range(FRAME_AT - DERIVS_AT):
        point[DERIVS_AT + k] = 0.0
    for c in range(3):
        point[DERIVS_AT + c] = state[R_AT + c]
    for k in range(9):
        point[FRAME_AT + k] = state[A_AT + k]
    if velocity:
        for c in range(3):
            point[POINT_V_AT + c] = state[V_AT + c]
    if jacobians:
        for k in range(state.size - J_AT):
            point[POINT_J_AT + k] = state[J_AT + k]


@njit(cache=True)
def plane_coordinates(state, c):
    """(η, ξ) [m] of the foot of the point c (3,) [m] on the plane through the frame
    origin spanned by its x and y axes: (a_x, a_y)ᵀ (c − r_O)."""
    eta = 0.0
    xi = 0.0
    for k in range(3):
        d = c[k] - state[R_AT + k]
        eta += state[A_AT + 3 * k] * d
        xi += state[A_AT + 3 * k + 1] * d
    return eta, xi


@njit(cache=True)
def plane_point(state, eta, xi, velocity, jacobians, point):
    """The point of the plane through the frame origin spanned by its x and y axes at
    (η, ξ) [m] into ``point``: r = r_O + d with d = η a_x + ξ a_y, r_η = a_x, r_ξ = a_y
    (the second derivatives zero), the frame's orientation as its frame (n = a_z), with
    ``velocity`` and ``jacobians`` the body point's ṙ, J_T and J_R at d (thesis eq. 2.70, 2.72)."""
    for k in range(FRAME_AT - DERIVS_AT):
        point[DERIVS_AT + k] = 0.0
    d = (eta * state[A_AT] + xi * state[A_AT + 1], eta * state[A_AT + 3] + xi * state[A_AT + 4],
         eta * state[A_AT + 6] + xi * state[A_AT + 7])
    for c in range(3):
        point[DERIVS_AT + c] = state[R_AT + c] + d[c]
        point[DERIVS_AT + 3 + c] = state[A_AT + 3 * c]          # r_η = a_x
        point[DERIVS_AT + 6 + c] = state[A_AT + 3 * c + 1]      # r_ξ = a_y
    for k in range(9):
        point[FRAME_AT + k] = state[A_AT + k]
    _offset_rates(state, d, velocity, jacobians, point)
