"""Cost of evaluating a NURBS contour on an FFR body, and of updating it once per step.

Claim under test (thesis Sec. 3.2.2, 4.4.1; issue 5): the knots of a neutral contour are
fixed and interpolation is linear, so the mode shapes Φ are interpolated once and a step
only combines control points, P_ū = P_ū0 + P_Φ q_f and P_r = R + A P_ū (the velocity's
P_ṙ = v + A (ω̄ × P_ū + P_Φ q̇_f) on first use in the step), at O(control points × n_f),
whatever the body's node count. An evaluation at (η, ξ) locates the basis once and
contracts a few control-point arrays: position, tangents, second derivatives and frame
(eq. 3.25–3.29), the Jacobians J_T = [1, −A ũ T, A Φ] and J_R (eq. 2.70, 2.72) and the
velocity ṙ.

Contours: a 2s contour (``Contour2sNeutralFFR``) on the top face ``'y1'`` of the
thesis's 250 x 50 x 50 mm beam (Sec. 5.2, free-free modes, tet4 ``box`` meshes with
divisions (10, 4, 4) and (40, 8, 8)), and a 1s contour (``Contour1sNeutralFFR.along_line``)
on the beam's centre line. Each with n_f = 20 and 100 modes (one modal analysis with 100
modes per mesh; the bodies take the first 20 or all). Timed, per contour and n_f:

* ``evaluate``: ``evaluate(point, η, ξ)`` — position, derivatives, frame;
* ``evaluate_J``: ``evaluate(..., jacobians=True)`` — adds J_T, J_R;
* ``evaluate_vJ``: ``evaluate(..., velocity=True, jacobians=True)`` with the velocity
  control points already current (a second evaluation in the same step);
* ``update``: ``update(q, u)``, once per step;
* ``update_v``: ``update(q, u)`` plus the step's first velocity evaluation (which computes
  the velocity control points lazily), i.e. one step with one contact point;
* ``ubar``: the ū stage of the update alone, P_ū = P_ū0 + P_Φ q_f
  (``contour.local_position.update(q_f)``);
* ``naive``: the route the linear update avoids — re-interpolating the nodal ū every step,
  ``contour.space.interpolate(ū0 + Φ q_f)`` at the contour's nodes (ū0 and Φ of those
  nodes gathered beforehand). It replaces only the ū stage: ``naive / ubar`` compares
  like with like; ``naive / update`` understates the saving (the frame state and
  P_r = R + A P_ū, common to both routes, are in ``update`` only).

Points (η, ξ) are uniform at random in the contour's domain, states are random (large
rotation and translation, elastic displacements ~ 2 mm, random velocities), cycled
through from call to call. Times are wall-clock (``time.perf_counter``) per call: the
mean over a batch of ``--batch`` calls, reported as the median and the minimum of
``--batches`` such batch means [µs], after one warm-up call (numba compilation). For one
contour the functions are timed interleaved batch by batch, so that a change of machine
load hits them alike. ``setup_s`` is the one-off construction of the contour (node
matrix, interpolation factored, Φ interpolated), the shortest of three. The naive
route's triangular solves and the ū stage's product P_Φ q_f go through the threaded BLAS,
which on a machine shared with other work can stall (medians several times the minima);
for steady times run with ``OPENBLAS_NUM_THREADS=1`` (the JSON records it). Prints a
markdown table and the update cost of the fine mesh over the coarse one next to the
ratios of control points and of body nodes; writes ``contour_evaluation.json`` to
``--out`` (default ``./bench_out``).

Usage::

    python3 -m validation.bench.contour_evaluation [--quick] [--out DIR]

``--quick``: fewer batches (runs in well under a minute); ``--divisions`` and ``--modes``
choose the meshes and mode counts (e.g. ``--divisions 10,4,4 --modes 20`` for a smoke run).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from contours import Contour1sNeutralFFR, Contour2sNeutralFFR
from mbs import FlexibleBodyFFR
from preprocess import Material, box, build_body

from .common import divisions_arg, machine, moving_state, write_json

L, H, W = 0.25, 0.05, 0.05                 # [m], thesis Sec. 5.2
MATERIAL = Material(920.0, 5e7, 0.3)      # [kg/m³, Pa, -], the thesis's rubber-like beam
DIVISIONS = ((10, 4, 4), (40, 8, 8))
MODES = (20, 100)
FULL = {"batches": 200, "batch": 50}
QUICK = {"batches": 20, "batch": 20}
N_POINTS = 97                              # random (η, ξ) per contour
N_STATES = 16                              # random states per body
FUNCTIONS = ("evaluate", "evaluate_J", "evaluate_vJ", "update", "update_v", "ubar", "naive")


def make_contour(kind, body):
    """The 2s contour on the top face or the 1s contour on the centre line of ``body``."""
    if kind == "2s":
        return Contour2sNeutralFFR(body, "y1")
    return Contour1sNeutralFFR.along_line(body, (0.0, H / 2, W / 2), (1.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))


def time_batches(fns, batches, batch):
    """(median, min) over ``batches`` of the mean wall time per call [µs] of each of
    ``fns`` (each called as fn(i) with a running call index i), after one warm-up call
    each; interleaved batch by batch."""
    for fn in fns:
        fn(0)
    means = np.empty((batches, len(fns)))
    for k in range(batches):
        first = k * batch
        for j, fn in enumerate(fns):
            start = time.perf_counter()
            for i in range(first, first + batch):
                fn(i)
            means[k, j] = (time.perf_counter() - start) / batch
    return [{"median": float(np.median(col)) * 1e6, "min": float(col.min()) * 1e6} for col in means.T]


def measure(kind, body, divisions, batches, batch, rng):
    """One entry: the timings of FUNCTIONS for the contour ``kind`` on ``body``."""
    setup = np.inf
    for _ in range(3):
        start = time.perf_counter()
        contour = make_contour(kind, body)
        setup = min(setup, time.perf_counter() - start)
    stepper = make_contour(kind, body)         # updated every call; `contour` keeps one state
    states = [moving_state(body, rng) for _ in range(N_STATES)]
    contour.update(*states[0])
    point, step_point = contour.new_point(), stepper.new_point()
    if contour.dim == 2:
        (a, b), (c, d) = contour.domain
        pts = np.column_stack([rng.uniform(a, b, N_POINTS), rng.uniform(c, d, N_POINTS)])
    else:
        a, b = contour.domain
        pts = np.column_stack([rng.uniform(a, b, N_POINTS), np.zeros(N_POINTS)])
    pts = [tuple(map(float, p)) for p in pts]
    nodes = np.asarray(contour.nodes)
    u0_nodes = body.data.u0[nodes]                                           # grid + (3,)
    phi_nodes = body.phi_nodes[nodes]  # grid + (3, n_f)
    q_fs = [body.elastic_coordinates(q) for q, _ in states]
    space = contour.space

    def evaluate(i):
        contour.evaluate(point, *pts[i % N_POINTS])

    def evaluate_J(i):
        contour.evaluate(point, *pts[i % N_POINTS], jacobians=True)

    def evaluate_vJ(i):
        contour.evaluate(point, *pts[i % N_POINTS], velocity=True, jacobians=True)

    def update(i):
        stepper.update(*states[i % N_STATES])

    def update_v(i):
        stepper.update(*states[i % N_STATES])
        stepper.evaluate(step_point, *pts[i % N_POINTS], velocity=True)

    def ubar(i):
        stepper.local_position.update(q_fs[i % N_STATES])

    def naive(i):
        space.interpolate(u0_nodes + phi_nodes @ q_fs[i % N_STATES])

    timings = time_batches([evaluate, evaluate_J, evaluate_vJ, update, update_v, ubar, naive], batches, batch)
    entry = {"contour": f"{kind} {'top face y1' if kind == '2s' else 'centre line'}", "kind": kind,
             "divisions": list(divisions), "body_nodes": int(body.data.n_nodes),
             "contour_nodes": int(nodes.size), "node_grid": list(nodes.shape),
             "control_points": int(np.prod(space.ctrl_shape)), "n_f": int(body.n_modes), "setup_s": setup}
    entry.update({f"{name}_us": t for name, t in zip(FUNCTIONS, timings)})
    for ref in ("update", "ubar"):
        entry[f"naive_over_{ref}"] = {s: entry["naive_us"][s] / entry[f"{ref}_us"][s] for s in ("median", "min")}
    return entry


def scaling(entries):
    """Per contour kind and n_f, the update time on the finest mesh over that on the
    coarsest, next to the ratios of control points and of body nodes."""
    rows = []
    for kind in sorted({e["kind"] for e in entries}):
        for n_f in sorted({e["n_f"] for e in entries}):
            group = sorted((e for e in entries if e["kind"] == kind and e["n_f"] == n_f),
                           key=lambda e: e["body_nodes"])
            if len(group) < 2:
                continue
            lo, hi = group[0], group[-1]
            rows.append({"contour": lo["contour"], "n_f": n_f, "divisions": [lo["divisions"], hi["divisions"]],
                         "control_points_ratio": hi["control_points"] / lo["control_points"],
                         "body_nodes_ratio": hi["body_nodes"] / lo["body_nodes"],
                         **{f"{fn}_ratio": {s: hi[f"{fn}_us"][s] / lo[f"{fn}_us"][s] for s in ("median", "min")}
                            for fn in ("update", "update_v", "ubar", "naive", "evaluate_J")}})
    return rows


def markdown(doc):
    """The results as markdown: timings (median / min of batch means [µs]) and scaling."""
    lines = ["Times per call [µs], median / min of batch means.", "",
             "| contour | divisions | body nodes | contour nodes | ctrl pts | n_f | evaluate | + J_T, J_R | "
             "+ v, J_T, J_R | update | update + 1st v | ū stage | naive ū re-interp. | naive / update | "
             "naive / ū stage |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for e in doc["rows"]:
        cells = " | ".join(f"{e[f'{fn}_us']['median']:.1f} / {e[f'{fn}_us']['min']:.1f}" for fn in FUNCTIONS)
        grid = " x ".join(map(str, e["node_grid"]))
        lines.append(f"| {e['contour']} | {tuple(e['divisions'])} | {e['body_nodes']} | {grid} | "
                     f"{e['control_points']} | {e['n_f']} | {cells} | "
                     f"{e['naive_over_update']['median']:.1f} | {e['naive_over_ubar']['median']:.1f} |")
    if doc["scaling"]:
        lines += ["", "Finest mesh over coarsest (medians):", "",
                  "| contour | n_f | ctrl pts ratio | body nodes ratio | update | update + 1st v | ū stage | naive | "
                  "evaluate + J |", "|---|---|---|---|---|---|---|---|---|"]
        lines += [f"| {r['contour']} | {r['n_f']} | {r['control_points_ratio']:.1f} | {r['body_nodes_ratio']:.1f} | "
                  f"{r['update_ratio']['median']:.2f} | {r['update_v_ratio']['median']:.2f} | "
                  f"{r['ubar_ratio']['median']:.2f} | "
                  f"{r['naive_ratio']['median']:.2f} | {r['evaluate_J_ratio']['median']:.2f} |"
                  for r in doc["scaling"]]
    return "\n".join(lines)


def benchmark(quick=False, batches=None, batch=None, divisions=DIVISIONS, modes=MODES, seed=0, log=print) -> dict:
    """The benchmark's document: one row per contour, mesh and n_f (``rows``), the
    ``scaling`` rows, the markdown ``table`` and the settings. ``batches``, ``batch``:
    None takes those of ``QUICK`` or ``FULL``."""
    sizes = dict(QUICK if quick else FULL)
    sizes.update({k: v for k, v in (("batches", batches), ("batch", batch)) if v is not None})
    rng = np.random.default_rng(seed)
    rows, modal_s = [], {}
    for div in divisions:
        start = time.perf_counter()
        data = build_body(box(L, H, W, None, order=1, divisions=div), MATERIAL, n_modes=max(modes))
        modal_s[",".join(map(str, div))] = time.perf_counter() - start
        for n_f in modes:
            body = FlexibleBodyFFR(data, modes=n_f)
            for kind in ("2s", "1s"):
                rows.append(measure(kind, body, div, sizes["batches"], sizes["batch"], rng))
            log(f"divisions {div}, n_f = {n_f}: done")
    doc = {"benchmark": "contour_evaluation", "quick": quick, **sizes, "seed": seed,
           "clock": "time.perf_counter (wall), mean per call over a batch",
           "beam_m": [L, H, W], "element": "tet4", "modes": "free-free",
           "machine": machine(),
           "body_build_s": modal_s, "rows": rows, "scaling": scaling(rows)}
    doc["table"] = markdown(doc)
    return doc


def run(quick: bool) -> dict:
    """The benchmark protocol of :mod:`validation.bench.runner`: :func:`benchmark` at its defaults."""
    return benchmark(quick)


def main(argv=None):
    """Run the benchmark (command line ``argv``), print the tables, write the JSON; return it."""
    parser = argparse.ArgumentParser(prog="python3 -m validation.bench.contour_evaluation",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK['batches']} batches of {QUICK['batch']} calls instead of "
                             f"{FULL['batches']} of {FULL['batch']}")
    parser.add_argument("--out", default="bench_out", help="output directory (default ./bench_out)")
    parser.add_argument("--batches", type=int, default=None, help="timed batches per function")
    parser.add_argument("--batch", type=int, default=None, help="calls per batch")
    parser.add_argument("--divisions", type=divisions_arg, nargs="+", default=list(DIVISIONS),
                        help="box mesh divisions, e.g. 10,4,4 40,8,8 (default)")
    parser.add_argument("--modes", type=int, nargs="+", default=list(MODES), help="mode counts n_f (default 20 100)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the points and states")
    args = parser.parse_args(argv)
    if any(n is not None and n < 1 for n in (args.batches, args.batch)):
        parser.error("--batches and --batch must be at least 1")
    if min(args.modes) < 1:
        parser.error("--modes must be at least 1")
    doc = benchmark(args.quick, args.batches, args.batch, args.divisions, args.modes, args.seed)
    print(doc["table"])
    write_json(doc, args.out, "contour_evaluation")
    return doc


if __name__ == "__main__":
    main()
