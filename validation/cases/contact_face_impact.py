"""A flexible rod landing on its end face: a face contact with and without the residual
flexibility of its nodes, against the elastic bar on a rigid wall.

Setup: a free steel rod (E = 210 GPa, ρ = 7850 kg/m³, ν = 0.3), 20 × 20 × 100 mm, tet4
(4 × 4 × 12 cells), its ``modes`` lowest free modes, lands at v = 1 m/s along its axis
on a rigid plane from 1 µm above it, no gravity. Its end face is one face contact
(:class:`contact.FaceContact`: a point contact with Newton's law, e = 0, at each of the
face's 25 nodes), the points carrying their nodes' static compliance of the modes left
out when ``residual_flexibility`` (:class:`contours.residual.NodeCompliance`).

Reference: the elastic bar on a rigid wall (Saint-Venant): the end stops, a compression
wave runs to the free end and back, and the bar leaves after one contact interval of
2L/c (c = √(E/ρ), 38.7 µs) with its energy — nothing is dissipated, and e = 0 acts
through the compliance, not on the bar's inertia. Errors:

- "energy (rel.)": |E_end / E_0 − 1|, E kinetic plus elastic after the contact;
- "contact duration (rel.)": |T / (2L/c) − 1|, T from the first step a point transmits a
  force to the last (one interval expected; the 3D rod is no 1D bar: a few % remain).

Extra columns: the number of contact intervals, the rebound momentum p_z / (m v) (the
rest of the energy is vibration), steps. Swept: ``modes`` 10, 20, 40 (quick: 10, 20),
``residual_flexibility`` false / true, ``dt`` 5e-7, 2.5e-7 s (quick: 5e-7). Without the
correction the first instant of contact stops the face nodes' lumped masses
plastically: the rod loses a sixth to a fifth of its energy whatever Δt.
"""

from __future__ import annotations

import functools

import numpy as np

from contact import UnilateralNewtonImpact, connect
from contours import Contour2sNeutralFFR, PlaneContour
from mbs import FlexibleBodyFFR, System, ground_frame
from preprocess import Material, build_body
from preprocess.geometry import box
from validation import CaseResult, make_row, timed

NAME = "contact_face_impact"
DESCRIPTION = ("a free rod landing on its end face (25 point contacts, e = 0): energy kept and contact "
               "duration 2L/c of the elastic bar on a rigid wall, with and without the nodes' residual flexibility")

E, RHO, NU = 2.1e11, 7850.0, 0.3          # [Pa], [kg/m³], [-]
SIDE, LENGTH, V = 0.02, 0.1, 1.0           # [m], [m], [m/s]
GAP, T_END = 1e-6, 6e-5                     # [m], [s]
WAVE = 2.0 * LENGTH / np.sqrt(E / RHO)      # 2L/c [s]
MODES = {True: (10, 20), False: (10, 20, 40)}
DTS = {True: (5e-7,), False: (5e-7, 2.5e-7)}    # [s]
KIND_ENERGY = "energy (rel.)"
KIND_DURATION = "contact duration (rel.)"


@functools.lru_cache(maxsize=1)
def rod_data():
    """The rod's body data with 40 free modes."""
    return build_body(box(SIDE, SIDE, LENGTH, None, order=1, divisions=(4, 4, 12)), Material(RHO, E, NU),
                      n_modes=40)


def simulate(modes, residual_flexibility, dt, t_end=T_END):
    """(Result, CPU [s]) of the landing."""
    system = System()
    rod = FlexibleBodyFFR(rod_data(), modes=modes, name="rod")
    rod.q_init[2], rod.u_init[2] = GAP, -V
    system.add(rod)
    system.add(connect(Contour2sNeutralFFR(rod, "z0", residual_flexibility=residual_flexibility),
                       PlaneContour(ground_frame()), UnilateralNewtonImpact(0.0), name="end"))
    return timed(system.simulate, t_end, dt, integrator="moreau", t_out=np.linspace(0.0, t_end, 121),
                 energies=True, trace=True,
                 outputs={"p_z": lambda t, q, u: system.linear_momentum(t, q, u)[2]})


def measure(res) -> dict:
    """Energy error, contact intervals and duration error, rebound momentum of a run."""
    energy = res.energy["kinetic"] + res.energy["potential"]
    t, pressed = res.trace["t"], res.trace["pressed"] > 0
    on = t[pressed]
    edges = np.count_nonzero(np.diff(pressed.astype(int)) == 1) + int(pressed[0])
    duration = on[-1] - on[0] + (t[1] - t[0]) if on.size else 0.0
    mass = RHO * SIDE * SIDE * LENGTH
    return {"energy": abs(energy[-1] / energy[0] - 1.0), "duration": abs(duration / WAVE - 1.0),
            "intervals": edges, "rebound": float(res["p_z"][-1] / (mass * V))}


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("residual_flexibility", "error_kind"))
    simulate(10, True, 5e-7, t_end=5e-6)                  # warm-up: imports and kernels not timed
    table = ["| modes | residual flexibility | Δt [s] | energy (rel.) | duration (rel.) | intervals | "
             "p_z / (m v) | CPU [s] |", "|---|---|---|---|---|---|---|---|"]
    for dt in DTS[quick]:
        for modes in MODES[quick]:
            for residual in (False, True):
                res, cpu = simulate(modes, residual, dt)
                m = measure(res)
                config = {"modes": modes, "residual_flexibility": residual, "dt": dt}
                extra = {"intervals": m["intervals"], "rebound": m["rebound"], "steps": res.stats["steps"]}
                result.rows.append(make_row(NAME, config, cpu, m["energy"], KIND_ENERGY,
                                            "elastic bar on a rigid wall: no energy lost", **extra))
                result.rows.append(make_row(NAME, config, cpu, m["duration"], KIND_DURATION,
                                            "elastic bar on a rigid wall: one contact of 2L/c = "
                                            f"{WAVE * 1e6:.1f} µs", **extra))
                table.append(f"| {modes} | {residual} | {dt:g} | {m['energy']:.2e} | {m['duration']:.2e} | "
                             f"{m['intervals']} | {m['rebound']:.3f} | {cpu:.2f} |")
    result.notes.append("\n".join(table))
    return result
