"""The main job: the point mass dropped on the clamped flexible beam (thesis Sec. 5.2,
setup A; :mod:`validation.scenes.point_mass_beam`), run by ``ffrmbs run``.

It simulates the scene with Moreau time-stepping, then once more at half the step to
estimate the time-discretization error of the outputs (|x(Δt) − x(Δt/2)|, the error of
the Δt/2 run being about half of it for this first-order scheme across impacts), and
reports:

- contact: the intervals in which the contact was closed (from the per-step trace), the
  largest penetration [m];
- energy balance: E(0), E(end), the work of the contact impulses Σ Λᵀ(γ⁺ + γ⁻)/2 (what the
  impact law takes out) and the residual E(end) − E(0) − W, the integrator's own error;
- outputs: point-mass y position [m] and velocity [m/s], node 19's y displacement [m];
- cost: wall and CPU seconds, µs per step (after a short warm-up run that compiles the
  numba kernels, whose time is printed apart).

Files written to ``out``: ``point_mass_beam.h5`` (datasets ``t``, ``y``, ``vy``,
``node19`` (n, 3), ``trace/*`` per step, attributes: the scene and the summary) and
``point_mass_beam.png`` (the three outputs against time). The mode-truncation error is
not part of this estimate: the validation case ``contact_point_mass_beam`` sweeps the
modes against all 750.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ffrmbs.errors import ModelError


@dataclass
class JobSettings:
    setup: str = "A"
    modes: int = 20
    law: str = "impact"           # "impact" (Newton, e) or "penalty" (k = 1e7 N/m)
    e: float = 0.0
    contour: str = "2s"           # "2s" or "band"
    t_end: float = 0.1            # [s]
    dt: float = 1e-5              # [s]
    theta: float = 0.5            # elastic forces trapezoidal: no numerical damping
    check: bool = True            # a second run at dt/2 for the error estimate
    n_out: int = 1001             # output samples


def contact_intervals(t, dt, closed):
    """[(t_close, t_open)] [s] of the runs of steps with a closed contact (trace arrays:
    step end times, step sizes, closed-contact counts)."""
    on = np.asarray(closed) > 0
    edges = np.flatnonzero(np.diff(np.concatenate(([0], on.view(np.int8), [0]))))
    starts, stops = edges[::2], edges[1::2] - 1
    return [(float(t[a] - dt[a]), float(t[b])) for a, b in zip(starts, stops)]


def energy_balance(system, trace) -> dict:
    """E(0), E(end) [J], the work of the contact impulses W = Σ Λᵀ(γ⁺ + γ⁻)/2 [J] and the
    residual E(end) − E(0) − W [J] (the integrator's own energy error) of a Moreau run
    with ``trace=True`` from the system's initial state."""
    q0, u0 = system.initial_state()
    E0 = float(system.kinetic_energy(0.0, q0, u0) + system.potential_energy(0.0, q0))
    work, E_end = float(trace["impulse_work"].sum()), float(trace["energy"][-1])
    return {"initial": E0, "final": E_end, "impulse_work": work, "residual": E_end - E0 - work}


def _simulate(settings, dt, data):
    from validation.scenes import point_mass_beam as pmb

    scene = pmb.build(settings.setup, settings.modes, settings.law, settings.e, contour=settings.contour,
                      data=data)
    t_out = np.linspace(0.0, settings.t_end, settings.n_out)
    c0, w0 = time.process_time(), time.perf_counter()
    res = scene.system.simulate(settings.t_end, dt, integrator="moreau", theta=settings.theta, t_out=t_out,
                                outputs=scene.outputs(), trace=True)
    res.stats["job_cpu_s"], res.stats["job_wall_s"] = time.process_time() - c0, time.perf_counter() - w0
    return scene, res


def run_job(settings: JobSettings, out, log=print) -> dict:
    """Run the scene, write the result file and the plot to ``out``; return the summary."""
    from validation.scenes import point_mass_beam as pmb

    if not (settings.t_end > 0 and settings.dt > 0 and settings.n_out >= 2):
        raise ModelError("need t_end > 0, dt > 0 and at least 2 output samples")
    out = Path(out)
    data = pmb.default_beam_data(log=log)
    if settings.modes > data.n_modes:
        raise ModelError(f"the beam has {data.n_modes} modes; asked for {settings.modes}")
    log(f"scene: thesis Sec. 5.2 setup {settings.setup}: point mass {pmb.MASS} kg at "
        f"({', '.join(f'{1e3 * x:g}' for x in pmb.SETUPS[settings.setup])}) mm, v = {pmb.VELOCITY} m/s, on the "
        f"{1e3 * pmb.LENGTH:g} x {1e3 * pmb.HEIGHT:g} x {1e3 * pmb.WIDTH:g} mm beam clamped at x = 0 "
        f"(E = {pmb.YOUNG / 1e6:g} MPa, ρ = {pmb.DENSITY:g} kg/m³, ν = {pmb.POISSON}); {settings.modes} of "
        f"{data.n_modes} modes, {settings.contour} contour, law {settings.law}"
        + (f" (e = {settings.e})" if settings.law == "impact" else f" (k = {pmb.PENALTY_K:g} N/m)")
        + f"; Moreau, dt = {settings.dt:g} s, θ = {settings.theta}, {settings.t_end:g} s")
    w0 = time.perf_counter()               # compile the kernels (numba, first use) outside the timing:
    warm = JobSettings(**{**settings.__dict__, "t_end": 0.0125, "n_out": 2})     # past the first contact
    _simulate(warm, 1e-4, data)
    log(f"kernels compiled or loaded in {time.perf_counter() - w0:.2f} s")
    scene, res = _simulate(settings, settings.dt, data)
    tr = res.trace
    summary = {
        "contact_intervals_s": contact_intervals(tr["t"], tr["dt"], tr["closed"]),
        "max_penetration_m": float(res.stats["max_penetration"]),
        "energy_J": energy_balance(scene.system, tr),
        "final": {"y_m": float(res["y"][-1]), "vy_m_s": float(res["vy"][-1]),
                  "node19_y_m": float(res["node19"][-1, 1])},
        "steps": int(res.stats["steps"]), "wall_s": res.stats["job_wall_s"], "cpu_s": res.stats["job_cpu_s"],
        "us_per_step": 1e6 * res.stats["job_wall_s"] / res.stats["steps"],
    }
    if settings.check:
        _, half = _simulate(settings, 0.5 * settings.dt, data)
        summary["error_estimate"] = {name: float(np.max(np.abs(res[name] - half[name])))
                                     for name in ("y", "vy", "node19")}
    _write(out, settings, res, summary)
    _report(summary, settings, log)
    return summary


def _write(out, settings, res, summary):
    import h5py

    out.mkdir(parents=True, exist_ok=True)
    path = out / "point_mass_beam.h5"
    tmp = out / ".point_mass_beam.h5.tmp"
    try:
        with h5py.File(tmp, "w") as f:
            f["t"] = res.t
            for name in ("y", "vy", "node19"):
                f[name] = res[name]
            for key, values in res.trace.items():
                f[f"trace/{key}"] = values
            f.attrs["scene"] = json.dumps(settings.__dict__)
            f.attrs["summary"] = json.dumps(summary)
            f.attrs["units"] = "SI: s, m, m/s, J"
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    _plot(res, out / "point_mass_beam.png", settings)


def _plot(res, path, settings):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 7))
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 1, sharex=True)
    t_ms = 1e3 * res.t
    axes[0].plot(t_ms, 1e3 * res["y"])
    axes[0].set_ylabel("point mass y [mm]")
    axes[1].plot(t_ms, res["vy"])
    axes[1].set_ylabel("point mass v_y [m/s]")
    axes[2].plot(t_ms, 1e3 * res["node19"][:, 1])
    axes[2].set_ylabel("node 19 u_y [mm]")
    axes[2].set_xlabel("t [ms]")
    fig.suptitle(f"point mass on beam, setup {settings.setup}, {settings.modes} modes, dt = {settings.dt:g} s")
    fig.savefig(path, dpi=100)


def _report(s, settings, log):
    iv = s["contact_intervals_s"]
    log(f"contact: closed in {len(iv)} interval(s)"
        + (": " + ", ".join(f"{1e3 * a:.3f}-{1e3 * b:.3f} ms" for a, b in iv[:5]) + (" ..." if len(iv) > 5 else "")
           if iv else ""))
    log(f"maximum penetration: {s['max_penetration_m']:.3g} m")
    e = s["energy_J"]
    log(f"energy: initial {e['initial']:.6g} J, final {e['final']:.6g} J, impulse work {e['impulse_work']:.6g} J, "
        f"residual {e['residual']:.3g} J ({e['residual'] / e['initial']:+.2e} of the initial)")
    f = s["final"]
    log(f"at t = {settings.t_end:g} s: point mass y = {1e3 * f['y_m']:.4f} mm, v_y = {f['vy_m_s']:.5f} m/s; "
        f"node 19 u_y = {1e3 * f['node19_y_m']:.5f} mm")
    if "error_estimate" in s:
        est = s["error_estimate"]
        log(f"accuracy (time step, |run(dt) - run(dt/2)| over all outputs): y {est['y']:.2e} m, "
            f"v_y {est['vy']:.2e} m/s, node 19 {est['node19']:.2e} m; mode truncation: see the "
            f"contact_point_mass_beam validation case")
    log(f"cost: {s['steps']} steps in {s['wall_s']:.2f} s wall ({s['cpu_s']:.2f} s CPU), "
        f"{s['us_per_step']:.0f} µs per step")
