"""Shared fixtures: small meshes of the report's beam (built once per session), and the
test helpers of ``tests/support`` on the import path of every test module."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))

from contours import Contour1sNeutralFFR
from mbs import FlexibleBodyFFR
from preprocess import Material, build_body
from preprocess.geometry import box


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


@pytest.fixture(scope="session")
def dask_client():
    """One Dask LocalCluster for the session's sweep and validate tests: two single-threaded
    worker processes (as ``ffrmbs sweep --workers 2`` makes), and its client."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        yield client
