"""Overrides of scene-file values from the command line: ``--set KEY=VALUE``.

KEY is a dotted path into the scene file's tables: ``scene.dt``, ``scene.options.theta``;
the entries of the arrays of tables ([[body]], [[spring]], [[joint]], [[load]],
[[contact]]) are named by their ``name`` (``body.beam.modes``, ``contact.impact.e``) or
by their 0-based index (``load.0.force``); a name that is not a bare TOML key is quoted
as in TOML (``'body."point mass".mass=1.0'``). VALUE is parsed as a TOML value (``5e-6``,
``50``, ``true``, ``[0.0, 1.0, 0.0]``, ``"fixed"``); a bare word that is no TOML value is
taken as a string (``--set contact.impact.contour2.kind=band``).

The overrides are applied to the parsed file before any check, so an overridden value is
checked exactly as the same value written in the file; its faults name the ``--set``
that gave it instead of a line.
"""

from __future__ import annotations

import re
import sys

from ffrmbs.errors import InputFileError

from .reading import DOTTED, key_parts

if sys.version_info >= (3, 11):
    import tomllib
else:   # pragma: no cover - Python 3.10
    import tomli as tomllib

#: the arrays of tables, whose entries a key names by ``name`` or index
ARRAYS = ("body", "spring", "joint", "load", "contact")
_BARE_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_.+\-]*")


def split_override(text: str) -> tuple[str, str]:
    """(KEY, VALUE) of ``KEY=VALUE``, split at the first ``=`` outside quotes."""
    quote = None
    for i, ch in enumerate(text):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "=":
            return text[:i].strip(), text[i + 1:].strip()
    raise ValueError("expected KEY=VALUE")


def parse_value(text: str):
    """The TOML value of ``text``; a bare word that is no TOML value is that string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        if _BARE_WORD.fullmatch(text):
            return text
        raise ValueError(f"{text!r} is not a TOML value (a number, true/false, \"text\", [a, b, ...])") from None


def apply_overrides(path, data: dict, overrides) -> dict:
    """Set each ``KEY=VALUE`` of ``overrides`` in the TOML ``data`` of the scene file
    ``path`` (in order; a later one wins). Returns {key path (tuple): the override's
    text}. A malformed override, an entry name the file does not have, or a path through
    a value is an InputFileError naming the ``--set``."""
    given = {}
    for text in overrides:
        try:
            key, value = split_override(text)
            if not re.fullmatch(DOTTED, key):
                raise ValueError(f"{key!r} is not a dotted key such as scene.dt or body.beam.modes")
            keypath = _set(data, key_parts(key), parse_value(value))
        except ValueError as exc:
            raise InputFileError(path, None, f"--set {text}: {exc}") from None
        given[keypath] = text
    return given


def _set(data: dict, parts: tuple, value) -> tuple:
    """Set ``value`` at the dotted ``parts`` of ``data``; returns its key path (with the
    indices of the array entries)."""
    node, keypath = data, ()
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(node, list):
            index = _entry(node, part, keypath)
            if last:
                raise ValueError(f"{_dotted(keypath + (part,))} is an entry of [[{keypath[0]}]]: name one of its "
                                 "keys after it")
            node, keypath = node[index], keypath + (index,)
            continue
        if not isinstance(node, dict):
            raise ValueError(f"{_dotted(keypath)} is a value, not a table")
        if last:
            node[part] = value
            return keypath + (part,)
        if part not in node:
            if not keypath and part in ARRAYS:
                raise ValueError(f"the scene file has no [[{part}]] entries")
            node[part] = {}
        node, keypath = node[part], keypath + (part,)
    return keypath


def _entry(entries: list, part: str, keypath: tuple) -> int:
    """The index of the entry of an array of tables named ``part`` (or numbered)."""
    names = [e.get("name") if isinstance(e, dict) else None for e in entries]
    if part in names:
        return names.index(part)
    if part.isdigit() and int(part) < len(entries):
        return int(part)
    listed = ", ".join(repr(n) for n in names if n is not None) or "none named"
    raise ValueError(f"no [[{keypath[-1]}]] entry {part!r} (entries: {listed}; or 0..{len(entries) - 1})")


def _dotted(keypath: tuple) -> str:
    return ".".join(str(k) for k in keypath)
