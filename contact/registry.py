"""The contact kinds by name: force laws (:data:`LAWS`), the kinematics of a pair of
contour kinds (:data:`PAIR_KINEMATICS` for unilateral contacts, :data:`BILATERAL_KINEMATICS`
for a point kept on a curve) and the contact solvers (:data:`SOLVERS`).

The contour kinds are those of :data:`contours.CONTOURS`; a pair is (kind of contour 1,
the point side; kind of contour 2, the surface side), thesis Sec. 3.1. A new force law is
its class plus one line ``LAWS.register(name, cls)``: a single-valued law (``kind =
"single-valued"``, ``force(g_N, gd_N)`` [N] and ``derivatives(g_N, gd_N)``, see
:mod:`contact.laws`) needs nothing else; a set-valued one needs its projection in
:mod:`contact.solver`. A scene file takes a law's parameters from its dataclass fields
of type float, with their units from the class's ``units`` (``{field: unit}``).
"""

from __future__ import annotations

from functools import partial

from ffrmbs.errors import ModelError
from ffrmbs.registry import Registry

from .kinematics import (ContactKinematicsPointContour1s, ContactKinematicsPointContour2s,
                         ContactKinematicsPointPlane, ContactKinematicsPointSphere, ContactKinematicsSphereContour1s,
                         ContactKinematicsSphereEdge,
                         ContactKinematicsSphereContour2s, ContactKinematicsSpherePlane,
                         ContactKinematicsSphereSphere, PointOnCurveConstraint)
from .laws import Bilateral, LinearRegularizedUnilateralConstraint, UnilateralCoulombContact, UnilateralNewtonImpact
from .solver import METHODS, ProxSolver

LAWS = Registry("contact law")
LAWS.register("impact", UnilateralNewtonImpact)                     # set-valued, Newton's e
LAWS.register("coulomb", UnilateralCoulombContact)                  # set-valued, e, mu, e_T
LAWS.register("penalty", LinearRegularizedUnilateralConstraint)     # single-valued, k [N/m], d [N s/m]
LAWS.register("bilateral", Bilateral)                               # a point kept on a curve

PAIR_KINEMATICS = Registry("contour pair")
for _surface in ("2s", "band", "cylinder", "2s-rigid"):
    PAIR_KINEMATICS.register(("point", _surface), ContactKinematicsPointContour2s)
for _surface in ("2s", "band", "cylinder", "2s-rigid"):
    PAIR_KINEMATICS.register(("sphere", _surface), ContactKinematicsSphereContour2s)
for _curve in ("1s", "1s-rigid"):
    PAIR_KINEMATICS.register(("point", _curve), ContactKinematicsPointContour1s)
    PAIR_KINEMATICS.register(("sphere", _curve), ContactKinematicsSphereContour1s)
PAIR_KINEMATICS.register(("sphere", "edge"), ContactKinematicsSphereEdge)   # a ball on a sharp edge (a rim)
PAIR_KINEMATICS.register(("point", "plane"), ContactKinematicsPointPlane)
PAIR_KINEMATICS.register(("sphere", "plane"), ContactKinematicsSpherePlane)
PAIR_KINEMATICS.register(("point", "sphere"), ContactKinematicsPointSphere)
PAIR_KINEMATICS.register(("sphere", "sphere"), ContactKinematicsSphereSphere)

BILATERAL_KINEMATICS = Registry("bilateral contour pair")
BILATERAL_KINEMATICS.register(("point", "1s"), PointOnCurveConstraint)
BILATERAL_KINEMATICS.register(("point", "1s-rigid"), PointOnCurveConstraint)

SOLVERS = Registry("contact solver")
for _method in METHODS:
    SOLVERS.register(_method, partial(ProxSolver, _method))         # SOLVERS[name](tol=..., ...) -> ProxSolver


def make_law(name, **parameters):
    """The law registered as ``name`` with ``parameters`` (its defaults for the others);
    a parameter missing or unknown is a ModelError naming it."""
    cls = LAWS[name]
    try:
        return cls(**parameters)
    except TypeError as exc:
        raise ModelError(f"contact law {name!r} ({cls.__name__}): {exc}") from None
