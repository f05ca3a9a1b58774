"""Benchmark: the preprocessing cost of the geometric stiffness (:mod:`preprocess.geometric`).

Times :func:`preprocess.geometric.geometric_stiffness` alone — one sparse LU factorization
of the inertia-relief bordered system (eq. R3 of :mod:`preprocess.residual`), twelve
solves, the K_σ assembly of the twelve stress fields (eq. G3) and their twelve modal
projections (eq. G4) — on structured tet10 beams of about 1 000, 5 000, 20 000 and
50 000 nodes: a 6 × 6-element square section of 0.12 m (element edge 0.02 m), the length
grown to reach the node count, steel, free-free. Slender bodies keep the factor banded
(its cost grows linearly with the length); a blocky body of the same node count costs
more (:mod:`preprocess.limits` on the factor's profile).

Φ: ten random M-orthonormal vectors (3N, 10), not eigenvectors: the cost of the call does
not depend on Φ's values (Φ enters only the n_f = 10 projections), and the 50 000-node
eigensolve would dominate the run.

Each mesh runs in its own process (``--worker nx,ny,nz``), so that the memory figures are
its own: RSS before the call (mesh, K, masses) and the peak RSS during it, sampled every
5 ms by a thread reading /proc/self/statm (Linux; elsewhere the memory columns are
empty). Times: wall seconds of the solves and of the assembly and projection, as the
function logs them, and the call's total wall and CPU seconds.

Run::

    python3 -m validation.bench.geometric_stiffness_cost [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import threading
import time

import numpy as np

SECTION = 6                                   # elements across each side of the square section
EDGE = 0.02                                   # element edge [m]
LENGTHS = (3, 14, 59, 148)                    # elements along the beam: 1 183, 4 901, 20 111, 50 193 nodes
QUICK_LENGTHS = LENGTHS[:2]
N_MODES = 10
STEEL = (7800.0, 2.1e11, 0.3)                 # density [kg/m³], E [Pa], ν [-]
_LOGGED = re.compile(r"solves ([0-9.]+) s, assembly and projection ([0-9.]+) s")


def _rss_bytes():
    """The resident set size of this process [B], or None off Linux."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:
        return None


class _PeakRss(threading.Thread):
    """Samples the RSS every ``interval`` [s] until stopped; ``peak`` [B] the largest seen."""

    def __init__(self, interval=0.005):
        super().__init__(daemon=True)
        self.interval, self.peak = interval, _rss_bytes()
        self._stop_event = threading.Event()

    def run(self):
        while not self._stop_event.wait(self.interval):
            rss = _rss_bytes()
            if rss is not None and self.peak is not None:
                self.peak = max(self.peak, rss)

    def stop(self):
        self._stop_event.set()
        self.join()
        rss = _rss_bytes()
        if rss is not None and self.peak is not None:
            self.peak = max(self.peak, rss)
        return self.peak


def random_modes(masses, n, seed=0):
    """``n`` random vectors (3N, n) [kg^-1/2], M-orthonormal with the lumped ``masses`` (N,):
    Φᵀ M Φ = I (QR of M^½ X, then Φ = M^-½ Q)."""
    sqrt_m = np.sqrt(np.repeat(masses, 3))
    q, _ = np.linalg.qr(np.random.default_rng(seed).standard_normal((len(sqrt_m), n)))
    return q / sqrt_m[:, None]


def measure(length):
    """One mesh of ``length`` elements along the beam, in this process: its row (dict)."""
    from preprocess import box, fe
    from preprocess.geometric import geometric_stiffness

    divisions = (SECTION, SECTION, length)
    mesh = box(SECTION * EDGE, SECTION * EDGE, length * EDGE, None, order=2, divisions=divisions,
               check_limits=False)
    density, young, poisson = STEEL
    K = fe.stiffness_matrix(mesh, young, poisson)
    masses = fe.lumped_masses(mesh, density)
    phi = random_modes(masses, N_MODES)
    logged = []
    rss_before = _rss_bytes()
    sampler = _PeakRss()
    sampler.start()
    wall, cpu = time.perf_counter(), time.process_time()
    geometric_stiffness(mesh, K, young, poisson, masses, phi, log=logged.append)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    peak = sampler.stop()
    solve_s, assembly_s = (float(x) for x in _LOGGED.search(logged[0]).groups())
    return {"divisions": list(divisions), "nodes": mesh.n_nodes, "elements": mesh.n_elements,
            "dofs": 3 * mesh.n_nodes, "solve_s": solve_s, "assembly_projection_s": assembly_s,
            "total_s": wall, "cpu_s": cpu,
            "rss_before_mb": None if rss_before is None else rss_before / 2 ** 20,
            "peak_rss_mb": None if peak is None else peak / 2 ** 20}


def _worker_row(length):
    """The row of ``length``, measured in a fresh Python process (its own memory)."""
    out = subprocess.run([sys.executable, "-m", "validation.bench.geometric_stiffness_cost", "--worker",
                          str(length)], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _mb(x):
    return "–" if x is None else f"{x:.0f}"


def table(rows):
    """Markdown table of the rows."""
    lines = ["| nodes | elements | DOFs | solves [s] | assembly + projection [s] | total wall [s] | "
             "total CPU [s] | RSS before [MB] | peak RSS [MB] |", "|---" * 9 + "|"]
    for r in rows:
        lines.append(f"| {r['nodes']} | {r['elements']} | {r['dofs']} | {r['solve_s']:.2f} | "
                     f"{r['assembly_projection_s']:.2f} | {r['total_s']:.2f} | {r['cpu_s']:.2f} | "
                     f"{_mb(r['rss_before_mb'])} | {_mb(r['peak_rss_mb'])} |")
    return "\n".join(lines)


def run(quick: bool) -> dict:
    """The benchmark protocol of :mod:`validation.bench.runner`: {"table", "rows"}."""
    rows = [_worker_row(n) for n in (QUICK_LENGTHS if quick else LENGTHS)]
    return {"table": table(rows), "rows": rows,
            "setup": f"tet10 beams, {SECTION} x {SECTION} section, edge {EDGE} m, free-free, "
                     f"{N_MODES} random M-orthonormal vectors as Φ"}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the two smallest meshes only")
    parser.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker is not None:
        print(json.dumps(measure(args.worker)))
        return
    print(run(args.quick)["table"])


if __name__ == "__main__":
    main()
