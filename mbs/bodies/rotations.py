"""Rotation parametrizations: unit quaternions (the default) and the thesis's Cardan angles.

Conventions
-----------
* ``A``: rotation matrix (3, 3) mapping body-frame components to inertial ones,
  r = R + A ū (thesis eq. 2.21).
* ``omega_bar`` (ω̄): angular velocity in body-frame components, Ȧ = A ω̄~ (thesis eq. 2.28).
* Quaternions ``p = (p0, p1, p2, p3)``, scalar first, unit norm; A(p) is the usual
  Euler–Rodrigues matrix and ṗ = ½ p ⊗ (0, ω̄) — the map q̇ = Y(q) u of thesis eq. 3.1a
  restricted to the orientation.
* Cardan angles θ = (α, β, γ), successive rotations about x, y', z'' (thesis eq. 2.22),
  with ω̄ = Ḡ θ̇ (eq. 2.30, 2.31); singular where cos β = 0.
"""

from __future__ import annotations

import numpy as np


def skew(v) -> np.ndarray:
    """The skew-symmetric matrix ṽ with ṽ w = v × w (thesis eq. 2.29)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


# --- unit quaternions -----------------------------------------------------------------

def quat_multiply(a, b) -> np.ndarray:
    """Hamilton product a ⊗ b of two quaternions (scalar first)."""
    a0, av, b0, bv = a[0], a[1:], b[0], b[1:]
    out = np.empty(4)
    out[0] = a0 * b0 - av @ bv
    out[1:] = a0 * bv + b0 * av + np.cross(av, bv)
    return out


def quat_to_matrix(p) -> np.ndarray:
    """Rotation matrix A (3, 3) of the unit quaternion p (scalar first)."""
    p0, p1, p2, p3 = p
    return np.array([
        [1 - 2 * (p2 * p2 + p3 * p3), 2 * (p1 * p2 - p0 * p3), 2 * (p1 * p3 + p0 * p2)],
        [2 * (p1 * p2 + p0 * p3), 1 - 2 * (p1 * p1 + p3 * p3), 2 * (p2 * p3 - p0 * p1)],
        [2 * (p1 * p3 - p0 * p2), 2 * (p2 * p3 + p0 * p1), 1 - 2 * (p1 * p1 + p2 * p2)],
    ])


def quat_from_rotvec(phi) -> np.ndarray:
    """Quaternion exp(φ/2) of the rotation vector φ [rad] (angle |φ| about φ/|φ|)."""
    phi = np.asarray(phi, dtype=float)
    angle = np.sqrt(phi @ phi)
    half = 0.5 * angle
    # sin(x)/x by its Taylor series near 0 keeps full precision for tiny increments
    s = 0.5 * (1.0 - half * half / 6.0 + half ** 4 / 120.0) if angle < 1e-4 else np.sin(half) / angle
    return np.concatenate(([np.cos(half)], s * phi))


def quat_from_matrix(A) -> np.ndarray:
    """Unit quaternion (scalar first, p0 >= 0) of the rotation matrix A (Shepperd's method,
    robust for every rotation including angle π)."""
    A = np.asarray(A, dtype=float)
    tr = np.trace(A)
    candidates = np.array([tr, A[0, 0], A[1, 1], A[2, 2]])
    i = int(np.argmax(candidates))
    p = np.empty(4)
    if i == 0:
        p[0] = 0.5 * np.sqrt(1.0 + tr)
        f = 0.25 / p[0]
        p[1:] = f * np.array([A[2, 1] - A[1, 2], A[0, 2] - A[2, 0], A[1, 0] - A[0, 1]])
    else:
        k = i - 1
        a, b = (k + 1) % 3, (k + 2) % 3
        p[1 + k] = 0.5 * np.sqrt(1.0 + 2.0 * A[k, k] - tr)
        f = 0.25 / p[1 + k]
        p[0] = f * (A[b, a] - A[a, b])
        p[1 + a] = f * (A[a, k] + A[k, a])
        p[1 + b] = f * (A[b, k] + A[k, b])
    return p if p[0] >= 0 else -p


def quat_rate_matrix(p) -> np.ndarray:
    """Y_p (4, 3) with ṗ = Y_p ω̄, i.e. ½ p ⊗ (0, ω̄) (thesis eq. 3.1a, orientation block)."""
    p0, p1, p2, p3 = p
    return 0.5 * np.array([[-p1, -p2, -p3], [p0, -p3, p2], [p3, p0, -p1], [-p2, p1, p0]])


def rotvec_from_matrix(A) -> np.ndarray:
    """Rotation vector φ [rad] with |φ| <= π of the rotation matrix A, robust at |φ| = π
    (via the quaternion, not via arccos of the trace)."""
    p = quat_from_matrix(A)
    s = np.sqrt(p[1:] @ p[1:])
    if s < 1e-12:
        return 2.0 * p[1:]
    return 2.0 * np.arctan2(s, p[0]) * p[1:] / s


# --- Cardan angles (thesis eq. 2.22, 2.31) ------------------------------------------------

def cardan_to_matrix(theta) -> np.ndarray:
    """A(α, β, γ) of thesis eq. 2.22: rotations about x, then y', then z''."""
    a, b, g = theta
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    return np.array([
        [cb * cg, -cb * sg, sb],
        [ca * sg + cg * sa * sb, ca * cg - sa * sb * sg, -cb * sa],
        [sa * sg - ca * cg * sb, cg * sa + ca * sb * sg, ca * cb],
    ])


def cardan_G_bar(theta) -> np.ndarray:
    """Ḡ(θ) of thesis eq. 2.31 with ω̄ = Ḡ θ̇ (body-frame angular velocity)."""
    _, b, g = theta
    cb, sb, cg, sg = np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    return np.array([[cb * cg, sg, 0.0], [-cb * sg, cg, 0.0], [sb, 0.0, 1.0]])


def cardan_G_bar_dot(theta, theta_dot) -> np.ndarray:
    """dḠ/dt = ∂Ḡ/∂β β̇ + ∂Ḡ/∂γ γ̇ (derivative of thesis eq. 2.31)."""
    _, b, g = theta
    _, db, dg = theta_dot
    cb, sb, cg, sg = np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    return np.array([
        [-sb * cg * db - cb * sg * dg, cg * dg, 0.0],
        [sb * sg * db - cb * cg * dg, -sg * dg, 0.0],
        [cb * db, 0.0, 0.0],
    ])


def cardan_from_matrix(A) -> np.ndarray:
    """Cardan angles (α, β, γ) of A with β in [−π/2, π/2] (inverse of thesis eq. 2.22)."""
    b = np.arcsin(np.clip(A[0, 2], -1.0, 1.0))
    a = np.arctan2(-A[1, 2], A[2, 2])
    g = np.arctan2(-A[0, 1], A[0, 0])
    return np.array([a, b, g])
