"""Structural claims behind the contour_fit_cost case (no timing here): a fitted contour's
compiled, span-local evaluation equals the reference route over all control points, and
the arrays the per-step kernels read scale with the control points, not with the patch's
nodes."""

import numpy as np
import pytest

from contours import Contour2sNeutralFFR
from contours.base import ContourPoint
from mbs import FlexibleBodyFFR
from preprocess import Material, build_body
from preprocess.geometry import box
from validation.bench.common import moving_state

STEEL = Material(7800.0, 2.1e11, 0.3)
N_MODES = 4


def plate(h, order):
    """A free FFR body of the plate 0.2 x 0.1 x 0.005 m (unstructured, clamped modes)."""
    return FlexibleBodyFFR(build_body(box(0.2, 0.1, 0.005, h, order=order), STEEL, N_MODES, clamp="x0"), N_MODES)


def test_compiled_evaluation_equals_the_reference_route():
    body = plate(0.02, 2)
    compiled = Contour2sNeutralFFR(body, "z1")
    reference = Contour2sNeutralFFR(body, "z1", compiled=False)
    assert compiled.fit is not None and reference.fit is not None
    rng = np.random.default_rng(3)
    a, b = ContourPoint(body.nu), ContourPoint(body.nu)
    for _ in range(5):
        q, u = moving_state(body, rng)
        compiled.update(q, u, 0.0)
        reference.update(q, u, 0.0)
        for eta, xi in rng.uniform(size=(20, 2)):
            compiled.evaluate(a, eta, xi, velocity=True, jacobians=True)
            reference.evaluate(b, eta, xi, velocity=True, jacobians=True)
            scale = max(1.0, np.abs(b.buffer).max())
            assert np.abs(a.buffer - b.buffer).max() < 1e-12 * scale


@pytest.mark.parametrize("control_points", [(8, 6), (11, 5)])
def test_kernel_arrays_follow_the_control_points_not_the_nodes(control_points):
    """Same control-point counts on two meshes of very different node counts: the same
    kernel array sizes (P_ū0 (n_η, n_ξ, 3), P_Φ (n_η, n_ξ, 3 n_f))."""
    shapes, nodes = set(), []
    for h, order in ((0.02, 1), (0.01, 2)):
        body = plate(h, order)
        contour = Contour2sNeutralFFR(body, "z1", control_points=control_points)
        ctrl0, phi = contour.kernel_data[-4], contour.kernel_data[-3]
        shapes.add((ctrl0.shape, phi.shape))
        nodes.append(contour.patch.k)
    assert shapes == {(control_points + (3,), control_points + (3 * N_MODES,))}
    assert nodes[1] > 8 * nodes[0]


def test_default_control_points_are_fewer_than_patch_nodes():
    """The default fit (knot spans of about two node spacings) keeps the per-step arrays
    smaller than the nodal data they replace."""
    body = plate(0.01, 2)
    contour = Contour2sNeutralFFR(body, "z1")
    ctrl0, phi = contour.kernel_data[-4], contour.kernel_data[-3]
    fit = contour.fit
    assert ctrl0.shape == (fit.eta.n_ctrl, fit.xi.n_ctrl, 3) and phi.shape == ctrl0.shape[:2] + (3 * N_MODES,)
    assert fit.eta.n_unique * fit.xi.n_unique < 0.5 * contour.patch.k


@pytest.mark.slow
def test_cost_case_rows(monkeypatch):
    """The quick run without the 10 mm tet10 mesh (the 20 mm tet10 one takes the same code
    path) and with one short timing batch per operation (its timings are not checked)."""
    from case_rows import quick_rows_without_files
    from validation.cases import contour_fit_cost as case

    monkeypatch.setitem(case.MESHES, True, tuple(m for m in case.MESHES[True] if m != (0.01, 2)))
    monkeypatch.setitem(case.REPEATS, True, 1)
    monkeypatch.setattr(case, "MIN_BATCH_S", 1e-3)
    rows = quick_rows_without_files([case])[case.NAME]
    by_nodes = {}
    for row in rows:
        by_nodes.setdefault(row["config"]["patch_nodes"], {})[row["operation"]] = row
    assert len(by_nodes) == len(case.MESHES[True]) and max(by_nodes) > 1500 and min(by_nodes) < 150
    for ops in by_nodes.values():
        assert set(ops) == set(case.OPERATIONS) | {"fit"}
        assert all(np.isnan(ops[name]["error"]) for name in case.OPERATIONS)
        assert 0 < ops["fit"]["error"] < 0.05
        fit = ops["fit"]                  # an open patch: no wrapped control points
        assert fit["ctrl0_size"] == 3 * fit["control_points"]
        assert fit["phi_size"] == 3 * case.N_MODES * fit["control_points"]
