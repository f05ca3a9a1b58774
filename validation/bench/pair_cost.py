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

A second table gives the per-step cost in far-apart pairs (issue 32's target: flat
within 10 %) for every unilateral pair kind: the same scene run by Moreau's stages under
a plan, alone, with 16 more point masses (2 m and more out along the surface's normal,
flying away) each in a contact of the same kind with the same surface, and with those
masses but no contacts. The pairs' share is (with pairs − without) / alone: what the
planned broad phase (:mod:`mbs.run.bounding_spheres`) leaves of the far pairs' cost. For
a surface on the beam the scene alone also runs with the beam meshed 20 x 8 x 8 (its 40
lowest modes stored, 20 used as before): the per-step cost against the node count.

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
FAR = 2.0               # [m], the nearest far-apart side's distance from the surface
FAR_PAIRS = 16          # far-apart pairs of the step-cost table
FLAT_TOL = 0.10         # far pairs, finer mesh: per-step cost within 10 % of the step without
FINE = (20, 8, 8)       # the finer mesh of the beam (tet4 divisions) of the node-count column
ON_BEAM = ("2s", "1s", "edge", "band", "cylinder")     # the surface kinds on the beam


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


def beam_data(divisions=None):
    """The beam's body data: the default scene's tet4 beam (10 x 4 x 4, all modes), or
    the same beam meshed with ``divisions`` (its 40 lowest modes)."""
    from ffrmbs_app.scenes import point_mass_beam as pmb

    return pmb.default_beam_data() if divisions is None else pmb.default_beam_data(divisions=divisions, modes=40)


def pair_scene(pair, bilateral=False, far=0, far_contacts=True, divisions=None, law="impact"):
    """(system, contact, q, u) of the contour pair ``pair`` (module docstring), the side
    pressed into the surface (on it for a ``bilateral`` pair); with ``far`` point masses
    more, FAR + k metres out along the surface's normal and flying away at 0.1 m/s, each
    (``far_contacts``) with a side of the same kind in a contact with the same surface;
    the beam meshed with ``divisions`` (:func:`beam_data`); ``law`` a unilateral law or its name."""
    from contact import connect
    from contours import PointContour, SphereContour
    from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, RigidBody, System

    def side_of(mass):
        return PointContour(mass.point) if pair[0] == "point" else SphereContour(mass.point, RADIUS)

    system = System()
    beam = system.add(FlexibleBodyFFR(beam_data(divisions), modes=20, frame=PrescribedFrameMotion.fixed(),
                                      name="beam"))
    table = system.add(RigidBody(10.0, 0.1 * np.eye(3), name="table"))
    mass = system.add(PointMass(0.05, name="side"))
    other = surface(pair[1], beam, table)
    contact = system.add(connect(side_of(mass), other, "bilateral" if bilateral else law, name="/".join(pair)))
    far_masses = [system.add(PointMass(0.05, name=f"far {k}")) for k in range(far)]
    if far_contacts:
        for k, m in enumerate(far_masses):
            system.add(connect(side_of(m), other, "impact", name=f"far {k}"))
    q, u = system.initial_state()
    body = other.body
    other.update(None if body is None else q[body.q_slice], None if body is None else u[body.u_slice])
    if pair[1] in ("plane", "sphere"):
        at = (0.0, 0.0) if pair[1] == "plane" else (0.0, 0.5 * np.pi)
    else:
        domain = other.domain if other.dim == 2 else (other.domain,)
        at = tuple(0.5 * (a + b) for a, b in domain)
    p = other.evaluate(other.new_point(), *at)
    q[mass.q_slice] = p.r + (0.0 if bilateral else getattr(contact.kinematics.contour1, "radius", 0.0) - PRESS) * p.n
    for k, m in enumerate(far_masses):
        q[m.q_slice], u[m.u_slice] = p.r + (FAR + k) * p.n, 0.1 * p.n
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


def _planned_run(pair, far, far_contacts, divisions=None):
    """(Model, Data) of a planned Moreau run of :func:`pair_scene` (θ = ½, Gauss–Seidel)."""
    from contact.solver import ProxSolver
    from mbs.run.model import Data, compile_model

    system, _, q, u = pair_scene(pair, far=far, far_contacts=far_contacts, divisions=divisions)
    model = compile_model(system, system.plan(1.0), theta=0.5,
                          solver=ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000))
    data = Data(model)
    data.q[:], data.u[:] = q, u
    return model, data


def far_pairs_row(pair, steps, rounds) -> dict:
    """The per-step cost [µs] of the pair's scene alone, with FAR_PAIRS far-apart pairs of
    its kind, with their point masses but no contacts, and (a surface on the beam) alone
    on the finer mesh FINE (module docstring), medians of ``rounds`` batches of ``steps``
    Moreau steps (Δt = 1e-5 s) alternating; the far pairs' own share = (pairs − bodies) /
    alone."""
    from mbs.run import stages

    runs = {"alone": _planned_run(pair, 0, True), "far_pairs": _planned_run(pair, FAR_PAIRS, True),
            "far_bodies": _planned_run(pair, FAR_PAIRS, False)}
    if pair[1] in ON_BEAM:
        runs["fine"] = _planned_run(pair, 0, True, FINE)

    def batch(run):
        model, data = run
        return _batch_mean(lambda: stages.step(model, data, 1e-5), steps)

    for run in runs.values():       # warm-up: compiles, factors M̂, builds the contact set
        batch(run)
    times = {name: [] for name in runs}
    for _ in range(rounds):
        for name, run in runs.items():
            times[name].append(batch(run))
    med = {f"{name}_us": float(np.median(t)) for name, t in times.items()}
    return {"pair": "/".join(pair), **med, "share": (med["far_pairs_us"] - med["far_bodies_us"]) / med["alone_us"],
            "fine_ratio": med["fine_us"] / med["alone_us"] if "fine_us" in med else None,
            "searched": int(runs["far_pairs"][1].n_live)}


def _far_table(rows, settings) -> list:
    nodes = [beam_data(d).u0.shape[0] for d in (None, FINE)]
    lines = [f"µs per Moreau step (planned run), median of {settings['rounds']} batches of {settings['batch'] // 2} "
             f"steps, alternating: the scene alone, with {FAR_PAIRS} far-apart pairs of its kind "
             f"({FAR:g} m and more out, flying away), with their point masses but no contacts, and alone with "
             f"the beam meshed {' x '.join(map(str, FINE))} ({nodes[1]} nodes, against {nodes[0]})", "",
             "| pair kind | alone | far pairs | far bodies | the pairs' share | contacts searched | finer mesh | "
             "finer / alone |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        fine = "" if r["fine_ratio"] is None else f"{r['fine_us']:.1f} | {r['fine_ratio']:.2f}"
        lines.append(f"| {r['pair']} | {r['alone_us']:.1f} | {r['far_pairs_us']:.1f} | {r['far_bodies_us']:.1f} | "
                     f"{100 * r['share']:+.1f} % | {r['searched']} of {FAR_PAIRS + 1} | {fine or ' | '} |")
    return lines


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
    far = [far_pairs_row(pair, settings["batch"] // 2, settings["rounds"]) for pair in PAIR_KINEMATICS.names()]
    lines += [""] + _far_table(far, settings)
    steep = [f"{r['pair']} {100 * r['share']:+.0f} %" for r in far if r["share"] > FLAT_TOL]
    flat = (f"target (per-step cost flat within {100 * FLAT_TOL:.0f} % in {FAR_PAIRS} far-apart pairs, every "
            f"unilateral pair kind): {'met' if not steep else 'NOT met (' + ', '.join(steep) + ')'}")
    growing = [f"{r['pair']} {r['fine_ratio']:.2f}" for r in far
               if r["fine_ratio"] is not None and abs(r["fine_ratio"] - 1.0) > FLAT_TOL]
    mesh = (f"target (per-step cost flat within {100 * FLAT_TOL:.0f} % in node count, every pair kind on the "
            f"beam): {'met' if not growing else 'NOT met (' + ', '.join(growing) + ')'}")
    return {"benchmark": "pair_cost", "machine": machine(), "settings": settings, "rows": rows, "far_pairs": far,
            "table": "\n".join(lines), "verdicts": [verdict, flat, mesh]}


def main(argv=None):
    return bench_main(argv, "pair_cost", run, __doc__, f"{QUICK['rounds']} batches of {QUICK['batch']} calls")


if __name__ == "__main__":
    main()
