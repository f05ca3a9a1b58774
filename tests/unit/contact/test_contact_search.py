"""Hierarchical contact search (thesis Sec. 3.3, Algorithms 4–6) and the broad phase:
coarse level from no start, warm-started Newton, fall-back from a bad start, points
outside open contours, seams of closed contours, several roots (the nearest wins)."""

import numpy as np
import pytest

from contact._detection_kernels import boxes_overlap
from contact.search import Contact1sSearch, Contact2sSearch
from contours import (Contour1sNeutralFFR, Contour2sNeutralFFR, FlexibleCylinder, PlaneContour, PointContour,
                      SphereContour)
from ffrmbs.errors import ModelError
from mbs import PointMass, ground_frame
from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix
from validation.bench.common import moving_state

L, H, W = 0.25, 0.05, 0.05


@pytest.fixture(scope="module")
def beam(thesis_beam):
    return thesis_beam


@pytest.fixture(scope="module")
def contours(beam):
    axis = Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0), degree=4)
    u0 = beam.data.u0
    ring = beam.node_group("x1")  # perimeter of the end face, closed; the seam lies on its y = 0 side
    ring = ring[(np.isclose(u0[ring, 1], 0) | np.isclose(u0[ring, 1], H) | np.isclose(u0[ring, 2], 0)
                 | np.isclose(u0[ring, 2], W))]
    ring = ring[np.argsort(np.arctan2(u0[ring, 2] - W / 2, u0[ring, 1] - H / 2))]
    lateral = np.unique(np.concatenate([beam.node_group(g) for g in ("y0", "y1", "z0", "z1")]))
    rows = []  # the lateral surface, closed around the beam axis in ξ
    for x in np.unique(np.round(u0[lateral, 0], 12)):
        section = lateral[np.isclose(u0[lateral, 0], x)]
        rows.append(section[np.argsort(np.arctan2(u0[section, 2] - W / 2, u0[section, 1] - H / 2))])
    return {"top": Contour2sNeutralFFR(beam, "y1"), "axis": axis, "cylinder": FlexibleCylinder(axis, 0.02),
            "ring": Contour1sNeutralFFR(beam, ring, normal=(1, 0, 0), closed=True),
            "tube": Contour2sNeutralFFR(beam, np.array(rows), closed=(False, True))}


def moved(beam, contours, seed):
    q, u = moving_state(beam, np.random.default_rng(seed), 3e-3)
    for c in contours.values():
        c.update(q, u)


def off_surface(contour, eta, xi, d):
    p = contour.evaluate(contour.new_point(), eta, xi)
    return p.r + d * p.n


def test_coarse_level_then_warm_started_newton(beam, contours):
    top = contours["top"]
    moved(beam, contours, 0)
    search = Contact2sSearch(top, n_eta=4, n_xi=3)  # the thesis's 4 x 3 grid (Fig. 3.6)
    r = off_surface(top, 0.37, 0.61, 0.01)
    assert np.allclose(search.solve(r), (0.37, 0.61), atol=1e-9)
    assert search.coarse_searches == 1 and search.newton_solves >= 1
    # the point moves a little: Newton from the last contact point, no coarse level, few iterations
    start = search.solve(r)
    search.reset_counters()
    r2 = off_surface(top, 0.372, 0.607, 0.009)
    assert np.allclose(search.solve(r2, start), (0.372, 0.607), atol=1e-9)
    assert search.coarse_searches == 0 and search.newton_solves == 1 and 1 <= search.last_iterations <= 3
    assert search.newton_iterations == search.last_iterations


def test_grid_through_given_nodes(beam, contours):
    top = contours["top"]
    moved(beam, contours, 1)
    nodes = top.space.eta.interp.params, top.space.xi.interp.params  # the FE node parameters
    search = Contact2sSearch(top, nodes=nodes)
    assert np.allclose(search.solve(off_surface(top, 0.83, 0.14, 0.02)), (0.83, 0.14), atol=1e-9)
    search.set_equal_spacing(2, 2)
    assert np.allclose(search.solve(off_surface(top, 0.83, 0.14, 0.02)), (0.83, 0.14), atol=1e-9)
    with pytest.raises(ModelError, match="strictly increasing"):
        search.set_nodes([0.0, 0.5, 0.4], [0.0, 1.0])
    with pytest.raises(ModelError, match="domain"):
        search.set_nodes([0.0, 1.5], [0.0, 1.0])


def test_point_outside_an_open_contour_has_no_contact_point(beam, contours):
    top, axis = contours["top"], contours["axis"]
    top.update(beam.q_init)
    axis.update(beam.q_init)
    beyond = np.array([L + 0.005, H + 0.01, W / 2])
    assert Contact2sSearch(top).solve(beyond) is None
    search = Contact2sSearch(top)
    assert search.solve(beyond, start=(0.99, 0.5)) is None  # Newton leaves the domain, coarse level finds none
    assert search.coarse_searches == 1
    assert Contact1sSearch(axis).solve(np.array([-0.01, 0.1, W / 2])) is None
    inside = Contact1sSearch(axis).solve(np.array([0.1, 0.1, W / 2]))
    assert np.allclose(axis.position(inside), [0.1, H / 2, W / 2], atol=1e-12)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_point_on_the_boundary_projects_onto_it(beam, contours, compiled):
    """The undeformed top face y = H spans x in [0, L], z in [0, W]: points above its edge
    x = L and its corner (L, W), on them or beyond them by up to edge_tol × the length
    scale, project onto the boundary (η = 1); 1e-5 m beyond is off the contour. Cold
    (coarse level) and warm-started from the boundary, kernel and Python reference."""
    top, axis = contours["top"], contours["axis"]
    top.update(beam.q_init)
    axis.update(beam.q_init)
    search = Contact2sSearch(top, compiled=compiled)
    edge = search.edge_tol * search.length_scale
    for d in (0.0, 1e-3 * edge, 0.5 * edge):
        for z, xi in ((W / 2, 0.5), (W + d, 1.0)):
            r = np.array([L + d, H + 0.01, z])
            for start in (None, (1.0, xi), (0.9, 0.5)):
                found = search.solve(r, start)
                assert found is not None, (d, z, start)
                np.testing.assert_allclose(found, (1.0, xi), atol=1e-9)
        assert Contact1sSearch(axis, compiled=compiled).solve(np.array([L + d, 0.1, W / 2])) == pytest.approx(1.0)
    for start in (None, (1.0, 0.5)):
        assert search.solve(np.array([L + 1e-5, H + 0.01, W / 2]), start) is None
    assert Contact1sSearch(axis, compiled=compiled).solve(np.array([L + 1e-5, 0.1, W / 2])) is None


def test_bad_warm_start_falls_back_to_the_coarse_level(beam, contours):
    """A start on the far side of the cylinder converges to a root of eq. 3.6 that is a
    distance maximum: rejected; the coarse level finds the near side."""
    cyl = contours["cylinder"]
    moved(beam, contours, 2)
    search = Contact2sSearch(cyl)
    r = off_surface(cyl, 0.3, 1.0, 0.005)
    found = search.solve(r, start=(0.3, 1.0 + np.pi))
    assert search.coarse_searches == 1 and np.allclose(found, (0.3, 1.0), atol=1e-8)
    far = search.solve(r, start=(0.95, 5.0))  # far away along the axis too
    assert np.allclose(far, (0.3, 1.0), atol=1e-8)


@pytest.mark.parametrize("phi", [0.0, 0.01, 2 * np.pi - 0.01])
def test_cylinder_seam_is_crossed(beam, contours, phi):
    cyl = contours["cylinder"]
    moved(beam, contours, 3)
    search = Contact2sSearch(cyl, n_eta=6, n_xi=6)
    r = off_surface(cyl, 0.6, phi, 0.004)
    eta, xi = search.solve(r)
    assert np.isclose(eta, 0.6, atol=1e-9) and np.isclose(np.angle(np.exp(1j * (xi - phi))), 0.0, atol=1e-9)
    # warm start on the other side of the seam: Newton wraps, no coarse level
    search.reset_counters()
    eta, xi = search.solve(off_surface(cyl, 0.6, phi - 0.02, 0.004), start=(eta, xi + 0.02))
    assert search.coarse_searches == 0 and 0.0 <= xi < 2 * np.pi
    assert np.isclose(np.angle(np.exp(1j * (xi - phi + 0.02))), 0.0, atol=1e-9)


def test_closed_ring_near_its_seam_and_from_inside(beam, contours):
    """The end face's perimeter, closed with its seam η = 0 ≡ 1 at the node (L, 0, 0.0125):
    a point just outside near the seam is found on either side of it (checked against
    dense sampling); a point inside the ring has a foot on every side: the nearest wins."""
    ring = contours["ring"]
    ring.update(beam.q_init)
    search = Contact1sSearch(ring, n=12)
    samples = ring.sample(4000)
    for z in (0.0125 - 0.002, 0.0125 + 0.002):
        r = np.array([L, -0.003, z])
        eta = search.solve(r)
        assert min(eta, 1 - eta) < 0.05 and (eta < 0.5) == (z < 0.0125)
        foot = ring.evaluate(ring.new_point(), eta)
        assert abs(foot.t_eta @ (r - foot.r)) < 1e-12
        assert np.linalg.norm(r - foot.r) <= np.linalg.norm(samples - r, axis=1).min() + 1e-12
    search.reset_counters()
    cold = search.solve(np.array([L, -0.003, 0.0105]))
    search.reset_counters()
    warm = search.solve(np.array([L, -0.003, 0.0105]), start=1.0 - 1e-3)  # across the seam
    assert search.coarse_searches == 0 and np.isclose(warm, cold, atol=1e-10)
    inner = np.array([L, H - 0.01, W / 2 + 0.004])
    eta = search.solve(inner)
    assert np.allclose(ring.position(eta), [L, H, W / 2 + 0.004], atol=1e-3)  # the top side (not quite straight)
    assert np.linalg.norm(inner - ring.position(eta)) <= np.linalg.norm(samples - inner, axis=1).min() + 1e-12
    moved(beam, contours, 4)  # moving and deformed: still the nearest of the feet
    samples = ring.sample(4000)
    target = samples.mean(axis=0) + 0.6 * (ring.position(eta) - samples.mean(axis=0))
    found = search.solve(target)
    assert np.linalg.norm(target - ring.position(found)) <= np.linalg.norm(samples - target, axis=1).min() + 1e-12


def test_several_roots_inside_a_closed_tube_the_nearest_wins(beam, contours):
    """A point inside the beam's lateral surface (closed in ξ): a local distance minimum
    on each of the four faces; the nearest is returned (checked against dense sampling)."""
    tube = contours["tube"]
    moved(beam, contours, 6)
    search = Contact2sSearch(tube, n_eta=6, n_xi=12)
    samples = tube.sample(200, 400).reshape(-1, 3)
    for k, seed in enumerate((0.3, 0.55, 0.8)):
        centre = np.mean([tube.position(seed, xi) for xi in np.linspace(0, 1, 40, endpoint=False)], axis=0)
        side = tube.position(seed, 0.25 * k)  # towards different faces, at different depths
        inner = centre + (0.4 + 0.2 * k) * (side - centre)
        eta, xi = search.solve(inner)
        foot = tube.position(eta, xi)
        assert np.linalg.norm(inner - foot) <= np.linalg.norm(samples - inner, axis=1).min() + 1e-12
        assert abs(eta - seed) < 0.02


def test_only_minima_count_on_a_cylinder(beam, contours):
    """A point inside the cylinder, off its axis: eq. 3.6 holds on the near side (a
    distance minimum) and on the far side (a maximum); the near one is returned."""
    cyl, axis = contours["cylinder"], contours["axis"]
    moved(beam, contours, 5)
    r = off_surface(cyl, 0.45, 4.0, -0.012)  # 8 mm from the axis towards φ = 4
    eta, xi = Contact2sSearch(cyl).solve(r)
    assert np.isclose(eta, 0.45, atol=1e-8) and np.isclose(xi, 4.0, atol=1e-8)
    assert np.isclose(np.linalg.norm(cyl.position(eta, xi) - axis.position(0.45)), 0.02, rtol=1e-12)


def test_rigid_sphere_and_plane_through_the_search():
    """The search on the analytic contours: the foot is the radial / orthogonal projection."""
    sphere = SphereContour(ground_frame((0.1, 0.2, 0.3), np.eye(3)), 0.5)
    r = np.array([0.1, 0.2, 0.3]) + 0.7 * np.array([0.48, -0.6, 0.64])
    eta, xi = Contact2sSearch(sphere).solve(r)
    assert np.allclose(sphere.position(eta, xi), np.array([0.1, 0.2, 0.3]) + 0.5 * np.array([0.48, -0.6, 0.64]))
    A = quat_to_matrix(quat_from_rotvec([0.2, 0.4, -0.3]))
    plane = PlaneContour(ground_frame((0, 0, 0), A), size=1.0)
    r = A @ [0.3, -0.7, 0.2]
    assert np.allclose(Contact2sSearch(plane).solve(r), (0.3, -0.7), atol=1e-12)
    assert Contact2sSearch(plane).solve(A @ [1.3, 0.0, 0.2]) is None


def test_bad_input(contours):
    with pytest.raises(ModelError, match="2s contour"):
        Contact2sSearch(contours["axis"])
    with pytest.raises(ModelError, match="at least one cell"):
        Contact2sSearch(contours["top"], n_eta=0)


# --- broad phase ------------------------------------------------------------------------

def test_the_box_test_of_a_contact():
    """contact._detection_kernels.boxes_overlap, the box test of Contact.locate: boxes (2, 3)
    each grown by the margin overlap; touching counts; an infinite (plane) box overlaps all."""
    a = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    assert boxes_overlap(a, a + 0.5, 0.0) and boxes_overlap(a, a + [1.0, 0, 0], 0.0)  # touching counts
    apart = a + [1.1, 0.0, 0.0]
    assert not boxes_overlap(a, apart, 0.0) and not boxes_overlap(apart, a, 0.0)
    assert boxes_overlap(a, apart, 0.051) and not boxes_overlap(a, apart, 0.049)
    assert not boxes_overlap(a, a + [0.0, 0.0, -1.5], 0.0)  # separated along z only
    plane = np.array([np.full(3, -np.inf), np.full(3, np.inf)])
    assert boxes_overlap(plane, apart + 100.0, 0.0) and boxes_overlap(apart, plane, 1.0)


def test_a_contact_locates_only_when_the_boxes_overlap():
    """Contact.locate locates a pair only when the contours' boxes, grown by the margin,
    overlap (else the kinematics are not updated: the gap stays NaN), and then finds the
    analytic gap: |p − c| − ρ of a point p and a sphere (c, ρ), the height above a floor."""
    from contact import UnilateralNewtonImpact, connect

    ball = SphereContour(ground_frame((0.0, 0.0, 0.05)), 0.03)  # box z in [0.02, 0.08], x, y in [-0.03, 0.03]
    floor = PlaneContour(ground_frame())

    def located(position, contour, margin):
        """(located, g_N [m]) of one locate of a point at ``position``."""
        point = PointContour(PointMass(1.0, position=position).point)
        contact = connect(point, contour, UnilateralNewtonImpact(0.0), margin=margin)
        contact.locate()
        return contact.kinematics.active, contact.kinematics.g_N

    found, g_N = located((0.025, 0.025, 0.05), ball, 0.0)          # inside the ball's box
    assert found and g_N == pytest.approx(np.sqrt(2) * 0.025 - 0.03, abs=1e-12)
    found, g_N = located((5.0, 0.0, 0.0), ball, 0.0)               # far apart
    assert not found and np.isnan(g_N)
    assert located((5.0, 0.0, 0.0), floor, 0.0)[1] == 0.0             # the plane's box is infinite
    below = (0.01, 0.0, 0.012)                                        # 8 mm below the box
    for margin in (0.0, 0.0039):                                      # the boxes grown by 2 x margin
        found, g_N = located(below, ball, margin)
        assert not found and np.isnan(g_N)
    found, g_N = located(below, ball, 0.005)                       # ... by 2 x 5 mm
    assert found and g_N == pytest.approx(np.hypot(0.01, 0.038) - 0.03, abs=1e-12)


def test_contact_searches_only_pairs_the_broad_phase_keeps():
    """The default margin is a tenth of contour 2's largest box edge: a point 0.3 m from a
    sphere of radius 0.03 (margin 0.006 m) is never searched; within the margin it is,
    and so is every pair with the broad phase off."""
    from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact

    ball = SphereContour(ground_frame((0.0, 0.0, 0.05)), 0.03)

    def searched(z, **kw):
        mass = PointMass(1.0, position=(0.0, 0.0, z))
        kin = ContactKinematicsPointContour2s(PointContour(mass.point), ball)
        contact = Contact(kin, UnilateralNewtonImpact(0.0), **kw)
        contact.locate()
        return kin.search.coarse_searches + kin.search.newton_solves

    assert Contact(ContactKinematicsPointContour2s(PointContour(ground_frame()), ball),
                   UnilateralNewtonImpact(0.0)).margin == pytest.approx(0.006)
    assert searched(0.35) == 0 and searched(0.35, margin=None) > 0
    assert searched(0.05 + 0.03 + 0.011) > 0          # 0.011 m above the box: within 2 x 0.006
    with pytest.raises(ModelError, match="margin"):
        searched(0.35, margin=-1.0)
