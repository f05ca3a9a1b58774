"""What every benchmark shares: the machine record and the report writer, and a random
moving state of a floating-frame body."""

from __future__ import annotations

import argparse
import json
import os
import platform

import numba
import numpy as np

from mbs.bodies.rotations import quat_from_rotvec

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")


def machine() -> dict:
    """Platform, versions, cores and the thread-count variables (timings depend on them)."""
    return {"platform": platform.platform(), "python": platform.python_version(), "numpy": np.__version__,
            "numba": numba.__version__, "cpu_count": os.cpu_count(),
            "thread_env": {v: os.environ.get(v) for v in THREAD_VARIABLES}}


def write_json(doc: dict, out: str, name: str) -> str:
    """Write ``doc`` to ``out/name.json``, print and return the path (nothing is written
    when ``doc`` cannot be serialized)."""
    text = json.dumps(doc, indent=1)
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, f"{name}.json")
    with open(path, "w") as f:
        f.write(text)
    print(f"wrote {path}")
    return path


def divisions_arg(text) -> tuple:
    """argparse type of a structured box mesh's divisions "nx,ny,nz" (element edges per axis)."""
    try:
        d = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"divisions must be three integers like 10,4,4, got {text!r}") from None
    if len(d) != 3 or min(d) < 1:
        raise argparse.ArgumentTypeError(f"divisions must be three positive integers like 10,4,4, got {text!r}")
    return d


def moving_state(body, rng, deform=2e-3):
    """A random state (q, u) of a free FFR body (quaternion frame): large rotation and
    translation, elastic displacements ~ ``deform`` [m] (largest nodal amplitude), random
    frame and elastic velocities — every term of the kinematics non-zero."""
    q, u = body.q_init.copy(), np.zeros(body.nu)
    q[:3] = rng.normal(size=3)
    q[3:7] = quat_from_rotvec(rng.normal(size=3))
    scale = deform / np.abs(body.phi).max()
    q[7:] = scale * rng.normal(size=body.n_modes) / np.sqrt(body.n_modes)
    u[:] = rng.normal(size=body.nu)
    u[6:] *= scale
    return q, u


def bench_main(argv, name, run, doc_string, quick_help):
    """The command line of a benchmark module ``validation.bench.<name>``: parse ``--quick``
    (help ``quick_help``) and ``--out``, run ``run(quick)``, print its table and verdicts,
    write ``<out>/<name>.json``; returns the document."""
    import argparse

    parser = argparse.ArgumentParser(prog=f"python3 -m validation.bench.{name}", description=doc_string.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument("--out", default="out/bench")
    args = parser.parse_args(argv)
    doc = run(args.quick)
    print(doc["table"])
    print("\n".join(doc.get("verdicts", [])))
    write_json(doc, args.out, name)
    return doc
