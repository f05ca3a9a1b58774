"""Input files are read only if they are regular files.

A directory, FIFO, device or socket given where a body or mesh file belongs could block
a reader forever (a FIFO without a writer) or never end (``/dev/zero``); it is refused
with :class:`~ffrmbs.errors.InputFileError` before anything opens it. Files that include
others (Abaqus ``*INCLUDE``, gmsh ``Include``) are walked by :func:`include_tree`, every
file checked before it is opened.
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


def include_tree(path, includes):
    """Yield ``(file, text)`` for ``path`` and every file it includes, at any depth, each
    once and each checked by :func:`regular_file` before it is read.

    ``includes(file, text)`` gives the paths ``file`` includes that are themselves to be
    walked (its other references the caller checks itself).
    """
    pending, seen = [Path(path)], set()
    while pending:
        current = regular_file(pending.pop())
        if current.resolve() in seen:
            continue
        seen.add(current.resolve())
        with open(current, encoding="utf-8", errors="replace") as f:
            text = f.read()
        yield current, text
        pending.extend(includes(current, text))
