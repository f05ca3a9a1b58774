"""Linear elastic isotropic solid: stiffness, consistent and lumped masses of tet4 / tet10 meshes.

DOF numbering: DOF ``3*j + k`` is node j, direction k (thesis Listing 4.2 layout).

* Stiffness (report eq. 1, thesis eq. 2.36): K = Σ_e ∫ Bᵀ C B dV, assembled
  isoparametrically, written per node pair as
  K_(a i)(b j) = ∫ λ ∂_i N_a ∂_j N_b + μ ∂_j N_a ∂_i N_b + μ δ_ij ∇N_a·∇N_b dV
  with Lamé constants λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)).
* Consistent mass (Zienkiewicz & Taylor, The FEM vol. 1, eq. 16.25): M_FE = M_s ⊗ 1₃ with
  the scalar matrix M_s,ab = Σ_e ∫ ρ N_a N_b dV, so (M_FE)_(3a+i)(3b+j) = δ_ij M_s,ab.
* Lumped masses (report Sec. 3.4.1): row sum of the consistent mass matrix for
  tet4 (ρV/4 per corner); HRZ diagonal scaling for tet10 — the diagonal of the
  consistent mass matrix scaled so that each element keeps its mass ρV_e — since
  row sums give zero or negative corner masses for tet10.

Element quadrature is exact for the polynomial degree of each integrand
(:func:`tet_quadrature`); assembly is vectorized over elements, in chunks.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ffrmbs.errors import ModelError
from preprocess.mesh import TET10_EDGES, Mesh

_CHUNK = 20000  # elements per vectorized block (bounds memory: chunk * 30 * 30 doubles)


def check_positive(name: str, value) -> float:
    """``value`` as a float if it is finite and > 0, else a ModelError naming ``name``."""
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ModelError(f"{name} must be positive and finite, not {value!r}")
    return value


def lame(young, poisson):
    """Lamé constants (λ, μ) [Pa] from Young's modulus E [Pa] and Poisson's ratio ν."""
    check_positive("Young's modulus", young)
    if not -1.0 < poisson < 0.5:
        raise ModelError(f"Poisson's ratio must lie in (-1, 0.5), not {poisson!r}")
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    return lam, young / (2 * (1 + poisson))


def tet_quadrature(degree):
    """Points (Q, 3) in the reference tetrahedron and weights (Q,) exact to ``degree``.

    Degree ≤ 1: centroid; ≤ 2: the symmetric 4-point rule; higher: a collapsed
    (Duffy) Gauss–Legendre product rule with ⌈(degree+3)/2⌉ points per direction,
    ξ = u, η = v(1−u), ζ = w(1−u)(1−v), Jacobian (1−u)²(1−v). Weights sum to 1/6.
    """
    if degree <= 1:
        return np.full((1, 3), 0.25), np.array([1.0 / 6.0])
    if degree <= 2:
        a, b = 0.5854101966249685, 0.1381966011250105
        pts = np.full((4, 3), b)
        pts[[1, 2, 3], [0, 1, 2]] = a
        return pts, np.full(4, 1.0 / 24.0)
    n = math.ceil((degree + 3) / 2)
    x, w = np.polynomial.legendre.leggauss(n)
    x, w = 0.5 * (x + 1), 0.5 * w
    u, v, t = np.meshgrid(x, x, x, indexing="ij")
    wu, wv, wt = np.meshgrid(w, w, w, indexing="ij")
    pts = np.stack([u, v * (1 - u), t * (1 - u) * (1 - v)], axis=-1).reshape(-1, 3)
    weights = (wu * wv * wt * (1 - u) ** 2 * (1 - v)).ravel()
    return pts, weights


def shape_functions(order, pts):
    """Shape functions N (Q, n) and their reference gradients dN (Q, n, 3) at ``pts`` (Q, 3).

    Barycentric L0 = 1−ξ−η−ζ, L1..L3 = ξ, η, ζ. tet4: N_a = L_a. tet10 (canonical
    order of :mod:`preprocess.mesh`): corners L_a(2L_a − 1), mid-edge nodes 4 L_a L_b.
    """
    pts = np.atleast_2d(pts)
    L = np.column_stack([1.0 - pts.sum(axis=1), pts])
    dL = np.array([[-1.0, -1.0, -1.0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    if order == 1:
        return L, np.broadcast_to(dL, (len(pts), 4, 3)).copy()
    a, b = TET10_EDGES[:, 0], TET10_EDGES[:, 1]
    N = np.column_stack([L * (2 * L - 1), 4 * L[:, a] * L[:, b]])
    dN_corner = (4 * L - 1)[:, :, None] * dL[None]
    dN_mid = 4 * (L[:, a, None] * dL[None, b] + L[:, b, None] * dL[None, a])
    return N, np.concatenate([dN_corner, dN_mid], axis=1)


def element_geometry(mesh, tets, degree):
    """The quadrature of the elements ``tets`` (E, n) of ``mesh`` by the rule exact to
    polynomial ``degree`` (:func:`tet_quadrature`, Q points): the weights × det J (E, Q)
    [m³], the shape functions N (Q, n) and their physical gradients ∇N (E, Q, n, 3) [1/m]
    at the points. ModelError for an element whose Jacobian is not positive."""
    pts, w = tet_quadrature(degree)
    N, dN = shape_functions(mesh.order, pts)
    x = mesh.points[tets]  # (E, n, 3)
    J = np.einsum("eni,qnj->eqij", x, dN)  # dx_i / dξ_j
    det = np.linalg.det(J)
    if np.any(det <= 0):
        raise ModelError(f"{mesh.source}: element with non-positive Jacobian (inverted or badly curved)")
    grad = np.einsum("qnj,eqji->eqni", dN, np.linalg.inv(J))
    return w[None, :] * det, N, grad


def stiffness_matrix(mesh: Mesh, young, poisson) -> sp.csr_matrix:
    """Global stiffness K (3N, 3N) [N/m for SI input], CSR, exactly symmetric."""
    lam, mu = lame(young, poisson)
    n = mesh.tets.shape[1]
    rows, cols, vals = [], [], []
    eye = np.eye(3)
    for start in range(0, mesh.n_elements, _CHUNK):
        tets = mesh.tets[start:start + _CHUNK]
        wdet, _, g = element_geometry(mesh, tets, 2 * (mesh.order - 1))
        ke = (lam * np.einsum("eq,eqai,eqbj->eaibj", wdet, g, g)
              + mu * np.einsum("eq,eqaj,eqbi->eaibj", wdet, g, g)
              + mu * np.einsum("eq,eqak,eqbk,ij->eaibj", wdet, g, g, eye))
        dof = (3 * tets[:, :, None] + np.arange(3)).reshape(len(tets), 3 * n)
        rows.append(np.repeat(dof, 3 * n, axis=1).ravel())
        cols.append(np.tile(dof, (1, 3 * n)).ravel())
        vals.append(ke.reshape(len(tets), -1).ravel())
    ndof = 3 * mesh.n_nodes
    K = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(ndof, ndof)).tocsr()
    K = (K + K.T) * 0.5
    K.sum_duplicates()
    K.sort_indices()
    return K


def lumped_masses(mesh: Mesh, density) -> np.ndarray:
    """Lumped node masses m_j [kg for SI input], shape (N,): row sum (tet4), HRZ (tet10)."""
    check_positive("density", density)
    masses = np.zeros(mesh.n_nodes)
    for start in range(0, mesh.n_elements, _CHUNK):
        tets = mesh.tets[start:start + _CHUNK]
        wdet, N, _ = element_geometry(mesh, tets, 2 * mesh.order)
        element_mass = density * wdet.sum(axis=1)  # (E,)
        if mesh.order == 1:
            share = np.einsum("eq,qa->ea", wdet, N) / wdet.sum(axis=1)[:, None]  # row sums
        else:
            diag = np.einsum("eq,qa->ea", wdet, N ** 2)  # consistent-mass diagonal / ρ
            share = diag / diag.sum(axis=1, keepdims=True)
        np.add.at(masses, tets, element_mass[:, None] * share)
    return masses


def consistent_mass_matrix(mesh: Mesh, density) -> sp.csr_matrix:
    """The scalar consistent mass matrix M_s,ab = Σ_e ∫ ρ N_a N_b dV [kg for SI input]
    (module docstring), scipy CSR (N, N), exactly symmetric; M_FE = M_s ⊗ 1₃ in the DOF
    numbering 3*j + k. Quadrature of degree 2·order (exact for straight-sided elements);
    its row sums are the tet4 lumped masses, 1ᵀ M_s 1 the body's mass."""
    check_positive("density", density)
    n = mesh.tets.shape[1]
    rows, cols, vals = [], [], []
    for start in range(0, mesh.n_elements, _CHUNK):
        tets = mesh.tets[start:start + _CHUNK]
        wdet, N, _ = element_geometry(mesh, tets, 2 * mesh.order)
        me = density * np.einsum("eq,qa,qb->eab", wdet, N, N)
        rows.append(np.repeat(tets, n, axis=1).ravel())
        cols.append(np.tile(tets, (1, n)).ravel())
        vals.append(me.ravel())
    M = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(mesh.n_nodes, mesh.n_nodes)).tocsr()
    M = (M + M.T) * 0.5
    M.sum_duplicates()
    M.sort_indices()
    return M


def face_load(mesh: Mesh, nodes, total_force) -> np.ndarray:
    """Consistent nodal forces (N, 3) [N] of a uniform traction on the surface faces
    whose nodes all lie in ``nodes``, summing to ``total_force`` (3,) [N].

    Straight faces: a linear triangle gives each corner area/3 of the traction
    resultant; a quadratic triangle gives its corners 0 and its mid-edge nodes area/3.
    """
    faces = mesh.surface_triangles()
    inside = np.isin(faces, np.asarray(nodes)).all(axis=1)
    faces = faces[inside]
    if len(faces) == 0:
        raise ModelError(f"{mesh.source}: no surface faces lie within the given node group")
    p = mesh.points[faces[:, :3]]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    carriers = faces[:, :3] if mesh.order == 1 else faces[:, 3:]
    weight = np.zeros(mesh.n_nodes)
    np.add.at(weight, carriers, np.repeat(area[:, None] / 3.0, 3, axis=1))
    return np.outer(weight / area.sum(), np.asarray(total_force, dtype=float))
