"""How far a fitted contour lies from the FE surface it was fitted to.

For the undeformed surface and for each mode shape the report compares the fitted
B-spline with the FE field at the patch's nodes and at its surface triangles'
mid-points (barycentric (1/3, 1/3, 1/3); a 6-node triangle's quadratic shape functions
there are −1/9 at the corners and 4/9 at the mid-edge nodes), each at the point's own
parameters (the nodes' from the map, a mid-point's as the same shape-function average).
Distances are parametric: |S(η_i, ξ_i) − x_i|, an upper bound of the distance to the
contour. The normal error is the angle between the contour's normal S_η × S_ξ and the FE
triangle's normal at the mid-points. Mode-shape errors are relative to the mode's largest
nodal displacement.

A fit is flagged over :data:`BOUNDS`: node distance over 1 % of the mean node spacing,
normal error over 2°, a mode shape's node error over 2 %.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .parameterization import unwrap_seam

#: warning bounds: geometry node distance / node spacing, normal angle [deg], mode node error
BOUNDS = {"distance": 0.01, "normal_deg": 2.0, "mode": 0.02}

_MID_CORNER, _MID_EDGE = -1.0 / 9.0, 4.0 / 9.0


@dataclass
class FitReport:
    """Errors of one fitted patch (lengths in m, angles in degrees).

    - rows : list of dicts, one for the geometry and one per mode: field, node_max,
      node_rms, mid_max, mid_rms (m for the geometry, relative for modes).
    - ctrl : (n_η n_ξ, 3) [m] the distinct control points of the undeformed surface.
    - node_deviation (k,), mid_deviation (T,) [m] : |S − x| at each node and mid-point.
    - normal_max, normal_rms : the normal's angle error [deg].
    - spacing : mean node spacing of the patch [m].
    - warnings : lines saying which bound is exceeded and how to lower the error.
    """

    name: str
    k: int
    control_points: tuple
    spacing: float
    normal_max: float
    normal_rms: float
    rows: list = field(default_factory=list)
    ctrl: np.ndarray | None = None
    node_deviation: np.ndarray | None = None
    mid_deviation: np.ndarray | None = None
    warnings: list = field(default_factory=list)

    def text(self) -> str:
        """The report as a table (plain text)."""
        lines = [f"fit of {self.name}: {self.k} nodes, {self.control_points[0]} x {self.control_points[1]} "
                 f"control points, node spacing {self.spacing:.4g} m",
                 f"{'field':<10} {'node max':>11} {'node rms':>11} {'mid max':>11} {'mid rms':>11}"]
        for r in self.rows:
            unit = " m" if r["field"] == "geometry" else ""
            lines.append(f"{r['field']:<10} {r['node_max']:>11.3g} {r['node_rms']:>11.3g} {r['mid_max']:>11.3g} "
                         f"{r['mid_rms']:>11.3g}{unit}")
        lines.append(f"normal angle error: max {self.normal_max:.3g} deg, rms {self.normal_rms:.3g} deg")
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def midpoints(patch, values, params, closed=False):
    """(values, params) at the mid-points of the patch's surface triangles (module docstring);
    on a closed band (``closed``) η is unwrapped across the seam first."""
    tri = patch.triangles
    t = np.asarray(params)[tri].copy()
    if tri.shape[1] == 3:
        w = np.full(3, 1.0 / 3.0)
    else:
        w = np.array([_MID_CORNER] * 3 + [_MID_EDGE] * 3)
        # the nodes' parameters are piecewise linear on the four sub-triangles: the
        # mid-point is the centroid of the middle one
        t = t[:, 3:]
    if closed:
        unwrap_seam(t)
    mid_params = t.mean(axis=1)
    if closed:
        mid_params[:, 0] %= 1.0
    mid_values = np.einsum("j,tj...->t...", w, np.asarray(values)[tri])
    return mid_values, mid_params


def fe_normals(patch) -> np.ndarray:
    """(T, 3) unit normals of the FE surface triangles at their mid-points."""
    x = patch.points[patch.triangles]
    if x.shape[1] == 3:
        n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    else:   # the 6-node shape functions' derivatives at the mid-point along L1 and L2 (L0 = 1 − L1 − L2)
        g1 = np.array([-1 / 3, 1 / 3, 0.0, 0.0, 4 / 3, -4 / 3])     # ∂N/∂L1 (− ∂/∂L0)
        g2 = np.array([-1 / 3, 0.0, 1 / 3, -4 / 3, 4 / 3, 0.0])     # ∂N/∂L2 (− ∂/∂L0)
        n = np.cross(np.einsum("j,tjc->tc", g1, x), np.einsum("j,tjc->tc", g2, x))
    return n / np.linalg.norm(n, axis=1)[:, None]


def fit_report(fit, patch, phi=None, name="patch", mode_numbers=None) -> FitReport:
    """The :class:`FitReport` of ``fit`` (a :class:`~.bspline_fit.SurfaceFit`) on ``patch``.

    phi : (k, 3, n_f) the patch nodes' mode shapes, or None.
    mode_numbers : labels of the modes (default 1..n_f).
    """
    params = fit.params
    B = fit.collocation(params)
    mid_x, mid_t = midpoints(patch, patch.points, params, fit.eta.closed)
    Bm = fit.collocation(mid_t)
    P = fit.distinct_control_points(patch.points)

    def deviations(P, nodal, mid):
        return np.linalg.norm(B @ P - nodal, axis=-1), np.linalg.norm(Bm @ P - mid, axis=-1)

    def errors(dn, dm):
        return dn.max(), np.sqrt((dn ** 2).mean()), dm.max(), np.sqrt((dm ** 2).mean())

    spacing = patch.edge_length
    node_dev, mid_dev = deviations(P, patch.points, mid_x)
    rows = [dict(zip(("field", "node_max", "node_rms", "mid_max", "mid_rms"),
                     ("geometry",) + errors(node_dev, mid_dev)))]
    n = np.cross(fit.collocation(mid_t, 1, 0) @ P, fit.collocation(mid_t, 0, 1) @ P)
    n /= np.linalg.norm(n, axis=1)[:, None]
    angle = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", n, fe_normals(patch))), 0.0, 1.0)))
    report = FitReport(name, patch.k, (fit.eta.n_unique, fit.xi.n_unique), spacing, float(angle.max()),
                       float(np.sqrt((angle ** 2).mean())), rows, P, node_dev, mid_dev)
    worst_mode = (0.0, None)
    if phi is not None and phi.shape[-1]:
        labels = mode_numbers if mode_numbers is not None else range(1, phi.shape[-1] + 1)
        Pphi = fit.distinct_control_points(phi)
        mid_phi, _ = midpoints(patch, phi, params, fit.eta.closed)
        for j, label in enumerate(labels):
            scale = np.linalg.norm(phi[:, :, j], axis=1).max()
            e = np.array(errors(*deviations(Pphi[:, :, j], phi[:, :, j], mid_phi[:, :, j]))) / (scale or 1.0)
            rows.append(dict(zip(("field", "node_max", "node_rms", "mid_max", "mid_rms"), (f"mode {label}",) +
                                 tuple(float(v) for v in e))))
            worst_mode = max(worst_mode, (float(e[0]), label), key=lambda w: w[0])
    hint = ("give more control points (control_points in a scene, --control-points for ffrmbs contour) or "
            "mesh finer (a smaller mesh size)")
    if rows[0]["node_max"] > BOUNDS["distance"] * spacing:
        report.warnings.append(f"the contour lies up to {rows[0]['node_max']:.3g} m from the nodes, over "
                               f"{BOUNDS['distance']:.0%} of the node spacing {spacing:.3g} m: {hint}")
    if report.normal_max > BOUNDS["normal_deg"]:
        report.warnings.append(f"the normal is off by up to {report.normal_max:.3g} deg (bound "
                               f"{BOUNDS['normal_deg']:g} deg): {hint}")
    if worst_mode[0] > BOUNDS["mode"]:
        report.warnings.append(f"mode {worst_mode[1]} is fitted to within {worst_mode[0]:.2%} of its largest "
                               f"nodal value (bound {BOUNDS['mode']:.0%}): {hint}")
    return report
