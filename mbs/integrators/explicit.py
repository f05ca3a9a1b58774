"""Explicit classical Runge–Kutta (RK4) on q̇ = Y(q) u (thesis eq. 3.1a), u̇ from the
index-1 equations [[M, −C_qᵀ], [C_q, 0]] (u̇, λ) = (h, −γ).

The quaternion ODE ṗ = ½ p ⊗ (0, ω̄) is integrated in R⁴ and p renormalized after the
step (a projection that keeps fourth order). With constraints, each step ends with a
projection onto g(q) = 0 (Newton, minimal M-norm corrections q ⊕ Δ with
Δ = −M⁻¹C_qᵀ (C_q M⁻¹ C_qᵀ)⁻¹ g) and onto ġ = 0; optional Baumgarte terms (a, b) [1/s]
damp drift between projections. Stable only for Δt ω_max ≲ 2.8: stiff elastic modes need
the implicit integrator.

Each of the four stages evaluates M and h with the body stage
(:class:`mbs.run.body_stage.BodyStage`, the kernels every integrator uses) into the
step's workspace; without constraints u̇ = M⁻¹ h is a Cholesky solve in numba
(:mod:`mbs.run.linalg_kernels`), with constraints the index-1 system is solved densely by
LAPACK (:meth:`mbs.run.equations.Equations.constrained_accelerations`).
"""

from __future__ import annotations

import numpy as np

from mbs.integrators.driver import Integrator, StepFailure
from mbs.run.linalg_kernels import cho_solve_vector, cholesky_into


class RK4(Integrator):
    """Explicit RK4 (see module docstring). Options: ``baumgarte`` = (a, b) [1/s],
    ``project`` (default True), ``projection_tol`` (default 1e-12) and ``projection_iter``."""

    name = "rk4"

    def __init__(self, system, baumgarte=(0.0, 0.0), project=True, projection_tol=1e-12,
                 projection_iter=10):
        super().__init__(system)
        self.baumgarte = tuple(baumgarte)
        self.project = project
        self.projection_tol, self.projection_iter = projection_tol, projection_iter

    def options(self):
        return {"baumgarte": self.baumgarte, "project": self.project}

    def start(self, t, q, u):
        self.t, self.q, self.u = t, q.copy(), u.copy()
        self.bodies = self.model.body_stage
        nu = self.model.equations.nu
        self._M, self._h = np.zeros((nu, nu)), np.zeros(nu)

    def _acc(self, t, q, u):
        """u̇ (nu,) at (t, q, u) (module docstring)."""
        M, h = self._M, self._h
        self.bodies.mass_and_h(t, q, u, M, h)
        sys = self.model.equations
        if sys.n_c:
            return sys.constrained_accelerations(t, q, u, M, h, self.baumgarte)[0]
        if cholesky_into(M, M):         # factored in place: the body stage writes M afresh
            raise StepFailure(f"the mass matrix is not positive definite at t = {t:.6g} s")
        a = np.empty(sys.nu)
        cho_solve_vector(M, h, a)
        return a

    def step(self, dt):
        sys, t, q, u = self.model.equations, self.t, self.q, self.u
        k1q, k1u = sys.qdot(q, u), self._acc(t, q, u)
        q2, u2 = q + 0.5 * dt * k1q, u + 0.5 * dt * k1u
        k2q, k2u = sys.qdot(q2, u2), self._acc(t + 0.5 * dt, q2, u2)
        q3, u3 = q + 0.5 * dt * k2q, u + 0.5 * dt * k2u
        k3q, k3u = sys.qdot(q3, u3), self._acc(t + 0.5 * dt, q3, u3)
        q4, u4 = q + dt * k3q, u + dt * k3u
        k4q, k4u = sys.qdot(q4, u4), self._acc(t + dt, q4, u4)
        self.q = q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
        self.u = u + dt / 6 * (k1u + 2 * k2u + 2 * k3u + k4u)
        self.t = t + dt
        sys.normalize(self.q)
        if sys.n_c and self.project:
            self._project()

    def _project(self):
        sys, t = self.model.equations, self.t
        M = sys.mass_matrix(t, self.q)
        for _ in range(self.projection_iter):
            g = sys.constraint_residual(t, self.q)
            if np.abs(g).max() <= self.projection_tol:
                break
            C = sys.constraint_jacobian(t, self.q)
            MiCT = np.linalg.solve(M, C.T)
            self.q = sys.increment(self.q, -MiCT @ np.linalg.solve(C @ MiCT, g))
            sys.normalize(self.q)
            self.iterations += 1
        else:
            raise StepFailure("projection onto the position constraints did not converge")
        C = sys.constraint_jacobian(t, self.q)
        MiCT = np.linalg.solve(M, C.T)
        gd = C @ self.u + sys.constraint_velocity_term(t, self.q)
        self.u = self.u - MiCT @ np.linalg.solve(C @ MiCT, gd)
