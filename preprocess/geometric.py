"""Geometric (stress) stiffness of an FE model under the inertia loads of a moving frame.

A body whose frame turns at Ω, accelerates angularly at Ω̇ and translates with the
acceleration a (all in body axes) carries, in its own frame, the body force density

    b(x) = −ρ [a + Ω̇ × x + Ω × (Ω × x)]                                    (G1)

at the undeformed position x = ū0. It is linear in the twelve **load parameters**

    p = (Ω_x², Ω_y², Ω_z², Ω_xΩ_y, Ω_xΩ_z, Ω_yΩ_z, Ω̇_x, Ω̇_y, Ω̇_z, a_x, a_y, a_z)   (G2)

since −Ω × (Ω × x) = |Ω|² x − Ω (Ω·x). Unit load case c (p_c = 1, the others 0) has the
body force b_c: for Ω_i² it is ρ (x − x_i e_i); for Ω_iΩ_j (i < j) −ρ (x_j e_i + x_i e_j);
for Ω̇_i −ρ e_i × x; for a_i −ρ e_i. Its nodal loads are F_c = M b_c(x_nodes)/ρ with the
body's mass matrix M (lumped or consistent; with the consistent M and the linear field
b_c this is the exact consistent load).

Each case is solved statically (u_c = G F_c, :class:`~preprocess.residual.StaticFlexibility`:
K⁻¹ on the free DOFs of a clamped body, inertia relief on a free-free one), its stress
σ_c = C ε(u_c) taken at the quadrature points, and the element geometric stiffness

    K_σ,(a i)(b j) = δ_ij ∫ ∇N_a · σ · ∇N_b dV                                (G3)

assembled (tet4: σ constant, one point; tet10: the integrand is cubic, a degree-3 rule).
K_σ is linear in σ, so the prestress of any frame motion gives

    K_geo(p) = Σ_c p_c Φᵀ K_σ,c Φ                                            (G4)

and the body file stores the twelve modal matrices Φᵀ K_σ,c Φ (12, n_f, n_f). Their
units are those of Φᵀ K Φ (s⁻², Φ in kg^-1/2) per unit p_c: s² for the Ω products
(dimensionless Φᵀ K_σ Φ / Ω²), s² for Ω̇, s²/m for a.

What (G4) leaves out: the stiffening is linear in the load (the prestress of the
undeformed body; a deflection large enough to change the load path is beyond it), and
forces other than the frame's inertia (gravity, joint reactions, contact) prestress
nothing here. On a free-free body the acceleration cases carry no stress (inertia relief
balances a uniform or rigidly rotating load by the rigid motion itself), and a
centrifugal load only stresses through its part about the centre of mass.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from preprocess import fe
from preprocess.body import mass_times
from preprocess.mesh import Mesh
from preprocess.residual import StaticFlexibility

#: the load parameters p of eq. G2, in the order of the stored matrices
LOAD_CASES = ("Omega_xx", "Omega_yy", "Omega_zz", "Omega_xy", "Omega_xz", "Omega_yz",
              "dOmega_x", "dOmega_y", "dOmega_z", "a_x", "a_y", "a_z")
#: elements per vectorized block of the K_σ assembly: its σ ∇N array holds
#: 12 cases x block x 27 points x 3 x 30 doubles (117 MB at 500 tet10 elements)
_CHUNK = 500


def inertia_load_fields(u0) -> np.ndarray:
    """The body force per unit density of each unit load case of eq. G1/G2 at the nodes
    ``u0`` (N, 3) [m]: (12, N, 3) [m/s² per unit p_c]."""
    x = np.asarray(u0, dtype=float)
    n = len(x)
    fields = np.zeros((12, n, 3))
    for i in range(3):
        fields[i] = x
        fields[i][:, i] = 0.0                          # Ω_i²: x − x_i e_i
    for c, (i, j) in zip((3, 4, 5), ((0, 1), (0, 2), (1, 2))):
        fields[c][:, i] = -x[:, j]                     # Ω_iΩ_j: −(x_j e_i + x_i e_j)
        fields[c][:, j] = -x[:, i]
    for i in range(3):
        e = np.zeros(3)
        e[i] = 1.0
        fields[6 + i] = -np.cross(e, x)                # Ω̇_i: −e_i × x
        fields[9 + i][:, i] = -1.0                     # a_i: −e_i
    return fields


def inertia_loads(u0, mass) -> np.ndarray:
    """Nodal loads F_c (3N, 12) [N per unit p_c] of the twelve load cases: M b_c / ρ with the
    body's mass ``mass``, lumped node masses (N,) [kg] or the scalar mass matrix (N, N)
    (:func:`preprocess.body.mass_times`)."""
    fields = inertia_load_fields(u0)
    return mass_times(mass, fields.reshape(12, -1).T)


def stress_geometric_matrices(mesh: Mesh, young, poisson, displacements) -> list:
    """The scalar geometric stiffness matrices K_s,c (N, N) [N/m], K_σ,c = K_s,c ⊗ I3
    (eq. G3), of the stress of each displacement field ``displacements`` (3N, m) [m]:
    σ = λ tr(ε) 1 + 2 μ ε, ε = sym ∇u, integrated exactly (degree 3 (order − 1))."""
    lam, mu = fe.lame(young, poisson)
    U = np.asarray(displacements, dtype=float).reshape(mesh.n_nodes, 3, -1)
    m = U.shape[2]
    n = mesh.tets.shape[1]
    rows, cols, vals = [], [], [[] for _ in range(m)]
    for start in range(0, mesh.n_elements, _CHUNK):
        tets = mesh.tets[start:start + _CHUNK]
        wdet, _, g = fe.element_geometry(mesh, tets, 3 * (mesh.order - 1))      # g (E, Q, n, 3)
        grad_u = np.einsum("enkc,eqni->ceqki", U[tets], g)              # ∂u_k/∂x_i
        strain = 0.5 * (grad_u + grad_u.transpose(0, 1, 2, 4, 3))
        trace = np.einsum("ceqkk->ceq", strain)
        stress = 2.0 * mu * strain
        stress += lam * trace[..., None, None] * np.eye(3)
        sg = stress @ g.transpose(0, 1, 3, 2)                            # σ ∇N_b (c, E, Q, 3, n)
        gw = (wdet[:, :, None, None] * g).transpose(0, 2, 1, 3).reshape(len(tets), n, -1)
        ke = gw @ sg.reshape(m, len(tets), -1, n)                         # Σ_q w ∇N_a·σ·∇N_b
        rows.append(np.repeat(tets, n, axis=1).ravel())
        cols.append(np.tile(tets, (1, n)).ravel())
        for c in range(m):
            vals[c].append(ke[c].ravel())
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    shape = (mesh.n_nodes, mesh.n_nodes)
    return [sp.coo_matrix((np.concatenate(v), (rows, cols)), shape=shape).tocsr() for v in vals]


def modal_projection(scalar_matrix, phi) -> np.ndarray:
    """Φᵀ (K_s ⊗ I3) Φ (n_f, n_f) = Σ_k Φ_kᵀ K_s Φ_k with Φ_k the rows of direction k of
    ``phi`` (3N, n_f); symmetrized."""
    P = np.asarray(phi, dtype=float)
    out = sum(P[k::3].T @ (scalar_matrix @ P[k::3]) for k in range(3))
    return 0.5 * (out + out.T)


def geometric_stiffness(mesh: Mesh, stiffness, young, poisson, mass, phi, clamped_nodes=None,
                        log=None) -> np.ndarray:
    """The modal geometric stiffness matrices Φᵀ K_σ,c Φ (12, n_f, n_f) of eq. G4.

    ``mesh`` in SI units, its stiffness matrix ``stiffness`` K (3N, 3N) [N/m], ``young``
    [Pa], ``poisson`` [-], ``mass`` the mass the modes were normalized with (lumped node
    masses (N,) [kg] or the scalar mass matrix (N, N)), ``phi`` (3N, n_f) [kg^-1/2],
    ``clamped_nodes`` the clamped node indices or None (free-free: inertia relief).
    Cost: one sparse factorization, twelve solves, one K_σ assembly of twelve stress
    fields and twelve projections. ``log(msg)`` receives a line with the timings.
    """
    t0 = time.perf_counter()
    flexibility = StaticFlexibility(stiffness, mass, mesh.points, clamped_nodes)
    displacements = flexibility.solve(inertia_loads(mesh.points, mass))
    t1 = time.perf_counter()
    matrices = stress_geometric_matrices(mesh, young, poisson, displacements)
    out = np.stack([modal_projection(Ks, phi) for Ks in matrices])
    if log is not None:
        log(f"geometric stiffness of {len(LOAD_CASES)} inertia load cases: solves {t1 - t0:.2f} s, "
            f"assembly and projection {time.perf_counter() - t1:.2f} s")
    return out
