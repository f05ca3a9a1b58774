"""Cost of one evaluation of an FFR body's M(q) and h(q, u) against node count and modes.

Claim under test (thesis Sec. 4.3.1, Algorithm 3): the shape integrals I1, S̄ (eq. 2.53,
2.54) and I_kl, Ī_kl, S̄_kl (eq. 2.65) are summed over the nodes once, at O(N n_f²); after
that the mass matrix (eq. 2.44–2.69) and the quadratic velocity vector (eq. 2.77–2.79)
cost O(n_f²) per evaluation, whatever the node count N. This benchmark times
``FlexibleBodyFFR.mass_matrix(q)`` and ``.h(q, u)`` of a free body (quaternion frame) for
n_f = 10, 30, 100 modes on bodies of N = 500, 5 000 and 50 000 nodes, and the one-off
construction of the body (shape integrals and K_ff = Φᵀ K Φ, eq. 2.19).

The bodies are synthetic :class:`preprocess.BodyData`: nodes at random in a 1 x 1 x 5 m box,
positive random masses (a 40 t block), mass-normalized random mode shapes
Φ = M^{-½} Q with Q from a QR factorization (Φᵀ M Φ = 1, like the modes of
:mod:`preprocess.modes`) and a positive diagonal sparse stiffness. An eigen solve of a
50 000-node mesh would take minutes; the evaluation cost does not depend on the values,
only on the array shapes (N, n_f).

Times are wall-clock (``time.perf_counter``) per call over ``--repeats`` calls after one
warm-up call, reported as median and minimum [µs]; for one n_f the bodies of all sizes are
called in turn, so that other load on the machine hits them alike. The setup time [s] is
the shortest of three constructions of the body; its matrix products use the threaded
BLAS, which on a machine shared with other work can stall for seconds, so for steady
setup times run with ``OPENBLAS_NUM_THREADS=1`` (the JSON records these variables). The
state is a random pose, angular velocity and elastic state (all terms non-zero). Prints a
markdown table and, per n_f, the ratio of the largest to the smallest body's time (of the
medians and of the minima); writes ``ffr_evaluation.json`` to ``--out`` (default
``./bench_out``).

Usage::

    python3 -m validation.bench.ffr_evaluation [--quick] [--out DIR] [--repeats N]

``--quick``: n_f = 10, 30 and N = 500, 5 000 only.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
from scipy.spatial.transform import Rotation

from mbs import FlexibleBodyFFR
from preprocess import BodyData

from .common import machine, write_json

FULL = {"n_f": (10, 30, 100), "nodes": (500, 5000, 50000)}
QUICK = {"n_f": (10, 30), "nodes": (500, 5000)}
BOX = np.array([1.0, 1.0, 5.0])        # [m]
TOTAL_MASS = 8000.0 * BOX.prod()       # [kg], a steel block of the box's size


def synthetic_body(n_nodes, n_f, rng) -> BodyData:
    """Random body data: u0 (N, 3) [m] in BOX, masses (N,) [kg] summing to about TOTAL_MASS,
    Φ (3N, n_f) [kg^-½] with Φᵀ M Φ = 1, K (3N, 3N) diagonal CSR in [1e8, 1e9] N/m."""
    u0 = rng.uniform(0.0, 1.0, (n_nodes, 3)) * BOX
    masses = rng.uniform(0.5, 1.5, n_nodes) * TOTAL_MASS / n_nodes
    Q, _ = np.linalg.qr(rng.standard_normal((3 * n_nodes, n_f)))
    phi = Q / np.sqrt(np.repeat(masses, 3))[:, None]
    stiffness = sp.diags(rng.uniform(1e8, 1e9, 3 * n_nodes)).tocsr()
    return BodyData(u0=u0, phi=phi, masses=masses, stiffness=stiffness)


def time_calls(fns, repeats):
    """(median, min) wall time [µs] of each of ``fns`` over ``repeats`` calls after one warm-up
    call each. The calls are interleaved (f0, f1, ..., f0, f1, ...), so that a change of
    machine load during the run affects all of them alike."""
    for fn in fns:
        fn()
    samples = np.empty((repeats, len(fns)))
    for k in range(repeats):
        for j, fn in enumerate(fns):
            start = time.perf_counter()
            fn()
            samples[k, j] = time.perf_counter() - start
    return [(float(np.median(col)) * 1e6, float(col.min()) * 1e6) for col in samples.T]


def prepared_body(n_nodes, n_f, rng, builds=3):
    """(body, setup time [s], q, u): a synthetic free body at a random pose, angular
    velocity and elastic state; the setup time (shape integrals and K_ff) is the shortest
    of ``builds`` constructions, the one-off cost without the machine's other load."""
    data = synthetic_body(n_nodes, n_f, rng)
    setup = np.inf
    for _ in range(builds):
        start = time.perf_counter()
        body = FlexibleBodyFFR(data, None)
        setup = min(setup, time.perf_counter() - start)
    body.set_initial(R=rng.uniform(-1, 1, 3), A=Rotation.from_quat(rng.standard_normal(4)).as_matrix(),
                     v=rng.uniform(-1, 1, 3), omega=rng.uniform(-5, 5, 3),
                     q_f=rng.uniform(-1e-3, 1e-3, n_f), qdot_f=rng.uniform(-0.1, 0.1, n_f))
    return body, setup, body.q_init, body.u_init


def measure(n_f, node_counts, repeats, rng):
    """Entries for one n_f, one per node count: setup time [s] and (median, min) [µs] of
    M(q) and h(q, u), the bodies of all node counts timed interleaved."""
    bodies = [prepared_body(n, n_f, rng) for n in node_counts]
    mass = time_calls([lambda b=b, q=q: b.mass_matrix(q) for b, _, q, _ in bodies], repeats)
    forces = time_calls([lambda b=b, q=q, u=u: b.h(q, u) for b, _, q, u in bodies], repeats)
    return [{"n_f": n_f, "nodes": n, "setup_s": setup,
             "mass_matrix_us": {"median": m[0], "min": m[1]}, "h_us": {"median": h[0], "min": h[1]}}
            for n, (_, setup, _, _), m, h in zip(node_counts, bodies, mass, forces)]


def ratios(rows, sizes):
    """Per n_f, the time of the largest body over that of the smallest, for M and h, of the
    medians and of the minima."""
    by_key = {(e["n_f"], e["nodes"]): e for e in rows}
    small, large = min(sizes["nodes"]), max(sizes["nodes"])
    return [{"n_f": n_f, "nodes": [small, large],
             **{fn: {stat: by_key[n_f, large][f"{fn}_us"][stat] / by_key[n_f, small][f"{fn}_us"][stat]
                     for stat in ("median", "min")} for fn in ("mass_matrix", "h")}}
            for n_f in sizes["n_f"]]


def markdown(doc):
    """The results as two markdown tables: timings per (n_f, N), and the ratios."""
    lines = ["| n_f | nodes | setup [s] | M median [µs] | M min [µs] | h median [µs] | h min [µs] |",
             "|---|---|---|---|---|---|---|"]
    for e in doc["rows"]:
        m, h = e["mass_matrix_us"], e["h_us"]
        lines.append(f"| {e['n_f']} | {e['nodes']} | {e['setup_s']:.3g} | {m['median']:.1f} | "
                     f"{m['min']:.1f} | {h['median']:.1f} | {h['min']:.1f} |")
    small, large = doc["ratios"][0]["nodes"]
    lines += ["", f"Time with {large} nodes / time with {small} nodes:", "",
              "| n_f | M (medians) | M (minima) | h (medians) | h (minima) |", "|---|---|---|---|---|"]
    lines += [f"| {r['n_f']} | {r['mass_matrix']['median']:.2f} | {r['mass_matrix']['min']:.2f} | "
              f"{r['h']['median']:.2f} | {r['h']['min']:.2f} |" for r in doc["ratios"]]
    return "\n".join(lines)


def benchmark(quick=False, repeats=1000, seed=0, log=print) -> dict:
    """The benchmark's document: timings (``rows``), ``ratios``, the markdown ``table`` and
    the settings; ``quick``: n_f 10, 30 on 500 and 5000 nodes only."""
    sizes = QUICK if quick else FULL
    rng = np.random.default_rng(seed)
    rows = []
    for n_f in sizes["n_f"]:
        rows += measure(n_f, sizes["nodes"], repeats, rng)
        log(f"n_f = {n_f}: done")
    doc = {"benchmark": "ffr_evaluation", "quick": quick, "repeats": repeats, "seed": seed,
           "clock": "time.perf_counter (wall)", "machine": machine(), "rows": rows, "ratios": ratios(rows, sizes)}
    doc["table"] = markdown(doc)
    return doc


def run(quick: bool) -> dict:
    """The benchmark protocol of :mod:`validation.bench.runner`: :func:`benchmark` at its defaults."""
    return benchmark(quick)


def main(argv=None):
    """Run the benchmark (command line ``argv``), print the tables, write the JSON; return it."""
    parser = argparse.ArgumentParser(prog="python3 -m validation.bench.ffr_evaluation",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="n_f 10, 30 and 500, 5000 nodes only")
    parser.add_argument("--out", default="bench_out", help="output directory (default ./bench_out)")
    parser.add_argument("--repeats", type=int, default=1000, help="timed calls per function")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic bodies")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    doc = benchmark(args.quick, args.repeats, args.seed)
    print(doc["table"])
    write_json(doc, args.out, "ffr_evaluation")
    return doc


if __name__ == "__main__":
    main()
