"""Tetrahedral meshes: reading gmsh and Abaqus input, canonical node order, surface.

A :class:`Mesh` holds linear (tet4) or quadratic (tet10) tetrahedra in one
canonical local order — the VTK/meshio order, which is also Abaqus C3D10's::

    vertices 0, 1, 2, 3 (positive volume), then mid-edge nodes of the edges
    (0,1), (1,2), (0,2), (0,3), (1,3), (2,3)

Input orderings differ between tools (gmsh swaps the last two mid-edge nodes,
:data:`GMSH_TET10`). Elements meshed or read by gmsh are brought into this order by
that known permutation, so mid-edge nodes placed on a curved surface (gmsh's
second-order meshing, :mod:`preprocess.geometry`) keep their edges however far they
lie from the straight edge's midpoint; tet10 elements from other tools are sorted
geometrically: each mid-edge node is matched to the edge whose midpoint it lies
closest to. This accepts any tool's convention and catches corrupt connectivity.

Readers (regular files only, :mod:`preprocess.inputfiles`):

* ``.geo`` and ``.msh``: the gmsh Python API (``.geo`` is meshed, see
  :func:`preprocess.geometry.mesh_geo_file`, after the checks of
  :func:`preprocess.geometry.check_geo_file`); physical groups become node groups.
* ``.step``, ``.stp``, ``.iges``, ``.igs``: CAD solids read by gmsh's OpenCASCADE
  kernel and meshed (:func:`preprocess.geometry.mesh_cad_file`); node groups from the
  file's names, selection boxes and the bounding planes.
* ``.inp`` and other formats meshio reads: node sets and element sets become node groups;
  surface and line elements are ignored, other volume elements refused. A fault meshio
  finds is one line naming the file (for ``.inp`` also the line and the fault,
  :mod:`preprocess.abaqus`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ffrmbs.errors import InputFileError, ModelError, quote
from preprocess.inputfiles import regular_file

#: mid-edge node k (local index 4 + k) sits on edge TET10_EDGES[k]
TET10_EDGES = np.array([(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)])

#: gmsh's tet10 (element type 11) -> canonical order: gmsh's mid-edge nodes 8 and 9 sit
#: on the edges (2,3) and (1,3), the canonical ones on (1,3) and (2,3)
GMSH_TET10 = np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8])

#: canonical tet10 with corners 1 and 2 swapped (orientation reversed), still canonical:
#: the mid-edge nodes of (0,1) <-> (0,2) and (1,3) <-> (2,3) swap with them
_TET10_FLIP = np.array([0, 2, 1, 3, 6, 5, 4, 7, 9, 8])

#: outward faces (corner triples) of a positively oriented tetrahedron, face i opposite vertex i
TET_FACES = np.array([(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)])


def _edge_slot(a, b):
    """Local mid-node index (4..9) of the edge between local corners a and b."""
    for k, (i, j) in enumerate(TET10_EDGES):
        if {i, j} == {a, b}:
            return 4 + k
    raise ValueError((a, b))


#: outward quadratic faces: corners, then mid-nodes of edges (c0,c1), (c1,c2), (c2,c0)
TET10_FACES = np.array([
    [*f, _edge_slot(f[0], f[1]), _edge_slot(f[1], f[2]), _edge_slot(f[2], f[0])]
    for f in TET_FACES
])


@dataclass
class Mesh:
    """A tetrahedral mesh in canonical order.

    Attributes
    ----------
    points : (N, 3) float array, node coordinates (units of the source; SI after
        :meth:`scaled`).
    tets : (E, 4) or (E, 10) int64 array, 0-based, canonical order (module docstring).
    node_groups : dict name -> sorted int64 node indices.
    source : str, where the mesh came from (for messages).
    """

    points: np.ndarray
    tets: np.ndarray
    node_groups: dict = field(default_factory=dict)
    source: str = "<memory>"

    @property
    def order(self) -> int:
        """Element order: 1 for tet4, 2 for tet10."""
        return 1 if self.tets.shape[1] == 4 else 2

    @property
    def n_nodes(self) -> int:
        return self.points.shape[0]

    @property
    def n_elements(self) -> int:
        return self.tets.shape[0]

    def scaled(self, factor: float) -> "Mesh":
        """A copy with coordinates multiplied by ``factor`` (unit conversion)."""
        return Mesh(self.points * factor, self.tets, dict(self.node_groups), self.source)

    def group(self, name: str) -> np.ndarray:
        """Node indices of group ``name``; InputFileError naming the known groups if absent."""
        try:
            return self.node_groups[name]
        except KeyError:
            known = ", ".join(sorted(self.node_groups)) or "none"
            raise InputFileError(self.source, None,
                                 f"unknown node group {name!r}; known groups: {known}") from None

    def surface_triangles(self) -> np.ndarray:
        """Outward surface faces: faces that belong to exactly one element.

        Returns (T, 3) corner triples for tet4, (T, 6) for tet10 (corners, then the
        mid-edge nodes of edges (c0,c1), (c1,c2), (c2,c0)), counter-clockwise seen
        from outside.
        """
        faces = TET_FACES if self.order == 1 else TET10_FACES
        all_faces = self.tets[:, faces].reshape(-1, faces.shape[1])
        key = np.sort(all_faces[:, :3], axis=1)
        _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        return all_faces[counts[inverse.ravel()] == 1]

    def surface_nodes(self) -> np.ndarray:
        """Sorted indices of all nodes on the surface."""
        return np.unique(self.surface_triangles())

    def parts(self) -> tuple[int, np.ndarray]:
        """Connected parts: (number of parts, part label (N,) of every node, 0-based).

        Two nodes are in one part when a chain of elements, each sharing a node with
        the next, joins them.
        """
        n_per = self.tets.shape[1]
        graph = sp.coo_matrix((np.ones(self.tets.size), (np.repeat(self.tets[:, 0], n_per), self.tets.ravel())),
                              shape=(self.n_nodes, self.n_nodes))
        return connected_components(graph, directed=False)

    def element_volumes(self) -> np.ndarray:
        """Volumes of the straight-sided tetrahedra spanned by the corners, shape (E,)."""
        p = self.points[self.tets[:, :4]]
        return np.linalg.det(p[:, 1:] - p[:, :1]) / 6.0


def canonical_mesh(points, tets, node_groups, source, mid_nodes_in_order=False) -> Mesh:
    """Build a :class:`Mesh` from raw arrays in any tet4/tet10 node convention.

    Drops nodes not used by any tetrahedron (renumbering groups accordingly),
    orients every element positively and sorts tet10 mid-edge nodes into the
    canonical order — geometrically, or, with ``mid_nodes_in_order``, taking them as
    already in the canonical order (e.g. gmsh's permuted by :data:`GMSH_TET10`).
    Raises InputFileError for degenerate elements or tet10 connectivity whose mid-edge
    nodes do not match the edges (geometric sorting only).
    """
    points = np.asarray(points, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)
    if tets.ndim != 2 or tets.shape[1] not in (4, 10) or len(tets) == 0:
        raise InputFileError(source, None, "no tetrahedra (tet4 or tet10) in the mesh")
    if not np.all(np.isfinite(points)):
        raise InputFileError(source, None, "node coordinates contain NaN or inf")
    used = np.unique(tets)
    new_index = -np.ones(len(points), dtype=np.int64)
    new_index[used] = np.arange(len(used))
    tets = new_index[tets]
    points = points[used]
    groups = {}
    for name, nodes in node_groups.items():
        mapped = new_index[np.asarray(nodes, dtype=np.int64)]
        groups[name] = np.unique(mapped[mapped >= 0])

    corners = points[tets[:, :4]]
    vol6 = np.linalg.det(corners[:, 1:] - corners[:, :1])
    scale = np.ptp(points, axis=0).max() ** 3
    if np.any(np.abs(vol6) <= 1e-14 * scale):
        bad = int(np.argmax(np.abs(vol6) <= 1e-14 * scale))
        raise InputFileError(source, None, f"degenerate tetrahedron (zero volume), element {bad + 1}")
    flip = vol6 < 0
    if tets.shape[1] == 10 and mid_nodes_in_order:
        tets[flip] = tets[flip][:, _TET10_FLIP]
    else:
        tets[flip, 1], tets[flip, 2] = tets[flip, 2].copy(), tets[flip, 1].copy()
        if tets.shape[1] == 10:
            tets = _sort_mid_nodes(points, tets, source)
    return Mesh(points, tets, groups, str(source))


def _sort_mid_nodes(points, tets, source):
    """Put the six mid-edge nodes of each tet10 on their edges (canonical order)."""
    corners = points[tets[:, :4]]
    edge_mid = 0.5 * (corners[:, TET10_EDGES[:, 0]] + corners[:, TET10_EDGES[:, 1]])  # (E,6,3)
    mids = points[tets[:, 4:]]  # (E,6,3)
    dist = np.linalg.norm(mids[:, :, None, :] - edge_mid[:, None, :, :], axis=-1)  # node x edge
    slot = np.argmin(dist, axis=2)  # edge of each given mid node
    ok = np.all(np.sort(slot, axis=1) == np.arange(6), axis=1)
    if not np.all(ok):
        bad = int(np.argmin(ok))
        raise InputFileError(source, None, f"tet10 element {bad + 1}: mid-edge nodes do not lie on distinct edges")
    out = tets.copy()
    rows = np.arange(len(tets))[:, None]
    out[rows, 4 + slot] = tets[:, 4:]
    return out


#: CAD files, read by gmsh's OpenCASCADE kernel (:func:`preprocess.geometry.mesh_cad_file`): STEP and IGES
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs")
#: geometry files meshed here: gmsh ``.geo`` and CAD files
MESHED_SUFFIXES = (".geo", *CAD_SUFFIXES)


def read_mesh(path, order=None, mesh_size=None, check_limits=True, length_unit="m", face_boxes=None) -> Mesh:
    """Read a tetrahedral mesh from ``.msh`` (gmsh), ``.geo``, a STEP or IGES file, ``.inp``
    (Abaqus) and other meshio formats. Units are those of the file, but a CAD file's are
    converted to ``length_unit`` ("m" or "mm"; STEP and IGES files state their unit).

    ``order`` (1 or 2; None: 2), ``mesh_size`` (maximum element size, file units) and
    ``check_limits`` (the limits of :mod:`preprocess.limits`, checked before meshing)
    apply to the geometry files of :data:`MESHED_SUFFIXES`, which are meshed here; meshes
    read from files keep their order, and an ``order`` or a ``mesh_size`` for them is a
    ModelError. ``face_boxes`` ({name: (xmin, ymin, zmin, xmax, ymax, zmax)}, CAD files
    only): node groups of the faces inside each box
    (:func:`preprocess.geometry.mesh_cad_file`).
    """
    path = regular_file(path)
    suffix = path.suffix.lower()
    check_meshing_options(path, order, mesh_size, face_boxes)
    order = 2 if order is None else order
    if suffix == ".geo":
        from preprocess.geometry import mesh_geo_file

        return mesh_geo_file(path, order, mesh_size, check_limits)
    if suffix in CAD_SUFFIXES:
        from preprocess.geometry import mesh_cad_file

        return mesh_cad_file(path, order, mesh_size, check_limits, length_unit, face_boxes)
    return _read_gmsh_msh(path) if suffix == ".msh" else _read_meshio(path)


def check_meshing_options(path, order=None, mesh_size=None, face_boxes=None):
    """A ModelError when an element ``order`` or a ``mesh_size`` is given (not None) for
    the mesh file ``path``: they apply to the geometry files of :data:`MESHED_SUFFIXES`
    (and built-in geometries) only, a mesh file keeps its own elements; likewise for
    ``face_boxes`` (``--group``) given for anything but a STEP or IGES file."""
    suffix = Path(path).suffix.lower()
    if face_boxes and suffix not in CAD_SUFFIXES:
        raise ModelError(f"--group applies to STEP and IGES files (.step, .stp, .iges, .igs), not {path}")
    if suffix in MESHED_SUFFIXES:
        return
    for option, value in (("--order", order), ("--mesh-size", mesh_size)):
        if value is not None:
            raise ModelError(f"{option} applies to built-in geometries, .geo, STEP and IGES files; "
                             f"{path} is already meshed")


def _read_gmsh_msh(path) -> Mesh:
    from preprocess.geometry import gmsh_session, mesh_from_gmsh_model

    with gmsh_session() as gmsh:
        try:
            gmsh.open(str(path))
        except Exception as exc:  # gmsh raises a bare Exception with its log line
            raise InputFileError(path, None, f"gmsh cannot read the mesh: {exc}") from None
        return mesh_from_gmsh_model(gmsh, path)


_TET_CELLS = ("tetra", "tetra10")
_VOLUME_CELLS = ("hexahedron", "wedge", "pyramid", "tetra")   # prefixes of meshio's volume cell types


def _read_meshio(path) -> Mesh:
    import meshio

    from preprocess.abaqus import check_includes

    if path.suffix.lower() == ".inp":
        check_includes(path)
    # the format's own reader: meshio.read prints a ReadError and exits the process
    formats = meshio.extension_to_filetypes.get(path.suffix.lower(), [""])
    reader = getattr(getattr(meshio, formats[0], None), "read", None)
    if reader is None:
        raise InputFileError(path, None, f"unknown mesh format {quote(path.suffix)} "
                                         "(.geo, .step, .stp, .iges, .igs, .msh, .inp or another format meshio reads)")
    try:
        m = reader(str(path))
    except Exception as exc:  # meshio raises ReadError, ValueError, KeyError, ...
        raise _meshio_error(path, exc) from None
    other = sorted({c.type for c in m.cells if c.type.startswith(_VOLUME_CELLS)} - set(_TET_CELLS))
    if other:
        raise InputFileError(path, None, f"volume elements of type {', '.join(other)} are not supported "
                                         "(tetrahedra only: tet4 or tet10)")
    blocks = [(i, c) for i, c in enumerate(m.cells) if c.type in _TET_CELLS]
    if not blocks:
        raise InputFileError(path, None, "no tetrahedra (tet4 or tet10) in the mesh")
    if len({c.type for _, c in blocks}) > 1:
        raise InputFileError(path, None, "mixed tet4 and tet10 elements are not supported")
    tets = np.concatenate([c.data for _, c in blocks])
    groups = {name: np.asarray(nodes) for name, nodes in m.point_sets.items()}
    for name, per_block in m.cell_sets.items():
        nodes = [m.cells[i].data[np.asarray(ids, dtype=np.int64)].ravel()
                 for i, ids in enumerate(per_block) if ids is not None and len(ids)]
        if nodes:
            groups.setdefault(name, np.unique(np.concatenate(nodes)))
    return canonical_mesh(m.points, tets, groups, path)


def _meshio_error(path, exc: Exception) -> InputFileError:
    """The InputFileError for meshio's exception ``exc`` reading ``path``: for ``.inp``
    the line and fault found by :func:`preprocess.abaqus.inp_fault`, else meshio's
    words, quoted short (they may hold file content)."""
    from preprocess.abaqus import inp_fault

    found = None
    if path.suffix.lower() == ".inp":
        try:
            found = inp_fault(path, exc)
        except OSError:
            found = None
    if found is not None:
        return InputFileError(path, *found)
    words = str(exc) or type(exc).__name__
    return InputFileError(path, None, f"cannot read the mesh: {quote(words, 80)}")
