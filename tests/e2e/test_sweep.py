"""Parameter sweeps (ffrmbs_app.sweeps, ffrmbs_app.sweep, ``ffrmbs sweep``) on one local Dask
cluster shared by the module: a ball bouncing on a rigid floor (runs of a few hundred
steps), a 2 x 2 grid with an invalid value, resume, zip mode, bitwise equality with the
same run made alone, the tables, the value splitting and the command line."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import h5py
import pytest

import ffrmbs_app
from ffrmbs.errors import FfrmbsError
from ffrmbs_app.sweeps import override_sets, parse_set, run_key, split_values
from qa.fixtures import fixture_text

import paths

pytest.importorskip("distributed")

ROOT = paths.REPO

BOUNCE = fixture_text("scenes/ball_on_floor.toml")     # a ball dropped from 50 mm, e = 0.5

GRID = {"scene.dt": ["1e-3", "5e-4"], "contact.floor.e": ["0.5", "2"]}     # e = 2: not in [0, 1]


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "bounce.toml"
    path.write_text(BOUNCE)
    return path


@pytest.fixture(scope="module")
def grid_sweep(dask_client, scene, tmp_path_factory):
    """The 2 x 2 sweep through the package's entry point, with its progress lines."""
    out = tmp_path_factory.mktemp("sweep")
    lines = []
    table = ffrmbs_app.sweep(scene, GRID, out, client=dask_client, progress=lines.append)
    return out, table, lines


def datasets(path) -> dict:
    """/t, /outputs/* and /bodies/*/q of a result file."""
    with h5py.File(path, "r") as f:
        out = {"t": f["t"][()]}
        out.update({f"outputs/{k}": f["outputs"][k][()] for k in f["outputs"]})
        out.update({f"bodies/{k}/q": f["bodies"][k]["q"][()] for k in f["bodies"]})
        return out


def alone(scene, overrides, out) -> dict:
    """The datasets of the same run made alone in this process, as ``ffrmbs run`` does."""
    from ffrmbs_app.job import run_scene
    from ffrmbs_app.scene_loader import load_scene

    summary = run_scene(lambda: load_scene(scene, overrides=overrides), out, check=False, export=False, plot=False,
                        checkpoint_every=None, log=lambda line: None)
    return datasets(summary["result_file"])


def test_split_values_keeps_lists_and_quoted_commas():
    assert split_values("1e-5,5e-6") == ["1e-5", "5e-6"]
    assert split_values("[1, 2],[3,4] , 5") == ["[1, 2]", "[3,4]", "5"]
    assert split_values('"a,b",c,{x = [1,2]}') == ['"a,b"', "c", "{x = [1,2]}"]
    assert parse_set(["body.beam.modes=10,20", "scene.dt=1e-5"]) == {"body.beam.modes": ["10", "20"],
                                                                     "scene.dt": ["1e-5"]}
    for bad in ("1,,2", "[1,2", "1,2]", '"a,b', "1,"):
        with pytest.raises(FfrmbsError):
            split_values(bad)
    for bad in (["scene.dt"], ["=1"], ["scene.dt=1", "scene.dt=2"]):
        with pytest.raises(FfrmbsError):
            parse_set(bad)


def test_override_sets_product_zip_and_run_names():
    grid = {"scene.dt": [1e-5, "5e-6"], "body.beam.modes": [10, 20]}
    assert override_sets(grid) == [("scene.dt=1e-05", "body.beam.modes=10"), ("scene.dt=1e-05", "body.beam.modes=20"),
                                   ("scene.dt=5e-6", "body.beam.modes=10"), ("scene.dt=5e-6", "body.beam.modes=20")]
    assert override_sets(grid, zip=True) == [("scene.dt=1e-05", "body.beam.modes=10"),
                                             ("scene.dt=5e-6", "body.beam.modes=20")]
    with pytest.raises(FfrmbsError, match="equal lengths"):
        override_sets({"scene.dt": [1, 2], "body.beam.modes": [1]}, zip=True)
    for bad in ({}, {"scene.dt": []}, {"scene.dt": [1, 1]}):
        with pytest.raises(FfrmbsError):
            override_sets(bad)
    assert run_key(("scene.dt=5e-06", "body.beam.modes=50")) == "dt=5e-06,modes=50"
    assert run_key(("body.a.modes=5", "body.b.modes=6")) == "a.modes=5,b.modes=6"
    assert run_key(("body.ball.position=[0, 0, 0.05]",)) == "position=0_0_0.05"    # more in test_sweep_plots.py


def test_grid_sweep_rows_files_and_tables(grid_sweep):
    out, table, lines = grid_sweep
    assert [(r["scene.dt"], r["contact.floor.e"]) for r in table] == [("1e-3", "0.5"), ("1e-3", "2"), ("5e-4", "0.5"),
                                                                     ("5e-4", "2")]
    assert [r["status"] for r in table] == ["complete", "failed"] * 2
    for r in table[1::2]:
        assert "e must be" in r["error"] and "\n" not in r["error"] and r["result_file"] is None
    for r in table[::2]:
        assert r["error"] is None and r["reused"] is False
        with h5py.File(out / r["result_file"], "r") as f:
            assert f.attrs["status"] == "complete"
            assert r["final:z"] == pytest.approx(f["outputs"]["z"][-1])
        assert r["steps"] == round(0.2 / float(r["scene.dt"]))
        assert r["wall_s"] >= 0 and r["cpu_s"] >= 0
    assert sorted(p.name for p in (out / "runs").glob("*.h5")) == ["dt=1e-3,e=0.5.h5", "dt=5e-4,e=0.5.h5"]
    assert lines[-1].startswith("sweep: 4/4 done, 0 running, 2 failed")
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["run"] for r in rows] == [r["run"] for r in table] and rows[1]["status"] == "failed"
    assert json.loads((out / "sweep.json").read_text())["rows"] == table
    md = (out / "sweep.md").read_text()
    assert all(f"| {r['run']} |" in md for r in table)
    assert not (out / "sweep.png").exists()        # no error estimates without check


def test_sweep_run_is_bitwise_the_run_alone(grid_sweep, scene, tmp_path):
    out, table, _ = grid_sweep
    swept = datasets(out / table[2]["result_file"])
    single = alone(scene, ("scene.dt=5e-4", "contact.floor.e=0.5"), tmp_path)
    assert swept.keys() == single.keys()
    for name in swept:
        assert swept[name].tobytes() == single[name].tobytes(), name


def test_resume_runs_only_what_is_missing(grid_sweep, dask_client, scene):
    out, table, _ = grid_sweep
    kept = out / table[0]["result_file"]
    stamp = kept.stat().st_mtime_ns
    (out / table[2]["result_file"]).unlink()
    again = ffrmbs_app.sweep(scene, GRID, out, client=dask_client, progress=lambda line: None)
    assert [r["reused"] for r in again] == [True, False, False, False]     # the failed ones run again too
    assert [r["status"] for r in again] == ["complete", "failed", "complete", "failed"]
    assert kept.stat().st_mtime_ns == stamp
    assert again[2]["final:z"] == table[2]["final:z"]


def test_zip_sweep_with_check_and_python_values(dask_client, scene, tmp_path):
    table = ffrmbs_app.sweep(scene, {"scene.dt": [1e-3, 5e-4], "scene.t_end": [0.2, 0.15]}, tmp_path, client=dask_client,
                             zip=True, check=True, progress=lambda line: None)
    assert [r["run"] for r in table] == ["dt=0.001,t_end=0.2", "dt=0.0005,t_end=0.15"]
    assert [r["steps"] for r in table] == [200, 300]
    for r in table:
        with h5py.File(tmp_path / r["result_file"], "r") as f:
            estimate = json.loads(f.attrs["summary"])["error_estimate"]
        assert r["error_estimate"] == max(e["relative_to_range"] for e in estimate.values())
        assert r["error:z"] == estimate["z"]["max_abs"]
    assert (tmp_path / "sweep.png").exists() == all(r["cpu_s"] > 0 for r in table)


def test_bad_sweeps_are_refused_before_running(scene, tmp_path):
    with pytest.raises(FfrmbsError, match="equal lengths"):
        ffrmbs_app.sweep(scene, {"scene.dt": [1e-3, 5e-4], "scene.t_end": [0.2]}, tmp_path, zip=True)
    with pytest.raises(FfrmbsError, match="not found"):
        ffrmbs_app.sweep(tmp_path / "missing.toml", GRID, tmp_path)
    with pytest.raises(FfrmbsError, match="not both"):
        ffrmbs_app.sweep(scene, GRID, tmp_path, client=object(), workers=2)
    with pytest.raises(FfrmbsError, match="workers"):
        ffrmbs_app.sweep(scene, GRID, tmp_path, workers=0)
    try:
        import pandas  # noqa: F401
    except ImportError:
        with pytest.raises(FfrmbsError, match="pandas"):
            ffrmbs_app.sweep(scene, GRID, tmp_path, as_frame=True)
    assert not (tmp_path / "runs").exists()


def test_cli_end_to_end(dask_client, scene, tmp_path):
    """``ffrmbs sweep`` on the module's cluster (--scheduler), a list-valued key whose
    values hold commas; a bad --set is one line and status 2."""
    out = tmp_path / "cli"
    cmd = [sys.executable, "-m", "ffrmbs_app.cli", "sweep", str(scene),
           "--set", "body.ball.position=[0.0, 0.0, 0.05],[0.0,0.0,0.02]", "--set", "scene.dt=1e-3",
           "--out", str(out), "--scheduler", dask_client.scheduler.address]
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = json.loads((out / "sweep.json").read_text())["rows"]
    assert [r["body.ball.position"] for r in rows] == ["[0.0, 0.0, 0.05]", "[0.0,0.0,0.02]"]
    assert [r["status"] for r in rows] == ["complete", "complete"]
    assert rows[0]["final:z"] != rows[1]["final:z"]
    assert "wrote" in done.stdout and "Traceback" not in done.stderr
    bad = subprocess.run(cmd[:6] + ["scene.dt", "--out", str(out)], capture_output=True, text=True, cwd=ROOT,
                         timeout=60)
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0 and "expected KEY=V1,V2" in bad.stderr
