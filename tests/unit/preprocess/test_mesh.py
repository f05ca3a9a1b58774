"""Meshes: canonical tet10 order from any convention, surfaces, gmsh / Abaqus input."""

import meshio
import numpy as np
import pytest
import trimesh

from ffrmbs.errors import InputFileError
from preprocess import fe
from preprocess.mesh import canonical_mesh
from preprocess.mesh_files import read_mesh

GMSH_TET10 = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]  # gmsh swaps the mid-nodes of edges (1,3), (2,3)


def test_report_mesh_statistics(report_beam):
    # report Table 1: 579 nodes, 426 surface nodes, 254 second-order tetrahedra
    assert (report_beam.n_nodes, len(report_beam.surface_nodes()), report_beam.n_elements) == (579, 426, 254)
    assert report_beam.element_volumes().sum() == pytest.approx(5.0, rel=1e-12)


def test_any_tet10_convention_gives_the_same_stiffness(small_box_tet10):
    m = small_box_tet10
    K0 = fe.stiffness_matrix(m, 1e9, 0.3)
    rng = np.random.default_rng(3)
    tets = m.tets.copy()
    tets = tets[:, GMSH_TET10]  # gmsh order
    flip = rng.random(len(tets)) < 0.5  # and half the elements inverted (vertices 1, 2 swapped)
    swapped = tets.copy()
    swapped[:, [1, 2]] = tets[:, [2, 1]]
    tets[flip] = swapped[flip]
    shuffled = canonical_mesh(m.points, tets, {}, "shuffled")
    K1 = fe.stiffness_matrix(shuffled, 1e9, 0.3)
    assert abs(K1 - K0).max() < 1e-12 * abs(K0).max()


def test_corrupt_tet10_connectivity_is_reported(small_box_tet10):
    tets = small_box_tet10.tets.copy()
    tets[5, 4:] = tets[5, 4]  # all mid-edge slots point at one node
    with pytest.raises(InputFileError, match="element 6"):
        canonical_mesh(small_box_tet10.points, tets, {}, "bad.inp")


@pytest.mark.parametrize("mesh_name", ["small_box_tet4", "small_box_tet10"])
def test_surface_is_closed_and_outward(mesh_name, request):
    m = request.getfixturevalue(mesh_name)
    tri = m.surface_triangles()[:, :3]
    surf = trimesh.Trimesh(m.points, tri, process=False)
    assert surf.is_watertight
    assert surf.volume == pytest.approx(1.0 * 0.5 * 2.0, rel=1e-12)  # > 0: normals point outward


def test_gmsh_msh_and_abaqus_inp_round_trip(small_box_tet10, tmp_path):
    m = small_box_tet10
    cells = [("tetra10", m.tets)]
    meshio.write(tmp_path / "b.inp", meshio.Mesh(m.points, cells, point_sets={"clamp": m.group("z0")}))
    inp = read_mesh(tmp_path / "b.inp")
    np.testing.assert_array_equal(inp.tets, m.tets)
    np.testing.assert_array_equal(inp.group("clamp"), m.group("z0"))
    meshio.write(tmp_path / "b.msh", meshio.Mesh(m.points, cells), file_format="gmsh")
    msh = read_mesh(tmp_path / "b.msh")
    assert msh.n_nodes == m.n_nodes and msh.order == 2
    K0, K1 = fe.stiffness_matrix(m, 1e9, 0.3), fe.stiffness_matrix(msh, 1e9, 0.3)
    assert abs(K1 - K0).max() < 1e-9 * abs(K0).max()


def test_geo_file_is_meshed_with_physical_groups(tmp_path):
    geo = tmp_path / "plate.geo"
    geo.write_text('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 2, 1, 0.5};\n'
                   'Physical Surface("left") = {1};\nPhysical Volume("solid") = {1};\n')
    m = read_mesh(geo, order=1, mesh_size=0.4)
    assert m.order == 1
    np.testing.assert_allclose(m.points[m.group("left"), 0], 0.0, atol=1e-12)
    assert m.element_volumes().sum() == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("text,suffix", [("garbage\n", ".inp"), ("", ".msh"), ("Box(1) = {;\n", ".geo")])
def test_unreadable_mesh_files(tmp_path, text, suffix):
    path = tmp_path / f"bad{suffix}"
    path.write_text(text)
    with pytest.raises(InputFileError, match="bad"):
        read_mesh(path)


def test_unknown_group_names_the_known_ones(small_box_tet4):
    with pytest.raises(InputFileError, match="unknown node group 'clamp'.*x0"):
        small_box_tet4.group("clamp")
