"""Review of the issue-18 change: checkpoint format errors, the fault audit's planted
checkpoints, and the other leftovers the review listed."""

from __future__ import annotations

import pytest

from ffrmbs.errors import InputFileError
from mbs.results.checkpoint import read_checkpoint


def test_a_checkpoint_of_the_older_unsigned_format_is_named_as_such(tmp_path):
    ckpt = tmp_path / "x.ckpt"
    ckpt.write_bytes(b"ffrmbs-checkpoint-1\n" + b"\x80\x05N.")
    with pytest.raises(InputFileError, match=r"pickled checkpoint of an older ffrmbs \(ffrmbs-checkpoint-1\): "
                                             "refused unread.*restart the run"):
        read_checkpoint(ckpt)


def _help(argv, capsys):
    from ffrmbs_app.cli import build_parser

    with pytest.raises(SystemExit):
        build_parser().parse_args([*argv, "--help"])
    return " ".join(capsys.readouterr().out.split())


def test_the_no_limits_help_gives_the_limits_in_force(monkeypatch, capsys):
    from ffrmbs_app import limits as run_limits
    from preprocess import limits as mesh_limits

    monkeypatch.setattr(mesh_limits, "MAX_NODES", 7_000)
    monkeypatch.setattr(mesh_limits, "MEMORY_SHARE", 0.3)
    monkeypatch.setattr(run_limits, "MAX_STEPS", 9_000)
    monkeypatch.setattr(run_limits, "MEMORY_SHARE", 0.1)
    assert "over 7e+03 nodes or 30% of the physical memory" in _help(["preprocess"], capsys)
    assert "beyond 9e+03 time steps or 10% of the physical memory" in _help(["run"], capsys)


def test_both_limits_say_how_to_lift_them_in_one_wording():
    from ffrmbs_app import limits as run_limits
    from preprocess import limits as mesh_limits

    assert mesh_limits.LIFT == "pass --no-limits (check_limits=False from Python) to run it anyway"
    assert run_limits.LIFT == "pass --no-limits (no_limits=True from Python) to run it anyway"


@pytest.mark.parametrize("integrator, options, traced", [
    ("moreau", {}, True), ("moreau-adaptive", {}, True), ("moreau", {"trace": False}, False),
    ("moreau", {"trace": True}, True), ("rk4", {}, False), ("generalized-alpha", {}, False)])
def test_a_scene_says_whether_its_run_keeps_a_trace_and_the_limits_count_it(integrator, options, traced):
    from ffrmbs_app.limits import TRACE_BYTES, estimate
    from ffrmbs_app.scene import Scene
    from mbs import PointMass, System
    from mbs.integrators.moreau import TRACE_KEYS

    system = System(gravity=(0.0, -9.81, 0.0))
    system.add(PointMass(1.0, position=(0.0, 0.0, 0.0)))
    scene = Scene(system, 0.01, 1e-3, integrator, options=options, energies=False, plan=False)
    assert scene.keeps_trace() is traced
    assert estimate(scene)["step_bytes"] == (len(TRACE_KEYS) * TRACE_BYTES if traced else 0)


def test_a_preprocess_checks_its_mesh_options_once_before_meshing(tmp_path, capsys, monkeypatch):
    from ffrmbs_app.cli import main
    from preprocess import pipeline

    calls = []
    check = pipeline.check_mesh_options
    monkeypatch.setattr(pipeline, "check_mesh_options", lambda *a: calls.append(a) or check(*a))
    rc = main(["preprocess", "box:1,0.2,0.2", "--clamp", "x0", "--modes", "2", "--density", "7800",
               "--young", "2e11", "--poisson", "0.3", "--mesh-size", "0.2", "--order", "1",
               "--out", str(tmp_path / "out")])
    assert rc in (0, None) and calls == [("box:1,0.2,0.2", 1, 0.2, None, None)]     # spec, order, size, structured, groups
    assert "meshing box:1,0.2,0.2 ..." in capsys.readouterr().err
