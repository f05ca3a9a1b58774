"""Shared fixtures: small meshes of the report's beam (built once per session)."""

import pytest

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
