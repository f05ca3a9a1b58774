"""Node matrix O from node groups (thesis Sec. 3.2.2, eq. 3.24) and the structured box mesh."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from contours.node_grid import check_node_matrix, node_line, node_matrix
from ffrmbs.errors import ModelError
from preprocess.geometry import box

L, H, W = 0.25, 0.05, 0.05


@pytest.fixture(scope="module")
def sbox1():
    return box(L, H, W, None, order=1, divisions=(10, 2, 2))


@pytest.fixture(scope="module")
def sbox2():
    return box(L, H, W, None, order=2, divisions=(10, 2, 2))


def tilted_grid(n_eta, n_xi, h_eta, h_xi, seed, noise=1e-9):
    """Points of a rectangular grid in a randomly rotated, shifted plane; returns (points, rotation, origin)."""
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(n_eta), np.arange(n_xi), indexing="ij")
    local = np.column_stack([i.ravel() * h_eta, j.ravel() * h_xi, np.zeros(i.size)])
    R = Rotation.random(random_state=seed).as_matrix()
    origin = rng.normal(size=3)
    pts = local @ R.T + origin + noise * rng.normal(size=local.shape)
    return pts, R, origin


def assert_is_grid(O, pts, h_eta, h_xi, tol=1e-7):
    """Consecutive entries are neighbours at the known spacings, rows straight and orthogonal."""
    d_eta = pts[O[1:, :]] - pts[O[:-1, :]]  # steps along eta
    d_xi = pts[O[:, 1:]] - pts[O[:, :-1]]  # steps along xi
    np.testing.assert_allclose(np.linalg.norm(d_eta, axis=2), h_eta, atol=tol)
    np.testing.assert_allclose(np.linalg.norm(d_xi, axis=2), h_xi, atol=tol)
    # all steps along one direction are the same vector (straight, parallel lines)
    np.testing.assert_allclose(d_eta, np.broadcast_to(d_eta[0, 0], d_eta.shape), atol=tol)
    np.testing.assert_allclose(d_xi, np.broadcast_to(d_xi[0, 0], d_xi.shape), atol=tol)
    assert abs(d_eta[0, 0] @ d_xi[0, 0]) < tol


@pytest.mark.parametrize("shape, spacing, seed", [((7, 4), (0.1, 0.1), 1), ((5, 9), (0.3, 0.05), 2),
                                                   ((6, 6), (0.2, 0.2), 3), ((3, 12), (0.02, 0.01), 4)])
def test_synthetic_tilted_grid_is_recovered(shape, spacing, seed):
    pts, R, _ = tilted_grid(*shape, *spacing, seed)
    perm = np.random.default_rng(seed + 10).permutation(len(pts))
    pts = pts[perm]
    O = node_matrix(pts, np.arange(len(pts)))
    assert sorted(O.ravel().tolist()) == list(range(len(pts)))
    # eta runs along the longer side: its extent is >= the xi extent
    ext = [(n - 1) * h for n, h in zip(shape, spacing)]
    long_first = ext[0] >= ext[1]
    assert O.shape == (shape if long_first else shape[::-1])
    h_eta, h_xi = spacing if long_first else spacing[::-1]
    assert_is_grid(O, pts, h_eta, h_xi)
    # documented convention: each axis signed so its dominant global component is positive
    for t in (pts[O[-1, 0]] - pts[O[0, 0]], pts[O[0, -1]] - pts[O[0, 0]]):
        assert t[np.argmax(np.abs(t))] > 0


def test_result_does_not_depend_on_node_order():
    pts, _, _ = tilted_grid(6, 4, 0.1, 0.07, 7, noise=0.0)
    O = node_matrix(pts, np.arange(len(pts)))
    perm = np.random.default_rng(0).permutation(len(pts))
    O2 = node_matrix(pts, perm)
    np.testing.assert_array_equal(O, O2)


@pytest.mark.parametrize("order, shape", [(1, (11, 3)), (2, (21, 5))])
def test_structured_box_face_y1(order, shape, sbox1, sbox2):
    m = sbox1 if order == 1 else sbox2
    nx, nz = shape
    face = m.group("y1")
    assert len(face) == nx * nz
    O = node_matrix(m.points, face)
    assert O.shape == shape
    p = m.points[O]
    np.testing.assert_allclose(p[..., 1], H, atol=1e-12)
    # rows along x at constant z, equally spaced, increasing; columns along z
    np.testing.assert_allclose(p[..., 0], np.linspace(0, L, nx)[:, None] * np.ones(nz), atol=1e-12)
    np.testing.assert_allclose(p[..., 2], np.ones(nx)[:, None] * np.linspace(0, W, nz), atol=1e-12)


def test_structured_box_is_structured_everywhere(sbox1, sbox2):
    assert (sbox1.n_nodes, sbox1.n_elements, sbox1.tets.shape[1]) == (11 * 3 * 3, 10 * 2 * 2 * 6, 4)
    assert (sbox2.n_nodes, sbox2.tets.shape[1]) == (21 * 5 * 5, 10)
    assert sbox1.element_volumes().sum() == pytest.approx(L * H * W, rel=1e-12)
    for name, (a, b) in {"x0": (3, 3), "x1": (3, 3), "z0": (11, 3), "z1": (11, 3), "y0": (11, 3)}.items():
        assert node_matrix(sbox1.points, sbox1.group(name)).shape == (a, b)
    for k, n in enumerate((11, 3, 3)):
        levels = np.unique(np.round(sbox1.points[:, k] / (1e-9), 0))
        assert len(levels) == n


@pytest.mark.parametrize("divisions", [(0, 2, 2), (2.5, 2, 2), (2, 2), "abc", (True, 2, 2), 3])
def test_bad_divisions(divisions):
    with pytest.raises(ModelError, match="divisions"):
        box(1, 1, 1, None, order=1, divisions=divisions)


def test_extra_rows_extend_where_the_grid_goes_on():
    n_eta, n_xi, h = 9, 7, 0.1
    pts, _, _ = tilted_grid(n_eta, n_xi, h, h, 11, noise=1e-10)
    # plus some off-plane points that must never be picked
    rng = np.random.default_rng(5)
    off = pts[rng.choice(len(pts), 10)] + 0.05 * rng.normal(size=(10, 3))
    allp = np.vstack([pts, off])
    ij = np.array(np.unravel_index(np.arange(len(pts)), (n_eta, n_xi))).T

    def patch(i0, i1, j0, j1):
        return np.flatnonzero((ij[:, 0] >= i0) & (ij[:, 0] < i1) & (ij[:, 1] >= j0) & (ij[:, 1] < j1))

    def cell_block(O):
        return ij[O.ravel()].reshape(*O.shape, 2)

    # interior patch rows 2..5 (4), cols 1..4 (4), extended by 1 each side -> 6 x 6
    sub = patch(2, 6, 1, 5)
    O0 = node_matrix(allp, sub)
    O1 = node_matrix(allp, sub, extra_rows=1)
    assert O0.shape == (4, 4) and O1.shape == (6, 6)
    np.testing.assert_array_equal(O1[1:-1, 1:-1], O0)
    c = cell_block(O1)
    assert sorted(set(c[..., 0].ravel())) == list(range(1, 7))
    assert sorted(set(c[..., 1].ravel())) == list(range(0, 6))
    assert_is_grid(O1, allp, h, h)
    # two rows asked: stops at the grid's boundary on the xi-low side (only one column there)
    O2 = node_matrix(allp, sub, extra_rows=2)
    c = cell_block(O2)
    assert sorted(O2.shape) == [7, 8]
    assert sorted(set(c[..., 0].ravel())) == list(range(0, 8))
    assert sorted(set(c[..., 1].ravel())) == list(range(0, 7))
    assert_is_grid(O2, allp, h, h)
    # a patch touching the boundary: no extension past the grid
    edge = patch(0, 4, 0, 3)
    O3 = node_matrix(allp, edge, extra_rows=3)
    c = cell_block(O3)
    assert sorted(set(c[..., 0].ravel())) == list(range(0, 7))
    assert sorted(set(c[..., 1].ravel())) == list(range(0, 6))
    # candidates restrict the extension: none given -> unchanged
    np.testing.assert_array_equal(node_matrix(allp, sub, extra_rows=2, candidates=sub), O0)


def test_extra_rows_on_the_box_face_stop_at_incomplete_rows(sbox1):
    # the face y1 of the structured box continues around the edges onto x0/x1/z0/z1,
    # which are not in its plane: nothing to add
    face = sbox1.group("y1")
    np.testing.assert_array_equal(node_matrix(sbox1.points, face, extra_rows=2), node_matrix(sbox1.points, face))
    # a part of the face: rows x in [0.05, 0.15] extend by one row each side in x
    p = sbox1.points
    part = face[(p[face, 0] > 0.049) & (p[face, 0] < 0.151)]
    O = node_matrix(p, part, extra_rows=1)
    assert O.shape == (7, 3)
    np.testing.assert_allclose(p[O[:, 0], 0], np.linspace(0.025, 0.175, 7), atol=1e-12)


def test_non_planar_patch_is_rejected():
    pts, _, _ = tilted_grid(5, 5, 0.1, 0.1, 3, noise=0.0)
    pts[12] += np.cross(pts[1] - pts[0], pts[5] - pts[0])  # the centre node 0.01 m out of the plane
    with pytest.raises(ModelError, match="not planar"):
        node_matrix(pts, np.arange(len(pts)))


def test_unstructured_face_is_rejected():
    m = box(L, H, W, 0.0125, order=1)
    with pytest.raises(ModelError, match=r"not a structured grid.*distinct levels.*pass the node matrix O"):
        node_matrix(m.points, m.group("y1"))


def test_node_line_along_the_box_axis(sbox1, sbox2):
    idx = node_line(sbox1.points, [0.0, H / 2, W / 2], [1.0, 0.0, 0.0])
    assert len(idx) == 11
    p = sbox1.points[idx]
    np.testing.assert_allclose(p[:, 0], np.linspace(0, L, 11), atol=1e-12)
    np.testing.assert_allclose(p[:, 1:], np.tile([H / 2, W / 2], (11, 1)), atol=1e-12)
    # opposite direction: reversed order; order-2 mesh: mid-edge nodes too
    np.testing.assert_array_equal(node_line(sbox1.points, [L, H / 2, W / 2], [-2.0, 0, 0]), idx[::-1])
    assert len(node_line(sbox2.points, [0.0, H / 2, W / 2], [1.0, 0.0, 0.0])) == 21
    with pytest.raises(ModelError, match="need at least 2"):
        node_line(sbox1.points, [0.0, H / 3, W / 2], [1.0, 0.0, 0.0])


def test_check_node_matrix():
    O = check_node_matrix([[0, 1, 2], [5, 4, 3]], 6)
    assert O.dtype == np.int64 and O.shape == (2, 3)
    with pytest.raises(ModelError, match="out of range"):
        check_node_matrix([[0, 1], [2, 6]], 6)
    with pytest.raises(ModelError, match="more than once"):
        check_node_matrix([[0, 1], [1, 2]], 6)
    with pytest.raises(ModelError, match="2D"):
        check_node_matrix([0, 1, 2], 6)
    with pytest.raises(ModelError, match="integer"):
        check_node_matrix([[0.0, 1.0], [2.0, 3.0]], 6)
