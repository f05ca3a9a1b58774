"""The command line run in the test's own process: ``ffrmbs_app.cli.main(argv)`` with its
output captured (no interpreter start; an exception escaping ``main``, which would be a
traceback, fails the calling test)."""

from __future__ import annotations

import contextlib
import io


def run_cli(*argv) -> tuple[int, str, str]:
    """``ffrmbs ARGV`` in this process (arguments as ``str``): (exit code, stdout, stderr)."""
    from ffrmbs_app import cli

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()
