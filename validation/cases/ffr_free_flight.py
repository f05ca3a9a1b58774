"""The report's free 1 × 1 × 5 m steel beam under its "complex forcing" (report Fig. 6c).

F1 on the z = 5 face and F2 on the z = 0 face, both along the body y axis and fixed in
the body frame (they turn with it), spread over the face nodes by area
(``preprocess.face_load``): F1 = −100 N, F2 = +100 N for t < 0.5 s, then F1 = 500 N,
F2 = 300 N; free-free modes (rigid modes removed), 1 s, at rest at t = 0.

Errors at 1 ms output intervals, against a converged reference (our explicit RK4 at
h = 2.5e-5 s with the same modes; its own step-halving difference is reported):

* trajectory: max_t |r_A − r_A,ref| / max_t |r_A,ref| of node A (the corner at the
  mesh origin, report Sec. 5.1), dominated by the rigid motion;
* elastic: max_t |ū_f,A − ū_f,A,ref| / max_t |ū_f,A,ref| of A's elastic displacement
  in the body frame (about 1e-7 m).

Swept: step size, mode count (10, 30) and integrator. With Exudyn importable, its
``ObjectFFRFreducedOrder`` runs the same scene with our stiffness, lumped masses and
modes (generalized-α, fixed step), timed in the same process. Load jumps: ours stops
just before t = 0.5 s and restarts there; Exudyn evaluates loads at the step ends.
"""

from __future__ import annotations

import time

import numpy as np

from mbs import DistributedForce, FlexibleBodyFFR, System, Tabulated
from preprocess import box, build_body, face_load
from validation import CaseResult, make_row
from validation.cases.cantilever import MATERIAL, REPORT_MESH_SIZE

NAME = "ffr_free_flight"
DESCRIPTION = ("report's free 1x1x5 m beam under its complex forcing, 1 s: node A trajectory "
               "and elastic deformation vs a converged reference; Exudyn side by side")

T_END, T_SWITCH, OUT_DT = 1.0, 0.5, 1e-3
REFERENCE_DT = 2.5e-5


def magnitudes(t):
    """(F1, F2) [N] of the complex forcing at time t [s] (report Fig. 6c)."""
    return (-100.0, 100.0) if t < T_SWITCH else (500.0, 300.0)


def face_weights(mesh):
    """{group: (nodes, area weights summing to 1)} of the two loaded faces."""
    out = {}
    for group in ("z1", "z0"):
        nodes = mesh.group(group)
        out[group] = (nodes, face_load(mesh, nodes, [1.0, 0.0, 0.0])[nodes, 0])
    return out


def simulate(data, weights, n_modes, dt, integrator, probe, plan=False, **options):
    """Run the scene; returns (times, r_A (n, 3), ū_f,A (n, 3), CPU s of ``System.simulate``,
    planning included). The loads are step tables (their jump is a breakpoint).
    ``plan=False`` (default) integrates the FFR equations with ``integrator`` and its
    ``options`` (the case measures the integrators); ``plan=True`` lets the planner
    choose (SimpleRB here: the coupling is negligible)."""
    system = System()
    beam = system.add(FlexibleBodyFFR(data, n_modes, name="beam"))
    for k, group in enumerate(("z1", "z0")):
        nodes, w = weights[group]
        rows = [(0.0, magnitudes(t)[k], 0.0) for t in (0.0, T_SWITCH)]
        system.add(DistributedForce(beam, nodes, w, Tabulated([0.0, T_SWITCH], rows)))
    node_a = beam.node(probe)
    start = time.process_time()
    res = system.simulate(T_END, dt, integrator=integrator, t_out=np.arange(0.0, T_END + 1e-12, OUT_DT),
                          outputs={"A": node_a,
                                   "A_elastic": lambda t, q, u: node_a.elastic_displacement(q[beam.q_slice])},
                          plan=plan, **options)
    return res.t, res["A"], res["A_elastic"], time.process_time() - start


def errors(r, e, ref):
    """(trajectory error, elastic error), both relative to the reference's maximum."""
    _, r_ref, e_ref = ref
    traj = np.linalg.norm(r - r_ref, axis=1).max() / np.linalg.norm(r_ref, axis=1).max()
    elas = np.linalg.norm(e - e_ref, axis=1).max() / np.linalg.norm(e_ref, axis=1).max()
    return traj, elas


def node_a(mesh) -> int:
    """Index of node A, the corner at the mesh origin (report Sec. 5.1)."""
    return int(np.argmin(np.linalg.norm(mesh.points, axis=1)))


def exudyn_run(data, weights, n_modes, dt, probe):
    """The same scene in Exudyn (:func:`validation.peers.exudyn_ffr.free_flight`, the peer
    must be installed): ``n_modes`` modes of ``data``, the two face loads of ``weights``
    (:func:`face_weights`), step ``dt`` [s]; returns (r_A (n, 3) [m], ū_f,A (n, 3) [m],
    CPU s) at the output times of :func:`simulate`, node A being ``probe``."""
    from validation.peers import exudyn_ffr

    loads = [(np.bincount(nodes, w, minlength=data.n_nodes), np.array([0.0, 1.0, 0.0]),
              lambda t, k=k: magnitudes(t)[k])
             for k, (nodes, w) in enumerate(weights[g] for g in ("z1", "z0"))]
    out = exudyn_ffr.free_flight(data.u0, data.masses, data.stiffness, data.phi[:, :n_modes], loads,
                                 T_END, dt, probe, np.arange(0.0, T_END + 1e-12, OUT_DT))
    return out["position"], out["elastic"], out["cpu_s"]


def run(quick: bool) -> CaseResult:
    mesh = box(1.0, 1.0, 5.0, REPORT_MESH_SIZE, order=2)
    probe = node_a(mesh)
    data = build_body(mesh, MATERIAL, 30, clamp=None)
    weights = face_weights(mesh)
    if quick:
        sweep = {10: [("generalized-alpha", 1e-3), ("generalized-alpha", 2.5e-4)]}
        ref_dt = 2 * REFERENCE_DT
    else:
        sweep = {10: [("generalized-alpha", h) for h in (1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5)]
                 + [("rk4", 1e-4)],
                 30: [("generalized-alpha", h) for h in (1e-3, 2.5e-4, 1e-4)]}
        ref_dt = REFERENCE_DT
    from validation.peers import exudyn_ffr

    result = CaseResult(plot_groups=["code", "n_modes", "integrator", "output"])
    lines = ["| code | modes | integrator | h [s] | µs/step | trajectory error | elastic error | CPU s |",
             "|---|---|---|---|---|---|---|---|"]
    for n_modes, configs in sweep.items():
        ref = simulate(data, weights, n_modes, ref_dt, "rk4", probe)[:3]
        check = simulate(data, weights, n_modes, 2 * ref_dt, "rk4", probe)[:3]
        ref_traj, ref_elas = errors(check[1], check[2], ref)
        result.notes.append(f"reference for {n_modes} modes: RK4 h = {ref_dt:g} s; RK4 at h = "
                            f"{2 * ref_dt:g} s differs from it by {ref_traj:.2e} (trajectory) and "
                            f"{ref_elas:.2e} (elastic); max |ū_f,A| = "
                            f"{np.linalg.norm(ref[2], axis=1).max():.3e} m")
        reference = f"RK4 h={ref_dt:g} s, {n_modes} modes"
        runs = [("ffrmbs", integ, h) for integ, h in configs]
        if exudyn_ffr.available():
            runs += [("exudyn", "generalized-alpha", h) for integ, h in configs
                     if integ == "generalized-alpha" and h >= 5e-5]
        for code, integ, h in runs:
            if code == "ffrmbs":
                options = {"rho_inf": 0.9} if integ == "generalized-alpha" else {}
                _, r, e, cpu = simulate(data, weights, n_modes, h, integ, probe, **options)
            else:
                r, e, cpu = exudyn_run(data, weights, n_modes, h, probe)
            traj, elas = errors(r, e, ref)
            config = {"n_modes": n_modes, "integrator": integ, "dt": h}
            per_step = cpu / round(T_END / h) * 1e6
            for kind, err in (("trajectory", traj), ("elastic", elas)):
                result.rows.append(make_row(NAME, {**config, "output": kind}, cpu, err, "relative",
                                            reference, code=code, us_per_step=per_step))
            lines.append(f"| {code} | {n_modes} | {integ} | {h:g} | {per_step:.0f} | {traj:.2e} | "
                         f"{elas:.2e} | {cpu:.2f} |")
    if not exudyn_ffr.available():
        result.skipped.append("exudyn: skipped: exudyn not installed (pip install '.[peers]')")
    result.notes.append("\n".join(lines))
    return result
