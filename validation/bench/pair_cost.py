"""Benchmark: the detection of one closed contact per step (stages 3 and 4 of a Moreau
step) for every registered pair kind, compiled against the Python path, side by side in
one process.

The compiled route is the pair's fused detection (:mod:`mbs.run.fused_detection`: one
numba call; a contour moved by a Python function updated in Python first); the Python
path is what runs without it and stays its reference: ``contour.update`` of both
contours, then ``Contact.locate`` (the broad phase, the warm-started search or the
analytic projection, the contour's evaluation, the gap, frame and Jacobians, a dozen
numba calls glued by Python).

Scenes, one per pair kind of :data:`contact.PAIR_KINEMATICS` and
:data:`contact.BILATERAL_KINEMATICS`: a point mass's point, or a sphere of 10 mm about
it, pressed 1 µm into the surface side at its domain's middle — on the default scene's
beam (20 modes, frame at rest): the top face (2s), its centre line (1s; as a sharp edge:
edge), a band on that line, a cylinder about the beam's axis; on a free rigid table: a 2s
grid, a 1s line; on the ground: a plane, a sphere of 0.1 m. Unilateral pairs take Newton's
impact law, bilateral ones keep the point on the curve. Each route locates the contact
``batch`` times at that state (the warm start is the root: the steady cost of a sliding
contact), batches alternating between the routes, ``rounds`` batches each; the table
gives the medians of the batch means [µs per call] and their ratio. Both routes must
leave the same gap (to 1e-12 m) or the benchmark fails. Compilation happens in the
untimed warm-up.

Run::

    python3 -m validation.bench --only pair_cost [--quick]
"""

from __future__ import annotations

import time

import numpy as np

from validation.bench.common import bench_main, machine

FULL = {"batch": 2000, "rounds": 7}
QUICK = {"batch": 200, "rounds": 3}
RADIUS = 0.01           # [m], the sphere about the point mass
PRESS = 1e-6            # [m], how far the side is pressed into the surface (closed)


def surface(kind, beam, table):
    """The surface side of kind ``kind`` (a name of :data:`contours.CONTOURS`) on the
    beam, the table or the ground (module docstring)."""
    from contours import (CONTOURS, Contour1sNeutralFFR, Contour1sNeutralRigid, Contour2sNeutralFFR,
                          Contour2sNeutralRigid, FlexibleBand, FlexibleCylinder, PlaneContour, SphereContour)
    from ffrmbs_app.scenes import point_mass_beam as pmb
    from mbs import ground_frame

    h, w = pmb.HEIGHT, pmb.WIDTH
    top = lambda cls=Contour1sNeutralFFR, z=w / 2: cls.along_line(beam, (0.0, h, z), (1, 0, 0),  # noqa: E731
                                                                  normal=(0, 1, 0), degree=4)
    s = np.linspace(-0.1, 0.1, 5)
    return {"2s": lambda: Contour2sNeutralFFR(beam, "y1"), "1s": top, "edge": lambda: top(CONTOURS["edge"], w),
            "band": lambda: FlexibleBand(top(), width=w),
            "cylinder": lambda: FlexibleCylinder(Contour1sNeutralFFR.along_line(
                beam, (0.0, h / 2, w / 2), (1, 0, 0), normal=(0, 1, 0), degree=4), radius=h / 2),
            "2s-rigid": lambda: Contour2sNeutralRigid(
                table, np.stack(np.meshgrid(s, s, [0.0], indexing="ij"), axis=-1)[:, :, 0], outward=1),
            "1s-rigid": lambda: Contour1sNeutralRigid(table, np.stack((s, 0 * s, 0 * s), axis=-1), normal=(0, 0, 1)),
            "plane": lambda: PlaneContour(ground_frame((0.0, 0.0, -1.0))),
            "sphere": lambda: SphereContour(ground_frame((0.0, 0.0, -1.0)), 0.1)}[kind]()


def pair_scene(pair, bilateral=False):
    """(system, contact, q, u) of the contour pair ``pair`` (module docstring), the side
    pressed into the surface (on it for a ``bilateral`` pair)."""
    from contact import connect
    from contours import PointContour, SphereContour
    from ffrmbs_app.scenes import point_mass_beam as pmb
    from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, RigidBody, System

    system = System()
    beam = system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=20, frame=PrescribedFrameMotion.fixed(),
                                      name="beam"))
    table = system.add(RigidBody(10.0, 0.1 * np.eye(3), name="table"))
    mass = system.add(PointMass(0.05, name="side"))
    side = PointContour(mass.point) if pair[0] == "point" else SphereContour(mass.point, RADIUS)
    other = surface(pair[1], beam, table)
    contact = system.add(connect(side, other, "bilateral" if bilateral else "impact", name="/".join(pair)))
    q, u = system.initial_state()
    body = other.body
    other.update(None if body is None else q[body.q_slice], None if body is None else u[body.u_slice])
    if pair[1] in ("plane", "sphere"):
        at = (0.0, 0.0) if pair[1] == "plane" else (0.0, 0.5 * np.pi)
    else:
        domain = other.domain if other.dim == 2 else (other.domain,)
        at = tuple(0.5 * (a + b) for a, b in domain)
    p = other.evaluate(other.new_point(), *at)
    q[mass.q_slice] = p.r + (0.0 if bilateral else getattr(side, "radius", 0.0) - PRESS) * p.n
    return system, contact, q, u


def _python_path(contact, q, u):
    """The Python path's locate at (q, u): both contours updated, then ``contact.locate``."""
    updates = [(c, None, None) if c.body is None else (c, c.body.q_slice, c.body.u_slice) for c in contact.contours()]

    def locate():
        for contour, qs, us in updates:
            contour.update(None if qs is None else q[qs], None if us is None else u[us], 0.0)
        return contact.locate()
    return locate


def _batch_mean(call, batch) -> float:
    """Mean wall time of one call [µs] over ``batch`` calls."""
    start = time.perf_counter()
    for _ in range(batch):
        call()
    return 1e6 * (time.perf_counter() - start) / batch


def measure(pair, bilateral, batch, rounds) -> dict:
    """The row of one pair kind: µs per locate of both routes, their ratio, the gap."""
    from mbs.run.fused_detection import fused_detection

    system, contact, q, u = pair_scene(pair, bilateral)
    fused = fused_detection(contact)
    if fused is None:
        return {"pair": "/".join(pair), "bilateral": bilateral, "fused": None}
    compiled = lambda: fused.locate(q, u, 0.0)  # noqa: E731
    python = _python_path(contact, q, u)
    gaps = []
    for locate in (python, compiled, python, compiled):          # warm-up: compiles and warm-starts both
        closed = locate()
        gaps.append(contact.kinematics.g_N)
    if not (closed and np.allclose(gaps, gaps[0], rtol=0.0, atol=1e-12)):
        raise RuntimeError(f"{'/'.join(pair)}: the routes disagree (closed {closed}, gaps {gaps} m)")
    times = {"compiled": [], "python": []}
    for _ in range(rounds):
        for name, call in (("compiled", compiled), ("python", python)):
            times[name].append(_batch_mean(call, batch))
    med = {name: float(np.median(t)) for name, t in times.items()}
    return {"pair": "/".join(pair), "bilateral": bilateral, "fused": type(fused).__name__,
            "compiled_us": med["compiled"], "python_us": med["python"], "ratio": med["python"] / med["compiled"],
            "g_N": float(gaps[0])}


def run(quick=False) -> dict:
    """Every registered pair kind's row (module docstring), the table and the verdict
    that each has a fused detection."""
    from contact import BILATERAL_KINEMATICS, PAIR_KINEMATICS

    settings = QUICK if quick else FULL
    pairs = [(pair, False) for pair in PAIR_KINEMATICS.names()] + [(pair, True) for pair in BILATERAL_KINEMATICS.names()]
    rows = [measure(pair, bilateral, settings["batch"], settings["rounds"]) for pair, bilateral in pairs]
    lines = [f"µs per locate of one closed contact, median of {settings['rounds']} batches of {settings['batch']}, "
             "compiled (fused detection) and the Python path alternately in one process", "",
             "| pair kind | fused detection | compiled µs | Python path µs | Python / compiled |", "|---|---|---|---|---|"]
    for r in rows:
        name = r["pair"] + (" (bilateral)" if r["bilateral"] else "")
        if r["fused"] is None:
            lines.append(f"| {name} | none | | | |")
        else:
            lines.append(f"| {name} | {r['fused']} | {r['compiled_us']:.1f} | {r['python_us']:.1f} | "
                         f"{r['ratio']:.1f} |")
    missing = [r["pair"] for r in rows if r["fused"] is None]
    verdict = (f"target (every registered pair kind has a fused detection): "
               f"{'met' if not missing else 'NOT met (' + ', '.join(missing) + ')'}")
    return {"benchmark": "pair_cost", "machine": machine(), "settings": settings, "rows": rows,
            "table": "\n".join(lines), "verdicts": [verdict]}


def main(argv=None):
    return bench_main(argv, "pair_cost", run, __doc__, f"{QUICK['rounds']} batches of {QUICK['batch']} calls")


if __name__ == "__main__":
    main()
