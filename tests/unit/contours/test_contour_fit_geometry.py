"""Fitted 2s contours (contours.fitting) against exact geometry and independent oracles.

Surfaces: unstructured gmsh meshes of a plate's top face, a cylinder's lateral band and a
spherical cap (preprocess.geometry), fitted with the defaults and measured against the
exact plane, cylinder and sphere; the band's periodic seam against scipy's B-spline
evaluation; the plate's mode shapes against their nodal values. Pieces: the Gram
matrices against scipy quadrature of scipy B-spline basis functions, exact reproduction
of polynomials evaluated with scipy's B-spline design matrices, the mean-value map's
orientation and corners, the band map against the cylinder's angle and height, and the
patch errors.
"""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.interpolate import BSpline

from contours import Contour2sNeutralFFR
from contours.base import ContourPoint
from contours.fitting import CurveFit, FitDirection, SurfaceFit, SurfacePatch, parameterize, surface_fit
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, PrescribedFrameMotion
from preprocess import Material, build_body
from preprocess.geometry import box, cylinder, spherical_cap

LX, LY, LZ = 0.2, 0.1, 0.02          # plate [m]
R_CYL, L_CYL = 0.05, 0.05            # cylinder [m]
R_CAP, H_CAP = 0.1, 0.04             # spherical cap [m]
COARSE, FINE = 0.02, 0.01            # mesh sizes [m]
GRID = np.stack(np.meshgrid(np.linspace(0, 1, 41), np.linspace(0, 1, 41), indexing="ij"), -1).reshape(-1, 2)


def fitted(mesh, group):
    """(fit, patch, distinct control points (n, 3)) of the default fit of ``group``."""
    fit, patch = surface_fit(mesh.points, mesh.surface_triangles(), mesh.group(group))
    P = fit.control_points(patch.points)[:fit.eta.n_unique, :fit.xi.n_unique].reshape(-1, 3)
    return fit, patch, P


def surface_and_normal(fit, P, params):
    """Points S (m, 3) [m] and unit normals (m, 3) of the fitted surface at ``params``."""
    x = fit.collocation(params) @ P
    n = np.cross(fit.collocation(params, 1, 0) @ P, fit.collocation(params, 0, 1) @ P)
    return x, n / np.linalg.norm(n, axis=1)[:, None]


def angle_deg(n, exact):
    return np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", n, exact)), 0.0, 1.0)))


def away_from_corners(params, clearance=0.05):
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    return np.linalg.norm(params[:, None] - corners[None], axis=2).min(axis=1) >= clearance


def cylinder_errors(h):
    """(max |ρ − R| / R, max normal angle [deg]) of the fitted lateral band, tet10 at size h."""
    fit, patch, P = fitted(cylinder(R_CYL, L_CYL, h, order=2), "lateral")
    params = np.vstack([GRID, fit.params])
    x, n = surface_and_normal(fit, P, params)
    exact = x * [1.0, 1.0, 0.0]
    exact /= np.linalg.norm(exact, axis=1)[:, None]
    return np.abs(np.hypot(x[:, 0], x[:, 1]) - R_CYL).max() / R_CYL, angle_deg(n, exact).max()


def cap_errors(h):
    """(max ||x| − R| / R, max normal angle [deg] off the square's corners) of the fitted
    cap, tet10 at size h (the normal is undefined at the map's four corners, which sit
    on the smooth boundary circle)."""
    fit, patch, P = fitted(spherical_cap(R_CAP, H_CAP, h, order=2), "cap")
    params = np.vstack([GRID, fit.params])
    x, n = surface_and_normal(fit, P, params)
    r = np.linalg.norm(x, axis=1)
    inner = away_from_corners(params)
    return np.abs(r - R_CAP).max() / R_CAP, angle_deg(n[inner], (x / r[:, None])[inner]).max()


# --- surfaces against the exact geometry -------------------------------------------------

@pytest.mark.parametrize("order", [1, 2])
def test_plate_face_is_reproduced_exactly(order):
    """Mean-value coordinates reproduce linear functions, so the map of a rectangle with
    arc-length sides is affine and the fit reproduces the plane face, edges included."""
    fit, patch, P = fitted(box(LX, LY, LZ, COARSE, order=order), "z1")
    x, n = surface_and_normal(fit, P, np.vstack([GRID, fit.params]))
    assert np.abs(x[:, 2] - LZ).max() < 1e-12 * LX
    assert angle_deg(n, np.tile([0.0, 0.0, 1.0], (len(n), 1))).max() < 1e-5
    t = np.linspace(0.0, 1.0, 101)
    edges = np.vstack([np.column_stack(s) for s in ((t, 0 * t), (t, 0 * t + 1), (0 * t, t), (0 * t + 1, t))])
    xe = fit.collocation(edges) @ P
    inplane = np.min(np.abs(np.stack([xe[:, 0], xe[:, 0] - LX, xe[:, 1], xe[:, 1] - LY])), axis=0)
    assert inplane.max() < 1e-12 * LX


def test_cylinder_band_distance_and_normal_converge():
    coarse, fine = cylinder_errors(COARSE), cylinder_errors(FINE)
    assert coarse[0] < 3e-5 and coarse[1] < 0.05          # relative distance, degrees
    assert fine[0] < 0.6 * coarse[0] and fine[1] < 0.7 * coarse[1]


def test_cap_distance_and_normal_converge():
    coarse, fine = cap_errors(COARSE), cap_errors(FINE)
    assert coarse[0] < 1e-3 and coarse[1] < 2.0
    assert fine[0] < 0.7 * coarse[0] and fine[1] < 0.9 * coarse[1]


def test_closed_band_is_c2_across_the_seam():
    """S, S_η, S_ηη at η = 0 and η = 1 from scipy's B-spline on the periodic knots and
    the wrapped control points (no wrapping of the parameter)."""
    fit, patch, _ = fitted(cylinder(R_CYL, L_CYL, COARSE, order=2), "lateral")
    assert fit.eta.closed and not fit.xi.closed
    ctrl = fit.control_points(patch.points)                       # (n_η + p, n_ξ, 3)
    xis = np.linspace(0.0, 1.0, 7)
    X = fit.xi.collocation(xis).toarray()                         # (7, n_ξ), ξ open
    curves = np.einsum("jb,abc->jac", X, ctrl)                    # curves in η at each ξ
    scale = np.abs(ctrl).max()
    for curve in curves:
        spline = BSpline(fit.eta.knots, curve, fit.eta.degree)
        for d in range(3):
            at0, at1 = spline(0.0, nu=d), spline(1.0, nu=d)
            assert np.abs(at0 - at1).max() < 1e-10 * scale * max(1.0, np.abs(at0).max() / scale)


def test_plate_mode_shapes_fit_their_nodal_values():
    """The contour's mode shapes (A Φ in J_T, frame fixed: A = 1) at each patch node's
    parameters against the node's own mode-shape rows, relative to the mode's largest."""
    data = build_body(box(LX, LY, LZ, COARSE, order=2), Material(7800.0, 2.1e11, 0.3), 4, clamp="x0")
    body = FlexibleBodyFFR(data, 4, frame=PrescribedFrameMotion.fixed())
    contour = Contour2sNeutralFFR(body, "z1")
    assert contour.fit is not None                                # not a grid: fitted
    point = ContourPoint(body.nu)
    phi = body.phi_nodes[contour.patch.nodes]                      # (k, 3, n_f)
    fitted_phi = np.empty_like(phi)
    for i, (eta, xi) in enumerate(contour.fit.params):
        contour.evaluate(point, eta, xi, jacobians=True)
        fitted_phi[i] = point.J_T[:, -4:]
    scale = np.linalg.norm(phi, axis=1).max(axis=0)                # (n_f,)
    error = np.linalg.norm(fitted_phi - phi, axis=1).max(axis=0) / scale
    assert error.max() < 0.01


# --- the pieces against independent oracles ----------------------------------------------

def scipy_basis(direction, d):
    """The distinct basis functions' d-th derivatives as callables (scipy), periodic copies
    summed for a closed direction."""
    t, p = direction.knots, direction.degree
    parts = [[] for _ in range(direction.n_unique)]
    for j in range(direction.n_ctrl):
        element = BSpline(t, np.eye(direction.n_ctrl)[j], p)
        parts[j % direction.n_unique].append(element.derivative(d) if d else element)
    return [lambda x, fs=fs: sum(f(x) for f in fs) for fs in parts]


@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("d", [0, 1, 2])
def test_gram_matrix_against_quadrature(closed, d):
    direction = FitDirection(6, 3, closed)
    G = direction.gram(d).toarray()
    basis = scipy_basis(direction, d)
    breaks = np.unique(direction.knots[(direction.knots > 0) & (direction.knots < 1)])
    ref = np.array([[quad(lambda x: float(fa(x) * fb(x)), 0.0, 1.0, points=breaks, limit=200)[0]
                     for fb in basis] for fa in basis])
    assert np.abs(G - ref).max() < 1e-9 * np.abs(ref).max()


def design(direction, t):
    """(m, n_ctrl) collocation matrix of scipy's B-spline basis (open direction)."""
    return BSpline.design_matrix(t, direction.knots, direction.degree).toarray()


def test_surface_fit_reproduces_a_bicubic_and_a_plane():
    rng = np.random.default_rng(1)
    params = rng.uniform(size=(300, 2))
    coef = rng.normal(size=(4, 4))
    bicubic = lambda e, x: np.einsum("ij,mi,mj->m", coef, e[:, None] ** np.arange(4), x[:, None] ** np.arange(4))
    plane = lambda e, x: 0.3 + 1.7 * e - 0.8 * x
    test = rng.uniform(size=(200, 2))
    for values, smoothing in ((bicubic, 0.0), (plane, 0.0), (plane, 1e-2)):
        fit = SurfaceFit(params, (6, 5), 3, (False, False), smoothing)
        P = fit.control_points(values(params[:, 0], params[:, 1]))
        S = np.einsum("ma,ab,mb->m", design(fit.eta, test[:, 0]), P, design(fit.xi, test[:, 1]))
        assert np.abs(S - values(test[:, 0], test[:, 1])).max() < 1e-10 * (1 + np.abs(coef).sum())


def test_curve_fit_reproduces_a_cubic_and_a_line():
    rng = np.random.default_rng(2)
    t = rng.uniform(size=80)
    test = np.linspace(0.0, 1.0, 57)
    cubic = lambda s: np.column_stack([1 - 2 * s + 3 * s ** 3, s ** 2 - s ** 3, 0.5 + 0 * s])
    line = lambda s: np.column_stack([s, 2 - s, 3 * s])
    for values, smoothing in ((cubic, 0.0), (line, 1e-2)):
        fit = CurveFit(t, 7, 3, False, smoothing)
        P = fit.control_points(values(t))
        assert np.abs(BSpline(fit.knots, P, fit.degree)(test) - values(test)).max() < 1e-11


def test_mean_value_map_of_a_square_face_is_one_to_one():
    mesh = box(0.1, 0.1, 0.02, 0.01, order=1)
    patch = SurfacePatch(mesh.points, mesh.surface_triangles(), mesh.group("z1"))
    uv, closed = parameterize(patch)
    assert closed == (False, False)
    a, b, c = (uv[patch.linear[:, i]] for i in range(3))
    signed = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    assert (signed > 0).all()
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    for corner in corners:
        node = np.flatnonzero(np.linalg.norm(uv - corner, axis=1) < 1e-12)
        assert node.size == 1
        xy = patch.points[node[0], :2]
        assert np.min(np.linalg.norm(np.array([[0, 0], [0.1, 0], [0.1, 0.1], [0, 0.1]]) - xy, axis=1)) < 1e-12


def test_band_map_follows_angle_and_height():
    """η ≈ ±θ/2π + const (mod 1) and ξ ≈ z/L or 1 − z/L on the cylinder's lateral band."""
    mesh = cylinder(R_CYL, L_CYL, COARSE, order=2)
    patch = SurfacePatch(mesh.points, mesh.surface_triangles(), mesh.group("lateral"))
    uv, closed = parameterize(patch)
    assert closed == (True, False)
    theta = np.arctan2(patch.points[:, 1], patch.points[:, 0]) / (2 * np.pi)
    z = patch.points[:, 2] / L_CYL

    def eta_error(sign):
        """max |η − (sign θ/2π + c)| (mod 1), c the circular mean of η − sign θ/2π."""
        r = uv[:, 0] - sign * theta
        c = np.angle(np.exp(2j * np.pi * r).mean()) / (2 * np.pi)
        return np.abs(((r - c + 0.5) % 1.0) - 0.5).max()

    assert min(eta_error(1.0), eta_error(-1.0)) < 0.02
    assert min(np.abs(uv[:, 1] - z).max(), np.abs(uv[:, 1] - (1 - z)).max()) < 0.02


def test_patch_errors():
    mesh = box(0.1, 0.1, 0.02, 0.02, order=1)
    points, tri = mesh.points, mesh.surface_triangles()
    with pytest.raises(ModelError, match="separate pieces"):
        SurfacePatch(points, tri, np.concatenate([mesh.group("z0"), mesh.group("z1")]))
    with pytest.raises(ModelError, match="closed surface"):
        SurfacePatch(points, tri, mesh.surface_nodes()).topology()
    top = mesh.group("z1")
    face = SurfacePatch(points, tri, top)
    inner = face.nodes[~np.isin(face.nodes, np.concatenate([face.nodes[loop] for loop in face.loops]))]
    # two holes: drop two inner nodes that share no triangle (their stars are disjoint)
    stars = {n: set(np.unique(face.nodes[face.linear[(face.nodes[face.linear] == n).any(axis=1)]])) for n in inner}
    boundary = set(face.nodes[face.loops[0]])
    deep = [n for n in inner if not stars[n] & boundary]
    a = deep[0]
    b = next(n for n in deep[1:] if not stars[a] & stars[n])
    holed = SurfacePatch(points, tri, np.setdiff1d(top, [a, b]))
    assert holed.topology() == "holes"                  # a flat face with two holes, not a band
    outer, holes = holed.outer_and_holes()
    assert len(holes) == 2 and set(face.nodes[face.loops[0]]) == set(holed.nodes[outer])


# --- the validation case, quick mode ----------------------------------------------------

@pytest.mark.slow
def test_geometry_case_rows_converge(monkeypatch):
    """The quick run with the fine mesh size 12.5 mm for 10 mm (the cylinder's mesh is the
    same at every size from 15 mm up, so the fine size must stay below that): about half
    the FE models' cost, the same rows and checks."""
    from case_rows import quick_rows_without_files, select
    from validation.cases import contour_fit_geometry as case

    monkeypatch.setitem(case.SIZES, True, (0.02, 0.0125))
    rows = quick_rows_without_files([case])[case.NAME]
    assert len(rows) == len(case.SURFACES) * len(case.SIZES[True])
    for row in select(rows, surface="plate"):
        assert row["error"] < 1e-12 and row["mode_node_max"] < 0.01
    for name in ("cylinder", "cap"):
        coarse, fine = (select(rows, surface=name, mesh_size=h)[0] for h in case.SIZES[True])
        assert fine["error"] < coarse["error"] and fine["normal_inner_max_deg"] < coarse["normal_inner_max_deg"]
        assert fine["patch_nodes"] > coarse["patch_nodes"]
