"""A point mass dropped on a clamped flexible beam (thesis Sec. 5.2, Fig. 5.4–5.13, Table 5.3).

Scene: :mod:`ffrmbs_app.scenes.point_mass_beam` — beam 250 x 50 x 50 mm, ρ = 920 kg/m³,
E = 50 MPa, ν = 0.3, clamped at x = 0 (our choice; the thesis leaves the support
implicit), structured tet4 mesh with 275 nodes and 750 clamped modes; point mass 0.5 kg
at (235, 52, 25) mm (setup A) or (235, 52, 40) mm (setup B), v = (0, −0.2, 0) m/s, no
gravity; the point against a 2s neutral contour on the top face (or a FlexibleBand on
its centre line). The contact closes at t = 2 mm / 0.2 m/s = 10 ms; simulated to
T = 0.05 s (the thesis's Table 5.3 end time), 501 output samples.

Outputs (thesis Fig. 5.12, 5.13): the point mass's y position and velocity and the
y displacement of node 19 at (250, 50, 25) mm. Errors against a reference run of the
same scene, law and contour with **all 750 modes** of the FE model at Δt = 2e-6 s
(the reduced model's error then contains the mode truncation and the time
discretization); the rows of the step-size sweep also compare against the same
number of modes at Δt = 1e-6 s, isolating the integrator's share:

- "v_y RMS / 0.2 m/s": RMS over the samples of v_y − v_y,ref, divided by the impact speed;
- "node 19 RMS / peak": RMS of u_y − u_y,ref at node 19 over max |u_y,ref|;
- "y max [m]": max |y − y_ref| of the point mass (absolute).

Sweeps (setup A, Newton impact e = 0, 2s contour, θ = 0.5, unless the row says):
modes 5 … 200 at Δt = 1e-5, each without and with residual flexibility (config
``residual_flexibility`` "off" / "on", :mod:`contours.residual`), setups A and B; the
integrator: fixed Δt = 4e-5 … 5e-6 and adaptive (step doubling with gap control, atol
1e-6 … 1e-8, rtol 0, largest step 1e-4 s) at 20 modes; the law: e ∈ {0, 0.7, 1} and the penalty law k = 1e7 N/m (no damping), each
against its own reference; e = 1 with residual flexibility, whose error is the
largest change of the total energy (kinetic + elastic + the contact spring's ½ Fᵀδ) over
the run; the FlexibleBand against the 2s contour at 20 modes in setups A and B, each
without and with residual flexibility (thesis Table 5.3: MBSim took 36 s / 74 s
(band / 2s) for setup A and 33 s / 46 s for setup B). Extra columns: the energy
balance residual (E(T) − E(0) − W_Λ)/E(0) with W_Λ the work of the contact impulses
(set-valued laws), the number of contact intervals, the largest penetration, steps.
CPU time: the simulation alone (body data cached, kernels compiled by a warm-up run); a
configuration in two sweeps (20 modes, 2s contour: the modes and the contour sweep) is
simulated once, its rows in both sweeps carry that run's CPU time.
"""

from __future__ import annotations

import numpy as np

from ffrmbs_app.job import contact_intervals, energy_balance
from validation import CaseResult, make_row, timed
from ffrmbs_app.scenes import point_mass_beam as pmb

NAME = "contact_point_mass_beam"
DESCRIPTION = ("thesis Sec. 5.2: point mass dropped on a clamped flexible beam; modes, integrator, law and "
               "contour against all 750 modes at a tiny step")

T_END = 0.05
N_OUT = 501
REF_DT = 2e-6
KINDS = ("v_y RMS / 0.2 m/s", "node 19 RMS / peak", "y max [m]")


def _simulate(data, setup="A", modes=20, law="impact", e=0.0, contour="2s", integrator="moreau", dt=1e-5,
              atol=None, t_end=T_END, residual_flexibility="off"):
    scene = pmb.build(setup, modes, law, e, contour=contour, data=data,
                      residual_flexibility=residual_flexibility == "on")
    options = dict(theta=0.5, trace=True)
    if integrator == "moreau-adaptive":
        options.update(atol=atol, rtol=0.0)
    res, cpu = timed(scene.system.simulate, t_end, dt, integrator=integrator,
                     t_out=np.linspace(0.0, t_end, N_OUT), outputs=scene.outputs(), **options)
    return scene, res, cpu


def _errors(res, ref):
    peak = np.abs(ref["node19"][:, 1]).max()
    return (float(np.sqrt(np.mean((res["vy"] - ref["vy"]) ** 2)) / 0.2),
            float(np.sqrt(np.mean((res["node19"][:, 1] - ref["node19"][:, 1]) ** 2)) / peak),
            float(np.abs(res["y"] - ref["y"]).max()))


def _extras(scene, res):
    tr = res.trace
    e = energy_balance(tr, res.stats["initial_energy"])
    return {"energy_residual": e["residual"] / e["initial"] if scene.contact.set_valued else None,
            "contact_intervals": len(contact_intervals(tr["t"], tr["dt"], tr["closed"])),
            "max_penetration": float(res.stats["max_penetration"]), "steps": int(res.stats["steps"])}


def run(quick: bool) -> CaseResult:
    data = pmb.default_beam_data()
    warm_up(data)
    return sweeps(data, 0.03 if quick else T_END, 5e-6 if quick else REF_DT, quick)


def warm_up(data):
    """Compile (or load) the kernels of every contour and residual flexibility setting: a
    run of each to just past the contact's closing, so the sweeps' CPU times hold no
    compilation."""
    for contour in ("2s", "band"):
        for on_off in ("off", "on"):
            _simulate(data, contour=contour, t_end=0.0102, residual_flexibility=on_off)


def sweeps(data, t_end, ref_dt, quick) -> CaseResult:
    """The rows, notes and figure of :func:`run`: every run simulated to ``t_end`` [s], the
    references with all modes of ``data`` at Δt = ``ref_dt`` [s]; ``quick`` picks the
    short sweeps."""
    n_all = data.n_modes
    result = CaseResult(plot_groups=("sweep", "error_kind"))
    refs = {}

    def reference(setup="A", law="impact", e=0.0, modes="all", dt=ref_dt, contour="2s"):
        key = (setup, law, e, modes, dt, contour)
        if key not in refs:
            refs[key] = _simulate(data, setup, modes, law, e, contour, dt=dt, t_end=t_end)[1]
        return refs[key]

    simulated = {}

    def add(sweep, ref, ref_name, **config):
        row_config = {"sweep": sweep, "setup": "A", "modes": 20, "residual_flexibility": "off", "law": "impact",
                      "e": 0.0, "contour": "2s", "integrator": "moreau", "dt": 1e-5, **config}
        key = tuple(sorted((k, v) for k, v in row_config.items() if k != "sweep"))
        if key not in simulated:                                # a configuration of two sweeps runs once
            simulated[key] = _simulate(data, t_end=t_end, **config)
        scene, res, cpu = simulated[key]
        for kind, err in zip(KINDS, _errors(res, ref)):
            result.rows.append(make_row(NAME, row_config, cpu, err, kind, ref_name, **_extras(scene, res)))
        return res

    all_name = f"all {n_all} modes, Δt = {ref_dt:g} s"
    ref_a = reference()
    mode_counts = (10, 20) if quick else (5, 10, 20, 50, 100, 200)
    runs = {}
    for setup in ("A",) if quick else ("A", "B"):
        ref = ref_a if setup == "A" else reference(setup="B")
        for m in mode_counts:
            for on_off in ("off", "on"):
                res = add("modes", ref, all_name, setup=setup, modes=m, residual_flexibility=on_off)
                if setup == "A":
                    runs[(m, on_off)] = res

    if not quick:
        own = reference(modes=20, dt=1e-6)
        for dt in (4e-5, 2e-5, 1e-5, 5e-6):
            add("fixed step vs 20 modes", own, "20 modes, Δt = 1e-06 s", dt=dt)
        for atol in (1e-6, 1e-7, 1e-8):
            add("adaptive vs 20 modes", own, "20 modes, Δt = 1e-06 s", integrator="moreau-adaptive", dt=1e-4,
                atol=atol)
    for atol in ((1e-7,) if quick else (1e-6, 1e-7, 1e-8)):
        add("adaptive", ref_a, all_name, integrator="moreau-adaptive", dt=1e-4, atol=atol)

    laws = (("impact", 1.0),) if quick else (("impact", 0.7), ("impact", 1.0), ("penalty", 0.0))
    for law, e in laws:
        add("law", reference(law=law, e=e), f"{all_name}, same law", law=law, e=e)
    for modes in ((20,) if quick else (10, 20, 50)):              # e = 1 on the compliance: energy kept
        scene, res, cpu = _simulate(data, modes=modes, e=1.0, t_end=t_end, residual_flexibility="on")
        energy = np.asarray(res.trace["energy"])
        e0 = 0.5 * pmb.MASS * 0.2 ** 2
        result.rows.append(make_row(NAME, {"sweep": "energy, e = 1", "setup": "A", "modes": modes,
                                           "residual_flexibility": "on", "law": "impact", "e": 1.0, "contour": "2s",
                                           "integrator": "moreau", "dt": 1e-5},
                                    cpu, float(np.abs(energy - e0).max() / e0), "max |E(t) − E(0)| / E(0)",
                                    "energy conservation (kinetic + elastic + ½ Fᵀδ of the spring)",
                                    **_extras(scene, res)))

    setups = ("A",) if quick else ("A", "B")
    for setup in setups:
        ref = reference(setup=setup)
        for contour in ("2s", "band"):
            for on_off in ("off", "on"):
                add("contour", ref, all_name, setup=setup, contour=contour, residual_flexibility=on_off)

    phases = {key[0]: len(contact_intervals(r.trace["t"], r.trace["dt"], r.trace["closed"]))
              for key, r in refs.items() if key[1:] == ("impact", 0.0, "all", ref_dt, "2s")}
    result.notes.append(_correction_table(result.rows) + "\n\nContact phases of the references: " +
                        ", ".join(f"setup {k}: {v}" for k, v in sorted(phases.items())) + ".")
    result.notes.append(_contour_table(result.rows))
    result.figures["outputs"] = lambda path: _figure(path, ref_a, runs)
    return result


def _contour_table(rows):
    lines = ["Contour type at 20 modes, Newton impact e = 0 (thesis Table 5.3; MBSim in 2014, 0.05 s: "
             "setup A 36 s band / 74 s 2s, setup B 33 s / 46 s):", "",
             "| setup | contour | residual flexibility | CPU [s] | v_y RMS / 0.2 m/s | node 19 RMS / peak |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        c = r["config"]
        if c["sweep"] == "contour" and r["error_kind"] == KINDS[0]:
            node = next(s for s in rows if s["config"] == c and s["error_kind"] == KINDS[1])
            lines.append(f"| {c['setup']} | {c['contour']} | {c['residual_flexibility']} | {r['cpu_s']:.2f} | "
                         f"{r['error']:.2e} | {node['error']:.2e} |")
    return "\n".join(lines)


def _correction_table(rows):
    """Modes × residual flexibility (off/on): errors, contact phases and CPU per setup."""
    lines = ["Modes with and without residual flexibility (2s contour, Newton impact e = 0, Δt = 1e-5 s; "
             "errors against all modes):", "",
             "| setup | modes | v_y RMS off | v_y RMS on | node 19 RMS off | node 19 RMS on | contact phases off / on "
             "| CPU off / on [s] |", "|---|---|---|---|---|---|---|---|"]
    table = {}
    for r in rows:
        c = r["config"]
        if c["sweep"] == "modes":
            table.setdefault((c["setup"], c["modes"]), {})[(c["residual_flexibility"], r["error_kind"])] = r
    for (setup, modes), t in sorted(table.items()):
        v, n = KINDS[0], KINDS[1]
        lines.append(f"| {setup} | {modes} | {t[('off', v)]['error']:.2%} | {t[('on', v)]['error']:.2%} | "
                     f"{t[('off', n)]['error']:.2%} | {t[('on', n)]['error']:.2%} | "
                     f"{t[('off', v)]['contact_intervals']} / {t[('on', v)]['contact_intervals']} | "
                     f"{t[('off', v)]['cpu_s']:.2f} / {t[('on', v)]['cpu_s']:.2f} |")
    return "\n".join(lines)


def _figure(path, ref, runs):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 1, sharex=True)
    for label, res, style in [("all modes (reference)", ref, "k-")] + [
            (f"{m} modes, correction {on_off}", r, "-" if on_off == "on" else ":") for (m, on_off), r in runs.items()
            if m in (10, 20)]:
        t = 1e3 * res.t
        axes[0].plot(t, 1e3 * res["y"], style, label=label, lw=1)
        axes[1].plot(t, res["vy"], style, lw=1)
        axes[2].plot(t, 1e3 * res["node19"][:, 1], style, lw=1)
    axes[0].set_ylabel("point mass y [mm]")
    axes[1].set_ylabel("point mass v_y [m/s]")
    axes[2].set_ylabel("node 19 u_y [mm]")
    axes[2].set_xlabel("t [ms]")
    axes[0].legend(fontsize=7)
    fig.suptitle("point mass on beam, setup A, Newton impact e = 0, Δt = 1e-5 s")
    fig.savefig(path, dpi=100)
