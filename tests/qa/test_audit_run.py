"""Issue 18, the run and the scene: bad options and scene values refused up front with one
clear line, a diverging run stopped (never "complete"), resources bounded before
anything is allocated, one run per output at a time, checkpoints that hold data, scene names
kept inside --out, short quotations of file contents."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from mbs.results.checkpoint import read_checkpoint
from cli_in_process import run_cli
from qa.fixtures import edited, fixture_text

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}

FALLING_MASS = fixture_text("scenes/falling_mass.toml")


def scene_file(tmp_path, name="fall", t_end=0.01, dt=1e-3, n_out=11, gravity="[0.0, -9.81, 0.0]",
               velocity="[0.0, 0.0, 0.0]", file="scene.toml") -> Path:
    """scenes/falling_mass.toml with the given values, written to ``tmp_path / file``."""
    path = tmp_path / file
    path.write_text(edited(FALLING_MASS, ('name = "fall"', f'name = "{name}"'), ("t_end = 0.01", f"t_end = {t_end}"),
                           ("dt = 1e-3", f"dt = {dt}"), ("n_out = 11", f"n_out = {n_out}"),
                           ("gravity = [0.0, -9.81, 0.0]", f"gravity = {gravity}"),
                           ("velocity = [0.0, 0.0, 0.0]", f"velocity = {velocity}")))
    return path


def ffrmbs(*args, cwd=None):
    """``python -m ffrmbs_app.cli ARGS`` in its own process: exit code, stdout, stderr."""
    return subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", *map(str, args)], capture_output=True, text=True,
                          env=ENV, cwd=cwd, timeout=600)


def ffrmbs_in_process(*args):
    """:func:`cli_in_process.run_cli` as a CompletedProcess, like :func:`ffrmbs` (a command
    refused up front costs no interpreter start);
    test_a_refusal_is_the_same_in_its_own_process checks that the process adds nothing."""
    return subprocess.CompletedProcess(["ffrmbs", *map(str, args)], *run_cli(*args))


def one_clear_line(res, *fragments):
    """Exit 2, one line 'ffrmbs: error: …' holding every fragment, no traceback."""
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2, res.stderr
    assert "Traceback" not in res.stderr and len(lines) == 1 and lines[0].startswith("ffrmbs: error: "), res.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


@pytest.mark.parametrize("args, scene", [(["--modes", "0"], None), ([], dict(gravity="[0.0, -1e300, 0.0]"))],
                         ids=["default scene option", "scene file value"])
def test_a_refusal_is_the_same_in_its_own_process(tmp_path, args, scene):
    """The refusals below run ffrmbs_app.cli.main in the test's process: the command in
    its own process gives the same exit code 2, the same one line (no traceback, no
    warning) and the same nothing on stdout, and writes no output directory."""
    argv = ["run", *([scene_file(tmp_path, **scene)] if scene else []), "--out", tmp_path / "out", *args]
    own, here = ffrmbs(*argv), ffrmbs_in_process(*argv)
    one_clear_line(own)
    assert (own.returncode, own.stdout, own.stderr) == (here.returncode, here.stdout, here.stderr)
    assert not (tmp_path / "out").exists()


# --- 15: checkpoints hold data, not code ----------------------------------------------------------

class _Plant:
    """A pickle that, once loaded, creates the file ``marker`` (the stand-in of os.system)."""

    def __init__(self, marker):
        self.marker = Path(marker)

    def __reduce__(self):
        return Path.touch, (self.marker,)


OLD_FORMAT = "a pickled checkpoint of an older ffrmbs (ffrmbs-checkpoint-{}): refused unread"
NOT_OURS = "not an ffrmbs checkpoint, or damaged"


def refused(kind):
    """The refusal read_checkpoint gives for a planted checkpoint of ``kind``."""
    return {"old format": OLD_FORMAT.format(1), "old signed format": OLD_FORMAT.format(2)}.get(kind, NOT_OURS)


def planted_checkpoints(marker):
    """Hand-made checkpoints holding the planted pickle: the two older pickled formats'
    headers (the second with a forged signature) and a bare pickle."""
    payload = pickle.dumps({"integrator": _Plant(marker)})
    return {"old format": b"ffrmbs-checkpoint-1\n" + payload,
            "old signed format": b"ffrmbs-checkpoint-2\n" + b"0" * 64 + b"\n" + payload,
            "bare pickle": payload}


@pytest.mark.parametrize("kind", ["old format", "old signed format", "bare pickle"])
def test_a_planted_checkpoint_is_refused_unread(tmp_path, kind):
    marker = tmp_path / "marker"
    ckpt = tmp_path / "run.h5.ckpt"
    ckpt.write_bytes(planted_checkpoints(marker)[kind])
    with pytest.raises(Exception) as err:
        read_checkpoint(ckpt)
    assert refused(kind) in str(err.value) and not marker.exists()


@pytest.mark.slow
def test_resume_from_a_planted_checkpoint_runs_nothing(tmp_path):
    scene = scene_file(tmp_path)
    out = tmp_path / "out"
    assert ffrmbs_in_process("run", scene, "--out", out, "--no-check", "--no-export").returncode == 0
    marker = tmp_path / "marker"
    for kind, data in planted_checkpoints(marker).items():
        (out / "fall.h5.ckpt").write_bytes(data)
        res = ffrmbs_in_process("run", scene, "--out", out, "--no-check", "--no-export", "--resume")
        one_clear_line(res, "fall.h5.ckpt", refused(kind))
        assert not marker.exists(), kind


# --- 8: the default scene's options ------------------------------------------------------------

@pytest.mark.parametrize("option, fragment", [
    (["--modes", "0"], "modes (elastic modes of the beam) must be an integer >= 1, got 0"),
    (["--modes", "-3"], "modes (elastic modes of the beam) must be an integer >= 1, got -3"),
    (["--e", "1.5"], "e (coefficient of restitution) must be in [0, 1], got 1.5"),
    (["--e", "nan"], "e (coefficient of restitution) must be in [0, 1], got nan"),
    (["--t-end", "inf"], "t_end must be a finite time > 0 [s], got inf"),
    (["--dt", "0"], "dt must be a finite time > 0 [s], got 0.0"),
    (["--dt", "0.2", "--t-end", "0.1"], "dt must be smaller than t_end, got dt = 0.2 s, t_end = 0.1 s"),
])
def test_default_scene_options_are_checked_up_front(tmp_path, option, fragment):
    res = ffrmbs_in_process("run", "--out", tmp_path / "out", *option)
    one_clear_line(res, "default scene: ", fragment)
    assert not (tmp_path / "out").exists()


# --- 12: options, scene values and diverging runs ------------------------------------------------

@pytest.mark.parametrize("value", ["-5", "0", "nan", "inf"])
def test_checkpoint_every_must_be_positive_and_finite(tmp_path, value):
    res = ffrmbs_in_process("run", scene_file(tmp_path), "--out", tmp_path / "out", f"--checkpoint-every={value}")
    one_clear_line(res, "checkpoint_every (--checkpoint-every) must be a finite number of seconds > 0")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("key, settings, line", [
    ("velocity", dict(velocity="[0.0, 1e308, 0.0]"), 13),
    ("gravity", dict(gravity="[0.0, -1e300, 0.0]"), 7),
    ("t_end", dict(t_end="1e13"), 3),
])
def test_scene_numbers_beyond_the_physical_bound_are_refused(tmp_path, key, settings, line):
    scene = scene_file(tmp_path, **settings)
    assert f"{key} =" in scene.read_text().splitlines()[line - 1]          # the line the message must name
    res = ffrmbs_in_process("run", scene, "--out", tmp_path / "out")
    one_clear_line(res, f"scene.toml, line {line}: ", f"{key!r}: ", "is beyond the bound |x| <= 1e+12 (SI units)")
    assert not (tmp_path / "out").exists()


def test_a_mass_beyond_the_bound_is_refused(tmp_path):
    scene = scene_file(tmp_path)
    scene.write_text(scene.read_text().replace("mass = 1.0", "mass = 1e300"))
    res = ffrmbs_in_process("run", scene, "--out", tmp_path / "out")
    one_clear_line(res, "line 12: body 'ball': ", "'mass': 1e+300 [kg] is beyond the bound")


def run_python_scene(make, out):
    from ffrmbs_app.job import run_scene

    return run_scene(make, out, check=False, export=False, plot=False, log=lambda msg: None)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # overflow and NaN: the divergence under test
def test_a_diverging_spring_stops_the_run_and_the_file_says_failed(tmp_path):
    """A point mass on a spring of absurd stiffness (1e12 N/m on 1 kg: ω Δt = 1e3) integrated
    by RK4 grows by about (ω Δt)⁴/24 ≈ 4e10 a step: past 1e308 within ten steps."""
    from ffrmbs.errors import SimulationError
    from ffrmbs_app.scene import Scene
    from mbs import PointMass, SpringDamper, System, ground_frame

    def make():
        system = System()
        mass = system.add(PointMass(1.0, position=(1.1, 0.0, 0.0), name="mass"))
        system.add(SpringDamper(ground_frame((0.0, 0.0, 0.0)), mass.point, 1e12, 0.0, free_length=1.0))
        return Scene(system, 1.0, 1e-3, "rk4", n_out=101, outputs={"x": mass.point}, plan=False, name="spring")

    with pytest.raises(SimulationError, match=r"state became non-finite \(NaN/inf\)") as err:
        run_python_scene(make, tmp_path)
    assert 0 < err.value.t < 0.05
    with h5py.File(tmp_path / "spring.h5", "r") as f:
        assert f.attrs["status"].startswith("failed: simulation stopped at t = ")
        assert f["t"].shape[0] >= 1 and f["t"][0] == 0.0           # the samples before are kept
    sparse = make()           # no sample before the overflow: the step's own finiteness check stops it
    with pytest.raises(SimulationError, match=r"state became non-finite \(NaN/inf\) in q/u"):
        sparse.system.simulate(1.0, 1e-3, integrator="rk4", t_out=[0.0, 0.5, 1.0], plan=False)


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")   # the divergence under test
def test_a_finite_state_whose_energy_overflows_is_not_complete(tmp_path):
    """A 1 kg point mass at 1.8e154 m/s under 1e153 m/s² along its velocity: its kinetic
    energy v²/2 passes the largest double (1.798e308 J) when v > 1.8962e154 m/s, at
    t = 0.962 s, while q and u stay finite. Sampled every 0.1 s: the samples t = 0 .. 0.9 s
    are kept and the run stops at the sample t = 1.0 s."""
    from ffrmbs.errors import SimulationError
    from ffrmbs_app.scene import Scene
    from mbs import PointMass, System

    def make():
        system = System(gravity=(0.0, 1e153, 0.0))
        system.add(PointMass(1.0, velocity=(0.0, 1.8e154, 0.0), name="ball"))
        return Scene(system, 1.0, 1e-2, "rk4", n_out=11, plan=False, name="overflow")

    with pytest.raises(SimulationError, match=r"state became non-finite \(NaN/inf\) in energy") as err:
        run_python_scene(make, tmp_path)
    assert err.value.t == 1.0
    with h5py.File(tmp_path / "overflow.h5", "r") as f:
        assert f.attrs["status"].startswith("failed: ")
        assert f["t"].shape == (10,) and f["t"][-1] == pytest.approx(0.9)


# --- 10: one run per result file -----------------------------------------------------------------

def test_a_second_run_into_the_same_output_is_refused_with_the_pid(tmp_path):
    from ffrmbs_app.output_lock import output_lock

    scene, out = scene_file(tmp_path), tmp_path / "out"
    with output_lock(out / "fall.h5"):                       # this process is the first run
        res = ffrmbs("run", scene, "--out", out, "--no-check", "--no-export")
        one_clear_line(res, f"{out / 'fall.h5'} is in use by another run (pid {os.getpid()})")
    assert not (out / "fall.h5").exists()
    res = ffrmbs_in_process("run", scene, "--out", out, "--no-check", "--no-export")   # once it ended: runs
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in out.iterdir()) == ["fall.h5", "fall.png"]   # the lock file is gone


def test_a_reader_holding_the_result_file_does_not_stop_a_new_run(tmp_path, monkeypatch):
    """A reader holds the old result file open (HDF5's file lock on): a new run into the
    same --out is not blocked (the new file is built under a temporary name and renamed
    into place), and the reader keeps reading the complete old file."""
    scene, out = scene_file(tmp_path), tmp_path / "out"
    monkeypatch.setitem(ENV, "HDF5_USE_FILE_LOCKING", "TRUE")        # HDF5's default, whatever the caller set,
    monkeypatch.setenv("HDF5_USE_FILE_LOCKING", "TRUE")              # for the reader and for the runs here
    assert ffrmbs_in_process("run", scene, "--out", out, "--no-check", "--no-export").returncode == 0
    reader = subprocess.Popen([sys.executable, "-c", "import h5py, sys; f = h5py.File(sys.argv[1], 'r'); "
                               "print('open', flush=True); sys.stdin.read(); print(f.attrs['status'], len(f['t']))",
                               str(out / "fall.h5")],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=ENV)
    try:
        assert reader.stdout.readline().strip() == "open"
        res = ffrmbs_in_process("run", scene, "--out", out, "--no-check", "--no-export")
    finally:
        seen, _ = reader.communicate("", timeout=60)
    assert res.returncode == 0, res.stderr
    status, samples = seen.split()
    assert status == "complete" and int(samples) > 0


# --- 13: resources bounded before anything is allocated --------------------------------------------

def test_too_many_steps_are_refused_with_the_numbers(tmp_path):
    res = ffrmbs_in_process("run", scene_file(tmp_path, t_end=1e9, dt=1e-3), "--out", tmp_path / "out")
    one_clear_line(res, "1e+12 time steps (t_end / dt = 1e+09 s / 0.001 s) exceed the limit of 1e+08",
                   "--no-limits")
    assert not (tmp_path / "out").exists()


def test_too_much_memory_is_refused_with_the_numbers(tmp_path):
    """The falling point mass holds per sample t, q (3), u (3), y and two energies: 10
    numbers, 80 bytes; with as many samples as the machine has bytes / 80 it would need all
    of the physical memory, four times the limit."""
    from ffrmbs_app.limits import physical_memory

    n_out = int(physical_memory()) // 80
    res = ffrmbs_in_process("run", scene_file(tmp_path, n_out=n_out), "--out", tmp_path / "out", "--no-check")
    line = one_clear_line(res, f"({n_out} samples x 80 bytes)", "over 25% of the machine's", "--no-limits")
    assert f"about {n_out * 80 / 1e9:.3g} GB" in line
    assert not (tmp_path / "out").exists()


def test_no_limits_lifts_both_limits(tmp_path):
    from ffrmbs_app.limits import check_resources
    from ffrmbs_app.scene_loader import load_scene

    scene = load_scene(scene_file(tmp_path, t_end=1e9, n_out=10 ** 15))
    estimate = check_resources(scene, check=False, no_limits=True)
    assert estimate["steps"] == pytest.approx(1e12) and estimate["bytes"] == 10 ** 15 * 80


# --- 16: scene names are plain file stems ----------------------------------------------------------

@pytest.mark.parametrize("name", ["../../ESCAPED", "/tmp/ESCAPED", "a/b", ".hidden", "", "x" * 101, "tab\there"])
def test_a_scene_name_that_is_no_plain_file_stem_is_refused(tmp_path, name):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    scene = scene_file(work, name=name.replace("\t", "\\t"))
    res = ffrmbs_in_process("run", scene, "--out", work / "out")
    one_clear_line(res, "scene.toml, line 2: [scene]: the scene name ", "is not a plain file stem")
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a", "b", "scene.toml"]


def test_a_scene_name_from_the_file_stem_is_checked_too(tmp_path):
    scene = scene_file(tmp_path, file=".hidden.toml")
    scene.write_text(scene.read_text().replace('name = "fall"\n', ""))
    res = ffrmbs_in_process("run", scene, "--out", tmp_path / "out")
    one_clear_line(res, ".hidden.toml, line 1: [scene]: the scene name '.hidden' is not a plain file stem",
                   "(taken from the file name; set 'name')")


def test_a_model_script_scene_name_and_times_are_checked(tmp_path):
    from ffrmbs.errors import ModelError
    from ffrmbs_app.scene import Scene
    from mbs import System

    with pytest.raises(ModelError, match="the scene name '../up' is not a plain file stem"):
        Scene(System(), 1.0, 0.1, name="../up")
    for t_end, dt in ((float("inf"), 0.1), (1.0, float("nan"))):
        with pytest.raises(ModelError, match="need finite t_end > 0 and dt > 0"):
            Scene(System(), t_end, dt)


def test_every_output_of_a_run_stays_inside_out(tmp_path):
    scene, out = scene_file(tmp_path, name="run-1.v2_b"), tmp_path / "out"
    res = ffrmbs_in_process("run", scene, "--out", out, "--no-check")
    assert res.returncode == 0, res.stderr
    outside = [p for p in tmp_path.rglob("*") if p != scene and out not in p.parents and p != out]
    assert outside == [] and (out / "run-1.v2_b.h5").is_file() and (out / "run-1.v2_b.png").is_file()


# --- 17: short quotations of the files a scene points at ------------------------------------------

def test_a_force_file_that_is_no_force_file_is_quoted_short(tmp_path):
    from ffrmbs.errors import InputFileError
    from mbs import read_force_file

    path = tmp_path / "passwd"
    path.write_text("root:x:0:0:root:/root:/bin/bash\x1b[2J" + "A" * 5000 + "\n")
    with pytest.raises(InputFileError) as err:
        read_force_file(path, 1)
    assert str(err.value) == f"{path}, line 1: entry 1 ('root:x:0:0:root:/roo…') is not a number"


def test_quote():
    from ffrmbs.errors import quote

    assert quote("abc") == "'abc'"
    assert quote("a\nb\x00c" + "d" * 30, 5) == "'a?b?c…'"
    assert quote("x" * 20) == "'" + "x" * 20 + "'" and quote("x" * 21) == "'" + "x" * 20 + "…'"


def test_the_scene_reader_quotes_a_force_file_short(tmp_path):
    """A nodal load whose force file is a password file: the message names the file, the
    line and the scene entry, and quotes 20 characters of it."""
    from ffrmbs.errors import InputFileError
    from ffrmbs_app.scene_file import read_scene

    (tmp_path / "passwd").write_text("root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin\n")
    scene = tmp_path / "scene.toml"
    scene.write_text('[scene]\nt_end = 0.01\ndt = 1e-3\n\n[[body]]\nname = "beam"\nkind = "flexible"\n'
                     'source = "builtin:point_mass_beam"\nmodes = 2\nframe = "fixed"\n\n'
                     '[[load]]\nkind = "nodal"\nbody = "beam"\nfile = "passwd"\n')
    with pytest.raises(InputFileError) as err:
        read_scene(scene)
    assert str(err.value) == (f"{tmp_path / 'passwd'}, line 1: entry 1 ('root:x:0:0:root:/roo…') is not a number "
                              f"(load #1 (nodal) of scene file {scene})")


def test_the_scene_reader_quotes_its_own_strings_short(tmp_path):
    from ffrmbs.errors import InputFileError
    from ffrmbs_app.scene_file import read_scene

    scene = scene_file(tmp_path)
    scene.write_text(scene.read_text().replace('"rk4"', '"\\u001b[2J' + "r" * 500 + '"'))
    with pytest.raises(InputFileError) as err:
        read_scene(scene)
    assert str(err.value).endswith("got a string ('?[2J" + "r" * 36 + "…')") and len(str(err.value)) < 300
