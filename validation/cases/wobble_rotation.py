"""Rotation of the free beam: the report's constant angular acceleration test (Sec. 5.7.2,
Fig. 6b, 15) and a free spin, in three formulations and Akantu.

Scene 1 ("couple"): +100 N along y on the face z = 5 and −100 N on z = 0, body-fixed,
from rest, 1 s (quick: 0.2 s). References: the analytic rigid rotation about x,
θ(t) = T t² / (2 I_xx) with T and I_xx of the lumped masses (the beam's x axis is a
principal axis up to mesh asymmetry), and Akantu's explicit FE run of the same mesh and
loads (follower forces: they turn with the body's best-fit rotation). Rows per
formulation: rotation-angle error vs analytic (max_t |θ_x − θ_ref| / max θ_ref) and RMS
displacement error over all nodes as a fraction of Akantu's RMS displacement.

Scene 2 ("spin"): no load, initial spin 1 rad/s about x through the centre of mass,
0.2 s: the centrifugal stretching couples rotation and deformation. SimpleRB ignores
it; CoupledRB (report Sec. 3.4.4) and the full FFR equations (:class:`~mbs.FlexibleBodyFFR`
with generalized-α: the same physics in a second formulation) resolve it. Error:
elastic displacement of node A in the body frame against FFR at the smallest step.

Scene 3 ("tumble"): SimpleRB's rigid-body schemes — the report's explicit one (eq. 26–28)
and RKMK4 — on a body spinning off its principal axes under a couple, 5 s, against
scipy's solve_ivp on the quaternion equations: the error-against-run-time table that
chose the default scheme.
"""

from __future__ import annotations

import numpy as np

from mbs import FlexibleBodyFFR, NodalForces, System
from mbs.modal import CoupledRB, ModalBasis, SimpleRB
from validation import CaseResult, cpu_per_call, make_row, timed
from validation.cases import _wobble as wb

NAME = "wobble_rotation"
DESCRIPTION = ("free beam under a ±100 N couple (report Fig. 15) and a free spin: SimpleRB, CoupledRB, "
               "full FFR equations, analytic rotation and Akantu")


def _ffr(data, n_modes, loads, t_out, dt, omega=None):
    """The scene with FlexibleBodyFFR + generalized-α: (displacements (n_t, N, 3), elastic
    displacements in B (n_t, N, 3), CPU s)."""
    system = System()
    beam = system.add(FlexibleBodyFFR(data, n_modes, name="beam"))
    if loads is not None:
        times, forces = wb.nodal_history(loads, data.n_nodes)
        system.add(NodalForces(beam, times, forces))
    if omega is not None:
        c = data.center_of_mass
        beam.set_initial(v=np.cross(omega, -c), omega=omega)
    P = data.phi[:, :n_modes]
    res = system.simulate(t_out[-1], dt, t_out=t_out, plan=False, outputs={
        "x": lambda t, q, u: beam.node_positions(q[beam.q_slice]),
        "e": lambda t, q, u: (P @ beam.elastic_coordinates(q[beam.q_slice])).reshape(-1, 3)})
    return res["x"] - data.u0[None], res["e"], res.stats["cpu_s"]


def _couple(result, quick, mesh, data):
    t_end = 0.2 if quick else 1.0
    t_out = np.linspace(0.0, t_end, 101)
    basis = ModalBasis.from_body(data)
    loads = wb.rotation_loads(mesh)
    T = loads.moments(basis.b0)[0]
    theta_ref = T[0] * t_out ** 2 / (2 * basis.inertia[0, 0])
    runs = {}
    for scheme in ("report", "rkmk4"):
        for dt in ((0.1, 0.01) if quick else (0.1, 0.01, 1e-3)):
            res = SimpleRB(basis, [loads], dt=dt, scheme=scheme).solve(t_out)
            runs[("SimpleRB", scheme, dt)] = (res.displacements(), res.rotation_vectors()[:, 0],
                                               res.stats["cpu_s"])
    for dt in ((1e-3,) if quick else (1e-3, 1e-4)):
        res = CoupledRB(basis, [loads], dt=dt).solve(t_out)
        runs[("CoupledRB", "report", dt)] = (res.displacements(), res.rotation_vectors()[:, 0], res.stats["cpu_s"])
    u, _, cpu = _ffr(data, basis.n_modes, loads, t_out, 1e-3)
    runs[("FFR", "generalized-alpha", 1e-3)] = (u, None, cpu)

    aka = None
    from validation.peers import akantu_dynamics

    if akantu_dynamics.available():
        aka = wb.akantu_run(mesh, data, loads, t_out, follower=True)
    else:
        result.skipped.append("akantu: skipped: akantu not installed (pip install '.[peers]')")
    lines = ["| formulation | scheme | dt [s] | CPU s | θ_x error vs analytic | RMS error vs Akantu |",
             "|---|---|---|---|---|---|"]
    a_idx = wb.node_a(mesh)
    for (form, scheme, dt), (u, theta, cpu) in runs.items():
        config = {"scene": "couple", "formulation": form, "scheme": scheme, "dt": dt}
        e_theta = None
        if theta is not None:
            e_theta = np.abs(theta - theta_ref).max() / np.abs(theta_ref).max()
            result.rows.append(make_row(NAME, config, cpu, e_theta, "rel. rotation angle",
                                        "analytic T t²/(2 I_xx)"))
        e_aka = None
        if aka is not None:
            _, e_aka = wb.rms_error(u[1:], aka["displacement"][1:])
            result.rows.append(make_row(NAME, config, cpu, e_aka, "RMS / Akantu RMS", "akantu explicit FE"))
        lines.append(f"| {form} | {scheme} | {dt:g} | {cpu:.3f} | "
                     f"{'—' if e_theta is None else f'{e_theta:.2e}'} | {'—' if e_aka is None else f'{e_aka:.2%}'} |")
    if aka is not None:
        # small-rotation angle of the FE body: θ = Î⁻¹ Σ m b × u (exact to O(θ²))
        mbu = np.einsum("i,tia->ta", data.masses, np.cross(basis.b0[None], aka["displacement"]))
        theta_aka = np.linalg.solve(basis.inertia, mbu.T)[0]
        e_theta = np.abs(theta_aka - theta_ref).max() / np.abs(theta_ref).max()
        u_a = aka["displacement"][:, a_idx]
        config = {"scene": "couple", "formulation": "akantu", "scheme": "central differences", "dt": aka["dt"]}
        result.rows.append(make_row(NAME, config, aka["cpu_s"], e_theta, "rel. rotation angle",
                                    "analytic T t²/(2 I_xx)", code="akantu"))
        lines.append(f"| Akantu | central differences | {aka['dt']:.3g} | {aka['cpu_s']:.2f} | {e_theta:.2e} "
                     f"| reference (its max |u_x(A)| / |u(A)| = {np.abs(u_a[:, 0]).max() / np.abs(u_a).max():.1e}, "
                     "0 for a rigid rotation about x) |")
    result.notes.append(f"**Couple** (±100 N, T_x = {T[0]:.1f} N m, I_xx = {basis.inertia[0, 0]:.1f} kg m², "
                        f"{t_end:g} s):\n\n" + "\n".join(lines))


def _spin(result, quick, data):
    t_out = np.linspace(0.0, 0.05 if quick else 0.2, 51)
    omega = np.array([1.0, 0.0, 0.0])
    basis = ModalBasis.from_body(data)
    a_idx = int(np.argmin(np.linalg.norm(data.u0, axis=1)))
    ref_dt = 2.5e-5 if quick else 1e-5
    (_, e_ref, _), cpu_ref = timed(_ffr, data, basis.n_modes, None, t_out, ref_dt, omega)
    ref = e_ref[:, a_idx]
    scale = np.linalg.norm(ref, axis=1).max()
    lines = ["| formulation | dt [s] | CPU s | error of A's elastic displacement vs FFR |", "|---|---|---|---|"]
    cases = [("SimpleRB", 1e-2), ("CoupledRB", 1e-4), ("CoupledRB", 1e-5)] + \
            [("FFR", dt) for dt in ((1e-4,) if quick else (1e-3, 1e-4, 5e-5))]
    for form, dt in cases:
        if form == "FFR":
            (_, e, _), cpu = timed(_ffr, data, basis.n_modes, None, t_out, dt, omega)
            e = e[:, a_idx]
        else:
            solver = SimpleRB if form == "SimpleRB" else CoupledRB
            res = solver(basis, angular_velocity=omega, dt=dt).solve(t_out, nodes=[a_idx])
            e, cpu = res.elastic_displacement()[:, 0], res.stats["cpu_s"]
        err = np.linalg.norm(e - ref, axis=1).max() / scale
        result.rows.append(make_row(NAME, {"scene": "spin", "formulation": form, "dt": dt}, cpu, err,
                                    "rel. elastic displacement of A", f"FFR generalized-α dt={ref_dt:g}"))
        lines.append(f"| {form} | {dt:g} | {cpu:.3f} | {err:.2e} |")
    result.notes.append(f"**Spin** (1 rad/s about x, no load): max elastic displacement of A "
                        f"{scale:.3e} m (reference FFR, dt = {ref_dt:g} s, {cpu_ref:.1f} CPU s).\n\n" + "\n".join(lines))


def _tumble_reference(basis, F_B, T_B, Om0, t_out):
    """R and Ω by scipy's solve_ivp (DOP853, rtol 1e-12) on the quaternion form of Euler's
    equations with constant body-frame loads: an independent formulation."""
    from scipy.integrate import solve_ivp

    from mbs.bodies.rotations import quat_multiply, quat_to_matrix

    I = basis.inertia

    def rhs(t, y):
        p, Om = y[:4] / np.linalg.norm(y[:4]), y[4:]
        return np.concatenate([0.5 * quat_multiply(p, np.concatenate([[0.0], Om])),
                               np.linalg.solve(I, T_B - np.cross(Om, I @ Om))])

    sol = solve_ivp(rhs, (0.0, t_out[-1]), np.concatenate([[1.0, 0, 0, 0], Om0]), t_eval=t_out,
                    rtol=1e-12, atol=1e-14, method="DOP853")
    return np.array([quat_to_matrix(p / np.linalg.norm(p)) for p in sol.y[:4].T])


def _tumble(result, quick, mesh, data):
    """SimpleRB's two rigid-body schemes on a tumbling body (off-principal spin plus a torque):
    the work-precision table that chose RKMK4 as the default."""
    t_out = np.linspace(0.0, 5.0, 11)
    basis = ModalBasis.from_body(data)
    loads = wb.rotation_loads(mesh, 2e4)
    Om0 = np.array([0.3, -0.2, 1.1])
    R_ref = _tumble_reference(basis, loads.resultants()[0], loads.moments(basis.b0)[0], Om0, t_out)
    lines = ["| scheme | dt [s] | CPU s | max orientation error |", "|---|---|---|---|"]
    for scheme in ("report", "rkmk4"):
        for dt in ((0.1, 0.01, 1e-3) if quick else (0.1, 0.03, 0.01, 3e-3, 1e-3, 3e-4, 1e-4)):
            timing = cpu_per_call(lambda: SimpleRB(basis, [loads], angular_velocity=Om0, dt=dt,
                                                   scheme=scheme).solve(t_out), repeats=3)
            err = np.abs(timing.result.R - R_ref).max()
            cpu = timing.median
            result.rows.append(make_row(NAME, {"scene": "tumble", "formulation": "SimpleRB", "scheme": scheme,
                                               "dt": dt}, cpu, err, "max |R − R_ref|", "solve_ivp quaternions"))
            lines.append(f"| {scheme} | {dt:g} | {cpu:.4f} | {err:.2e} |")
    result.notes.append("**Tumble** (Ω0 = (0.3, −0.2, 1.1) rad/s, ±20 kN couple, 5 s; rigid motion only, "
                        "median CPU of 3 batches):\n\n" + "\n".join(lines))


def run(quick: bool) -> CaseResult:
    mesh, data = wb.beam(n_modes=10)
    result = CaseResult(plot_groups=["scene", "formulation", "error_kind"])
    wb.warm_up()
    _couple(result, quick, mesh, data)
    _spin(result, quick, data)
    _tumble(result, quick, mesh, data)
    return result
