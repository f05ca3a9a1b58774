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
                              summary (JSON, written when the run ends), stats (JSON)
    /t                        (n,) [s] sample times
    /bodies/<body>/           attrs: kind (class name), q_start, q_stop, u_start, u_stop
                                     (the body's slices of the system's q and u), n_modes
        q (n, nq_b), u (n, nu_b)          the body's coordinates and velocities
        R (n, 3) [m], A (n, 3, 3)         its frame's position and orientation (world)
        q_f (n, n_f) [-]                  modal coordinates (flexible bodies)
        surface/                          flexible bodies with surface triangles:
            nodes (m,) int64              FE node numbers of the surface nodes
            u0 (m, 3) [m]                 their undeformed positions in the body frame
            phi (m, 3, n_f)               the body's mode shapes at them
            triangles (k, 3) or (k, 6) int64   rows into ``nodes``: corners (tet4 bodies),
                                          or corners then the mid-edge nodes of edges
                                          (c0,c1), (c1,c2), (c2,c0) (tet10 bodies)
                                          → deformed surface x = R + A (u0 + phi · q_f)
    /energy/kinetic, /energy/potential      (n,) [J]          (when recorded)
    /outputs/<name>           (n, ...) the requested outputs (node positions [m], ...)
    /contacts/<contact>/      attrs: law (class name), set_valued (bool)
        active (n,) int8      closed at the last step's midpoint
        gap (n,) [m]          normal gap g_N (NaN while no contact point is located)
        point (n, 3) [m]      contact point on the second contour (world)
        normal (n, 3)         contact normal (world)
        force (n, 3) [N]      contact force on the first contour's body (world): the
                              impulse of the last step / Δt for set-valued laws
    /trace/<key>              (steps,) per-step records of integrators that keep them
                              (written when the run ends)

Writing: :class:`ResultRecorder` is the driver's recorder (``System.simulate(recorder=)``).
Samples are buffered and appended every ``flush_every`` seconds of wall time (and at
every checkpoint and at the end), then the file is flushed, so a reader — or a killed
run — finds every sample up to the last flush. Every ``checkpoint_every`` seconds of wall
time, at the next output sample, the whole run state goes to the checkpoint
``<name>.h5.ckpt`` beside the file (:mod:`mbs.checkpoint`, written atomically); after the
samples up to it are in the file. :func:`resume_recording` continues a killed run from its
checkpoint: the file is cut back to the checkpoint's samples and the run goes on; the
result equals the uninterrupted run's bit for bit (the state is restored exactly, the
computation is deterministic). The checkpoint is removed when the run completes and kept
when it is interrupted or fails.

Reading: :func:`load_result` gives a :class:`~mbs.result.Result` and the file's
attributes.
"""

from __future__ import annotations

import hashlib
import json
import platform
import time
from pathlib import Path

import h5py
import numpy as np

from ffrmbs.errors import InputFileError

from .body import Frame
from .checkpoint import read_checkpoint, write_checkpoint
from .result import Result

FORMAT, FORMAT_VERSION = "ffrmbs-result", 1
CHUNK_ROWS = 256


def versions() -> dict:
    """Versions of ffrmbs and of the libraries that decide its numbers."""
    import numba
    import scipy

    from ffrmbs import __version__

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
    """{label: {"path", "sha256"}} of the input files (built-in sources have no file)."""
    out = {}
    for label, path in inputs.items():
        p = Path(path)
        out[label] = {"path": str(path), "sha256": sha256(p) if p.exists() else None}
    return out


class ResultRecorder:
    """Streams a run's samples to the HDF5 result file ``path`` (layout above) and takes
    checkpoints.

    meta: {"scene", "description", "inputs": {label: path}} written as attributes;
    flush_every [s]: wall time between appends of the buffered samples; checkpoint_every
    [s] or None: wall time between checkpoints (taken at output samples).
    """

    def __init__(self, path, meta=None, flush_every=2.0, checkpoint_every=60.0):
        self.path = Path(path)
        self.checkpoint_path = self.path.with_name(self.path.name + ".ckpt")
        self.meta = dict(meta or {})
        self.flush_every = float(flush_every)
        self.checkpoint_every = None if checkpoint_every is None else float(checkpoint_every)
        self.file = None
        self.written = 0            # samples in the file
        self.checkpoints = 0

    # --- the driver's hooks -----------------------------------------------------------------
    def begin(self, integ):
        """Create the file and its layout (replacing an older file of the same name)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.checkpoint_path.unlink(missing_ok=True)
        self.file = f = h5py.File(self.path, "w")
        st, sys = integ.state, integ.system
        f.attrs.update(format=FORMAT, format_version=FORMAT_VERSION, status="running",
                       scene=self.meta.get("scene", ""), description=self.meta.get("description", ""),
                       integrator=integ.name, options=json.dumps(integ.options(), default=str), dt=integ.dt,
                       t_end=float(st.times[-1]), n_out=len(st.times), plan=st.result.plan,
                       versions=json.dumps(versions()),
                       inputs=json.dumps(input_hashes(self.meta.get("inputs", {}))), units="SI")
        for body in sys.bodies:
            self._body_layout(f.create_group(f"bodies/{body.name}"), body)
        self.written = 0
        self._clocks()

    def resume(self, integ):
        """Reopen the file of a run restored from its checkpoint and cut it back to the
        checkpoint's samples."""
        if not self.path.is_file():
            raise InputFileError(self.path, None, "the result file of the run to resume is missing")
        try:
            self.file = f = h5py.File(self.path, "r+")
        except OSError as exc:
            raise InputFileError(self.path, None, f"cannot reopen the result file to resume ({exc})") from None
        if f.attrs.get("format") != FORMAT:
            raise InputFileError(self.path, None, "not an ffrmbs result file")
        self.written = n = integ.state.recorded
        for name, obj in _datasets(f):
            if obj.maxshape[0] is None and obj.shape[0] > n:
                obj.resize(n, axis=0)
        f.attrs["status"] = "running"
        f.attrs["resumed_at"] = np.asarray(integ.state.resumed_at, dtype=float)
        self._clocks()

    def landed(self, integ):
        now = time.perf_counter()
        if self.checkpoint_every is not None and now - self._last_checkpoint >= self.checkpoint_every:
            self.checkpoint(integ)
        elif now - self._last_flush >= self.flush_every:
            self._flush(integ)

    def checkpoint(self, integ):
        """Append the samples so far, then save the run state (the checkpoint refers to
        them by count)."""
        self._flush(integ)
        write_checkpoint(self.checkpoint_path, {"integrator": integ, "samples": self.written,
                                                "result_file": str(self.path)})
        self.checkpoints += 1
        self._last_checkpoint = time.perf_counter()

    def end(self, integ, status):
        """Append the rest, write the trace, statistics and status, close the file."""
        if self.file is None:
            return
        try:
            self._flush(integ)
            f = self.file
            for key, values in integ.trace().items():
                if f"trace/{key}" in f:
                    del f[f"trace/{key}"]
                f[f"trace/{key}"] = values
            f.attrs["status"] = status
            f.attrs["stats"] = json.dumps(integ.diagnostics() | {"steps": integ.steps,
                                                                 "checkpoints": self.checkpoints}, default=float)
        finally:
            self.file.close()
            self.file = None
        if status == "complete":
            self.checkpoint_path.unlink(missing_ok=True)

    def write_summary(self, summary: dict):
        """Add the job's summary (JSON) to the closed file."""
        with h5py.File(self.path, "r+") as f:
            f.attrs["summary"] = json.dumps(summary, default=float)

    # --- internals ----------------------------------------------------------------------------
    def _clocks(self):
        self._last_flush = self._last_checkpoint = time.perf_counter()

    def _body_layout(self, g, body):
        g.attrs.update(kind=type(body).__name__, q_start=body.q_slice.start, q_stop=body.q_slice.stop,
                       u_start=body.u_slice.start, u_stop=body.u_slice.stop, n_modes=getattr(body, "n_modes", 0))
        data = getattr(body, "data", None)
        if data is not None and getattr(data, "surface_triangles", None) is not None:
            nodes = data.surface_nodes
            s = g.create_group("surface")
            s["nodes"] = nodes
            s["u0"] = data.u0[nodes]
            s["phi"] = body.phi_nodes[nodes]
            s["triangles"] = np.searchsorted(nodes, data.surface_triangles)

    def _flush(self, integ):
        st, f = integ.state, self.file
        a, b = self.written, st.recorded
        if b <= a:
            return
        res = st.result
        _append(f, "t", res.t[a:b])
        for body in integ.system.bodies:
            g = f"bodies/{body.name}"
            q, u = res.q[a:b, body.q_slice], res.u[a:b, body.u_slice]
            _append(f, f"{g}/q", q)
            _append(f, f"{g}/u", u)
            R, A = _frame_rows(body, q, res.t[a:b])
            _append(f, f"{g}/R", R)
            _append(f, f"{g}/A", A)
            if getattr(body, "n_modes", 0):
                _append(f, f"{g}/q_f", body.modal_coordinates(q))
        for key, values in res.energy.items():
            _append(f, f"energy/{key}", values[a:b])
        for name, values in res.outputs.items():
            _append(f, f"outputs/{name}", values[a:b])
        for name, rec in res.contacts.items():
            for key, values in rec.items():
                _append(f, f"contacts/{name}/{key}", values[a:b])
        f.flush()
        self.written = b
        self._last_flush = time.perf_counter()


def resume_recording(recorder, progress=None, inputs=None):
    """Continue the run whose checkpoint sits beside ``recorder.path`` to its end,
    recording with ``recorder``; returns the full :class:`~mbs.result.Result` (samples
    before the checkpoint included). ``inputs`` ({label: path}, the scene's): refuse if
    one changed since the run started."""
    from .integrators.driver import resume

    path, ckpt = recorder.path, recorder.checkpoint_path
    if not ckpt.is_file():
        raise InputFileError(ckpt, None, "no checkpoint to resume from (the run completed, or never "
                                         "reached its first checkpoint)")
    if inputs:
        _, attrs = load_result(path)
        then, now = attrs.get("inputs", {}), input_hashes(inputs)
        changed = [label for label, entry in now.items() if then.get(label, {}).get("sha256") != entry["sha256"]]
        if changed:
            raise InputFileError(path, None, f"cannot resume: input(s) changed since the run started: "
                                             f"{', '.join(changed)}")
    return resume(read_checkpoint(ckpt)["integrator"], recorder, progress)


def _append(f, name, rows):
    rows = np.asarray(rows)
    if name not in f:
        f.create_dataset(name, data=rows, maxshape=(None,) + rows.shape[1:],
                         chunks=(CHUNK_ROWS,) + rows.shape[1:] if rows.ndim else True)
        return
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


def _datasets(f):
    found = []
    f.visititems(lambda name, obj: found.append((name, obj)) if isinstance(obj, h5py.Dataset) else None)
    return found


def load_result(path) -> tuple[Result, dict]:
    """The samples of a result file as a :class:`~mbs.result.Result` (q, u assembled from
    the bodies' datasets) and the file's attributes (JSON ones decoded)."""
    path = Path(path)
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise InputFileError(path, None, f"not a readable HDF5 file ({exc})") from None
    with f:
        if f.attrs.get("format") != FORMAT:
            raise InputFileError(path, None, "not an ffrmbs result file (attribute format missing)")
        attrs = {k: (json.loads(v) if k in ("options", "versions", "inputs", "summary", "stats") else v)
                 for k, v in f.attrs.items()}
        t = f["t"][()] if "t" in f else np.zeros(0)
        n = len(t)
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
        res.trace = _group(f, "trace")
        res.contacts = {name: {k: v[()][:n] for k, v in g.items()} for name, g in f.get("contacts", {}).items()}
        res.stats = attrs.get("stats", {}) or {}
    return res, attrs


def _group(f, name) -> dict:
    return {k: v[()] for k, v in f[name].items()} if name in f else {}

