"""Dense symmetric positive definite solves in numba, allocation-free: the Cholesky factor
A = L Lᵀ written into a caller-owned L, and the two triangular solves (Golub & Van Loan,
Matrix Computations, Alg. 4.2.1 and 3.1.1/3.1.2), also block by block for a
block-diagonal matrix (the Moreau iteration matrix when no force element couples the
bodies: one block per body, so that its cost is Σ n_b², not n²). The iteration matrices of the
integrators (M + θΔt D + θ²Δt² K; M + βh²c K + γhc D) are small, dense and SPD: these
kernels solve them without a LAPACK call's Python overhead. Reference: scipy.linalg
``cho_factor`` / ``cho_solve`` (tests).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SHORT_ROW = 32          # rows (blocks) shorter than this: one running sum, dot-form sweeps


@njit(cache=True)
def cholesky_into(A, L):
    """Lower Cholesky factor of the symmetric (n, n) ``A`` (only its lower triangle is
    read) into ``L`` (n, n; the strict upper triangle is set to zero). Returns 0, or
    j + 1 when the leading (j+1) × (j+1) minor is not positive definite to working
    precision: its pivot a_jj − Σ_k l_jk² is at most n ε a_jj (like LAPACK's ``info``,
    with a rounding-level margin, so a matrix singular but for rounding is reported,
    not factored); L is then incomplete. ``L`` may be ``A``."""
    return cholesky_block(A, L, np.int64(0), A.shape[0])


@njit(cache=True)
def cholesky_block(A, L, lo, hi):
    """:func:`cholesky_into` of the diagonal block A[lo:hi, lo:hi] into the same block of
    ``L``, indexed in place (a block view would give the kernel a second array layout to
    compile for); returns 0 or the block's j + 1."""
    n = hi - lo
    tol = n * 2.220446049250313e-16
    for j in range(n):
        s = A[lo + j, lo + j]
        floor = tol * abs(s)
        for k in range(j):
            s -= L[lo + j, lo + k] * L[lo + j, lo + k]
        if not s > floor:
            return j + 1
        d = math.sqrt(s)
        L[lo + j, lo + j] = d
        for i in range(j + 1, n):
            s = A[lo + i, lo + j]
            for k in range(j):
                s -= L[lo + i, lo + k] * L[lo + j, lo + k]
            L[lo + i, lo + j] = s / d
    for i in range(n):
        for j in range(i + 1, n):
            L[lo + i, lo + j] = 0.0
    return 0


@njit(cache=True)
def row_dot(A, i, x, lo, hi):
    """Σ_{k=lo}^{hi−1} A[i, k] x[k] in four interleaved partial sums (k mod 4) added
    pairwise at the end: the summation order of the long row products (SHORT_ROW
    entries or more) of the step's kernels. One running sum chains every addition on the
    one before (a latency-bound loop, several times slower for rows of hundreds of
    entries); four independent ones overlap, but cost more than they save on short rows,
    which the callers sum in one running sum."""
    s0 = s1 = s2 = s3 = 0.0
    k = lo
    while k + 3 < hi:
        s0 += A[i, k] * x[k]
        s1 += A[i, k + 1] * x[k + 1]
        s2 += A[i, k + 2] * x[k + 2]
        s3 += A[i, k + 3] * x[k + 3]
        k += 4
    while k < hi:
        s0 += A[i, k] * x[k]
        k += 1
    return (s0 + s1) + (s2 + s3)


@njit(cache=True)
def cho_solve_rows(L, lo, hi, B, X, c):
    """Column c of X = (L Lᵀ)⁻¹ B on the rows [lo, hi) of one diagonal block of a
    C-ordered L (no view is made: per-block slices cost numba a view each, which a
    many-body block solve would pay per body); ``X`` may be ``B``. A block of SHORT_ROW
    rows or more is solved along L's rows in both sweeps — L y = b by :func:`row_dot`,
    Lᵀ x = y as x_i = y_i / L_ii, then y_k −= L_ik x_i for k < i — so that a body of
    hundreds of modes reads L contiguously and without one long chain of additions; a
    smaller block in two dot-form sweeps with one running sum each."""
    if hi - lo >= SHORT_ROW:
        cho_solve_long_rows(L, lo, hi, B, X, c)
        return
    for i in range(lo, hi):
        s = B[i, c]
        for k in range(lo, i):
            s -= L[i, k] * X[k, c]
        X[i, c] = s / L[i, i]
    for i in range(hi - 1, lo - 1, -1):
        s = X[i, c]
        for k in range(i + 1, hi):
            s -= L[k, i] * X[k, c]
        X[i, c] = s / L[i, i]


@njit(cache=True, inline="never")
def cho_solve_long_rows(L, lo, hi, B, X, c):
    """:func:`cho_solve_rows` of a block of SHORT_ROW rows or more, along L's rows."""
    x = X[:, c]
    for i in range(lo, hi):
        X[i, c] = (B[i, c] - row_dot(L, i, x, lo, i)) / L[i, i]
    for i in range(hi - 1, lo - 1, -1):
        xi = X[i, c] / L[i, i]
        X[i, c] = xi
        for k in range(lo, i):
            X[k, c] -= L[i, k] * xi


@njit(cache=True)
def cho_solve_vector(L, b, x):
    """x = (L Lᵀ)⁻¹ b for b, x (n,); ``x`` may be ``b``."""
    cho_solve_rows(L, np.int64(0), L.shape[0], b.reshape(-1, 1), x.reshape(-1, 1), np.int64(0))


@njit(cache=True)
def cho_solve_matrix(L, B, X):
    """X = (L Lᵀ)⁻¹ B for B, X (n, m), column by column; ``X`` may be ``B``."""
    for c in range(B.shape[1]):
        cho_solve_rows(L, np.int64(0), L.shape[0], B, X, c)


def cho_solve_into(L, b, x):
    """x = (L Lᵀ)⁻¹ b for a vector (n,) or a matrix (n, m) right-hand side ``b`` (``x``
    of the same shape, may be ``b``); L from :func:`cholesky_into`."""
    if b.ndim == 1:
        cho_solve_vector(L, b, x)
    else:
        cho_solve_matrix(L, b, x)


@njit(cache=True)
def block_cholesky_into(A, blocks, L):
    """:func:`cholesky_into` of each diagonal block A[a:b, a:b] of (n, n) ``A`` into the
    same block of ``L``, (a, b) the rows of ``blocks`` (k, 2); the rest of L is not
    read by the block solves. Returns 0, or the first row a + j + 1 whose pivot fails."""
    for k in range(blocks.shape[0]):
        a, b = blocks[k, 0], blocks[k, 1]
        info = cholesky_block(A, L, a, b)
        if info:
            return a + info
    return 0


@njit(cache=True)
def block_cho_solve_vector(L, blocks, idle, b, x):
    """x = A⁻¹ b block by block (L from :func:`block_cholesky_into`), zero on the rows
    ``idle`` outside every block; b, x (n,), ``x`` may be ``b``."""
    block_cho_solve_matrix(L, blocks, idle, b.reshape(-1, 1), x.reshape(-1, 1))


@njit(cache=True)
def block_cho_solve_matrix(L, blocks, idle, B, X):
    """X = A⁻¹ B column by column (:func:`block_cho_solve_vector`); B, X (n, m), ``X``
    may be ``B``."""
    for c in range(B.shape[1]):
        for k in range(blocks.shape[0]):
            cho_solve_rows(L, blocks[k, 0], blocks[k, 1], B, X, c)
        for i in idle:
            X[i, c] = 0.0


@njit(cache=True)
def block_iteration_factor(M, K0, D0, a, b, blocks, A, L):
    """A = (M + a D0) + b K0 (n, n) — the iteration matrix M̂ = M + θΔt D + θ²Δt² K with
    a = θΔt [s], b = θ²Δt² [s²] and the bodies' constant tangents K0, D0 — and its
    :func:`block_cholesky_into` factor into ``L``; returns its info. Numpy reference: the
    same sums with ``np.multiply``/``np.add`` (:func:`mbs.run.stages._factor`)."""
    n = M.shape[0]
    for i in range(n):
        for j in range(n):
            A[i, j] = (M[i, j] + D0[i, j] * a) + K0[i, j] * b
    return block_cholesky_into(A, blocks, L)
