"""Contact kinematics (thesis eq. 3.2–3.8) against independent oracles: hand-computed
gaps, frames, relative velocities and Jacobians on rigid bodies and point masses, the
geometry of the undeformed beam, and on the moving deformed beam the closest-point
property, ġ = Wᵀ u and finite differences of g_N in time and along q ⊕ ε e_i."""

import numpy as np
import pytest

from contact.kinematics import (ContactKinematicsPointContour1s, ContactKinematicsPointContour2s,
                                ContactKinematicsPointPlane, ContactKinematicsPointSphere,
                                ContactKinematicsSphereContour1s,
                                ContactKinematicsSphereContour2s, ContactKinematicsSpherePlane,
                                ContactKinematicsSphereSphere, PointOnCurveConstraint)
from contact.search import Contact1sSearch, Contact2sSearch
from contours import (Contour1sNeutralFFR, Contour2sNeutralFFR, FlexibleBand, FlexibleCylinder, PlaneContour,
                      PointContour, SphereContour)
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, PointMass, RigidBody, System, ground_frame
from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix
from validation.bench.common import moving_state

L, H, W = 0.25, 0.05, 0.05
S_BALL = np.array([0.1, -0.05, 0.02])  # a point of the ball body in its body frame [m]


class World:
    """One System: an FFR beam, a point mass, a rigid ball and a rigid slab, with their
    contours; ``set(q, u)`` updates every contour from the global state."""

    def __init__(self, data):
        self.system = s = System()
        self.beam = s.add(FlexibleBodyFFR(data, modes=8, name="beam"))
        self.mass = s.add(PointMass(0.3, name="mass"))
        self.ball = s.add(RigidBody(1.0, np.diag([0.1, 0.2, 0.3]), name="ball"))
        self.slab = s.add(RigidBody(2.0, np.diag([0.3, 0.2, 0.1]), name="slab"))
        self.top = Contour2sNeutralFFR(self.beam, "y1")
        self.axis = Contour1sNeutralFFR.along_line(self.beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0),
                                                   degree=4)
        self.band = FlexibleBand(self.axis, W, H / 2)
        self.cylinder = FlexibleCylinder(self.axis, 0.02)
        self.dot = PointContour(self.mass.point)
        self.ball_dot = PointContour(self.ball.frame_at(S_BALL))
        self.ball_sphere = SphereContour(self.ball.frame_at(S_BALL), 0.03)
        self.mass_sphere = SphereContour(self.mass.point, 0.02)
        self.slab_plane = PlaneContour(self.slab.origin)
        self.contours = [self.top, self.axis, self.band, self.cylinder, self.dot, self.ball_dot,
                         self.ball_sphere, self.mass_sphere, self.slab_plane]

    def state(self, seed, deform=3e-3):
        """A random global (q, u): moving deformed beam, moving and rotating rigid bodies."""
        rng = np.random.default_rng(seed)
        q, u = self.system.initial_state()
        qb, ub = moving_state(self.beam, rng, deform)
        q[self.beam.q_slice], u[self.beam.u_slice] = qb, ub
        for body in (self.ball, self.slab):
            q[body.q_slice][:3] = rng.normal(size=3)
            q[body.q_slice][3:7] = quat_from_rotvec(rng.normal(size=3))
            u[body.u_slice] = rng.normal(size=6)
        q[self.mass.q_slice] = rng.normal(size=3)
        u[self.mass.u_slice] = rng.normal(size=3)
        return q, u

    def set(self, q, u=None):
        for c in self.contours:
            b = c.body
            c.update(q[b.q_slice], None if u is None else u[b.u_slice])

    def place(self, body, q, position, offset=np.zeros(3)):
        """Move ``body`` (translation only) so that its body point ``offset`` is at ``position``."""
        qs = q[body.q_slice]
        A = np.eye(3) if body is self.mass else quat_to_matrix(qs[3:7])
        qs[:3] = position - A @ offset


@pytest.fixture(scope="module")
def world(thesis_beam_data):
    return World(thesis_beam_data)


def check_derivatives(world, kin, q, u, tol_t=1e-6, tol_u=1e-7, gap=lambda k: k.g_N,
                      W=lambda k, nu: k.W_N(np.empty(nu)), rate=lambda k: k.gd_N):
    """ġ = Wᵀ u (1e-12); ġ = d/dt g along q ⊕ t u (relative tol_t); W_i = ∂g/∂u_i along
    q ⊕ ε e_i (tol_u relative to max |W|). Leaves the world at (q, u)."""
    nu = world.system.nu
    world.set(q, u)
    assert kin.update()
    Wk, gd = W(kin, nu).copy(), np.copy(rate(kin))
    assert np.allclose(Wk.T @ u, gd, rtol=1e-12, atol=1e-12 * np.abs(Wk).max() * np.abs(u).max())

    def g_at(du):
        world.set(world.system.increment(q, du))
        assert kin.update(velocity=False, jacobians=False)
        return np.copy(gap(kin))

    h = 1e-6
    fd = (g_at(h * u) - g_at(-h * u)) / (2 * h)
    assert np.linalg.norm(fd - gd) <= tol_t * max(np.linalg.norm(gd), 1e-3)
    eps = 1e-6
    for i in range(nu):
        e = np.zeros(nu)
        e[i] = eps
        assert np.allclose((g_at(e) - g_at(-e)) / (2 * eps), Wk[i], rtol=0, atol=tol_u * np.abs(Wk).max())
    world.set(q, u)
    kin.update()


def rigid_J_T(body, q, point):
    """Hand-written ∂v/∂u (3, 6) of an inertial point on a quaternion rigid body:
    v = Ṙ + A (ω̄ × s̄), s̄ = Aᵀ (point − R)."""
    qs = q[body.q_slice]
    A = quat_to_matrix(qs[3:7])
    s = A.T @ (point - qs[:3])
    return np.hstack([np.eye(3), -A @ np.array([[0, -s[2], s[1]], [s[2], 0, -s[0]], [-s[1], s[0], 0]])])


# --- analytic contacts: hand-computed oracles ------------------------------------------

def test_point_mass_on_a_tilted_ground_plane():
    """g_N = nᵀ(P − O), C2 = P − g_N n, ġ = (n, T)ᵀ v, W = (n, T) in the mass's slice."""
    A = quat_to_matrix(quat_from_rotvec([0.3, -0.2, 0.5]))
    O = np.array([0.1, -0.2, 0.3])
    mass = PointMass(1.0, position=(0.4, 0.5, 0.9), velocity=(0.2, -0.7, 0.3))
    plane, dot = PlaneContour(ground_frame(O, A)), PointContour(mass.point)
    kin = ContactKinematicsPointPlane(dot, plane, nu_total=5)
    assert kin.update()
    P, v = mass.q_init, mass.u_init
    g = A[:, 2] @ (P - O)
    assert np.isclose(kin.g_N, g, atol=1e-15)
    assert np.allclose(kin.n, A[:, 2], atol=1e-15) and np.allclose(kin.T, A[:, :2], atol=1e-15)
    assert np.allclose(kin.point2.r, P - g * A[:, 2], atol=1e-15) and np.allclose(kin.point1.r, P)
    assert np.isclose(kin.gd_N, A[:, 2] @ v) and np.allclose(kin.gd_T, A[:, :2].T @ v)
    W_N, W_T = kin.W_N(np.full(5, 7.0)), kin.W_T(np.full((5, 2), 7.0))
    assert np.allclose(W_N, np.r_[A[:, 2], 0, 0], atol=1e-15)  # local layout, zero-padded to nu_total
    assert np.allclose(W_T, np.vstack([A[:, :2], np.zeros((2, 2))]), atol=1e-15)
    assert kin.u_slices() == (slice(0, 3), None)


def test_point_on_a_rigid_body_against_a_plane_on_another(world):
    q, u = world.state(1)
    world.set(q, u)
    kin = ContactKinematicsPointPlane(world.ball_dot, world.slab_plane)
    assert kin.update()
    ball, slab = world.ball, world.slab
    A_b, A_s = quat_to_matrix(q[ball.q_slice][3:7]), quat_to_matrix(q[slab.q_slice][3:7])
    R_b, R_s = q[ball.q_slice][:3], q[slab.q_slice][:3]
    P = R_b + A_b @ S_BALL
    n, T = A_s[:, 2], A_s[:, :2]
    g = n @ (P - R_s)
    C2 = P - g * n
    J1, J2 = rigid_J_T(ball, q, P), rigid_J_T(slab, q, C2)
    dv = J1 @ u[ball.u_slice] - J2 @ u[slab.u_slice]
    assert np.isclose(kin.g_N, g, atol=1e-14) and np.allclose(kin.point2.r, C2, atol=1e-14)
    assert np.isclose(kin.gd_N, n @ dv, atol=1e-13) and np.allclose(kin.gd_T, T.T @ dv, atol=1e-13)
    W_N, W_T = kin.W_N(np.empty(world.system.nu)), kin.W_T(np.empty((world.system.nu, 2)))
    assert np.allclose(W_N[ball.u_slice], J1.T @ n, atol=1e-14)
    assert np.allclose(W_N[slab.u_slice], -J2.T @ n, atol=1e-14)
    assert np.allclose(W_T[slab.u_slice], -J2.T @ T, atol=1e-14)
    others = np.ones(world.system.nu, bool)
    others[ball.u_slice] = others[slab.u_slice] = False
    assert not W_N[others].any() and not W_T[others].any()
    check_derivatives(world, kin, q, u)


def test_sphere_on_a_rigid_body_against_a_plane(world):
    """C1 = c − ρ n moves with the ball: ġ_T includes the rolling term ω × (−ρ n)."""
    q, u = world.state(2)
    world.set(q, u)
    kin = ContactKinematicsSpherePlane(world.ball_sphere, world.slab_plane)
    assert kin.update()
    ball, slab = world.ball, world.slab
    A_b, A_s = quat_to_matrix(q[ball.q_slice][3:7]), quat_to_matrix(q[slab.q_slice][3:7])
    c = q[ball.q_slice][:3] + A_b @ S_BALL
    n, T = A_s[:, 2], A_s[:, :2]
    g = n @ (c - q[slab.q_slice][:3])
    C1, C2 = c - 0.03 * n, c - g * n
    J1, J2 = rigid_J_T(ball, q, C1), rigid_J_T(slab, q, C2)
    dv = J1 @ u[ball.u_slice] - J2 @ u[slab.u_slice]
    assert np.isclose(kin.g_N, g - 0.03, atol=1e-14)
    assert np.allclose(kin.point1.r, C1, atol=1e-14) and np.allclose(kin.point2.r, C2, atol=1e-14)
    assert np.isclose(kin.gd_N, n @ dv, atol=1e-13) and np.allclose(kin.gd_T, T.T @ dv, atol=1e-13)
    W_T = kin.W_T(np.empty((world.system.nu, 2)))
    assert np.allclose(W_T[ball.u_slice], J1.T @ T, atol=1e-14)
    check_derivatives(world, kin, q, u)


def test_sphere_against_sphere(world):
    """n along the centre line, g_N = |c1 − c2| − ρ1 − ρ2, C2 = c2 + ρ2 n, C1 = c1 − ρ1 n."""
    q, u = world.state(3)
    world.place(world.mass, q, world.ball_dot.frame_ref.position(q[world.ball.q_slice]) + [0.03, -0.04, 0.05])
    world.set(q, u)
    kin = ContactKinematicsSphereSphere(world.ball_sphere, world.mass_sphere)
    assert kin.update()
    ball, mass = world.ball, world.mass
    c1 = q[ball.q_slice][:3] + quat_to_matrix(q[ball.q_slice][3:7]) @ S_BALL
    c2 = q[mass.q_slice]
    d = c1 - c2
    n = d / np.linalg.norm(d)
    assert np.isclose(kin.g_N, np.linalg.norm(d) - 0.05, atol=1e-15)
    assert np.allclose(kin.n, n, atol=1e-15)
    assert np.allclose(kin.point1.r, c1 - 0.03 * n, atol=1e-15) and np.allclose(kin.point2.r, c2 + 0.02 * n)
    assert np.allclose(kin.T.T @ kin.T, np.eye(2), atol=1e-14) and np.allclose(kin.T.T @ n, 0, atol=1e-14)
    J1 = rigid_J_T(ball, q, c1 - 0.03 * n)
    dv = J1 @ u[ball.u_slice] - u[mass.u_slice]
    assert np.isclose(kin.gd_N, n @ dv, atol=1e-13) and np.allclose(kin.gd_T, kin.T.T @ dv, atol=1e-13)
    W_N = kin.W_N(np.empty(world.system.nu))
    assert np.allclose(W_N[mass.u_slice], -n, atol=1e-15) and np.allclose(W_N[ball.u_slice], J1.T @ n)
    check_derivatives(world, kin, q, u)



def test_point_against_a_sphere(world):
    """n along the line from the sphere's centre c to the point p, g_N = |p − c| − ρ,
    C2 = c + ρ n, ġ = Wᵀ u; inactive with the point on the centre."""
    q, u = world.state(4)
    world.place(world.mass, q, world.ball_dot.frame_ref.position(q[world.ball.q_slice]) + [0.01, 0.025, -0.02])
    world.set(q, u)
    kin = ContactKinematicsPointSphere(world.dot, world.ball_sphere)
    assert kin.update()
    ball = world.ball
    c = q[ball.q_slice][:3] + quat_to_matrix(q[ball.q_slice][3:7]) @ S_BALL
    d = q[world.mass.q_slice] - c
    n = d / np.linalg.norm(d)
    assert np.isclose(kin.g_N, np.linalg.norm(d) - 0.03, atol=1e-15) and np.allclose(kin.n, n, atol=1e-15)
    assert np.allclose(kin.point2.r, c + 0.03 * n, atol=1e-15) and np.allclose(kin.point1.r, q[world.mass.q_slice])
    J2 = rigid_J_T(ball, q, c + 0.03 * n)
    dv = u[world.mass.u_slice] - J2 @ u[ball.u_slice]
    assert np.isclose(kin.gd_N, n @ dv, atol=1e-13) and np.allclose(kin.gd_T, kin.T.T @ dv, atol=1e-13)
    check_derivatives(world, kin, q, u)
    world.place(world.mass, q, c)
    world.set(q, u)
    assert not kin.update() and not kin.active

# --- searched contacts on the beam ------------------------------------------------------

def test_point_above_the_undeformed_top_face(world):
    """g_N = d exactly, C2 = (x, H, z), n = +y."""
    q, u = world.system.initial_state()
    kin = ContactKinematicsPointContour2s(world.dot, world.top)
    for x, z, d in [(0.1, 0.02, 0.01), (0.2437, 0.001, 0.003), (0.03, 0.049, -0.002), (0.0, 0.0, 0.02)]:
        world.place(world.mass, q, np.array([x, H + d, z]))
        world.set(q, u)
        assert kin.update()
        assert np.isclose(kin.g_N, d, rtol=0, atol=1e-14)
        assert np.allclose(kin.point2.r, [x, H, z], atol=1e-13)
        assert np.allclose(kin.n, [0, 1, 0], atol=1e-13)
        assert np.allclose(world.top.position(kin.point2.eta, kin.point2.xi), [x, H, z], atol=1e-13)
    world.place(world.mass, q, np.array([L + 0.01, H + 0.01, 0.02]))  # beyond the end: no contact point
    world.set(q, u)
    assert not kin.update() and not kin.active


@pytest.mark.parametrize("contour", ["top", "band", "cylinder"])
def test_point_against_a_2s_contour_on_the_moving_deformed_beam(world, contour):
    """The found C2 is the closest point (r1 − r2 ∥ n), g_N the distance, and the
    derivatives agree with finite differences."""
    surface = getattr(world, contour)
    q, u = world.state(4)
    world.set(q, u)
    eta0, xi0 = (0.37, {"top": 0.61, "band": 0.013, "cylinder": 2.2}[contour])
    foot = surface.evaluate(surface.new_point(), eta0, xi0)
    world.place(world.mass, q, foot.r + 0.004 * foot.n)
    world.set(q, u)
    kin = ContactKinematicsPointContour2s(world.dot, surface)
    assert kin.update()
    assert np.isclose(kin.g_N, 0.004, rtol=1e-9)
    assert np.allclose([kin.point2.eta, kin.point2.xi], [eta0, xi0], atol=1e-8)
    d = kin.point1.r - kin.point2.r
    assert np.linalg.norm(np.cross(d, kin.n)) < 1e-10 and d @ kin.n > 0  # Newton tol: 1e-10 x size
    assert kin.gd_N != 0 and np.all(kin.gd_T != 0)
    check_derivatives(world, kin, q, u)


def test_point_against_the_beam_axis(world):
    """1s contact: normal = the curve's n; an offset along t2 does not enter g_N."""
    q, u = world.state(5)
    world.set(q, u)
    foot = world.axis.evaluate(world.axis.new_point(), 0.42)
    world.place(world.mass, q, foot.r + 0.03 * foot.n + 0.01 * foot.t2)
    world.set(q, u)
    kin = ContactKinematicsPointContour1s(world.dot, world.axis)
    assert kin.update()
    assert np.isclose(kin.point2.eta, 0.42, atol=1e-9) and np.isclose(kin.g_N, 0.03, rtol=1e-9)
    assert np.allclose(kin.n, foot.n, atol=1e-9) and np.allclose(kin.T, foot.frame[:, :2], atol=1e-9)
    world.place(world.mass, q, foot.r + 0.03 * foot.n)  # no t2 offset: ġ_N is the exact rate
    check_derivatives(world, kin, q, u)


@pytest.mark.parametrize("kind", ["2s", "1s"])
def test_sphere_on_a_rigid_body_against_the_beam(world, kind):
    q, u = world.state(6)
    world.set(q, u)
    contour = world.top if kind == "2s" else world.axis
    cls = ContactKinematicsSphereContour2s if kind == "2s" else ContactKinematicsSphereContour1s
    foot = contour.evaluate(contour.new_point(), 0.6, 0.3)
    world.place(world.ball, q, foot.r + (0.03 + 0.002) * foot.n, S_BALL)
    world.set(q, u)
    kin = cls(world.ball_sphere, contour)
    assert kin.update()
    assert np.isclose(kin.g_N, 0.002, rtol=1e-8)
    assert np.allclose(kin.point1.r, foot.r + 0.002 * foot.n, atol=1e-10)
    assert np.allclose(kin.point2.r, foot.r, atol=1e-10)
    check_derivatives(world, kin, q, u)


def test_point_on_curve_constraint(world):
    """g = (nᵀ d, t2ᵀ d) in the curve frame; on the curve, W is the gradient of g."""
    q, u = world.state(7)
    world.set(q, u)
    foot = world.axis.evaluate(world.axis.new_point(), 0.55)
    world.place(world.mass, q, foot.r + 0.004 * foot.n - 0.002 * foot.t2)
    world.set(q, u)
    con = PointOnCurveConstraint(world.dot, world.axis)
    assert con.update()
    assert np.allclose(con.g, [0.004, -0.002], rtol=1e-8)
    world.place(world.mass, q, foot.r)
    world.set(q, u)
    assert con.update() and np.allclose(con.g, 0.0, atol=1e-12)
    assert np.isclose(con.point2.eta, 0.55, atol=1e-9)
    W = con.W(np.empty((world.system.nu, 2)))
    assert np.allclose(W[:, 0], con.W_N(np.empty(world.system.nu))) and np.allclose(W.T @ u, con.gd, atol=1e-12)
    check_derivatives(world, con, q, u, gap=lambda k: k.g, W=lambda k, nu: k.W(np.empty((nu, 2))),
                      rate=lambda k: k.gd)


# --- layout and input ---------------------------------------------------------------------

def test_bodies_outside_a_system_get_a_local_layout_and_blocks():
    a, b = PointMass(1.0, position=(0, 0, 0.5), velocity=(0, 0, -1)), RigidBody(1.0, np.eye(3))
    kin = ContactKinematicsPointPlane(PointContour(a.point), PlaneContour(b.origin))
    assert kin.update() and kin.u_slices() == (slice(0, 3), slice(3, 9)) and kin.nu_total == 9
    blocks = kin.local_blocks()
    assert [s for s, *_ in blocks] == [slice(0, 3), slice(3, 9)]
    assert np.allclose(blocks[1][1], [0, 0, -1, 0, 0, 0]) and kin.gd_N == -1.0
    same = ContactKinematicsSphereSphere(SphereContour(b.frame_at((0.5, 0, 0)), 0.1),
                                         SphereContour(b.frame_at((-0.5, 0, 0)), 0.1))
    assert same.update() and np.isclose(same.g_N, 0.8) and same.u_slices() == (slice(0, 6), slice(0, 6))
    assert np.allclose(same.W_N(), 0.0, atol=1e-15)  # both on one rigid body: g_N is constant


def test_bad_input(world):
    with pytest.raises(ModelError, match="PointContour"):
        ContactKinematicsPointContour2s(world.ball_sphere, world.top)
    with pytest.raises(ModelError, match="2s contour"):
        ContactKinematicsPointContour2s(world.dot, world.axis)
    with pytest.raises(ModelError, match="1s contour"):
        ContactKinematicsSphereContour1s(world.ball_sphere, world.top)
    with pytest.raises(ModelError, match="PlaneContour"):
        ContactKinematicsPointPlane(world.dot, world.top)
    with pytest.raises(ModelError, match="search runs on"):
        ContactKinematicsPointContour2s(world.dot, world.top, search=Contact2sSearch(world.band))
    with pytest.raises(ModelError, match="1s contour"):
        Contact1sSearch(world.top)
    loose = PointContour(PointMass(1.0).point)
    with pytest.raises(ModelError, match="System"):
        ContactKinematicsPointContour2s(loose, world.top).u_slices()
