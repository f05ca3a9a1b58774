"""Reading a tetrahedral :class:`~preprocess.mesh.Mesh` from a file of any kind: mesh
files are read, geometry files meshed (:func:`read_mesh`).

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

from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, ModelError, quote
from preprocess.abaqus import check_includes, inp_fault
from preprocess.geometry import gmsh_session, mesh_cad_file, mesh_from_gmsh_model, mesh_geo_file
from preprocess.inputfiles import regular_file
from preprocess.mesh import Mesh, canonical_mesh

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
            return mesh_geo_file(path, order, mesh_size, check_limits)
    if suffix in CAD_SUFFIXES:
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
