"""Smooth integrators against analytic solutions: convergence orders, stiff modes, rigid
spin through the Cardan singularity, free-flight conservation, graceful failure."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ffrmbs.errors import ModelError, SimulationError
from mbs import FlexibleBodyFFR, Joint, PrescribedFrameMotion, RigidBody, System
from preprocess import box, build_body
from validation.cases.cantilever import MATERIAL


@pytest.fixture(scope="module")
def free_data():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, 4, clamp=None)


@pytest.fixture(scope="module")
def clamped_data():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, 3, clamp="z0")


def modal_oscillators(data, integrator, dt, t_end, **opt):
    """Frame-fixed body: q_i(t) = v_i / ω_i sin(ω_i t) exactly (thesis Sec. 5.1)."""
    system = System()
    body = system.add(FlexibleBodyFFR(data, 3, frame=PrescribedFrameMotion.fixed()))
    v0 = np.array([0.2, 0.17, 0.14])
    body.set_initial(qdot_f=v0)
    res = system.simulate(t_end, dt, integrator=integrator, t_out=[t_end], plan=False, **opt)
    omega = np.sqrt(data.modal_eigenvalues())
    exact = v0 / omega * np.sin(omega * t_end)
    return np.abs(res.q[-1] - exact).max() / np.abs(v0 / omega).max()


@pytest.mark.parametrize("integrator, order, dts, opt", [
    ("generalized-alpha", 2, (4e-5, 2e-5), {"rho_inf": 0.8}),
    ("generalized-alpha", 2, (4e-5, 2e-5), {"rho_inf": 1.0}),
    ("rk4", 4, (1e-4, 5e-5), {}),
])
def test_convergence_order_on_modal_oscillators(clamped_data, integrator, order, dts, opt):
    e1, e2 = (modal_oscillators(clamped_data, integrator, dt, 0.02, **opt) for dt in dts)
    observed = np.log2(e1 / e2)
    assert abs(observed - order) < 0.3, (e1, e2, observed)


def test_stiff_modes_do_not_limit_the_implicit_step(clamped_data):
    """h ω_max ≈ 1e3: generalized-α stays bounded and damps the unresolved modes (ρ∞ = 0.5)."""
    omega = np.sqrt(clamped_data.modal_eigenvalues())
    dt = 1e3 / omega.max()
    system = System()
    body = system.add(FlexibleBodyFFR(clamped_data, 3, frame=PrescribedFrameMotion.fixed()))
    body.set_initial(qdot_f=[0.2, 0.17, 0.14])
    res = system.simulate(50 * dt, dt, rho_inf=0.5, energies=True, plan=False)
    assert np.all(np.isfinite(res.q))
    assert res.total_energy()[-1] < res.total_energy()[0]


def spinning_body(rotation, tilt_deg=0.0):
    """A rigid cuboid (1 × 2 × 3 m, 6 kg) spinning at 10 rad/s about its body y axis
    (a principal axis): the orientation is A(t) = A0 exp(ω t ỹ) exactly."""
    m, (a, b, c) = 6.0, (1.0, 2.0, 3.0)
    I = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    body = RigidBody(m, I, rotation=rotation)
    A0 = Rotation.from_euler("x", tilt_deg, degrees=True).as_matrix()
    body.set_initial(A=A0, omega=A0 @ np.array([0.0, 10.0, 0.0]))
    return body, A0


def orientation_error(system, body, res, A0):
    errs = []
    for t, q in zip(res.t, res.q):
        exact = A0 @ Rotation.from_rotvec([0.0, 10.0 * t, 0.0]).as_matrix()
        errs.append(np.abs(body.orientation(q[body.q_slice]) - exact).max())
    return max(errs)


def test_quaternion_spins_through_the_cardan_singularity():
    """100 revolutions about y: β passes ±90° 200 times; the default stays accurate."""
    system = System()
    body, A0 = spinning_body("quaternion")
    system.add(body)
    t_end = 100 * 2 * np.pi / 10.0
    res = system.simulate(t_end, 2e-2, t_out=np.linspace(0, t_end, 401), energies=True)
    assert orientation_error(system, body, res, A0) < 1e-6
    assert res.energy_drift() < 1e-10


def test_cardan_fails_clearly_at_the_singularity():
    """Cardan angles (thesis eq. 2.22) cannot pass β = 90° (Ḡ singular, eq. 2.31): the run
    either stops with a SimulationError or loses accuracy; the quaternion does not."""
    system = System()
    body, A0 = spinning_body("cardan")
    system.add(body)
    t_end = 2 * np.pi / 10.0
    try:
        res = system.simulate(t_end, 1e-3, t_out=np.linspace(0, t_end, 41))
    except SimulationError as err:
        assert err.result.t[-1] < t_end
        return
    assert orientation_error(system, body, res, A0) > 1e-3


def test_cardan_and_quaternion_agree_away_from_the_singularity(free_data):
    """Same free flexible body and initial state, both parametrizations: node trajectories agree."""
    out = {}
    for rotation in ("quaternion", "cardan"):
        system = System()
        body = system.add(FlexibleBodyFFR(free_data, 4, rotation=rotation))
        body.set_initial(A=Rotation.from_euler("XYZ", [0.2, -0.3, 0.1]).as_matrix(),
                         v=[0.1, 0.0, 0.2], omega=[0.3, 0.2, 0.5], qdot_f=[0.02, 0.01, 0.0, 0.01])
        out[rotation] = system.simulate(0.5, 2e-4, integrator="rk4",
                                        outputs={"A": body.node(0), "B": body.node(100)})
    for key in ("A", "B"):
        np.testing.assert_allclose(out["cardan"][key], out["quaternion"][key], atol=1e-9)


def test_free_flight_conserves_energy_and_momenta(free_data):
    """A free flexible body, spinning and vibrating, 10 s, generalized-α with ρ∞ = 1 (no
    numerical damping): relative drifts of energy, linear and angular momentum."""
    system = System()
    body = system.add(FlexibleBodyFFR(free_data, 4))
    body.set_initial(v=[0.1, 0.2, 0.0], omega=[0.5, 1.0, 0.2], qdot_f=[0.05, 0.04, 0.03, 0.02])
    res = system.simulate(10.0, 2e-3, rho_inf=1.0, energies=True, t_out=np.linspace(0, 10, 51))
    L = np.array([system.angular_momentum(t, q, u) for t, q, u in zip(res.t, res.q, res.u)])
    P = np.array([system.linear_momentum(t, q, u) for t, q, u in zip(res.t, res.q, res.u)])
    assert res.energy_drift() < 1e-4
    assert np.abs(P - P[0]).max() / np.linalg.norm(P[0]) < 1e-5
    assert np.abs(L - L[0]).max() / np.linalg.norm(L[0]) < 1e-4


def test_divergence_stops_with_the_results_so_far(clamped_data):
    """RK4 far beyond its stability limit: a SimulationError naming time and step, with the
    samples computed before the blow-up kept."""
    omega = np.sqrt(clamped_data.modal_eigenvalues()).max()
    system = System()
    body = system.add(FlexibleBodyFFR(clamped_data, 3, frame=PrescribedFrameMotion.fixed()))
    body.set_initial(qdot_f=[0.2, 0.17, 0.14])
    dt = 10.0 / omega
    with pytest.raises(SimulationError, match=r"state became non-finite \(NaN/inf\) in q/u") as info:
        system.simulate(2000 * dt, dt, integrator="rk4", plan=False)
    err = info.value
    assert err.step > 1 and 0 < len(err.result.t) <= err.step
    assert np.all(np.isfinite(err.result.q))


def test_simulate_rejects_bad_requests(clamped_data):
    system = System()
    system.add(FlexibleBodyFFR(clamped_data, 3, frame=PrescribedFrameMotion.fixed()))
    with pytest.raises(ModelError, match="integrator"):
        system.simulate(1.0, 1e-3, integrator="euler")
    with pytest.raises(ModelError, match="t_out"):
        system.simulate(1.0, 1e-3, t_out=[0.5, 0.2])
    with pytest.raises(ModelError, match="dt"):
        system.simulate(1.0, 0.0)


def test_unconstrained_accelerations_are_scipys_cholesky_solve(free_data):
    """u̇ = M⁻¹ h of a free flexible body in motion (the explicit integrators' right-hand
    side) by :func:`mbs.run.equations.solve_spd`: the same bits as
    ``scipy.linalg.solve(M, h, assume_a="pos")``; a mass matrix that is not positive
    definite is a LinAlgError, as there."""
    import scipy.linalg

    from mbs.run.equations import Equations, solve_spd

    system = System()
    body = system.add(FlexibleBodyFFR(free_data, 4))
    body.set_initial(A=Rotation.from_euler("XYZ", [0.2, -0.3, 0.1]).as_matrix(), v=[0.1, 0.0, 0.2],
                     omega=[0.3, 0.2, 0.5], q_f=[1e-3, -2e-3, 0.0, 5e-4], qdot_f=[0.02, 0.01, 0.0, 0.01])
    equations = Equations(system)
    q, u = system.initial_state()
    M, h = equations.mass_and_h(0.0, q, u)
    a, lam = equations.accelerations(0.0, q, u)
    assert lam.size == 0 and np.array_equal(a, scipy.linalg.solve(M, h, assume_a="pos", check_finite=False))
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        solve_spd(np.diag([1.0, -1.0, 2.0]), np.ones(3))


@pytest.mark.parametrize("constrained", [False, True])
def test_rk4_accelerations_on_the_body_stage_equal_the_numpy_reference(free_data, constrained):
    """RK4's right-hand side u̇ comes from the body stage's kernels (M, h) and, without
    constraints, a Cholesky solve in numba; with a revolute joint the index-1 system. Both
    equal :meth:`mbs.run.equations.Equations.accelerations` (Python per body, LAPACK) to
    rounding, for a free flexible body in motion, gravity and a spinning rigid body."""
    from mbs.integrators import integrator_class

    system = System(gravity=(0.0, -9.81, 0.0))
    body = system.add(FlexibleBodyFFR(free_data, 4))
    body.set_initial(A=Rotation.from_euler("XYZ", [0.2, -0.3, 0.1]).as_matrix(), v=[0.1, 0.0, 0.2],
                     omega=[0.3, 0.2, 0.5], q_f=[1e-3, -2e-3, 0.0, 5e-4], qdot_f=[0.02, 0.01, 0.0, 0.01])
    system.add(RigidBody(3.0, np.diag([0.2, 0.3, 0.4]), rotation="cardan").set_initial(omega=(0.0, 2.0, 0.5)))
    if constrained:
        system.add(Joint.revolute(system.ground, body.origin, axis=(0.0, 0.0, 1.0)))
    rk4 = integrator_class("rk4")(system)
    rk4.compile()
    q, u = system.initial_state()
    rk4.start(0.0, q, u)
    reference, _ = rk4.model.equations.accelerations(0.0, q, u)
    np.testing.assert_allclose(rk4._acc(0.0, q, u), reference, rtol=1e-12, atol=1e-12 * np.abs(reference).max())
