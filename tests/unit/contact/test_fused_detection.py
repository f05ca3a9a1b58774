"""The fused detection (mbs.run.fused_detection) against the Python path it replaces:
``contour.update`` of both contours, then ``Contact.locate`` — on two copies of the
default scene (its point, or a sphere on the same point mass; its 2s contour, its band, or
a curve along the top face's centre line) driven through the same
random deformed states (warm and cold starts, open, closed, apart by the broad phase,
outside the contour), and the choice of the path per contact in the Model."""

import numpy as np
import pytest

from centre_scenes import centre_scene as _scene
from contact import Contact, ContactKinematicsPointPlane, UnilateralNewtonImpact
from contours import PlaneContour, PointContour
from contours.neutral import _kernels as NK
from mbs import PointMass, System, ground_frame
from mbs.run.fused_detection import CentreOnNeutral1s, CentreOnNeutral2s, CentreOnOffset, fused_detection
from mbs.run.model import compile_model


def _python_locate(scene, q, u, t):
    """The reference: the two contours updated, then Contact.locate."""
    contact = scene.contact
    for contour in contact.contours():
        b = contour.body
        contour.update(q[b.q_slice], u[b.u_slice], t)
    return contact.locate()


def _states(scene, rng, n):
    """n global states (q, u): the beam deformed at random (nodal displacements up to
    ~1 mm) and the point (a sphere's surface) near a random point of the top surface —
    above it, pressed into it, high above (apart), beyond its edge — with random
    velocities; runs of small moves between jumps, so that Newton starts warm from the
    last contact point."""
    system, beam, mass = scene.system, scene.beam, scene.mass
    surface = scene.contact.kinematics.contour2
    radius = scene.contact.kinematics.radius
    q0, u0 = system.initial_state()
    (a, b), (c, d) = surface.domain if surface.dim == 2 else (surface.domain, (0.0, 0.0))
    scale = 1e-3 / np.abs(beam.phi_nodes).max() / beam.n_modes
    states = []
    eta, xi = 0.5 * (a + b), 0.5 * (c + d)
    for k in range(n):
        q, u = q0.copy(), u0.copy()
        q[beam.q_slice] = rng.normal(size=beam.nq) * scale
        u[beam.u_slice] = rng.normal(size=beam.nu)
        u[mass.u_slice] = rng.normal(size=3)
        if k % 5 == 0:                                  # a jump: a cold-ish start far from the last point
            eta, xi = rng.uniform(a, b), rng.uniform(c, d)
        else:                                           # a small move: warm start
            eta = min(b, max(a, eta + 0.01 * (b - a) * rng.normal()))
            xi = min(d, max(c, xi + 0.01 * (d - c) * rng.normal()))
        surface.update(q[beam.q_slice], u[beam.u_slice])
        p = surface.evaluate(surface.new_point(), eta, xi)
        kind = rng.choice(["above", "pressed", "far", "beyond", "above", "pressed"])
        if kind == "above":
            r = p.r + rng.uniform(0.0, 2e-3) * p.n
        elif kind == "pressed":
            r = p.r - rng.uniform(0.0, 1e-4) * p.n
        elif kind == "far":
            r = p.r + 1.0 * p.n
        else:
            r = p.r + (b - a) * p.t1 + 1e-3 * p.n
        q[mass.q_slice] = r + radius * p.n - mass.point.u0
        states.append((q, u, 1e-3 * k))
    return states


def _assert_same(fused_scene, python_scene, closed_f, closed_p):
    kf, kp = fused_scene.contact.kinematics, python_scene.contact.kinematics
    assert closed_f == closed_p
    assert kf.active == kp.active
    same = dict(rtol=1e-12, atol=1e-300)
    if kp.active:
        np.testing.assert_allclose(kf.g_N, kp.g_N, rtol=1e-12, atol=1e-18)
        if not fused_scene.contact.set_valued:
            np.testing.assert_allclose(kf.gd_N, kp.gd_N, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(kf.buffer, kp.buffer, **same)
        np.testing.assert_allclose(kf.point1.buffer, kp.point1.buffer, **same)
        np.testing.assert_allclose(kf.point2.buffer, kp.point2.buffer, **same)
        assert (kf.point2.eta, kf.point2.xi) == pytest.approx((kp.point2.eta, kp.point2.xi), rel=1e-12, abs=1e-15)
        assert (kf.point1.eta, kf.point1.xi) == pytest.approx((kp.point1.eta, kp.point1.xi), rel=1e-12, abs=1e-15)
        np.testing.assert_allclose(kf.centre, kp.centre, **same)
        np.testing.assert_array_equal(kf.axes1, kp.axes1)
    np.testing.assert_array_equal(np.isnan(kf.start), np.isnan(kp.start))
    np.testing.assert_allclose(kf.start, kp.start, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(kf.search.counts, kp.search.counts)
    neutral = lambda contour: getattr(contour, "neutral", contour)  # noqa: E731  (a band's state is its curve's)
    sf, sp = neutral(kf.contour2).kernel_data[-2], neutral(kp.contour2).kernel_data[-2]
    keep = np.arange(sf.size) != NK.STAMP_AT                 # the stamps count updates, not states
    np.testing.assert_array_equal(sf[keep], sp[keep])
    np.testing.assert_array_equal(kf.contour1.state, kp.contour1.state)


@pytest.mark.parametrize("law, side, contour", [("impact", "point", "2s"), ("penalty", "point", "2s"),
                                                ("impact", "sphere", "2s"), ("penalty", "sphere", "2s"),
                                                ("penalty", "point", "band"), ("impact", "sphere", "band"),
                                                ("impact", "point", "1s"), ("penalty", "sphere", "1s")])
def test_fused_detection_is_the_python_path(law, side, contour):
    """Warm and cold starts (a warm start dropped now and then, as a search that found
    nothing leaves it), open, closed, apart and outside the contour: the fused path
    leaves the same kinematics, contact points (a sphere's C1 with its coordinates),
    warm start, search counters and contour states as the Python path (to 1e-12), and
    says closed when it does."""
    fused_scene, python_scene = _scene(law, side, contour), _scene(law, side, contour)
    fused = fused_detection(fused_scene.contact)
    assert isinstance(fused, {"2s": CentreOnNeutral2s, "band": CentreOnOffset, "1s": CentreOnNeutral1s}[contour])
    rng = np.random.default_rng(19)
    outcomes = set()
    fallbacks = []
    python_locate = fused.contact.locate
    fused.contact.locate = lambda: fallbacks.append(1) or python_locate()
    states = _states(fused_scene, rng, 120)
    for i, (q, u, t) in enumerate(states):
        if i % 20 == 10:                                 # a lost contact point: both start cold
            for scene in (fused_scene, python_scene):
                scene.contact.kinematics.start[:] = np.nan
        closed_f = fused.locate(q, u, t)
        closed_p = _python_locate(python_scene, q, u, t)
        _assert_same(fused_scene, python_scene, closed_f, closed_p)
        outcomes.add((closed_p, python_scene.contact.kinematics.active))
    assert outcomes == {(True, True), (False, True), (False, False)}
    assert 0 < len(fallbacks) < len(states) // 3          # mostly the kernel's own work
    search = python_scene.contact.kinematics.search
    assert search.coarse_searches > 1 and search.newton_solves > search.coarse_searches


def test_fused_contour_products_follow_the_state():
    """The neutral contour's control-point products, synced on demand, follow a state the
    fused kernel wrote (its stamp): the position field equals the Python path's."""
    fused_scene, python_scene = _scene("impact"), _scene("impact")
    fused = fused_detection(fused_scene.contact)
    for q, u, t in _states(fused_scene, np.random.default_rng(5), 12):
        fused.locate(q, u, t)
        _python_locate(python_scene, q, u, t)
        sf, sp = fused_scene.contact.kinematics.contour2, python_scene.contact.kinematics.contour2
        np.testing.assert_allclose(sf.position_field.ctrl, sp.position_field.ctrl, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(sf.velocity_field.ctrl, sp.velocity_field.ctrl, rtol=1e-12, atol=1e-12)


def test_the_model_fuses_the_pairs_that_have_a_kernel():
    """The default scene's contact (2s or band) has a fused detection and its contours are
    left to it by the contour stage; a point on a plane keeps the Python path (the contour
    stage updates both its contours)."""
    for contour, kind in (("2s", CentreOnNeutral2s), ("band", CentreOnOffset)):
        scene = _scene("impact", contour=contour)
        model = compile_model(scene.system, scene.system.plan(0.01))
        assert isinstance(model.fused[0], kind)
        assert model.owners.size == 0 and np.all(model.owner_at == 0)
    system = System(gravity=(0.0, 0.0, -9.81))
    mass = system.add(PointMass(1.0, position=(0.0, 0.0, 0.1)))
    system.add(Contact(ContactKinematicsPointPlane(PointContour(mass.point), PlaneContour(ground_frame())),
                       UnilateralNewtonImpact(0.5)))
    model = compile_model(system, system.plan(0.01))
    assert model.fused == (None,)
    assert model.owners.size == len(model.contours) == 2
