"""The planned broad phase and the step's bookkeeping as kernels (mbs.run.bounding_spheres,
mbs.run._sphere_kernels, mbs.run._stage_kernels, the point-mass kernels of mbs.run.body_stage)
against their plain-Python references: the sphere callables and the pair test
d·d > (r1 + r2 + margin)², list comprehensions, the System's assembly."""

import numpy as np
import pytest

from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact
from contours import PointContour
from contours import CONTOURS
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, RigidBody, System
from mbs.run import _stage_kernels as SK
from mbs.run.body_stage import BodyStage
from mbs.run.bounding_spheres import GroundPlane, SphereTable, contour_sphere, live_pair, sphere_pair


def far_pairs_scene(n):
    """The default scene with n point masses, each in a contact with the beam's top face."""
    from ffrmbs_app.scenes import point_mass_beam as pmb

    scene = pmb.build("A", modes=20)
    system = scene.system
    surface = scene.contact.kinematics.contour2
    for k in range(n):
        mass = system.add(PointMass(0.1, position=(0.0, 0.2 + 0.1 * k, 0.0), name=f"far{k}"))
        system.add(Contact(ContactKinematicsPointContour2s(PointContour(mass.point), surface),
                           UnilateralNewtonImpact(0.0), name=f"far contact {k}"))
    return system


def reference_prune(contacts, q, t):
    """live flags of the prunable contacts by the sphere callables, pair by pair
    (:func:`live_pair`: the distance of the centres, or of a centre from a plane)."""
    return {i: live_pair(*pair, c.margin + c.closing_tol, q, t)
            for i, c in enumerate(contacts) if (pair := sphere_pair(c)) is not None}


@pytest.mark.parametrize("seed", range(4))
def test_sphere_table_prunes_as_the_sphere_callables(seed):
    system = far_pairs_scene(6)
    contacts = list(system.contacts)
    table = SphereTable(contacts)
    assert len(table) == len(contacts)
    assert len(table.spheres) == 1 + len(contacts)           # the beam's sphere once
    rng = np.random.default_rng(seed)
    q, _ = system.initial_state()
    beam = system.bodies[0]
    q[beam.q_slice] = 1e-3 * rng.normal(size=beam.nq)
    for b in system.bodies[1:]:
        q[b.q_slice] = rng.normal(scale=0.2, size=3)
    centres, radii = np.zeros((len(table.spheres), 3)), np.zeros(len(table.spheres))
    live, closed = np.ones(len(contacts), dtype=bool), np.ones(len(contacts), dtype=bool)
    table.start(q, 0.0, centres, radii)
    live_idx = np.full(len(contacts), -1, dtype=np.intp)
    pruned, n_live = table.prune(q, 0.0, centres, radii, live, closed, live_idx)
    ref = reference_prune(contacts, q, 0.0)
    assert live.tolist() == [ref[i] for i in range(len(contacts))]
    assert pruned == sum(not v for v in ref.values())
    assert live_idx[:n_live].tolist() == [i for i in range(len(contacts)) if ref[i]]
    assert not closed[~live].any() and closed[live].all()
    for s, sphere in enumerate(table.spheres):
        c, r = sphere(q, 0.0)
        np.testing.assert_allclose(centres[s], c, rtol=1e-15, atol=1e-15)
        assert abs(radii[s] - r) <= 1e-14 * r


@pytest.mark.parametrize("seed", range(4))
def test_free_bodies_spheres_are_compiled_and_equal_the_callables(seed, thesis_beam_data):
    """A free flexible beam (quaternion frame), a sphere on a rigid ball (quaternion) and
    one on a rigid ball with Cardan angles, each against the beam's top face and the
    other ball, turned and moved at random: the table computes the quaternion frames'
    spheres in its kernel (FREE), the Cardan ball's by its callable, all equal to the
    callables, and prunes as they do."""
    from contact import connect
    from contours import Contour2sNeutralFFR, SphereContour
    from mbs import FlexibleBodyFFR
    from mbs.bodies.rotations import quat_from_rotvec
    from mbs.run import _sphere_kernels as K

    system = System()
    beam = system.add(FlexibleBodyFFR(thesis_beam_data, modes=8, name="beam"))
    top = Contour2sNeutralFFR(beam, "y1")
    balls = [system.add(RigidBody(1.0, 0.01 * np.eye(3), rotation=rotation, name=f"ball {rotation}"))
             for rotation in ("quaternion", "cardan")]
    spheres = [SphereContour(ball.frame_at((0.01, -0.02, 0.03)), 0.02) for ball in balls]
    for sphere in spheres:
        system.add(connect(sphere, top, "impact"))
    system.add(connect(spheres[0], SphereContour(balls[1].origin, 0.03), "impact"))
    contacts = list(system.contacts)
    table = SphereTable(contacts)
    assert sorted(table.kind.tolist()) == [K.CALLED, K.CALLED, K.FREE, K.FREE]   # the Cardan ball's two
    rng = np.random.default_rng(seed)
    q, _ = system.initial_state()
    q[beam.q_slice][:3] = 0.05 * rng.normal(size=3)
    q[beam.q_slice][3:7] = quat_from_rotvec(rng.normal(size=3))
    q[beam.q_slice][7:] = 1e-4 * rng.normal(size=beam.n_modes)
    q[balls[0].q_slice][:3] = 0.1 * rng.normal(size=3)
    q[balls[0].q_slice][3:7] = quat_from_rotvec(rng.normal(size=3))
    q[balls[1].q_slice] = np.r_[0.1 * rng.normal(size=3), rng.normal(size=3)]
    n = len(table.spheres)
    centres, radii = np.zeros((n, 3)), np.zeros(n)
    live, closed = np.ones(len(contacts), dtype=bool), np.ones(len(contacts), dtype=bool)
    table.start(q, 0.0, centres, radii)
    live_idx = np.full(len(contacts), -1, dtype=np.intp)
    table.prune(q, 0.0, centres, radii, live, closed, live_idx)
    for s, sphere in enumerate(table.spheres):
        c, r = sphere(q, 0.0)
        np.testing.assert_allclose(centres[s], c, rtol=1e-14, atol=1e-15)
        assert abs(radii[s] - r) <= 1e-14 * r
    ref = reference_prune(contacts, q, 0.0)
    assert live.tolist() == [ref[i] for i in range(len(contacts))]


@pytest.mark.parametrize("seed", range(4))
def test_stage_kernels_equal_their_references(seed):
    rng = np.random.default_rng(seed)
    n_contacts, n_contours = 7, 5
    owners = [sorted(rng.choice(n_contacts, size=rng.integers(1, 3), replace=False).tolist())
              for _ in range(n_contours)]
    owner_at = np.cumsum([0] + [len(o) for o in owners]).astype(np.int64)
    flat = np.array([i for o in owners for i in o], dtype=np.int64)
    live = rng.random(n_contacts) < 0.5
    out = np.zeros(n_contours, dtype=np.intp)
    n = SK.contours_in_use(owner_at, flat, live, out)
    assert out[:n].tolist() == [k for k in range(n_contours) if any(live[i] for i in owners[k])]
    out = np.zeros(n_contacts, dtype=np.intp)
    n = SK.live_contacts(live, out)
    assert out[:n].tolist() == np.flatnonzero(live).tolist()


@pytest.mark.parametrize("gravity", [(0.0, 0.0, 0.0), (0.0, -9.81, 1.0)])
def test_point_masses_in_the_body_stage_equal_the_system_assembly(gravity):
    """Point masses among a quaternion rigid body (non-additive increment): M, h and the
    increment of the body stage's point-mass kernels against the System's."""
    system = System(gravity=gravity)
    for k in range(3):
        system.add(PointMass(0.5 + k, position=(k, 1.0, 2.0), velocity=(0.1, k, 0.0), name=f"p{k}"))
    system.add(RigidBody(3.0, np.diag([1.0, 2.0, 3.0]), com=(0.1, 0.2, -0.3), name="rigid"))
    system.add(PointMass(0.7, name="p3"))
    q, u = system.initial_state()
    rng = np.random.default_rng(5)
    u[:] = rng.normal(size=system.nu)
    stage = BodyStage.of_equations(system.equations())
    assert stage._point_u.size == 4
    nu = system.nu
    M, h = np.full((nu, nu), np.nan), np.full(nu, np.nan)
    stage.mass_and_h(0.3, q, u, M, h)
    M_ref, h_ref = system.mass_and_h(0.3, q, u)
    np.testing.assert_array_equal(M, M_ref)
    np.testing.assert_allclose(h, h_ref, rtol=1e-14, atol=1e-14)
    h2 = np.full(nu, np.nan)
    stage.h_only(0.3, q, u, h2)
    np.testing.assert_array_equal(h2, h)
    du = 0.1 * rng.normal(size=nu)
    out = np.full(system.nq, np.nan)
    stage.increment(q, du, out)
    np.testing.assert_allclose(out, system.increment(q, du), rtol=1e-15, atol=1e-15)


SURFACE_KINDS = [name for name in CONTOURS.names() if name != "point"]


def _moved_state(system, q, rng):
    """q with the beam's modes excited (tip deflections of millimetres) and the rigid
    table moved and turned at random."""
    from mbs.bodies.rotations import quat_from_rotvec

    q = q.copy()
    for body in system.bodies:
        s = q[body.q_slice]
        if isinstance(body, FlexibleBodyFFR):
            s[body.q_f_slice] = 1e-3 * rng.normal(size=body.n_modes)
        elif isinstance(body, RigidBody):
            s[:3] = 0.05 * rng.normal(size=3)
            s[3:7] = quat_from_rotvec(rng.normal(size=3))
    return q


def _samples(contour, n=21):
    """Points r (k, 3) [m] of ``contour`` on an n (x n) grid of its domain (its state as
    last updated)."""
    point = contour.new_point()
    domains = contour.domain if contour.dim == 2 else (contour.domain,)
    axes = [np.linspace(a, b, n) for a, b in domains]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, contour.dim)
    return np.array([contour.evaluate(point, *at).r.copy() for at in grid])


@pytest.mark.parametrize("kind", SURFACE_KINDS)
@pytest.mark.parametrize("seed", range(2))
def test_every_surface_kind_is_bounded_and_no_pair_within_the_margin_is_pruned(kind, seed):
    """Each surface kind (on the beam, the free rigid table or the ground; pair_cost's
    scenes) against a sphere side, the beam deformed and the table moved at random: every
    point sampled over the surface's domain lies in its bounding sphere (a plane: on its
    plane), the compiled table's flags are the reference's, and a pair the table prunes
    has every sampled point farther from the side's centre than the side's radius plus
    the margin — pruning never drops a pair that could close."""
    from validation.bench.pair_cost import RADIUS, pair_scene

    system, contact, q, u = pair_scene(("sphere", kind), far=1)     # two contacts: the table prunes
    surface = contact.kinematics.contour2
    side = contact.kinematics.contour1.body
    bound = contour_sphere(surface)
    assert bound is not None, f"{kind}: no bound: its pairs cannot be pruned"
    rng = np.random.default_rng(seed)
    q = _moved_state(system, q, rng)
    body = surface.body
    surface.update(None if body is None else q[body.q_slice], None if body is None else u[body.u_slice], 0.0)
    r = _samples(surface)
    centre, radius = bound(q, 0.0)
    if isinstance(bound, GroundPlane):
        np.testing.assert_allclose((r - centre) @ bound.normal, 0.0, atol=1e-15)
    else:
        assert np.linalg.norm(r - centre, axis=1).max() <= radius * (1 + 1e-12)
    table = SphereTable(list(system.contacts))
    assert len(table) == 2
    n = len(table.spheres)
    centres, radii = np.zeros((n, 3)), np.zeros(n)
    live, closed = np.ones(2, dtype=bool), np.ones(2, dtype=bool)
    live_idx = np.zeros(2, dtype=np.intp)
    table.start(q, 0.0, centres, radii)
    margin = contact.margin + contact.closing_tol
    reach = np.max(np.linalg.norm(r - r.mean(axis=0), axis=1)) + 4 * RADIUS
    flags = []
    for k in range(400):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        if k % 2:       # touching or within the margin of a surface point: must stay live
            c1 = r[rng.integers(len(r))] + (RADIUS + margin) * rng.uniform() * direction
        else:           # anywhere around the surface
            c1 = r[rng.integers(len(r))] + reach * rng.uniform() * direction
        q[side.q_slice] = c1
        table.prune(q, 0.0, centres, radii, live, closed, live_idx)
        assert live[0] == live_pair(*sphere_pair(contact), margin, q, 0.0)
        if not live[0]:
            assert np.linalg.norm(r - c1, axis=1).min() > RADIUS + margin
        flags.append(bool(live[0]))
    assert 0 < sum(flags) < len(flags), "the samples should give live and pruned pairs"


@pytest.mark.parametrize("kind", ["band", "cylinder"])
def test_an_offset_contour_beyond_its_body_lies_in_its_grown_sphere(kind):
    """A band 1 m wide and a cylinder of 0.5 m radius about the beam's top line reach far
    beyond the beam's own sphere (radius about 0.14 m): their bounds grow by the offset's
    reach and still hold every sampled point."""
    from contours import Contour1sNeutralFFR, FlexibleBand, FlexibleCylinder
    from ffrmbs_app.scenes import point_mass_beam as pmb

    system = System()
    beam = system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=20, frame=PrescribedFrameMotion.fixed(),
                                      name="beam"))
    line = Contour1sNeutralFFR.along_line(beam, (0.0, pmb.HEIGHT, pmb.WIDTH / 2), (1, 0, 0), normal=(0, 1, 0),
                                          degree=4)
    surface = FlexibleBand(line, width=1.0) if kind == "band" else FlexibleCylinder(line, radius=0.5)
    q, u = system.initial_state()
    q = _moved_state(system, q, np.random.default_rng(1))
    surface.update(q[beam.q_slice], u[beam.u_slice], 0.0)
    r = _samples(surface)
    centre, radius = contour_sphere(surface)(q, 0.0)
    beam_radius = contour_sphere(line)(q, 0.0)[1]
    assert np.linalg.norm(r - centre, axis=1).max() > beam_radius, "the offset contour reaches beyond the beam"
    assert np.linalg.norm(r - centre, axis=1).max() <= radius * (1 + 1e-12)


def test_a_single_prunable_contact_is_searched_every_step():
    """One prunable contact: no sphere table (its detection's box test is its broad
    phase), and the plan says so; two: both pruned, and the plan says that."""
    from validation.bench.pair_cost import pair_scene

    for far, pruned in ((0, False), (1, True)):
        system, contact, q, u = pair_scene(("sphere", "plane"), far=far)
        assert len(SphereTable(list(system.contacts))) == (2 if pruned else 0)
        line = next(c for c in system.plan(0.1).contacts if contact.name in c)
        assert ("only while the bodies' bounding spheres" in line) == pruned
        assert ("its detection's own box test is the broad phase" in line) == (not pruned)

