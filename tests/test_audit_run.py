"""Issue 18, the run and the scene: bad options and scene values refused up front with one
clear line, a diverging run stopped (never "complete"), resources bounded before
anything is allocated, one run per output at a time, signed checkpoints, scene names
kept inside --out, short quotations of file contents."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from mbs.checkpoint import MAGIC, key_path, read_checkpoint, write_checkpoint

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}

FALLING_MASS = """\
[scene]
name = "{name}"
t_end = {t_end}
dt = {dt}
integrator = "rk4"
n_out = {n_out}
gravity = {gravity}

[[body]]
name = "ball"
kind = "point_mass"
mass = 1.0
velocity = {velocity}

[outputs]
y = {{ body = "ball", quantity = "position", component = "y" }}
"""


def scene_file(tmp_path, name="fall", t_end=0.01, dt=1e-3, n_out=11, gravity="[0.0, -9.81, 0.0]",
               velocity="[0.0, 0.0, 0.0]", file="scene.toml") -> Path:
    path = tmp_path / file
    path.write_text(FALLING_MASS.format(name=name, t_end=t_end, dt=dt, n_out=n_out, gravity=gravity,
                                        velocity=velocity))
    return path


def ffrmbs(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ffrmbs.cli", *map(str, args)], capture_output=True, text=True,
                          env=ENV, cwd=cwd, timeout=600)


def one_clear_line(res, *fragments):
    """Exit 2, one line 'ffrmbs: error: …' holding every fragment, no traceback."""
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2, res.stderr
    assert "Traceback" not in res.stderr and len(lines) == 1 and lines[0].startswith("ffrmbs: error: "), res.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


# --- 15: checkpoints are signed ----------------------------------------------------------------

class _Plant:
    """A pickle that, once loaded, creates the file ``marker`` (the stand-in of os.system)."""

    def __init__(self, marker):
        self.marker = Path(marker)

    def __reduce__(self):
        return Path.touch, (self.marker,)


REFUSED = "not written by this installation: signature does not match; a checkpoint is refused rather than run"


def planted_checkpoints(marker):
    """Hand-made checkpoints holding the planted pickle: the old unsigned format, the
    current header with no signature, and one with a forged signature."""
    payload = pickle.dumps({"integrator": _Plant(marker)})
    return {"old format": b"ffrmbs-checkpoint-1\n" + payload,
            "no signature": MAGIC + payload,
            "forged signature": MAGIC + b"0" * 64 + b"\n" + payload}


def test_the_checkpoint_key_lives_in_the_test_config_not_in_home(checkpoint_key_dir, tmp_path):
    write_checkpoint(tmp_path / "x.ckpt", {"a": 1})
    assert key_path() == checkpoint_key_dir / "checkpoint.key"
    assert key_path().stat().st_size == 32 and key_path().stat().st_mode & 0o777 == 0o600
    assert read_checkpoint(tmp_path / "x.ckpt") == {"a": 1}


@pytest.mark.parametrize("kind", ["old format", "no signature", "forged signature"])
def test_a_planted_checkpoint_is_refused_before_unpickling(tmp_path, kind):
    marker = tmp_path / "marker"
    ckpt = tmp_path / "run.h5.ckpt"
    ckpt.write_bytes(planted_checkpoints(marker)[kind])
    with pytest.raises(Exception) as err:
        read_checkpoint(ckpt)
    assert REFUSED in str(err.value) and not marker.exists()


def test_a_checkpoint_signed_with_another_key_is_refused(tmp_path, monkeypatch):
    write_checkpoint(tmp_path / "x.ckpt", {"a": 1})
    monkeypatch.setenv("FFRMBS_CONFIG", str(tmp_path / "other-user"))
    with pytest.raises(Exception, match="signature does not match"):
        read_checkpoint(tmp_path / "x.ckpt")


def test_resume_from_a_planted_checkpoint_runs_nothing(tmp_path):
    scene = scene_file(tmp_path)
    out = tmp_path / "out"
    assert ffrmbs("run", scene, "--out", out, "--no-check", "--no-export").returncode == 0
    marker = tmp_path / "marker"
    for kind, data in planted_checkpoints(marker).items():
        (out / "fall.h5.ckpt").write_bytes(data)
        res = ffrmbs("run", scene, "--out", out, "--no-check", "--no-export", "--resume")
        one_clear_line(res, "fall.h5.ckpt", REFUSED)
        assert not marker.exists(), kind
