"""The contour kinds by name (:data:`CONTOURS`), as the scene files and
:func:`contact.connect` name them. A new contour kind is its class plus one line here
(or ``CONTOURS.register(name, cls)`` in the user's code) and its pairs in
:data:`contact.PAIR_KINEMATICS`."""

from __future__ import annotations

from ffrmbs.registry import Registry

from .derived import FlexibleBand, FlexibleCylinder
from .neutral import Contour1sEdgeFFR, Contour1sNeutralFFR, Contour1sNeutralRigid, Contour2sNeutralFFR, Contour2sNeutralRigid
from .rigid import PlaneContour, PointContour, SphereContour

CONTOURS = Registry("contour kind")
CONTOURS.register("point", PointContour)                  # a point on a frame
CONTOURS.register("sphere", SphereContour)                # a sphere on a frame (radius [m])
CONTOURS.register("plane", PlaneContour)                  # a plane on a frame, normal along its z axis
CONTOURS.register("2s", Contour2sNeutralFFR)              # NURBS surface on an FFR body (thesis Sec. 4.4)
CONTOURS.register("1s", Contour1sNeutralFFR)              # NURBS curve on an FFR body (thesis Sec. 4.4)
CONTOURS.register("edge", Contour1sEdgeFFR)               # a sharp edge of an FFR body (a face's rim)
CONTOURS.register("band", FlexibleBand)                   # a band of width [m] on a 1s curve
CONTOURS.register("cylinder", FlexibleCylinder)           # a tube of radius [m] around a 1s curve
CONTOURS.register("2s-rigid", Contour2sNeutralRigid)      # NURBS surface on a rigid body
CONTOURS.register("1s-rigid", Contour1sNeutralRigid)      # NURBS curve on a rigid body
