"""SpringDamper: forces against the potential's gradient, generalized forces against
finite differences along velocity-space increments, the harmonic and damped
oscillator's analytic solutions, and tangents against finite differences of h."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ffrmbs.errors import ModelError
from mbs.bodies.body import ground_frame
from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.bodies.rigid_body import PointMass, RigidBody
from mbs.bodies.rotations import cardan_to_matrix
from mbs.links.springs import SpringDamper
from mbs.system import System
from preprocess import box, build_body
from validation.cases.cantilever import MATERIAL


@pytest.fixture(scope="module")
def beam_data():
    """A coarse free-free 1 x 1 x 5 m tet10 beam with 6 modes."""
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, 6, clamp=None)


def spring_force(spring, system, t, q, u):
    h = np.zeros(system.nu)
    spring.add_forces(t, q, u, h)
    return h


def two_point_masses(k, c, l0, seed=0):
    rng = np.random.default_rng(seed)
    system = System()
    a = system.add(PointMass(1.5, position=rng.standard_normal(3), velocity=rng.standard_normal(3)))
    b = system.add(PointMass(0.5, position=rng.standard_normal(3), velocity=rng.standard_normal(3)))
    spring = system.add(SpringDamper(a.point, b.point, k, c, free_length=l0))
    q, u = system.initial_state()
    return system, spring, q, u


def central_difference(f, x, eps):
    """∂f/∂x (m, n) by central differences of f (m,) in each coordinate of x (n,)."""
    cols = []
    for i in range(x.size):
        dx = np.zeros(x.size)
        dx[i] = eps
        cols.append((f(x + dx) - f(x - dx)) / (2 * eps))
    return np.array(cols).T


@pytest.mark.parametrize("to_ground", [False, True])
def test_force_is_minus_the_gradient_of_the_potential(to_ground):
    system, spring, q, u = two_point_masses(40.0, 0.0, 0.8)
    if to_ground:
        spring = SpringDamper(ground_frame((0.3, -0.1, 0.2)), spring.frame2, 40.0, free_length=0.8)
    Q = spring_force(spring, system, 0.0, q, u)
    grad = central_difference(lambda x: np.atleast_1d(spring.potential_energy(0.0, x)), q, 1e-6)[0]
    np.testing.assert_allclose(Q, -grad, rtol=1e-8, atol=1e-8 * np.abs(Q).max())
    if to_ground:
        assert not Q[:3].any()


@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
def test_generalized_force_is_minus_the_derivative_of_the_potential(beam_data, rotation):
    """Q·δ = −d/dε V(q ⊕ εδ) at ε = 0 between a rigid body and a node of an FFR body."""
    rng = np.random.default_rng(1)
    system = System()
    rigid = system.add(RigidBody(3.0, np.diag([1.0, 2.0, 2.5]), rotation=rotation)
                       .set_initial(R=(2.0, -1.0, 0.5), A=cardan_to_matrix((0.4, 0.3, -0.6))))
    flex = system.add(FlexibleBodyFFR(beam_data, modes=6, rotation=rotation).set_initial(
        R=(-0.5, 0.2, 0.1), A=cardan_to_matrix((-0.2, 0.5, 0.9)), q_f=0.1 * rng.standard_normal(6)))
    spring = system.add(SpringDamper(rigid.frame_at((0.3, 0.2, -0.4)), flex.node(123), 7e3, free_length=1.2))
    q, _ = system.initial_state()
    Q = spring_force(spring, system, 0.0, q, np.zeros(system.nu))
    eps = 1e-6
    for _ in range(3):
        delta = rng.standard_normal(system.nu)
        dV = (spring.potential_energy(0.0, system.increment(q, eps * delta))
              - spring.potential_energy(0.0, system.increment(q, -eps * delta))) / (2 * eps)
        assert Q @ delta == pytest.approx(-dV, rel=1e-7)


def oscillator(k, c, m, l0, x0):
    """A point mass on a spring-damper to a ground point at the origin, moving along x."""
    system = System()
    mass = system.add(PointMass(m, position=(x0, 0.0, 0.0)))
    spring = system.add(SpringDamper(ground_frame(), mass.point, k, c, free_length=l0))
    return system, spring


def integrate(system, t_end, **kw):
    q0, u0 = system.initial_state()

    def rhs(t, y):
        q, u = y[:3], y[3:]
        return np.concatenate((u, np.linalg.solve(system.mass_matrix(t, q), system.h(t, q, u))))

    return solve_ivp(rhs, (0.0, t_end), np.concatenate((q0, u0)), method="DOP853",
                     rtol=1e-12, atol=1e-13, **kw)


def test_point_mass_oscillates_with_the_natural_frequency():
    k, m, l0 = 250.0, 0.4, 1.0
    system, _ = oscillator(k, 0.0, m, l0, 1.3)
    maximum = lambda t, y: y[3]        # ẋ = 0 going from + to −: a maximum of x
    maximum.direction = -1
    sol = integrate(system, 1.0, events=maximum)
    t_max = sol.t_events[0]
    period = 2 * np.pi * np.sqrt(m / k)
    assert len(t_max) >= 3
    np.testing.assert_allclose(np.diff(t_max), period, rtol=1e-6)
    np.testing.assert_allclose(sol.y_events[0][:, 0], l0 + 0.3, rtol=1e-9)


def test_damped_oscillator_follows_the_analytic_solution_and_loses_energy():
    k, c, m, l0, a = 250.0, 2.0, 0.4, 1.0, 0.3
    system, spring = oscillator(k, c, m, l0, l0 + a)
    t = np.linspace(0.0, 1.0, 201)
    sol = integrate(system, 1.0, t_eval=t)
    w0 = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    wd = w0 * np.sqrt(1 - zeta ** 2)
    x = l0 + a * np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(sol.y[0], x, rtol=1e-9)
    energy = [system.total_energy(ti, yi[:3], yi[3:]) for ti, yi in zip(t, sol.y.T)]
    assert np.all(np.diff(energy) < 0)
    assert energy[-1] < 0.1 * energy[0]
    assert system.potential_energy(0.0, sol.y[:3, 0]) == pytest.approx(0.5 * k * a ** 2, rel=1e-14)


def test_tangents_of_point_masses_are_exact():
    """K = −∂h/∂q and D = −∂h/∂u (finite differences), including the damping terms."""
    system, spring, q, u = two_point_masses(40.0, 3.0, 0.8, seed=2)
    K, D = system.tangents(0.0, q, u)
    K_fd = -central_difference(lambda x: system.h(0.0, x, u), q, 1e-6)
    D_fd = -central_difference(lambda v: system.h(0.0, q, v), u, 1e-6)
    scale = np.abs(K_fd).max()
    np.testing.assert_allclose(K, K_fd, rtol=0, atol=1e-7 * scale)
    np.testing.assert_allclose(D, D_fd, rtol=0, atol=1e-9 * np.abs(D_fd).max())
    assert np.abs(K - K.T).max() > 1e-3 * scale       # the damping term makes K unsymmetric


def test_tangents_between_flexible_and_rigid_body(beam_data):
    """D is exact for any bodies (J_T does not depend on u). At rest, K is exact in the
    rows of the rigid body's translation (J_T's translational block is 1): no ∂J_T/∂q
    terms enter there (they do in the rotational and elastic rows, and through
    ḋ = J_rel u when moving)."""
    rng = np.random.default_rng(3)
    system = System()
    rigid = system.add(RigidBody(3.0, np.diag([1.0, 2.0, 2.5])).set_initial(
        R=(2.0, -1.0, 0.5), A=cardan_to_matrix((0.4, 0.3, -0.6))))
    flex = system.add(FlexibleBodyFFR(beam_data, modes=6).set_initial(
        R=(-0.5, 0.2, 0.1), A=cardan_to_matrix((-0.2, 0.5, 0.9)), q_f=0.1 * rng.standard_normal(6)))
    spring = system.add(SpringDamper(rigid.frame_at((0.3, 0.2, -0.4)), flex.node(57), 7e3, 40.0,
                                     free_length=1.2))
    q, rest = system.initial_state()
    u = rng.standard_normal(system.nu)
    K, D = np.zeros((system.nu, system.nu)), np.zeros((system.nu, system.nu))
    spring.add_tangents(0.0, q, rest, K, D)
    K_fd = -central_difference(
        lambda du: spring_force(spring, system, 0.0, system.increment(q, du), rest), np.zeros(system.nu), 1e-6)
    np.testing.assert_allclose(K[:3], K_fd[:3], rtol=0, atol=1e-7 * np.abs(K_fd[:3]).max())
    K, D = np.zeros((system.nu, system.nu)), np.zeros((system.nu, system.nu))
    spring.add_tangents(0.0, q, u, K, D)
    # h is linear in u: a large step leaves no truncation error and little rounding
    D_fd = -central_difference(lambda v: spring_force(spring, system, 0.0, q, v), u, 1e-2)
    np.testing.assert_allclose(D, D_fd, rtol=0, atol=1e-10 * np.abs(D_fd).max())


def test_spring_inside_one_rigid_body_does_nothing():
    """Between two points of one rigid body at its free length: Q, K and D vanish (the
    two ends' Jacobians must be added into the same columns)."""
    system = System()
    rigid = system.add(RigidBody(2.0, np.diag([1.0, 2.0, 3.0])).set_initial(
        R=(0.5, 1.0, -0.3), A=cardan_to_matrix((0.3, -0.2, 0.5)), v=(1, 0, 2), omega=(0.5, -1, 2)))
    a, b = np.array([0.2, 0.1, -0.4]), np.array([-0.3, 0.5, 0.6])
    spring = SpringDamper(rigid.frame_at(a), rigid.frame_at(b), 1e3, 20.0,
                          free_length=np.linalg.norm(b - a))
    q, u = system.initial_state()
    K, D = np.zeros((6, 6)), np.zeros((6, 6))
    spring.add_tangents(0.0, q, u, K, D)
    scale = 1e3 * np.linalg.norm(b - a)
    np.testing.assert_allclose(spring_force(spring, system, 0.0, q, u), 0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(K, 0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(D, 0.0, atol=1e-12 * 20.0)


def test_coincident_points():
    system = System()
    mass = system.add(PointMass(1.0, position=(0.5, 0.5, 0.5)))
    at_mass = ground_frame((0.5, 0.5, 0.5))
    q, u = system.initial_state()
    u[:] = (1.0, 0.0, 0.0)
    for spring in (SpringDamper(at_mass, mass.point, 10.0, free_length=0.1),
                   SpringDamper(at_mass, mass.point, 10.0, 1.0, free_length=0.0)):
        with pytest.raises(ModelError, match="coincide at t = 0.0 s"):
            spring.add_forces(0.0, q, u, np.zeros(3))
    zero_length = SpringDamper(at_mass, mass.point, 10.0, free_length=0.0)
    assert not spring_force(zero_length, system, 0.0, q, u).any()
    K, D = np.zeros((3, 3)), np.zeros((3, 3))
    zero_length.add_tangents(0.0, q, u, K, D)
    np.testing.assert_array_equal(K, 10.0 * np.eye(3))
    assert not D.any()


def test_parameter_errors():
    point = PointMass(1.0).point
    with pytest.raises(ModelError, match="stiffness must be finite and >= 0"):
        SpringDamper(ground_frame(), point, -1.0, free_length=0.0)
    with pytest.raises(ModelError, match="damping must be finite and >= 0"):
        SpringDamper(ground_frame(), point, 1.0, np.nan, free_length=0.0)
    with pytest.raises(ModelError, match="both frames are fixed"):
        SpringDamper(ground_frame(), ground_frame((1, 0, 0)), 1.0, free_length=0.0)
    with pytest.raises(TypeError, match="free_length"):
        SpringDamper(ground_frame(), point, 1.0)
