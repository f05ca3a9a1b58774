"""Bodies described in a floating frame of reference (thesis Sec. 2.4): kinematics and layout.

The frame has origin R and orientation A; a point sits at r = R + A ū with
ū = ū0 + Φ q_f (thesis eq. 2.24). Two kinds of frame:

* **free**: q = (R, q_r, q_f), u = (Ṙ, u_r, q̇_f) with the orientation parametrization
  of :mod:`mbs.bodies.parametrization` (ω̄ = T(q_r) u_r). Then (thesis eq. 2.70, 2.72, here with
  ω̄ = T u_r)

      J_T = [1, −A ũ T, A Φ],   J_R = [0, A T, 0],
      J̇_T u = A [ω̃² ū + 2 ω̃ Φ q̇_f − ũ Ṫ u_r],   J̇_R u = A Ṫ u_r.

* **prescribed** (frame-fixed, thesis Sec. 5.1, or moving on a given path): q = q_f,
  u = q̇_f, the frame's motion R(t), A(t) given by a :class:`PrescribedFrameMotion`;
  J_T = A Φ, J_R = 0, and J̇_T u = R̈ + A [ω̄̇ × ū + ω̃² ū + 2 ω̃ Φ q̇_f].

Subclasses supply the inertia: ``_dynamics(A, q_f, ω̄, q̇_f)`` gives the mass matrix M̄ in
the full coordinates (Ṙ, ω̄, q̇_f) and the forces Q̄_v = −Σ m J̄ᵀ J̄̇ u there; this module
maps both to the body's own coordinates,

    free:        M = Tᵀ M̄ T,   h = Tᵀ (Q̄_v − M̄ (0, Ṫ u_r, 0)) − K q − D u
    prescribed:  M = M̄_ff,     h = Q̄_f − M̄_f,(R,θ) (R̈, ω̄̇) − K q − D u

with T = blockdiag(1, T(q_r), 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ffrmbs.errors import ModelError
from ffrmbs.vec3 import cross3

from mbs.bodies._kernels import add_free_point_force, free_quat_increment, normalize_quaternion, point_jacobian_T
from mbs.bodies.body import Body, Frame
from mbs.bodies.parametrization import parametrization


@dataclass(frozen=True)
class PrescribedFrameMotion:
    """A body frame moving on a given path (or fixed, :meth:`fixed`).

    ``translation(t)`` returns (R, Ṙ, R̈) in inertial components [m, m/s, m/s²];
    ``rotation(t)`` returns (A, ω̄, ω̄̇) with ω̄ in body-frame components [rad/s, rad/s²].
    """

    translation: Callable
    rotation: Callable
    at_rest: bool = False      # True for :meth:`fixed`: no frame velocity or acceleration ever

    @classmethod
    def fixed(cls, R=(0.0, 0.0, 0.0), A=None) -> "PrescribedFrameMotion":
        """The body frame fixed in the inertial frame at R [m] with orientation A."""
        R = np.asarray(R, dtype=float)
        A = np.eye(3) if A is None else np.asarray(A, dtype=float)
        zero = np.zeros(3)
        return cls(lambda t: (R, zero, zero), lambda t: (A, zero, zero), at_rest=True)

    @classmethod
    def spin_up(cls, omega, ramp_time, axis=2, R=(0.0, 0.0, 0.0)) -> "PrescribedFrameMotion":
        """The frame at R [m] turning about its body axis ``axis`` (0, 1, 2), spun up
        smoothly from rest to ``omega`` [rad/s] in ``ramp_time`` T [s] (Kane, Ryan &
        Banerjee, J. Guid. Control Dyn. 10 (1987) 139–151, eq. 46): the angle

            θ(t) = (Ω/T) [t²/2 + (T/2π)² (cos(2πt/T) − 1)]   for t <= T,
            θ(t) = Ω (t − T/2)                                 after,

        so θ̇ = (Ω/T)[t − (T/2π) sin(2πt/T)] and θ̈ = (Ω/T)[1 − cos(2πt/T)] rise from 0
        and reach Ω and 0 at T, continuously."""
        if axis not in (0, 1, 2):
            raise ModelError(f"spin_up axis must be 0, 1 or 2, not {axis!r}")
        for name, value in (("spin_up omega", omega), ("spin_up ramp_time", ramp_time)):
            if not (np.isfinite(value) and value > 0):
                raise ModelError(f"{name} must be positive and finite, not {value!r}")
        R = np.asarray(R, dtype=float)
        zero = np.zeros(3)
        i, j = [k for k in range(3) if k != axis]
        k = 2.0 * math.pi / ramp_time
        rate0 = omega / ramp_time

        def rotation(t):
            if t <= ramp_time:
                ck = math.cos(k * t)
                theta = rate0 * (0.5 * t * t + (ck - 1.0) / (k * k))
                rate, acc = rate0 * (t - math.sin(k * t) / k), rate0 * (1.0 - ck)
            else:
                theta, rate, acc = omega * (t - 0.5 * ramp_time), omega, 0.0
            c, s = math.cos(theta), math.sin(theta)
            A = np.zeros((3, 3))
            A[axis, axis] = 1.0
            A[i, i], A[i, j], A[j, i], A[j, j] = c, -s, s, c
            w, wd = np.zeros(3), np.zeros(3)
            w[axis], wd[axis] = rate, acc
            return A, w, wd

        return cls(lambda t: (R, zero, zero), rotation)


class FloatingFrameBody(Body):
    """Shared kinematics of FFR and rigid bodies (see module docstring).

    ``frame`` is "free" or a :class:`PrescribedFrameMotion`; ``rotation`` names the
    parametrization of a free frame ("quaternion" default, or "cardan").
    """

    n_modes = 0

    def __init__(self, name, n_modes, frame="free", rotation="quaternion"):
        super().__init__(name)
        self.n_modes = n_modes
        self._M_rest = None
        if isinstance(frame, PrescribedFrameMotion):
            self.motion, self.param = frame, None
            self.nq = self.nu = n_modes
            self._f = slice(0, n_modes)
            self._fu = slice(0, n_modes)
        elif frame == "free":
            self.motion, self.param = None, parametrization(rotation)
            nr = self.param.nq
            self.nq = 3 + nr + n_modes
            self.nu = 6 + n_modes
            self._r = slice(3, 3 + nr)
            self._f = slice(3 + nr, self.nq)
            self._fu = slice(6, self.nu)
        else:
            raise ModelError(f"{name}: frame must be 'free' or a PrescribedFrameMotion, got {frame!r}")
        self._T_unused = np.zeros((3, 3))  # placeholder T of a prescribed frame for the J_T kernel
        self.q_init = np.zeros(self.nq)
        self.u_init = np.zeros(self.nu)
        if self.param is not None:
            self.q_init[self._r] = self.param.coordinates(np.eye(3))

    @property
    def frame_at_rest(self) -> bool:
        """True for a frame fixed in space (:meth:`PrescribedFrameMotion.fixed`): Q_v = 0
        and M = m_ff, so h and the kinetic energy skip the shape-integral pass."""
        return self.motion is not None and self.motion.at_rest

    @property
    def rheonomic(self) -> bool:
        """A prescribed frame motion that is not at rest moves the body's points at u = 0
        (:attr:`mbs.bodies.body.Body.rheonomic`)."""
        return self.motion is not None and not self.motion.at_rest

    @property
    def constant_mass(self) -> bool:
        """A prescribed frame leaves M = M_ff = Φᵀ M Φ, constant (thesis eq. 2.69)."""
        return self.motion is not None

    @property
    def additive(self) -> bool:
        """A prescribed frame leaves q = q_f, so q ⊕ Δu = q + Δu."""
        return self.motion is not None

    @property
    def is_free(self) -> bool:
        """True for a free frame, False for a prescribed one."""
        return self.motion is None

    # --- initial state ----------------------------------------------------------------
    def set_initial(self, R=None, A=None, v=None, omega=None, q_f=None, qdot_f=None):
        """Set the initial state: origin R [m], orientation A (3, 3), origin velocity v
        [m/s], inertial angular velocity ω [rad/s], elastic coordinates and rates.
        Returns self."""
        if self.motion is not None and any(x is not None for x in (R, A, v, omega)):
            raise ModelError(f"{self.name}: the frame motion is prescribed; set only q_f and qdot_f")
        q, u = self.q_init, self.u_init
        if R is not None:
            q[:3] = R
        if A is not None:
            q[self._r] = self.param.coordinates(np.asarray(A, dtype=float))
        if v is not None:
            u[:3] = v
        if omega is not None:
            A_now = self.param.matrix(q[self._r])
            u[3:6] = self.param.velocity_coordinates(q[self._r], A_now.T @ np.asarray(omega, float))
        if q_f is not None:
            q[self._f] = q_f
        if qdot_f is not None:
            u[self._fu] = qdot_f
        return self

    # --- frame state ------------------------------------------------------------------
    def _frame(self, q, u, t):
        """(R, A, v, ω̄, T, Ṫu_r, a_R, ω̄̇); the last two are zero for a free frame (their
        effect there enters through u̇)."""
        if self.motion is None:
            qr, ur = q[self._r], u[3:6] if u is not None else None
            A = self.param.matrix(qr)
            T = self.param.T(qr)
            if u is None:
                return q[:3], A, None, None, T, None, None, None
            return q[:3], A, u[:3], T @ ur, T, self.param.T_dot_u(qr, ur), None, None
        R, v, a = self.motion.translation(t)
        A, w, wd = self.motion.rotation(t)
        return R, A, v, w, None, None, a, wd

    def frame_state(self, q, u=None, t=0.0):
        """(R [m], A (3, 3), v [m/s], ω̄ [rad/s], T) of the body frame at (q, u, t): origin,
        orientation, origin velocity, body-frame angular velocity and the map ω̄ = T u_r
        (None on a prescribed frame); v and ω̄ are None when u is None. The narrow
        protocol through which contours read frame kinematics."""
        R, A, v, w, T, *_ = self._frame(q, u, t)
        return R, A, v, w, T

    def orientation(self, q, t=0.0):
        """Body-frame orientation A (3, 3)."""
        return self._frame(q, None, t)[1]

    def modal_coordinates(self, q) -> np.ndarray:
        """q_f (..., n_f) [-]: the modal part of the body's coordinates ``q`` (..., nq_b)."""
        return q[..., self._f]

    def angular_velocity(self, q, u, t=0.0):
        """Inertial angular velocity ω = A ω̄ [rad/s]."""
        _, A, _, w, *_ = self._frame(q, u, t)
        return A @ w

    @property
    def q_f_slice(self) -> slice:
        """Where the elastic coordinates q_f (n_f,) [-] sit in the body's own q."""
        return self._f

    @property
    def u_f_slice(self) -> slice:
        """Where the elastic velocities q̇_f (n_f,) [1/s] sit in the body's own u."""
        return self._fu

    @property
    def q_r_slice(self) -> slice:
        """Where the rotation coordinates of a free frame (quaternion p (4,) [-] or Cardan
        angles (3,) [rad], :attr:`param`) sit in the body's own q; AttributeError on a
        prescribed frame, which has none."""
        return self._r

    def elastic_coordinates(self, q):
        """q_f (n_f,) of the body's own q (empty for rigid bodies)."""
        return q[self._f]

    def elastic_velocities(self, u):
        """q̇_f (n_f,) of the body's own u (empty for rigid bodies)."""
        return u[self._fu]

    def _u_bar(self, q, frame: Frame):
        return frame.u0 + frame.phi @ q[self._f] if self.n_modes else frame.u0

    def point_position(self, q, frame, t=0.0):
        R, A, *_ = self._frame(q, None, t)
        return R + A @ self._u_bar(q, frame)

    def point_velocity(self, q, u, frame, t=0.0):
        R, A, v, w, *_ = self._frame(q, u, t)
        rel = cross3(w, self._u_bar(q, frame))
        if self.n_modes:
            rel += frame.phi @ u[self._fu]
        return v + A @ rel

    def point_J_T(self, q, frame, t=0.0):
        _, A, _, _, T, *_ = self._frame(q, None, t)
        return self.fill_J_T(A, T, self._u_bar(q, frame), frame.phi, np.empty((3, self.nu)))

    def point_kinematics(self, q, frame, t=0.0):
        """(r, A, J_T, J_R) of ``frame`` (:meth:`mbs.bodies.body.Body.point_kinematics`)
        from one evaluation of the body frame."""
        R, A, _, _, T, *_ = self._frame(q, None, t)
        u_bar = self._u_bar(q, frame)
        return (R + A @ u_bar, A @ frame.A_rel, self.fill_J_T(A, T, u_bar, frame.phi, np.empty((3, self.nu))),
                self.fill_J_R(A, T, np.empty((3, self.nu))))

    def fill_J_T(self, A, T, u_bar, phi, out):
        """Write J_T = [1, −A ũ T, A Φ] (thesis eq. 2.70; only A Φ on a prescribed frame)
        of the body point at ū = ``u_bar`` with mode-shape rows ``phi`` (3, n_f) into
        ``out`` (3, nu) and return it. A, T from :meth:`frame_state` (T is None for a
        prescribed frame). Contours call it with interpolated ū and Φ (thesis Sec. 3.2.2)."""
        point_jacobian_T(A, self._T_unused if T is None else T, u_bar, phi, self.motion is None,
                         self._fu.start, out)
        return out

    def fill_J_R(self, A, T, out):
        """Write J_R = [0, A T, 0] (thesis eq. 2.72) into ``out`` (3, nu) and return it:
        the same for every point of the body."""
        out[:] = 0.0
        if self.motion is None:
            out[:, 3:6] = A @ T
        return out

    def J_R(self, q, t=0.0):
        _, A, _, _, T, *_ = self._frame(q, None, t)
        return self.fill_J_R(A, T, np.empty((3, self.nu)))

    def point_bias_T(self, q, u, frame, t=0.0):
        R, A, v, w, T, Tdu, a, wd = self._frame(q, u, t)
        ub = self._u_bar(q, frame)
        acc = cross3(w, cross3(w, ub))
        if self.n_modes:
            acc += 2.0 * cross3(w, frame.phi @ u[self._fu])
        if self.motion is None:
            return A @ (acc + cross3(Tdu, ub))
        return a + A @ (acc + cross3(wd, ub))

    def bias_R(self, q, u, t=0.0):
        _, A, _, _, _, Tdu, _, wd = self._frame(q, u, t)
        return A @ (Tdu if self.motion is None else wd)

    # --- dynamics -----------------------------------------------------------------------
    def _dynamics(self, A, q_f, w, qdot_f):
        """(M̄ (6+n_f, 6+n_f), Q̄_v (6+n_f,)) in the full coordinates (Ṙ, ω̄, q̇_f); fresh
        arrays the caller may modify."""
        raise NotImplementedError

    def _elastic(self, q_f, qdot_f):
        """K q_f + D q̇_f (n_f,); rigid bodies have none."""
        return np.zeros(self.n_modes)

    def mass_and_h(self, q, u, t=0.0):
        """(M, h) at one state, sharing the shape-integral pass (module docstring)."""
        q_f, qd_f = q[self._f], u[self._fu]
        if self.frame_at_rest:
            return self.mass_matrix(q, t), self.h(q, u, t)
        _, A, _, w, T, Tdu, a, wd = self._frame(q, u, t)
        Mb, Q = self._dynamics(A, q_f, w, qd_f)
        if self.motion is not None:
            h = Q[6:] - Mb[6:, :3] @ a - Mb[6:, 3:6] @ wd
            M = Mb[6:, 6:]
        else:
            h, M = Q, Mb
            if self.param.name != "quaternion":
                h = Q - Mb[:, 3:6] @ Tdu
                h[3:6] = T.T @ h[3:6]
                M[3:6, :] = T.T @ M[3:6, :]
                M[:, 3:6] = M[:, 3:6] @ T
        if self.n_modes:
            h[-self.n_modes:] -= self._elastic(q_f, qd_f)
        return M, h

    def mass_matrix(self, q, t=0.0):
        if self.frame_at_rest:
            if self._M_rest is None:    # frame at rest: M = m_ff, constant (thesis eq. 2.69)
                _, A, *_ = self._frame(q, None, t)
                self._M_rest = self._dynamics(A, q[self._f], np.zeros(3), np.zeros(self.n_modes))[0][6:, 6:]
            return self._M_rest.copy()
        return self.mass_and_h(q, np.zeros(self.nu), t)[0]

    def h(self, q, u, t=0.0):
        if self.frame_at_rest:    # Q_v = 0 with the frame at rest (eq. 4.2)
            return -self._elastic(q[self._f], u[self._fu]) if self.n_modes else np.zeros(self.nu)
        return self.mass_and_h(q, u, t)[1]

    def _generalized_momentum(self, q, u, t):
        """(R, A, ū̇ = (Ṙ, ω̄, q̇_f), M̄ ū̇): the full velocities and their momenta."""
        R, A, v, w, *_ = self._frame(q, u, t)
        uf = np.concatenate((v, w, u[self._fu]))
        return R, A, uf, self._dynamics(A, q[self._f], w, uf[6:])[0] @ uf

    def kinetic_energy(self, q, u, t=0.0):
        """T = ½ ū̇ᵀ M̄ ū̇ over the full frame and elastic velocities [J] (thesis eq. 2.43);
        with the frame at rest ½ q̇_fᵀ m_ff q̇_f."""
        if self.frame_at_rest:
            if self._M_rest is None:
                self.mass_matrix(q, t)
            return 0.5 * u @ (self._M_rest @ u)
        _, _, uf, Mu = self._generalized_momentum(q, u, t)
        return 0.5 * uf @ Mu

    def linear_momentum(self, q, u, t=0.0):
        """Σ m_j ṙ_j [kg m/s]: the first three rows of M̄ ū̇."""
        return self._generalized_momentum(q, u, t)[3][:3]

    def angular_momentum(self, q, u, t=0.0):
        """Σ m_j r_j × ṙ_j about the inertial origin [kg m²/s] = R × p + A (M̄ ū̇)_θ."""
        R, A, _, Mu = self._generalized_momentum(q, u, t)
        return np.cross(R, Mu[:3]) + A @ Mu[3:6]

    def qdot(self, q, u):
        if self.motion is not None:
            return u.copy()
        out = np.empty(self.nq)
        out[:3] = u[:3]
        out[self._r] = self.param.qdot(q[self._r], u[3:6])
        out[self._f] = u[self._fu]
        return out

    def increment(self, q, du):
        if self.motion is not None:
            return q + du
        out = np.empty(self.nq)
        out[:3] = q[:3] + du[:3]
        out[self._r] = self.param.increment(q[self._r], du[3:6])
        out[self._f] = q[self._f] + du[self._fu]
        return out

    def normalize(self, q):
        if self.free_quaternion:
            normalize_quaternion(q, 3)
        elif self.param is not None:
            self.param.normalize(q[self._r])

    @property
    def free_quaternion(self) -> bool:
        """True for a free frame with the quaternion parametrization: the layout of the
        numba kernels (q = (R, p, q_f), u = (Ṙ, ω̄, q̇_f))."""
        return self.param is not None and self.param.name == "quaternion"

    def increment_into(self, q, du, out):
        if self.motion is not None:
            np.add(q, du, out=out)
        elif self.free_quaternion:
            free_quat_increment(q, du, out)
        else:
            super().increment_into(q, du, out)

    def workspace(self):
        """(A (3, 3), G (3, 3, n_f), M̄ (6+n_f, 6+n_f), Q̄ (6+n_f,), M (nu, nu)): scratch of
        the kernels (orientation, shape-integral contraction, full-coordinate terms of a
        prescribed frame, the mass block :meth:`h_into` does not return)."""
        n = 6 + self.n_modes
        return (np.empty((3, 3)), np.empty((3, 3, self.n_modes)), np.empty((n, n)), np.empty(n),
                np.empty((self.nu, self.nu)))

    def h_into(self, q, u, t, h, work=None):
        if work is None:
            work = self.workspace()
        self.mass_and_h_into(q, u, t, work[4], h, work)

    def add_point_load_into(self, q, frame, times, values, t, body_axes, h, work=None):
        if not self.free_quaternion:
            super().add_point_load_into(q, frame, times, values, t, body_axes, h, work)
            return
        add_free_point_force(q, frame.u0, frame.phi, times, values, t, body_axes,
                             np.empty((3, 3)) if work is None else work[0], h)

    # --- frames -----------------------------------------------------------------------
    def frame_at(self, position, orientation=None, name=None) -> Frame:
        """A frame fixed to the body frame at ū0 = ``position`` [m] (does not follow the
        elastic deformation)."""
        return Frame(self, position, None, orientation, name)

    @property
    def origin(self) -> Frame:
        """The origin of the body frame, R."""
        return self.frame_at((0.0, 0.0, 0.0), name="origin")
