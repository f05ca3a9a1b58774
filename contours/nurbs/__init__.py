"""NURBS core: parameters and knot vectors, global interpolation of curves and surfaces,
and numba evaluation kernels (thesis Sec. 3.2.1, eq. 3.9–3.23; The NURBS Book ch. 2, 3, 9).

The contours interpolate with unit weights: a NURBS with all w_i = 1 (eq. 3.15–3.17) is
a B-spline, R_{i,p} = N_{i,p} (eq. 3.10). Open curves use clamped knot vectors on [0, 1],
closed curves periodic knot vectors with wrapped control points, also on [0, 1].
"""

from ._kernels import curve_derivs, ders_basis, find_span, surface_derivs, wrap_parameter
from .interpolation import Interpolation1D, SurfaceInterpolation
from .knots import averaged_knots, parameters, periodic_knots, surface_parameters

__all__ = [
    "Interpolation1D",
    "SurfaceInterpolation",
    "averaged_knots",
    "curve_derivs",
    "ders_basis",
    "find_span",
    "parameters",
    "periodic_knots",
    "surface_derivs",
    "surface_parameters",
    "wrap_parameter",
]
