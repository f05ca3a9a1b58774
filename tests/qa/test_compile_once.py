"""Each numba kernel is compiled for one signature: a kernel calling another passes no
literal constant, since numba types a literal argument (``0``, ``True``, a module constant
such as ``Q_AT``) as ``Literal[int](0)`` / ``Literal[bool](True)`` and compiles the callee
once more for it, beside the ``int64`` / ``bool`` version the other callers use (issue 30,
item 22: compile only what a scene needs). A first run compiles them in a second process
while the beam is preprocessed (:mod:`ffrmbs_app.precompile`)."""

import ast
import importlib
import inspect
import json
import os
import subprocess
import sys
import textwrap

import pytest
from numba.core.registry import CPUDispatcher

import paths

ROOT = paths.REPO


def _kernel_modules():
    """The modules of the packages whose source defines numba kernels (mentions njit)."""
    for package in ("contact", "contours", "mbs", "preprocess", "ffrmbs", "validation"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if "njit" in path.read_text(encoding="utf-8"):
                name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
                yield name


# Runs the default scene for 2 ms (200 steps) in a fresh process with an empty numba cache
# (kernels loaded from the disk cache do not list their nested callees' overloads) and
# prints every kernel of the project numba holds more than one signature of.
OVERLOADS = textwrap.dedent("""
    import json, sys
    from numba.core.registry import CPUDispatcher
    from ffrmbs_app.main_job import JobSettings, run_job

    run_job(JobSettings(check=False, t_end=0.002), sys.argv[1], log=lambda *a: None, export=False, precompile=False)
    kernels = {}
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] in ("contact", "contours", "mbs", "ffrmbs", "preprocess", "ffrmbs_app"):
            for f in vars(module).values():
                if isinstance(f, CPUDispatcher):
                    kernels[f.py_func.__module__ + "." + f.py_func.__name__] = [str(s) for s in f.signatures]
    print(json.dumps({"used": sum(1 for s in kernels.values() if s),
                      "several": {k: s for k, s in kernels.items() if len(s) > 1}}))
""")


def _literal_arguments(source, names):
    """(caller, callee, line) of each call of a kernel from a kernel in ``source`` (a module
    whose namespace is ``names``) with an argument numba types as a literal: an int or bool
    constant (``0``, ``True``) or module-level one (``Q_AT``); numba has no float literals."""
    kernels = {n for n, f in names.items() if isinstance(f, CPUDispatcher)}
    numbers = {n for n, v in names.items() if type(v) in (bool, int)}
    found = []
    for fn in ast.parse(source).body:
        if not (isinstance(fn, ast.FunctionDef) and fn.name in kernels):
            continue
        local = {a.arg for a in fn.args.args} | {n.id for n in ast.walk(fn)
                                                  if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        for call in ast.walk(fn):
            if isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id in kernels:
                for a in call.args:
                    a = a.operand if isinstance(a, ast.UnaryOp) else a
                    if (isinstance(a, ast.Constant) and type(a.value) in (bool, int)) or (
                            isinstance(a, ast.Name) and a.id in numbers and a.id not in local):
                        found.append((fn.name, call.func.id, call.lineno))
    return found


@pytest.mark.parametrize("name", list(_kernel_modules()))
def test_no_kernel_passes_a_literal_to_a_kernel(name):
    module = importlib.import_module(name)
    assert _literal_arguments(inspect.getsource(module), vars(module)) == []


def test_the_check_finds_a_literal_argument():
    """The source check above on a module written for it: a literal 0, a literal True and a
    module constant passed to a kernel are found; typed values, local variables and floats
    are not, and numba compiles the callee once per literal found."""
    source = textwrap.dedent("""
        import numpy as np
        from numba import njit
        AT = 3

        @njit(cache=False)
        def callee(x, k, flag):
            return x + k if flag else x

        @njit(cache=False)
        def caller(x, n):
            at = AT + n
            return (callee(x, 0, np.bool_(True)) + callee(x, np.int64(AT), True) + callee(x, AT, np.bool_(False))
                    + callee(x, at, np.bool_(False)) + callee(x, 1.5, np.bool_(False)))
    """)
    names = {}
    exec(compile(source, "<literal_example>", "exec"), names)
    assert _literal_arguments(source, names) == [("caller", "callee", 13)] * 3
    names["caller"](1.0, 2)
    assert len(names["callee"].signatures) == 5     # numba's: int64/bool, float64/bool, three literal variants


@pytest.mark.slow      # about a minute of CPU: every kernel of the default scene compiled from an empty cache
def test_a_cold_default_run_compiles_each_kernel_once(tmp_path):
    """The default scene, 200 steps from an empty numba cache: no kernel holds more than one
    signature (before: point_jacobian_T, frame_rates_jacobians, contract_surface, prox_step
    twice, _modal and _grown three times)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               PYTHONPATH=os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    done = subprocess.run([sys.executable, "-c", OVERLOADS, str(tmp_path / "out")], env=env, cwd=tmp_path,
                          capture_output=True, text=True, check=True)
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["used"] > 30               # the run compiled its kernels here, nested ones included
    assert report["several"] == {}


# The default scene's first run (empty numba cache and body cache), 200 steps, as ``ffrmbs
# run`` does it: the kernels compiled by a second process while the beam is preprocessed.
PRECOMPILED = textwrap.dedent("""
    import json, sys
    from ffrmbs_app.main_job import JobSettings, run_job

    lines = []
    summary = run_job(JobSettings(check=False, t_end=0.002), sys.argv[1], log=lines.append, export=False)
    print(json.dumps({"compiled": summary["kernels_compiled"], "log": lines}))
""")


@pytest.mark.slow      # about a minute of CPU: every kernel of the default scene compiled from an empty cache
def test_a_first_run_compiles_the_kernels_in_a_second_process_beside_the_preprocessing(tmp_path):
    """The job compiles no kernel itself: the second process, started before the beam's
    preprocessing, compiled them all into numba's disk cache (before: 23 compiled in the
    job's warm-up, after the preprocessing)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), FFRMBS_CACHE=str(tmp_path / "bodies"),
               PYTHONPATH=os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    done = subprocess.run([sys.executable, "-c", PRECOMPILED, str(tmp_path / "out")], env=env, cwd=tmp_path,
                          capture_output=True, text=True, check=True)
    report = json.loads(done.stdout.strip().splitlines()[-1])
    log = report["log"]
    started = next(i for i, line in enumerate(log) if "compiling numba kernels in a second process" in line)
    preprocessing = next(i for i, line in enumerate(log) if line.startswith("preprocessing the point_mass_beam"))
    finished = next(i for i, line in enumerate(log) if line.startswith("kernels compiled in a second process"))
    assert started < preprocessing < finished
    assert report["compiled"] == 0
    assert any(line.startswith("kernels: loaded from numba's disk cache") for line in log)


def test_a_failed_second_process_is_named_and_the_job_goes_on():
    from ffrmbs_app.precompile import Precompiler

    lines = []
    Precompiler(subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])).wait(lines.append)
    assert lines == ["compiling the kernels in a second process failed (exit 3); the run compiles them itself"]
    child = Precompiler(subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]))
    child.stop()
    assert child.process.returncode is not None
