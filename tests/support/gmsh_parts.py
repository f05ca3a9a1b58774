"""Unstructured gmsh meshes with feature-edge groups, built directly with gmsh for the
node-path tests (test_node_path.py, test_scene_reader.py): a cylinder with its two
circular rims and a box with edges, each a gmsh physical curve, so the groups are the
nodes gmsh puts on those curves (no grid, no order)."""

from __future__ import annotations

from preprocess.geometry import gmsh_session, mesh_from_gmsh_model

RADIUS, LENGTH = 0.05, 0.1          # cylinder [m]: axis z, base circle at z = 0
BOX = (0.2, 0.1, 0.05)              # box [m]: [0, lx] x [0, ly] x [0, lz]


def _entities_in(gmsh, dim, lo, hi, eps=1e-6):
    """Tags of the model entities of dimension ``dim`` inside the box lo..hi (± eps)."""
    return [tag for _, tag in gmsh.model.getEntitiesInBoundingBox(*(c - eps for c in lo), *(c + eps for c in hi),
                                                                    dim)]


def _mesh(gmsh, size, order, curved, source):
    """Mesh the synchronized model at element size ``size`` [m] (min = max), tet4 or tet10;
    ``curved``: tet10 mid-edge nodes on the CAD geometry (as :mod:`preprocess.geometry`
    meshes), else on straight edges."""
    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0 if curved else 1)
    gmsh.model.mesh.generate(3)
    if order == 2:
        gmsh.model.mesh.setOrder(2)
    return mesh_from_gmsh_model(gmsh, source)


def cylinder_mesh(size, order=1, curved=True):
    """A cylinder of radius RADIUS and length LENGTH along z, meshed with tetrahedra of
    ``order`` at element size ``size`` [m]. Node groups: ``rim0`` and ``rim1`` (the
    circles at z = 0 and z = LENGTH, physical curves), ``base`` (the disc at z = 0, a
    physical surface), ``body`` (all nodes)."""
    with gmsh_session() as gmsh:
        volume = gmsh.model.occ.addCylinder(0.0, 0.0, 0.0, 0.0, 0.0, LENGTH, RADIUS)
        gmsh.model.occ.synchronize()
        lo, hi = (-RADIUS, -RADIUS), (RADIUS, RADIUS)
        for name, z in (("rim0", 0.0), ("rim1", LENGTH)):
            gmsh.model.addPhysicalGroup(1, _entities_in(gmsh, 1, (*lo, z), (*hi, z)), name=name)
        gmsh.model.addPhysicalGroup(2, _entities_in(gmsh, 2, (*lo, 0.0), (*hi, 0.0)), name="base")
        gmsh.model.addPhysicalGroup(3, [volume], name="body")
        return _mesh(gmsh, size, order, curved, "cylinder")


def box_mesh(size, order=1):
    """The box [0, lx] x [0, ly] x [0, lz] (BOX) meshed with tetrahedra of ``order`` at
    element size ``size`` [m]. Node groups: ``edge_x`` (the edge y = z = 0), ``edge_y``
    (the edge x = z = 0), ``corner_xy`` (both: an L through the origin), ``z0`` (the face
    z = 0), ``body``."""
    lx, ly, lz = BOX
    with gmsh_session() as gmsh:
        volume = gmsh.model.occ.addBox(0.0, 0.0, 0.0, lx, ly, lz)
        gmsh.model.occ.synchronize()
        edge_x = _entities_in(gmsh, 1, (0.0, 0.0, 0.0), (lx, 0.0, 0.0))
        edge_y = _entities_in(gmsh, 1, (0.0, 0.0, 0.0), (0.0, ly, 0.0))
        gmsh.model.addPhysicalGroup(1, edge_x, name="edge_x")
        gmsh.model.addPhysicalGroup(1, edge_y, name="edge_y")
        gmsh.model.addPhysicalGroup(1, edge_x + edge_y, name="corner_xy")
        gmsh.model.addPhysicalGroup(2, _entities_in(gmsh, 2, (0.0, 0.0, 0.0), (lx, ly, 0.0)), name="z0")
        gmsh.model.addPhysicalGroup(3, [volume], name="body")
        return _mesh(gmsh, size, order, False, "box")
