"""The job's side process (:mod:`ffrmbs_app.side_process`): a task run beside the caller,
a failing one quiet, a stopped one ended; and the job (:mod:`ffrmbs_app.job`) writing its
plot and ParaView export there while it runs the accuracy checks — the same files as in
its own process, and written again by it when the side process fails."""

from __future__ import annotations

import os
import threading
import time

import h5py
import pytest

from ffrmbs_app import job, side_process
from ffrmbs_app.job import run_scene
from ffrmbs_app.scene_loader import load_scene

import paths

needs_two = pytest.mark.skipif(not side_process.available(), reason="no second CPU or no fork on this machine")
FALL = paths.FIXTURES / "summary_scenes" / "fall.toml"


@needs_two
def test_a_task_runs_in_another_process(tmp_path):
    mark = tmp_path / "pid"
    side = side_process.start(lambda: mark.write_text(str(os.getpid())))
    assert side.join()
    assert int(mark.read_text()) not in (0, os.getpid())


@needs_two
def test_a_failing_task_says_so_without_a_traceback(capfd):
    def fail():
        raise RuntimeError("the side task failed")

    side = side_process.start(fail)
    assert not side.join()
    out, err = capfd.readouterr()
    assert "Traceback" not in err and "the side task failed" not in err + out


@needs_two
def test_a_stopped_task_ends_at_once():
    side = side_process.start(lambda: time.sleep(60))
    t0 = time.perf_counter()
    side.stop()
    assert time.perf_counter() - t0 < 5.0
    assert not side.process.is_alive() and not side.join()


def test_no_side_process_outside_the_main_thread():
    seen = []
    worker = threading.Thread(target=lambda: seen.append(side_process.available()))
    worker.start()
    worker.join()
    assert seen == [False]


def _job(out):
    lines = []
    summary = run_scene(lambda: load_scene(FALL), out, check=True, log=lines.append)
    return summary, lines


def _files(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
            and p.suffix in (".vtu", ".pvd")}


@needs_two
def test_the_job_writes_plot_and_export_beside_its_checks_as_in_its_own_process(tmp_path, monkeypatch):
    started = []
    real_start = side_process.start
    monkeypatch.setattr(side_process, "start", lambda task: started.append(real_start(task)) or started[-1])
    beside, lines_beside = _job(tmp_path / "beside")
    assert len(started) == 1 and started[0] is not None and started[0].process.exitcode == 0
    monkeypatch.setattr(side_process, "start", lambda task: None)
    alone, lines_alone = _job(tmp_path / "alone")
    timed = ("cost", "warm-up", "kernels")
    assert [x for x in lines_beside if not x.startswith(timed)] == [x for x in lines_alone if not x.startswith(timed)]
    for key in ("plot", "paraview"):
        assert os.path.isfile(beside[key]) and os.path.isfile(alone[key])
    assert _files(tmp_path / "beside") == _files(tmp_path / "alone")
    with h5py.File(beside["result_file"]) as f:
        assert b"error_estimate" in bytes(f.attrs["summary"])     # written once the side process was done


@needs_two
def test_a_failed_side_process_leaves_the_job_to_write_plot_and_export(tmp_path, monkeypatch):
    parent = os.getpid()
    real = job._derived_files

    def derived_files(*args):
        if os.getpid() != parent:
            raise OSError("the side process cannot write")
        return real(*args)

    monkeypatch.setattr(job, "_derived_files", derived_files)
    summary, _ = _job(tmp_path)
    assert os.path.isfile(summary["plot"]) and os.path.isfile(summary["paraview"])
