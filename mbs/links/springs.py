"""A linear spring-damper between the points of two frames.

With d = r2 − r1 the vector from frame 1's point to frame 2's, l = |d| the length,
e = d / l and l̇ = eᵀ ḋ, the spring pulls with the tension

    f = k (l − l0) + c l̇      [N],

i.e. the force f e acts on frame 1 and −f e on frame 2; through the Jacobians (thesis
eq. 2.76) Q = J_T1ᵀ f e − J_T2ᵀ f e = −J_relᵀ f e with J_rel = J_T2 − J_T1 (ḋ = J_rel u).
The stored energy is V = ½ k (l − l0)².
"""

from __future__ import annotations

import math

import numpy as np

from ffrmbs.errors import ModelError

from mbs.bodies.body import Frame
from mbs.links.link import ForceElement, add_point_force, body_q, body_u

COINCIDENT_RTOL = 1e-12   # points closer than this times their distance from the origin coincide


def _check_nonnegative(value, what) -> float:
    value = float(value)
    if not (np.isfinite(value) and value >= 0.0):
        raise ModelError(f"SpringDamper: {what} must be finite and >= 0, got {value!r}")
    return value


class SpringDamper(ForceElement):

    """A linear spring-damper along the line between two frames' points (module docstring).

    Parameters
    ----------
    frame1, frame2 : Frame
        The end points; either may be fixed in the inertial frame (``frame.body is None``),
        not both.
    stiffness : float [N/m]
        k >= 0.
    damping : float [N s/m]
        c >= 0.
    free_length : float [m], keyword-only and required
        l0 >= 0. There is no default: a forgotten free length (0, or the initial distance)
        would silently give another model.

    Notes
    -----
    Where the points coincide the direction e is undefined and a :class:`ModelError` is
    raised — except for an undamped spring of zero free length, whose force k d needs no
    direction.
    """

    has_tangents = True
    applied = False             # the spring's force is −∂V/∂q, the damper's dissipates

    def __init__(self, frame1: Frame, frame2: Frame, stiffness, damping=0.0, *, free_length):
        if frame1.body is None and frame2.body is None:
            raise ModelError("SpringDamper: both frames are fixed in the inertial frame")
        self.frame1, self.frame2 = frame1, frame2
        self.stiffness = _check_nonnegative(stiffness, "stiffness")
        self.damping = _check_nonnegative(damping, "damping")
        self.free_length = _check_nonnegative(free_length, "free_length")

    def bodies(self):
        return [f.body for f in (self.frame1, self.frame2) if f.body is not None]

    def _geometry(self, t, q):
        """(d (3,) [m], l [m], e (3,)); e = 0 where the points coincide and no direction
        is needed (undamped, l0 = 0)."""
        r1 = self.frame1.position(body_q(self.frame1, q), t)
        r2 = self.frame2.position(body_q(self.frame2, q), t)
        d = r2 - r1
        l = float(np.sqrt(d @ d))
        if not math.isfinite(l) or l > COINCIDENT_RTOL * max(np.abs(r1).max(), np.abs(r2).max(), self.free_length):
            # an overflowed state is not coinciding points: its NaN forces reach the state,
            # where the integrator's finiteness check stops the run
            return d, l, d / l
        if self.free_length == 0.0 and self.damping == 0.0:
            return d, l, np.zeros(3)
        raise ModelError(f"SpringDamper between {self.frame1!r} and {self.frame2!r}: the points "
                         f"coincide at t = {t} s (l = {l} m), so the spring's direction is "
                         "undefined")

    def _rate(self, t, q, u):
        """ḋ = ṙ2 − ṙ1 (3,) [m/s]."""
        v = [f.velocity(body_q(f, q), body_u(f, u), t) for f in (self.frame1, self.frame2)]
        return v[1] - v[0]

    def length(self, t, q) -> float:
        """The current length l [m]."""
        return self._geometry(t, q)[1]

    def force(self, t, q, u) -> np.ndarray:
        """f e (3,) [N]: the force on frame 1 (frame 2 gets −f e); f = k (l − l0) + c l̇."""
        d, l, e = self._geometry(t, q)
        ldot = e @ self._rate(t, q, u)
        return self.stiffness * (d - self.free_length * e) + self.damping * ldot * e

    def add_forces(self, t, q, u, h):
        F = self.force(t, q, u)
        add_point_force(self.frame1, q, t, F, h)
        add_point_force(self.frame2, q, t, -F, h)

    def potential_energy(self, t, q) -> float:
        """V = ½ k (l − l0)² [J]."""
        return 0.5 * self.stiffness * (self.length(t, q) - self.free_length) ** 2

    @property
    def dissipative(self) -> bool:
        return self.damping > 0.0

    def dissipation(self, t, q, u) -> float:
        """The damper's power c l̇² [W] (l̇ = eᵀ ḋ)."""
        e = self._geometry(t, q)[2]
        return self.damping * float(e @ self._rate(t, q, u)) ** 2

    def add_tangents(self, t, q, u, K, D):
        """K += J_relᵀ K_d J_rel and D += J_relᵀ (c e eᵀ) J_rel with the exact derivative
        of the force f e with respect to d,

            K_d = k e eᵀ + (f / l)(1 − e eᵀ) + (c / l) e ḋᵀ (1 − e eᵀ).

        The terms of ∂J_rel/∂q (rotational geometric stiffness of points off a body's
        reference point, and the change of ḋ = J_rel u with q) are neglected; for point
        masses the tangents are exact."""
        d, l, e = self._geometry(t, q)
        ddot = self._rate(t, q, u)
        k, c, l0 = self.stiffness, self.damping, self.free_length
        if e.any():
            P = np.eye(3) - np.outer(e, e)
            f = k * (l - l0) + c * (e @ ddot)
            K_d = k * np.outer(e, e) + (f / l) * P + (c / l) * np.outer(e, ddot @ P)
        else:   # coincident points of an undamped zero-length spring: force k d
            K_d = k * np.eye(3)
        cols, J = self._relative_jacobian(t, q)
        idx = np.ix_(cols, cols)
        K[idx] += J.T @ K_d @ J
        D[idx] += c * np.outer(J.T @ e, J.T @ e)

    def _relative_jacobian(self, t, q):
        """(columns, J_rel): the global velocity indices of the bodies involved and
        ∂ḋ/∂u restricted to them (3, n)."""
        cols, blocks = [], []
        for sign, frame in ((-1.0, self.frame1), (1.0, self.frame2)):
            if frame.body is not None:
                cols.append(np.arange(frame.body.u_slice.start, frame.body.u_slice.stop))
                blocks.append(sign * frame.J_T(body_q(frame, q), t))
        cols_all = np.concatenate(cols)
        unique, where = np.unique(cols_all, return_inverse=True)
        J = np.zeros((3, unique.size))
        np.add.at(J.T, where, np.concatenate(blocks, axis=1).T)
        return unique, J
