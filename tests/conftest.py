"""Shared fixtures: small meshes of the report's beam (built once per session), and the
test helpers of ``tests/support`` on the import path of every test module.

The session's caches, shared by every test, every xdist worker and every subprocess a test
starts (they inherit the environment), and kept for the next run, under
``$FFRMBS_TEST_CACHE`` (default ``.pytest_cache/ffrmbs`` in the repository):

* ``bodies/``: :func:`preprocess.build_body`'s results by recipe (:mod:`body_cache`);
* ``scenes/``: ``$FFRMBS_CACHE``, the built-in scenes' bodies and the peers' results, by
  their recipes (:mod:`ffrmbs_app.scenes.cache`), as a user's run keeps them;
* ``numba/``: ``$NUMBA_CACHE_DIR``, numba's compiled kernels, each compiled by one worker
  at a time (:mod:`compile_lock`, ``numba-locks/``).

They are set before numba is imported. A test that checks the first run gives its
process an empty cache of its own (``tests/qa/test_compile_once.py``).

Every subprocess a test starts imports this checkout (``PYTHONPATH`` starts with it), not
an installed copy: numba keys its disk cache by the source file's directory, so a second
copy of the code would compile every kernel again. Each process keeps BLAS to one thread
(``OPENBLAS_NUM_THREADS`` and the like, unless set): the xdist workers and the processes
they start share the machine's cores, and idle BLAS threads spinning beside them cost CPU.
Python writes and reads its bytecode cache (``__pycache__``, ignored by git) even where
``PYTHONDONTWRITEBYTECODE`` is set: without it each process compiles every module of
ffrmbs it imports from source again, about 1.5 CPU seconds per run of the CLI.

Under ``pytest -n`` each test module runs on one worker (its module fixtures are made
once) and the tests marked ``xdist_group(name)`` of all modules on one worker (the Dask
tests: ``dask``); the addopts' ``--dist loadgroup`` does this.
"""

import contextlib
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))

import paths  # noqa: E402

CACHE = Path(os.environ.get("FFRMBS_TEST_CACHE") or paths.REPO / ".pytest_cache" / "ffrmbs").resolve()
os.environ["FFRMBS_CACHE"] = str(CACHE / "scenes")
os.environ["NUMBA_CACHE_DIR"] = str(CACHE / "numba")
os.environ["PYTHONPATH"] = os.pathsep.join([str(paths.REPO)] + [p for p in [os.environ.get("PYTHONPATH")] if p])
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

from threadpoolctl import threadpool_limits  # noqa: E402

threadpool_limits(int(os.environ["OPENBLAS_NUM_THREADS"]))   # for a BLAS loaded before this file

import pytest  # noqa: E402

import compile_lock  # noqa: E402
import preprocess  # noqa: E402
from preprocess import pipeline  # noqa: E402
from body_cache import BodyCache  # noqa: E402

preprocess.build_body = pipeline.build_body = BodyCache(CACHE / "bodies", pipeline.build_body)
compile_lock.install(CACHE / "numba-locks")

from contours import Contour1sNeutralFFR  # noqa: E402
from mbs import FlexibleBodyFFR  # noqa: E402
from preprocess import Material, build_body  # noqa: E402
from preprocess.geometry import box  # noqa: E402

DASK = "dask"


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """The ``xdist_group`` of every test without one (given before xdist reads the marks for
    ``--dist loadgroup``): ``dask`` for the modules of the tests that use the session's
    Dask cluster (:func:`dask_client`, one per worker process), else the test's module."""
    def module(item):
        return item.nodeid.split("::")[0]

    on_dask = {module(item) for item in items if "dask_client" in item.fixturenames}
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            item.add_marker(pytest.mark.xdist_group(DASK if module(item) in on_dask else module(item)))


@pytest.fixture(scope="session")
def report_beam():
    """The report's 1 x 1 x 5 m beam, tet10, mesh size 0.5 (report Table 1)."""
    return box(1.0, 1.0, 5.0, 0.5, order=2)


@pytest.fixture(scope="session")
def small_box_tet4():
    return box(1.0, 0.5, 2.0, 0.5, order=1)


@pytest.fixture(scope="session")
def small_box_tet10():
    return box(1.0, 0.5, 2.0, 0.5, order=2)


@pytest.fixture(scope="session")
def thesis_beam_data():
    """The thesis's 250 x 50 x 50 mm beam (Sec. 5.2: ρ = 920 kg/m³, E = 50 MPa, ν = 0.3),
    structured tet4 (10 x 4 x 4 divisions, every face a node grid), free-free, 12 modes."""
    return build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(10, 4, 4)), Material(920.0, 5e7, 0.3),
                      n_modes=12)


@pytest.fixture(scope="module")
def thesis_beam(thesis_beam_data):
    """A free FFR body of the thesis's beam with its first 8 modes (one per test module:
    a body joins at most one System)."""
    return FlexibleBodyFFR(thesis_beam_data, modes=8)


@pytest.fixture(scope="module")
def thesis_centre_line(thesis_beam):
    """The beam's centre line as a degree-4 1s neutral contour, reference normal y: a C²
    band and cylinder on it (module docstring of contours.derived)."""
    return Contour1sNeutralFFR.along_line(thesis_beam, (0, 0.025, 0.025), (1, 0, 0), normal=(0, 1, 0), degree=4)


_DASK_CLUSTER = contextlib.ExitStack()


@pytest.fixture(scope="session")
def dask_client():
    """One Dask LocalCluster for the session's sweep and validate tests: two single-threaded
    worker processes (as ``ffrmbs sweep --workers 2`` makes), and its client. It is shut
    down after the session's last test that uses it (:func:`pytest_runtest_teardown`): an
    idle cluster costs about 0.1 CPU s per second."""
    from distributed import Client, LocalCluster

    with _DASK_CLUSTER:
        cluster = _DASK_CLUSTER.enter_context(
            LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None))
        yield _DASK_CLUSTER.enter_context(Client(cluster))


def pytest_runtest_teardown(item, nextitem):
    """Shut the Dask cluster down after the last test (in the session's order) that uses it."""
    if "dask_client" in item.fixturenames and not any(
            "dask_client" in later.fixturenames for later in item.session.items[item.session.items.index(item) + 1:]):
        _DASK_CLUSTER.close()
