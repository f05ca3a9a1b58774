"""Progress bars: silent off a terminal, drawn on one or when forced, never in the way."""

import io

import pytest

from ffrmbs_app import cli
from ffrmbs_app.progress import ENV_VAR, ProgressCallback, progress_bar, progress_enabled, stage_bar, write


class Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self):
        return True


def run_bars():
    with progress_bar(0.1, "simulating", unit="s") as bar:
        for t in (0.025, 0.05, 0.075, 0.1):
            bar.update_to(t)
    with ProgressCallback(0.2, t_start=0.1) as progress:
        for t in (0.15, 0.2):
            progress(t)
    with stage_bar(2, "preprocess") as bar:
        bar.stage("meshing")
        bar.stage("modes")


def test_silent_when_stderr_is_not_a_terminal(monkeypatch, capsys):
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert not progress_enabled()                 # pytest's captured stderr is no terminal
    run_bars()
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize("value", ["1", "yes", "on"])
def test_forced_on_draws_on_stderr(monkeypatch, capsys, value):
    monkeypatch.setenv(ENV_VAR, value)
    run_bars()
    out, err = capsys.readouterr()
    assert out == ""
    assert "simulating: 100%" in err and "0.1/0.1 s" in err
    assert "2/2 stages" in err and "modes" in err


def test_terminal_draws_unless_forced_off(monkeypatch):
    term = Terminal()
    monkeypatch.setattr("sys.stderr", term)
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert progress_enabled()
    with progress_bar(10, "export", unit="file") as bar:
        bar.update(4)
        assert bar.n == 4
    assert "export: 100%" in term.getvalue() and "10/10 file" in term.getvalue()
    monkeypatch.setenv(ENV_VAR, "0")
    quiet = Terminal()
    monkeypatch.setattr("sys.stderr", quiet)
    run_bars()
    assert quiet.getvalue() == ""


def test_callback_follows_time_and_clips_at_the_end(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "1")
    monkeypatch.setattr("sys.stderr", io.StringIO())
    progress = ProgressCallback(1.0, t_start=0.5)
    progress(0.75)
    assert progress.n == pytest.approx(0.25)
    progress(0.6)                                  # never goes back
    assert progress.n == pytest.approx(0.25)
    progress(2.0)                                  # clipped at t_end
    assert progress.n == pytest.approx(0.5)
    progress.close()
    progress.close()                               # idempotent
    monkeypatch.setenv(ENV_VAR, "0")
    silent = ProgressCallback(1.0)
    silent(0.5)
    assert silent.n == 0.0


def test_log_lines_go_above_a_drawn_bar(monkeypatch):
    monkeypatch.setenv(ENV_VAR, "1")
    term = Terminal()
    monkeypatch.setattr("sys.stderr", term)
    with progress_bar(1.0, "run") as bar:
        bar.update_to(0.5)
        write("contact closed at t = 0.5 s")
    text = term.getvalue()
    assert "contact closed at t = 0.5 s\n" in text
    assert text.index("contact closed") < text.rindex("run: 100%")


PREPROCESS = ["preprocess", "box:1,1,1", "--modes", "2", "--clamp", "z0", "--density", "1000",
              "--young", "1e6", "--poisson", "0.3", "--order", "1", "--mesh-size", "1"]


def test_preprocess_stages_show_only_when_forced(monkeypatch, capsys, tmp_path):
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert cli.main([*PREPROCESS, "--out", str(tmp_path / "quiet")]) == 0
    out, err = capsys.readouterr()
    assert "preprocess:" not in err and "\r" not in err   # the log lines only, as before
    assert err.splitlines()[0] == "meshing box:1,1,1 ..."
    assert err.splitlines()[2].startswith("assembled K")
    assert "nodes  surface nodes" in out and "omega [rad/s]" in out
    monkeypatch.setenv(ENV_VAR, "1")
    assert cli.main([*PREPROCESS, "--out", str(tmp_path / "bar")]) == 0
    out2, err2 = capsys.readouterr()
    assert "preprocess: 4/4 stages" in err2 and "computing modes" in err2
    assert "meshing box:1,1,1 ..." in err2
    assert out2 == out                             # stdout is the same table either way
