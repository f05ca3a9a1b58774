"""The Moreau step as stages over Model/Data (mbs.run.model, mbs.run.stages): no numpy array is
allocated in a steady step, for every registered pair kind, the in-place kernels agree with their numpy references,
and a planned run leaves the System as it was."""

import numpy as np
import pytest

from centre_scenes import PAIRS, centre_scene
from contact import BILATERAL_KINEMATICS, PAIR_KINEMATICS
from contact import _kernels as kern
from contact.kinematics import ACTIVE_AT, G_N_AT
from contact.solver import ProxSolver, _diagonal
from mbs.run import _stage_kernels as SK
from mbs.run import stages
from mbs.run.model import Data, compile_model
from validation.bench.pair_cost import pair_scene

from numpy_allocations import NumpyAllocations

REGISTERED = [(pair, False) for pair in PAIR_KINEMATICS.names()] + [(p, True) for p in BILATERAL_KINEMATICS.names()]


def _default_scene(side="point", contour="2s"):
    """The default scene's Model and Data, its contact one of :data:`centre_scenes.PAIRS`
    (a sphere starts its radius higher: the same gap)."""
    scene = centre_scene("impact", side, contour)
    system = scene.system
    model = compile_model(system, system.plan(0.1), theta=0.5, solver=ProxSolver("gauss-seidel", tol=1e-10,
                                                                                   max_iter=2000))
    data = Data(model)
    data.q[:], data.u[:] = system.initial_state()
    data.q[scene.mass.q_slice][1] += scene.contact.kinematics.radius
    return model, data


@pytest.mark.parametrize("side, contour", PAIRS)
def test_a_steady_step_allocates_no_numpy_array(side, contour):
    """The default scene (setup A, 20 modes, Δt = 1e-5 s) with every pair kind of a fused
    detection: 200 steps with the contact open (from 5 ms, it closes at 10 ms) and 200
    with it closed throughout, after warm-up steps that compile the kernels and build the
    factor of M̂ and the contact set: not one array (not even a 0-d one) is allocated."""
    model, data = _default_scene(side, contour)
    assert model.fused[0] is not None
    dt = 1e-5
    phases = {}
    while data.t < 0.04 and len(phases) < 2:
        before = data.stats["closed_contacts"]
        with NumpyAllocations() as count:
            for _ in range(200):
                stages.step(model, data, dt)
        closed = data.stats["closed_contacts"] - before
        if data.t > 0.005 and closed in (0, 200):
            phases.setdefault(closed, count.sizes)
    assert set(phases) == {0, 200}
    for closed, sizes in phases.items():
        assert sizes == [], (closed, len(sizes), sorted(set(sizes)))


def test_the_diagonal_floor_kernel_is_its_numpy_reference():
    rng = np.random.default_rng(3)
    for G in (rng.random((4, 4)), np.diag([1.0, 0.0, 1e-20, 2.0]), np.zeros((3, 3)), -np.eye(2)):
        d = np.empty(G.shape[0])
        kern.diagonal_floor(np.ascontiguousarray(G), 1e-14, d)
        np.testing.assert_array_equal(d, _diagonal(G))


def test_step_is_the_eight_stages_in_order():
    assert stages.STAGES == ("midpoint", "bodies", "contours", "detect", "constraints", "impulses", "velocity",
                             "position")
    model, data = _default_scene()
    other = Data(model)
    other.q[:], other.u[:] = data.q, data.u
    for _ in range(3):
        stages.step(model, data, 1e-5)
        for name in stages.STAGES:
            getattr(stages, name)(model, other, 1e-5)
    np.testing.assert_array_equal(data.q, other.q)
    np.testing.assert_array_equal(data.u, other.u)


def test_a_planned_run_leaves_the_system_as_it_was():
    """The plan's modal bodies are left out of the compiled model, not of the System."""
    from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
    from ffrmbs_app.scenes import point_mass_beam as pmb

    system = System()
    beam = system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=5, frame=PrescribedFrameMotion.fixed()))
    mass = system.add(PointMass(1.0, velocity=(1.0, 0.0, 0.0)))
    plan = system.plan(0.01)
    model = compile_model(system, plan)
    assert model.idle == (beam,) and model.equations.active == (mass,)
    assert list(model.active_u) == list(range(beam.nu, beam.nu + 3))
    assert system.equations().active == (beam, mass) and not hasattr(system, "leave_out")
    res = system.simulate(0.01, 1e-3, integrator="rk4")
    assert system.equations().idle == () and res.stats["steps"] == 10
    np.testing.assert_allclose(res.q[-1, beam.nu], 0.01, rtol=1e-12)


def test_contact_problem_velocity_and_work_kernels_equal_numpy():
    """Stage kernels (mbs.run._stage_kernels) against numpy's products, W and M̂⁻¹W in the
    layout of Data.problem (C order), m = 1..3 rows."""
    from mbs.run import _stage_kernels as SK

    rng = np.random.default_rng(3)
    for m in (1, 2, 3):
        nu = 23
        W = rng.normal(size=(nu, m))
        MW = rng.normal(size=(nu, m))
        u_free, u, lam = rng.normal(size=nu), rng.normal(size=nu), rng.normal(size=m)
        offset, closing, gamma_plus = rng.normal(size=m), rng.normal(size=m), rng.normal(size=m)
        G, xi_free, gamma_pre = np.empty((m, m)), np.empty(m), np.empty(m)
        SK.contact_problem_into(W, MW, u_free, u, offset, closing, G, xi_free, gamma_pre)
        np.testing.assert_allclose(G, W.T @ MW, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(xi_free, W.T @ u_free + offset + closing, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(gamma_pre, W.T @ u + offset, rtol=1e-13, atol=1e-13)
        out = np.empty(nu)
        SK.velocity_into(u_free, MW, lam, out)
        np.testing.assert_allclose(out, u_free + MW @ lam, rtol=1e-13, atol=1e-13)
        ref = 0.5 * lam @ (gamma_plus - closing + gamma_pre)
        assert abs(SK.impulse_work(lam, gamma_plus, closing, gamma_pre) - ref) <= 1e-13 * max(1.0, abs(ref))


def test_free_velocity_kernels_equal_numpy_and_scipy():
    """u_free = u + M̂⁻¹ h Δt by the block kernel against scipy's Cholesky solve on the
    active rows (zero increment on a left-out row), and stage 7's open update."""
    import scipy.linalg

    from mbs.run import _stage_kernels as SK
    from mbs.run.linalg_kernels import block_cholesky_into

    rng = np.random.default_rng(4)
    blocks = np.array([[0, 4], [4, 7]], dtype=np.int64)
    idle = np.array([7], dtype=np.int64)
    n = 8
    A = np.eye(n)
    for a, b in blocks:
        X = rng.normal(size=(b - a, b - a))
        A[a:b, a:b] = X @ X.T + (b - a) * np.eye(b - a)
    L = np.zeros((n, n))
    assert block_cholesky_into(A, blocks, L) == 0
    h, u, dt = rng.normal(size=n), rng.normal(size=n), 1e-3
    u_free = np.full(n, np.nan)
    SK.free_velocity(L, blocks, idle, h, dt, u, u_free)
    ref = u.copy()
    ref[:7] += scipy.linalg.cho_solve(scipy.linalg.cho_factor(A[:7, :7]), h[:7] * dt)
    np.testing.assert_allclose(u_free, ref, rtol=1e-13, atol=1e-15)
    assert u_free[7] == u[7]
    u_prev = np.full(n, np.nan)
    u_new = u.copy()
    SK.free_velocity_update(u_new, u_free, u_prev)
    np.testing.assert_array_equal(u_prev, u)
    np.testing.assert_array_equal(u_new, u_free)


def _closed_set_reference(located, live, table, contact_f, warm, comp_force, comp_delta, n_c):
    """The detection stage's bookkeeping as a loop over the contact objects' fields."""
    closed, closed_idx, m, largest = {}, [], n_c, 0.0
    for i in live:
        kin, at = table[i, SK.KIN_AT], table[i, SK.LAM_AT]
        c = bool(located[i])
        compliant = bool(table[i, SK.COMPLIANT]) and bool(warm[i])
        if not c and compliant and comp_force[at] > 0.0 and bool(contact_f[kin + ACTIVE_AT]):
            c = True
        closed[i] = c
        if c:
            if table[i, SK.DIM]:
                closed_idx.append(i)
                m += table[i, SK.DIM]
            if table[i, SK.UNILATERAL]:
                pen = -contact_f[kin + G_N_AT] - (comp_delta[at] if compliant else 0.0)
                largest = max(largest, pen)
    return closed, closed_idx, m, largest


@pytest.mark.parametrize("seed", range(6))
def test_the_closed_set_kernel_is_the_loop_over_the_contacts(seed):
    """Random contact tables (set-valued of 1–3 rows or single-valued, unilateral or not,
    compliant or not), gaps, active flags, springs and live sets: the kernel's closed
    flags, closed set, rows and largest penetration are the loop's."""
    rng = np.random.default_rng(seed)
    n, width = 9, 20
    table = np.zeros((n, SK.TABLE_COLUMNS), dtype=np.int64)
    table[:, SK.KIN_AT] = np.arange(n) * width
    table[:, SK.DIM] = rng.choice([0, 1, 2, 3], size=n)
    table[:, SK.LAM_AT] = np.concatenate(([0], np.cumsum(table[:-1, SK.DIM])))
    table[:, SK.UNILATERAL] = rng.random(n) < 0.8
    table[:, SK.COMPLIANT] = rng.random(n) < 0.5
    contact_f = rng.normal(scale=1e-6, size=n * width)
    contact_f[table[:, SK.KIN_AT] + ACTIVE_AT] = rng.random(n) < 0.7
    rows = int(table[:, SK.DIM].sum()) + 1
    comp_force, comp_delta = rng.normal(size=rows), rng.normal(scale=1e-7, size=rows)
    located, warm = rng.random(n) < 0.4, rng.random(n) < 0.6
    live = np.sort(rng.choice(n, size=6, replace=False)).astype(np.intp)
    closed, closed_idx = np.zeros(n, dtype=bool), np.zeros(n, dtype=np.intp)
    n_closed, m, largest = SK.closed_set(located, live, live.size, table, contact_f, warm, comp_force, comp_delta,
                                         closed, closed_idx, 2)
    ref_closed, ref_idx, ref_m, ref_largest = _closed_set_reference(located, live, table, contact_f, warm,
                                                                    comp_force, comp_delta, 2)
    assert {i: bool(closed[i]) for i in live} == ref_closed
    assert closed_idx[:n_closed].tolist() == ref_idx and m == ref_m and largest == ref_largest


def test_warm_start_kernels_equal_the_loops_over_the_closed_contacts():
    """warm_start_into / keep_warm_start_into against the Python loops over the closed
    contacts (blocks of dims 1, 3, 2, 1 at lam_at in lam_prev; two joint rows first)."""
    rng = np.random.default_rng(6)
    dims = [1, 3, 2, 1]
    lam_at = [0, 1, 4, 6]
    table = np.zeros((4, SK.TABLE_COLUMNS), dtype=np.int64)        # the contact table's columns
    table[:, SK.LAM_AT], table[:, SK.DIM] = lam_at, dims
    n_c = 2
    closed_idx = np.array([1, 2, 3, 0], dtype=np.intp)
    n_closed = 3                                  # contacts 1, 2, 3
    warm = np.array([True, True, False, True])
    lam_prev = rng.normal(size=7)
    m = n_c + 3 + 2 + 1
    lam = np.full(m, np.nan)
    SK.warm_start_into(table, closed_idx, n_closed, warm, lam_prev, n_c, lam)
    ref = np.zeros(m)
    row = n_c
    for i in closed_idx[:n_closed]:
        if warm[i]:
            ref[row:row + dims[i]] = lam_prev[lam_at[i]:lam_at[i] + dims[i]]
        row += dims[i]
    np.testing.assert_array_equal(lam, ref)
    new = rng.normal(size=m)
    prev_ref, warm_ref = lam_prev.copy(), np.zeros(4, dtype=bool)
    row = n_c
    for i in closed_idx[:n_closed]:
        prev_ref[lam_at[i]:lam_at[i] + dims[i]] = new[row:row + dims[i]]
        warm_ref[i] = True
        row += dims[i]
    SK.keep_warm_start_into(table, closed_idx, n_closed, new, n_c, warm, lam_prev)
    np.testing.assert_array_equal(lam_prev, prev_ref)
    np.testing.assert_array_equal(warm, warm_ref)


@pytest.mark.parametrize("side, surface", [("point", "plane"), ("sphere", "plane"), ("sphere", "sphere")])
def test_a_steady_step_of_an_analytic_pair_allocates_no_numpy_array(side, surface):
    """A ball (a point mass: its point or a sphere of 10 mm about it) dropped from 10 mm
    onto the ground — a tilted plane, or the top of a sphere of 50 mm — under gravity,
    Newton's e = 0, Δt = 1e-4 s: 200 steps falling and 200 resting, after warm-up steps:
    not one array is allocated (the fused detection of the pair, mbs.run.fused_detection)."""
    from contact import connect
    from contours import PlaneContour, PointContour, SphereContour
    from mbs import PointMass, System, ground_frame
    from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix

    A = quat_to_matrix(quat_from_rotvec([0.2, -0.1, 0.0]))
    system = System(gravity=tuple(-9.81 * A[:, 2]))      # gravity along the plane's normal: the ball rests
    radius = 0.01 if side == "sphere" else 0.0
    ground = PlaneContour(ground_frame((0.0, 0.0, 0.0), A)) if surface == "plane" else \
        SphereContour(ground_frame((0.0, 0.0, -0.05)), 0.05)
    start = (0.0, 0.0, 0.01 + radius) if surface == "sphere" else tuple((0.01 + radius) * A[:, 2])
    if surface == "sphere":
        system = System(gravity=(0.0, 0.0, -9.81))
    ball = system.add(PointMass(0.1, position=start))
    contour = SphereContour(ball.point, radius) if side == "sphere" else PointContour(ball.point)
    system.add(connect(contour, ground, "impact"))
    model = compile_model(system, system.plan(0.2), theta=0.5,
                          solver=ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000))
    assert model.fused[0] is not None
    data = Data(model)
    data.q[:], data.u[:] = system.initial_state()
    for _ in range(20):
        stages.step(model, data, 1e-4)
    phases = {}
    while data.t < 0.2 and len(phases) < 2:
        before = data.stats["closed_contacts"]
        with NumpyAllocations() as count:
            for _ in range(200):
                stages.step(model, data, 1e-4)
        closed = data.stats["closed_contacts"] - before
        if closed in (0, 200):
            phases.setdefault(closed, count.sizes)
    assert set(phases) == {0, 200}
    for closed, sizes in phases.items():
        assert sizes == [], (closed, len(sizes), sorted(set(sizes)))


def test_a_steady_step_of_a_point_kept_on_a_curve_allocates_no_numpy_array():
    """The default scene's point kept on the top face's centre line (a bilateral
    CurveConstraint, its fused detection): 200 steps after warm-up steps, not one array."""
    from contact import CurveConstraint, PointOnCurveConstraint

    scene = centre_scene("impact", "point", "1s")
    k = scene.contact.kinematics
    system = scene.system
    system.contacts[system.contacts.index(scene.contact)] = CurveConstraint(PointOnCurveConstraint(k.contour1,
                                                                                                   k.contour2))
    model = compile_model(system, system.plan(0.1), theta=0.5, solver=ProxSolver("gauss-seidel", tol=1e-10,
                                                                                    max_iter=2000))
    assert model.fused[0] is not None
    data = Data(model)
    data.q[:], data.u[:] = system.initial_state()
    for _ in range(20):
        stages.step(model, data, 1e-5)
    with NumpyAllocations() as count:
        for _ in range(200):
            stages.step(model, data, 1e-5)
    assert data.stats["closed_contacts"] == 220
    assert count.sizes == [], (len(count.sizes), sorted(set(count.sizes)))


@pytest.mark.parametrize("pair, bilateral", REGISTERED, ids=lambda v: "/".join(v) if isinstance(v, tuple) else str(v))
def test_a_steady_step_of_every_registered_pair_kind_allocates_no_numpy_array(pair, bilateral):
    """Every pair kind of PAIR_KINEMATICS and BILATERAL_KINEMATICS (validation.bench.pair_cost:
    the side pressed into the surface of a flexible beam, a free rigid body or the ground;
    kept on a curve for a bilateral one), with a second contact of the same kind open and
    flying away: 200 steps after warm-up steps, the first contact closed in each, not one
    array allocated."""
    system, contact, q, u = pair_scene(pair, bilateral, far=1)
    model = compile_model(system, None, theta=0.5, solver=ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000))
    assert all(f is not None for f in model.fused)
    data = Data(model)
    data.q[:], data.u[:] = q, u
    closed, sizes = _steady_steps(model, data, warm_up=20)
    assert closed == 200 and not data.closed[1]
    assert sizes == [], (len(sizes), sorted(set(sizes)))


def _steady_steps(model, data, warm_up, steps=200, dt=1e-5):
    """(closed contact-steps, sizes [bytes] of the numpy arrays allocated) over ``steps``
    steps after ``warm_up`` steps."""
    for _ in range(warm_up):
        stages.step(model, data, dt)
    before = data.stats["closed_contacts"]
    with NumpyAllocations() as count:
        for _ in range(steps):
            stages.step(model, data, dt)
    return data.stats["closed_contacts"] - before, count.sizes


def test_a_steady_step_of_a_face_contact_with_node_compliance_allocates_no_numpy_array():
    """The clamped beam's end face pressed 0.1 µm into a plane, a face contact whose 25
    points carry their nodes' residual flexibility (contact.FaceContact): 200 steps after
    warm-up steps, every point closed in each, not one array allocated (the node frames
    written by the fused detections, the compliance of all pairs by one kernel)."""
    from contact import UnilateralNewtonImpact, connect
    from contours import Contour2sNeutralFFR, PlaneContour
    from mbs import FlexibleBodyFFR, PrescribedFrameMotion, System, ground_frame
    from validation.bench.pair_cost import beam_data

    data = beam_data(None)
    system = System()
    beam = system.add(FlexibleBodyFFR(data, modes=20, frame=PrescribedFrameMotion.fixed(), name="beam"))
    end = data.u0[:, 0].max()
    axes = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])        # the plane's normal along −x
    face = system.add(connect(Contour2sNeutralFFR(beam, "x1", residual_flexibility=True),
                              PlaneContour(ground_frame((end - 1e-7, 0.0, 0.0), axes)), UnilateralNewtonImpact(0.0)))
    model = compile_model(system, None, theta=0.5, solver=ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000))
    data = Data(model)
    data.q[:], data.u[:] = system.initial_state()
    closed, sizes = _steady_steps(model, data, warm_up=50)
    assert closed == 200 * len(face.points) == 200 * 25
    assert sizes == [], (len(sizes), sorted(set(sizes)))
