"""Generalized-α for constrained multibody systems on Lie groups (Arnold & Brüls 2007;
Brüls, Cardona & Arnold 2012), with the parameters of Chung & Hulbert (1993).

Per step Δt, with the pseudo-acceleration ā, unknowns u̇_{n+1} and λ_{n+1}:

    (1 − α_m) ā_{n+1} + α_m ā_n = (1 − α_f) u̇_{n+1} + α_f u̇_n
    u_{n+1} = u_n + Δt (1 − γ) ā_n + Δt γ ā_{n+1}
    q_{n+1} = q_n ⊕ (Δt u_n + Δt² (½ − β) ā_n + Δt² β ā_{n+1})
    M(q_{n+1}) u̇_{n+1} = h(q_{n+1}, u_{n+1}, t_{n+1}) + C_qᵀ λ_{n+1},    g(q_{n+1}) = 0

solved by Newton with the iteration matrix S = M + β Δt² c K_t + γ Δt c D_t,
c = (1 − α_f)/(1 − α_m), and the constraint rows scaled by 1/(β Δt² c). K_t, D_t are the
constant elastic, damping and link tangents; the gyroscopic tangents are left out
(a quasi-Newton method), which only slows convergence for fast rotation.

Newton stops when the correction Δu̇ is below ``tol`` |u̇| or, with constraints, below
their round-off floor: g(q) is known to about ε max(1, |q|∞) and its rows are scaled by
1/(β Δt² c), so Δu̇ < 16 ε max(1, |q|∞) / (β Δt² c) moves q by less than its own round-off
and cannot be resolved: at small steps (a hinged beam at Δt = 1e-5 s) the correction
stalls there, above ``tol`` |u̇|, however many iterations are taken.

Each iteration is allocation-free: M and the forces h come from the body stage
(:class:`mbs.run.body_stage.BodyStage`) into a preallocated workspace, the vector algebra
and the Cholesky solve of S from numba kernels (:mod:`mbs.integrators._kernels`,
:mod:`mbs.run.linalg_kernels`). S is read from its upper triangle (it is symmetric unless a
force element's tangent is not); where it is not positive definite the step solves it
with LAPACK's symmetric indefinite solver instead. With constraints the KKT system is
solved densely by LAPACK.

ρ∞ ∈ [0, 1] is the spectral radius at Δt ω → ∞: α_m = (2ρ∞ − 1)/(ρ∞ + 1),
α_f = ρ∞/(ρ∞ + 1), γ = ½ − α_m + α_f, β = ¼ (γ + ½)²; second-order accurate,
unconditionally stable for linear problems.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ffrmbs.errors import ModelError

from mbs.integrators._kernels import combine_into, ga_base, ga_newton_update, ga_predict
from mbs.integrators.driver import CarriedEntry, Integrator, StepFailure

ROUNDOFF = 16 * np.finfo(float).eps     # the constraint residual's relative round-off (module docstring)


class _Workspace:
    """The arrays of one step: iterate, predictions, M, h, tangents, factor."""

    def __init__(self, nq, nu):
        self.a1, self.abar1, self.u1, self.dq = (np.zeros(nu) for _ in range(4))
        self.base_u, self.base_dq, self.h1, self.res, self.da = (np.zeros(nu) for _ in range(5))
        self.q1 = np.zeros(nq)
        self.M, self.K, self.D, self.stiff, self.L = (np.zeros((nu, nu)) for _ in range(5))
        self.stiff_dt = None     # the step size ``stiff`` was built for (constant tangents)


class GeneralizedAlpha(Integrator):
    """Implicit generalized-α (see module docstring).

    Options: ``rho_inf`` (default 0.9), ``tol`` relative Newton tolerance on u̇
    (default 1e-10), ``max_iter`` (default 30).
    """

    name = "generalized-alpha"

    def __init__(self, system, rho_inf=0.9, tol=1e-10, max_iter=30):
        super().__init__(system)
        if not 0.0 <= rho_inf <= 1.0:
            raise ModelError(f"rho_inf must lie in [0, 1], got {rho_inf}")
        self.rho_inf, self.tol, self.max_iter = rho_inf, tol, max_iter
        self.alpha_m = (2 * rho_inf - 1) / (rho_inf + 1)
        self.alpha_f = rho_inf / (rho_inf + 1)
        self.gamma = 0.5 - self.alpha_m + self.alpha_f
        self.beta = 0.25 * (self.gamma + 0.5) ** 2

    def options(self):
        return {"rho_inf": self.rho_inf, "tol": self.tol}

    a, abar, lam = CarriedEntry(), CarriedEntry(), CarriedEntry()      # u̇_n, ā_n, λ_n

    def start(self, t, q, u):
        sys = self.model.equations
        self.t, self.q, self.u = t, q.copy(), u.copy()
        self.a, self.lam = sys.accelerations(t, self.q, self.u)
        self.abar = self.a.copy()
        self.bodies = self.model.body_stage
        self.work = _Workspace(sys.nq, sys.nu)

    def _stiffness(self, t1, dt, c):
        """stiff = βΔt²c K + γΔtc D (nu, nu) with the tangents at (t1, q_n, u_n); built once
        per step size when they are constant."""
        w, bodies = self.work, self.bodies
        if bodies.constant_tangents and w.stiff_dt == dt:
            return w.stiff
        bodies.tangents(t1, self.q, self.u, w.K, w.D)
        combine_into(w.K, self.beta * dt * dt * c, w.D, self.gamma * dt * c, w.stiff)
        w.stiff_dt = dt
        return w.stiff

    def step(self, dt):
        sys, bodies, w = self.model.equations, self.bodies, self.work
        am, af, gm, bt = self.alpha_m, self.alpha_f, self.gamma, self.beta
        c = (1 - af) / (1 - am)
        t1 = self.t + dt
        stiff = self._stiffness(t1, dt, c)
        a1 = w.a1
        a1[:] = self.a
        lam = self.lam.copy() if sys.n_c else self.lam
        nc = sys.n_c
        g_dt, b_dt2 = dt * gm, dt * dt * bt
        floor = ROUNDOFF * max(1.0, float(np.abs(self.q).max())) / (b_dt2 * c) if nc else 0.0
        ga_base(self.u, self.abar, dt * (1 - gm), dt, dt * dt * (0.5 - bt), w.base_u, w.base_dq)
        for it in range(1, self.max_iter + 1):
            ga_predict(self.a, a1, self.abar, w.base_u, w.base_dq, af, am, g_dt, b_dt2, w.abar1, w.u1, w.dq)
            bodies.increment(self.q, w.dq, w.q1)
            bodies.mass_and_h(t1, w.q1, w.u1, w.M, w.h1)
            if nc:
                da, lam = self._constrained_correction(t1, w, stiff, lam, bt * dt * dt * c)
                a1 += da
                err, scale, finite = np.abs(da).max(), np.abs(a1).max(), bool(np.all(np.isfinite(a1)))
            else:
                info, err, scale, finite = ga_newton_update(w.M, stiff, a1, w.h1, w.L, w.res, w.da)
                if info:        # S not positive definite: the symmetric indefinite solver
                    da = scipy.linalg.solve(w.M + stiff, w.h1 - w.M @ a1, assume_a="sym", check_finite=False)
                    a1 += da
                    err, scale, finite = np.abs(da).max(), np.abs(a1).max(), bool(np.all(np.isfinite(a1)))
            self.iterations += 1
            if not finite:
                break
            if err <= self.tol * (scale + 1e-300) + floor:
                break
        else:
            raise StepFailure(f"generalized-α Newton did not converge in {self.max_iter} iterations "
                              f"(last correction {err:.3g}); reduce dt")
        ga_predict(self.a, a1, self.abar, w.base_u, w.base_dq, af, am, g_dt, b_dt2, w.abar1, w.u1, w.dq)
        bodies.increment(self.q, w.dq, w.q1)
        bodies.normalize(w.q1)
        # the new state: q and u copied into the run's Data, the accelerations' buffers swapped
        self.q = w.q1
        self.u = w.u1
        self.a, w.a1 = a1, self.a
        self.abar, w.abar1 = w.abar1, self.abar
        self.lam, self.t = lam, t1

    def _constrained_correction(self, t1, w, stiff, lam, scale):
        """(Δu̇, λ) of one Newton correction of the KKT system with the constraint rows
        scaled by 1/``scale`` = 1/(βΔt²c) (LAPACK, allocating)."""
        sys = self.model.equations
        nu, nc = sys.nu, sys.n_c
        res = w.M @ w.a1 - w.h1
        g, C = sys.constraint_residual_and_jacobian(t1, w.q1)
        res -= C.T @ lam
        KKT = np.zeros((nu + nc, nu + nc))
        KKT[:nu, :nu] = w.M + stiff
        KKT[:nu, nu:] = -C.T
        KKT[nu:, :nu] = C
        d = np.linalg.solve(KKT, -np.concatenate((res, g / scale)))
        return d[:nu], lam + d[nu:]
