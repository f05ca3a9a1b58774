"""The per-scene step benchmark's plumbing (validation.bench.scene_cost): one case run as
``ffrmbs run`` in a fresh process of a checkout, its cost line read; a run without one
is named."""

import shutil

import pytest

from validation.bench import scene_cost


def test_a_case_runs_the_scene_for_its_steps_and_reads_the_cost(tmp_path):
    """The bouncing ball for 0.02 s at Δt = 1e-4 s: 200 steps (t_end / Δt), a positive CPU
    time, from this checkout's packages."""
    shutil.copy(scene_cost.ROOT / "examples" / "scenes" / "bouncing_ball.toml", tmp_path)
    steps, cpu = scene_cost.run_case(scene_cost.ROOT, "bouncing_ball", tmp_path, tmp_path, 0.02)
    assert steps == 200
    assert 0.0 < cpu < 60.0


def test_output_without_a_cost_line_is_named():
    assert scene_cost.cost_of("x\ncost: 10000 steps in 1.69 s wall (1.52 s CPU), 169 µs per step\n") == (10000, 1.52)
    with pytest.raises(ValueError, match="no cost line.*it failed"):
        scene_cost.cost_of("some output\nit failed\n")
