"""A 1s contour fitted by least squares to a walked edge group (``control_points``):
against the exact circle of a cylinder's rim, converging with the control points."""

import numpy as np
import pytest
from scipy.interpolate import BSpline

from contours import Contour1sNeutralFFR
from mbs import FlexibleBodyFFR, PrescribedFrameMotion
from preprocess import build_body
from preprocess.geometry import cylinder
from preprocess.pipeline import Material

R = 0.05


@pytest.fixture(scope="module")
def body():
    """A disc-like cylinder, one 10 mm element long: its rim carries as many nodes (on the
    exact circle, order 2) as a long one's, at a tenth of the FE model."""
    mesh = cylinder(R, 0.01, 0.01, order=2)
    data = build_body(mesh, Material(7800.0, 2e11, 0.3), 2, clamp="end0")
    return FlexibleBodyFFR(data, frame=PrescribedFrameMotion.fixed())


def radial_error(contour):
    """max | |x(t)| − R | of the undeformed curve on 400 parameters (scipy's B-spline)."""
    space = contour.space.eta
    x = BSpline(space.knots, contour._local_position.ctrl0, space.p)(np.linspace(0, 1, 400, endpoint=False))
    return np.abs(np.hypot(x[:, 0], x[:, 1]) - R).max()


def test_fitted_rim_is_closed_and_converges_to_the_circle(body):
    errors = []
    for n in (12, 24, 48):
        c = Contour1sNeutralFFR(body, "rim1", (0.0, 0.0, 1.0), control_points=n)
        assert c.closed == (True,) and c.space.eta.n_ctrl == n + 3
        errors.append(radial_error(c))
    assert errors[2] < 1e-6 * R
    assert errors[0] > 8 * errors[1] > 64 * errors[2]        # a cubic fit: about h⁴


def test_too_few_control_points_is_a_clear_error(body):
    with pytest.raises(Exception, match="at least 4 control points"):
        Contour1sNeutralFFR(body, "rim1", (0.0, 0.0, 1.0), control_points=3)
