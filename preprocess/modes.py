"""Mode shapes: lowest eigenpairs of K φ = ω² M φ (thesis Sec. 2.4.4, report eq. 2-3).

The mass ``masses`` of every function here is either the lumped node masses (N,) [kg],
M = diag(m_j, each repeated 3x), or the scalar consistent mass matrix M_s (N, N) [kg]
as a scipy sparse matrix, M = M_s ⊗ 1₃ (:func:`preprocess.fe.consistent_mass_matrix`,
:func:`preprocess.body.mass_times`). The modes are normalized with the mass given.

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
from threadpoolctl import threadpool_limits

from ffrmbs.errors import ModelError
from preprocess.body import mass_times

RIGID_TOL = 1e-6  # eigenvalues below RIGID_TOL × largest computed one count as rigid


def dof_mass_matrix(masses) -> sp.csr_matrix:
    """M (3N, 3N) sparse of lumped masses (N,) (diagonal) or of a scalar sparse M_s (M_s ⊗ 1₃)."""
    if sp.issparse(masses):
        return sp.kron(masses, sp.identity(3), format="csr")
    return sp.diags(np.repeat(masses, 3)).tocsr()


def rigid_body_modes(u0, masses):
    """The six rigid-body modes (3N, 6), M-orthonormal: three translations, three
    rotations about the centre of mass c = Σ w_j ū0_j / Σ w_j, w = M_s 1 the row sums
    (the masses themselves when lumped) (report eq. 13-14)."""
    n = masses.shape[0]
    w = masses if not sp.issparse(masses) else np.asarray(masses.sum(axis=1)).ravel()
    c = w @ u0 / w.sum()
    r = u0 - c
    R = np.zeros((n, 3, 6))
    R[:, [0, 1, 2], [0, 1, 2]] = 1.0
    for k in range(3):  # rotation about axis k: e_k × r
        e = np.zeros(3)
        e[k] = 1.0
        R[:, :, 3 + k] = np.cross(e, r)
    R = R.reshape(3 * n, 6)
    return _mass_orthonormalize(R, masses)


def _mass_orthonormalize(V, mass):
    """Columns of V made M-orthonormal by a Cholesky factor of Vᵀ M V; ``mass``: lumped
    masses (N,), or any sparse M of V's rows (``mass`` of :func:`preprocess.body.mass_times`)."""
    if sp.issparse(mass) and mass.shape[0] == V.shape[0]:
        G = V.T @ (mass @ V)
    else:
        G = V.T @ mass_times(mass, V)
    L = la.cholesky(0.5 * (G + G.T), lower=True)
    return la.solve_triangular(L, V.T, lower=True).T


def _eigsh(K, M, k, sigma):
    """Shift-invert Lanczos from a fixed generic start vector: without one ARPACK draws it
    from a generator whose state depends on earlier calls, and the same mesh gave modes
    differing in the last digits from one run (or call order) to the next. A singular
    K − σM (which the mesh checks of :func:`preprocess.pipeline.build_body` should have
    caught) is a ModelError. ``M``: the sparse mass matrix of K's DOFs. One BLAS thread:
    the iteration's vector operations and SuperLU's solves are too small to gain from
    more, and on a busy machine their spin-waiting costs more than the work (the default
    beam's 40 modes: 10.6 CPU s with two threads on two loaded cores, 5.8 s with one)."""
    v0 = np.random.default_rng(0).standard_normal(K.shape[0])
    try:
        with threadpool_limits(limits=1, user_api="blas"):
            vals, vecs = sla.eigsh(K.tocsc(), k=k, M=M.tocsc(), sigma=sigma, which="LM", v0=v0)
    except RuntimeError as exc:     # SuperLU: "Factor is exactly singular"
        if "singular" not in str(exc):
            raise
        raise ModelError("the stiffness matrix is singular (K - σM cannot be factored): part of the body "
                         "moves without deforming, i.e. a part with no clamped node, a mechanism, or too "
                         "few clamped nodes (one clamped node leaves the rotations free)") from None
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
    M = dof_mass_matrix(masses)[free][:, free]
    vals, vecs = _eigsh(K[free][:, free], M, n_modes, sigma=0.0)
    vecs = _mass_orthonormalize(vecs, M)
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
    M = dof_mass_matrix(masses)
    if n_modes + 6 >= K.shape[0]:
        raise ModelError(f"{n_modes} elastic modes requested but the mesh has only {K.shape[0]} DOFs")
    # shift below zero: K − σM is positive definite although K is singular
    sigma = -1e-6 * (K.diagonal().mean() / M.diagonal().mean())
    vals, vecs = _eigsh(K, M, n_modes + 6, sigma=sigma)
    rigid = np.abs(vals) < RIGID_TOL * vals.max()
    if rigid.sum() != 6:
        raise ModelError(
            f"expected 6 rigid-body modes in a free-free body, found {rigid.sum()} "
            f"(lowest eigenvalues ω² = {np.array2string(vals[:8], precision=3)}); "
            "is the mesh connected and free of mechanisms?")
    vals, vecs = vals[~rigid], vecs[:, ~rigid]
    R = rigid_body_modes(u0, masses)
    vecs = vecs - R @ (R.T @ (M @ vecs))
    return vals, _mass_orthonormalize(vecs, M)


def all_modes(stiffness, masses, clamped_nodes=None, u0=None, max_dof=6000):
    """ALL elastic modes of a small model by a dense eigensolve (report Sec. 4.3).

    The reference "all modes" set of the 90 % effective-mass criterion (report
    eq. 36, Sec. 5.3). K φ = ω² M φ with the lumped M = diag(m3) is solved as the
    equivalent symmetric standard problem (M^-1/2 K M^-1/2) ψ = ω² ψ, φ = M^-1/2 ψ,
    with scipy.linalg.eigh; with a consistent M (``masses`` a sparse M_s) as the
    generalized problem by scipy.linalg.eigh(K, M). The φ are M-orthonormal, Φᵀ M Φ = I.

    * clamped (``clamped_nodes`` given): the clamped DOFs are removed; rows of Φ
      at clamped nodes are zero, as in :func:`clamped_modes`.
    * free (``clamped_nodes=None``, ``u0`` needed): the problem is restricted to the
      M-orthogonal complement of the six exact rigid-body modes
      (:func:`rigid_body_modes`, report eq. 13-14), so no eigenvalue threshold is
      needed to drop them, as :func:`free_modes` does by eigenvalue.

    Parameters: ``stiffness`` K (3N, 3N) [N/m] (sparse or dense), ``masses`` (N,)
    [kg] or sparse M_s (N, N) [kg] (module docstring), ``clamped_nodes`` node indices
    or None, ``u0`` (N, 3) [m].
    Returns (ω² (n,) [rad²/s²] ascending, Φ (3N, n) [kg^-1/2]) with n = free DOFs
    (clamped) or 3N − 6 (free). A ModelError is raised above ``max_dof`` free DOFs
    (the solve holds about five dense n x n matrices of 8 n² bytes each and takes
    O(n³) time) and when a zero eigenvalue remains (a mechanism, unconnected parts,
    or an empty clamp).
    """
    if not sp.issparse(masses):
        masses = np.asarray(masses, dtype=float)
    ndof = 3 * masses.shape[0]
    if stiffness.shape != (ndof, ndof):
        raise ModelError(f"stiffness is {stiffness.shape}, expected ({ndof}, {ndof}) for {ndof // 3} nodes")
    free = np.ones(ndof, dtype=bool) if clamped_nodes is None else ~clamped_dofs(ndof, clamped_nodes)
    n_free = int(free.sum())
    if n_free > max_dof:
        raise ModelError(
            f"all_modes: {n_free} free DOFs exceed max_dof={max_dof}; the dense eigensolve needs "
            f"~{5 * 8 * n_free ** 2 / 1e9:.1f} GB and O(n³) time — use a coarser mesh or raise max_dof")
    if clamped_nodes is None and u0 is None:
        raise ModelError("all_modes of a free body needs the node positions u0 to remove the rigid-body modes")
    K = stiffness.toarray() if sp.issparse(stiffness) else np.asarray(stiffness, dtype=float)
    solve = _dense_consistent if sp.issparse(masses) else _dense_lumped
    vals, phi_free = solve(K, masses, free, None if clamped_nodes is not None else np.asarray(u0, float))
    if vals[0] <= 1e-10 * vals[-1]:
        raise ModelError(
            f"all_modes: zero eigenvalue ω² = {vals[0]:.3g} among the elastic modes (largest {vals[-1]:.3g}); "
            "is the mesh connected, free of mechanisms and sufficiently clamped?")
    phi = np.zeros((ndof, vals.size))
    phi[free] = phi_free
    return vals, phi


def _dense_lumped(K, masses, free, u0):
    """(ω², Φ on the free DOFs) of :func:`all_modes` with lumped masses (N,): the standard
    problem of M^-1/2 K M^-1/2; ``u0`` given (a free body): on the M-orthogonal complement
    of the rigid modes."""
    m3 = np.repeat(masses, 3)
    s = 1.0 / np.sqrt(m3[free])
    A = s[:, None] * K[np.ix_(free, free)] * s[None, :]
    if u0 is not None:
        Q = la.qr(np.sqrt(m3)[:, None] * rigid_body_modes(u0, masses), mode="full")[0][:, 6:]
        vals, V = la.eigh(Q.T @ A @ Q)
        V = Q @ V
    else:
        vals, V = la.eigh(A)
    return vals, s[:, None] * V


def _dense_consistent(K, M_s, free, u0):
    """(ω², Φ on the free DOFs) of :func:`all_modes` with a scalar sparse M_s: the
    generalized problem K φ = ω² M φ; ``u0`` given (a free body): restricted to the
    null space Q of (M R)ᵀ (Q orthonormal), eigh(Qᵀ K Q, Qᵀ M Q), Φ = Q V."""
    M = dof_mass_matrix(M_s).toarray()[np.ix_(free, free)]
    K = K[np.ix_(free, free)]
    if u0 is None:
        return la.eigh(K, M)
    Q = la.qr(M @ rigid_body_modes(u0, M_s), mode="full")[0][:, 6:]
    vals, V = la.eigh(Q.T @ K @ Q, Q.T @ M @ Q)
    return vals, Q @ V
