"""Full finite-element static contact: the exact reference of face contacts.

Elastic parts (tetrahedral meshes, every DOF, linear elasticity, small displacements:
K from :func:`preprocess.fe.stiffness_matrix`) held by supports (given displacement
components of node groups: a clamp, a roller, a prescribed stroke), loaded by nodal
forces, and pressed on each other or on rigid planes through frictionless unilateral
contacts — solved exactly, not by penalty. The reference of the static oracle of
surface-to-surface contact (a flat punch or a flexible block pressed on a flexible
support) against which a reduced model's resultant and pressure are measured.

Contact: node to surface
------------------------
Each node s of a ``slave`` node group is paired, in the reference configuration, with
the point of the ``master`` — a rigid plane, or the surface triangles of another part
whose nodes all lie in a node group — that it projects onto along the master's
outward normal n (for a part: the triangle that contains the projection, the
triangle's shape functions N_i at it; linear 3-node or quadratic 6-node triangles).
The gap, linear in the displacements (flat master faces, small displacements), is

    g_s = n · (x_s + u_s − x_m − Σ N_i u_i) ≥ 0              (a part's face)
    g_s = n · (x_s + u_s) − d ≥ 0                             (a plane n·x = d)

and the contact force λ_s ≥ 0 [N] acts on s along n and on the master's nodes along
−n by N_i. Slave nodes that project onto no master triangle are left out (counted).
Node to surface with non-matching meshes does not pass the contact patch test (a
uniform pressure is not transmitted exactly); node to node (matching meshes, a
plane) does.

Solution
--------
With u_p the prescribed DOFs and u_f the free ones (K_ff positive definite: every part
supported against its rigid motions), the equilibrium K_ff u_f = f̃ + Gᵀ λ with
f̃ = f_f − K_fp u_p, the gaps g = G u_f + c₀, and the conditions λ ≥ 0, g ≥ 0, λ·g = 0
(Signorini) are the linear complementarity problem

    g = D λ + c,   D = G K_ff⁻¹ Gᵀ,   c = c₀ + G K_ff⁻¹ f̃,

the optimality conditions of min ½ λᵀ D λ + cᵀ λ over λ ≥ 0. With D = L Lᵀ (Cholesky)
this is the non-negative least-squares problem min ‖Lᵀ λ + L⁻¹ c‖ (λ ≥ 0), solved
exactly (to rounding) by the active-set method of Lawson and Hanson
(:func:`scipy.optimize.nnls`). K_ff is factored once (:func:`scipy.sparse.linalg.splu`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import nnls

from ffrmbs.errors import ModelError
from preprocess.fe import check_positive, stiffness_matrix


@dataclass
class Part:
    """An elastic part: ``mesh`` (:class:`preprocess.mesh.Mesh`, SI units), Young's
    modulus [Pa] and Poisson's ratio; ``supports`` [(nodes, components, displacement [m])]:
    the given components (0, 1, 2 = x, y, z) of those nodes fixed to that displacement;
    ``forces`` (N, 3) [N] nodal loads (default none)."""

    mesh: object
    young: float
    poisson: float
    supports: list = field(default_factory=list)
    forces: np.ndarray | None = None


@dataclass(frozen=True)
class Plane:
    """A rigid plane n · x = d, ``normal`` n (3,) pointing towards the slave, ``offset`` d [m]."""

    normal: tuple
    offset: float


@dataclass(frozen=True)
class Pairing:
    """Nodes ``slave_nodes`` of part ``slave`` against ``master``: a :class:`Plane` or
    (part index, node group of the master's face nodes)."""

    slave: int
    slave_nodes: np.ndarray
    master: object


@dataclass
class StaticContactResult:
    """The solution: ``displacements`` per part (N, 3) [m]; per pairing its paired
    slave ``nodes``, contact forces ``forces`` [N], gaps ``gaps`` [m] and the number of
    slave nodes left out (``unpaired``); ``reactions`` per part (N, 3) [N] at the supported
    DOFs (K u − f, zero elsewhere)."""

    displacements: list
    nodes: list
    forces: list
    gaps: list
    unpaired: list
    reactions: list

    def resultant(self, k=0) -> float:
        """Σ λ of pairing ``k`` [N]."""
        return float(self.forces[k].sum())


def solve(parts, pairings) -> StaticContactResult:
    """The static contact solution of ``parts`` (:class:`Part`) in ``pairings``
    (:class:`Pairing`), module docstring. ModelError when a part is not held against
    its rigid motions or no slave node is paired."""
    offsets = np.cumsum([0] + [3 * p.mesh.n_nodes for p in parts])
    n = int(offsets[-1])
    K = sp.block_diag([_stiffness(p) for p in parts], format="csr")
    f = np.concatenate([np.zeros(3 * p.mesh.n_nodes) if p.forces is None else np.asarray(p.forces, float).ravel()
                        for p in parts])
    fixed, u = np.zeros(n, dtype=bool), np.zeros(n)
    for part, at in zip(parts, offsets):
        for nodes, components, value in part.supports:
            dofs = (at + 3 * np.asarray(nodes, dtype=np.int64)[:, None] + np.asarray(components)[None, :]).ravel()
            fixed[dofs], u[dofs] = True, value
    free = ~fixed
    rows, c0, nodes, unpaired = _gaps(parts, pairings, offsets, n)
    G = sp.csr_matrix(rows) if len(rows) else sp.csr_matrix((0, n))
    if G.shape[0] == 0:
        raise ModelError("static contact: no slave node projects onto its master")
    K_ff = K[free][:, free].tocsc()
    try:
        lu = spla.splu(K_ff)
    except RuntimeError as err:
        raise ModelError(f"static contact: the stiffness is singular ({err}): hold every part against "
                         "its rigid motions") from None
    f_tilde = f[free] - K[free][:, fixed] @ u[fixed]
    G_f = G[:, free].toarray()
    c = c0 + G[:, fixed] @ u[fixed] + G_f @ lu.solve(f_tilde)
    KG = lu.solve(G_f.T)
    D = G_f @ KG
    L = sla.cholesky(0.5 * (D + D.T), lower=True)
    lam, _ = nnls(L.T, -sla.solve_triangular(L, c, lower=True), maxiter=50 * len(c))
    u[free] = lu.solve(f_tilde) + KG @ lam
    gaps = G @ u + c0
    reactions = K @ u - f - G.T @ lam
    reactions[free] = 0.0
    split = np.cumsum([len(k) for k in nodes])[:-1]
    return StaticContactResult(
        displacements=[u[a:b].reshape(-1, 3) for a, b in zip(offsets[:-1], offsets[1:])], nodes=nodes,
        forces=np.split(lam, split), gaps=np.split(gaps, split), unpaired=unpaired,
        reactions=[reactions[a:b].reshape(-1, 3) for a, b in zip(offsets[:-1], offsets[1:])])


def _stiffness(part) -> sp.csr_matrix:
    check_positive("Young's modulus", part.young)
    return stiffness_matrix(part.mesh, part.young, part.poisson)


def _gaps(parts, pairings, offsets, n):
    """The gap rows (dense per row, n DOFs), c₀ and the paired slave nodes of every
    pairing, in order; the number of unpaired slave nodes per pairing."""
    rows, c0, nodes, unpaired = [], [], [], []
    for pairing in pairings:
        slave = parts[pairing.slave]
        s_nodes = np.asarray(pairing.slave_nodes, dtype=np.int64)
        x_s = slave.mesh.points[s_nodes]
        at_s = offsets[pairing.slave]
        if isinstance(pairing.master, Plane):
            normal = _unit(pairing.master.normal)
            found = [(k, normal, normal @ x - pairing.master.offset, (), ()) for k, x in enumerate(x_s)]
        else:
            m_index, m_nodes = pairing.master
            found = _projections(parts[m_index].mesh, m_nodes, x_s)
            at_m = offsets[m_index]
        kept = []
        for k, normal, g0, m_dofs_nodes, weights in found:
            row = np.zeros(n)
            row[at_s + 3 * s_nodes[k]:at_s + 3 * s_nodes[k] + 3] = normal
            for node, w in zip(m_dofs_nodes, weights):
                row[at_m + 3 * node:at_m + 3 * node + 3] -= w * normal
            rows.append(row)
            c0.append(g0)
            kept.append(s_nodes[k])
        nodes.append(np.array(kept, dtype=np.int64))
        unpaired.append(len(s_nodes) - len(kept))
    return rows, np.array(c0), nodes, unpaired


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    norm = np.linalg.norm(v)
    if not norm > 0:
        raise ModelError(f"static contact: a plane's normal must not be zero, got {v.tolist()}")
    return v / norm


def _projections(mesh, group, points, tol=1e-9):
    """Per point that projects onto a surface triangle of ``mesh`` whose nodes all lie in
    ``group``: (its index, the triangle's outward unit normal, the reference gap, the
    triangle's nodes, their shape functions at the projection)."""
    faces = mesh.surface_triangles()
    faces = faces[np.isin(faces, np.asarray(group)).all(axis=1)]
    if len(faces) == 0:
        raise ModelError(f"{mesh.source}: no surface face lies within the master's node group")
    found = []
    for k, x in enumerate(points):
        for face in faces:
            a, b, c = mesh.points[face[:3]]
            normal = np.cross(b - a, c - a)
            normal /= np.linalg.norm(normal)
            y = x - (x - a) @ normal * normal                     # the projection
            l1, l2 = np.linalg.lstsq(np.column_stack([b - a, c - a]), y - a, rcond=None)[0]
            l0 = 1.0 - l1 - l2
            if min(l0, l1, l2) < -tol:
                continue
            found.append((k, normal, (x - a) @ normal, face, _triangle_shape(len(face), l0, l1, l2)))
            break
    return found


def _triangle_shape(n_nodes, l0, l1, l2) -> np.ndarray:
    """Shape functions of a 3-node or 6-node triangle (corners, then the mid-edge nodes
    of edges 01, 12, 20) at area coordinates (l0, l1, l2)."""
    if n_nodes == 3:
        return np.array([l0, l1, l2])
    return np.array([l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l2 * l0])
