"""Input files are read only if they are regular files.

A directory, FIFO, device or socket given where a body or mesh file belongs could block
a reader forever (a FIFO without a writer) or never end (``/dev/zero``); it is refused
with :class:`~ffrmbs.errors.InputFileError` before anything opens it.
"""

from __future__ import annotations

import stat
from pathlib import Path

from ffrmbs.errors import InputFileError

_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def regular_file(path) -> Path:
    """``path`` as a Path if it names a regular file (symbolic links followed).

    InputFileError: "file not found", "cannot read file: ..." (e.g. no permission to
    reach it) or "not a regular file (a FIFO)" and the like.
    """
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise InputFileError(path, None, "file not found") from None
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read file: {exc.strerror}") from None
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _KINDS if test(mode)), "a special file")
        raise InputFileError(path, None, f"not a regular file ({kind})")
    return path
