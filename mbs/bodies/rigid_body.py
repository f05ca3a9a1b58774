"""RigidBody (Newton–Euler about a body-fixed reference point) and PointMass.

The rigid body's frame origin R need not be its centre of mass; with the centre of mass
at c̄ in the body frame and the inertia tensor Ī_c about it, the classical equations read
in the coordinates (Ṙ, ω̄):

    M̄ = [[m 1, −m A c̃], [m c̃ Aᵀ, Ī_O]],   Ī_O = Ī_c + m (|c̄|² 1 − c̄ c̄ᵀ)   (parallel axes)
    Q̄_v = (−m A ω̃ ω̃ c̄,  −ω̃ Ī_O ω̄)

(the FFR equations with no modes, thesis eq. 2.46, written independently of the shape
integrals). Orientation parametrizations as for every floating-frame body.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError
from ffrmbs.vec3 import cross3

from mbs.bodies._kernels import rigid_free_mass_and_h
from mbs.bodies.body import Body, Frame
from mbs.bodies.floating_frame import FloatingFrameBody
from mbs.bodies.rotations import skew


class RigidBody(FloatingFrameBody):
    """A rigid body of ``mass`` [kg], inertia tensor ``inertia`` (3, 3) [kg m²] about its
    centre of mass in body axes, centre of mass at ``com`` [m] in the body frame."""

    def __init__(self, mass, inertia, com=(0.0, 0.0, 0.0), rotation="quaternion", name="rigid"):
        super().__init__(name, 0, "free", rotation)
        inertia = np.asarray(inertia, dtype=float)
        if not mass > 0:
            raise ModelError(f"{name}: mass must be positive, got {mass}")
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T) \
                or np.linalg.eigvalsh(inertia).min() < 0:
            raise ModelError(f"{name}: inertia must be a symmetric positive semi-definite 3x3 matrix")
        self.mass = float(mass)
        self.com = np.asarray(com, dtype=float)
        c = self.com
        self.inertia_origin = inertia + self.mass * ((c @ c) * np.eye(3) - np.outer(c, c))

    def _dynamics(self, A, q_f, w, qdot_f):
        M = np.empty((6, 6))
        M[:3, :3] = self.mass * np.eye(3)
        M[:3, 3:] = -self.mass * A @ skew(self.com)
        M[3:, :3] = M[:3, 3:].T
        M[3:, 3:] = self.inertia_origin
        Q = np.concatenate((-self.mass * A @ cross3(w, cross3(w, self.com)),
                            -cross3(w, self.inertia_origin @ w)))
        return M, Q

    def mass_and_h_into(self, q, u, t, M, h, work=None):
        """M̄ and Q̄_v (module docstring) by :func:`mbs.bodies._kernels.rigid_free_mass_and_h` on a
        quaternion frame; a Cardan frame takes the generic path."""
        if self.free_quaternion:
            rigid_free_mass_and_h(q, u, self.mass, self.com, self.inertia_origin,
                                  np.empty((3, 3)) if work is None else work[0], M, h)
        else:
            super().mass_and_h_into(q, u, t, M, h, work)

    def com_frame(self) -> Frame:
        return self.frame_at(self.com, name="centre of mass")


class PointMass(Body):
    """A point of ``mass`` [kg]: q = r (3) [m], u = ṙ (3) [m/s], M = m 1, h = 0."""

    nq = nu = 3
    n_modes = 0
    constant_mass = True
    additive = True
    translation_only = True

    def __init__(self, mass, position=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0), name="point"):
        super().__init__(name)
        if not mass > 0:
            raise ModelError(f"{name}: mass must be positive, got {mass}")
        self.mass = float(mass)
        self.q_init = np.array(position, dtype=float)
        self.u_init = np.array(velocity, dtype=float)

    def mass_matrix(self, q, t=0.0):
        return self.mass * np.eye(3)

    def h(self, q, u, t=0.0):
        return np.zeros(3)

    def qdot(self, q, u):
        return u.copy()

    def increment(self, q, du):
        return q + du

    def mass_and_h_into(self, q, u, t, M, h, work=None):
        M.fill(0.0)
        for i in range(3):
            M[i, i] = self.mass
        h.fill(0.0)

    def h_into(self, q, u, t, h, work=None):
        h.fill(0.0)

    def increment_into(self, q, du, out):
        np.add(q, du, out=out)

    def add_point_load_into(self, q, frame, times, values, t, body_axes, h, work=None):
        """h += F: J_T = 1 and the point mass's axes are the inertial ones."""
        r = int(np.searchsorted(times, t, side="right")) - 1
        if r >= 0:
            h += values[r]

    def kinetic_energy(self, q, u, t=0.0):
        return 0.5 * self.mass * u @ u

    def bounding_sphere(self, q, t=0.0):
        return q, 0.0

    def linear_momentum(self, q, u, t=0.0):
        return self.mass * u

    def angular_momentum(self, q, u, t=0.0):
        return np.cross(q, self.mass * u)

    @property
    def point(self) -> Frame:
        """The point itself as a frame (orientation: the inertial axes)."""
        return Frame(self, (0.0, 0.0, 0.0), name=self.name)

    def com_frame(self) -> Frame:
        return self.point

    def orientation(self, q, t=0.0):
        return np.eye(3)

    def angular_velocity(self, q, u, t=0.0):
        return np.zeros(3)

    def point_position(self, q, frame, t=0.0):
        return q + frame.u0

    def point_velocity(self, q, u, frame, t=0.0):
        return u.copy()

    def point_J_T(self, q, frame, t=0.0):
        return np.eye(3)

    def J_R(self, q, t=0.0):
        return np.zeros((3, 3))

    def point_bias_T(self, q, u, frame, t=0.0):
        return np.zeros(3)

    def bias_R(self, q, u, t=0.0):
        return np.zeros(3)
