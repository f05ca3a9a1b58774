"""``--set KEY=VALUE`` overrides of scene files (ffrmbs_app.scene_file.overrides): an
overridden scene equals the same file edited by hand; each fault is one line naming the
--set; the result file records the overrides and a resume with other ones is refused."""

import subprocess
import sys

import h5py
import numpy as np
import pytest

from ffrmbs.errors import InputFileError
from ffrmbs_app.scene_loader import load_scene
from ffrmbs_app.scene_file.overrides import parse_value, split_override
from qa.fixtures import fixture_text

BALL = fixture_text("scenes/two_point_masses.toml")


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "ball.toml"
    path.write_text(BALL)
    return path


def edited(tmp_path, old, new):
    """The scene file with ``old`` replaced by ``new`` (once)."""
    assert BALL.count(old) == 1
    path = tmp_path / "edited.toml"
    path.write_text(BALL.replace(old, new))
    return path


def describe(scene):
    """What the overrides below change, read from the built scene."""
    bodies = scene.system.bodies
    contact = scene.system.contacts[0]
    return (scene.t_end, scene.dt, scene.options, bodies[0].mass, bodies[1].mass, list(bodies[1].q_init),
            contact.law.e)


@pytest.mark.parametrize("override, old, new", [
    ("scene.dt=5e-4", "dt = 1e-3", "dt = 5e-4"),
    ("scene.options.theta=0.75", "theta = 0.5", "theta = 0.75"),
    ('body."ball one".mass=2', "mass = 0.5", "mass = 2"),
    ("body.1.position=[0.5, 0.2, 0.0]", "position = [1.0, 0.1, 0.0]", "position = [0.5, 0.2, 0.0]"),
    ("contact.floor.e=1", "e = 0.5", "e = 1"),
])
def test_an_override_equals_the_file_edited_by_hand(scene_file, tmp_path, override, old, new):
    assert describe(load_scene(scene_file, [override])) == describe(load_scene(edited(tmp_path, old, new)))
    assert load_scene(scene_file, [override]).overrides == (override,)


def test_the_last_override_of_a_key_wins_and_values_parse_as_toml(scene_file):
    scene = load_scene(scene_file, ["scene.dt=1e-4", "scene.dt = 2e-4"])
    assert scene.dt == 2e-4
    assert parse_value("band") == "band" and parse_value('"band"') == "band"
    assert parse_value("[1, 2]") == [1, 2] and parse_value("true") is True and parse_value("5e-6") == 5e-6
    assert split_override('body."a=b".mass=1') == ('body."a=b".mass', "1")


@pytest.mark.parametrize("override, fault", [
    ("scene.dt", "expected KEY=VALUE"),
    ("scene..dt=1", "not a dotted key"),
    ("body.ball.mass=1", "no [[body]] entry 'ball' (entries: 'ball one', 'bob'; or 0..1)"),
    ("body.bob=1", "name one of its keys after it"),
    ("scene.dt.x=1", "scene.dt is a value, not a table"),
    ("spring.s.stiffness=1", "the scene file has no [[spring]] entries"),
    ("scene.dt=[1,", "is not a TOML value"),
])
def test_malformed_overrides_are_one_line_naming_the_set(scene_file, override, fault):
    with pytest.raises(InputFileError) as info:
        load_scene(scene_file, [override])
    assert info.value.line is None
    assert f"--set {override}: " in str(info.value) and fault in str(info.value)


@pytest.mark.parametrize("override, fault", [
    ("scene.dt=abc", "'dt' must be a number [s], got a string"),
    ("scene.dtt=1e-3", "unknown key 'dtt'"),
    ("body.bob.mass=-1", "'mass'"),
    ("contact.floor.e=2", "e must be"),
])
def test_overridden_values_are_checked_like_the_file(scene_file, override, fault):
    with pytest.raises(InputFileError) as info:
        load_scene(scene_file, [override])
    assert fault in str(info.value) and f"(the value of --set {override})" in str(info.value)
    assert info.value.line is None


def test_a_model_script_takes_no_overrides(tmp_path):
    script = tmp_path / "model.py"
    script.write_text("def scene():\n    raise AssertionError('not called')\n")
    with pytest.raises(InputFileError, match="--set sets values of a scene file"):
        load_scene(script, ["scene.dt=1e-3"])


def ffrmbs(*args, cwd):
    return subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


@pytest.mark.slow
def test_run_records_the_overrides_and_a_resume_with_others_is_refused(scene_file, tmp_path):
    out = tmp_path / "out"
    res = ffrmbs("run", str(scene_file), "--set", "scene.dt=5e-4", "--set", "contact.floor.e=0", "--no-check",
                 "--no-export", "--out", str(out), cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    with h5py.File(out / "ball.h5", "r") as f:
        assert f.attrs["overrides"] == '["scene.dt=5e-4", "contact.floor.e=0"]'
        t, y = f["t"][()], f["outputs/y"][()]
    assert np.diff(t) == pytest.approx(0.01) and y.min() > -1e-9      # e = 0: it stays on the floor
    (out / "ball.h5.ckpt").write_bytes(b"")                           # a checkpoint to resume from
    res = ffrmbs("run", str(scene_file), "--set", "scene.dt=1e-3", "--resume", "--no-check", "--no-export",
                 "--out", str(out), cwd=tmp_path)
    assert res.returncode != 0 and "Traceback" not in res.stderr
    assert "cannot resume: the run started with --set ['scene.dt=5e-4', 'contact.floor.e=0']" in res.stderr
    res = ffrmbs("run", "--set", "scene.dt=1e-3", "--out", str(tmp_path / "default"), cwd=tmp_path)
    assert res.returncode != 0 and "--set sets values of a scene file" in res.stderr
