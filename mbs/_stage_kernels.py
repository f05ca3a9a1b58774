"""numba kernels of the step's stages (:mod:`mbs.stages`): which contours and contacts
the contour and detection stages visit, in one call each instead of a Python loop over
every contact (far-apart pairs cost nothing per step); the contact problem's products
(G, ξ_free, γ⁻), the velocity update and the impulses' work, each one call.

Plain-Python or numpy references in the docstrings; ``tests/test_stages.py`` compares them.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def contours_in_use(owner_at, owners, live, out):
    """Indices of the contours with a live owner into ``out``; returns their number.
    Contour k's owning contacts are owners[owner_at[k]:owner_at[k + 1]]. Reference:
    ``[k for k in range(n) if any(live[i] for i in owners of k)]``."""
    n = 0
    for k in range(owner_at.shape[0] - 1):
        for j in range(owner_at[k], owner_at[k + 1]):
            if live[owners[j]]:
                out[n] = k
                n += 1
                break
    return n


@njit(cache=True)
def live_contacts(live, out):
    """Indices i of the live contacts (live[i] True) into ``out``, in order; returns
    their number. Reference: ``np.flatnonzero(live)``."""
    n = 0
    for i in range(live.shape[0]):
        if live[i]:
            out[n] = i
            n += 1
    return n


@njit(cache=True)
def contact_problem_into(W, MW, u_free, u, offset, closing, G, xi_free, gamma_pre):
    """The contact problem of stage 5 from W (nu, m) and M̂⁻¹W (nu, m): G = Wᵀ M̂⁻¹ W
    (m, m) [1/kg], ξ_free = Wᵀ u_free + offset + closing, γ⁻ = Wᵀ u_k + offset (m,)
    [m/s]. Numpy reference: ``W.T @ MW``, ``W.T @ u_free`` ... (``tests/test_stages.py``)."""
    nu, m = W.shape
    for i in range(m):
        for j in range(m):
            s = 0.0
            for k in range(nu):
                s += W[k, i] * MW[k, j]
            G[i, j] = s
        a = 0.0
        b = 0.0
        for k in range(nu):
            a += W[k, i] * u_free[k]
            b += W[k, i] * u[k]
        xi_free[i] = a + offset[i] + closing[i]
        gamma_pre[i] = b + offset[i]


@njit(cache=True)
def velocity_into(u_free, MW, lam, u):
    """u = u_free + M̂⁻¹W Λ (nu,) [m/s] (stage 7; numpy reference ``u_free + MW @ lam``)."""
    nu, m = MW.shape
    for k in range(nu):
        s = 0.0
        for j in range(m):
            s += MW[k, j] * lam[j]
        u[k] = u_free[k] + s


@njit(cache=True)
def impulse_work(lam, gamma_plus, closing, gamma_pre):
    """Λᵀ(γ⁺ − closing + γ⁻)/2 [J]: the impulses' work over the step (stage 6)."""
    s = 0.0
    for i in range(lam.shape[0]):
        s += lam[i] * ((gamma_plus[i] - closing[i]) + gamma_pre[i])
    return 0.5 * s
