"""Global interpolation (contours.nurbs.interpolation) against independent oracles: geomdl's
fitting (A9.1, A9.4) and evaluation, scipy's periodic spline interpolation, the data
themselves, finite differences, and continuity of the polynomial pieces at the knots."""

import numpy as np
import pytest
from geomdl import fitting
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import make_interp_spline

from contours.nurbs import (
    Interpolation1D,
    SurfaceInterpolation,
    curve_derivs,
    ders_basis,
    parameters,
    surface_derivs,
)
from contours.nurbs.geomdl_io import to_geomdl_curve, to_geomdl_surface

LOWER = np.add.outer(np.arange(3), np.arange(3)) <= 2  # surface derivatives a + b <= 2


def wavy_points(rng, k, closed=False):
    """k distinct 3D points on a perturbed circle (closed) or a perturbed helix arc."""
    s = np.arange(k) / k * 2 * np.pi if closed else np.sort(rng.uniform(0, 4, k)) + np.arange(k)
    r = 1.0 + 0.2 * rng.uniform(-1, 1, k)
    if closed:
        return np.c_[r * np.cos(s), r * np.sin(s), 0.1 * rng.normal(size=k)]
    return np.c_[np.cos(s), np.sin(s), 0.3 * s] * r[:, None]


def cylinder_grid(rng, k_eta, k_xi):
    """Grid closed along η (around the axis), open along ξ (along the axis)."""
    phi = 2 * np.pi * np.arange(k_eta) / k_eta
    z = np.linspace(0.0, 2.0, k_xi)
    r = 1.0 + 0.1 * np.sin(3 * phi)[:, None] * np.cos(z)[None, :] + 0.02 * rng.normal(size=(k_eta, k_xi))
    return np.stack([r * np.cos(phi)[:, None], r * np.sin(phi)[:, None], np.broadcast_to(z, r.shape)], axis=-1)


def evaluate(interp, ctrl, t, nd=2, closed=None):
    p = interp.degree
    out = np.empty((nd + 1, ctrl.shape[1]))
    closed = interp.closed if closed is None else closed
    return curve_derivs(interp.knots, p, ctrl, t, nd, closed, np.empty((nd + 1, p + 1)), out)


def piece_derivs(knots, p, ctrl, span, t, nd):
    """Derivatives at t of the polynomial piece of knot span ``span`` (also at its ends)."""
    work = np.empty((nd + 1, p + 1))
    ders_basis(knots, p, span, t, nd, work)
    return work @ ctrl[span - p:span + 1]


def assert_continuous_at_knots(interp, ctrl, order):
    """Derivatives 0..order of adjacent pieces agree at every interior knot (and the seam)."""
    p, u = interp.degree, interp.knots
    for s in range(p + 1, interp.n_ctrl):
        if u[s] == u[s - 1]:
            continue
        left = piece_derivs(u, p, ctrl, s - 1, u[s], order)
        right = piece_derivs(u, p, ctrl, s, u[s], order)
        scale = np.maximum(np.abs(left), np.abs(right)).max(axis=1, keepdims=True)
        assert np.all(np.abs(left - right) <= 1e-8 * scale + 1e-12)
    if interp.closed:  # seam: end of the last span at t = 1 against start of the first at t = 0
        end = piece_derivs(u, p, ctrl, interp.n_ctrl - 1, u[interp.n_ctrl], order)
        start = piece_derivs(u, p, ctrl, p, u[p], order)
        scale = np.maximum(np.abs(end), np.abs(start)).max(axis=1, keepdims=True)
        assert np.all(np.abs(end - start) <= 1e-8 * scale + 1e-12)


@pytest.mark.parametrize("method", ["chord", "centripetal"])
@pytest.mark.parametrize("p,k", [(1, 5), (2, 6), (3, 4), (3, 11), (4, 9)])
def test_open_curve_equals_geomdl(method, p, k):
    rng = np.random.default_rng(p * 100 + k)
    pts = wavy_points(rng, k)
    interp = Interpolation1D.from_points(pts, p, method=method)
    ctrl = interp.control_points(pts)
    ref = fitting.interpolate_curve(pts.tolist(), p, centripetal=method == "centripetal")
    np.testing.assert_allclose(interp.knots, ref.knotvector, atol=1e-12, rtol=0)
    np.testing.assert_allclose(ctrl, np.array(ref.ctrlpts), atol=1e-10, rtol=0)
    assert interp.domain == (0.0, 1.0) and interp.n_ctrl == k
    for t in np.concatenate([rng.uniform(0, 1, 10), interp.params]):
        ours = evaluate(interp, ctrl, t)
        geo = np.array(ref.derivatives(t, 2))
        np.testing.assert_allclose(ours, geo, atol=1e-10 * (1 + np.abs(ours).max()), rtol=0)
    np.testing.assert_allclose([evaluate(interp, ctrl, t)[0] for t in interp.params], pts, atol=1e-12, rtol=0)
    if p >= 2:
        assert_continuous_at_knots(interp, ctrl, p - 1)


def test_open_cubic_is_c2_and_matches_data_with_uneven_spacing():
    rng = np.random.default_rng(3)
    s = np.cumsum(rng.uniform(0.01, 1.0, 15))
    pts = np.c_[s, np.sin(s), np.cos(2 * s)]
    interp = Interpolation1D.from_points(pts)
    ctrl = interp.control_points(pts)
    np.testing.assert_allclose([evaluate(interp, ctrl, t)[0] for t in interp.params], pts, atol=1e-12, rtol=0)
    assert_continuous_at_knots(interp, ctrl, 2)


@pytest.mark.parametrize("p,k", [(1, 3), (2, 3), (2, 8), (3, 4), (3, 9), (4, 7), (5, 12)])
def test_closed_curve_interpolates_is_smooth_and_matches_geomdl(p, k):
    rng = np.random.default_rng(p * 10 + k)
    pts = wavy_points(rng, k, closed=True)
    interp = Interpolation1D.from_points(pts, p, closed=True)
    ctrl = interp.control_points(pts)
    assert interp.n_ctrl == k + p and interp.knots.size == k + 2 * p + 1
    assert interp.domain == (0.0, 1.0)
    np.testing.assert_array_equal(ctrl[k:], ctrl[:p])
    np.testing.assert_allclose([evaluate(interp, ctrl, t)[0] for t in interp.params], pts, atol=1e-12, rtol=0)
    # Q_0 repeats at t = 1 (evaluated without wrapping, on the last span)
    np.testing.assert_allclose(evaluate(interp, ctrl, 1.0, closed=False)[0], pts[0], atol=1e-12)
    assert_continuous_at_knots(interp, ctrl, p - 1)
    curve = to_geomdl_curve(interp.knots, p, ctrl)
    nd = min(p, 2)
    for t in np.concatenate([rng.uniform(0, 1, 10), [0.0, 1.0]]):
        ours = evaluate(interp, ctrl, t, nd, closed=False)
        np.testing.assert_allclose(ours, np.array(curve.derivatives(t, nd)), atol=1e-10 * (1 + np.abs(ours).max()))


@pytest.mark.parametrize("p", [3, 5])
def test_closed_odd_degree_equals_scipy_periodic_spline(p):
    """For odd degree the knots sit at the parameters: the periodic spline interpolant with
    knots at the data sites is unique, so scipy's must be the same curve."""
    rng = np.random.default_rng(p)
    pts = wavy_points(rng, 10, closed=True)
    interp = Interpolation1D.from_points(pts, p, closed=True)
    ctrl = interp.control_points(pts)
    ref = make_interp_spline(np.append(interp.params, 1.0), np.vstack([pts, pts[:1]]), k=p, bc_type="periodic")
    for t in rng.uniform(0, 1, 20):
        ours = evaluate(interp, ctrl, t)
        np.testing.assert_allclose(ours, [ref(t, nu) for nu in range(3)], atol=1e-10 * np.abs(ours).max(), rtol=0)


@pytest.mark.parametrize("p,tol", [(2, 0.1), (3, 1e-2), (4, 1e-3), (5, 1e-4)])
def test_closed_circle_points_give_a_smooth_circle(p, tol):
    """Radius 1, speed 2π (chord parametrization ~ arc length) and curvature 1 everywhere,
    the seam included. Even degrees are looser: their seam knot at 0 replaces the midpoint
    knot, so the spans next to the seam are uneven (see knots.periodic_knots)."""
    k = 24
    phi = 2 * np.pi * np.arange(k) / k
    pts = np.c_[np.cos(phi), np.sin(phi), np.zeros(k)]
    interp = Interpolation1D.from_points(pts, p, closed=True)
    ctrl = interp.control_points(pts)
    for t in np.linspace(0.0, 1.0, 97):
        c, dc, ddc = evaluate(interp, ctrl, t)
        assert abs(np.linalg.norm(c) - 1.0) < 0.01 * tol
        assert abs(np.linalg.norm(dc) / (2 * np.pi) - 1.0) < 0.3 * tol
        kappa = np.linalg.norm(np.cross(dc, ddc)) / np.linalg.norm(dc) ** 3
        assert abs(kappa - 1.0) < tol


def test_open_open_surface_equals_geomdl():
    rng = np.random.default_rng(11)
    ku, kv = 7, 6
    u, v = np.meshgrid(np.linspace(0, 1, ku) ** 1.3, np.linspace(0, 2, kv), indexing="ij")
    grid = np.stack([u + 0.05 * rng.normal(size=u.shape), v, np.sin(2 * u) * np.cos(v)], axis=-1)
    for (pu, pv), centripetal in (((3, 3), False), ((2, 4), True)):
        method = "centripetal" if centripetal else "chord"
        surf = SurfaceInterpolation.from_grid(grid, (pu, pv), method=method)
        ctrl = surf.control_points(grid)
        ref = fitting.interpolate_surface(grid.reshape(-1, 3).tolist(), ku, kv, pu, pv, centripetal=centripetal)
        np.testing.assert_allclose(surf.eta.knots, ref.knotvector_u, atol=1e-12)
        np.testing.assert_allclose(surf.xi.knots, ref.knotvector_v, atol=1e-12)
        np.testing.assert_allclose(ctrl, np.array(ref.ctrlpts).reshape(ku, kv, 3), atol=1e-10, rtol=0)
        for eta, xi in rng.uniform(0, 1, (10, 2)):
            ours = surf_eval(surf, ctrl, eta, xi)
            geo = np.array(ref.derivatives(eta, xi, 2))  # geomdl fills a + b > 2 too
            np.testing.assert_allclose(ours[LOWER], geo[LOWER], atol=1e-10 * np.abs(ours).max())
        vals = np.array([[surf_eval(surf, ctrl, a, b, 0)[0, 0] for b in surf.xi.params] for a in surf.eta.params])
        np.testing.assert_allclose(vals, grid, atol=1e-12, rtol=0)


def surf_eval(surf, ctrl, eta, xi, nd=2, closed=None):
    e, x = surf.eta, surf.xi
    ce, cx = (e.closed, x.closed) if closed is None else closed
    out = np.empty((nd + 1, nd + 1, ctrl.shape[2]))
    return surface_derivs(e.knots, e.degree, x.knots, x.degree, ctrl, eta, xi, nd, ce, cx,
                          np.empty((nd + 1, e.degree + 1)), np.empty((nd + 1, x.degree + 1)), out)


def test_cylinder_surface_interpolates_is_c2_across_seam_and_matches_geomdl():
    rng = np.random.default_rng(5)
    grid = cylinder_grid(rng, 12, 6)
    surf = SurfaceInterpolation.from_grid(grid, 3, closed=(True, False))
    ctrl = surf.control_points(grid)
    assert ctrl.shape == (15, 6, 3)
    np.testing.assert_array_equal(ctrl[12:], ctrl[:3])
    vals = np.array([[surf_eval(surf, ctrl, a, b, 0)[0, 0] for b in surf.xi.params] for a in surf.eta.params])
    np.testing.assert_allclose(vals, grid, atol=1e-12, rtol=0)
    for xi in rng.uniform(0, 1, 5):
        start = surf_eval(surf, ctrl, 0.0, xi, closed=(False, False))
        end = surf_eval(surf, ctrl, 1.0, xi, closed=(False, False))
        np.testing.assert_allclose(end[LOWER], start[LOWER], atol=1e-9 * np.abs(start).max())
    ref = to_geomdl_surface(surf.eta.knots, 3, surf.xi.knots, 3, ctrl)
    for eta, xi in rng.uniform(0, 1, (8, 2)):
        ours = surf_eval(surf, ctrl, eta, xi)
        geo = np.array(ref.derivatives(eta, xi, 2))
        np.testing.assert_allclose(ours[LOWER], geo[LOWER], atol=1e-10 * np.abs(ours).max())
        shifted = surf_eval(surf, ctrl, eta - 2.0, xi)
        np.testing.assert_allclose(shifted, ours, atol=1e-12 * np.abs(ours).max())


def test_surface_derivatives_match_finite_differences():
    rng = np.random.default_rng(8)
    grid = cylinder_grid(rng, 10, 7)
    surf = SurfaceInterpolation.from_grid(grid, (3, 4), closed=(True, False))
    ctrl = surf.control_points(grid)
    h = 1e-5
    for eta, xi in rng.uniform(0.05, 0.95, (6, 2)):
        d = surf_eval(surf, ctrl, eta, xi)
        de = (surf_eval(surf, ctrl, eta + h, xi) - surf_eval(surf, ctrl, eta - h, xi)) / (2 * h)
        dx = (surf_eval(surf, ctrl, eta, xi + h) - surf_eval(surf, ctrl, eta, xi - h)) / (2 * h)
        tol = 1e-6 * np.abs(d).max()
        np.testing.assert_allclose(d[1, 0], de[0, 0], atol=tol)
        np.testing.assert_allclose(d[0, 1], dx[0, 0], atol=tol)
        np.testing.assert_allclose(d[2, 0], de[1, 0], atol=tol)
        np.testing.assert_allclose(d[0, 2], dx[0, 1], atol=tol)
        np.testing.assert_allclose(d[1, 1], de[0, 1], atol=tol)
        np.testing.assert_allclose(d[1, 1], dx[1, 0], atol=tol)


@settings(max_examples=20, deadline=None)
@given(p=st.integers(1, 4), extra=st.integers(0, 5), closed=st.booleans(), n_f=st.integers(1, 4),
       a=st.floats(-3, 3), b=st.floats(-3, 3), seed=st.integers(0, 2**32 - 1))
def test_control_points_are_linear_in_the_data(p, extra, closed, n_f, a, b, seed):
    rng = np.random.default_rng(seed)
    k = p + 1 + extra
    interp = Interpolation1D(parameters(wavy_points(rng, k, closed), closed=closed), p, closed)
    X, Y = rng.normal(size=(2, k, 3, n_f))
    lhs = interp.control_points(a * X + b * Y)
    assert lhs.shape == (interp.n_ctrl, 3, n_f)
    tol = 1e-12 * (1 + np.abs(lhs).max())
    np.testing.assert_allclose(lhs, a * interp.control_points(X) + b * interp.control_points(Y), atol=tol)
    # each trailing column is the interpolation of that column alone
    np.testing.assert_allclose(lhs[:, 1, 0], interp.control_points(a * X[:, 1, 0] + b * Y[:, 1, 0]), atol=tol)


def test_surface_control_points_linear_with_trailing_shape():
    rng = np.random.default_rng(2)
    surf = SurfaceInterpolation.from_grid(cylinder_grid(rng, 8, 5), (3, 2), closed=(True, False))
    X, Y = rng.normal(size=(2, 8, 5, 3, 4))
    lhs = surf.control_points(2.5 * X - 0.5 * Y)
    assert lhs.shape == (11, 5, 3, 4)
    tol = 1e-12 * np.abs(lhs).max()
    np.testing.assert_allclose(lhs, 2.5 * surf.control_points(X) - 0.5 * surf.control_points(Y), atol=tol)
    # the tensor product equals interpolating along ξ first, then η
    R = np.moveaxis(surf.xi.control_points(np.moveaxis(X, 1, 0)), 0, 1)
    np.testing.assert_allclose(surf.control_points(X), surf.eta.control_points(R), atol=tol)


def test_basis_kernels_get_writable_knots(monkeypatch):
    """numba compiles a read-only array apart from a writable one: the interpolation and
    the fit keep their knots frozen but hand the basis kernels writable copies, so
    find_span and ders_basis are compiled once for a scene, not once per array kind."""
    import numba

    from contours.fitting import bspline_fit
    from contours.nurbs import _kernels, interpolation

    seen = []

    def recording(kernel):
        def call(knots, *args):
            seen.append(numba.typeof(knots))
            return kernel(knots, *args)
        return call

    for module in (interpolation, bspline_fit):
        monkeypatch.setattr(module, "find_span", recording(_kernels.find_span))
        monkeypatch.setattr(module, "ders_basis", recording(_kernels.ders_basis))
    interp = Interpolation1D(np.linspace(0.0, 1.0, 7), 3)
    fit = bspline_fit.FitDirection(6, 3)
    fit.basis(np.linspace(0.0, 1.0, 5))
    assert len(seen) == 2 * (7 + 5)
    assert set(seen) == {numba.typeof(np.zeros(3))}
    assert not interp.knots.flags.writeable and not fit.knots.flags.writeable
