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

Unpickling runs code, so a checkpoint is signed: the file is ``MAGIC``, the hex
HMAC-SHA256 of the pickle under a per-user secret key and a newline, then the pickle.
:func:`read_checkpoint` checks the signature before anything is unpickled and refuses
any checkpoint this installation did not write, naming the older unsigned format
(``UNSIGNED_MAGIC``) as such. The key (32 random bytes) is
``checkpoint.key`` in ``$FFRMBS_CONFIG`` (default ``~/.config/ffrmbs``), outside every
output directory; it is created on first use with mode 0600 in a directory of mode 0700.
"""

from __future__ import annotations

import hashlib
import hmac
import io
import os
from pathlib import Path

import cloudpickle
import numpy as np

from ffrmbs.errors import InputFileError

MAGIC = b"ffrmbs-checkpoint-2\n"
UNSIGNED_MAGIC = b"ffrmbs-checkpoint-1\n"                   # the older format: no signature
KEY_FILE, KEY_BYTES = "checkpoint.key", 32
SIGNATURE_CHARS = 2 * hashlib.sha256().digest_size         # hex HMAC-SHA256


def key_path() -> Path:
    """The per-user checkpoint key: ``$FFRMBS_CONFIG/checkpoint.key``, by default in
    ``~/.config/ffrmbs``."""
    config = os.environ.get("FFRMBS_CONFIG") or Path.home() / ".config" / "ffrmbs"
    return Path(config) / KEY_FILE


def _key() -> bytes:
    """The checkpoint key, created (os.urandom, mode 0600, directory 0700) on first use;
    a new key is linked into place whole, so concurrent first runs agree on one.
    InputFileError if the key cannot be created (read-only directory, no hard links)."""
    path = key_path()
    if not path.exists():
        try:
            _create_key(path)
        except OSError as exc:
            raise InputFileError(path, None, f"cannot create the checkpoint key ({exc.strerror})") from None
    try:
        key = path.read_bytes() if path.is_file() else b""
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read the checkpoint key ({exc.strerror})") from None
    if len(key) != KEY_BYTES:
        raise InputFileError(path, None, f"the checkpoint key must be a file of {KEY_BYTES} bytes; remove it "
                                         "and a new one is made (older checkpoints are then refused)")
    return key


def _create_key(path: Path) -> None:
    """Write a new random key to a temporary file and link it to ``path`` (kept if
    another process linked its key first); OSError if the file system refuses."""
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    tmp = path.with_name(f"{KEY_FILE}.{os.getpid()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        try:
            os.write(fd, os.urandom(KEY_BYTES))
            os.fsync(fd)
        finally:
            os.close(fd)
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass                       # another process made it first: use theirs
    finally:
        tmp.unlink(missing_ok=True)


def _signature(payload: bytes) -> bytes:
    return hmac.new(_key(), payload, hashlib.sha256).hexdigest().encode()


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
    """Write ``state`` (any picklable object graph) to ``path`` atomically, signed."""
    path = Path(path)
    payload = dumps(state)
    signature = _signature(payload)
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "wb") as f:
            f.write(MAGIC + signature + b"\n")
            f.write(payload)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def read_checkpoint(path):
    """The state saved by :func:`write_checkpoint`; InputFileError if ``path`` is not one
    or was not signed with this installation's key (checked before unpickling)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read the checkpoint ({exc.strerror})") from None
    if data.startswith(UNSIGNED_MAGIC):
        raise InputFileError(path, None, "an older, unsigned checkpoint format: refused (it could run code); "
                                         "restart the run")
    head = len(MAGIC) + SIGNATURE_CHARS + 1
    signature, payload = data[len(MAGIC):head - 1], data[head:]
    if not (data.startswith(MAGIC) and data[head - 1:head] == b"\n"
            and hmac.compare_digest(signature, _signature(payload))):
        raise InputFileError(path, None, "not written by this installation: signature does not match; "
                                         "a checkpoint is refused rather than run")
    try:
        return loads(payload)
    except Exception as exc:          # a checkpoint of another ffrmbs version, or damaged
        raise InputFileError(path, None, f"the checkpoint cannot be restored ({type(exc).__name__}: {exc}); "
                                         "was it written by another ffrmbs version?") from None
