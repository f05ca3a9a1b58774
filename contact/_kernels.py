"""numba kernels of the prox iterations of :mod:`contact.solver` (Studer 2009, ch. 6).

The contact problem is encoded in arrays: ``kinds`` (n_e,) int64 of the entries
(``BILATERAL`` one scalar row, ``UNILATERAL`` one normal row, ``COULOMB`` rows
[N, T1, T2]), their first rows ``offsets`` (n_e,) int64 and friction coefficients
``mu`` (n_e,). The law's velocity is affine in Λ: ξ = c + G Λ with
c = ξ_free + ε γ⁻ (m,) [m/s]; ``r`` (m,) [kg] holds the prox factors (equal on T1, T2).
Every kernel works in place and allocates nothing. Each returns the largest scaled change
max_i |Λ_i^new − Λ_i| / r_i [m/s], the natural-map residual of the rows it visited.
The plain-numpy reference, built on the laws' ``project``, is in the tests.
"""

from __future__ import annotations

import math

from numba import njit

BILATERAL = 0
UNILATERAL = 1
COULOMB = 2


@njit(cache=True)
def _row_velocity(G, c, lam, i):
    """ξ_i = c_i + Σ_j G_ij Λ_j."""
    s = c[i]
    for j in range(lam.shape[0]):
        s += G[i, j] * lam[j]
    return s


@njit(cache=True)
def _disk(z1, z2, radius):
    """Projection of (z1, z2) onto the disk of radius ``radius`` >= 0."""
    norm = math.hypot(z1, z2)
    if norm > radius:
        scale = radius / norm
        return z1 * scale, z2 * scale
    return z1, z2


@njit(cache=True)
def _finite(x):
    for v in x:
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True)
def velocities(G, c, lam, xi):
    """ξ = c + G Λ into ``xi`` (m,)."""
    for i in range(lam.shape[0]):
        xi[i] = _row_velocity(G, c, lam, i)


@njit(cache=True)
def prox_step(xi, r, kinds, offsets, mu, lam, update):
    """Λ ← prox_C(Λ − r ξ) for all entries at once from the given ``xi`` (Jacobi).

    With ``update`` False ``lam`` is left alone and the return value is the natural-map
    residual max_i |Λ_i − prox_C(Λ − r ξ)_i| / r_i [m/s] of the current Λ.
    """
    change = 0.0
    for k in range(kinds.shape[0]):
        o = offsets[k]
        z = lam[o] - r[o] * xi[o]
        if kinds[k] != BILATERAL:
            z = max(z, 0.0)
        change = max(change, abs(z - lam[o]) / r[o])
        if kinds[k] == COULOMB:
            z1, z2 = _disk(lam[o + 1] - r[o + 1] * xi[o + 1],
                           lam[o + 2] - r[o + 2] * xi[o + 2], mu[k] * z)
            change = max(change, abs(z1 - lam[o + 1]) / r[o + 1],
                         abs(z2 - lam[o + 2]) / r[o + 2])
            if update:
                lam[o + 1] = z1
                lam[o + 2] = z2
        if update:
            lam[o] = z
    return change


@njit(cache=True)
def gauss_seidel_sweep(G, c, r, kinds, offsets, mu, lam):
    """One projected Gauss–Seidel sweep over the entries, in place.

    Each row's ξ_i uses the newest Λ; in a Coulomb entry the normal row goes first and
    the tangential pair then uses the new Λ_N both in ξ_T and in the disk radius μ Λ_N.
    """
    change = 0.0
    for k in range(kinds.shape[0]):
        o = offsets[k]
        z = lam[o] - r[o] * _row_velocity(G, c, lam, o)
        if kinds[k] != BILATERAL:
            z = max(z, 0.0)
        change = max(change, abs(z - lam[o]) / r[o])
        lam[o] = z
        if kinds[k] == COULOMB:
            xi1 = _row_velocity(G, c, lam, o + 1)
            xi2 = _row_velocity(G, c, lam, o + 2)
            z1, z2 = _disk(lam[o + 1] - r[o + 1] * xi1, lam[o + 2] - r[o + 2] * xi2, mu[k] * z)
            change = max(change, abs(z1 - lam[o + 1]) / r[o + 1],
                         abs(z2 - lam[o + 2]) / r[o + 2])
            lam[o + 1] = z1
            lam[o + 2] = z2
    return change


@njit(cache=True)
def prox_iterate(G, c, r, kinds, offsets, mu, lam, xi, jacobi, tol_v, max_iter):
    """Sweep until the scaled change and then the natural residual are <= ``tol_v`` [m/s].

    ``xi`` (m,) is a work array. Returns (sweeps, residual, converged); the residual is
    the natural-map residual of the returned Λ (one extra G Λ per check).
    """
    residual = math.inf
    for it in range(1, max_iter + 1):
        if jacobi:
            velocities(G, c, lam, xi)
            change = prox_step(xi, r, kinds, offsets, mu, lam, True)
        else:
            change = gauss_seidel_sweep(G, c, r, kinds, offsets, mu, lam)
        if not _finite(lam):
            return it, math.inf, False
        if change <= tol_v:
            velocities(G, c, lam, xi)
            residual = prox_step(xi, r, kinds, offsets, mu, lam, False)
            if residual <= tol_v:
                return it, residual, True
    velocities(G, c, lam, xi)
    residual = prox_step(xi, r, kinds, offsets, mu, lam, False)
    return max_iter, residual, residual <= tol_v
