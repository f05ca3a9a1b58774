"""The fault audit: bad inputs through the command line, each classified by what the user sees.

``python3 -m validation.fault_audit --out DIR [--only KIND] [--jobs N] [--timeout S]``
writes over a hundred bad inputs into ``DIR/cases/<case>/`` and runs each through
``python3 -m ffrmbs_app.cli ...`` in its own process group (``FFRMBS_PROGRESS=0``, a time limit and
an address-space limit of :data:`MEMORY_LIMIT` bytes, so that a run that would eat the
machine dies instead). Each case is classified (:func:`classify`) as

- ``clear``      exit status non-zero, no ``Traceback`` on stderr, and stderr's last non-empty
  line is one message of at most :data:`MAX_MESSAGE` characters starting with
  ``ffrmbs: error:`` (or argparse's ``ffrmbs <command>: error:``) that names
  the file or key at fault (one of the case's expected substrings);
- ``traceback``  a Python traceback on stderr;
- ``unclear``    non-zero exit otherwise (a multi-line, long or unspecific message, a signal);
- ``silent``     exit status 0: the bad input was accepted;
- ``hang``       no exit within the time limit (the process group is killed).

A case that plants code (a pickle whose ``__reduce__`` runs ``touch MARKER``) is
``silent`` whenever the marker exists afterwards, whatever the exit status, and is flagged
``EXECUTED``.

Kinds of bad inputs (``--only``): ``scene`` (TOML scene files, :mod:`ffrmbs_app.scene_file`),
``body`` (the thesis's text files and ``body.h5``, via ``ffrmbs info`` and via a scene),
``mesh`` (``ffrmbs preprocess`` inputs and options), ``run`` (options of the default
scene, ``--resume`` with missing, damaged and planted checkpoints) and ``result``
(``ffrmbs plot`` / ``export`` of missing, foreign or damaged result files).

Every case is one record (:class:`Case`): its name, kind, the files to write (built from
valid inputs in ``DIR/shared/`` by one small edit each), the argument list and the
substrings a clear message contains. Valid controls run first (:func:`controls`): the
base scene, body and meshes each run cleanly, so a case's outcome is due to its one
fault. Results: a table and counts on stdout, ``DIR/audit.json`` and ``DIR/audit.md``.
Exit status 0 when every case is ``clear`` and every control passed, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import shlex
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from validation.harness import cell, write_atomic

KINDS = ("scene", "body", "mesh", "run", "result")
OUTCOMES = ("clear", "traceback", "unclear", "silent", "hang")
TIMEOUT = 60.0                  # [s] per case
MEMORY_LIMIT = 4 << 30          # [bytes] address space per case
MAX_MESSAGE = 300               # [characters] of a clear message
ERROR_PREFIX = "ffrmbs: error:"
PICKLED_HEADER = b"ffrmbs-checkpoint-2\n" + b"0" * 64 + b"\n"   # the older pickled format's, a forged signature
FAST_RUN = ("--t-end", "0.001", "--no-check", "--no-export")   # the default scene, 100 steps
OUT = "{case}/out"


# --- the case records ------------------------------------------------------------------------

@dataclass
class Case:
    """One bad input.

    name: unique identifier (also the case directory's name). kind: one of :data:`KINDS`.
    argv: the arguments after ``ffrmbs``; ``{case}`` and ``{shared}`` stand for the case
    directory and the shared valid inputs. expect: substrings naming the file or key at
    fault; a clear message contains at least one. files: (path relative to the case
    directory, builder ``f(path, shared)``) pairs. marker: a file (relative to the case
    directory) that only planted code creates.
    """

    name: str
    kind: str
    argv: tuple
    expect: tuple
    files: tuple = ()
    marker: str | None = None

    def paths(self, root: Path) -> dict:
        """The directories ``{case}`` and ``{shared}`` stand for, under the audit's ``root``."""
        return {"case": str(root / "cases" / self.name), "shared": str(root / "shared")}


@dataclass
class Outcome:
    """The result of one case: its classification, exit status, wall seconds and the
    message (stderr's last non-empty line)."""

    case: str
    kind: str
    outcome: str
    returncode: int | None
    seconds: float
    message: str
    argv: list = field(default_factory=list)
    executed: bool = False


def classify(returncode, stderr: str, expect, timed_out=False, executed=False) -> tuple[str, str]:
    """(outcome, message) of one case (module docstring): ``returncode`` of the process (None
    when it timed out), its ``stderr`` text, ``expect`` the substrings a clear message
    names, ``executed`` whether planted code ran."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    message = lines[-1] if lines else ""
    if executed:
        return "silent", "EXECUTED: planted code ran; " + message
    if timed_out:
        return "hang", message
    if returncode == 0:
        return "silent", message
    if "Traceback" in stderr:
        return "traceback", message
    prefix = message.split(":", 1)[0] + ":" if ":" in message else ""
    argparse_error = prefix.startswith("ffrmbs ") and message[len(prefix):].startswith(" error:")
    if returncode < 0:
        return "unclear", f"killed by {signal.Signals(-returncode).name}; " + message
    clear = ((message.startswith(ERROR_PREFIX) or argparse_error) and len(message) <= MAX_MESSAGE
             and any(_words(e.lstrip("-")) in _words(message) for e in expect))
    return ("clear" if clear else "unclear"), message


def _words(s: str) -> str:
    """``s`` lower-cased with '-' and '_' as spaces, so that "mesh-size" (of "--mesh-size"),
    "mesh_size" and "Mesh size" match."""
    return s.lower().replace("-", " ").replace("_", " ")


# --- builders of case files ------------------------------------------------------------------

def text(content: str):
    return lambda path, shared: path.write_text(content)


def scene_file(content: str):
    """A scene file; ``@CASE@`` in ``content`` stands for the case directory."""
    return lambda path, shared: path.write_text(content.replace("@CASE@", str(path.parent)))


def raw(content: bytes):
    return lambda path, shared: path.write_bytes(content)


def fifo():
    return lambda path, shared: os.mkfifo(path)


def folder():
    return lambda path, shared: path.mkdir()


def copy(rel: str):
    """A copy of ``shared/rel`` (a file or a directory)."""
    def build(path, shared):
        src = shared / rel
        if src.is_dir():
            shutil.copytree(src, path)
        else:
            shutil.copyfile(src, path)
    return build


def edited(rel: str, edit):
    """``shared/rel`` (a text file) with its lines passed through ``edit(lines) -> lines``."""
    def build(path, shared):
        path.write_text("\n".join(edit((shared / rel).read_text().splitlines())) + "\n")
    return build


def h5_edited(rel: str, edit):
    """A copy of the HDF5 file ``shared/rel`` changed in place by ``edit(h5py.File)``."""
    def build(path, shared):
        shutil.copyfile(shared / rel, path)
        with h5py.File(path, "r+") as f:
            edit(f)
    return build


def truncated(rel: str, n_bytes: int):
    return lambda path, shared: path.write_bytes((shared / rel).read_bytes()[:n_bytes])


class _Planted:
    """An object whose unpickling runs ``touch marker`` (what an attacker plants)."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {shlex.quote(str(self.marker))}",)


def planted_pickle(header: bytes, marker: str):
    """A checkpoint made of ``header`` and a pickle that creates the file ``marker`` beside
    the checkpoint when loaded."""
    return lambda path, shared: path.write_bytes(header + pickle.dumps(_Planted(path.parent / marker)))


def planted_object_array(marker: str):
    """A checkpoint in the current format (an .npz) with a header and an object array
    whose pickle creates the file ``marker`` beside the checkpoint when loaded."""
    def build(path, shared):
        with open(path, "wb") as f:
            np.savez(f, header=np.frombuffer(b'{"format": "ffrmbs-checkpoint", "format_version": 3}', dtype=np.uint8),
                     plant=np.array([_Planted(path.parent / marker)], dtype=object))
    return build


# --- the valid inputs every case starts from -------------------------------------------------

BODY_SOURCE = '"../../shared/body.h5"'

BASE_SCENE = """\
[scene]
name = "audit"
t_end = 0.002
dt = 1e-4
integrator = "moreau"
n_out = 3
gravity = [0.0, -9.81, 0.0]

[[body]]
name = "beam"
kind = "flexible"
source = SOURCE
modes = 3
frame = "fixed"
q_f = [0.0, 0.0, 0.0]

[[body]]
name = "block"
kind = "rigid"
mass = 1.0
inertia = [0.01, 0.02, 0.03]
position = [1.0, 0.0, 0.0]

[[body]]
name = "bob"
kind = "point_mass"
mass = 0.5
position = [0.2, 0.0502, 0.025]
velocity = [0.0, -0.1, 0.0]

[[spring]]
frame1 = { body = "ground", point = [1.0, 0.5, 0.0] }
frame2 = { body = "block" }
stiffness = 100.0
damping = 0.1
free_length = 0.4

[[joint]]
kind = "spherical"
frame1 = { body = "ground", point = [1.0, 0.0, 0.0] }
frame2 = { body = "block" }

[[load]]
kind = "force"
body = "beam"
node = 7
force = [0.0, -1.0, 0.0]

[[contact]]
name = "hit"
contour1 = { kind = "point", body = "bob" }
contour2 = { kind = "2s", body = "beam", nodes = "y1" }
law = "coulomb"
e = 0.0
mu = 0.3

[outputs]
y = { body = "bob", quantity = "position", component = "y" }
tip = { body = "beam", at = [0.25, 0.05, 0.05] }
"""
"""A scene touching every kind of entry: the audit's small beam (``shared/body.h5``), a
rigid block on a spring and a spherical joint, a point mass on the beam's top face with
Coulomb contact, gravity, a force and two outputs. 20 Moreau steps."""

CUBE_INP = """\
*HEADING
audit cube: 0.1 m, six tet4
*NODE
1, 0.0, 0.0, 0.0
2, 0.1, 0.0, 0.0
3, 0.1, 0.1, 0.0
4, 0.0, 0.1, 0.0
5, 0.0, 0.0, 0.1
6, 0.1, 0.0, 0.1
7, 0.1, 0.1, 0.1
8, 0.0, 0.1, 0.1
*ELEMENT, TYPE=C3D4, ELSET=SOLID
1, 1, 2, 3, 7
2, 1, 3, 4, 7
3, 1, 4, 8, 7
4, 1, 8, 5, 7
5, 1, 5, 6, 7
6, 1, 6, 2, 7
*NSET, NSET=x0
1, 4, 5, 8
"""

BAR_GEO = """\
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.2, 0.05, 0.05};
Physical Volume("body") = {1};
Physical Surface("x0") = {1};
"""

TEXT_BODY_CONTACT = ('contour2 = { kind = "2s", body = "beam", nodes = "y1" }',
                     'contour2 = { kind = "plane", point = [0.0, 0.05, 0.0], normal = [0.0, 1.0, 0.0] }')
"""The base scene's edit for a body read from text files, which carry no node groups: the
point mass hits a ground plane instead of the beam's top face."""

def _material(density="1000", young="1e7", poisson="0.3"):
    """The material options of ``ffrmbs preprocess`` [kg/m³, Pa, -]."""
    return ("--density", density, "--young", young, "--poisson", poisson)


MATERIAL = _material()


def build_shared(shared: Path) -> None:
    """The valid inputs: ``body/`` (the thesis's four text files of a 250 x 50 x 50 mm tet4
    beam, 5 x 2 x 3 divisions, 72 nodes, clamped at x = 0, 6 modes), ``body.h5`` (the same
    body), ``scene.toml`` (:data:`BASE_SCENE`, for ``--dt`` beside a scene), ``cube.inp``,
    ``bar.geo`` and ``notes.txt``."""
    from preprocess import Material, box, build_body, write_body
    from preprocess.bodyfiles import HDF5_FILE

    body = build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(5, 2, 3)), Material(920.0, 5e7, 0.3),
                      n_modes=6, clamp="x0")
    write_body(shared / "body", body)
    os.replace(shared / "body" / HDF5_FILE, shared / "body.h5")
    (shared / "scene.toml").write_text(BASE_SCENE.replace("SOURCE", BODY_SOURCE))
    (shared / "cube.inp").write_text(CUBE_INP)
    (shared / "bar.geo").write_text(BAR_GEO)
    (shared / "notes.txt").write_text("not a result file\n")


def edited_text(content: str, edits) -> str:
    """``content`` with each (old, new) edit applied; ``old`` must occur exactly once."""
    for old, new in edits:
        if content.count(old) != 1:
            raise ValueError(f"edit {old!r} does not match exactly once")
        content = content.replace(old, new)
    return content


def scene_text(*edits, source=BODY_SOURCE) -> str:
    """:data:`BASE_SCENE` with its body file ``source`` and each (old, new) edit applied."""
    return edited_text(BASE_SCENE.replace("SOURCE", source), edits)


def scene_case(name, expect, *edits, source=BODY_SOURCE, extra=(), kind="scene") -> Case:
    """A case running the base scene with ``edits`` (see :func:`scene_text`), plus files."""
    return Case(name, kind, ("run", "{case}/scene.toml", "--out", OUT, "--no-check", "--no-export"),
                tuple(expect), (("scene.toml", scene_file(scene_text(*edits, source=source))), *extra))


# --- the cases -------------------------------------------------------------------------------

E_KEY = ("'e'", " e =", " e must", "restitution")     # ways a message names the key e

#: (case, key at fault, the line of BASE_SCENE, its bad replacement)
SCENE_EDITS = [
    ("syntax_table", ("scene.toml",), "[scene]\n", "[scene\n"),
    ("syntax_value", ("scene.toml",), "dt = 1e-4", "dt = 1e-4x"),
    ("syntax_string", ("scene.toml",), 'name = "audit"', 'name = "audit'),
    ("unknown_top_key", ("output",), "[outputs]", "[output]"),
    ("unknown_scene_key", ("t_ned",), "n_out = 3", "n_out = 3\nt_ned = 1.0"),
    ("unknown_body_key", ("modez",), "modes = 3", "modes = 3\nmodez = 3"),
    ("unknown_contact_key", ("friction",), "mu = 0.3", "mu = 0.3\nfriction = 0.3"),
    ("missing_t_end", ("t_end",), "t_end = 0.002\n", ""),
    ("missing_dt", ("dt",), "dt = 1e-4\n", ""),
    ("missing_mass", ("mass",), "mass = 0.5\n", ""),
    ("missing_source", ("source",), "source = SRC\n", ""),
    ("missing_law", ("law",), 'law = "coulomb"\n', ""),
    ("type_dt_string", ("dt",), "dt = 1e-4", 'dt = "1e-4"'),
    ("type_modes", ("modes",), "modes = 3", 'modes = "three"'),
    ("type_position", ("position",), "position = [0.2, 0.0502, 0.025]", "position = 0.2"),
    ("type_gravity", ("gravity",), "gravity = [0.0, -9.81, 0.0]", 'gravity = "down"'),
    ("type_n_out_float", ("n_out",), "n_out = 3", "n_out = 3.5"),
    ("dt_zero", ("dt",), "dt = 1e-4", "dt = 0.0"),
    ("dt_negative", ("dt",), "dt = 1e-4", "dt = -1e-4"),
    ("dt_nan", ("dt",), "dt = 1e-4", "dt = nan"),
    ("dt_inf", ("dt",), "dt = 1e-4", "dt = inf"),
    ("dt_1e308", ("dt",), "dt = 1e-4", "dt = 1e308"),
    ("t_end_zero", ("t_end",), "t_end = 0.002", "t_end = 0.0"),
    ("t_end_negative", ("t_end",), "t_end = 0.002", "t_end = -1.0"),
    ("t_end_nan", ("t_end",), "t_end = 0.002", "t_end = nan"),
    ("t_end_inf", ("t_end",), "t_end = 0.002", "t_end = inf"),
    ("t_end_1e300", ("t_end", "steps"), "t_end = 0.002", "t_end = 1e300"),
    ("n_out_zero", ("n_out",), "n_out = 3", "n_out = 0"),
    ("n_out_negative", ("n_out",), "n_out = 3", "n_out = -5"),
    ("n_out_2e9", ("n_out", "memory"), "n_out = 3", "n_out = 2000000000"),
    ("mass_zero", ("mass",), "mass = 0.5", "mass = 0.0"),
    ("mass_negative", ("mass",), "mass = 0.5", "mass = -0.5"),
    ("mass_nan", ("mass",), "mass = 0.5", "mass = nan"),
    ("mass_inf", ("mass",), "mass = 0.5", "mass = inf"),
    ("mass_1e308", ("mass",), "mass = 0.5", "mass = 1e308"),
    ("rigid_mass_zero", ("mass",), "mass = 1.0", "mass = 0.0"),
    ("inertia_negative", ("inertia",), "inertia = [0.01, 0.02, 0.03]", "inertia = [-0.01, 0.02, 0.03]"),
    ("stiffness_negative", ("stiffness",), "stiffness = 100.0", "stiffness = -100.0"),
    ("stiffness_nan", ("stiffness",), "stiffness = 100.0", "stiffness = nan"),
    ("stiffness_inf", ("stiffness",), "stiffness = 100.0", "stiffness = inf"),
    ("stiffness_1e308", ("stiffness",), "stiffness = 100.0", "stiffness = 1e308"),
    ("damping_negative", ("damping",), "damping = 0.1", "damping = -0.1"),
    ("e_negative", E_KEY, "e = 0.0", "e = -0.5"),
    ("e_two", E_KEY, "e = 0.0", "e = 2.0"),
    ("e_nan", E_KEY, "e = 0.0", "e = nan"),
    ("mu_negative", ("mu",), "mu = 0.3", "mu = -0.3"),
    ("mu_nan", ("mu",), "mu = 0.3", "mu = nan"),
    ("mu_inf", ("mu",), "mu = 0.3", "mu = inf"),
    ("gravity_nan", ("gravity",), "gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, nan, 0.0]"),
    ("gravity_inf", ("gravity",), "gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, -inf, 0.0]"),
    ("gravity_1e300", ("gravity",), "gravity = [0.0, -9.81, 0.0]", "gravity = [0.0, -1e300, 0.0]"),
    ("position_nan", ("position",), "position = [0.2, 0.0502, 0.025]", "position = [nan, 0.0502, 0.025]"),
    ("position_1e308", ("position",), "position = [0.2, 0.0502, 0.025]", "position = [1e308, 0.0502, 0.025]"),
    ("velocity_inf", ("velocity",), "velocity = [0.0, -0.1, 0.0]", "velocity = [0.0, -inf, 0.0]"),
    ("velocity_1e300", ("velocity",), "velocity = [0.0, -0.1, 0.0]", "velocity = [0.0, -1e300, 0.0]"),
    ("q_f_1e308", ("q_f",), "q_f = [0.0, 0.0, 0.0]", "q_f = [1e308, 0.0, 0.0]"),
    ("force_1e308", ("force",), "force = [0.0, -1.0, 0.0]", "force = [0.0, -1e308, 0.0]"),
    ("name_parent", ("name",), 'name = "audit"', 'name = "../../ESCAPED"'),
    ("name_absolute", ("name",), 'name = "audit"', 'name = "@CASE@/ESCAPED"'),
    ("name_empty", ("name",), 'name = "audit"', 'name = ""'),
    ("unknown_spring_body", ("nobody",), 'frame2 = { body = "block" }\nstiffness',
     'frame2 = { body = "nobody" }\nstiffness'),
    ("unknown_output_body", ("nobody",), 'y = { body = "bob"', 'y = { body = "nobody"'),
    ("unknown_contact_body", ("nobody",), 'contour1 = { kind = "point", body = "bob" }',
     'contour1 = { kind = "point", body = "nobody" }'),
    ("unknown_node_group", ("y9",), 'nodes = "y1"', 'nodes = "y9"'),
    ("node_out_of_range", ("node",), "node = 7", "node = 100000"),
    ("no_node_at", ("tip", "at"), "at = [0.25, 0.05, 0.05]", "at = [0.25, 0.05, 0.07]"),
    ("modes_too_many", ("modes",), "modes = 3", "modes = 50"),
    ("duplicate_body", ("block",), 'name = "bob"', 'name = "block"'),
    ("duplicate_contact", ("hit",), "[outputs]",
     '[[contact]]\nname = "hit"\ncontour1 = { kind = "point", body = "bob" }\n'
     'contour2 = { kind = "2s", body = "beam", nodes = "y1" }\nlaw = "impact"\n\n[outputs]'),
    ("unknown_integrator", ("integrator",), 'integrator = "moreau"', 'integrator = "euler"'),
]

#: (case, source given in the scene, files in the case directory, expected substrings)
SCENE_SOURCES = [
    ("source_missing", '"missing.h5"', (), ("missing.h5",)),
    ("source_empty_dir", '"empty"', (("empty", folder()),), ("empty",)),
    ("source_etc_passwd", '"/etc/passwd"', (), ("/etc/passwd",)),
    ("source_fifo", '"pipe.h5"', (("pipe.h5", fifo()),), ("pipe.h5",)),
    ("source_empty_file", '"empty.h5"', (("empty.h5", raw(b"")),), ("empty.h5",)),
    ("source_text_as_h5", '"garbage.h5"', (("garbage.h5", text("this is no HDF5 file\n" * 20)),), ("garbage.h5",)),
]

#: whole scene files: (case, files, expected substrings)
SCENE_FILES = [
    ("scene_empty", (("scene.toml", raw(b"")),), ("scene.toml",)),
    ("scene_binary", (("scene.toml", raw(bytes(range(256)) * 4)),), ("scene.toml",)),
    ("scene_fifo", (("scene.toml", fifo()),), ("scene.toml",)),
    ("scene_directory", (("scene.toml", folder()),), ("scene.toml",)),
    ("scene_no_body", (("scene.toml", text('[scene]\nname = "x"\nt_end = 0.1\ndt = 1e-3\n')),), ("body",)),
]


def scene_cases() -> list[Case]:
    cases = [scene_case(name, expect, (old.replace("SRC", BODY_SOURCE), new)) for name, expect, old, new in SCENE_EDITS]
    cases += [scene_case(name, expect, source=src, extra=files) for name, src, files, expect in SCENE_SOURCES]
    cases += [Case(name, "scene", ("run", "{case}/scene.toml", "--out", OUT, "--no-check", "--no-export"), expect,
                   files) for name, files, expect in SCENE_FILES]
    cases.append(Case("scene_etc_passwd", "scene", ("run", "/etc/passwd", "--out", OUT), ("/etc/passwd",)))
    return cases


def _set(row: int, col: int, value: str):
    """An edit setting token ``col`` of line ``row`` (0-based) of a text file to ``value``."""
    def edit(lines):
        tokens = lines[row].split("\t")
        tokens[col] = value
        return [*lines[:row], "\t".join(tokens), *lines[row + 1:]]
    return edit


def _keep(fraction: float):
    return lambda lines: lines[:max(1, int(len(lines) * fraction))]


def _append(line: str):
    return lambda lines: [*lines, line]


def _stiffness_entry(value: str):
    """Replace the value of the stiffness file's second entry (K[3, 0] for node 2, DOF 1)."""
    return lambda lines: [lines[0], lines[1].rsplit(",", 1)[0] + ", " + value, *lines[2:]]


#: faults in the thesis's text files: (case, file, builder of the faulty file)
TEXT_FAULTS = [
    ("u0_truncated", "u0.dat", _keep(0.5)),
    ("u0_not_a_number", "u0.dat", _set(3, 1, "abc")),
    ("u0_nan", "u0.dat", _set(3, 1, "nan")),
    ("u0_1e308", "u0.dat", _set(3, 1, "1e308")),
    ("u0_two_columns", "u0.dat", _set(3, 2, "% gone")),
    ("mij_truncated", "mij.dat", _keep(0.5)),
    ("mij_negative", "mij.dat", _set(5, 0, "-0.1")),
    ("mij_zero", "mij.dat", _set(5, 0, "0.0")),
    ("mij_nan", "mij.dat", _set(5, 0, "nan")),
    ("mij_1e308", "mij.dat", _set(5, 0, "1e308")),
    ("modes_truncated", "modeShapeMatrix.dat", _keep(0.7)),
    ("modes_short_row", "modeShapeMatrix.dat", _set(40, 2, "% gone")),
    ("modes_1e308", "modeShapeMatrix.dat", _set(40, 1, "1e308")),
    ("modes_not_a_number", "modeShapeMatrix.dat", _set(40, 1, "0x1p3")),
    ("stiffness_unsymmetric", "stiffnessMatrix.dat", _append("1,1, 2,1, 12345.0")),
    ("stiffness_1e308", "stiffnessMatrix.dat", _stiffness_entry("1e308")),
    ("stiffness_nan", "stiffnessMatrix.dat", _stiffness_entry("nan")),
    ("stiffness_index_range", "stiffnessMatrix.dat", _append("9999,1, 1,1, 1.0")),
    ("stiffness_empty", "stiffnessMatrix.dat", lambda lines: []),
]

TEXT_SPECIAL = [          # (case, file, builder): the file replaced by something that is not a text file
    ("mij_fifo", "mij.dat", fifo()),
    ("u0_directory", "u0.dat", folder()),
    ("stiffness_binary", "stiffnessMatrix.dat", raw(bytes(range(256)) * 8)),
]


def _drop(name):
    return lambda f: f.__delitem__(name)


def _replace(name, make):
    """An edit replacing dataset ``name`` by ``make(old array)``."""
    def edit(f):
        data = make(f[name][()])
        del f[name]
        f[name] = data
    return edit


def _with_entry(index, value):
    def make(a):
        a = np.array(a, dtype=float)
        a.flat[index] = value
        return a
    return make


def _unsymmetric(f):
    f["stiffness/data"][1] = f["stiffness/data"][1] * 3.0 + 1.0


#: faults in body.h5: (case, builder of the faulty body.h5)
H5_FAULTS = [
    ("h5_no_phi", h5_edited("body.h5", _drop("phi"))),
    ("h5_no_masses", h5_edited("body.h5", _drop("masses"))),
    ("h5_no_stiffness", h5_edited("body.h5", _drop("stiffness"))),
    ("h5_u0_strings", h5_edited("body.h5", _replace("u0", lambda a: np.array([b"x"] * len(a))))),
    ("h5_u0_two_columns", h5_edited("body.h5", _replace("u0", lambda a: a[:, :2]))),
    ("h5_masses_negative", h5_edited("body.h5", _replace("masses", lambda a: -a))),
    ("h5_phi_nan", h5_edited("body.h5", _replace("phi", _with_entry(40, np.nan)))),
    ("h5_u0_1e308", h5_edited("body.h5", _replace("u0", _with_entry(9, 1e308)))),
    ("h5_stiffness_1e308", h5_edited("body.h5", _replace("stiffness/data", _with_entry(1, 1e308)))),
    ("h5_stiffness_unsymmetric", h5_edited("body.h5", _unsymmetric)),
    ("h5_group_out_of_range", h5_edited("body.h5", _replace("node_groups/y1", lambda a: a + 10_000))),
    ("h5_wrong_format", h5_edited("body.h5", lambda f: f.attrs.__setitem__("format", "something-else"))),
    ("h5_truncated", truncated("body.h5", 4096)),
    ("h5_empty", raw(b"")),
    ("h5_text", text("this is no HDF5 file\n" * 20)),
    ("h5_fifo", fifo()),
]


def body_cases() -> list[Case]:
    """Each text-file fault in a copy of the directory of the four text files, each body.h5
    fault as a lone file; both read by ``ffrmbs info`` and by the base scene."""
    faulty = [(name, file, _replacing(edited(f"body/{file}", edit))) for name, file, edit in TEXT_FAULTS]
    faulty += [(name, file, _replacing(build)) for name, file, build in TEXT_SPECIAL]
    bodies = [(name, (("body", copy("body")), (f"body/{file}", build)), "body", file) for name, file, build in faulty]
    bodies += [(name, (("body.h5", build),), "body.h5", "body.h5") for name, build in H5_FAULTS]
    cases = []
    for name, files, target, fault_file in bodies:
        cases.append(Case(f"info_{name}", "body", ("info", f"{{case}}/{target}"), (fault_file,), files))
        edits = (TEXT_BODY_CONTACT,) if target == "body" else ()
        cases.append(scene_case(f"scene_{name}", (fault_file,), *edits, source=f'"{target}"', extra=files,
                                kind="body"))
    return cases


def _replacing(build):
    """``build`` after removing the file a copied directory holds at the path."""
    def run(path, shared):
        path.unlink()
        build(path, shared)
    return run


def _preprocess(source, *options):
    """``ffrmbs preprocess source`` with valid options (2 modes, the face x = 0 clamped, a soft
    material, into the case's ``out/``) followed by ``options``: argparse keeps the last value
    of a repeated option."""
    return ("preprocess", source, "--modes", "2", "--clamp", "x0", *MATERIAL, "--out", OUT, *options)


def _cube(*edits):
    """cube.inp with (old, new) edits."""
    return text(edited_text(CUBE_INP, edits))


BOX = "box:0.2,0.05,0.05"
CUBE = "{shared}/cube.inp"
EXTRA_TET = (("8, 0.0, 0.1, 0.1\n", "8, 0.0, 0.1, 0.1\n9, 1.0, 1.0, 1.0\n10, 1.1, 1.0, 1.0\n11, 1.0, 1.1, 1.0\n"
              "12, 1.0, 1.0, 1.1\n"), ("6, 1, 6, 2, 7\n", "6, 1, 6, 2, 7\n7, 9, 10, 11, 12\n"))
"""cube.inp plus a tetrahedron that touches nothing: a part left unconstrained by the clamp."""

#: bad mesh files: (case, file name, builder; None: the file is missing)
MESH_FILES = [
    ("inp_unknown_element", "m.inp", _cube(("C3D4", "C3D99"))),
    ("inp_missing_node", "m.inp", _cube(("6, 1, 6, 2, 7", "6, 1, 6, 2, 99"))),
    ("inp_disconnected", "m.inp", _cube(*EXTRA_TET)),
    ("inp_degenerate", "m.inp", _cube(("1, 1, 2, 3, 7", "1, 1, 2, 3, 3"))),
    ("inp_nan_coordinate", "m.inp", _cube(("2, 0.1, 0.0, 0.0", "2, nan, 0.0, 0.0"))),
    ("inp_empty", "m.inp", raw(b"")),
    ("inp_garbage", "m.inp", text("*NODE\n1, a, b\n*ELEMENT\n?\n")),
    ("inp_binary", "m.inp", raw(bytes(range(256)) * 8)),
    ("inp_fifo", "m.inp", fifo()),
    ("inp_missing", "missing.inp", None),
    ("inp_directory", "d.inp", folder()),
    ("geo_syntax", "m.geo", text(BAR_GEO.replace("Box(1) = {", "Box(1) = {{"))),
    ("geo_no_volume", "m.geo", text('SetFactory("OpenCASCADE");\nRectangle(1) = {0, 0, 0, 1, 1};\n')),
    ("geo_empty", "m.geo", raw(b"")),
    ("msh_garbage", "m.msh", text("$MeshFormat\ngarbage\n$EndMeshFormat\n")),
    ("msh_empty", "m.msh", raw(b"")),
    ("unknown_suffix", "m.stl", text("solid x\nendsolid x\n")),
]

#: bad built-in geometries and options: (case, input, options, expected substrings)
MESH_OPTIONS = [
    ("box_zero", "box:0,1,1", (), ("box",)),
    ("box_letters", "box:a,b,c", (), ("box",)),
    ("box_negative", "box:-1,1,1", (), ("box",)),
    ("box_nan", "box:nan,1,1", (), ("box",)),
    ("box_two_lengths", "box:1,1", (), ("box",)),
    ("cylinder_one_length", "cylinder:1", (), ("cylinder",)),
    ("cap_too_high", "spherical-cap:1,3", (), ("cap height",)),
    ("groove_too_wide", "grooved-block:1,1,1,0.6", (), ("groove radius",)),
    ("structured_two_numbers", BOX, ("--structured", "4,2"), ("--structured",)),
    ("structured_zero", BOX, ("--structured", "4,0,2"), ("--structured",)),
    ("structured_mesh_file", CUBE, ("--structured", "2,2,2"), ("--structured",)),
    ("mesh_size_zero", BOX, ("--mesh-size", "0"), ("mesh-size",)),
    ("mesh_size_negative", BOX, ("--mesh-size", "-1"), ("mesh-size",)),
    ("mesh_size_nan", BOX, ("--mesh-size", "nan"), ("mesh-size",)),
    ("modes_zero", CUBE, ("--modes", "0"), ("modes",)),
    ("modes_negative", CUBE, ("--modes", "-3"), ("modes",)),
    ("modes_above_dofs", CUBE, ("--modes", "100000"), ("modes",)),
    ("clamp_unknown", CUBE, ("--clamp", "nosuchgroup"), ("nosuchgroup",)),
    ("poisson_half", CUBE, ("--poisson", "0.5"), ("poisson",)),
    ("poisson_negative", CUBE, ("--poisson", "-1.5"), ("poisson",)),
    ("density_negative", CUBE, ("--density", "-1"), ("density",)),
    ("density_zero", CUBE, ("--density", "0"), ("density",)),
    ("young_zero", CUBE, ("--young", "0"), ("young",)),
    ("young_nan", CUBE, ("--young", "nan"), ("young",)),
    ("out_is_a_file", CUBE, ("--out", "{shared}/notes.txt"), ("notes.txt",)),
]


def mesh_cases() -> list[Case]:
    cases = [Case(f"mesh_{name}", "mesh", _preprocess(f"{{case}}/{file}"), (file,),
                  () if build is None else ((file, build),)) for name, file, build in MESH_FILES]
    return cases + [Case(f"mesh_{name}", "mesh", _preprocess(source, *options), expect)
                    for name, source, options, expect in MESH_OPTIONS]


def _run(*options):
    return ("run", *FAST_RUN, "--out", OUT, *options)


def _resume(files=(), marker=None, expect=("ckpt", "checkpoint")):
    return dict(argv=("run", *FAST_RUN, "--out", OUT, "--resume"), expect=expect, files=files, marker=marker)


CKPT = "out/point_mass_beam.h5.ckpt"
SEED = "{shared}/seed/point_mass_beam.h5"      # the result file of control_default_run
RESULT = (("out", folder()), ("out/point_mass_beam.h5", copy("seed/point_mass_beam.h5")))

#: (case, argv, expected substrings) of the default scene's options
RUN_OPTIONS = [
    ("modes_zero", _run("--modes", "0"), ("modes",)),
    ("modes_negative", _run("--modes", "-1"), ("modes",)),
    ("modes_100000", _run("--modes", "100000"), ("modes",)),
    ("dt_zero", _run("--dt", "0"), ("dt",)),
    ("dt_negative", _run("--dt", "-1"), ("dt",)),
    ("dt_nan", _run("--dt", "nan"), ("dt",)),
    ("dt_inf", _run("--dt", "inf"), ("dt",)),
    ("t_end_nan", _run("--t-end", "nan"), ("t_end",)),
    ("t_end_zero", _run("--t-end", "0"), ("t_end",)),
    ("t_end_inf", _run("--t-end", "inf"), ("t_end",)),
    ("t_end_1e300", _run("--t-end", "1e300"), ("t_end", "steps")),
    ("e_two", _run("--e", "2"), E_KEY),
    ("e_negative", _run("--e", "-1"), E_KEY),
    ("e_nan", _run("--e", "nan"), E_KEY),
    ("checkpoint_every_negative", _run("--checkpoint-every", "-5"), ("checkpoint-every",)),
    ("checkpoint_every_nan", _run("--checkpoint-every", "nan"), ("checkpoint-every",)),
    ("scene_with_default_options", ("run", "{shared}/scene.toml", "--dt", "1e-3", "--out", OUT), ("--dt",)),
    ("out_is_a_file", ("run", *FAST_RUN, "--out", "{shared}/notes.txt"), ("notes.txt",)),
]

#: (case, keyword arguments of Case) of --resume
RESUME_CASES = [
    ("resume_without_checkpoint", _resume(RESULT)),
    ("resume_garbage_checkpoint", _resume((*RESULT, (CKPT, text("garbage\n" * 10))))),
    ("resume_empty_checkpoint", _resume((*RESULT, (CKPT, raw(b""))))),
    ("resume_truncated_checkpoint", _resume((*RESULT, (CKPT, raw(b"PK\x03\x04" + b"\x00" * 40))))),
    ("resume_planted_pickle", _resume((*RESULT, (CKPT, planted_pickle(b"", "EXECUTED"))), marker="out/EXECUTED")),
    ("resume_planted_pickle_with_header",
     _resume((*RESULT, (CKPT, planted_pickle(PICKLED_HEADER, "EXECUTED"))), marker="out/EXECUTED")),
    ("resume_planted_object_array", _resume((*RESULT, (CKPT, planted_object_array("EXECUTED"))),
                                            marker="out/EXECUTED")),
    ("resume_checkpoint_directory", _resume((*RESULT, (CKPT, folder())))),
]

#: (case, argv, expected substrings, files) of plot and export
RESULT_CASES = [
    ("plot_missing", ("plot", "{case}/missing.h5"), ("missing.h5",), ()),
    ("plot_body_file", ("plot", "{shared}/body.h5", "--out", "{case}/p.png"), ("body.h5",), ()),
    ("plot_text_file", ("plot", "{shared}/notes.txt", "--out", "{case}/p.png"), ("notes.txt",), ()),
    ("plot_truncated", ("plot", "{case}/r.h5"), ("r.h5",), (("r.h5", truncated("seed/point_mass_beam.h5", 2048)),)),
    ("plot_unknown_name", ("plot", SEED, "nosuchname", "--out", "{case}/p.png"), ("nosuchname",), ()),
    ("plot_fifo", ("plot", "{case}/r.h5"), ("r.h5",), (("r.h5", fifo()),)),
    ("export_missing", ("export", "{case}/missing.h5"), ("missing.h5",), ()),
    ("export_body_file", ("export", "{shared}/body.h5", "--out", "{case}/pv"), ("body.h5",), ()),
    ("export_text_file", ("export", "{shared}/notes.txt", "--out", "{case}/pv"), ("notes.txt",), ()),
    ("export_truncated", ("export", "{case}/r.h5"), ("r.h5",), (("r.h5", truncated("seed/point_mass_beam.h5", 2048)),)),
    ("export_every_zero", ("export", SEED, "--every", "0", "--out", "{case}/pv"), ("every",), ()),
    ("export_every_negative", ("export", SEED, "--every", "-2", "--out", "{case}/pv"), ("every",), ()),
    ("export_unknown_body", ("export", SEED, "--body", "nosuchbody", "--out", "{case}/pv"), ("nosuchbody",), ()),
    ("info_etc_passwd", ("info", "/etc/passwd"), ("/etc/passwd",), ()),
    ("info_missing", ("info", "{case}/missing"), ("missing",), ()),
]


def all_cases() -> list[Case]:
    """Every case, in a fixed order; names are unique."""
    cases = scene_cases() + body_cases()
    cases += mesh_cases()
    cases += [Case(f"run_{name}", "run", argv, expect) for name, argv, expect in RUN_OPTIONS]
    cases += [Case(f"run_{name}", "run", **kwargs) for name, kwargs in RESUME_CASES]
    cases += [Case(f"result_{name}", "result", argv, expect, files) for name, argv, expect, files in RESULT_CASES]
    names = Counter(c.name for c in cases)
    duplicates = [n for n, k in names.items() if k > 1]
    if duplicates:
        raise ValueError(f"duplicate case names: {duplicates}")
    return cases


def all_cases_by_name() -> dict:
    """{name: case} of :func:`all_cases`."""
    return {c.name: c for c in all_cases()}


def controls() -> list[Case]:
    """Valid inputs that must run cleanly (exit 0) for the audit to mean anything. The first
    writes ``shared/seed/point_mass_beam.h5``, which later cases copy."""
    return [
        Case("control_default_run", "run", ("run", *FAST_RUN, "--out", "{shared}/seed"), ()),
        scene_case("control_scene", ()),
        scene_case("control_scene_text_body", (), TEXT_BODY_CONTACT, source='"body"', extra=(("body", copy("body")),)),
        Case("control_info_text", "body", ("info", "{shared}/body"), ()),
        Case("control_info_h5", "body", ("info", "{shared}/body.h5"), ()),
        Case("control_inp", "mesh", _preprocess(CUBE), ()),
        Case("control_geo", "mesh", _preprocess("{shared}/bar.geo", "--order", "1", "--mesh-size", "0.05"), ()),
        Case("control_box", "mesh", _preprocess(BOX, "--order", "1"), ()),
    ]


# --- running ---------------------------------------------------------------------------------

LAUNCH = ("import resource, runpy; resource.setrlimit(resource.RLIMIT_AS, ({0}, {0})); "
          "runpy.run_module('ffrmbs_app.cli', run_name='__main__', alter_sys=True)").format(MEMORY_LIMIT)
"""``python3 -c LAUNCH ARGS`` is ``python3 -m ffrmbs_app.cli ARGS`` with the address space bounded
(set in the child itself: ``preexec_fn`` is unsafe beside the runner's threads)."""


def run_case(case: Case, root: Path, timeout=TIMEOUT) -> Outcome:
    """Build ``case``'s files under ``root/cases/<name>/``, run it and classify it."""
    where = case.paths(root)
    case_dir = Path(where["case"])
    shared = Path(where["shared"])
    case_dir.mkdir(parents=True)
    for rel, build in case.files:
        build(case_dir / rel, shared)
    argv = [a.format(**where) for a in case.argv]
    env = dict(os.environ, FFRMBS_PROGRESS="0")
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-c", LAUNCH, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, env=env, start_new_session=True, cwd=case_dir)
    try:
        _, err = proc.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        _, err = proc.communicate()
        timed_out = True
    seconds = time.perf_counter() - t0
    stderr = err.decode("utf-8", errors="replace")
    executed = case.marker is not None and (case_dir / case.marker).exists()
    outcome, message = classify(None if timed_out else proc.returncode, stderr, case.expect, timed_out, executed)
    return Outcome(case.name, case.kind, outcome, None if timed_out else proc.returncode, seconds, message, argv,
                   executed)


def run_audit(root, only=None, jobs=2, timeout=TIMEOUT, log=print) -> dict:
    """Run the controls, then every case (of kind ``only`` if given) on ``jobs`` processes;
    write ``root/audit.json`` and ``root/audit.md``; return the document."""
    root = Path(root).resolve()
    for sub in ("cases", "shared"):
        shutil.rmtree(root / sub, ignore_errors=True)
    (root / "shared").mkdir(parents=True)
    build_shared(root / "shared")
    chosen = [c for c in all_cases() if only is None or c.kind == only]
    first, *rest = controls()
    checks = [run_case(first, root, timeout)]          # the seed result file, before the cases copying it
    if checks[0].returncode != 0:
        raise SystemExit(f"fault audit: the default scene does not run cleanly ({checks[0].message}); "
                         f"nothing audited")
    with ThreadPoolExecutor(max(1, jobs)) as pool:
        checks += list(pool.map(lambda c: run_case(c, root, timeout), rest))
        for check in checks:
            check.outcome = "ok" if check.returncode == 0 else "failed"
            log(f"control {check.case}: {check.outcome} ({check.seconds:.1f} s) {check.message[:100]}")
        results = []
        for result in pool.map(lambda c: run_case(c, root, timeout), chosen):
            results.append(result)
            log(f"{result.case:44s} {result.kind:6s} {result.outcome:9s} {result.message[:100]}")
    doc = {"counts": dict(Counter(r.outcome for r in results)), "tried": len(results),
           "by_kind": {kind: dict(Counter(r.outcome for r in results if r.kind == kind))
                       for kind in KINDS if any(r.kind == kind for r in results)},
           "executed": [r.case for r in results if r.executed],
           "controls": [vars(c) for c in checks], "cases": [vars(r) for r in results],
           "limits": {"timeout_s": timeout, "memory_bytes": MEMORY_LIMIT}}
    doc["counts"] = {k: doc["counts"].get(k, 0) for k in OUTCOMES}
    write_atomic(root / "audit.json", lambda f: f.write(json.dumps(doc, indent=1).encode()))
    write_atomic(root / "audit.md", lambda f: f.write(markdown(doc).encode()))
    return doc


def summary_line(doc) -> str:
    c = doc["counts"]
    return (f"bad inputs tried {doc['tried']}: clear {c['clear']}, traceback {c['traceback']}, "
            f"unclear {c['unclear']}, silent {c['silent']}, hang {c['hang']}"
            + (f"; EXECUTED planted code: {', '.join(doc['executed'])}" if doc["executed"] else ""))


def markdown(doc) -> str:
    lines = ["# Fault audit", "", summary_line(doc), "",
             f"Limits per case: {doc['limits']['timeout_s']:g} s, {doc['limits']['memory_bytes'] / 2**30:g} GiB "
             "address space.", "", "| kind | " + " | ".join(OUTCOMES) + " |", "|---" * (len(OUTCOMES) + 1) + "|"]
    lines += [f"| {kind} | " + " | ".join(str(counts.get(o, 0)) for o in OUTCOMES) + " |"
              for kind, counts in doc["by_kind"].items()]
    failed = [c for c in doc["controls"] if c["outcome"] != "ok"]
    lines += ["", f"Controls (valid inputs): {len(doc['controls']) - len(failed)} of {len(doc['controls'])} ran cleanly"
              + (": failed " + ", ".join(c["case"] for c in failed) if failed else "."), "",
              "| case | kind | outcome | exit | s | message |", "|---|---|---|---|---|---|"]
    lines += [f"| {cell(r['case'])} | {r['kind']} | {r['outcome']} | {cell(r['returncode'])} | {r['seconds']:.1f} | "
              f"{cell(r['message'][:100])} |" for r in doc["cases"]]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m validation.fault_audit", description=__doc__.split("\n")[0])
    p.add_argument("--out", required=True, help="directory for the cases, audit.json and audit.md")
    p.add_argument("--only", choices=KINDS, help="run only the cases of this kind")
    p.add_argument("--jobs", type=int, default=2, help="cases run at once (default 2)")
    p.add_argument("--timeout", type=float, default=TIMEOUT, help=f"seconds per case (default {TIMEOUT:g})")
    args = p.parse_args(argv)
    doc = run_audit(args.out, args.only, args.jobs, args.timeout)
    print(summary_line(doc))
    print(f"wrote {Path(args.out) / 'audit.json'} and {Path(args.out) / 'audit.md'}")
    failed = [c for c in doc["controls"] if c["outcome"] != "ok"]
    if failed:
        print(f"controls failed: {', '.join(c['case'] for c in failed)}: the audit's outcomes are not meaningful")
    return 0 if not failed and doc["counts"]["clear"] == doc["tried"] else 1


if __name__ == "__main__":
    sys.exit(main())
