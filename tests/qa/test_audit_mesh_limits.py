"""Preprocessing resources bounded up front, and .geo inputs read safely (issue 18, 13).

A mesh size far below the body's size, in a built-in geometry or a ``.geo`` file, is
refused before gmsh meshes, with the estimate and ``--no-limits``; a mesh file over the
limits is refused before assembly; ``--mesh-size`` for an already meshed file is an
error; a file a ``.geo`` merges or includes must be a regular file (a FIFO would hang
gmsh). Cases that would exhaust memory without the guard run in a child process with
bounded address space and time, so a regression fails instead of taking the machine.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from ffrmbs_app.cli import main
from ffrmbs.errors import InputFileError, ModelError
from preprocess import Material, build_body, fe, limits, read_mesh
from preprocess.geometry import box, stepped_beam
from qa.fixtures import fixture_text

import paths

REPO = paths.REPO
MATERIAL = ["--density", "7800", "--young", "2e11", "--poisson", "0.3"]
ADDRESS_SPACE = 4 << 30            # bytes a child process may map


def run_bounded(argv, cwd, timeout=30):
    """``python argv`` with this worktree first on the path, at most ADDRESS_SPACE of
    memory and ``timeout`` seconds (TimeoutExpired fails the test)."""
    def bound():
        resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))

    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.run([sys.executable, *argv], capture_output=True, text=True, env=env, timeout=timeout,
                          cwd=cwd, preexec_fn=bound)


def preprocess_bounded(spec, tmp_path, *options):
    """``ffrmbs preprocess spec`` in a bounded child process: (exit status, error lines, stderr)."""
    res = run_bounded(["-m", "ffrmbs_app.cli", "preprocess", spec, "--modes", "2", "--free", *MATERIAL,
                       "--out", str(tmp_path / "out"), *options], tmp_path)
    errors = [line for line in res.stderr.splitlines() if line.startswith("ffrmbs: error:")]
    return res.returncode, errors, res.stderr


def assert_refused(rc, errors, err, *fragments):
    assert rc == 2, err
    assert len(errors) == 1 and "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in errors[0], errors[0]
    return errors[0]


def number_before(line, words):
    """The number printed just before ``words`` in ``line`` ("about 5.5e+12 tet10 elements")."""
    return float(line.split(words)[0].split()[-1])


# --- the estimate against real gmsh meshes ---------------------------------------------------------

@pytest.mark.parametrize("make, volume, extent, size, order", [
    (lambda h, o: box(1.0, 1.0, 1.0, h, o), 1.0, 1.0, 0.1, 1),
    (lambda h, o: box(1.0, 1.0, 1.0, h, o), 1.0, 1.0, 0.05, 1),
    (lambda h, o: box(1.0, 0.2, 5.0, h, o), 1.0, 5.0, 0.1, 2),
    (lambda h, o: stepped_beam(h, o), 10 * 34.2 * 20 + 95 * 10 * 9.74, 105.0, 2.0, 2),
])
def test_the_estimate_bounds_real_gmsh_meshes_closely(make, volume, extent, size, order):
    """Counted elements and nodes, and K's nonzeros, lie within the estimate and at most
    1.5 times below it (the volume computed by hand)."""
    mesh = make(size, order)
    estimate = limits.from_mesh_size(volume, extent, size, order)
    assert mesh.n_elements <= estimate.n_elements <= 1.5 * mesh.n_elements
    assert mesh.n_nodes <= estimate.n_nodes <= 1.5 * mesh.n_nodes
    nonzeros = fe.stiffness_matrix(mesh, 2e11, 0.3).nnz
    assert nonzeros <= limits.K_NONZEROS_PER_NODE[order] * mesh.n_nodes <= 1.5 * nonzeros


def test_a_known_mesh_is_estimated_from_its_counts():
    mesh = box(1.0, 0.2, 0.2, 0.1, order=1)
    estimate = limits.from_mesh(mesh.n_nodes, mesh.n_elements, 1, 0.04, 1.0)
    assert (estimate.n_nodes, estimate.n_elements) == (mesh.n_nodes, mesh.n_elements)
    assert estimate.memory >= mesh.n_elements * 12 ** 2 * 24      # the element matrices' triplets, at least


# --- refusals before meshing -----------------------------------------------------------------------

def test_a_tiny_mesh_size_is_refused_before_meshing(tmp_path):
    rc, errors, err = preprocess_bounded("box:1,1,1", tmp_path, "--mesh-size", "1e-4")
    line = assert_refused(rc, errors, err, "<builtin box>", "element size 0.0001", "tet10 elements", "nodes",
                          "GB of memory", "5e+06 nodes", "of physical memory",
                          "pass --no-limits (check_limits=False from Python) to run it anyway")
    elements = number_before(line, " tet10 elements")
    assert 4.5e12 <= elements <= 7e12          # 4.6 to 5.9 V / h³ measured in gmsh meshes, V = 1, h = 1e-4
    assert not (tmp_path / "out").exists()


def test_a_geo_file_with_a_tiny_characteristic_length_is_refused_before_meshing(tmp_path):
    (tmp_path / "part.geo").write_text(textwrap.dedent("""\
        lc = 1e-4;
        Point(1) = {0, 0, 0, lc}; Point(2) = {2, 0, 0, lc}; Point(3) = {2, 1, 0, lc}; Point(4) = {0, 1, 0, lc};
        Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
        Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
        Extrude {0, 0, 0.5} { Surface{1}; }
        """))
    rc, errors, err = preprocess_bounded("part.geo", tmp_path)
    line = assert_refused(rc, errors, err, "part.geo", "element size 0.0001", "(volume 1)",
                          "pass --no-limits (check_limits=False from Python) to run it anyway")
    assert 4.5e12 <= number_before(line, " tet10 elements") <= 7e12     # V = 2 x 1 x 0.5, h = 1e-4


def test_a_structured_box_of_too_many_cells_is_refused_before_meshing(tmp_path):
    res = run_bounded(["-c", textwrap.dedent("""\
        from ffrmbs.errors import ModelError
        from preprocess.geometry import box
        try:
            box(1.0, 1.0, 1.0, None, order=1, divisions=(2000, 2000, 2000))
        except ModelError as exc:
            print(exc)
        """)], tmp_path)
    assert res.returncode == 0, res.stderr
    assert "about 4.8e+10 tet4 elements" in res.stdout           # 6 tetrahedra per cell
    assert "pass --no-limits (check_limits=False from Python) to run it anyway" in res.stdout


def test_no_limits_lifts_the_limit(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(limits, "MAX_NODES", 20)
    argv = ["preprocess", "box:1,1,1", "--mesh-size", "0.5", "--order", "1", "--modes", "2", "--free", *MATERIAL]
    rc = main(argv + ["--out", str(tmp_path / "limited")])
    err = capsys.readouterr().err
    assert rc == 2 and "2e+01 nodes" in err, err
    assert "pass --no-limits (check_limits=False from Python) to run it anyway" in err, err
    assert not (tmp_path / "limited").exists()
    assert main(argv + ["--out", str(tmp_path / "lifted"), "--no-limits"]) == 0
    assert (tmp_path / "lifted" / "body.h5").is_file()


@pytest.mark.skipif(not Path("/proc/meminfo").is_file(), reason="no /proc/meminfo to compare with")
def test_physical_memory_is_the_machine_memory():
    total_kb = next(int(line.split()[1]) for line in Path("/proc/meminfo").read_text().splitlines()
                    if line.startswith("MemTotal:"))
    assert limits.physical_memory() == pytest.approx(1024.0 * total_kb, rel=0.01)


# --- a mesh file over the limits: refused before assembly ------------------------------------------

INP = fixture_text("meshes/two_tets.inp")


def test_a_mesh_file_over_the_node_limit_is_refused_before_assembly(tmp_path, monkeypatch):
    path = tmp_path / "part.inp"
    path.write_text(INP)
    mesh = read_mesh(path)
    monkeypatch.setattr(limits, "MAX_NODES", 4)
    monkeypatch.setattr(fe, "stiffness_matrix", lambda *a: pytest.fail("assembled"))
    with pytest.raises(ModelError) as info:
        build_body(mesh, Material(1000.0, 1e9, 0.3), n_modes=2)
    message = str(info.value)
    assert message.startswith(f"{path}: about 2 tet4 elements, 5 nodes") and "4e+00 nodes" in message
    assert message.endswith("pass --no-limits (check_limits=False from Python) to run it anyway")


def test_a_mesh_over_the_memory_limit_is_refused_with_the_machine_memory(tmp_path, monkeypatch, capsys):
    path = tmp_path / "part.inp"
    path.write_text(INP)
    monkeypatch.setattr(limits, "physical_memory", lambda: 1e4)     # 10 kB, below 2 element matrices' triplets
    rc = main(["preprocess", str(path), "--modes", "1", "--free", *MATERIAL, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 2 and f"ffrmbs: error: {path}: about 2 tet4 elements, 5 nodes" in err, err
    assert "50% of the 1e-05 GB of physical memory" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


# --- 2. --mesh-size for a meshed file ----------------------------------------------------------------

@pytest.mark.parametrize("name", ["part.inp", "part.msh"])
def test_mesh_size_for_a_meshed_file_is_refused(tmp_path, capsys, name):
    import meshio

    (tmp_path / "p.inp").write_text(INP)
    path = tmp_path / name
    meshio.write(path, meshio.read(tmp_path / "p.inp"), **({"file_format": "gmsh22"} if name.endswith(".msh") else {}))
    assert read_mesh(path).n_nodes == 5
    rc = main(["preprocess", str(path), "--mesh-size", "0.1", "--modes", "1", "--free", *MATERIAL,
               "--out", str(tmp_path / "o")])
    out, err = capsys.readouterr()
    assert rc == 2 and "Traceback" not in err
    assert err.strip().splitlines()[-1] == (f"ffrmbs: error: --mesh-size applies to built-in geometries, "
                                            f".geo, STEP and IGES files; {path} is already meshed")


# --- 3. files a .geo reads --------------------------------------------------------------------------

BOX_GEO = 'SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 1, 0.2, 0.2};\n'


def read_geo_isolated(path, cwd):
    """read_mesh(path) in a bounded child process; prints the InputFileError or the node count."""
    return run_bounded(["-c", textwrap.dedent(f"""\
        from ffrmbs.errors import InputFileError
        from preprocess import read_mesh
        try:
            print(read_mesh({str(path)!r}, order=1, mesh_size=0.1).n_nodes)
        except InputFileError as exc:
            print(exc)
        """)], cwd, timeout=20)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("statement", ['Merge "parts/shape.step";', 'Include "parts/shape.geo";',
                                       'v() = ShapeFromFile("parts/shape.step");'])
def test_a_fifo_read_by_a_geo_file_is_refused_without_hanging(tmp_path, statement):
    (tmp_path / "parts").mkdir()
    fifo = tmp_path / "parts" / statement.split('"')[1].split("/")[1]
    os.mkfifo(fifo)
    path = tmp_path / "part.geo"
    path.write_text(BOX_GEO + statement + "\n")
    res = read_geo_isolated(path, tmp_path)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == f"{fifo}: not a regular file (a FIFO)"


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_merged_by_an_included_geo_file_is_refused(tmp_path):
    (tmp_path / "sub").mkdir()
    os.mkfifo(tmp_path / "sub" / "data.pos")
    (tmp_path / "sub" / "inner.geo").write_text('Merge "data.pos";\n')      # relative to sub/
    path = tmp_path / "part.geo"
    path.write_text(BOX_GEO + 'Include "sub/inner.geo";\n')
    res = read_geo_isolated(path, tmp_path)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == f"{tmp_path / 'sub' / 'data.pos'}: not a regular file (a FIFO)"


def test_a_missing_included_file_is_one_clear_line(tmp_path):
    path = tmp_path / "part.geo"
    path.write_text(BOX_GEO + "// Include \"commented.geo\";\nInclude \"missing.geo\";\n")
    with pytest.raises(InputFileError) as info:
        read_mesh(path, order=1, mesh_size=0.1)
    assert str(info.value) == f"{tmp_path / 'missing.geo'}: file not found"


def test_an_included_geo_file_is_still_read(tmp_path):
    (tmp_path / "inner.geo").write_text("Box(1) = {0, 0, 0, 1, 0.2, 0.2};\n")
    path = tmp_path / "part.geo"
    path.write_text('SetFactory("OpenCASCADE");\n/* a comment\n spanning lines */\nInclude "inner.geo";\n')
    mesh = read_mesh(path, order=1, mesh_size=0.1)
    np.testing.assert_allclose(np.ptp(mesh.points, axis=0), [1.0, 0.2, 0.2])


def test_a_mesh_command_in_a_geo_file_is_refused_unless_limits_are_lifted(tmp_path):
    path = tmp_path / "part.geo"
    path.write_text(BOX_GEO + "/* two\nlines */\nMesh 3;\n")
    with pytest.raises(InputFileError) as info:
        read_mesh(path, order=1, mesh_size=0.1)
    assert info.value.line == 5 and "'Mesh 3;' meshes while gmsh reads the file" in info.value.fault
    assert read_mesh(path, order=1, mesh_size=0.1, check_limits=False).n_nodes > 8
