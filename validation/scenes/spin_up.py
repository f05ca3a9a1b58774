"""The spin-up beam of Kane, Ryan & Banerjee (J. Guid. Control Dyn. 10 (1987) 139–151) as a 3-D solid.

A cantilever of length L = 10 m with EA = 2.8e7 N, EI = 1.4e4 N m² and ρA = 1.2 kg/m,
clamped at x = 0 to a hub turning about z with the smooth spin-up profile of
:meth:`mbs.PrescribedFrameMotion.spin_up` (Ω_s = 6 rad/s reached at T_s = 15 s), no
gravity, 0–20 s. Here it is a solid with those properties: a square section of side
a = 0.0775 m centred on the x axis, E = 4.667e9 Pa, ρ = 200 kg/m³, ν = 0 (EA = 2.803e7 N,
EI = E a⁴/12 = 1.403e4 N m², ρA = 1.201 kg/m), meshed structured with tet10 elements,
``n_elements`` along x and 2 × 2 across, the face x = 0 clamped. Its first bending
frequency is ω1 = 1.8751² √(EI/(ρA L⁴)) = 3.80 rad/s, which the hub's spin passes at
t ≈ 8.5 s.

Output: v_tip, the transverse (y) displacement of the node at the centre of the tip face
in the hub frame [m] — the elastic displacement Φ_tip,y q_f, the frame being the hub's.
"""

from __future__ import annotations

import numpy as np

from mbs import FlexibleBodyFFR, PrescribedFrameMotion, System
from preprocess import BodyData, Material, box, build_body

LENGTH = 10.0            # [m]
SIDE = 0.0775            # [m], square section
MATERIAL = Material(density=200.0, young=4.667e9, poisson=0.0)
SPIN = 6.0               # Ω_s [rad/s]
RAMP_TIME = 15.0         # T_s [s]
T_END = 20.0             # [s]
N_ELEMENTS = 40          # tet10 element edges along the beam (0.25 m)


def beam_body(n_modes=10, n_elements=N_ELEMENTS, geometric_stiffness=True) -> BodyData:
    """The preprocessed solid beam: ``n_modes`` clamped modes of the tet10 mesh with
    ``n_elements`` along x, with the geometric stiffness of its inertia loads."""
    mesh = box(LENGTH, SIDE, SIDE, None, order=2, divisions=(n_elements, 2, 2))
    mesh.points[:, 1:] -= 0.5 * SIDE                    # section centred on the x axis
    return build_body(mesh, MATERIAL, n_modes, clamp="x0", geometric_stiffness=geometric_stiffness)


def spin_up_system(data: BodyData, modes=None, geometric_stiffening=True):
    """(system, beam, v_tip) of the spin-up: the beam on the hub's prescribed frame and
    the output callable v_tip(t, q, u) [m] (module docstring)."""
    beam = FlexibleBodyFFR(data, modes, frame=PrescribedFrameMotion.spin_up(SPIN, RAMP_TIME, axis=2),
                           geometric_stiffening=geometric_stiffening, name="beam")
    system = System()
    system.add(beam)
    tip_y = np.ascontiguousarray(beam.phi_nodes[data.node_at((LENGTH, 0.0, 0.0)), 1])
    f = beam.q_slice

    def v_tip(t, q, u):
        return float(tip_y @ q[f])

    return system, beam, v_tip
