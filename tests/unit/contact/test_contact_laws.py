"""Contact force laws (contact.laws): prox operators, hand-computed impacts, friction,
single-valued laws against finite differences."""

import numpy as np
import pytest

from contact.laws import (
    Bilateral,
    LinearRegularizedUnilateralConstraint,
    RegularizedCoulombFriction,
    SpatialCoulombFriction,
    UnilateralCoulombContact,
    UnilateralNewtonImpact,
    project_disk,
)
from contact.solver import ProxSolver
from ffrmbs.errors import ModelError

TIGHT = ProxSolver(tol=1e-13)


@pytest.mark.parametrize("make", [
    lambda: UnilateralNewtonImpact(-0.1),
    lambda: UnilateralNewtonImpact(1.5),
    lambda: UnilateralNewtonImpact(float("nan")),
    lambda: SpatialCoulombFriction(-0.2),
    lambda: UnilateralCoulombContact(0.5, -1.0),
    lambda: UnilateralCoulombContact(0.5, 0.3, e_T=2.0),
    lambda: Bilateral(0),
    lambda: Bilateral(1.5),
    lambda: LinearRegularizedUnilateralConstraint(-1.0),
    lambda: LinearRegularizedUnilateralConstraint(1e5, d=-2.0),
    lambda: RegularizedCoulombFriction(0.3, 0.0),
    lambda: RegularizedCoulombFriction(-0.3, 1e-3),
])
def test_bad_parameters_raise_model_error(make):
    with pytest.raises(ModelError):
        make()


def test_law_attributes_and_projections():
    assert UnilateralNewtonImpact(0.3).kind == "set-valued"
    assert LinearRegularizedUnilateralConstraint(1.0).kind == "single-valued"
    assert (UnilateralNewtonImpact().dim, Bilateral(4).dim, UnilateralCoulombContact(0, 0.1).dim) == (1, 4, 3)
    np.testing.assert_array_equal(UnilateralNewtonImpact().project([-1.0, 2.0]), [0.0, 2.0])
    np.testing.assert_array_equal(Bilateral(2).project([-1.0, 2.0]), [-1.0, 2.0])
    np.testing.assert_array_equal(UnilateralCoulombContact(0.2, 0.5, 0.1).restitution, [0.2, 0.1, 0.1])
    # disk: inside unchanged, outside scaled onto the rim
    np.testing.assert_allclose(project_disk([0.3, 0.4], 1.0), [0.3, 0.4])
    np.testing.assert_allclose(project_disk([3.0, 4.0], 1.0), [0.6, 0.8])
    np.testing.assert_allclose(project_disk([3.0, 4.0], 0.0), [0.0, 0.0])
    contact = UnilateralCoulombContact(0.0, 0.5)
    np.testing.assert_allclose(contact.project([2.0, 3.0, 4.0]), [2.0, 0.6, 0.8])
    np.testing.assert_allclose(contact.project([-2.0, 3.0, 4.0]), [0.0, 0.0, 0.0])


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_head_on_collision_of_two_point_masses(e):
    """m1 at x1 moving right hits m2 at x2 > x1: g_N = x2 − x1, W = [−1, 1]ᵀ."""
    m1, m2, v1, v2 = 2.0, 3.0, 4.0, -1.0
    W = np.array([[-1.0], [1.0]])
    G = W.T @ np.diag([1 / m1, 1 / m2]) @ W            # = 1/m1 + 1/m2
    gamma_pre = W.T @ [v1, v2]                          # v2 − v1 = −5 (approaching)
    sol = TIGHT.solve([UnilateralNewtonImpact(e)], G, gamma_pre, gamma_pre)
    u = np.array([v1, v2]) + np.diag([1 / m1, 1 / m2]) @ W @ sol.lam
    # textbook: v1' = v1 − m2 (1 + e)(v1 − v2)/(m1 + m2), v2' = v2 + m1 (1 + e)(v1 − v2)/(m1 + m2)
    expected = [v1 - m2 * (1 + e) * (v1 - v2) / (m1 + m2), v2 + m1 * (1 + e) * (v1 - v2) / (m1 + m2)]
    np.testing.assert_allclose(u, expected, rtol=1e-12)
    assert m1 * u[0] + m2 * u[1] == pytest.approx(m1 * v1 + m2 * v2, rel=1e-12)
    assert sol.gamma_plus[0] == pytest.approx(-e * gamma_pre[0], abs=1e-12)
    assert sol.converged


def test_separating_masses_get_no_impulse():
    G = np.array([[0.5 + 1 / 3]])
    sol = TIGHT.solve([UnilateralNewtonImpact(0.5)], G, [2.0], [2.0])
    assert sol.lam[0] == 0.0 and sol.gamma_plus[0] == 2.0


def block_on_plane(F_x, v_x, mu=0.4, m=2.0, dt=1e-3, grav=9.81):
    """A point mass on the plane z = 0 pushed along x: rows [N, T1, T2] = (z, x, y)."""
    W = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])   # columns N, T1, T2
    G = W.T @ W / m
    u_pre = np.array([v_x, 0.0, 0.0])
    u_free = u_pre + dt * np.array([F_x, 0.0, -m * grav]) / m
    sol = TIGHT.solve([UnilateralCoulombContact(0.0, mu)], G, W.T @ u_free, W.T @ u_pre)
    return sol, m * grav * dt, mu


def test_block_sticks_below_the_friction_limit():
    sol, lam_N, mu = block_on_plane(F_x=5.0, v_x=0.0)          # μ m g = 7.85 N > 5 N
    F_x, dt = 5.0, 1e-3
    np.testing.assert_allclose(sol.lam, [lam_N, -F_x * dt, 0.0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sol.gamma_plus, 0.0, atol=1e-12)
    assert abs(sol.lam[1]) < mu * sol.lam[0]


def test_block_slips_above_the_friction_limit():
    F_x, v_x, dt, m = 20.0, 0.5, 1e-3, 2.0
    sol, lam_N, mu = block_on_plane(F_x=F_x, v_x=v_x)
    np.testing.assert_allclose(sol.lam, [lam_N, -mu * lam_N, 0.0], rtol=1e-12, atol=1e-15)
    v_after = v_x + (F_x * dt - mu * lam_N) / m
    np.testing.assert_allclose(sol.gamma_plus, [0.0, v_after, 0.0], atol=1e-12)


def test_sliding_block_stops_when_friction_suffices():
    """v_x = 1 mm/s: μ g Δt = 3.9 mm/s per step exceeds it, so the block sticks at once."""
    sol, lam_N, mu = block_on_plane(F_x=0.0, v_x=1e-3)
    np.testing.assert_allclose(sol.lam, [lam_N, -2.0 * 1e-3, 0.0], rtol=1e-12)
    np.testing.assert_allclose(sol.gamma_plus[1:], 0.0, atol=1e-13)


def random_spatial_problem(rng, n_contacts, n_dof=None):
    n_dof = n_dof or 3 * n_contacts + 2
    A = rng.normal(size=(n_dof, n_dof))
    M = A @ A.T + n_dof * np.eye(n_dof)
    W = rng.normal(size=(n_dof, 3 * n_contacts))
    return M, W, W.T @ np.linalg.solve(M, W)


def test_spatial_friction_stick_or_slip_against_relative_velocity():
    rng = np.random.default_rng(7)
    slips = sticks = 0
    for _ in range(40):
        n = int(rng.integers(1, 4))
        _, _, G = random_spatial_problem(rng, n)
        laws = [UnilateralCoulombContact(0.0, float(rng.uniform(0.1, 1.0))) for _ in range(n)]
        xi_free = rng.normal(size=3 * n)
        xi_free[0::3] -= 0.5                                   # mostly approaching
        sol = TIGHT.solve(laws, G, xi_free, xi_free)
        assert sol.converged
        for k, law in enumerate(laws):
            lam_N, lam_T = sol.lam[3 * k], sol.lam[3 * k + 1:3 * k + 3]
            g_N, g_T = sol.gamma_plus[3 * k], sol.gamma_plus[3 * k + 1:3 * k + 3]
            assert lam_N >= 0 and g_N >= -1e-10 and abs(lam_N * g_N) < 1e-10
            if np.linalg.norm(g_T) > 1e-9 and lam_N > 0:      # slip
                slips += 1
                assert np.linalg.norm(lam_T) == pytest.approx(law.mu * lam_N, rel=1e-8)
                np.testing.assert_allclose(lam_T / np.linalg.norm(lam_T),
                                           -g_T / np.linalg.norm(g_T), atol=1e-7)
            else:                                              # stick
                sticks += 1
                assert np.linalg.norm(lam_T) <= law.mu * lam_N * (1 + 1e-10)
    assert slips > 5 and sticks > 5


def test_bilateral_rows_end_at_rest():
    rng = np.random.default_rng(3)
    M, W, G = random_spatial_problem(rng, 2)
    xi_free = rng.normal(size=6)
    sol = TIGHT.solve([Bilateral(2), Bilateral(4)], G, xi_free, np.zeros(6))
    np.testing.assert_allclose(sol.gamma_plus, 0.0, atol=1e-12)
    np.testing.assert_allclose(sol.lam, np.linalg.solve(G, -xi_free), rtol=1e-9)


def test_linear_regularized_unilateral_values_and_derivatives():
    law = LinearRegularizedUnilateralConstraint(k=1e5, d=50.0)
    g = np.array([1e-3, -1e-3, -1e-3, -1e-3, 0.0])
    gd = np.array([-1.0, 0.0, 1.0, 3.0, -1.0])
    # apart; resting penetration; separating but still pushing; separating fast (clipped); touching
    np.testing.assert_allclose(law.force(g, gd), [0.0, 100.0, 50.0, 0.0, 0.0])
    dg, dgd = law.derivatives(g, gd)
    h = 1e-9
    fd_g = (law.force(g + h, gd) - law.force(g - h, gd)) / (2 * h)
    fd_gd = (law.force(g, gd + h) - law.force(g, gd - h)) / (2 * h)
    smooth = [0, 1, 2, 3]                                 # away from the kinks
    np.testing.assert_allclose(dg[smooth], fd_g[smooth], rtol=1e-6)
    np.testing.assert_allclose(dgd[smooth], fd_gd[smooth], rtol=1e-6)
    np.testing.assert_array_equal(dg, [0.0, -1e5, -1e5, 0.0, 0.0])


@pytest.mark.parametrize("gamma_T", [[0.3, -0.4], [2e-4, 1e-4], [0.0, 0.0], [-2.0, 0.5]])
def test_regularized_coulomb_values_and_derivatives(gamma_T):
    law = RegularizedCoulombFriction(mu=0.3, v_eps=1e-3)
    gamma_T, F_N = np.array(gamma_T), 40.0
    F_T = law.force(gamma_T, F_N)
    speed = np.linalg.norm(gamma_T)
    if speed > law.v_eps:
        assert np.linalg.norm(F_T) == pytest.approx(law.mu * F_N)
        np.testing.assert_allclose(F_T / np.linalg.norm(F_T), -gamma_T / speed)
    else:
        np.testing.assert_allclose(F_T, -law.mu * F_N * gamma_T / law.v_eps)
    dF_dg, dF_dN = law.derivatives(gamma_T, F_N)
    h = 1e-8
    fd = np.column_stack([(law.force(gamma_T + h * e, F_N) - law.force(gamma_T - h * e, F_N)) / (2 * h)
                          for e in np.eye(2)])
    np.testing.assert_allclose(dF_dg, fd, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(dF_dN, (law.force(gamma_T, F_N + 1e-3) - law.force(gamma_T, F_N - 1e-3)) / 2e-3,
                               rtol=1e-9, atol=1e-12)


def test_regularized_coulomb_broadcasts_over_contacts():
    law = RegularizedCoulombFriction(mu=0.5, v_eps=0.01)
    gamma_T = np.array([[1.0, 0.0], [0.0, 0.005], [0.0, 0.0]])
    F_N = np.array([2.0, 4.0, 1.0])
    np.testing.assert_allclose(law.force(gamma_T, F_N), [[-1.0, 0.0], [0.0, -1.0], [0.0, 0.0]])
    dF_dg, dF_dN = law.derivatives(gamma_T, F_N)
    assert dF_dg.shape == (3, 2, 2) and dF_dN.shape == (3, 2)
    np.testing.assert_allclose(dF_dg[0], [[0.0, 0.0], [0.0, -1.0]])
    np.testing.assert_allclose(dF_dg[2], -50.0 * np.eye(2))
