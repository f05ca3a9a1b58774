"""Command-line behaviour a new user meets first (issue 18): a closed pipe, an output
directory that is a file."""

import os
import subprocess
import sys

import pytest


def test_info_into_a_closed_pipe_ends_quietly(tmp_path):
    """`ffrmbs info ... | head` whose reader has gone: no BrokenPipeError traceback, the
    shell's SIGPIPE status. The reading end is closed before the command writes, so the
    first write fails deterministically (Python ignores SIGPIPE and raises instead)."""
    from preprocess import Material, box, build_body, write_body

    body = build_body(box(0.2, 0.05, 0.05, mesh_size=0.05, order=1), Material(7800.0, 2e11, 0.3), 2, clamp="x0")
    write_body(tmp_path / "beam", body)
    read, write = os.pipe()
    os.close(read)
    try:
        res = subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", "info", str(tmp_path / "beam" / "body.h5")],
                             stdout=write, stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write)
    assert "Traceback" not in res.stderr and "BrokenPipeError" not in res.stderr, res.stderr
    assert res.returncode == 141


@pytest.mark.parametrize("argv", [
    ["run", "--out", "{file}", "--t-end", "0.001", "--no-check", "--no-export"],
    ["preprocess", "box:0.2,0.05,0.05", "--modes", "2", "--clamp", "x0", "--density", "7800",
     "--young", "2e11", "--poisson", "0.3", "--order", "1", "--mesh-size", "0.05", "--out", "{file}"],
    ["validate", "--quick", "--only", "cantilever", "--out", "{file}"],
    ["bench", "--quick", "--out", "{file}"],
])
def test_an_output_directory_that_is_a_file_is_one_clear_line(tmp_path, capsys, argv):
    """--out naming an existing regular file is refused before any work (it was a
    FileExistsError traceback after the run or the meshing)."""
    from ffrmbs_app.cli import main

    blocker = tmp_path / "taken"
    blocker.write_text("not a directory\n")
    with pytest.raises(SystemExit) as stop:
        main([a.replace("{file}", str(blocker)) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert stop.value.code == 2
    assert err[-1].endswith(f"argument --out: {blocker} exists and is not a directory")
    assert blocker.read_text() == "not a directory\n"
