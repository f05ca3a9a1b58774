"""numba kernels of the residual compliance (:mod:`contours.residual`, eq. C1–C2) and of
a contact's compliance block in its frame (:mod:`mbs.run.residual_contact`); the numpy
references are :func:`compliance_between_reference` and the blocks route of
:meth:`contours.residual.ResidualCompliance.weights` for neutral contours. The blocks of a
derived contour (:func:`offset_weights`) are checked against the full FE static solution
(``tests/unit/preprocess/test_residual_flexibility.py``)."""

from __future__ import annotations

import numba
import numpy as np

from ._offset_kernels import neutral_frame, offset_derivative
from .neutral import _kernels as NK


@numba.njit(cache=True)
def compliance_between(G, Ba, ia, ka, Bb, ib, kb, out):
    """out (3, 3) = Σ_{i<ka} Σ_{j<kb} Ba[i] G[3 ia[i]:+3, 3 ib[j]:+3] Bb[j]ᵀ [m/N]
    (eq. C2) from the residual flexibility G (3 n_P, 3 n_P) and the blocks Ba, Bb
    (k, 3, 3) of two points' control points ia, ib."""
    for r in range(3):
        for c in range(3):
            out[r, c] = 0.0
    for i in range(ka):
        I = 3 * ia[i]
        for j in range(kb):
            J = 3 * ib[j]
            for r in range(3):
                for c in range(3):
                    s = 0.0                       # (Ba_i G_ij Bb_jᵀ)[r, c]
                    for s1 in range(3):
                        a = Ba[i, r, s1]
                        if a == 0.0:
                            continue
                        for s2 in range(3):
                            s += a * G[I + s1, J + s2] * Bb[j, c, s2]
                    out[r, c] += s


def compliance_between_reference(G, Ba, ia, ka, Bb, ib, kb):
    """The numpy reference of :func:`compliance_between`: Bₐ G_sub B_bᵀ with the blocks
    laid side by side."""
    rows = (3 * ia[:ka, None] + np.arange(3)).ravel()
    cols = (3 * ib[:kb, None] + np.arange(3)).ravel()
    A = np.concatenate(list(Ba[:ka]), axis=1)          # (3, 3 ka)
    B = np.concatenate(list(Bb[:kb]), axis=1)          # (3, 3 kb)
    return A @ G[np.ix_(rows, cols)] @ B.T


@numba.njit(cache=True)
def neutral_weights(dim, knots_e, ints, dom, knots_x, eta, xi, Be, Bx, offset, w, index):
    """The blocks B_i = N_i I (k, 3, 3) of eq. C1 on a neutral contour into ``w`` and the
    control points' indices in G_P (their ``offset`` added) at (η, ξ) of a 1s (``dim``
    1) or 2s contour with the geometry arrays of its space (``ints`` = p, n_ctrl, closed
    per direction, ``dom`` the domains); returns k. Be, Bx (3, p + 1) work."""
    pe, ne, ce = ints[0], ints[1], ints[2] != 0
    se = NK.locate(knots_e, pe, ne, ce, dom[0], dom[1], eta, Be)
    k = 0
    if dim == 1:
        for a in range(pe + 1):
            _diagonal(w[k], Be[0, a])
            index[k] = offset + se - pe + a
            k += 1
        return k
    px, nx, cx = ints[3], ints[4], ints[5] != 0
    sx = NK.locate(knots_x, px, nx, cx, dom[2], dom[3], xi, Bx)
    for a in range(pe + 1):
        for b in range(px + 1):
            _diagonal(w[k], Be[0, a] * Bx[0, b])
            index[k] = offset + (se - pe + a) * nx + (sx - px + b)
            k += 1
    return k


@numba.njit(cache=True)
def offset_weights(knots, ints, dom, eta, al, be, ctrl0, n0, offset, B, work, w, index):
    """The blocks B_i = N_i I + N'_i Ğ (k, 3, 3) of eq. C1 on a derived contour at the
    offsets (α, β) [m] from a 1s neutral curve into ``w`` and the control points' indices
    in G_P (their ``offset`` added) into ``index``; returns k. Ğ = α ∂n̄/∂ū_η + β ∂t̄2/∂ū_η
    at the undeformed tangent ū_η = Σ N'_i P_i (P = ``ctrl0`` (n_P, 3) [m], the neutral's
    undeformed control points; ``n0`` its reference normal (3,)), applied column by column
    (:func:`contours._offset_kernels.offset_derivative`). B (3, p + 1) and work (4, 3)."""
    k = neutral_weights(np.int64(1), knots, ints, dom, knots, eta, eta, B, B, offset, w, index)
    a, frame = work[0], work[1:4]
    for c in range(3):
        a[c] = 0.0
    for j in range(k):
        for c in range(3):
            a[c] += B[1, j] * ctrl0[index[j] - offset, c]
    la, lc = neutral_frame(a, n0, frame)
    for col in range(3):                      # Ğ e_col
        g = offset_derivative(frame[0], frame[1], n0, la, lc, al, be, 1.0 if col == 0 else 0.0,
                              1.0 if col == 1 else 0.0, 1.0 if col == 2 else 0.0)
        for j in range(k):
            for r in range(3):
                w[j, r, col] += B[1, j] * g[r]
    return k


@numba.njit(cache=True)
def neutral_between(G, knots_ea, ints_a, dom_a, knots_xa, off_a, eta_a, xi_a,
                    knots_eb, ints_b, dom_b, knots_xb, off_b, eta_b, xi_b, B, w, index, out):
    """c(a, b) (3, 3) [m/N] of two points of neutral contours (eq. C2 with B_i = N_i I):
    each point's blocks by :func:`neutral_weights` (a contour is 1s when its ints hold
    one direction), then :func:`compliance_between`. Work: B (2, 3, p + 1), w (2,
    (p + 1)², 3, 3) and index (2, (p + 1)²)."""
    dim_a = 1 if ints_a.shape[0] == 3 else 2
    dim_b = 1 if ints_b.shape[0] == 3 else 2
    ka = neutral_weights(dim_a, knots_ea, ints_a, dom_a, knots_xa, eta_a, xi_a, B[0], B[1], off_a, w[0], index[0])
    kb = neutral_weights(dim_b, knots_eb, ints_b, dom_b, knots_xb, eta_b, xi_b, B[0], B[1], off_b, w[1], index[1])
    compliance_between(G, w[0], index[0], ka, w[1], index[1], kb, out)


@numba.njit(cache=True)
def _diagonal(block, value):
    """block (3, 3) ← value · I."""
    for r in range(3):
        for c in range(3):
            block[r, c] = value if r == c else 0.0


@numba.njit(cache=True)
def add_contact_block(C, ra, da, rb, db, sign, n_a, T_a, sa, n_b, T_b, sb, A, c, work):
    """C[ra:ra+da, rb:rb+db] += sign R_aᵀ A c Aᵀ R_b with R = [n, T[:, s:]] (3, dim) in
    world axes (s = 0: rows [n, t1, t2]; s = 1: rows [n, t2] of a point kept on a curve),
    A (3, 3) the body rotation, c (3, 3) body axes [m/N]; ``work`` (2, 3, 3)."""
    AcAt, R = work[0], work[1]
    for r in range(3):                       # A c Aᵀ
        for q in range(3):
            s = 0.0
            for i in range(3):
                for j in range(3):
                    s += A[r, i] * c[i, j] * A[q, j]
            AcAt[r, q] = s
    for x in range(db):                      # R = (A c Aᵀ) R_b, column x
        for r in range(3):
            s = 0.0
            for q in range(3):
                s += AcAt[r, q] * (n_b[q] if x == 0 else T_b[q, x - 1 + sb])
            R[r, x] = s
    for y in range(da):
        for x in range(db):
            s = 0.0
            for r in range(3):
                s += (n_a[r] if y == 0 else T_a[r, y - 1 + sa]) * R[r, x]
            C[ra + y, rb + x] += sign * s


@numba.njit(cache=True)
def add_table_blocks(C, G, n_e, ints, blocks, index, signs, normals, tangents, rotations, c, work):
    """Every pair (a, b) of the ``n_e`` compliant sides on one body:
    C[r_a:+d_a, r_b:+d_b] += s_a s_b R_aᵀ A_a c(a, b) A_aᵀ R_b (:func:`add_contact_block`)
    with c(a, b) of eq. C2 from the sides' weight blocks and their points' places in ``G``
    (the bodies' residual flexibilities, block diagonal; :func:`compliance_between`). Per
    side ``ints`` (row r, rows d, body, tangent skip, number of blocks k, first place of
    its body's points in G), its ``blocks`` (k, 3, 3) and ``index`` (k,; places in its
    body's G_P, moved to G here), ``signs``, the contact's n (3,), T (3, 2) and the body
    rotation A (3, 3); ``c`` (3, 3) and ``work`` (2, 3, 3) scratch. The pairs in the order
    of the loop of :func:`mbs.run.residual_contact.assemble`, the same sums."""
    for a in range(n_e):
        for i in range(ints[a, 4]):
            index[a, i] += ints[a, 5]
    for a in range(n_e):
        ra, da, body_a, skip_a, ka = ints[a, 0], ints[a, 1], ints[a, 2], ints[a, 3], ints[a, 4]
        for b in range(n_e):
            if ints[b, 2] != body_a:
                continue
            compliance_between(G, blocks[a], index[a], ka, blocks[b], index[b], ints[b, 4], c)
            add_contact_block(C, ra, da, ints[b, 0], ints[b, 1], signs[a] * signs[b], normals[a], tangents[a], skip_a,
                              normals[b], tangents[b], ints[b, 3], rotations[a], c, work)
