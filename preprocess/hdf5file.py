"""The HDF5 body file: one :class:`~preprocess.body.BodyData` in one file, SI units.

It holds the four text files' data (thesis Sec. 4.2.1) plus what they cannot:
eigenvalues, node groups, surface triangles, material, preprocessing params and the
consistent mass matrix.

Layout (N nodes, n_f modes, indices 0-based)::

    /                      attrs: format = "ffrmbs-body", format_version = 1,
                                  units = "si", params = JSON string of BodyData.params
    /u0                    (N, 3) f8        undeformed node positions [m]
    /phi                   (3N, n_f) f8     mode shapes, row 3i+k = node i, DOF k [kg^-1/2]
    /masses                (N,) f8          lumped node masses [kg], > 0
    /stiffness/            group, attr shape = (3N, 3N): K [N/m] in CSR form
        data               (nnz,) f8
        indices            (nnz,) i8        column indices
        indptr             (3N+1,) i8       row pointers
    /mass_matrix/          group, attr shape = (N, N): the scalar consistent mass matrix
                           M_s [kg] (M_FE = M_s ⊗ 1₃) in CSR form, datasets as
                           /stiffness; symmetric, positive diagonal   (optional:
                           absent means lumped masses, BodyData.mass_matrix None)
    /eigenvalues           (n_f,) f8        ω² [rad²/s²]            (optional)
    /node_groups/<name>    (n,) i8          node indices of the group (one dataset per group)
    /surface/triangles     (T, 3|6) i8      surface faces            (optional)
    /material              group, attrs density [kg/m³], young [Pa], poisson [-] (those known)
    /geometric_stiffness   (12, n_f, n_f) f8  Φᵀ K_σ,c Φ of the inertia load cases of
                                            :mod:`preprocess.geometric`      (optional)

:func:`read_hdf5` checks the format attributes, the presence, shape, type and
finiteness of every dataset, magnitudes (at most :data:`~preprocess.body.MAX_MAGNITUDE`),
index ranges, the symmetry of K and of M_s and M_s's positive diagonal; any fault
(also a file that is not a regular HDF5 file) raises :class:`~ffrmbs.errors.InputFileError` naming the dataset.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import scipy.sparse as sp

from ffrmbs.errors import InputFileError, ModelError, quote
from preprocess.body import MAX_MAGNITUDE, SYMMETRY_RTOL, BodyData
from preprocess.inputfiles import regular_file

FORMAT = "ffrmbs-body"
FORMAT_VERSION = 1


def write_hdf5(path, body: BodyData) -> None:
    """Write ``body`` to the HDF5 file ``path`` (overwritten) in the layout above."""
    bad = [name for name in body.node_groups if "/" in name or name in ("", ".")]
    if bad:
        raise ModelError(f"node group names unusable in HDF5: {bad}")
    with h5py.File(path, "w") as f:
        f.attrs.update(format=FORMAT, format_version=FORMAT_VERSION, units="si",
                       params=json.dumps(body.params))
        f["u0"] = np.asarray(body.u0, dtype="f8")
        f["phi"] = np.asarray(body.phi, dtype="f8")
        f["masses"] = np.asarray(body.masses, dtype="f8")
        _write_csr(f, "stiffness", body.stiffness)
        if body.mass_matrix is not None:
            _write_csr(f, "mass_matrix", body.mass_matrix)
        if body.eigenvalues is not None:
            f["eigenvalues"] = np.asarray(body.eigenvalues, dtype="f8")
        groups = f.create_group("node_groups")
        for name, nodes in body.node_groups.items():
            groups[name] = np.asarray(nodes, dtype="i8")
        if body.surface_triangles is not None:
            f["surface/triangles"] = np.asarray(body.surface_triangles, dtype="i8")
        if body.geometric_stiffness is not None:
            f["geometric_stiffness"] = np.asarray(body.geometric_stiffness, dtype="f8")
        f.create_group("material").attrs.update(
            {key: float(value) for key, value in body.material.items()})


def _write_csr(f: h5py.File, name: str, matrix) -> None:
    """Group ``name`` holding the sparse ``matrix`` in CSR form (attr shape, data, indices, indptr)."""
    a = sp.csr_matrix(matrix).sorted_indices()
    group = f.create_group(name)
    group.attrs["shape"] = np.asarray(a.shape, dtype="i8")
    group["data"] = a.data.astype("f8")
    group["indices"] = a.indices.astype("i8")
    group["indptr"] = a.indptr.astype("i8")


class _Reader:
    """Checked access to the datasets of one open body file."""

    def __init__(self, f: h5py.File, path: Path):
        self.f = f
        self.path = path

    def fail(self, fault: str):
        raise InputFileError(self.path, None, fault)

    def array(self, name: str, integer: bool = False, shape: tuple = ()) -> np.ndarray:
        """Dataset ``name`` as f8 (or i8) array of ``shape`` (None = any length)."""
        obj = self.f.get(name)
        if not isinstance(obj, h5py.Dataset):
            self.fail(f"missing dataset '{name}'")
        a = obj[()]
        kinds = "iu" if integer else "iuf"
        if not isinstance(a, np.ndarray) or a.dtype.kind not in kinds or a.ndim != len(shape) \
                or any(s is not None and s != n for s, n in zip(shape, a.shape)):
            want = "x".join("?" if s is None else str(s) for s in shape)
            kind = "integer" if integer else "numeric"
            self.fail(f"dataset '{name}' must be a {kind} array of shape ({want}), "
                      f"found {getattr(a, 'dtype', type(a))} {getattr(a, 'shape', ())}")
        if integer:
            return a.astype(np.int64)
        if not np.isfinite(a).all():
            self.fail(f"dataset '{name}' contains NaN or inf")
        if a.size and np.abs(a).max() > MAX_MAGNITUDE:
            self.fail(f"dataset '{name}' holds values out of range (|value| > {MAX_MAGNITUDE:g})")
        return a.astype(np.float64)

    def indices(self, name: str, n_nodes: int, shape: tuple) -> np.ndarray:
        """Integer dataset of node indices, checked against 0..n_nodes-1."""
        a = self.array(name, integer=True, shape=shape)
        if a.size and (a.min() < 0 or a.max() >= n_nodes):
            self.fail(f"dataset '{name}' has node indices outside 0..{n_nodes - 1}")
        return a

    def group(self, name: str, required: bool = False) -> h5py.Group | None:
        """Group ``name``, or None if absent and not required."""
        obj = self.f.get(name)
        if obj is None and not required:
            return None
        if not isinstance(obj, h5py.Group):
            self.fail(f"missing group '{name}'")
        return obj

    def text_attr(self, name: str) -> str:
        value = self.f.attrs.get(name)
        return value.decode() if isinstance(value, bytes) else value


def _symmetric_csr(r: _Reader, name: str, n: int, label: str, symbol: str) -> sp.csr_matrix:
    """The symmetric CSR matrix (n, n) of group ``name`` (the ``label`` ``symbol`` in messages)."""
    shape = tuple(np.asarray(r.group(name, required=True).attrs.get("shape", ())).tolist())
    if shape != (n, n):
        r.fail(f"group '{name}' must have attribute shape = ({n}, {n}), found {shape}")
    parts = (r.array(f"{name}/data", shape=(None,)),
             r.array(f"{name}/indices", integer=True, shape=(None,)),
             r.array(f"{name}/indptr", integer=True, shape=(n + 1,)))
    try:
        k = sp.csr_matrix(parts, shape=shape)
        k.check_format(full_check=True)
    except ValueError as exc:
        r.fail(f"group '{name}' is not a valid CSR matrix: {exc}")
    if k.nnz and abs(k - k.T).max() > SYMMETRY_RTOL * abs(k).max():
        r.fail(f"the {label} in group '{name}' is not symmetric "
               f"(relative tolerance {SYMMETRY_RTOL:g} of max|{symbol}|)")
    return k


def _stiffness(r: _Reader, n_dof: int) -> sp.csr_matrix:
    """The CSR stiffness matrix of group 'stiffness', shape (n_dof, n_dof)."""
    return _symmetric_csr(r, "stiffness", n_dof, "stiffness matrix", "K")


def _mass_matrix(r: _Reader, n: int) -> sp.csr_matrix | None:
    """The scalar consistent mass matrix M_s (n, n) of the optional group 'mass_matrix'
    (None when absent), symmetric with a positive diagonal."""
    if "mass_matrix" not in r.f:
        return None
    m = _symmetric_csr(r, "mass_matrix", n, "mass matrix", "M_s")
    if not (m.diagonal() > 0).all():
        r.fail("the mass matrix in group 'mass_matrix' has a non-positive diagonal entry")
    return m


def _read(r: _Reader) -> BodyData:
    if r.text_attr("format") != FORMAT:
        r.fail(f"not an ffrmbs body file (root attribute 'format' is not '{FORMAT}')")
    if r.f.attrs.get("format_version") != FORMAT_VERSION:
        r.fail(f"unsupported format_version {quote(str(r.f.attrs.get('format_version')))}, "
               f"expected {FORMAT_VERSION}")
    if r.text_attr("units") != "si":
        r.fail(f"unsupported units {quote(str(r.text_attr('units')))}, expected 'si'")
    u0 = r.array("u0", shape=(None, 3))
    n = u0.shape[0]
    masses = r.array("masses", shape=(n,))
    if (masses <= 0).any():
        r.fail("dataset 'masses' holds non-positive masses")
    phi = r.array("phi", shape=(3 * n, None))
    stiffness = _stiffness(r, 3 * n)
    mass_matrix = _mass_matrix(r, n)
    eigenvalues = (r.array("eigenvalues", shape=(phi.shape[1],)) if "eigenvalues" in r.f
                   else None)
    groups = r.group("node_groups")
    node_groups = {} if groups is None else {
        name: r.indices(f"node_groups/{name}", n, (None,)) for name in groups}
    surface = None
    if "surface" in r.f:
        surface = r.indices("surface/triangles", n, (None, None))
        if surface.shape[1] not in (3, 6):
            r.fail("dataset 'surface/triangles' must have 3 or 6 columns, "
                   f"found {surface.shape[1]}")
    material_group = r.group("material")
    try:
        material = {} if material_group is None else {
            key: float(value) for key, value in material_group.attrs.items()}
    except (TypeError, ValueError):
        r.fail("group 'material' has a non-numeric attribute")
    try:
        params = json.loads(r.text_attr("params") or "{}")
    except (TypeError, ValueError):
        params = None
    if not isinstance(params, dict):
        r.fail("root attribute 'params' is not a JSON object string")
    geometric = (r.array("geometric_stiffness", shape=(12, phi.shape[1], phi.shape[1]))
                 if "geometric_stiffness" in r.f else None)
    return BodyData(u0=u0, phi=phi, masses=masses, stiffness=stiffness, eigenvalues=eigenvalues,
                    mass_matrix=mass_matrix, node_groups=node_groups, surface_triangles=surface, material=material,
                    params=params, geometric_stiffness=geometric)


def read_hdf5(path) -> BodyData:
    """The body stored in the HDF5 file ``path`` (SI units), validated (see module docstring)."""
    path = regular_file(path)
    if not h5py.is_hdf5(path):
        raise InputFileError(path, None, "not an HDF5 file")
    try:
        with h5py.File(path, "r") as f:
            return _read(_Reader(f, path))
    except (OSError, KeyError, TypeError, ValueError, RuntimeError) as exc:
        # h5py raises RuntimeError for some damaged files (e.g. "Link iteration failed")
        raise InputFileError(path, None, f"unreadable HDF5 body file: {exc}") from None
