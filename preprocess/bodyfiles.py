"""A body on disk: the thesis's four text files and/or one HDF5 file (Sec. 4.2.1).

A body directory holds ``u0.dat``, ``modeShapeMatrix.dat``, ``mij.dat``,
``stiffnessMatrix.dat`` (:mod:`preprocess.textfiles`, Listings 4.1-4.5) and
``body.h5`` (:mod:`preprocess.hdf5file`, which also keeps eigenvalues, node groups,
surface, material and params). :func:`write_body` writes all five atomically.
"""

from __future__ import annotations

import os
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

    ``path`` is a directory — its text files if any of them is present (read in
    ``units``), else its ``body.h5`` — or a ``.h5``/``.hdf5`` file (always SI; ``units``
    applies to text files only). Anything else raises InputFileError.
    """
    unit_system(units)
    path = Path(path)
    if path.is_dir():
        if any((path / name).exists() for name in TEXT_FILES):
            return read_text_body(path, units)
        if (path / HDF5_FILE).exists():
            return read_hdf5(path / HDF5_FILE)
        raise InputFileError(path, None, f"no body files: expected {', '.join(TEXT_FILES)}"
                                         f" or {HDF5_FILE}")
    if path.suffix.lower() in HDF5_SUFFIXES:
        return read_hdf5(path)
    fault = "not a body directory or .h5/.hdf5 file" if path.exists() else "not found"
    raise InputFileError(path, None, fault)


def write_body(directory, body: BodyData, units: str = "si") -> None:
    """Write the four text files (in ``units``) and ``body.h5`` (SI) into ``directory``.

    Atomic per file set: everything is first written to hidden temporary files in
    ``directory`` (created if missing), then each is moved into place with
    ``os.replace``; on any exception the temporaries are removed and the exception
    re-raised, so no half-written file is left.
    """
    unit_system(units)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    token = uuid.uuid4().hex
    temporaries = {name: directory / f".{name}.{token}.tmp" for name in (*TEXT_FILES, HDF5_FILE)}
    try:
        write_text_files({name: temporaries[name] for name in TEXT_FILES}, body, units)
        write_hdf5(temporaries[HDF5_FILE], body)
        for name in list(temporaries):
            os.replace(temporaries.pop(name), directory / name)
    except BaseException:
        for temporary in temporaries.values():
            temporary.unlink(missing_ok=True)
        raise
