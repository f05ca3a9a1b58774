"""Benchmark: planned against unplanned on the planner scene (:mod:`validation.scenes.planner_scene`).

The point mass dropped on the clamped beam (setup A, 20 modes), a second point mass far
from the beam with a contact pair against it, and a second frame-fixed beam with all 750
modes under a step tip load, in no contact. Moreau, θ = 0.5, Δt = 1e-5 s, 0.05 s
(quick: 0.015 s), 101 outputs. Planned (``plan=True``, the default of
``System.simulate``): the second beam by exact modal propagation on the modes the plan
keeps, the far pair pruned before its contours update. Unplanned (``plan=False``):
every body in Moreau, every contour updated each step.

Each row is the median wall time over ``repeats`` runs (after one warm-up run of each),
the two taken in turn so machine load hits both alike; the ratio is unplanned/planned.
Agreement: the largest difference of each output between the two runs, relative to its
largest magnitude — the outputs of the unchanged bodies agree to rounding; the second
beam's tip differs by Moreau's time-discretization error there (the planned run is exact
for the step load up to the dropped modes' bound, printed in the plan). Run alone::

    python3 -m validation.bench.planner [--quick]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from validation.bench.common import machine, write_json
from validation.scenes import planner_scene as ps
from ffrmbs_app.scenes import point_mass_beam as pmb

DT = 1e-5


def _run(data, plan, t_end):
    scene = ps.build(data=data)
    start = time.perf_counter()
    res = scene.system.simulate(t_end, DT, integrator="moreau", theta=0.5, t_out=np.linspace(0.0, t_end, 101),
                                outputs=scene.outputs(), plan=plan)
    return time.perf_counter() - start, res


def run(quick: bool = False, repeats: int | None = None) -> dict:
    """Time the planned and unplanned runs; the doc dict with "rows", "table", "plan"."""
    t_end = 0.015 if quick else 0.05
    repeats = repeats or (1 if quick else 3)
    data = pmb.default_beam_data()
    for plan in (True, False):
        _run(data, plan, 1e-3)                                     # compile the kernels
    walls = {True: [], False: []}
    results = {}
    for _ in range(repeats):
        for plan in (True, False):
            wall, results[plan] = _run(data, plan, t_end)
            walls[plan].append(wall)
    planned, unplanned = results[True], results[False]
    agreement = {name: float(np.abs(planned[name] - unplanned[name]).max() / np.abs(unplanned[name]).max())
                 for name in planned.outputs}
    rows = [{"run": name, "t_end": t_end, "dt": DT, "wall_s": float(np.median(walls[plan])),
             "steps": int(res.stats["steps"]), "pruned_contact_steps": int(res.stats["pruned_contacts"])}
            for name, plan, res in (("planned", True, planned), ("unplanned", False, unplanned))]
    ratio = rows[1]["wall_s"] / rows[0]["wall_s"]
    lines = [f"planner scene, {t_end} s at Δt = {DT:g} s, median of {repeats}",
             "| run | wall [s] | steps | pruned contact-steps |", "|---|---|---|---|"]
    lines += [f"| {r['run']} | {r['wall_s']:.3f} | {r['steps']} | {r['pruned_contact_steps']} |" for r in rows]
    lines.append(f"unplanned / planned: {ratio:.2f}")
    lines.append("largest difference / largest value: "
                 + ", ".join(f"{k} {v:.1e}" for k, v in sorted(agreement.items())))
    return {"benchmark": "planner", "machine": machine(), "rows": rows, "ratio": ratio,
            "agreement": agreement, "plan": planned.plan, "table": "\n".join(lines)}


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m validation.bench.planner", description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default="out/bench")
    args = parser.parse_args(argv)
    doc = run(args.quick)
    print(doc["plan"])
    print(doc["table"])
    write_json(doc, args.out, "planner")
    return doc


if __name__ == "__main__":
    main()
