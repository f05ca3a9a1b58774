"""The two kinds of link a System holds: force elements and bilateral constraints.

Both act on bodies through the Jacobians of frames (thesis eq. 2.76: Q = J_Tᵀ F + J_Rᵀ τ).
They see the System's global arrays: q (nq,), u (nu,), and write into global arrays;
a frame's body owns ``frame.body.q_slice`` and ``frame.body.u_slice`` of them
(``frame.body is None`` for frames fixed in the inertial frame).

* :class:`ForceElement` adds its generalized forces into h.
* :class:`Constraint` holds ``n_c`` scalar conditions g(q, t) = 0 with
  ġ = C_q u + g_t and g̈ = C_q u̇ + γ(q, u, t); its reaction forces are W λ with
  W = C_qᵀ (thesis eq. 2.73, 2.74).
"""

from __future__ import annotations

import numpy as np


def body_q(frame, q):
    """The slice of the global q that belongs to ``frame``'s body (None for ground frames)."""
    return None if frame.body is None else q[frame.body.q_slice]


def body_u(frame, u):
    """The slice of the global u that belongs to ``frame``'s body (None for ground frames)."""
    return None if frame.body is None else u[frame.body.u_slice]


def add_point_force(frame, q, t, force, h):
    """h[body] += J_Tᵀ F for an inertial force F (3,) [N] at ``frame``'s point."""
    if frame.body is not None:
        h[frame.body.u_slice] += frame.J_T(body_q(frame, q), t).T @ force


def add_torque(frame, q, t, torque, h):
    """h[body] += J_Rᵀ τ for an inertial torque τ (3,) [N m] on ``frame``'s body."""
    if frame.body is not None:
        h[frame.body.u_slice] += frame.J_R(body_q(frame, q), t).T @ torque


class ForceElement:
    """A link that contributes smooth generalized forces; ``has_tangents`` is True for
    elements that override :meth:`add_tangents`. For the energy balance of a run
    (:mod:`mbs.run.step_work`): ``applied`` is True for an applied load (its force stores no
    energy, its work is the loads' work), False for an element whose force is −∂V/∂q of
    its :meth:`potential_energy` plus its damping; ``dissipative`` is True when
    :meth:`dissipation` may be non-zero."""

    has_tangents = False
    applied = True
    dissipative = False

    def bodies(self):
        """The bodies this element acts on (the System checks they were added)."""
        return []

    def add_forces(self, t, q, u, h) -> None:
        """Add the generalized forces at (t, q, u) into the global h (nu,) in place."""
        raise NotImplementedError

    def potential_energy(self, t, q) -> float:
        """Stored energy [J] (springs, gravity); 0 for non-conservative elements."""
        return 0.0

    def dissipation(self, t, q, u) -> float:
        """The power [W] the element's damping takes out at (t, q, u) (>= 0); 0 by default."""
        return 0.0

    def step_loads(self):
        """The element as nodal step loads (:class:`mbs.modal.StepLoads`) on its one body,
        or None (the default: not expressible, e.g. a spring or a callable load)."""
        return None

    def breakpoints(self):
        """Times [s] where the element's force jumps (step loads); the integrators stop
        just before each and restart there (``System.simulate``)."""
        return ()

    def point_load(self):
        """The element as one point force given by a step table, or None (the default):
        ``(frame, times (n_t,) [s], values (n_t, 3) [N], body_axes)`` with the force
        values[r] from times[r] on (none before times[0]; −inf for "always"), in the
        frame's axes when ``body_axes``. The body stage (:mod:`mbs.run.body_stage`) then adds
        it through :meth:`mbs.bodies.body.Body.add_point_load_into`, allocation-free."""
        return None

    def add_tangents(self, t, q, u, K, D) -> None:
        """Optionally add −∂Q/∂q (in velocity-increment coordinates) and −∂Q/∂u into the
        global K, D (nu, nu) for implicit integrators; the default adds nothing."""


class Constraint:
    """A bilateral constraint of ``n_c`` scalar equations (see module docstring)."""

    n_c: int = 0

    def bodies(self):
        return []

    def residual(self, t, q) -> np.ndarray:
        """g(q, t) (n_c,)."""
        raise NotImplementedError

    def jacobian(self, t, q, C_q) -> None:
        """Write ∂ġ/∂u into the rows C_q (n_c, nu) of the global constraint Jacobian
        (the caller passes a zeroed view)."""
        raise NotImplementedError

    def residual_and_jacobian(self, t, q, C_q) -> np.ndarray:
        """g(q, t) of :meth:`residual`, with C_q written as by :meth:`jacobian` (what a
        Newton iteration needs; a constraint may share work between the two)."""
        self.jacobian(t, q, C_q)
        return self.residual(t, q)

    def velocity_term(self, t, q) -> np.ndarray:
        """g_t = ∂g/∂t (n_c,); zero for constraints that do not depend on time."""
        return np.zeros(self.n_c)

    def bias(self, t, q, u) -> np.ndarray:
        """γ with g̈ = C_q u̇ + γ (n_c,)."""
        raise NotImplementedError
