"""FlexibleBodyFFR against independent oracles: brute-force node sums, Lagrange's equations
by finite differences of the kinetic energy, the rigid limit, Jacobians by finite
differences, and the Cardan and quaternion parametrizations against each other."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mbs import FlexibleBodyFFR, PrescribedFrameMotion, RigidBody
from mbs.bodies import rotations as rot
from preprocess import box, build_body
from validation.cases.cantilever import MATERIAL

N_F = 6
seeds = st.integers(0, 2**32 - 1)


@pytest.fixture(scope="module")
def data():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, N_F, clamp=None)


@pytest.fixture(scope="module")
def bodies(data):
    return {r: FlexibleBodyFFR(data, N_F, rotation=r) for r in ("quaternion", "cardan")}


def random_state(body, seed, qf_scale=1.0):
    """A random state; q_f of order 1 kg^½ m (elastic displacements of millimetres,
    exaggerated so that the q_f-dependent terms weigh)."""
    rng = np.random.default_rng(seed)
    q, u = np.zeros(body.nq), rng.normal(size=body.nu)
    q[:3] = rng.normal(size=3)
    if body.param.name == "quaternion":
        p = rng.normal(size=4)
        q[3:7] = p / np.linalg.norm(p)
    else:
        q[3:6] = rng.uniform(-1.2, 1.2, size=3)
    q[body.q_f_slice] = qf_scale * rng.normal(size=body.n_modes)
    return q, u


def frame_terms(body, q, u):
    """(A, T, ω̄, Ṫ u_r) written out from the parametrization formulas (thesis eq. 2.22, 2.31)."""
    if body.param.name == "quaternion":
        return rot.quat_to_matrix(q[3:7]), np.eye(3), u[3:6], np.zeros(3)
    th, thd = q[3:6], u[3:6]
    G = rot.cardan_G_bar(th)
    return rot.cardan_to_matrix(th), G, G @ thd, rot.cardan_G_bar_dot(th, thd) @ thd


def brute_force(body, q, u):
    """Per node j: J_Tj = [1, −A ũ_j T, A Φ_j] (thesis eq. 2.70) and J̇_Tj u as the time
    derivative of that product (Ȧ = A ω̃, d ũ_j/dt = (Φ_j q̇_f)~); returns
    (M = Σ m_j J_Tjᵀ J_Tj, Q_v = −Σ m_j J_Tjᵀ J̇_Tj u)."""
    d = body.data
    A, T, w, Tdu = frame_terms(body, q, u)
    q_f, qd = q[-N_F:], u[-N_F:]
    P = body.phi.reshape(d.n_nodes, 3, N_F)
    M = np.zeros((body.nu, body.nu))
    Q = np.zeros(body.nu)
    for j in range(d.n_nodes):
        ub = d.u0[j] + P[j] @ q_f
        J = np.hstack([np.eye(3), -A @ rot.skew(ub) @ T, A @ P[j]])
        Jd_u = (A @ rot.skew(w)) @ (-rot.skew(ub) @ T @ u[3:6] + P[j] @ qd) \
            + A @ (-rot.skew(P[j] @ qd) @ T @ u[3:6] - rot.skew(ub) @ Tdu)
        M += d.masses[j] * J.T @ J
        Q -= d.masses[j] * J.T @ Jd_u
    return M, Q


def quadratic_velocity(body, q, u):
    """Q_v = h + K q_f (no damping): the body's h without the elastic force."""
    Q = body.h(q, u).copy()
    Q[-N_F:] += body.K_ff @ q[-N_F:]
    return Q


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@settings(max_examples=15, deadline=None)
@given(seed=seeds, rotation=st.sampled_from(["quaternion", "cardan"]))
def test_mass_matrix_and_quadratic_velocity_equal_node_sums(bodies, seed, rotation):
    body = bodies[rotation]
    q, u = random_state(body, seed)
    M_ref, Q_ref = brute_force(body, q, u)
    assert rel(body.mass_matrix(q), M_ref) < 1e-10
    assert rel(quadratic_velocity(body, q, u), Q_ref) < 1e-10


@settings(max_examples=10, deadline=None)
@given(seed=seeds)
def test_numba_kernel_equals_numpy_reference(bodies, seed):
    """mbs.bodies._kernels.ffr_mass_and_qv against ShapeIntegrals.deformed / quadratic_velocity."""
    body = bodies["quaternion"]
    q, u = random_state(body, seed)
    A, si = rot.quat_to_matrix(q[3:7]), body.integrals
    M, Q = body._dynamics(A, q[-N_F:], u[3:6], u[-N_F:])
    S_t, I_thth, I_thf, G = si.deformed(q[-N_F:])
    M_ref = np.zeros_like(M)
    M_ref[:3, :3] = si.mass * np.eye(3)
    M_ref[:3, 3:6] = -A @ rot.skew(S_t)
    M_ref[:3, 6:] = A @ si.S_bar
    M_ref[3:6, 3:6], M_ref[3:6, 6:], M_ref[6:, 6:] = I_thth, I_thf, si.M_ff
    M_ref[3:, :3] = M_ref[:3, 3:].T
    M_ref[6:, 3:6] = I_thf.T
    Q_ref = np.concatenate(si.quadratic_velocity(A, u[3:6], u[-N_F:], S_t, I_thth, G))
    assert rel(M, M_ref) < 1e-13
    assert rel(Q, Q_ref) < 1e-13


@settings(max_examples=10, deadline=None)
@given(seed=seeds)
def test_lagrange_equations_by_finite_differences(bodies, seed):
    """Cardan coordinates (u = q̇): M = ∂²T/∂q̇² and Q_v = −Ṁ q̇ + ∂T/∂q (thesis eq. 2.77),
    with T = ½ Σ m_j |J_Tj q̇|² summed over the nodes and derivatives by central differences."""
    body = bodies["cardan"]
    q, qd = random_state(body, seed)
    d = body.data
    P = body.phi.reshape(d.n_nodes, 3, N_F)

    def node_velocities(q, qd):
        A, T, _, _ = frame_terms(body, q, qd)
        ub = d.u0 + P @ q[-N_F:]
        return qd[:3] + (np.cross(T @ qd[3:6], ub) + P @ qd[-N_F:]) @ A.T

    def kinetic(q, qd):
        v = node_velocities(q, qd)
        return 0.5 * np.sum(d.masses * np.sum(v * v, axis=1))

    # T is quadratic in q̇: central differences in q̇ are exact for any step, so take 1
    eps = 1e-6
    E = np.eye(body.nu)
    grad_qd = lambda q: np.array([(kinetic(q, qd + e) - kinetic(q, qd - e)) / 2 for e in E])
    Mqd_dot = (grad_qd(q + eps * qd) - grad_qd(q - eps * qd)) / (2 * eps)
    dT_dq = np.array([(kinetic(q + eps * e, qd) - kinetic(q - eps * e, qd)) / (2 * eps) for e in E])
    assert rel(quadratic_velocity(body, q, qd), -Mqd_dot + dT_dq) < 1e-6
    M_fd = np.array([[(kinetic(q, a + b) - kinetic(q, a - b)) / 2 for b in E] for a in E])
    assert rel(body.mass_matrix(q), M_fd) < 1e-6


@settings(max_examples=10, deadline=None)
@given(seed=seeds, rotation=st.sampled_from(["quaternion", "cardan"]))
def test_power_of_quadratic_velocity_forces(bodies, seed, rotation):
    """dT/dt at u̇ = 0 along the flow q ⊕ εu equals −uᵀ Q_v (Q_v = −Σ m Jᵀ J̇ u)."""
    body = bodies[rotation]
    q, u = random_state(body, seed)
    eps = 1e-6
    dT = (body.kinetic_energy(body.increment(q, eps * u), u)
          - body.kinetic_energy(body.increment(q, -eps * u), u)) / (2 * eps)
    assert abs(dT + u @ quadratic_velocity(body, q, u)) < 1e-6 * abs(u @ quadratic_velocity(body, q, u)) + 1e-9


@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
def test_rigid_limit_equals_rigid_body(data, rotation):
    """With no modes, FlexibleBodyFFR is the RigidBody with the lumped-mass inertia."""
    m = data.masses.sum()
    com = data.masses @ data.u0 / m
    r = data.u0 - com
    I_c = np.einsum("j,jk,jl->kl", data.masses, r, r)
    I_c = np.trace(I_c) * np.eye(3) - I_c
    flex = FlexibleBodyFFR(data, 0, rotation=rotation)
    rigid = RigidBody(m, I_c, com, rotation=rotation)
    for seed in range(5):
        q, u = random_state(flex, seed)
        assert rel(flex.mass_matrix(q), rigid.mass_matrix(q)) < 1e-12
        assert rel(flex.h(q, u), rigid.h(q, u)) < 1e-12


@settings(max_examples=10, deadline=None)
@given(seed=seeds, rotation=st.sampled_from(["quaternion", "cardan"]))
def test_jacobians_equal_finite_difference_velocities(bodies, seed, rotation):
    """J_T u = dr/dt and J_R u = ω by central differences along q ⊕ εu (q̇ = Y(q) u)."""
    body = bodies[rotation]
    q, u = random_state(body, seed, qf_scale=0.1)
    eps = 1e-6
    qp, qm = body.increment(q, eps * u), body.increment(q, -eps * u)
    frames = [body.node(0), body.node(body.data.n_nodes - 1), body.frame_at((0.3, -0.2, 4.0)),
              body.com_frame(), body.origin]
    for fr in frames:
        v_fd = (fr.position(qp) - fr.position(qm)) / (2 * eps)
        np.testing.assert_allclose(fr.J_T(q) @ u, v_fd, rtol=0, atol=1e-7 * np.abs(v_fd).max())
        np.testing.assert_allclose(fr.velocity(q, u), v_fd, rtol=0, atol=1e-7 * np.abs(v_fd).max())
    W = (body.orientation(qp) - body.orientation(qm)) / (2 * eps) @ body.orientation(q).T
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    np.testing.assert_allclose(body.J_R(q) @ u, omega, atol=1e-7 * np.abs(omega).max())


@settings(max_examples=10, deadline=None)
@given(seed=seeds, rotation=st.sampled_from(["quaternion", "cardan"]))
def test_bias_accelerations_by_finite_differences(bodies, seed, rotation):
    """J̇_T u: the acceleration of a point at u̇ = 0, by central differences of J_T u along
    the flow; for Cardan coordinates u = θ̇ is held fixed."""
    body = bodies[rotation]
    q, u = random_state(body, seed, qf_scale=0.1)
    eps = 1e-5
    qp, qm = body.increment(q, eps * u), body.increment(q, -eps * u)
    for fr in (body.node(3), body.frame_at((0.5, 0.5, 2.0))):
        fd = (fr.velocity(qp, u) - fr.velocity(qm, u)) / (2 * eps)
        np.testing.assert_allclose(fr.bias_T(q, u), fd, atol=1e-6 * np.abs(fd).max())
    fdR = (body.angular_velocity(qp, u) - body.angular_velocity(qm, u)) / (2 * eps)
    np.testing.assert_allclose(body.bias_R(q, u), fdR, atol=1e-6 * (np.abs(fdR).max() + 1e-3))


def test_cardan_and_quaternion_agree_on_accelerations(bodies):
    """The same physical state in both parametrizations gives the same node accelerations."""
    bq, bc = bodies["quaternion"], bodies["cardan"]
    for seed in range(5):
        qc, uc = random_state(bc, seed)
        A, T, w, _ = frame_terms(bc, qc, uc)
        qq = np.concatenate((qc[:3], rot.quat_from_matrix(A), qc[6:]))
        uq = np.concatenate((uc[:3], w, uc[6:]))
        ac = np.linalg.solve(bc.mass_matrix(qc), bc.h(qc, uc))
        aq = np.linalg.solve(bq.mass_matrix(qq), bq.h(qq, uq))
        fr_c, fr_q = bc.node(7), bq.node(7)
        np.testing.assert_allclose(fr_c.J_T(qc) @ ac + fr_c.bias_T(qc, uc),
                                   fr_q.J_T(qq) @ aq + fr_q.bias_T(qq, uq), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(ac[6:], aq[6:], rtol=1e-9, atol=1e-9)


def test_prescribed_frame_equals_free_body_under_the_same_motion(data, bodies):
    """Elastic accelerations of a body whose frame follows a prescribed motion equal the
    free body's when its frame accelerations are imposed (rows f of M̄ u̇ = h)."""
    free = bodies["quaternion"]
    rng = np.random.default_rng(3)
    p = rng.normal(size=4)
    A = rot.quat_to_matrix(p / np.linalg.norm(p))
    R, v, a = rng.normal(size=(3, 3))
    w, wd = rng.normal(size=(2, 3))
    motion = PrescribedFrameMotion(lambda t: (R, v, a), lambda t: (A, w, wd))
    bound = FlexibleBodyFFR(data, N_F, frame=motion)
    q_f, qd_f = rng.normal(size=(2, N_F))
    qb = np.concatenate((R, rot.quat_from_matrix(A), q_f))
    ub = np.concatenate((v, w, qd_f))
    M, h = free.mass_matrix(qb), free.h(qb, ub)
    qdd_free = np.linalg.solve(M[6:, 6:], h[6:] - M[6:, :3] @ a - M[6:, 3:6] @ wd)
    qdd_bound = np.linalg.solve(bound.mass_matrix(q_f), bound.h(q_f, qd_f))
    np.testing.assert_allclose(qdd_bound, qdd_free, rtol=1e-10, atol=1e-10 * np.abs(qdd_free).max())
    node = 11
    np.testing.assert_allclose(bound.node(node).position(q_f), free.node(node).position(qb), atol=1e-12)


def test_frame_fixed_body_is_a_set_of_modal_oscillators(data):
    """Frame fixed (thesis Sec. 5.1): M = Φᵀ M Φ = 1 and h = −K_ff q_f = −ω² q_f."""
    body = FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed())
    q = np.linspace(-1, 1, N_F)
    np.testing.assert_allclose(body.mass_matrix(q), np.eye(N_F), atol=1e-10)
    np.testing.assert_allclose(body.h(q, np.zeros(N_F)), -data.modal_eigenvalues() * q,
                               rtol=1e-8, atol=1e-6 * data.modal_eigenvalues().max())


def test_shape_integral_cost_is_independent_of_nodes(data):
    """Evaluating M and h touches only arrays of size O(n_f²): the body keeps no per-step
    reference to node arrays in the shape integrals."""
    body = FlexibleBodyFFR(data, N_F)
    sizes = [np.asarray(v).size for v in vars(body.integrals).values() if isinstance(v, np.ndarray)]
    assert max(sizes) <= 9 * N_F * N_F


def test_damping_rayleigh_and_modal(data):
    """Rayleigh D = α M_ff + β K_ff; modal damping gives each mode 2 ζ ω (report Sec. 7.1)."""
    omega2 = data.modal_eigenvalues()
    ray = FlexibleBodyFFR(data, N_F, rayleigh=(2.0, 1e-4))
    np.testing.assert_allclose(np.diag(ray.D_ff), 2.0 + 1e-4 * omega2, rtol=1e-8)
    modal = FlexibleBodyFFR(data, N_F, modal_damping=0.02)
    np.testing.assert_allclose(np.diag(modal.D_ff), 2 * 0.02 * np.sqrt(omega2), rtol=1e-6)


def test_mode_selection_and_errors(data):
    from ffrmbs.errors import ModelError

    body = FlexibleBodyFFR(data, [2, 0])
    np.testing.assert_array_equal(body.phi, data.phi[:, [2, 0]])
    for bad in (N_F + 1, [0, 0], [N_F]):
        with pytest.raises(ModelError):
            FlexibleBodyFFR(data, bad)
    with pytest.raises(ModelError, match="rotation parametrization"):
        FlexibleBodyFFR(data, 2, rotation="euler")
    with pytest.raises(ModelError, match="node"):
        body.node(10**6)


def test_node_positions_equal_node_frames(bodies):
    """The vectorized node positions (eq. 2.24) equal each node frame's position."""
    body = bodies["quaternion"]
    q, _ = random_state(body, 11)
    nodes = [0, 5, body.data.n_nodes - 1]
    expected = np.array([body.node(j).position(q) for j in nodes])
    np.testing.assert_allclose(body.node_positions(q, nodes), expected, atol=1e-13)
    np.testing.assert_allclose(body.node_positions(q)[nodes], expected, atol=1e-13)


@pytest.mark.parametrize("rotation, n_r", [("quaternion", 4), ("cardan", 3)])
def test_bounding_sphere_holds_every_node_by_the_public_constants(data, bodies, rotation, n_r):
    """The state layout q = (R, q_r, q_f), u = (Ṙ, ω̄, q̇_f) read through the public slices;
    rest_radius and mode_reach against the nodes and modes (brute force), and the
    bounding sphere, rest_radius + Σ mode_reach |q_f|, holds every node of random states."""
    body = bodies[rotation]
    assert (body.q_r_slice, body.q_f_slice, body.u_f_slice) == (slice(3, 3 + n_r), slice(3 + n_r, body.nq),
                                                                 slice(6, body.nu))
    centre = 0.5 * (data.u0.min(axis=0) + data.u0.max(axis=0))
    assert body.rest_radius == np.linalg.norm(data.u0 - centre, axis=1).max()
    phi = data.phi[:, :N_F].reshape(data.n_nodes, 3, N_F)
    np.testing.assert_allclose(body.mode_reach, [np.linalg.norm(phi[:, :, k], axis=1).max() for k in range(N_F)],
                               rtol=1e-15)
    for seed in range(3):
        q, _ = random_state(body, seed, qf_scale=0.1)
        c, radius = body.bounding_sphere(q)
        assert radius == pytest.approx(body.rest_radius + body.mode_reach @ np.abs(q[body.q_f_slice]), rel=1e-15)
        assert np.linalg.norm(body.node_positions(q) - c, axis=1).max() <= radius


def test_point_jacobian_kernel_matches_the_formula():
    """mbs.bodies._kernels.point_jacobian_T against J_T = [1, −A ũ T, A Φ] (thesis eq. 2.70) in numpy."""
    from mbs.bodies._kernels import point_jacobian_T
    from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix, skew

    rng = np.random.default_rng(3)
    A = quat_to_matrix(quat_from_rotvec(rng.normal(size=3)))
    T, ub, phi = rng.normal(size=(3, 3)), rng.normal(size=3), rng.normal(size=(3, 5))
    out = np.full((3, 11), np.nan)
    point_jacobian_T(A, T, ub, phi, True, 6, out)
    assert np.allclose(out, np.hstack([np.eye(3), -A @ skew(ub) @ T, A @ phi]), atol=1e-14)
    out = np.full((3, 5), np.nan)
    point_jacobian_T(A, T, ub, phi, False, 0, out)
    assert np.allclose(out, A @ phi, atol=1e-14)
