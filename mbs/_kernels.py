"""numba kernels of the FFR body's per-step terms; the plain-numpy reference is
:class:`mbs.shape_integrals.ShapeIntegrals` (``deformed``, ``quadratic_velocity``), and
the tests compare the two.

``ffr_mass_and_qv`` fills, in the full coordinates (Ṙ, ω̄, q̇_f), the mass matrix M̄ of
thesis eq. 2.44 (blocks eq. 2.47, 2.50, 2.57, 2.58, 2.66, 2.69) and the quadratic
velocity vector Q̄_v of eq. 2.77–2.79 (formulas in :mod:`mbs.shape_integrals`), in one
pass over the shape integrals: O(n_f²), no allocation beyond a few 3 × 3 × n_f scratch
arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def ffr_mass_and_qv(A, w, q_f, qd_f, mass, I1, S_bar, I_kl, I_bar, S_kl, M_ff, S_skew, M, Q):
    n = q_f.shape[0]
    # G[k, l] = Ī_kl + S_lk q_f ;  U[k, l] = Σ m ū_k ū_l ;  S_t = I1 + S̄ q_f
    G = np.empty((3, 3, n))
    U = np.empty((3, 3))
    S_t = np.empty(3)
    Sqd = np.zeros(3)
    for k in range(3):
        s = I1[k]
        sd = 0.0
        for a in range(n):
            s += S_bar[k, a] * q_f[a]
            sd += S_bar[k, a] * qd_f[a]
        S_t[k] = s
        Sqd[k] = sd
    for k in range(3):
        for l in range(3):
            for a in range(n):
                acc = I_bar[k, l, a]
                for b in range(n):
                    acc += S_kl[l, k, a, b] * q_f[b]
                G[k, l, a] = acc
    for k in range(3):
        for l in range(3):
            acc = I_kl[k, l]
            for a in range(n):
                acc += (I_bar[l, k, a] + G[k, l, a]) * q_f[a]
            U[k, l] = acc
    tr = U[0, 0] + U[1, 1] + U[2, 2]
    I_thth = -U.copy()
    for k in range(3):
        I_thth[k, k] += tr
    # mass matrix
    N = 6 + n
    for i in range(N):
        for j in range(N):
            M[i, j] = 0.0
    St_skew = np.array([[0.0, -S_t[2], S_t[1]], [S_t[2], 0.0, -S_t[0]], [-S_t[1], S_t[0], 0.0]])
    for i in range(3):
        M[i, i] = mass
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc -= A[i, k] * St_skew[k, j]
            M[i, 3 + j] = acc
            M[3 + j, i] = acc
            M[3 + i, 3 + j] = I_thth[i, j]
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
    # quadratic velocity vector
    # (Q_v)_R = −A [ω × (ω × S_t) + 2 ω × S̄ q̇_f]
    c1 = np.array([w[1] * S_t[2] - w[2] * S_t[1], w[2] * S_t[0] - w[0] * S_t[2], w[0] * S_t[1] - w[1] * S_t[0]])
    v = np.array([w[1] * c1[2] - w[2] * c1[1], w[2] * c1[0] - w[0] * c1[2], w[0] * c1[1] - w[1] * c1[0]])
    v[0] += 2.0 * (w[1] * Sqd[2] - w[2] * Sqd[1])
    v[1] += 2.0 * (w[2] * Sqd[0] - w[0] * Sqd[2])
    v[2] += 2.0 * (w[0] * Sqd[1] - w[1] * Sqd[0])
    for i in range(3):
        Q[i] = -(A[i, 0] * v[0] + A[i, 1] * v[1] + A[i, 2] * v[2])
    # (Q_v)_θ = −ω × (Ī_θθ ω) − 2 (tr P ω − Pᵀ ω),  P[k, l] = G[k, l] q̇_f
    P = np.zeros((3, 3))
    for k in range(3):
        for l in range(3):
            acc = 0.0
            for a in range(n):
                acc += G[k, l, a] * qd_f[a]
            P[k, l] = acc
    Iw = np.zeros(3)
    for i in range(3):
        Iw[i] = I_thth[i, 0] * w[0] + I_thth[i, 1] * w[1] + I_thth[i, 2] * w[2]
    trP = P[0, 0] + P[1, 1] + P[2, 2]
    Q[3] = -(w[1] * Iw[2] - w[2] * Iw[1])
    Q[4] = -(w[2] * Iw[0] - w[0] * Iw[2])
    Q[5] = -(w[0] * Iw[1] - w[1] * Iw[0])
    for l in range(3):
        PTw = P[0, l] * w[0] + P[1, l] * w[1] + P[2, l] * w[2]
        Q[3 + l] -= 2.0 * (trP * w[l] - PTw)
    # (Q_v)_f = −(Σ ω_k ω_l G[k, l] − |ω|² Σ G[k, k]) − 2 Σ_k ω_k S_skew[k] q̇_f
    w2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    for a in range(n):
        acc = 0.0
        for k in range(3):
            for l in range(3):
                acc += w[k] * w[l] * G[k, l, a]
        acc -= w2 * (G[0, 0, a] + G[1, 1, a] + G[2, 2, a])
        cor = 0.0
        for b in range(n):
            cor += (w[0] * S_skew[0, a, b] + w[1] * S_skew[1, a, b] + w[2] * S_skew[2, a, b]) * qd_f[b]
        Q[6 + a] = -acc - 2.0 * cor


@njit(cache=True)
def point_jacobian_T(A, T, u_bar, phi, free, f0, out):
    """J_T of a body point into out (3, nu) (thesis eq. 2.70): on a free frame
    [1, −A ũ T, A Φ] with the elastic columns from f0 = 6; on a prescribed frame only A Φ
    (f0 = 0, T unused). Numpy reference: the formula, in ``tests/test_ffr_body.py``."""
    n_f = phi.shape[1]
    if free:
        # B = −A ũ: column j of ũ is e_j × ū
        B = np.empty((3, 3))
        for c in range(3):
            B[c, 0] = -(A[c, 1] * u_bar[2] - A[c, 2] * u_bar[1])
            B[c, 1] = -(A[c, 2] * u_bar[0] - A[c, 0] * u_bar[2])
            B[c, 2] = -(A[c, 0] * u_bar[1] - A[c, 1] * u_bar[0])
        for c in range(3):
            for j in range(3):
                out[c, j] = 1.0 if c == j else 0.0
                out[c, 3 + j] = B[c, 0] * T[0, j] + B[c, 1] * T[1, j] + B[c, 2] * T[2, j]
    for c in range(3):
        for k in range(n_f):
            out[c, f0 + k] = A[c, 0] * phi[0, k] + A[c, 1] * phi[1, k] + A[c, 2] * phi[2, k]
