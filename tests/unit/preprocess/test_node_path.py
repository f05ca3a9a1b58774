"""Node groups of unstructured gmsh meshes ordered by walking the surface edges
(contours.node_grid.node_path, issue 20 item 2) and 1s contours through them: the walk
against the exact order (polar angle on a cylinder's rim, the coordinate along a box
edge), its errors, and the rim curve against the exact circle."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from contours import Contour1sNeutralFFR
from contours.node_grid import node_path
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR
from preprocess import Material, build_body
from validation.bench.common import moving_state

from gmsh_parts import BOX, RADIUS, box_mesh, cylinder_mesh

STEEL = Material(7800.0, 2.1e11, 0.3)
MESHES = [(1, True), (2, True), (2, False)]          # (order, tet10 mid-edge nodes on the CAD curve)


@pytest.fixture(scope="module", params=MESHES, ids=["tet4", "tet10-curved", "tet10-straight"])
def cylinder(request):
    order, curved = request.param
    return cylinder_mesh(0.02, order, curved)


@pytest.fixture(scope="module", params=[1, 2], ids=["tet4", "tet10"])
def box(request):
    return box_mesh(0.03, request.param)


def polar_order(points, nodes, first, second):
    """``nodes`` sorted by polar angle about the z axis, starting at ``first`` and turning
    towards ``second`` (the exact order of a circle's nodes)."""
    theta = np.arctan2(points[:, 1], points[:, 0])
    sense = np.sign(np.angle(np.exp(1j * (theta[second] - theta[first]))))
    key = np.mod(sense * (theta[nodes] - theta[first]), 2.0 * np.pi)
    return nodes[np.argsort(key)]


# --- the walk ------------------------------------------------------------------------------------

def test_rim_of_an_unstructured_cylinder_is_walked_in_polar_order(cylinder):
    rim = cylinder.group("rim0")
    path, closed = node_path(cylinder.surface_triangles(), rim, cylinder.points)
    assert closed
    assert len(path) == len(rim) and set(path.tolist()) == set(rim.tolist())
    # the convention: the smallest index first, then the smaller of its two neighbours on the circle
    exact = polar_order(cylinder.points, rim, path[0], path[1])
    np.testing.assert_array_equal(path, exact)
    assert path[0] == rim.min() and path[1] == min(exact[1], exact[-1])
    theta = np.unwrap(np.arctan2(cylinder.points[path, 1], cylinder.points[path, 0]))
    steps = np.diff(np.append(theta, theta[0] + 2.0 * np.pi * np.sign(theta[1] - theta[0])))
    assert np.all(steps * steps[0] > 0)                                  # monotone modulo 2π
    assert np.sum(np.abs(steps)) == pytest.approx(2.0 * np.pi, rel=1e-12)   # exactly one turn


@pytest.mark.parametrize("curved", [True, False], ids=["curved", "straight"])
def test_tet10_rim_holds_the_mid_edge_nodes(curved):
    """tet10: every second node of the walk is a mid-edge node (half-edges corner–mid–corner)."""
    mesh = cylinder_mesh(0.02, 2, curved)
    path, _ = node_path(mesh.surface_triangles(), mesh.group("rim0"))
    is_corner = np.isin(path, np.unique(mesh.tets[:, :4]))
    assert len(path) % 2 == 0 and np.all(is_corner[::2] != is_corner[1::2])


def test_open_box_edge_is_walked_along_the_edge_from_the_origin(box):
    tri, points = box.surface_triangles(), box.points
    edge = box.group("edge_x")
    path, closed = node_path(tri, edge, points)
    assert not closed
    np.testing.assert_array_equal(path, edge[np.argsort(points[edge, 0])])    # x increasing from the origin
    # without positions the walk starts at the end with the smaller index
    path, _ = node_path(tri, edge)
    by_x = edge[np.argsort(points[edge, 0])]
    np.testing.assert_array_equal(path, by_x if by_x[0] < by_x[-1] else by_x[::-1])


def test_an_l_of_two_box_edges_is_walked_round_the_corner(box):
    """edge_y (x = 0) then edge_x: ordered by arc length from the end nearer the origin,
    (0, ly, 0) at distance ly = 0.1 m against (lx, 0, 0) at lx = 0.2 m."""
    lx, ly, _ = BOX
    points, group = box.points, box.group("corner_xy")
    path, closed = node_path(box.surface_triangles(), group, points)
    assert not closed
    arc = np.where(points[group, 0] == 0.0, ly - points[group, 1], ly + points[group, 0])
    np.testing.assert_array_equal(path, group[np.argsort(arc)])
    assert arc.max() == pytest.approx(lx + ly)


def test_groups_that_are_not_a_line_of_surface_nodes_are_refused(cylinder, box):
    tri = cylinder.surface_triangles()
    rim0, rim1 = cylinder.group("rim0"), cylinder.group("rim1")
    with pytest.raises(ModelError, match=r"^node group 'z0' is not a line of surface nodes: node \d+ has \d+ "
                                         r"neighbours in the group along surface edges \(a branching or a face"):
        node_path(box.surface_triangles(), box.group("z0"), name="node group 'z0'")
    with pytest.raises(ModelError, match=r"has \d+ neighbours in the group"):
        node_path(tri, cylinder.group("base"))
    with pytest.raises(ModelError, match="it falls into 2 disconnected pieces"):
        node_path(tri, np.concatenate([rim0, rim1]))
    interior = np.setdiff1d(np.arange(cylinder.n_nodes), np.unique(tri))
    assert interior.size
    with pytest.raises(ModelError, match=rf"1 of its {len(rim0) + 1} nodes are not on the body's surface "
                                         rf"\(e.g. node {interior[0]}\)"):
        node_path(tri, np.append(rim0, interior[0]))
    with pytest.raises(ModelError, match=rf"node {rim1[0]} has no neighbour in the group"):
        node_path(tri, np.append(rim0, rim1[0]))
    with pytest.raises(ModelError, match=r"it has 1 node\(s\), a line needs at least 2"):
        node_path(tri, rim0[:1])


# --- 1s contours on the walked groups -------------------------------------------------------------

def rim_body(size, order, curved=True, n_modes=4):
    """A free-free steel cylinder (RADIUS x LENGTH) meshed at ``size`` [m], ``n_modes`` modes."""
    return FlexibleBodyFFR(build_body(cylinder_mesh(size, order, curved), STEEL, n_modes=n_modes), modes=n_modes)


def between_nodes(curve, n=10):
    """Curve parameters at ``n`` points strictly inside each span between consecutive nodes
    (the last span of a closed curve runs back to the first node at η = 1)."""
    params = np.append(curve.space.eta.interp.params, 1.0)
    s = np.linspace(0.0, 1.0, n + 2)[1:-1]
    return (params[:-1, None] + s * np.diff(params)[:, None]).ravel()


def radial_error(curve, n=10):
    """Max deviation [m] of the undeformed curve from the exact circle (radius RADIUS in
    z = 0) at ``n`` points between each pair of nodes: (radial, axial)."""
    p = np.array([curve.local_position_at(t) for t in between_nodes(curve, n)])
    return np.abs(np.hypot(p[:, 0], p[:, 1]) - RADIUS).max(), np.abs(p[:, 2]).max()


def spline_bound(nodes_xyz):
    """Hall–Meyer bound of the cubic spline interpolation error, 5/384 h⁴ max|r''''|, with
    |r''''| = 1/R³ per unit arc length on a circle and h the longest chord between
    consecutive nodes [m]."""
    chords = np.linalg.norm(np.diff(np.vstack([nodes_xyz, nodes_xyz[:1]]), axis=0), axis=1)
    return 5.0 / 384.0 * chords.max() ** 4 / RADIUS ** 3


@pytest.mark.parametrize("order", [1, 2], ids=["tet4", "tet10-curved"])
def test_rim_contour_interpolates_the_nodes_and_converges_to_the_circle(order):
    errors = []
    for size in (0.04, 0.02):
        body = rim_body(size, order)
        curve = Contour1sNeutralFFR(body, "rim0", normal=(0.0, 0.0, -1.0))
        path, closed = node_path(body.data.surface_triangles, body.node_group("rim0"), body.data.u0)
        np.testing.assert_array_equal(curve.nodes, path)
        assert closed and curve.space.eta.interp.closed
        u0 = body.data.u0[curve.nodes]
        for t, node in zip(curve.space.eta.interp.params, u0):
            np.testing.assert_allclose(curve.local_position_at(t), node, rtol=0, atol=1e-14)
        radial, axial = radial_error(curve)
        assert axial < 1e-15 and radial < spline_bound(u0)
        errors.append(radial)
        # deformed and moving: the curve still runs through the nodes
        q, u = moving_state(body, np.random.default_rng(20), deform=1e-3)
        curve.update(q, u)
        for t, r in zip(curve.space.eta.interp.params, body.node_positions(q, curve.nodes)):
            np.testing.assert_allclose(curve.position(t), r, rtol=0, atol=1e-12)
    assert errors[1] < errors[0] / 8.0            # third order at least (cubic spline: fourth)


def test_closed_flag_is_taken_from_the_walk_and_checked():
    body = rim_body(0.04, 1, n_modes=2)
    assert Contour1sNeutralFFR(body, "rim0", normal=(0, 0, -1), closed=True).space.eta.interp.closed
    with pytest.raises(ModelError, match=r"closed=False but node group 'rim0' is a closed loop of surface edges"):
        Contour1sNeutralFFR(body, "rim0", normal=(0, 0, -1), closed=False)
    box_body = FlexibleBodyFFR(build_body(box_mesh(0.05, 1), STEEL, n_modes=2), modes=2)
    edge = Contour1sNeutralFFR(box_body, "edge_x", normal=(0, -1, 0))
    assert not edge.space.eta.interp.closed
    group = box_body.node_group("edge_x")
    np.testing.assert_array_equal(edge.nodes, group[np.argsort(box_body.data.u0[group, 0])])
    with pytest.raises(ModelError, match=r"closed=True but node group 'edge_x' is an open line with two ends"):
        Contour1sNeutralFFR(box_body, "edge_x", normal=(0, -1, 0), closed=True)
    without = FlexibleBodyFFR(dataclasses.replace(body.data, surface_triangles=None), modes=2)
    with pytest.raises(ModelError, match=r"holds no surface triangles, so node group 'rim0' cannot be walked"):
        Contour1sNeutralFFR(without, "rim0", normal=(0, 0, -1))
