"""Savings of the boundary approach in the case study (report Sec. 4.2.1, 6.2, Table 3, eq. 40–41, Fig. 20).

The case-study load (report Sec. 6: 100 N along x and 10 N along z shared equally by
the nodes of the face x = 0 with y > 0.3 m and z > 4.1 m, for 10 ms) on the free beam,
10 elastic modes, SimpleRB (RKMK4, rigid step ≤ 8.7e-4 s as in the report's case study)
over 1 s with outputs every 1 ms; the result is the nodal displacement history
``res.displacements()`` (n_t, k, 3) [m], rigid motion included. Without the boundary
approach the loads are projected over all N nodes and the output is all nodes; with
it (``boundary=True``) both use the N_b surface nodes only.

Meshes (tet10): coarse — a gmsh box with point sizes 1 m (``box()`` cannot give it: every
size from 0.5 to 2 m yields 579–580 nodes), regular — ``box(1, 1, 5, 0.5)`` (report Table 1),
fine — ``box(1, 1, 5, 0.4)``; report Table 3: 237/178, 579/426, 1141/798 nodes/boundary nodes.

Error of each row: max |u_boundary − u_all[surface]| / max |u_all[surface]|, which the
report says is zero (the boundary approach changes only the order of the sums).
Run time per row: building the solver, solving and producing the displacements,
median CPU seconds per run over interleaved samples (7 in the full run, report
footnote 11: 7 runs of ``%%timeit``), with their standard deviation. Eq. 40–41 predict
Δcost = cost(all) − cost(boundary) = C2 (N − N_b); C2 is fitted through zero by
weighted least squares (report Fig. 20): Δcost per mesh is the median of the paired
differences of the interleaved samples, weighted by 1/σ² with σ their robust scatter
(1.4826 × median absolute deviation; a run allocates 2 × 24 kB per output node, the
elastic and the total displacement histories, and the page faults of these fresh
arrays make a few samples much slower than the rest).

The timed runs use one BLAS thread (threadpoolctl, restored afterwards). CPU time counts every thread, and the products here are small
((1001 × 10) times (10 × 3N)): with the default threads on this 2-core machine they
cost more CPU and scatter by tens of percent, which hides the saving. One comparison
with the default threads (fine mesh) is in the notes.
"""

from __future__ import annotations

import os
import tempfile
from functools import lru_cache

import numpy as np
from threadpoolctl import threadpool_limits

from mbs.modal import ModalBasis, SimpleRB
from preprocess import build_body
from preprocess.geometry import mesh_geo_file
from validation import CaseResult, CpuTiming, cpu_samples, make_row
from validation.cases import _wobble
from validation.cases.cantilever import MATERIAL

NAME = "wobble_boundary"
DESCRIPTION = ("case-study load with SimpleRB on three meshes, with and without the boundary "
               "approach: identical surface results, cost saving vs N − N_b (report Table 3, Fig. 20)")

T_END, OUT_DT, RIGID_DT = 1.0, 1e-3, 8.7e-4      # [s]
N_MODES = 10
COARSE_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 5};
MeshSize{ PointsOf{ Volume{1}; } } = 1.0;
Physical Surface("x0") = {1};
Physical Volume("body") = {1};
"""
MESHES = {"coarse": None, "regular": 0.5, "fine": 0.4}   # box() mesh size [m]; None: COARSE_GEO


@lru_cache(maxsize=1)
def coarse_beam():
    """(mesh, BodyData) of the coarse beam: COARSE_GEO meshed by gmsh (tet10)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "coarse_beam.geo")
        with open(path, "w") as f:
            f.write(COARSE_GEO)
        mesh = mesh_geo_file(path, order=2, mesh_size=1.0)
    if np.abs(mesh.points[mesh.group("x0"), 0]).max() > 1e-12:
        raise RuntimeError("COARSE_GEO: surface 1 of the OpenCASCADE box is not the face x = 0")
    return mesh, build_body(mesh, MATERIAL, N_MODES)


def scene(name):
    """(mesh, ModalBasis, case-study StepLoads) of one mesh of MESHES."""
    size = MESHES[name]
    mesh, data = coarse_beam() if size is None else _wobble.beam(size, N_MODES)
    return mesh, ModalBasis.from_body(data), _wobble.case_study_loads(mesh)


def simulate(basis, loads, boundary, t_out):
    """Displacements (n_t, k, 3) [m]: k = N_b surface nodes with the boundary approach, else all N."""
    return SimpleRB(basis, [loads], dt=RIGID_DT, boundary=boundary).solve(t_out).displacements()


def fit_through_zero(x, y, sigma):
    """(C2, its standard error, residuals y − C2 x) of the weighted least-squares line
    y = C2 x through zero, weights 1/σ²."""
    w = 1.0 / sigma ** 2
    c2 = np.sum(w * x * y) / np.sum(w * x * x)
    return c2, 1.0 / np.sqrt(np.sum(w * x * x)), y - c2 * x


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("boundary",))
    t_out = np.arange(0.0, T_END + 0.5 * OUT_DT, OUT_DT)
    repeats, batch = (3, 0.05) if quick else (7, 0.3)
    table = ["| mesh | N | N_b | boundary approach | median CPU [ms] | std [ms] | robust σ [ms] | loops | "
             "max rel. difference (displacement / elastic part) |", "|---|---|---|---|---|---|---|---|---|"]
    fit = ["| mesh | N − N_b | Δcost [ms] | σ [ms] | C2 (N − N_b) [ms] | residual [ms] | residual / σ |",
           "|---|---|---|---|---|---|---|"]
    x, dcost, sigma = [], [], []
    for name in MESHES:
        mesh, basis, loads = scene(name)
        surface = basis.surface
        runs = [lambda: simulate(basis, loads, True, t_out), lambda: simulate(basis, loads, False, t_out)]
        with threadpool_limits(limits=1, user_api="blas"):
            timings = cpu_samples(runs, repeats, batch)
        if name == "fine":
            default = cpu_samples(runs, repeats, batch)
        ref = timings[1].result[:, surface]
        diff = np.abs(timings[0].result - ref).max() / np.abs(ref).max()
        elastic = [SimpleRB(basis, [loads], dt=RIGID_DT, boundary=b).solve(t_out, nodes=surface)
                   .elastic_displacement() for b in (True, False)]
        diff_elastic = np.abs(elastic[0] - elastic[1]).max() / np.abs(elastic[1]).max()
        for boundary, timing in zip((True, False), timings):
            result.rows.append(make_row(NAME, {"mesh": name, "nodes": mesh.n_nodes, "boundary": boundary},
                                        timing.median, diff, "max rel. difference boundary vs all nodes",
                                        "all-node run restricted to the surface", surface_nodes=surface.size,
                                        cpu_std=timing.std))
            table.append(f"| {name} | {mesh.n_nodes} | {surface.size} | {'yes' if boundary else 'no'} | "
                         f"{timing.median * 1e3:.2f} | {timing.std * 1e3:.2f} | "
                         f"{timing.robust_std * 1e3:.2f} | {timing.loops} | {diff:.1e} / {diff_elastic:.1e} |")
        paired = CpuTiming(None, timings[1].samples - timings[0].samples, 1)
        x.append(mesh.n_nodes - surface.size)
        dcost.append(paired.median)
        sigma.append(max(paired.robust_std, 1e-6))       # 1 µs floor: tied samples give zero scatter
    result.notes.append("Case study (report Table 3; report: 0.61/0.63 s, 1.34/1.50 s, 3.30/3.61 s with/"
                        "without on 237/579/1141 nodes). Differences relative to the all-node maximum; "
                        "'elastic part': P r of the surface nodes alone. robust σ = 1.4826 × median "
                        "absolute deviation. BLAS threads: 1; with the default BLAS threads "
                        f"the fine mesh took {default[0].median * 1e3:.2f} ± {default[0].std * 1e3:.2f} ms "
                        f"(boundary) and {default[1].median * 1e3:.2f} ± {default[1].std * 1e3:.2f} ms "
                        "(all nodes).\n\n" + "\n".join(table))
    x, dcost, sigma = map(np.asarray, (x, dcost, sigma))
    c2, c2_err, residuals = fit_through_zero(x, dcost, sigma)
    for name, xi, d, sd, res in zip(MESHES, x, dcost, sigma, residuals):
        fit.append(f"| {name} | {xi} | {d * 1e3:.2f} | {sd * 1e3:.2f} | {c2 * xi * 1e3:.2f} | "
                   f"{res * 1e3:+.2f} | {res / sd:+.2f} |")
    result.notes.append("Eq. 41 fit through zero (report Fig. 20): Δcost = median of the paired differences "
                        "cost(all) − cost(boundary) of the interleaved samples, σ its robust scatter, "
                        f"weights 1/σ². C2 = {c2 * 1e6:.2f} ± {c2_err * 1e6:.2f} µs per interior node "
                        f"({T_END:g} s, {t_out.size} outputs, {N_MODES} modes); "
                        f"χ²/dof = {np.sum((residuals / sigma) ** 2) / (x.size - 1):.2f}.\n\n" + "\n".join(fit))
    return result
