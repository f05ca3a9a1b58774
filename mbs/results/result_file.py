"""The HDF5 result file, written while the run goes (issue 8).

Layout (format "ffrmbs-result", version 1; SI units; n = samples written so far; every
per-sample dataset is chunked along its first axis, resizable, and grows as the run
goes)::

    /                         attrs: format = "ffrmbs-result", format_version = 1,
                              status = "running" | "complete" | "interrupted" | "failed: <reason>",
                              scene (name), description, integrator, options (JSON),
                              dt, t_end [s], n_out, plan (the printed scene plan, "" if none),
                              versions (JSON: ffrmbs, python, numpy, scipy, numba, h5py),
                              inputs (JSON: {label: {"path": str, "sha256": hex}}),
                              overrides (JSON: the scene file's --set KEY=VALUE texts),
                              summary (JSON, written when the run ends), stats (JSON)
    /t                        (n,) [s] sample times
    /bodies/<body>/           attrs: kind (class name), q_start, q_stop, u_start, u_stop
                                     (the body's slices of the system's q and u), n_modes
        q (n, nq_b), u (n, nu_b)          the body's coordinates and velocities
        R (n, 3) [m], A (n, 3, 3)         its frame's position and orientation (world)
        q_f (n, n_f)                      modal coordinates (flexible bodies)
        surface/                          flexible bodies with surface triangles:
            nodes (m,) int64              FE node numbers of the surface nodes
            u0 (m, 3) [m]                 their undeformed positions in the body frame
            phi (m, 3, n_f)               the body's mode shapes at them
            triangles (k, 3) or (k, 6) int64   rows into ``nodes``: corners (tet4 bodies),
                                          or corners then the mid-edge nodes of edges
                                          (c0,c1), (c1,c2), (c2,c0) (tet10 bodies)
                                          → deformed surface x = R + A (u0 + phi · q_f)
    /energy/kinetic, /energy/potential      (n,) [J]          (when recorded)
    /outputs/<name>           (n, ...) the requested outputs (node positions [m], ...);
                              attrs: units, label (what it is, when the scene says)
    /contacts/<contact>/      attrs: law (class name), set_valued (bool); each dataset
                              says what it is in its ``description`` attribute
                              (:mod:`mbs.results.contact_record`)
        active (n,) int8      closed at the last step's midpoint
        gap (n,) [m]          normal gap of the contact geometry: while closed at the
                              last step's midpoint, g_N + deflection; while open at the
                              sample time (NaN where no contact point exists)
        point (n, 3) [m]      contact point on the second contour (world)
        normal (n, 3)         contact normal (world)
        deflection (n,) [m]   spring deflection of residual flexibility (0 without)
        force (n, 3) [N]      contact force on the first contour's body (world): the
                              impulse of the last step / Δt for set-valued laws
    /trace/<key>              (steps,) per-step records of integrators that keep them
                              (Moreau's ``trace=True``), streamed with the samples

Every dataset has a ``units`` attribute: "s", "m", "m/s", "J", "N", "1" (dimensionless:
orientation matrices, normals, flags, counts, node numbers), for q and u the units of
their blocks (e.g. "m (R, 3), 1 (quaternion, 4), kg^(1/2) m (q_f, 20)"), for the mode
shapes and modal coordinates those of their normalization (:func:`modal_units`), for an
output the unit its scene gives it, else "SI".

Writing: :class:`ResultRecorder` is the driver's recorder (``System.simulate(recorder=)``).
The file is created with every dataset (zero rows) and flushed under a temporary name,
then renamed into place, so it is readable from its first moment. Samples and trace rows
are buffered and appended every ``flush_every`` seconds of wall time, every FLUSH_SAMPLES
samples, at every checkpoint and at the end, then the file is flushed, so a reader — or
a run killed at any moment — finds every sample up to the last flush. Every
``checkpoint_every`` seconds of wall time, at the next output sample, the whole run state
goes to the checkpoint ``<name>.h5.ckpt`` beside the file (:mod:`mbs.results.checkpoint`: arrays,
written atomically), after the samples up to it are in the file. A write that fails (full disk)
stops the run with :class:`~ffrmbs.errors.OutputFileError`, the file's status set to
"failed: …" where the disk still allows; the free space is checked before each flush, as
HDF5 cannot close a file after a failed write (:func:`ensure_space`).
:func:`resume_checkpoint` reads the checkpoint of a killed run (refused if an input file
changed since the run started); the run made again from its inputs and given it
(``System.simulate(checkpoint=…)``) reopens the file, cuts it back to the checkpoint's
samples and trace rows and goes on; the result equals the uninterrupted run's bit for bit
(the state is restored exactly, the computation is deterministic); a result file with
fewer rows than its checkpoint is refused. The checkpoint is removed when the run
completes and kept when it is interrupted or fails.

Reading: :func:`load_result` gives a :class:`~mbs.results.result.Result` and the file's
attributes; a damaged file is an InputFileError (:func:`damaged_result_file`, which the
plot and the ParaView export read through as well).
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import platform
import re
import time
from pathlib import Path

import h5py
import numpy as np

from ffrmbs import __version__
from ffrmbs.errors import InputFileError, OutputFileError, first_line, os_reason
from preprocess.body import mass_normalized
from preprocess.inputfiles import regular_file

from mbs.bodies.body import Frame
from mbs.results.checkpoint import read_checkpoint, write_checkpoint
from mbs.results.contact_record import DESCRIPTIONS as CONTACT_DESCRIPTIONS
from mbs.results.contact_record import FIELDS as CONTACT_FIELDS
from mbs.results.result import Result

FORMAT, FORMAT_VERSION = "ffrmbs-result", 1
CHUNK_ROWS = 256
FLUSH_SAMPLES = CHUNK_ROWS      # buffered samples that force a flush: each flush completes a chunk
HDF5_WRITE_FAILED = re.compile(r"file write failed.*?error message = '([^']*)'", re.S)
SPACE_RESERVE = 1 << 20         # [bytes] kept free on the disk for closing the file cleanly


def versions() -> dict:
    """Versions of ffrmbs and of the libraries that decide its numbers."""
    import numba
    import scipy

    return {"ffrmbs": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__, "h5py": h5py.__version__}


def sha256(path) -> str:
    """Hex SHA-256 of a file, or of every file below a directory (sorted by name)."""
    path = Path(path)
    digest = hashlib.sha256()
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    for f in files:
        if path.is_dir():
            digest.update(str(f.relative_to(path)).encode())
        with open(f, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
    return digest.hexdigest()


def input_hashes(inputs: dict) -> dict:
    """{label: {"path", "sha256"}} of the input files, the path of a file made absolute
    (which file it was, whatever the working directory; built-in sources have no file
    and keep their name)."""
    out = {}
    for label, path in inputs.items():
        p = Path(path)
        out[label] = {"path": str(p.absolute()), "sha256": sha256(p)} if p.exists() else {"path": str(path),
                                                                                         "sha256": None}
    return out


class ResultRecorder:
    """Streams a run's samples to the HDF5 result file ``path`` (layout above) and takes
    checkpoints.

    meta: {"scene", "description", "inputs": {label: path}, "overrides": [KEY=VALUE],
    "units": {output name: unit}}
    (attributes; an output without a unit is "SI"); flush_every [s]: wall time between
    appends of the buffered samples; checkpoint_every [s] or None: wall time between
    checkpoints (taken at output samples).

    A failed write (a full disk, a vanished directory: an ``OSError``) stops the run with
    :class:`~ffrmbs.errors.OutputFileError` naming the file and the system's reason, after
    the file's status is set to "failed: …" and the file is closed (as far as the disk
    still allows).
    """

    def __init__(self, path, meta=None, flush_every=2.0, checkpoint_every=60.0):
        self.path = Path(path)
        self.checkpoint_path = self.path.with_name(self.path.name + ".ckpt")
        self.meta = dict(meta or {})
        self.flush_every = float(flush_every)
        self.checkpoint_every = None if checkpoint_every is None else float(checkpoint_every)
        self.file = None
        self.written = 0            # samples in the file
        self.traced = 0             # trace rows (steps) in the file
        self.checkpoints = 0

    # --- the driver's hooks -----------------------------------------------------------------
    def begin(self, integ):
        """Create the file with its whole layout (every dataset, zero rows), flushed, under
        a temporary name renamed into place: from its first moment under ``path`` the
        file is readable (an older file of the same name is replaced)."""
        part = self.path.with_name(self.path.name + ".part")
        try:
            with self._writing(self.path, "result file"):
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self.checkpoint_path.unlink(missing_ok=True)
                ensure_space(self.path.parent, sum(getattr(b, "phi", np.zeros(0)).nbytes for b in integ.system.bodies))
                self.file = f = h5py.File(part, "w")
                metadata_at_flush_only(f)
                st = integ.state
                f.attrs.update(format=FORMAT, format_version=FORMAT_VERSION, status="running",
                               scene=self.meta.get("scene", ""), description=self.meta.get("description", ""),
                               integrator=integ.name, options=json.dumps(integ.options(), default=str),
                               dt=integ.dt, t_end=float(st.times[-1]), n_out=len(st.times), plan=st.result.plan,
                               versions=json.dumps(versions()),
                               inputs=json.dumps(input_hashes(self.meta.get("inputs", {}))),
                               overrides=json.dumps(list(self.meta.get("overrides", ()))), units="SI")
                self._layout(f, integ)
                f.flush()
                os.replace(part, self.path)
        except BaseException:
            if self.file is not None:
                self.file.close()
                self.file = None
            part.unlink(missing_ok=True)
            raise
        self.written = self.traced = 0
        self._clocks()

    def resume(self, integ):
        """Reopen the file of a run restored from its checkpoint and cut it back to the
        checkpoint's samples and trace rows."""
        if not self.path.is_file():
            raise InputFileError(self.path, None, "the result file of the run to resume is missing")
        try:
            f = h5py.File(self.path, "r+")
            metadata_at_flush_only(f)
        except BlockingIOError:              # HDF5's own file lock: another process has it open
            raise OutputFileError(self.path, "in use by another process (HDF5 file lock); wait for it to "
                                             "end") from None
        except OSError as exc:
            raise InputFileError(self.path, None, f"cannot reopen the result file to resume "
                                                  f"({os_reason(exc)})") from None
        if f.attrs.get("format") != FORMAT:
            f.close()
            raise InputFileError(self.path, None, "not an ffrmbs result file")
        self.file = f
        with self._writing(self.path, "result file"):
            self.written = n = integ.state.recorded
            traced = {key: len(rows) for key, rows in integ.trace().items()}
            self.traced = min(traced.values(), default=0)
            for name, obj in datasets(f):
                keep = traced.get(name[len("trace/"):], 0) if name.startswith("trace/") else n
                if obj.maxshape[0] is None and obj.shape[0] < keep:
                    f.close()
                    self.file = None
                    raise InputFileError(self.path, None, f"holds fewer rows in {name} ({obj.shape[0]}) than its "
                                                          f"checkpoint ({keep}); restart the run")
                if obj.maxshape[0] is None and obj.shape[0] > keep:
                    obj.resize(keep, axis=0)
            f.attrs["status"] = "running"
            f.attrs["resumed_at"] = np.asarray(integ.state.resumed_at, dtype=float)
            f.flush()
        self._clocks()

    def landed(self, integ):
        now = time.perf_counter()
        if self.checkpoint_every is not None and now - self._last_checkpoint >= self.checkpoint_every:
            self.checkpoint(integ)
        elif now - self._last_flush >= self.flush_every or integ.state.recorded - self.written >= FLUSH_SAMPLES:
            with self._writing(self.path, "result file"):
                self._flush(integ)

    def checkpoint(self, integ):
        """Append the samples so far, then save the run state (the checkpoint refers to
        them by count)."""
        with self._writing(self.path, "result file"):
            self._flush(integ)
        with self._writing(self.checkpoint_path, "checkpoint"):
            write_checkpoint(self.checkpoint_path, integ, {"samples": self.written, "trace_rows": self.traced})
        self.checkpoints += 1
        self._last_checkpoint = time.perf_counter()

    def end(self, integ, status):
        """Append the rest of the samples and trace, write the statistics and status,
        close the file."""
        if self.file is None:
            return
        try:
            with self._writing(self.path, "result file"):
                self._flush(integ)
                f = self.file
                f.attrs["status"] = status
                json_attribute(f, "stats", integ.diagnostics() | {"steps": integ.steps, "checkpoints": self.checkpoints})
                f.close()
                self.file = None
        finally:                             # an unexpected error: the file is closed all the same
            self._close_failed(f"failed: the file could not be finished ({status})")
        if status == "complete":
            self.checkpoint_path.unlink(missing_ok=True)

    def write_summary(self, summary: dict):
        """Add the job's summary (JSON) to the closed file."""
        with self._writing(self.path, "result file"):
            with h5py.File(self.path, "r+") as f:
                json_attribute(f, "summary", summary)

    # --- internals ----------------------------------------------------------------------------
    def _clocks(self):
        self._last_flush = self._last_checkpoint = time.perf_counter()

    @contextlib.contextmanager
    def _writing(self, path, what):
        """Turn an OSError (or HDF5's "file write failed") while writing ``path`` into
        OutputFileError, after marking the result file failed and closing it."""
        try:
            yield
        except (OSError, RuntimeError) as exc:
            hdf5 = HDF5_WRITE_FAILED.search(str(exc))      # HDF5 reports some failed writes as RuntimeError
            if isinstance(exc, RuntimeError) and hdf5 is None:
                raise
            fault = f"cannot write the {what}: {hdf5[1] if hdf5 else os_reason(exc)}"
            self._close_failed(f"failed: {fault}")
            raise OutputFileError(path, fault) from None

    def _close_failed(self, status):
        """Best effort on a failing disk: set ``status`` and close the open file."""
        f, self.file = self.file, None
        if f is None:
            return
        try:
            f.attrs["status"] = status
            f.close()
        except (OSError, RuntimeError):
            pass

    def _layout(self, f, integ):
        """Every dataset of the file (layout above) with zero rows and its units."""
        st, sys = integ.state, integ.system
        units = self.meta.get("units", {})
        _create(f, "t", (), float, "s")
        for body in sys.bodies:
            g = f.create_group(f"bodies/{body.name}")
            phi_units, q_f_units = modal_units(body)
            self._body_layout(g, body, phi_units)
            q_units, u_units = coordinate_units(body, q_f_units)
            _create(g, "q", (body.nq,), float, q_units)
            _create(g, "u", (body.nu,), float, u_units)
            _create(g, "R", (3,), float, "m")
            _create(g, "A", (3, 3), float, "1")
            if getattr(body, "n_modes", 0):
                _create(g, "q_f", (body.n_modes,), float, q_f_units)
        if st.energies:
            for key in ("kinetic", "potential"):
                _create(f, f"energy/{key}", (), float, "J")
        for name, probe in st.probes.items():
            shape = np.shape(np.asarray(probe(integ.t, integ.q, integ.u), dtype=float))
            _create(f, f"outputs/{name}", shape, float, units.get(name) or "SI")
            if self.meta.get("labels", {}).get(name):
                f[f"outputs/{name}"].attrs["label"] = self.meta["labels"][name]
        for name in st.result.contacts:
            for key, (shape, dtype, unit) in CONTACT_FIELDS.items():
                _create(f, f"contacts/{name}/{key}", shape, dtype, unit)
                f[f"contacts/{name}/{key}"].attrs["description"] = CONTACT_DESCRIPTIONS[key]
        for key, rows in integ.trace().items():
            _create(f, f"trace/{key}", rows.shape[1:], rows.dtype, integ.trace_units.get(key, "SI"))

    def _body_layout(self, g, body, phi_units):
        g.attrs.update(kind=type(body).__name__, q_start=body.q_slice.start, q_stop=body.q_slice.stop,
                       u_start=body.u_slice.start, u_stop=body.u_slice.stop, n_modes=getattr(body, "n_modes", 0))
        data = getattr(body, "data", None)
        if data is not None and getattr(data, "surface_triangles", None) is not None:
            nodes = data.surface_nodes
            s = g.create_group("surface")
            for key, values, unit in (("nodes", nodes, "1"), ("u0", data.u0[nodes], "m"),
                                      ("phi", body.phi_nodes[nodes], phi_units),
                                      ("triangles", np.searchsorted(nodes, data.surface_triangles), "1")):
                s[key] = values
                s[key].attrs["units"] = unit

    def _flush(self, integ):
        """Append the samples and trace rows not yet in the file, then flush it."""
        st, f = integ.state, self.file
        a, b = self.written, st.recorded
        blocks = []                                  # (dataset name, rows to append)
        if b > a:
            res = st.result
            blocks.append(("t", res.t[a:b]))
            for body in integ.system.bodies:
                g = f"bodies/{body.name}"
                q, u = res.q[a:b, body.q_slice], res.u[a:b, body.u_slice]
                R, A = _frame_rows(body, q, res.t[a:b])
                blocks += [(f"{g}/q", q), (f"{g}/u", u), (f"{g}/R", R), (f"{g}/A", A)]
                if getattr(body, "n_modes", 0):
                    blocks.append((f"{g}/q_f", body.modal_coordinates(q)))
            blocks += [(f"energy/{key}", values[a:b]) for key, values in res.energy.items()]
            blocks += [(f"outputs/{name}", values[a:b]) for name, values in res.outputs.items()]
            blocks += [(f"contacts/{name}/{key}", values[a:b])
                       for name, rec in res.contacts.items() for key, values in rec.items()]
        rows = integ.trace(self.traced)
        blocks += [(f"trace/{key}", values) for key, values in rows.items() if len(values)]
        if blocks:              # whole chunks may be allocated: room for one more chunk per dataset
            ensure_space(self.path.parent, sum((len(v) + CHUNK_ROWS) * np.asarray(v)[:1].nbytes for _, v in blocks))
        for name, values in blocks:
            _append(f, name, values)
        f.flush()
        self.written = b
        self.traced += min((len(v) for v in rows.values()), default=0)
        self._last_flush = time.perf_counter()


def metadata_at_flush_only(f) -> None:
    """Keep HDF5's metadata of the open file ``f`` in memory until the next flush: with
    evictions disabled (which needs the cache's automatic resizing off) the library writes
    no metadata between flushes, so a run killed there leaves the file as of its last
    flush. With evictions on, a chunk index could reach the disk pointing at space that
    the file's end-of-allocation did not yet cover ("addr overflow" on reading), found by
    killing runs at random moments (tests/qa/test_audit_results.py)."""
    config = f.id.get_mdc_config()
    config.incr_mode = config.decr_mode = config.flash_incr_mode = 0     # H5C_*_off
    config.evictions_enabled = False
    f.id.set_mdc_config(config)


def free_bytes(directory) -> int:
    """Bytes available to this user on the file system of ``directory``."""
    st = os.statvfs(directory)
    return st.f_bavail * st.f_frsize


def ensure_space(directory, nbytes):
    """Raise OSError(ENOSPC) unless ``nbytes`` plus SPACE_RESERVE fit on the file system
    of ``directory``. HDF5 cannot close a file after a failed write (and its library then
    crashes the process as it exits), so a full disk is caught before HDF5 writes; the
    reserve leaves room for the status attribute and the close."""
    free = free_bytes(directory)
    if free < nbytes + SPACE_RESERVE:
        raise OSError(errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} ({free / 1e6:.2f} MB free, "
                                    f"{(nbytes + SPACE_RESERVE) / 1e6:.2f} MB needed with the reserve)")


def coordinate_units(body, q_f_units="SI") -> tuple[str, str]:
    """The units of a body's coordinates q and velocities u, by blocks, e.g.
    "m (R, 3), 1 (quaternion, 4), kg^(1/2) m (q_f, 20)" (``q_f_units``: those of its
    modal coordinates, :func:`modal_units`)."""
    from mbs.bodies.floating_frame import FloatingFrameBody
    from mbs.bodies.rigid_body import PointMass

    if isinstance(body, PointMass):
        return "m", "m/s"
    if not isinstance(body, FloatingFrameBody):
        return "SI", "SI"
    q, u = [], []
    if body.param is not None:
        rotation = "rad" if body.param.name == "cardan" else "1"
        q += ["m (R, 3)", f"{rotation} ({body.param.name}, {body.param.nq})"]
        u += ["m/s (v, 3)", "rad/s (angular velocity, 3)"]
    if body.n_modes:
        q.append(f"{q_f_units} (q_f, {body.n_modes})")
        u.append(f"{q_f_units}/s (q_f rates, {body.n_modes})")
    return ", ".join(q) or "1", ", ".join(u) or "1"


def modal_units(body) -> tuple[str, str]:
    """(units of the mode shapes Φ, of the modal coordinates q_f): Φ q_f is in m. Modes
    normalized to the body's mass, lumped or consistent (Φᵀ M Φ = I, as :mod:`preprocess.modes` writes them)
    give Φ [kg^(-1/2)] and q_f [kg^(1/2) m]; other normalizations are "SI"."""
    data = getattr(body, "data", None)
    if getattr(data, "masses", None) is None:
        return "SI", "SI"
    if mass_normalized(body.phi, data.mass):
        return "kg^(-1/2)", "kg^(1/2) m"
    return "SI", "SI"


def resume_checkpoint(recorder, inputs=None, overrides=()):
    """The checkpoint (:class:`mbs.results.checkpoint.Checkpoint`) beside ``recorder.path``, to
    continue its run with ``System.simulate(checkpoint=…, recorder=recorder)``.
    ``inputs`` ({label: path}, the scene's): refused if one changed since the run
    started; ``overrides`` (the scene's ``--set`` texts): refused if they differ from the
    run's. InputFileError if there is no checkpoint or it cannot be read."""
    path, ckpt = recorder.path, recorder.checkpoint_path
    if not ckpt.exists():
        raise InputFileError(ckpt, None, "no checkpoint to resume from (the run completed, or never "
                                         "reached its first checkpoint)")
    _, attrs = load_result(path)
    then = list(attrs.get("overrides") or [])
    if then != list(overrides):
        raise InputFileError(path, None, f"cannot resume: the run started with --set {then or 'nothing'}, "
                                         f"not {list(overrides) or 'nothing'}")
    if inputs:
        then, now = attrs.get("inputs", {}), input_hashes(inputs)
        changed = [label for label, entry in now.items() if then.get(label, {}).get("sha256") != entry["sha256"]]
        if changed:
            raise InputFileError(path, None, f"cannot resume: input(s) changed since the run started: "
                                             f"{', '.join(changed)}")
    return read_checkpoint(ckpt)


def _create(f, name, row_shape, dtype, units):
    """An empty per-sample dataset (0, *row_shape), resizable along its first axis,
    chunked by CHUNK_ROWS rows, with its ``units`` attribute."""
    d = f.create_dataset(name, shape=(0,) + tuple(row_shape), dtype=dtype, maxshape=(None,) + tuple(row_shape),
                         chunks=(CHUNK_ROWS,) + tuple(row_shape))
    d.attrs["units"] = units


def _append(f, name, rows):
    rows = np.asarray(rows)
    d = f[name]
    n = d.shape[0]
    d.resize(n + rows.shape[0], axis=0)
    d[n:] = rows


def _frame_rows(body, q, t):
    """The body frame's position R (k, 3) [m] and orientation A (k, 3, 3) at each sample."""
    R, A = np.empty((len(q), 3)), np.empty((len(q), 3, 3))
    origin = Frame(body, np.zeros(3))
    for i, (qi, ti) in enumerate(zip(q, t)):
        R[i] = origin.position(qi, ti)
        A[i] = origin.orientation(qi, ti)
    return R, A


def datasets(f) -> list:
    """(name, h5py Dataset) of every dataset of the open file ``f``."""
    found = []
    f.visititems(lambda name, obj: found.append((name, obj)) if isinstance(obj, h5py.Dataset) else None)
    return found


def per_sample(name) -> bool:
    """Whether the dataset ``name`` holds one row per output sample (not the per-step
    trace, not a body's fixed surface mesh)."""
    return not name.startswith("trace/") and "/surface/" not in name


def json_attribute(obj, name, value) -> None:
    """Write ``value`` as JSON into the attribute ``name`` of ``obj``, a fixed-length UTF-8
    string (read back as bytes, which ``json.loads`` takes). Fixed length keeps the text in
    the attribute itself: a variable-length string lives in the file's global heap, and
    libhdf5 can hang for good reading a damaged global heap."""
    text = json.dumps(value, default=float).encode("utf-8")
    obj.attrs.create(name, np.bytes_(text), dtype=h5py.string_dtype("utf-8", max(len(text), 1)))


def attribute(obj, name, default=None):
    """An HDF5 attribute of ``obj`` as a Python str/number (bytes decoded; bytes that are
    not UTF-8, which h5py hands over as surrogate escapes in a str, replaced by U+FFFD),
    or ``default``."""
    value = obj.attrs.get(name, default)
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    elif isinstance(value, str):
        value = value.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
    elif isinstance(value, np.generic):
        value = value.item()
    return value


@contextlib.contextmanager
def open_result_file(path):
    """Open the result file ``path`` read-only and check that it is one; yields the
    ``h5py.File``. InputFileError (path, None, fault) when it is missing or not a regular
    file (never opened then: :func:`preprocess.inputfiles.regular_file`), not HDF5, not of
    format ``ffrmbs-result`` version :data:`FORMAT_VERSION`, and when reading fails inside
    the block (:func:`damaged_result_file`)."""
    path = regular_file(path)
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise InputFileError(path, None, f"not an HDF5 file ({exc})") from None
    with f, damaged_result_file(path):
        fmt = attribute(f, "format")
        if fmt != FORMAT:
            raise InputFileError(path, None, f"not an ffrmbs result file (format attribute {fmt!r}, "
                                             f"expected {FORMAT!r})")
        version = attribute(f, "format_version")
        if version != FORMAT_VERSION:
            raise InputFileError(path, None, f"result format version {version!r} is not supported "
                                             f"(this ffrmbs reads version {FORMAT_VERSION})")
        yield f


def load_result(path) -> tuple[Result, dict]:
    """The samples of a result file as a :class:`~mbs.results.result.Result` (q, u assembled from
    the bodies' datasets) and the file's attributes (JSON ones decoded).

    A file cut short (a killed run) may hold more rows in some per-sample datasets than
    in others; every one is read up to the shortest, and the trace up to its shortest key.
    A file that is not a result file is an InputFileError (:func:`open_result_file`).
    """
    with open_result_file(path) as f:
        return _read(f, path)


@contextlib.contextmanager
def damaged_result_file(path):
    """Reading the result file ``path`` inside the block: what h5py raises on damaged
    metadata (OSError, RuntimeError, KeyError, ValueError) and the json module on bad
    JSON in an attribute (ValueError) become InputFileError (path, None, "damaged result
    file (<reason>)"), the reason the first line of the library's message, at most 120
    characters. The same exceptions raised by other code in the block (a bug of ours,
    numpy, matplotlib) pass unchanged: they are not the file's fault."""
    try:
        yield
    except (OSError, RuntimeError, KeyError, ValueError) as exc:
        if not _raised_by_a_reader(exc):
            raise
        raise InputFileError(path, None, f"damaged result file ({first_line(exc, 120)})") from None


def _raised_by_a_reader(exc) -> bool:
    """Whether ``exc`` was raised inside h5py or the json module (its innermost frame)."""
    tb = exc.__traceback__
    while tb.tb_next is not None:
        tb = tb.tb_next
    where = Path(tb.tb_frame.f_code.co_filename).parts
    return "h5py" in where or "json" in where


def _read(f, path) -> tuple[Result, dict]:
    """The body of :func:`load_result` on the open file ``f``."""
    attrs = {k: (json.loads(v) if k in ("options", "versions", "inputs", "overrides", "summary", "stats") else v)
             for k, v in f.attrs.items()}
    n = min((d.shape[0] for name, d in datasets(f) if per_sample(name)), default=0)
    t = f["t"][:n] if "t" in f else np.zeros(0)
    bodies = f.get("bodies", {})
    nq = max((g.attrs["q_stop"] for g in bodies.values()), default=0)
    nu = max((g.attrs["u_stop"] for g in bodies.values()), default=0)
    q, u = np.full((n, nq), np.nan), np.full((n, nu), np.nan)
    for g in bodies.values():
        if "q" in g:
            q[:, g.attrs["q_start"]:g.attrs["q_stop"]] = g["q"][:n]
            u[:, g.attrs["u_start"]:g.attrs["u_stop"]] = g["u"][:n]
    res = Result(t, q, u, plan=str(attrs.get("plan", "")))
    res.outputs = {k: v[:n] for k, v in _group(f, "outputs").items()}
    res.energy = {k: v[:n] for k, v in _group(f, "energy").items()}
    trace = _group(f, "trace")
    steps = min((len(v) for v in trace.values()), default=0)
    res.trace = {k: v[:steps] for k, v in trace.items()}
    res.contacts = {name: {k: v[:n] for k, v in g.items()} for name, g in f.get("contacts", {}).items()}
    res.stats = attrs.get("stats", {}) or {}
    return res, attrs


def _group(f, name) -> dict:
    return {k: v[()] for k, v in f[name].items()} if name in f else {}

