"""The body stage and its kernels against independent references: the shape-integral
formulas in numpy (:class:`mbs.bodies.shape_integrals.ShapeIntegrals`), the rigid body's and
the quaternion's numpy formulas, J_T written out (thesis eq. 2.70), scipy's Cholesky,
the System's numpy assembly, and generalized-α's previous algorithm (System assembly and
LAPACK) recomputed here; plus a count of numpy allocations in a steady step."""

import tracemalloc

import numpy as np
import pytest
import scipy.linalg

from mbs import (DistributedForce, FlexibleBodyFFR, Force, PointMass, PrescribedFrameMotion, RigidBody,
                 SpringDamper, System, Tabulated)
from mbs.bodies import _kernels as kern
from mbs.bodies import rotations as rot
from mbs.run.body_stage import BodyStage
from mbs.run.equations import Equations
from mbs.integrators.generalized_alpha import GeneralizedAlpha
from mbs.run.linalg_kernels import (block_cho_solve_matrix, block_cho_solve_vector, block_cholesky_into,
                                block_iteration_factor, cho_solve_into, cholesky_into)
from preprocess import box, build_body
from validation.cases.cantilever import MATERIAL

N_F = 5
SEEDS = range(6)


@pytest.fixture(scope="module")
def data():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, N_F, clamp=None)


def rel(a, b):
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


def random_quaternion_state(body, rng):
    q, u = body.q_init.copy(), rng.normal(size=body.nu)
    q[:3] = rng.normal(size=3)
    q[3:7] = rng.normal(size=4)
    q[3:7] /= np.linalg.norm(q[3:7])
    q[7:] = rng.normal(size=body.nq - 7)
    return q, u


def ffr_reference(body, A, w, q_f, qd_f):
    """(M̄, Q̄_v) in (Ṙ, ω̄, q̇_f) from ShapeIntegrals' numpy formulas (thesis eq. 2.44, 2.77–2.79)."""
    si = body.integrals
    S_t, I_thth, I_thf, G = si.deformed(q_f)
    n = 6 + body.n_modes
    M = np.zeros((n, n))
    M[:3, :3] = si.mass * np.eye(3)
    M[:3, 3:6] = -A @ rot.skew(S_t)
    M[:3, 6:] = A @ si.S_bar
    M[3:6, 3:6], M[3:6, 6:], M[6:, 6:] = I_thth, I_thf, si.M_ff
    M[3:, :3] = M[:3, 3:].T
    M[6:, 3:6] = I_thf.T
    return M, np.concatenate(si.quadratic_velocity(A, w, qd_f, S_t, I_thth, G))


# --- body kernels ----------------------------------------------------------------------

@pytest.mark.parametrize("seed", SEEDS)
def test_free_ffr_kernel_equals_shape_integral_formulas(data, seed):
    rng = np.random.default_rng(seed)
    body = FlexibleBodyFFR(data, N_F, rayleigh=(0.3, 1e-3))
    q, u = random_quaternion_state(body, rng)
    M, h = np.empty((body.nu, body.nu)), np.empty(body.nu)
    body.mass_and_h_into(q, u, 0.0, M, h, body.workspace())
    M_ref, Q_ref = ffr_reference(body, rot.quat_to_matrix(q[3:7]), u[3:6], q[7:], u[6:])
    h_ref = Q_ref.copy()
    h_ref[6:] -= body.K_ff @ q[7:] + body.D_ff @ u[6:]
    assert rel(M, M_ref) < 1e-12
    assert rel(h, h_ref) < 1e-12
    h2 = np.empty(body.nu)
    body.h_into(q, u, 0.0, h2, body.workspace())
    assert np.array_equal(h2, h)


@pytest.mark.parametrize("seed", SEEDS)
def test_prescribed_ffr_kernel_equals_shape_integral_formulas(data, seed):
    """M = M̄_ff, h = Q̄_f − M̄_fR R̈ − M̄_fθ ω̄̇ − K q_f − D q̇_f on a moving prescribed frame."""
    rng = np.random.default_rng(seed)
    A0 = rot.quat_to_matrix(rot.quat_from_rotvec(rng.normal(size=3)))
    w, wd, a_R = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    motion = PrescribedFrameMotion(lambda t: (np.zeros(3), np.zeros(3), a_R), lambda t: (A0, w, wd))
    body = FlexibleBodyFFR(data, N_F, frame=motion, modal_damping=0.02)
    q, u = rng.normal(size=N_F), rng.normal(size=N_F)
    M, h = np.empty((N_F, N_F)), np.empty(N_F)
    body.mass_and_h_into(q, u, 0.3, M, h, body.workspace())
    Mb, Qb = ffr_reference(body, A0, w, q, u)
    h_ref = Qb[6:] - Mb[6:, :3] @ a_R - Mb[6:, 3:6] @ wd - body.K_ff @ q - body.D_ff @ u
    assert rel(M, Mb[6:, 6:]) < 1e-12
    assert rel(h, h_ref) < 1e-12


def test_fixed_frame_ffr_in_place_equals_constant_mass_and_elastic_forces(data):
    body = FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed(), rayleigh=(0.1, 1e-3))
    rng = np.random.default_rng(1)
    q, u = rng.normal(size=N_F), rng.normal(size=N_F)
    M, h = np.empty((N_F, N_F)), np.empty(N_F)
    body.mass_and_h_into(q, u, 0.0, M, h, body.workspace())
    assert rel(M, body.integrals.M_ff) < 1e-12
    assert rel(h, -(body.K_ff @ q + body.D_ff @ u)) < 1e-12


@pytest.mark.parametrize("seed", SEEDS)
def test_rigid_kernel_equals_newton_euler_formulas(seed):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(3, 3))
    body = RigidBody(2.5, X @ X.T + np.eye(3), com=rng.normal(size=3))
    q, u = random_quaternion_state(body, rng)
    M, h = np.empty((6, 6)), np.empty(6)
    body.mass_and_h_into(q, u, 0.0, M, h, body.workspace())
    A, c, w, m = rot.quat_to_matrix(q[3:7]), body.com, u[3:6], body.mass
    M_ref = np.block([[m * np.eye(3), -m * A @ rot.skew(c)], [m * rot.skew(c) @ A.T, body.inertia_origin]])
    h_ref = np.concatenate((-m * A @ np.cross(w, np.cross(w, c)), -np.cross(w, body.inertia_origin @ w)))
    assert rel(M, M_ref) < 1e-12
    assert rel(h, h_ref) < 1e-12


@pytest.mark.parametrize("seed", SEEDS)
def test_quaternion_increment_kernel_equals_the_exponential_map(data, seed):
    rng = np.random.default_rng(seed)
    body = FlexibleBodyFFR(data, N_F)
    q, _ = random_quaternion_state(body, rng)
    du = rng.normal(size=body.nu) * (1e-6 if seed % 2 else 1.0)     # both branches of exp
    ref = np.concatenate((q[:3] + du[:3], rot.quat_multiply(q[3:7], rot.quat_from_rotvec(du[3:6])),
                          q[7:] + du[6:]))
    ref[3:7] /= np.linalg.norm(ref[3:7])
    out = np.empty(body.nq)
    kern.free_quat_increment(q, du, out)
    assert rel(out, ref) < 1e-14
    kern.free_quat_increment(q, du, q)          # in place
    assert np.array_equal(q, out)


@pytest.mark.parametrize("seed", SEEDS)
def test_quaternion_advance_kernel_equals_scaled_increment_and_normalization(data, seed):
    """free_quat_advance = (Δu = s u, q ⊕ Δu, renormalized) by the numpy exponential map."""
    rng = np.random.default_rng(seed)
    body = FlexibleBodyFFR(data, N_F)
    q, u = random_quaternion_state(body, rng)
    s = 1e-3 * (seed + 1)
    du_ref = u * s
    ref = np.concatenate((q[:3] + du_ref[:3], rot.quat_multiply(q[3:7], rot.quat_from_rotvec(du_ref[3:6])),
                          q[7:] + du_ref[6:]))
    ref[3:7] /= np.linalg.norm(ref[3:7])
    out, du = np.empty(body.nq), np.empty(body.nu)
    kern.free_quat_advance(q, u, s, du, out)
    assert np.array_equal(du, du_ref) and rel(out, ref) < 1e-14


@pytest.mark.parametrize("seed", SEEDS)
def test_point_force_kernel_equals_jacobian_transpose(data, seed):
    """h += J_Tᵀ F with J_T = [1, −A ũ, A Φ] (thesis eq. 2.70), F from a step table."""
    rng = np.random.default_rng(seed)
    body = FlexibleBodyFFR(data, N_F)
    q, _ = random_quaternion_state(body, rng)
    u0, phi = rng.normal(size=3), rng.normal(size=(3, N_F))
    times, values = np.array([0.0, 0.5]), rng.normal(size=(2, 3))
    A = rot.quat_to_matrix(q[3:7])
    ub = u0 + phi @ q[7:]
    J = np.hstack([np.eye(3), -A @ rot.skew(ub), A @ phi])
    for t, row in ((-0.1, None), (0.2, 0), (0.7, 1)):
        for body_axes in (False, True):
            h = np.ones(body.nu)
            kern.add_free_point_force(q, u0, phi, times, values, t, body_axes, np.empty((3, 3)), h)
            F = np.zeros(3) if row is None else (A @ values[row] if body_axes else values[row])
            assert rel(h, 1.0 + J.T @ F) < 1e-13


# --- linear algebra --------------------------------------------------------------------

@pytest.mark.parametrize("n", [1, 4, 17])
def test_cholesky_and_solves_equal_scipy(n):
    rng = np.random.default_rng(n)
    X = rng.normal(size=(n, n))
    A = X @ X.T + n * np.eye(n)
    L = np.full((n, n), np.nan)
    assert cholesky_into(A, L) == 0
    assert rel(L, scipy.linalg.cholesky(A, lower=True)) < 1e-13
    b, B = rng.normal(size=n), rng.normal(size=(n, 3))
    x, X_ = np.empty(n), np.empty((n, 3))
    cho_solve_into(L, b, x)
    cho_solve_into(L, B, X_)
    factor = scipy.linalg.cho_factor(A)
    assert rel(x, scipy.linalg.cho_solve(factor, b)) < 1e-12
    assert rel(X_, scipy.linalg.cho_solve(factor, B)) < 1e-12
    cho_solve_into(L, b, b)                     # in place
    assert np.array_equal(b, x)
    A2 = A.copy()
    assert cholesky_into(A2, A2) == 0 and np.array_equal(A2, L)


def test_block_cholesky_and_solves_equal_scipy_on_the_active_rows():
    """A block-diagonal matrix with rows 5, 6 left out (idle): the block factor and
    solves equal scipy's on the active rows and give zero on the idle ones."""
    rng = np.random.default_rng(11)
    blocks = np.array([[0, 3], [3, 5], [7, 11]], dtype=np.int64)
    idle = np.array([5, 6], dtype=np.int64)
    n = 11
    A = np.zeros((n, n))
    for a, b in blocks:
        X = rng.normal(size=(b - a, b - a))
        A[a:b, a:b] = X @ X.T + (b - a) * np.eye(b - a)
    A[5:7, 5:7] = np.nan                          # never read
    L = np.zeros((n, n))
    assert block_cholesky_into(A, blocks, L) == 0
    act = np.setdiff1d(np.arange(n), idle)
    factor = scipy.linalg.cho_factor(A[np.ix_(act, act)])
    b, B = rng.normal(size=n), rng.normal(size=(n, 3))
    x, X_ = np.full(n, np.nan), np.full((n, 3), np.nan)
    block_cho_solve_vector(L, blocks, idle, b, x)
    block_cho_solve_matrix(L, blocks, idle, B, X_)
    assert rel(x[act], scipy.linalg.cho_solve(factor, b[act])) < 1e-12 and not x[idle].any()
    assert rel(X_[act], scipy.linalg.cho_solve(factor, B[act])) < 1e-12 and not X_[idle].any()
    A[8, 8] = -1.0
    assert block_cholesky_into(A, blocks, L) == 8 + 1


def test_linear_bodies_kernel_equals_elastic_and_point_mass_kernels_and_numpy():
    """linear_bodies_h over a damped and an undamped elastic block, a point mass with a
    constant force and a left-out block: bit for bit the kernels it replaces
    (elastic_h_into, point_masses_h), and −(K q + D u) / f / 0 in numpy to rounding."""
    rng = np.random.default_rng(8)
    nu = 4 + 3 + 5 + 2
    rows = np.array([[0, 4, kern.ELASTIC_DAMPED], [4, 7, kern.CONSTANT_FORCE], [7, 12, kern.ELASTIC],
                     [12, 14, kern.LEFT_OUT]], dtype=np.int64)
    KD = np.full((2, nu, nu), np.nan)             # only the diagonal blocks of the elastic rows are read
    KD[:, 0:4, 0:4] = rng.normal(size=(2, 4, 4))
    KD[0, 7:12, 7:12] = rng.normal(size=(5, 5))
    force = np.full(nu, np.nan)
    force[4:7] = rng.normal(size=3)
    q, u = rng.normal(size=nu), rng.normal(size=nu)
    h = np.full(nu, np.nan)
    kern.linear_bodies_h(rows, KD, force, q, u, h)
    ref = np.full(nu, np.nan)
    for a, b, damped in ((0, 4, True), (7, 12, False)):     # the blocks as a body holds them (C order)
        kern.elastic_h_into(KD[0, a:b, a:b].copy(), KD[1, a:b, a:b].copy(), damped, q[a:b], u[a:b], ref[a:b])
    kern.point_masses_h(np.array([4], dtype=np.int64), force[4:7].reshape(1, 3), ref)
    ref[12:] = 0.0
    np.testing.assert_array_equal(h, ref)
    assert rel(h[0:4], -(KD[0, 0:4, 0:4] @ q[0:4] + KD[1, 0:4, 0:4] @ u[0:4])) < 1e-14
    assert rel(h[7:12], -KD[0, 7:12, 7:12] @ q[7:12]) < 1e-14
    np.testing.assert_array_equal(h[4:7], force[4:7])
    rows[:, 2] = [kern.ELASTIC_DAMPED_LOADED, kern.CONSTANT_FORCE, kern.ELASTIC_LOADED, kern.LEFT_OUT]
    force[0:4], force[7:12] = rng.normal(size=4), rng.normal(size=5)
    kern.linear_bodies_h(rows, KD, force, q, u, h)
    ref[0:4] += force[0:4]                          # the load added after the elastic h
    ref[7:12] += force[7:12]
    np.testing.assert_array_equal(h, ref)


def test_additive_advance_equals_numpy_bit_for_bit():
    rng = np.random.default_rng(9)
    q, u, out = rng.normal(size=23), rng.normal(size=23), np.empty(23)
    kern.additive_advance(q, u, 0.37e-5, out)
    np.testing.assert_array_equal(out, np.add(q, np.multiply(u, 0.37e-5)))
    kern.additive_advance(q, u, 0.37e-5, q)                 # in place
    np.testing.assert_array_equal(q, out)


def test_linear_body_stage_equals_system_assembly_with_left_out_bodies(data):
    """The one-kernel body stage (a frame-fixed FFR body, point masses, a left-out body)
    is taken and gives the System's h and increment; with gravity or a load on the FFR
    body it is not taken (loads are added per step)."""
    for leave_out in (False, True):
        system = System()
        beam = system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed()))
        system.add(PointMass(0.5, velocity=(0.0, -0.2, 0.0)))
        other = system.add(PointMass(2.0, velocity=(1.0, 0.0, 0.0)))
        q, u = system.initial_state()
        q[beam.q_slice] = np.arange(N_F) * 1e-3
        u[:] = np.linspace(-1.0, 1.0, system.nu)
        if leave_out:
            u[other.u_slice] = 0.0                  # a left-out body's velocity is held at zero
        eq = Equations(system, [other], []) if leave_out else Equations(system, [], [])
        stage = BodyStage.of_equations(eq)
        assert stage.linear
        h = np.full(system.nu, np.nan)
        stage.h_only(0.0, q, u, h)
        assert rel(h, eq.h(0.0, q, u)) < 1e-12
        out = np.full(system.nq, np.nan)
        stage.advance(q, u, 1e-3, np.empty(system.nu), out)
        assert rel(out, eq.increment(q, 1e-3 * u)) < 1e-15
    system = System()
    beam = system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed()))
    system.add(Force(beam.node(0), (1.0, 0.0, 0.0)))
    assert not BodyStage.of_equations(system.equations()).linear


def test_block_iteration_factor_equals_numpy_sum_and_scipy_factor():
    """M̂ = (M + a D0) + b K0 equals the numpy sum bit for bit; its block factor scipy's."""
    rng = np.random.default_rng(5)
    blocks = np.array([[0, 4], [4, 9]], dtype=np.int64)
    n = 9
    M, K0, D0 = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    for a, b in blocks:
        for X in (M, K0, D0):
            Y = rng.normal(size=(b - a, b - a))
            X[a:b, a:b] = Y @ Y.T + (b - a) * np.eye(b - a)
    a, b = 5e-4, 2.5e-7
    A, L = np.zeros((n, n)), np.zeros((n, n))
    assert block_iteration_factor(M, K0, D0, a, b, blocks, A, L) == 0
    assert np.array_equal(A, np.add(np.add(M, np.multiply(D0, a)), np.multiply(K0, b)))
    for lo, hi in blocks:
        assert rel(np.tril(L[lo:hi, lo:hi]), scipy.linalg.cholesky(A[lo:hi, lo:hi], lower=True)) < 1e-13
    M[6, 6] = -1e6
    assert block_iteration_factor(M, K0, D0, a, b, blocks, A, L) > 0


def test_cholesky_reports_matrices_not_positive_definite():
    L = np.empty((3, 3))
    assert cholesky_into(np.diag([1.0, -1.0, 1.0]), L) == 2
    singular = np.array([[2.5, 0.0, -2.5], [0.0, 5.0, 0.0], [-2.5, 0.0, 2.5]])   # a zero pivot up to rounding
    assert cholesky_into(singular, L) == 3


# --- the stage against the System's assembly --------------------------------------------

def mixed_system(data, leave_out=False):
    """(system, its Equations, q, u): every body kind, gravity, springs, step and callable
    loads; ``leave_out``: the equations leave out two bodies and a load, as a plan does."""
    rng = np.random.default_rng(7)
    system = System(gravity=(0.3, -9.81, 1.0))
    free = system.add(FlexibleBodyFFR(data, N_F, rayleigh=(0.1, 1e-4), name="free"))
    cardan = system.add(FlexibleBodyFFR(data, N_F, rotation="cardan", name="cardan"))
    A0 = rot.quat_to_matrix(rot.quat_from_rotvec([0.2, -0.1, 0.4]))
    moving = system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion(
        lambda t: (np.zeros(3), np.zeros(3), np.array([0.0, t, 1.0])),
        lambda t: (A0, np.array([0.0, 1.0, t]), np.array([0.5, 0.0, 0.0]))), name="moving"))
    fixed = system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed(), modal_damping=0.01,
                                       name="fixed"))
    rigid = system.add(RigidBody(3.0, np.diag([1.0, 2.0, 3.0]), com=(0.1, 0.2, -0.3), name="rigid"))
    system.add(RigidBody(2.0, np.diag([1.0, 1.5, 2.0]), rotation="cardan", name="rigid cardan"))
    point = system.add(PointMass(0.7, position=(1.0, 2.0, 3.0), name="point"))
    system.add(SpringDamper(free.node(3), point.point, 1e3, 5.0, free_length=0.5))
    system.add(SpringDamper(rigid.frame_at((0.3, 0.0, 0.0)), system.ground, 50.0, free_length=0.1))
    nodes = data.u0[:, 2] > 4.9
    w = np.full(nodes.sum(), 1.0 / nodes.sum())
    system.add(DistributedForce(free, np.flatnonzero(nodes), w,
                                Tabulated([0.0, 0.5], [(1.0, 2.0, 3.0), (-4.0, 0.0, 1.0)])))
    system.add(Force(rigid.frame_at((0.0, 0.5, 0.0)), (0.0, 0.0, 7.0), frame_fixed=True))
    system.add(Force(point.point, Tabulated([0.2], [(1.0, 0.0, 0.0)], hold_first=True)))
    system.add(Force(cardan.node(5), lambda t: np.array([np.sin(t), 0.0, 1.0])))
    system.add(Force(moving.node(2), (0.0, 3.0, 0.0), frame_fixed=True))
    q, u = system.initial_state()
    for b in system.bodies:
        qs, us = b.q_slice, b.u_slice
        u[us] = rng.normal(size=b.nu)
        if getattr(b, "free_quaternion", False):
            q[qs][:3] = rng.normal(size=3)
            p = rng.normal(size=4)
            q[qs][3:7] = p / np.linalg.norm(p)
            q[qs][7:] = 1e-2 * rng.normal(size=b.nq - 7)
        else:
            q[qs] = 0.1 * rng.normal(size=b.nq)
    eq = Equations(system, [cardan, fixed], [system.forces[-2]]) if leave_out else system.equations()
    return system, eq, q, u


@pytest.mark.parametrize("leave_out", [False, True])
@pytest.mark.parametrize("t", [0.1, 0.7])
def test_stage_equals_system_assembly(data, leave_out, t):
    system, eq, q, u = mixed_system(data, leave_out)
    stage = BodyStage.of_equations(eq)
    nu = system.nu
    M, h, K, D = (np.full((nu, nu), np.nan), np.full(nu, np.nan), np.full((nu, nu), np.nan),
                  np.full((nu, nu), np.nan))
    stage.mass_and_h(t, q, u, M, h)
    M_ref, h_ref = eq.mass_and_h(t, q, u)
    assert rel(M, M_ref) < 1e-12
    assert rel(h, h_ref) < 1e-12
    h2 = np.full(nu, np.nan)
    stage.h_only(t, q, u, h2)
    assert rel(h2, eq.h(t, q, u)) < 1e-12
    stage.tangents(t, q, u, K, D)
    K_ref, D_ref = eq.tangents(t, q, u)
    assert rel(K, K_ref) < 1e-12 and rel(D, D_ref) < 1e-12
    du = 0.1 * np.random.default_rng(3).normal(size=nu)
    for b in eq.idle:
        du[b.u_slice] = 0.0
    out = np.full(system.nq, np.nan)
    stage.increment(q, du, out)
    ref = eq.increment(q, du)
    assert rel(out, ref) < 1e-14
    stage.normalize(out)
    eq.normalize(ref)
    assert rel(out, ref) < 1e-14
    assert stage.constant_iteration_matrix == eq.constant_iteration_matrix


def test_stage_of_one_frame_fixed_body_and_a_point_mass(data):
    """The default scene's bodies (constant M): h alone."""
    system = System()
    beam = system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed()))
    system.add(PointMass(0.5, velocity=(0.0, -0.2, 0.0)))
    q, u = system.initial_state()
    q[beam.q_slice] = np.arange(N_F) * 1e-3
    u[:] = np.linspace(-1.0, 1.0, system.nu)
    stage = BodyStage.of_equations(system.equations())
    assert stage.constant_iteration_matrix
    h = np.empty(system.nu)
    stage.h_only(0.0, q, u, h)
    assert rel(h, system.h(0.0, q, u)) < 1e-12


# --- generalized-α against its previous algorithm ---------------------------------------

class PreviousGeneralizedAlpha(GeneralizedAlpha):
    """The step as it was written before the body stage: System assembly, numpy
    temporaries, LAPACK's symmetric solver (no constraints)."""

    def start(self, t, q, u):
        self.t, self.q, self.u = t, q.copy(), u.copy()
        self.a, self.lam = self.system.accelerations(t, self.q, self.u)
        self.abar = self.a.copy()

    def step(self, h):
        sys = self.system
        am, af, gm, bt = self.alpha_m, self.alpha_f, self.gamma, self.beta
        c = (1 - af) / (1 - am)
        t1 = self.t + h
        K, D = sys.tangents(t1, self.q, self.u)
        stiff = bt * h * h * c * K + gm * h * c * D
        a1 = self.a.copy()
        base_u = self.u + h * (1 - gm) * self.abar
        base_dq = h * self.u + h * h * (0.5 - bt) * self.abar
        for _ in range(self.max_iter):
            abar1 = (af * self.a + (1 - af) * a1 - am * self.abar) / (1 - am)
            u1 = base_u + h * gm * abar1
            q1 = sys.increment(self.q, base_dq + h * h * bt * abar1)
            M, h1 = sys.mass_and_h(t1, q1, u1)
            da = scipy.linalg.solve(M + stiff, -(M @ a1 - h1), assume_a="sym", check_finite=False)
            a1 += da
            self.iterations += 1
            if np.abs(da).max() <= self.tol * (np.abs(a1).max() + 1e-300):
                break
        abar1 = (af * self.a + (1 - af) * a1 - am * self.abar) / (1 - am)
        self.u = base_u + h * gm * abar1
        self.q = sys.increment(self.q, base_dq + h * h * bt * abar1)
        sys.normalize(self.q)
        self.a, self.abar, self.t = a1, abar1, t1


def test_generalized_alpha_equals_its_previous_algorithm(data):
    runs = []
    for integrator in (GeneralizedAlpha, PreviousGeneralizedAlpha):
        system, _, q, u = mixed_system(data)
        u *= 0.1
        res = system.simulate(0.05, 1e-3, integrator=integrator, q0=q, u0=u, plan=False)
        runs.append(res)
    new, old = runs
    assert new.stats["newton_iterations"] == old.stats["newton_iterations"]
    assert rel(new.q, old.q) < 1e-12
    assert rel(new.u, old.u) < 1e-12


# --- allocations ------------------------------------------------------------------------

def free_flight_system(data, n_modes=N_F):
    """A free FFR body under two body-fixed step loads (the Exudyn free-flight scene)."""
    system = System()
    beam = system.add(FlexibleBodyFFR(data, n_modes, name="beam"))
    for z, f in ((5.0, -100.0), (0.0, 100.0)):
        nodes = np.flatnonzero(np.abs(data.u0[:, 2] - z) < 1e-9)
        system.add(DistributedForce(beam, nodes, np.full(nodes.size, 1.0 / nodes.size),
                                    Tabulated([0.0, 0.5], [(0.0, f, 0.0), (0.0, 3 * f, 0.0)])))
    return system


def memory_of(fn, repeats):
    """(numpy buffers left allocated, largest transient peak [bytes]) of ``repeats`` calls of
    ``fn``: the first counts array buffers (numpy's tracemalloc domain) still alive after
    the calls, the second the peak of all traced memory above its level at each call's
    start (Python objects included: it catches temporaries freed within the call)."""
    domain = np.lib.tracemalloc_domain
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        peak = 0
        for _ in range(repeats):
            current = tracemalloc.get_traced_memory()[0]
            tracemalloc.reset_peak()
            fn()
            peak = max(peak, tracemalloc.get_traced_memory()[1] - current)
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    filters = [tracemalloc.DomainFilter(True, domain)]
    stats = after.filter_traces(filters).compare_to(before.filter_traces(filters), "traceback")
    return sum(s.count_diff for s in stats if s.count_diff > 0), peak


@pytest.fixture(scope="module")
def data_60():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, 60, clamp=None)


def steady_step(data, n_modes, extra=None):
    """A function taking one steady generalized-α step of the free-flight scene (after
    the kernels compiled and the workspace was built); ``extra`` runs after it."""
    system = free_flight_system(data, n_modes)
    integ = GeneralizedAlpha(system)
    integ.compile()
    integ.start(0.0, *system.initial_state())
    for _ in range(3):
        integ.step(1e-3)

    def step():
        integ.step(1e-3)
        if extra is not None:
            extra(system.nu)
    return step


def test_steady_generalized_alpha_step_allocates_no_numpy_array(data, data_60):
    """No array outlives a step, and the step's transient memory does not grow with the
    body (a 5-mode and a 60-mode body: any temporary vector or matrix of size nu would
    differ by at least 55 x 8 bytes); the probe catches one temporary vector."""
    small, large = memory_of(steady_step(data, 5), 20), memory_of(steady_step(data_60, 60), 20)
    assert small[0] == large[0] == 0
    assert large[1] == small[1]
    probe = memory_of(steady_step(data_60, 60, lambda nu: np.zeros(nu) + 1.0), 20)
    assert probe[1] >= small[1] + 8 * 66


def test_stage_calls_allocate_no_numpy_array(data, data_60):
    peaks = []
    for d, n in ((data, 5), (data_60, 60)):
        system = free_flight_system(d, n)
        stage = BodyStage.of_equations(system.equations())
        q, u = system.initial_state()
        M, h, out = np.empty((system.nu, system.nu)), np.empty(system.nu), np.empty(system.nq)
        du = np.full(system.nu, 1e-3)

        def calls():
            stage.mass_and_h(0.1, q, u, M, h)
            stage.h_only(0.1, q, u, h)
            stage.increment(q, du, out)
            stage.normalize(out)
        calls()
        left, peak = memory_of(calls, 10)
        assert left == 0
        peaks.append(peak)
    assert peaks[0] == peaks[1]


@pytest.mark.parametrize("damped", [False, True])
def test_linear_energy_is_the_systems_energy(data, damped):
    """Frame-fixed FFR bodies and point masses, no gravity and no links: the one-kernel
    energy equals the System's sum of the bodies' kinetic and elastic energies on random
    states; with a link there is no one-kernel energy."""
    rng = np.random.default_rng(11)
    options = {"rayleigh": (0.1, 1e-4)} if damped else {}
    system = System()
    system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed(), **options))
    for k in range(3):
        system.add(PointMass(0.2 + k, position=(k, 0.0, 0.0)))
    stage = BodyStage.of_equations(system.equations())
    for _ in range(5):
        q, u = rng.normal(size=system.nq), rng.normal(size=system.nu)
        ref = system.kinetic_energy(0.0, q, u) + system.potential_energy(0.0, q)
        assert abs(stage.energy(q, u) - ref) <= 1e-13 * abs(ref)
    linked = System()
    beam = linked.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed()))
    mass = linked.add(PointMass(1.0, position=(0.0, 0.0, 7.0)))
    linked.add(SpringDamper(beam.node(0), mass.point, 10.0, free_length=1.0))
    assert BodyStage.of_equations(linked.equations()).energy(*linked.initial_state()) is None


def _heavy_scene(data, n_points, damped=False, lift=(0.0, 0.0, 0.0)):
    """A frame-fixed FFR body (its frame at ``lift`` [m], turned 0.3 rad about z when
    lifted) and ``n_points`` point masses under gravity, no links."""
    system = System(gravity=(0.3, -9.81, 1.0))
    options = {"rayleigh": (0.1, 1e-4)} if damped else {}
    c, s = np.cos(0.3), np.sin(0.3)
    A = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) if any(lift) else None
    system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed(lift, A), **options))
    for k in range(n_points):
        system.add(PointMass(0.5 + k, position=(k, 1.0, 0.0)))
    return system


@pytest.mark.parametrize("damped", [False, True])
@pytest.mark.parametrize("n_points", [0, 1, 2])
def test_gravity_on_a_body_at_rest_joins_the_linear_h_bit_for_bit(data, damped, n_points):
    """Gravity on a frame-fixed FFR body is the constant J_Tᵀ m g (thesis eq. 2.76):
    the one-kernel h equals the body stage's per-body path (elastic h, then the load
    added) to the bit and the System's numpy assembly to rounding."""
    rng = np.random.default_rng(21 + n_points)
    system = _heavy_scene(data, n_points, damped)
    stage = BodyStage.of_equations(system.equations())
    assert stage.linear
    q, u = rng.normal(size=system.nq) * 1e-3, rng.normal(size=system.nu)
    h = np.full(system.nu, np.nan)
    stage.h_only(0.2, q, u, h)
    per_body = BodyStage.of_equations(system.equations())
    per_body.linear = False                     # the per-body path: h_into, then the gravity loads
    ref = np.full(system.nu, np.nan)
    per_body.h_only(0.2, q, u, ref)
    np.testing.assert_array_equal(h, ref)
    assert rel(h, system.equations().h(0.2, q, u)) < 1e-12


@pytest.mark.parametrize("lift", [(0.0, 0.0, 0.0), (0.4, -2.0, 3.0)])
@pytest.mark.parametrize("n_points", [0, 1, 3])
def test_linear_energies_with_gravity_are_the_systems(data, n_points, lift):
    """Frame-fixed FFR bodies (also lifted off the origin) and point masses under
    gravity: the one-kernel (kinetic, potential) equal the System's sums over the bodies
    (½ uᵀ M u; ½ q_fᵀ K q_f − m g·r_com) to 1e-12 on random states."""
    rng = np.random.default_rng(31 + n_points)
    system = _heavy_scene(data, n_points, lift=lift)
    stage = BodyStage.of_equations(system.equations())
    for _ in range(4):
        q, u = rng.normal(size=system.nq), rng.normal(size=system.nu)
        kinetic, potential = stage.energies(q, u)
        ref_T, ref_V = system.kinetic_energy(0.0, q, u), system.potential_energy(0.0, q)
        assert abs(kinetic - ref_T) <= 1e-12 * abs(ref_T)
        assert abs(potential - ref_V) <= 1e-12 * max(abs(ref_V), abs(ref_T))


def test_a_lone_point_mass_under_gravity_is_linear():
    """One point mass alone (the bouncing ball): h = m g in the one kernel, bit for bit as
    the per-body path adds it, and its energy ½ m |u|² − m g·r."""
    system = System(gravity=(0.0, 0.0, -9.81))
    system.add(PointMass(2.0, position=(0.1, 0.2, 0.3), velocity=(1.0, -2.0, 0.5)))
    stage = BodyStage.of_equations(system.equations())
    assert stage.linear
    q, u = system.initial_state()
    h = np.full(3, np.nan)
    stage.h_only(0.0, q, u, h)
    np.testing.assert_array_equal(h, [0.0, 0.0, 2.0 * -9.81])
    kinetic, potential = stage.energies(q, u)
    assert kinetic == pytest.approx(0.5 * 2.0 * (1.0 + 4.0 + 0.25), rel=1e-15)
    assert potential == pytest.approx(2.0 * 9.81 * 0.3, rel=1e-15)


def test_linear_energy_of_point_masses_under_gravity():
    """Point masses alone under gravity: ½ m |u|² − m g·r summed, as the System sums it."""
    rng = np.random.default_rng(12)
    system = System(gravity=(0.3, -9.81, 1.0))
    for k in range(3):
        system.add(PointMass(0.5 + k))
    stage = BodyStage.of_equations(system.equations())
    q, u = rng.normal(size=system.nq), rng.normal(size=system.nu)
    ref = system.kinetic_energy(0.0, q, u) + system.potential_energy(0.0, q)
    assert abs(stage.energy(q, u) - ref) <= 1e-13 * abs(ref)


@pytest.fixture(scope="module")
def stiff_data():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, N_F, clamp=None, geometric_stiffness=True)


@pytest.mark.parametrize("n_points", [0, 2])
@pytest.mark.parametrize("stiffened", [False, True])
def test_free_frame_energies_are_the_systems(data, stiff_data, n_points, stiffened):
    """FFR bodies on free quaternion frames (one with geometric stiffening) beside point
    masses under gravity: the per-body kernels' (kinetic, potential) equal the System's
    sums (T = ½ ūᵀ M̄ ū from the frame's velocities, ½ q_fᵀ K q_f, −m g·r_com at the
    centre-of-mass frame) to 1e-12 on random turned and deformed states."""
    rng = np.random.default_rng(7 + n_points + 10 * stiffened)
    system = System(gravity=(0.4, -9.81, 2.0))
    system.add(FlexibleBodyFFR(stiff_data if stiffened else data, N_F, geometric_stiffening=stiffened, name="a"))
    system.add(FlexibleBodyFFR(data, N_F, name="b"))
    for k in range(n_points):
        system.add(PointMass(0.3 + k, position=(0.1, 0.2, 0.3)))
    stage = BodyStage.of_equations(system.equations())
    assert stage.energies(*system.initial_state()) is not None
    for _ in range(4):
        q, u = rng.normal(size=system.nq), rng.normal(size=system.nu)
        for b in system.bodies[:2]:
            q[b.q_slice] = random_quaternion_state(b, rng)[0]
        kinetic, potential = stage.energies(q, u)
        ref_T, ref_V = system.kinetic_energy(0.0, q, u), system.potential_energy(0.0, q)
        assert abs(kinetic - ref_T) <= 1e-12 * abs(ref_T)
        assert abs(potential - ref_V) <= 1e-12 * max(abs(ref_V), abs(ref_T))


def test_a_force_element_or_another_frame_leaves_the_energies_to_the_system(data):
    """A spring between two free bodies, or a Cardan frame: no kernel sum (None)."""
    system = System(gravity=(0.0, 0.0, -9.81))
    a = system.add(FlexibleBodyFFR(data, N_F, name="a"))
    b = system.add(FlexibleBodyFFR(data, N_F, name="b"))
    system.add(SpringDamper(a.node(3), b.node(4), 1e3, 5.0, free_length=0.5))
    assert BodyStage.of_equations(system.equations()).energies(*system.initial_state()) is None
    system = System()
    system.add(FlexibleBodyFFR(data, N_F, rotation="cardan"))
    assert BodyStage.of_equations(system.equations()).energies(*system.initial_state()) is None
