"""Contours on faces with holes (issue 30, items 4 and 11): a face whose boundary has
several loops is told from a closed band, fitted over its outer loop's domain and
trimmed to its material."""

from __future__ import annotations

import numpy as np
import pytest

import gmsh_parts
from contact import connect
from contours import Contour2sNeutralFFR, SphereContour
from contours.fitting import SurfacePatch, Trim, fit_report, surface_fit
from contours.fitting.trim import in_material_reference
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from preprocess import build_body
from validation.cases import contact_hole as case

# the 2-mode tet4 plate's mode shapes fit to ~6 % (a coarse mesh); these tests check geometry
pytestmark = pytest.mark.filterwarnings("ignore:.*is fitted to within:UserWarning")


@pytest.fixture(scope="module")
def plate_hole():
    """The validation case's plate with a 12 mm through hole, tet10 at 5 mm."""
    return case.plate_hole_mesh(0.005, order=2)


def test_face_with_a_hole_is_no_band(plate_hole):
    """The top face of a plate with a through hole has two boundary loops like a band, but
    it is a graph over its plane: a face with one hole whose outer loop is the rectangle
    (the plate's 2 (lx + ly) perimeter), never a band periodic in eta."""
    mesh = plate_hole
    patch = SurfacePatch(mesh.points, mesh.surface_triangles(), mesh.node_groups["top"], "top")
    assert patch.topology() == "holes"
    outer, holes = patch.outer_and_holes()
    lx, ly, _ = case.PLATE
    perimeter = np.linalg.norm(np.diff(patch.points[np.append(outer, outer[0])], axis=0), axis=1).sum()
    assert perimeter == pytest.approx(2 * (lx + ly), rel=1e-9)
    (hole,) = holes
    r = np.linalg.norm(patch.points[hole, :2] - case.HOLE[:2], axis=1)
    assert np.allclose(r, case.HOLE[2], rtol=1e-6)


def test_band_stays_a_band():
    """A cylinder's lateral surface (two loops, normals all around): still a closed band."""
    mesh = gmsh_parts.cylinder_mesh(0.02, order=1)
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    side = np.flatnonzero(np.abs(r - gmsh_parts.RADIUS) < 1e-9)
    patch = SurfacePatch(mesh.points, mesh.surface_triangles(), side, "side")
    assert patch.topology() == "annulus"
    fit, _ = surface_fit(mesh.points, mesh.surface_triangles(), side)
    assert fit.eta.closed


def half_cylinder_with_a_hole(radius=0.05, length=0.2, n_theta=25, n_z=41):
    """(points, triangles, outward) of a half cylinder x² + y² = R², y >= 0, 0 <= z <= L,
    triangulated on a (θ, z) grid, outward normal (x, y, 0)/R, with the grid nodes within
    0.15 L of (θ, z) = (π/2, L/2) left out: a curved face with one hole."""
    theta, z = np.linspace(0.0, np.pi, n_theta), np.linspace(0.0, length, n_z)
    T, Z = np.meshgrid(theta, z, indexing="ij")
    points = np.column_stack([radius * np.cos(T.ravel()), radius * np.sin(T.ravel()), Z.ravel()])
    idx = np.arange(T.size).reshape(T.shape)
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    # (θ, z) counter-clockwise seen from outside: t_θ × t_z points outward
    tri = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    gone = np.hypot(radius * (T.ravel() - np.pi / 2), Z.ravel() - length / 2) < 0.15 * length
    return points, tri[~gone[tri].any(axis=1)], np.flatnonzero(~gone)


def test_curved_face_with_a_hole_is_no_band():
    """A half cylinder with a hole (flatness below 2/π, the triangles at its two straight
    edges facing across its mean normal): a face with one hole, fitted over its outer loop's square to the cylinder
    (within the chords' sag), trimmed; not a band."""
    points, tri, nodes = half_cylinder_with_a_hole()
    patch = SurfacePatch(points, tri, nodes, "half cylinder")
    assert 0.25 < patch.flatness() < 2 / np.pi          # the hole takes some of the top's share
    assert patch.topology() == "holes"
    fit, patch = surface_fit(points, tri, nodes, name="half cylinder")
    report = fit_report(fit, patch)
    assert not fit.eta.closed and Trim.of_fit(fit, patch) is not None
    S = fit.collocation(fit.params) @ report.ctrl
    sag = 0.05 * (1 - np.cos(np.pi / 24 / 2))           # a chord's sag between grid nodes
    assert np.abs(np.hypot(S[:, 0], S[:, 1]) - 0.05).max() < sag


def _fit(mesh):
    fit, patch = surface_fit(mesh.points, mesh.surface_triangles(), mesh.node_groups["top"], name="top")
    return fit, patch, fit_report(fit, patch, name="top")


def _face_distance(fit, patch, report, params):
    """max |S_z − lz| [m] at the nodes and at ``params``: the face is the plane z = lz."""
    lz = case.PLATE[2]
    S = fit.collocation(params) @ report.ctrl
    return max(np.abs(fit.collocation(fit.params) @ report.ctrl - patch.points)[:, 2].max(), np.abs(S[:, 2] - lz).max())


def test_face_with_a_hole_is_fitted_on_its_material(plate_hole):
    """The flat top face with a hole: fitted over the rectangle's square (not a band), on
    the plane z = lz to rounding at the nodes, at the triangles' mid-points and anywhere
    on the trimmed domain — as the same face without the hole; the parameters are an
    affine image of (x, y) (mean-value weights reproduce linear functions), so the hole's
    polygon in parameter space is the rim's image."""
    fit, patch, report = _fit(plate_hole)
    assert not fit.eta.closed and not fit.xi.closed
    trim = Trim.of_fit(fit, patch)
    assert trim is not None and len(trim.polygons) == 1
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 81), np.linspace(0, 1, 81), indexing="ij"), -1).reshape(-1, 2)
    material = grid[trim.contains_many(grid)]
    assert 0 < len(material) < len(grid)
    assert _face_distance(fit, patch, report, material) < 1e-12
    affine = np.column_stack([patch.points[:, :2], np.ones(patch.k)])
    coef, *_ = np.linalg.lstsq(affine, fit.params, rcond=None)
    assert np.abs(affine @ coef - fit.params).max() < 1e-12
    # without the hole: the same (rounding) distance
    plain = case.plate_hole_mesh(0.005, order=2, hole=False)
    fit0, patch0, report0 = _fit(plain)
    assert Trim.of_fit(fit0, patch0) is None
    assert _face_distance(fit0, patch0, report0, grid) < 1e-12
    assert report.rows[0]["node_max"] < 1e-12 and report0.rows[0]["node_max"] < 1e-12


def test_trim_kernel_against_reference_and_circle():
    """The numba crossing-number test = its numpy reference = the exact disc test, for a
    polygon of 64 corners on a circle and a non-convex (L-shaped) hole."""
    rng = np.random.default_rng(3)
    angle = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
    centre, radius = np.array([0.3, 0.6]), 0.2
    circle = centre + radius * np.column_stack([np.cos(angle), np.sin(angle)])
    ell = np.array([[0.6, 0.1], [0.9, 0.1], [0.9, 0.2], [0.7, 0.2], [0.7, 0.4], [0.6, 0.4]])
    trim = Trim([circle[::-1], ell])                       # a hole loop runs clockwise
    points = rng.random((4000, 2))
    inside_circle = np.linalg.norm(points - centre, axis=1) < radius * np.cos(np.pi / 64)   # inscribed
    outside_circle = np.linalg.norm(points - centre, axis=1) > radius
    inside_ell = (((points[:, 0] > 0.6) & (points[:, 0] < 0.9) & (points[:, 1] > 0.1) & (points[:, 1] < 0.2))
                  | ((points[:, 0] > 0.6) & (points[:, 0] < 0.7) & (points[:, 1] > 0.1) & (points[:, 1] < 0.4)))
    got = trim.contains_many(points)
    assert (got == in_material_reference(points, trim.polygons)).all()
    assert not got[inside_circle | inside_ell].any()
    assert got[outside_circle & ~inside_ell].all()


# --- contact on the trimmed face and its rim -----------------------------------------------------

@pytest.fixture(scope="module")
def plate_data():
    """The validation case's plate with the hole, tet4 at 6 mm, bottom clamped, 2 modes."""
    return build_body(case.plate_hole_mesh(0.006, order=1), case.STEEL, n_modes=2, clamp="bottom")


def _ball(data, position, rims=True):
    system = System(gravity=(0.0, 0.0, -case.G))
    plate = system.add(FlexibleBodyFFR(data, modes=2, frame=PrescribedFrameMotion.fixed(), name="plate"))
    top = Contour2sNeutralFFR(plate, "top")
    ball = system.add(PointMass(case.BALL_MASS, position=position, name="ball"))
    sphere = SphereContour(ball.point, case.BALL_RADIUS)
    face = system.add(connect(sphere, top, "impact", name="face"))
    edges = top.rims()
    rim = system.add(connect(sphere, edges[1], "impact", name="rim")) if rims else None
    return system, face, rim, edges


@pytest.mark.parametrize("compiled", [True, False])
def test_no_contact_point_in_the_hole(plate_data, compiled):
    """A ball whose centre is over the hole has no contact point on the face (compiled
    Newton and the Python reference alike); beside the hole its gap is the analytic
    height above z = lz less the radius."""
    lx, ly, lz = case.PLATE
    r = case.BALL_RADIUS
    for xy, found in ((case.HOLE[:2], False), ((case.HOLE[0] + 0.7 * case.HOLE[2], case.HOLE[1]), False),
                      ((case.HOLE[0] + 1.3 * case.HOLE[2], case.HOLE[1]), True), (case.BESIDE, True)):
        system, face, _, _ = _ball(plate_data, (*xy, lz + r + 1e-3), rims=False)
        face.kinematics.search.compiled = compiled
        assert face.kinematics.update() is found, xy
        if found:
            assert face.kinematics.g_N == pytest.approx(1e-3, abs=1e-12)


def test_rims_of_the_face(plate_data):
    """The face's rims: the outer edge (the rectangle, length 2 (lx + ly)) and the hole's
    circle (radius 6 mm at z = lz), as closed edge contours."""
    _, _, _, edges = _ball(plate_data, (*case.BESIDE, 0.1), rims=False)
    outer, hole = edges
    lx, ly, lz = case.PLATE
    eta = np.linspace(0.0, 1.0, 200, endpoint=False)
    x = np.array([hole.position(e) for e in eta])
    assert np.abs(np.linalg.norm(x[:, :2] - case.HOLE[:2], axis=1) - case.HOLE[2]).max() < 2e-5   # chord sag
    assert np.abs(x[:, 2] - lz).max() < 1e-12
    y = np.array([outer.position(e) for e in eta])
    assert np.abs(y[:, 2] - lz).max() < 1e-12 and hole.closed[0] and outer.closed[0]


def test_rim_contact_normal_points_from_the_edge_to_the_centre(plate_data):
    """A ball over the hole's rim, its centre inside the circle: the rim contact's normal
    is (c − r*)/|c − r*| with r* the exact circle's closest point, g_N = |c − r*| − ρ, up
    to the rim curve's distance e from the circle (an interpolant through the tet4 rim's
    nodes): angle error <= 2 e / |c − r*|."""
    lx, ly, lz = case.PLATE
    hx, hy, R = case.HOLE
    r = case.BALL_RADIUS
    for angle, inset, height in ((0.0, 0.5e-3, 3e-3), (2.0, 1e-3, 1e-3), (4.0, 2e-3, 0.5e-3)):
        u = np.array([np.cos(angle), np.sin(angle)])
        c = np.array([*(np.array([hx, hy]) + (R - inset) * u), lz + height])
        _, face, rim, edges = _ball(plate_data, c)
        curve = np.array([edges[1].position(e) for e in np.linspace(0.0, 1.0, 2000, endpoint=False)])
        e = np.abs(np.linalg.norm(curve - (hx, hy, lz), axis=1) - R).max()
        assert rim.kinematics.update()
        star = np.array([*(np.array([hx, hy]) + R * u), lz])
        n = (c - star) / np.linalg.norm(c - star)
        assert np.arccos(min(1.0, rim.kinematics.n @ n)) < 2 * e / np.linalg.norm(c - star)
        assert rim.kinematics.g_N == pytest.approx(np.linalg.norm(c - star) - r, abs=e)
        assert rim.kinematics.n[:2] @ u < 0                 # towards the hole's centre
        assert not face.kinematics.update()                 # the centre is over the hole


def test_ball_falls_through_the_hole_and_rests_beside_it(plate_data):
    """Dropped over the hole's centre the ball falls freely through the plate (exact free
    fall, no contact closes); dropped beside it, it rests at lz + r to within the Moreau
    closing step's offset (contact_unstructured.closing_offset, exact free fall)."""
    from validation.cases.contact_unstructured import closing_offset

    lz, r, drop, dt = case.PLATE[2], case.BALL_RADIUS, case.DROP, 1e-4
    for xy, t_end in ((case.HOLE[:2], 0.04), (case.BESIDE, 0.025)):
        system, face, rim, _ = _ball(plate_data, (*xy, lz + r + drop))
        ball = face.kinematics.contour1.body
        res = system.simulate(t_end, dt, integrator="moreau", theta=0.5, trace=True,
                              outputs={"z": lambda t, q, u: q[ball.q_slice][2]})
        if xy == case.BESIDE:
            assert res["z"][-1] - (lz + r) == pytest.approx(closing_offset(dt), abs=1e-9)
        else:
            assert not np.any(res.trace["closed"])
            assert res["z"][-1] == pytest.approx(lz + r + drop - 0.5 * case.G * res.t[-1] ** 2, abs=1e-12)
            assert res["z"][-1] < lz                       # below the top: through the hole


@pytest.mark.slow
def test_hole_case_rows():
    """The validation case contact_hole, quick mode (its rows as the harness runs it, no
    plot or report: this test reads the rows): the fit on the material as without the
    hole (rounding), the rest height within its bound, the free fall through the hole, the
    rim's normal from the edge to the centre as the exact circle's and the ball in the hole."""
    from case_rows import quick_rows_without_files, select

    rows = quick_rows_without_files([case])[case.NAME]
    for row in select(rows, check="fit"):
        assert row["error"] < 1e-12 and row["node_max_m"] < 1e-12
    (rest,) = select(rows, check="rest beside the hole")
    assert rest["error"] <= rest["bound_rel"]
    (through,) = select(rows, check="fall through the hole")
    assert through["contacts_closed"] == 0 and through["error"] < 1e-9
    (rolled,) = select(rows, check="roll into the hole")
    assert rolled["rim_closed_steps"] > 0 and rolled["error"] < 1e-3
    assert rolled["z_end_below_top_m"] > 0                 # its centre below the top: in the hole
    assert rolled["first_rim_normal"][2] > 0.99 and rolled["last_rim_normal"][0] > 0.5   # up, then to the centre


def test_edge_frame_kernel_against_numpy():
    """edge_frame: n = (c − r)/|c − r|, t1 the tangent without its n part, t2 = n × t1 (a
    right-handed orthonormal frame), as computed with numpy; False on the curve."""
    from contact._detection_kernels import edge_frame

    rng = np.random.default_rng(7)
    for _ in range(20):
        D = np.zeros((6, 3))
        D[0], tangent, c = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        F = np.zeros((3, 3))
        F[:, 0] = tangent / np.linalg.norm(tangent)
        assert edge_frame(F, c, D)
        n = (c - D[0]) / np.linalg.norm(c - D[0])
        t1 = tangent - (tangent @ n) * n
        t1 /= np.linalg.norm(t1)
        assert np.allclose(F, np.column_stack([t1, np.cross(n, t1), n]), atol=1e-14)
    assert not edge_frame(F, D[0].copy(), D)
