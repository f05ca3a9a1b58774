"""C²-continuous NURBS contours on bodies (thesis Sec. 3.2, 4.4).

Public API::

    from contours import (Contour2sNeutralFFR, Contour1sNeutralFFR, Contour1sEdgeFFR, FlexibleBand,
                          FlexibleCylinder, PointContour, SphereContour, PlaneContour)

* :mod:`contours.nurbs` — knot vectors, basis functions, interpolation factored once.
* :mod:`contours.neutral` — neutral contours by abstract factories: the FFR family
  (``Contour1sNeutralFFR``, ``Contour2sNeutralFFR``) and the rigid family.
* :mod:`contours.derived` — ``FlexibleBand`` and ``FlexibleCylinder`` on a 1s neutral contour.
* :mod:`contours.rigid` — point, sphere and plane on any frame.
* :mod:`contours.node_grid` — the node matrix O from a node group, node lines.
* :mod:`contours.registry` — the contour kinds by name (:data:`CONTOURS`).

Every contour: ``update(q, u, t)`` once per step, then ``evaluate(point, η, ξ, …)`` into
a :class:`ContourPoint` (position, tangents, frame, velocity, J_T, J_R),
``bounding_box(out)`` and ``to_trimesh()``.
"""

from ffrmbs.caches import configure_numba

configure_numba()      # numba's cache directory, before any kernel is defined (ffrmbs.caches)

from .base import Contour, ContourPoint
from .derived import FlexibleBand, FlexibleCylinder
from .neutral import (Contour1sEdgeFFR, Contour1sNeutralFFR, Contour1sNeutralFactory, Contour1sNeutralRigid, Contour2sNeutralFFR,
                      Contour2sNeutralFactory, Contour2sNeutralRigid)
from .node_grid import node_line, node_matrix
from .registry import CONTOURS
from .rigid import PlaneContour, PointContour, SphereContour

__all__ = ["CONTOURS", "Contour", "Contour1sEdgeFFR", "Contour1sNeutralFFR", "Contour1sNeutralFactory", "Contour1sNeutralRigid",
           "Contour2sNeutralFFR", "Contour2sNeutralFactory", "Contour2sNeutralRigid", "ContourPoint",
           "FlexibleBand", "FlexibleCylinder", "PlaneContour", "PointContour", "SphereContour", "node_line",
           "node_matrix"]
