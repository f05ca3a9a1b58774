"""numba kernels of the full-FE contact peer (:mod:`validation.peers.full_fe_contact`):
the sparse internal force, the projection of a point on the faces, and blocks of explicit steps with
the semi-implicit penalty contact. Allocation-free; plain-numpy references of each are
written out in ``tests/integration/test_full_fe_contact.py`` and compared there.

Notation (SI): N nodes, DOF ``3 j + d`` is node j, direction d (as :mod:`preprocess.fe`);
``X`` (N, 3) [m] reference positions, ``u`` (3N,) [m] displacements; ``inv_m3`` (3N,)
[1/kg] the inverse lumped masses, 0 on clamped DOFs (they never move); K in CSR
(``indptr``, ``indices``, ``data`` [N/m]); the point mass m_p [kg] at ``xp`` (3,) [m].

Quadratic 6-node triangle (the faces of :meth:`preprocess.mesh.Mesh.surface_triangles`:
corners c0, c1, c2 at (ξ, η) = (0, 0), (1, 0), (0, 1), then the mid-edge nodes of
(c0, c1), (c1, c2), (c2, c0)); with L0 = 1 − ξ − η, L1 = ξ, L2 = η:

    N = (L0 (2 L0 − 1), L1 (2 L1 − 1), L2 (2 L2 − 1), 4 L0 L1, 4 L1 L2, 4 L2 L0),
    x(ξ, η) = Σ_a N_a (X_a + u_a).

The faces of one contact surface are coplanar at rest; ``axes`` (2, 3) are orthonormal
axes of that plane, ordered so that n0 = axes[0] × axes[1] is its outward normal (for the
beam's top face (e_z, e_x), n0 = e_y).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

NEWTON_ITERATIONS = 30      # Newton iterations of the projection (converges in 2–4)
NEWTON_TOL = 1e-14          # stop when the step |Δ(ξ, η)| falls below this


@njit(cache=True)
def csr_matvec(indptr, indices, data, x, out):
    """out = K x for K in CSR (``indptr`` (n+1,), ``indices``, ``data``); x, out (n,)."""
    for i in range(out.shape[0]):
        s = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            s += data[p] * x[indices[p]]
        out[i] = s


@njit(cache=True)
def tri6_shape(xi, eta, N, dN):
    """Shape functions N (6,) of the quadratic triangle at (ξ, η) and their derivatives
    dN (6, 2) = (∂N/∂ξ, ∂N/∂η) (module docstring)."""
    L0, L1, L2 = 1.0 - xi - eta, xi, eta
    N[0] = L0 * (2.0 * L0 - 1.0)
    N[1] = L1 * (2.0 * L1 - 1.0)
    N[2] = L2 * (2.0 * L2 - 1.0)
    N[3] = 4.0 * L0 * L1
    N[4] = 4.0 * L1 * L2
    N[5] = 4.0 * L2 * L0
    dN[0, 0] = dN[0, 1] = 1.0 - 4.0 * L0
    dN[1, 0], dN[1, 1] = 4.0 * L1 - 1.0, 0.0
    dN[2, 0], dN[2, 1] = 0.0, 4.0 * L2 - 1.0
    dN[3, 0], dN[3, 1] = 4.0 * (L0 - L1), -4.0 * L1
    dN[4, 0], dN[4, 1] = 4.0 * L2, 4.0 * L1
    dN[5, 0], dN[5, 1] = -4.0 * L2, 4.0 * (L0 - L2)


@njit(cache=True)
def _face_point(X, u, face, N, dN, x, tangents):
    """x = Σ N_a x_a and tangents (2, 3) = (x_ξ, x_η) of the deformed face ``face`` (6,)."""
    for d in range(3):
        x[d] = 0.0
        tangents[0, d] = 0.0
        tangents[1, d] = 0.0
    for a in range(6):
        j = face[a]
        for d in range(3):
            xa = X[j, d] + u[3 * j + d]
            x[d] += N[a] * xa
            tangents[0, d] += dN[a, 0] * xa
            tangents[1, d] += dN[a, 1] * xa


@njit(cache=True)
def _newton(xp, X, u, face, axes, xi, eta, N, dN, x, tangents):
    """(ξ, η) where the ray through ``xp`` along the faces' reference normal meets the
    deformed quadratic face: Newton on the two in-plane conditions
    F = A (x(ξ, η) − xp) = 0, A = ``axes`` (2, 3) (orthonormal, spanning the faces'
    reference plane), J = A (x_ξ, x_η), J Δ = −F, from (ξ, η)."""
    for _ in range(NEWTON_ITERATIONS):
        tri6_shape(xi, eta, N, dN)
        _face_point(X, u, face, N, dN, x, tangents)
        j00 = j01 = j10 = j11 = f0 = f1 = 0.0
        for d in range(3):
            j00 += axes[0, d] * tangents[0, d]
            j01 += axes[0, d] * tangents[1, d]
            j10 += axes[1, d] * tangents[0, d]
            j11 += axes[1, d] * tangents[1, d]
            f0 += axes[0, d] * (x[d] - xp[d])
            f1 += axes[1, d] * (x[d] - xp[d])
        det = j00 * j11 - j01 * j10
        dxi = -(j11 * f0 - j01 * f1) / det
        deta = -(j00 * f1 - j10 * f0) / det
        xi += dxi
        eta += deta
        if math.sqrt(dxi * dxi + deta * deta) < NEWTON_TOL:
            break
    return xi, eta


@njit(cache=True)
def project_on_faces(xp, X, u, faces, axes, tol, N, dN, x, tangents, normal):
    """Project the point ``xp`` (3,) [m] onto the deformed quadratic faces ``faces`` (T, 6)
    along their reference normal n0 = axes[0] × axes[1] (module docstring).

    Candidates: faces whose deformed corner triangle, seen along the ray, contains xp up
    to ``tol`` in barycentric units (max(−s, −t, s + t − 1) ≤ tol). On each,
    :func:`_newton` from the flat (s, t); the face whose point lies least outside its
    triangle wins (first on ties: on a shared edge both faces give the same x, the
    surface being C0). Returns (face index, ξ, η, gap g = n0·(xp − x(ξ, η)) [m]) and
    fills N (6,), x (3,) and ``normal`` m = (x_ξ × x_η) / (n0·(x_ξ × x_η)) (3,), the
    deformed face's normal scaled to unit n0-component (so g = m·(xp − x) too, xp − x
    being along n0, and m is ∂g/∂xp); face index −1 (and g = inf) when no face has the
    point within ``tol`` of its triangle (off the faces' footprint).
    """
    best, best_out, best_xi, best_eta = -1, np.inf, 0.0, 0.0
    for f in range(faces.shape[0]):
        c0, c1, c2 = faces[f, 0], faces[f, 1], faces[f, 2]
        a00 = a01 = a10 = a11 = r0 = r1 = 0.0
        for d in range(3):
            p0 = X[c0, d] + u[3 * c0 + d]
            e1 = X[c1, d] + u[3 * c1 + d] - p0
            e2 = X[c2, d] + u[3 * c2 + d] - p0
            a00 += axes[0, d] * e1
            a01 += axes[0, d] * e2
            a10 += axes[1, d] * e1
            a11 += axes[1, d] * e2
            r0 += axes[0, d] * (xp[d] - p0)
            r1 += axes[1, d] * (xp[d] - p0)
        det = a00 * a11 - a01 * a10
        s = (a11 * r0 - a01 * r1) / det
        t = (a00 * r1 - a10 * r0) / det
        if max(-s, -t, s + t - 1.0) > tol:
            continue
        xi, eta = _newton(xp, X, u, faces[f], axes, s, t, N, dN, x, tangents)
        outside = max(-xi, -eta, xi + eta - 1.0)
        if outside < best_out:
            best, best_out, best_xi, best_eta = f, outside, xi, eta
    if best < 0 or best_out > tol:
        return -1, 0.0, 0.0, np.inf
    tri6_shape(best_xi, best_eta, N, dN)
    _face_point(X, u, faces[best], N, dN, x, tangents)
    n0_0 = axes[0, 1] * axes[1, 2] - axes[0, 2] * axes[1, 1]
    n0_1 = axes[0, 2] * axes[1, 0] - axes[0, 0] * axes[1, 2]
    n0_2 = axes[0, 0] * axes[1, 1] - axes[0, 1] * axes[1, 0]
    normal[0] = tangents[0, 1] * tangents[1, 2] - tangents[0, 2] * tangents[1, 1]
    normal[1] = tangents[0, 2] * tangents[1, 0] - tangents[0, 0] * tangents[1, 2]
    normal[2] = tangents[0, 0] * tangents[1, 1] - tangents[0, 1] * tangents[1, 0]
    scale = normal[0] * n0_0 + normal[1] * n0_1 + normal[2] * n0_2
    gap = 0.0
    for d in range(3):
        normal[d] /= scale
        gap += normal[d] * (xp[d] - x[d])
    return best, best_xi, best_eta, gap


@njit(cache=True)
def forces(dt, k, m_p, indptr, indices, data, inv_m3, X, faces, axes, tol, u, v, xp, vp, f, a, ap, work):
    """Accelerations at step n: ``a`` (3N,) [m/s²] of the mesh, ``ap`` (3,) of the point
    mass, from the state (u_n, v_{n−1/2}, xp_n, vp_{n−1/2}); ``f`` (3N,) receives K u_n [N].

    Elastic part: a = −M⁻¹ K u_n (``inv_m3`` = 0 on clamped DOFs). Contact (the
    semi-implicit penalty of :mod:`validation.peers.full_fe_contact`): with the gap g_n,
    normal m and shape functions N_a of the projection of xp_n, the gap Jacobian
    W = (m on the mass, −N_a m on face node a), its Delassus number
    w = Wᵀ M⁻¹ W = |m|² (1/m_p + Σ_a N_a² / m_a) and the gap predicted without contact force,
    g̃ = g_n + Δt Wᵀ (v_{n−1/2} + Δt a), the force

        λ = k max(0, −g̃) / (1 + k Δt² w)   [N]

    is the penalty force k max(0, −g_{n+1}) of the end-of-step gap linearized in W;
    it acts as λ m on the mass and −N_a λ m on the face nodes.

    ``work`` (30,) is scratch for the projection (:func:`_unpack`); after the call its
    N and normal are those of the contact. Returns (λ [N], g_n [m]; inf off the faces).
    """
    csr_matvec(indptr, indices, data, u, f)
    for i in range(a.shape[0]):
        a[i] = -inv_m3[i] * f[i]
    for d in range(3):
        ap[d] = 0.0
    N, dN, x, tangents, normal = _unpack(work)
    face, _, _, gap = project_on_faces(xp, X, u, faces, axes, tol, N, dN, x, tangents, normal)
    if face < 0:
        return 0.0, gap
    mm = normal[0] ** 2 + normal[1] ** 2 + normal[2] ** 2
    w = mm / m_p
    gd = 0.0
    for d in range(3):
        gd += normal[d] * vp[d]
    for b in range(6):
        j = faces[face, b]
        w += mm * N[b] * N[b] * inv_m3[3 * j]
        for d in range(3):
            gd -= N[b] * normal[d] * (v[3 * j + d] + dt * a[3 * j + d])
    g_pred = gap + dt * gd
    if g_pred >= 0.0:
        return 0.0, gap
    lam = -k * g_pred / (1.0 + k * dt * dt * w)
    for d in range(3):
        ap[d] = lam * normal[d] / m_p
    for b in range(6):
        j = faces[face, b]
        for d in range(3):
            a[3 * j + d] -= inv_m3[3 * j + d] * N[b] * lam * normal[d]
    return lam, gap


@njit(cache=True)
def _unpack(work):
    """The scratch arrays of :func:`forces` as views of ``work`` (30,): N (6,),
    dN (6, 2), x (3,), tangents (2, 3), normal (3,)."""
    return (work[0:6], work[6:18].reshape(6, 2), work[18:21], work[21:27].reshape(2, 3),
            work[27:30])


@njit(cache=True)
def advance(n_steps, dt, k, m_p, indptr, indices, data, inv_m3, X, faces, axes, tol, u, v, a, xp, vp, ap, f,
            work, node_dof, track):
    """``n_steps`` central-difference steps (leapfrog) of mesh and point mass, in place:

        v_{n+1/2} = v_{n−1/2} + Δt a_n,   u_{n+1} = u_n + Δt v_{n+1/2}   (mesh; xp, vp alike)
        a_{n+1} = :func:`forces` at (u_{n+1}, v_{n+1/2}, ...).

    On entry and exit u, xp hold step n, v, vp step n − 1/2 and a, ap, f the forces of
    step n. ``track`` (4,) is updated with the per-step extremes and the last gap:
    [min xp_y [m], max |u[node_dof]| [m], min g_n [m], last g_n [m]].
    """
    for _ in range(n_steps):
        for i in range(u.shape[0]):
            v[i] += dt * a[i]
            u[i] += dt * v[i]
        for d in range(3):
            vp[d] += dt * ap[d]
            xp[d] += dt * vp[d]
        gap = forces(dt, k, m_p, indptr, indices, data, inv_m3, X, faces, axes, tol, u, v, xp, vp, f, a, ap,
                     work)[1]
        track[0] = min(track[0], xp[1])
        track[1] = max(track[1], abs(u[node_dof]))
        track[2] = min(track[2], gap)
        track[3] = gap
