"""Command-line behaviour a new user meets first (issue 18): a closed pipe."""

import os
import subprocess
import sys


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
        res = subprocess.run([sys.executable, "-m", "ffrmbs.cli", "info", str(tmp_path / "beam" / "body.h5")],
                             stdout=write, stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write)
    assert "Traceback" not in res.stderr and "BrokenPipeError" not in res.stderr, res.stderr
    assert res.returncode == 141
