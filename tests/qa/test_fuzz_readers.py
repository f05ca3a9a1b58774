"""Fuzzing the readers: body files (the thesis's text files, body.h5) and TOML scene files.

Each test starts from a valid input written by the project's own writers, mutates it
(hypothesis, derandomized so CI is reproducible) and requires that reading either
succeeds with consistent data or raises InputFileError naming the file at fault. For
text files and scene files the error also gives the line, and for scene files the key,
when the mutation pins them down. No other exception may escape. The last test makes
``preprocess.write_body`` fail at each step and requires that the directory keeps the
old file set, or stays empty, with no partial file.

Not fuzzed: random byte corruption inside body.h5. The HDF5 C library can hang or
crash the process on such files, which is beyond what a reader in Python can guard.
Truncated files are fuzzed, and structural damage through h5py is fuzzed: missing
datasets, attributes and groups, wrong dtypes and shapes.
"""

from __future__ import annotations

import copy
import functools
import json
import math
import re
import shutil
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ffrmbs.errors import InputFileError
from ffrmbs_app.scene import Scene
from ffrmbs_app.scene_file import bodies as scene_bodies
from ffrmbs_app.scene_file import read_scene
from preprocess import Material, bodyfiles, build_body, read_body, write_body
from preprocess.bodyfiles import HDF5_FILE, TEXT_FILES
from preprocess.geometry import box
from qa.fixtures import fixture_text

FUZZ = settings(deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def fuzz(examples: int):
    """Derandomized hypothesis settings with ``examples`` examples and no deadline."""
    return settings(FUZZ, max_examples=examples)


@pytest.fixture(scope="module")
def small_body():
    """The 250 x 50 x 50 mm beam meshed coarsely: tet4, 4 x 1 x 2 divisions (30 nodes),
    clamped at x = 0, 4 modes."""
    return build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(4, 1, 2)), Material(920.0, 5e7, 0.3),
                      n_modes=4, clamp="x0")


@pytest.fixture(scope="module")
def other_body():
    """Another body (2 x 1 x 1 divisions, 2 modes), whose files differ from small_body's."""
    return build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(2, 1, 1)), Material(920.0, 5e7, 0.3),
                      n_modes=2, clamp="x0")


@pytest.fixture(scope="module")
def originals(small_body, tmp_path_factory):
    """{file name: bytes} of the small body as write_body writes it, and a work directory."""
    source = tmp_path_factory.mktemp("original")
    write_body(source, small_body)
    return {name: (source / name).read_bytes() for name in (*TEXT_FILES, HDF5_FILE)}, \
        tmp_path_factory.mktemp("work")


def assert_consistent(body):
    """A body that was read: the arrays agree with each other (N nodes, n_f modes)."""
    n = body.u0.shape[0]
    assert body.u0.shape == (n, 3) and body.masses.shape == (n,) and body.phi.shape[0] == 3 * n
    assert body.stiffness.shape == (3 * n, 3 * n)
    assert np.isfinite(body.u0).all() and np.isfinite(body.phi).all() and (body.masses > 0).all()


# --- the thesis's text files -------------------------------------------------------------------------

TOKEN = re.compile(r"[^\s,%#]+")
GARBAGE = st.text(alphabet="abcdfghijklmnopqrstuvwxyzABCXYZ!@$^&*?~|<>", min_size=1, max_size=6)
NON_FINITE = st.sampled_from(["nan", "NaN", "inf", "-inf", "+Infinity", "1e999", "-1.0D+400"])
NUMBER = st.one_of(st.floats(allow_nan=False, allow_infinity=False).map(repr), st.integers(-5, 60).map(str))


@functools.lru_cache(maxsize=len(TEXT_FILES))
def data_lines(text):
    """Indices of the lines holding data, with their token spans (before any comment);
    computed once per file text (the mutations start from the original files)."""
    out = []
    for i, line in enumerate(text.split("\n")):
        data = line.split("%", 1)[0].split("#", 1)[0]
        spans = [m.span() for m in TOKEN.finditer(data)]
        if spans:
            out.append((i, spans))
    return out


@st.composite
def text_mutations(draw):
    """(file, op, argument): one mutation of one text file."""
    name = draw(st.sampled_from(TEXT_FILES))
    op = draw(st.sampled_from(["garbage", "non-finite", "number", "extra", "drop-token", "delete-line",
                               "duplicate-line", "swap", "truncate", "bytes", "empty", "remove"]))
    if op == "garbage":
        return name, op, draw(GARBAGE)
    if op == "non-finite":
        return name, op, draw(NON_FINITE)
    if op in ("number", "extra"):
        return name, op, draw(NUMBER)
    if op == "bytes":
        return name, op, draw(st.binary(min_size=1, max_size=8))
    return name, op, None


def mutate_text(text: str, op, argument, draw_index):
    """The mutated text and the 1-based line of the fault when the mutation pins one down
    (None otherwise), plus the lines whose data follows (for "extra" on a first row)."""
    rows = data_lines(text)
    i, spans = rows[draw_index(len(rows))]
    lines = text.split("\n")
    line = lines[i]
    if op in ("garbage", "non-finite", "number", "drop-token"):
        a, b = spans[draw_index(len(spans))]
        lines[i] = line[:a] + ("" if op == "drop-token" else argument) + line[b:]
        pinned = op in ("garbage", "non-finite")
    elif op == "extra":
        a = spans[-1][1]
        lines[i] = line[:a] + " " + argument + line[a:]
        pinned = True
    elif op == "delete-line":
        del lines[i]
        pinned = False
    elif op == "duplicate-line":
        lines.insert(i, line)
        pinned = False
    elif op == "swap":
        if len(spans) >= 2:
            (a1, b1), (a2, b2) = spans[0], spans[-1]
            lines[i] = line[:a1] + line[a2:b2] + line[b1:a2] + line[a1:b1] + line[b2:]
        pinned = False
    else:
        raise AssertionError(op)
    following = [r[0] + 1 for r in rows if r[0] > i][:1]
    return "\n".join(lines), (i + 1 if pinned else None), following


@pytest.mark.slow
@fuzz(600)
@given(mutation=text_mutations(), data=st.data())
def test_text_body_files_read_or_fail_with_file_and_line(originals, mutation, data):
    files, work = originals
    directory = work / "text"
    directory.mkdir(exist_ok=True)
    for name in TEXT_FILES:             # every file back to the original (one was mutated or removed)
        (directory / name).write_bytes(files[name])
    name, op, argument = mutation
    path = directory / name
    text = files[name].decode()
    line, following = None, []
    if op == "truncate":
        path.write_bytes(files[name][:data.draw(st.integers(0, len(files[name]) - 1))])
    elif op == "bytes":
        k = data.draw(st.integers(0, len(files[name])))
        path.write_bytes(files[name][:k] + argument + files[name][k:])
    elif op == "empty":
        path.write_bytes(b"")
    elif op == "remove":
        path.unlink()
    else:
        mutated, line, following = mutate_text(text, op, argument, lambda n: data.draw(st.integers(0, n - 1)))
        path.write_text(mutated)
    try:
        body = read_body(directory)
    except InputFileError as error:
        assert Path(error.path).parent == directory and Path(error.path).name in TEXT_FILES, error
        if line is not None:
            assert error.path == str(path), error
            allowed = {line, *following} if (op == "extra" and name == "modeShapeMatrix.dat") else {line}
            assert error.line in allowed, (error, line)
        if op in ("empty", "remove"):
            assert error.path == str(path) and error.line is None, error
        return
    assert line is None and op not in ("empty", "remove"), f"{op} on line {line} of {name} was accepted"
    assert_consistent(body)


# --- body.h5 -------------------------------------------------------------------------------------------

REQUIRED_DATASETS = ("u0", "phi", "masses", "stiffness/data", "stiffness/indices", "stiffness/indptr")
ROOT_ATTRIBUTES = ("format", "format_version", "units", "params")


def h5_objects(path):
    names = []
    with h5py.File(path, "r") as f:
        f.visit(names.append)
    return sorted(names)


def filled(shape, dtype, fill):
    with np.errstate(invalid="ignore", over="ignore"):
        return np.full(shape, fill).astype(dtype)


ARRAYS = st.one_of(
    st.builds(filled,
              st.sampled_from([(), (0,), (1,), (5,), (30,), (30, 3), (90, 4), (3, 30), (4,), (91,), (2, 2, 2)]),
              st.sampled_from(["f8", "f4", "i8", "i4", "u1", "?", "c16", "S4"]),
              st.sampled_from([0.0, 1.0, -1.0, 2.5, 1e300, math.nan, math.inf, 31.0, 1e5])),
    st.just(np.array("text", dtype=h5py.string_dtype())),
)
ATTRIBUTE_VALUES = st.one_of(st.integers(-3, 3), st.floats(),
                             st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"),
                                     max_size=8), st.just(np.arange(3)),
                             st.just(b"ffrmbs-body"), st.just("{}"), st.just("[1, 2]"))


@st.composite
def h5_mutations(draw, names):
    op = draw(st.sampled_from(["delete", "replace", "attribute", "delete-attribute", "shape-attribute",
                               "material", "truncate", "group-for-dataset"]))
    if op in ("delete", "replace", "group-for-dataset"):
        return op, draw(st.sampled_from(names)), draw(ARRAYS)
    if op == "attribute":
        return op, draw(st.sampled_from(ROOT_ATTRIBUTES)), draw(ATTRIBUTE_VALUES)
    if op == "delete-attribute":
        return op, draw(st.sampled_from(ROOT_ATTRIBUTES)), None
    if op == "shape-attribute":
        return op, "stiffness", draw(st.one_of(st.just(np.array([90, 91])), st.just(np.array([90])),
                                               st.just("90x90"), st.just(np.array([[90, 90]]))))
    if op == "material":
        return op, "material", draw(ATTRIBUTE_VALUES)
    return op, None, draw(st.floats(0.0, 0.999))


@fuzz(400)
@given(data=st.data())
def test_hdf5_body_file_reads_or_fails_naming_the_file(originals, data):
    files, work = originals
    path = work / "b.h5"
    path.write_bytes(files[HDF5_FILE])
    op, name, value = data.draw(h5_mutations(h5_objects(path)))
    if op == "truncate":
        path.write_bytes(files[HDF5_FILE][:int(value * len(files[HDF5_FILE]))])
    else:
        with h5py.File(path, "a") as f:
            if op in ("delete", "replace", "group-for-dataset"):
                del f[name]
                if op == "replace":
                    f[name] = value
                elif op == "group-for-dataset":
                    f.create_group(name)
            elif op == "attribute":
                f.attrs[name] = value
            elif op == "delete-attribute":
                del f.attrs[name]
            elif op == "shape-attribute":
                f["stiffness"].attrs["shape"] = value
            else:
                f["material"].attrs["density"] = value
    try:
        body = read_body(path)
    except InputFileError as error:
        assert error.path == str(path) and error.line is None, error
        if op in ("delete", "group-for-dataset") and name in REQUIRED_DATASETS:
            assert f"'{name}'" in error.fault, error
        return
    assert op != "truncate" and not (op == "delete-attribute" and name != "params") \
        and not (op == "delete" and name in REQUIRED_DATASETS), f"{op} {name} was accepted"
    assert_consistent(body)


# --- TOML scene files ----------------------------------------------------------------------------------

FUZZ_TABLES = """\
[scene]
name = "fuzz"
description = "the fuzzing base"
t_end = 0.01
dt = 1e-4
integrator = "moreau"
n_out = 3
energies = false
plan = true
tolerance = 1e-6
gravity = [0.0, -9.81, 0.0]

[scene.options]
theta = 0.5
trace = false

[[spring]]
frame1 = { body = "ground", point = [0.0, 0.3, 0.0] }
frame2 = { body = "block" }
stiffness = 10.0
damping = 0.1
free_length = 0.1

[[joint]]
kind = "revolute"
frame1 = { body = "ground", point = [0.1, 0.2, 0.0] }
frame2 = { body = "block" }
axis = [0.0, 0.0, 1.0]

[[load]]
kind = "force"
body = "beam"
node = 5
force = { times = [0.0, 0.005], values = [[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]], kind = "step", hold_first = false }
frame_fixed = false

[[load]]
kind = "distributed"
body = "beam"
nodes = "x1"
force = [0.0, 0.0, 1.0]

[[contact]]
name = "top"
contour1 = { kind = "point", body = "bob" }
contour2 = { kind = "2s", body = "beam", nodes = "y1", degree = [3, 2] }
law = "impact"
e = 0.0
margin = "auto"

[[contact]]
name = "floor"
contour1 = { kind = "sphere", body = "block", radius = 0.05 }
contour2 = { kind = "plane", point = [0.0, -1.0, 0.0], normal = [0.0, 1.0, 0.0] }
law = "penalty"
k = 1e5
d = 1.0

[outputs]
y = { body = "bob", quantity = "position", component = "y" }
tip = { body = "beam", at = [0.25, 0.05, 0.05] }
spin = { body = "block", quantity = "angular_velocity" }
"""


@functools.cache
def _parsed_base_scene() -> dict:
    return tomllib.loads(fixture_text("scenes/beam_block_bob.toml")) | tomllib.loads(FUZZ_TABLES)


def base_scene() -> dict:
    """The fuzzing base, parsed: the three bodies of scenes/beam_block_bob.toml with every
    key of [scene] and the links, loads, contacts and outputs of :data:`FUZZ_TABLES` (a
    fresh copy to mutate; the texts are parsed once)."""
    return copy.deepcopy(_parsed_base_scene())


BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def toml_key(key: str) -> str:
    return key if BARE_KEY.fullmatch(key) else toml_value(key)


def toml_value(value) -> str:
    """``value`` (what tomllib returns) written as TOML."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, list):
        return "[" + ", ".join(map(toml_value, value)) + "]"
    return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + " }"


def toml_document(doc: dict) -> str:
    """A TOML text of ``doc``: plain keys first, then each table as a [section], each
    array of tables as [[entries]]."""
    out = []

    def is_array_of_tables(v):
        return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)

    def emit(prefix, table):
        for key, value in table.items():
            if not isinstance(value, dict) and not is_array_of_tables(value):
                out.append(f"{toml_key(key)} = {toml_value(value)}")
        for key, value in table.items():
            header = ".".join(map(toml_key, prefix + (key,)))
            if isinstance(value, dict):
                out.append(f"[{header}]")
                emit(prefix + (key,), value)
            elif is_array_of_tables(value):
                for entry in value:
                    out.append(f"[[{header}]]")
                    emit(prefix + (key,), entry)

    emit((), doc)
    return "\n".join(out) + "\n"


def paths(node, prefix=()):
    """Every key path of a parsed document (dict keys and list indices)."""
    out = []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        out.append(prefix + (key,))
        out += paths(value, prefix + (key,))
    return out


def tables(node, prefix=()):
    """The key paths of every table (dict) of a parsed document, the root included."""
    out = [prefix] if isinstance(node, dict) else []
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        out += tables(value, prefix + (key,))
    return out


def get(doc, path):
    for key in path:
        doc = doc[key]
    return doc


TEXT = st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=12)
SCALARS = st.one_of(st.booleans(), st.integers(-(2 ** 70), 2 ** 70), st.integers(-3, 60), st.floats(), TEXT,
                    st.sampled_from(["beam", "bob", "ground", "all", "y1", "auto", "off", "x", "2s", "point"]))
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                       st.dictionaries(st.from_regex(BARE_KEY, fullmatch=True),
                                                                       inner, max_size=3)),
                      max_leaves=8)
EXTRA_KEY = st.from_regex(re.compile(r"x_[a-z0-9]{1,6}"), fullmatch=True)


@pytest.fixture(scope="module")
def scene_dir(originals):
    files, work = originals
    directory = work / "scene"
    (directory / "body").mkdir(parents=True)
    (directory / "body" / HDF5_FILE).write_bytes(files[HDF5_FILE])
    return directory


@pytest.fixture
def body_read_once(monkeypatch):
    """The scene reader's ``read_body`` remembering what it read, by (path, units): the
    fuzz never changes the body file, so every scene that names it gets the BodyData read
    the first time (as scenes sharing a built-in beam share its BodyData); a source that
    fails to read is read, and fails, every time. The body file's own reader is fuzzed
    above."""
    monkeypatch.setattr(scene_bodies, "read_body", functools.lru_cache(maxsize=None)(scene_bodies.read_body))


def test_the_fuzzing_base_scene_is_valid(scene_dir):
    path = scene_dir / "base.toml"
    path.write_text(toml_document(base_scene()))
    scene = read_scene(path)
    assert [b.name for b in scene.system.bodies] == ["beam", "block", "bob"]
    assert len(scene.system.contacts) == 2 and len(scene.system.forces) == 3 and sorted(scene.outputs) == \
        ["spin", "tip", "y"]


@pytest.mark.slow
@fuzz(400)
@given(data=st.data())
def test_scene_files_read_or_fail_naming_file_line_and_key(scene_dir, body_read_once, data):
    doc = base_scene()
    op = data.draw(st.sampled_from(["delete", "replace", "extra-key", "text"]))
    key = None
    if op == "delete":
        path = data.draw(st.sampled_from(paths(doc)))
        del get(doc, path[:-1])[path[-1]]
    elif op == "replace":
        path = data.draw(st.sampled_from(paths(doc)))
        get(doc, path[:-1])[path[-1]] = data.draw(VALUES)
    elif op == "extra-key":
        path = data.draw(st.sampled_from(tables(doc)))
        key = data.draw(EXTRA_KEY)
        get(doc, path)[key] = data.draw(VALUES)
    text = toml_document(doc)
    if op == "text":
        lines = text.split("\n")
        lines.insert(data.draw(st.integers(0, len(lines))), data.draw(TEXT))
        text = "\n".join(lines)
    file = scene_dir / "fuzz.toml"
    file.write_text(text, encoding="utf-8")
    try:
        scene = read_scene(file)
    except InputFileError as error:
        assert error.path == str(file), error
        whole_file = error.fault.startswith(("missing required table 'scene'", "no bodies"))
        assert error.line is not None or whole_file, error
        if op == "extra-key":
            assert repr(key) in error.fault, error
            lines = text.split("\n")
            if path == ("outputs",):    # a new output: the fault may be a key of its own table
                first = next(i for i, line in enumerate(lines, 1) if key in line)
                assert error.line >= first, error
            else:
                assert key in lines[error.line - 1], error
        elif op in ("delete", "replace"):
            assert re.search(r"'[^']+'", error.fault), error       # names a key (or the value at fault)
        return
    assert op != "extra-key", f"extra key {key!r} was accepted"
    assert isinstance(scene, Scene)


# --- write_body leaves no partial files ------------------------------------------------------------------

class Injected(Exception):
    """The failure the test injects into a writer step."""


@fuzz(60)
@given(step=st.sampled_from(["text", "hdf5", "replace", "keep"]), k=st.integers(0, 4), fresh=st.booleans())
def test_write_body_fails_midway_and_leaves_the_old_files(other_body, originals, monkeypatch, step, k, fresh):
    """write_body fails at the text files (after writing part of one), at body.h5 (a
    partial file), at the k-th move into place or at keeping the k-th old file. The
    directory then holds exactly the old files, or nothing if it was new."""
    files, work = originals
    directory = work / "write"
    shutil.rmtree(directory, ignore_errors=True)
    directory.mkdir()
    if not fresh:
        for name, content in files.items():
            (directory / name).write_bytes(content)
    new_body = other_body
    calls = []

    def failing(original):
        def wrapper(*args, **kwargs):
            calls.append(1)
            if len(calls) == k + 1:
                raise Injected(f"{step} #{k}")
            return original(*args, **kwargs)
        return wrapper

    with monkeypatch.context() as m:
        if step == "text":
            def partial_text(paths, body, units="si"):
                target = list(paths.values())[min(k, 3)]
                Path(target).write_text("1.0\t2.0\n3.0")
                raise Injected("text")
            m.setattr(bodyfiles, "write_text_files", partial_text)
        elif step == "hdf5":
            def partial_hdf5(path, body):
                Path(path).write_bytes(files[HDF5_FILE][:1000])
                raise Injected("hdf5")
            m.setattr(bodyfiles, "write_hdf5", partial_hdf5)
        elif step == "replace":
            m.setattr(bodyfiles.os, "replace", failing(bodyfiles.os.replace))
        else:
            m.setattr(bodyfiles, "_keep", failing(bodyfiles._keep))
        raised = True
        try:
            write_body(directory, new_body)
            raised = False
        except Injected:
            pass
    left = {p.name: p.read_bytes() for p in directory.iterdir()}
    if not raised:      # the step was not reached (e.g. no old file to keep): the new set is complete
        assert step == "keep" and fresh and sorted(left) == sorted(files)
        assert_consistent(read_body(directory))
        return
    assert left == ({} if fresh else files)
