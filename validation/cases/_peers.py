"""Side-by-side frequencies from a peer code's own FE assembly (used by the beam cases)."""

from __future__ import annotations

import numpy as np

from preprocess import clamped_modes
from validation import timed


def akantu_frequencies(mesh_si, material_si, n_modes, clamp):
    """(ω [rad/s] of the first ``n_modes`` clamped modes, CPU s) from Akantu's stiffness and
    lumped masses on the same mesh, or (None, reason) when Akantu is not importable."""
    from validation.peers import akantu_fe

    if not akantu_fe.available():
        return None, "akantu: skipped: akantu not installed (pip install '.[peers]')"

    def solve():
        K, m = akantu_fe.assemble(mesh_si.points, mesh_si.tets, material_si.density,
                                  material_si.young, material_si.poisson)
        return np.sqrt(clamped_modes(K, m, n_modes, mesh_si.group(clamp))[0])

    return timed(solve)
