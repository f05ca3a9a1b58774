"""Joints against independent oracles: finite differences of g along exact motions,
the physical pendulum's small-amplitude period, the kinematics each joint allows, and
statics for the reactions."""

import zlib

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from ffrmbs.errors import ModelError
from mbs.bodies.body import Frame, ground_frame
from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.bodies.floating_frame import PrescribedFrameMotion
from mbs.links.joints import Joint
from mbs.bodies.rigid_body import PointMass, RigidBody
from mbs.system import System

KINDS = ["spherical", "revolute", "prismatic", "fixed"]
PAIRS = ["ground-flex", "flex-flex", "rigid-flex", "same-body", "point-rigid", "prescribed-rigid"]
GRAVITY = 9.81


@pytest.fixture(scope="module")
def beam_data():
    """The report's 1 x 1 x 5 m steel beam, coarse tet10 mesh, 6 free-free modes."""
    from preprocess import box, build_body
    from validation.cases.cantilever import MATERIAL
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, 6, clamp=None)


def rng_for(*key):
    return np.random.default_rng(zlib.crc32(repr(key).encode()))


def random_rotation(rng):
    return Rotation.from_rotvec(rng.uniform(-1.2, 1.2, 3)).as_matrix()


def prescribed_motion():
    """Body frame translating on R(t) = (0.3 sin 2t, 0.1 t², 1) and turning about a fixed
    unit axis n by θ(t) = 0.5 t + 0.4 t² (so ω̄ = θ̇ n, ω̄̇ = θ̈ n, since A n = n)."""
    n = np.array([1.0, 2.0, 2.0]) / 3.0

    def translation(t):
        return (np.array([0.3 * np.sin(2 * t), 0.1 * t * t, 1.0]),
                np.array([0.6 * np.cos(2 * t), 0.2 * t, 0.0]),
                np.array([-1.2 * np.sin(2 * t), 0.2, 0.0]))

    def rotation(t):
        return (Rotation.from_rotvec((0.5 * t + 0.4 * t * t) * n).as_matrix(),
                (0.5 + 0.8 * t) * n, 0.8 * n)

    return PrescribedFrameMotion(translation, rotation)


def random_case(beam_data, kind, rotation, pair):
    """(system, joint, q, u, u̇) at a random state: random orientations and positions,
    elastic coordinates of about 1 (≈ 1 cm deformation), random velocities."""
    rng = rng_for(kind, rotation, pair)
    system = System()
    flex1 = system.add(FlexibleBodyFFR(beam_data, rotation=rotation, name="flex1"))
    flex2 = system.add(FlexibleBodyFFR(beam_data, rotation=rotation, name="flex2"))
    rigid = system.add(RigidBody(3.0, np.diag([0.2, 0.3, 0.4]), com=(0.1, -0.2, 0.3),
                                 rotation=rotation, name="rigid"))
    point = system.add(PointMass(2.0, position=rng.normal(size=3), name="point"))
    moving = system.add(FlexibleBodyFFR(beam_data, frame=prescribed_motion(), name="moving"))

    def node_frame(body, j):
        node = body.node(j)
        return Frame(body, node.u0, node.phi, random_rotation(rng))

    def rigid_frame():
        return rigid.frame_at(rng.normal(size=3), random_rotation(rng))

    frames = {
        "ground-flex": lambda: (ground_frame(rng.normal(size=3), random_rotation(rng)),
                                node_frame(flex1, 7)),
        "flex-flex": lambda: (node_frame(flex1, 3), node_frame(flex2, 50)),
        "rigid-flex": lambda: (rigid_frame(), node_frame(flex1, 11)),
        "same-body": lambda: (node_frame(flex1, 5), node_frame(flex1, 40)),
        "point-rigid": lambda: (Frame(point, rng.normal(size=3)), rigid_frame()),
        "prescribed-rigid": lambda: (node_frame(moving, 20), rigid_frame()),
    }[pair]()
    axis = rng.normal(size=3) if kind in ("revolute", "prismatic") else None
    joint = system.add(Joint(*frames, kind, axis))

    for b in (flex1, flex2):
        b.set_initial(R=rng.normal(size=3), A=random_rotation(rng), q_f=rng.normal(size=b.n_modes))
    rigid.set_initial(R=rng.normal(size=3), A=random_rotation(rng))
    moving.set_initial(q_f=rng.normal(size=moving.n_modes))
    q, _ = system.initial_state()
    return system, joint, q, rng.normal(size=system.nu), rng.normal(size=system.nu)


def constraint_rate(system, joint, t, q, u):
    """ġ = C_q u + g_t from the joint's Jacobian and velocity term."""
    C = np.zeros((joint.n_c, system.nu))
    joint.jacobian(t, q, C)
    return C @ u + joint.velocity_term(t, q)


@pytest.mark.parametrize("pair", PAIRS)
@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
@pytest.mark.parametrize("kind", KINDS)
def test_jacobian_is_the_rate_of_g_along_the_motion(beam_data, kind, rotation, pair):
    """ġ = C_q u + g_t against the central difference of g(t0 + s, q ⊕ s u) at s = ±ε.
    ε = 1e-6: truncation ε²/6 |g⃛| ~ 1e-12, round-off ~ 1e-16 |g| / ε ~ 1e-10."""
    system, joint, q, u, _ = random_case(beam_data, kind, rotation, pair)
    t0, eps = 0.3, 1e-6
    g = [joint.residual(t0 + s, system.increment(q, s * u)) for s in (eps, -eps)]
    fd = (g[0] - g[1]) / (2 * eps)
    rate = constraint_rate(system, joint, t0, q, u)
    assert np.abs(rate).max() > 1e-3  # the motion moves the constraint
    np.testing.assert_allclose(rate, fd, rtol=0, atol=1e-7 * max(1.0, np.abs(fd).max()))


@pytest.mark.parametrize("pair", PAIRS)
@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
@pytest.mark.parametrize("kind", KINDS)
def test_one_pass_kinematics_equal_the_frame_by_frame_values(beam_data, kind, rotation, pair):
    """A frame's (r, A, J_T, J_R) from one evaluation of its body (what the joints'
    Jacobian uses) are the bits of Frame.position, orientation, J_T and J_R, on every
    body kind (free and prescribed flexible, rigid, point mass, ground); and g from
    ``residual_and_jacobian`` (the Newton iteration's call) is ``residual``'s."""
    system, joint, q, _, _ = random_case(beam_data, kind, rotation, pair)
    t = 0.3
    for f in (joint.frame1, joint.frame2):
        qb = q if f.body is None else q[f.body.q_slice]
        r, A, J_T, J_R = f.kinematics(qb, t)
        assert np.array_equal(r, f.position(qb, t)) and np.array_equal(A, f.orientation(qb, t))
        if f.body is not None:
            assert np.array_equal(J_T, f.J_T(qb, t)) and np.array_equal(J_R, f.J_R(qb, t))
    C = np.zeros((joint.n_c, system.nu))
    assert np.array_equal(joint.residual_and_jacobian(t, q, C), joint.residual(t, q))
    assert np.abs(C).max() > 0.0


@pytest.mark.parametrize("pair", PAIRS)
@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
@pytest.mark.parametrize("kind", KINDS)
def test_bias_gives_the_second_derivative_of_g(beam_data, kind, rotation, pair):
    """g̈ = C_q u̇ + γ against the central difference of ġ(s) = C_q(q(s)) u(s) + g_t along
    q(s) = q ⊕ (s u + s²/2 u̇), u(s) = u + s u̇, t = t0 + s. Its derivative at s = 0 is
    exactly Ċ_q u + C_q u̇ + ġ_t, since dC_q/ds at 0 depends on q'(0) ↔ u only (for
    quaternions the body rate of the path differs from u(s) by O(s²), which changes
    nothing at s = 0). ε = 1e-4: truncation ε²/6 |ġ⃛| ≈ 2e-9 |ġ⃛| with |ġ⃛| = O(10)
    for unit rates on a 5 m body; round-off 1e-16 |ġ| / ε ~ 1e-11. Tolerance 1e-6,
    far below the O(1) size of any γ term, so a missing or wrong term fails."""
    system, joint, q, u, ud = random_case(beam_data, kind, rotation, pair)
    t0, eps = 0.3, 1e-4

    def rate(s):
        qs = system.increment(q, s * u + 0.5 * s * s * ud)
        return constraint_rate(system, joint, t0 + s, qs, u + s * ud)

    fd = (rate(eps) - rate(-eps)) / (2 * eps)
    C = np.zeros((joint.n_c, system.nu))
    joint.jacobian(t0, q, C)
    gamma = joint.bias(t0, q, u)
    assert np.abs(fd).max() > 1e-3  # g̈ is not trivially zero along the motion
    np.testing.assert_allclose(C @ ud + gamma, fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))


# --- physics: the physical pendulum ----------------------------------------------------

M, I_C, D_COM, D_PIVOT = 2.0, np.diag([0.05, 0.08, 0.03]), 0.3, 0.2
PIVOT = np.array([0.1, -0.2, 1.0])


def pendulum(kind, rotation, theta0):
    """A rigid body whose centre of mass sits at (0, 0, −0.3) and whose pivot frame sits at
    (0, 0, 0.2) in body axes (d = 0.5 m), hung from a ground frame at PIVOT and tilted by
    θ0 about y. The revolute joint's ground frame is turned, its axis given in its own
    axes so that it is the inertial y axis."""
    system = System(gravity=(0.0, 0.0, -GRAVITY))
    body = system.add(RigidBody(M, I_C, com=(0.0, 0.0, -D_COM), rotation=rotation, name="pendulum"))
    A_ground = Rotation.from_rotvec([0.3, -0.5, 0.7]).as_matrix()
    ground = system.frame(PIVOT, A_ground)
    pivot = body.frame_at((0.0, 0.0, D_PIVOT), orientation=A_ground)
    if kind == "revolute":
        joint = Joint.revolute(ground, pivot, axis=A_ground.T @ [0.0, 1.0, 0.0])
    else:
        joint = Joint.spherical(ground, pivot)
    system.add(joint)
    A0 = Rotation.from_rotvec([0.0, theta0, 0.0]).as_matrix()
    body.set_initial(R=PIVOT - A0 @ [0.0, 0.0, D_PIVOT], A=A0)
    return system, body


def integrate(system, q0, u0, t_end, baumgarte, t_eval=None, events=None):
    """(q, u) from solve_ivp (DOP853, rtol 1e-10) with u̇ from System.accelerations
    (Baumgarte terms (a, b) [1/s]) and q̇ = Y(q) u from System.qdot."""
    nq = system.nq

    def rhs(t, y):
        q, u = y[:nq], y[nq:]
        ud, _ = system.accelerations(t, q, u, baumgarte=baumgarte)
        return np.concatenate((system.qdot(q, u), ud))

    return solve_ivp(rhs, (0.0, t_end), np.concatenate((q0, u0)), method="DOP853",
                     rtol=1e-10, atol=1e-12, t_eval=t_eval, events=events)


@pytest.mark.parametrize("kind, rotation", [("spherical", "quaternion"),
                                            ("revolute", "quaternion"),
                                            ("revolute", "cardan")])
def test_pendulum_period(kind, rotation):
    """Small-amplitude period T0 = 2π sqrt(I_O / (m g d)), I_O = I_c,yy + m d², to 1e-3;
    and, sharper, the finite-amplitude period T0 (1 + θ0²/16 + 11 θ0⁴/3072 + …) of
    θ̈ = −ω0² sin θ: at θ0 = 0.02 rad the θ0² term is 2.5e-5, the θ0⁴ term 6e-10, so
    1e-7 checks the joint's dynamics well beyond the amplitude effect. Baumgarte (5, 5)
    keeps the drift of the index-1 form below 1e-6."""
    theta0 = 0.02
    system, body = pendulum(kind, rotation, theta0)
    d = D_COM + D_PIVOT
    T0 = 2 * np.pi * np.sqrt((I_C[1, 1] + M * d * d) / (M * GRAVITY * d))
    com = body.com_frame()

    def swing(t, y):  # horizontal offset of the centre of mass from the pivot
        return com.position(y[body.q_slice])[0] - PIVOT[0]

    sol = integrate(system, *system.initial_state(), 1.4 * T0, (5.0, 5.0),
                    t_eval=np.linspace(0, 1.4 * T0, 50), events=swing)
    crossings = sol.t_events[0]  # at T/4, 3T/4, 5T/4
    assert len(crossings) == 3
    period = crossings[2] - crossings[0]
    assert abs(period / T0 - 1) < 1e-3
    assert abs(period / (T0 * (1 + theta0 ** 2 / 16)) - 1) < 1e-7
    residuals = [np.abs(system.constraint_residual(t, y[:system.nq])).max()
                 for t, y in zip(sol.t, sol.y.T)]
    assert max(residuals) < 1e-6


# --- kinematics each joint allows ---------------------------------------------------------

def two_bodies(kind, axis):
    """Two free rigid bodies (quaternion and Cardan) under gravity joined at assembled
    frames (A1 = A2, r1 = r2); returns (system, frame1, frame2, q0, u0) with random
    velocities u0 projected onto C_q u = 0."""
    rng = rng_for("two bodies", kind)
    system = System(gravity=(0.0, 0.0, -GRAVITY))
    b1 = system.add(RigidBody(1.5, np.diag([0.1, 0.2, 0.25]), com=(0.1, 0.0, -0.1), name="b1"))
    b2 = system.add(RigidBody(0.8, np.diag([0.05, 0.04, 0.06]), com=(0.0, 0.2, 0.1),
                              rotation="cardan", name="b2"))
    B1, B2 = random_rotation(rng), random_rotation(rng)
    p1, p2 = rng.normal(size=3), rng.normal(size=3)
    f1, f2 = b1.frame_at(p1, B1), b2.frame_at(p2, B2)
    system.add(Joint(f1, f2, kind, axis))
    Q1 = random_rotation(rng)
    Q2 = Q1 @ B1 @ B2.T
    R1 = rng.normal(size=3)
    b1.set_initial(R=R1, A=Q1, v=rng.normal(size=3), omega=rng.normal(size=3))
    b2.set_initial(R=R1 + Q1 @ p1 - Q2 @ p2, A=Q2, v=rng.normal(size=3), omega=rng.normal(size=3))
    q, u = system.initial_state()
    C = system.constraint_jacobian(0.0, q)
    u -= np.linalg.pinv(C) @ (C @ u)
    return system, f1, f2, q, u


def frame_states(system, f1, f2, y):
    """(r1, r2, A1, A2, ω1, ω2) of the two frames at the solver state y = (q, u)."""
    q, u = y[:system.nq], y[system.nq:]
    q1, q2, u1, u2 = q[f1.body.q_slice], q[f2.body.q_slice], u[f1.body.u_slice], u[f2.body.u_slice]
    return (f1.position(q1), f2.position(q2), f1.orientation(q1), f2.orientation(q2),
            f1.angular_velocity(q1, u1), f2.angular_velocity(q2, u2))


def test_revolute_allows_only_rotation_about_the_axis():
    axis = np.array([1.0, 2.0, -0.5])
    system, f1, f2, q0, u0 = two_bodies("revolute", axis)
    sol = integrate(system, q0, u0, 0.5, (10.0, 10.0), t_eval=np.linspace(0.0, 0.5, 11))
    for y in sol.y.T:
        r1, r2, A1, _, w1, w2 = frame_states(system, f1, f2, y)
        a1 = A1 @ axis / np.linalg.norm(axis)
        rel = w2 - w1
        assert np.linalg.norm(rel) > 0.1  # the hinge does turn
        assert np.linalg.norm(np.cross(rel, a1)) < 1e-9 * np.linalg.norm(rel)
        assert np.linalg.norm(r2 - r1) < 1e-9


def test_prismatic_allows_only_translation_along_the_axis():
    axis = np.array([0.3, -1.0, 0.4])
    system, f1, f2, q0, u0 = two_bodies("prismatic", axis)
    sol = integrate(system, q0, u0, 0.5, (10.0, 10.0), t_eval=np.linspace(0.0, 0.5, 11))
    slide = []
    for y in sol.y.T:
        r1, r2, A1, A2, w1, w2 = frame_states(system, f1, f2, y)
        a1 = A1 @ axis / np.linalg.norm(axis)
        np.testing.assert_allclose(A1.T @ A2, np.eye(3), atol=1e-9)
        assert np.linalg.norm(w2 - w1) < 1e-9
        assert np.linalg.norm(np.cross(r2 - r1, a1)) < 1e-9
        slide.append(a1 @ (r2 - r1))
    assert np.ptp(slide) > 0.01  # the slider does slide


# --- reactions: statics -------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["fixed", "prismatic", "spherical"])
def test_reaction_balances_gravity_at_rest(kind):
    """A rigid body at rest held by a joint whose free motions gravity does not drive
    (fixed; prismatic with a horizontal axis; spherical with the centre of mass below the
    pivot) stays at rest, and the joint's force and torque on it balance its weight:
    F2 = −m g, τ2 = −(r_c − r2) × m g (statics)."""
    g_vec, y_axis = np.array([0.0, 0.0, -GRAVITY]), np.array([0.0, 1.0, 0.0])
    system = System(gravity=g_vec)
    R, A = np.array([0.3, 0.5, 0.7]), Rotation.from_rotvec([0.4, 0.1, -0.3]).as_matrix()
    p_held = np.array([0.1, -0.25, 0.05])
    com = p_held + A.T @ [0.0, 0.0, -0.4] if kind == "spherical" else (0.2, -0.1, -0.4)
    body = system.add(RigidBody(2.5, np.diag([0.1, 0.2, 0.3]), com=com, name="held"))
    body.set_initial(R=R, A=A)
    held = body.frame_at(p_held)
    r_held = R + A @ p_held
    if kind == "prismatic":  # slide along the inertial y axis, frames 0.75 m apart on it
        joint = Joint.prismatic(system.frame(r_held - 0.75 * y_axis, A), held, axis=A.T @ y_axis)
    else:
        joint = Joint(system.frame(r_held, A), held, kind)
    system.add(joint)
    q, u = system.initial_state()
    assert np.abs(system.constraint_residual(0.0, q)).max() < 1e-12
    ud, lam = system.accelerations(0.0, q, u)
    np.testing.assert_allclose(ud, 0.0, atol=1e-10)
    force, torque = joint.reaction(0.0, q, lam)
    weight = body.mass * g_vec
    r2 = held.position(q[body.q_slice])
    r_c = body.com_frame().position(q[body.q_slice])
    np.testing.assert_allclose(force, -weight, atol=1e-10)
    np.testing.assert_allclose(torque, -np.cross(r_c - r2, weight), atol=1e-10)


# --- user errors ----------------------------------------------------------------------------

def test_errors_name_the_problem():
    body = RigidBody(1.0, np.eye(3))
    ground, frame = ground_frame(), body.origin
    with pytest.raises(ModelError, match="zero"):
        Joint.revolute(ground, frame, axis=(0.0, 0.0, 0.0))
    with pytest.raises(ModelError, match="zero"):
        Joint.prismatic(ground, frame, axis=(0.0, 0.0, 0.0))
    with pytest.raises(ModelError, match="unknown joint kind 'hinge'"):
        Joint(ground, frame, "hinge")
    with pytest.raises(ModelError, match="needs an axis"):
        Joint(ground, frame, "revolute")
    with pytest.raises(ModelError, match="takes no axis"):
        Joint(ground, frame, "fixed", axis=(1.0, 0.0, 0.0))
    with pytest.raises(ModelError, match="two ground frames"):
        Joint.spherical(ground, ground_frame((1.0, 0.0, 0.0)))
    with pytest.raises(ModelError, match="two different frames"):
        Joint.spherical(frame, frame)


def test_axis_is_normalized_and_triad_orthonormal():
    joint = Joint.revolute(ground_frame(), RigidBody(1.0, np.eye(3)).origin, axis=(0.0, 3.0, 4.0))
    np.testing.assert_allclose(joint.triad[0], [0.0, 0.6, 0.8])
    np.testing.assert_allclose(joint.triad @ joint.triad.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(joint.triad) == pytest.approx(1.0)
