"""A fitted 2s contour warns, on construction, about each bound of its fit report it
exceeds, and the command line shows such a warning as one line."""

import warnings

import numpy as np
import pytest

from contours import Contour2sNeutralFFR
from ffrmbs_app.cli import _show_warning
from mbs import FlexibleBodyFFR, PrescribedFrameMotion
from preprocess import build_body
from preprocess.geometry import box
from preprocess.pipeline import Material


@pytest.fixture(scope="module")
def plate():
    mesh = box(0.2, 0.1, 0.02, 0.02, order=2)          # unstructured: face z1 is no grid
    data = build_body(mesh, Material(7800.0, 2e11, 0.3), 4, clamp="x0")
    return FlexibleBodyFFR(data, frame=PrescribedFrameMotion.fixed(), name="plate")


def test_a_good_fit_is_silent_and_a_coarse_one_warns_with_the_remedy(plate):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        good = Contour2sNeutralFFR(plate, "z1")
    assert good.fit is not None and not good.fit_report.warnings
    with pytest.warns(UserWarning, match=r"node group 'z1' of body 'plate': mode \d+ is fitted to within .* "
                                         r"give more control points"):
        coarse = Contour2sNeutralFFR(plate, "z1", control_points=4)
    # the warned error is the mode's own: the fitted control points against its nodal values
    phi = plate.phi_nodes[coarse.nodes]
    worst = max(r["node_max"] for r in coarse.fit_report.rows[1:])
    Pphi = coarse.fit.control_points(phi)[:4, :4].reshape(-1, 3, phi.shape[-1])
    at_nodes = np.einsum("ka,ajm->kjm", coarse.fit.collocation(coarse.fit.params).toarray(), Pphi)
    direct = max(np.linalg.norm(at_nodes[:, :, j] - phi[:, :, j], axis=1).max()
                 / np.linalg.norm(phi[:, :, j], axis=1).max() for j in range(phi.shape[-1]))
    assert worst == pytest.approx(direct, rel=1e-9) and worst > 0.02


def test_the_command_line_shows_a_warning_as_one_line(capsys):
    _show_warning(UserWarning("a fit is coarse"), UserWarning, "x.py", 3)
    assert capsys.readouterr().err == "ffrmbs: warning: a fit is coarse\n"
