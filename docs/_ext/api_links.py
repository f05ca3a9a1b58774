"""Two small fixes of how the API reference links names.

1. A package re-exports the names of its modules (``mbs.System`` is
   ``mbs.system.System``). The reference documents each object once, in its defining
   module, so a reference to the re-exported name (``:class:`mbs.System```) is resolved
   by importing it and following ``__module__`` to the defining module's entry.
2. The numpy-style docstrings give types in prose with shapes and units ("(N, 3) ndarray
   [m]"). Sphinx would try to link every word of a ``:type:``, ``:vartype:`` or
   ``:rtype:`` field (``N``, ``m`` ...) to any attribute of that name; such a type is
   shown as text instead. An attribute entry naming several attributes
   (``w_N1, w_N2 : (nu1,), (nu2,)``) becomes one field per name: Sphinx would read the
   first name as a type.
3. The docstrings write math in plain text, where ``|x|`` is a magnitude; reST would read
   it as a substitution reference. A bar outside literals, roles and literal blocks is
   shown as a bar.
"""
from __future__ import annotations

import importlib
import re

from sphinx.util.nodes import make_refnode

_TYPE_FIELD = re.compile(r"^(\s*:(?:type|vartype|rtype)(?: [^:]+)?:)\s+(\S.*)$")
_LITERAL = re.compile(r"(``.+?``|:[\w:.-]+:`[^`]*`|`[^`]*`_{0,2})")       # literals, roles, interpreted text
_BLOCK_START = re.compile(r"(::\s*$)|(^\s*\.\. [\w:-]+::)")          # a literal block or a directive follows


def _defining_name(target: str) -> str | None:
    """``pkg.sub.Name[.attr]`` for a re-exported ``pkg.Name[.attr]`` (None if it is not one)."""
    parts = target.split(".")
    for cut in range(len(parts) - 1, 0, -1):          # the longest importable module prefix
        module_name = ".".join(parts[:cut])
        try:
            obj = importlib.import_module(module_name)
        except ImportError:
            continue
        try:
            for attr in parts[cut:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        home = getattr(obj, "__module__", None)
        qualname = getattr(obj, "__qualname__", None)
        if not home or not qualname or f"{home}.{qualname}" == target:
            return None
        return f"{home}.{qualname}"
    return None


def resolve_reexport(app, env, node, contnode):
    """``missing-reference`` handler: link a re-exported name to its defining module's entry."""
    if node.get("refdomain") != "py":
        return None
    target = _defining_name(node.get("reftarget", ""))
    if target is None:
        return None
    domain = env.get_domain("py")
    entry = domain.objects.get(target)
    if entry is None:
        return None
    return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, target)


_SHARED_FIELD = re.compile(r"^:(ivar|vartype) ([^:]+,[^:]*):(.*)$")


def _fields_per_name(lines: list) -> list:
    """``:ivar a, b: text`` (and its indented continuation) as ``:ivar a: text``, ``:ivar b: text``."""
    out, i = [], 0
    while i < len(lines):
        m = _SHARED_FIELD.match(lines[i])
        j = i + 1
        while m and j < len(lines) and lines[j][:1].isspace() and lines[j].strip():
            j += 1
        if m:
            for name in (n.strip() for n in m.group(2).split(",") if n.strip()):
                out += [f":{m.group(1)} {name}:{m.group(3)}"] + lines[i + 1:j]
        else:
            out += lines[i:j]
        i = j
    return out


def types_as_text(app, what, name, obj, options, lines):
    """``autodoc-process-docstring`` handler (after napoleon): one attribute field per
    name, type fields as emphasized text."""
    lines[:] = _fields_per_name(lines)
    for i, line in enumerate(lines):
        m = _TYPE_FIELD.match(line)
        if m and not m.group(2).startswith("*") and "`" not in m.group(2):     # a role stays a link
            text = m.group(2).replace("*", "\\*")
            lines[i] = f"{m.group(1)} *{text}*"


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _bars_escaped(line: str) -> str:
    parts = _LITERAL.split(line)
    return "".join(p if i % 2 else p.replace("|", "\\|") for i, p in enumerate(parts))


def bars_as_text(app, what, name, obj, options, lines):
    """``autodoc-process-docstring`` handler: ``|`` of plain-text math as a bar, not a
    substitution (literal blocks, directives' bodies, literals and roles untouched)."""
    block_indent = None                       # the indent of the line that opened a literal block
    for i, line in enumerate(lines):
        if block_indent is not None:
            if not line.strip() or _indent(line) > block_indent:
                continue
            block_indent = None
        lines[i] = _bars_escaped(line) if "|" in line else line
        if _BLOCK_START.search(line):
            block_indent = _indent(line)


def setup(app):
    app.connect("missing-reference", resolve_reexport)
    app.connect("autodoc-process-docstring", types_as_text, priority=900)
    app.connect("autodoc-process-docstring", bars_as_text, priority=910)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
