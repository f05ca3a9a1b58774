"""The body data a flexible body is built from (thesis Sec. 4.2.1, report Sec. 2).

A :class:`BodyData` holds, in SI units, exactly what the thesis's four text files
hold plus what the HDF5 body file adds. It is fixed for a run and never mutated
by the multibody code.

Conventions
-----------
* ``u0``: undeformed node positions ū0 in the body frame, shape (N, 3) [m].
* ``phi``: mode shapes Φ, shape (3N, n_f), row ``3*i + k`` is node i, direction k
  (the layout of thesis Listing 4.2, 0-based). Clamped nodes have zero rows.
  Produced by :mod:`preprocess.modes` mass-normalized: Φᵀ M Φ = I with the mass M the
  body uses (below), so Φ has units kg^-1/2.
* ``masses``: lumped node masses m_j, shape (N,) [kg] (thesis Listing 4.3); always
  present, used wherever a mass per node is needed (e.g. a node's point load of gravity
  in the text files).
* ``mass_matrix``: the scalar consistent mass matrix M_s, scipy CSR (N, N) [kg], with
  M_FE = M_s ⊗ 1₃ in the numbering of ``phi`` (:func:`preprocess.fe.consistent_mass_matrix`),
  or None: the body's inertia is the lumped M_FE = diag(m_j, each repeated 3x). The mass
  actually used (:attr:`BodyData.mass`) is M_s when present, else the lumped masses; the
  modes, eigenvalues, total mass and centre of mass all refer to it.
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


def mass_times(mass, V) -> np.ndarray:
    """M_FE V [kg × units of V] for ``V`` (3N,) or (3N, m) in the DOF numbering 3*j + k,
    with ``mass`` either lumped node masses (N,) [kg] — M_FE = diag(m_j, each repeated
    3x) — or a scalar sparse mass matrix M_s (N, N) [kg] — M_FE = M_s ⊗ 1₃, i.e.
    (M_FE V)_(3a+k) = Σ_b M_s,ab V_(3b+k)."""
    V = np.asarray(V, dtype=float)
    if sp.issparse(mass):
        return (mass @ V.reshape(mass.shape[0], -1)).reshape(V.shape)
    m3 = np.repeat(np.asarray(mass, dtype=float), 3)
    return m3[:, None] * V if V.ndim == 2 else m3 * V


def mass_normalized(phi: np.ndarray, mass) -> bool:
    """Whether the mode shapes ``phi`` (3N, n_f) are normalized to ``mass`` (lumped masses
    (N,) or a scalar sparse M_s (N, N), see :func:`mass_times`): max|Φᵀ M_FE Φ − I| <
    NORMALIZED_TOL."""
    gram = phi.T @ mass_times(mass, phi)
    return bool(np.abs(gram - np.eye(phi.shape[1])).max() < NORMALIZED_TOL)


@dataclass
class BodyData:
    """Preprocessed data of one flexible body, in SI units (see module docstring)."""

    u0: np.ndarray
    phi: np.ndarray
    masses: np.ndarray
    stiffness: sp.csr_matrix
    eigenvalues: np.ndarray | None = None
    mass_matrix: sp.csr_matrix | None = None
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
    def mass(self):
        """The mass the body uses: M_s (N, N) sparse when ``mass_matrix`` is set, else the
        lumped masses (N,) [kg] — the form :mod:`preprocess.modes` and :func:`mass_times` take."""
        return self.masses if self.mass_matrix is None else self.mass_matrix

    def scalar_mass_matrix(self) -> sp.csr_matrix:
        """The scalar mass matrix used, CSR (N, N) [kg]: ``mass_matrix``, or diag(masses)."""
        if self.mass_matrix is not None:
            return sp.csr_matrix(self.mass_matrix)
        return sp.diags(self.masses).tocsr()

    def node_weights(self) -> np.ndarray:
        """w = M_s 1, (N,) [kg]: the row sums of the mass used (the lumped masses when
        lumped). They give its zeroth and first moments exactly, m = Σ w_j and
        Σ_ab M_ab ū0_b = Σ w_j ū0_j, and the consistent nodal forces w_j g of gravity g."""
        return self.masses if self.mass_matrix is None else np.asarray(self.mass_matrix.sum(axis=1)).ravel()

    @property
    def total_mass(self) -> float:
        """Total mass m = 1ᵀ M_s 1 = Σ w_j [kg] of the mass used (:meth:`node_weights`)."""
        return float(self.node_weights().sum())

    @property
    def center_of_mass(self) -> np.ndarray:
        """Centre of mass c = Σ w_j ū0_j / Σ w_j in the body frame, shape (3,) [m], w the
        row sums of the mass used (:meth:`node_weights`; w = m_j when lumped)."""
        w = self.node_weights()
        return w @ self.u0 / w.sum()

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
        ω_i² = φ_iᵀ K φ_i / φ_iᵀ M φ_i with the mass M used (:attr:`mass`; exact for
        eigenvectors).
        """
        if self.eigenvalues is not None:
            return np.asarray(self.eigenvalues, dtype=float)
        num = np.einsum("ij,ij->j", self.phi, self.stiffness @ self.phi)
        den = np.einsum("ij,ij->j", self.phi, mass_times(self.mass, self.phi))
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
            self.mass_line(),
            f"centre of mass: ({c[0]:.6g}, {c[1]:.6g}, {c[2]:.6g}) m",
        ]
        if self.node_groups:
            lines.append("node groups:    " + ", ".join(
                f"{k} ({len(v)})" for k, v in sorted(self.node_groups.items())))
        return "\n".join(lines) + "\n" + self.frequency_table()

    def mass_line(self) -> str:
        """'total mass: m kg (lumped mass, density ρ kg/m³ x volume V m³)': the total mass
        (:attr:`total_mass`) and the mesh volume V = m / ρ it implies (the mass is the
        density integrated over the elements, curved ones included)."""
        density = self.material.get("density") if self.material else None
        kind = "lumped" if self.mass_matrix is None else "consistent"
        split = (f", density {density:.6g} kg/m³ x volume {self.total_mass / density:.6g} m³"
                 if density else "")
        return f"total mass:     {self.total_mass:.6g} kg ({kind} mass{split})"

    def frequency_table(self) -> str:
        """One line per mode: number, ω [rad/s], f [Hz]."""
        omega, hz = self.frequencies()
        rows = [" mode   omega [rad/s]        f [Hz]"]
        rows += [f"{i:5d} {w:15.6g} {f:13.6g}" for i, (w, f) in enumerate(zip(omega, hz), start=1)]
        return "\n".join(rows)
