"""Contact kinematics, hierarchical search, force laws and solvers (thesis Sec. 3.1, 3.3, 4.5).

Public API::

    from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact, ...

* :mod:`contact.kinematics` — gaps, frames, relative velocities and Jacobians (eq. 3.2–3.8).
* :mod:`contact.search` — the hierarchical contact search (Sec. 3.3, Alg. 4–6).
* :mod:`contact.laws` — set-valued and regularized force laws.
* :mod:`contact.solver` — the contact problem of a Moreau step (prox, semismooth Newton).
* :mod:`contact.contact` — a contact (kinematics + law) to add to a System, with its broad
  phase (the contours' bounding boxes); :func:`connect` picks the kinematics from the two
  contour kinds.
* :mod:`contact.registry` — the laws, pair kinematics and solvers by name.
"""

from ffrmbs.caches import configure_numba

configure_numba()      # numba's cache directory, before any kernel is defined (ffrmbs.caches)

from .connect import connect
from .contact import Contact, ContactElement, CurveConstraint
from .face import FaceContact
from .kinematics import (ContactKinematics, ContactKinematicsPointContour1s, ContactKinematicsPointContour2s,
                         ContactKinematicsPointPlane, ContactKinematicsPointSphere, ContactKinematicsSphereContour1s,
                         ContactKinematicsSphereEdge,
                         ContactKinematicsSphereContour2s, ContactKinematicsSpherePlane,
                         ContactKinematicsSphereSphere, PointOnCurveConstraint)
from .laws import (Bilateral, LinearRegularizedUnilateralConstraint, RegularizedCoulombFriction,
                   SpatialCoulombFriction, UnilateralCoulombContact, UnilateralNewtonImpact)
from .registry import BILATERAL_KINEMATICS, LAWS, PAIR_KINEMATICS, SOLVERS, make_law
from .search import Contact1sSearch, Contact2sSearch
from .solver import ContactSolution, ProxSolver

__all__ = ["BILATERAL_KINEMATICS", "Bilateral", "Contact", "Contact1sSearch", "Contact2sSearch", "ContactElement", "ContactKinematics",
           "ContactKinematicsPointContour1s", "ContactKinematicsPointContour2s", "ContactKinematicsPointPlane",
           "ContactKinematicsPointSphere",
           "ContactKinematicsSphereContour1s", "ContactKinematicsSphereContour2s", "ContactKinematicsSphereEdge", "ContactKinematicsSpherePlane",
           "ContactKinematicsSphereSphere", "ContactSolution", "CurveConstraint", "FaceContact", "LAWS",
           "LinearRegularizedUnilateralConstraint", "PAIR_KINEMATICS", "PointOnCurveConstraint", "ProxSolver",
           "RegularizedCoulombFriction", "SOLVERS", "SpatialCoulombFriction", "UnilateralCoulombContact",
           "UnilateralNewtonImpact", "connect", "make_law"]
