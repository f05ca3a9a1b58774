"""The side-by-side step benchmark's plumbing: the baseline export and one worker run."""

import json
import subprocess
import sys

import numpy as np
import pytest

from validation.bench import step_cost


def test_a_missing_baseline_commit_is_named(tmp_path):
    """An unknown commit (or no git at all) is a reason in the table, never an exception."""
    why = step_cost.export_baseline("0" * 40, tmp_path)
    assert why is not None and (why.startswith(f"commit {'0' * 40} not found") or why.startswith("git not available"))
    assert not any(tmp_path.iterdir())


@pytest.mark.slow
def test_the_worker_times_the_default_scene_and_reports_its_answer():
    """The worker, run in its own process on this checkout, times the default scene for
    200 steps and reports v_y(T) equal to the same scene run here."""
    spec = {"cases": [{"name": "default", "kind": "default", "t_end": 0.002, "dt": 1e-5}], "repeats": 2}
    out = step_cost.run_worker(step_cost.ROOT, spec)["default"]
    assert out["steps"] == 200 and len(out["walls"]) == 2 and min(out["walls"]) > 0
    from ffrmbs_app.scenes import point_mass_beam as pmb

    scene = pmb.build("A", modes=20)
    res = scene.system.simulate(0.002, 1e-5, integrator="moreau", t_out=np.linspace(0, 0.002, 101),
                                outputs=scene.outputs())
    assert out["check"] == float(res["vy"][-1])
