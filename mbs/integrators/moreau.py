"""Moreau's midpoint time-stepping for set-valued contacts and impacts (thesis eq. 3.1, 4.1).

One step of size Δt (DESIGN, "the data flow of one Moreau step"):

1. q_m = q_k ⊕ (Δt/2) u_k;
2. M, h at (t_m, q_m, u_k); single-valued contact forces join h;
3. the contours of the contacts update at q_m (each once);
4. contacts located; a unilateral contact is closed where g_N(q_m) <= 0;
5. bilateral joints (velocity level, C_q u⁺ + g_t = 0) and closed contacts form
   W (nu, m); with M̂ = M + θ Δt D + θ Δt² K (linearly implicit stiffness and damping,
   so stiff modes do not limit Δt) the free velocity is u_free = u_k + M̂⁻¹ h Δt, the
   Delassus matrix G = Wᵀ M̂⁻¹ W, and the impulses Λ solve the laws on velocity level
   (:class:`contact.solver.ProxSolver`, Newton's impact law with γ⁻ = Wᵀ u_k);
6. u_{k+1} = u_free + M̂⁻¹ W Λ;
7. q_{k+1} = q_m ⊕ (Δt/2) u_{k+1}, orientations renormalized.

Options: ``theta`` (0.5..1, default 1: the damped implicit Euler on the elastic
forces, unconditionally stable; 0.5 conserves elastic energy), ``solver`` (a ProxSolver
or its method name), ``tol``. Non-convergence of the contact problem stops the run with
a SimulationError naming the residual.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

from contact.laws import Bilateral
from contact.solver import ContactSet, ProxSolver
from ffrmbs.errors import ModelError

from .driver import Integrator, StepFailure


class MoreauTimeStepping(Integrator):
    """Moreau's midpoint time-stepping (module docstring)."""

    name = "moreau"

    def __init__(self, system, theta=1.0, solver="gauss-seidel", tol=1e-10, max_iter=2000):
        super().__init__(system)
        if not 0.5 <= theta <= 1.0:
            raise ModelError(f"theta must lie in [0.5, 1], got {theta}")
        self.theta = float(theta)
        self.solver = solver if isinstance(solver, ProxSolver) else ProxSolver(solver, tol=tol, max_iter=max_iter)
        self.contacts = list(system.contacts)
        contours = {}
        for c in self.contacts:
            for contour in c.contours():
                contours[id(contour)] = contour
        self.contours = list(contours.values())
        self.stats = {"closed_contacts": 0, "solver_iterations": 0, "max_penetration": 0.0}
        self._lam = {}
        self._sets = {}

    def options(self):
        return {"theta": self.theta, "solver": self.solver.method}

    def diagnostics(self):
        """Closed-contact steps summed over contacts, contact-solver iterations, largest
        penetration max(0, −g_N) at a midpoint [m]."""
        return dict(self.stats)

    def start(self, t, q, u):
        self.t, self.q, self.u = t, q.copy(), u.copy()

    def _update_contours(self, t, q, u):
        for contour in self.contours:
            body = contour.body
            if body is None:
                contour.update(None, None, t)
            else:
                contour.update(q[body.q_slice], u[body.u_slice], t)

    def step(self, dt):
        sys = self.system
        t_m = self.t + 0.5 * dt
        q_m = sys.increment(self.q, 0.5 * dt * self.u)
        sys.normalize(q_m)
        M, h = sys.mass_and_h(t_m, q_m, self.u)
        closed = []
        if self.contacts:
            self._update_contours(t_m, q_m, self.u)
            for c in self.contacts:
                if c.detect() and c.set_valued:
                    closed.append(c)
                if not c.set_valued:
                    c.add_forces(h)
                self.stats["max_penetration"] = max(self.stats["max_penetration"], c.penetration)
        K, D = sys.tangents(t_m, q_m, self.u)  # elastic, damping and link (spring) tangents at the midpoint
        th = self.theta
        M_hat = M + th * dt * D + th * dt * dt * K
        factor, info = dpotrf(M_hat, lower=True, overwrite_a=True)
        if info != 0:
            raise StepFailure(f"M + θΔt D + θΔt² K is not positive definite (LAPACK dpotrf info {info})")
        u_free = self.u + dpotrs(factor, dt * h, lower=True)[0]
        m = sys.n_c + sum(c.dim for c in closed)
        if m == 0:
            self.u = u_free
        else:
            W = np.zeros((sys.nu, m))
            laws = []
            if sys.n_c:
                W[:, :sys.n_c] = sys.constraint_jacobian(t_m, q_m).T
                laws.append(Bilateral(sys.n_c))
            i = sys.n_c
            for c in closed:
                c.jacobian(W[:, i:i + c.dim])
                laws.append(c.law)
                i += c.dim
            offset = np.zeros(m)
            if sys.n_c:
                offset[:sys.n_c] = sys.constraint_velocity_term(t_m, q_m)
            MW = dpotrs(factor, W, lower=True)[0]
            G = W.T @ MW
            xi_free = W.T @ u_free + offset
            gamma_pre = W.T @ self.u + offset
            sol = self.solver.solve(self._contact_set(closed, laws), G, xi_free, gamma_pre,
                                    self._warm(closed, m), validate=False)
            if not sol.converged:
                raise StepFailure(f"contact problem not solved: residual {sol.residual:.3g} m/s after "
                                  f"{sol.iterations} iterations ({len(closed)} closed contacts)")
            self.stats["solver_iterations"] += sol.iterations
            self._store(closed, sol.lam)
            self.u = u_free + MW @ sol.lam
        self.stats["closed_contacts"] += len(closed)
        self.q = sys.increment(q_m, 0.5 * dt * self.u)
        sys.normalize(self.q)
        self.t += dt

    def _contact_set(self, closed, laws):
        """The ContactSet of this active set, built once per set of closed contacts."""
        key = tuple(id(c) for c in closed)
        cs = self._sets.get(key)
        if cs is None:
            cs = self._sets[key] = ContactSet(laws)
        return cs

    def _warm(self, closed, m):
        """Λ of the previous step for contacts closed again (joints first), else zero."""
        lam = np.zeros(m)
        i = self.system.n_c
        if i and "joints" in self._lam and self._lam["joints"].size == i:
            lam[:i] = self._lam["joints"]
        for c in closed:
            prev = self._lam.get(id(c))
            if prev is not None:
                lam[i:i + c.dim] = prev
            i += c.dim
        return lam

    def _store(self, closed, lam):
        i = self.system.n_c
        self._lam = {"joints": lam[:i].copy()}
        for c in closed:
            self._lam[id(c)] = lam[i:i + c.dim].copy()
            i += c.dim

