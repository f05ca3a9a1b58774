"""Result files to ParaView: deformed surfaces, bodies and contact points over time.

:func:`export_paraview` reads an ffrmbs result file (the HDF5 layout of
:mod:`mbs.results.result_file`) and writes, with meshio, one VTK unstructured grid (``.vtu``) per
written sample and series, and ParaView collection files (``.pvd``) that give each file
its time. Open ``<out_dir>/<stem>.pvd`` in ParaView (File > Open, Apply) to see every
series as one multiblock dataset moving with the time slider; each series also has its
own ``<series>/<series>.pvd``.

Series
------
* a body with a ``surface`` group: its surface triangles at the deformed positions
  (thesis eq. 2.24) — linear triangles (VTK ``triangle``) for tet4 bodies, quadratic
  triangles (VTK ``triangle6``: corners, then the mid-edge nodes of edges (c0,c1),
  (c1,c2), (c2,c0), the order of :meth:`preprocess.mesh.Mesh.surface_triangles`) for
  tet10 bodies. Quadratic cells rather than each split into four linear ones: every
  surface node stays one point with its own data, the cells are the FE mesh's own
  faces, and ParaView draws the curved faces of a bent body (nonlinear subdivision)

      x = R + A (ū0 + Φ q_f)      [m]

  with point data ``displacement`` = x − ū0 [m] (from the undeformed FE mesh, the body
  frame at rest at the origin, as the report's displacements u in G),
  ``elastic_displacement`` = A Φ q_f [m] (world axes), its magnitude
  ``elastic_displacement_magnitude`` [m] and ``node`` (the FE node numbers);
* any other body (rigid body, point mass, a flexible body without surface): one vertex at
  its frame origin R [m], with point data ``velocity`` = Ṙ [m/s] for point masses and
  rigid bodies (the first three velocity coordinates, :mod:`mbs.bodies.rigid_body`);
* the contacts (``/contacts``): one vertex per contact at its contact point [m], with
  point data ``force`` [N] (on the second contour's body, world), ``gap`` [m] (NaN while
  no contact point is located), ``normal`` (world; 0 while not located), ``active``
  (1 when closed), ``located`` (1 when the contact point was located at that sample) and
  ``contact`` (the index of the contact, in the file's sorted order, listed in the
  series' ``.pvd`` as a comment). While a contact point is not located the vertex stays
  at the last located point (before the first one: at the first one); a contact never
  located is left out.

File names: ``<out_dir>/<series>/<series>_<k>.vtu`` with ``k`` the sample's index in the
result file; series names are the body names with characters other than letters,
digits, ``_ . -`` replaced by ``_``. The export is written into a temporary directory
beside ``out_dir`` (``.<out_dir name>.tmp-<pid>-…``) and renamed into place, so a failed
or interrupted export (Ctrl-C, SIGTERM) leaves nothing behind; what an export killed
outright (kill -9) left is removed by the next export to the same ``out_dir``
(:func:`remove_stale_exports`). An existing ``out_dir`` is replaced only when it is empty or an earlier export (it holds the
marker file ``.ffrmbs-export``). The ``.vtu`` files are raw binary by default (fast to
write); ``compress=True`` (``ffrmbs export --compress``) zlib-compresses them.

In ParaView: open ``<stem>.pvd``, Apply, press Play; colour the bodies by
``elastic_displacement_magnitude``; show the contact forces with a Glyph filter on the
``contacts`` block (orientation and scale by ``force``).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from xml.sax.saxutils import quoteattr

import h5py
import numpy as np

from ffrmbs.errors import FfrmbsError, InputFileError, OutputFileError, os_reason
from ffrmbs_app.output_dirs import new_directories, remove_stale, temporary_name, terminate_interrupts
from ffrmbs_app.result_reading import check_shape, dataset, group, open_result
from mbs.results.result_file import attribute, damaged_result_file

MARKER = ".ffrmbs-export"
POINT_BODY_VELOCITY = ("PointMass", "RigidBody")   # kinds whose u[:3] is Ṙ (world) [m/s]
TRIANGLE_CELLS = {3: "triangle", 6: "triangle6"}  # VTK cell type of a surface triangle by its node count
_CHUNK_VALUES = 3_000_000      # floats per block of samples held at once (~24 MB per array)


# --------------------------------------------------------------------------- writing


def write_pvd(path, datasets, comment=None):
    """Write a ParaView collection file.

    ``datasets`` are ``(t, file, part, name)`` tuples: time [s], the ``.vtu`` path
    relative to the ``.pvd``, the block index and the block name. Datasets with the same
    time and different parts appear as one multiblock dataset in ParaView.
    """
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">']
    if comment:
        lines.append(f"<!-- {comment.replace('--', '- -')} -->")
    lines.append("  <Collection>")
    for t, file, part, name in datasets:
        lines.append(f'    <DataSet timestep="{float(t)!r}" group="" part="{int(part)}" '
                     f'name={quoteattr(str(name))} file={quoteattr(Path(file).as_posix())}/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    Path(path).write_text("\n".join(lines), encoding="utf-8")


def _series_names(names):
    """File-system-safe, unique series names for ``names`` (order kept)."""
    out, seen = [], {"contacts"}
    for name in names:
        base = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "body"
        safe, i = base, 1
        while safe.lower() in seen:
            i += 1
            safe = f"{base}_{i}"
        seen.add(safe.lower())
        out.append(safe)
    return out


def _write_vtu(path, points, cells, point_data, compress=False):
    """One VTK XML unstructured grid (binary; zlib-compressed when ``compress``)."""
    import meshio

    meshio.write(path, meshio.Mesh(points, cells, point_data=point_data), file_format="vtu",
                 compression="zlib" if compress else None)


def _forward_fill(points, located):
    """Points (n, 3) with the rows where ``located`` is False replaced by the last located
    row (the first located row before it); None when no row is located."""
    if not located.any():
        return None
    idx = np.where(located, np.arange(len(located)), -1)
    idx = np.maximum.accumulate(idx)
    idx[idx < 0] = np.flatnonzero(located)[0]
    return points[idx]


# --------------------------------------------------------------------------- export


def export_paraview(result_path, out_dir=None, every=1, bodies=None, compress=False) -> Path:
    """Export a result file to ParaView: ``.vtu`` files per sample and ``.pvd`` collections.

    Parameters
    ----------
    result_path : str or os.PathLike
        An ffrmbs result file (layout in :mod:`mbs.results.result_file`).
    out_dir : str or os.PathLike, optional
        Output directory; default ``<result stem>-paraview/`` beside the result file.
    every : int
        Export every ``every``-th written sample (samples 0, every, 2 every, ...).
    bodies : iterable of str, optional
        Names of the bodies to export (default: all); contacts are always exported.
    compress : bool
        zlib-compress the ``.vtu`` arrays: about half the disk space for mesh-sized data,
        but five to ten times slower to write (default: raw binary, base64 as VTK XML wants).

    Returns
    -------
    Path
        ``<out_dir>/<result stem>.pvd``, the collection of every series (open it in
        ParaView).

    Raises
    ------
    InputFileError
        The file is not an ffrmbs result file or is damaged, or a group or dataset the
        export needs is missing or malformed; an unknown body name. Nothing is written.
    FfrmbsError
        ``every`` is not a positive integer, or ``out_dir`` exists and is not an earlier
        export.
    OutputFileError
        The export cannot be written (a full disk, no permission); nothing is left behind.
    """
    result_path = Path(result_path)
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise FfrmbsError(f"every must be a positive integer, got {every!r}")
    every = int(every)
    out_dir = Path(out_dir) if out_dir is not None else default_export_dir(result_path)
    out_dir = out_dir.absolute()
    if out_dir.exists() and not _is_export(out_dir):
        raise FfrmbsError(f"{out_dir} exists and is not an ffrmbs export; remove it or choose another output directory")

    with open_result(result_path) as f:
        plan = _plan(f, result_path, bodies)
        remove_stale_exports(out_dir)
        try:
            with terminate_interrupts(), new_directories(out_dir.parent), _temporary_dir(out_dir) as tmp:
                _write_series(tmp, plan, result_path, every, compress)
                _replace_dir(tmp, out_dir)
        except OSError as exc:
            raise OutputFileError(out_dir, f"cannot write the ParaView export: {os_reason(exc)}") from None
    return collection_path(result_path, out_dir)


def collection_path(result_path, out_dir=None) -> Path:
    """``<out_dir>/<result stem>.pvd``: the collection of every series that
    :func:`export_paraview` writes for ``result_path`` (``out_dir`` default
    :func:`default_export_dir`)."""
    result_path = Path(result_path)
    return (default_export_dir(result_path) if out_dir is None else Path(out_dir)) / f"{result_path.stem}.pvd"


def default_export_dir(result_path) -> Path:
    """``<result stem>-paraview/`` beside the result file: where :func:`export_paraview`
    writes by default."""
    result_path = Path(result_path)
    return result_path.with_name(result_path.stem + "-paraview")


def _is_export(out_dir: Path) -> bool:
    """Whether ``out_dir`` is a directory that an export may replace: empty or an earlier export."""
    return out_dir.is_dir() and (not any(out_dir.iterdir()) or (out_dir / MARKER).exists())


def remove_stale_exports(out_dir) -> list:
    """Remove the temporary directories beside ``out_dir`` that exports to it killed
    mid-write left (``.<name>.tmp-<pid>-…`` and ``.<name>.old-<pid>-…`` of ended
    processes, :func:`ffrmbs_app.output_dirs.remove_stale`); returns them."""
    out_dir = Path(out_dir)
    return [p for kind in ("tmp", "old") for p in remove_stale(out_dir.parent, f".{out_dir.name}.{kind}-")]


def remove_export(out_dir) -> None:
    """Remove the export ``out_dir`` (only an earlier ffrmbs export, marked by
    :data:`MARKER`) and what killed exports to it left beside it."""
    out_dir = Path(out_dir)
    if (out_dir / MARKER).exists():
        shutil.rmtree(out_dir)
    remove_stale_exports(out_dir)


@contextmanager
def _temporary_dir(out_dir: Path):
    """A new hidden directory beside ``out_dir`` for the block, removed if the block raises."""
    tmp = Path(tempfile.mkdtemp(prefix=temporary_name(f".{out_dir.name}.tmp-"), dir=out_dir.parent))
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _write_series(tmp: Path, plan, result_path: Path, every, compress) -> None:
    """Write every series of ``plan`` and the main .pvd (:func:`collection_path`) into ``tmp``."""
    from ffrmbs_app.progress import progress_bar

    idx = np.arange(0, plan["n"], every)
    n_files = len(idx) * len(plan["series"])
    width = max(6, len(str(plan["n"] - 1)))
    entries = []
    with progress_bar(n_files, "export", unit="file") as bar:
        for part, series in enumerate(plan["series"]):
            name, label, t = series["name"], series["label"], plan["t"]
            (tmp / name).mkdir()
            own = []
            for k, points, cells, point_data in _read(series["samples"](series, idx), result_path):
                file = f"{name}_{k:0{width}d}.vtu"
                _write_vtu(tmp / name / file, points, cells, point_data, compress)
                own.append((t[k], file, 0, label))
                entries.append((t[k], Path(name) / file, part, label))
                bar.update()
            write_pvd(tmp / name / f"{name}.pvd", own, series.get("comment"))
    entries.sort(key=lambda e: (e[0], e[2]))
    write_pvd(collection_path(result_path, tmp), entries,
              f"ffrmbs export of {result_path.name}: " + ", ".join(s["label"] for s in plan["series"]))
    (tmp / MARKER).write_text(json.dumps({"result": str(result_path.absolute()), "every": every,
                                          "series": [s["name"] for s in plan["series"]]}) + "\n")


def _replace_dir(tmp: Path, out_dir: Path):
    """Move ``tmp`` to ``out_dir``, replacing an earlier export there."""
    if out_dir.exists():
        old = Path(tempfile.mkdtemp(prefix=temporary_name(f".{out_dir.name}.old-"), dir=out_dir.parent))
        old.rmdir()
        os.replace(out_dir, old)
        os.replace(tmp, out_dir)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, out_dir)


def _plan(f, path, bodies):
    """Check the file and list the series to write: dicts with name, label, samples (a
    generator of (k, points, cells, point_data) per sample k), ..."""
    t_ds = f["t"]
    lengths = [t_ds.shape[0]]
    bodies_group = group(f, "bodies", path)
    names = sorted(bodies_group.keys())
    if bodies is not None:
        bodies = [bodies] if isinstance(bodies, str) else list(bodies)
        unknown = [b for b in bodies if b not in bodies_group]
        if unknown:
            raise InputFileError(path, None, f"no body {', '.join(map(repr, unknown))} in the file; "
                                             f"bodies: {', '.join(names) or '(none)'}")
        names = [b for b in names if b in set(bodies)]
    series = []
    for name, safe in zip(names, _series_names(names)):
        g = group(bodies_group, name, path)
        R = dataset(g, "R", path)
        check_shape(R, (None, 3), path)
        lengths.append(R.shape[0])
        entry = dict(name=safe, label=name, group=g)
        if "surface" in g:
            s = group(g, "surface", path)
            u0, phi, tri = (dataset(s, k, path) for k in ("u0", "phi", "triangles"))
            check_shape(u0, (None, 3), path)
            m = u0.shape[0]
            check_shape(phi, (m, 3, None), path)
            if tri.ndim != 2 or tri.shape[1] not in TRIANGLE_CELLS:
                raise InputFileError(path, None, f"{tri.name} has shape {tri.shape}, expected (n, 3) for linear "
                                                 "or (n, 6) for quadratic triangles")
            n_f = phi.shape[2]
            A = dataset(g, "A", path)
            check_shape(A, (None, 3, 3), path)
            lengths.append(A.shape[0])
            if n_f or "q_f" in g:
                q_f = dataset(g, "q_f", path)
                check_shape(q_f, (None, n_f), path)
                lengths.append(q_f.shape[0])
            tri_a = np.asarray(tri[...], dtype=np.int64)
            if tri_a.size and (tri_a.min() < 0 or tri_a.max() >= m):
                raise InputFileError(path, None, f"{tri.name} refers to rows outside 0..{m - 1} of the surface nodes")
            nodes = np.asarray(s["nodes"][...], dtype=np.int64) if "nodes" in s else np.arange(m)
            entry.update(samples=_surface_samples, u0=np.asarray(u0[...], dtype=float),
                         phi=np.asarray(phi[...], dtype=float), triangles=tri_a, nodes=nodes)
        else:
            kind = attribute(g, "kind", "")
            u = g.get("u")
            velocity = kind in POINT_BODY_VELOCITY and isinstance(u, h5py.Dataset) \
                and u.ndim == 2 and u.shape[1] >= 3
            if velocity:
                lengths.append(u.shape[0])
            entry.update(samples=_point_body_samples, velocity=velocity)
        series.append(entry)
    contacts = None
    if "contacts" in f:
        cg_all = group(f, "contacts", path)
        contacts = {}
        for c in sorted(cg_all.keys()):
            cg = group(cg_all, c, path)
            ds = {k: dataset(cg, k, path) for k in ("active", "gap", "point", "normal", "force")}
            for k in ("active", "gap"):
                check_shape(ds[k], (None,), path)
            for k in ("point", "normal", "force"):
                check_shape(ds[k], (None, 3), path)
            lengths += [d.shape[0] for d in ds.values()]
            contacts[c] = ds
    n = min(lengths)
    t = np.asarray(t_ds[:n], dtype=float)
    if contacts:
        data, names = {}, list(contacts)
        for i, (c, ds) in enumerate(contacts.items()):
            point = np.asarray(ds["point"][:n], dtype=float)
            located = np.isfinite(point).all(axis=1)
            filled = _forward_fill(point, located)
            if filled is None:
                continue                                   # never located: nothing to show
            normal = np.asarray(ds["normal"][:n], dtype=float)
            normal[~np.isfinite(normal).all(axis=1)] = 0.0
            data[i] = dict(point=filled, normal=normal, located=located.astype(np.int8),
                           force=np.asarray(ds["force"][:n], dtype=float),
                           gap=np.asarray(ds["gap"][:n], dtype=float),
                           active=np.asarray(ds["active"][:n], dtype=np.int8))
        if data:
            series.append(dict(name="contacts", label="contacts", samples=_contact_samples, contacts=data,
                               comment="contact index: " + ", ".join(f"{i} = {c}" for i, c in enumerate(names))))
    if not series:
        raise InputFileError(path, None, "nothing to export: no bodies and no located contacts")
    if n == 0:
        raise InputFileError(path, None, "no samples written yet")
    return dict(n=n, t=t, series=series)


def _read(samples, path):
    """The items of ``samples`` (a generator reading the result file ``path`` as it goes),
    a failed read being the file's fault (InputFileError: a damaged file), not the
    export's."""
    while True:
        with damaged_result_file(path):
            item = next(samples, None)
        if item is None:
            return
        yield item


def _blocks(idx, per_sample):
    """Split the sample indices ``idx`` (a stride) into blocks of at most
    _CHUNK_VALUES / per_sample samples; yields (slice into the file, the indices)."""
    size = max(1, _CHUNK_VALUES // max(1, per_sample))
    step = int(idx[1] - idx[0]) if len(idx) > 1 else 1
    for i in range(0, len(idx), size):
        block = idx[i:i + size]
        yield slice(int(block[0]), int(block[-1]) + 1, step), block


def _surface_samples(series, idx):
    """The deformed surface x = R + A (ū0 + Φ q_f) per sample (thesis eq. 2.24), read and
    computed by block; yields (k, points, cells, point_data) per sample k of ``idx``."""
    g = series["group"]
    u0, phi, tri, nodes = series["u0"], series["phi"], series["triangles"], series["nodes"]
    n_f = phi.shape[2]
    cells = [(TRIANGLE_CELLS[tri.shape[1]], tri.astype(np.int32) if len(u0) < 2**31 else tri)]
    for sl, block in _blocks(idx, 4 * 3 * len(u0)):
        R = np.asarray(g["R"][sl], dtype=float)                            # (s, 3)
        A = np.asarray(g["A"][sl], dtype=float)                            # (s, 3, 3)
        q_f = np.asarray(g["q_f"][sl], dtype=float) if n_f else np.zeros((len(block), 0))
        elastic = np.einsum("sij,mjf,sf->smi", A, phi, q_f, optimize=True)  # A Φ q_f (s, m, 3)
        x = R[:, None, :] + np.einsum("sij,mj->smi", A, u0) + elastic       # (s, m, 3) [m]
        magnitude = np.linalg.norm(elastic, axis=2)
        for j, k in enumerate(block):
            yield k, x[j], cells, {"displacement": x[j] - u0, "elastic_displacement": elastic[j],
                                   "elastic_displacement_magnitude": magnitude[j], "node": nodes}


def _point_body_samples(series, idx):
    """One vertex at the frame origin R [m] per sample (velocity Ṙ [m/s] when known)."""
    g = series["group"]
    cells = [("vertex", np.zeros((1, 1), dtype=np.int64))]
    for sl, block in _blocks(idx, 6):
        R = np.asarray(g["R"][sl], dtype=float)
        v = np.asarray(g["u"][sl, :3], dtype=float) if series["velocity"] else None
        for j, k in enumerate(block):
            yield k, R[j:j + 1], cells, {} if v is None else {"velocity": v[j:j + 1]}


def _contact_samples(series, idx):
    """One vertex per located contact at its contact point [m], with force [N], gap [m],
    normal, active, located and the contact index as point data."""
    data = series["contacts"]
    ids = np.fromiter(data, dtype=np.int32)
    stacked = {k: np.stack([data[i][k][idx] for i in data], axis=1)   # (samples, contacts, ...)
               for k in ("point", "force", "gap", "normal", "active", "located")}
    pts = stacked.pop("point")
    cells = [("vertex", np.arange(len(ids), dtype=np.int64)[:, None])]
    for j, k in enumerate(idx):
        point_data = {key: np.ascontiguousarray(v[j]) for key, v in stacked.items()}
        point_data["contact"] = ids
        yield k, pts[j], cells, point_data
