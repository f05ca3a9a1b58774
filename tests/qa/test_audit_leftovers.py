"""Issue 18, leftovers of the fault audit: result files damaged under `ffrmbs plot` and
`ffrmbs export`, `--order` for an already meshed file, a FIFO or a directory as the
scene file. Issue 30: two scenes whose results have one name do not overwrite each
other's; a new run removes the plot and export of the run before; an export killed or
stopped leaves no temporary directory for good."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

from ffrmbs.errors import InputFileError
from ffrmbs_app import cli
from mbs.results.result_file import load_result
from qa.fixtures import edited, fixture_text

import paths
from cli_in_process import run_cli
from fifo_watch import FifoWatch
from damage_places import damage_places, damaged as damaged_bytes

REPO = str(paths.REPO)



# --- damaged result files under plot and export --------------------------------------------------

@pytest.fixture(scope="module")
def result_file(tmp_path_factory) -> Path:
    """The result file of `ffrmbs run` with no scene (15 ms: free flight and the impact)."""
    out = tmp_path_factory.mktemp("run")
    code, _, stderr = run_cli("run", "--no-export", "--no-check", "--t-end", "0.015", "--out", out)
    assert code == 0, stderr
    return out / "point_mass_beam.h5"


def unreadable(path) -> bool:
    """Whether h5py fails to read some attribute or dataset of ``path`` in full (a direct
    reading of every object, independent of ffrmbs)."""
    def read(_, obj):
        dict(obj.attrs)
        if isinstance(obj, h5py.Dataset):
            obj[()]
    try:
        with h5py.File(path, "r") as f:
            dict(f.attrs)
            f.visititems(read)
    except Exception:   # noqa: BLE001 — any failure of the library is what is sought
        return True
    return False


@pytest.mark.slow
def test_plot_and_export_of_a_damaged_result_file_are_clear_errors(result_file, tmp_path):
    """64 bytes of 0xff every 4 KiB of a result file, one place at a time (as
    test_audit_results.py damages one for load_result; within one dataset's raw data, one
    place per dataset: h5py reads such bytes as values, never fails on them); at every
    place where h5py itself cannot read the file, `ffrmbs plot` and `ffrmbs export` either
    work or exit 2 with one line naming the file (h5py raised a raw OSError, RuntimeError
    or KeyError through both), and write nothing. The export writes every 100th sample:
    11 of 1001, still from each 256-sample chunk of every dataset."""
    data = result_file.read_bytes()
    damaged = tmp_path / "damaged.h5"
    png, paraview = tmp_path / "damaged.png", tmp_path / "damaged-paraview"
    places, errors = 0, {"plot": 0, "export": 0}
    for offset in damage_places(result_file):
        damaged.write_bytes(damaged_bytes(data, offset))
        if not unreadable(damaged):
            continue
        places += 1
        for command, output, options in (("plot", png, ()), ("export", paraview, ("--every", 100))):
            code, _, stderr = run_cli(command, damaged, "--out", output, *options)     # every 100th of 1001
            if code == 0:
                shutil.rmtree(output) if output.is_dir() else output.unlink()
                continue
            errors[command] += 1
            assert code == 2 and stderr.startswith(f"ffrmbs: error: {damaged}: "), (offset, stderr)
            assert stderr.count("\n") == 1 and len(stderr) < 300, (offset, stderr)
            assert not output.exists(), (offset, command)
    assert places >= 3
    assert errors["plot"] >= 2 and errors["export"] >= 2, errors


@pytest.mark.slow
def test_export_of_a_result_file_with_a_damaged_chunk_index_names_the_file(result_file, tmp_path):
    """The signature of each chunk index node (HDF5 v1 B-tree "TREE", node type 1: raw
    data chunks) overwritten, one at a time: the per-sample reads during the export fail
    ("wrong B-tree signature"); that is the result file's fault, not "cannot write the
    ParaView export" (an OSError from reading was taken for one from writing)."""
    data = result_file.read_bytes()
    nodes = [m.start() for m in re.finditer(b"TREE\x01", data)]
    damaged, paraview = tmp_path / "damaged.h5", tmp_path / "damaged-paraview"
    assert len(nodes) >= 5
    errors = 0
    for offset in nodes:
        damaged.write_bytes(data[:offset] + b"\xff" * 4 + data[offset + 4:])
        code, _, stderr = run_cli("export", damaged, "--every", 100, "--out", paraview)
        if code == 0:
            shutil.rmtree(paraview)
            continue
        errors += 1
        assert code == 2 and stderr.startswith(f"ffrmbs: error: {damaged}: damaged result file ("), (offset, stderr)
        assert stderr.count("\n") == 1 and not paraview.exists(), (offset, stderr)
        assert not list(tmp_path.glob(".damaged-paraview*")), offset      # no temporary directory left
    assert errors >= 3


@pytest.mark.parametrize("command", ["plot", "export"])
def test_a_directory_as_the_result_file_is_named(tmp_path, command):
    """A directory given as the result file said "no such result file"."""
    directory = tmp_path / "run.h5"
    directory.mkdir()
    code, _, stderr = run_cli(command, directory, "--out", tmp_path / "out")
    assert code == 2 and stderr == f"ffrmbs: error: {directory}: not a regular file (a directory)\n"
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("command", ["plot", "export"])
def test_a_fifo_as_the_result_file_is_named_and_not_opened(tmp_path, command):
    """A FIFO given as the result file said "no such result file"; it is named, and never
    opened (watched: :mod:`fifo_watch`)."""
    fifo = tmp_path / "run.h5"
    os.mkfifo(fifo)
    with FifoWatch(fifo) as watch:
        code, _, stderr = run_cli(command, fifo, "--out", tmp_path / "out")
    assert not watch.opened
    assert code == 2 and stderr == f"ffrmbs: error: {fifo}: not a regular file (a FIFO)\n", stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_load_result_of_a_fifo_is_refused_without_opening_it(tmp_path):
    """mbs.results.result_file.load_result handed the FIFO to HDF5, whose open blocks without a
    writer (watched: :mod:`fifo_watch`)."""
    fifo = tmp_path / "run.h5"
    os.mkfifo(fifo)
    with FifoWatch(fifo) as watch, pytest.raises(InputFileError) as err:
        load_result(fifo)
    assert not watch.opened, "load_result opened the FIFO"
    assert str(err.value) == f"{fifo}: not a regular file (a FIFO)"


# --- outputs of another scene, of the run before, of an export killed (issue 30) --------------------


def drop_scene(path, mass=1.0, t_end=0.05, options="") -> Path:
    """scenes/drop.toml (a point mass dropped 1 mm onto the ground plane, its result named
    "drop" whatever the file's name) with ``mass`` [kg], ``t_end`` [s] and the TOML text
    ``options`` appended."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(edited(fixture_text("scenes/drop.toml"), ("mass = 1.0", f"mass = {mass}"),
                           ("t_end = 0.05", f"t_end = {t_end}")) + options)
    return path


def files_in(directory) -> dict:
    """{name: bytes or "dir"} of every entry of ``directory`` (hidden ones included)."""
    return {p.name: "dir" if p.is_dir() else p.read_bytes() for p in sorted(Path(directory).iterdir())}


def dead_pid() -> int:
    """The pid of a process that has ended."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def replaced(path, theirs, ours) -> str:
    return (f"ffrmbs: warning: {path} held the result of {theirs}; this run of {ours} replaces it (its plot and "
            "ParaView export too; another --out keeps both)\n")


def test_two_scene_files_naming_their_results_alike_say_so_when_one_replaces_the_other(tmp_path):
    """Scene files a/drop.toml and b/drop.toml both name their result "drop": the second
    into the same --out warns in one line naming the file and both scenes before it
    replaces the first's result; a scene run again over its own result says nothing."""
    a, b, out = drop_scene(tmp_path / "a" / "drop.toml"), drop_scene(tmp_path / "b" / "drop.toml", 2.0), tmp_path / "out"
    for scene, warning in ((a, ""), (a, ""), (b, replaced(out / "drop.h5", f"scene file {a}", f"scene file {b}"))):
        code, _, stderr = run_cli("run", scene, "--no-check", "--no-export", "--out", out)
        assert code == 0 and stderr == warning, stderr
    with h5py.File(out / "drop.h5", "r") as f:
        assert json.loads(f.attrs["inputs"])["scene file"]["path"] == str(b)


@pytest.mark.slow
def test_the_example_scene_file_says_it_replaces_the_default_scenes_result(result_file, tmp_path):
    """examples/scenes/point_mass_beam.toml and the default scene both write
    point_mass_beam.*: the scene file run into the default scene's --out says so."""
    out = tmp_path / "out"
    shutil.copytree(result_file.parent, out)
    example = Path(REPO) / "examples" / "scenes" / "point_mass_beam.toml"
    code, _, stderr = run_cli("run", example, "--no-check", "--no-export", "--set", "scene.t_end=2e-5", "--set",
                              "scene.n_out=3", "--out", out)
    assert code == 0 and stderr == replaced(out / "point_mass_beam.h5", "the default scene", f"scene file {example}")


def stale_exports(out) -> list:
    """Temporary directories of exports to ``out/drop-paraview`` left by processes that
    ended (a kill -9 mid-export)."""
    pid = dead_pid()
    made = [out / f".drop-paraview.tmp-{pid}-x1y2z3", out / f".drop-paraview.old-{pid}-a1b2c3"]
    for d in made:
        (d / "body").mkdir(parents=True)
        (d / "body" / "body_000001.vtu").write_text("partial")
    return made


def test_a_new_run_removes_the_plot_and_export_of_the_run_before(tmp_path):
    """A run that fails (here: a penetration beyond its bound at the first impact) after
    starting its result file leaves no plot or ParaView export of the run before beside
    it, nor what a killed export left; the result file says "failed"."""
    scene, out = drop_scene(tmp_path / "drop.toml"), tmp_path / "out"
    code, _, stderr = run_cli("run", scene, "--no-check", "--out", out)
    assert code == 0, stderr
    stale = stale_exports(out)
    drop_scene(scene, options="[scene.options]\npenetration_bound = 1e-9\n")
    code, _, stderr = run_cli("run", scene, "--no-check", "--out", out)
    assert code == 2 and "penetration" in stderr, stderr
    assert sorted(files_in(out)) == ["drop.h5"]
    with h5py.File(out / "drop.h5", "r") as f:
        assert f.attrs["status"].startswith("failed: ")
    assert not any(d.exists() for d in stale)


def test_an_export_removes_what_killed_exports_left_and_keeps_a_running_ones(tmp_path):
    scene, out = drop_scene(tmp_path / "drop.toml"), tmp_path / "out"
    code, _, stderr = run_cli("run", scene, "--no-check", "--no-export", "--out", out)
    assert code == 0, stderr
    stale = stale_exports(out)
    running = out / f".drop-paraview.tmp-{os.getpid()}-r4s5t6"       # an export of a live process
    running.mkdir()
    code, _, stderr = run_cli("export", out / "drop.h5")
    assert code == 0, stderr
    assert not any(d.exists() for d in stale) and running.is_dir()
    assert (out / "drop-paraview" / "drop.pvd").is_file()


@pytest.mark.slow
def test_a_run_killed_after_starting_its_file_leaves_no_plot_or_export_of_the_run_before(tmp_path):
    """kill -9 of a run once it has replaced the result file of the run before: the new
    file (status "running") stands alone."""
    scene, out = drop_scene(tmp_path / "drop.toml"), tmp_path / "out"
    code, _, stderr = run_cli("run", scene, "--no-check", "--out", out)
    assert code == 0, stderr
    path = out / "drop.h5"
    first = path.stat().st_ino
    drop_scene(scene, t_end=200.0)           # 2e6 steps: still running when killed
    proc = subprocess.Popen([sys.executable, "-m", "ffrmbs_app.cli", "run", str(scene), "--no-check", "--no-limits",
                             "--out", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env=os.environ | {"PYTHONPATH": REPO})
    deadline = time.monotonic() + 300
    while not (path.exists() and path.stat().st_ino != first):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the run did not start its file"
        time.sleep(0.01)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate()
    assert sorted(files_in(out)) == ["drop.h5", "drop.lock"]        # the lock file of the killed job stays
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == "running"


@pytest.mark.slow
def test_sigterm_during_an_export_leaves_no_temporary_directory(result_file, tmp_path):
    """SIGTERM while `ffrmbs export` writes: it stops like Ctrl-C (exit 130) and removes
    its temporary directory; nothing is left in the output's directory."""
    target = tmp_path / "exports" / "pmb-paraview"
    target.parent.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "ffrmbs_app.cli", "export", str(result_file), "--out", str(target)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=os.environ | {"PYTHONPATH": REPO})
    deadline = time.monotonic() + 300
    while not list(target.parent.glob(".pmb-paraview.tmp-*/*/*.vtu")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the export wrote nothing"
        time.sleep(0.01)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130 and stderr == "ffrmbs: interrupted\n", stderr
    assert not any(target.parent.iterdir())


# --- --order for an already meshed file -----------------------------------------------------------

PREPROCESS = ["--modes", "2", "--free", "--density", "7800", "--young", "2e11", "--poisson", "0.3"]


@pytest.fixture(scope="module")
def meshed_files(tmp_path_factory) -> dict:
    """A 0.2 x 0.05 x 0.05 box of tet4 and of tet10 elements, each as .inp and .msh:
    {(suffix, order): path}."""
    import meshio

    from preprocess.geometry import box

    directory = tmp_path_factory.mktemp("meshed")
    files = {}
    for order, cell in ((1, "tetra"), (2, "tetra10")):
        mesh = box(0.2, 0.05, 0.05, 0.05, order)
        for suffix, fmt in ((".inp", "abaqus"), (".msh", "gmsh")):
            path = directory / f"box{order}{suffix}"
            meshio.write(path, meshio.Mesh(mesh.points, [(cell, mesh.tets)]), file_format=fmt)
            files[suffix, order] = path
    return files


def order_column(stdout) -> str:
    """The element type printed by the mesh statistics (the row under "element type")."""
    lines = stdout.splitlines()
    head = next(i for i, line in enumerate(lines) if "element type" in line)
    return lines[head + 1].split()[3]


@pytest.mark.parametrize("suffix", [".inp", ".msh"])
@pytest.mark.parametrize("order", ["1", "2"])
def test_an_order_for_a_meshed_file_is_refused(meshed_files, tmp_path, suffix, order):
    """`--order` was silently ignored for a .msh or .inp (the file's elements decide the
    order): it is refused in one line, like `--mesh-size` for such a file, before anything
    is written."""
    path = meshed_files[suffix, 1]
    code, stdout, stderr = run_cli("preprocess", path, "--order", order, *PREPROCESS, "--out", tmp_path / "out")
    assert code == 2 and stderr.count("\n") == 1 and stderr.startswith("ffrmbs: error: "), stderr
    assert "--order" in stderr and str(path) in stderr and "already meshed" in stderr, stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("suffix", [".inp", ".msh"])
@pytest.mark.parametrize("order, element", [(1, "tet4"), (2, "tet10")])
def test_a_meshed_file_keeps_its_order(meshed_files, tmp_path, suffix, order, element):
    code, stdout, stderr = run_cli("preprocess", meshed_files[suffix, order], *PREPROCESS, "--out", tmp_path / "out")
    assert code == 0, stderr
    assert order_column(stdout) == element


@pytest.mark.parametrize("option, element", [((), "tet10"), (("--order", "1"), "tet4"), (("--order", "2"), "tet10")])
def test_a_built_in_geometry_is_tet10_unless_asked(tmp_path, option, element):
    code, stdout, stderr = run_cli("preprocess", "box:0.2,0.05,0.05", "--mesh-size", "0.05", *option, *PREPROCESS,
                                   "--out", tmp_path / "out")
    assert code == 0, stderr
    assert order_column(stdout) == element


def test_the_order_help_says_what_it_applies_to(capsys):
    with pytest.raises(SystemExit):
        cli.main(["preprocess", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--order {1,2}" in text and ".geo" in text and "default 2" in text and "own order" in text


# --- a FIFO or a directory as the scene file -------------------------------------------------------

@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("name", ["scene.toml", "model.py"])
def test_a_fifo_as_the_scene_file_is_named_and_not_opened(tmp_path, name):
    """`ffrmbs run FIFO` said "no such scene file"; it says what the path is, and never
    opens it (opening a FIFO without a writer blocks; watched: :mod:`fifo_watch`)."""
    fifo = tmp_path / name
    os.mkfifo(fifo)
    with FifoWatch(fifo) as watch:
        code, _, stderr = run_cli("run", fifo, "--out", tmp_path / "out")
    assert not watch.opened
    assert code == 2, stderr
    assert stderr == f"ffrmbs: error: {fifo}: not a regular file (a FIFO)\n"
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("name", ["scene.toml", "model.py"])
def test_a_directory_as_the_scene_file_is_named(tmp_path, name):
    directory = tmp_path / name
    directory.mkdir()
    code, _, stderr = run_cli("run", directory, "--out", tmp_path / "out")
    assert code == 2 and stderr == f"ffrmbs: error: {directory}: not a regular file (a directory)\n"
    assert not (tmp_path / "out").exists()


def test_read_scene_refuses_a_fifo_without_opening_it(tmp_path):
    """ffrmbs_app.scene_file.read_scene called from Python (not through load_scene) on a
    FIFO: refused at once (it blocked in read_bytes)."""
    from ffrmbs_app.scene_file import read_scene

    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    with FifoWatch(fifo) as watch, pytest.raises(InputFileError) as err:
        read_scene(fifo)
    assert not watch.opened
    assert "not a regular file (a FIFO)" in str(err.value)
