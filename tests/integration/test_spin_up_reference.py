"""The spin-up beam reference (:mod:`validation.peers.spin_up_beam`), coarse settings,
each check against something independent of the ANCF model:

1. the hub angle's derivatives against central finite differences, θ continuous and C¹
   (also C²) at T_s;
2. static: a small tip force against PL³/(3EI); a large one against the inextensible
   elastica (scipy's ``solve_bvp``) — less than the linear deflection;
3. the first clamped frequency 1.8751² √(EI/(ρA L⁴)): the eigenvalues of the tangent
   stiffness and mass, and a released free vibration integrated in time;
4. the numba element forces against the plain-numpy ones, the analytic tangent against
   finite differences of the forces;
5. centrifugal stiffening at Ω = 3 rad/s (steady state, gyroscopic eigenproblem in the
   rotating frame) against Southwell's ω² = ω1² + (K_s − 1)Ω², K_s = 1.193, and a
   Rayleigh–Ritz model of the linear rotating beam with the centrifugal tension;
6. the spin-up: a coarse run bounded, lagging, its peak within 1 % of :func:`reference`,
   and the reference against a linear Ritz model WITH geometric stiffening
   (ρA(v̈ − θ̇² v) + EI v'''' − (T v')' = −ρA θ̈ x, T = ρA θ̇² (L² − x²)/2, integrated by
   scipy's DOP853), which for these small deflections must agree closely;

plus the cache (atomic npz in $FFRMBS_CACHE, read back; the reference comes from the
session's cache) and the convergence table rows.
"""

import math

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.integrate import solve_bvp, solve_ivp

from validation.peers import spin_up_beam as sb

L, EI, RHO_A = sb.LENGTH, sb.EI, sb.RHO_A
OMEGA1 = 1.8751040687**2 * math.sqrt(EI / (RHO_A * L**4))      # [rad/s], Euler–Bernoulli cantilever


@pytest.fixture(scope="module")
def ritz():
    """Rayleigh–Ritz of the linear rotating beam on the clamped basis (x/L)^k, k = 2..9,
    reduced to its 5 lowest non-rotating modes: (K_E, K_G − M, f0, tip row, M, K_E, K_G)
    with K_G = ∫ ρA (L² − x²)/2 φ' φ'^T dx, f0 = ∫ ρA x φ dx."""
    xg, wg = np.polynomial.legendre.leggauss(40)
    x, w = 0.5 * L * (xg + 1), 0.5 * L * wg
    k = np.arange(2, 10)
    phi = (x[:, None] / L) ** k
    d1 = k * (x[:, None] / L) ** (k - 1) / L
    d2 = k * (k - 1) * (x[:, None] / L) ** (k - 2) / L**2
    m = RHO_A * np.einsum("g,gi,gj->ij", w, phi, phi)
    ke = EI * np.einsum("g,gi,gj->ij", w, d2, d2)
    kg = RHO_A * np.einsum("g,gi,gj->ij", w * (L**2 - x**2) / 2, d1, d1)
    f0 = RHO_A * np.einsum("g,g,gi->i", w, x, phi)
    v = sl.eigh(ke, m)[1][:, :5]
    return {"ke": v.T @ ke @ v, "kgm": v.T @ (kg - m) @ v, "f0": v.T @ f0, "tip": v.sum(axis=0),
            "M": m, "KE": ke, "KG": kg}


# ------------------------------------------------------------------------ 1. hub angle
def test_hub_angle_derivatives_and_smoothness():
    t = np.array([0.3, 2.0, 7.5, 11.1, 14.9, 15.2, 18.0])
    h = 1e-5
    th, om, al = sb.hub_angle(t)
    thp, omp, _ = sb.hub_angle(t + h)
    thm, omm, _ = sb.hub_angle(t - h)
    assert np.allclose((thp - thm) / (2 * h), om, rtol=1e-8, atol=1e-8)
    assert np.allclose((omp - omm) / (2 * h), al, rtol=1e-6, atol=1e-8)
    before = np.array(sb.hub_angle(sb.T_S - 1e-9))
    after = np.array(sb.hub_angle(sb.T_S + 1e-9))
    assert np.allclose(before, after, atol=1e-7)
    assert math.isclose(sb.hub_angle(sb.T_S)[0], sb.OMEGA_S * sb.T_S / 2, rel_tol=1e-12)
    assert sb.hub_angle(0.0)[0] == 0.0 and sb.hub_angle(0.0)[1] == 0.0


# --------------------------------------------------------------------------- 2. static
def elastica_tip(p):
    """Tip (x, y) [m] of the inextensible cantilever under a transverse tip force p [N]:
    θ' = m/EI, m' = −p cos θ, x' = cos θ, y' = sin θ; θ(0) = x(0) = y(0) = 0, m(L) = 0."""
    def f(s, y):
        return np.vstack([y[1] / EI, -p * np.cos(y[0]), np.cos(y[0]), np.sin(y[0])])

    def bc(a, b):
        return np.array([a[0], b[1], a[2], a[3]])

    s = np.linspace(0, L, 200)
    guess = np.vstack([p * (L * s - s**2 / 2) / EI, p * (L - s), s, p * s**2 * (3 * L - s) / (6 * EI)])
    sol = solve_bvp(f, bc, s, guess, tol=1e-10)
    assert sol.success
    return sol.y[2, -1], sol.y[3, -1]


def test_static_small_and_large_tip_force():
    beam = sb.Beam(8)
    q = beam.static([0.0, 1.0], n_load_steps=1)
    assert q[-3] == pytest.approx(L**3 / (3 * EI), rel=2e-5)
    p = 100.0
    q = beam.static([0.0, p])
    x, y = elastica_tip(p)
    assert q[-3] < 0.96 * p * L**3 / (3 * EI)            # geometric nonlinearity: stiffer than linear
    assert q[-3] == pytest.approx(y, rel=1e-3)
    assert q[-4] == pytest.approx(x, rel=1e-3)


# ---------------------------------------------------------------------- 3. frequency
def test_first_frequency_eigen_and_time_run():
    beam = sb.Beam(8)
    k = beam.tangent(sb.straight_beam(8))[4:, 4:]
    w = np.sqrt(sl.eigh(k, beam.mass[4:, 4:], eigvals_only=True))
    assert w[0] == pytest.approx(OMEGA1, rel=1e-4)
    assert w[1] == pytest.approx(4.6940911330**2 * math.sqrt(EI / (RHO_A * L**4)), rel=1e-3)

    q0 = beam.static([0.0, 1.0], n_load_steps=1)          # released from the static deflection, hub at rest
    t, s = sb.run(beam, 0.01, 10.0, q0=q0, omega_s=0.0)
    y = s[:, 1]
    i = np.nonzero(np.sign(y[:-1]) != np.sign(y[1:]))[0]
    tz = t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
    period = 2 * (tz[-1] - tz[0]) / (len(tz) - 1)
    assert len(tz) >= 10
    assert 2 * math.pi / period == pytest.approx(OMEGA1, rel=5e-3)


# -------------------------------------------------------------------------- 4. kernels
@pytest.mark.parametrize("curvature", ["exact", "simple"])
def test_numba_forces_and_tangent(curvature):
    n = 4
    beam = sb.Beam(n, curvature)
    rng = np.random.default_rng(3)
    q = sb.straight_beam(n, 0.4) + 0.05 * rng.standard_normal(4 * (n + 1))
    f = beam.forces(q)
    assert np.max(np.abs(f - sb.element_forces_numpy(q, n, curvature))) <= 1e-12 * np.max(np.abs(f))
    k = beam.tangent(q)
    h = 1e-6
    kfd = np.array([(beam.forces(q + h * e) - beam.forces(q - h * e)) / (2 * h) for e in np.eye(q.size)]).T
    assert np.max(np.abs(k - kfd)) <= 1e-6 * np.max(np.abs(k))
    assert np.array_equal(k, k.T)


# ------------------------------------------------------------------------- 5. rotation
def rotating_frequency(beam, omega):
    """Lowest in-plane bending frequency [rad/s] in the frame spinning at ``omega``
    about the root: steady state Q_f − Ω² (M q)_f = 0, then M ü + 2Ω M_J u̇ + (K − Ω² M) u = 0
    (M_J = M with each 2×2 block times J, J the 90° rotation) as a first-order eigenproblem."""
    q = sb.straight_beam(beam.n)
    m = beam.mass
    for _ in range(20):
        r = beam.forces(q)[4:] - omega**2 * (m @ q)[4:]
        dq = np.linalg.solve(beam.tangent(q)[4:, 4:] - omega**2 * m[4:, 4:], -r)
        q[4:] += dq
        if np.max(np.abs(dq)) < 1e-12:
            break
    mf = m[4:, 4:]
    g = 2 * omega * mf @ np.kron(np.eye(mf.shape[0] // 2), np.array([[0.0, -1.0], [1.0, 0.0]]))
    kf = beam.tangent(q)[4:, 4:] - omega**2 * mf
    nf = mf.shape[0]
    a = np.block([[np.zeros((nf, nf)), np.eye(nf)], [-np.linalg.solve(mf, kf), -np.linalg.solve(mf, g)]])
    lam = np.linalg.eigvals(a)
    w = np.sort(np.abs(lam.imag[lam.imag > 1e-9]))
    assert np.max(np.abs(lam.real)) < 1e-6 * np.max(np.abs(lam))      # undamped: a pure imaginary spectrum
    return w[0]


def test_centrifugal_stiffening(ritz):
    omega = 3.0
    w = rotating_frequency(sb.Beam(8), omega)
    southwell = math.sqrt(OMEGA1**2 + (1.193 - 1.0) * omega**2)
    assert w == pytest.approx(southwell, rel=2e-2)
    assert w > OMEGA1 * 1.05
    wr = np.sqrt(sl.eigh(ritz["KE"] + omega**2 * (ritz["KG"] - ritz["M"]), ritz["M"], eigvals_only=True)[0])
    assert w == pytest.approx(wr, rel=2e-3)


# -------------------------------------------------------------------------- 6. spin-up
def test_spin_up_against_reference_and_stiffened_linear_model(ritz):
    """The reference from the session's cache (computed once, shared with
    tests/integration/test_spin_up_beam.py; the cache itself: :func:`test_runs_are_cached_atomically`)."""
    t, v = sb.simulate(8, 0.01)
    tr, vr = sb.reference()
    assert np.array_equal(t, tr) and t.shape == (2001,) and t[1] == pytest.approx(0.01)
    assert np.max(np.abs(v)) < 1.0 and np.all(np.isfinite(v))
    assert np.min(v[: int(sb.T_S / 0.01)]) == pytest.approx(np.min(vr), rel=1e-2)
    assert np.min(vr) < 0 and np.max(vr[: int(sb.T_S / 0.01)]) < 0.02 * abs(np.min(vr))   # lags while spun up
    assert np.sqrt(np.mean((v - vr) ** 2)) < 2e-3 * np.max(np.abs(vr))

    f, ke, kgm, tip = ritz["f0"], ritz["ke"], ritz["kgm"], ritz["tip"]
    n = f.size

    def rhs(time, y):
        _, om, al = sb.hub_angle(time)
        return np.concatenate([y[n:], -(ke + om**2 * kgm) @ y[:n] - al * f])

    sol = solve_ivp(rhs, (0.0, sb.T_END), np.zeros(2 * n), method="DOP853", t_eval=tr, rtol=1e-10, atol=1e-12)
    vl = tip @ sol.y[:n]
    scale = np.max(np.abs(vr))
    assert np.min(vl) == pytest.approx(np.min(vr), rel=3e-3)
    assert np.sqrt(np.mean((vl - vr) ** 2)) < 2e-3 * scale


def test_runs_are_cached_atomically(tmp_path, monkeypatch):
    """A run (2 elements: the same code path as the reference's 32) stored in
    $FFRMBS_CACHE, no temporary file left, read back equal to a fresh simulation; the
    reference is a cached run under its own key."""
    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path))
    t, v = sb.cached_run(2, 0.01)
    key = sb.recipe(2, 0.01)
    assert sb.cache_path(key).exists() and sb.cache_path(key).parent == tmp_path
    assert not list(tmp_path.glob("*.tmp"))
    assert np.array_equal(sb.cached_run(2, 0.01)[1], v)              # read back from the file
    fresh = sb.simulate(2, 0.01)
    assert np.array_equal(fresh[0], t) and np.array_equal(fresh[1], v)
    assert sb.cache_path(sb.recipe(*sb.REFERENCE_SETTINGS)) != sb.cache_path(key)


def test_convergence_table_rows(tmp_path, monkeypatch):
    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path))
    rows = sb.convergence_table(((2, 0.01), (4, 0.005)))
    assert [r[:2] for r in rows] == [(2, 0.01), (4, 0.005)]
    assert rows[1][2:] == (0.0, 0.0) and 0 < rows[0][2] <= rows[0][3]
