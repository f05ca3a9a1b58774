"""Reading a scene file: TOML text -> a dict (parsed by :mod:`tomllib`) and the line of
every key path (:class:`KeyLines`).

tomllib (the standard library's TOML 1.0 parser; ``tomli`` on Python 3.10) returns plain
dicts without positions, and no maintained Python TOML package reports the line of a
key (tomlkit keeps the text's layout, but not line numbers), so :class:`KeyLines` finds
them with a small line scanner run on text tomllib has accepted. Faults raise
:class:`~ffrmbs.errors.InputFileError` with the file and, where known, the line.
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

from ffrmbs.errors import InputFileError, os_reason
from preprocess.inputfiles import regular_file

if sys.version_info >= (3, 11):
    import tomllib
else:   # pragma: no cover - Python 3.10
    import tomli as tomllib

_KEY = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')"""
#: a dotted TOML key (bare or quoted parts)
DOTTED = rf"{_KEY}(?:[ \t]*\.[ \t]*{_KEY})*"
_ARRAY_HEADER = re.compile(rf"[ \t]*\[\[[ \t]*({DOTTED})[ \t]*\]\]")
_TABLE_HEADER = re.compile(rf"[ \t]*\[[ \t]*({DOTTED})[ \t]*\]")
_KEY_VALUE = re.compile(rf"[ \t]*({DOTTED})[ \t]*=[ \t]*(.*)")


def key_parts(dotted: str) -> tuple:
    """The keys of a dotted TOML key: 'contour2."kind"' -> ("contour2", "kind")."""
    parts = []
    for part in re.findall(_KEY, dotted):
        if part.startswith('"'):
            try:
                part = json.loads(part)
            except ValueError:
                part = part[1:-1]
        elif part.startswith("'"):
            part = part[1:-1]
        parts.append(part)
    return tuple(parts)


class KeyLines:
    """1-based line numbers of the tables and keys of a TOML text. A key path is a tuple
    such as ("body", 0, "modes"), where the entries of an array of tables count from 0.

    A line scanner, not a parser, for text that tomllib accepted: it reads table headers
    (``[a.b]``, ``[[a]]``) and ``key = value`` lines (dotted keys too) and skips the
    inside of multi-line strings. A key inside an inline table (which TOML keeps on one
    line) or a multi-line array takes the line of its enclosing key.
    """

    def __init__(self, text: str):
        self.lines: dict = {}
        arrays: dict = {}           # path of an array of tables -> index of its last entry
        current: tuple = ()
        closing = None              # delimiter of an open multi-line string
        for lineno, line in enumerate(text.split("\n"), start=1):     # tomllib counts "\n" only
            if closing is not None:
                if closing in line:
                    closing = None
                continue
            header = _ARRAY_HEADER.match(line)
            if header:
                path = self._resolve(key_parts(header[1]), arrays)
                self.lines.setdefault(path, lineno)
                arrays[path] = arrays.get(path, -1) + 1
                current = path + (arrays[path],)
                self.lines.setdefault(current, lineno)
                continue
            header = _TABLE_HEADER.match(line)
            if header:
                current = self._resolve(key_parts(header[1]), arrays)
                self.lines.setdefault(current, lineno)
                continue
            pair = _KEY_VALUE.match(line)
            if pair:
                self.lines.setdefault(current + key_parts(pair[1]), lineno)
                for delimiter in ('"""', "'''"):
                    rest = pair[2]
                    if rest.startswith(delimiter) and rest.count(delimiter) == 1:
                        closing = delimiter

    @staticmethod
    def _resolve(parts, arrays) -> tuple:
        """The key path of a header: each array of tables on the way is its last entry."""
        path: tuple = ()
        for i, part in enumerate(parts):
            path += (part,)
            if path in arrays and i < len(parts) - 1:
                path += (arrays[path],)
        return path

    def find(self, path) -> int | None:
        """The line of ``path``, or of its longest prefix that has one (None if none)."""
        path = tuple(path)
        for k in range(len(path), 0, -1):
            if path[:k] in self.lines:
                return self.lines[path[:k]]
        return None


@dataclass
class Document:
    """A parsed scene file: its path, the TOML data, the lines of its keys and the
    overridden key paths (key path -> the ``--set`` text that gave the value,
    :mod:`.overrides`)."""

    path: Path
    data: dict
    lines: KeyLines
    overridden: dict = field(default_factory=dict)

    def fail(self, keypath, fault):
        """Raise InputFileError at the line of ``keypath`` (a tuple of keys), or naming the
        ``--set`` that gave the value at ``keypath`` or above it."""
        keypath = tuple(keypath)
        for given, text in self.overridden.items():
            if keypath[:len(given)] == given:
                raise InputFileError(self.path, None, f"{fault} (the value of --set {text})")
        raise InputFileError(self.path, self.lines.find(keypath), fault)


def parse(path: Path, raw: bytes) -> Document:
    """The Document of the TOML bytes ``raw`` of file ``path``; undecodable text and
    syntax errors as InputFileError with the line."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputFileError(path, raw[:exc.start].count(b"\n") + 1,
                             "not UTF-8 text (a TOML scene file is UTF-8)") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        line, column = getattr(exc, "lineno", None), getattr(exc, "colno", None)
        where = re.search(r"\(at line (\d+), column (\d+)\)", message)
        if line is None and where:
            line, column = int(where[1]), int(where[2])
        elif line is None and "end of document" in message:
            line = text.count("\n") + 1
        fault = getattr(exc, "msg", None) or re.sub(r"\s*\(at (line \d+, column \d+|end of document)\)", "",
                                                    message)
        raise InputFileError(path, line, f"TOML syntax error: {fault}"
                             + (f" (column {column})" if column else "")) from None
    return Document(path, data, KeyLines(text))


def read_toml(path) -> Document:
    """The Document of the scene file ``path`` (a regular file: never a FIFO or a device)."""
    path = regular_file(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read the scene file: {os_reason(exc)}") from None
    return parse(path, raw)
