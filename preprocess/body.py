"""The body data a flexible body is built from (thesis Sec. 4.2.1, report Sec. 2).

A :class:`BodyData` holds, in SI units, exactly what the thesis's four text files
hold plus what the HDF5 body file adds. It is fixed for a run and never mutated
by the multibody code.

Conventions
-----------
* ``u0``: undeformed node positions ū0 in the body frame, shape (N, 3) [m].
* ``phi``: mode shapes Φ, shape (3N, n_f), row ``3*i + k`` is node i, direction k
  (the layout of thesis Listing 4.2, 0-based). Clamped nodes have zero rows.
  Produced by :mod:`preprocess.modes` mass-normalized: Φᵀ M Φ = I with the lumped M,
  so Φ has units kg^-1/2.
* ``masses``: lumped node masses m_j, shape (N,) [kg] (thesis Listing 4.3).
* ``stiffness``: the unconstrained stiffness matrix K, scipy CSR, shape (3N, 3N)
  [N/m], same DOF numbering as ``phi`` (thesis Listings 4.4-4.5).
* ``eigenvalues``: ω² of the modes [rad²/s²], shape (n_f,), or None when unknown
  (text files do not store them; see :meth:`BodyData.modal_eigenvalues`).
* ``node_groups``: name -> sorted 0-based node indices (int64 arrays).
* ``surface_triangles``: surface faces, shape (T, 3) for linear or (T, 6) for
  quadratic meshes (corners first, then mid-edge nodes), 0-based; or None.
* ``material``: dict with ``density`` [kg/m³], ``young`` [Pa], ``poisson`` [-], or {}.
* ``params``: the preprocessing parameters (JSON-serializable dict), or {}.
* ``geometric_stiffness``: the modal geometric stiffness matrices Φᵀ K_σ,c Φ of the
  twelve inertia load cases of :mod:`preprocess.geometric` (eq. G4), shape
  (12, n_f, n_f), or None when not computed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

#: largest magnitude a body file may hold: a product of three such values (e.g. qᵀ K q)
#: stays finite, while 1e308 or 1e201 overflow in the first energy they enter
MAX_MAGNITUDE = 1e100

#: K must equal Kᵀ within this tolerance relative to max|K|
SYMMETRY_RTOL = 1e-9

#: max|Φᵀ M Φ − I| of mass-normalized modes
NORMALIZED_TOL = 1e-6


def mass_normalized(phi: np.ndarray, masses: np.ndarray) -> bool:
    """Whether the mode shapes ``phi`` (3N, n_f) are normalized to the lumped ``masses``
    (N,): max|Φᵀ M Φ − I| < NORMALIZED_TOL with M = diag(masses, each repeated 3x)."""
    gram = phi.T @ (np.repeat(masses, 3)[:, None] * phi)
    return bool(np.abs(gram - np.eye(phi.shape[1])).max() < NORMALIZED_TOL)


@dataclass
class BodyData:
    """Preprocessed data of one flexible body, in SI units (see module docstring)."""

    u0: np.ndarray
    phi: np.ndarray
    masses: np.ndarray
    stiffness: sp.csr_matrix
    eigenvalues: np.ndarray | None = None
    node_groups: dict = field(default_factory=dict)
    surface_triangles: np.ndarray | None = None
    material: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    geometric_stiffness: np.ndarray | None = None

    @property
    def n_nodes(self) -> int:
        """Number of nodes N."""
        return self.u0.shape[0]

    @property
    def n_modes(self) -> int:
        """Number of mode shapes n_f."""
        return self.phi.shape[1]

    @property
    def total_mass(self) -> float:
        """Total mass Σ m_j [kg]."""
        return float(self.masses.sum())

    @property
    def center_of_mass(self) -> np.ndarray:
        """Centre of mass c = Σ m_j ū0_j / Σ m_j in the body frame, shape (3,) [m]."""
        return self.masses @ self.u0 / self.masses.sum()

    @property
    def surface_nodes(self) -> np.ndarray:
        """Sorted indices of the nodes on the surface triangles (empty if unknown)."""
        if self.surface_triangles is None:
            return np.zeros(0, dtype=np.int64)
        return np.unique(self.surface_triangles)

    def node_at(self, point, tol=1e-9) -> int:
        """Index of the node at ``point`` (3,) [m] in the body frame, within ``tol`` [m];
        a ModelError names the nearest node's distance otherwise."""
        from ffrmbs.errors import ModelError

        d = np.linalg.norm(self.u0 - np.asarray(point, dtype=float), axis=1)
        j = int(np.argmin(d))
        if d[j] > tol:
            raise ModelError(f"no node at {tuple(point)} m (nearest {d[j]:.3g} m away)")
        return j

    def modal_eigenvalues(self) -> np.ndarray:
        """ω² of each mode [rad²/s²].

        The stored eigenvalues if present, otherwise the Rayleigh quotients
        ω_i² = φ_iᵀ K φ_i / φ_iᵀ M φ_i with the lumped M (exact for eigenvectors).
        """
        if self.eigenvalues is not None:
            return np.asarray(self.eigenvalues, dtype=float)
        m3 = np.repeat(self.masses, 3)
        num = np.einsum("ij,ij->j", self.phi, self.stiffness @ self.phi)
        den = np.einsum("ij,i,ij->j", self.phi, m3, self.phi)
        return num / den

    def frequencies(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenfrequencies (ω [rad/s], f [Hz]) of the modes."""
        omega = np.sqrt(np.clip(self.modal_eigenvalues(), 0.0, None))
        return omega, omega / (2 * np.pi)

    def summary(self) -> str:
        """A human-readable summary: nodes, surface nodes, modes, mass, centre of mass, frequencies."""
        c = self.center_of_mass
        lines = [
            f"nodes:          {self.n_nodes}",
            f"surface nodes:  {len(self.surface_nodes) if self.surface_triangles is not None else 'unknown'}",
            f"modes:          {self.n_modes}",
            f"total mass:     {self.total_mass:.6g} kg",
            f"centre of mass: ({c[0]:.6g}, {c[1]:.6g}, {c[2]:.6g}) m",
        ]
        if self.node_groups:
            lines.append("node groups:    " + ", ".join(
                f"{k} ({len(v)})" for k, v in sorted(self.node_groups.items())))
        return "\n".join(lines) + "\n" + self.frequency_table()

    def frequency_table(self) -> str:
        """One line per mode: number, ω [rad/s], f [Hz]."""
        omega, hz = self.frequencies()
        rows = [" mode   omega [rad/s]        f [Hz]"]
        rows += [f"{i:5d} {w:15.6g} {f:13.6g}" for i, (w, f) in enumerate(zip(omega, hz), start=1)]
        return "\n".join(rows)
