"""The modal model of one body shared by the modal solvers (report Sec. 2.1, 3.4.1, 4.2).

Built once from preprocessed body data (the same modes, masses and surface nodes a
:class:`~mbs.FlexibleBodyFFR` uses) and never mutated. The mass M is the body's: the
lumped ``masses`` (N,), or the consistent ``mass_matrix`` M_s (N, N) when the body has
one (M = M_s ⊗ 1₃, :mod:`preprocess.fe`); every integral below is taken with it.

* ``P`` — mode shapes, (N, 3, n) [kg^-1/2], mass-normalized: Pᵀ M P = I (eq. 3);
* ``omega2`` — eigenvalues ω² (n,) [rad²/s²] (eq. 3, Λ = diag ω²);
* ``b0`` — node positions relative to the centre of mass, (N, 3) [m] (coordinates
  in the body frame B of report Fig. 3);
* ``inertia`` — the inertia tensor of M about the centre of mass (eq. 17, 25),
  (3, 3) [kg m²];
* ``surface`` — the surface node indices (the boundary approach of Sec. 4.2).

For a free body the modes are the elastic ones; ``with_rigid_modes`` adds the six
rigid-body modes with ω² = 0 (eq. 13, 14), which :class:`~mbs.modal.PureMA` needs to
move an unconstrained body by linear (small-rotation) theory.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from ffrmbs.errors import ModelError
from preprocess.modes import rigid_body_modes


@dataclass(frozen=True)
class ModalBasis:
    """Modes, masses and geometry of one body (see module docstring); the derived
    geometry (centre of mass, b0, inertia) is computed on first use and kept."""

    u0: np.ndarray
    masses: np.ndarray
    P: np.ndarray
    omega2: np.ndarray
    surface: np.ndarray
    clamped: bool
    mass_matrix: sp.csr_matrix | None = None

    @classmethod
    def from_body(cls, data, modes=None, with_rigid_modes=False):
        """From :class:`preprocess.BodyData`; ``modes``: None (all), an int n (the first
        n) or a list of mode indices (e.g. from effective-mass selection, Sec. 4.3)."""
        n_all = data.n_modes
        if modes is None:
            idx = np.arange(n_all)
        elif np.isscalar(modes):
            if not 1 <= int(modes) <= n_all:
                raise ModelError(f"ModalBasis: {modes} modes requested, the body file has {n_all}")
            idx = np.arange(int(modes))
        else:
            idx = np.asarray(modes, dtype=np.int64).ravel()
            if idx.size == 0 or idx.min() < 0 or idx.max() >= n_all:
                raise ModelError(f"ModalBasis: mode indices must lie in 0..{n_all - 1}, got {idx.tolist()}")
        omega2 = data.modal_eigenvalues()[idx]
        phi = data.phi[:, idx]
        clamped = bool(data.params.get("clamp")) if data.params else False
        if with_rigid_modes:
            if clamped:
                raise ModelError("ModalBasis: a clamped body has no rigid-body modes")
            phi = np.hstack([rigid_body_modes(data.u0, data.mass), phi])
            omega2 = np.concatenate([np.zeros(6), omega2])
        return cls(u0=np.asarray(data.u0, dtype=float), masses=np.asarray(data.masses, dtype=float),
                   P=np.ascontiguousarray(phi.reshape(data.n_nodes, 3, -1)),
                   omega2=np.asarray(omega2, dtype=float), surface=data.surface_nodes, clamped=clamped,
                   mass_matrix=data.mass_matrix)

    # --- sizes and rigid-body quantities ----------------------------------------------

    @property
    def n_nodes(self) -> int:
        return self.u0.shape[0]

    @property
    def n_modes(self) -> int:
        return self.P.shape[2]

    @property
    def mass(self):
        """The mass used: ``mass_matrix`` M_s (N, N) if set, else ``masses`` (N,) [kg]
        (the argument of :func:`preprocess.body.mass_times`)."""
        return self.masses if self.mass_matrix is None else self.mass_matrix

    def mass_nodal(self, x) -> np.ndarray:
        """M_s x [kg × units of x] of a nodal array ``x`` (N, ...): Σ_b M_ab x_b, or m_a x_a when lumped."""
        x = np.asarray(x, dtype=float)
        if self.mass_matrix is None:
            return self.masses.reshape((-1,) + (1,) * (x.ndim - 1)) * x
        return (self.mass_matrix @ x.reshape(x.shape[0], -1)).reshape(x.shape)

    @cached_property
    def node_weights(self) -> np.ndarray:
        """w = M_s 1 (N,) [kg] (the masses when lumped): m_tot = Σ w, centre of mass Σ w u0 / Σ w."""
        return self.masses if self.mass_matrix is None else np.asarray(self.mass_matrix.sum(axis=1)).ravel()

    @property
    def total_mass(self) -> float:
        """m_tot = 1ᵀ M_s 1 [kg]."""
        return float(self.node_weights.sum())

    @cached_property
    def center_of_mass(self) -> np.ndarray:
        """Centre of mass of the undeformed body in mesh coordinates, (3,) [m]."""
        return self.node_weights @ self.u0 / self.node_weights.sum()

    @cached_property
    def b0(self) -> np.ndarray:
        """Node positions in B: relative to the centre of mass, (N, 3) [m]."""
        return self.u0 - self.center_of_mass

    @cached_property
    def inertia(self) -> np.ndarray:
        """Inertia tensor about the centre of mass of the mass used (eq. 25), (3, 3) [kg m²]:
        tr(U) 1 − U with U = Σ_ab M_ab b_a b_bᵀ."""
        b = self.b0
        U = self.mass_nodal(b).T @ b
        return np.trace(U) * np.eye(3) - U

    @property
    def rigid(self) -> np.ndarray:
        """Boolean (n,): modes with ω² = 0 (rigid-body modes, eq. 13)."""
        return self.omega2 == 0.0

    # --- projections (eq. 5, 8, 33) -----------------------------------------------------

    def project_forces(self, nodes, forces) -> np.ndarray:
        """Modal forces 𝓕 = Pᵀ f (eq. 5, 33) of forces (..., k, 3) [N] on ``nodes`` (k,)."""
        return np.einsum("...ia,ian->...n", forces, self.P[nodes])

    def project_field(self, field) -> np.ndarray:
        """Modal coordinates Pᵀ M x (n,) of a nodal field (N, 3) — displacements or
        velocities (initial conditions, eq. 8 with Pᵀ M P = I). Needs all nodes: the
        boundary approach does not apply here (report Sec. 4.2.1)."""
        field = np.asarray(field, dtype=float)
        if field.shape != self.u0.shape:
            raise ModelError(f"ModalBasis: a nodal field must have shape {self.u0.shape}, got {field.shape}")
        return np.einsum("ia,ian->n", self.mass_nodal(field), self.P)

    def output_nodes(self, nodes) -> np.ndarray:
        """Resolve an output selection: "all", "surface" (the boundary approach, Sec. 4.2),
        a node-group-like index array."""
        if isinstance(nodes, str):
            if nodes == "all":
                return np.arange(self.n_nodes)
            if nodes == "surface":
                if self.surface.size == 0:
                    raise ModelError("ModalBasis: the body data has no surface triangles, "
                                     "so the boundary approach cannot find the surface nodes")
                return self.surface
            raise ModelError(f"ModalBasis: output nodes must be 'all', 'surface' or indices, got {nodes!r}")
        idx = np.asarray(nodes, dtype=np.int64).ravel()
        if idx.size and (idx.min() < 0 or idx.max() >= self.n_nodes):
            raise ModelError(f"ModalBasis: output node indices must lie in 0..{self.n_nodes - 1}")
        return idx
