"""numba kernels of the floating-frame bodies' per-step terms, allocation-free: each
writes into arrays the caller owns. Plain-numpy references: :class:`mbs.bodies.shape_integrals.
ShapeIntegrals` (``deformed``, ``quadratic_velocity``) for the FFR terms, the bodies'
formulas in :mod:`mbs.bodies.rigid_body`, :mod:`mbs.bodies.rotations` and :mod:`mbs.bodies.floating_frame`
for the others; the tests compare each kernel with its reference.

``ffr_mass_qv_into`` fills, in the full coordinates (Ṙ, ω̄, q̇_f), the mass matrix M̄ of
thesis eq. 2.44 (blocks eq. 2.47, 2.50, 2.57, 2.58, 2.66, 2.69) and the quadratic
velocity vector Q̄_v of eq. 2.77–2.79 (formulas in :mod:`mbs.bodies.shape_integrals`), in one
pass over the shape integrals: O(n_f²), with one (3, 3, n_f) scratch array G.

A free frame here has the quaternion layout q = (R (3), p (4), q_f), u = (Ṙ, ω̄, q̇_f)
(:mod:`mbs.bodies.parametrization`, T = 1).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def ffr_mass_qv_into(A, w, q_f, qd_f, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, G, M, Q):
    """M̄ (6+n_f, 6+n_f) and Q̄_v (6+n_f,) into ``M``, ``Q`` (module docstring); ``G``
    (3, 3, n_f) scratch: G[k, l] = Ī_kl + S_lk q_f."""
    n = q_f.shape[0]
    # S_t = I1 + S̄ q_f ;  Sqd = S̄ q̇_f
    S0 = I1[0]
    S1 = I1[1]
    S2 = I1[2]
    d0 = 0.0
    d1 = 0.0
    d2 = 0.0
    for a in range(n):
        S0 += S_bar[0, a] * q_f[a]
        S1 += S_bar[1, a] * q_f[a]
        S2 += S_bar[2, a] * q_f[a]
        d0 += S_bar[0, a] * qd_f[a]
        d1 += S_bar[1, a] * qd_f[a]
        d2 += S_bar[2, a] * qd_f[a]
    for k in range(3):
        for l in range(3):
            for a in range(n):
                acc = I_bar[k, l, a]
                for b in range(n):
                    acc += S_kl[l, k, a, b] * q_f[b]
                G[k, l, a] = acc
    # U[k, l] = Σ m ū_k ū_l ;  Ī_θθ = tr(U) 1 − U  (kept in the θθ block of M)
    N = 6 + n
    for i in range(N):
        for j in range(N):
            M[i, j] = 0.0
    for k in range(3):
        for l in range(3):
            acc = I_kl[k, l]
            for a in range(n):
                acc += (I_bar[l, k, a] + G[k, l, a]) * q_f[a]
            M[3 + k, 3 + l] = -acc
    tr = -(M[3, 3] + M[4, 4] + M[5, 5])
    for k in range(3):
        M[3 + k, 3 + k] += tr
    # mass matrix: −A S̃_t, A S̄, Ī_θf, m_ff
    for i in range(3):
        M[i, i] = mass
        c0 = -(A[i, 1] * S2 - A[i, 2] * S1)          # −(A S̃_t)[i, 0]
        c1 = -(-A[i, 0] * S2 + A[i, 2] * S0)         # −(A S̃_t)[i, 1]
        c2 = -(A[i, 0] * S1 - A[i, 1] * S0)          # −(A S̃_t)[i, 2]
        M[i, 3] = c0
        M[3, i] = c0
        M[i, 4] = c1
        M[4, i] = c1
        M[i, 5] = c2
        M[5, i] = c2
        for a in range(n):
            acc = 0.0
            for k in range(3):
                acc += A[i, k] * S_bar[k, a]
            M[i, 6 + a] = acc
            M[6 + a, i] = acc
    for a in range(n):
        t0 = G[1, 2, a] - G[2, 1, a]
        t1 = G[2, 0, a] - G[0, 2, a]
        t2 = G[0, 1, a] - G[1, 0, a]
        M[3, 6 + a] = t0
        M[4, 6 + a] = t1
        M[5, 6 + a] = t2
        M[6 + a, 3] = t0
        M[6 + a, 4] = t1
        M[6 + a, 5] = t2
        for b in range(n):
            M[6 + a, 6 + b] = M_ff[a, b]
    # (Q_v)_R = −A [ω × (ω × S_t) + 2 ω × S̄ q̇_f]
    w0 = w[0]
    w1 = w[1]
    w2 = w[2]
    e0 = w1 * S2 - w2 * S1
    e1 = w2 * S0 - w0 * S2
    e2 = w0 * S1 - w1 * S0
    v0 = w1 * e2 - w2 * e1 + 2.0 * (w1 * d2 - w2 * d1)
    v1 = w2 * e0 - w0 * e2 + 2.0 * (w2 * d0 - w0 * d2)
    v2 = w0 * e1 - w1 * e0 + 2.0 * (w0 * d1 - w1 * d0)
    for i in range(3):
        Q[i] = -(A[i, 0] * v0 + A[i, 1] * v1 + A[i, 2] * v2)
    # (Q_v)_θ = −ω × (Ī_θθ ω) − 2 (tr P ω − Pᵀ ω),  P[k, l] = G[k, l] q̇_f
    Iw0 = M[3, 3] * w0 + M[3, 4] * w1 + M[3, 5] * w2
    Iw1 = M[4, 3] * w0 + M[4, 4] * w1 + M[4, 5] * w2
    Iw2 = M[5, 3] * w0 + M[5, 4] * w1 + M[5, 5] * w2
    Q[3] = -(w1 * Iw2 - w2 * Iw1)
    Q[4] = -(w2 * Iw0 - w0 * Iw2)
    Q[5] = -(w0 * Iw1 - w1 * Iw0)
    trP = 0.0
    for k in range(3):
        acc = 0.0
        for a in range(n):
            acc += G[k, k, a] * qd_f[a]
        trP += acc
    for l in range(3):
        PTw = 0.0
        for k in range(3):
            acc = 0.0
            for a in range(n):
                acc += G[k, l, a] * qd_f[a]
            PTw += acc * w[k]
        Q[3 + l] -= 2.0 * (trP * w[l] - PTw)
    # (Q_v)_f = −(Σ ω_k ω_l G[k, l] − |ω|² Σ G[k, k]) − 2 Σ_k ω_k S_skew[k] q̇_f
    ww = w0 * w0 + w1 * w1 + w2 * w2
    for a in range(n):
        acc = 0.0
        for k in range(3):
            for l in range(3):
                acc += w[k] * w[l] * G[k, l, a]
        acc -= ww * (G[0, 0, a] + G[1, 1, a] + G[2, 2, a])
        cor = 0.0
        for b in range(n):
            cor += (w0 * S_skew[0, a, b] + w1 * S_skew[1, a, b] + w2 * S_skew[2, a, b]) * qd_f[b]
        Q[6 + a] = -acc - 2.0 * cor


@njit(cache=True)
def ffr_mass_and_qv(A, w, q_f, qd_f, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, M, Q):
    """:func:`ffr_mass_qv_into` with its own scratch (for callers outside a step)."""
    G = np.empty((3, 3, q_f.shape[0]))
    ffr_mass_qv_into(A, w, q_f, qd_f, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, G, M, Q)


@njit(cache=True)
def quat_matrix_into(q, k, A):
    """A (3, 3) of the unit quaternion q[k:k+4] (scalar first; :func:`mbs.bodies.rotations.quat_to_matrix`)."""
    p0 = q[k]
    p1 = q[k + 1]
    p2 = q[k + 2]
    p3 = q[k + 3]
    A[0, 0] = 1 - 2 * (p2 * p2 + p3 * p3)
    A[0, 1] = 2 * (p1 * p2 - p0 * p3)
    A[0, 2] = 2 * (p1 * p3 + p0 * p2)
    A[1, 0] = 2 * (p1 * p2 + p0 * p3)
    A[1, 1] = 1 - 2 * (p1 * p1 + p3 * p3)
    A[1, 2] = 2 * (p2 * p3 - p0 * p1)
    A[2, 0] = 2 * (p1 * p3 - p0 * p2)
    A[2, 1] = 2 * (p2 * p3 + p0 * p1)
    A[2, 2] = 1 - 2 * (p1 * p1 + p2 * p2)


@njit(cache=True)
def elastic_row(K, D, damped, q_f, qd_f, a):
    """Row a of K q_f + D q̇_f (the elastic and damping forces, thesis eq. 2.36, with
    their sign reversed), summed in a fixed order."""
    return elastic_block_row(K, D, damped, q_f, qd_f, np.int64(0), q_f.shape[0], a)


@njit(cache=True)
def elastic_block_row(K, D, damped, q, u, lo, hi, a):
    """Row a of the diagonal block [lo, hi) of K q + D q̇, indexed in place (a block view
    would give the kernel a second array layout to compile for): :func:`elastic_row` of
    K[lo:hi, lo:hi], q[lo:hi], in its order."""
    acc = 0.0
    for b in range(hi - lo):
        acc += K[lo + a, lo + b] * q[lo + b]
    if damped:
        for b in range(hi - lo):
            acc += D[lo + a, lo + b] * u[lo + b]
    return acc


@njit(cache=True)
def elastic_h_into(K, D, damped, q_f, qd_f, h):
    """h = −(K q_f + D q̇_f) (n_f,): the elastic and damping forces (thesis eq. 2.36)."""
    for a in range(q_f.shape[0]):
        h[a] = -elastic_row(K, D, damped, q_f, qd_f, a)


@njit(cache=True)
def ffr_free_mass_and_h(q, u, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, K, D, damped, A, G, M, h):
    """M (nu, nu) and h = Q̄_v − (0, 0, K q_f + D q̇_f) (nu,) of a free FFR body with a
    quaternion frame at its own (q, u) (:mod:`mbs.bodies.floating_frame`, T = 1); ``A``
    (3, 3) and ``G`` (3, 3, n_f) scratch."""
    quat_matrix_into(q, np.int64(3), A)
    q_f = q[7:]
    qd_f = u[6:]
    ffr_mass_qv_into(A, u[3:6], q_f, qd_f, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, G, M, h)
    for a in range(q_f.shape[0]):
        h[6 + a] -= elastic_row(K, D, damped, q_f, qd_f, a)


@njit(cache=True)
def half_quadratic(M, x) -> float:
    """½ xᵀ M x for a square M (n, n) and x (n,) (½ first in each row, as
    :func:`linear_bodies_energy`)."""
    total = 0.0
    for i in range(x.shape[0]):
        s = 0.0
        for j in range(x.shape[0]):
            s += M[i, j] * x[j]
        total += 0.5 * x[i] * s
    return total


@njit(cache=True)
def ffr_free_energies(q, u, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, K, gravity, A, G, M, Q):
    """(kinetic, potential) energy [J] of a free FFR body with a quaternion frame at its
    own (q, u), u = (Ṙ, ω̄, q̇_f): T = ½ uᵀ M̄ u (thesis eq. 2.43, M̄ of
    :func:`ffr_mass_qv_into`) and V = ½ q_fᵀ K q_f − gᵀ (m R + A (I1 + S̄ q_f)), the
    elastic energy and gravity's potential −m g·r_com (eq. 2.55: m ū_com = I1 + S̄ q_f).
    ``A``, ``G``, ``M``, ``Q`` scratch as :func:`ffr_free_mass_and_h`'s. Numpy reference:
    the body's ``kinetic_energy``, ``elastic_energy`` and its centre-of-mass frame."""
    quat_matrix_into(q, np.int64(3), A)
    q_f = q[7:]
    ffr_mass_qv_into(A, u[3:6], q_f, u[6:], mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, G, M, Q)
    potential = half_quadratic(K, q_f)
    for c in range(3):
        moment = mass * q[c]                    # m r_com = m R + A S̄_t
        for d in range(3):
            s_t = I1[d]
            for a in range(q_f.shape[0]):
                s_t += S_bar[d, a] * q_f[a]
            moment += A[c, d] * s_t
        potential -= gravity[c] * moment
    return half_quadratic(M, u), potential


@njit(cache=True)
def point_masses_energies(q_at, u_at, mass, gravity, q, u):
    """(kinetic, potential) energy [J] of the point masses with rows q_at[p], u_at[p] and
    masses mass[p] [kg]: Σ ½ m |u_p|² and Σ −m g·q_p."""
    kinetic = 0.0
    potential = 0.0
    for p in range(q_at.shape[0]):
        for c in range(3):
            v = u[u_at[p] + c]
            kinetic += 0.5 * mass[p] * v * v
            potential -= mass[p] * gravity[c] * q[q_at[p] + c]
    return kinetic, potential


@njit(cache=True)
def ffr_prescribed_mass_and_h(A, w, a_R, wd, q, u, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, K, D,
                              damped, G, Mb, Qb, M, h):
    """M = M̄_ff and h = Q̄_f − M̄_fR R̈ − M̄_fθ ω̄̇ − K q_f − D q̇_f (n_f,) of an FFR body on a
    prescribed frame (orientation A, body-frame ω̄, ω̄̇ = ``wd``, R̈ = ``a_R``) at its own
    q = q_f, u = q̇_f; ``G``, ``Mb`` (6+n_f, 6+n_f), ``Qb`` (6+n_f,) scratch."""
    ffr_mass_qv_into(A, w, q, u, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, G, Mb, Qb)
    n = q.shape[0]
    for a in range(n):
        acc = Qb[6 + a]
        s = 0.0
        for k in range(3):
            s += Mb[6 + a, k] * a_R[k]
        acc -= s
        s = 0.0
        for k in range(3):
            s += Mb[6 + a, 3 + k] * wd[k]
        acc -= s
        h[a] = acc - elastic_row(K, D, damped, q, u, a)
        for b in range(n):
            M[a, b] = Mb[6 + a, 6 + b]


@njit(cache=True)
def rigid_free_mass_and_h(q, u, mass, com, I_O, A, M, h):
    """M̄ = [[m 1, −m A c̃], [m c̃ Aᵀ, Ī_O]] and Q̄_v = (−m A ω̃ ω̃ c̄, −ω̃ Ī_O ω̄) of a rigid
    body with a quaternion frame (:mod:`mbs.bodies.rigid_body`) at its own (q, u); ``A`` scratch."""
    quat_matrix_into(q, np.int64(3), A)
    c0 = com[0]
    c1 = com[1]
    c2 = com[2]
    for i in range(3):
        for j in range(3):
            M[i, j] = mass if i == j else 0.0
            M[3 + i, 3 + j] = I_O[i, j]
        # −m A c̃: column j of c̃ is e_j × c̄
        b0 = -mass * (A[i, 1] * c2 - A[i, 2] * c1)
        b1 = -mass * (A[i, 2] * c0 - A[i, 0] * c2)
        b2 = -mass * (A[i, 0] * c1 - A[i, 1] * c0)
        M[i, 3] = b0
        M[i, 4] = b1
        M[i, 5] = b2
        M[3, i] = b0
        M[4, i] = b1
        M[5, i] = b2
    w0 = u[3]
    w1 = u[4]
    w2 = u[5]
    e0 = w1 * c2 - w2 * c1
    e1 = w2 * c0 - w0 * c2
    e2 = w0 * c1 - w1 * c0
    v0 = w1 * e2 - w2 * e1
    v1 = w2 * e0 - w0 * e2
    v2 = w0 * e1 - w1 * e0
    for i in range(3):
        h[i] = -mass * (A[i, 0] * v0 + A[i, 1] * v1 + A[i, 2] * v2)
    I0 = I_O[0, 0] * w0 + I_O[0, 1] * w1 + I_O[0, 2] * w2
    I1 = I_O[1, 0] * w0 + I_O[1, 1] * w1 + I_O[1, 2] * w2
    I2 = I_O[2, 0] * w0 + I_O[2, 1] * w1 + I_O[2, 2] * w2
    h[3] = -(w1 * I2 - w2 * I1)
    h[4] = -(w2 * I0 - w0 * I2)
    h[5] = -(w0 * I1 - w1 * I0)


@njit(cache=True)
def free_quat_increment(q, du, out):
    """q ⊕ Δu of a free quaternion frame into ``out`` (may be ``q``): R + ΔR,
    p ⊗ exp(Δθ/2) renormalized (:meth:`mbs.bodies.parametrization.Quaternion.increment`),
    q_f + Δq_f."""
    x0 = du[3]
    x1 = du[4]
    x2 = du[5]
    angle = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    half = 0.5 * angle
    if angle < 1e-4:
        s = 0.5 * (1.0 - half * half / 6.0 + half ** 4 / 120.0)
    else:
        s = math.sin(half) / angle
    b0 = math.cos(half)
    b1 = s * x0
    b2 = s * x1
    b3 = s * x2
    a0 = q[3]
    a1 = q[4]
    a2 = q[5]
    a3 = q[6]
    p0 = a0 * b0 - (a1 * b1 + a2 * b2 + a3 * b3)
    p1 = a0 * b1 + b0 * a1 + (a2 * b3 - a3 * b2)
    p2 = a0 * b2 + b0 * a2 + (a3 * b1 - a1 * b3)
    p3 = a0 * b3 + b0 * a3 + (a1 * b2 - a2 * b1)
    norm = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2 + p3 * p3)
    for i in range(3):
        out[i] = q[i] + du[i]
    out[3] = p0 / norm
    out[4] = p1 / norm
    out[5] = p2 / norm
    out[6] = p3 / norm
    for a in range(q.shape[0] - 7):
        out[7 + a] = q[7 + a] + du[6 + a]


@njit(cache=True)
def normalize_quaternion(q, k):
    """q[k:k+4] /= |q[k:k+4]| in place."""
    norm = math.sqrt(q[k] * q[k] + q[k + 1] * q[k + 1] + q[k + 2] * q[k + 2] + q[k + 3] * q[k + 3])
    for i in range(4):
        q[k + i] /= norm


@njit(cache=True)
def add_free_point_force(q, u0, phi, times, values, t, body_axes, A, h):
    """h += J_Tᵀ F (thesis eq. 2.70, 2.76) of a point ū = u0 + Φ q_f of a free quaternion
    body at its own q, with F the row of the step table (``times`` (n_t,) [s],
    ``values`` (n_t, 3) [N]) holding at t (none before times[0]); ``body_axes``: F in
    body-frame components (inertial force A F), else inertial. ``A`` scratch."""
    r = np.searchsorted(times, t, side="right") - 1
    if r < 0:
        return
    quat_matrix_into(q, np.int64(3), A)
    n = phi.shape[1]
    F0 = values[r, 0]
    F1 = values[r, 1]
    F2 = values[r, 2]
    if body_axes:
        G0 = A[0, 0] * F0 + A[0, 1] * F1 + A[0, 2] * F2
        G1 = A[1, 0] * F0 + A[1, 1] * F1 + A[1, 2] * F2
        G2 = A[2, 0] * F0 + A[2, 1] * F1 + A[2, 2] * F2
        F0 = G0
        F1 = G1
        F2 = G2
    ub0 = u0[0]
    ub1 = u0[1]
    ub2 = u0[2]
    for a in range(n):
        ub0 += phi[0, a] * q[7 + a]
        ub1 += phi[1, a] * q[7 + a]
        ub2 += phi[2, a] * q[7 + a]
    h[0] += F0
    h[1] += F1
    h[2] += F2
    # J_T columns 3..5: B = −A ũ, column j of ũ is e_j × ū
    r0 = 0.0
    r1 = 0.0
    r2 = 0.0
    for c in range(3):
        Fc = F0 if c == 0 else (F1 if c == 1 else F2)
        r0 += -(A[c, 1] * ub2 - A[c, 2] * ub1) * Fc
        r1 += -(A[c, 2] * ub0 - A[c, 0] * ub2) * Fc
        r2 += -(A[c, 0] * ub1 - A[c, 1] * ub0) * Fc
    h[3] += r0
    h[4] += r1
    h[5] += r2
    for a in range(n):
        acc = 0.0
        for c in range(3):
            Fc = F0 if c == 0 else (F1 if c == 1 else F2)
            acc += (A[c, 0] * phi[0, a] + A[c, 1] * phi[1, a] + A[c, 2] * phi[2, a]) * Fc
        h[6 + a] += acc


@njit(cache=True)
def point_jacobian_T(A, T, u_bar, phi, free, f0, out):
    """J_T of a body point into out (3, nu) (thesis eq. 2.70): on a free frame
    [1, −A ũ T, A Φ] with the elastic columns from f0 = 6; on a prescribed frame only A Φ
    (f0 = 0, T unused). Numpy reference: the formula, in ``tests/unit/mbs/test_ffr_body.py``."""
    n_f = phi.shape[1]
    if free:
        for c in range(3):
            # row c of B = −A ũ (column j of ũ is e_j × ū)
            b0 = -(A[c, 1] * u_bar[2] - A[c, 2] * u_bar[1])
            b1 = -(A[c, 2] * u_bar[0] - A[c, 0] * u_bar[2])
            b2 = -(A[c, 0] * u_bar[1] - A[c, 1] * u_bar[0])
            for j in range(3):
                out[c, j] = 1.0 if c == j else 0.0
                out[c, 3 + j] = b0 * T[0, j] + b1 * T[1, j] + b2 * T[2, j]
    for c in range(3):
        for k in range(n_f):
            out[c, f0 + k] = A[c, 0] * phi[0, k] + A[c, 1] * phi[1, k] + A[c, 2] * phi[2, k]


@njit(cache=True)
def point_masses_mass(u_at, mass, M):
    """The point masses' blocks m_p 1 (3, 3) of M at rows/columns u_at[p].. (the rest of
    M untouched)."""
    for p in range(u_at.shape[0]):
        for c in range(3):
            M[u_at[p] + c, u_at[p] + c] = mass[p]


@njit(cache=True)
def point_masses_h(u_at, force, h):
    """The point masses' h (zero: no velocity-dependent or elastic forces) plus the
    constant force[p] (3,) [N] (their gravity m g) into h at rows u_at[p].."""
    for p in range(u_at.shape[0]):
        for c in range(3):
            h[u_at[p] + c] = 0.0 + force[p, c]


LEFT_OUT, CONSTANT_FORCE, ELASTIC, ELASTIC_DAMPED, ELASTIC_LOADED, ELASTIC_DAMPED_LOADED = 0, 1, 2, 3, 4, 5
# ^ kinds of linear_bodies_h's rows


@njit(cache=True)
def linear_bodies_h(rows, KD, force, q, u, h):
    """h (nu,) of bodies whose forces are linear in (q, u) with constant coefficients,
    block by block over ``rows`` (k, 3) = (first row, end row, kind) of q = u (additive
    bodies):

    - ``LEFT_OUT`` (0): h = 0 (a body a planned run solves apart);
    - ``CONSTANT_FORCE`` (1): h = 0 + force (a point mass: its gravity m g [N]);
    - ``ELASTIC`` (2): h = −K q_f (a FFR body on a frame at rest, thesis eq. 2.36);
    - ``ELASTIC_DAMPED`` (3): h = −(K q_f + D q̇_f);
    - ``ELASTIC_LOADED`` (4), ``ELASTIC_DAMPED_LOADED`` (5): those plus the constant
      force (gravity J_Tᵀ m g [N] on a body at rest, thesis eq. 2.76),

    with K = KD[0], D = KD[1] (nu, nu), read on each block's diagonal block, force (nu,).
    The rows are :func:`elastic_row`'s, as in :func:`elastic_h_into`, and the constant
    force is :func:`point_masses_h`'s (the references the tests compare); a loaded row
    adds the force after the elastic one as :meth:`mbs.bodies.body.Body.add_point_load_into`
    adds it after :meth:`~mbs.bodies.body.Body.h_into`: the same to the bit."""
    for k in range(rows.shape[0]):
        a, b, kind = rows[k, 0], rows[k, 1], rows[k, 2]
        if kind == 0:
            for i in range(a, b):
                h[i] = 0.0
        elif kind == 1:
            for i in range(a, b):
                h[i] = 0.0 + force[i]
        else:
            K, D = KD[0], KD[1]
            damped = kind == 3 or kind == 5
            if kind >= 4:
                for i in range(b - a):
                    h[a + i] = -elastic_block_row(K, D, damped, q, u, a, b, i) + force[a + i]
            else:
                for i in range(b - a):
                    h[a + i] = -elastic_block_row(K, D, damped, q, u, a, b, i)


@njit(cache=True)
def linear_bodies_energy(rows, M, K, force, V0, q, u):
    """(kinetic, potential) energy [J] of the bodies of :func:`linear_bodies_h`'s rows
    (no left-out ones): T = ½ uᵀ M u over each body's block of the constant mass matrix M
    (nu, nu) (thesis eq. 2.43 with the frame at rest; ½ m |u|² for a point mass);
    V = ½ q_fᵀ K q_f of the elastic rows, −forceᵀ q of the ``CONSTANT_FORCE`` and loaded
    rows (gravity, −m g·r = V0_b − (J_Tᵀ m g)·q_f for a body at rest, r linear in q_f)
    plus V0 (Σ −m g·r_com at q_f = 0 of the loaded bodies). Numpy reference:
    ``System.kinetic_energy`` and ``System.potential_energy`` (equal to rounding)."""
    kinetic = 0.0
    elastic = 0.0
    gravity = 0.0
    for k in range(rows.shape[0]):
        a, b, kind = rows[k, 0], rows[k, 1], rows[k, 2]
        for i in range(a, b):
            s = 0.0
            for j in range(a, b):
                s += M[i, j] * u[j]
            kinetic += 0.5 * u[i] * s           # ½ first: the same bits, and no overflow of u M u
            if kind == CONSTANT_FORCE or kind >= ELASTIC_LOADED:
                gravity -= force[i] * q[i]
            if kind != CONSTANT_FORCE:
                s = 0.0
                for j in range(a, b):
                    s += K[i, j] * q[j]
                elastic += 0.5 * q[i] * s
    return kinetic, elastic + gravity + V0


@njit(cache=True)
def additive_advance(q, u, step, out):
    """out = q + step · u (n,) [step: s], q and u of the same length (bodies whose
    q ⊕ Δu = q + Δu: point masses, FFR bodies on a prescribed frame); ``out`` may be
    ``q``. Numpy reference: ``np.add(q, np.multiply(u, step))``, the same roundings."""
    for i in range(q.shape[0]):
        out[i] = q[i] + u[i] * step


@njit(cache=True)
def scaled_into(u, step, out):
    """out = step · u (n,): ``np.multiply(u, step, out=out)`` without the 0-d array numpy
    makes of a Python float."""
    for i in range(u.shape[0]):
        out[i] = u[i] * step


@njit(cache=True)
def point_masses_increment(q_at, u_at, q, du, out):
    """out = q + Δu on the point masses' coordinates (q[q_at[p]..] and Δu[u_at[p]..], 3
    each); ``out`` may be ``q``."""
    for p in range(q_at.shape[0]):
        for c in range(3):
            out[q_at[p] + c] = q[q_at[p] + c] + du[u_at[p] + c]


@njit(cache=True)
def free_point_position_into(q, at, u0, phi, out):
    """r = R + A (ū0 + Φ q_f) (3,) [m] (thesis eq. 2.24) of a point of a free quaternion
    body whose coordinates (R, p, q_f) start at q[at] (the system's q), into ``out``.
    Numpy reference: :meth:`mbs.bodies.floating_frame.FloatingFrameBody.point_position`."""
    n = phi.shape[1]
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for a in range(n):
        x = q[at + 7 + a]
        s0 += phi[0, a] * x
        s1 += phi[1, a] * x
        s2 += phi[2, a] * x
    ub0 = u0[0] + s0
    ub1 = u0[1] + s1
    ub2 = u0[2] + s2
    p0 = q[at + 3]
    p1 = q[at + 4]
    p2 = q[at + 5]
    p3 = q[at + 6]
    out[0] = q[at] + ((1 - 2 * (p2 * p2 + p3 * p3)) * ub0 + 2 * (p1 * p2 - p0 * p3) * ub1
                      + 2 * (p1 * p3 + p0 * p2) * ub2)
    out[1] = q[at + 1] + (2 * (p1 * p2 + p0 * p3) * ub0 + (1 - 2 * (p1 * p1 + p3 * p3)) * ub1
                          + 2 * (p2 * p3 - p0 * p1) * ub2)
    out[2] = q[at + 2] + (2 * (p1 * p3 - p0 * p2) * ub0 + 2 * (p2 * p3 + p0 * p1) * ub1
                          + (1 - 2 * (p1 * p1 + p2 * p2)) * ub2)


@njit(cache=True)
def finite_sum(q, u):
    """Σ q + Σ u: finite exactly when every entry is (barring overflow of the sum), the
    test of a diverged state (numpy reference: ``q.sum() + u.sum()``)."""
    s = 0.0
    for i in range(q.shape[0]):
        s += q[i]
    for i in range(u.shape[0]):
        s += u[i]
    return s


@njit(cache=True)
def free_quat_advance(q, u, step, du, out):
    """Δu = step · u into ``du``, then q ⊕ Δu (:func:`free_quat_increment`) into ``out``
    (may be ``q``) with its quaternion renormalized (:func:`normalize_quaternion`): a
    whole position update of one free quaternion body, step [s]."""
    for i in range(u.shape[0]):
        du[i] = u[i] * step
    free_quat_increment(q, du, out)
    normalize_quaternion(out, np.int64(3))
