"""Ideal joints between two frames: fixed, spherical, revolute, prismatic.

A :class:`Joint` is a bilateral constraint g(q, t) = 0 between ``frame1`` and ``frame2``
(thesis eq. 2.73–2.75 with the frame Jacobians of eq. 2.70, 2.72); its reactions enter
the equations of motion as M u̇ = h + C_qᵀ λ (the System's sign, see
:meth:`mbs.system.System.accelerations`).

Geometry. Let r_i (3,) [m] be the inertial positions of the frames, A_i (3, 3) their
orientations and d = r2 − r1. The joint axis a (revolute, prismatic) is a unit vector
given in frame1's axes; b, c complete it to a right-handed orthonormal triad (a, b, c)
of constant local vectors (for the fixed joint (a, b, c) are frame1's x, y, z axes).
The same local vectors seen from each frame give inertial directions
a1 = A1 a, b1 = A1 b, ... and a2 = A2 a, b2 = A2 b, c2 = A2 c. Every equation vanishes
in the reference configuration r1 = r2, A1 = A2, and has unit-length gradient rows
there (a well-conditioned C_q):

* spherical (3): d = r2 − r1                         (inertial components)
* revolute  (5): d;  a1·b2, a1·c2                   (a1 ⟂ b2, c2 ⇔ a1 ∥ a2)
* prismatic (5): b1·d, c1·d;  a1·b2, a1·c2, b1·c2   (no offset across the axis,
                                                     no relative rotation)
* fixed     (6): d;  a1·b2, a1·c2, b1·c2            (x1·y2, x1·z2, y1·z2)

in this order. Like every set of three orientation conditions, the dot products also
vanish at isolated far-away orientations (relative half turns); the joint is meant to
be assembled near A1 = A2 and held there.

Kinematics. With frame velocities v_i = J_Ti u_i + v_i⁰, angular velocities
ω_i = J_Ri u_i + ω_i⁰ (v_i⁰, ω_i⁰: the parts due to a prescribed body-frame motion at
u = 0) and accelerations a_i = J_Ti u̇_i + a_i⁰, α_i = J_Ri u̇_i + α_i⁰ (a_i⁰, α_i⁰
= ``Frame.bias_T``, ``Frame.bias_R``: J̇u plus any prescribed-motion terms), every
equation's rate is linear in the frame velocities, ġ = G (v1, ω1, v2, ω2) with
G (n_c, 12):

* point d:            ḋ = v2 − v1
* dot e·f (e fixed in frame i, f in frame j):
                      d/dt (e·f) = (e × f)·(ω_i − ω_j)
* offset e·d (e fixed in frame1):
                      d/dt (e·d) = e·(v2 − v1) + (e × d)·ω1

so that C_q = Σ_i (G_Ti J_Ti + G_Ri J_Ri), g_t = G (v1⁰, ω1⁰, v2⁰, ω2⁰), and
g̈ = C_q u̇ + γ with γ = G (a1⁰, α1⁰, a2⁰, α2⁰) + Ġ (v1, ω1, v2, ω2):

* point:   Ġ (…) = 0
* dot:     Ġ (…) = (ė × f + e × ḟ)·(ω_i − ω_j),        ė = ω_i × e, ḟ = ω_j × f
* offset:  Ġ (…) = 2 ė·(v2 − v1) + (ω1 × ė)·d,          ė = ω1 × e

A ground frame (``frame.body is None``) has no columns; two frames on one body add
their columns; a point mass has J_R = 0, so orientation equations see only the other
frame.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError
from ffrmbs.vec3 import cross3
from ffrmbs.registry import Registry

from mbs.bodies.body import Frame
from mbs.links.link import Constraint, body_q, body_u

# JOINTS: kind -> (point equations d?, offset directions (rows of the triad), dot-product
# pairs (row of e fixed in frame1, row of f fixed in frame2)); a new kind is one line here
JOINTS = Registry("joint kind")
JOINTS.register("fixed", (True, (), ((0, 1), (0, 2), (1, 2))))
JOINTS.register("spherical", (True, (), ()))
JOINTS.register("revolute", (True, (), ((0, 1), (0, 2))))
JOINTS.register("prismatic", (False, (1, 2), ((0, 1), (0, 2), (1, 2))))
AXIS_KINDS = ("revolute", "prismatic")      # the kinds that take an axis


def _cross_rows(a, b):
    """a × b row by row, ``a`` and ``b`` (k, 3) or (3,): np.cross(a, b) to the bit,
    without its overhead on such small arrays (:func:`ffrmbs.vec3.cross3`)."""
    return cross3(np.transpose(a), np.transpose(b)).T


def _triad(axis):
    """Right-handed orthonormal (a, b, c) (3, 3) rows with a = axis/|axis| and b ⟂ a
    built from the coordinate axis least aligned with a."""
    a = np.asarray(axis, dtype=float).reshape(3)
    norm = np.sqrt(a @ a)
    if not (np.isfinite(norm) and norm > 0.0):
        raise ModelError(f"joint axis {a.tolist()} is zero or not finite: give a nonzero direction")
    a = a / norm
    b = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    b /= np.sqrt(b @ b)
    return np.array([a, b, np.cross(a, b)])


class Joint(Constraint):
    """An ideal joint between ``frame1`` and ``frame2`` (see module docstring).

    Parameters
    ----------
    frame1, frame2 : Frame
        The joined frames; ``frame.body is None`` for an inertial (ground) frame.
    kind : str
        "fixed", "spherical", "revolute" or "prismatic".
    axis : (3,) or None
        Joint axis in frame1's axes (any length, normalized here); required for
        revolute and prismatic joints, not accepted for the others.

    Attributes
    ----------
    n_c : int
        Number of equations (3, 5, 5 or 6).
    triad : (3, 3)
        Rows a, b, c (local, unit) of the module docstring; frame1's x, y, z axes for
        the joints without an axis.
    """

    def __init__(self, frame1, frame2, kind, axis=None):
        equations = JOINTS[kind]
        for f in (frame1, frame2):
            if not isinstance(f, Frame):
                raise ModelError(f"a {kind} joint joins two frames, got {f!r}")
        if frame1 is frame2:
            raise ModelError(f"a {kind} joint needs two different frames, got {frame1!r} twice")
        if frame1.body is None and frame2.body is None:
            raise ModelError(f"a {kind} joint between two ground frames constrains nothing")
        needs_axis = kind in AXIS_KINDS
        if needs_axis and axis is None:
            raise ModelError(f"a {kind} joint needs an axis (3 components in frame1's axes)")
        if not needs_axis and axis is not None:
            raise ModelError(f"a {kind} joint takes no axis, got {axis!r}")
        self.frame1, self.frame2, self.kind = frame1, frame2, kind
        self.triad = np.eye(3) if axis is None else _triad(axis)
        self._point, offsets, pairs = equations
        self._offsets = self.triad[list(offsets)]
        self._dot_e = self.triad[[i for i, _ in pairs]]
        self._dot_f = self.triad[[j for _, j in pairs]]
        self.n_c = 3 * self._point + len(offsets) + len(pairs)
        self._rheonomic = any(f.body is not None and f.body.rheonomic for f in (frame1, frame2))   # g_t ≠ 0

    # --- constructors -----------------------------------------------------------------
    @classmethod
    def fixed(cls, frame1, frame2) -> "Joint":
        """Weld ``frame2`` to ``frame1``: same point, same orientation (6 equations)."""
        return cls(frame1, frame2, "fixed")

    @classmethod
    def spherical(cls, frame1, frame2) -> "Joint":
        """Ball joint: same point, free rotation (3 equations)."""
        return cls(frame1, frame2, "spherical")

    @classmethod
    def revolute(cls, frame1, frame2, axis) -> "Joint":
        """Hinge about ``axis`` (in frame1's axes): same point, rotation only about
        the axis (5 equations)."""
        return cls(frame1, frame2, "revolute", axis)

    @classmethod
    def prismatic(cls, frame1, frame2, axis) -> "Joint":
        """Slider along ``axis`` (in frame1's axes): same orientation, relative
        translation only along the axis (5 equations)."""
        return cls(frame1, frame2, "prismatic", axis)

    # --- Constraint interface ------------------------------------------------------------
    def bodies(self):
        """The distinct bodies of the two frames (ground frames have none)."""
        out = []
        for f in (self.frame1, self.frame2):
            if f.body is not None and f.body not in out:
                out.append(f.body)
        return out

    def _pose(self, t, q):
        """(r1, r2, E, F, O): positions (3,) [m] and the inertial directions (k, 3) of the
        dot-product vectors e (frame1), f (frame2) and of the offset directions (frame1)."""
        f1, f2 = self.frame1, self.frame2
        q1, q2 = body_q(f1, q), body_q(f2, q)
        A1, A2 = f1.orientation(q1, t), f2.orientation(q2, t)
        return self._pose_of(f1.position(q1, t), A1, f2.position(q2, t), A2)

    def _pose_of(self, r1, A1, r2, A2):
        """:meth:`_pose` from the frames' positions and orientations."""
        return r1, r2, self._dot_e @ A1.T, self._dot_f @ A2.T, self._offsets @ A1.T

    def residual(self, t, q):
        """g(q, t) (n_c,) [m for d and offsets, 1 for dot products]."""
        return self._residual_of(self._pose(t, q))

    def _residual_of(self, pose):
        r1, r2, E, F, O = pose
        d = r2 - r1
        return np.concatenate((d if self._point else np.zeros(0), O @ d, np.sum(E * F, axis=1)))

    def _coefficients(self, t, q):
        """G (n_c, 12) with ġ = G (v1, ω1, v2, ω2) (module docstring), plus the pose."""
        pose = self._pose(t, q)
        return self._coefficients_of(pose), pose

    def _coefficients_of(self, pose):
        """G of :meth:`_coefficients` at ``pose``."""
        r1, r2, E, F, O = pose
        d = r2 - r1
        G = np.zeros((self.n_c, 12))
        i = 0
        if self._point:
            G[:3, 0:3] = -np.eye(3)
            G[:3, 6:9] = np.eye(3)
            i = 3
        k = len(O)
        G[i:i + k, 0:3] = -O
        G[i:i + k, 6:9] = O
        G[i:i + k, 3:6] = _cross_rows(O, d)
        n = _cross_rows(E, F)
        G[i + k:, 3:6] = n
        G[i + k:, 9:12] = -n
        return G

    def jacobian(self, t, q, C_q):
        """Write C_q = Σ_i (G_Ti J_Ti + G_Ri J_Ri) into the zeroed rows (n_c, nu)."""
        self._jacobian_into(t, q, C_q)

    def residual_and_jacobian(self, t, q, C_q):
        """g(q, t) (n_c,) of :meth:`residual`, and C_q written as by :meth:`jacobian`."""
        return self._residual_of(self._jacobian_into(t, q, C_q))

    def _jacobian_into(self, t, q, C_q):
        """:meth:`jacobian`, each frame's position, orientation and Jacobians from one
        evaluation of its body (:meth:`mbs.bodies.body.Frame.kinematics`); returns the
        pose."""
        f1, f2 = self.frame1, self.frame2
        k1, k2 = f1.kinematics(body_q(f1, q), t), f2.kinematics(body_q(f2, q), t)
        pose = self._pose_of(k1[0], k1[1], k2[0], k2[1])
        G = self._coefficients_of(pose)
        for f, (_, _, J_T, J_R), cols in ((f1, k1, slice(0, 6)), (f2, k2, slice(6, 12))):
            if f.body is not None:
                C_q[:, f.body.u_slice] += G[:, cols] @ np.vstack((J_T, J_R))
        return pose

    def _frame_rates(self, t, q, u):
        """(v1, ω1, v2, ω2) (12,); at u = None the prescribed-motion part (u = 0)."""
        out = []
        for f in (self.frame1, self.frame2):
            qb, ub = body_q(f, q), None
            if f.body is not None:
                ub = np.zeros(f.body.nu) if u is None else body_u(f, u)
            out += [f.velocity(qb, ub, t), f.angular_velocity(qb, ub, t)]
        return np.concatenate(out)

    def velocity_term(self, t, q):
        """g_t = G (v1⁰, ω1⁰, v2⁰, ω2⁰) (n_c,): nonzero only for frames on bodies with a
        prescribed frame motion (zeros, without evaluating G, when neither body is
        :attr:`~mbs.bodies.body.Body.rheonomic`)."""
        if not self._rheonomic:
            return np.zeros(self.n_c)
        G, _ = self._coefficients(t, q)
        return G @ self._frame_rates(t, q, None)

    def bias(self, t, q, u):
        """γ = G (a1⁰, α1⁰, a2⁰, α2⁰) + Ġ (v1, ω1, v2, ω2) (n_c,) [m/s² or 1/s²] with
        g̈ = C_q u̇ + γ (module docstring)."""
        G, (r1, r2, E, F, O) = self._coefficients(t, q)
        rates = self._frame_rates(t, q, u)
        v1, w1, v2, w2 = rates[0:3], rates[3:6], rates[6:9], rates[9:12]
        acc = []
        for f in (self.frame1, self.frame2):
            qb, ub = body_q(f, q), body_u(f, u)
            acc += [f.bias_T(qb, ub, t), f.bias_R(qb, ub, t)]
        gamma = G @ np.concatenate(acc)
        d, dd = r2 - r1, v2 - v1
        i = 3 * self._point
        k = len(O)
        Od = _cross_rows(w1, O)
        gamma[i:i + k] += 2.0 * Od @ dd + _cross_rows(w1, Od) @ d
        Ed, Fd = _cross_rows(w1, E), _cross_rows(w2, F)
        gamma[i + k:] += (_cross_rows(Ed, F) + _cross_rows(E, Fd)) @ (w1 - w2)
        return gamma

    def reaction(self, t, q, lam):
        """(F2, τ2): the force [N] and the torque about frame2's point [N m], inertial
        components, that the joint exerts on frame2's body, F2 = G_T2ᵀ λ, τ2 = G_R2ᵀ λ
        (so that C_q ᵀλ restricted to that body is J_T2ᵀ F2 + J_R2ᵀ τ2, thesis eq. 2.76).
        Frame1's body receives −F2 at r1 and the torque G_R1ᵀ λ, which balances:
        G_R1ᵀ λ = −τ2 − (r2 − r1) × F2 wherever g = 0."""
        G, _ = self._coefficients(t, q)
        lam = np.asarray(lam, dtype=float).reshape(self.n_c)
        return G[:, 6:9].T @ lam, G[:, 9:12].T @ lam

    def __repr__(self):
        return f"Joint({self.kind}, {self.frame1!r}, {self.frame2!r})"
