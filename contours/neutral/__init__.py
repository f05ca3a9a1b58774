"""Neutral contours: NURBS interpolation of a body's nodal fields by abstract factories
(thesis Sec. 3.2.2, 4.4.1). Abstract factories in :mod:`.factory`, products in
:mod:`.products`, the FFR family in :mod:`.ffr`, the rigid family in :mod:`.rigid`."""

from .factory import Contour1sNeutralFactory, Contour2sNeutralFactory, NeutralContour
from .ffr import Contour1sEdgeFFR, Contour1sNeutralFFR, Contour2sNeutralFFR
from .products import (NeutralNurbs, NeutralNurbsLocalPosition, NeutralNurbsModeShapes, NeutralNurbsPosition,
                       NeutralNurbsVelocity)
from .rigid import Contour1sNeutralRigid, Contour2sNeutralRigid

__all__ = ["Contour1sEdgeFFR", "Contour1sNeutralFFR", "Contour1sNeutralFactory", "Contour1sNeutralRigid", "Contour2sNeutralFFR",
           "Contour2sNeutralFactory", "Contour2sNeutralRigid", "NeutralContour", "NeutralNurbs",
           "NeutralNurbsLocalPosition", "NeutralNurbsModeShapes", "NeutralNurbsPosition", "NeutralNurbsVelocity"]
