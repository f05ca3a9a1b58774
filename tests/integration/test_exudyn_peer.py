"""Exudyn's FFR body (optional peer, validation/peers/exudyn_ffr.py) against physics.

Skipped when exudyn is not installed: it is an optional reference code. Every
expected value here comes from rigid-body mechanics or bar theory with the beam's
lumped masses, never from Exudyn's own output. The beam is the report's
1 x 1 x 5 m steel beam (ρ = 8000 kg/m³, E = 200 GPa, ν = 0), free-free, 10 modes.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

exudyn = pytest.importorskip("exudyn")

from preprocess import build_body, face_load  # noqa: E402
from validation.cases.cantilever import MATERIAL  # noqa: E402
from validation.peers import exudyn_ffr  # noqa: E402

Y = np.array([0.0, 1.0, 0.0])
Z = np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def beam(report_beam):
    """(mesh, body, weights on z1, weights on z0, index of the node at the origin)."""
    body = build_body(report_beam, MATERIAL, n_modes=10, clamp=None)
    w1 = face_load(report_beam, report_beam.group("z1"), [1.0, 0.0, 0.0])[:, 0]
    w0 = face_load(report_beam, report_beam.group("z0"), [1.0, 0.0, 0.0])[:, 0]
    origin = np.flatnonzero(np.all(np.abs(report_beam.points) < 1e-12, axis=1))
    assert len(origin) == 1
    return report_beam, body, w1, w0, int(origin[0])


def _run(beam, loads, t_end, h, n_out=None, rho_inf=0.9):
    _, body, _, _, probe = beam
    n_out = int(round(t_end / h)) + 1 if n_out is None else n_out
    times = np.linspace(0.0, t_end, n_out)
    return exudyn_ffr.free_flight(body.u0, body.masses, body.stiffness, body.phi, loads,
                                  t_end, h, probe, times, rho_inf=rho_inf)


def _rigid_properties(body):
    """Mass [kg], centre of mass [m] and inertia tensor about it [kg m²] of the lumped masses."""
    m = body.masses
    mass = m.sum()
    com = m @ body.u0 / mass
    d = body.u0 - com
    second = np.einsum("i,ij,ik->jk", m, d, d)
    return mass, com, np.trace(second) * np.eye(3) - second


def test_available():
    assert exudyn_ffr.available()


def test_equal_end_forces_accelerate_the_beam_as_a_rigid_body(beam):
    """50 N along body y on each end face: a_y = 100 N / m, no rotation (forces symmetric
    about the centre of mass), so the probe node moves by 0.5 a t² along y plus its
    elastic displacement."""
    _, body, w1, w0, probe = beam
    t_end = 0.05
    r = _run(beam, [(w1, Y, lambda t: 50.0), (w0, Y, lambda t: 50.0)], t_end, 1e-3, n_out=11)
    mass = body.masses.sum()
    a = 100.0 / mass                                        # 2.5e-3 m/s² for 40 t
    rigid = r["position"] - r["elastic"] - body.u0[probe]   # R + (A - I)(u0 + e) with A ≈ I
    expected = 0.5 * a * r["t"] ** 2                        # 3.1e-6 m at t_end

    np.testing.assert_allclose(r["t"], np.linspace(0, t_end, 11))
    np.testing.assert_array_equal(r["position"][0], body.u0[probe])
    # Generalized-α integrates a constant acceleration exactly (the rigid part of the
    # motion is a quadratic in t), so only the Newton tolerance (1e-8 relative) and the
    # rotation left by the mesh's asymmetry (A - I ~ 1e-17 here) remain: 1e-6 relative
    # leaves two orders of margin and still catches any error in mass, load sum, load
    # timing (a one-step lag would be 4 % at t = 0.05 s) or frame origin.
    np.testing.assert_allclose(rigid[1:, 1], expected[1:], rtol=1e-6)
    assert np.abs(rigid[:, [0, 2]]).max() < 1e-6 * expected[-1]
    # the elastic part is small against the rigid one but not zero: the beam bends under
    # the end loads while its middle lags behind (order 1e-8 m)
    elastic = np.abs(r["elastic"][:, 1]).max()
    assert 1e-10 < elastic < 1e-2 * expected[-1]
    assert r["steps"] == 50 and r["cpu_s"] >= 0 and r["setup_s"] >= 0


def _axial_static(body):
    """Probe (z = 0 face) shortening of a free-free bar under end compression F, first axial
    mode only: (8/π²) · F L / (2 E A) (the modal series of the free-free bar sums the odd
    modes to F L / (2 E A); the first, 8/π² of it, is the only axial mode among 10 modes)."""
    F, L, E, A = 1.0e6, 5.0, MATERIAL.young, 1.0
    return F, 8.0 / np.pi ** 2 * F * L / (2 * E * A)


def test_suddenly_applied_end_compression_gives_bar_theory_deformation(beam):
    """A balanced compression (−F on z1, +F on z0, along body z) applied at t = 0: no rigid
    motion; the probe node at z = 0 moves +z in the body frame. With full numerical
    damping (ρ∞ = 0) the response settles at the static value; without it (ρ∞ = 1)
    it oscillates between 0 and twice the static value (suddenly applied load)."""
    _, body, w1, w0, probe = beam
    F, static = _axial_static(body)                     # 1.01e-5 m
    loads = [(w1, Z, lambda t: -F), (w0, Z, lambda t: F)]
    t_end, h = 0.05, 2e-4                               # 16 periods of the axial mode (2.0 ms)

    damped = _run(beam, loads, t_end, h, rho_inf=0.0)
    # 3D tet10 model vs bar theory: the FE axial mode carries 1.6 % more end
    # displacement than the bar's (measured 1.029e-5 vs 1.013e-5 m); 5 % tolerance
    np.testing.assert_allclose(damped["elastic"][-1, 2], static, rtol=0.05)
    assert np.abs(damped["elastic"][-1, :2]).max() < 0.05 * static
    # no net force, no net torque: the body frame keeps the probe at u0 + elastic
    drift = damped["position"] - damped["elastic"] - body.u0[probe]
    assert np.abs(drift).max() < 1e-3 * static

    undamped = _run(beam, loads, t_end, h, rho_inf=1.0)
    ez = undamped["elastic"][:, 2]
    late = ez[undamped["t"] > 0.03]
    np.testing.assert_allclose(late.max() - late.min(), 2 * static, rtol=0.05)
    np.testing.assert_allclose(ez.mean(), static, rtol=0.05)
    assert ez.min() > -0.05 * static                    # compression only, never stretched


def test_body_fixed_loads_rotate_with_the_beam(beam):
    """A body-fixed couple (−Fc on z1, +Fc on z0 along body y) spins the beam about x by
    about 0.5 rad in 0.5 s, while a body-fixed axial force Fa on z0 along body z drives
    the centre of mass along the TURNING body axis; a force fixed in space would give no
    lateral (y) motion at all. Reference: rigid-body dynamics of the lumped masses
    (Newton–Euler with the full inertia tensor), integrated by solve_ivp."""
    _, body, w1, w0, probe = beam
    Fc, Fa = 7.0e4, 4.0e5
    t_end, h = 0.5, 1e-3
    loads = [(w1, Y, lambda t: -Fc), (w0, Y, lambda t: Fc), (w0, Z, lambda t: Fa)]
    r = _run(beam, loads, t_end, h, n_out=51)

    mass, com0, inertia = _rigid_properties(body)
    # resultant force and moment about the centre of mass, constant in the body frame
    force_b = np.zeros(3)
    moment_b = np.zeros(3)
    for w, d, f in loads:
        force_b += d * f(0.0)
        moment_b += np.cross(w @ (body.u0 - com0), d * f(0.0))
    inv_inertia = np.linalg.inv(inertia)

    def rhs(_t, s):
        A, omega, v = s[:9].reshape(3, 3), s[9:12], s[15:18]
        w_tilde = np.array([[0, -omega[2], omega[1]], [omega[2], 0, -omega[0]],
                            [-omega[1], omega[0], 0]])
        return np.concatenate([(A @ w_tilde).ravel(),
                               inv_inertia @ (moment_b - np.cross(omega, inertia @ omega)),
                               v, A @ force_b / mass])

    s0 = np.concatenate([np.eye(3).ravel(), np.zeros(3), com0, np.zeros(3)])
    sol = solve_ivp(rhs, (0.0, t_end), s0, t_eval=r["t"], rtol=1e-11, atol=1e-13, method="DOP853")
    A_ref = sol.y[:9].T.reshape(-1, 3, 3)
    com_ref = sol.y[12:15].T
    probe_ref = com_ref + np.einsum("tij,j->ti", A_ref, body.u0[probe] - com0)

    angle = np.arctan2(A_ref[-1, 2, 1], A_ref[-1, 1, 1])
    assert 0.45 < angle < 0.55                                   # a large rotation
    lateral = com_ref[-1, 1] - com0[1]
    assert lateral < -0.05                                       # 0.10 m from the turning force

    # Elastic deformation (a few µm) and the time step (h = 1 ms, error O(h²)) keep
    # Exudyn off the rigid reference by ~1e-6 m; 2e-5 m is 0.02 % of the 0.1 m lateral
    # motion, far below what a space-fixed force (0.1 m) or a frame at the centre of
    # mass instead of the u0 origin (metres) would give.
    np.testing.assert_allclose(r["rotation"], A_ref, atol=1e-5)
    np.testing.assert_allclose(r["position"], probe_ref, atol=2e-5)
    assert np.abs(r["elastic"]).max() < 2e-5
