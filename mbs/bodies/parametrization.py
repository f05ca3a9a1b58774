"""How a floating frame's orientation enters q and u (thesis eq. 2.25, 2.26, 3.1a).

A parametrization maps the orientation coordinates q_r and velocities u_r to the
rotation matrix A and the body-frame angular velocity ω̄ = T(q_r) u_r:

* :class:`Quaternion` (the default): q_r = unit quaternion p (4), u_r = ω̄ (3), T = 1,
  q̇_r = ½ p ⊗ (0, ω̄); no singularity, updated by the exponential map.
* :class:`Cardan`: q_r = θ = (α, β, γ) (thesis eq. 2.22), u_r = θ̇, T = Ḡ(θ)
  (eq. 2.31); singular at β = ±90°, kept for comparison with the thesis.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.registry import Registry

from mbs.bodies import rotations as rot


class Quaternion:
    """Unit quaternion orientation, body-frame angular velocity as generalized velocity."""

    name = "quaternion"
    nq, nu = 4, 3

    @staticmethod
    def coordinates(A) -> np.ndarray:
        return rot.quat_from_matrix(A)

    @staticmethod
    def matrix(qr) -> np.ndarray:
        return rot.quat_to_matrix(qr)

    @staticmethod
    def T(qr) -> np.ndarray:
        """ω̄ = T u_r: the identity."""
        return np.eye(3)

    @staticmethod
    def T_dot_u(qr, ur) -> np.ndarray:
        """Ṫ u_r = 0."""
        return np.zeros(3)

    @staticmethod
    def qdot(qr, ur) -> np.ndarray:
        """ṗ = ½ p ⊗ (0, ω̄) (thesis eq. 3.1a)."""
        return rot.quat_rate_matrix(qr) @ ur

    @staticmethod
    def velocity_coordinates(qr, omega_bar) -> np.ndarray:
        return np.asarray(omega_bar, dtype=float).copy()

    @staticmethod
    def increment(qr, dur) -> np.ndarray:
        """p ⊗ exp(Δ/2): the orientation after a body-frame rotation vector Δ [rad]."""
        p = rot.quat_multiply(qr, rot.quat_from_rotvec(dur))
        return p / np.sqrt(p @ p)

    @staticmethod
    def normalize(qr) -> None:
        qr /= np.sqrt(qr @ qr)


class Cardan:
    """Cardan angles X–Y–Z (thesis eq. 2.22) with θ̇ as generalized velocity (eq. 2.26)."""

    name = "cardan"
    nq, nu = 3, 3

    @staticmethod
    def coordinates(A) -> np.ndarray:
        return rot.cardan_from_matrix(A)

    @staticmethod
    def matrix(qr) -> np.ndarray:
        return rot.cardan_to_matrix(qr)

    @staticmethod
    def T(qr) -> np.ndarray:
        """ω̄ = Ḡ θ̇ (thesis eq. 2.30, 2.31)."""
        return rot.cardan_G_bar(qr)

    @staticmethod
    def T_dot_u(qr, ur) -> np.ndarray:
        return rot.cardan_G_bar_dot(qr, ur) @ ur

    @staticmethod
    def qdot(qr, ur) -> np.ndarray:
        return np.asarray(ur, dtype=float).copy()

    @staticmethod
    def velocity_coordinates(qr, omega_bar) -> np.ndarray:
        """θ̇ = Ḡ⁻¹ ω̄; fails at the singularity cos β = 0."""
        return np.linalg.solve(rot.cardan_G_bar(qr), omega_bar)

    @staticmethod
    def increment(qr, dur) -> np.ndarray:
        return qr + dur

    @staticmethod
    def normalize(qr) -> None:
        pass


PARAMETRIZATIONS = Registry("rotation parametrization")
PARAMETRIZATIONS.register("quaternion", Quaternion)
PARAMETRIZATIONS.register("cardan", Cardan)


def parametrization(name: str):
    """The parametrization class named ``name`` ("quaternion" or "cardan")."""
    return PARAMETRIZATIONS[name]
