"""The compiled contact path against the reference implementations it replaces.

* neutral contours: the span-local numba evaluation (``compiled=True``) against the full
  control-point route of the products (``compiled=False``, the same nodes), at random
  states and parameters, at knots (span boundaries) and the domain ends;
* the search: the Newton kernels against the Python Newton (``compiled=False``): the
  same roots from the same starts, warm and cold, on open and closed directions;
* the kinematics: g_N, frame, rates and W of the point-mass-on-beam contact, open and
  closed (penetrating), compiled against reference;
* locality: with every control point outside the located span poisoned with NaN, update,
  evaluation and search give the same bits;
* the small kernels (box test, contact frame and Jacobian pieces, W assembly) against
  their numpy formulas, the point-mass shortcut of the rigid contours against the frame's
  methods, and a Moreau run of a point mass dropped on a frame-fixed beam.
"""

import numpy as np
import pytest

from contact import (Contact, ContactKinematicsPointContour1s, ContactKinematicsPointContour2s,
                     ContactKinematicsSphereContour2s, UnilateralNewtonImpact)
from contact import _detection_kernels as DK
from contact.search import Contact1sSearch, Contact2sSearch
from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, FlexibleBand, PointContour, SphereContour
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from mbs.bodies.body import Frame
from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix
from validation.bench.common import moving_state

import test_contact_search as search_tests
from test_contact_kinematics import World
from test_contact_search import off_surface

beam = search_tests.beam           # the fixtures of the search tests: a free beam and
contours = search_tests.contours   # its top face, centre line, cylinder, closed ring and tube


def twin(contour):
    """The same neutral FFR contour (nodes, degree, closedness, normal) on the reference route."""
    if contour.dim == 2:
        return Contour2sNeutralFFR(contour.body, contour.nodes, degree=(contour.space.eta.p, contour.space.xi.p),
                                   closed=contour.closed, outward=contour.sign, compiled=False)
    return Contour1sNeutralFFR(contour.body, contour.nodes, contour.normal_ref, degree=contour.space.eta.p,
                               closed=contour.closed[0], compiled=False)


def near_knots(direction, ends):
    """Parameters at, just below and just above the interior knots (span boundaries), and
    with ``ends`` the domain ends."""
    d = direction
    inner = np.unique(d.knots[(d.knots > d.a) & (d.knots < d.b)])
    return np.concatenate([[d.a, d.b] if ends else [], inner, inner - 1e-12, inner + 1e-12])


def parameters(contour, rng, n=12, ends=True):
    """Random (η, ξ) plus pairs at knots of either direction (and at the domain ends); ξ = 0
    on curves."""
    e = contour.space.eta
    if contour.dim == 1:
        etas = np.concatenate([rng.uniform(e.a, e.b, n), near_knots(e, ends)])
        return [(t, 0.0) for t in etas]
    x = contour.space.xi
    pts = [tuple(p) for p in rng.uniform((e.a, x.a), (e.b, x.b), size=(n, 2))]
    pts += [(t, rng.uniform(x.a, x.b)) for t in near_knots(e, ends)]
    pts += [(rng.uniform(e.a, e.b), t) for t in near_knots(x, ends)]
    return pts


def close(a, b, rel=1e-12):
    """a == b to rel × the larger of 1 and max |b|."""
    b = np.asarray(b, dtype=float)
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * max(1.0, np.abs(b).max(initial=0.0)))


def same_point(a, b):
    for name in ("derivs", "frame", "v", "J_T", "J_R"):
        close(getattr(a, name), getattr(b, name))


@pytest.fixture(scope="module")
def world(thesis_beam_data):
    return World(thesis_beam_data)


def set_both(world, extra_contours, q, u):
    """Update the world's contours and ``extra_contours`` (the reference twins) at (q, u)."""
    world.set(q, u)
    for c in extra_contours:
        c.update(q[c.body.q_slice], u[c.body.u_slice])


# --- neutral contours: span-local evaluation against the control-point route -------------

@pytest.mark.parametrize("name", ["top", "axis", "ring", "tube"])
def test_span_local_fields_equal_the_control_point_route(beam, contours, name):
    compiled = contours[name]
    ref = twin(compiled)
    rng = np.random.default_rng(1)
    for seed in range(3):
        q, u = moving_state(beam, np.random.default_rng(seed), 3e-3)
        compiled.update(q, u)
        ref.update(q, u)
        for eta, xi in parameters(compiled, rng):
            a = compiled.evaluate(compiled.new_point(), eta, xi, velocity=True, jacobians=True)
            same_point(a, ref.evaluate(ref.new_point(), eta, xi, velocity=True, jacobians=True))
        close(compiled.local_position_at(0.41, 0.3), ref.local_position_at(0.41, 0.3))
    if compiled.closed[-1]:  # a parameter outside a closed direction wraps alike
        args = (0.3, -0.25) if compiled.dim == 2 else (-0.25,)
        same_point(compiled.evaluate(compiled.new_point(), *args), ref.evaluate(ref.new_point(), *args))


def test_band_on_a_compiled_curve_equals_the_reference(world):
    """The derived contours read ū and Φ rows through local_fields (span-local when compiled)."""
    ref_axis = twin(world.axis)
    band, ref_band = world.band, FlexibleBand(ref_axis, world.band.width, world.band.offset)
    rng = np.random.default_rng(2)
    q, u = world.state(3)
    set_both(world, [ref_axis], q, u)
    for eta, xi in rng.uniform((0, -0.02), (1, 0.02), size=(8, 2)):
        a = band.evaluate(band.new_point(), eta, xi, velocity=True, jacobians=True)
        same_point(a, ref_band.evaluate(ref_band.new_point(), eta, xi, velocity=True, jacobians=True))


def test_bounding_box_contains_the_control_points_and_is_exact_at_rest(beam, contours):
    top = contours["top"]
    ref = twin(top)
    top.update(beam.q_init, beam.u_init)
    ref.update(beam.q_init, beam.u_init)
    close(top.bounding_box(), ref.bounding_box(), 1e-15)
    q, u = moving_state(beam, np.random.default_rng(5), 3e-3)
    top.update(q, u)
    ref.update(q, u)
    out = np.empty((2, 3))
    lo, hi = top.bounding_box(out)
    assert out is top.bounding_box(out)
    P = ref.position_field.rows()
    assert (lo <= P.min(axis=0)).all() and (hi >= P.max(axis=0)).all()
    pts = top.sample(20, 8).reshape(-1, 3)
    assert (pts >= lo).all() and (pts <= hi).all()


# --- locality: the per-step work never touches control points outside the span -----------

@pytest.mark.parametrize("kind", ["2s", "1s"])
def test_far_control_points_poisoned_with_nan_change_nothing(beam, kind):
    """Update, evaluation, Newton and bounding box read only the located span's control
    points: with all others NaN (P_ū0 and P_Φ) they give the same bits as a clean contour.
    And they write none: the products' full control-point arrays (the reference route),
    NaN too, stay untouched."""
    def make():
        if kind == "2s":
            return Contour2sNeutralFFR(beam, "y1")
        return Contour1sNeutralFFR.along_line(beam, (0, 0.025, 0.025), (1, 0, 0), normal=(0, 1, 0))

    clean, poisoned = make(), make()
    eta, xi = 0.37, (0.61 if kind == "2s" else 0.0)
    clean.space.locate(eta, xi)
    keep = [np.arange(d.span - d.p, d.span + 1) for d in ((clean.space.eta,) if kind == "1s"
                                                          else (clean.space.eta, clean.space.xi))]
    far = np.ones(clean.space.ctrl_shape, dtype=bool)
    far[np.ix_(*keep)] = False
    ctrl0, phi = poisoned.kernel_data[-4], poisoned.kernel_data[-3]
    ctrl0[far] = np.nan
    phi[far] = np.nan
    products = (poisoned._local_position, poisoned._position_field, poisoned._velocity_field)
    for product in products:
        product.ctrl[...] = np.nan
    search = Contact2sSearch if kind == "2s" else Contact1sSearch
    searches = [search(c, length_scale=0.25) for c in (clean, poisoned)]   # (no grid sweep for the scale)
    for seed in range(3):
        q, u = moving_state(beam, np.random.default_rng(seed), 3e-3)
        points = []
        for c in (clean, poisoned):
            c.update(q, u)
            points.append(c.evaluate(c.new_point(), eta + 1e-4, xi, velocity=True, jacobians=True))
            assert np.isfinite(c.bounding_box()).all()
        for name in ("derivs", "frame", "v", "J_T"):
            np.testing.assert_array_equal(getattr(points[1], name), getattr(points[0], name))
        target = points[0].r + 1e-3 * points[0].n
        start = (eta - 1e-4, xi) if kind == "2s" else eta - 1e-4
        roots = [s.solve(target, start) for s in searches]
        assert roots[0] is not None and np.array_equal(roots[1], roots[0])
        assert searches[0].coarse_searches == searches[1].coarse_searches == 0
    assert all(np.isnan(p.ctrl).all() for p in products)


# --- the search: Newton kernels against the Python Newton -------------------------------

@pytest.mark.parametrize("name", ["top", "tube", "axis", "ring"])
def test_newton_kernels_follow_the_python_newton(beam, contours, name):
    """Same roots and the same starts (warm, then coarse level) for points off the contour
    at random and at span boundaries. The tolerance is tightened to 1e-13 so that a root's
    last Newton step is below 1e-12: the two agree only to rounding, and at the default
    tolerance one may stop a step before the other. (Feet on an open domain's end are left
    out: there the outcome turns on whether rounding clips an iterate.)"""
    contour = contours[name]
    ref = twin(contour)
    search_class = Contact2sSearch if contour.dim == 2 else Contact1sSearch
    compiled, python = search_class(contour, tol=1e-13), search_class(ref, tol=1e-13, compiled=False)
    assert compiled.compiled and not python.compiled
    rng = np.random.default_rng(7)
    q, u = moving_state(beam, np.random.default_rng(8), 3e-3)
    contour.update(q, u)
    ref.update(q, u)
    pts = parameters(contour, rng, n=6, ends=False)
    for eta, xi in pts[:: max(1, len(pts) // 12)]:
        d = rng.uniform(-2e-3 if name != "tube" else 5e-4, 4e-3)  # inside the tube the nearest root may tie
        r = off_surface(contour, eta, xi, d) if contour.dim == 2 else curve_offset(contour, eta, d, rng)
        for start in (None, (eta + 0.04, xi - 0.03) if contour.dim == 2 else eta + 0.04):
            found = [s.solve(r, start) for s in (compiled, python)]
            assert (found[0] is None) == (found[1] is None)
            if found[0] is not None:
                close(seam_difference(contour, found[0], found[1]), 0.0)
    assert compiled.newton_solves == python.newton_solves and compiled.coarse_searches == python.coarse_searches


def seam_difference(contour, a, b):
    """a − b per surface coordinate, across the seam (modulo the period) of closed ones."""
    diff = np.atleast_1d(np.subtract(a, b))
    domains = [contour.domain] if contour.dim == 1 else contour.domain
    for k, ((lo, hi), closed) in enumerate(zip(domains, contour.closed)):
        if closed:
            diff[k] = (diff[k] + 0.5 * (hi - lo)) % (hi - lo) - 0.5 * (hi - lo)
    return diff


def curve_offset(curve, eta, d, rng):
    """A point at distance ~d from the curve in its normal plane at η."""
    p = curve.evaluate(curve.new_point(), eta)
    return p.r + d * p.n + rng.uniform(-1e-3, 1e-3) * p.t2


def test_newton_kernel_finds_no_point_beyond_an_open_end(world):
    top, ref = world.top, twin(world.top)
    q, u = world.state(9)
    set_both(world, [ref], q, u)
    beyond = off_surface(top, 1.0, 0.5, 0.0) + 0.02 * top.evaluate(top.new_point(), 1.0, 0.5).t1
    searches = Contact2sSearch(top), Contact2sSearch(ref, compiled=False)
    assert all(s.solve(beyond, (0.95, 0.5)) is None for s in searches)
    assert searches[0].newton_iterations == searches[1].newton_iterations > 0


# --- contact kinematics: compiled against reference ------------------------------------

@pytest.mark.parametrize("gap", [2e-3, -5e-4])   # open, closed (penetrating)
@pytest.mark.parametrize("side", ["point", "sphere"])
def test_point_and_sphere_on_the_beam_compiled_equal_reference(world, gap, side):
    top, ref = world.top, twin(world.top)
    if side == "point":
        kin = ContactKinematicsPointContour2s(world.dot, top)
        kin_ref = ContactKinematicsPointContour2s(PointContour(world.mass.point), ref,
                                                  search=Contact2sSearch(ref, compiled=False))
        lift = gap
    else:
        kin = ContactKinematicsSphereContour2s(world.mass_sphere, top)
        kin_ref = ContactKinematicsSphereContour2s(SphereContour(world.mass.point, 0.02), ref,
                                                   search=Contact2sSearch(ref, compiled=False))
        lift = gap + 0.02
    nu = world.system.nu
    for seed, (eta, xi) in enumerate([(0.37, 0.61), (0.2, 0.5), (0.9, 0.25)]):   # (0.2, 0.5): knots of both
        q, u = world.state(20 + seed)
        set_both(world, [ref], q, u)
        foot = top.evaluate(top.new_point(), eta, xi)
        world.place(world.mass, q, foot.r + lift * foot.n)
        set_both(world, [ref, kin_ref.contour1], q, u)
        assert kin.update() and kin_ref.update() and kin.search.compiled
        close(kin.g_N, gap, 1e-9)
        close([kin.point2.eta, kin.point2.xi], [kin_ref.point2.eta, kin_ref.point2.xi])
        for name in ("g_N", "n", "T", "gd_N", "gd_T"):
            close(getattr(kin, name), getattr(kin_ref, name))
        W_N, W_T = kin.W_N(np.empty(nu)), kin.W_T(np.empty((nu, 2)))
        close(W_N, kin_ref.W_N(np.empty(nu)))
        close(W_T, kin_ref.W_T(np.empty((nu, 2))))
        W = np.full((nu, 3), np.nan)
        kin.fill_W(W)
        close(W, np.column_stack([W_N, W_T]), 1e-15)
        wide = np.full((nu, 6), np.nan)                 # the columns 2..4 of a wider W
        kin.fill_W(wide, 2, 3)
        close(wide[:, 2:5], W, 0.0)
        assert np.isnan(wide[:, [0, 1, 5]]).all()


def test_point_on_a_curve_compiled_equals_reference(world):
    axis, ref = world.axis, twin(world.axis)
    kin = ContactKinematicsPointContour1s(world.dot, axis)
    kin_ref = ContactKinematicsPointContour1s(PointContour(world.mass.point), ref,
                                              search=Contact1sSearch(ref, compiled=False))
    q, u = world.state(30)
    set_both(world, [ref], q, u)
    foot = axis.evaluate(axis.new_point(), 0.42)
    world.place(world.mass, q, foot.r + 0.03 * foot.n + 0.004 * foot.t2)
    set_both(world, [ref, kin_ref.contour1], q, u)
    assert kin.update() and kin_ref.update()
    close(kin.point2.eta, kin_ref.point2.eta)
    for name in ("g_N", "n", "T", "gd_N", "gd_T", "w_N1", "w_N2", "w_T1", "w_T2"):
        close(getattr(kin, name), getattr(kin_ref, name))


def test_moreau_run_of_a_mass_dropped_on_the_beam_equals_the_reference(thesis_beam_data):
    """The whole step (contour update, broad phase, search, W, impact) along 600 steps
    of which ~350 in contact: compiled and reference trajectories agree to rounding."""
    def run(compiled):
        system = System()
        body = system.add(FlexibleBodyFFR(thesis_beam_data, modes=6, frame=PrescribedFrameMotion.fixed()))
        mass = system.add(PointMass(0.05, position=(0.2, 0.0505, 0.02), velocity=(0.0, -0.2, 0.0)))
        top = Contour2sNeutralFFR(body, "y1", compiled=compiled)
        kin = ContactKinematicsPointContour2s(PointContour(mass.point), top,
                                              search=Contact2sSearch(top, compiled=compiled))
        system.add(Contact(kin, UnilateralNewtonImpact(0.0)))
        return system.simulate(6e-3, 1e-5, integrator="moreau")

    res, ref = run(True), run(False)
    assert res.stats["closed_contacts"] == ref.stats["closed_contacts"] > 100
    close(res.q[-1], ref.q[-1], 1e-10)
    close(res.u[-1], ref.u[-1], 1e-10)


# --- small kernels and the point-mass shortcut ------------------------------------------

def test_box_overlap_kernel_matches_the_numpy_formula():
    rng = np.random.default_rng(3)
    for _ in range(300):
        b1, b2 = np.sort(rng.normal(size=(2, 2, 3)), axis=1)
        if rng.random() < 0.2:
            b2[0, rng.integers(3)], b2[1, rng.integers(3)] = -np.inf, np.inf
        m = rng.uniform(0.0, 0.3)
        ref = bool(np.all(b1[0] - 2 * m <= b2[1]) and np.all(b2[0] - 2 * m <= b1[1]))
        assert DK.boxes_overlap(b1, b2, m) == ref


def test_frame_and_jacobian_kernel_matches_the_numpy_formulas():
    """eq. 3.4, 3.8: n, T from contour 2's frame, ġ = (n, T)ᵀ (v1 − v2), w = ±Jᵀ (n, T)."""
    rng = np.random.default_rng(4)
    F = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    v1, v2, J1, J2 = rng.normal(size=3), rng.normal(size=3), rng.normal(size=(3, 4)), rng.normal(size=(3, 7))
    n, T, gd_T = np.empty(3), np.empty((3, 2)), np.empty(2)
    w = [np.empty(4), np.empty(7), np.empty((4, 2)), np.empty((7, 2))]
    gd_N = DK.frame_rates_jacobians(F, v1, v2, J1, J2, True, True, n, T, gd_T, *w)
    close(n, F[:, 2], 1e-15)
    close(T, F[:, :2], 1e-15)
    close(gd_N, F[:, 2] @ (v1 - v2))
    close(gd_T, F[:, :2].T @ (v1 - v2))
    for got, expected in zip(w, (J1.T @ n, -J2.T @ n, J1.T @ T, -J2.T @ T)):
        close(got, expected)
    c, D = rng.normal(size=3), rng.normal(size=(6, 3))
    close(DK.normal_gap(F, c, D, 0.1), F[:, 2] @ (c - D[0]) - 0.1)


def test_point_mass_shortcut_equals_the_frame_methods():
    """A point mass's frame read without its (allocating) methods: r, A, v, ω, J_T, J_R
    as the frame gives them, for a point and a sphere at an offset with an orientation."""
    mass = PointMass(0.3, position=(0.1, 0.2, 0.3))
    frame = Frame(mass, (0.01, -0.02, 0.03), orientation=quat_to_matrix(quat_from_rotvec([0.3, -0.2, 0.5])))
    rng = np.random.default_rng(6)
    for contour in (PointContour(frame), SphereContour(frame, 0.02)):
        assert contour._on_point_mass
        q, u = rng.normal(size=3), rng.normal(size=3)
        contour.update(q, u)
        p = contour.evaluate(contour.new_point(), 0.4, 0.2, velocity=True, jacobians=True)
        d = 0.02 * p.n if isinstance(contour, SphereContour) else np.zeros(3)
        close(p.r, frame.position(q) + d, 1e-15)
        close(p.v, frame.velocity(q, u) + np.cross(frame.angular_velocity(q, u), d), 1e-15)
        close(p.J_T, frame.J_T(q), 1e-15)
        close(p.J_R, frame.J_R(q), 1e-15)
        if isinstance(contour, PointContour):
            close(p.frame, frame.orientation(q), 1e-15)
        contour.update(q + 1.0)               # without u: the position moves, the velocity stays
        p2 = contour.evaluate(contour.new_point(), 0.4, 0.2, velocity=True)
        close(p2.r, p.r + 1.0, 1e-15)
        close(p2.v, p.v, 1e-15)
