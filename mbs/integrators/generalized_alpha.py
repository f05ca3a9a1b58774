"""Generalized-α for constrained multibody systems on Lie groups (Arnold & Brüls 2007;
Brüls, Cardona & Arnold 2012), with the parameters of Chung & Hulbert (1993).

Per step h, with the pseudo-acceleration ā, unknowns u̇_{n+1} and λ_{n+1}:

    (1 − α_m) ā_{n+1} + α_m ā_n = (1 − α_f) u̇_{n+1} + α_f u̇_n
    u_{n+1} = u_n + h (1 − γ) ā_n + h γ ā_{n+1}
    q_{n+1} = q_n ⊕ (h u_n + h² (½ − β) ā_n + h² β ā_{n+1})
    M(q_{n+1}) u̇_{n+1} = h(q_{n+1}, u_{n+1}, t_{n+1}) + C_qᵀ λ_{n+1},    g(q_{n+1}) = 0

solved by Newton with the iteration matrix S = M + β h² c K_t + γ h c D_t,
c = (1 − α_f)/(1 − α_m), and the constraint rows scaled by 1/(β h² c). K_t, D_t are the
constant elastic, damping and link tangents; the gyroscopic tangents are left out
(a quasi-Newton method), which only slows convergence for fast rotation.

ρ∞ ∈ [0, 1] is the spectral radius at h ω → ∞: α_m = (2ρ∞ − 1)/(ρ∞ + 1),
α_f = ρ∞/(ρ∞ + 1), γ = ½ − α_m + α_f, β = ¼ (γ + ½)²; second-order accurate,
unconditionally stable for linear problems.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ffrmbs.errors import ModelError

from .driver import Integrator, StepFailure


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

    def start(self, t, q, u):
        self.t, self.q, self.u = t, q.copy(), u.copy()
        self.a, self.lam = self.model.equations.accelerations(t, self.q, self.u)
        self.abar = self.a.copy()

    def step(self, h):
        sys = self.model.equations
        am, af, gm, bt = self.alpha_m, self.alpha_f, self.gamma, self.beta
        c = (1 - af) / (1 - am)
        t1 = self.t + h
        K, D = sys.tangents(t1, self.q, self.u)
        stiff = bt * h * h * c * K + gm * h * c * D
        a1, lam = self.a.copy(), self.lam.copy()
        nu, nc = sys.nu, sys.n_c
        base_u = self.u + h * (1 - gm) * self.abar
        base_dq = h * self.u + h * h * (0.5 - bt) * self.abar
        for it in range(1, self.max_iter + 1):
            abar1 = (af * self.a + (1 - af) * a1 - am * self.abar) / (1 - am)
            u1 = base_u + h * gm * abar1
            q1 = sys.increment(self.q, base_dq + h * h * bt * abar1)
            M, h1 = sys.mass_and_h(t1, q1, u1)
            res = M @ a1 - h1
            S = M + stiff
            if nc:
                C = sys.constraint_jacobian(t1, q1)
                res -= C.T @ lam
                g = sys.constraint_residual(t1, q1)
                KKT = np.zeros((nu + nc, nu + nc))
                KKT[:nu, :nu] = S
                KKT[:nu, nu:] = -C.T
                KKT[nu:, :nu] = C
                d = np.linalg.solve(KKT, -np.concatenate((res, g / (bt * h * h * c))))
                da, lam = d[:nu], lam + d[nu:]
            else:
                da = scipy.linalg.solve(S, -res, assume_a="sym", check_finite=False)
            a1 += da
            self.iterations += 1
            if not np.all(np.isfinite(a1)):
                break
            if np.abs(da).max() <= self.tol * (np.abs(a1).max() + 1e-300):
                break
        else:
            raise StepFailure(f"generalized-α Newton did not converge in {self.max_iter} iterations "
                              f"(last correction {np.abs(da).max():.3g}); reduce dt")
        abar1 = (af * self.a + (1 - af) * a1 - am * self.abar) / (1 - am)
        self.u = base_u + h * gm * abar1
        self.q = sys.increment(self.q, base_dq + h * h * bt * abar1)
        sys.normalize(self.q)
        self.a, self.abar, self.lam, self.t = a1, abar1, lam, t1
