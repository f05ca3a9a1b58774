"""Benchmark: the cost of one step, this checkout against a baseline commit and Exudyn,
side by side in one run.

Cases (each the wall time of ``System.simulate`` divided by its steps; output sampling
and planning included, compilation excluded — every case runs once untimed first):

- ``default``: the default scene (setup A of :mod:`ffrmbs_app.scenes.point_mass_beam`,
  20 clamped modes, 2s contour, Moreau θ = ½, Δt = 1e-5 s, 0.1 s, 101 samples);
- ``far pairs N``: the same with N more point masses flying away from the beam, each in
  a contact with its surface that never closes, and ``far bodies N``: the same point
  masses without contacts. The cost of the far pairs themselves is the difference of the
  two (the rest is the N bodies' own velocity and position updates); the target: per-step
  cost flat in far-apart pairs;
- ``free moreau`` / ``free gen-alpha``: the report's free-flying beam (the
  ``ffr_free_flight`` case, Exudyn's free-flight comparison), 10 free-free modes, full
  FFR equations (plan off), h = 1e-3 s, 1 s; Exudyn's ``ObjectFFRFreducedOrder`` with
  the same matrices, generalized-α ρ∞ = 0.9, h = 1e-3 s, timed in this process.

The baseline (default :data:`BASELINE`, the main of before the Model/Data split) is
exported with ``git archive`` into a temporary directory; this checkout and the baseline
each run :mod:`validation.bench.step_worker` in their own process, alternately,
``rounds`` times, each importing the project's packages from its own tree only (an
installed ``ffrmbs`` never fills in what the old tree lacks); the table gives medians
over all timed runs and the ratio baseline / this checkout, and its header names the
directory each side's code came from. Each case also reports a result figure (v_y(T) or
|r_A(T)|) from both, so that a speed-up that changed the answer shows. When the baseline
cannot run — no git, this code is an installed copy rather than a clone, the commit is
missing, or its worker fails — the header says why in one line and the baseline
columns stay empty.

Run::

    python3 -m validation.bench --only step_cost [--quick]
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from validation.bench.common import bench_main, machine

ROOT = Path(__file__).resolve().parents[2]
WORKER = Path(__file__).with_name("step_worker.py")
BASELINE = "f934873"          # main after issue 18, before the Model/Data split (issue 19)
T_END, DT = 0.1, 1e-5         # [s], the default scene
FREE_DT, FREE_MODES = 1e-3, 10
FAR_PAIRS = (8, 32)
TARGETS_US = {"default": 12.0, "free moreau": 30.0, "free gen-alpha": 50.0}   # issue 19
FLAT_TOL = 0.10               # far pairs: per-step cost within 10 % of the default scene's
FULL = {"rounds": 3, "repeats": 3, "t_end": T_END}
QUICK = {"rounds": 2, "repeats": 1, "t_end": 0.02}


def cases(t_end) -> list[dict]:
    default = {"kind": "default", "t_end": t_end, "dt": DT}
    return ([{"name": "default", **default}]
            + [{"name": f"far pairs {n}", **default, "far_pairs": n} for n in FAR_PAIRS]
            + [{"name": f"far bodies {FAR_PAIRS[-1]}", **default, "far_pairs": FAR_PAIRS[-1], "contacts": False}]
            + [{"name": "free moreau", "kind": "free", "integrator": "moreau", "dt": FREE_DT, "modes": FREE_MODES},
               {"name": "free gen-alpha", "kind": "free", "integrator": "generalized-alpha", "dt": FREE_DT,
                "modes": FREE_MODES}])


def export_baseline(rev, into, root=ROOT) -> str | None:
    """Export commit ``rev`` of the git clone ``root`` into ``into``; None, or why it could not."""
    try:
        top = subprocess.run(["git", "-C", str(root), "rev-parse", "--show-toplevel"], capture_output=True,
                             text=True, check=False)
    except OSError as exc:
        return f"git not available ({exc.strerror})"
    if top.returncode or Path(top.stdout.strip()).resolve() != Path(root).resolve():
        return f"{root} is not a git clone (an installed copy?): no commit {rev} to compare with"
    archive = subprocess.run(["git", "-C", str(root), "archive", "--format=tar", rev], capture_output=True, check=False)
    if archive.returncode:
        return f"commit {rev} not found ({archive.stderr.decode(errors='replace').strip()})"
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)
    return None


class WorkerFailed(RuntimeError):
    """A step worker ended with an error; the message ends with the last lines it printed."""


def run_worker(checkout, spec) -> dict:
    """The worker's measurements of the product in ``checkout`` (its project packages
    imported from there only): {"cases": {name: {"walls", "steps", "check"}}, "origins":
    {package: directory}}."""
    out = subprocess.run([sys.executable, str(WORKER), str(checkout), json.dumps(spec)], capture_output=True,
                         text=True, check=False)
    if out.returncode:
        raise WorkerFailed(f"step worker in {checkout} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def last_line(text) -> str:
    """The last non-empty line of ``text`` (an error's one-line summary)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else text


def exudyn_us_per_step(repeats) -> float | None:
    """Median µs per step of Exudyn's free flight (10 modes, h = 1e-3 s), or None."""
    from validation.peers import exudyn_ffr

    if not exudyn_ffr.available():
        return None
    from preprocess import box, build_body
    from validation.cases import ffr_free_flight as ff
    from validation.cases.cantilever import MATERIAL, REPORT_MESH_SIZE

    mesh = box(1.0, 1.0, 5.0, REPORT_MESH_SIZE, order=2)
    data = build_body(mesh, MATERIAL, FREE_MODES, clamp=None)
    weights, probe = ff.face_weights(mesh), ff.node_a(mesh)
    ff.exudyn_run(data, weights, FREE_MODES, FREE_DT, probe)            # warm-up
    cpu = [ff.exudyn_run(data, weights, FREE_MODES, FREE_DT, probe)[2] for _ in range(repeats)]
    return 1e6 * float(np.median(cpu)) / round(ff.T_END / FREE_DT)


def benchmark(rounds, repeats, t_end, baseline=BASELINE, log=print) -> dict:
    spec = {"cases": cases(t_end), "repeats": repeats}
    walls = {"this": {}, "baseline": {}}
    checks = {"this": {}, "baseline": {}}
    steps = {}
    origins = {}
    with tempfile.TemporaryDirectory(prefix="ffrmbs-baseline-") as tmp:
        why_not = export_baseline(baseline, tmp)
        checkouts = {"this": ROOT} if why_not else {"this": ROOT, "baseline": Path(tmp)}
        for k in range(rounds):
            for who, checkout in list(checkouts.items()):
                start = time.perf_counter()
                try:
                    measured = run_worker(checkout, spec)
                except WorkerFailed as exc:
                    if who == "this":
                        raise
                    why_not = f"its worker failed: {last_line(str(exc))}"
                    del checkouts[who]
                    walls[who], checks[who] = {}, {}
                    log(f"round {k + 1}/{rounds}: baseline skipped, {why_not}")
                    continue
                for name, m in measured["cases"].items():
                    walls[who].setdefault(name, []).extend(m["walls"])
                    checks[who][name] = m["check"]
                    steps[name] = m["steps"]
                origins[who] = sorted(set(measured["origins"].values()))
                log(f"round {k + 1}/{rounds}: {who} in {time.perf_counter() - start:.1f} s")
    exudyn = exudyn_us_per_step(max(3, repeats))
    rows = []
    for case in spec["cases"]:
        name = case["name"]
        us = {who: 1e6 * float(np.median(w[name])) / steps[name] for who, w in walls.items() if name in w}
        rows.append({"case": name, "steps": steps[name], "us_this": us["this"], "us_baseline": us.get("baseline"),
                     "ratio": us["baseline"] / us["this"] if "baseline" in us else None,
                     "check_this": checks["this"][name], "check_baseline": checks["baseline"].get(name),
                     "runs": len(walls["this"][name])})
    by = {r["case"]: r for r in rows}
    if exudyn is not None:
        for name in ("free moreau", "free gen-alpha"):
            by[name]["exudyn_us"] = exudyn
            by[name]["exudyn_ratio"] = exudyn / by[name]["us_this"]
    table = ["| case | steps | baseline µs/step | this µs/step | baseline / this | Exudyn µs/step | "
             "Exudyn / this | result (this) | result (baseline) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        fmt = lambda v, f: "—" if v is None else format(v, f)  # noqa: E731
        table.append(f"| {r['case']} | {r['steps']} | {fmt(r['us_baseline'], '.1f')} | {r['us_this']:.1f} | "
                     f"{fmt(r['ratio'], '.2f')} | {fmt(r.get('exudyn_us'), '.1f')} | "
                     f"{fmt(r.get('exudyn_ratio'), '.2f')} | {r['check_this']:.9g} | "
                     f"{fmt(r['check_baseline'], '.9g')} |")
    verdicts = []
    for name, target in TARGETS_US.items():
        us = by[name]["us_this"]
        verdicts.append(f"target ({name} ≤ {target:g} µs per step): {us:.1f} µs — {'met' if us <= target else 'NOT met'}")
    n = FAR_PAIRS[-1]
    pairs = (by[f"far pairs {n}"]["us_this"] - by[f"far bodies {n}"]["us_this"]) / by["default"]["us_this"]
    whole = by[f"far pairs {n}"]["us_this"] / by["default"]["us_this"] - 1.0
    verdicts.append(f"target (per-step cost flat within {FLAT_TOL:.0%} in the number of far-apart pairs, up to {n}): "
                    f"the {n} pairs add {pairs:.1%} of the default step (their {n} bodies another "
                    f"{whole - pairs:.1%}) — {'met' if abs(pairs) <= FLAT_TOL else 'NOT met'}")
    header = (f"Per-step cost, median of {rounds} rounds x {repeats} runs, this checkout and baseline {baseline} "
              f"alternately in separate processes" + (f"; baseline: {why_not}" if why_not else "")
              + ("" if exudyn is not None else "; Exudyn: not installed (pip install '.[peers]')")
              + "".join(f"; {who}: code from {', '.join(dirs)}" for who, dirs in origins.items()))
    return {"benchmark": "step_cost", "machine": machine(), "baseline": baseline, "origins": origins, "rows": rows,
            "table": header + "\n\n" + "\n".join(table), "verdicts": verdicts}


def run(quick: bool) -> dict:
    return benchmark(**(QUICK if quick else FULL))


def main(argv=None):
    """Run the benchmark (command line ``argv``), print the table, write the JSON; return it."""
    return bench_main(argv, "step_cost", run, __doc__, "two rounds of one run each, 0.02 s of the default scene")


if __name__ == "__main__":
    main()
