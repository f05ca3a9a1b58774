"""Checkpoints of a running simulation: the whole integrator — its System, bodies,
contours, contacts, warm starts, caches, counters and per-step trace — pickled in one
piece, so that a run restored from it continues bit for bit as if never stopped.

Pickling an object graph exactly needs two things plain pickle does not give:

- closures and lambdas (prescribed frame motions, load tables, output probes):
  cloudpickle serializes them by value;
- numpy views that share memory with another array of the graph (a contour's rows of a
  kernel workspace, a body's slice of a buffer). Pickle copies each view, after which an
  in-place update of the base no longer shows through the view, and the restored run
  silently differs. :class:`_Pickler` writes a view as (its base, byte offset, shape,
  strides), so the restored view is again a window on the restored base.

Files are written atomically (temporary file, fsync, rename): a kill at any moment
leaves either the previous checkpoint or the new one, never a torn file.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import cloudpickle
import numpy as np

from ffrmbs.errors import InputFileError

MAGIC = b"ffrmbs-checkpoint-1\n"


def _view(base, offset, shape, strides, dtype, writeable):
    """A numpy view on ``base`` (the inverse of the view reduction)."""
    flat = base.reshape(-1, order="A").view(np.uint8) if base.flags.c_contiguous or base.flags.f_contiguous else None
    if flat is None:
        raise ValueError("a view whose base is not contiguous cannot be restored")
    arr = np.ndarray(shape, dtype=dtype, buffer=flat, offset=offset, strides=strides)
    arr.flags.writeable = writeable
    return arr


class _Pickler(cloudpickle.Pickler):
    """cloudpickle with numpy views kept as views of their (pickled once) base array."""

    def reducer_override(self, obj):
        if type(obj) is np.ndarray and isinstance(obj.base, np.ndarray) and obj.dtype.hasobject is False:
            base = obj.base
            if type(base) is np.ndarray and (base.flags.c_contiguous or base.flags.f_contiguous):
                offset = obj.__array_interface__["data"][0] - base.__array_interface__["data"][0]
                if 0 <= offset <= base.nbytes:
                    return _view, (base, offset, obj.shape, obj.strides, obj.dtype, obj.flags.writeable)
        return super().reducer_override(obj)


def dumps(obj) -> bytes:
    """``obj`` pickled with closures by value and numpy views as views."""
    buf = io.BytesIO()
    _Pickler(buf, protocol=5).dump(obj)
    return buf.getvalue()


def loads(data: bytes):
    return cloudpickle.loads(data)


def write_checkpoint(path, state) -> None:
    """Write ``state`` (any picklable object graph) to ``path`` atomically."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "wb") as f:
            f.write(MAGIC)
            f.write(dumps(state))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def read_checkpoint(path):
    """The state saved by :func:`write_checkpoint`; InputFileError if ``path`` is not one."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read the checkpoint ({exc.strerror})") from None
    if not data.startswith(MAGIC):
        raise InputFileError(path, None, "not an ffrmbs checkpoint")
    try:
        return loads(data[len(MAGIC):])
    except Exception as exc:          # a checkpoint of another ffrmbs version, or damaged
        raise InputFileError(path, None, f"the checkpoint cannot be restored ({type(exc).__name__}: {exc}); "
                                         "was it written by another ffrmbs version?") from None
