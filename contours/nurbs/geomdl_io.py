"""Export of our B-spline curves and surfaces to geomdl (NURBS-Python), the test reference.

The knot vectors are passed as they are (``normalize_kv=False``): geomdl evaluates on
[knots[p], knots[-p-1]], which for our closed curves (wrapped control points, unclamped
periodic knots) is [0, 1] as in :mod:`contours.nurbs.knots`. Unit weights: plain
``geomdl.BSpline`` objects.
"""

from __future__ import annotations

import numpy as np
from geomdl import BSpline


def to_geomdl_curve(knots, degree, ctrl):
    """geomdl.BSpline.Curve of degree ``degree`` with ``knots`` (n_ctrl + p + 1,) and ``ctrl`` (n_ctrl, d)."""
    curve = BSpline.Curve(normalize_kv=False)
    curve.degree = int(degree)
    curve.ctrlpts = np.asarray(ctrl, dtype=float).tolist()
    curve.knotvector = np.asarray(knots, dtype=float).tolist()
    return curve


def to_geomdl_surface(knots_eta, p_eta, knots_xi, p_xi, ctrl):
    """geomdl.BSpline.Surface with u = η, v = ξ; ``ctrl`` (n_eta, n_xi, d).

    geomdl stores the control points flat with the v index running fastest, which is
    ``ctrl.reshape(n_eta * n_xi, d)``.
    """
    P = np.asarray(ctrl, dtype=float)
    surf = BSpline.Surface(normalize_kv=False)
    surf.degree_u = int(p_eta)
    surf.degree_v = int(p_xi)
    surf.set_ctrlpts(P.reshape(-1, P.shape[2]).tolist(), P.shape[0], P.shape[1])
    surf.knotvector_u = np.asarray(knots_eta, dtype=float).tolist()
    surf.knotvector_v = np.asarray(knots_xi, dtype=float).tolist()
    return surf
