"""PureMA and the step-load recursion (report Sec. 2, eq. 8–12, 34–35, 37).

Oracles: the direct sum of eq. 10 over the whole load history (with eq. 8's phase
corrected), scipy's solve_ivp for damped modes, the matrix exponential of the full
finite-element system M ü + K u = f (no modal decomposition), Newton's law for the
centre of mass of a free body, and energy balances of a single mode.
"""

from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as la
from scipy.integrate import solve_ivp

from ffrmbs.errors import ModelError
from mbs.modal import ModalBasis, PureMA, StepLoads
from mbs.modal.oscillator import StepResponse
from preprocess import box, build_body, face_load
from preprocess.modes import clamped_dofs
from validation.cases.cantilever import MATERIAL


def eq10_direct_sum(w, r0, v0, times, F, t):
    """Report eq. 10 summed over every load step up to t, with A, φ from eq. 8 (phase
    taken as atan2(r0, v0/ω): eq. 8's arcsin loses the sign of v0)."""
    A = np.hypot(r0, v0 / w)
    phi = np.arctan2(r0, v0 / w)
    out = A * np.sin(w * t + phi)
    prev = 0.0
    for tj, Fj in zip(times, F):
        if t >= tj:
            out += (Fj - prev) / w ** 2 * (1.0 - np.cos(w * (t - tj)))
        prev = Fj
    return out


def test_recursion_matches_direct_sum_of_eq10():
    rng = np.random.default_rng(1)
    w = np.array([198.0, 1096.0, 12021.0])
    times = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 2.0, 300))])   # non-uniform
    F = rng.normal(size=(times.size, 3)) * w ** 2 * 1e-3
    r0, v0 = np.array([1e-3, -2e-3, 0.0]), np.array([0.5, -0.1, 3.0])
    resp = StepResponse(w ** 2, 0.0, times, F, r0, v0)
    t = np.sort(rng.uniform(0.0, 2.5, 200))
    r, _ = resp(t)
    ref = np.array([[eq10_direct_sum(w[i], r0[i], v0[i], times, F[:, i], tt) for i in range(3)] for tt in t])
    scale = np.abs(ref).max(axis=0)
    assert np.abs(r - ref).max(axis=0).max() / scale.min() < 1e-12 * 300


def test_recursion_is_exact_to_round_off_per_load_step():
    """Per load step the recursion adds round-off only: error vs eq. 10 below 1e-12 relative
    for a short history."""
    w = np.array([400.0, 1096.0])
    times = np.array([0.0, 0.002, 0.005, 0.011])
    F = np.array([[1.0, 2.0], [-3.0, 0.5], [0.0, 4.0], [2.0, -1.0]]) * 1e5
    resp = StepResponse(w ** 2, 0.0, times, F, np.zeros(2), np.zeros(2))
    t = np.linspace(0.0, 0.05, 97)
    r, _ = resp(t)
    ref = np.array([[eq10_direct_sum(w[i], 0.0, 0.0, times, F[:, i], tt) for i in range(2)] for tt in t])
    assert np.abs(r - ref).max() <= 1e-12 * np.abs(ref).max()


def test_amplitude_phase_form_of_eq12():
    w = np.array([300.0, 900.0])
    times = np.array([0.0, 0.01, 0.03])
    F = np.array([[5e4, -1e5], [0.0, 2e5], [1e5, 0.0]])
    resp = StepResponse(w ** 2, 0.0, times, F, np.array([1e-3, 0.0]), np.array([0.0, 1.0]))
    alpha, beta = resp.amplitude_phase()
    t = np.array([0.005, 0.02, 0.07])
    k = np.searchsorted(times, t, side="right") - 1
    r, _ = resp(t)
    r_eq12 = alpha[k] * np.sin(w * t[:, None] + beta[k]) + F[k] / w ** 2
    np.testing.assert_allclose(r_eq12, r, rtol=1e-10, atol=1e-12 * np.abs(r).max())


@pytest.mark.parametrize("sigma", [0.0, 30.0, 1500.0, 4000.0])   # undamped, under-, over-damped
def test_damped_step_response_against_solve_ivp(sigma):
    w2 = 1096.0 ** 2
    times = np.array([0.0, 0.004, 0.009])
    F = np.array([2e5, -1e5, 0.0])
    resp = StepResponse(np.array([w2]), np.array([sigma]), times, F[:, None], np.array([1e-4]), np.array([0.2]))
    t = np.linspace(0.0, 0.02, 41)
    r, v = resp(t)

    def rhs(tt, x):
        f = F[np.searchsorted(times, tt, side="right") - 1]
        return [x[1], f - 2 * sigma * x[1] - w2 * x[0]]

    sol = solve_ivp(rhs, (0.0, 0.02), [1e-4, 0.2], t_eval=t, rtol=1e-12, atol=1e-16, max_step=1e-5,
                    method="DOP853")
    assert np.abs(r[:, 0] - sol.y[0]).max() < 1e-8 * np.abs(sol.y[0]).max()
    assert np.abs(v[:, 0] - sol.y[1]).max() < 1e-8 * np.abs(sol.y[1]).max()


def test_single_mode_energy_between_and_within_steps():
    """Report Sec. 5.5.1, Fig. 10: E = ½ṙ² + ½ω²r² is constant where the force is zero,
    and E − 𝓕 r is constant within each load step."""
    w = 198.0
    times = np.array([0.0, 0.05, 0.1, 0.15, 0.2, 0.25])
    F = np.array([0.0, 2e3, -1e3, 3e3, 1e3, 0.0])
    resp = StepResponse(np.array([w * w]), 0.0, times, F[:, None], np.zeros(1), np.ones(1))
    for k in range(times.size):
        t = np.linspace(times[k], times[k] + 0.049, 50)
        r, v = resp(t)
        E = 0.5 * v[:, 0] ** 2 + 0.5 * w * w * r[:, 0] ** 2
        corrected = E - F[k] * r[:, 0]
        assert np.ptp(corrected) < 1e-12 * max(1.0, np.abs(E).max())


def test_cosine_forcing_converges_to_eq37_at_second_order():
    """Report eq. 37, non-resonant ω_F = 400, ω = 1096: midpoint step loads; halving the
    steps cuts the error about four times."""
    w, wf, t_end = 1096.0, 400.0, 0.1
    t = np.linspace(0, t_end, 501)
    exact = (np.cos(wf * t) - np.cos(w * t)) / (w * w - wf * wf)
    errs = []
    for per_period in (32, 64, 128):
        n = int(np.ceil(t_end * wf / (2 * np.pi) * per_period))
        times = np.linspace(0.0, t_end, n + 1)
        mid = np.append(0.5 * (times[:-1] + times[1:]), t_end)
        resp = StepResponse(np.array([w * w]), 0.0, times, np.cos(wf * mid)[:, None], np.zeros(1), np.zeros(1))
        errs.append(np.abs(resp(t)[0][:, 0] - exact).max() / np.abs(exact).max())
    assert errs[-1] < 1e-3
    assert 3.0 < errs[0] / errs[1] < 5.0 and 3.0 < errs[1] / errs[2] < 5.0


# --- PureMA on finite-element bodies ---------------------------------------------------

@pytest.fixture(scope="module")
def clamped_all_modes():
    """A small clamped tet4 beam with ALL its modes (dense eigensolve), and its M, K, f."""
    mesh = box(1.0, 0.5, 2.0, 0.5, order=1)
    data = build_body(mesh, MATERIAL, 2, clamp="z0")
    fixed = clamped_dofs(3 * mesh.n_nodes, mesh.group("z0"))
    free = ~fixed
    m3 = np.repeat(data.masses, 3)
    K = data.stiffness.toarray()[np.ix_(free, free)]
    w2, V = la.eigh(K, np.diag(m3[free]))
    phi = np.zeros((3 * mesh.n_nodes, w2.size))
    phi[free] = V
    return mesh, replace(data, phi=phi, eigenvalues=w2), K, m3[free], free


def test_pure_ma_with_all_modes_equals_the_full_fe_solution(clamped_all_modes):
    """With every mode kept, PureMA is exact: compare with x(t) = e^{At}(x0 − x_p) + x_p of
    the full FE system (scipy's expm; no modes involved), for two load steps."""
    mesh, data, K, m, free = clamped_all_modes
    tip = mesh.group("z1")
    f1 = face_load(mesh, tip, [0.0, 500.0, 0.0])
    f2 = face_load(mesh, tip, [300.0, 0.0, -200.0])
    rng = np.random.default_rng(0)
    u_init = np.zeros((mesh.n_nodes, 3))
    u_init.reshape(-1)[free] = rng.normal(scale=1e-8, size=free.sum())
    basis = ModalBasis.from_body(data)
    loads = StepLoads.from_nodal([0.0, 2e-3], np.stack([f1, f2]))
    t_out = np.array([1e-3, 2e-3, 3.5e-3])
    res = PureMA(basis, [loads], u_init=u_init).solve(t_out)
    n = free.sum()
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K / m[:, None], np.zeros((n, n))]])

    def propagate(x, f, tau):
        xp = np.concatenate([np.linalg.solve(K, f.reshape(-1)[free]), np.zeros(n)])
        return la.expm(A * tau) @ (x - xp) + xp

    x0 = np.concatenate([u_init.reshape(-1)[free], np.zeros(n)])
    x_switch = propagate(x0, f1, 2e-3)
    ref = [propagate(x0, f1, 1e-3), x_switch, propagate(x_switch, f2, 1.5e-3)]
    u = res.elastic_displacement().reshape(3, -1)[:, free]
    for k in range(3):
        assert np.abs(u[k] - ref[k][:n]).max() < 1e-9 * np.abs(ref[k][:n]).max()


def test_free_body_pure_ma_moves_the_centre_of_mass_by_newton():
    mesh = box(1.0, 0.5, 2.0, 0.5, order=1)
    data = build_body(mesh, MATERIAL, 4)
    basis = ModalBasis.from_body(data, with_rigid_modes=True)
    F = np.array([100.0, -50.0, 20.0])
    f = face_load(mesh, mesh.group("x1"), F)
    res = PureMA(basis, [StepLoads.from_nodal([0.0], f[None])]).solve([0.1, 0.2])
    com = np.einsum("i,tia->ta", data.masses, res.displacements()) / data.total_mass
    expected = np.outer([0.1 ** 2, 0.2 ** 2], F) / (2 * data.total_mass)
    np.testing.assert_allclose(com, expected, rtol=1e-10)


def test_boundary_approach_gives_identical_results():
    """Report Sec. 4.2: surface-only projection and output equal the all-node results
    (to 1e-12 relative); modal energies equal."""
    mesh = box(1.0, 1.0, 5.0, 0.5, order=2)
    data = build_body(mesh, MATERIAL, 8, clamp="z0")
    basis = ModalBasis.from_body(data)
    f = face_load(mesh, mesh.group("z1"), [0.0, 500.0, 0.0])
    loads = [StepLoads.from_nodal([0.0, 0.01], np.stack([f, -0.5 * f]))]
    t = np.linspace(0.0, 0.05, 11)
    full = PureMA(basis, loads, rayleigh=(0.5, 1e-5)).solve(t)
    surf = PureMA(basis, loads, rayleigh=(0.5, 1e-5), boundary=True).solve(t)
    assert surf.nodes.size == data.surface_nodes.size < data.n_nodes
    u_full = full.elastic_displacement()[:, data.surface_nodes]
    assert np.abs(surf.elastic_displacement() - u_full).max() <= 1e-12 * np.abs(u_full).max()
    for key, val in full.energies().items():
        np.testing.assert_allclose(surf.energies()[key], val, rtol=1e-12, atol=0)
    interior = np.setdiff1d(np.arange(data.n_nodes), data.surface_nodes)[:1]
    with pytest.raises(ModelError, match="surface"):
        PureMA(basis, [StepLoads([0.0], interior, np.ones((1, 1, 3)))], boundary=True)


def test_modal_energies_equal_the_nodal_energies():
    """Eq. 34–35: ½ṙᵀṙ = ½ u̇ᵀ M u̇ and ½ rᵀΛr = ½ uᵀ K u summed over all nodes."""
    mesh = box(1.0, 0.5, 2.0, 0.5, order=1)
    data = build_body(mesh, MATERIAL, 6, clamp="z0")
    f = face_load(mesh, mesh.group("z1"), [0.0, 1e4, 0.0])
    res = PureMA(ModalBasis.from_body(data), [StepLoads.from_nodal([0.0], f[None])]).solve([3e-4, 1e-3])
    u = res.elastic_displacement().reshape(2, -1)
    ud = res.elastic_velocity().reshape(2, -1)
    m3 = np.repeat(data.masses, 3)
    e = res.energies()
    np.testing.assert_allclose(e["kinetic_vib"], 0.5 * np.einsum("ti,i,ti->t", ud, m3, ud), rtol=1e-10)
    np.testing.assert_allclose(e["potential_vib"], 0.5 * np.einsum("ti,ti->t", u, (data.stiffness @ u.T).T),
                               rtol=1e-8)


def test_step_loads_read_force_files_and_reject_bad_tables(tmp_path):
    from mbs import write_force_file

    forces = np.zeros((2, 4, 3))
    forces[0, 1] = [1.0, 2.0, 3.0]
    forces[1, 3] = [0.0, -4.0, 0.0]
    path = tmp_path / "force.txt"
    write_force_file(path, [0.0, 0.5], forces)
    loads = StepLoads.from_file(path, 4)
    assert loads.nodes.tolist() == [1, 3]
    np.testing.assert_array_equal(loads.forces, forces[:, [1, 3]])
    with pytest.raises(ModelError, match="increase"):
        StepLoads([0.0, 0.0], [0], np.zeros((2, 1, 3)))
    with pytest.raises(ModelError, match="shape"):
        StepLoads([0.0], [0, 1], np.zeros((1, 1, 3)))
