"""Effective-mass mode selection on the report's beam (report Sec. 4.3, 5.3, eq. 36, Table 2).

Two loads: the shear test (clamped at z = 0, 500 N along y on z = 5) and the complex
forcing (free beam, both load steps). For each, the effective masses of the first 10
modes (80 preprocessed) against the total over ALL elastic modes of the mesh (dense eigensolve: 1725
clamped / 1731 free modes), with eq. 36 as printed (``report``: |φᵀ M f| / ω²) and as
derived (``static``: |φᵀ f| / ω²), and the modes the 90 % criterion keeps.

Does the criterion keep enough? Each selection is run with PureMA (clamped: 0.1 s,
undamped; free: the same modal loads, rigid motion left out) and compared with the
run using all modes, which is the exact solution of the FE model: RMS over nodes and
output times of the elastic displacement, relative to the all-modes RMS.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mbs.modal import ModalBasis, PureMA
from mbs.modal.mode_selection import auto_select_modes, effective_mass_table, effective_masses
from preprocess.modes import all_modes
from validation import CaseResult, make_row
from validation.cases import _wobble as wb

NAME = "wobble_effective_mass"
DESCRIPTION = ("effective masses (report eq. 36, Table 2) of the shear test and complex forcing, and the "
               "displacement error of the 90 % selection vs all modes")


def _response(data, modes, loads, t_out):
    res = PureMA(ModalBasis.from_body(data, modes), [loads]).solve(t_out)
    return res.elastic_displacement(), res.stats["cpu_s"]


def _scene(result, name, data, loads, clamp_nodes, t_out):
    times, forces = wb.nodal_history(loads, data.n_nodes)
    w2_all, phi_all = all_modes(data.stiffness, data.masses, clamp_nodes, data.u0)
    full = replace(data, phi=phi_all, eigenvalues=w2_all)
    u_all, cpu_all = _response(full, None, loads, t_out)
    scale = np.sqrt(np.mean(np.sum(u_all ** 2, axis=2)))
    omega2 = data.modal_eigenvalues()
    for weighting in ("report", "static"):
        sel = auto_select_modes(data, forces, weighting=weighting)
        m_all = effective_masses(phi_all, w2_all, data.masses, forces, weighting)
        shown = max(12, sel.indices.max() + 1)
        result.notes.append(f"**{name}, eq. 36 {'as printed' if weighting == 'report' else 'derived'} "
                            f"({weighting})**: total over all {w2_all.size} modes; the 90 % criterion keeps "
                            f"modes {(sel.indices + 1).tolist()} ({sel.fraction_held:.1%}); all-modes run "
                            f"{cpu_all:.2f} CPU s.\n\n"
                            + effective_mass_table(omega2[:shown], sel.m_eff[:shown], sel.indices, m_all.sum()))
        _error_row(result, name, f"90 % ({weighting})", data, sel.indices, loads, t_out, u_all, scale, w2_all.size)
    _error_row(result, name, "first 10", data, np.arange(10), loads, t_out, u_all, scale, w2_all.size)


def _error_row(result, name, label, data, modes, loads, t_out, u_all, scale, n_all):
    u, cpu = _response(data, modes, loads, t_out)
    err = np.sqrt(np.mean(np.sum((u - u_all) ** 2, axis=2))) / scale
    result.rows.append(make_row(NAME, {"load": name, "selection": label, "n_modes": len(modes)}, cpu, err,
                                "RMS elastic displacement", f"all {n_all} modes (exact FE)",
                                kept=str((np.asarray(modes) + 1).tolist())))


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=["load", "selection"])
    t_out = np.linspace(0.0, 0.1, 201)
    mesh, data = wb.beam(n_modes=80, clamp="z0")
    _scene(result, "shear test", data, wb.shear_loads(mesh), mesh.group("z0"), t_out)
    mesh, data = wb.beam(n_modes=80)
    _scene(result, "complex forcing", data, wb.complex_loads(mesh), None, np.linspace(0.0, 0.6, 201))
    return result
