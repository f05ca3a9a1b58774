"""Output directories that leave nothing behind when writing into them fails."""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path


@contextmanager
def new_directories(path):
    """Create the directory ``path`` and its missing ancestors for the block; if the block
    raises, remove the ones it created (innermost first, if empty) and re-raise.

    Yields the directories created (outermost first)."""
    missing = []
    p = Path(path)
    while not p.exists():
        missing.append(p)
        p = p.parent
    missing.reverse()
    created = []
    try:
        for d in missing:
            d.mkdir()
            created.append(d)
        yield created
    except BaseException:
        for d in reversed(created):
            try:
                d.rmdir()
            except OSError:
                pass
        raise


def shown(path) -> str:
    """``path`` as a command prints it: relative to the current directory when it lies
    under it ("out/bounce.h5"), else absolute ("/data/runs/bounce.h5"), so every path a
    command prints reads one way, whichever way it was made."""
    p = Path(path).absolute()
    try:
        return str(p.relative_to(Path.cwd()))
    except ValueError:
        return str(p)
