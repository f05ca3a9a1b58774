"""The point mass on the beam against a full finite-element run of the same tet10 mesh
(issue 21: the residual flexibility's like-with-like check, and the mesh study).

Reference: :mod:`validation.peers.full_fe_contact` — every DOF of the tet10 mesh, central
differences at 0.9 of the critical step, the point mass on the quadratic top face by a
semi-implicit penalty of k = 1e9 N/m (its own convergence, k → 10 k and Δt → Δt/2, is a
note of this case: ≤ 6e-4 at 12.5 mm; at 25 mm setup A's rebound moves 1.4 % of the
impact speed with the step). Ours: the same mesh as an FFR
body (:func:`ffrmbs_app.scenes.point_mass_beam.default_beam_data` with ``order=2``, its
40 lowest clamped modes), 20 of them, the 2s contour on the top face without and with
residual flexibility, Newton impact e = 0 (the full FE's penalty is stiff: its mass
sticks to the face, which stores and returns the elastic energy, as our spring does),
Moreau Δt = 1e-5 s, θ = 0.5, to 0.1 s.

Errors (setups A and B; meshes 25 mm (10 x 2 x 2), 12.5 mm (20 x 4 x 4) and, in full
mode, 6.25 mm (40 x 8 x 8)):

- "rebound v_y(0.1 s) rel.": the mass's velocity at 0.1 s (free flight after the last
  contact phase) against the full FE's, relative;
- "node 19 peak rel.": the largest |u_y| of node 19 (250, 50, 25) mm, relative;
- "min y [m]": the lowest position of the mass, absolute.

The point load on a solid is mesh-sensitive: a finer mesh resolves more of the local
compliance under the contact, so each mesh is compared with its own full-FE run, and the
mesh study (a note) lists both codes' figures against the element size. Setup A hits
the face on the mid-plane z = 25 mm, a mesh line where the full FE's quadratic faces fold
and our NURBS contour (through the same nodes) is smooth; setup B (z = 40 mm) is inside a
face. CPU: the ffrmbs simulation alone; the full-FE runs are cached (6.25 mm: ~5 min each).
"""

from __future__ import annotations

import numpy as np

from ffrmbs_app.scenes import point_mass_beam as pmb
from validation import CaseResult, make_row, timed
from validation.peers import full_fe_contact as fe

NAME = "contact_full_fe"
DESCRIPTION = ("point mass on the beam against a full-FE run of the same tet10 mesh: 20 modes without and with "
               "residual flexibility; mesh study")

T_END, DT, N_OUT = 0.1, 1e-5, 1001
MODES, STORED = 20, 40
MESHES = fe.ELEMENT_SIZES                  # element size [m] -> tet10 divisions
KINDS = ("rebound v_y(0.1 s) rel.", "node 19 peak rel.", "min y [m]")


def figures_of(res) -> dict:
    """Rebound v_y at t_end [m/s], node-19 peak |u_y| [m], lowest y [m] of an ffrmbs run."""
    return {"rebound_vy": float(res["vy"][-1]), "node19_peak": float(np.abs(res["node19"][:, 1]).max()),
            "min_y": float(np.min(res["y"]))}


def errors(ours, ref) -> tuple:
    return (ours["rebound_vy"] / ref["rebound_vy"] - 1.0, ours["node19_peak"] / ref["node19_peak"] - 1.0,
            ours["min_y"] - ref["min_y"])


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("residual_flexibility", "error_kind"))
    sizes = (0.025,) if quick else tuple(MESHES)
    study = {}
    for h in sizes:
        div = MESHES[h]
        data = pmb.default_beam_data(divisions=div, modes=STORED, order=2)
        for on_off in ("off", "on"):                       # compile, and the residual projection cached
            pmb.build("A", MODES, data=data, residual_flexibility=on_off == "on").system.simulate(
                0.0102, DT, integrator="moreau", theta=0.5)
        for setup in ("A", "B"):
            ref = fe.figures(fe.simulate(setup, div))
            study[(setup, h, "full FE")] = ref
            for on_off in ("off", "on"):
                scene = pmb.build(setup, MODES, data=data, residual_flexibility=on_off == "on")
                res, cpu = timed(scene.system.simulate, T_END, DT, integrator="moreau", theta=0.5,
                                 t_out=np.linspace(0.0, T_END, N_OUT), outputs=scene.outputs())
                ours = figures_of(res)
                study[(setup, h, on_off)] = ours
                config = {"setup": setup, "mesh": f"{1e3 * h:g} mm", "modes": MODES, "residual_flexibility": on_off}
                for kind, err in zip(KINDS, errors(ours, ref)):
                    result.rows.append(make_row(NAME, config, cpu, err, kind,
                                                f"full FE of the same tet10 mesh (k = {fe.PENALTY_K:g} N/m)"))
    result.notes.append(_study_table(study, sizes))
    result.notes.append(fe.convergence("B", MESHES[sizes[-1]])["table"])
    return result


def _study_table(study, sizes) -> str:
    lines = [f"Mesh study (tet10; ffrmbs: {MODES} of {STORED} modes, 2s contour, e = 0; full FE: every DOF, "
             "penalty): rebound v_y(0.1 s) [m/s], node-19 peak [mm], lowest y [mm]", "",
             "| setup | element | full FE | ffrmbs, correction off | ffrmbs, correction on |", "|---|---|---|---|---|"]
    for setup in ("A", "B"):
        for h in sizes:
            cells = [f"{f['rebound_vy']:.4f} / {1e3 * f['node19_peak']:.4f} / {1e3 * f['min_y']:.4f}"
                     for f in (study[(setup, h, k)] for k in ("full FE", "off", "on"))]
            lines.append(f"| {setup} | {1e3 * h:g} mm | " + " | ".join(cells) + " |")
    return "\n".join(lines)
