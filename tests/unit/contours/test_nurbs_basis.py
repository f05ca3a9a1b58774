"""B-spline basis and evaluation kernels (contours.nurbs._kernels) against independent oracles:
the literal Cox–de Boor recursion (contours.nurbs.basis), geomdl's A2.1/A2.3, finite
differences, and partition of unity."""

import numpy as np
import pytest
from geomdl import helpers
from hypothesis import given, settings
from hypothesis import strategies as st

from contours.nurbs import (
    Interpolation1D,
    curve_derivs,
    ders_basis,
    find_span,
    parameters,
    surface_derivs,
    wrap_parameter,
)
from contours.nurbs.basis import basis_functions, curve_point, surface_point
from ffrmbs.errors import ModelError


def random_knots(rng, p, n_ctrl, clamped=True):
    """Knot vector of n_ctrl + p + 1 entries, interior multiplicities up to p."""
    n_inner = n_ctrl - p - 1 if clamped else n_ctrl + p + 1
    inner = np.sort(rng.uniform(0.0, 1.0, n_inner))
    mult = min(p, 3, n_inner)  # one knot repeated, multiplicity <= p
    if n_inner:
        inner[1:mult] = inner[0]
    if not clamped:
        return inner
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)])


def sample_params(rng, knots, p, n_ctrl):
    """Random parameters, every distinct knot in the domain, and both domain ends."""
    a, b = knots[p], knots[n_ctrl]
    at_knots = np.unique(knots[(knots >= a) & (knots <= b)])
    return np.concatenate([rng.uniform(a, b, 8), at_knots, [a, b]])


def kernel_ders(knots, p, n_ctrl, t, nd):
    span = find_span(knots, p, n_ctrl, t)
    out = np.empty((nd + 1, p + 1))
    ders_basis(knots, p, span, t, nd, out)
    return span, out


@pytest.mark.parametrize("p", [1, 2, 3, 4])
@pytest.mark.parametrize("clamped", [True, False])
def test_ders_basis_matches_cox_de_boor_and_geomdl(p, clamped):
    rng = np.random.default_rng(10 * p + clamped)
    for n_ctrl in (p + 1, p + 4, p + 9):
        knots = random_knots(rng, p, n_ctrl, clamped)
        kv = knots.tolist()
        for t in sample_params(rng, knots, p, n_ctrl):
            span, out = kernel_ders(knots, p, n_ctrl, t, p + 1)
            assert span == helpers.find_span_linear(p, kv, n_ctrl, t)
            ref = basis_functions(knots, p, t, nd=p + 1)
            scale = np.abs(ref).max(axis=1, keepdims=True) + 1.0
            np.testing.assert_allclose(out / scale, ref[:, span - p:span + 1] / scale, atol=1e-12, rtol=0)
            # all other basis functions vanish at t
            outside = np.delete(ref, np.arange(span - p, span + 1), axis=1)
            assert np.all(outside == 0.0)
            geo = np.array(helpers.basis_function_ders(p, kv, span, t, p))
            np.testing.assert_allclose(out[: p + 1] / scale[: p + 1], geo / scale[: p + 1], atol=1e-12, rtol=0)
            assert np.all(out[p + 1] == 0.0)
            geo0 = np.array(helpers.basis_function(p, kv, span, t))
            np.testing.assert_allclose(out[0], geo0, atol=1e-13, rtol=0)


@pytest.mark.parametrize("p", [1, 2, 3, 4])
def test_partition_of_unity(p):
    rng = np.random.default_rng(p)
    knots = random_knots(rng, p, p + 6)
    for t in sample_params(rng, knots, p, p + 6):
        _, out = kernel_ders(knots, p, p + 6, t, p)
        assert abs(out[0].sum() - 1.0) < 1e-14
        assert np.all(out[0] >= 0.0)
        np.testing.assert_allclose(out[1:].sum(axis=1), 0.0, atol=1e-9 * np.abs(out).max())


@pytest.mark.parametrize("p", [2, 3, 4])
def test_derivatives_match_finite_differences(p):
    rng = np.random.default_rng(100 + p)
    n_ctrl = p + 5
    knots = random_knots(rng, p, n_ctrl)
    h = 1e-6
    distinct = np.unique(knots)
    for t in rng.uniform(0.0, 1.0, 20):
        if np.min(np.abs(distinct - t)) < 10 * h:
            continue
        ref = basis_functions(knots, p, t, nd=p)
        plus = basis_functions(knots, p, t + h, nd=p)
        minus = basis_functions(knots, p, t - h, nd=p)
        fd = (plus[:-1] - minus[:-1]) / (2 * h)
        np.testing.assert_allclose(ref[1:], fd, atol=1e-5 * (np.abs(ref).max() + 1.0), rtol=0)


def test_find_span_ends_and_wrap_parameter():
    knots = np.array([0, 0, 0, 0.3, 0.3, 0.7, 1, 1, 1.0])
    p, n = 2, 6
    assert find_span(knots, p, n, 0.0) == 2
    assert find_span(knots, p, n, 0.3) == 4
    assert find_span(knots, p, n, 0.69) == 4
    assert find_span(knots, p, n, 1.0) == 5
    assert find_span(knots, p, n, 1.5) == 5
    assert find_span(knots, p, n, -0.5) == 2
    assert wrap_parameter(1.25, 0.0, 1.0, True) == pytest.approx(0.25, abs=1e-15)
    assert wrap_parameter(-0.25, 0.0, 1.0, True) == pytest.approx(0.75, abs=1e-15)
    assert wrap_parameter(3.5, 1.0, 3.0, True) == pytest.approx(1.5, abs=1e-15)
    assert wrap_parameter(1.25, 0.0, 1.0, False) == 1.0
    assert wrap_parameter(-0.25, 0.0, 1.0, False) == 0.0


@settings(max_examples=30, deadline=None)
@given(p=st.integers(1, 4), extra=st.integers(0, 6), m=st.integers(1, 6), seed=st.integers(0, 2**32 - 1))
def test_curve_derivs_matches_reference(p, extra, m, seed):
    rng = np.random.default_rng(seed)
    n_ctrl = p + 1 + extra
    knots = random_knots(rng, p, n_ctrl)
    ctrl = rng.normal(size=(n_ctrl, m))
    nd = 3
    work = np.empty((nd + 1, p + 1))
    out = np.empty((nd + 1, m))
    for t in sample_params(rng, knots, p, n_ctrl):
        curve_derivs(knots, p, ctrl, t, nd, False, work, out)
        ref = curve_point(knots, p, ctrl, t, nd)
        np.testing.assert_allclose(out, ref, atol=1e-11 * (np.abs(ref).max() + 1.0), rtol=0)


def test_curve_derivs_wraps_closed_and_clips_open():
    rng = np.random.default_rng(7)
    pts = rng.normal(size=(7, 3))
    closed = Interpolation1D.from_points(pts, 3, closed=True)
    ctrl = closed.control_points(pts)
    work, out, ref = np.empty((3, 4)), np.empty((3, 3)), np.empty((3, 3))
    for t in (0.1, 0.55, 0.9):
        curve_derivs(closed.knots, 3, ctrl, t, 2, True, work, ref)
        for shift in (-2.0, -1.0, 1.0, 3.0):
            curve_derivs(closed.knots, 3, ctrl, t + shift, 2, True, work, out)
            np.testing.assert_allclose(out, ref, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_allclose(ref, curve_point(closed.knots, 3, ctrl, 0.9, 2), atol=1e-12 * np.abs(ref).max())
    opened = Interpolation1D.from_points(pts, 3)
    ctrl = opened.control_points(pts)
    curve_derivs(opened.knots, 3, ctrl, 1.7, 0, False, work, out)
    np.testing.assert_allclose(out[0], pts[-1], atol=1e-12)


@pytest.mark.parametrize("p_eta,p_xi", [(1, 2), (3, 3), (2, 4)])
def test_surface_derivs_matches_reference(p_eta, p_xi):
    rng = np.random.default_rng(p_eta * 10 + p_xi)
    n_eta, n_xi, m, nd = p_eta + 4, p_xi + 3, 5, 3
    ke = random_knots(rng, p_eta, n_eta)
    kx = random_knots(rng, p_xi, n_xi)
    ctrl = rng.normal(size=(n_eta, n_xi, m))
    we, wx = np.empty((nd + 1, p_eta + 1)), np.empty((nd + 1, p_xi + 1))
    out = np.empty((nd + 1, nd + 1, m))
    etas = sample_params(rng, ke, p_eta, n_eta)
    xis = sample_params(rng, kx, p_xi, n_xi)
    for eta, xi in zip(etas, rng.permutation(np.resize(xis, etas.size))):
        surface_derivs(ke, p_eta, kx, p_xi, ctrl, eta, xi, nd, False, False, we, wx, out)
        ref = surface_point(ke, p_eta, kx, p_xi, ctrl, eta, xi, nd)
        lower = np.add.outer(np.arange(nd + 1), np.arange(nd + 1)) <= nd
        np.testing.assert_allclose(out[lower], ref[lower], atol=1e-11 * (np.abs(ref).max() + 1.0), rtol=0)
        assert np.all(out[~lower] == 0.0)


def test_bad_input_raises_model_error():
    good = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    with pytest.raises(ModelError, match="coincide"):
        parameters(np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0]]))
    with pytest.raises(ModelError, match="coincide"):  # closing chord of zero length
        parameters(np.vstack([good, good[:1]]), closed=True)
    with pytest.raises(ModelError, match="NaN"):
        parameters(np.array([[0.0, 0], [np.nan, 1]]))
    with pytest.raises(ModelError, match="k >= 2"):
        parameters(np.array([[0.0, 0, 0]]))
    with pytest.raises(ModelError, match="method"):
        parameters(good, method="uniform")
    with pytest.raises(ModelError, match="at least 4 points"):
        Interpolation1D.from_points(good[:3], degree=3)
    with pytest.raises(ModelError, match="at least 4 points"):
        Interpolation1D.from_points(good[:3], degree=3, closed=True)
    with pytest.raises(ModelError, match="degree"):
        Interpolation1D.from_points(good, degree=0)
    with pytest.raises(ModelError, match="strictly increasing"):
        Interpolation1D(np.array([0.0, 0.5, 0.5, 0.7, 1.0]))
    with pytest.raises(ModelError, match="shape"):
        Interpolation1D.from_points(good, degree=2).control_points(np.zeros((3, 3)))
