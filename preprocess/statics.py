"""Linear statics on the unconstrained stiffness matrix: K_ff u_f = f_f with clamped nodes fixed."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as sla

from ffrmbs.errors import ModelError
from preprocess.modes import clamped_dofs


def solve_static(K, forces, clamped_nodes) -> np.ndarray:
    """Static displacements (N, 3) [m] under nodal ``forces`` (N, 3) [N] with the
    DOFs of ``clamped_nodes`` fixed (report eq. 1 without inertia)."""
    forces = np.asarray(forces, dtype=float)
    fixed = clamped_dofs(K.shape[0], clamped_nodes)
    if not fixed.any():
        raise ModelError("a static solution needs clamped nodes (the free body is not supported)")
    free = ~fixed
    u = np.zeros(K.shape[0])
    u[free] = sla.spsolve(K[free][:, free].tocsc(), forces.ravel()[free])
    return u.reshape(-1, 3)
