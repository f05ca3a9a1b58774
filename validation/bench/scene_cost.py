"""Benchmark: the cost of one step of ``ffrmbs run`` per scene and pair kind, this
checkout against a baseline commit, side by side in one run (issue 32's targets).

Each case is the command ``ffrmbs run SCENE --no-check --no-export`` (the main job as a
user runs it: output sampling, the energy trace and the result file included) run by
``python -m ffrmbs_app.cli`` with one checkout's packages first on the path, in a fresh
process; its cost line ("cost: N steps in … s wall (… s CPU), … µs per step", the
simulation loop alone: the kernels are compiled or loaded in the untimed warm-up) gives
the CPU µs per step. The cases:

- ``default``: the embedded default scene (point against the neutral 2s contour, residual
  flexibility); ``default band``: the same with ``--contour band`` (an offset contour);
- ``ball_on_plate``, ``ball_in_channel``: the example scenes (a sphere on a point mass
  against a fitted 2s contour of an unstructured tet10 part), their parts preprocessed
  once into a temporary directory by this checkout (``examples/parts/*.geo``, as each
  scene's header says);
- ``bouncing_ball``: the example scene of a ball on a plane.

The baseline (default :data:`BASELINE`, the main of issue 32's start) is exported with
``git archive``; both run alternately, ``rounds`` times; the table gives medians of the
CPU µs per step and the ratio baseline / this. When the baseline cannot run, the header
says why and its columns stay empty (:func:`validation.bench.step_cost.export_baseline`).

Run::

    python3 -m validation.bench --only scene_cost [--quick]
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from validation.bench.common import bench_main, machine
from validation.bench.step_cost import export_baseline, last_line

ROOT = Path(__file__).resolve().parents[2]
BASELINE = "5781a2a"          # main at the start of issue 32 (contacts as data)
PARTS = {   # part: the preprocessing of its scene's header (examples/scenes/<scene>.toml)
    "plate": ["--units", "si-mm", "--modes", "10", "--clamp", "clamp", "--density", "2.7e-9", "--young", "70000",
              "--poisson", "0.33"],
    "channel": ["--units", "si-mm", "--modes", "6", "--clamp", "bottom", "--density", "7.85e-9", "--young",
                "210000", "--poisson", "0.3"],
}
CASES = {   # name: (scene file or None for the default scene, extra arguments)
    "default": (None, []),
    "default band": (None, ["--contour", "band"]),
    "ball_on_plate": ("ball_on_plate.toml", []),
    "ball_in_channel": ("ball_in_channel.toml", []),
    "bouncing_ball": ("bouncing_ball.toml", []),
}
TARGETS = {"ball_on_plate": 8.0, "ball_in_channel": 8.0, "default band": 3.0}   # speed-up over the baseline
TARGET_DEFAULT_US = 15.0      # the default scene, recording included
FULL = {"rounds": 3, "t_end": None}
QUICK = {"rounds": 1, "t_end": 0.02}
COST = re.compile(r"^cost: (\d+) steps in ([0-9.]+) s wall \(([0-9.]+) s CPU\)", re.M)


def cost_of(output: str) -> tuple[int, float]:
    """(steps, CPU s) from the cost line of ``ffrmbs run``'s output; ValueError without one."""
    found = COST.search(output)
    if found is None:
        raise ValueError(f"no cost line in the run's output: {last_line(output)!r}")
    return int(found.group(1)), float(found.group(3))


def run_case(checkout, case, scenes, out, t_end) -> tuple[int, float]:
    """(steps, CPU s) of one case run with ``checkout``'s packages first on the path."""
    scene, extra = CASES[case]
    args = ([] if scene is None else [str(scenes / scene)]) + extra + ["--no-check", "--no-export", "--out", str(out)]
    if t_end is not None:
        args += ["--t-end", str(t_end)] if scene is None else ["--set", f"scene.t_end={t_end}"]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(checkout)] + [p for p in [os.environ.get("PYTHONPATH")]
                                                                        if p]))
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    done = subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", "run", *args], cwd=out, env=env,
                          capture_output=True, text=True, check=False)
    if done.returncode:
        raise RuntimeError(f"{case} in {checkout}: {last_line(done.stderr or done.stdout)}")
    return cost_of(done.stdout + done.stderr)


def prepare_scenes(into: Path) -> Path:
    """The example scenes and their preprocessed parts in ``into`` (by this checkout)."""
    for scene in ("ball_on_plate.toml", "ball_in_channel.toml", "bouncing_ball.toml"):
        shutil.copy(ROOT / "examples" / "scenes" / scene, into / scene)
    for part, options in PARTS.items():
        subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", "preprocess", str(ROOT / "examples" / "parts" /
                        f"{part}.geo"), *options, "--out", str(into / part)], check=True, capture_output=True)
    return into


def benchmark(rounds, t_end, baseline=BASELINE, log=print) -> dict:
    cpu = {"this": {}, "baseline": {}}
    steps = {}
    with tempfile.TemporaryDirectory(prefix="ffrmbs-scene-cost-") as tmp:
        tmp = Path(tmp)
        (tmp / "base").mkdir()
        why_not = export_baseline(baseline, tmp / "base", ROOT)
        checkouts = {"this": ROOT} if why_not else {"this": ROOT, "baseline": tmp / "base"}
        scenes = tmp / "scenes"
        scenes.mkdir()
        prepare_scenes(scenes)
        for k in range(rounds):
            for case in CASES:
                for who, checkout in list(checkouts.items()):
                    out = tmp / f"out-{who}"
                    out.mkdir(exist_ok=True)
                    try:
                        n, seconds = run_case(checkout, case, scenes, out, t_end)
                    except RuntimeError as exc:
                        if who == "this":
                            raise
                        why_not = f"its run failed: {exc}"
                        del checkouts[who]
                        cpu[who] = {}
                        continue
                    steps[case] = n
                    cpu[who].setdefault(case, []).append(1e6 * seconds / n)
            log(f"round {k + 1}/{rounds} done")
    rows = []
    for case in CASES:
        us = {who: float(np.median(v[case])) for who, v in cpu.items() if case in v}
        rows.append({"case": case, "steps": steps[case], "us_this": us["this"], "us_baseline": us.get("baseline"),
                     "ratio": us["baseline"] / us["this"] if "baseline" in us else None, "runs": len(cpu["this"][case])})
    fmt = lambda v, f: "—" if v is None else format(v, f)  # noqa: E731
    table = ["| case | steps | baseline µs/step (CPU) | this µs/step (CPU) | baseline / this |", "|---|---|---|---|---|"]
    table += [f"| {r['case']} | {r['steps']} | {fmt(r['us_baseline'], '.1f')} | {r['us_this']:.1f} | "
              f"{fmt(r['ratio'], '.2f')} |" for r in rows]
    by = {r["case"]: r for r in rows}
    verdicts = [f"target (default scene ≤ {TARGET_DEFAULT_US:g} µs per step): {by['default']['us_this']:.1f} µs — "
                + ("met" if by["default"]["us_this"] <= TARGET_DEFAULT_US else "NOT met")]
    for case, target in TARGETS.items():
        ratio = by[case]["ratio"]
        verdicts.append(f"target ({case} ≥ {target:g}x faster than {baseline}): "
                        + ("no baseline — NOT met" if ratio is None else
                           f"{ratio:.2f}x — {'met' if ratio >= target else 'NOT met'}"))
    header = (f"CPU µs per step of `ffrmbs run SCENE --no-check --no-export`, median of {rounds} runs, this checkout "
              f"and baseline {baseline} alternately in separate processes"
              + (f"; baseline: {why_not}" if why_not else ""))
    return {"benchmark": "scene_cost", "machine": machine(), "baseline": baseline, "rows": rows,
            "table": header + "\n\n" + "\n".join(table), "verdicts": verdicts}


def run(quick: bool) -> dict:
    return benchmark(**(QUICK if quick else FULL))


def main(argv=None):
    """Run the benchmark (command line ``argv``), print the table, write the JSON; return it."""
    return bench_main(argv, "scene_cost", run, __doc__, "one round, 0.02 s of each scene")


if __name__ == "__main__":
    main()
