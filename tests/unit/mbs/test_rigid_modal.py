"""SimpleRB and CoupledRB (report Sec. 3): rigid-body kernels, coupling terms, inertial loads.

Oracles: scipy's solve_ivp on the quaternion form of Euler's equations (an independent
formulation), analytic rotation under a constant torque about a principal axis and
projectile motion, node-by-node sums of report eq. 19, 22 and 25, and PureMA where
the coupling vanishes.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ffrmbs.errors import ModelError
from mbs.modal import CoupledRB, ModalBasis, PureMA, SimpleRB, StepLoads
from mbs.modal.coupled_rb import CouplingIntegrals
from mbs.bodies.rotations import quat_to_matrix
from preprocess import box, build_body, face_load
from validation.cases.cantilever import MATERIAL


@pytest.fixture(scope="module")
def free_beam():
    mesh = box(1.0, 0.6, 2.5, 0.5, order=1)
    data = build_body(mesh, MATERIAL, 6)
    return mesh, data, ModalBasis.from_body(data)


def quaternion_reference(basis, F_B, T_B, Om0, t_out, gravity=np.zeros(3)):
    """ρ, R, Ω by solve_ivp on (ρ, v, p, Ω) with ṗ = ½ p ⊗ (0, Ω), constant body loads."""
    I = basis.inertia
    m = basis.total_mass

    def rhs(t, y):
        p = y[6:10] / np.linalg.norm(y[6:10])
        Om = y[10:]
        R = quat_to_matrix(p)
        w0, w1, w2, w3 = 0.0, *Om
        p0, p1, p2, p3 = p
        pdot = 0.5 * np.array([p0 * w0 - p1 * w1 - p2 * w2 - p3 * w3, p0 * w1 + p1 * w0 + p2 * w3 - p3 * w2,
                               p0 * w2 - p1 * w3 + p2 * w0 + p3 * w1, p0 * w3 + p1 * w2 - p2 * w1 + p3 * w0])
        return np.concatenate([y[3:6], (R @ F_B) / m + gravity, pdot,
                               np.linalg.solve(I, T_B - np.cross(Om, I @ Om))])

    y0 = np.concatenate([basis.center_of_mass, np.zeros(3), [1.0, 0, 0, 0], Om0])
    sol = solve_ivp(rhs, (0.0, t_out[-1]), y0, t_eval=t_out, rtol=1e-12, atol=1e-14, method="DOP853")
    R = np.array([quat_to_matrix(p / np.linalg.norm(p)) for p in sol.y[6:10].T])
    return sol.y[:3].T, R, sol.y[10:].T


def body_loads(mesh, F_face, times=(0.0,)):
    """A force on face x1 (body frame), giving a resultant and a torque about the centre."""
    f = face_load(mesh, mesh.group("x1"), F_face)
    return StepLoads.from_nodal(list(times), np.stack([f] + [0.0 * f] * (len(times) - 1)))


def test_rkmk4_against_the_quaternion_reference_and_fourth_order(free_beam):
    mesh, data, basis = free_beam
    loads = body_loads(mesh, [30.0, 200.0, -80.0])
    Om0 = np.array([0.3, -0.2, 1.1])
    t = np.linspace(0.0, 4.0, 9)
    rho_ref, R_ref, Om_ref = quaternion_reference(basis, loads.resultants()[0], loads.moments(basis.b0)[0], Om0, t)
    errs = []
    for dt in (0.1, 0.05, 0.025):
        res = SimpleRB(basis, [loads], angular_velocity=Om0, dt=dt).solve(t)
        errs.append(max(np.abs(res.R - R_ref).max(), np.abs(res.Omega - Om_ref).max() / np.abs(Om_ref).max()))
    assert 12.0 < errs[0] / errs[1] < 20.0 and 12.0 < errs[1] / errs[2] < 20.0
    res = SimpleRB(basis, [loads], angular_velocity=Om0, dt=1e-3).solve(t)
    assert np.abs(res.R - R_ref).max() < 1e-10
    assert np.abs(res.rho - rho_ref).max() < 1e-10 * np.abs(rho_ref - rho_ref[0]).max()
    assert np.abs(res.R[-1].T @ res.R[-1] - np.eye(3)).max() < 1e-13


def test_report_scheme_converges_at_first_order(free_beam):
    mesh, data, basis = free_beam
    loads = body_loads(mesh, [0.0, 200.0, 0.0])
    Om0 = np.array([0.3, -0.2, 1.1])
    t = np.array([0.0, 2.0])
    _, R_ref, _ = quaternion_reference(basis, loads.resultants()[0], loads.moments(basis.b0)[0], Om0, t)
    errs = [np.abs(SimpleRB(basis, [loads], angular_velocity=Om0, dt=dt, scheme="report").solve(t).R[-1]
                   - R_ref[-1]).max() for dt in (4e-3, 2e-3, 1e-3)]
    assert 1.7 < errs[0] / errs[1] < 2.3 and 1.7 < errs[1] / errs[2] < 2.3


def symmetric_box_basis():
    """Eight equal masses at the corners of a 1 x 1 x 5 m box (principal axes x, y, z) with
    two arbitrary mass-orthonormal 'modes' (the rigid motion does not use them)."""
    u0 = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 5.0)])
    masses = np.full(8, 5000.0)
    P = np.zeros((8, 3, 2))
    P[[0, 1], 0, 0] = [1.0, -1.0]
    P[[2, 3], 1, 1] = [1.0, -1.0]
    P /= np.sqrt(2 * 5000.0)
    return ModalBasis(u0=u0, masses=masses, P=P, omega2=np.array([1e4, 2e4]), surface=np.arange(8),
                      clamped=False)


@pytest.mark.parametrize("scheme", ["report", "rkmk4"])
def test_constant_torque_about_a_principal_axis_is_exact(scheme):
    """θ = T t² / (2 I_xx) about the principal axis x: both schemes are exact here
    (constant α, Ω × ÎΩ = 0)."""
    basis = symmetric_box_basis()
    forces = np.zeros((8, 3))
    forces[basis.u0[:, 2] == 5.0, 1] = 25.0       # +y on the top corners, −y on the bottom ones
    forces[basis.u0[:, 2] == 0.0, 1] = -25.0
    loads = StepLoads.from_nodal([0.0], forces[None])
    T = loads.moments(basis.b0)[0]
    assert T[1] == 0.0 and T[2] == 0.0 and T[0] < 0
    t = np.linspace(0.0, 10.0, 6)
    res = SimpleRB(basis, [loads], dt=0.5, scheme=scheme).solve(t)
    np.testing.assert_allclose(res.rotation_vectors()[:, 0], T[0] * t ** 2 / (2 * basis.inertia[0, 0]),
                               rtol=1e-12, atol=1e-15)


def test_gravity_moves_the_centre_of_mass_only(free_beam):
    mesh, data, basis = free_beam
    g = np.array([0.0, 0.0, -9.81])
    v0 = np.array([1.0, 2.0, 3.0])
    t = np.linspace(0.0, 2.0, 5)
    res = SimpleRB(basis, gravity=g, velocity=v0, angular_velocity=[0.0, 0.0, 0.5]).solve(t)
    expected = basis.center_of_mass + np.outer(t, v0) + 0.5 * np.outer(t ** 2, g)
    np.testing.assert_allclose(res.rho, expected, rtol=1e-13, atol=1e-13)
    assert np.abs(res.r).max() == 0.0


def test_inertial_loads_equal_body_loads_when_they_agree(free_beam):
    """A body turned by R0 at rest: inertial-frame forces R0 f equal body-frame forces f at
    t = 0; with a force through the centre of mass (no rotation follows) both runs agree."""
    mesh, data, basis = free_beam
    R0 = quat_to_matrix(np.array([0.9, 0.3, -0.2, 0.1]) / np.linalg.norm([0.9, 0.3, -0.2, 0.1]))
    f = face_load(mesh, mesh.group("x1"), [50.0, 0.0, 0.0]) + face_load(mesh, mesh.group("x0"), [50.0, 0.0, 0.0])
    body = StepLoads.from_nodal([0.0, 0.01], np.stack([f, 0 * f]))
    inertial = StepLoads.from_nodal([0.0, 0.01], np.stack([f @ R0.T, 0 * f]), frame="inertial")
    t = np.linspace(0.0, 0.03, 7)
    a = SimpleRB(basis, [body], orientation=R0, dt=1e-3).solve(t)
    b = SimpleRB(basis, [inertial], orientation=R0, dt=1e-3).solve(t)
    assert np.abs(a.Omega).max() < 1e-12
    np.testing.assert_allclose(b.rho, a.rho, rtol=0, atol=1e-12 * np.abs(a.rho - a.rho[0]).max() + 1e-15)
    np.testing.assert_allclose(b.r, a.r, rtol=0, atol=1e-10 * np.abs(a.r).max())


def test_rotation_vector_at_pi():
    basis = symmetric_box_basis()
    t = np.array([0.0, 1.0])
    res = SimpleRB(basis, angular_velocity=[0.0, 0.0, np.pi], dt=0.01).solve(t)
    theta = res.rotation_vectors()[-1]
    np.testing.assert_allclose(np.abs(theta), [0.0, 0.0, np.pi], atol=1e-9)


def test_coupling_integrals_equal_node_by_node_sums(free_beam):
    """Pᵀ f_fict (eq. 22), Î(r) (eq. 25) and Σ m b × ḃ from the integrals vs per-node sums."""
    mesh, data, basis = free_beam
    rng = np.random.default_rng(3)
    r, rd = rng.normal(size=6) * 1e-2, rng.normal(size=6)
    alpha, Om = rng.normal(size=3), rng.normal(size=3)
    ci = CouplingIntegrals(basis)
    m, P = basis.masses, basis.P
    b = basis.b0 + P @ r
    bd = P @ rd
    f = np.array([-mi * np.cross(alpha, bi) - 2 * mi * np.cross(Om, bdi) - mi * np.cross(Om, np.cross(Om, bi))
                  for mi, bi, bdi in zip(m, b, bd)])
    F_ref = np.einsum("ia,ian->n", f, P)
    np.testing.assert_allclose(ci.fictitious(alpha, Om, r, rd), F_ref, rtol=1e-11, atol=1e-12 * np.abs(F_ref).max())
    I_ref = sum(mi * (bi @ bi * np.eye(3) - np.outer(bi, bi)) for mi, bi in zip(m, b))
    np.testing.assert_allclose(ci.inertia(r), I_ref, rtol=1e-12)
    h_ref = sum(mi * np.cross(bi, bdi) for mi, bi, bdi in zip(m, b, bd))
    np.testing.assert_allclose(ci.relative_angular_momentum(r, rd), h_ref, rtol=1e-10, atol=1e-12 * np.abs(h_ref).max())


def test_coupled_torque_uses_the_deformed_lever_arms(free_beam):
    """Eq. 19 with b = b0 + P r: the D matrices of CoupledRB against the per-node cross sum."""
    mesh, data, basis = free_beam
    loads = body_loads(mesh, [30.0, 200.0, -80.0])
    c = CoupledRB(basis, [loads])
    F, D = c._per_interval(np.array([0.0, 1e-3]))
    r = np.random.default_rng(4).normal(size=6) * 1e-3
    f_full = np.zeros((basis.n_nodes, 3))
    f_full[loads.nodes] = loads.forces[0]
    T_ref = np.cross(basis.b0 + basis.P @ r, f_full).sum(axis=0)
    np.testing.assert_allclose(loads.moments(basis.b0)[0] + D[0] @ r, T_ref, rtol=0,
                               atol=1e-12 * np.abs(T_ref).max())
    np.testing.assert_allclose(F[0], np.einsum("ia,ian->n", f_full, basis.P), rtol=1e-12)


def test_coupled_rb_without_rotation_reduces_to_pure_ma(free_beam):
    """A symmetric push through the centre of mass: no rotation, no fictitious forces, so
    CoupledRB's modes follow the exact PureMA recursion (B's translation does not load
    the elastic modes: Σ m_i φ_i = 0)."""
    mesh, data, basis = free_beam
    f = face_load(mesh, mesh.group("x0"), [80.0, 0.0, 0.0])
    loads = StepLoads.from_nodal([0.0, 2e-3], np.stack([f, 0.0 * f]))
    t = np.linspace(0.0, 5e-3, 11)
    coupled = CoupledRB(basis, [loads], dt=1e-4).solve(t)
    pure = PureMA(basis, [loads]).solve(t)
    assert np.abs(coupled.Omega).max() < 1e-9
    assert np.abs(coupled.r - pure.r).max() < 1e-6 * np.abs(pure.r).max()


def test_coupled_spin_energy_bounded_simple_exact():
    """Report Sec. 5.5.2, Fig. 11: spin about x without loads; SimpleRB keeps the energy
    exactly, CoupledRB's total varies by a small bounded amount."""
    mesh = box(1.0, 1.0, 5.0, 1.0, order=1)
    basis = ModalBasis.from_body(build_body(mesh, MATERIAL, 6))
    t = np.linspace(0.0, 0.2, 201)
    simple = SimpleRB(basis, angular_velocity=[1.0, 0.0, 0.0], dt=1e-3).solve(t).energies()["total"]
    coupled = CoupledRB(basis, angular_velocity=[1.0, 0.0, 0.0], dt=1e-4).solve(t).energies()
    assert np.ptp(simple) <= 1e-14 * simple[0]
    assert coupled["potential_vib"].max() > 0
    assert np.ptp(coupled["total"]) < 1e-6 * coupled["total"][0]


def test_rigid_solvers_reject_bad_bodies():
    mesh = box(1.0, 0.5, 2.0, 0.5, order=1)
    clamped = ModalBasis.from_body(build_body(mesh, MATERIAL, 3, clamp="z0"))
    with pytest.raises(ModelError, match="free body"):
        SimpleRB(clamped)
    with pytest.raises(ModelError, match="free body"):
        CoupledRB(clamped)
    free = ModalBasis.from_body(build_body(mesh, MATERIAL, 3))
    with pytest.raises(ModelError, match="scheme"):
        SimpleRB(free, scheme="euler")
