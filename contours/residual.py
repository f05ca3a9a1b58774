"""Residual compliance of a flexible contour: the static flexibility, at any point of the
contour, of the modes its body leaves out (:mod:`preprocess.residual`).

A neutral contour's local position is a NURBS over control points P = F ū (F the
interpolation or fitting matrix of the contour's nodes, thesis eq. 3.22–3.23), so a
point's small displacement is

    δū(η, ξ) = Σ_i B_i(η, ξ) δP_i,        B_i = N_i I                          (C1)

(3 × 3 blocks, body axes) over the (p + 1) or (p_η + 1)(p_ξ + 1) control points of the
span; on a derived contour at offset d̄ = α n̄ + β t̄2 from a 1s neutral curve
(:mod:`contours.derived`), B_i = N_i I + N'_i Ğ with Ğ = ∂d̄/∂ū_η of the undeformed
curve. By virtual work a force f at the point loads control point i with B_iᵀ f and the
nodes with the transfer matrix T = (F ⊗ I₃)ᵀ scattered on the contour's nodes. With the
residual flexibility of the control points G_P = Tᵀ G_res T (3 n_P, 3 n_P) [m/N], the
displacement at point a under a force f at point b of the same contour is c(a, b) f with

    c(a, b) = Σ_i Σ_j B_i(a) G_P[i, j] B_j(b)ᵀ          (3 × 3, body axes) [m/N]  (C2)

— the residual compliance: span-local, a few numbers per point whatever the mesh, and
exact (to rounding) against the full FE static solution for loads the contour can apply:
Φ K_n⁻¹ Φᵀ + G_res = G (:func:`preprocess.residual.residual_flexibility`). The linear
correction is taken on the undeformed contour (B, Ğ at q_f = 0), as G_res itself is.

A point or sphere contour on a node frame of a flexible body (``body.node(j)``,
:func:`node_of`) is the case of one "control point", the node itself, B = I: its
:class:`NodeCompliance` c(a, b) is the 3 × 3 block of G_res between two nodes, exact
against the full FE for forces at the nodes; with the neutral contours of the same body
it shares G_P (cross-compliances included).

:func:`residual_compliance` builds it for a contour of a flexible body (one sparse
factorization of the body's stiffness per body: a clamped body's projection Tᵀ G T comes
from the factor's Schur complement on the loaded DOFs, eq. R4 of :mod:`preprocess.residual`;
the projection optionally cached on disk, keyed by the body's matrices and T).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ffrmbs.errors import ModelError
from preprocess.residual import (StaticFlexibility, clamped_nodes_of, clamped_projected_flexibility,
                                 projected_flexibility, residual_flexibility)

from . import _offset_kernels as OK
from . import _residual_kernels as RK
from .derived import OffsetContour
from .neutral import _kernels as NK
from .neutral.factory import NeutralContour


def node_of(contour) -> int | None:
    """The FE node a point or sphere contour sits on (its frame a node frame of a
    flexible body, ``body.node(j)``), else None."""
    frame = getattr(contour, "frame_ref", None)
    return None if frame is None else frame.node_index


class ResidualCompliance:
    """The residual compliance c(a, b) of one contour (module docstring, eq. C1–C2).

    Parameters
    ----------
    contour : NeutralContour or OffsetContour (on a neutral 1s contour)
    G_P : (3 n, 3 n) [m/N]
        Residual flexibility of the control points of this contour, or of all the corrected
        contours of its body (then cross-compliances between them are included).
    offset : int
        The first of this contour's n_P control points in G_P (their order: the flattened
        control-point array, wrapped copies of a closed direction included).

    Attributes
    ----------
    contour, G_P, n_P, offset
    n_weights : int
        The blocks B_i of eq. C1 at a point (:meth:`weights`).
    """

    def __init__(self, contour, G_P, offset=0):
        self.contour = contour
        self.neutral = neutral_of(contour)
        space = self.neutral.space
        self.n_P = int(np.prod(space.ctrl_shape))
        self.offset = int(offset)
        G_P = np.ascontiguousarray(G_P, dtype=float)
        if G_P.ndim != 2 or G_P.shape[0] != G_P.shape[1] or G_P.shape[0] < 3 * (self.offset + self.n_P):
            raise ModelError(f"{contour.name}: residual flexibility of shape {G_P.shape} does not hold its "
                             f"{self.n_P} control points from {self.offset} on")
        self.G_P = G_P
        self._dirs = (space.eta,) if space.dim == 1 else (space.eta, space.xi)
        n_w = self.n_weights = int(np.prod([d.p + 1 for d in self._dirs]))     # blocks of eq. C1 at a point
        self._B = [np.zeros((3, d.p + 1)) for d in self._dirs]
        self._work = np.zeros((2, n_w, 3, 3)), np.zeros((2, n_w), dtype=np.int64)
        derived = isinstance(contour, OffsetContour)
        self._offset = contour.offset_law if derived else None        # (law, size) of the offsets
        self._ctrl0 = self.neutral.local_position.ctrl0.reshape(self.n_P, 3) if derived else None
        self._offset_work = np.zeros((4, 3))
        # the compiled route of a neutral contour (B_i = N_i I): knots η, ints, domains,
        # knots ξ (η's again on a curve), bases, weights
        g = space.geometry
        self._kernel_geometry = (g[0], g[1], g[2], g[0]) if space.dim == 1 else (g[0], g[2], g[3], g[1])
        p_max = 8                                   # any contour of the body: a pair's second point
        if max(d.p for d in self._dirs) > p_max:
            raise ModelError(f"{contour.name}: residual flexibility supports degrees up to {p_max}")
        self._Bc = np.zeros((2, 3, p_max + 1))
        self._w = np.zeros((2, (p_max + 1) ** 2, 3, 3))
        self._index = np.zeros((2, (p_max + 1) ** 2), dtype=np.int64)

    @property
    def rotation(self) -> np.ndarray:
        """The body rotation A (3, 3) of the contour's last update."""
        return self.neutral.A

    @property
    def neutral_kernel(self) -> bool:
        """c(a, b) between two such contours takes the compiled neutral route."""
        return self._offset is None

    def weights(self, eta, xi, blocks, index) -> int:
        """The blocks B_i (k, 3, 3) of eq. C1 and their control points' indices (k,) in
        G_P at (η, ξ) into ``blocks``, ``index``; returns k. A derived contour's in one
        kernel (:func:`._residual_kernels.offset_weights`)."""
        if self._offset is not None:
            al, be = OK.offsets(*self._offset, float(xi))[:2]
            g = self._kernel_geometry
            return RK.offset_weights(g[0], g[1], g[2], float(eta), al, be, self._ctrl0, self.neutral.normal_ref,
                                     self.offset, self._B[0], self._offset_work, blocks, index)
        k = 0
        if len(self._dirs) == 1:
            d = self._dirs[0]
            B = self._B[0]
            s = NK.locate(d.knots, d.p, d.n_ctrl, d.closed, d.a, d.b, float(eta), B)
            for a in range(d.p + 1):
                index[k] = self.offset + s - d.p + a
                blocks[k] = B[0, a] * np.eye(3)
                k += 1
            return k
        e, x = self._dirs
        Be, Bx = self._B
        se = NK.locate(e.knots, e.p, e.n_ctrl, e.closed, e.a, e.b, float(eta), Be)
        sx = NK.locate(x.knots, x.p, x.n_ctrl, x.closed, x.a, x.b, float(xi), Bx)
        for a in range(e.p + 1):
            for b in range(x.p + 1):
                index[k] = self.offset + (se - e.p + a) * x.n_ctrl + (sx - x.p + b)
                blocks[k] = Be[0, a] * Bx[0, b] * np.eye(3)
                k += 1
        return k

    def kernel_weights(self, eta, xi, blocks, index) -> int:
        """:meth:`weights` by the compiled route (:func:`._residual_kernels.neutral_weights`,
        the blocks :meth:`between` takes for two neutral contours), allocation-free."""
        if self._offset is not None:
            return self.weights(eta, xi, blocks, index)
        g = self._kernel_geometry
        return RK.neutral_weights(1 if g[1].shape[0] == 3 else 2, g[0], g[1], g[2], g[3], float(eta), float(xi),
                                  self._Bc[0], self._Bc[1], self.offset, blocks, index)

    def between(self, eta_a, xi_a, eta_b, xi_b, other=None, out=None) -> np.ndarray:
        """c(a, b) (3, 3) [m/N] in body axes (eq. C2): the displacement at (η_a, ξ_a) of this
        contour per unit force at (η_b, ξ_b) of ``other`` (this contour when None; another
        contour of the same body sharing G_P). Two neutral contours take the compiled
        route (allocation-free with ``out``), a derived one the blocks of :meth:`weights`."""
        other = self if other is None else other
        if other.G_P is not self.G_P:
            raise ModelError(f"{self.contour.name} and {other.contour.name}: no cross-compliance (not built together "
                             "by residual_compliances)")
        out = np.zeros((3, 3)) if out is None else out
        (blocks_a, _), (index_a, _) = self._work
        (_, blocks_b), (_, index_b) = other._work
        if self.neutral_kernel and other.neutral_kernel:
            ga, gb = self._kernel_geometry, other._kernel_geometry
            RK.neutral_between(self.G_P, ga[0], ga[1], ga[2], ga[3], self.offset, float(eta_a), float(xi_a),
                               gb[0], gb[1], gb[2], gb[3], other.offset, float(eta_b), float(xi_b),
                               self._Bc, self._w, self._index, out)
            return out
        ka = self.weights(eta_a, xi_a, blocks_a, index_a)
        kb = other.weights(eta_b, xi_b, blocks_b, index_b)
        RK.compliance_between(self.G_P, blocks_a, index_a, ka, blocks_b, index_b, kb, out)
        return out

    def at(self, eta, xi=0.0, out=None) -> np.ndarray:
        """c(a, a) (3, 3) [m/N] in body axes at (η, ξ) (eq. C2)."""
        return self.between(eta, xi, eta, xi, out=out)


class NodeCompliance:
    """The residual compliance at a point or sphere contour on a node of a flexible body
    (:func:`node_of`): eq. C2 with one "control point", the node itself (B = I), so
    c(a, b) is the 3 × 3 block of G_P between two such nodes, or eq. C2 with B(a) = I
    against a neutral contour's point. Same interface as :class:`ResidualCompliance`
    (the surface coordinates are not used).

    Parameters
    ----------
    contour : PointContour or SphereContour on ``body.node(j)``
    G_P : (3 n, 3 n) [m/N]
        As for :class:`ResidualCompliance`.
    offset : int
        The node's place among G_P's points.
    """

    neutral_kernel = False
    n_weights = 1           # blocks of eq. C1 at the point: the node's

    def __init__(self, contour, G_P, offset=0):
        self.contour, self.n_P, self.offset = contour, 1, int(offset)
        self.G_P = np.ascontiguousarray(G_P, dtype=float)
        if self.G_P.shape[0] < 3 * (self.offset + 1):
            raise ModelError(f"{contour.name}: residual flexibility of shape {self.G_P.shape} does not hold its "
                             f"node at {self.offset}")
        self._work = np.zeros((2, 1, 3, 3)), np.zeros((2, 1), dtype=np.int64)
        for k in range(2):
            self.weights(0.0, 0.0, self._work[0][k], self._work[1][k])
        self._rotation = np.zeros((3, 3))

    @property
    def rotation(self) -> np.ndarray:
        """The body rotation A (3, 3) of the contour's last update: its frame's axes
        without the frame's constant orientation relative to the body."""
        return np.matmul(self.contour.axes, self.contour.frame_ref.A_rel.T, out=self._rotation)

    def weights(self, eta, xi, blocks, index) -> int:
        """B = I at the node (eq. C1 with one point) into ``blocks``, ``index``; returns 1."""
        block = blocks[0]
        block.fill(0.0)
        block[0, 0] = block[1, 1] = block[2, 2] = 1.0
        index[0] = self.offset
        return 1

    kernel_weights = weights

    def between(self, eta_a, xi_a, eta_b, xi_b, other=None, out=None) -> np.ndarray:
        """c(a, b) (3, 3) [m/N] in body axes: the displacement at this node per unit force
        at (η_b, ξ_b) of ``other`` (a node or a neutral contour of the same body sharing G_P)."""
        other = self if other is None else other
        if other.G_P is not self.G_P:
            raise ModelError(f"{self.contour.name} and {other.contour.name}: no cross-compliance (not built together "
                             "by residual_compliances)")
        out = np.zeros((3, 3)) if out is None else out
        if isinstance(other, NodeCompliance):
            a, b = 3 * self.offset, 3 * other.offset
            out[...] = self.G_P[a:a + 3, b:b + 3]
            return out
        (blocks_a, _), (index_a, _) = self._work
        (_, blocks_b), (_, index_b) = other._work
        kb = other.weights(eta_b, xi_b, blocks_b, index_b)
        RK.compliance_between(self.G_P, blocks_a, index_a, 1, blocks_b, index_b, kb, out)
        return out

    def at(self, eta=0.0, xi=0.0, out=None) -> np.ndarray:
        """c(a, a) (3, 3) [m/N] at the node."""
        return self.between(eta, xi, eta, xi, out=out)


def neutral_of(contour) -> NeutralContour:
    """The neutral contour a residual compliance is built on: the contour itself, or a
    derived contour's 1s neutral curve; ModelError for anything else."""
    if isinstance(contour, NeutralContour):
        return contour
    if isinstance(contour, OffsetContour):
        return contour.neutral
    raise ModelError(f"{getattr(contour, 'name', contour)!r}: residual flexibility needs a neutral contour of a "
                     f"flexible body (or a band or cylinder on one), not a {type(contour).__name__}")


def transfer_matrix(contour) -> sp.csr_matrix:
    """T (3N, 3 n_P): column 3 i + d is the nodal load of a unit force along body axis d on
    control point i of ``contour`` (Fᵀ scattered on the contour's nodes, module
    docstring); a node contour's (:func:`node_of`) three columns load its node."""
    node = node_of(contour)
    if node is not None:
        n_dof = 3 * contour.body.data.n_nodes
        return sp.csr_matrix((np.ones(3), (3 * node + np.arange(3), np.arange(3))), shape=(n_dof, 3))
    neutral = neutral_of(contour)
    nodes = np.asarray(neutral.nodes).reshape(-1)
    k = nodes.size
    identity = np.eye(k).reshape(np.asarray(neutral.nodes).shape + (k,))
    F = np.asarray(neutral.space.interpolate(identity)).reshape(-1, k)       # (n_P, k): P = F ū
    n_P = F.shape[0]
    n_dof = 3 * neutral.body.data.n_nodes
    rows = (3 * nodes[None, :, None] + np.arange(3)[None, None, :]).repeat(n_P, axis=0)
    cols = (3 * np.arange(n_P)[:, None, None] + np.arange(3)[None, None, :]).repeat(k, axis=1)
    vals = np.repeat(F[:, :, None], 3, axis=2)
    T = sp.coo_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(n_dof, 3 * n_P)).tocsr()
    T.eliminate_zeros()
    return T


def static_flexibility(body) -> StaticFlexibility:
    """The static flexibility of a flexible body's FE model (clamped or inertia relief,
    :class:`preprocess.residual.StaticFlexibility`), factored once; a free-free body's
    inertia relief with the mass the body uses (lumped or consistent, ``BodyData.mass``)."""
    data = body.data
    return StaticFlexibility(data.stiffness, data.mass, data.u0, clamped_nodes_of(data))


def projection(body, transfer, flexibility=None) -> np.ndarray:
    """Tᵀ G T (m, m) [m/N] of a flexible body for load patterns ``transfer`` T (3N, m):
    through ``flexibility`` (a :class:`~preprocess.residual.StaticFlexibility`) when given,
    else a clamped body's from one factorization
    (:func:`preprocess.residual.clamped_projected_flexibility`) and a free-free body's
    through its inertia relief (:func:`static_flexibility`)."""
    clamped = clamped_nodes_of(body.data)
    if flexibility is None and clamped.size:
        return clamped_projected_flexibility(body.data.stiffness, clamped, transfer)
    return projected_flexibility(static_flexibility(body) if flexibility is None else flexibility, transfer)


def residual_compliances(contours, flexibility=None, cache_dir=None) -> list:
    """The :class:`ResidualCompliance` of each of ``contours`` (all on one body) on the
    body's kept modes (``body.K_ff``; their control points Φ_P = F Φ are the contours'
    own, so Φᵀ T needs no T), sharing one G_P, so that cross-compliances between them
    are included. ``flexibility``: the body's
    :class:`~preprocess.residual.StaticFlexibility`, or None (:func:`projection`);
    ``cache_dir``: a directory where Tᵀ G T (the costly part, independent of the modes
    kept) is read or written, keyed by the body's matrices and the contours' fitting
    matrices (:func:`_key`)."""
    nodes = [node_of(c) for c in contours]
    neutrals = [None if j is not None else neutral_of(c) for c, j in zip(contours, nodes)]
    body = contours[0].body
    if any(c.body is not body for c in contours):
        raise ModelError("residual_compliances: the contours are on different bodies")
    sizes = [1 if n is None else int(np.prod(n.space.ctrl_shape)) for n in neutrals]
    TGT = path = None
    if cache_dir is not None:
        path = Path(cache_dir) / f"residual-{_key(body.data, neutrals, nodes)}.npy"
        if path.is_file():
            TGT = np.load(path, allow_pickle=False)
            if TGT.shape != (3 * sum(sizes),) * 2:
                TGT = None
    if TGT is None:
        T = sp.hstack([transfer_matrix(c) for c in contours], format="csr")
        TGT = projection(body, T, flexibility)
        if path is not None:
            _save(path, TGT)
    n_f = body.K_ff.shape[0]
    phi_t = np.vstack([np.zeros((3 * k, 0)) if not n_f else
                       c.frame_ref.phi if n is None else n.mode_shapes.ctrl.reshape(-1, n_f)
                       for c, n, k in zip(contours, neutrals, sizes)]).T              # Φᵀ T (n_f, 3 n_P)
    G_P = residual_flexibility(TGT, phi_t, body.K_ff)
    offsets = np.cumsum([0] + sizes)
    return [(ResidualCompliance if n is not None else NodeCompliance)(c, G_P, int(o))
            for c, n, o in zip(contours, neutrals, offsets)]


def residual_compliance(contour, flexibility=None, cache_dir=None) -> ResidualCompliance:
    """The :class:`ResidualCompliance` of one contour (:func:`residual_compliances`)."""
    return residual_compliances([contour], flexibility, cache_dir)[0]


def _key(data, neutrals, nodes) -> str:
    """Hash of what Tᵀ G T depends on: K, the masses (and the consistent mass matrix if
    the body has one), the node positions, the supports,
    and per neutral contour its nodes, knots and the fitting matrix F, fingerprinted by the
    control points of a fixed pseudo-random nodal field (F r: equal for two F only if
    they are equal, with probability one); per node contour its node."""
    h = hashlib.sha256()
    K = sp.csr_matrix(data.stiffness)
    for a in (K.indptr, K.indices, K.data, data.masses, data.u0, clamped_nodes_of(data)):
        h.update(np.ascontiguousarray(a).tobytes())
    if data.mass_matrix is not None:
        M = sp.csr_matrix(data.mass_matrix)
        for a in (M.indptr, M.indices, M.data):
            h.update(np.ascontiguousarray(a).tobytes())
    for n, node in zip(neutrals, nodes):
        if n is None:
            h.update(np.array([-1, node], dtype=np.int64).tobytes())
            continue
        grid = np.asarray(n.nodes)
        field = np.random.default_rng(12345).standard_normal(grid.shape + (2,))
        for a in (grid, *n.space.geometry, n.space.interpolate(field)):
            h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:20]


def _save(path: Path, array) -> None:
    """``array`` to ``path`` (.npy) through a temporary file and a rename (never half-written)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.save(f, array, allow_pickle=False)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
