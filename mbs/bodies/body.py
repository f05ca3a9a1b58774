"""What every body offers the System, and frames: points with an orientation on a body.

A body owns ``nq`` position coordinates q and ``nu`` velocities u (q̇ = Y(q) u, thesis
eq. 3.1a) and supplies, at (q, u, t): the mass matrix M (nu, nu), the smooth forces
h = Q_v − K q − D u (nu,), q̇, the exact position update q ⊕ Δu, energies and
momenta. The System gives each body its slices of the global q and u when it is added.

A :class:`Frame` is a point of a body with an orientation. On a floating-frame body its
body-frame position is ū = ū0 + Φ q_f (thesis eq. 2.23): ``phi`` holds the point's
mode-shape rows (3, n_f) — those of a node, or zeros for a point fixed to the body frame.
It supplies position, velocity, orientation, angular velocity, the Jacobians J_T, J_R
(thesis eq. 2.70, 2.72) and the velocity-product accelerations J̇_T u, J̇_R u.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError


class Body:
    """Base of all bodies: a name, sizes, initial state and its rows of q and u (``q_slice``,
    ``u_slice``) in the System that placed it last (:meth:`mbs.system.System.layout`)."""

    nq: int
    nu: int
    constant_mass = False   # True when M does not depend on q or t (Moreau then factors once)
    additive = False        # True when q ⊕ Δu = q + Δu (no rotation coordinates)
    translation_only = False  # True when q = u = the position and velocity of every frame's
                              # origin offset (a point mass: J_T = 1, J_R = 0, constant A)

    def __init__(self, name: str):
        self.name = name
        self.q_slice: slice | None = None
        self.u_slice: slice | None = None

    # interface every body implements -------------------------------------------------
    def mass_matrix(self, q, t=0.0) -> np.ndarray:
        raise NotImplementedError

    def h(self, q, u, t=0.0) -> np.ndarray:
        raise NotImplementedError

    def mass_and_h(self, q, u, t=0.0):
        """(M, h) at one state; bodies override it to share work between the two."""
        return self.mass_matrix(q, t), self.h(q, u, t)

    def qdot(self, q, u) -> np.ndarray:
        raise NotImplementedError

    def increment(self, q, du) -> np.ndarray:
        """q ⊕ Δu: the position reached from q by the velocity-space increment Δu (nu,)."""
        raise NotImplementedError

    def normalize(self, q) -> None:
        """Project q onto its constraint manifold in place (unit quaternions)."""

    # in-place versions for the step (mbs.run.body_stage): q, u, M, h, out are the body's
    # blocks of the caller's arrays; ``work`` is what :meth:`workspace` returned. These
    # generic versions copy from the allocating methods; bodies override them with kernels.
    def workspace(self):
        """Scratch arrays of the in-place methods (None when they need none)."""
        return None

    def mass_and_h_into(self, q, u, t, M, h, work=None) -> None:
        """Write M (nu, nu) and h (nu,) at (q, u, t) into ``M`` and ``h``."""
        M[...], h[...] = self.mass_and_h(q, u, t)

    def h_into(self, q, u, t, h, work=None) -> None:
        """Write h (nu,) at (q, u, t) into ``h``."""
        h[...] = self.h(q, u, t)

    def increment_into(self, q, du, out) -> None:
        """Write q ⊕ Δu into ``out`` (nq,); ``out`` may be ``q``."""
        out[...] = self.increment(q, du)

    def add_point_load_into(self, q, frame, times, values, t, body_axes, h, work=None) -> None:
        """h += J_Tᵀ F (thesis eq. 2.76) for the force F [N] of the step table (``times``
        (n_t,) [s], ``values`` (n_t, 3)) holding at t (none before times[0]) at
        ``frame``'s point; F in the frame's axes (inertial force A F) when ``body_axes``."""
        r = int(np.searchsorted(times, t, side="right")) - 1
        if r < 0:
            return
        F = values[r]
        if body_axes:
            F = frame.orientation(q, t) @ F
        h += frame.J_T(q, t).T @ F

    def kinetic_energy(self, q, u, t=0.0) -> float:
        return 0.5 * u @ self.mass_matrix(q, t) @ u

    def elastic_energy(self, q) -> float:
        return 0.0

    def bounding_sphere(self, q, t=0.0):
        """(centre (3,) [m], radius [m]) of a sphere holding every point of the body at
        (q, t), or None when the body cannot say (then its contacts are never pruned)."""
        return None

    def stiffness_tangent(self) -> np.ndarray | None:
        """Constant −∂h/∂q in velocity-increment coordinates (nu, nu), or None."""
        return None

    def damping_tangent(self) -> np.ndarray | None:
        """Constant −∂h/∂u (nu, nu), or None."""
        return None

    #: True when the body adds tangents that change with (t, q, u) (:meth:`add_tangents`)
    varying_tangents = False

    #: True when the body's points move at u = 0 (a prescribed frame motion that is not at
    #: rest): a constraint on them depends on t explicitly (∂g/∂t ≠ 0)
    rheonomic = False

    def add_tangents(self, t, q, u, K, D) -> None:
        """Add the varying −∂h/∂q and −∂h/∂u at the body's (q, u, t) into its blocks ``K``,
        ``D`` (nu, nu) (nothing unless :attr:`varying_tangents`)."""

    def linear_forces(self):
        """(K, D) when h = −K q − D u with constant K (nu, nu) and D (nu, nu) or None
        (undamped) and q ⊕ Δu = q + Δu — the body stage then evaluates h of all such
        bodies in one kernel (:func:`mbs.bodies._kernels.linear_bodies_h`) — else None."""
        return None

    def com_frame(self) -> "Frame":
        """The centre of mass as a frame: gravity acts there with the whole mass."""
        raise NotImplementedError

    def point_kinematics(self, q, frame, t=0.0):
        """(r (3,) [m], A (3, 3), J_T (3, nu), J_R (3, nu)) of ``frame`` at (q, t): its
        position, orientation and Jacobians (thesis eq. 2.70, 2.72), the values of
        :meth:`Frame.position`, :meth:`Frame.orientation`, :meth:`Frame.J_T` and
        :meth:`Frame.J_R`. A body that builds them from one evaluation of its frame
        overrides this (:class:`mbs.bodies.floating_frame.FloatingFrameBody`)."""
        return (self.point_position(q, frame, t), self.orientation(q, t) @ frame.A_rel,
                self.point_J_T(q, frame, t), self.J_R(q, t))

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r}, nq={self.nq}, nu={self.nu})"


class Frame:
    """A point of ``body`` with an orientation (see module docstring).

    Parameters
    ----------
    body : Body or None
        None for a frame fixed in the inertial frame (see :func:`ground_frame`).
    u0 : (3,) [m]
        Undeformed position in the body frame (inertial position for ground frames).
    phi : (3, n_f) or None
        Mode-shape rows of the point; None or zeros for a point fixed to the body frame.
    orientation : (3, 3) or None
        Constant rotation of the frame relative to the body frame (identity if None).
    """

    def __init__(self, body, u0, phi=None, orientation=None, name=None):
        self.body = body
        self.u0 = np.asarray(u0, dtype=float).reshape(3)
        n_f = getattr(body, "n_modes", 0)
        self.phi = np.zeros((3, n_f)) if phi is None else np.asarray(phi, dtype=float).reshape(3, n_f)
        self.A_rel = np.eye(3) if orientation is None else np.asarray(orientation, dtype=float)
        self.name = name
        self.node_index = None      # the FE node a flexible body's node frame sits on

    @property
    def is_ground(self) -> bool:
        return self.body is None

    def position(self, q, t=0.0):
        """Inertial position r (3,) [m]."""
        return self.u0.copy() if self.body is None else self.body.point_position(q, self, t)

    def velocity(self, q, u, t=0.0):
        """Inertial velocity ṙ (3,) [m/s]."""
        return np.zeros(3) if self.body is None else self.body.point_velocity(q, u, self, t)

    def orientation(self, q, t=0.0):
        """Rotation matrix of the frame (3, 3): body orientation times the constant A_rel."""
        return self.A_rel.copy() if self.body is None else self.body.orientation(q, t) @ self.A_rel

    def angular_velocity(self, q, u, t=0.0):
        """Inertial angular velocity ω (3,) [rad/s] (points share their body's rotation)."""
        return np.zeros(3) if self.body is None else self.body.angular_velocity(q, u, t)

    def elastic_displacement(self, q):
        """ū_f = Φ q_f (3,) [m]: the point's elastic displacement in body-frame components
        (thesis eq. 2.23); zero for points fixed to the frame and for rigid bodies."""
        if self.body is None or not self.phi.size:
            return np.zeros(3)
        return self.phi @ self.body.elastic_coordinates(q)

    def J_T(self, q, t=0.0):
        """∂ṙ/∂u (3, nu) (thesis eq. 2.70)."""
        return self._owner().point_J_T(q, self, t)

    def J_R(self, q, t=0.0):
        """∂ω/∂u (3, nu) (thesis eq. 2.72)."""
        return self._owner().J_R(q, t)

    def kinematics(self, q, t=0.0):
        """(r, A, J_T, J_R) of :meth:`Body.point_kinematics` for the body's own q; the
        Jacobians None for a ground frame."""
        if self.body is None:
            return self.u0.copy(), self.A_rel.copy(), None, None
        return self.body.point_kinematics(q, self, t)

    def _owner(self):
        if self.body is None:
            raise ModelError(f"{self!r} is fixed in the inertial frame: it has no Jacobian")
        return self.body

    def bias_T(self, q, u, t=0.0):
        """J̇_T u (3,) [m/s²]: the acceleration of the point at u̇ = 0."""
        return np.zeros(3) if self.body is None else self.body.point_bias_T(q, u, self, t)

    def bias_R(self, q, u, t=0.0):
        """J̇_R u (3,) [rad/s²]: the angular acceleration at u̇ = 0."""
        return np.zeros(3) if self.body is None else self.body.bias_R(q, u, t)

    def __repr__(self):
        owner = "ground" if self.body is None else self.body.name
        return f"Frame({self.name or ''!s} on {owner}, u0={self.u0.tolist()})"


def ground_frame(position=(0.0, 0.0, 0.0), orientation=None, name="ground") -> Frame:
    """A frame fixed in the inertial frame at ``position`` [m]."""
    return Frame(None, position, orientation=orientation, name=name)


def place_bodies(layout) -> None:
    """Give each body of ``layout`` ((body, q_slice, u_slice), …) its rows of q and u."""
    for body, q_slice, u_slice in layout:
        body.q_slice, body.u_slice = q_slice, u_slice
