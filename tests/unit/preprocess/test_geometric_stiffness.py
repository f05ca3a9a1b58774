"""Geometric stiffening (preprocess.geometric, mbs.bodies.geometric_stiffening) against beam theory,
finite differences and the numpy references.

Oracles: the Rayleigh quotients of the Euler–Bernoulli cantilever's first mode under the
axial force of a spin about the root, N(x) = ρAΩ²(L² − x²)/2 (the Southwell coefficient
K_s = ∫ N φ'² dx / (Ω² ∫ ρA φ² dx) = 1.193), and of a root acceleration along the beam,
N(x) = −ρA a (L − x), computed here by quadrature of the analytic mode shape."""

import numpy as np
import pytest
import scipy.integrate

from ffrmbs.errors import InputFileError, ModelError
from mbs import FlexibleBodyFFR, PrescribedFrameMotion, System
from mbs.bodies.geometric_stiffening import (add_geometric_tangents, geometric_force, load_parameters,
                                      load_parameters_into, sub_geometric_force)
from mbs.bodies.validity import SpinMonitor
from preprocess import Material, box, build_body, read_body, write_body
from preprocess.geometric import LOAD_CASES

L, SIDE = 1.0, 0.04
STEEL0 = Material(7800.0, 2e11, 0.0)
BETA = 1.8751040687119611          # β1 L of the clamped-free beam


@pytest.fixture(scope="module")
def cantilever():
    """A 1 m x 40 mm x 40 mm tet10 cantilever along x, section centred, ν = 0, 4 modes."""
    mesh = box(L, SIDE, SIDE, None, order=2, divisions=(20, 2, 2))
    mesh.points[:, 1:] -= 0.5 * SIDE
    return build_body(mesh, STEEL0, 4, clamp="x0", geometric_stiffness=True)


@pytest.fixture(scope="module")
def free_beam():
    mesh = box(L, SIDE, SIDE, None, order=2, divisions=(10, 1, 1))
    return build_body(mesh, STEEL0, 4, clamp=None, geometric_stiffness=True)


def first_mode_quotient(axial_force):
    """∫ N(x) φ'(x)² dx / ∫ φ(x)² dx of the Euler–Bernoulli cantilever's first mode (L = 1)."""
    b = BETA
    s = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))

    def phi(x):
        return np.cosh(b * x) - np.cos(b * x) - s * (np.sinh(b * x) - np.sin(b * x))

    def dphi(x):
        return b * (np.sinh(b * x) + np.sin(b * x) - s * (np.cosh(b * x) - np.cos(b * x)))

    num = scipy.integrate.quad(lambda x: axial_force(x) * dphi(x) ** 2, 0.0, L, epsabs=1e-13)[0]
    return num / scipy.integrate.quad(lambda x: phi(x) ** 2, 0.0, L, epsabs=1e-13)[0]


def bending_block(data, case):
    """Eigenvalues of the load case's 2 x 2 block on the first bending pair (y and z)."""
    c = LOAD_CASES.index(case)
    return np.linalg.eigvalsh(data.geometric_stiffness[c, :2, :2])


def test_centrifugal_case_gives_the_southwell_coefficient(cantilever):
    rho_a = 1.0    # per unit ρA: the modes are mass-normalized, so K_s = Φᵀ K_σ Φ / Ω²
    k_s = first_mode_quotient(lambda x: rho_a * (L ** 2 - x ** 2) / 2)
    assert k_s == pytest.approx(1.1933, abs=2e-4)                    # Wright et al. 1982
    # spin about z (in-plane bending along y) and about y: the tension is the same
    for case in ("Omega_zz", "Omega_yy"):
        assert bending_block(cantilever, case) == pytest.approx([k_s, k_s], rel=2e-3)
    # a spin about the beam's own axis leaves the axial force at zero
    assert np.abs(bending_block(cantilever, "Omega_xx")).max() < 1e-3 * k_s


def test_root_acceleration_along_the_beam_compresses_it(cantilever):
    expected = first_mode_quotient(lambda x: -(L - x))             # N = −ρA a (L − x), a = 1
    assert bending_block(cantilever, "a_x") == pytest.approx([expected, expected], rel=2e-3)


def test_free_free_body_carries_no_stress_from_frame_accelerations(free_beam):
    G = free_beam.geometric_stiffness
    scale = np.abs(G[:6]).max()
    assert scale > 0
    assert np.abs(G[6:]).max() < 1e-8 * scale       # inertia relief balances them exactly


def test_body_file_keeps_the_geometric_stiffness(cantilever, tmp_path):
    write_body(tmp_path, cantilever)
    back = read_body(tmp_path)
    assert np.array_equal(back.geometric_stiffness, cantilever.geometric_stiffness)


def test_a_wrongly_shaped_geometric_stiffness_is_named(cantilever, tmp_path):
    import h5py

    write_body(tmp_path, cantilever)
    with h5py.File(tmp_path / "body.h5", "r+") as f:
        del f["geometric_stiffness"]
        f["geometric_stiffness"] = np.zeros((11, 4, 4))
    with pytest.raises(InputFileError, match="geometric_stiffness"):
        read_body(tmp_path)


def test_stiffening_without_the_data_is_a_clear_error(cantilever):
    from dataclasses import replace

    with pytest.raises(ModelError, match="--geometric-stiffness"):
        FlexibleBodyFFR(replace(cantilever, geometric_stiffness=None), 2, geometric_stiffening=True)


def test_kernels_match_the_numpy_references():
    rng = np.random.default_rng(3)
    K_cases = rng.standard_normal((12, 5, 5))
    w, wd, a_R = rng.standard_normal((3, 3))
    A = np.linalg.qr(rng.standard_normal((3, 3)))[0]
    p = np.empty(12)
    load_parameters_into(w, 0, wd, A, a_R, True, p)
    assert p == pytest.approx(load_parameters(w, wd, A.T @ a_R), abs=1e-15)
    u = np.concatenate([np.zeros(3), w])
    load_parameters_into(u, 3, wd, A, a_R, False, p)
    assert p == pytest.approx(load_parameters(w), abs=1e-15)
    q = np.concatenate([np.zeros(7), rng.standard_normal(5)])
    h = rng.standard_normal(11)
    expected = h.copy()
    expected[6:] -= geometric_force(K_cases, p, q[7:])
    sub_geometric_force(K_cases, p, q, 7, h, 6)
    assert h == pytest.approx(expected, abs=1e-13)


def test_free_frame_tangents_are_the_derivatives_of_the_force():
    """−∂h_f/∂q_f and −∂h_f/∂ω̄ of the kernel's force against central differences."""
    rng = np.random.default_rng(5)
    K_cases = rng.standard_normal((12, 4, 4))
    q = np.concatenate([np.zeros(7), rng.standard_normal(4)])
    u = rng.standard_normal(10)

    def force(q, u):
        p = np.empty(12)
        load_parameters_into(u, 3, p, np.eye(3), p, False, p)
        h = np.zeros(10)
        sub_geometric_force(K_cases, p, q, 7, h, 6)
        return h[6:]

    p = np.empty(12)
    load_parameters_into(u, 3, p, np.eye(3), p, False, p)
    K, D = np.zeros((10, 10)), np.zeros((10, 10))
    add_geometric_tangents(K_cases, p, q, 7, True, u, 3, K, D, 6, 3)
    eps = 1e-6
    for j in range(4):
        dq = np.zeros(11)
        dq[7 + j] = eps
        assert -(force(q + dq, u) - force(q - dq, u)) / (2 * eps) == pytest.approx(K[6:, 6 + j], abs=1e-7)
    for k in range(3):
        du = np.zeros(10)
        du[3 + k] = eps
        assert -(force(q, u + du) - force(q, u - du)) / (2 * eps) == pytest.approx(D[6:, 3 + k], abs=1e-7)


def steady_spin_frequencies(data, omega, stiffening):
    """Frequencies [rad/s] of the prescribed-spin body's linearized modal equations at
    t in the steady phase: K_t from central differences of h, M the modal mass."""
    system = System()
    beam = system.add(FlexibleBodyFFR(data, 4, frame=PrescribedFrameMotion.spin_up(omega, 1.0, axis=2),
                                      geometric_stiffening=stiffening))
    t = 5.0
    q, u = np.zeros(4), np.zeros(4)
    M, h0 = beam.mass_and_h(q, u, t)
    K = np.empty((4, 4))
    for j in range(4):
        dq = np.zeros(4)
        dq[j] = 1e-6
        K[:, j] = -(beam.mass_and_h(q + dq, u, t)[1] - beam.mass_and_h(q - dq, u, t)[1]) / 2e-6
    return np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real))


def test_steady_spin_stiffens_the_bending_modes_as_southwell_says(cantilever):
    """Spin about z at Ω: to first order in Ω² out of plane (z) ω² = ω1² + K_s Ω², in plane
    (y) ω1² + (K_s − 1) Ω² (Southwell); linear FFR gives ω1² and ω1² − Ω². The Coriolis
    coupling of a bending and an axial mode is left out of this stiffness-only
    linearization; Ω = 0.3 ω1 keeps the second-order terms (which lower the coefficients)
    below the tolerance."""
    w1 = np.sqrt(cantilever.eigenvalues[:2]).mean()
    omega = 0.3 * w1
    k_s = first_mode_quotient(lambda x: (L ** 2 - x ** 2) / 2)

    def coefficients(stiffening):
        return (steady_spin_frequencies(cantilever, omega, stiffening)[:2] ** 2 - w1 ** 2) / omega ** 2

    assert coefficients(True) == pytest.approx([k_s - 1, k_s], abs=4e-3)
    assert coefficients(False) == pytest.approx([-1.0, 0.0], abs=4e-3)


def test_spin_monitor_leaves_stiffened_bodies_alone(cantilever):
    system = System()
    system.add(FlexibleBodyFFR(cantilever, 2, frame=PrescribedFrameMotion.spin_up(3.0, 1.0),
                               geometric_stiffening=True, name="on"))
    system.add(FlexibleBodyFFR(cantilever, 2, frame=PrescribedFrameMotion.spin_up(3.0, 1.0), name="off"))
    assert [b.name for b in SpinMonitor(system).watched] == ["off"]


def test_spin_up_profile_is_smooth_and_reaches_the_spin():
    motion = PrescribedFrameMotion.spin_up(6.0, 15.0, axis=2)
    eps = 1e-5
    for t in (0.3, 7.0, 14.9, 15.0, 16.0):
        A, w, wd = motion.rotation(t)
        Ap, wp, _ = motion.rotation(t + eps)
        Am, wm, _ = motion.rotation(t - eps)
        Adot = (Ap - Am) / (2 * eps)
        skew = A.T @ Adot                                   # ω̃ in body axes
        assert [skew[2, 1], skew[0, 2], skew[1, 0]] == pytest.approx(w, abs=1e-7)
        assert (wp - wm) / (2 * eps) == pytest.approx(wd, abs=1e-6)
    assert motion.rotation(15.0)[1][2] == pytest.approx(6.0) and motion.rotation(15.0)[2][2] == pytest.approx(0.0)
    theta = np.arctan2(motion.rotation(20.0)[0][1, 0], motion.rotation(20.0)[0][0, 0])
    assert theta == pytest.approx(np.angle(np.exp(1j * 6.0 * (20.0 - 7.5))))
    with pytest.raises(ModelError, match="axis"):
        PrescribedFrameMotion.spin_up(1.0, 1.0, axis=3)


def test_scene_file_turns_the_stiffening_on(cantilever, tmp_path):
    from ffrmbs_app.scene_file import read_scene

    write_body(tmp_path / "beam", cantilever)
    (tmp_path / "spin.toml").write_text(
        '[scene]\nt_end = 0.01\ndt = 1e-3\n\n[[body]]\nname = "beam"\nkind = "flexible"\nsource = "beam"\n'
        'modes = 2\nangular_velocity = [0.0, 0.0, 50.0]\ngeometric_stiffening = true\n')
    beam = read_scene(tmp_path / "spin.toml").system.bodies[0]
    assert beam.geometric_stiffening and beam.varying_tangents
    assert np.array_equal(beam.K_cases, cantilever.geometric_stiffness[:, :2, :2])
