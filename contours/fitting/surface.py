"""A least-squares B-spline surface on a node group of an FE body: patch, parameters,
control-point counts and the factored fit, in one call (:func:`surface_fit`)."""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from .bspline_fit import SMOOTHING, SurfaceFit
from .parameterization import parameterize, unwrap_seam
from .patch import SurfacePatch

#: default knot span, in mean node spacings of the patch (about one tet10 element edge)
SPAN_NODE_SPACINGS = 2.0


def default_control_points(patch: SurfacePatch, params, degree=(3, 3), closed=(False, False)) -> tuple:
    """(n_η, n_ξ) distinct control points: knot spans of :data:`SPAN_NODE_SPACINGS` node
    spacings along the patch's mean length in each parametric direction.

    The lengths come from the map's Jacobian on each linear triangle (x = x0 + J (η, ξ)):
    L_η = Σ_T area_T |J_η| / Σ_T area_T (the length of a line η ∈ [0, 1]), likewise L_ξ."""
    x = patch.points[patch.linear]
    t = np.asarray(params)[patch.linear].copy()
    if closed[0]:
        unwrap_seam(t)
    dx = x[:, 1:] - x[:, :1]                              # (T, 2, 3)
    dt = t[:, 1:] - t[:, :1]                              # (T, 2, 2)
    det = dt[:, 0, 0] * dt[:, 1, 1] - dt[:, 0, 1] * dt[:, 1, 0]
    ok = np.abs(det) > 1e-14
    inv = np.stack([np.stack([dt[:, 1, 1], -dt[:, 0, 1]], -1), np.stack([-dt[:, 1, 0], dt[:, 0, 0]], -1)], 1)
    J = np.einsum("tij,tjk->tik", inv[ok] / det[ok, None, None], dx[ok])       # rows: ∂x/∂η, ∂x/∂ξ
    area = 0.5 * np.linalg.norm(np.cross(dx[ok, 0], dx[ok, 1]), axis=1)
    lengths = (area[:, None] * np.linalg.norm(J, axis=2)).sum(axis=0) / area.sum()
    spacing = patch.edge_length * SPAN_NODE_SPACINGS
    counts = []
    for length, p, c in zip(lengths, degree, closed):
        spans = max(1, int(np.ceil(length / spacing)))
        counts.append(max(spans, p + 1) if c else spans + p)
    return tuple(counts)


def surface_fit(points, surface_triangles, group, control_points=None, degree=3, smoothing=SMOOTHING,
                name="patch"):
    """(fit, patch) of the node ``group`` of a body with undeformed positions ``points``
    (N, 3) [m] and ``surface_triangles``.

    - control_points : None (:func:`default_control_points`), an int or (n_η, n_ξ): the
      distinct control points per direction.
    - degree : int or (p_η, p_ξ) (3: C²).
    - smoothing : dimensionless thin-plate weight (:mod:`.bspline_fit`).
    """
    patch = SurfacePatch(points, surface_triangles, group, name)
    params, closed = parameterize(patch)
    degree = (degree, degree) if np.isscalar(degree) else tuple(degree)
    if control_points is None:
        control_points = default_control_points(patch, params, degree, closed)
    elif np.isscalar(control_points):
        control_points = (control_points, control_points)
    control_points = tuple(int(n) for n in control_points)
    if len(control_points) != 2:
        raise ModelError(f"{name}: control_points must be one count or a pair (eta, xi), got {control_points}")
    fit = SurfaceFit(params, control_points, degree, closed, smoothing)
    return fit, patch
