"""The side-by-side step benchmark's plumbing: the baseline export and one worker run,
from this checkout and from an installed (not editable) copy."""

import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from validation.bench import step_cost

SOURCE_LITTER = (".git", "build", "dist", "*.egg-info", "__pycache__", "out", ".pytest_cache", ".hypothesis")


def test_a_missing_baseline_commit_is_named(tmp_path):
    """An unknown commit (or no git at all) is a reason in the table, never an exception."""
    why = step_cost.export_baseline("0" * 40, tmp_path)
    assert why is not None and (why.startswith(f"commit {'0' * 40} not found") or why.startswith("git not available"))
    assert not any(tmp_path.iterdir())


def default_vy(t_end):
    """v_y(T) of the default scene run in this process (Moreau, Δt = 1e-5 s, 101 samples)."""
    from ffrmbs_app.scenes import point_mass_beam as pmb

    scene = pmb.build("A", modes=20)
    res = scene.system.simulate(t_end, 1e-5, integrator="moreau", t_out=np.linspace(0, t_end, 101),
                                outputs=scene.outputs())
    return float(res["vy"][-1])


@pytest.mark.slow
def test_the_worker_times_the_default_scene_and_reports_its_answer():
    """The worker, run in its own process on this checkout, times the default scene for
    200 steps and reports v_y(T) equal to the same scene run here, and imports the
    product from this checkout."""
    spec = {"cases": [{"name": "default", "kind": "default", "t_end": 0.002, "dt": 1e-5}], "repeats": 2}
    measured = step_cost.run_worker(step_cost.ROOT, spec)
    out = measured["cases"]["default"]
    assert out["steps"] == 200 and len(out["walls"]) == 2 and min(out["walls"]) > 0
    assert set(measured["origins"].values()) == {str(step_cost.ROOT)}
    assert out["check"] == default_vy(0.002)


def install_copy(into, tmp_path):
    """``pip install --no-deps --target into`` of a copy of this source tree (pip builds in
    the tree it is given); skips the test when pip cannot build here."""
    source = tmp_path / "source"
    shutil.copytree(step_cost.ROOT, source, ignore=shutil.ignore_patterns(*SOURCE_LITTER))
    pip = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(into),
                          str(source)], capture_output=True, text=True, check=False)
    if pip.returncode:
        pytest.skip(f"pip cannot build the package here: {step_cost.last_line(pip.stderr)}")


BENCH_FROM_INSTALLED_COPY = """
import json, sys
from validation.bench import step_cost
export_into, baseline, t_end = sys.argv[1], sys.argv[2], float(sys.argv[3])
spec = {"cases": [{"name": "default", "kind": "default", "t_end": t_end, "dt": 1e-5}], "repeats": 1}
print(json.dumps({"root": str(step_cost.ROOT),
                  "why": step_cost.export_baseline(step_cost.BASELINE, export_into),
                  "this": step_cost.run_worker(step_cost.ROOT, {"cases": [], "repeats": 0}),
                  "baseline": step_cost.run_worker(baseline, spec)}))
"""


@pytest.mark.slow
def test_the_bench_runs_from_an_installed_copy_and_its_baseline_from_the_old_tree_only(tmp_path):
    """After ``pip install .`` (not editable; here ``--target``, first on PYTHONPATH as
    site-packages would be), ``step_cost`` imported from the installed copy: its root is
    the installed copy, which is no git clone (one line says so), and its worker imports
    the installed packages. The baseline commit's tree (exported from this clone; it has
    no ``ffrmbs_app``, the installed copy has) runs the default scene with every project
    package from its own tree and gives this checkout's v_y(T). Both copies run their
    kernels as Python (``NUMBA_DISABLE_JIT``): numba's disk cache is keyed by the source's
    directory, so they would compile every kernel anew (some 40 CPU s), and what is
    checked here is where the code comes from and what it computes, not its speed; this
    checkout's v_y(T) is the compiled kernels'."""
    site, baseline = tmp_path / "site", tmp_path / "baseline"
    baseline.mkdir()
    why = step_cost.export_baseline(step_cost.BASELINE, baseline)
    if why:
        pytest.skip(f"no baseline to run: {why}")
    install_copy(site, tmp_path)
    t_end = 2e-4
    env = {**os.environ, "PYTHONPATH": str(site), "NUMBA_DISABLE_JIT": "1"}    # the kernels' Python: no compiling
    run = subprocess.run([sys.executable, "-c", BENCH_FROM_INSTALLED_COPY, str(tmp_path), str(baseline), str(t_end)],
                         cwd=tmp_path, env=env, capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    doc = json.loads(run.stdout.strip().splitlines()[-1])
    assert doc["root"] == str(site)
    assert doc["why"] == (f"{site} is not a git clone (an installed copy?): "
                          f"no commit {step_cost.BASELINE} to compare with")
    assert "ffrmbs_app" in doc["this"]["origins"] and set(doc["this"]["origins"].values()) == {str(site)}
    assert "ffrmbs_app" not in doc["baseline"]["origins"]
    assert set(doc["baseline"]["origins"].values()) == {str(baseline)}
    assert doc["baseline"]["cases"]["default"]["check"] == pytest.approx(default_vy(t_end), rel=1e-9)
