"""Mode shapes: lowest eigenpairs of K φ = ω² M φ with the lumped M (thesis Sec. 2.4.4, report eq. 2-3).

Two ways, as thesis Sec. 2.4.4 describes:

* **clamped**: the DOFs of a node group are fixed; the modes satisfy the boundary
  condition, their rows for clamped nodes are zero (thesis Listing 4.2), and K is
  kept unconstrained in the body file.
* **free-free**: the six rigid-body modes (ω ≈ 0) are detected by eigenvalue and
  removed; the elastic modes are then M-orthogonalized against the exact rigid
  modes (translations and rotations about the centre of mass), so they carry no
  rigid motion: Σ m_j φ^j = 0 and Σ m_j (ū0^j − c) × φ^j = 0.

Both are solved with scipy's ARPACK in shift-invert mode and mass-normalized,
Φᵀ M Φ = I, so Φᵀ K Φ = diag(ω²).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from ffrmbs.errors import ModelError

RIGID_TOL = 1e-6  # eigenvalues below RIGID_TOL × largest computed one count as rigid


def rigid_body_modes(u0, masses):
    """The six rigid-body modes (3N, 6), M-orthonormal: three translations, three
    rotations about the centre of mass (report eq. 13-14)."""
    n = len(masses)
    c = masses @ u0 / masses.sum()
    r = u0 - c
    R = np.zeros((n, 3, 6))
    R[:, [0, 1, 2], [0, 1, 2]] = 1.0
    for k in range(3):  # rotation about axis k: e_k × r
        e = np.zeros(3)
        e[k] = 1.0
        R[:, :, 3 + k] = np.cross(e, r)
    R = R.reshape(3 * n, 6)
    return _mass_orthonormalize(R, np.repeat(masses, 3))


def _mass_orthonormalize(V, m3):
    """Columns of V made M-orthonormal (M = diag(m3)) by a Cholesky factor of Vᵀ M V."""
    G = V.T @ (m3[:, None] * V)
    L = la.cholesky(0.5 * (G + G.T), lower=True)
    return la.solve_triangular(L, V.T, lower=True).T


def _eigsh(K, m, k, sigma):
    M = sp.diags(m)
    vals, vecs = sla.eigsh(K.tocsc(), k=k, M=M.tocsc(), sigma=sigma, which="LM")
    order = np.argsort(vals)
    return vals[order], vecs[:, order]


def clamped_dofs(n_dof, clamped_nodes) -> np.ndarray:
    """Boolean mask (n_dof,) of the DOFs of ``clamped_nodes`` (DOF 3*node + direction)."""
    fixed = np.zeros(n_dof, dtype=bool)
    fixed[(3 * np.asarray(clamped_nodes, dtype=np.int64)[:, None] + np.arange(3)).ravel()] = True
    return fixed


def clamped_modes(K, masses, n_modes, clamped_nodes):
    """Lowest ``n_modes`` modes with the DOFs of ``clamped_nodes`` fixed.

    Returns (ω² (n,), Φ (3N, n)) with zero rows at clamped nodes and Φᵀ M Φ = I.
    """
    ndof = K.shape[0]
    fixed = clamped_dofs(ndof, clamped_nodes)
    if not fixed.any():
        raise ModelError("the clamped node group is empty")
    free = ~fixed
    if n_modes >= free.sum():
        raise ModelError(f"{n_modes} modes requested but only {free.sum() - 1} can be computed")
    m3 = np.repeat(masses, 3)
    vals, vecs = _eigsh(K[free][:, free], m3[free], n_modes, sigma=0.0)
    vecs = _mass_orthonormalize(vecs, m3[free])
    phi = np.zeros((ndof, vecs.shape[1]))
    phi[free] = vecs
    return vals, phi


def free_modes(K, masses, u0, n_modes):
    """Lowest ``n_modes`` elastic modes of the unconstrained body.

    The six rigid-body modes are computed with the elastic ones and recognized by
    eigenvalue (|ω²| < RIGID_TOL × the largest computed ω²); exactly six must be
    found, or a ModelError reports the eigenvalues (a mechanism, or a body made of
    unconnected parts, has more). Returns (ω² (n,), Φ (3N, n)), Φᵀ M Φ = I.
    """
    m3 = np.repeat(masses, 3)
    if n_modes + 6 >= K.shape[0]:
        raise ModelError(f"{n_modes} elastic modes requested but the mesh has only {K.shape[0]} DOFs")
    # shift below zero: K − σM is positive definite although K is singular
    sigma = -1e-6 * (K.diagonal().mean() / m3.mean())
    vals, vecs = _eigsh(K, m3, n_modes + 6, sigma=sigma)
    rigid = np.abs(vals) < RIGID_TOL * vals.max()
    if rigid.sum() != 6:
        raise ModelError(
            f"expected 6 rigid-body modes in a free-free body, found {rigid.sum()} "
            f"(lowest eigenvalues ω² = {np.array2string(vals[:8], precision=3)}); "
            "is the mesh connected and free of mechanisms?")
    vals, vecs = vals[~rigid], vecs[:, ~rigid]
    R = rigid_body_modes(u0, masses)
    vecs = vecs - R @ (R.T @ (m3[:, None] * vecs))
    return vals, _mass_orthonormalize(vecs, m3)
