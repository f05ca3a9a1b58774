"""One process's share of :mod:`validation.bench.step_cost`: the per-step cost of the
product in one checkout (this one, an older commit's exported tree, or an installed
copy's directory), printed as one JSON line.

The checkout alone supplies the product: every top-level package of the project
(:data:`PROJECT_PACKAGES`) is imported from it and from nowhere else, whatever else is on
``sys.path`` — an installed ``ffrmbs`` (``pip install .`` or editable) would otherwise lend
an older checkout the packages it lacks (``ffrmbs_app`` did not exist before the
Model/Data split), and the mix fails. A package the checkout lacks cannot be imported.
Third-party packages (numpy, numba, ...) come from the environment as usual. The JSON
names the directory each project package was imported from (``"origins"``).

It uses only the public API that every version since the first benchmark has (the
built-in point-mass-on-beam scene, ``System.simulate``, the free-flight case's scene),
so that an older checkout runs the very same work. Every case runs once untimed (numba
compiles or loads its cache), then ``repeats`` timed runs whose wall times are returned.

Run by :mod:`validation.bench.step_cost`::

    python3 validation/bench/step_worker.py CHECKOUT '{"repeats": 3, ...}'
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import json
import os
import sys
import time

import numpy as np

PROJECT_PACKAGES = ("ffrmbs", "ffrmbs_app", "preprocess", "mbs", "contours", "contact", "validation")


class CheckoutOnly(importlib.abc.MetaPathFinder):
    """A meta path finder that finds the top-level project packages in ``checkout`` only
    (their submodules follow from the package's ``__path__``); a project package the
    checkout lacks raises ModuleNotFoundError. Other names pass to the next finder."""

    def __init__(self, checkout):
        self.checkout = os.fspath(checkout)

    def find_spec(self, name, path=None, target=None):
        if path is not None or name not in PROJECT_PACKAGES:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, [self.checkout])
        if spec is None:
            raise ModuleNotFoundError(f"No module named {name!r} in {self.checkout}", name=name)
        return spec


def confine_to(checkout) -> None:
    """Import the project's packages from ``checkout`` only, from now on in this process."""
    sys.meta_path.insert(0, CheckoutOnly(checkout))


def origins() -> dict:
    """{project package: the directory it was imported from} for those imported so far."""
    return {name: os.path.dirname(os.path.dirname(sys.modules[name].__file__))
            for name in PROJECT_PACKAGES if getattr(sys.modules.get(name), "__file__", None)}


def point_mass_beam():
    """The built-in scene module (its home moved from ``validation.scenes`` to
    ``ffrmbs_app.scenes``)."""
    try:
        from ffrmbs_app.scenes import point_mass_beam as pmb
    except ImportError:
        from validation.scenes import point_mass_beam as pmb
    return pmb


def default_scene(t_end, far_pairs=0, contacts=True):
    """(system, outputs) of setup A, 20 modes, with ``far_pairs`` extra point masses
    flying away from the beam 1 m apart, each (with ``contacts``) in a unilateral
    contact with the beam's surface that never closes (their contours never come within
    the broad phase)."""
    from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact
    from contours import PointContour
    from mbs import PointMass

    pmb = point_mass_beam()
    scene = pmb.build("A", modes=20)
    system = scene.system
    surface = scene.contact.kinematics.contour2
    for k in range(far_pairs):
        mass = system.add(PointMass(0.1, position=(0.0, 2.0 + k, 0.0), velocity=(0.0, 0.1, 0.0), name=f"far{k}"))
        if contacts:
            system.add(Contact(ContactKinematicsPointContour2s(PointContour(mass.point), surface),
                               UnilateralNewtonImpact(0.0), name=f"far contact {k}"))
    return system, scene.outputs()


def run_default(t_end, dt, far_pairs=0, contacts=True):
    """(wall s, steps, v_y(T)) of the default scene by Moreau, 101 output samples."""
    system, outputs = default_scene(t_end, far_pairs, contacts)
    start = time.perf_counter()
    res = system.simulate(t_end, dt, integrator="moreau", theta=0.5, t_out=np.linspace(0.0, t_end, 101),
                          outputs=outputs)
    wall = time.perf_counter() - start
    return wall, int(res.stats["steps"]), float(res["vy"][-1])


_FREE = {}


def run_free(integrator, dt, modes):
    """(wall s, steps, |r_A(T)|) of the report's free-flying beam, full FFR (plan off)."""
    from validation.cases import ffr_free_flight as ff

    if modes not in _FREE:
        from preprocess import box, build_body
        from validation.cases.cantilever import MATERIAL, REPORT_MESH_SIZE

        mesh = box(1.0, 1.0, 5.0, REPORT_MESH_SIZE, order=2)
        _FREE[modes] = (build_body(mesh, MATERIAL, modes, clamp=None), ff.face_weights(mesh), ff.node_a(mesh))
    data, weights, probe = _FREE[modes]
    options = {"rho_inf": 0.9} if integrator == "generalized-alpha" else {"theta": 0.5}
    start = time.perf_counter()
    _, r, _, _ = ff.simulate(data, weights, modes, dt, integrator, probe, plan=False, **options)
    wall = time.perf_counter() - start
    return wall, int(round(ff.T_END / dt)), float(np.linalg.norm(r[-1]))


def measure(spec: dict) -> dict:
    """{case name: {"walls": [s...], "steps": n, "check": a result figure}} for the cases of ``spec``."""
    cases = {}
    for case in spec["cases"]:
        if case["kind"] == "default":
            call = lambda c=case: run_default(c["t_end"], c["dt"], c.get("far_pairs", 0), c.get("contacts", True))  # noqa: E731
        else:
            call = lambda c=case: run_free(c["integrator"], c["dt"], c["modes"])  # noqa: E731
        call()                                     # compile or load the numba cache
        walls = []
        for _ in range(spec["repeats"]):
            wall, steps, check = call()
            walls.append(wall)
        cases[case["name"]] = {"walls": walls, "steps": steps, "check": check}
    return cases


if __name__ == "__main__":
    confine_to(sys.argv[1])
    point_mass_beam()                              # the product's packages, imported before any timing
    measured = measure(json.loads(sys.argv[2]))
    print(json.dumps({"cases": measured, "origins": origins()}))
