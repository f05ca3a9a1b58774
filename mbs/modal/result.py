"""Results of the modal solvers: modal and rigid-body histories, nodal fields, energies.

Everything is stored at the requested output times only (report Sec. 2.2: the
analytic solution is evaluated where it is wanted). Nodal fields are produced on
demand for the output nodes (all nodes, or the surface nodes under the boundary
approach of report Sec. 4.2): u = P r (eq. 4, 33) in the body frame and
ρ_cm + R(θ) (b0 + P r) in the inertial frame (eq. 24).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mbs.bodies.rotations import rotvec_from_matrix
from mbs.modal._kernels import place_nodes
from mbs.modal.basis import ModalBasis


@dataclass
class ModalResult:
    """Output of PureMA, SimpleRB and CoupledRB.

    - t : (n_t,) [s] output times.
    - r, rdot : (n_t, n) modal coordinates and velocities.
    - basis : the :class:`ModalBasis` the modes come from.
    - nodes : (k,) node indices of the nodal outputs.
    - rho, v : (n_t, 3) centre of mass [m] and its velocity [m/s] in G, or None (PureMA).
    - R : (n_t, 3, 3) orientation of B in G, or None.
    - Omega : (n_t, 3) angular velocity [rad/s] in B axes, or None.
    - inertia : (n_t, 3, 3) inertia tensor about the centre of mass [kg m²] (constant
      for SimpleRB, updated with the deformation for CoupledRB), or None.
    - relative_angular_momentum : (n_t, 3) Σ m_i b_i × ḃ_i in B axes (CoupledRB), or None.
    - stats : dict, e.g. ``cpu_s`` (solver CPU time), ``load_steps``, ``rigid_steps``.
    """

    t: np.ndarray
    r: np.ndarray
    rdot: np.ndarray
    basis: ModalBasis
    nodes: np.ndarray
    rho: np.ndarray | None = None
    v: np.ndarray | None = None
    R: np.ndarray | None = None
    Omega: np.ndarray | None = None
    inertia: np.ndarray | None = None
    relative_angular_momentum: np.ndarray | None = None
    stats: dict = field(default_factory=dict)

    def elastic_displacement(self) -> np.ndarray:
        """u = P r (eq. 4) of the output nodes in the body frame, (n_t, k, 3) [m]."""
        return self._modes_times(self.r)

    def elastic_velocity(self) -> np.ndarray:
        """u̇ = P ṙ of the output nodes in the body frame, (n_t, k, 3) [m/s]."""
        return self._modes_times(self.rdot)

    def _modes_times(self, coords) -> np.ndarray:
        P = self.basis.P[self.nodes]
        return (coords @ P.reshape(-1, P.shape[2]).T).reshape(coords.shape[0], -1, 3)

    def positions(self) -> np.ndarray:
        """Output node positions in G, (n_t, k, 3) [m]: ρ_cm + R (b0 + u) (eq. 24); for a
        PureMA result (no rigid-body state) ū0 + u."""
        return self._placed(np.zeros((self.nodes.size, 3)))

    def displacements(self) -> np.ndarray:
        """Output node displacements from the initial mesh positions, (n_t, k, 3) [m] —
        what an FE code such as Akantu reports (the body starts with B at the centre of
        mass, axes parallel to the mesh axes)."""
        return self._placed(self.basis.u0[self.nodes])

    def _placed(self, offset) -> np.ndarray:
        u = self.elastic_displacement()
        if self.R is None:
            return self.basis.u0[self.nodes][None] + u - offset[None]
        out = np.empty_like(u)
        place_nodes(self.rho, np.ascontiguousarray(self.R), self.basis.b0[self.nodes], u, offset, out)
        return out

    def rotation_vectors(self) -> np.ndarray:
        """Rotation vectors θ (n_t, 3) [rad] with R = R(θ) (eq. 23), |θ| <= π, robust at
        |θ| = π (report Sec. 7.2: recovered through the quaternion, no log-map singularity)."""
        if self.R is None:
            raise ValueError("a PureMA result has no rigid-body rotation")
        return np.array([rotvec_from_matrix(R) for R in self.R])

    def energies(self) -> dict:
        """Energies per output time [J] (arrays (n_t,)).

        ``kinetic_vib`` = ½ ṙᵀṙ (eq. 34), ``potential_vib`` = ½ rᵀΛr (eq. 35), computed in
        modal space (so the boundary approach changes nothing); rigid modes (ω² = 0) count
        in ``kinetic_vib`` like the elastic ones. With a rigid-body state:
        ``kinetic_rbm`` = ½ m |ρ̇|² + ½ Ωᵀ Î Ω (eq. 21). With the deformation coupled
        (CoupledRB): ``kinetic_coupling`` = Ω · Σ m_i b_i × ḃ_i, the cross term that makes
        the sum the exact kinetic energy of the body's masses (eq. 21 and 34 omit it; it
        is of second order in the deformation). ``total`` is their sum.
        """
        e = {"kinetic_vib": 0.5 * np.einsum("tn,tn->t", self.rdot, self.rdot),
             "potential_vib": 0.5 * np.einsum("tn,n,tn->t", self.r, self.basis.omega2, self.r)}
        if self.R is not None:
            e["kinetic_rbm"] = (0.5 * self.basis.total_mass * np.einsum("ta,ta->t", self.v, self.v)
                                + 0.5 * np.einsum("ta,tab,tb->t", self.Omega, self.inertia, self.Omega))
        if self.relative_angular_momentum is not None:
            e["kinetic_coupling"] = np.einsum("ta,ta->t", self.Omega, self.relative_angular_momentum)
        e["total"] = sum(e.values())
        return e
