"""Results that last (issue 8): a run killed with SIGKILL, or stopped by SIGTERM, and then
resumed with ``ffrmbs run --resume`` writes a result file equal bit for bit to the
uninterrupted run's; the interrupted file is readable and says so. The oracle is the
uninterrupted run of the same scene in its own process."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from mbs.results.result_file import load_result

pytestmark = pytest.mark.slow   # seconds each: left out of the fast subset (-m "not slow")

RUN = [sys.executable, "-m", "ffrmbs_app.cli", "run", "--no-check", "--no-export", "--t-end", "0.1"]
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


def ffrmbs_run(out, *extra):
    return subprocess.run(RUN + ["--out", str(out), *extra], capture_output=True, text=True, env=ENV, timeout=600)


def datasets(path) -> dict:
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return found


def assert_bitwise_equal(a, b):
    da, db = datasets(a), datasets(b)
    assert sorted(da) == sorted(db)
    for name in da:
        assert da[name].dtype == db[name].dtype and da[name].shape == db[name].shape, name
        assert da[name].tobytes() == db[name].tobytes(), f"{name} differs"


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("uninterrupted")
    res = ffrmbs_run(out)
    assert res.returncode == 0, res.stderr
    return out / "point_mass_beam.h5"


def start_and_wait_for_a_checkpoint(out):
    """Start the run; return the process once a checkpoint was (re)written and no flush
    or checkpoint is due for a while (they come every 0.1 s of wall time; the 10 000 steps
    take about 2 CPU s here)."""
    proc = subprocess.Popen(RUN + ["--out", str(out), "--checkpoint-every", "0.1"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=ENV)
    ckpt = out / "point_mass_beam.h5.ckpt"
    deadline, seen = time.time() + 300, None
    while time.time() < deadline:
        if proc.poll() is not None:
            pytest.fail(f"the run ended before it was killed: {proc.communicate()}")
        if ckpt.exists():
            mtime = ckpt.stat().st_mtime_ns
            if seen is not None and mtime != seen:
                time.sleep(0.05)              # mid-computation, between two checkpoints
                return proc
            seen = mtime
        time.sleep(0.01)
    proc.kill()
    pytest.fail("no checkpoint within 300 s")


def test_kill_9_and_resume_is_bit_identical(reference, tmp_path):
    proc = start_and_wait_for_a_checkpoint(tmp_path)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate()
    path = tmp_path / "point_mass_beam.h5"
    partial, attrs = load_result(path)                # the killed run's file is readable
    assert attrs["status"] == "running" and 0 < len(partial.t) < 1001
    res = ffrmbs_run(tmp_path, "--resume")
    assert res.returncode == 0, res.stderr
    assert "resuming" in res.stdout
    _, attrs = load_result(path)
    assert attrs["status"] == "complete" and len(attrs["resumed_at"]) == 1
    assert not (tmp_path / "point_mass_beam.h5.ckpt").exists()
    assert_bitwise_equal(reference, path)
    summary, before = attrs["summary"], round(attrs["resumed_at"][0] / 1e-5)   # fixed Δt = 1e-5 s
    assert summary["timed_steps"] == summary["steps"] - before > 0      # the cost per step: this process's steps


def test_sigterm_closes_the_file_cleanly_and_resume_is_bit_identical(reference, tmp_path):
    proc = start_and_wait_for_a_checkpoint(tmp_path)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "interrupted" in err and "--resume" in err
    path = tmp_path / "point_mass_beam.h5"
    partial, attrs = load_result(path)
    assert attrs["status"] == "interrupted" and 0 < len(partial.t) < 1001
    ref, _ = load_result(reference)
    n = len(partial.t)                                # the samples so far are the reference's
    assert np.array_equal(partial.q, ref.q[:n]) and np.array_equal(partial.t, ref.t[:n])
    res = ffrmbs_run(tmp_path, "--resume")
    assert res.returncode == 0, res.stderr
    assert_bitwise_equal(reference, path)


def test_resume_without_a_checkpoint_is_a_clear_error(tmp_path):
    res = ffrmbs_run(tmp_path, "--resume")
    assert res.returncode == 2 and "no checkpoint to resume from" in res.stderr and "Traceback" not in res.stderr
