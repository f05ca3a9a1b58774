"""Meshing with gmsh: ``.geo`` files, STEP and IGES files and the built-in validation geometries.

CAD files (:data:`preprocess.mesh_files.CAD_SUFFIXES`) are read by gmsh's OpenCASCADE kernel
in mm, meshed and scaled to the run's length unit (:func:`mesh_cad_file`); their node
groups come from the names in the file, selection boxes (``--group``) and the bounding
planes that hold a face.

Built-in bodies (OpenCASCADE kernel, meshed with tetrahedra of order 1 or 2):

* :func:`box` — a cuboid ``[0, lx] x [0, ly] x [0, lz]``, e.g. the report's
  1 x 1 x 5 m beam (report Sec. 5.1, Table 1); structured with ``divisions``.
* :func:`stepped_beam` — our reading of the thesis's "complex beam" (thesis
  Sec. 5.1, Fig. 5.1, Listing 4.1); see its docstring.
* :func:`cylinder`, :func:`spherical_cap`, :func:`grooved_block` — curved surfaces
  with exact equations, for contours fitted to unstructured face patches.

Every built-in body carries node groups for its bounding faces, named
``x0, x1, y0, y1, z0, z1`` (nodes on the plane x = min, x = max, ...; only the planes
that are faces of the body), and ``body`` (all nodes), found on the mesh nodes with a
tolerance relative to the body's own size (:func:`bounding_face_groups`), so at any
scale. The curved bodies also name their faces and edges as gmsh physical groups
(``lateral``, ``groove``, ``rim0``, ...), which become node groups: the nodes of that
surface's or curve's mesh, mid-edge nodes included. Meshing is single-threaded so that
it is deterministic.

Order 2 is gmsh's own second-order meshing: each mid-edge node is placed on the
geometry the edge lies on (``Mesh.SecondOrderLinear`` = 0), so a curved face's nodes
lie on the exact CAD surface, not on the straight chord between the corners; on flat
faces and inside the body they are the edges' midpoints. Curved elements are checked
for inversion at their nodes and repaired or refused (:func:`_repair_curved_elements`).

Before gmsh meshes, the mesh is estimated from the model's volume and mesh size and
refused over the limits of :mod:`preprocess.limits` (``check_limits=False`` lifts them).
A ``.geo`` file is scanned first (:func:`check_geo_file`): every file it merges or
includes must be a regular file (gmsh would block on a FIFO), and it must not mesh
itself while gmsh reads it (before the estimate).
"""

from __future__ import annotations

import math
import re
import threading
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, ModelError, quote
from preprocess import fe, limits
from preprocess.inputfiles import include_tree, regular_file
from preprocess.mesh import GMSH_TET10, Mesh, canonical_mesh

_GMSH_TET = {1: 4, 2: 11}  # gmsh element type numbers of tet4 and tet10
PLANE_RTOL = 1e-9          # a node on a bounding plane: within this x the body's size


@contextmanager
def gmsh_session():
    """Initialize gmsh quietly for one job and finalize it afterwards. Off the main thread
    (e.g. a Dask worker's task) gmsh is not made interruptible: its Ctrl-C handler can
    only be installed by the main thread."""
    import gmsh

    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=threading.current_thread() is threading.main_thread())
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MaxNumThreads3D", 1)
    try:
        yield gmsh
    finally:
        gmsh.clear()
        if owner:
            gmsh.finalize()


def mesh_from_gmsh_model(gmsh, source) -> Mesh:
    """Extract the tetrahedra and physical groups of the current gmsh model."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    if len(tags) == 0:
        raise InputFileError(source, None, "the mesh has no nodes")
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    points = coords.reshape(-1, 3)
    blocks = []
    for order, etype in _GMSH_TET.items():
        _, nodes = gmsh.model.mesh.getElementsByType(etype)
        if len(nodes):
            tets = index[nodes.astype(np.int64)].reshape(-1, 4 if order == 1 else 10)
            blocks.append(tets if order == 1 else tets[:, GMSH_TET10])
    if len(blocks) != 1:
        fault = "no tetrahedra in the mesh" if not blocks else "mixed tet4 and tet10 elements"
        raise InputFileError(source, None, fault)
    groups = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, tag) or f"{dim}:{tag}"
        node_tags, _ = gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)
        groups[name] = index[node_tags.astype(np.int64)]
    return canonical_mesh(points, blocks[0], groups, source, mid_nodes_in_order=True)


def _generate(gmsh, order, mesh_size, source, check_limits=True, n_elements=None):
    """Mesh the current (synchronized) model; a ModelError first if it is estimated over
    the limits (from ``n_elements`` tetrahedra if known, else from the mesh size)."""
    if order not in (1, 2):
        raise ModelError(f"element order must be 1 or 2, not {order}")
    if mesh_size is not None:
        gmsh.option.setNumber("Mesh.MeshSizeMax", fe.check_positive("mesh size", mesh_size))
    if check_limits:
        volume, box = model_volume(gmsh), np.array(gmsh.model.getBoundingBox(-1, -1))
        extent = float((box[3:] - box[:3]).max())
        if n_elements is None:
            size = model_mesh_size(gmsh)
            estimate = limits.from_mesh_size(volume, extent, size, order)
            what = f"{source} meshed at element size {size:g} (volume {volume:g})"
        else:
            estimate, what = limits.from_elements(n_elements, order, volume, extent), str(source)
        limits.check(estimate, what)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)  # mid-edge nodes on the geometry
    gmsh.model.mesh.generate(3)
    if order == 2:
        gmsh.model.mesh.setOrder(2)
        _repair_curved_elements(gmsh, source)


def _repair_curved_elements(gmsh, source):
    """Make the curved tet10 of the current mesh valid, or a ModelError.

    A tetrahedron whose mid-edge nodes were moved onto a curved surface may fold over
    (its Jacobian determinant det J changes sign inside it), e.g. where the surface
    bends by more than an element is thick. det J is evaluated at the ten nodes of each
    element (:func:`inverted_elements`); if any element is inverted, gmsh's elastic
    analogy (``HighOrderElastic``) moves the inner high-order nodes — those on the
    geometry stay — and the elements are checked again. (gmsh's ``HighOrder``
    optimizer can abort the process on failure, so it is not used.)"""
    mesh = gmsh.model.mesh
    local_nodes = mesh.getElementProperties(_GMSH_TET[2])[4]

    def inverted():
        _, det, _ = mesh.getJacobians(_GMSH_TET[2], local_nodes)
        return inverted_elements(det.reshape(-1, 10))

    if inverted().size:
        mesh.optimize("HighOrderElastic")
        bad = inverted()
        if bad.size:
            tags, nodes = mesh.getElementsByType(_GMSH_TET[2])
            corner = mesh.getNode(int(nodes[10 * bad[0]]))[0]
            raise ModelError(f"{source}: {bad.size} of {len(tags)} second-order tetrahedra are inverted by "
                             f"placing their mid-edge nodes on the curved geometry (the first has a corner at "
                             f"({', '.join(f'{v:g}' for v in corner)})); use a smaller mesh size or order 1")


def inverted_elements(det) -> np.ndarray:
    """Indices of the elements whose Jacobian determinants ``det`` (E, n) — det J at
    n points of each element — are not all of one strict sign: a sign change or zero
    means the element's map folds over (inverted or degenerate), whatever its
    orientation."""
    det = np.asarray(det, dtype=float)
    return np.flatnonzero(~(np.all(det > 0, axis=1) | np.all(det < 0, axis=1)))


def model_volume(gmsh) -> float:
    """Volume of the current model: the sum of its OpenCASCADE volumes, or, for the
    built-in kernel (which cannot tell without a mesh), its bounding box's volume."""
    occ = gmsh.model.occ.getEntities(3)
    if occ and len(occ) == len(gmsh.model.getEntities(3)):
        return float(sum(gmsh.model.occ.getMass(dim, tag) for dim, tag in occ))
    if not gmsh.model.getEntities(3):
        return 0.0
    box = np.array(gmsh.model.getBoundingBox(-1, -1))
    return float(np.prod(box[3:] - box[:3]))


def model_mesh_size(gmsh) -> float:
    """The smallest element size gmsh will aim at in the current model: the smallest
    size given at a point (when ``Mesh.MeshSizeFromPoints``) — else a tenth of the
    model's diagonal, about gmsh's default — clipped to [``Mesh.MeshSizeMin``,
    ``Mesh.MeshSizeMax``] and times ``Mesh.MeshSizeFactor``. Size fields and sizes from
    curvature are not seen."""
    option = gmsh.option.getNumber
    points = gmsh.model.getEntities(0)
    given = gmsh.model.mesh.getSizes(points) if points and option("Mesh.MeshSizeFromPoints") else []
    given = [s for s in given if s > 0]
    box = np.array(gmsh.model.getBoundingBox(-1, -1)) if points else np.zeros(6)
    size = min(given) if given else 0.1 * float(np.linalg.norm(box[3:] - box[:3]))
    size = min(max(size, option("Mesh.MeshSizeMin")), option("Mesh.MeshSizeMax"))
    return size * option("Mesh.MeshSizeFactor")


def mesh_geo_file(path, order=2, mesh_size=None, check_limits=True) -> Mesh:
    """Mesh a gmsh ``.geo`` file with tetrahedra of ``order`` and maximum size ``mesh_size``.

    ``check_limits``: refuse a ``Mesh`` command in the file and an estimated mesh over
    the limits of :mod:`preprocess.limits` (ModelError) before meshing."""
    path = Path(path)
    check_geo_file(path, check_limits)
    with gmsh_session() as gmsh:
        try:
            gmsh.open(str(path))
            _generate(gmsh, order, mesh_size, path, check_limits)
        except ModelError:
            raise
        except Exception as exc:  # gmsh reports parse and meshing errors as Exception
            raise InputFileError(path, None, f"gmsh: {exc}") from None
        return mesh_from_gmsh_model(gmsh, path)


BOX_GROW = 1e-6            # a face lies in a selection box grown by this x the model's size, plus this


def mesh_cad_file(path, order=2, mesh_size=None, check_limits=True, length_unit="m", face_boxes=None) -> Mesh:
    """Mesh the solids of a STEP or IGES file (:data:`preprocess.mesh_files.CAD_SUFFIXES`, gmsh's
    OpenCASCADE reader) with tetrahedra of ``order`` and maximum size ``mesh_size`` (in
    ``length_unit``).

    Coordinates are converted from the file's own length unit to ``length_unit`` ("m" or
    "mm", the run's unit system): OpenCASCADE reads the file in mm (:func:`_import_cad`),
    gmsh meshes it in mm (``mesh_size`` converted), and the mesh is scaled by
    :data:`UNIT_PER_MM` (scaling the CAD model instead would turn its planes and
    cylinders into B-spline surfaces). Node groups:

    * the names the file gives its entities (STEP labels: a product, a face, ...), each
      named by the last part of its label path — ``Shapes/bracket`` gives ``bracket``;
    * ``face_boxes`` {name: (xmin, ymin, zmin, xmax, ymax, zmax)} (``length_unit``): the
      faces whose bounding box lies inside the box, grown by BOX_GROW x the model's size
      plus BOX_GROW, in mm (OpenCASCADE's bounding boxes carry a tolerance); a ModelError
      names a box that holds no face. They replace a file name of the same name;
    * the bounding planes ``x0 .. z1`` of :func:`bounding_face_groups` that hold a face
      of the mesh (a surface triangle with all its corners on the plane), and ``body``.

    A file of faces only (IGES mostly is) is sewn into the solid they bound
    (:func:`_solid_from_faces`); one whose faces bound none is an InputFileError.
    ``check_limits`` as for :func:`box`."""
    path, scale = Path(path), UNIT_PER_MM[length_unit]
    with gmsh_session() as gmsh:
        _import_cad(gmsh, path)
        if not gmsh.model.getEntities(3):
            _solid_from_faces(gmsh, path)
        _cad_groups(gmsh, path, face_boxes or {}, scale)
        try:
            _generate(gmsh, order, None if mesh_size is None else mesh_size / scale, path, check_limits)
        except ModelError:
            raise
        except Exception as exc:
            raise InputFileError(path, None, f"gmsh cannot mesh the CAD solid: {exc}") from None
        mesh = mesh_from_gmsh_model(gmsh, path).scaled(scale)
    for name, nodes in face_planes(mesh).items():
        mesh.node_groups.setdefault(name, nodes)
    return mesh


#: the run's length unit per millimetre, OpenCASCADE's unit of imported CAD files
UNIT_PER_MM = {"m": 1e-3, "mm": 1.0}


def _import_cad(gmsh, path):
    """Import the CAD file ``path`` into the current model, in millimetres: OpenCASCADE
    converts the file's unit to its default target unit, mm, which ffrmbs never changes
    (``Geometry.OCCTargetUnit`` would stay set for the whole process, and an IGES file
    cannot take it before a STEP file was read)."""
    try:
        gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
    except Exception as exc:  # gmsh raises a bare Exception with its log line
        raise InputFileError(path, None, f"gmsh cannot read the CAD file: {exc}") from None


def _solid_from_faces(gmsh, path):
    """Make the solid of a CAD model given by its faces only (as IGES files mostly are):
    the faces sewn into one closed shell (OpenCASCADE's sewing, within its tolerance),
    the solid it bounds replacing them. An InputFileError when there are no faces or
    they do not close."""
    faces = gmsh.model.getEntities(2)
    fault = "no solid in the CAD file, and no faces that bound one (a wire model?)"
    if faces:
        try:
            shell = gmsh.model.occ.addSurfaceLoop([tag for _, tag in faces], sewing=True)
            solid = gmsh.model.occ.addVolume([shell])
            gmsh.model.occ.remove(faces, recursive=True)
            gmsh.model.occ.synchronize()
            if gmsh.model.occ.getMass(3, solid) > 0:
                return
        except Exception:  # gmsh raises a bare Exception when the faces do not close
            pass
        fault = (f"no solid in the CAD file, and the {len(faces)} face(s) in it do not close into one "
                 "(an open surface?)")
    raise InputFileError(path, None, f"{fault}: ffrmbs meshes volumes with tetrahedra")


def _cad_groups(gmsh, path, face_boxes, scale):
    """Physical groups of the imported CAD model (in mm): its entities' names, then the
    faces inside each of ``face_boxes`` (in the run's unit, ``scale`` of them per mm;
    :func:`mesh_cad_file`)."""
    named = {}
    for dim, tag in gmsh.model.getEntities():
        label = gmsh.model.getEntityName(dim, tag).rstrip("/").rpartition("/")[2].strip()
        if label and label not in face_boxes:
            named.setdefault((label, dim), []).append(tag)
    for (label, dim), tags in named.items():
        gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, tags), label)
    box = np.array(gmsh.model.getBoundingBox(-1, -1))
    grow = BOX_GROW * (1.0 + float(np.linalg.norm(box[3:] - box[:3])))
    for name, corners in face_boxes.items():
        corners_mm = np.asarray(corners, dtype=float) / scale
        faces = [tag for _, tag in gmsh.model.getEntitiesInBoundingBox(*(corners_mm[:3] - grow),
                                                                        *(corners_mm[3:] + grow), dim=2)]
        if not faces:
            extent = ", ".join(f"{v * scale:g}" for v in box)
            raise ModelError(f"{path}: group {name!r}: no face lies inside the box "
                             f"{', '.join(f'{v:g}' for v in corners)} (the model spans {extent})")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, faces), name)


def face_planes(mesh: Mesh) -> dict:
    """The bounding-plane groups ``x0`` to ``z1`` of :func:`bounding_face_groups` that hold a
    face of ``mesh`` (a surface triangle with its three corners on the plane), and ``body``."""
    corners = mesh.surface_triangles()[:, :3]
    groups = {}
    for name, nodes in bounding_face_groups(mesh.points).items():
        on_plane = np.isin(corners, nodes).all(axis=1)
        if name == "body" or on_plane.any():
            groups[name] = nodes
    return groups


_GEO_COMMENT = re.compile(r"//[^\n]*|/\*.*?\*/", re.DOTALL)
_GEO_READS = re.compile(r'\b(?:Merge|Include|ShapeFromFile)\s*\(?\s*"([^"]*)"')
_GEO_MESH = re.compile(r"^[ \t]*Mesh[ \t]+[123][ \t]*;", re.MULTILINE)


def check_geo_file(path, check_limits=True) -> None:
    """InputFileError if the ``.geo`` file ``path`` or a file it reads (``Merge "…"``,
    ``Include "…"``, ``ShapeFromFile("…")``, relative to the reading file's folder,
    ``.geo`` files followed at any depth) is not a regular file; with ``check_limits``
    also if one holds a ``Mesh 1|2|3;`` command (it would mesh while gmsh reads the
    file, before the mesh size is checked). File names built by expressions
    (``StrCat``) are not seen."""
    def reads(current, text):
        text = _GEO_COMMENT.sub(lambda m: "\n" * m[0].count("\n"), text)
        command = _GEO_MESH.search(text)
        if check_limits and command:
            raise InputFileError(current, text.count("\n", 0, command.start()) + 1,
                                 f"{quote(command[0].strip())} meshes while gmsh reads the file, before its size is "
                                 f"checked; remove it (ffrmbs preprocess meshes the file) or {limits.LIFT}")
        for name in _GEO_READS.findall(text):
            read = regular_file(current.parent / name)
            if read.suffix.lower() == ".geo":
                yield read

    for _ in include_tree(path, reads):
        pass

def bounding_face_groups(points) -> dict:
    """Node groups on the six bounding planes of ``points`` (N, 3) and ``body``.

    ``x0`` holds the nodes with x = min x, ``x1`` those with x = max x, likewise
    ``y0 .. z1``; ``body`` holds all nodes. A node lies on a plane when its coordinate
    is within PLANE_RTOL x the body's size (its largest extent or coordinate, whichever
    is larger) of it: the rounding of node placement, far below any element size.
    """
    points = np.asarray(points, dtype=float)
    lo, hi = points.min(axis=0), points.max(axis=0)
    tol = PLANE_RTOL * max(float((hi - lo).max()), float(np.abs(points).max()))
    groups = {}
    for axis, name in enumerate("xyz"):
        for side, value in (("0", lo[axis]), ("1", hi[axis])):
            groups[name + side] = np.flatnonzero(np.abs(points[:, axis] - value) <= tol)
    groups["body"] = np.arange(len(points))
    return groups


def _set_transfinite_box(gmsh, divisions):
    """Transfinite curves / surfaces / volume of a box: ``divisions[a]`` element edges along axis a."""
    for dim, tag in gmsh.model.getEntities(1):
        bb = np.array(gmsh.model.getBoundingBox(dim, tag))
        axis = int(np.argmax(bb[3:] - bb[:3]))
        gmsh.model.mesh.setTransfiniteCurve(tag, divisions[axis] + 1)
    for dim, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
    for dim, tag in gmsh.model.getEntities(3):
        gmsh.model.mesh.setTransfiniteVolume(tag)


def _mesh_occ(name, build, mesh_size, order, divisions=None, check_limits=True, groups=None,
              planes=("x0", "x1", "y0", "y1", "z0", "z1")) -> Mesh:
    """Mesh the OpenCASCADE model made by ``build(occ)``; ``groups(gmsh)`` (after the
    model is synchronized) adds its physical groups, which become node groups; the
    bounding-plane groups named in ``planes`` (:func:`bounding_face_groups`) and
    ``body`` are added to them."""
    source = f"<builtin {name}>"
    with gmsh_session() as gmsh:
        gmsh.model.add(name)
        build(gmsh.model.occ)
        gmsh.model.occ.synchronize()
        if groups is not None:
            groups(gmsh)
        if divisions is not None:
            _set_transfinite_box(gmsh, divisions)
        _generate(gmsh, order, mesh_size, source, check_limits,   # structured: 6 tetrahedra per cell
                  None if divisions is None else 6 * math.prod(divisions))
        mesh = mesh_from_gmsh_model(gmsh, source)
    mesh.node_groups.update({name: nodes for name, nodes in bounding_face_groups(mesh.points).items()
                             if name in planes or name == "body"})
    return mesh


def _physical_groups(gmsh, dim, name_of, expected):
    """One named physical group per name that ``name_of(tag)`` (a name, or None for
    none) gives the model's entities of dimension ``dim``. A ModelError if a name in
    ``expected`` found no entity (OpenCASCADE made another shape than expected)."""
    tags = {}
    for _, tag in gmsh.model.getEntities(dim):
        name = name_of(tag)
        if name is not None:
            tags.setdefault(name, []).append(tag)
    missing = sorted(set(expected) - set(tags))
    if missing:
        raise ModelError(f"built-in {gmsh.model.getCurrent()}: no {dim}-d entity for the group(s) "
                         f"{', '.join(missing)} (OpenCASCADE made another shape)")
    for name, members in tags.items():
        gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, members), name)


def _centre(gmsh, dim, tag):
    """Centre of mass (3,) of the entity (dim, tag) of the OpenCASCADE model."""
    return np.array(gmsh.model.occ.getCenterOfMass(dim, tag))


def box(lx, ly, lz, mesh_size, order=2, divisions=None, check_limits=True) -> Mesh:
    """Cuboid [0, lx] x [0, ly] x [0, lz] meshed with tetrahedra of maximum size ``mesh_size``.

    The report's beam is ``box(1, 1, 5, 0.5)`` (report Table 1: 579 nodes, 426 surface
    nodes, 254 tet10 with gmsh).

    ``divisions=(nx, ny, nz)`` (positive ints, element edges per axis) meshes the box
    structured instead (gmsh transfinite curves, surfaces and volume, still tetrahedra;
    ``mesh_size`` is then ignored and may be None). The vertices then lie on the grid
    ``x_i = i lx / nx`` (i = 0..nx), likewise in y and z, so every face's nodes form a
    regular grid: (n_a + 1) x (n_b + 1) levels for order 1, (2 n_a + 1) x (2 n_b + 1)
    with the mid-edge nodes of order 2 (the edges' midpoints, the faces being flat) — the
    node matrix O of thesis eq. 3.24 (see :func:`contours.node_grid.node_matrix`).

    ``check_limits``: a mesh estimated over the limits of :mod:`preprocess.limits` is a
    ModelError before meshing.
    """
    for name, length in (("box length lx", lx), ("box length ly", ly), ("box length lz", lz)):
        fe.check_positive(name, length)
    if divisions is not None:
        divisions = _check_divisions(divisions)
    return _mesh_occ("box", lambda occ: occ.addBox(0, 0, 0, lx, ly, lz), mesh_size, order, divisions,
                     check_limits)


def _check_divisions(divisions):
    try:
        items = list(divisions)
    except TypeError:
        items = None
    ok = items is not None and len(items) == 3 and all(
        isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 1 for n in items)
    if not ok:
        raise ModelError(f"divisions must be three integers >= 1 (element edges along x, y, z), "
                         f"not {divisions!r}")
    return tuple(int(n) for n in items)


def stepped_beam(mesh_size, order=2, l=95.0, h1=10.0, h2=34.2, w1=20.0, w2=9.74, base=10.0,
                 check_limits=True) -> Mesh:
    """Our reading of the thesis's complex beam (thesis Sec. 5.1, Fig. 5.1), in mm.

    The figure is not in the text. What the text fixes: the dimensions l, h1, h2,
    w1, w2; the body frame at the left bottom corner (ū0 = 0 there); the left side
    clamped; and Listing 4.1, whose first nodes lie at x = 95 and 105 mm with
    y in [0, 10] = [0, h1] and z in [5.13, 14.87], i.e. the width w2 = 9.74 centred
    in w1 = 20. Our reading: a base block of length ``base`` = 105 − 95 = 10 along x
    with cross-section h2 x w1 (y x z), then the slender part of length l with
    cross-section h1 x w2, flush with the bottom (y in [0, h1]) and centred in z,
    ending at x = base + l = 105. Clamp the face x = 0 (node group ``x0``).

    Other readings tried (block 0..95 with a 10 mm tip; slender 0..95 with the
    block at the tip) match the thesis's ABAQUS frequencies no better; its ratio
    f2/f1 = 2.0 suggests a cross-section of about 20 x 9.74 mm that the text does
    not describe. Treat frequency differences to the thesis as geometry, not error.

    ``check_limits`` as for :func:`box`.
    """
    zc = (w1 - w2) / 2.0

    def build(occ):
        a = occ.addBox(0, 0, 0, base, h2, w1)
        b = occ.addBox(base, 0, zc, l, h1, w2)
        occ.fuse([(3, a)], [(3, b)])

    return _mesh_occ("stepped_beam", build, mesh_size, order, check_limits=check_limits)


def cylinder(radius, length, mesh_size, order=2, check_limits=True) -> Mesh:
    """Solid circular cylinder x² + y² <= radius², 0 <= z <= length, meshed with
    tetrahedra of maximum size ``mesh_size`` (lengths in any one unit).

    Node groups (the nodes of each surface's or curve's mesh, mid-edge nodes included,
    which order 2 places on the exact surface): ``lateral`` — the closed curved surface
    x² + y² = radius²; ``end0``, ``end1`` — the flat ends z = 0 and z = length (also
    named ``z0``, ``z1`` as for a box); ``rim0``, ``rim1`` — the circles
    x² + y² = radius² at z = 0 and z = length; ``body``.

    ``check_limits`` as for :func:`box`.
    """
    fe.check_positive("cylinder radius", radius)
    fe.check_positive("cylinder length", length)

    def groups(gmsh):
        def face(tag):
            if gmsh.model.getType(2, tag) == "Cylinder":
                return "lateral"
            return "end0" if _centre(gmsh, 2, tag)[2] < length / 2 else "end1"

        def rim(tag):
            if gmsh.model.getType(1, tag) != "Circle":
                return None                               # the lateral surface's seam
            return "rim0" if _centre(gmsh, 1, tag)[2] < length / 2 else "rim1"

        _physical_groups(gmsh, 2, face, ("lateral", "end0", "end1"))
        _physical_groups(gmsh, 1, rim, ("rim0", "rim1"))

    return _mesh_occ("cylinder", lambda occ: occ.addCylinder(0, 0, 0, 0, 0, length, radius), mesh_size, order,
                     check_limits=check_limits, groups=groups, planes=("z0", "z1"))


def spherical_cap(radius, height, mesh_size, order=2, check_limits=True) -> Mesh:
    """The solid cut from the ball x² + y² + z² <= radius² by the plane
    z = radius − height: the cap radius − height <= z <= radius, 0 < height < 2 radius,
    meshed with tetrahedra of maximum size ``mesh_size``.

    Node groups (mid-edge nodes included, on the exact surface for order 2): ``cap`` —
    the curved surface x² + y² + z² = radius², z >= radius − height; ``base`` — the flat
    disk z = radius − height, x² + y² <= radius² − (radius − height)² (also ``z0``);
    ``body``.

    ``check_limits`` as for :func:`box`.
    """
    check_cap_dimensions(radius, height)

    def groups(gmsh):
        _physical_groups(gmsh, 2, lambda tag: "cap" if gmsh.model.getType(2, tag) == "Sphere" else "base",
                         ("cap", "base"))

    polar = math.asin((radius - height) / radius)     # latitude of the cutting plane
    return _mesh_occ("spherical_cap", lambda occ: occ.addSphere(0, 0, 0, radius, angle1=polar), mesh_size, order,
                     check_limits=check_limits, groups=groups, planes=("z0",))


def check_cap_dimensions(radius, height) -> None:
    """ModelError unless the radius and height of :func:`spherical_cap` are positive and
    finite, height < 2 radius."""
    fe.check_positive("cap radius", radius)
    fe.check_positive("cap height", height)
    if not height < 2 * radius:
        raise ModelError(f"cap height must be below twice the radius ({2 * radius:g}), not {height!r}")


def check_groove_dimensions(lx, ly, lz, radius) -> None:
    """ModelError unless the dimensions of :func:`grooved_block` are positive and finite,
    radius < min(ly/2, lz)."""
    for name, length in (("block length lx", lx), ("block length ly", ly), ("block length lz", lz),
                         ("groove radius", radius)):
        fe.check_positive(name, length)
    if not radius < min(ly / 2, lz):
        raise ModelError(f"groove radius must be below min(ly/2, lz) = {min(ly / 2, lz):g}, not {radius!r}")


def grooved_block(lx, ly, lz, radius, mesh_size, order=2, check_limits=True) -> Mesh:
    """The block [0, lx] x [0, ly] x [0, lz] with a half-cylinder channel cut into its
    top face z = lz, meshed with tetrahedra of maximum size ``mesh_size``.

    The channel's axis runs along x at y = ly/2, z = lz; its surface (the groove) is
    exactly (y − ly/2)² + (z − lz)² = radius², 0 <= x <= lx, z <= lz, a half cylinder
    from z = lz − radius to lz. ``radius`` < min(ly/2, lz), so that the top face keeps
    two strips and the block one piece.

    Node groups (mid-edge nodes included, on the exact surface for order 2):
    ``groove``; ``bottom`` — the face z = 0; the bounding planes ``x0 .. z1`` of
    :func:`bounding_face_groups` (``z1`` is the two strips of the top face); ``body``.

    ``check_limits`` as for :func:`box`.
    """
    check_groove_dimensions(lx, ly, lz, radius)

    def build(occ):
        block = occ.addBox(0, 0, 0, lx, ly, lz)
        occ.cut([(3, block)], [(3, occ.addCylinder(0, ly / 2, lz, lx, 0, 0, radius))])

    def groups(gmsh):
        def face(tag):
            if gmsh.model.getType(2, tag) == "Cylinder":
                return "groove"
            return "bottom" if gmsh.model.getBoundingBox(2, tag)[5] < lz / 2 else None   # top z below lz/2

        _physical_groups(gmsh, 2, face, ("groove", "bottom"))

    return _mesh_occ("grooved_block", build, mesh_size, order, check_limits=check_limits, groups=groups)
