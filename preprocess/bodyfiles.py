"""A body on disk: the thesis's four text files and/or one HDF5 file (Sec. 4.2.1).

A body directory holds ``u0.dat``, ``modeShapeMatrix.dat``, ``mij.dat``,
``stiffnessMatrix.dat`` (:mod:`preprocess.textfiles`, Listings 4.1-4.5) and
``body.h5`` (:mod:`preprocess.hdf5file`, which also keeps eigenvalues, node groups,
surface, material, params and a consistent mass matrix). :func:`write_body` writes all
five atomically (``body.h5`` alone for a body with a consistent mass matrix);
:func:`read_body` reads a directory's ``body.h5``, the text files being the fallback.
"""

from __future__ import annotations

import os
import shutil
import uuid
from pathlib import Path

from ffrmbs.errors import InputFileError
from preprocess.body import BodyData
from preprocess.hdf5file import read_hdf5, write_hdf5
from preprocess.textfiles import TEXT_FILES, read_text_body, write_text_files
from preprocess.units import unit_system

HDF5_FILE = "body.h5"
HDF5_SUFFIXES = (".h5", ".hdf5")


def read_body(path, units: str = "si") -> BodyData:
    """The body at ``path``, in SI units.

    ``path`` is a directory — its ``body.h5`` if present (with node groups, surface,
    eigenvalues, material and params), else its text files (read in ``units``) — or a
    ``.h5``/``.hdf5`` file (always SI; ``units`` applies to text files only). Anything
    else raises InputFileError.
    """
    unit_system(units)
    path = Path(path)
    if path.is_dir():
        if not any(f.exists() for f in body_files(path)):
            raise InputFileError(path, None, f"no body files: expected {HDF5_FILE} or "
                                             f"{', '.join(TEXT_FILES)}")
        return read_hdf5(path / HDF5_FILE) if (path / HDF5_FILE).exists() else read_text_body(path, units)
    if path.suffix.lower() in HDF5_SUFFIXES:
        return read_hdf5(path)
    fault = "not a body directory or .h5/.hdf5 file" if path.exists() else "not found"
    raise InputFileError(path, None, fault)


def body_files(path) -> list[Path]:
    """The files :func:`read_body` reads for ``path``: a directory's ``body.h5`` if it
    exists, else its four text files; any other path itself."""
    path = Path(path)
    if not path.is_dir():
        return [path]
    if (path / HDF5_FILE).exists():
        return [path / HDF5_FILE]
    return [path / name for name in TEXT_FILES]


def write_body(directory, body: BodyData, units: str = "si", text_files: bool = True) -> None:
    """Write the four text files (in ``units``) and ``body.h5`` (SI) into ``directory``;
    ``body.h5`` alone with ``text_files=False`` (a cache that only :func:`read_body` reads:
    formatting the text files costs 1.7 s of the default beam's preprocessing).

    Atomic per file set: everything is first written to hidden temporary files in
    ``directory`` (created if missing), then each is moved into place with
    ``os.replace``, an existing file being kept aside (a hard link, or a copy) until
    all five are in place. On any exception the files already moved are put back (or
    removed if they are new), the temporaries removed and the exception re-raised:
    the directory holds the old set or the new one, never a mix or a half-written file.

    A body with a consistent mass matrix (``body.mass_matrix``), which the text files
    cannot hold, is written as ``body.h5`` alone; text files of an earlier body in
    ``directory`` are then removed (as with ``text_files=False``), so that none is left
    that disagrees with it.
    """
    unit_system(units)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    token = uuid.uuid4().hex
    text = text_files and body.mass_matrix is None
    names = (*TEXT_FILES, HDF5_FILE) if text else (HDF5_FILE,)
    temporaries = {name: directory / f".{name}.{token}.tmp" for name in names}
    backups = {name: directory / f".{name}.{token}.old" for name in names}
    placed = []
    try:
        if text:
            write_text_files({name: temporaries[name] for name in TEXT_FILES}, body, units)
        write_hdf5(temporaries[HDF5_FILE], body)
        for name in names:
            target = directory / name
            if target.exists():
                _keep(target, backups[name])
            os.replace(temporaries[name], target)
            placed.append(name)
    except BaseException:
        for name in reversed(placed):           # back to the old set
            if backups[name].exists():
                os.replace(backups[name], directory / name)
            else:
                (directory / name).unlink(missing_ok=True)
        raise
    finally:
        for path in (*temporaries.values(), *backups.values()):
            path.unlink(missing_ok=True)
    if not text:
        for name in TEXT_FILES:
            (directory / name).unlink(missing_ok=True)


def _keep(target: Path, backup: Path) -> None:
    """Keep the current ``target`` as ``backup``: a hard link, else a copy."""
    try:
        os.link(target, backup)
    except OSError:
        shutil.copy2(target, backup)
