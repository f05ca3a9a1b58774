"""Static and residual flexibility of an FE model (static correction of a modal model).

A modally reduced body keeps n modes Φ (3N, n) of K φ = ω² M φ. Under a force f its
static deflection is Φ K_n⁻¹ Φᵀ f (K_n = Φᵀ K Φ); the full model's is G f with the
static flexibility G. The modes left out carry the difference, the **residual
flexibility** (MacNeal 1971; Craig & Kurdila 2006, Sec. 17.4)

    G_res = G − Φ K_n⁻¹ Φᵀ                                             (R1)

which is symmetric, positive semi-definite, and equal to Σ_{dropped} φ φᵀ / ω² when Φ
holds exact eigenvectors. G is

* **clamped** (some DOFs fixed): G = K_ff⁻¹ on the free DOFs, zero rows and columns at
  the clamped ones (R2);
* **free-free** (inertia relief): the flexibility of the elastic modes only,
  G = Σ_{elastic} φ φᵀ / ω², so that G f carries no rigid motion. With R (3N, 6) the
  M-orthonormal rigid modes (:func:`preprocess.modes.rigid_body_modes`), u = G f solves
  the bordered system

      [ K      M R ] [u]   [f]
      [ Rᵀ M   0   ] [μ] = [0]                                          (R3)

  the last rows make u M-orthogonal to R, and μ = Rᵀ f removes from f the part that
  would accelerate the body rigidly (the loads are balanced by the inertia of the
  rigid motion, hence "inertia relief").

Both are solved with one sparse LU factorization (:class:`StaticFlexibility`). A
contour needs G_res only on the loads it can apply: with a transfer matrix T (3N, m)
whose columns are nodal load patterns (for a NURBS contour, a unit force on one
control point spread over the contour's nodes by the fitting matrix), the reduced
residual flexibility is Tᵀ G_res T (m, m): :func:`projected_flexibility` solves Tᵀ G T
(independent of the modes kept), :func:`residual_flexibility` removes the kept modes.

A clamped body's Tᵀ G T needs no solve at all (:func:`clamped_projected_flexibility`):
with the free DOFs the loads act on (T's non-zero rows, c) ordered after the others (i),
the LU factor K_ff = L U holds in its trailing blocks the Schur complement

    L_cc U_cc = S = K_cc − K_ci K_ii⁻¹ K_ic,     (K_ff⁻¹)_cc = S⁻¹,
    Tᵀ G T = T_cᵀ U_cc⁻¹ L_cc⁻¹ T_c                                       (R4)

(block inverse; T_c the rows c of T), so the factorization alone gives it, and the
|c| × |c| triangular inverses replace the m solves through the whole factor.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from threadpoolctl import threadpool_limits

from ffrmbs.errors import ModelError

from .body import mass_times
from .modes import clamped_dofs, rigid_body_modes


#: smallest |pivot| of the LU factor, relative to the largest, of a regular stiffness matrix
SINGULAR_PIVOT = 1e-12


def factor(matrix, **options):
    """SuperLU's LU factor of a stiffness ``matrix`` (sparse CSC; ``options`` of
    ``scipy.sparse.linalg.splu``); ModelError when it is singular, or nearly (smallest
    |pivot| below ``SINGULAR_PIVOT`` of the largest): the supports do not hold the body."""
    try:
        lu = sla.splu(matrix, **options)
        pivots = np.abs(lu.U.diagonal())
        if not pivots.min() > SINGULAR_PIVOT * pivots.max():
            raise RuntimeError(f"pivot ratio {pivots.min() / pivots.max():.2g}")
    except RuntimeError as exc:            # SuperLU: "Factor is exactly singular", or nearly
        raise ModelError("the static flexibility cannot be computed: the stiffness matrix is singular "
                         f"with the body's supports ({exc}); clamp enough nodes to hold the body") from None
    return lu


class StaticFlexibility:
    """The static flexibility G of an FE model, factored once (module docstring, R2/R3).

    Parameters
    ----------
    stiffness : (3N, 3N) sparse [N/m]
        The unconstrained stiffness matrix K.
    masses : (N,) or sparse (N, N) [kg]
        The body's mass, lumped node masses or the scalar consistent M_s (the inertia
        relief M R of a free-free body, eq. R3; see :mod:`preprocess.modes`).
    u0 : (N, 3) [m]
        Node positions (the rigid modes of a free-free body).
    clamped_nodes : int array or None
        Nodes whose DOFs are fixed; None or empty: a free-free body.
    """

    def __init__(self, stiffness, masses, u0, clamped_nodes=None):
        K = sp.csc_matrix(stiffness)
        n_dof = K.shape[0]
        self.n_dof = n_dof
        self.clamped = clamped_nodes is not None and len(clamped_nodes) > 0
        if self.clamped:
            self.free = ~clamped_dofs(n_dof, clamped_nodes)
            self._lu = factor(K[self.free][:, self.free].tocsc())
        else:
            mass = masses if sp.issparse(masses) else np.asarray(masses, float)
            self.rigid = rigid_body_modes(np.asarray(u0, float), mass)
            MR = mass_times(mass, self.rigid)
            self._lu = factor(sp.bmat([[K, sp.csc_matrix(MR)], [sp.csc_matrix(MR.T), None]], format="csc"))

    def solve(self, forces) -> np.ndarray:
        """Displacements G f (3N, m) [m] of load columns ``forces`` (3N, m) [N]."""
        f = np.asarray(forces, dtype=float).reshape(self.n_dof, -1)
        if self.clamped:
            u = np.zeros_like(f)
            u[self.free] = self._lu.solve(np.asfortranarray(f[self.free]))
            return u
        rhs = np.asfortranarray(np.vstack([f, np.zeros((6, f.shape[1]))]))
        return self._lu.solve(rhs)[:self.n_dof]


#: load columns solved at once by :func:`projected_flexibility` (bounds its memory)
CHUNK = 64


def projected_flexibility(flexibility: StaticFlexibility, transfer) -> np.ndarray:
    """Tᵀ G T (m, m) [m/N] of load patterns ``transfer`` T (3N, m) (dense or sparse),
    solved ``CHUNK`` columns at a time; symmetrized.

    The triangular solves run on one BLAS thread: SuperLU's supernode blocks are small,
    so more threads add no speed, and on a busy machine their spin-waiting costs many
    times the work (the default beam's 1107 columns: 47 CPU s with two threads on two
    loaded cores, 5.5 CPU s with one)."""
    T = sp.csc_matrix(transfer)
    m = T.shape[1]
    out = np.empty((m, m))
    with threadpool_limits(limits=1, user_api="blas"):
        for a in range(0, m, CHUNK):
            b = min(a + CHUNK, m)
            out[:, a:b] = T.T @ flexibility.solve(T[:, a:b].toarray())
    return 0.5 * (out + out.T)


#: SuperLU on a symmetric positive definite matrix: pivots on the diagonal, in the order given
SYMMETRIC = dict(diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))


def clamped_projected_flexibility(stiffness, clamped_nodes, transfer) -> np.ndarray:
    """Tᵀ G T (m, m) [m/N] of a clamped body (G = K_ff⁻¹, eq. R2) for load patterns
    ``transfer`` T (3N, m) from one factorization, through the Schur complement on the
    loaded DOFs (eq. R4): the loaded DOFs c ordered last, the others in SuperLU's
    minimum-degree order of K_ii (a factorization of K_ii finds it). Equal to
    :func:`projected_flexibility` to rounding, without its m solves. Symmetrized.
    ModelError for supports that do not hold the body."""
    K = sp.csc_matrix(stiffness)
    T = sp.csr_matrix(transfer)
    free = ~clamped_dofs(K.shape[0], clamped_nodes)
    loaded = np.zeros(K.shape[0], dtype=bool)
    loaded[T.nonzero()[0]] = True
    loaded &= free
    inner, outer = np.flatnonzero(free & ~loaded), np.flatnonzero(loaded)
    with threadpool_limits(limits=1, user_api="blas"):
        if inner.size:
            lu_inner = factor(K[inner][:, inner].tocsc(), permc_spec="MMD_AT_PLUS_A", **SYMMETRIC)
            inner = inner[np.argsort(lu_inner.perm_c)]         # column j of K_ii is at perm_c[j]
        order = np.concatenate([inner, outer])
        lu = factor(K[order][:, order].tocsc(), permc_spec="NATURAL", **SYMMETRIC)
        S_inv = _trailing_inverse(lu, outer.size)
        T_c = T[outer]
        out = T_c.T @ (S_inv @ T_c)
    return 0.5 * (out + out.T)


def _trailing_inverse(lu, c) -> np.ndarray:
    """The trailing c × c block of A⁻¹ (A = L U, SuperLU's ``lu``): U_cc⁻¹ L_cc⁻¹ when SuperLU
    kept the trailing rows and columns in place (eq. R4), else c solves through the factor."""
    n = lu.shape[0]
    kept = np.arange(n - c, n)
    if np.array_equal(lu.perm_c[kept], kept) and np.array_equal(lu.perm_r[kept], kept):
        L = lu.L[n - c:, n - c:].toarray()
        U = lu.U[n - c:, n - c:].toarray()
        return la.solve_triangular(U, la.solve_triangular(L, np.eye(c), lower=True, unit_diagonal=True))
    unit = np.zeros((n, c))
    unit[kept, np.arange(c)] = 1.0
    return lu.solve(unit)[kept]


def residual_flexibility(projected, phi_t, modal_stiffness) -> np.ndarray:
    """Tᵀ G_res T = Tᵀ G T − (Φᵀ T)ᵀ K_n⁻¹ (Φᵀ T) (m, m) [m/N] (eq. R1) from the projected
    flexibility Tᵀ G T (m, m) (:func:`projected_flexibility`), Φᵀ T (n, m) of the kept
    modes and their stiffness K_n = Φᵀ K Φ (n, n); symmetrized."""
    out = np.array(projected, dtype=float)
    if phi_t.shape[0]:
        out -= phi_t.T @ np.linalg.solve(modal_stiffness, phi_t)
    return 0.5 * (out + out.T)


def clamped_nodes_of(data) -> np.ndarray:
    """The clamped nodes of body data: the preprocessor's ``clamp`` group (``params``), else
    the nodes whose rows of Φ are zero in every mode (thesis Listing 4.2: clamped nodes
    have zero rows); empty for a free-free body."""
    group = data.params.get("clamp") if data.params else None
    if group:
        if group not in data.node_groups:
            raise ModelError(f"the body's clamped node group {group!r} is not in its node groups")
        return np.asarray(data.node_groups[group], dtype=np.int64)
    if data.params and data.params.get("free"):
        return np.zeros(0, dtype=np.int64)
    rows = np.abs(data.phi).reshape(data.n_nodes, -1).max(axis=1) if data.n_modes else np.ones(data.n_nodes)
    return np.flatnonzero(rows == 0.0).astype(np.int64)
