"""A compliant unilateral contact in the Moreau step: the contact acts through a massless
linear spring in series — the residual flexibility of the modes a reduced body leaves out
(:mod:`contours.residual`, :mod:`preprocess.residual`).

Let a closed contact have rows ρ of the contact problem (normal, and tangential with
friction), W its Jacobian, C (r × r) [m/N] the compliance of its rows (and of the other
compliant contacts' rows on the same bodies: cross-compliance), F [N] the spring force at
the end of a step and δ = C F [m] the spring's deflection, which opens the gap:

    g_eff = g + δ,      γ_eff = Wᵀ u + δ̇                                       (S1)

Signorini and Newton's law hold for the effective quantities, as for a rigid contact.
The spring is integrated by the same θ-method as the bodies (Moreau–Jean; θ = ½ the
trapezoidal rule, θ = 1 implicit Euler):

    Λ = Δt ((1 − θ) F_k + θ F_{k+1})                  (impulse over the step)    (S2)
    δ_{k+1} − δ_k = Δt ((1 − θ) δ̇_k + θ δ̇_{k+1})                               (S3)

Taking the unknown Λ' = θ Δt F_{k+1} ≥ 0 (so the cone of Coulomb's law bounds the end
force) and Λ₀ = (1 − θ) Δt F_k (known), (S2)–(S3) with δ_{k+1} = C F_{k+1} give

    δ̇_{k+1} = C Λ' / (θ Δt)² − δ_k / (θ Δt) − (1 − θ) δ̇_k / θ                  (S4)

and with u_{k+1} = u_free + M̂⁻¹ W (Λ₀ + Λ') the end-of-step effective velocity is

    γ⁺_eff = ξ'_free + G' Λ',   G' = G + C / (θ Δt)²,
             ξ'_free = ξ_free + G Λ₀ − δ_k / (θ Δt) − (1 − θ) δ̇_k / θ,
             γ⁻_eff = γ⁻ + δ̇_k                                                 (S5)

— the contact problem the solver already solves (:mod:`contact.solver`), with the
compliance on the diagonal scaled by the step (implicit: no step limit appears however
soft or stiff C is) and the spring's state in the free velocity. :func:`compliant_problem`
makes it; after the solve :func:`compliant_update` sets F_{k+1} = Λ'/(θΔt),
δ_{k+1} = C F_{k+1}, δ̇_{k+1} and the total impulse Λ = Λ₀ + Λ' the velocity update uses.

Energy (θ = ½). Per step the impulse does the work Λᵀ(γ⁻ + γ⁺)/2 on the bodies (the
θ = ½ identity) and ½(F_k + F_{k+1})ᵀ(δ_{k+1} − δ_k) = Λᵀ(δ̇_k + δ̇_{k+1})/2 on the spring
(S2–S3), together Λᵀ(γ⁻_eff + γ⁺_eff)/2. The spring's energy ½ FᵀC F changes by its work
minus ½ F_kᵀ(C_{k+1} − C_k)F_{k+1} (C symmetric; C_{k+1} is this step's compliance, which
differs from C_k when a contact point slides over the contour or the contact frame
turns). So the bodies' energy plus the spring's changes per step by

    ΔE = Λᵀ(γ⁻_eff + γ⁺_eff)/2 − ½ F_kᵀ(C_{k+1} − C_k)F_{k+1}                     (S6)

The last term, the sliding exchange, is first order in the compliance change: summed
over a contact it tends to −∫ ½ Fᵀ dC F, which does not vanish with Δt — the work the
slope of the deflected surface would do on a sliding point, which a force along the
contour's normal leaves out. A point sliding towards a stiffer place (C falling) gains
energy, towards a softer one loses it; the change is bounded by ½ F_max² times the
variation of C along the path (a 50 g mass on a small soft beam, e = 0: +1e-4 of its
energy, tests/unit/contact/test_compliant_contact.py checks the bound; the default scene of
``ffrmbs run``: +1.6e-3). Taking δ_k on the midpoint compliance ½(C_k + C_{k+1})F_k
instead makes the term second order for a smooth force (it removes both gains) but pumps
energy into a face of contacts whose forces jump from step to step (+11 % for two coarse
rods with 16 face points), so it is not done.

The first term: with e = 1 it is zero on every row where Newton's law holds with
equality (γ⁺_eff = −γ⁻_eff), so the bodies' energy plus the spring's ½ Fᵀ δ is kept while
the contact stays closed, to the (S6) sliding term. With e = 0 (Λ'ᵀγ⁺_eff = 0) it is
Λᵀγ⁻_eff/2 + Λ₀ᵀγ⁺_eff/2: a loss at the impact (Λ₀ = 0, γ⁻_eff < 0); while the contact
stays closed γ⁻_eff is the change of Wᵀu_k with the contact frame, O(Δt) per step; at the
release step (Λ' = 0, the bodies parting at γ⁺_eff > 0) the last end force still acts
over (1 − θ)Δt while the massless spring would relax within the step, a gain
Λ₀ᵀγ⁺_eff/2 = O(F_k γ⁺_eff Δt) per release, which vanishes with Δt. θ > ½ damps the spring
as it damps the bodies. With e < 1 the spring still stores and returns its energy; the
law's loss is of the order (ω Δt)² of the contact's spring–mass frequency ω. When the end
force and the deflection vanish (release of a contact alone on its body) the rate δ̇
(undefined for a massless spring) is set to zero. A closed contact without force whose
point the other contacts' forces still deflect (cross-compliance) keeps its rate:
zeroing it too gave the next step's (S3) a wrong start, and a face of contacts on a
corrected plate, some pressing and some not from step to step, gained 40 % of its
energy (25 point masses on a plate, e = 0; tests/unit/contact/test_compliant_contact.py).
A contact that was open in the last step starts with F = δ̇ = 0 and the deflection
δ = (C F_k) its point already has from the other closed contacts' forces on the same
body (cross-compliance; zero for a contact alone on its body): with δ = 0 the deflection
would jump within its first step, which the θ-rule (S3) turns into a spurious rate, and
a face of contacts closing one after another would gain energy. C = 0 gives back the
rigid contact exactly.

:func:`compliant_problem` and :func:`compliant_update` are numba kernels that allocate
nothing; :func:`compliant_problem_reference` and :func:`compliant_update_reference` are
their numpy references.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def compliant_problem(G, xi_free, gamma_pre, rows, C, force, delta, delta_dot, fresh, dt, theta, lam0):
    """The contact problem (S5) in place: ``G`` (m, m), ``xi_free``, ``gamma_pre`` (m,) of
    the rigid contacts, the compliant rows ``rows`` (r,) with their compliance ``C``
    (r, r) [m/N] of this step and spring state ``force`` [N], ``delta`` [m],
    ``delta_dot`` [m/s] (r,) at the start of the step (``delta`` of the rows ``fresh``
    (r,) bool, of contacts open in the last step, set to C F_k in place);
    Λ₀ = (1 − θ) Δt F_k into ``lam0`` (r,) [N s]."""
    r = rows.shape[0]
    m = G.shape[0]
    th_dt = theta * dt
    for a in range(r):
        lam0[a] = (1.0 - theta) * dt * force[a]
    for a in range(r):              # a contact open in the last step: its neighbours' deflection C F_k
        if not fresh[a]:
            continue
        d = 0.0
        for b in range(r):
            d += C[a, b] * force[b]
        delta[a] = d
    for i in range(m):
        s = 0.0
        for a in range(r):
            s += G[i, rows[a]] * lam0[a]
        xi_free[i] += s
    for a in range(r):
        ra = rows[a]
        xi_free[ra] -= delta[a] / th_dt + (1.0 - theta) / theta * delta_dot[a]
        gamma_pre[ra] += delta_dot[a]
    scale = 1.0 / (th_dt * th_dt)
    for a in range(r):
        for b in range(r):
            G[rows[a], rows[b]] += scale * C[a, b]


@numba.njit(cache=True)
def compliant_update(lam, gamma_plus, gamma_pre, rows, normal, C, force, delta, delta_dot, dt, theta, lam0):
    """After the solve (Λ' in ``lam``, γ⁺_eff in ``gamma_plus``, γ⁻_eff in ``gamma_pre``):
    the spring state at the end of the step, F = Λ'/(θΔt), δ = C F, δ̇ by (S3) (zero where
    the contact's normal force and deflection, row ``normal[a]`` of ``rows``, vanish), γ⁺ and γ⁻
    of the bodies (γ_eff − δ̇) and Λ = Λ₀ + Λ' in place."""
    r = rows.shape[0]
    th_dt = theta * dt
    for a in range(r):
        gamma_pre[rows[a]] -= delta_dot[a]
        force[a] = lam[rows[a]] / th_dt
    for a in range(r):
        d = 0.0
        for b in range(r):
            d += C[a, b] * force[b]
        rate = (d - delta[a]) / th_dt - (1.0 - theta) / theta * delta_dot[a]
        gamma_plus[rows[a]] -= rate
        delta[a] = d
        delta_dot[a] = rate
    for a in range(r):
        if force[normal[a]] == 0.0 and delta[normal[a]] == 0.0:
            delta_dot[a] = 0.0
        lam[rows[a]] += lam0[a]


def compliant_problem_reference(G, xi_free, gamma_pre, rows, C, force, delta, delta_dot, fresh, dt, theta):
    """numpy reference of :func:`compliant_problem`; returns new (G, ξ_free, γ⁻, Λ₀, δ)."""
    lam0 = (1.0 - theta) * dt * force
    delta = np.where(fresh, C @ force, delta)
    xi = xi_free + G[:, rows] @ lam0
    xi[rows] -= delta / (theta * dt) + (1.0 - theta) / theta * delta_dot
    gp = gamma_pre.copy()
    gp[rows] += delta_dot
    G2 = G.copy()
    G2[np.ix_(rows, rows)] += C / (theta * dt) ** 2
    return G2, xi, gp, lam0, delta


def compliant_update_reference(lam, gamma_plus, gamma_pre, rows, normal, C, force, delta, delta_dot, dt, theta,
                               lam0):
    """numpy reference of :func:`compliant_update`; returns new (Λ, γ⁺, γ⁻, F, δ, δ̇)."""
    F = lam[rows] / (theta * dt)
    d = C @ F
    rate = (d - delta) / (theta * dt) - (1.0 - theta) / theta * delta_dot
    gp, gm, la = gamma_plus.copy(), gamma_pre.copy(), lam.copy()
    gp[rows] -= rate
    gm[rows] -= delta_dot
    la[rows] += lam0
    rate = np.where((F[normal] == 0.0) & (d[normal] == 0.0), 0.0, rate)
    return la, gp, gm, F, d, rate
