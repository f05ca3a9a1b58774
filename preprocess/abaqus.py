"""Abaqus ``.inp`` files: what meshio does not check, or reports without a line.

meshio reads ``.inp`` files (:mod:`preprocess.mesh_files`). Before it does,
:func:`check_includes` makes sure every file an ``*INCLUDE`` pulls in is a regular
file (meshio would block on a FIFO). When meshio fails, :func:`inp_fault` scans the
file once more, only then, for the line of the fault: an element type it cannot read,
or an element or node set that refers to a node no ``*NODE`` block defines. Abaqus
keyword lines start with ``*`` (``**`` is a comment); a data line ending with a comma
continues on the next line.
"""

from __future__ import annotations

import re
from pathlib import Path

from ffrmbs.errors import quote
from preprocess.inputfiles import include_tree

#: Abaqus element types read as tetrahedra (tet4, tet10)
TET_TYPES = ("C3D4", "C3D10", "C3D10H", "C3D10I", "C3D10M", "C3D10MH")

_UNKNOWN_TYPE = re.compile(r"Element type not available: (\S+)")
_INCLUDE = re.compile(r"^[ \t]*\*[ \t]*INCLUDE\b.*$", re.IGNORECASE | re.MULTILINE)


def _keyword(line: str) -> tuple[str, dict]:
    """The keyword (upper case) of a ``*KEYWORD, KEY=VALUE, ...`` line and its parameters."""
    words = line[1:].split(",")
    params = {}
    for word in words[1:]:
        key, _, value = word.partition("=")
        params[key.strip().upper()] = value.strip()
    return words[0].strip().upper(), params


def check_includes(path) -> None:
    """InputFileError if ``path`` or a file it includes (``*INCLUDE, INPUT=...``, at any
    depth) is not a regular file. Included paths are resolved as meshio does: as given,
    else relative to the including file's directory."""
    def includes(current, text):
        for line in _INCLUDE.findall(text):
            included = Path(line.split("=")[-1].strip())
            yield included if included.exists() else current.parent / included

    for _ in include_tree(path, includes):
        pass


def _records(lines):
    """(keyword, parameters, first line number, fields) of every data record, the
    fields being the record's comma-separated words."""
    keyword, params, record, start = None, {}, [], None
    for lineno, line in enumerate(lines, start=1):
        text = line.strip()
        if text.startswith("**") or not text:
            continue
        if text.startswith("*"):
            keyword, params = _keyword(text)
            continue
        record.append(text.rstrip(","))
        start = start or lineno
        if not text.endswith(","):
            yield keyword, params, start, [v.strip() for v in ",".join(record).split(",") if v.strip()]
            record, start = [], None


def _labels(fields) -> list[int]:
    """The integers among ``fields`` (node or element labels; others skipped)."""
    return [int(v) for v in fields if v.lstrip("+-").isdigit()]


def inp_fault(path, error: Exception) -> tuple[int | None, str] | None:
    """(line, fault) of the fault behind meshio's ``error`` reading the ``.inp`` file
    ``path``, or None if the scan does not find it."""
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().split("\n")
    unknown = _UNKNOWN_TYPE.search(str(error))
    if unknown:
        fault = f"element type {quote(unknown[1])} not supported (supported: {', '.join(TET_TYPES)})"
        for lineno, line in enumerate(lines, start=1):
            text = line.strip()
            if text.startswith("*") and not text.startswith("**"):
                keyword, params = _keyword(text)
                if keyword == "ELEMENT" and params.get("TYPE") == unknown[1]:
                    return lineno, fault
        return None, fault
    if not isinstance(error, KeyError):
        return None
    records = list(_records(lines))
    nodes = {_labels(fields[:1])[0] for keyword, _, _, fields in records
             if keyword == "NODE" and _labels(fields[:1])}
    for keyword, params, lineno, fields in records:
        labels = _labels(fields)
        if keyword == "ELEMENT":
            bad = [n for n in labels[1:] if n not in nodes]
            if bad:
                return lineno, f"element {labels[0]} refers to node {bad[0]}, which is not defined"
        if keyword == "NSET" and "GENERATE" not in params:
            bad = [n for n in labels if n not in nodes]
            if bad:
                return lineno, (f"node set {quote(params.get('NSET', '?'))} refers to node {bad[0]}, "
                                "which is not defined")
    return None
