"""numba kernels of the integrators' vector algebra, allocation-free (plain-numpy
references: the formulas in the docstrings, written out in the tests).

Generalized-α (:mod:`mbs.integrators.generalized_alpha`, Arnold & Brüls 2007), per step Δt:

    base_u  = u_n + Δt (1 − γ) ā_n,     base_dq = Δt u_n + Δt² (½ − β) ā_n
    ā_{n+1} = (α_f u̇_n + (1 − α_f) u̇_{n+1} − α_m ā_n) / (1 − α_m)
    u_{n+1} = base_u + Δt γ ā_{n+1},    Δq = base_dq + Δt² β ā_{n+1}

and one Newton correction of u̇_{n+1} with the iteration matrix S = M + stiff:
r = M u̇ − h, S Δu̇ = −r (Cholesky), u̇ += Δu̇.

Moreau–Jean (:mod:`mbs.integrators.moreau`): the iteration matrix M̂ = M + θΔt D + θ²Δt² K.
"""

from __future__ import annotations

import math

from numba import njit

from mbs.run.linalg_kernels import cho_solve_vector, cholesky_into


@njit(cache=True)
def ga_base(u, abar, c_u, c_du, c_da, base_u, base_dq):
    """base_u = u + c_u ā, base_dq = c_du u + c_da ā (c_u = Δt (1 − γ), c_du = Δt,
    c_da = Δt² (½ − β))."""
    for i in range(u.shape[0]):
        base_u[i] = u[i] + c_u * abar[i]
        base_dq[i] = c_du * u[i] + c_da * abar[i]


@njit(cache=True)
def ga_predict(a, a1, abar, base_u, base_dq, af, am, g_dt, b_dt2, abar1, u1, dq):
    """ā_{n+1}, u_{n+1} and Δq from the iterate a1 = u̇_{n+1} (module docstring; g_dt = Δt γ,
    b_dt2 = Δt² β)."""
    for i in range(a.shape[0]):
        ab = (af * a[i] + (1 - af) * a1[i] - am * abar[i]) / (1 - am)
        abar1[i] = ab
        u1[i] = base_u[i] + g_dt * ab
        dq[i] = base_dq[i] + b_dt2 * ab


@njit(cache=True)
def combine_into(K, s_k, D, s_d, out):
    """out = s_k K + s_d D (n, n)."""
    n = K.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = s_k * K[i, j] + s_d * D[i, j]


@njit(cache=True)
def ga_newton_update(M, stiff, a1, h1, L, res, da):
    """One Newton correction (module docstring): res = M a1 − h1, L = chol(S) with
    S = M + stiff symmetrized from its upper triangle (as LAPACK's symmetric solvers read
    it), da = −S⁻¹ res, a1 += da. Returns (info, max |da|, max |a1|, all a1 finite):
    info ≠ 0 when S is not positive definite (then da and a1 are left unchanged)."""
    n = a1.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += M[i, j] * a1[j]
        res[i] = acc - h1[i]
    for i in range(n):
        for j in range(i, n):
            L[j, i] = M[i, j] + stiff[i, j]
    info = cholesky_into(L, L)
    if info != 0:
        return info, 0.0, 0.0, True
    for i in range(n):
        res[i] = -res[i]
    cho_solve_vector(L, res, da)
    err = 0.0
    scale = 0.0
    finite = True
    for i in range(n):
        a1[i] += da[i]
        d = abs(da[i])
        if d > err or d != d:
            err = d if d == d else math.inf
        x = abs(a1[i])
        if x > scale:
            scale = x
        if not math.isfinite(a1[i]):
            finite = False
    return 0, err, scale, finite


@njit(cache=True)
def moreau_iteration_matrix(M, D, c_d, K, c_k, out):
    """M̂ = M + c_d D + c_k K (n, n) of Moreau–Jean's θ-method (c_d = θΔt, c_k = θ²Δt²;
    :mod:`mbs.integrators.moreau`), summed in that order."""
    n = M.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = M[i, j] + c_d * D[i, j] + c_k * K[i, j]
