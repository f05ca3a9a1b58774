"""α–Ω decision boundaries (report Sec. 4.1 eq. 29-32, Sec. 5.4 Fig. 9) against independent
oracles: a hand-computed dumbbell, brute-force sampling of directions with the fictitious
forces built node by node, and the static FE solution (K u = f with inertia relief)."""

import numpy as np
import pytest
import scipy.linalg as la

from ffrmbs.errors import ModelError
from mbs.modal.decision import decision_boundaries, force_limit
from preprocess.modes import all_modes, rigid_body_modes
from preprocess.pipeline import Material, build_body

M_END, LENGTH, K_SPRING = 3.0, 2.0, 50.0  # kg, m, N/m


@pytest.fixture(scope="module")
def dumbbell():
    """Two point masses m at x = ±L/2 joined by an axial spring k (stiffness only in x).

    Hand results. The only elastic mode is the axial stretch φ = (−1,0,0, 1,0,0)/√(2m)
    (φᵀMφ = 2m/(2m) = 1) with ω² = φᵀKφ = k·(2)²/(2m) = 2k/m.

    * α: −m α × b_n is perpendicular to b_n, i.e. to the x axis (α ⊥ axis: tangential
      forces; α ∥ axis: α × b = 0), so φᵀf = 0 and d_alpha = 0.
    * Ω ⊥ axis (|Ω| = 1): the centrifugal forces m(b_n − (Ω·b_n)Ω) = m b_n pull each end
      outward with m L/2. The spring carries the tension T = m L/2 and stretches by
      T/k, each end moving half of it: d_omega = m L/(4k). (Modal check:
      F = φᵀf = 2·(m L/2)/√(2m), r = F/ω², u = r/√(2m) = m L/(4k).) Ω ∥ axis gives no
      force, oblique Ω gives (1 − cos²) times the perpendicular value, so Ω ⊥ axis is
      the maximum.
    * force limit (eq. 31): max m|b| = m L/2.
    """
    u0 = np.array([[-LENGTH / 2, 0.0, 0.0], [LENGTH / 2, 0.0, 0.0]]) + [0.3, -0.2, 1.0]  # off-origin
    masses = np.array([M_END, M_END])
    phi = np.array([[-1.0, 0, 0, 1.0, 0, 0]]).T / np.sqrt(2 * M_END)
    K = np.zeros((6, 6))
    K[np.ix_([0, 3], [0, 3])] = K_SPRING * np.array([[1, -1], [-1, 1]])
    omega2 = np.array([phi[:, 0] @ K @ phi[:, 0]])
    assert omega2[0] == pytest.approx(2 * K_SPRING / M_END)
    return u0, masses, phi, omega2


def test_dumbbell_hand_values(dumbbell):
    db = decision_boundaries(*dumbbell)
    assert db.d_alpha < 1e-15
    assert db.d_omega == pytest.approx(M_END * LENGTH / (4 * K_SPRING), rel=1e-10)
    assert abs(db.omega_direction[0]) < 1e-5  # Ω perpendicular to the axis
    assert force_limit(dumbbell[0], dumbbell[1], 2.0) == pytest.approx(2.0 / (M_END * LENGTH / 2), rel=1e-14)
    s_neg, s_lin = db.sum_limits
    assert s_neg == pytest.approx(1e-6 / (2 * db.d_omega)) and s_lin == pytest.approx(0.05 / (2 * db.d_omega))


@pytest.mark.parametrize("k_dyn", [2.0, 1.0])
def test_dumbbell_recommendations_either_side_of_the_boundaries(dumbbell, k_dyn):
    db = decision_boundaries(*dumbbell, d_negligible=1e-6, d_linear=0.05, k_dyn=k_dyn)
    d_omega = M_END * LENGTH / (4 * K_SPRING)
    w_neg = np.sqrt(1e-6 / (k_dyn * d_omega))  # |Ω| where k_dyn d_omega |Ω|² = d
    w_lin = np.sqrt(0.05 / (k_dyn * d_omega))
    assert db.recommend(0.0, 0.99 * w_neg) == "SimpleRB"
    assert db.recommend(0.0, 1.01 * w_neg) == "CoupledRB"
    assert db.recommend(0.0, 0.99 * w_lin) == "CoupledRB"
    assert db.recommend(0.0, 1.01 * w_lin) == "outside linear elasticity"
    assert db.recommend(1e9, 0.0) == "SimpleRB"  # d_alpha = 0: α alone deforms nothing
    assert db.recommend([0.0, 0.0, 1e9], [0.0, 1.01 * w_lin, 0.0]) == "outside linear elasticity"
    assert db.displacement(0.0, 3.0) == pytest.approx(k_dyn * d_omega * 9.0)


def test_bad_parameters_are_model_errors(dumbbell):
    u0, masses, phi, omega2 = dumbbell
    for kwargs in ({"d_negligible": 0.1, "d_linear": 0.05}, {"k_dyn": 0.5}):
        with pytest.raises(ModelError):
            decision_boundaries(u0, masses, phi, omega2, **kwargs)
    with pytest.raises(ModelError, match="rigid"):
        decision_boundaries(u0, masses, phi, np.array([0.0]))
    with pytest.raises(ModelError):
        decision_boundaries(u0, masses, phi[:3], omega2)
    with pytest.raises(ModelError):
        force_limit(u0, masses, -1.0)


def random_body(seed, n_nodes=7, n_modes=5):
    """Random positions and masses, random M-orthonormal modes, random ω²."""
    rng = np.random.default_rng(seed)
    u0 = rng.uniform(-1.0, 1.0, (n_nodes, 3)) * [2.0, 1.0, 0.5]
    masses = rng.uniform(0.5, 3.0, n_nodes)
    s = np.repeat(np.sqrt(masses), 3)
    Q = np.linalg.qr(rng.standard_normal((3 * n_nodes, n_modes)))[0]
    phi = Q / s[:, None]
    return u0, masses, phi, rng.uniform(1.0, 20.0, n_modes)


def sampled_max(u0, masses, phi, omega2, force, n=20000, seed=0):
    """max over n random unit directions and over nodes of |Φ diag(1/ω²) Φᵀ f(dir)|,
    the fictitious force f built node by node."""
    b = u0 - masses @ u0 / masses.sum()
    dirs = np.random.default_rng(seed).standard_normal((n, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    F = np.zeros((n, len(masses), 3))
    for i in range(len(masses)):
        F[:, i] = force(masses[i], b[i], dirs)
    U = (F.reshape(n, -1) @ phi / omega2) @ phi.T
    return np.linalg.norm(U.reshape(n, -1, 3), axis=2).max()


def euler_force(m, b, a):  # −m α × b, α = a (n, 3)
    return -m * np.cross(a, b)


def centrifugal_force(m, b, w):  # −m Ω × (Ω × b), Ω = w (n, 3)
    return -m * np.cross(w, np.cross(w, b))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_body_against_sampled_directions(seed):
    body = random_body(seed)
    db = decision_boundaries(*body)
    for exact, force in ((db.d_alpha, euler_force), (db.d_omega, centrifugal_force)):
        sampled = sampled_max(*body, force, seed=seed)
        assert sampled <= exact * (1 + 1e-9)
        assert sampled >= 0.97 * exact
    # the returned direction attains d_omega
    b = body[0] - body[1] @ body[0] / body[1].sum()
    f = np.stack([centrifugal_force(m, bn, db.omega_direction[None])[0] for m, bn in zip(body[1], b)])
    u = body[2] @ ((body[2].T @ f.ravel()) / body[3])
    assert np.linalg.norm(u.reshape(-1, 3), axis=1).max() == pytest.approx(db.d_omega, rel=1e-12)


@pytest.fixture(scope="module")
def free_box(small_box_tet4):
    mesh = small_box_tet4
    body = build_body(mesh, Material(8000.0, 200e9, 0.3), 6)
    return mesh, body, all_modes(body.stiffness, body.masses, None, body.u0)


def test_free_body_inertia_relief_and_static_fe_oracle(free_box):
    """With ALL elastic modes the quasi-static modal response is the FE static solution
    with inertia relief: K u + M R λ = f, Rᵀ M u = 0 (R the rigid modes). Solved densely
    at the worst Ω direction found, it must reproduce d_omega. The Euler (α) loads are
    M times a rigid rotation mode, so a free body has d_alpha = 0 (to rounding)."""
    mesh, body, (w2, phi) = free_box
    db = decision_boundaries(body.u0, body.masses, phi, w2)
    assert db.d_alpha < 1e-9 * db.d_omega
    truncated = decision_boundaries(body.u0, body.masses, body.phi, body.eigenvalues)
    assert truncated.d_alpha < 1e-9 * truncated.d_omega
    assert truncated.d_omega < db.d_omega * (1 + 1e-9)  # truncation misses some static response

    m3 = np.repeat(body.masses, 3)
    R = rigid_body_modes(body.u0, body.masses)
    n = 3 * mesh.n_nodes
    A = np.zeros((n + 6, n + 6))
    A[:n, :n] = body.stiffness.toarray()
    A[:n, n:] = m3[:, None] * R
    A[n:, :n] = (m3[:, None] * R).T
    b = body.u0 - body.center_of_mass
    f = np.stack([centrifugal_force(m, bn, db.omega_direction[None])[0] for m, bn in zip(body.masses, b)])
    u = la.solve(A, np.concatenate([f.ravel(), np.zeros(6)]))[:n]
    assert np.linalg.norm(u.reshape(-1, 3), axis=1).max() == pytest.approx(db.d_omega, rel=1e-8)


def test_plot_writes_png(dumbbell, tmp_path):
    db = decision_boundaries(*dumbbell)
    path = tmp_path / "fig9.png"
    fig = db.plot(path, points=[(0.0, 0.5, "const. Ω"), (10.0, 1e-3, "const. α"), (1e-3, 0.0, "rest")])
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000
    assert fig.axes[0].get_xscale() == "log" and fig.axes[0].get_yscale() == "log"
