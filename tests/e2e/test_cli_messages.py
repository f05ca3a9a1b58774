"""What the command line says: help texts without markup and with every argument described,
the --no-check help naming every run it skips, the job's header under --set, and one way of
printing paths."""

import os

import pytest

from ffrmbs_app import cli
from ffrmbs_app.job import header
from ffrmbs_app.output_dirs import shown
from ffrmbs_app.scene import Scene
from qa.fixtures import fixture_text


def help_text(capsys, *argv):
    with pytest.raises(SystemExit):
        cli.main([*argv, "--help"])
    return capsys.readouterr().out


def test_help_shows_no_markup(capsys):
    text = help_text(capsys)
    assert "``" not in text and ":func:" not in text
    assert "The ffrmbs command line" in text


def test_every_argument_is_described():
    import argparse

    parser = cli.build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name, sub in commands.items():
        for action in sub._actions:
            if not isinstance(action, argparse._HelpAction):
                assert action.help, f"ffrmbs {name}: {action.dest} has no help text"


def test_no_check_names_every_run_it_skips(capsys):
    text = " ".join(help_text(capsys, "run").split())
    assert "dt/2" in text and "twice the modes" in text and "coarser mesh" in text


def test_header_says_the_description_is_the_file_s_under_set():
    scene = Scene(None, 0.2, 5e-4, description="a ball, e = 0.5, dt = 1 ms", name="bounce",
                  overrides=("scene.dt=5e-4", "contact.floor.e=0.8"))
    assert header(scene) == ("scene bounce: a ball, e = 0.5, dt = 1 ms\n  (the file's description; overridden by "
                             "--set scene.dt=5e-4, contact.floor.e=0.8)")
    scene.overrides = ()
    assert header(scene) == "scene bounce: a ball, e = 0.5, dt = 1 ms"
    scene.description, scene.overrides = "", ("scene.dt=5e-4",)
    assert header(scene) == "scene bounce, overridden by --set scene.dt=5e-4"


def test_paths_are_printed_one_way(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    inside = tmp_path / "out" / "bounce-paraview" / "bounce.pvd"
    assert shown(inside) == os.path.join("out", "bounce-paraview", "bounce.pvd")
    assert shown("out/bounce.h5") == os.path.join("out", "bounce.h5")
    assert shown(tmp_path.parent / "elsewhere.h5") == str(tmp_path.parent / "elsewhere.h5")


BALL = fixture_text("scenes/ball_on_floor.toml")


def test_the_job_says_what_its_warm_up_run_is(tmp_path):
    from ffrmbs_app.job import run_scene
    from ffrmbs_app.scene_loader import load_scene

    path = tmp_path / "ball.toml"
    path.write_text(BALL)

    def make():
        scene = load_scene(path, ("contact.floor.e=0.8",))
        scene.warmup = (0.01, 1e-3)
        return scene

    lines = []
    run_scene(make, tmp_path / "out", check=False, export=False, plot=False, checkpoint_every=None, log=lines.append)
    assert lines[0] == ("scene bounce: a ball dropped on a floor, e = 0.5\n"
                        "  (the file's description; overridden by --set contact.floor.e=0.8)")
    warm = next(line for line in lines if line.startswith("warm-up run"))
    assert "compiles the kernels" in warm and "0.01 s of simulated time at dt = 0.001 s" in warm
    assert "not counted in the cost" in warm
