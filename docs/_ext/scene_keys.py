"""The scene-file key reference, generated from the schema when the docs build.

``.. scene-keys::`` inserts :func:`reference_text`: the schema module's own description
(:mod:`ffrmbs_app.scene_file.schema`, the prose reference with its example), then one table
per table of a scene file — every :class:`~ffrmbs_app.scene_file.schema.Key` with its type,
unit, default, allowed values or bounds and its description, read from the schema's data
and the library's registries, so nothing here is written twice.
"""
from __future__ import annotations

import inspect

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx.util.nodes import nested_parse_with_titles

from api_links import bars_as_text
from ffrmbs.registry import Registry
from ffrmbs_app.scene_file import schema
from mbs.integrators import MoreauTimeStepping

COLUMNS = ("key", "type", "unit", "default", "allowed values", "description")


def _choices(choices) -> str:
    names = choices.names() if isinstance(choices, Registry) else tuple(choices)
    return ", ".join(f'``"{n}"``' for n in names)


def _bounds(key: schema.Key) -> str:
    """"> 0", ">= 2", "1 .. 9" or ""."""
    if key.low is not None and key.high is not None:
        return f"{key.low:g} .. {key.high:g}"
    if key.low is not None:
        return f"{'>' if key.strict else '>='} {key.low:g}"
    if key.high is not None:
        return f"<= {key.high:g}"
    return ""


def allowed(key: schema.Key) -> str:
    """The allowed values of a key: its choices, or its bounds, or its size."""
    parts = []
    if key.type == "choice" and key.choices:
        parts.append(_choices(key.choices))
    if _bounds(key):
        parts.append(("each " if key.type == "numbers" else "") + _bounds(key))
    if key.type == "numbers":
        parts.append(f"{key.size} numbers" if key.size else "1 or more numbers")
    return "; ".join(parts)


def default(value) -> str:
    """A default as TOML would spell it."""
    if value is schema.REQUIRED:
        return "no default"
    if value is None:
        return "optional"
    if isinstance(value, bool):
        return f"``{str(value).lower()}``"
    if isinstance(value, str):
        return f'``"{value}"``'
    if isinstance(value, (tuple, list)):
        return "``[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]``"
    if isinstance(value, dict):
        return "``{}``" if not value else f"``{value}``"
    if isinstance(value, float):
        return f"``{value:g}``"
    return f"``{value}``"


def _cell(text: str) -> str:
    return text.replace("\n", " ").strip() or " "


def key_table(title: str, keys: dict, defaults: dict | None = None, intro: str = "") -> list[str]:
    """An RST section ``title`` with a list-table of ``keys`` ({name: Key}); ``defaults``
    overrides the default column (an integrator's signature defaults)."""
    lines = [title, "~" * len(title), ""]
    if intro:
        lines += [intro, ""]
    if not keys:
        return lines
    lines += [".. list-table::", "   :header-rows: 1", "   :widths: 14 9 8 12 22 35", ""]
    lines += ["   * - " + COLUMNS[0]] + [f"     - {c}" for c in COLUMNS[1:]]
    for name, key in keys.items():
        shown = default((defaults or {}).get(name, key.default))
        row = (f"``{name}``", key.type, f"[{key.unit}]" if key.unit else "", shown, allowed(key), key.doc)
        lines += [f"   * - {_cell(row[0])}"] + [f"     - {_cell(c)}" for c in row[1:]]
    return lines + [""]


def _signature_defaults(integrator: str) -> dict:
    """The defaults of an integrator's keyword options, from its signature (as option_keys reads them)."""
    cls = schema.INTEGRATORS[integrator]
    params = dict(inspect.signature(cls.__init__).parameters)
    if integrator == "moreau-adaptive":
        params.update(inspect.signature(MoreauTimeStepping.__init__).parameters)
    return {n: p.default for n, p in params.items() if p.default is not inspect.Parameter.empty}


def tables() -> list[tuple[str, dict, dict | None, str]]:
    """(title, {key: Key}, defaults or None, intro) of every table a scene file has."""
    out = [("[scene]", schema.SCENE, None, "Top-level tables and arrays of tables: "
            + ", ".join(f"``{t}``" for t in schema.TOP_LEVEL) + ".")]
    for name in schema.INTEGRATORS.names():
        out.append((f'[scene.options] of integrator = "{name}"', schema.option_keys(name),
                    _signature_defaults(name), ""))
    for kind, keys in schema.BODY.items():
        out.append((f'[[body]] kind = "{kind}"', keys, None, ""))
    out.append(("frame tables (frame1, frame2, loads, outputs, contours)", schema.FRAME, None,
                "At most one of ``node``, ``at`` and ``point``."))
    out.append(("[[spring]]", schema.SPRING, None, ""))
    out.append(("[[joint]]", schema.JOINT, None, ""))
    for kind, keys in schema.LOAD.items():
        out.append((f'[[load]] kind = "{kind}"', keys, None, ""))
    out.append(("time functions (a force or torque given as a table)", schema.TABULATED, None, ""))
    out.append(("[[contact]]", schema.CONTACT, None, "Plus the law's parameters (below)."))
    for kind in schema.CONTOUR1_KINDS:
        out.append((f'contour1 kind = "{kind}"', schema.CONTOUR[kind], None, ""))
    for kind in schema.CONTOUR2_KINDS:
        out.append((f'contour2 kind = "{kind}"', schema.CONTOUR[kind], None, ""))
    for law in schema.LAWS.names():
        keys = {**schema.law_keys(law), **schema.friction_keys(law)}
        cls = schema.LAWS[law]
        out.append((f'law = "{law}"', keys, None,
                    f"The parameters of :class:`{cls.__module__}.{cls.__qualname__}`"
                    + (" (friction: both ``mu`` and ``v_eps`` or neither)." if schema.friction_keys(law) else ".")
                    + ("" if keys else " It has none.")))
    out.append(("[outputs] (one table per output)", schema.OUTPUT, None,
                "Units of the quantities: " + ", ".join(f"{q} [{u}]" for q, u in schema.QUANTITY_UNITS.items())
                + "; ``q_f`` in the modes' normalization."))
    return out


def reference_text() -> str:
    """The whole generated reference, RST."""
    lines = [inspect.cleandoc(schema.__doc__), "", "Tables of keys", "==============", "",
             "Generated from :mod:`ffrmbs_app.scene_file.schema` when these pages were built: "
             "every key of every table, its type, unit, default, the allowed values and its note.",
             "*no default* marks a key that has to be given when its table needs it, *optional* one "
             "that may be left out (the description above says what each means then).", ""]
    for title, keys, defaults, intro in tables():
        lines += key_table(title, keys, defaults, intro)
    return "\n".join(lines)


class SceneKeys(Directive):
    """``.. scene-keys::``: the generated reference, parsed in place."""

    has_content = False

    def run(self):
        container = nodes.container()
        lines = reference_text().splitlines()
        bars_as_text(None, "module", schema.__name__, schema, {}, lines)      # |x| of plain-text math
        text = StringList(lines, source="ffrmbs_app/scene_file/schema.py")
        nested_parse_with_titles(self.state, text, container)
        return container.children


def setup(app):
    app.add_directive("scene-keys", SceneKeys)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
