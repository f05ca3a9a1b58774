"""2s contours fitted to unstructured FE face patches, measured against the exact surfaces.

Setup (issue 20, "Geometry"): gmsh default (unstructured, no transfinite) tetrahedral
meshes of three solids from :mod:`preprocess.geometry`, steel (ρ = 7800 kg/m³,
E = 210 GPa, ν = 0.3), :data:`N_MODES` clamped modes, body frame fixed in space. On
one face group of each a :class:`contours.Contour2sNeutralFFR` is fitted by least
squares (:mod:`contours.fitting`: mean-value map onto [0, 1]², a C² bicubic B-spline
with knot spans of about two node spacings, thin-plate smoothing 1e-6):

* ``plate``: the top face z = lz of the box [0, lx] x [0, ly] x [0, lz] (group ``z1``,
  clamped at ``x0``): a disk patch, the exact surface is the plane z = lz;
* ``cylinder``: the lateral surface x² + y² = R², 0 <= z <= L (group ``lateral``,
  clamped at ``end0``): a closed band, fitted periodically in η;
* ``cap``: the curved surface |x| = R of the spherical cap z >= R − H (group ``cap``,
  clamped at ``base``): a disk patch whose boundary circle is mapped onto the square by
  arc length (four corners a quarter circle apart).

Tet10 meshes have their mid-edge nodes on the CAD surface (gmsh second order), tet4 meshes
only their vertices. Swept: mesh size h (quick: 0.04, 0.02 m; full: 0.04, 0.02, 0.01 m)
and element order (quick: tet10; full: tet4 and tet10).

Measured against the exact surface, at the parameters of a :data:`GRID` x :data:`GRID`
grid on [0, 1]² and at every patch node's own parameters, with the contour's compiled
evaluation (``contour.evaluate``):

* distance to the exact surface d = |z − lz| (plane), |ρ − R| (cylinder, ρ = sqrt(x² + y²)),
  ||x| − R| (sphere centred at the origin) [m]: the row's error is max d / size, size =
  lx (plate) or R (cylinder, cap); ``dist_rms_rel`` the RMS over the same points;
* normal angle error [deg]: the angle between the contour's normal (eq. 3.27) and the
  exact normal (e_z; (x, y, 0)/ρ; x/|x|), sign ignored; ``normal_inner_max_deg`` the max
  over the points at least :data:`CORNER_CLEARANCE` (in parameters) from the square's
  corners. A disk patch's map sends four boundary nodes to the corners; where the
  boundary is smooth there (the cap's circle) the boundary turns by 0° in space but 90° in
  parameters, so S_η and S_ξ are parallel at the corner and the normal is undefined: the
  normal error near the four corners is large by construction, not by fit;
* ``boundary_max_rel``: max distance of the contour's boundary curves (the square's four
  sides of a disk patch, ξ = 0 and ξ = 1 of the band; :data:`BOUNDARY_POINTS` points each)
  from the exact boundary of the face (the rectangle's edge lines; the rims ρ = R,
  z ∈ {0, L}; the base circle), / size: how far the contour's edge strays from the face's
  edge (on the plane the only geometric error there is).

From the fit report (:func:`contours.fitting.fit_report`, FE-relative): ``fe_node_max_m``,
``fe_mid_max_m`` the distance to the FE surface at the nodes and at the surface triangles'
mid-points [m], ``fe_normal_max_deg`` the normal's angle to the FE triangles'; and
``mode_node_max`` the worst mode's max nodal fit error relative to its largest nodal
value; ``patch_nodes`` and ``spacing_m`` the patch's node count and mean node spacing [m]
(the orders of convergence in the notes are taken against it). CPU time: the contour's construction (patch, map, factored fit, F ū0 and F Φ),
numba compilation excluded, after one warm-up construction.
"""

from __future__ import annotations

import math

import numpy as np

from contours import Contour2sNeutralFFR
from contours.base import ContourPoint
from contours.fitting import fit_report
from mbs import FlexibleBodyFFR, PrescribedFrameMotion
from preprocess import Material, build_body
from preprocess.geometry import box, cylinder, spherical_cap
from validation import CaseResult, make_row, timed

NAME = "contour_fit_geometry"
DESCRIPTION = ("2s contours fitted to unstructured tet4/tet10 face patches (plate, closed cylinder band, "
               "spherical cap): distance and normal error vs the exact surfaces over mesh size")

MATERIAL = Material(7800.0, 2.1e11, 0.3)      # steel, SI
N_MODES = 4
PLATE = (0.2, 0.1, 0.02)                      # lx, ly, lz [m]
CYLINDER = (0.05, 0.05)                        # R, L [m]
CAP = (0.1, 0.04)                             # R, H [m]
SIZES = {True: (0.02, 0.01), False: (0.02, 0.014, 0.01)}     # mesh sizes h [m]
ORDERS = {True: (2,), False: (1, 2)}
GRID = 50
BOUNDARY_POINTS = 200
CORNER_CLEARANCE = 0.05                       # parameter distance from a square corner
ERROR_KIND = "max distance to exact surface / size"


class ExactSurface:
    """One test surface: its mesh, face group and clamp, and its exact geometry.

    size [m] scales the errors; ``distance(x)``, ``normal(x)`` and ``boundary_distance(x)``
    take points (m, 3) [m] and return (m,) [m], (m, 3) unit normals, (m,) [m]."""

    def __init__(self, name, mesher, group, clamp, size, reference, distance, normal, boundary_distance):
        self.name, self.mesher, self.group, self.clamp, self.size = name, mesher, group, clamp, size
        self.reference = reference
        self.distance, self.normal, self.boundary_distance = distance, normal, boundary_distance


def _plate():
    lx, ly, lz = PLATE

    def boundary(x):
        inplane = np.min(np.abs(np.stack([x[:, 0], x[:, 0] - lx, x[:, 1], x[:, 1] - ly])), axis=0)
        return np.hypot(inplane, x[:, 2] - lz)

    return ExactSurface("plate", lambda h, order: box(lx, ly, lz, h, order=order), "z1", "x0", lx,
                        f"plane z = lz of the {lx} x {ly} x {lz} m box, size lx = {lx} m",
                        lambda x: np.abs(x[:, 2] - lz),
                        lambda x: np.tile([0.0, 0.0, 1.0], (len(x), 1)), boundary)


def _cylinder():
    R, L = CYLINDER

    def normal(x):
        n = x.copy()
        n[:, 2] = 0.0
        return n / np.linalg.norm(n, axis=1)[:, None]

    def boundary(x):
        rho = np.hypot(x[:, 0], x[:, 1])
        return np.hypot(rho - R, np.minimum(np.abs(x[:, 2]), np.abs(x[:, 2] - L)))

    return ExactSurface("cylinder", lambda h, order: cylinder(R, L, h, order=order), "lateral", "end0", R,
                        f"cylinder x² + y² = R², R = {R} m, L = {L} m, size R",
                        lambda x: np.abs(np.hypot(x[:, 0], x[:, 1]) - R), normal, boundary)


def _cap():
    R, H = CAP
    z_base = R - H
    rho_base = math.sqrt(R ** 2 - z_base ** 2)

    def boundary(x):
        return np.hypot(np.hypot(x[:, 0], x[:, 1]) - rho_base, x[:, 2] - z_base)

    return ExactSurface("cap", lambda h, order: spherical_cap(R, H, h, order=order), "cap", "base", R,
                        f"sphere |x| = R, R = {R} m, cap height H = {H} m, size R",
                        lambda x: np.abs(np.linalg.norm(x, axis=1) - R),
                        lambda x: x / np.linalg.norm(x, axis=1)[:, None], boundary)


SURFACES = (_plate(), _cylinder(), _cap())


def fitted_contour(surface, h, order):
    """(body, contour, CPU seconds of the contour's construction) of ``surface`` meshed at
    size ``h`` [m] with tetrahedra of ``order``; the body frame fixed at the origin."""
    data = build_body(surface.mesher(h, order), MATERIAL, N_MODES, clamp=surface.clamp)
    body = FlexibleBodyFFR(data, N_MODES, frame=PrescribedFrameMotion.fixed())
    contour, cpu = timed(Contour2sNeutralFFR, body, surface.group, name=surface.name)
    return body, contour, cpu


def evaluate_at(contour, params):
    """(positions (m, 3) [m], unit normals (m, 3)) of ``contour`` at ``params`` (m, 2)."""
    point = ContourPoint(contour.body.nu)
    x, n = np.empty((len(params), 3)), np.empty((len(params), 3))
    for i, (eta, xi) in enumerate(params):
        contour.evaluate(point, eta, xi)
        x[i], n[i] = point.r, point.frame[:, 2]
    return x, n


def boundary_params(closed_eta):
    """(m, 2) parameters on the patch's boundary: the square's four sides (a disk), or
    ξ = 0 and ξ = 1 (a band, periodic in η)."""
    t = np.linspace(0.0, 1.0, BOUNDARY_POINTS)
    zero, one = np.zeros_like(t), np.ones_like(t)
    sides = [(t, zero), (t, one)] + ([] if closed_eta else [(zero, t), (one, t)])
    return np.concatenate([np.column_stack(s) for s in sides])


def measure(surface, body, contour):
    """The figures of one fitted contour (module docstring) as a dict."""
    g = np.linspace(0.0, 1.0, GRID)
    params = np.concatenate([np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2), contour.fit.params])
    x, n = evaluate_at(contour, params)
    d = surface.distance(x)
    angle = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", n, surface.normal(x))), 0.0, 1.0)))
    inner = np.ones(len(params), dtype=bool)
    if not contour.fit.eta.closed:
        corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
        inner = np.linalg.norm(params[:, None] - corners[None], axis=2).min(axis=1) >= CORNER_CLEARANCE
    xb, _ = evaluate_at(contour, boundary_params(contour.fit.eta.closed))
    report = fit_report(contour.fit, contour.patch, body.phi_nodes[contour.patch.nodes], surface.name)
    return {"dist_max_rel": float(d.max() / surface.size),
            "dist_rms_rel": float(np.sqrt((d ** 2).mean()) / surface.size),
            "normal_max_deg": float(angle.max()), "normal_rms_deg": float(np.sqrt((angle ** 2).mean())),
            "normal_inner_max_deg": float(angle[inner].max()),
            "boundary_max_rel": float(surface.boundary_distance(xb).max() / surface.size),
            "fe_node_max_m": report.rows[0]["node_max"], "fe_mid_max_m": report.rows[0]["mid_max"],
            "fe_normal_max_deg": report.normal_max,
            "mode_node_max": max(r["node_max"] for r in report.rows[1:]),
            "patch_nodes": contour.patch.k, "spacing_m": contour.patch.edge_length,
            "control_points": f"{contour.fit.eta.n_unique}x{contour.fit.xi.n_unique}"}


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("surface", "order"))
    fitted_contour(SURFACES[0], SIZES[quick][0], ORDERS[quick][0])       # warm-up: load compiled kernels
    figures = {}
    for surface in SURFACES:
        for order in ORDERS[quick]:
            for h in SIZES[quick]:
                body, contour, cpu = fitted_contour(surface, h, order)
                m = measure(surface, body, contour)
                figures[surface.name, order, h] = m
                result.rows.append(make_row(NAME, {"surface": surface.name, "mesh_size": h, "order": order}, cpu,
                                            m["dist_max_rel"], ERROR_KIND, surface.reference,
                                            **{k: v for k, v in m.items() if k != "dist_max_rel"}))
    result.notes += [_setup_note(quick), _table(figures, quick), _order_note(figures, quick)]
    return result


def _setup_note(quick):
    lx, ly, lz = PLATE
    return (f"Unstructured gmsh meshes (no transfinite): plate {lx} x {ly} x {lz} m (face z1), cylinder "
            f"R = {CYLINDER[0]} m, L = {CYLINDER[1]} m (lateral band, periodic fit), spherical cap R = {CAP[0]} m, "
            f"H = {CAP[1]} m (curved face); steel, {N_MODES} clamped modes. Distances and normal errors at a "
            f"{GRID} x {GRID} parameter grid plus every patch node's parameters, against the exact surface; "
            f"lengths relative to the size (plate: lx, cylinder and cap: R). On the plane the fit reproduces "
            f"the whole face to rounding: mean-value coordinates reproduce linear functions (Floater 2003), so "
            f"with the rectangle's sides mapped by arc length the map is affine, x(η, ξ) is bilinear and lies in "
            f"the spline space; its geometry errors are at rounding level for every mesh and only the mode-shape "
            f"error converges. Near the four corners of a disk patch whose boundary is smooth (the cap) the normal "
            f"is undefined (the map's corners), hence the column 'normal max off corners' (parameter distance "
            f">= {CORNER_CLEARANCE} from a corner).")


def _table(figures, quick):
    lines = ["| surface | order | h [m] | patch nodes | node spacing [mm] | control points | max dist / size | rms dist / size | "
             "normal max [deg] | normal max off corners [deg] | normal rms [deg] | boundary max / size | FE node max [m] | FE mid max [m] | "
             "FE normal max [deg] | mode node max (rel.) |", "|" + "---|" * 16]
    for (name, order, h), m in figures.items():
        lines.append(f"| {name} | {'tet10' if order == 2 else 'tet4'} | {h:g} | {m['patch_nodes']} | "
                     f"{1e3 * m['spacing_m']:.2f} | {m['control_points']} | {m['dist_max_rel']:.2e} | {m['dist_rms_rel']:.2e} | "
                     f"{m['normal_max_deg']:.3g} | {m['normal_inner_max_deg']:.3g} | {m['normal_rms_deg']:.3g} | {m['boundary_max_rel']:.2e} | "
                     f"{m['fe_node_max_m']:.2e} | {m['fe_mid_max_m']:.2e} | {m['fe_normal_max_deg']:.3g} | "
                     f"{m['mode_node_max']:.2e} |")
    return "\n".join(lines)


def _order_note(figures, quick):
    """Observed orders p = ln(e₁/e₂) / ln(s₁/s₂) between consecutive mesh sizes, s the
    patch's mean node spacing (gmsh's own size limits can make two nominal sizes h mesh
    alike)."""
    lines = ["Observed convergence orders p = ln(e₁/e₂) / ln(s₁/s₂) between consecutive mesh sizes, s the patch's "
             "mean node spacing (gmsh's curvature and default size limits can make two nominal sizes h give nearly "
             "the same mesh, e.g. the cylinder at 0.02 and 0.014 m) "
             "(max distance, max normal error off the corners, boundary, mode-shape error; the plane's geometry "
             "errors at rounding level are left out):", ""]
    keys = ("dist_max_rel", "normal_inner_max_deg", "boundary_max_rel", "mode_node_max")
    sizes = SIZES[quick]
    for surface in SURFACES:
        for order in ORDERS[quick]:
            parts = []
            for h1, h2 in zip(sizes[:-1], sizes[1:]):
                a, b = figures[surface.name, order, h1], figures[surface.name, order, h2]
                orders = []
                for key in keys:
                    if surface.name == "plate" and key != "mode_node_max":
                        orders.append("—")
                    else:
                        orders.append(f"{math.log(a[key] / b[key]) / math.log(a['spacing_m'] / b['spacing_m']):.2f}")
                parts.append(f"h {h1:g}→{h2:g} (s {1e3 * a['spacing_m']:.2f}→{1e3 * b['spacing_m']:.2f} mm): "
                             + " / ".join(orders))
            lines.append(f"- {surface.name}, {'tet10' if order == 2 else 'tet4'}: " + "; ".join(parts))
    return "\n".join(lines)
