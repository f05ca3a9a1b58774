"""The fused detection (mbs.run.fused_detection) against the Python path it replaces:
``contour.update`` of both contours, then ``Contact.locate`` — on two copies of the
default scene (its point, or a sphere on the same point mass; its 2s contour, its band, or
a curve along the top face's centre line) driven through the same
random deformed states (warm and cold starts, open, closed, apart by the broad phase,
outside the contour); the analytic pairs (a point or a sphere on a plane or a sphere) on
point masses, rigid bodies and the ground through random states; and the choice of the
path per contact in the Model."""

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from centre_scenes import centre_scene as _scene
from contact import (Contact, ContactKinematicsPointPlane, CurveConstraint,
                     LinearRegularizedUnilateralConstraint, PointOnCurveConstraint, UnilateralNewtonImpact, connect)
from contours import (Contour1sNeutralFFR, Contour1sNeutralRigid, Contour2sNeutralFFR, Contour2sNeutralRigid,
                      FlexibleBand, PlaneContour, PointContour, SphereContour)
from contours.neutral import _kernels as NK
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, RigidBody, System, ground_frame
from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix
from ffrmbs.errors import ModelError
from mbs.run.fused_detection import (CentreOnNeutral1s, CentreOnNeutral2s, CentreOnOffset, CentreOnPlane,
                                     PointKeptOnCurve, SphereOnSphere, fused_detection)
from mbs.run import _fused_detection_kernels as K
from mbs.run.model import compile_model
from validation.bench.common import moving_state


def _python_locate(scene, q, u, t):
    """The reference: the two contours updated, then Contact.locate."""
    contact = scene.contact
    for contour in contact.contours():
        b = contour.body
        contour.update(q[b.q_slice], u[b.u_slice], t)
    return contact.locate()


def _states(scene, rng, n, body_state=None):
    """n global states (q, u, t): the surface's body at ``body_state(rng, k)`` = (q_b, u_b,
    t) (default: the beam deformed at random, nodal displacements up to ~1 mm, random
    rates, t = k ms) and the point (a sphere's surface) near a random point of the
    surface — above it, pressed into it, high above (apart), beyond its edge — with
    random velocities; runs of small moves between jumps, so that Newton starts warm
    from the last contact point."""
    system, mass = scene.system, scene.mass
    surface = scene.contact.kinematics.contour2
    body = surface.body
    radius = scene.contact.kinematics.radius
    q0, u0 = system.initial_state()
    (a, b), (c, d) = surface.domain if surface.dim == 2 else (surface.domain, (0.0, 0.0))
    if body_state is None:
        scale = 1e-3 / np.abs(body.phi_nodes).max() / body.n_modes
        body_state = lambda rng, k: (rng.normal(size=body.nq) * scale, rng.normal(size=body.nu),  # noqa: E731
                                     1e-3 * k)
    states = []
    eta, xi = 0.5 * (a + b), 0.5 * (c + d)
    for k in range(n):
        q, u = q0.copy(), u0.copy()
        q[body.q_slice], u[body.u_slice], t = body_state(rng, k)
        u[mass.u_slice] = rng.normal(size=mass.nu)
        if k % 5 == 0:                                  # a jump: a cold-ish start far from the last point
            eta, xi = rng.uniform(a, b), rng.uniform(c, d)
        else:                                           # a small move: warm start
            eta = min(b, max(a, eta + 0.01 * (b - a) * rng.normal()))
            xi = min(d, max(c, xi + 0.01 * (d - c) * rng.normal()))
        surface.update(q[body.q_slice], u[body.u_slice], t)
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
        q[mass.q_slice][:3] = r + radius * p.n - scene.contact.kinematics.contour1.frame_ref.u0   # side 1 unturned
        states.append((q, u, t))
    return states


def _both_routes(fused, fused_scene, python_scene, states):
    """Each state located by ``fused`` and by the Python path of ``python_scene`` (every
    20th from index 10 with both warm starts lost: a cold start), asserted the same
    (:func:`_assert_same`); returns ({(closed, active)} seen, the fused route's fallbacks
    to the Python path)."""
    fallbacks = []
    python_locate = fused.contact.locate
    fused.contact.locate = lambda: fallbacks.append(1) or python_locate()
    outcomes = set()
    for i, (q, u, t) in enumerate(states):
        if i % 20 == 10:
            for scene in (fused_scene, python_scene):
                scene.contact.kinematics.start[:] = np.nan
        closed_f = fused.locate(q, u, t)
        closed_p = _python_locate(python_scene, q, u, t)
        _assert_same(fused_scene, python_scene, closed_f, closed_p)
        outcomes.add((closed_p, python_scene.contact.kinematics.active))
    return outcomes, len(fallbacks)


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
                                                ("impact", "point", "1s"), ("penalty", "sphere", "1s"),
                                                ("penalty", "sphere", "edge")])
def test_fused_detection_is_the_python_path(law, side, contour):
    """Warm and cold starts (a warm start dropped now and then, as a search that found
    nothing leaves it), open, closed, apart and outside the contour: the fused path
    leaves the same kinematics, contact points (a sphere's C1 with its coordinates),
    warm start, search counters and contour states as the Python path (to 1e-12), and
    says closed when it does."""
    fused_scene, python_scene = _scene(law, side, contour), _scene(law, side, contour)
    fused = fused_detection(fused_scene.contact)
    assert isinstance(fused, {"2s": CentreOnNeutral2s, "band": CentreOnOffset, "1s": CentreOnNeutral1s,
                              "edge": CentreOnNeutral1s}[contour])
    states = _states(fused_scene, np.random.default_rng(19), 120)
    outcomes, fallbacks = _both_routes(fused, fused_scene, python_scene, states)
    assert outcomes == {(True, True), (False, True), (False, False)}
    assert 0 < fallbacks < len(states) // 3          # mostly the kernel's own work
    search = python_scene.contact.kinematics.search
    assert search.coarse_searches > 1 and search.newton_solves > search.coarse_searches


MOVING = {     # case: (the surface's body, contour kind, side 1)
    "2s on a spinning beam, point": ("spinning", "2s", "point"),
    "2s on a free beam, sphere": ("free", "2s", "sphere"),
    "band on a free beam, point": ("free", "band", "point"),
    "1s on a spinning beam, sphere": ("spinning", "1s", "sphere"),
    "2s on a rigid body, point": ("rigid", "2s", "point"),
    "1s on a rigid body, sphere": ("rigid", "1s", "sphere"),
    "2s on a spinning beam, sphere on a rigid body": ("spinning", "2s", "rigid sphere"),
    "band on a free beam, point on a rigid body": ("free", "band", "rigid point"),
}


def _moving_scene(data, case, law):
    """A point mass's point or a sphere of 10 mm about it (or about a point of a rigid
    body) against a contour of a moving body (:data:`MOVING`): the thesis beam's top face,
    its band or its centre line on a frame spun up about z (ω = 20 rad/s after 10 ms) or
    free, or a curved 2s or 1s contour on a rigid body."""
    frame, kind, side = MOVING[case]
    system = System()
    if frame == "rigid":
        body = system.add(RigidBody(2.0, np.diag([0.01, 0.02, 0.03]), name="block"))
        x = np.linspace(-0.1, 0.1, 7)
        if kind == "2s":
            X, Y = np.meshgrid(x, x, indexing="ij")
            surface = Contour2sNeutralRigid(body, np.stack((X, Y, 0.3 * (X ** 2 - Y ** 2)), axis=-1), outward=1)
        else:
            surface = Contour1sNeutralRigid(body, np.stack((x, 0.2 * x ** 2, 0 * x), axis=-1), normal=(0, 1, 0))
    else:
        motion = PrescribedFrameMotion.spin_up(20.0, 0.01) if frame == "spinning" else "free"
        body = system.add(FlexibleBodyFFR(data, modes=8, frame=motion, name="beam"))
        if kind == "2s":
            surface = Contour2sNeutralFFR(body, "y1")
        else:
            surface = Contour1sNeutralFFR.along_line(body, (0.0, 0.05, 0.025), (1, 0, 0), normal=(0, 1, 0), degree=4)
            if kind == "band":
                surface = FlexibleBand(surface, width=0.05, offset=0.0)
    if side.startswith("rigid"):
        mass = system.add(RigidBody(0.5, np.diag([1e-3, 2e-3, 3e-3]), name="ball"))
        at = mass.frame_at((0.01, -0.02, 0.005))
    else:
        mass = system.add(PointMass(0.5, name="mass"))
        at = mass.point
    point = PointContour(at) if side.endswith("point") else SphereContour(at, 0.01)
    law = UnilateralNewtonImpact(0.0) if law == "impact" else LinearRegularizedUnilateralConstraint(1e4, 10.0)
    contact = system.add(connect(point, surface, law, name=case))
    return SimpleNamespace(system=system, mass=mass, contact=contact, body=body, frame=frame)


def _moving_body_state(scene):
    """body_state of :func:`_states` for the moving body of a :func:`_moving_scene`: a free
    beam by :func:`validation.bench.common.moving_state`, a spinning one deformed at t up
    to 50 ms, a rigid body turned and moving at random."""
    body = scene.body
    if scene.frame == "free":
        return lambda rng, k: (*moving_state(body, rng, 1e-3), 1e-3 * k)
    if scene.frame == "spinning":
        scale = 1e-3 / np.abs(body.phi_nodes).max() / body.n_modes
        return lambda rng, k: (rng.normal(size=body.nq) * scale, rng.normal(size=body.nu), rng.uniform(0.0, 0.05))
    return lambda rng, k: (np.r_[0.1 * rng.normal(size=3), quat_from_rotvec(rng.normal(size=3))],
                           rng.normal(size=6), 1e-3 * k)


@pytest.mark.parametrize("law", ["impact", "penalty"])
@pytest.mark.parametrize("case", list(MOVING))
def test_fused_detection_on_a_moving_frame_is_the_python_path(thesis_beam_data, case, law):
    """A surface on a moving body — a prescribed spin, a free frame (its J_T and J_R have
    the frame's columns), a rigid body's neutral contour: the fused detection (the
    surface's update in Python, the rest in the kernel; a free quaternion frame all in the
    kernel) leaves what the Python path leaves,
    through warm and cold starts, open, closed, apart and outside the contour."""
    fused_scene, python_scene = _moving_scene(thesis_beam_data, case, law), _moving_scene(thesis_beam_data, case, law)
    fused = fused_detection(fused_scene.contact)
    kind = MOVING[case][1]
    assert isinstance(fused, {"2s": CentreOnNeutral2s, "band": CentreOnOffset, "1s": CentreOnNeutral1s}[kind])
    in_kernel = MOVING[case][0] in ("free", "rigid")        # a free quaternion frame: the kernel's
    assert not fused._before if in_kernel and "rigid" not in MOVING[case][2] else fused._before
    assert (fused.probe() is None) == bool(fused._before)    # else the recorder takes the Python path
    states = _states(fused_scene, np.random.default_rng(29), 80, _moving_body_state(fused_scene))
    outcomes, fallbacks = _both_routes(fused, fused_scene, python_scene, states)
    assert {(True, True), (False, True)} <= outcomes
    assert fallbacks < len(states) // 3           # mostly the kernel's own work
    kp = python_scene.contact.kinematics
    if MOVING[case][0] != "spinning":
        assert np.abs(kp.point2.J_R).max() > 0.1          # a free frame's rotation columns took part


def test_fused_detection_of_a_point_kept_on_a_curve_is_the_python_path():
    """A point kept on a curve (a bilateral CurveConstraint: the default scene's point on
    the top face's centre line): the fused detection leaves the kinematics and the gaps g
    that the Python path leaves, and the point beyond the curve's end is the Python
    path's error."""
    scenes = []
    for _ in range(2):
        scene = _scene("impact", "point", "1s")
        k = scene.contact.kinematics
        element = CurveConstraint(PointOnCurveConstraint(k.contour1, k.contour2), name="kept on the curve")
        contacts = scene.system.contacts
        contacts[contacts.index(scene.contact)] = element
        scenes.append(dataclasses.replace(scene, contact=element))
    fused_scene, python_scene = scenes
    fused = fused_detection(fused_scene.contact)
    assert type(fused) is PointKeptOnCurve
    left = 0
    for i, (q, u, t) in enumerate(_states(fused_scene, np.random.default_rng(31), 100)):
        if i % 20 == 10:
            for scene in scenes:
                scene.contact.kinematics.start[:] = np.nan
        try:
            closed_f = fused.locate(q, u, t)
        except ModelError as fault:
            with pytest.raises(ModelError, match=str(fault)):
                _python_locate(python_scene, q, u, t)
            left += 1
            continue
        assert closed_f and _python_locate(python_scene, q, u, t)
        _assert_same(fused_scene, python_scene, closed_f, True)
        np.testing.assert_allclose(fused_scene.contact.kinematics.g, python_scene.contact.kinematics.g,
                                   rtol=1e-12, atol=1e-18)
    assert left > 0                                   # a point beyond the curve's end left it


@pytest.fixture(scope="module")
def plate_hole_data():
    """The validation case contact_hole's plate with its 12 mm hole, tet4 at 6 mm, bottom
    clamped, 2 modes: its top face is fitted and trimmed."""
    from preprocess import build_body
    from validation.cases import contact_hole as case

    return build_body(case.plate_hole_mesh(0.006, order=1), case.STEEL, n_modes=2, clamp="bottom")


def _trimmed_scene(data):
    from validation.cases import contact_hole as case

    system = System(gravity=(0.0, 0.0, -case.G))
    plate = system.add(FlexibleBodyFFR(data, modes=2, frame=PrescribedFrameMotion.fixed(), name="plate"))
    ball = system.add(PointMass(case.BALL_MASS, position=(*case.BESIDE, 0.1), name="ball"))
    face = system.add(connect(SphereContour(ball.point, case.BALL_RADIUS), Contour2sNeutralFFR(plate, "top"),
                              "impact", name="face"))
    return SimpleNamespace(system=system, mass=ball, contact=face)


@pytest.mark.filterwarnings("ignore:neutral 2s.*fitted to within")     # the coarse mesh's mode 2: not the point here
def test_fused_detection_on_a_trimmed_face_is_the_python_path(plate_hole_data):
    """A ball over a face with a hole — on the material, over the hole (no contact point:
    the kernel falls back and the Python path keeps the hole as the next warm start),
    back on the material (the hole forgotten): the fused detection leaves what the Python
    path leaves, the search's hole included."""
    fused_scene, python_scene = _trimmed_scene(plate_hole_data), _trimmed_scene(plate_hole_data)
    assert fused_scene.contact.kinematics.contour2.trim is not None
    fused = fused_detection(fused_scene.contact)
    assert isinstance(fused, CentreOnNeutral2s)
    fallbacks = []
    python_locate = fused.contact.locate
    fused.contact.locate = lambda: fallbacks.append(1) or python_locate()
    outcomes = set()
    from validation.cases import contact_hole as case

    rng = np.random.default_rng(37)
    states = _states(fused_scene, rng, 150)
    (hx, hy, radius), lz = case.HOLE, case.PLATE[2]
    for k in range(5, len(states), 10):              # runs of states over the hole
        for q, _, _ in states[k:k + 3]:
            q[fused_scene.mass.q_slice] = (hx + 0.3 * radius * rng.normal(), hy + 0.3 * radius * rng.normal(),
                                           lz + case.BALL_RADIUS + 1e-3)
    for q, u, t in states:
        closed_f = fused.locate(q, u, t)
        closed_p = _python_locate(python_scene, q, u, t)
        _assert_same(fused_scene, python_scene, closed_f, closed_p)
        hf, hp = fused_scene.contact.kinematics.search.hole, python_scene.contact.kinematics.search.hole
        np.testing.assert_array_equal(np.isnan(hf), np.isnan(hp))
        np.testing.assert_allclose(hf, hp, rtol=1e-12, atol=1e-15)
        outcomes.add((closed_p, python_scene.contact.kinematics.active, bool(np.isnan(hp[0]))))
    assert {(True, True, True), (False, True, True), (False, False, False)} <= outcomes   # ... the last: in the hole
    assert 0 < len(fallbacks) < len(states) // 2


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
    """The default scene's contact (2s or band) and a point on a plane have a fused
    detection and their contours are left to it by the contour stage; a point on a rigid
    body's 2s contour built for the reference route (``compiled=False``) keeps the Python
    path (the contour stage updates both its contours)."""
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
    assert isinstance(model.fused[0], CentreOnPlane)
    assert model.owners.size == 0 and len(model.contours) == 2
    table = system.add(RigidBody(1.0, np.eye(3), name="table"))
    x = np.linspace(-0.1, 0.1, 5)
    grid = np.stack(np.meshgrid(x, x, [0.0], indexing="ij"), axis=-1)[:, :, 0]
    system.add(connect(PointContour(mass.point), Contour2sNeutralRigid(table, grid, outward=1, compiled=False),
                       "impact"))
    model = compile_model(system, system.plan(0.01))
    assert model.fused[1] is None
    assert model.owner_at.tolist() == [0, 0, 0, 1, 2]   # the plane's contact's contours: none; the table's: its
    assert model.owners.tolist() == [1, 1]


# --- the analytic pairs: a point or a sphere on a plane, two spheres --------------------------------------

TILT = quat_to_matrix(quat_from_rotvec([0.3, -0.2, 0.5]))      # a tilted ground plane's axes
ANALYTIC = {    # case: (side 1, side 2) as (contour kind, body: "mass", "ball" (rigid), "slab" (rigid), "ground")
    "point/mass on ground plane": (("point", "mass"), ("plane", "ground")),
    "sphere/mass on ground plane": (("sphere", "mass"), ("plane", "ground")),
    "sphere/ball on slab plane": (("sphere", "ball"), ("plane", "slab")),
    "point/mass on plane/mass": (("point", "mass"), ("plane", "mass2")),
    "sphere/mass on sphere/mass": (("sphere", "mass"), ("sphere", "mass2")),
    "sphere/ball on sphere/mass": (("sphere", "ball"), ("sphere", "mass2")),
    "sphere/mass on ground sphere": (("sphere", "mass"), ("sphere", "ground")),
    "point/mass on sphere/ball": (("point", "mass"), ("sphere", "ball")),
}
RADII = {"mass": 0.02, "mass2": 0.05, "ball": 0.03, "ground": 0.04}     # [m]


def _analytic_scene(case, law):
    """A System of two point masses and two rigid bodies with the contact of ``case``
    (:data:`ANALYTIC`) under ``law`` ("impact": no velocity asked; "penalty": with it)."""
    system = System()
    bodies = {"mass": system.add(PointMass(0.3, name="mass")), "mass2": system.add(PointMass(0.5, name="mass2")),
              "ball": system.add(RigidBody(1.0, np.diag([0.1, 0.2, 0.3]), name="ball")),
              "slab": system.add(RigidBody(2.0, np.diag([0.3, 0.2, 0.1]), name="slab"))}
    frames = {"mass": bodies["mass"].point, "mass2": bodies["mass2"].point, "ball": bodies["ball"].frame_at((0.1, -0.05, 0.02)),
              "slab": bodies["slab"].origin, "ground": ground_frame((0.1, -0.2, 0.3), TILT)}
    contours = []
    for kind, owner in ANALYTIC[case]:
        frame = frames[owner]
        contours.append({"point": lambda: PointContour(frame), "plane": lambda: PlaneContour(frame),
                         "sphere": lambda: SphereContour(frame, RADII[owner])}[kind]())
    law = UnilateralNewtonImpact(0.5) if law == "impact" else LinearRegularizedUnilateralConstraint(1e4, 10.0)
    contact = system.add(connect(*contours, law, name=case))
    return system, bodies, contact


def _analytic_states(system, bodies, contact, rng, n):
    """n global states: the rigid bodies turned and moving at random, side 1's centre
    placed at a random distance from side 2 (pressed in, just apart, far apart: separated
    by the broad phase of two spheres), now and then on the other sphere's centre (no
    normal)."""
    k = contact.kinematics
    radii = k.radius + getattr(k.contour2, "radius", 0.0)
    distances = {"pressed": 0.9 * radii - 1e-3, "apart": radii + 2e-3, "far": radii + 1.0, "centre": 0.0}
    states = []
    for i in range(n):
        q, u = system.initial_state()
        for body in bodies.values():
            qs, us = q[body.q_slice], u[body.u_slice]
            qs[:3] = 0.1 * rng.normal(size=3)
            if body.nq == 7:
                qs[3:7] = quat_from_rotvec(rng.normal(size=3))
            us[:] = rng.normal(size=body.nu)
        side2 = k.contour2
        body2 = side2.body
        side2.update(None if body2 is None else q[body2.q_slice], None if body2 is None else u[body2.u_slice])
        origin, axes = side2.state[:3], side2.state[3:12].reshape(3, 3)
        if isinstance(side2, PlaneContour):        # above (or now and then below) a point of the plane
            target = origin + axes[:, :2] @ rng.normal(size=2) * 0.05
            direction = axes[:, 2] * rng.choice([1.0, -1.0], p=[0.8, 0.2])
        else:                                       # about the sphere's centre
            target = origin.copy()
            direction = rng.normal(size=3)
            direction /= np.linalg.norm(direction)
        centre = target + distances[rng.choice(list(distances), p=[0.4, 0.35, 0.15, 0.1])] * direction
        frame1 = k.contour1.frame_ref
        qs = q[frame1.body.q_slice]
        A = np.eye(3) if frame1.body.nq == 3 else quat_to_matrix(qs[3:7])
        qs[:3] = centre - A @ frame1.u0
        states.append((q, u, 1e-3 * i))
    return states


def _python_locate_analytic(contact, q, u, t):
    for contour in contact.contours():
        b = contour.body
        contour.update(None if b is None else q[b.q_slice], None if b is None else u[b.u_slice], t)
    return contact.locate()


@pytest.mark.parametrize("law", ["impact", "penalty"])
@pytest.mark.parametrize("case", list(ANALYTIC))
def test_the_analytic_fused_detections_are_the_python_path(case, law):
    """Closed, open, apart by the broad phase and (two spheres) without a normal: the fused
    detection of a point or a sphere on a plane or on a sphere — on point masses, rigid
    bodies (their contours updated in Python) and the ground — leaves the same
    kinematics, contact points and contour states as the Python path (to 1e-12)."""
    fused_sys, fused_bodies, fused_contact = _analytic_scene(case, law)
    python_sys, _, python_contact = _analytic_scene(case, law)
    fused = fused_detection(fused_contact)
    assert isinstance(fused, SphereOnSphere if ANALYTIC[case][1][0] == "sphere" else CentreOnPlane)
    outcomes = set()
    for q, u, t in _analytic_states(fused_sys, fused_bodies, fused_contact, np.random.default_rng(23), 80):
        closed_f = fused.locate(q, u, t)
        closed_p = _python_locate_analytic(python_contact, q, u, t)
        kf, kp = fused_contact.kinematics, python_contact.kinematics
        assert closed_f == closed_p and kf.active == kp.active
        outcomes.add((closed_p, kp.active))
        same = dict(rtol=1e-12, atol=1e-15)
        if kp.active:
            np.testing.assert_allclose(kf.g_N, kp.g_N, **same)
            if law == "penalty":
                np.testing.assert_allclose(kf.gd_N, kp.gd_N, **same)
            for a, b in ((kf.buffer, kp.buffer), (kf.point1.buffer, kp.point1.buffer),
                         (kf.point2.buffer, kp.point2.buffer), (kf.centre, kp.centre), (kf.axes1, kp.axes1)):
                np.testing.assert_allclose(a, b, **same)
            assert (kf.point1.eta, kf.point1.xi, kf.point2.eta, kf.point2.xi) == pytest.approx(
                (kp.point1.eta, kp.point1.xi, kp.point2.eta, kp.point2.xi), rel=1e-12, abs=1e-15)
            if hasattr(kp, "axes2"):
                np.testing.assert_array_equal(kf.axes2, kp.axes2)
        for cf, cp in zip(fused_contact.contours(), python_contact.contours()):
            np.testing.assert_allclose(cf.state, cp.state, **same)
    expected = {(True, True), (False, True)}
    if ANALYTIC[case][1][0] == "sphere":
        expected.add((False, False))                 # coincident centres: no normal
    assert expected <= outcomes


# --- a point at a node of a flexible body: its frame written by the kernel ---------------------------------

@pytest.mark.parametrize("frame", ["free", "fixed"])
@pytest.mark.parametrize("surface", ["plane", "2s"])
def test_a_point_at_a_node_has_its_frame_written_by_the_kernel_as_its_update_writes_it(thesis_beam_data, frame,
                                                                                           surface):
    """A point at a node of a flexible body — on a free quaternion frame turned, moving and
    deformed at random, or on a frame at rest — against the ground plane or the top face of
    another beam: the fused detection writes the point contour's state (r, A, ṙ, ω, J_T, J_R)
    itself, no update in Python before it, and it equals the contour's own update (to 1e-12);
    the kinematics too."""
    def scene():
        system = System()
        motion = "free" if frame == "free" else PrescribedFrameMotion.fixed(R=(0.1, 0.0, 0.3), A=TILT)
        rod = system.add(FlexibleBodyFFR(thesis_beam_data, modes=6, frame=motion, name="rod"))
        if surface == "plane":
            other = PlaneContour(ground_frame((0.0, 0.0, 0.0), TILT))
        else:
            beam = system.add(FlexibleBodyFFR(thesis_beam_data, modes=6, frame=PrescribedFrameMotion.fixed(),
                                              name="beam"))
            other = Contour2sNeutralFFR(beam, "y1")
        point = PointContour(rod.node(int(rod.node_group("x1")[3])))
        return system, rod, system.add(connect(point, other, UnilateralNewtonImpact(0.0)))

    system, rod, contact = scene()
    _, _, reference = scene()
    fused = fused_detection(contact)
    assert fused._before == [] and fused._itab[K.NODE_Q] == rod.q_slice.start
    rng = np.random.default_rng(5)
    for _ in range(20):
        q, u = system.initial_state()
        qr, ur = q[rod.q_slice], u[rod.u_slice]
        ur[:] = rng.normal(size=rod.nu)
        qr[rod.q_f_slice] = 1e-3 * rng.normal(size=rod.n_modes)
        if frame == "free":
            qr[:3], qr[3:7] = 0.1 * rng.normal(size=3), quat_from_rotvec(rng.normal(size=3))
        fused.locate(q, u, 0.0)
        reference.kinematics.contour1.update(qr, ur, 0.0)
        np.testing.assert_allclose(contact.kinematics.contour1.state, reference.kinematics.contour1.state,
                                   rtol=1e-12, atol=1e-15)
