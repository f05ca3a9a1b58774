"""The equations of motion of a System over an active set of bodies and force elements:
M(q) u̇ = h(q, u, t) + W λ, g(q, t) = 0 (thesis eq. 3.1), q̇ = Y(q) u (eq. 3.1a).

:class:`Equations` assembles the block-diagonal mass matrix M (nu, nu), the smooth
forces h (nu,) (bodies' Q_v − K q − D u, gravity, force elements), the tangents K, D,
the constraint residuals g, their Jacobian C_q (W = C_qᵀ) and acceleration terms γ of
the bodies it is given. A body left out (a planned run solves it apart, :mod:`mbs.run.plan`)
gets an identity mass block, zero force and a zero increment: its rows decouple and its
velocities stay zero. ``System`` uses one over all its bodies; a compiled
:class:`~mbs.run.model.Model` holds one over the active set, so planning never mutates the
System. Every method returns new arrays (the implicit and explicit integrators' route);
the in-place body stage of a step is :mod:`mbs.run.body_stage`.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from mbs.links.link import add_point_force, body_q


def solve_spd(M, b):
    """x = M⁻¹ b for a symmetric positive definite M (n, n), b (n,): LAPACK's ``dposv``
    (Cholesky), the routine ``scipy.linalg.solve(M, b, assume_a="pos")`` calls, without
    that function's argument checks and condition estimate (~15 times its cost at n ~ 10;
    an explicit step solves once per stage). Same result to the bit; ``LinAlgError`` if M
    is not positive definite."""
    _, x, info = lapack.dposv(M, b)
    if info > 0:
        raise np.linalg.LinAlgError(f"the mass matrix is not positive definite (leading minor {info})")
    if info < 0:
        raise ValueError(f"dposv: argument {-info} is invalid")
    return x


class Equations:
    """The equations of ``system`` with ``idle`` bodies and ``idle_forces`` left out
    (module docstring). Attributes: nq, nu, n_c (sizes), bodies (all), active (the
    bodies integrated), idle, forces (the active force elements), constraints."""

    def __init__(self, system, idle=(), idle_forces=()):
        self.system = system
        self.gravity = system.gravity
        self.nq, self.nu, self.n_c = system.nq, system.nu, system.n_c
        self.bodies = tuple(system.bodies)
        self.idle = tuple(b for b in self.bodies if b in tuple(idle))
        self.active = tuple(b for b in self.bodies if b not in self.idle)
        self.forces = tuple(f for f in system.forces if f not in tuple(idle_forces))
        self.constraints = tuple(system.constraints)
        self.com = tuple((b, com) for b, com in zip(self.bodies, system.com_frames) if b not in self.idle)
        self.additive = all(b.additive for b in self.active)

    @property
    def constant_iteration_matrix(self) -> bool:
        """True when M, the bodies' tangents K and D and the links' (none) do not change:
        every active body has a constant mass matrix (point masses, FFR bodies on a
        prescribed frame), no active body's tangents vary and no active force element has
        tangents."""
        return (all(b.constant_mass and not b.varying_tangents for b in self.active)
                and not any(f.has_tangents for f in self.forces))

    # --- kinematics ---------------------------------------------------------------------
    def qdot(self, q, u):
        """q̇ = Y(q) u (thesis eq. 3.1a); zero for idle bodies."""
        out = np.empty(self.nq) if not self.idle else np.zeros(self.nq)
        for b in self.active:
            out[b.q_slice] = b.qdot(q[b.q_slice], u[b.u_slice])
        return out

    def increment(self, q, du):
        """q ⊕ Δu, exact for rotations (exponential map); idle bodies keep their q
        (their Δu is zero). One vector sum when no active body has rotation coordinates."""
        if self.additive:
            return q + du
        out = np.empty(self.nq) if not self.idle else q.copy()
        for b in self.active:
            out[b.q_slice] = b.increment(q[b.q_slice], du[b.u_slice])
        return out

    def normalize(self, q):
        """Renormalize the orientation coordinates of the active bodies in place."""
        for b in self.active:
            if not b.additive:
                b.normalize(q[b.q_slice])

    # --- dynamics -----------------------------------------------------------------------
    def _idle_identity(self, M):
        for b in self.idle:
            np.fill_diagonal(M[b.u_slice, b.u_slice], 1.0)

    def mass_matrix(self, t, q):
        """Block-diagonal M (nu, nu) [kg, kg m, kg m²]."""
        M = np.zeros((self.nu, self.nu))
        for b in self.active:
            M[b.u_slice, b.u_slice] = b.mass_matrix(q[b.q_slice], t)
        self._idle_identity(M)
        return M

    def h(self, t, q, u):
        """Smooth generalized forces h (nu,): bodies' Q_v − K q − D u, gravity, links."""
        out = np.empty(self.nu) if not self.idle else np.zeros(self.nu)
        for b in self.active:
            out[b.u_slice] = b.h(q[b.q_slice], u[b.u_slice], t)
        self.add_external(t, q, u, out)
        return out

    def mass_and_h(self, t, q, u):
        """(M, h) in one pass over the bodies (what an implicit step needs per iteration)."""
        M = np.zeros((self.nu, self.nu))
        out = np.empty(self.nu) if not self.idle else np.zeros(self.nu)
        for b in self.active:
            M[b.u_slice, b.u_slice], out[b.u_slice] = b.mass_and_h(q[b.q_slice], u[b.u_slice], t)
        self._idle_identity(M)
        self.add_external(t, q, u, out)
        return M, out

    def add_external(self, t, q, u, out):
        """Gravity on the active bodies and the active force elements into ``out`` (nu,)."""
        if self.gravity.any():
            for b, com in self.com:
                add_point_force(com, q, t, b.mass * self.gravity, out)
        for f in self.forces:
            f.add_forces(t, q, u, out)

    def tangents(self, t, q, u):
        """(K_t, D_t) (nu, nu): elastic and damping tangents (constant and varying) plus link tangents,
        for the iteration matrix of implicit integrators."""
        K = np.zeros((self.nu, self.nu))
        D = np.zeros((self.nu, self.nu))
        for b in self.active:
            Kb, Db = b.stiffness_tangent(), b.damping_tangent()
            if Kb is not None:
                K[b.u_slice, b.u_slice] += Kb
            if Db is not None:
                D[b.u_slice, b.u_slice] += Db
            us = b.u_slice
            b.add_tangents(t, q[b.q_slice], u[us], K[us, us], D[us, us])
        for f in self.forces:
            f.add_tangents(t, q, u, K, D)
        return K, D

    # --- constraints --------------------------------------------------------------------
    def constraint_residual(self, t, q):
        """g(q, t) (n_c,) [m or rad]."""
        return np.concatenate([c.residual(t, q) for c in self.constraints]) \
            if self.constraints else np.zeros(0)

    def constraint_jacobian(self, t, q, out=None):
        """C_q (n_c, nu) (into ``out`` when given); W = C_qᵀ."""
        C = np.zeros((self.n_c, self.nu)) if out is None else out
        i = 0
        for c in self.constraints:
            c.jacobian(t, q, C[i:i + c.n_c])
            i += c.n_c
        return C

    def constraint_residual_and_jacobian(self, t, q, out=None):
        """(g (n_c,), C_q (n_c, nu)) of :meth:`constraint_residual` and
        :meth:`constraint_jacobian` in one pass over the constraints."""
        C = np.zeros((self.n_c, self.nu)) if out is None else out
        g = np.empty(self.n_c)
        i = 0
        for c in self.constraints:
            g[i:i + c.n_c] = c.residual_and_jacobian(t, q, C[i:i + c.n_c])
            i += c.n_c
        return g, C

    def constraint_velocity_term(self, t, q):
        """∂g/∂t (n_c,): ġ = C_q u + ∂g/∂t."""
        return np.concatenate([c.velocity_term(t, q) for c in self.constraints]) \
            if self.constraints else np.zeros(0)

    def constraint_bias(self, t, q, u):
        """γ (n_c,) with g̈ = C_q u̇ + γ."""
        return np.concatenate([c.bias(t, q, u) for c in self.constraints]) \
            if self.constraints else np.zeros(0)

    def accelerations(self, t, q, u, baumgarte=(0.0, 0.0)):
        """(u̇, λ) from [[M, −C_qᵀ], [C_q, 0]] (u̇, λ) = (h, −γ − 2a ġ − b² g): the
        index-1 form, with Baumgarte's stabilization terms a [1/s], b [1/s] if given.
        Sign convention: reaction forces W λ = C_qᵀ λ enter as M u̇ = h + W λ."""
        M, h = self.mass_and_h(t, q, u)
        if not self.n_c:
            return solve_spd(M, h), np.zeros(0)
        return self.constrained_accelerations(t, q, u, M, h, baumgarte)

    def constrained_accelerations(self, t, q, u, M, h, baumgarte=(0.0, 0.0)):
        """(u̇, λ) of :meth:`accelerations` with M (nu, nu) and h (nu,) at (t, q, u) given
        (an integrator's body stage computed them): the constraint rows and the dense
        solve (LAPACK, allocating)."""
        C = self.constraint_jacobian(t, q)
        a, b = baumgarte
        rhs_c = -self.constraint_bias(t, q, u)
        if a or b:
            g = self.constraint_residual(t, q)
            gd = C @ u + self.constraint_velocity_term(t, q)
            rhs_c -= 2 * a * gd + b * b * g
        n = self.nu
        K = np.zeros((n + self.n_c, n + self.n_c))
        K[:n, :n] = M
        K[:n, n:] = -C.T
        K[n:, :n] = C
        sol = np.linalg.solve(K, np.concatenate((h, rhs_c)))
        return sol[:n], sol[n:]

    # --- energies -----------------------------------------------------------------------
    def kinetic_energy(self, t, q, u):
        """Σ over all bodies of their kinetic energy [J]."""
        return sum(b.kinetic_energy(q[b.q_slice], u[b.u_slice], t) for b in self.bodies)

    def potential_energy(self, t, q):
        """Elastic energy of the bodies, gravity (−m g·r_com) and links' stored energy [J]
        (all bodies and force elements: the energy of the whole scene)."""
        sys = self.system
        e = sum(b.elastic_energy(q[b.q_slice]) for b in self.bodies)
        if self.gravity.any():
            e -= sum(b.mass * self.gravity @ com.position(body_q(com, q), t)
                     for b, com in zip(self.bodies, sys.com_frames))
        return e + sum(f.potential_energy(t, q) for f in sys.forces)
