"""Preprocessing and body-file inputs under a new user's hands and a fault audit (issue 18).

Body directories read body.h5 first (node groups and surface kept); the face groups of
built-in boxes exist at every scale; disconnected or unconstrained mesh parts, unknown
Abaqus element types and elements pointing at undefined nodes are one clear line; bad
preprocessing options and absurd body-file values are refused up front; only regular
files are read (a FIFO does not hang the reader); quoted file content is short and
sanitized.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from ffrmbs_app.cli import main
from ffrmbs import errors
from ffrmbs.errors import InputFileError, ModelError
from preprocess import Material, build_body, read_body, read_mesh, write_body
from preprocess.geometry import box
from preprocess.modes import clamped_modes
from preprocess.textfiles import TEXT_FILES
from qa.fixtures import fixture_text

import paths

REPO = paths.REPO


@pytest.fixture(scope="module")
def small_body():
    """A 250 x 50 x 50 mm beam, tet4, 4 x 1 x 2 divisions (30 nodes), clamped at x = 0, 3 modes."""
    return build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(4, 1, 2)), Material(920.0, 5e7, 0.3),
                      n_modes=3, clamp="x0")


@pytest.fixture
def body_dir(small_body, tmp_path):
    """The small body written by write_body (four text files and body.h5)."""
    directory = tmp_path / "plate"
    write_body(directory, small_body)
    return directory


def error_lines(capsys):
    """(stdout, the stderr lines that are errors, all stderr) of the last CLI call."""
    out, err = capsys.readouterr()
    return out, [line for line in err.splitlines() if line.startswith("ffrmbs: error:")], err


def assert_one_clear_line(rc, capsys, *fragments):
    """Exit 2, exactly one ``ffrmbs: error:`` line holding every fragment, no traceback."""
    out, errors, err = error_lines(capsys)
    assert rc == 2, err
    assert len(errors) == 1, err
    assert "Traceback" not in err + out
    for fragment in fragments:
        assert fragment in errors[0], errors[0]
    return errors[0], err


# --- 2. a body directory reads body.h5: node groups and surface ----------------------------------

def test_a_body_directory_reads_body_h5_with_groups_and_surface(small_body, body_dir):
    from_dir, from_h5 = read_body(body_dir), read_body(body_dir / "body.h5")
    assert sorted(from_dir.node_groups) == sorted(small_body.node_groups) == sorted(from_h5.node_groups)
    assert {"x0", "x1", "y0", "y1", "z0", "z1"} <= set(from_dir.node_groups)
    for name, nodes in small_body.node_groups.items():
        np.testing.assert_array_equal(from_dir.node_groups[name], nodes)
    np.testing.assert_array_equal(from_dir.surface_triangles, small_body.surface_triangles)
    np.testing.assert_array_equal(from_dir.surface_triangles, from_h5.surface_triangles)
    np.testing.assert_array_equal(from_dir.eigenvalues, small_body.eigenvalues)


def test_a_directory_without_body_h5_falls_back_to_the_text_files(small_body, body_dir):
    (body_dir / "body.h5").unlink()
    text = read_body(body_dir)
    np.testing.assert_array_equal(text.u0, small_body.u0)
    assert text.node_groups == {} and text.surface_triangles is None


def test_info_on_a_body_directory_prints_the_surface_nodes(small_body, body_dir, capsys):
    assert main(["info", str(body_dir)]) == 0
    out = capsys.readouterr().out
    surface = len(np.unique(small_body.surface_triangles))       # counted from the body written
    assert f"surface nodes:  {surface}\n" in out
    assert f"x0 ({len(small_body.node_groups['x0'])})" in out


def test_a_scene_body_given_as_a_directory_keeps_its_node_groups(body_dir):
    from ffrmbs_app.scene_file import read_scene

    scene_file = body_dir.parent / "scene.toml"
    scene_file.write_text(fixture_text("scenes/plate_distributed_load.toml"))
    scene = read_scene(scene_file)
    assert Path(scene.inputs["body 'plate'"]) == body_dir / "body.h5"


# --- 5. face groups of built-in boxes at every scale ------------------------------------------------

FACES = {"x0": (0, 0), "x1": (0, 1), "y0": (1, 0), "y1": (1, 1), "z0": (2, 0), "z1": (2, 1)}


@pytest.mark.parametrize("scale", [1e-3, 1e-2, 0.1, 1.0, 10.0])
def test_structured_box_faces_have_their_grid_nodes_at_every_scale(scale):
    """(n_a + 1)(n_b + 1) nodes on each face of a box of n = (4, 2, 3) divisions."""
    n = (4, 2, 3)
    mesh = box(scale, 0.2 * scale, 0.3 * scale, None, order=1, divisions=n)
    for name, (axis, _) in FACES.items():
        a, b = (k for k in range(3) if k != axis)
        assert len(mesh.group(name)) == (n[a] + 1) * (n[b] + 1), name


@pytest.mark.parametrize("scale", [1e-3, 0.1, 10.0])
def test_unstructured_box_faces_are_the_nodes_on_the_planes(scale):
    size = np.array([1.0, 0.2, 0.2]) * scale
    mesh = box(*size, 0.1 * scale, order=2)
    for name, (axis, side) in FACES.items():
        on_plane = np.flatnonzero(np.abs(mesh.points[:, axis] - side * size[axis]) <= 1e-9 * scale)
        assert on_plane.size > 0
        np.testing.assert_array_equal(mesh.group(name), on_plane, err_msg=name)


def test_preprocess_clamps_a_face_of_a_small_box(tmp_path, capsys):
    rc = main(["preprocess", "box:0.1,0.02,0.02", "--clamp", "x0", "--modes", "2", "--order", "1",
               "--mesh-size", "0.01", "--density", "7800", "--young", "2e11", "--poisson", "0.3",
               "--out", str(tmp_path / "small")])
    assert rc == 0, capsys.readouterr().err
    body = read_body(tmp_path / "small" / "body.h5")
    clamped = body.node_groups["x0"]
    np.testing.assert_allclose(body.u0[clamped, 0], 0.0, atol=1e-12)
    assert np.abs(body.phi.reshape(-1, 3, body.n_modes)[clamped]).max() == 0.0


# --- 7. disconnected and unconstrained mesh parts ----------------------------------------------------

INP = fixture_text("meshes/two_tets_and_a_stray.inp")


def write_inp(tmp_path, text=INP, name="part.inp"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_an_unconstrained_part_is_named_before_factoring(tmp_path):
    path = write_inp(tmp_path)
    with pytest.raises(InputFileError) as info:
        build_body(read_mesh(path), Material(1000.0, 1e9, 0.3), n_modes=2, clamp="base")
    assert info.value.path == str(path)
    fault = info.value.fault
    assert "unconstrained" in fault and "'base'" in fault and "4 nodes" in fault
    assert "6, 7, 8, 9" in fault and "(5, 0, 0)" in fault      # u0.dat numbers, the first one's place


def test_a_disconnected_part_is_named_for_free_modes(tmp_path):
    path = write_inp(tmp_path)
    with pytest.raises(InputFileError) as info:
        build_body(read_mesh(path), Material(1000.0, 1e9, 0.3), n_modes=2)
    assert info.value.path == str(path)
    assert "not connected" in info.value.fault and "2 parts" in info.value.fault
    assert "4 nodes" in info.value.fault and "6, 7, 8, 9" in info.value.fault


def test_disconnected_mesh_on_the_command_line(tmp_path, capsys):
    path = write_inp(tmp_path)
    rc = main(["preprocess", str(path), "--clamp", "base", "--modes", "2", "--density",
               "1000", "--young", "1e9", "--poisson", "0.3", "--out", str(tmp_path / "out")])
    assert_one_clear_line(rc, capsys, str(path), "unconstrained")
    assert not (tmp_path / "out").exists()


def test_a_singular_stiffness_is_a_model_error_not_a_runtime_error(small_body):
    """The last resort: K with a node of zero stiffness (no mesh to check)."""
    k = small_body.stiffness.tolil()
    free_node = int(np.setdiff1d(np.arange(small_body.n_nodes), small_body.node_groups["x0"])[0])
    dofs = 3 * free_node + np.arange(3)
    k[dofs, :] = 0.0
    k[:, dofs] = 0.0
    with pytest.raises(ModelError, match="singular"):
        clamped_modes(sp.csr_matrix(k), small_body.masses, 2, small_body.node_groups["x0"])


# --- 9. unreadable Abaqus input: one clear line ------------------------------------------------------

def test_an_unknown_element_type_is_one_clear_line(tmp_path, capsys):
    path = write_inp(tmp_path, INP.replace("type=C3D4", "type=C3D99"))
    rc = main(["preprocess", str(path), "--free", "--modes", "2", "--density", "1000", "--young", "1e9",
               "--poisson", "0.3", "--out", str(tmp_path / "out")])
    line, _ = assert_one_clear_line(rc, capsys, str(path), "line 13", "element type 'C3D99' not supported",
                                 "C3D4", "C3D10")
    assert "Couldn't read" not in line


def test_an_element_at_an_undefined_node_is_one_clear_line(tmp_path, capsys):
    path = write_inp(tmp_path, INP.replace("3, 6, 7, 8, 9", "3, 6, 7, 8, 99"))
    rc = main(["preprocess", str(path), "--free", "--modes", "2", "--density", "1000", "--young", "1e9",
               "--poisson", "0.3", "--out", str(tmp_path / "out")])
    assert_one_clear_line(rc, capsys, str(path), "line 16", "element 3 refers to node 99, which is not defined")


def test_a_node_set_at_an_undefined_node_is_one_clear_line(tmp_path):
    path = write_inp(tmp_path, INP.replace("1, 2, 3\n", "1, 2, 42\n"))
    with pytest.raises(InputFileError) as info:
        read_mesh(path)
    assert info.value.line == 18 and "node set 'base' refers to node 42, which is not defined" in info.value.fault


# --- 12. preprocessing options and body-file values ---------------------------------------------------

PREPROCESS = {"--modes": "2", "--density": "7800", "--young": "2e11", "--poisson": "0.3", "--mesh-size": "0.1"}


@pytest.mark.parametrize("option, value, fragment", [
    ("--mesh-size", "0", "mesh size"), ("--mesh-size", "-0.01", "mesh size"), ("--mesh-size", "nan", "mesh size"),
    ("--mesh-size", "inf", "mesh size"), ("--modes", "0", "modes"), ("--modes", "-3", "modes"),
    ("--density", "0", "density"), ("--density", "-7800", "density"), ("--density", "inf", "density"),
    ("--young", "0", "Young"), ("--young", "nan", "Young"), ("--young", "1e400", "Young"),
    ("--poisson", "0.5", "Poisson"), ("--poisson", "-1", "Poisson"), ("--poisson", "nan", "Poisson"),
])
def test_bad_preprocess_options_are_refused_before_meshing(tmp_path, capsys, option, value, fragment):
    options = dict(PREPROCESS, **{option: value})
    argv = ["preprocess", "box:1,0.2,0.2", "--clamp", "x0", "--out", str(tmp_path / "out")]
    rc = main(argv + [item for pair in options.items() for item in pair])
    _, err = assert_one_clear_line(rc, capsys, fragment)
    assert "meshing" not in err
    assert not (tmp_path / "out").exists()


def test_the_library_refuses_a_zero_mesh_size():
    from preprocess import mesh_source

    with pytest.raises(ModelError, match="mesh size"):
        mesh_source("box:0.1,0.02,0.02", 1, 0.0)


def text_body(small_body, tmp_path):
    """The small body as the four text files only (no body.h5)."""
    directory = tmp_path / "text"
    write_body(directory, small_body)
    (directory / "body.h5").unlink()
    return directory


@pytest.mark.parametrize("name", TEXT_FILES)
@pytest.mark.parametrize("value", ["1e308", "-1.0D+250", "3e201"])
def test_absurd_values_in_text_body_files_are_refused(small_body, tmp_path, name, value):
    directory = text_body(small_body, tmp_path)
    path = directory / name
    lines = path.read_text().splitlines()
    row = 4                                        # the value of the 5th data row
    fields = lines[row].split("\t") if name != "stiffnessMatrix.dat" else lines[row].split(", ")
    fields[-1 if name == "stiffnessMatrix.dat" else 0] = value
    lines[row] = ("\t" if name != "stiffnessMatrix.dat" else ", ").join(fields)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputFileError) as info:
        read_body(directory)
    assert info.value.path == str(path) and info.value.line == row + 1, info.value


@pytest.mark.parametrize("dataset", ["u0", "phi", "masses", "stiffness/data", "eigenvalues"])
def test_absurd_values_in_body_h5_are_refused(body_dir, dataset):
    path = body_dir / "body.h5"
    with h5py.File(path, "a") as f:
        data = f[dataset][()]
        data.flat[0] = 1e308
        f[dataset][...] = data
    with pytest.raises(InputFileError) as info:
        read_body(path)
    assert info.value.path == str(path) and f"'{dataset}'" in info.value.fault


def test_a_non_symmetric_stiffness_in_body_h5_is_refused(small_body, body_dir):
    path = body_dir / "body.h5"
    k = small_body.stiffness.tocoo()
    off = np.flatnonzero(k.row != k.col)[0]
    with h5py.File(path, "a") as f:
        data = f["stiffness/data"][()]
        csr = sp.csr_matrix((data, f["stiffness/indices"][()], f["stiffness/indptr"][()]))
        position = csr.indptr[k.row[off]] + np.flatnonzero(
            csr.indices[csr.indptr[k.row[off]]:csr.indptr[k.row[off] + 1]] == k.col[off])[0]
        data[position] *= 1.01
        f["stiffness/data"][...] = data
    with pytest.raises(InputFileError, match="not symmetric") as info:
        read_body(path)
    assert info.value.path == str(path)


# --- 13. only regular files are read ----------------------------------------------------------------

def run_isolated(code, tmp_path):
    """Run ``code`` in a fresh interpreter with this worktree first on the path; a hang fails."""
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=20,
                          cwd=tmp_path)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_as_a_body_text_file_is_refused_without_hanging(small_body, tmp_path):
    directory = text_body(small_body, tmp_path)
    (directory / "mij.dat").unlink()
    os.mkfifo(directory / "mij.dat")
    res = run_isolated(textwrap.dedent(f"""\
        from ffrmbs.errors import InputFileError
        from preprocess import read_body
        try:
            read_body({str(directory)!r})
        except InputFileError as exc:
            print(exc)
        """), tmp_path)
    assert res.returncode == 0, res.stderr
    assert str(directory / "mij.dat") in res.stdout and "not a regular file" in res.stdout


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("name", ["part.inp", "part.msh", "part.geo"])
def test_a_fifo_as_a_mesh_file_is_refused_without_hanging(tmp_path, name):
    os.mkfifo(tmp_path / name)
    res = run_isolated(textwrap.dedent(f"""\
        from ffrmbs.errors import InputFileError
        from preprocess import read_mesh
        try:
            read_mesh({str(tmp_path / name)!r})
        except InputFileError as exc:
            print(exc)
        """), tmp_path)
    assert res.returncode == 0, res.stderr
    assert "not a regular file" in res.stdout


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_included_by_an_abaqus_file_is_refused_without_hanging(tmp_path):
    os.mkfifo(tmp_path / "nodes.inp")
    path = write_inp(tmp_path, INP.replace("*Node\n", "*Node\n*INCLUDE, INPUT=nodes.inp\n"))
    res = run_isolated(textwrap.dedent(f"""\
        from ffrmbs.errors import InputFileError
        from preprocess import read_mesh
        try:
            read_mesh({str(path)!r})
        except InputFileError as exc:
            print(exc)
        """), tmp_path)
    assert res.returncode == 0, res.stderr
    assert "nodes.inp: not a regular file (a FIFO)" in res.stdout


def test_an_abaqus_include_is_still_read(tmp_path):
    write_inp(tmp_path, INP, "mesh.inp")
    mesh = read_mesh(write_inp(tmp_path, "*Heading\nthe mesh is included\n*INCLUDE, INPUT=mesh.inp\n"))
    assert mesh.n_nodes == 9 and mesh.n_elements == 3


def test_a_directory_as_a_mesh_file_is_refused(tmp_path):
    (tmp_path / "part.inp").mkdir()
    with pytest.raises(InputFileError, match="not a regular file"):
        read_mesh(tmp_path / "part.inp")


# --- 17. quoted file content is short and sanitized ----------------------------------------------------

def test_quote_is_short_and_printable():
    assert errors.quote("abc") == "'abc'"
    assert errors.quote("a\x00b\x1b[31m") == "'a?b?[31m'"
    assert errors.quote("x" * 30) == "'" + "x" * 20 + "…'"
    assert errors.quote("y" * 8, limit=5) == "'yyyyy…'"


def test_a_foreign_file_as_a_body_file_is_quoted_in_short(small_body, tmp_path):
    directory = text_body(small_body, tmp_path)
    secret = "root:x:0:0:root:/root:/bin/bash"
    (directory / "mij.dat").write_text(secret + "\n")
    with pytest.raises(InputFileError) as info:
        read_body(directory)
    message = str(info.value)
    assert not any(secret[i:i + 21] in message for i in range(len(secret) - 20)), message
    assert secret[:10] in message


def test_a_foreign_file_as_a_force_file_is_quoted_in_short(tmp_path):
    from mbs.links.force_file import read_force_file

    secret = "root:x:0:0:root:/root:/bin/bash"
    path = tmp_path / "passwd"
    path.write_text(secret + "\n")
    with pytest.raises(InputFileError) as info:
        read_force_file(path, 1)
    message = str(info.value)
    assert info.value.line == 1 and secret[:10] in message
    assert not any(secret[i:i + 21] in message for i in range(len(secret) - 20)), message


def test_other_volume_elements_are_refused_not_dropped(tmp_path):
    """A hexahedron beside the tetrahedra: meshio reads it, the mesh would lose it."""
    hexahedron = "".join(f"{10 + i}, {x}.0, {y}.0, {z}.0\n" for i, (x, y, z) in enumerate(
        [(0, 0, 3), (1, 0, 3), (1, 1, 3), (0, 1, 3), (0, 0, 4), (1, 0, 4), (1, 1, 4), (0, 1, 4)]))
    text = INP.replace("*Element, type=C3D4", hexahedron + "*Element, type=C3D4") + \
        "*Element, type=C3D8\n4, 10, 11, 12, 13, 14, 15, 16, 17\n"
    with pytest.raises(InputFileError, match="hexahedron are not supported"):
        read_mesh(write_inp(tmp_path, text))


def test_a_vtu_mesh_is_read_through_its_own_reader(tmp_path):
    import meshio

    mesh = box(0.25, 0.05, 0.05, None, order=1, divisions=(4, 1, 2))
    meshio.write(tmp_path / "b.vtu", meshio.Mesh(mesh.points, [("tetra", mesh.tets)]))
    back = read_mesh(tmp_path / "b.vtu")
    np.testing.assert_array_equal(back.tets, mesh.tets)


def test_a_stiffness_file_of_both_triangles_needs_every_mirror(tmp_path):
    """A lower-triangle stiffness file with one entry added in the upper triangle, where
    the lower triangle holds no mirror: the storage is mixed, so the lone entry is a
    fault (it was taken silently as a new symmetric coupling)."""
    from preprocess.textfiles import parse_stiffness

    lines = ["1,1, 1,1, 4.0", "1,2, 1,2, 4.0", "2,1, 1,1, -1.0", "2,1, 2,1, 4.0"]
    path = tmp_path / "stiffnessMatrix.dat"
    path.write_text("\n".join(lines) + "\n")
    k = parse_stiffness(path, 6).toarray()                     # one triangle: mirrored
    assert k[3, 0] == k[0, 3] == -1.0
    path.write_text("\n".join(lines + ["1,2, 2,1, 7.0"]) + "\n")
    with pytest.raises(InputFileError) as err:
        parse_stiffness(path, 6)
    assert err.value.line == 5 and "no mirror" in str(err.value)
