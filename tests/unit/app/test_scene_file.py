"""The scene-file package's pieces on their own: the line of every key path (reading),
the schema's tables against the library's registries and signatures, and the checked
access of a table against its Key (tables)."""

from __future__ import annotations

import inspect
import re
import sys

import numpy as np
import pytest

from contact import LAWS, PAIR_KINEMATICS
from contours import CONTOURS
from ffrmbs.errors import InputFileError
from ffrmbs_app.scene_file import schema
from ffrmbs_app.scene_file.reading import KeyLines, parse
from ffrmbs_app.scene_file.schema import REQUIRED, Key
from ffrmbs_app.scene_file.tables import Table
from mbs import BODIES, INTEGRATORS, LOADS

if sys.version_info >= (3, 11):
    import tomllib
else:   # pragma: no cover
    import tomli as tomllib


# --- reading: key lines ---------------------------------------------------------------------------------

TEXT = '''\
[scene]
t_end = 1.0
"quoted key" = 2
a . b.c = 3
[scene.options]
theta = 0.5
[[body]]
name = "one"
frame = { body = "x", node = 3 }
[[body]]
  name = "two"
[body.sub]
x = 1
[[body.parts]]
y = 2
[[body.parts]]
y = 3
text = """
z = 4
"""
after = 5
values = [
  1, 2,
]
last = 6
'''

# key path -> the text of its line (found in TEXT by search, not by the scanner)
EXPECTED = {
    ("scene",): "[scene]",
    ("scene", "t_end"): "t_end = 1.0",
    ("scene", "quoted key"): '"quoted key" = 2',
    ("scene", "a", "b", "c"): "a . b.c = 3",
    ("scene", "options"): "[scene.options]",
    ("scene", "options", "theta"): "theta = 0.5",
    ("body", 0): "[[body]]",
    ("body", 0, "name"): 'name = "one"',
    ("body", 0, "frame"): "frame = { body",
    ("body", 0, "frame", "node"): "frame = { body",          # inline tables keep to one line
    ("body", 1, "name"): '  name = "two"',
    ("body", 1, "sub"): "[body.sub]",
    ("body", 1, "sub", "x"): "x = 1",
    ("body", 1, "parts", 0, "y"): "y = 2",
    ("body", 1, "parts", 1): "[[body.parts]]",
    ("body", 1, "parts", 1, "y"): "y = 3",
    ("body", 1, "parts", 1, "text"): 'text = """',
    ("body", 1, "parts", 1, "after"): "after = 5",
    ("body", 1, "parts", 1, "values"): "values = [",
    ("body", 1, "parts", 1, "last"): "last = 6",
}


def line_of(text, start, nth=1):
    """The 1-based number of the nth line of ``text`` that starts with ``start``."""
    found = [i for i, line in enumerate(text.split("\n"), start=1) if line.startswith(start)]
    return found[nth - 1]


def test_key_lines_of_nested_tables_arrays_of_tables_and_inline_tables():
    tomllib.loads(TEXT)                                  # valid TOML
    lines = KeyLines(TEXT)
    nth = {("body", 1): 2, ("body", 1, "parts", 1): 2, ("body", 1, "parts", 1, "y"): 1}
    for path, start in EXPECTED.items():
        expected = line_of(TEXT, start, nth.get(path, 1))
        if path == ("body", 1):
            expected = line_of(TEXT, "[[body]]", 2)
        assert lines.find(path) == expected, path
    assert lines.find(("body", 1)) == line_of(TEXT, "[[body]]", 2)
    assert lines.find(("body", 1, "parts", 0)) == line_of(TEXT, "[[body.parts]]", 1)
    assert ("body", 1, "parts", 1, "z") not in lines.lines         # inside a multi-line string
    assert lines.find(("body", 1, "parts", 1, "values", 1)) == line_of(TEXT, "values = [")   # an array entry
    assert lines.find(("body", 0, "mass")) == line_of(TEXT, "[[body]]")                       # an absent key
    assert lines.find(("nothing",)) is None


def test_parse_reports_syntax_and_encoding_faults_with_their_line(tmp_path):
    with pytest.raises(InputFileError, match=r"line 2: TOML syntax error") as info:
        parse(tmp_path / "s.toml", b"[scene]\nt_end = = 1\n")
    assert info.value.line == 2
    with pytest.raises(InputFileError, match="not UTF-8") as info:
        parse(tmp_path / "s.toml", b"[scene]\n\nname = '\xff'\n")
    assert info.value.line == 3
    doc = parse(tmp_path / "s.toml", TEXT.encode())
    assert doc.data["body"][1]["parts"][1]["y"] == 3
    with pytest.raises(InputFileError) as info:
        doc.fail(("body", 1, "sub", "x"), "x is wrong")
    assert (info.value.line, info.value.fault) == (line_of(TEXT, "x = 1"), "x is wrong")


# --- the schema against the library -------------------------------------------------------------------

TYPES = ("number", "integer", "boolean", "string", "choice", "numbers", "matrix3", "table", "special")


def schema_tables():
    """(name, {key: Key}) of every table of the schema."""
    yield "SCENE", schema.SCENE
    for kind, keys in schema.BODY.items():
        yield f"BODY[{kind}]", keys
    for name in ("FRAME", "SPRING", "JOINT", "TABULATED", "CONTACT", "OUTPUT"):
        yield name, getattr(schema, name)
    for kind, keys in schema.LOAD.items():
        yield f"LOAD[{kind}]", keys
    for kind, keys in schema.CONTOUR.items():
        yield f"CONTOUR[{kind}]", keys
    for name in LAWS:
        yield f"law {name}", {**schema.law_keys(name), **schema.friction_keys(name)}
    for name in INTEGRATORS:
        yield f"options of {name}", schema.option_keys(name)


@pytest.mark.parametrize("name, keys", list(schema_tables()), ids=[n for n, _ in schema_tables()])
def test_every_key_has_a_known_type_and_is_documented(name, keys):
    doc = schema.__doc__
    for key, spec in keys.items():
        assert isinstance(spec, Key) and spec.type in TYPES, (name, key)
        if spec.type == "choice" and spec.default not in (REQUIRED, None):
            assert spec.default in tuple(spec.choices), (name, key)
        if not name.startswith(("options", "law")):
            assert re.search(rf"``{key}``|``\[scene\.{key}\]``|[{{,] {key}[ ,]|\b{key} =", doc), \
                f"{name}: key {key!r} is not in the schema's documentation"


def test_the_kinds_of_the_schema_are_the_registered_ones():
    assert tuple(schema.BODY) == BODIES.names()
    assert tuple(schema.LOAD) == LOADS.names()
    assert set(schema.CONTOUR) == set(schema.CONTOUR1_KINDS) | set(schema.CONTOUR2_KINDS)
    assert set(schema.CONTOUR) <= set(CONTOURS.names())
    for kind1 in schema.CONTOUR1_KINDS:                   # every pair the schema offers has kinematics
        point = "point" if kind1 in schema.FACE_KINDS else kind1       # a face: a point at each node
        for kind2 in schema.CONTOUR2_KINDS:
            if (point, kind2) != ("point", "edge"):       # a point's distance to a curve is never negative:
                assert (point, kind2) in PAIR_KINEMATICS, (kind1, kind2)    # only a sphere touches an edge
    assert ("point", "edge") not in PAIR_KINEMATICS


@pytest.mark.parametrize("law", LAWS.names())
def test_law_keys_are_the_float_parameters_of_the_law_class(law):
    """Against the class's signature: the parameters annotated float, required exactly
    when the signature has no default (unless the schema gives one)."""
    keys = schema.law_keys(law)
    parameters = inspect.signature(LAWS[law]).parameters
    floats = [p for p in parameters.values() if p.annotation in ("float", float)]
    assert list(keys) == [p.name for p in floats]
    for p in floats:
        overridden = p.name in schema.LAW_DEFAULTS.get(law, {})
        assert keys[p.name].required == (p.default is inspect.Parameter.empty and not overridden), p.name


@pytest.mark.parametrize("integrator", INTEGRATORS.names())
def test_option_keys_are_the_integrator_keywords(integrator):
    keys = schema.option_keys(integrator)
    parameters = dict(inspect.signature(INTEGRATORS[integrator]).parameters)
    if integrator == "moreau-adaptive":
        parameters.update(inspect.signature(INTEGRATORS["moreau"]).parameters)
    expected = {k for k, p in parameters.items() if k != "system" and p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
    assert set(keys) == expected
    if "solver" in keys:
        assert tuple(keys["solver"].choices) == ("gauss-seidel", "jacobi", "newton")


# --- tables: checked access by Key ---------------------------------------------------------------------

class Fault(str):
    """A fragment of the expected fault message."""


CASES = [
    # (Key, value, the value read, or Fault(a fragment of the message))
    (Key("number", unit="s", low=0.0, strict=True), 2, 2.0),
    (Key("number", unit="s", low=0.0, strict=True), 0.0, Fault("'v' must be > 0 [s], got 0.0")),
    (Key("number", high=1.0), 1.5, Fault("'v' must be <= 1, got 1.5")),
    (Key("number", unit="m"), "1", Fault("'v' must be a number [m], got a string ('1')")),
    (Key("number"), float("inf"), Fault("'v' must be finite")),
    (Key("number", unit="N"), 1e13, Fault("'v': 10000000000000.0 [N] is beyond the bound |x| <= 1e+12")),
    (Key("integer", low=2), 3, 3),
    (Key("integer", low=2), 1, Fault("'v' must be >= 2, got 1")),
    (Key("integer", low=0, high=5), 6, Fault("'v' must be in 0..5, got 6")),
    (Key("integer"), 2 ** 63, Fault("'v' must be an integer (64 bits)")),
    (Key("integer"), True, Fault("'v' must be an integer (64 bits), got a boolean (true)")),
    (Key("boolean"), 1, Fault("'v' must be true or false, got an integer (1)")),
    (Key("string"), 3, Fault("'v' must be a string, got an integer (3)")),
    (Key("choice", choices=("a", "b")), "b", "b"),
    (Key("choice", choices=LAWS), "glue", Fault("'v' must be one of 'impact', 'coulomb', 'penalty', 'bilateral'")),
    (Key("numbers", size=3, unit="m"), [1, 2, 3], np.array([1.0, 2.0, 3.0])),
    (Key("numbers", size=3, unit="m"), [1, 2], Fault("'v' must be an array of 3 numbers [m], got an array of 2")),
    (Key("numbers", low=0.0), [1, -2], Fault("'v' must hold numbers >= 0")),
    (Key("numbers"), [1, "x"], Fault("entry 2 is a string ('x')")),
    (Key("matrix3"), [[1, 0, 0], [0, 1, 0], [0, 0, 1]], np.eye(3)),
    (Key("matrix3", unit="kg m²"), [[1, 0, 0]], Fault("'v' must be a 3 x 3 matrix [kg m²] (three rows of three numbers)")),
]


@pytest.mark.parametrize("spec, value, expected", CASES)
def test_table_get_checks_the_value_against_its_key(tmp_path, spec, value, expected):
    doc = parse(tmp_path / "t.toml", b"[entry]\nv = 0\n")
    t = Table(doc, {"v": value}, ("entry",), "entry #1", {"v": spec})
    if isinstance(expected, Fault):
        with pytest.raises(InputFileError) as info:
            t.get("v")
        assert info.value.line == 2 and info.value.fault.startswith("entry #1: ")
        assert expected in info.value.fault, info.value.fault
    else:
        np.testing.assert_array_equal(t.get("v"), expected)


def test_table_defaults_required_keys_and_unknown_keys(tmp_path):
    doc = parse(tmp_path / "t.toml", b"[entry]\nv = 0\n")
    keys = {"v": Key("number", 1.5), "w": Key("integer")}
    t = Table(doc, {}, ("entry",), "entry #1", keys)
    assert t.get("v") == 1.5 and t.get("v", 2.5) == 2.5
    with pytest.raises(InputFileError, match="entry #1: missing required key 'w'") as info:
        t.get("w")
    assert info.value.line == 1
    with pytest.raises(InputFileError, match=r"entry #1: unknown key 'x' \(allowed: v, w\)") as info:
        Table(doc, {"x": 1}, ("entry",), "entry #1", keys)
    Table(doc, {"x": 1}, ("entry",), "entry #1", None)      # a head table checks no keys
