"""FE assembly against independent oracles: exact integrals, closed-form element
matrices, patch tests, analytic HRZ masses and beam theory."""

import math

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from preprocess import fe
from preprocess.mesh import canonical_mesh
from preprocess.modes import clamped_modes, rigid_body_modes


def exact_monomial(a, b, c):
    """∫ ξ^a η^b ζ^c over the reference tetrahedron = a! b! c! / (a+b+c+3)!."""
    return math.factorial(a) * math.factorial(b) * math.factorial(c) / math.factorial(a + b + c + 3)


@pytest.mark.parametrize("degree", [1, 2, 3, 4, 6])
def test_quadrature_exact_to_its_degree(degree):
    pts, w = fe.tet_quadrature(degree)
    for a in range(degree + 1):
        for b in range(degree + 1 - a):
            for c in range(degree + 1 - a - b):
                got = w @ (pts[:, 0] ** a * pts[:, 1] ** b * pts[:, 2] ** c)
                assert got == pytest.approx(exact_monomial(a, b, c), rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_shape_functions_interpolate_and_differentiate(order):
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    if order == 2:
        edges = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
        nodes = np.vstack([nodes, [(nodes[i] + nodes[j]) / 2 for i, j in edges]])
    N, _ = fe.shape_functions(order, nodes)
    np.testing.assert_allclose(N, np.eye(len(nodes)), atol=1e-14)
    rng = np.random.default_rng(0)
    p = rng.dirichlet(np.ones(4), size=5)[:, 1:]
    N, dN = fe.shape_functions(order, p)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
    h = 1e-6
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        fd = (fe.shape_functions(order, p + e)[0] - fe.shape_functions(order, p - e)[0]) / (2 * h)
        np.testing.assert_allclose(dN[:, :, k], fd, atol=1e-8)


def test_tet4_element_stiffness_equals_closed_form_BtDB():
    rng = np.random.default_rng(1)
    x = rng.random((4, 3))
    E, nu = 2.1e11, 0.3
    mesh = canonical_mesh(x, np.array([[0, 1, 2, 3]]), {}, "one-tet")
    K = fe.stiffness_matrix(mesh, E, nu).toarray()
    # closed form: gradients of barycentric coordinates from the inverse of [1 x]
    p = mesh.points
    C = np.linalg.inv(np.column_stack([np.ones(4), p]))  # rows: coefficients of L_a
    grads = C[1:].T  # (4, 3)
    V = abs(np.linalg.det(p[1:] - p[0])) / 6
    B = np.zeros((6, 12))
    for a, (gx, gy, gz) in enumerate(grads):
        B[:, 3 * a:3 * a + 3] = [[gx, 0, 0], [0, gy, 0], [0, 0, gz], [gy, gx, 0], [0, gz, gy], [gz, 0, gx]]
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[range(3), range(3)] += 2 * mu
    D[range(3, 6), range(3, 6)] = mu
    np.testing.assert_allclose(K, V * B.T @ D @ B, rtol=1e-12, atol=1e-12 * np.abs(K).max())


@pytest.mark.parametrize("mesh_name", ["small_box_tet4", "small_box_tet10"])
def test_stiffness_symmetric_rigid_free_and_passes_patch_test(mesh_name, request):
    mesh = request.getfixturevalue(mesh_name)
    K = fe.stiffness_matrix(mesh, 1e9, 0.25)
    assert abs(K - K.T).max() == 0.0
    R = rigid_body_modes(mesh.points, np.ones(mesh.n_nodes))
    assert np.abs(K @ R).max() < 1e-9 * abs(K).max()
    # patch test: a linear displacement field leaves interior nodes in equilibrium
    A = np.array([[1e-3, 2e-4, -1e-4], [3e-4, -2e-3, 5e-4], [0.0, 1e-4, 7e-4]])
    u = mesh.points @ A.T
    f = (K @ u.ravel()).reshape(-1, 3)
    interior = np.setdiff1d(np.arange(mesh.n_nodes), mesh.surface_nodes())
    assert len(interior) > 0
    assert np.abs(f[interior]).max() < 1e-8 * np.abs(f).max()


def test_tet10_hrz_masses_match_analytic_values():
    corners = np.array([[0, 0, 0], [2.0, 0, 0], [0, 1.0, 0], [0.3, 0.2, 1.5]])
    edges = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
    pts = np.vstack([corners, [(corners[i] + corners[j]) / 2 for i, j in edges]])
    mesh = canonical_mesh(pts, np.arange(10)[None], {}, "one-tet10")
    rho = 7800.0
    m = fe.lumped_masses(mesh, rho)
    V = abs(np.linalg.det(corners[1:] - corners[0])) / 6
    # consistent diagonal ρV/70 (corners), 8ρV/105 (mid-edge); HRZ scales it to total ρV
    np.testing.assert_allclose(m[:4], rho * V / 36, rtol=1e-12)
    np.testing.assert_allclose(m[4:], 4 * rho * V / 27, rtol=1e-12)


@pytest.mark.parametrize("mesh_name", ["small_box_tet4", "small_box_tet10"])
def test_lumped_masses_positive_and_sum_to_rho_V(mesh_name, request):
    mesh = request.getfixturevalue(mesh_name)
    m = fe.lumped_masses(mesh, 2700.0)
    assert np.all(m > 0)
    assert m.sum() == pytest.approx(2700.0 * 1.0 * 0.5 * 2.0, rel=1e-12)


def test_face_load_sums_to_total(report_beam):
    f = fe.face_load(report_beam, report_beam.group("z1"), [1.0, -2.0, 3.0])
    np.testing.assert_allclose(f.sum(axis=0), [1.0, -2.0, 3.0], rtol=1e-13)
    outside = np.setdiff1d(np.arange(report_beam.n_nodes), report_beam.group("z1"))
    assert np.all(f[outside] == 0)


def test_bad_material_is_a_clear_error(small_box_tet4):
    from ffrmbs.errors import ModelError

    with pytest.raises(ModelError, match="Poisson"):
        fe.stiffness_matrix(small_box_tet4, 1e9, 0.5)
    with pytest.raises(ModelError, match="density"):
        fe.lumped_masses(small_box_tet4, -1.0)


# --- the report's cantilever against beam theory (report Sec. 5.7.1) ----------------

E, RHO, L = 200e9, 8000.0, 5.0
EULER_BERNOULLI_OMEGA1 = 1.8751040687 ** 2 * math.sqrt(E / 12 / (RHO * L ** 4))  # 203.0 rad/s


def _cantilever(mesh):
    K = fe.stiffness_matrix(mesh, E, 0.0)
    m = fe.lumped_masses(mesh, RHO)
    clamp = mesh.group("z0")
    omega = np.sqrt(clamped_modes(K, m, 1, clamp)[0][0])
    free = np.ones(3 * mesh.n_nodes, dtype=bool)
    free[(3 * clamp[:, None] + np.arange(3)).ravel()] = False
    f = fe.face_load(mesh, mesh.group("z1"), [0.0, 500.0, 0.0]).ravel()
    u = np.zeros_like(f)
    u[free] = sla.spsolve(K[free][:, free].tocsc(), f[free])
    return omega, u.reshape(-1, 3)[mesh.group("z1"), 1].mean()


def test_cantilever_frequency_and_deflection_against_beam_theory(report_beam):
    from preprocess.geometry import box

    omegas = []
    for h in (0.5, 0.35, 0.25):
        mesh = report_beam if h == 0.5 else box(1, 1, 5, h)
        omega, tip = _cantilever(mesh)
        omegas.append(omega)
        assert abs(omega / EULER_BERNOULLI_OMEGA1 - 1) < 0.08
        if h == 0.5:
            # Euler-Bernoulli P L^3 / (3 E I) = 1.25e-6 m (report Sec. 5.7.1)
            assert abs(tip / 1.25e-6 - 1) < 0.05
            # Timoshenko adds P L / (κ G A) with κ = 5/6, G = E/2 (ν = 0): 1.28e-6 m
            assert abs(tip / (1.25e-6 + 500 * 5 / (5 / 6 * E / 2)) - 1) < 0.01
    # converging: successive changes shrink under refinement
    assert abs(omegas[2] - omegas[1]) < abs(omegas[1] - omegas[0])
