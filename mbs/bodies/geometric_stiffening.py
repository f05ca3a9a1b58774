"""Geometric stiffening of an FFR body by the inertia loads of its moving frame.

Linear FFR keeps the stiffness of the unloaded body. A frame that turns and accelerates
loads the body with its own inertia (eq. G1 of :mod:`preprocess.geometric`); the
prestress of that load stiffens (centrifugal tension) or softens it. The body file holds
the modal geometric stiffness of twelve unit load cases, K_c = Φᵀ K_σ,c Φ (eq. G4), so
the stiffening at the current frame motion is

    K_geo(p) = Σ_c p_c K_c,    p = (Ω_x², Ω_y², Ω_z², Ω_xΩ_y, Ω_xΩ_z, Ω_yΩ_z, Ω̇, a)      (S1)

with Ω, Ω̇ = ω̄, ω̄̇ in body axes and a = Aᵀ R̈ the frame's acceleration in body axes,
and the elastic force of the body becomes −(K_ff + K_geo(p)) q_f (Wallrapp &
Schwertassek, Int. J. Numer. Meth. Eng. 32 (1991) 1833–1850; MBSim's FFR body carries the
same matrices). Per step: 12 n_f² multiply-adds, whatever the node count.

* **prescribed frame**: ω̄, ω̄̇ and R̈ are known functions of time: all twelve cases.
* **free frame**: ω̄ is part of the state, the centrifugal cases (the first six) enter;
  ω̄̇ and R̈ are unknowns of the step (they would enter the mass matrix unsymmetrically)
  and are left out. On a free-free body those cases carry no stress anyway (inertia
  relief, :mod:`preprocess.geometric`).

Tangents (for the implicit integrators): −∂h_f/∂q_f = K_geo(p); on a free quaternion
frame also −∂h_f/∂ω̄_k = Σ_c (∂p_c/∂ω̄_k) K_c q_f. The recorded potential energy stays
½ q_fᵀ K_ff q_f: the prestress comes from the frame's motion, it is no potential of the body.

The numba kernels write into arrays the caller owns; the numpy references
(:func:`load_parameters`, :func:`geometric_force`) are what the tests compare them with.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: number of load parameters (eq. S1)
N_CASES = 12
#: the first six parameters are the centrifugal products Ω_iΩ_j
N_CENTRIFUGAL = 6


def load_parameters(w, wd=None, a_body=None) -> np.ndarray:
    """p of eq. S1 (12,) from ω̄ (3,) [rad/s], ω̄̇ (3,) [rad/s²] and a = Aᵀ R̈ (3,) [m/s²]
    (None: zero) — the numpy reference of :func:`load_parameters_into`."""
    w = np.asarray(w, dtype=float)
    p = np.zeros(N_CASES)
    p[:6] = (w[0] ** 2, w[1] ** 2, w[2] ** 2, w[0] * w[1], w[0] * w[2], w[1] * w[2])
    if wd is not None:
        p[6:9] = wd
    if a_body is not None:
        p[9:12] = a_body
    return p


def geometric_force(K_cases, p, q_f) -> np.ndarray:
    """K_geo(p) q_f (n_f,) (eq. S1), numpy reference of :func:`sub_geometric_force`."""
    return np.einsum("c,cij,j->i", p, K_cases, q_f)


@njit(cache=True)
def load_parameters_into(w, w0, wd, A, a_R, prescribed, p):
    """p of eq. S1 into ``p`` (12,): the centrifugal products of ω̄ = w[w0:w0+3]; with
    ``prescribed`` also ω̄̇ = ``wd`` (3,) and a = Aᵀ R̈ (``A`` (3, 3), ``a_R`` (3,)), else
    zeros (``wd``, ``A``, ``a_R`` then unread)."""
    x, y, z = w[w0], w[w0 + 1], w[w0 + 2]
    p[0] = x * x
    p[1] = y * y
    p[2] = z * z
    p[3] = x * y
    p[4] = x * z
    p[5] = y * z
    for k in range(3):
        if prescribed:
            p[6 + k] = wd[k]
            p[9 + k] = A[0, k] * a_R[0] + A[1, k] * a_R[1] + A[2, k] * a_R[2]
        else:
            p[6 + k] = 0.0
            p[9 + k] = 0.0


@njit(cache=True)
def sub_geometric_force(K_cases, p, q, q0, h, h0):
    """h[h0:h0+n_f] −= K_geo(p) q[q0:q0+n_f] (eq. S1); cases with p_c = 0 are skipped."""
    n = K_cases.shape[1]
    for c in range(K_cases.shape[0]):
        pc = p[c]
        if pc == 0.0:
            continue
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += K_cases[c, i, j] * q[q0 + j]
            h[h0 + i] -= pc * s


@njit(cache=True)
def add_geometric_tangents(K_cases, p, q, q0, free, w, wi, K, D, f0, c0):
    """K[f0:f0+n_f, f0:f0+n_f] += K_geo(p); with ``free`` also the coupling to ω̄ =
    w[wi:wi+3], D[f0:f0+n_f, c0:c0+3] += Σ_c ∂p_c/∂ω̄_k K_c q_f (module docstring), with
    q_f = q[q0:q0+n_f]."""
    n = K_cases.shape[1]
    for c in range(K_cases.shape[0]):
        pc = p[c]
        if pc == 0.0:
            continue
        for i in range(n):
            for j in range(n):
                K[f0 + i, f0 + j] += pc * K_cases[c, i, j]
    if not free:
        return
    # ∂p/∂ω̄_k of the centrifugal products p_0..p_5 = x², y², z², xy, xz, yz
    x, y, z = w[wi], w[wi + 1], w[wi + 2]
    for i in range(n):
        k0 = k1 = k2 = k3 = k4 = k5 = 0.0
        for j in range(n):
            qj = q[q0 + j]
            k0 += K_cases[0, i, j] * qj
            k1 += K_cases[1, i, j] * qj
            k2 += K_cases[2, i, j] * qj
            k3 += K_cases[3, i, j] * qj
            k4 += K_cases[4, i, j] * qj
            k5 += K_cases[5, i, j] * qj
        D[f0 + i, c0] += 2.0 * x * k0 + y * k3 + z * k4
        D[f0 + i, c0 + 1] += 2.0 * y * k1 + x * k3 + z * k5
        D[f0 + i, c0 + 2] += 2.0 * z * k2 + x * k4 + y * k5
