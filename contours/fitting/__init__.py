"""Contours fitted to any FE surface patch (unstructured tet4 or tet10 meshes).

* :mod:`.patch` — the surface triangles of a node group, their boundary loops.
* :mod:`.parameterization` — the patch's nodes on the unit square (mean-value map;
  periodic for a closed band).
* :mod:`.bspline_fit` — least-squares B-spline surfaces and curves, factored once: the
  fitting matrix F with control points = F · nodal values.
* :mod:`.report` — the fit's distance, normal and mode-shape errors against the FE surface.
* :mod:`.trim` — a face with holes: the holes' polygons in parameter space, the material test.

:func:`surface_fit` chains the first three for a body's node group; the 2s FFR contour
uses it when the group is not a structured grid (:class:`contours.Contour2sNeutralFFR`).
"""

from .bspline_fit import SMOOTHING, CurveFit, FitDirection, SurfaceFit
from .parameterization import parameterize
from .patch import SurfacePatch
from .report import BOUNDS, FitReport, fit_report
from .surface import default_control_points, surface_fit
from .trim import Trim

__all__ = ["BOUNDS", "FitReport", "fit_report", "SMOOTHING", "CurveFit", "FitDirection", "SurfacePatch", "SurfaceFit", "Trim", "default_control_points",
           "parameterize", "surface_fit"]
