"""Band and cylinder on a 1s neutral contour, and the rigid contours (point, sphere,
plane), against geometry, rigid-body kinematics and finite differences."""

import contextlib

import numpy as np
import pytest

from contours import (Contour1sNeutralFFR, FlexibleBand, FlexibleCylinder, PlaneContour, PointContour,
                      SphereContour)
from contours.derived import offset_frame
from ffrmbs.errors import ModelError
from mbs import PointMass, RigidBody, ground_frame
from mbs.bodies.rotations import quat_from_rotvec
from validation.bench.common import moving_state

L, H, W = 0.25, 0.05, 0.05


@pytest.fixture(scope="module")
def beam(thesis_beam):
    return thesis_beam


@pytest.fixture(scope="module")
def axis(thesis_centre_line):
    return thesis_centre_line


def finite_difference_checks(contour, body, q, u, eta, xi, tol=1e-7):
    """v = J_T u = d/dt r along q ⊕ t u; r_η, r_ξ, r_ηξ, r_ξξ = finite differences of r."""
    contour.update(q, u)
    point = contour.evaluate(contour.new_point(), eta, xi, velocity=True, jacobians=True)
    D, v = point.derivs.copy(), point.v.copy()
    assert np.allclose(point.J_T @ u, v, rtol=1e-12, atol=1e-12 * np.abs(v).max())
    h = 1e-5
    r = []
    for s in (h, -h):
        contour.update(body.increment(q, s * u))
        r.append(contour.position(eta, xi))
    contour.update(q, u)
    assert np.linalg.norm((r[0] - r[1]) / (2 * h) - v) < tol * np.linalg.norm(v)
    pos = contour.position
    he = 1e-5
    fd_eta = (pos(eta + he, xi) - pos(eta - he, xi)) / (2 * he)
    fd_xi = (pos(eta, xi + he) - pos(eta, xi - he)) / (2 * he)
    assert np.allclose(D[1], fd_eta, rtol=1e-6, atol=1e-8 * np.abs(D[1]).max())
    assert np.allclose(D[2], fd_xi, rtol=1e-6, atol=1e-8 * np.abs(D[2]).max())
    t_xi = lambda e, x: contour.evaluate(contour.new_point(), e, x).t_xi.copy()  # noqa: E731
    assert np.allclose(D[4], (t_xi(eta + he, xi) - t_xi(eta - he, xi)) / (2 * he), rtol=1e-5,
                       atol=1e-6 * np.abs(D[2]).max())
    assert np.allclose(D[5], (t_xi(eta, xi + he) - t_xi(eta, xi - he)) / (2 * he), rtol=1e-5,
                       atol=1e-6 * np.abs(D[2]).max())
    F = point.frame
    assert np.allclose(F.T @ F, np.eye(3), atol=1e-13) and np.isclose(np.linalg.det(F), 1.0)
    return point


def test_offset_frame_derivatives_equal_finite_differences():
    rng = np.random.default_rng(0)
    a, n0 = rng.normal(size=3), rng.normal(size=3)
    t, t2, n, Dt2, Dn = offset_frame(a, n0)
    assert np.allclose(np.column_stack([t, t2, n]).T @ np.column_stack([t, t2, n]), np.eye(3), atol=1e-14)
    h = 1e-6
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        p, m = offset_frame(a + e, n0), offset_frame(a - e, n0)
        assert np.allclose((p[2] - m[2]) / (2 * h), Dn[:, i], atol=1e-8)
        assert np.allclose((p[1] - m[1]) / (2 * h), Dt2[:, i], atol=1e-8)


@pytest.mark.filterwarnings("error")  # degree 4: no continuity warning
def test_band_on_the_undeformed_beam_is_its_top_face(beam, axis):
    band = FlexibleBand(axis, width=W, offset=H / 2)
    band.update(beam.q_init)
    point = band.new_point()
    for eta, xi in [(0.0, -W / 2), (0.5, 0.0), (0.8, 0.01), (1.0, W / 2)]:
        band.evaluate(point, eta, xi)
        assert np.allclose(point.r, [eta * L, H, W / 2 - xi], atol=1e-14)
        assert np.allclose(point.n, [0, 1, 0], atol=1e-14)


def test_band_kinematics_on_the_moving_deformed_beam(beam, axis):
    band = FlexibleBand(axis, width=W, offset=H / 2)
    q, u = moving_state(beam, np.random.default_rng(1), 3e-3)
    for eta, xi in [(0.3, 0.01), (0.77, -0.02)]:
        point = finite_difference_checks(band, beam, q, u, eta, xi)
        axis.update(q, u)
        neutral = axis.evaluate(axis.new_point(), eta)
        assert np.isclose(np.linalg.norm(point.r - neutral.r), np.hypot(H / 2, xi), rtol=1e-12)


def test_band_is_C2_on_a_degree_4_neutral_curve_and_C1_on_a_cubic(beam, axis):
    """At an interior knot, the central difference of r converges to r_η at O(h²) when
    r is C² there and only at O(h) when r_ηη jumps (degree 3: warned)."""
    q, u = moving_state(beam, np.random.default_rng(7), 3e-3)
    cubic = Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0))
    errors = {}
    for neutral in (axis, cubic):
        with pytest.warns(UserWarning, match="degree >= 4") if neutral is cubic else contextlib.nullcontext():
            band = FlexibleBand(neutral, W, H / 2)
        band.update(q, u)
        knot = neutral.space.eta.knots[neutral.space.eta.p + 3]
        t_eta = band.evaluate(band.new_point(), knot, 0.02).t_eta.copy()
        errors[neutral.space.eta.p] = [np.linalg.norm((band.position(knot + h, 0.02) - band.position(knot - h, 0.02))
                                                      / (2 * h) - t_eta) for h in (1e-3, 1e-4)]
    assert errors[4][1] < 0.02 * errors[4][0]  # O(h²): 100x smaller for 10x smaller h
    assert errors[3][1] > 0.05 * errors[3][0]  # O(h): a kink in r_η


def test_cylinder_is_round_outward_and_closed(beam, axis):
    cyl = FlexibleCylinder(axis, radius=0.02)
    q, u = moving_state(beam, np.random.default_rng(2), 3e-3)
    cyl.update(q, u)
    axis.update(q, u)
    point = cyl.new_point()
    for eta, phi in np.random.default_rng(3).uniform([0, 0], [1, 2 * np.pi], size=(8, 2)):
        cyl.evaluate(point, eta, phi)
        centre = axis.evaluate(axis.new_point(), eta)
        radial = point.r - centre.r
        assert np.isclose(np.linalg.norm(radial), 0.02, rtol=1e-12)
        assert abs(radial @ centre.t1) < 1e-12
        assert radial @ point.n > 0.99 * 0.02
    a = cyl.evaluate(point, 0.4, 0.0).derivs.copy()
    assert np.allclose(cyl.evaluate(point, 0.4, 2 * np.pi).derivs, a, atol=1e-14)
    finite_difference_checks(cyl, beam, q, u, 0.55, 1.3)


def test_bounding_boxes_contain_the_derived_contours(beam, axis):
    q, u = moving_state(beam, np.random.default_rng(4), 3e-3)
    for contour in (FlexibleBand(axis, W, H / 2), FlexibleCylinder(axis, 0.03)):
        contour.update(q, u)
        lo, hi = contour.bounding_box()
        pts = contour.sample(25, 9).reshape(-1, 3)
        assert (pts >= lo).all() and (pts <= hi).all()
        mesh = contour.to_trimesh(25, 9)
        assert len(mesh.vertices) == 25 * 9
    axis.update(beam.q_init)
    tube = axis.to_trimesh(20, 8, radius=0.01)
    assert len(tube.faces) == 2 * 19 * 8 and np.isclose(tube.bounds[1, 1] - tube.bounds[0, 1], 0.02, rtol=0.05)


def test_sphere_on_a_point_mass_and_on_a_spinning_rigid_body():
    mass = PointMass(0.5, position=(1.0, 2.0, 3.0), velocity=(0.1, -0.2, 0.3))
    ball = SphereContour(mass.point, 0.05)
    point = ball.evaluate(ball.new_point(), 0.3, -0.4, velocity=True, jacobians=True)
    assert np.isclose(np.linalg.norm(point.r - mass.q_init), 0.05)
    assert np.allclose(point.v, mass.u_init) and np.allclose(point.J_T, np.eye(3))
    body = RigidBody(2.0, np.diag([0.1, 0.2, 0.3]))
    q, u = body.q_init.copy(), np.random.default_rng(5).normal(size=6)
    q[3:7] = quat_from_rotvec([0.3, -1.2, 2.0])
    sphere = SphereContour(body.frame_at((0.1, 0.0, 0.0)), 0.2)
    finite_difference_checks(sphere, body, q, u, 1.1, 0.3)
    sphere.update(q, u)
    p = sphere.evaluate(sphere.new_point(), 1.1, 0.3)
    centre = body.frame_at((0.1, 0.0, 0.0)).position(q)
    assert np.allclose(p.r - centre, 0.2 * p.n, atol=1e-14)


def test_plane_on_the_ground_and_on_a_rigid_body():
    floor = PlaneContour(ground_frame((0, 0, -1.0)), size=2.0)
    point = floor.evaluate(floor.new_point(), 0.5, -0.25)
    assert np.allclose(point.r, [0.5, -0.25, -1.0]) and np.allclose(point.n, [0, 0, 1])
    assert np.isinf(floor.bounding_box()).all()
    body = RigidBody(1.0, np.eye(3) * 0.01)
    q, u = body.q_init.copy(), np.random.default_rng(6).normal(size=6)
    q[3:7] = quat_from_rotvec([1.0, 0.5, -0.2])
    finite_difference_checks(PlaneContour(body.origin), body, q, u, 0.3, -0.6)
    dot = PointContour(body.frame_at((0.2, 0.1, 0.0)))
    dot.update(q, u)
    p = dot.evaluate(dot.new_point(), velocity=True, jacobians=True)
    assert np.allclose(p.v, body.frame_at((0.2, 0.1, 0.0)).velocity(q, u)) and np.allclose(p.J_T @ u, p.v)


def test_bad_input(axis):
    with pytest.raises(ModelError, match="width"):
        FlexibleBand(axis, width=0.0)
    with pytest.raises(ModelError, match="radius"):
        FlexibleCylinder(axis, radius=-1.0)
    with pytest.raises(ModelError, match="1s neutral"):
        FlexibleBand(SphereContour(ground_frame(), 1.0), width=1.0)
