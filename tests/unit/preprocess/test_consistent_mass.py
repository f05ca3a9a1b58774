"""Consistent mass: the matrix, the modes, the shape integrals, the body file and the CLI,
against analytic values and brute-force sums."""

import subprocess
import sys

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from ffrmbs.errors import InputFileError, ModelError
from mbs import FlexibleBodyFFR
from mbs.bodies.shape_integrals import ShapeIntegrals
from preprocess import Material, box, build_body, fe, modes, read_body
from preprocess.body import mass_times
from preprocess.hdf5file import read_hdf5, write_hdf5
from preprocess.mesh import Mesh
from preprocess.textfiles import TEXT_FILES, write_text_body
from validation.beam_theory import (euler_bernoulli_cantilever_frequencies, rect_shear_coefficient,
                                    timoshenko_cantilever_frequencies)

RHO = 7850.0
STEEL = Material(RHO, 210e9, 0.3)
LX, LY, LZ = 0.1, 0.2, 0.5


@pytest.fixture(scope="module")
def tet10_box():
    return box(LX, LY, LZ, 0.1, order=2)


@pytest.fixture(scope="module")
def tet4_box():
    return box(LX, LY, LZ, None, order=1, divisions=(2, 3, 5))


@pytest.fixture(scope="module")
def consistent_body():
    return build_body(box(LX, LY, LZ, None, order=2, divisions=(1, 2, 4)), STEEL, 4, clamp="z0", mass="consistent")


def brute_force_inertia(M, x):
    """(m, c, J about c) from a dense M_s by explicit double sums over node pairs."""
    M = M.toarray()
    n = len(x)
    m = sum(M[a, b] for a in range(n) for b in range(n))
    c = sum(M[a, b] * x[b] for a in range(n) for b in range(n)) / m
    r = x - c
    U = sum(M[a, b] * np.outer(r[a], r[b]) for a in range(n) for b in range(n))
    return m, c, np.trace(U) * np.eye(3) - U


@pytest.mark.parametrize("mesh_name", ["tet10_box", "tet4_box"])
def test_consistent_mass_gives_the_exact_inertia_of_a_box(mesh_name, request):
    mesh = request.getfixturevalue(mesh_name)
    M = fe.consistent_mass_matrix(mesh, RHO)
    m0 = RHO * LX * LY * LZ
    J0 = m0 / 12 * np.diag([LY ** 2 + LZ ** 2, LX ** 2 + LZ ** 2, LX ** 2 + LY ** 2])
    if mesh.n_nodes < 200:
        m, c, J = brute_force_inertia(M, mesh.points)
    else:
        w = M @ np.ones(mesh.n_nodes)
        m, c = w.sum(), w @ mesh.points / w.sum()
        r = mesh.points - c
        U = (M @ r).T @ r
        J = np.trace(U) * np.eye(3) - U
    assert abs(M - M.T).max() == 0.0
    assert m == pytest.approx(m0, rel=1e-13)
    np.testing.assert_allclose(c, [LX / 2, LY / 2, LZ / 2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(J, J0, rtol=0, atol=1e-13 * np.abs(J0).max())


def test_row_sums_are_the_tet4_lumped_masses(tet4_box):
    M = fe.consistent_mass_matrix(tet4_box, RHO)
    np.testing.assert_allclose(M @ np.ones(tet4_box.n_nodes), fe.lumped_masses(tet4_box, RHO), rtol=1e-14)


def test_one_tet4_element_matrix_is_rho_v_over_20_times_one_plus_delta():
    pts = np.array([[0.0, 0, 0], [2, 0, 0], [0, 3, 0], [0, 0, 4]])       # V = 2·3·4/6 = 4
    mesh = Mesh(points=pts, tets=np.array([[0, 1, 2, 3]]), node_groups={}, source="one tet")
    M = fe.consistent_mass_matrix(mesh, 5.0).toarray()
    np.testing.assert_allclose(M, 5.0 * 4.0 / 20 * (np.ones((4, 4)) + np.eye(4)), rtol=1e-14)


def test_consistent_modes_are_mass_orthonormal_and_solvers_agree(tet4_box):
    K = fe.stiffness_matrix(tet4_box, 210e9, 0.3)
    M = fe.consistent_mass_matrix(tet4_box, RHO)
    M3 = sp.kron(M, sp.identity(3)).toarray()
    clamped = tet4_box.group("z0")
    w2, phi = modes.clamped_modes(K, M, 4, clamped)
    np.testing.assert_allclose(phi.T @ M3 @ phi, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(phi.T @ K @ phi, np.diag(w2), rtol=1e-9, atol=1e-9 * w2.max())
    w2_all, _ = modes.all_modes(K, M, clamped)
    np.testing.assert_allclose(w2, w2_all[:4], rtol=1e-9)
    w2_free, phi_free = modes.free_modes(K, M, tet4_box.points, 4)
    R = modes.rigid_body_modes(tet4_box.points, M)
    np.testing.assert_allclose(R.T @ M3 @ R, np.eye(6), atol=1e-12)
    np.testing.assert_allclose(R.T @ M3 @ phi_free, 0.0, atol=1e-10)
    np.testing.assert_allclose(phi_free.T @ M3 @ phi_free, np.eye(4), atol=1e-12)
    w2_free_all, phi_all = modes.all_modes(K, M, None, tet4_box.points)
    np.testing.assert_allclose(w2_free, w2_free_all[:4], rtol=1e-9)
    np.testing.assert_allclose(phi_all.T @ M3 @ phi_all, np.eye(phi_all.shape[1]), atol=1e-10)


def test_slender_beam_frequency_consistent_above_and_lumped_below_beam_theory():
    """A clamped 0.4 x 0.02 x 0.02 m tet10 beam (ν = 0, 10 elements along): the consistent-mass
    frequency is a Rayleigh–Ritz upper bound, above Timoshenko's (which is below
    Euler–Bernoulli's by shear and rotary inertia); the lumped one falls below it. Both
    lie within 0.3 % of either theory."""
    L, a, E = 0.4, 0.02, 210e9
    mesh = box(L, a, a, None, order=2, divisions=(10, 1, 1))
    w = {mass: build_body(mesh, Material(RHO, E, 0.0), 1, clamp="x0", mass=mass).frequencies()[0][0]
         for mass in ("lumped", "consistent")}
    I, A = a ** 4 / 12, a * a
    eb = euler_bernoulli_cantilever_frequencies(E, I, RHO, A, L, 1)[0]
    timo = timoshenko_cantilever_frequencies(E, E / 2, rect_shear_coefficient(0.0), I, RHO, A, L, 1)[0]
    assert w["lumped"] < timo < w["consistent"] < eb
    for value in w.values():
        assert abs(value / eb - 1) < 3e-3 and abs(value / timo - 1) < 3e-3


def test_from_mass_matrix_of_a_diagonal_equals_from_nodes():
    rng = np.random.default_rng(3)
    u0, phi, m = rng.standard_normal((12, 3)), rng.standard_normal((36, 4)), rng.uniform(1, 2, 12)
    a = ShapeIntegrals.from_nodes(u0, phi, m)
    b = ShapeIntegrals.from_mass_matrix(u0, phi, sp.diags(m).tocsr())
    for name in ("mass", "I1", "S_bar", "I_kl", "I_bar", "S_kl", "M_ff", "S_skew"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-13, atol=1e-13, err_msg=name)


def test_from_mass_matrix_equals_the_double_sums():
    """Eq. C1 of mbs.bodies.shape_integrals by explicit loops over node pairs, M_s dense symmetric."""
    rng = np.random.default_rng(4)
    n, nf = 6, 2
    u0, phi = rng.standard_normal((n, 3)), rng.standard_normal((3 * n, nf))
    B = rng.standard_normal((n, n))
    M = B @ B.T + n * np.eye(n)
    si = ShapeIntegrals.from_mass_matrix(u0, phi, sp.csr_matrix(M))
    P = phi.reshape(n, 3, nf)
    pairs = [(a, b) for a in range(n) for b in range(n)]
    assert si.mass == pytest.approx(M.sum(), rel=1e-14)
    np.testing.assert_allclose(si.I1, sum(M[a, b] * u0[b] for a, b in pairs), rtol=1e-12)
    np.testing.assert_allclose(si.S_bar, sum(M[a, b] * P[b] for a, b in pairs), rtol=1e-12)
    np.testing.assert_allclose(si.I_kl, sum(M[a, b] * np.outer(u0[a], u0[b]) for a, b in pairs), rtol=1e-12)
    np.testing.assert_allclose(si.I_bar, sum(M[a, b] * np.einsum("k,lf->klf", u0[a], P[b]) for a, b in pairs),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(si.S_kl, sum(M[a, b] * np.einsum("kf,lg->klfg", P[a], P[b]) for a, b in pairs),
                               rtol=1e-12, atol=1e-12)


def test_body_data_and_ffr_body_use_the_consistent_mass(consistent_body):
    data = consistent_body
    M = data.mass_matrix
    assert data.params["mass"] == "consistent"
    m0 = RHO * LX * LY * LZ
    assert data.total_mass == pytest.approx(m0, rel=1e-13)
    np.testing.assert_allclose(data.center_of_mass, [LX / 2, LY / 2, LZ / 2], atol=1e-15)
    np.testing.assert_allclose(data.phi.T @ mass_times(M, data.phi), np.eye(4), atol=1e-12)
    data_no_eig = type(data)(**{**data.__dict__, "eigenvalues": None})
    np.testing.assert_allclose(data_no_eig.modal_eigenvalues(), data.eigenvalues, rtol=1e-9)
    si = FlexibleBodyFFR(data).integrals
    assert si.mass == pytest.approx(m0, rel=1e-13)
    np.testing.assert_allclose(si.M_ff, np.eye(4), atol=1e-12)            # Φᵀ M Φ = I, eq. 2.69
    np.testing.assert_allclose(si.I_kl[0, 0], m0 * LX ** 2 / 3, rtol=1e-13)  # ∫ρx² dV


def test_build_body_refuses_an_unknown_mass(tet4_box):
    with pytest.raises(ModelError, match="mass must be 'lumped' or 'consistent', not 'diagonal'"):
        build_body(tet4_box, STEEL, 2, clamp="z0", mass="diagonal")


def test_hdf5_round_trip_keeps_the_mass_matrix(consistent_body, tmp_path):
    path = tmp_path / "body.h5"
    write_hdf5(path, consistent_body)
    back = read_hdf5(path)
    assert (back.mass_matrix != consistent_body.mass_matrix).nnz == 0
    np.testing.assert_array_equal(back.phi, consistent_body.phi)
    assert back.params["mass"] == "consistent"


def _damaged(path, edit):
    with h5py.File(path, "r+") as f:
        edit(f)


@pytest.mark.parametrize("fault, edit", [
    ("attribute shape", lambda f: f["mass_matrix"].attrs.__setitem__("shape", np.array([2, 2]))),
    ("NaN or inf", lambda f: f["mass_matrix/data"].__setitem__(0, np.nan)),
    ("not a valid CSR matrix", lambda f: f["mass_matrix/indices"].__setitem__(0, 10 ** 6)),
    ("not symmetric", lambda f: f["mass_matrix/data"].__setitem__(1, 2 * f["mass_matrix/data"][1] + 1.0)),
    ("non-positive diagonal", lambda f: f["mass_matrix/data"].__setitem__(0, -f["mass_matrix/data"][0])),
    ("missing dataset 'mass_matrix/indptr'", lambda f: f.__delitem__("mass_matrix/indptr")),
])
def test_hdf5_reader_names_each_mass_matrix_fault(consistent_body, tmp_path, fault, edit):
    path = tmp_path / "body.h5"
    write_hdf5(path, consistent_body)
    _damaged(path, edit)
    with pytest.raises(InputFileError, match="mass_matrix") as err:
        read_hdf5(path)
    assert fault in str(err.value)
    assert "\n" not in str(err.value)


def test_text_files_refuse_a_consistent_mass_body(consistent_body, tmp_path):
    with pytest.raises(ModelError, match="consistent mass matrix cannot be written as text files"):
        write_text_body(tmp_path, consistent_body)
    assert not any((tmp_path / name).exists() for name in TEXT_FILES)


def test_cli_mass_consistent_writes_a_body_file_with_the_mass_matrix(tmp_path):
    res = subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", "preprocess", "box:0.1,0.2,0.5", "--structured",
                          "1,1,2", "--order", "1", "--modes", "2", "--clamp", "z0", "--density", "1000",
                          "--young", "1e9", "--poisson", "0.3", "--mass", "consistent", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    body = read_body(tmp_path)
    assert body.mass_matrix is not None and body.params["mass"] == "consistent"
    assert body.total_mass == pytest.approx(1000 * 0.01, rel=1e-13)
    assert not any((tmp_path / name).exists() for name in TEXT_FILES)


def test_ffr_inertia_case_blocks_are_the_stepped_beam():
    """The validation case's exact stepped-beam inertia (two blocks) against the mesh: equal
    volume, and the consistent-mass inertia of the mesh equal to the blocks' to rounding."""
    from preprocess import stepped_beam
    from validation.cases.ffr_inertia import exact_blocks, fe_inertia, stepped_beam_blocks

    mesh = stepped_beam(10.0, order=1).scaled(1e-3)
    blocks = stepped_beam_blocks()
    assert mesh.element_volumes().sum() == pytest.approx(sum(np.prod(hi - lo) for lo, hi in blocks), rel=1e-12)
    m0, c0, J0 = exact_blocks(blocks, RHO)
    m, c, J = fe_inertia(mesh, RHO, "consistent")
    assert m == pytest.approx(m0, rel=1e-12)
    np.testing.assert_allclose(c, c0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(J, J0, rtol=0, atol=1e-12 * np.abs(J0).max())


def test_inertia_relief_with_consistent_mass_is_the_elastic_modal_flexibility(tet4_box):
    """Free body: the bordered solve (eq. R3 of preprocess.residual, M R with the consistent
    M) equals Σ_elastic φ φᵀ f / ω² over ALL elastic modes of a dense eigensolve."""
    from preprocess.residual import StaticFlexibility

    K = fe.stiffness_matrix(tet4_box, 210e9, 0.3)
    M = fe.consistent_mass_matrix(tet4_box, RHO)
    w2, phi = modes.all_modes(K, M, None, tet4_box.points)
    f = np.random.default_rng(5).standard_normal((K.shape[0], 2))
    u = StaticFlexibility(K, M, tet4_box.points).solve(f)
    expected = phi @ ((phi.T @ f) / w2[:, None])
    np.testing.assert_allclose(u, expected, rtol=0, atol=1e-8 * np.abs(expected).max())


def test_modal_basis_and_decision_use_the_consistent_mass():
    """ModalBasis of a free consistent-mass box: exact rigid inertia, Pᵀ M (P r) = r,
    CoupledRB's B0 = Σ_ab M_ab b_a b_bᵀ, and the α response of free modes vanishes
    (inertia relief, mbs.modal.decision docstring) only with the consistent loads."""
    from mbs.modal import ModalBasis
    from mbs.modal.coupled_rb import CouplingIntegrals
    from mbs.modal.decision import alpha_response

    data = build_body(box(LX, LY, LZ, None, order=2, divisions=(1, 2, 4)), STEEL, 4, clamp=None,
                      mass="consistent")
    basis = ModalBasis.from_body(data)
    m0 = RHO * LX * LY * LZ
    J0 = m0 / 12 * np.diag([LY ** 2 + LZ ** 2, LX ** 2 + LZ ** 2, LX ** 2 + LY ** 2])
    np.testing.assert_allclose(basis.inertia, J0, rtol=0, atol=1e-13 * J0.max())
    r = np.array([1.0, -2.0, 0.5, 3.0])
    np.testing.assert_allclose(basis.project_field(basis.P @ r), r, rtol=1e-12)
    B0 = J0.trace() / 2 * np.eye(3) - J0                 # Σ M b bᵀ from J = tr(B) 1 − B
    np.testing.assert_allclose(CouplingIntegrals(basis).B0, B0, rtol=0, atol=1e-13 * J0.max())
    phi = basis.P.reshape(-1, 4)
    consistent = alpha_response(basis.b0, data.mass_matrix, phi, basis.omega2)
    lumped = alpha_response(basis.b0, data.masses, phi, basis.omega2)
    assert np.abs(consistent).max() < 1e-10 * np.abs(lumped).max()
