"""Benchmark: ours against Exudyn on the report's free-flying beam, side by side in one process.

The scene, the errors and Exudyn's run are those of the ``ffr_free_flight`` validation
case (:mod:`validation.cases.ffr_free_flight`): the free 1 x 1 x 5 m steel beam (report
mesh, tet10, free-free modes) under its complex forcing for 1 s; errors of node A's
trajectory and of its elastic displacement against the case's converged reference (our
RK4 at ``REFERENCE_DT`` = 2.5e-5 s with the same modes), both relative to the
reference's largest value. Exudyn's ``ObjectFFRFreducedOrder`` gets our matrices and
modes and runs its generalized-α (ρ∞ = 0.9) at its natural steps ``EXUDYN_STEPS``.

Ours runs every configuration of ``CANDIDATES`` (integrator, step, options). For each
Exudyn row the comparison takes our fastest candidate whose trajectory AND elastic
errors are both at most Exudyn's, and prints Exudyn's time over ours (target
≥ ``TARGET_RATIO``); "none" when no candidate is as accurate. Times are CPU seconds
(ours: the whole ``System.simulate`` call, planning and output sampling included;
Exudyn: its ``SolveDynamic``), the median over ``repeats`` runs; all runs of one mode count are
interleaved (every configuration once, then again), after one untimed run of each that
compiles the kernels. Errors come from the first timed run (the runs are deterministic).

Run::

    python3 -m validation.bench.exudyn_free_flight [--quick] [--out out/bench]

or with all benchmarks, ``python3 -m validation.bench --only exudyn_free_flight``.
``--quick``: 10 modes, Exudyn at 1e-3 s only, one repeat, reference step 5e-5 s.
"""

from __future__ import annotations

import numpy as np

from validation.bench.common import bench_main, machine
from validation.cases import _wobble as wb
from validation.cases import ffr_free_flight as ff

# Our configurations to choose from: (integrator name, step [s], options of System.simulate).
# "plan": True lets the planner choose the formulation (SimpleRB here, mbs.run.plan); the
# others integrate the full FFR equations (plan=False).
CANDIDATES = (
    ("generalized-alpha", 1e-3, {"plan": True}),
    ("generalized-alpha", 1e-3, {"rho_inf": 0.9}),
    ("generalized-alpha", 5e-4, {"rho_inf": 0.9}),
    ("generalized-alpha", 2.5e-4, {"rho_inf": 0.9}),
    ("moreau", 1e-3, {"theta": 0.5}),
    ("moreau", 5e-4, {"theta": 0.5}),
    ("moreau", 2.5e-4, {"theta": 0.5}),
    ("moreau", 1e-4, {"theta": 0.5}),
)
EXUDYN_STEPS = (1e-3, 5e-4)                # [s], Exudyn's generalized-α
TARGET_RATIO = 3.0                         # Exudyn CPU / ours, at errors no larger than Exudyn's
FULL = {"modes": (10, 30), "exudyn_steps": EXUDYN_STEPS, "repeats": 3, "reference_dt": ff.REFERENCE_DT}
QUICK = {"modes": (10,), "exudyn_steps": EXUDYN_STEPS[:1], "repeats": 1, "reference_dt": 2 * ff.REFERENCE_DT}
SKIPPED = "skipped: exudyn not installed (pip install '.[peers]')"


def select(ours, peer):
    """Our fastest row (median CPU) among ``ours`` whose trajectory and elastic errors are
    both at most ``peer``'s, or None."""
    good = [r for r in ours if r["trajectory_error"] <= peer["trajectory_error"]
            and r["elastic_error"] <= peer["elastic_error"]]
    return min(good, key=lambda r: r["cpu_s"], default=None)


def _label(row):
    options = ", ".join(f"{k}={v:g}" for k, v in row["options"].items())
    return f"{row['integrator']} h={row['dt']:g}" + (f" ({options})" if options else "")


def _runs(data, weights, probe, n_modes, exudyn_steps):
    """[(row, callable returning (r_A, ū_f,A, CPU s))]: our candidates, then Exudyn's steps."""
    runs = []
    for integrator, dt, options in CANDIDATES:
        def ours(integrator=integrator, dt=dt, options=options):
            _, r, e, cpu = ff.simulate(data, weights, n_modes, dt, integrator, probe, **options)
            return r, e, cpu
        runs.append(({"code": "ffrmbs", "n_modes": n_modes, "integrator": integrator, "dt": dt,
                      "options": dict(options)}, ours))
    for dt in exudyn_steps:
        runs.append(({"code": "exudyn", "n_modes": n_modes, "integrator": "generalized-alpha", "dt": dt,
                      "options": {"rho_inf": 0.9}},
                     lambda dt=dt: ff.exudyn_run(data, weights, n_modes, dt, probe)))
    return runs


def benchmark(modes, exudyn_steps, repeats, reference_dt, log=print) -> dict:
    """The benchmark's document: ``rows`` (every run: median CPU s, µs/step, both errors),
    ``comparisons`` (one per Exudyn row), ``verdicts``, the markdown ``table``."""
    from validation.peers import exudyn_ffr

    doc = {"benchmark": "exudyn_free_flight", "machine": machine(), "t_end": ff.T_END, "repeats": repeats,
           "reference_dt": reference_dt, "target_ratio": TARGET_RATIO, "rows": [], "comparisons": []}
    if not exudyn_ffr.available():
        doc.update(skipped=SKIPPED, verdicts=[f"target (Exudyn / ours ≥ {TARGET_RATIO:g}): {SKIPPED}"],
                   table=f"Exudyn free flight: {SKIPPED}")
        return doc
    mesh, data = wb.beam(n_modes=max(modes))
    probe, weights = ff.node_a(mesh), ff.face_weights(mesh)
    for n_modes in modes:
        ref = ff.simulate(data, weights, n_modes, reference_dt, "rk4", probe)[:3]
        runs = _runs(data, weights, probe, n_modes, exudyn_steps)
        for _, fn in runs:
            fn()                                                # compiles the kernels, untimed
        cpus, errors = [[] for _ in runs], []
        for repeat in range(repeats):
            for k, (_, fn) in enumerate(runs):
                r, e, cpu = fn()
                cpus[k].append(cpu)
                if repeat == 0:
                    errors.append(ff.errors(r, e, ref))
        rows = [{**row, "cpu_s": float(np.median(c)), "cpu_samples": c,
                 "us_per_step": 1e6 * float(np.median(c)) / round(ff.T_END / row["dt"]),
                 "trajectory_error": float(err[0]), "elastic_error": float(err[1])}
                for (row, _), c, err in zip(runs, cpus, errors)]
        doc["rows"] += rows
        ours = [r for r in rows if r["code"] == "ffrmbs"]
        for peer in (r for r in rows if r["code"] == "exudyn"):
            best = select(ours, peer)
            doc["comparisons"].append({"n_modes": n_modes, "exudyn_dt": peer["dt"], "exudyn_cpu_s": peer["cpu_s"],
                                       "ours": None if best is None else _label(best),
                                       "ours_cpu_s": None if best is None else best["cpu_s"],
                                       "ratio": None if best is None else peer["cpu_s"] / best["cpu_s"]})
        log(f"{n_modes} modes: done")
    doc["verdicts"] = [
        f"target (Exudyn / ours ≥ {TARGET_RATIO:g} at both errors ≤ Exudyn's), {c['n_modes']} modes, Exudyn h = "
        f"{c['exudyn_dt']:g}: " + ("no candidate as accurate — NOT met" if c["ratio"] is None else
                                  f"{c['ratio']:.2f} with {c['ours']} — "
                                  f"{'met' if c['ratio'] >= TARGET_RATIO else 'NOT met'}")
        for c in doc["comparisons"]]
    doc["table"] = markdown(doc)
    return doc


def markdown(doc) -> str:
    """Every run, then the comparisons, as markdown tables."""
    lines = [f"Free flight, {doc['t_end']:g} s; CPU s of the integration, median of {doc['repeats']}; errors against "
             f"RK4 h = {doc['reference_dt']:g} s", "",
             "| code | modes | integrator | options | h [s] | µs/step | CPU [s] | trajectory error | elastic error |",
             "|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['code']} | {r['n_modes']} | {r['integrator']} | "
              f"{', '.join(f'{k}={v:g}' for k, v in r['options'].items())} | {r['dt']:g} | {r['us_per_step']:.0f} | "
              f"{r['cpu_s']:.3f} | {r['trajectory_error']:.2e} | {r['elastic_error']:.2e} |" for r in doc["rows"]]
    lines += ["", "Exudyn against our fastest candidate with both errors ≤ Exudyn's:", "",
              "| modes | Exudyn h [s] | Exudyn CPU [s] | ours | our CPU [s] | Exudyn / ours |", "|---|---|---|---|---|---|"]
    lines += [f"| {c['n_modes']} | {c['exudyn_dt']:g} | {c['exudyn_cpu_s']:.3f} | {c['ours'] or 'none'} | "
              + ("- | - |" if c["ratio"] is None else f"{c['ours_cpu_s']:.3f} | {c['ratio']:.2f} |")
              for c in doc["comparisons"]]
    return "\n".join(lines)


def run(quick: bool) -> dict:
    """The benchmark protocol of :mod:`validation.bench.runner` (``FULL`` or ``QUICK`` settings)."""
    return benchmark(**(QUICK if quick else FULL))


def main(argv=None):
    """Run the benchmark (command line ``argv``), print the table, write the JSON; return it."""
    return bench_main(argv, "exudyn_free_flight", run, __doc__, "10 modes, Exudyn at 1e-3 s, 1 repeat")


if __name__ == "__main__":
    main()
