"""The fault audit's cases (:mod:`qa.fault_audit`): bad inputs, each one small edit of a valid one.

Every case is one record (:class:`Case`): its name, kind, the files to write into its case
directory (builders of :mod:`qa.planted_files`), the argument list after ``ffrmbs`` and the
substrings a clear message contains. The valid inputs every case starts from are written
into the audit's ``shared/`` directory by :func:`build_shared`: the base scene
(``tests/fixtures/scenes/every_entry.toml``), the meshes ``tests/fixtures/meshes/cube_six_tet4.inp``
and ``bar.geo`` (the tests' fixture files) and a small body. :func:`controls` are valid
inputs that must run cleanly, so that a case's outcome is due to its one fault.

Kinds of bad inputs (:data:`KINDS`): ``scene`` (TOML scene files, :mod:`ffrmbs_app.scene_file`),
``body`` (the thesis's text files and ``body.h5``, via ``ffrmbs info`` and via a scene),
``mesh`` (``ffrmbs preprocess`` inputs and options), ``run`` (options of the default
scene, ``--resume`` with missing, damaged and planted checkpoints) and ``result``
(``ffrmbs plot`` / ``export`` of missing, foreign or damaged result files).
"""

from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from qa.fixtures import edited, fixture_text
from qa.planted_files import (PICKLED_HEADER, copy, fifo, folder, h5_edited, lines_edited, planted_object_array,
                              planted_pickle, raw, scene_file, text, truncated)

KINDS = ("scene", "body", "mesh", "run", "result")
FAST_RUN = ("--t-end", "0.001", "--no-check", "--no-export")   # the default scene, 100 steps
OUT = "{case}/out"


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


# --- the valid inputs every case starts from -------------------------------------------------

BASE_SCENE = fixture_text("scenes/every_entry.toml")
"""A scene touching every kind of entry: the audit's small beam (``shared/body.h5``), a
rigid block on a spring and a spherical joint, a point mass on the beam's top face with
Coulomb contact, gravity, a force and two outputs. 20 Moreau steps."""

BODY_SOURCE = '"../../shared/body.h5"'
"""The base scene's body file, as named from a case directory."""

CUBE_INP = fixture_text("meshes/cube_six_tet4.inp")
"""A 0.1 m cube of six tet4, its face x = 0 the node set x0."""

BAR_GEO = fixture_text("meshes/bar.geo")
"""A 200 x 50 x 50 mm bar (gmsh), its face x = 0 the surface group x0."""

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
    (shared / "scene.toml").write_text(BASE_SCENE)
    (shared / "cube.inp").write_text(CUBE_INP)
    (shared / "bar.geo").write_text(BAR_GEO)
    (shared / "notes.txt").write_text("not a result file\n")


def scene_text(*edits, source=BODY_SOURCE) -> str:
    """:data:`BASE_SCENE` with its body file ``source`` and each (old, new) edit applied."""
    return edited(BASE_SCENE, (f"source = {BODY_SOURCE}", f"source = {source}"), *edits)


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
    ("missing_source", ("source",), f"source = {BODY_SOURCE}\n", ""),
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
    cases = [scene_case(name, expect, (old, new)) for name, expect, old, new in SCENE_EDITS]
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
    faulty = [(name, file, _replacing(lines_edited(f"body/{file}", edit))) for name, file, edit in TEXT_FAULTS]
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
    return text(edited(CUBE_INP, *edits))


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
