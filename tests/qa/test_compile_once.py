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
import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

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


# The default scene's first run (empty numba cache and body cache), 200 steps, as ``ffrmbs
# run`` does it: the kernels compiled by a second process while the beam is preprocessed.
PRECOMPILED = textwrap.dedent("""
    import json, sys
    from ffrmbs_app.main_job import JobSettings, run_job

    lines = []
    summary = run_job(JobSettings(check=False, t_end=0.002), sys.argv[1], log=lines.append, export=False)
    print(json.dumps({"compiled": summary["kernels_compiled"], "log": lines}))
""")


@pytest.fixture(scope="module")
def first_run(tmp_path_factory):
    """The suite's one cold run (about a minute of CPU: every kernel of the default scene
    compiled from an empty cache): its report and its numba cache directory."""
    tmp = tmp_path_factory.mktemp("first_run")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp / "numba"), FFRMBS_CACHE=str(tmp / "bodies"))
    done = subprocess.run([sys.executable, "-c", PRECOMPILED, str(tmp / "out")], env=env, cwd=tmp,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1]), tmp / "numba"


def _cached_signatures(cache_dir):
    """{kernel: number of signatures} in a numba disk cache: each kernel's index file
    (``<name>-<line>.py<version>.nbi``: numba's format version, then the pickled source
    stamp and the overloads, one per compiled signature, nested callees included)."""
    counts = {}
    for index in sorted(Path(cache_dir).rglob("*.nbi")):
        with open(index, "rb") as f:
            pickle.load(f)
            _, overloads = pickle.loads(f.read())
        counts[f"{index.parent.name.rsplit('_', 1)[0]}/{index.name.split('.py')[0]}"] = len(overloads)
    return counts


@pytest.mark.slow
def test_a_first_run_compiles_the_kernels_in_a_second_process_beside_the_preprocessing(first_run):
    """The job compiles no kernel itself: the second process, started before the beam's
    preprocessing, compiled them all into numba's disk cache (before: 23 compiled in the
    job's warm-up, after the preprocessing)."""
    report, _ = first_run
    log = report["log"]
    started = next(i for i, line in enumerate(log) if "compiling numba kernels in a second process" in line)
    preprocessing = next(i for i, line in enumerate(log) if line.startswith("preprocessing the point_mass_beam"))
    finished = next(i for i, line in enumerate(log) if line.startswith("kernels compiled in a second process"))
    assert started < preprocessing < finished
    assert report["compiled"] == 0
    assert any(line.startswith("kernels: loaded from numba's disk cache") for line in log)


@pytest.mark.slow
def test_a_cold_default_run_compiles_each_kernel_once(first_run):
    """The first run's numba cache holds one signature of each kernel (before:
    point_jacobian_T, frame_rates_jacobians, contract_surface, prox_step twice, _modal and
    _grown three times)."""
    signatures = _cached_signatures(first_run[1])
    assert len(signatures) > 30              # the run compiled its kernels there, nested ones included
    assert {k: n for k, n in signatures.items() if n > 1} == {}


def test_the_cache_reader_counts_each_signature(tmp_path):
    """:func:`_cached_signatures` on a cache written for it: a kernel called with an int, a
    float and (from a second kernel) a literal 0 holds three signatures, the caller one."""
    source = textwrap.dedent("""
        from numba import njit

        @njit(cache=True)
        def callee(x, k):
            return x + k

        @njit(cache=True)
        def caller(x):
            return callee(x, 0)

        callee(1.0, 2); callee(1.0, 2.5); caller(1.0)
    """)
    (tmp_path / "toy.py").write_text(source)
    subprocess.run([sys.executable, "toy.py"], cwd=tmp_path, check=True,
                   env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba")))
    counts = _cached_signatures(tmp_path / "numba")
    assert sorted(counts.values()) == [1, 3] and len(counts) == 2


# Two point masses landing one after the other on the default beam's top face (residual
# flexibility on, one contact frictionless, one with Coulomb friction), stepped by the
# Moreau stages: the contact problem has 1, 3 and 4 rows in turn; then a free beam alone
# and beside a point mass (its mass matrix the whole M, then a block of it). In a process
# of its own (kernels loaded from the suite's cache or compiled there), every kernel it
# called holds one signature.
TWO_LANDINGS = textwrap.dedent("""
    import json, sys
    sys.path.insert(0, sys.argv[1])
    import compile_lock
    compile_lock.install(sys.argv[2])
    import numpy as np
    from numba.core.registry import CPUDispatcher
    from contact import UnilateralCoulombContact, connect
    from contact.solver import ProxSolver
    from contours import PointContour
    from ffrmbs_app.scenes import point_mass_beam as pmb
    from mbs import FlexibleBodyFFR, PointMass, System
    from mbs.run import stages
    from mbs.run.model import Data, compile_model

    scene = pmb.build(residual_flexibility=True)
    second = scene.system.add(PointMass(pmb.MASS, position=(0.15, pmb.HEIGHT + 0.003, 0.02), velocity=pmb.VELOCITY,
                                        name="second mass"))
    surface = scene.contact.kinematics.contour2
    scene.system.add(connect(PointContour(second.point), surface, UnilateralCoulombContact(0.0, 0.3), name="second"))
    model = compile_model(scene.system, None, theta=0.5, solver=ProxSolver())
    data = Data(model)
    data.q[:], data.u[:] = scene.system.initial_state()
    rows = set()
    for _ in range(2500):
        stages.step(model, data, 1e-5)
        rows.add(data.m)
    for beside in (False, True):            # a free beam alone, then beside a point mass
        system = System(gravity=(0.0, -9.81, 0.0))
        system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=4, name="free beam"))
        if beside:
            system.add(PointMass(1.0, position=(1.0, 0.0, 0.0), name="mass"))
        free = compile_model(system, None, theta=0.5, solver=ProxSolver())
        state = Data(free)
        state.q[:], state.u[:] = system.initial_state()
        for _ in range(3):
            stages.step(free, state, 1e-4)
    twice = {}                              # each kernel once, under its defining module's name
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] in ("contact", "contours", "mbs", "ffrmbs", "preprocess"):
            for value in vars(module).values():
                if isinstance(value, CPUDispatcher) and len(value.signatures) > 1:
                    kernel = f"{value.py_func.__module__}.{value.py_func.__qualname__}"
                    twice[kernel] = [str(s) for s in value.signatures]
    print(json.dumps({"rows": sorted(rows), "twice": twice}))
""")


@pytest.mark.slow
def test_a_scene_whose_contact_problem_changes_size_compiles_each_kernel_once():
    """The scratch and problem arrays of every size are C-contiguous views
    (:meth:`mbs.run.model.Data.problem`, ``solver_scratch``, ``compliance``), block factors are
    indexed in place, and a contact's W block is written into the whole W: the kernels see
    one array layout for every problem size, and a body's mass kernel writes a C-contiguous
    block of its own. Before, a problem of fewer rows than the most a scene can have
    passed column slices ('A' layout) and compiled the contact solver a second time in the
    middle of a run (15 CPU s), the one-row problem (M̂⁻¹W both C- and Fortran-contiguous)
    compiled the stage kernels twice, and a free body's mass kernels (ffr_mass_qv_into: 4
    CPU s) compiled again for a block of M."""
    done = subprocess.run([sys.executable, "-c", TWO_LANDINGS, str(ROOT / "tests" / "support"),
                           str(Path(os.environ["NUMBA_CACHE_DIR"]).with_name("numba-locks"))], capture_output=True, text=True, check=True)
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert {1, 3, 4} <= set(report["rows"])
    assert report["twice"] == {}


def test_the_second_process_runs_the_copy_of_ffrmbs_the_job_runs(tmp_path):
    """From a directory holding another ffrmbs_app (a clone after ``pip install .``), the
    child still imports the job's copy: numba keys its disk cache by the source's
    directory, and ``python -m`` (the working directory first on sys.path) ran the clone's
    source, so the job compiled every kernel a second time (README's first command: two
    compilations of the default scene). Here the other copy exits 7 on import, and the
    job's child stops at once on a settings key it does not know."""
    from ffrmbs_app.main_job import JobSettings
    from ffrmbs_app.precompile import child_command

    decoy = tmp_path / "ffrmbs_app"
    decoy.mkdir()
    (decoy / "__init__.py").write_text("raise SystemExit(7)\n")
    command = child_command(JobSettings())[:-1] + ['{"no_such_setting": 1}']
    done = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 1 and "no_such_setting" in done.stderr


def test_a_failed_second_process_is_named_and_the_job_goes_on():
    from ffrmbs_app.precompile import Precompiler

    lines = []
    Precompiler(subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])).wait(lines.append)
    assert lines == ["compiling the kernels in a second process failed (exit 3); the run compiles them itself"]
    child = Precompiler(subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]))
    child.stop()
    assert child.process.returncode is not None
