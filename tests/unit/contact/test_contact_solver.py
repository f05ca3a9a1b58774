"""Contact problem solvers (contact.solver): exact LCP oracles, energy, semismooth Newton,
numba kernels against a numpy reference, errors."""

import itertools

import numpy as np
import pytest
from scipy.optimize import nnls

from contact import _kernels as kern
from contact.laws import Bilateral, UnilateralCoulombContact, UnilateralNewtonImpact
from contact.solver import SUBSPACE_EVERY, WORK_ROWS, ContactSet, ProxSolver, newton_work
from ffrmbs.errors import ModelError


def brute_force_mlcp(G, q, unilateral):
    """Exact solution of w = G Λ + q with w = 0 on bilateral rows and 0 <= Λ ⟂ w >= 0 on
    unilateral rows, by enumerating the active sets of the unilateral rows."""
    m = len(q)
    bilateral = [i for i in range(m) if not unilateral[i]]
    free = [i for i in range(m) if unilateral[i]]
    for k in range(len(free) + 1):
        for subset in itertools.combinations(free, k):
            active = sorted(bilateral + list(subset))
            lam = np.zeros(m)
            if active:
                lam[active] = np.linalg.solve(G[np.ix_(active, active)], -q[active])
            w = G @ lam + q
            inactive = [i for i in free if i not in subset]
            if np.all(lam[list(subset)] >= -1e-12) and np.all(w[inactive] >= -1e-12):
                return lam
    raise AssertionError("no active set solves the LCP")


def random_delassus(rng, m, eps=0.1):
    A = rng.normal(size=(m + 2, m))
    return A.T @ A + eps * np.eye(m)


def reference_gauss_seidel_sweep(cs, G, c, r, lam):
    """Plain-numpy projected Gauss–Seidel sweep built on the laws' ``project``."""
    change = 0.0
    for law, o in zip(cs.laws, cs.offsets):
        rows = [o] if isinstance(law, UnilateralCoulombContact) else range(o, o + law.dim)
        for i in rows:
            new = (law.normal if isinstance(law, UnilateralCoulombContact) else law).project(
                lam[i] - r[i] * (c[i] + G[i] @ lam))
            change = max(change, abs(new - lam[i]) / r[i])
            lam[i] = new
        if isinstance(law, UnilateralCoulombContact):
            t = slice(o + 1, o + 3)
            new = law.friction.project(lam[t] - r[t] * (c[t] + G[t] @ lam), lam[o])
            change = max(change, np.max(np.abs(new - lam[t]) / r[t]))
            lam[t] = new
    return change


def reference_prox_step(cs, G, c, r, lam):
    """Plain-numpy Jacobi prox step: (prox_C(Λ − r ξ(Λ)), natural residual)."""
    z = lam - r * (c + G @ lam)
    new = np.concatenate([law.project(z[o:o + law.dim]) for law, o in zip(cs.laws, cs.offsets)])
    return new, np.max(np.abs(new - lam) / r)


def mixed_laws(rng, n):
    choices = [lambda: UnilateralNewtonImpact(float(rng.uniform())),
               lambda: Bilateral(int(rng.integers(1, 3))),
               lambda: UnilateralCoulombContact(float(rng.uniform()), float(rng.uniform(0, 1)))]
    return [choices[int(rng.integers(3))]() for _ in range(n)]


@pytest.mark.parametrize("method", ["gauss-seidel", "jacobi", "newton"])
def test_frictionless_lcp_equals_enumeration(method):
    rng = np.random.default_rng(11)
    solver = ProxSolver(method, tol=1e-13, max_iter=None if method != "jacobi" else 100_000)
    for trial in range(30):
        m = int(rng.integers(1, 9))
        G, q = random_delassus(rng, m), rng.normal(size=m)
        sol = solver.solve([UnilateralNewtonImpact()] * m, G, q, np.zeros(m))
        assert sol.converged, (trial, sol)
        np.testing.assert_allclose(sol.lam, brute_force_mlcp(G, q, [True] * m), atol=1e-9)


def test_restitution_enters_the_lcp_as_e_gamma_pre():
    rng = np.random.default_rng(5)
    m = 6
    G, xi_free, gamma_pre = random_delassus(rng, m), rng.normal(size=m), rng.normal(size=m)
    e = rng.uniform(size=m)
    sol = ProxSolver(tol=1e-13).solve([UnilateralNewtonImpact(x) for x in e], G, xi_free, gamma_pre)
    np.testing.assert_allclose(sol.lam, brute_force_mlcp(G, xi_free + e * gamma_pre, [True] * m),
                               atol=1e-9)


@pytest.mark.parametrize("method", ["gauss-seidel", "newton"])
def test_mixed_bilateral_unilateral_equals_enumeration(method):
    rng = np.random.default_rng(2)
    for _ in range(20):
        laws = [UnilateralNewtonImpact() if rng.uniform() < 0.6 else Bilateral(1)
                for _ in range(int(rng.integers(2, 8)))]
        m = len(laws)
        G, q = random_delassus(rng, m), rng.normal(size=m)
        sol = ProxSolver(method, tol=1e-13).solve(laws, G, q, np.zeros(m))
        unilateral = [isinstance(law, UnilateralNewtonImpact) for law in laws]
        np.testing.assert_allclose(sol.lam, brute_force_mlcp(G, q, unilateral), atol=1e-9)


def test_larger_lcp_equals_scipy_nnls():
    """min ½ΛᵀGΛ + qᵀΛ over Λ >= 0 is nnls(Lᵀ, −L⁻¹q) with G = L Lᵀ (Cholesky)."""
    rng = np.random.default_rng(4)
    m = 25
    G, q = random_delassus(rng, m, eps=1.0), rng.normal(size=m)
    L = np.linalg.cholesky(G)
    lam_ref = nnls(L.T, -np.linalg.solve(L, q))[0]
    for method in ("gauss-seidel", "newton"):
        sol = ProxSolver(method, tol=1e-13).solve([UnilateralNewtonImpact()] * m, G, q, np.zeros(m))
        np.testing.assert_allclose(sol.lam, lam_ref, atol=1e-8)


def kinetic_energy_change(rng, laws, n_dof):
    m = ContactSet(laws).m
    A = rng.normal(size=(n_dof, n_dof))
    M = A @ A.T + 0.5 * np.eye(n_dof)
    W = rng.normal(size=(n_dof, m))
    G = W.T @ np.linalg.solve(M, W)
    u_pre = rng.normal(size=n_dof)
    gamma_pre = W.T @ u_pre
    sol = ProxSolver(tol=1e-13, max_iter=100_000).solve(laws, G, gamma_pre, gamma_pre)
    assert sol.converged
    u_post = u_pre + np.linalg.solve(M, W @ sol.lam)
    return 0.5 * u_post @ M @ u_post, 0.5 * u_pre @ M @ u_pre


def test_impacts_never_create_kinetic_energy():
    """Frictionless with one e in [0, 1], friction with e = e_T, and friction with e = 0."""
    rng = np.random.default_rng(9)
    for trial in range(150):
        n = int(rng.integers(1, 6))
        e = float(rng.uniform())
        kind = trial % 3
        if kind == 0:
            laws = [UnilateralNewtonImpact(e) for _ in range(n)]
        elif kind == 1:
            laws = [UnilateralCoulombContact(e, float(rng.uniform(0, 1)), e_T=e) for _ in range(n)]
        else:
            laws = [UnilateralCoulombContact(0.0, float(rng.uniform(0, 1))) for _ in range(n)]
        n_dof = ContactSet(laws).m + int(rng.integers(2, 6))
        T_post, T_pre = kinetic_energy_change(rng, laws, n_dof)
        assert T_post <= T_pre * (1 + 1e-10), (trial, T_post, T_pre)


def stack(masses, dt=1e-3, grav=9.81):
    """Point masses stacked on the ground along z, at rest under gravity: contact k between
    mass k−1 (ground for k = 0) and mass k, γ_k = v_k − v_{k−1}."""
    n = len(masses)
    W = np.zeros((n, n))
    for k in range(n):
        W[k, k] = 1.0
        if k > 0:
            W[k - 1, k] = -1.0
    G = W.T @ np.diag(1.0 / np.asarray(masses)) @ W
    u_free = -grav * dt * np.ones(n)
    lam_exact = grav * dt * np.cumsum(np.asarray(masses)[::-1])[::-1]   # weight above each contact
    return G, W.T @ u_free, lam_exact


def test_newton_and_subspace_steps_converge_on_mass_ratio_1e6_where_pgs_crawls():
    masses = [1.0, 1e6, 1.0, 1e6, 1.0]
    G, xi_free, lam_exact = stack(masses)
    laws = [UnilateralNewtonImpact()] * len(masses)
    newton = ProxSolver("newton", tol=1e-12).solve(laws, G, xi_free, np.zeros(5))
    pgs = ProxSolver("gauss-seidel", tol=1e-12, max_iter=20_000, subspace_every=0).solve(
        laws, G, xi_free, np.zeros(5))
    pgs_sm = ProxSolver("gauss-seidel", tol=1e-12).solve(laws, G, xi_free, np.zeros(5))
    print(f"\nstack, mass ratio 1e6: Newton {newton.iterations} steps (residual "
          f"{newton.residual:.1e} m/s), PGS {pgs.iterations} sweeps (residual {pgs.residual:.1e} m/s, "
          f"converged {pgs.converged}), with subspace steps {pgs_sm.iterations}")
    assert newton.converged and newton.iterations < 30
    np.testing.assert_allclose(newton.lam, lam_exact, rtol=1e-9)
    assert pgs.iterations > 20 * newton.iterations
    assert pgs_sm.converged and pgs_sm.iterations < 50
    np.testing.assert_allclose(pgs_sm.lam, lam_exact, rtol=1e-9)


def test_newton_agrees_with_pgs_on_random_frictionless_problems():
    rng = np.random.default_rng(21)
    for _ in range(30):
        laws = [UnilateralNewtonImpact(float(rng.uniform())) if rng.uniform() < 0.7 else Bilateral(1)
                for _ in range(int(rng.integers(1, 12)))]
        m = len(laws)
        G, xi_free, gamma_pre = random_delassus(rng, m, eps=0.05), rng.normal(size=m), rng.normal(size=m)
        a = ProxSolver("newton", tol=1e-13).solve(laws, G, xi_free, gamma_pre)
        b = ProxSolver("gauss-seidel", tol=1e-13, max_iter=100_000).solve(laws, G, xi_free, gamma_pre)
        assert a.converged and b.converged
        np.testing.assert_allclose(a.lam, b.lam, atol=1e-8 * max(1.0, np.max(np.abs(b.lam))))


def test_cycling_frictional_contact_converges_by_r_reduction():
    """A strongly coupled contact on which plain PGS with α = 1 cycles with period 2
    (sweeps alone, subspace_every = 0: no normal or Newton phase)."""
    G = np.array([[1.237326, 2.24091, -1.251171],
                  [2.24091, 7.796883, -2.855814],
                  [-1.251171, -2.855814, 4.652451]])
    c = np.array([-1.073583, -2.566174, 3.599061])
    law = UnilateralCoulombContact(0.0, 0.9566748993705659)
    sol = ProxSolver(tol=1e-12, subspace_every=0).solve([law], G, c, np.zeros(3))
    assert sol.converged and sol.iterations > 50
    lam_T, g_T = sol.lam[1:], sol.gamma_plus[1:]
    assert sol.lam[0] > 0 and abs(sol.gamma_plus[0]) < 1e-11
    assert np.linalg.norm(lam_T) == pytest.approx(law.mu * sol.lam[0], rel=1e-10)
    np.testing.assert_allclose(lam_T / np.linalg.norm(lam_T), -g_T / np.linalg.norm(g_T), atol=1e-9)
    jacobi = ProxSolver("jacobi", tol=1e-12, subspace_every=0).solve([law], G, c, np.zeros(3))
    np.testing.assert_allclose(jacobi.lam, sol.lam, atol=1e-10)


def test_warm_start_from_the_solution_needs_one_sweep():
    rng = np.random.default_rng(8)
    laws = mixed_laws(rng, 6)
    m = ContactSet(laws).m
    G = random_delassus(rng, m)
    xi_free = rng.normal(size=m) - 0.3
    solver = ProxSolver(tol=1e-12, max_iter=100_000)
    cold = solver.solve(laws, G, xi_free, xi_free)
    warm = solver.solve(laws, G, xi_free, xi_free, lam0=cold.lam)
    assert cold.converged and warm.converged
    assert warm.iterations == 1 < cold.iterations
    np.testing.assert_allclose(warm.lam, cold.lam, atol=1e-10)


def test_no_convergence_is_reported_not_raised():
    G, xi_free, _ = stack([1.0, 1e6, 1.0])
    sol = ProxSolver(max_iter=3).solve([UnilateralNewtonImpact()] * 3, G, xi_free, np.zeros(3))
    assert not sol.converged and sol.iterations == 3 and sol.residual > 0.0


def test_contact_set_layout():
    laws = [UnilateralCoulombContact(0.1, 0.3), Bilateral(2), UnilateralNewtonImpact(0.5)]
    cs = ContactSet(laws)
    assert cs.m == 6 and cs.frictional
    np.testing.assert_array_equal(cs.offsets, [0, 3, 5])
    np.testing.assert_array_equal(cs.kinds, [kern.COULOMB, kern.BILATERAL, kern.BILATERAL, kern.UNILATERAL])
    np.testing.assert_array_equal(cs.entry_offsets, [0, 3, 4, 5])
    np.testing.assert_array_equal(cs.restitution, [0.1, 0.0, 0.0, 0.0, 0.0, 0.5])
    np.testing.assert_array_equal(cs.tangent_rows(), [1])


def test_numba_kernels_equal_numpy_reference():
    rng = np.random.default_rng(13)
    for _ in range(20):
        cs = ContactSet(mixed_laws(rng, int(rng.integers(1, 7))))
        m = cs.m
        G, c = random_delassus(rng, m), rng.normal(size=m)
        r = rng.uniform(0.2, 1.5, size=m) / np.diag(G)
        r[cs.tangent_rows() + 1] = r[cs.tangent_rows()]
        lam = rng.normal(size=m)
        # Gauss–Seidel sweep
        lam_ref, lam_nb = lam.copy(), lam.copy()
        ch_ref = reference_gauss_seidel_sweep(cs, G, c, r, lam_ref)
        ch_nb, _ = kern.gauss_seidel_sweep(G, c, r, cs.kinds, cs.entry_offsets, cs.mu, lam_nb)
        np.testing.assert_allclose(lam_nb, lam_ref, rtol=1e-14, atol=1e-14)
        assert ch_nb == pytest.approx(ch_ref, rel=1e-14)
        # Jacobi step and natural residual
        xi = np.empty(m)
        kern.velocities(G, c, lam, xi)
        new_ref, res_ref = reference_prox_step(cs, G, c, r, lam)
        lam_nb = lam.copy()
        assert kern.prox_step(xi, r, cs.kinds, cs.entry_offsets, cs.mu, lam_nb, False) == \
            pytest.approx(res_ref, rel=1e-14)
        np.testing.assert_array_equal(lam_nb, lam)
        kern.prox_step(xi, r, cs.kinds, cs.entry_offsets, cs.mu, lam_nb, True)
        np.testing.assert_allclose(lam_nb, new_ref, rtol=1e-14, atol=1e-14)


def test_zero_free_velocity_gives_zero_impulse():
    G = random_delassus(np.random.default_rng(1), 3)
    sol = ProxSolver().solve([UnilateralCoulombContact(0.5, 0.3)], G, np.zeros(3), np.zeros(3),
                             lam0=[1.0, 0.1, 0.0])
    assert sol.converged and sol.iterations == 0
    np.testing.assert_array_equal(sol.lam, 0.0)


def test_massless_row_does_not_break_the_prox_factors():
    """A contact whose W column is zero (between two fixed bodies) and which separates."""
    G = np.array([[2.0, 0.0], [0.0, 0.0]])
    sol = ProxSolver().solve([UnilateralNewtonImpact()] * 2, G, [-1.0, 0.5], np.zeros(2))
    assert sol.converged
    np.testing.assert_allclose(sol.lam, [0.5, 0.0])


@pytest.mark.parametrize("kwargs", [dict(method="lemke"), dict(r=-1.0), dict(r="fast"),
                                    dict(relaxation=2.0), dict(tol=0.0), dict(max_iter=0)])
def test_bad_solver_parameters(kwargs):
    with pytest.raises(ModelError):
        ProxSolver(**kwargs)


def test_bad_problems_raise_model_error():
    solver = ProxSolver()
    laws = [UnilateralNewtonImpact()] * 2
    with pytest.raises(ModelError, match="square"):
        solver.solve(laws, np.ones((2, 3)), np.zeros(2), np.zeros(2))
    with pytest.raises(ModelError, match="rows"):
        solver.solve(laws, np.eye(3), np.zeros(3), np.zeros(3))
    with pytest.raises(ModelError, match="xi_free"):
        solver.solve(laws, np.eye(2), np.zeros(3), np.zeros(2))
    with pytest.raises(ModelError, match="lam0"):
        solver.solve(laws, np.eye(2), np.zeros(2), np.zeros(2), lam0=np.zeros(1))
    with pytest.raises(ModelError, match="non-finite"):
        solver.solve(laws, np.eye(2), [np.nan, 0.0], np.zeros(2))
    with pytest.raises(ModelError, match="semi-definite"):
        solver.solve(laws, -np.eye(2), np.zeros(2), np.zeros(2))
    with pytest.raises(ModelError, match="not a set-valued"):
        solver.solve([UnilateralCoulombContact(0, 0.3).friction], np.eye(2), np.zeros(2), np.zeros(2))


def reference_gauss_seidel_solve(cs, G, xi_free, gamma_pre, lam, alpha=1.0, tol=1e-10, max_iter=10_000):
    """Projected Gauss–Seidel with automatic r, step by step in numpy around the sweep
    kernel: c = ξ_free + ε γ⁻, r = α / diag(G) (Coulomb tangents α / max(λ_max(G_TT),
    G_TT diagonal)), prox_iterate, γ⁺ = ξ_free + G Λ."""
    c = xi_free + cs.restitution * gamma_pre
    d = np.diag(G).copy()
    r = alpha / d
    for t in cs.tangent_at:
        GT = G[t:t + 2, t:t + 2]
        r[t:t + 2] = alpha / max(np.linalg.eigvalsh(GT).max(), d[t], d[t + 1])
    m = len(c)
    J, pivots, local = newton_work(m)
    it, residual, converged = kern.prox_iterate(G, c, r, cs.kinds, cs.entry_offsets, cs.mu, lam, np.empty(m),
                                                np.empty(m), False, tol, max_iter, SUBSPACE_EVERY, np.empty(m),
                                                np.empty(m), False, J, pivots[0], pivots[1], local)
    return it, residual, converged, xi_free + G @ lam


@pytest.mark.parametrize("seed", range(12))
def test_gauss_seidel_solve_kernel_equals_the_numpy_steps(seed):
    """ProxSolver's Gauss–Seidel solve (one kernel) takes the same iterations to the same
    Λ and γ⁺ as the numpy steps around the sweep kernel, on random mixed problems
    (1–3 contacts: the closed sets of a step), with and without a warm start."""
    rng = np.random.default_rng(seed)
    cs = ContactSet(mixed_laws(rng, 1 + seed % 3))
    m = cs.m
    G = random_delassus(rng, m)
    xi_free, gamma_pre = rng.normal(size=m), rng.normal(size=m)
    lam0 = rng.normal(size=m) if seed % 2 else np.zeros(m)
    lam_ref = lam0.copy()
    it_ref, res_ref, conv_ref, gp_ref = reference_gauss_seidel_solve(cs, G, xi_free, gamma_pre, lam_ref)
    lam, gamma_plus = lam0.copy(), np.empty(m)
    it, res, conv = ProxSolver("gauss-seidel").solve_into(cs, G, xi_free, gamma_pre, lam, gamma_plus,
                                                          np.empty((WORK_ROWS, m)))
    assert (it, conv) == (it_ref, conv_ref)
    scale = max(1.0, np.abs(lam_ref).max())
    assert np.abs(lam - lam_ref).max() <= 1e-12 * scale
    assert np.abs(gamma_plus - gp_ref).max() <= 1e-12 * max(1.0, np.abs(gp_ref).max())
    assert abs(res - res_ref) <= 1e-12 * max(1.0, abs(res_ref))


def reference_subspace_step(cs, G, c, r, lam, accuracy, max_steps):
    """Numpy reference of kern.subspace_step: preconditioned conjugate gradients on
    ½ ΛᵀGΛ + cᵀΛ over the active rows (bilateral, Λ > 0), a step cut where a unilateral
    Λ_i reaches 0, then a restart; returns the steps."""
    bilateral = cs.kinds == kern.BILATERAL
    steps = 0
    while steps < max_steps:
        active = bilateral | (lam > 0.0)
        rho = np.where(active, -(c + G @ lam), 0.0)
        p = r * rho
        rz, hit = rho @ p, None
        while np.abs(rho).max() > accuracy and steps < max_steps:
            steps += 1
            q = np.where(active, G @ p, 0.0)
            pq = p @ q
            if not pq > 0.0:
                return steps
            a = rz / pq
            blocking = active & ~bilateral & (p < 0.0)
            cuts = np.where(blocking, -lam / np.where(blocking, p, -1.0), np.inf)
            if cuts.min() < a:
                a, hit = cuts.min(), int(np.argmin(cuts))
            lam[active] += a * p[active]
            lam[active & ~bilateral] = np.maximum(lam[active & ~bilateral], 0.0)
            if hit is not None:
                lam[hit] = 0.0
                break
            rho[active] -= a * q[active]
            rz_new = rho @ (r * rho)
            p = np.where(active, r * rho + rz_new / rz * p, 0.0)
            rz = rz_new
        if hit is None:
            return steps
    return steps


@pytest.mark.parametrize("seed", range(8))
def test_subspace_step_kernel_equals_the_numpy_reference(seed):
    """The conjugate-gradient subspace step on random frictionless problems (unilateral and
    bilateral rows, some impulses at 0), singular G included: the same steps and Λ."""
    rng = np.random.default_rng(seed)
    laws = [UnilateralNewtonImpact() if rng.uniform() < 0.7 else Bilateral(1) for _ in range(12)]
    cs = ContactSet(laws)
    W = rng.normal(size=(8 if seed % 2 else 14, 12))
    G = W.T @ W
    c = rng.normal(size=12)
    lam0 = np.where(rng.uniform(size=12) < 0.3, 0.0, rng.uniform(0.1, 1.0, size=12))
    r = 1.0 / np.diag(G)
    lam_ref = lam0.copy()
    steps_ref = reference_subspace_step(cs, G, c, r, lam_ref, 1e-12, 40)
    lam = lam0.copy()
    steps = kern.subspace_step(G, c, r, cs.kinds, cs.entry_offsets, lam, np.empty(12), np.empty(12),
                               np.empty(12), 1e-12, 40)
    assert steps == steps_ref
    np.testing.assert_allclose(lam, lam_ref, atol=1e-10 * max(1.0, np.abs(lam_ref).max()))
    f = lambda x: 0.5 * x @ G @ x + c @ x     # noqa: E731  the objective never increases
    assert f(lam) <= f(lam0) + 1e-12 * abs(f(lam0))
    unilateral = cs.kinds == kern.UNILATERAL
    assert np.all(lam[unilateral] >= 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_normal_phase_solves_the_normal_problem_with_the_tangential_impulses_held(seed):
    """kern.normal_phase on random problems with friction (some contacts pressed, some
    pulled apart): Λ_T unchanged, and Λ_N equal to NNLS on the normal rows with the held
    Λ_T in the free velocity, min_{Λ_N ≥ 0} |L_Nᵀ Λ_N + L_N⁻¹ c'_N| with G_NN = L_N L_Nᵀ."""
    rng = np.random.default_rng(seed)
    n = 6
    cs = ContactSet([UnilateralCoulombContact(0.0, 0.4)] * n)
    G = random_delassus(rng, 3 * n, eps=0.05)
    c = rng.normal(size=3 * n)
    lam = rng.uniform(0.0, 1.0, size=3 * n)
    lam_T = np.delete(lam, cs.entry_offsets).copy()
    N = cs.entry_offsets
    c_N = c[N] + np.delete(G[N], N, axis=1) @ lam_T
    L = np.linalg.cholesky(G[np.ix_(N, N)])
    lam_N = nnls(L.T, -np.linalg.solve(L, c_N), maxiter=1000)[0]
    m = 3 * n
    steps = kern.normal_phase(G, c, 1.0 / np.diag(G), cs.kinds, cs.entry_offsets, lam, np.empty(m), np.empty(m),
                              np.empty(m), 1e-13, np.abs(c).max(), SUBSPACE_EVERY, 10_000)
    assert steps < 10_000
    np.testing.assert_array_equal(np.delete(lam, N), lam_T)
    np.testing.assert_allclose(lam[N], lam_N, atol=1e-9 * max(1.0, lam_N.max()))


@pytest.mark.parametrize("seed", range(6))
def test_natural_map_kernel_equals_the_laws_projections_and_its_jacobian_finite_differences(seed):
    """F(Λ) = (Λ − prox_C(Λ − s r ξ)) / (s r) of the Newton phase against the laws'
    ``project`` in numpy, and its Jacobian against central differences at a random Λ (off
    the kinks of the projection with probability one)."""
    rng = np.random.default_rng(seed)
    cs = ContactSet(mixed_laws(rng, 6))
    m = cs.m
    G = random_delassus(rng, m)
    c, lam = rng.normal(size=m), rng.normal(size=m)
    r, scale = rng.uniform(0.5, 2.0, size=m), 10.0
    r[cs.tangent_rows() + 1] = r[cs.tangent_rows()]           # the disk's r is isotropic
    F, J, dF = np.empty(m), np.empty((m, m)), np.empty(m)
    local = newton_work(0)[2]
    psi = kern.natural_map(G, c, r, scale, cs.kinds, cs.entry_offsets, cs.mu, lam, F, J, True, local)
    sr = scale * r
    z = lam - sr * (c + G @ lam)
    prox = np.concatenate([law.project(z[o:o + law.dim]) for law, o in zip(cs.laws, cs.offsets)])
    np.testing.assert_allclose(F, (lam - prox) / sr, rtol=1e-12, atol=1e-12 * np.abs(F).max())
    assert psi == pytest.approx(F @ F, rel=1e-12)
    h = 1e-7
    for j in range(m):
        e = np.zeros(m)
        e[j] = h
        plus, minus = np.empty(m), np.empty(m)
        kern.natural_map(G, c, r, scale, cs.kinds, cs.entry_offsets, cs.mu, lam + e, plus, J[:0, :0], False, local)
        kern.natural_map(G, c, r, scale, cs.kinds, cs.entry_offsets, cs.mu, lam - e, minus, J[:0, :0], False, local)
        dF[:] = (plus - minus) / (2 * h)
        np.testing.assert_allclose(J[:, j], dF, rtol=1e-5, atol=1e-6 * np.abs(J).max())


def test_complete_pivoting_solve_equals_numpy_and_solves_a_consistent_singular_system():
    """Regular: np.linalg.solve. Singular of rank 5 (a Delassus matrix of more contacts
    than velocities) with b in its range: rank 5 found, A x = b to rounding."""
    rng = np.random.default_rng(2)
    m = 12
    A, b = rng.normal(size=(m, m)), rng.normal(size=m)
    x, pivots = np.empty(m), np.empty((2, m), dtype=np.int64)
    assert kern.complete_pivoting_solve(A.copy(), b.copy(), x, pivots[0], pivots[1], 1e-13) == m
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-10)
    W = rng.normal(size=(5, m))
    S = W.T @ W
    b = S @ rng.normal(size=m)
    assert kern.complete_pivoting_solve(S.copy(), b.copy(), x, pivots[0], pivots[1], 1e-13) == 5
    np.testing.assert_allclose(S @ x, b, atol=1e-12 * np.abs(b).max())


@pytest.mark.parametrize("seed", range(8))
def test_newton_with_friction_agrees_with_gauss_seidel(seed):
    """Random problems with Coulomb contacts: the Newton method (a Newton phase first)
    and the Gauss–Seidel method both converge, each to a Λ whose natural residual with
    r = 1 (the laws' projections in numpy) is zero to the tolerance."""
    rng = np.random.default_rng(seed)
    laws = mixed_laws(rng, 8)
    m = sum(law.dim for law in laws)
    G, xi_free = random_delassus(rng, m), rng.normal(size=m)
    for method in ("gauss-seidel", "newton"):
        sol = ProxSolver(method, tol=1e-12, max_iter=5000).solve(laws, G, xi_free, np.zeros(m))
        assert sol.converged
        _, residual = reference_prox_step(ContactSet(laws), G, xi_free, np.ones(m), sol.lam)
        assert residual <= 1e-9 * np.abs(xi_free).max()
