"""Mode shapes: mass normalization, clamped rows, no rigid motion in free-free modes,
eigenvalues against a dense generalized eigensolver."""

import os

import numpy as np
import pytest
import scipy.linalg as la

from ffrmbs.errors import ModelError
from preprocess import fe
from preprocess.geometry import box
from preprocess.modes import clamped_modes, free_modes


@pytest.fixture(scope="module")
def beam():
    """A 0.4 x 0.3 x 1.2 m tet10 beam, structured 3 x 2 x 8 (595 nodes, 1785 dof): small
    enough for the dense oracle, with 35 clamped nodes on z = 0."""
    mesh = box(0.4, 0.3, 1.2, None, order=2, divisions=(3, 2, 8))
    return mesh, fe.stiffness_matrix(mesh, 70e9, 0.33), fe.lumped_masses(mesh, 2700.0)


def dense_eigenvalues(K, m, count):
    """The ``count`` lowest eigenvalues of K x = w2 diag(m) x by LAPACK's dense solver."""
    return la.eigh(K, np.diag(m), eigvals_only=True, subset_by_index=[0, count - 1])


def test_clamped_modes_normalized_and_zero_at_clamp(beam):
    mesh, K, m = beam
    clamp = mesh.group("z0")
    w2, phi = clamped_modes(K, m, 8, clamp)
    m3 = np.repeat(m, 3)
    np.testing.assert_allclose(phi.T @ (m3[:, None] * phi), np.eye(8), atol=1e-10)
    np.testing.assert_allclose(phi.T @ (K @ phi), np.diag(w2), atol=1e-8 * w2.max())
    assert np.all(phi.reshape(-1, 3, 8)[clamp] == 0.0)
    free = np.ones(3 * mesh.n_nodes, dtype=bool)
    free[(3 * clamp[:, None] + np.arange(3)).ravel()] = False
    ref = dense_eigenvalues(K[free][:, free].toarray(), m3[free], 8)
    np.testing.assert_allclose(w2, ref, rtol=1e-9)


def test_free_modes_carry_no_rigid_motion(beam):
    mesh, K, m = beam
    w2, phi = free_modes(K, m, mesh.points, 10)
    m3 = np.repeat(m, 3)
    np.testing.assert_allclose(phi.T @ (m3[:, None] * phi), np.eye(10), atol=1e-10)
    ref = dense_eigenvalues(K.toarray(), m3, 16)
    np.testing.assert_allclose(w2, ref[6:16], rtol=1e-9)  # six rigid-body modes removed
    P = phi.reshape(-1, 3, 10)
    c = m @ mesh.points / m.sum()
    scale = np.einsum("j,jkn->n", m, np.abs(P)) * np.abs(mesh.points - c).max()
    momentum = np.einsum("j,jkn->kn", m, P)
    angular = np.einsum("j,jkn->kn", m, np.cross((mesh.points - c)[:, :, None], P, axisa=1, axisb=1, axisc=1))
    assert np.abs(momentum).max() < 1e-8 * scale.min()
    assert np.abs(angular).max() < 1e-8 * scale.min()


def test_disconnected_body_is_reported():
    a = box(1, 1, 1, 0.6, order=1)
    pts = np.vstack([a.points, a.points + [3.0, 0, 0]])
    tets = np.vstack([a.tets, a.tets + a.n_nodes])
    from preprocess.mesh import canonical_mesh

    mesh = canonical_mesh(pts, tets, {}, "two boxes")
    with pytest.raises(ModelError, match="rigid-body modes"):
        free_modes(fe.stiffness_matrix(mesh, 1e9, 0.3), fe.lumped_masses(mesh, 1000.0), mesh.points, 4)


def test_too_many_modes_and_empty_clamp_are_errors(beam):
    mesh, K, m = beam
    with pytest.raises(ModelError):
        clamped_modes(K, m, 3, np.array([], dtype=int))
    with pytest.raises(ModelError):
        free_modes(K, m, mesh.points, 3 * mesh.n_nodes)


def test_modes_are_bitwise_repeatable(beam):
    """The same mesh gives the same modes to the last bit, whatever ran before (ARPACK's
    own start vector depends on its earlier calls)."""
    mesh, K, m = beam
    first = clamped_modes(K, m, 6, mesh.group("z0")), free_modes(K, m, mesh.points, 6)
    second = clamped_modes(K, m, 6, mesh.group("z0")), free_modes(K, m, mesh.points, 6)
    for (w_a, phi_a), (w_b, phi_b) in zip(first, second):
        assert w_a.tobytes() == w_b.tobytes() and phi_a.tobytes() == phi_b.tobytes()


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: BLAS has one thread anyway")
def test_shift_invert_runs_on_one_blas_thread(beam, monkeypatch):
    """The default beam's 40 modes cost 10.6 CPU s on two BLAS threads of a loaded two-core
    machine and 5.8 s on one: the Lanczos iteration runs with one BLAS thread."""
    import scipy.sparse.linalg as sla
    from threadpoolctl import threadpool_info

    threads = []
    eigsh = sla.eigsh

    def counting(*args, **kwargs):
        threads.extend(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
        return eigsh(*args, **kwargs)

    monkeypatch.setattr(sla, "eigsh", counting)
    mesh, K, m = beam
    clamped_modes(K, m, 4, mesh.group("z0"))
    assert threads and set(threads) == {1}
