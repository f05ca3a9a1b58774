"""Second-order meshing on curved CAD surfaces and the curved built-in bodies, against the
exact surfaces: cylinder, sphere, the grooved block's half cylinder."""

import math

import gmsh
import numpy as np
import pytest

from ffrmbs.errors import ModelError
from preprocess import fe
from preprocess.geometry import (box, cylinder, gmsh_session, grooved_block, inverted_elements, mesh_geo_file,
                                 spherical_cap, stepped_beam)
from preprocess.mesh import GMSH_TET10, TET10_EDGES, canonical_mesh

# the groove: radius 40 mm meshed at 9 mm elements, in a 60 x 120 x 60 mm block
LX, LY, LZ, R_GROOVE, H_GROOVE = 60.0, 120.0, 60.0, 40.0, 9.0

#: the ten nodes of the reference tetrahedron, canonical order (preprocess.mesh)
REFERENCE_NODES = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1],
                            [.5, 0, 0], [.5, .5, 0], [0, .5, 0], [0, 0, .5], [.5, 0, .5], [0, .5, .5]])


def groove_radius(x):
    """Distance of points (..., 3) from the groove's axis (y = LY/2, z = LZ)."""
    return np.hypot(x[..., 1] - LY / 2, x[..., 2] - LZ)


@pytest.fixture(scope="module")
def groove():
    return grooved_block(LX, LY, LZ, R_GROOVE, H_GROOVE)


def patch_triangles(mesh, group):
    """The surface triangles (T, 6) of ``mesh`` whose six nodes all lie in node group ``group``."""
    inside = np.zeros(mesh.n_nodes, dtype=bool)
    inside[mesh.group(group)] = True
    tri = mesh.surface_triangles()
    return tri[inside[tri].all(axis=1)]


def node_jacobians(mesh):
    """det J of every canonical tet10 at its ten nodes (E, 10), from the shape functions of
    preprocess.fe (the canonical order): a node sorted onto the wrong edge folds the element."""
    _, dN = fe.shape_functions(2, REFERENCE_NODES)
    return np.linalg.det(np.einsum("eni,qnj->eqij", mesh.points[mesh.tets], dN))


def curved_volume(mesh):
    """Volume of the curved tet10 mesh: ∫ det J over each element, exact (det J is cubic)."""
    pts, w = fe.tet_quadrature(3)
    _, dN = fe.shape_functions(2, pts)
    return float(np.einsum("q,eq->", w, np.linalg.det(np.einsum("eni,qnj->eqij", mesh.points[mesh.tets], dN))))


def test_groove_nodes_lie_on_the_exact_cylinder_and_straight_mid_nodes_would_not(groove):
    """Every node of the groove's group, mid-edge nodes included, lies on r = 40 mm; the
    straight-line placement (the midpoint of an edge's corners) lies inside by the chord's
    sagitta R − √(R² − (c/2)²), c the chord projected on the cross-section (y, z)."""
    nodes = groove.points[groove.group("groove")]
    assert len(nodes) > 100
    np.testing.assert_allclose(groove_radius(nodes), R_GROOVE, rtol=1e-9, atol=0)
    tri = patch_triangles(groove, "groove")
    assert len(tri) > 100
    corners = groove.points[tri[:, :3]]
    ends = np.roll(corners, -1, axis=1)                         # edges (c0,c1), (c1,c2), (c2,c0)
    straight = 0.5 * (corners + ends)
    chord = np.hypot(*(ends - corners)[..., 1:].transpose(2, 0, 1))
    sagitta = R_GROOVE - np.sqrt(R_GROOVE ** 2 - (chord / 2) ** 2)
    np.testing.assert_allclose(R_GROOVE - groove_radius(straight), sagitta, rtol=0, atol=1e-9 * R_GROOVE)
    assert 0.25 < sagitta.max() < 0.5                           # the "up to 0.3 mm inside"
    np.testing.assert_allclose(groove_radius(groove.points[tri[:, 3:]]), R_GROOVE, rtol=1e-9, atol=0)


def test_quadratic_triangles_follow_the_groove_far_closer_than_linear_ones(groove):
    """Centroids (1/3, 1/3) of the groove's triangles: the 6-node triangle (corner shape
    functions L(2L − 1) = −1/9, mid-edge 4 L_a L_b = 4/9) deviates from the exact cylinder
    by a small fraction of the flat triangle's deviation."""
    tri = patch_triangles(groove, "groove")
    corners, mids = groove.points[tri[:, :3]], groove.points[tri[:, 3:]]
    linear = np.abs(groove_radius(corners.mean(axis=1)) - R_GROOVE).max()
    quadratic = np.abs(groove_radius(-corners.sum(axis=1) / 9 + 4 * mids.sum(axis=1) / 9) - R_GROOVE).max()
    assert linear > 0.1                                         # mm: flat triangles cut the groove
    assert quadratic < 1e-2 * linear and quadratic < 1e-5 * R_GROOVE


BUILT = {
    "cylinder": lambda order: cylinder(1.0, 3.0, 0.4, order),
    "spherical_cap": lambda order: spherical_cap(1.0, 0.6, 0.25, order),
    "grooved_block": lambda order: grooved_block(LX, LY, LZ, R_GROOVE, 15.0, order),
}


@pytest.fixture(scope="module", params=[1, 2], ids=["tet4", "tet10"])
def built(request):
    return {name: make(request.param) for name, make in BUILT.items()}


def on_planes(points, axis, value, tol=1e-9):
    return np.abs(points[:, axis] - value) <= tol


def test_cylinder_groups_lie_on_their_exact_surfaces(built):
    m = built["cylinder"]
    p, r = m.points, np.hypot(m.points[:, 0], m.points[:, 1])
    lateral, end0, end1, rim0, rim1 = (m.group(g) for g in ("lateral", "end0", "end1", "rim0", "rim1"))
    np.testing.assert_allclose(r[lateral], 1.0, rtol=1e-9)
    assert on_planes(p[end0], 2, 0.0).all() and on_planes(p[end1], 2, 3.0).all()
    np.testing.assert_array_equal(rim0, np.intersect1d(lateral, end0))
    np.testing.assert_array_equal(rim1, np.intersect1d(lateral, end1))
    assert len(rim0) >= 12
    np.testing.assert_array_equal(m.group("z0"), end0)
    np.testing.assert_array_equal(m.group("z1"), end1)
    np.testing.assert_array_equal(m.surface_nodes(), np.union1d(lateral, np.union1d(end0, end1)))
    assert not {"x0", "x1", "y0", "y1"} & set(m.node_groups)   # no face on those planes


def test_spherical_cap_groups_lie_on_their_exact_surfaces(built):
    m = built["spherical_cap"]
    p = m.points
    cap, base = m.group("cap"), m.group("base")
    np.testing.assert_allclose(np.linalg.norm(p[cap], axis=1), 1.0, rtol=1e-9)
    assert (p[cap, 2] >= 0.4 - 1e-9).all()
    assert on_planes(p[base], 2, 0.4).all()
    assert (np.hypot(p[base, 0], p[base, 1]) <= math.sqrt(1 - 0.4 ** 2) * (1 + 1e-9)).all()
    np.testing.assert_array_equal(m.group("z0"), base)
    np.testing.assert_array_equal(m.surface_nodes(), np.union1d(cap, base))


def test_grooved_block_groups_lie_on_their_exact_surfaces(built):
    m = built["grooved_block"]
    p = m.points
    groove_nodes = m.group("groove")
    np.testing.assert_allclose(groove_radius(p[groove_nodes]), R_GROOVE, rtol=1e-9)
    assert (p[groove_nodes, 2] <= LZ + 1e-9).all()
    np.testing.assert_array_equal(m.group("bottom"), m.group("z0"))
    assert on_planes(p[m.group("z1")], 2, LZ).all()
    assert (np.abs(p[m.group("z1"), 1] - LY / 2) >= R_GROOVE - 1e-9).all()  # the two strips
    faces = groove_nodes
    for g in ("x0", "x1", "y0", "y1", "z0", "z1"):
        faces = np.union1d(faces, m.group(g))
    np.testing.assert_array_equal(m.surface_nodes(), faces)


@pytest.mark.parametrize("name, exact", [
    ("cylinder", math.pi * 3.0),
    ("spherical_cap", math.pi * 0.6 ** 2 * (3 - 0.6) / 3),
    ("grooved_block", LX * LY * LZ - LX * math.pi * R_GROOVE ** 2 / 2),
])
def test_curved_tet10_fill_the_exact_volume_and_are_valid_at_their_nodes(name, exact):
    """The curved tet10's volume (∫ det J) is far closer to the body's exact volume than the
    straight-sided tetrahedra's, and det J > 0 at every node of every element."""
    mesh = BUILT[name](2)
    assert (node_jacobians(mesh) > 0).all()
    curved, straight = curved_volume(mesh), mesh.element_volumes().sum()
    assert abs(curved - exact) < 1e-2 * abs(straight - exact)   # measured: 1.1e-3 to 3.4e-3
    assert abs(curved - exact) < 2e-4 * exact


@pytest.mark.parametrize("make", [lambda: box(1, 1, 5, 0.5), lambda: stepped_beam(5.0),
                                  lambda: box(0.25, 0.05, 0.05, None, divisions=(10, 2, 2))],
                         ids=["box", "stepped_beam", "structured_box"])
def test_flat_bodies_keep_straight_mid_edge_nodes(make):
    """On flat faces and inside the body gmsh's second-order nodes are the edges' midpoints."""
    m = make()
    corners = m.points[m.tets[:, :4]]
    mids = 0.5 * (corners[:, TET10_EDGES[:, 0]] + corners[:, TET10_EDGES[:, 1]])
    np.testing.assert_allclose(m.points[m.tets[:, 4:]], mids, rtol=0, atol=1e-12 * np.ptp(m.points).max())


def test_curved_meshing_is_deterministic(groove):
    again = grooved_block(LX, LY, LZ, R_GROOVE, H_GROOVE)
    np.testing.assert_array_equal(again.points, groove.points)
    np.testing.assert_array_equal(again.tets, groove.tets)
    assert again.node_groups.keys() == groove.node_groups.keys()
    for name, nodes in groove.node_groups.items():
        np.testing.assert_array_equal(again.node_groups[name], nodes)


# a tube 0.02 thick around a radius of 1, meshed at 2: its mid-edge nodes, placed on the
# cylinders, fold most elements over (the chord's sagitta 0.13 exceeds the wall)
THIN_TUBE = """SetFactory("OpenCASCADE");
Cylinder(1) = {0, 0, 0, 0, 0, 1, 1};
Cylinder(2) = {0, 0, 0, 0, 0, 1, 0.98};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Physical Surface("outer") = {Surface{:}};
"""


def test_a_thin_curved_wall_is_repaired_with_its_nodes_on_the_surfaces(tmp_path):
    (tmp_path / "tube.geo").write_text(THIN_TUBE)
    mesh = mesh_geo_file(tmp_path / "tube.geo", order=2, mesh_size=2.0)
    assert (node_jacobians(mesh) > 0).all()
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    surface = mesh.surface_nodes()
    on_cylinders = (np.abs(r[surface] - 1.0) < 1e-9) | (np.abs(r[surface] - 0.98) < 1e-9)
    on_ends = (np.abs(mesh.points[surface, 2]) < 1e-9) | (np.abs(mesh.points[surface, 2] - 1) < 1e-9)
    assert (on_cylinders | on_ends).all()
    assert np.abs(r[surface] - 1.0).min() < 1e-9 and np.abs(r[surface] - 0.98).min() < 1e-9


def test_inverted_curved_elements_left_unrepaired_are_a_model_error(tmp_path, monkeypatch):
    monkeypatch.setattr(gmsh.model.mesh, "optimize", lambda *args, **kwargs: None)   # no repair
    (tmp_path / "tube.geo").write_text(THIN_TUBE)
    with pytest.raises(ModelError, match=r"tube\.geo: \d+ of \d+ second-order tetrahedra are inverted"):
        mesh_geo_file(tmp_path / "tube.geo", order=2, mesh_size=2.0)


def test_inverted_elements_are_those_whose_determinant_changes_sign_or_vanishes():
    det = np.array([[1, 2, 3], [-1, -2, -0.5], [1, -1, 2], [0, 1, 1], [-1, 0, -1]], dtype=float)
    np.testing.assert_array_equal(inverted_elements(det), [2, 3, 4])


def test_gmsh_tet10_permutation_matches_gmsh_own_reference_element():
    """GMSH_TET10 read off gmsh's reference tetrahedron of type 11: the node at the midpoint of
    corners a and b goes to the canonical slot of edge (a, b)."""
    with gmsh_session():
        local = np.array(gmsh.model.mesh.getElementProperties(11)[4]).reshape(10, 3)
    corners = local[:4]
    canonical = local[GMSH_TET10]
    np.testing.assert_allclose(canonical[:4], corners)
    np.testing.assert_allclose(canonical[4:], 0.5 * (corners[TET10_EDGES[:, 0]] + corners[TET10_EDGES[:, 1]]))


def relabel(tet, corner_order):
    """The canonical tet10 ``tet`` (10,) with its corners taken in ``corner_order``: the
    mid-edge node of each new edge found by the old edge it sits on."""
    old_edge = {frozenset(map(int, e)): tet[4 + k] for k, e in enumerate(TET10_EDGES)}
    corners = [tet[c] for c in corner_order]
    mids = [old_edge[frozenset((corner_order[a], corner_order[b]))] for a, b in TET10_EDGES]
    return np.array(corners + mids)


def test_mid_nodes_in_order_with_reversed_elements_match_the_geometric_sorting(groove):
    """Elements given in the canonical order but negatively oriented (corners 0, 2, 1, 3) are
    turned back exactly as the geometric sorting of mid-edge nodes turns them."""
    rng = np.random.default_rng(4)
    flip = rng.random(groove.n_elements) < 0.5
    tets = groove.tets.copy()
    tets[flip] = [relabel(t, [0, 2, 1, 3]) for t in groove.tets[flip]]
    exact = canonical_mesh(groove.points, tets, {}, "given", mid_nodes_in_order=True)
    geometric = canonical_mesh(groove.points, tets, {}, "sorted")
    np.testing.assert_array_equal(exact.tets, groove.tets)
    np.testing.assert_array_equal(geometric.tets, groove.tets)


@pytest.mark.parametrize("make, fault", [
    (lambda: cylinder(0, 1, 0.1), "cylinder radius"),
    (lambda: cylinder(1, float("nan"), 0.1), "cylinder length"),
    (lambda: spherical_cap(1, 2, 0.1), "cap height must be below twice the radius"),
    (lambda: spherical_cap(1, -0.5, 0.1), "cap height"),
    (lambda: grooved_block(1, 1, 1, 0.5, 0.1), r"groove radius must be below min\(ly/2, lz\) = 0.5"),
    (lambda: grooved_block(1, 4, 0.3, 0.3, 0.1), r"groove radius must be below min\(ly/2, lz\) = 0.3"),
    (lambda: grooved_block(1, float("inf"), 1, 0.3, 0.1), "block length ly"),
])
def test_bad_dimensions_are_model_errors(make, fault):
    with pytest.raises(ModelError, match=fault):
        make()
