"""Neutral NURBS contours on FFR and rigid bodies (issue 5), each field against an
independent oracle: nodal values, rigid-body kinematics, finite differences in time and
in u, per-step re-interpolation with the reference basis, geomdl, convexity of the box."""

import numpy as np
import pytest

from contours import (Contour1sNeutralFFR, Contour1sNeutralRigid, Contour2sNeutralFFR, Contour2sNeutralRigid)
from contours.neutral import _kernels as K
from contours.nurbs import SurfaceInterpolation
from contours.nurbs.basis import curve_point, surface_point
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, RigidBody
from mbs.bodies.rotations import quat_from_rotvec, quat_to_matrix
from preprocess import Material, box, build_body
from validation.bench.common import moving_state

L, H, W = 0.25, 0.05, 0.05


@pytest.fixture(scope="module")
def beam_data(thesis_beam_data):
    return thesis_beam_data


@pytest.fixture(scope="module")
def beam(beam_data):
    return FlexibleBodyFFR(beam_data, modes=12)


@pytest.fixture(scope="module")
def top(beam):
    return Contour2sNeutralFFR(beam, "y1")


def nodal_positions(body, q, nodes):
    return body.node_positions(q, nodes.ravel()).reshape(nodes.shape + (3,))


def test_interpolation_reproduces_the_nodal_positions_and_velocities(beam, top):
    q, u = moving_state(beam, np.random.default_rng(0))
    top.update(q, u)
    r_nodes = nodal_positions(beam, q, top.nodes)
    v_nodes = np.array([beam.node(j).velocity(q, u) for j in top.nodes.ravel()]).reshape(r_nodes.shape)
    te, tx = top.space.eta.interp.params, top.space.xi.interp.params
    point = top.new_point()
    for i, eta in enumerate(te):
        for j, xi in enumerate(tx):
            top.evaluate(point, eta, xi, velocity=True)
            assert np.allclose(point.r, r_nodes[i, j], rtol=0, atol=1e-12)
            assert np.allclose(point.v, v_nodes[i, j], rtol=0, atol=1e-11 * np.abs(v_nodes).max())


def test_linear_update_equals_per_step_interpolation_of_the_nodal_fields(beam, top):
    """ū = ū0 + Φ q_f from control points interpolated once equals re-interpolating the
    nodal ū (and r) at this step, evaluated with the plain Cox–de Boor reference."""
    rng = np.random.default_rng(1)
    q, u = moving_state(beam, rng, deform=5e-3)
    top.update(q, u)
    grid = beam.data.u0[top.nodes]
    interp = SurfaceInterpolation.from_grid(grid, (3, 3), (False, False))
    ub_nodes = grid + beam.phi_nodes[top.nodes] @ q[7:]
    P_ub = interp.control_points(ub_nodes)
    P_r = interp.control_points(nodal_positions(beam, q, top.nodes))
    e, x = interp.eta, interp.xi
    for eta, xi in rng.uniform(0, 1, size=(20, 2)):
        ref_ub = surface_point(e.knots, e.degree, x.knots, x.degree, P_ub, eta, xi)
        ref_r = surface_point(e.knots, e.degree, x.knots, x.degree, P_r, eta, xi, nd=1)
        assert np.allclose(top.local_position_at(eta, xi), ref_ub, rtol=0, atol=1e-12 * np.abs(grid).max())
        point = top.evaluate(top.new_point(), eta, xi)
        assert np.allclose(point.r, ref_r[0][0], rtol=0, atol=1e-12)
        assert np.allclose(point.t_eta, ref_r[1][0], rtol=1e-12, atol=1e-12)
        assert np.allclose(point.t_xi, ref_r[0][1], rtol=1e-12, atol=1e-12)


def test_position_field_agrees_with_geomdl(beam, top):
    q, u = moving_state(beam, np.random.default_rng(2))
    top.update(q, u)
    surf = top.to_geomdl()
    point = top.new_point()
    for eta, xi in np.random.default_rng(3).uniform(0, 1, size=(10, 2)):
        d = surf.derivatives(eta, xi, order=2)
        top.evaluate(point, eta, xi)
        for row, (a, b) in zip(range(6), [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]):
            assert np.allclose(point.derivs[row], d[a][b], rtol=1e-10, atol=1e-10)


def test_velocity_and_curve_exports_agree_with_geomdl(beam, top):
    q, u = moving_state(beam, np.random.default_rng(18))
    top.update(q, u)
    axis = Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0))
    axis.update(q, u)
    assert np.allclose(top.to_geomdl("velocity").evaluate_single((0.2, 0.9)), top.velocity(0.2, 0.9), atol=1e-12)
    assert np.allclose(axis.to_geomdl().evaluate_single(0.42), axis.position(0.42), atol=1e-14)
    with pytest.raises(ModelError, match="field"):
        top.to_geomdl("speed")


def test_second_derivatives_are_continuous_across_knots(beam, top):
    q, u = moving_state(beam, np.random.default_rng(4), deform=5e-3)
    top.update(q, u)
    knots = top.space.eta.knots
    interior = np.unique(knots[(knots > 0) & (knots < 1)])
    point = top.new_point()
    eps = 1e-10
    scale = max(np.abs(top.evaluate(point, k, 0.37).derivs[3]).max() for k in interior)
    for k in interior:
        left = top.evaluate(point, k - eps, 0.37).derivs.copy()
        right = top.evaluate(point, k + eps, 0.37).derivs
        assert np.abs(right[3] - left[3]).max() < 1e-8 * scale
        assert np.abs(right[1] - left[1]).max() < 1e-8 * np.abs(right[1]).max()


def test_rigid_motion_of_the_undeformed_body_moves_the_contour_rigidly(beam, top):
    rng = np.random.default_rng(5)
    top.update(beam.q_init)
    samples = rng.uniform(0, 1, size=(15, 2))
    point = top.new_point()
    ref = [top.evaluate(point, *s).derivs.copy() for s in samples]
    frames = [top.evaluate(point, *s).frame.copy() for s in samples]
    q = beam.q_init.copy()
    q[:3] = R = rng.normal(size=3)
    q[3:7] = quat_from_rotvec(rng.normal(size=3))
    A = quat_to_matrix(q[3:7])
    top.update(q)
    for s, d0, F0 in zip(samples, ref, frames):
        top.evaluate(point, *s)
        assert np.allclose(point.r, R + A @ d0[0], atol=1e-14)
        assert np.allclose(point.derivs[1:], d0[1:] @ A.T, atol=1e-12)
        assert np.allclose(point.frame, A @ F0, atol=1e-12)


def test_velocity_equals_J_T_u_and_the_time_derivative_of_the_position(beam, top):
    rng = np.random.default_rng(6)
    q, u = moving_state(beam, rng)
    top.update(q, u)
    point = top.new_point()
    h = 1e-5
    for eta, xi in rng.uniform(0, 1, size=(8, 2)):
        top.evaluate(point, eta, xi, velocity=True, jacobians=True)
        v = point.v.copy()
        assert np.allclose(point.J_T @ u, v, rtol=1e-12, atol=1e-12 * np.abs(v).max())
        assert np.allclose(point.J_R @ u, beam.angular_velocity(q, u), rtol=1e-12, atol=1e-14)
        r = []
        for s in (h, -h):
            top.update(beam.increment(q, s * u))
            r.append(top.evaluate(point, eta, xi).r.copy())
        top.update(q, u)
        fd = (r[0] - r[1]) / (2 * h)
        assert np.linalg.norm(fd - v) < 1e-7 * np.linalg.norm(v)


def test_J_T_columns_equal_finite_differences_in_u(beam, top):
    """Each column of J_T is ∂r/∂u_i: the position change along q ⊕ ε e_i."""
    q, u = moving_state(beam, np.random.default_rng(7))
    top.update(q, u)
    J = top.J_T(0.31, 0.77)
    eps = 1e-6
    for i in range(beam.nu):
        e = np.zeros(beam.nu)
        e[i] = eps
        top.update(beam.increment(q, e))
        rp = top.position(0.31, 0.77)
        top.update(beam.increment(q, -e))
        rm = top.position(0.31, 0.77)
        assert np.allclose((rp - rm) / (2 * eps), J[:, i], rtol=1e-7, atol=1e-9 * np.abs(J).max())
    top.update(q, u)


@pytest.mark.parametrize("face", ["x0", "x1", "y0", "y1", "z0", "z1"])
def test_normals_are_unit_and_outward_and_frames_right_handed(beam, face):
    """The box is convex: an outward normal points away from its centre; deformed too."""
    contour = Contour2sNeutralFFR(beam, face)
    q, u = moving_state(beam, np.random.default_rng(8), deform=1e-3)
    contour.update(q, u)
    centre = beam.node_positions(q).mean(axis=0)
    point = contour.new_point()
    for eta, xi in np.random.default_rng(9).uniform(0, 1, size=(10, 2)):
        contour.evaluate(point, eta, xi)
        F = point.frame
        assert np.allclose(F.T @ F, np.eye(3), atol=1e-13)
        assert np.isclose(np.linalg.det(F), 1.0, atol=1e-13)
        assert np.allclose(F[:, 0], point.t_eta / np.linalg.norm(point.t_eta), atol=1e-14)
        assert (point.r - centre) @ point.n > 0.4 * min(L, H, W)


def test_closed_surface_around_the_beam_axis(beam):
    """The lateral surface as one contour closed in ξ: the perimeter nodes of each
    cross-section in angular order. Continuous across the seam, outward normals."""
    u0 = beam.data.u0
    lateral = np.unique(np.concatenate([beam.node_group(g) for g in ("y0", "y1", "z0", "z1")]))
    xs = np.unique(np.round(u0[lateral, 0], 12))
    rows = []
    for x in xs:
        ring = lateral[np.isclose(u0[lateral, 0], x)]
        angle = np.arctan2(u0[ring, 2] - W / 2, u0[ring, 1] - H / 2)
        rows.append(ring[np.argsort(angle)])
    contour = Contour2sNeutralFFR(beam, np.array(rows), closed=(False, True))
    q, u = moving_state(beam, np.random.default_rng(10))
    contour.update(q, u)
    point = contour.new_point()
    a = contour.evaluate(point, 0.4, 0.0, velocity=True).derivs.copy()
    b = contour.evaluate(point, 0.4, 1.0, velocity=True).derivs.copy()
    c = contour.evaluate(point, 0.4, 1.0 - 1e-10).derivs.copy()
    assert np.allclose(a, b, atol=1e-13)
    assert np.allclose(a[[0, 1, 2, 5]], c[[0, 1, 2, 5]], rtol=1e-6, atol=1e-8 * np.abs(a).max())
    centre_line = lambda pt: np.array([pt, H / 2, W / 2])  # noqa: E731
    top_ref = contour.evaluate(point, 0.5, 0.3).n
    contour.update(beam.q_init)
    for eta, xi in np.random.default_rng(11).uniform(0, 1, size=(10, 2)):
        contour.evaluate(point, eta, xi)
        radial = point.r - centre_line(point.r[0])
        assert radial @ point.n > 0.5 * np.linalg.norm(radial)
    assert np.isfinite(top_ref).all()


def test_bounding_box_contains_the_contour(beam, top):
    q, u = moving_state(beam, np.random.default_rng(12))
    top.update(q, u)
    lo, hi = top.bounding_box()
    pts = top.sample(30, 12).reshape(-1, 3)
    assert (pts >= lo - 1e-15).all() and (pts <= hi + 1e-15).all()
    mesh = top.to_trimesh(30, 12)
    assert np.allclose(mesh.vertices, pts) and len(mesh.faces) == 2 * 29 * 11
    lo0, hi0 = top.rest_box                    # the body-frame box at rest, grown per mode
    P0 = top.local_position.ctrl0.reshape(-1, 3)
    assert np.array_equal(lo0, P0.min(axis=0)) and np.array_equal(hi0, P0.max(axis=0))
    P = P0 + top.mode_shapes.ctrl.reshape(-1, 3, top.n_modes) @ top.q_f   # control points of ū
    grown = top.mode_box_growth @ np.abs(top.q_f)
    assert (P >= lo0 - grown - 1e-15).all() and (P <= hi0 + grown + 1e-15).all()
    assert np.isclose(P - P0, 0.0).mean() < 0.5                            # q_f moves them


def test_neutral_axis_contour(beam):
    """A 1s contour along the beam's centre line: frame from the reference normal,
    velocity by finite differences, nodes reproduced."""
    axis = Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0))
    assert len(axis.nodes) == 11
    point = axis.evaluate(axis.new_point(), 0.5)
    assert np.allclose(point.frame, np.column_stack([(1, 0, 0), (0, 0, -1), (0, 1, 0)]), atol=1e-12)
    q, u = moving_state(beam, np.random.default_rng(13))
    axis.update(q, u)
    r_nodes = beam.node_positions(q, axis.nodes)
    for t, r in zip(axis.space.eta.interp.params, r_nodes):
        assert np.allclose(axis.position(t), r, atol=1e-12)
    axis.evaluate(point, 0.63, velocity=True, jacobians=True)
    assert np.allclose(point.J_T @ u, point.v, rtol=1e-12, atol=1e-12)
    F = point.frame
    assert np.allclose(F.T @ F, np.eye(3), atol=1e-13) and np.isclose(np.linalg.det(F), 1.0)
    h = 1e-5
    axis.update(beam.increment(q, h * u))
    rp = axis.position(0.63)
    axis.update(beam.increment(q, -h * u))
    rm = axis.position(0.63)
    assert np.linalg.norm((rp - rm) / (2 * h) - point.v) < 1e-7 * np.linalg.norm(point.v)


def test_too_few_nodes_on_the_line_say_so_and_what_to_do(beam):
    """The centre line holds 11 nodes: a degree-10 curve through them builds, a degree-11
    one is refused with the count, the need and the way out (before: the interpolation's
    bare "needs at least 12 points")."""
    assert len(Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0),
                                              degree=10).nodes) == 11
    with pytest.raises(ModelError, match=r"only 11 nodes of .* lie on the line through \(0, 0.025, 0.025\) m along "
                                         r"\(1, 0, 0\), a degree-11 curve needs 12: mesh the part with nodes along"):
        Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0), degree=11)


def test_closed_curve_through_a_ring_of_nodes(beam):
    """The perimeter of the end face x1 as a closed 1s contour: C² across the seam."""
    u0 = beam.data.u0
    ring = beam.node_group("x1")
    ring = ring[(np.isclose(u0[ring, 1], 0) | np.isclose(u0[ring, 1], H) | np.isclose(u0[ring, 2], 0)
                 | np.isclose(u0[ring, 2], W))]
    ring = ring[np.argsort(np.arctan2(u0[ring, 2] - W / 2, u0[ring, 1] - H / 2))]
    curve = Contour1sNeutralFFR(beam, ring, normal=(1, 0, 0), closed=True)
    q, u = moving_state(beam, np.random.default_rng(14))
    curve.update(q, u)
    point = curve.new_point()
    start = curve.evaluate(point, 0.0).derivs.copy()
    end = curve.evaluate(point, 1.0 - 1e-10).derivs
    assert np.allclose(start[[0, 1, 3]], end[[0, 1, 3]], rtol=1e-6, atol=1e-7 * np.abs(start).max())
    for t, r in zip(curve.space.eta.interp.params, beam.node_positions(q, ring)):
        assert np.allclose(curve.position(t), r, atol=1e-12)


def test_rigid_family_plugs_into_the_same_factories():
    """A rigid body's contours: same interface, kinematics v + ω × (r − R)."""
    rng = np.random.default_rng(15)
    body = RigidBody(2.0, np.diag([0.1, 0.2, 0.3]), com=(0.01, 0.0, 0.02))
    eta, xi = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 0.5, 5), indexing="ij")
    grid = np.stack([eta, xi, 0.1 * np.sin(3 * eta) * xi], axis=-1)
    surface = Contour2sNeutralRigid(body, grid)
    curve = Contour1sNeutralRigid(body, grid[:, 2], normal=(0, 0, 1))
    q = body.q_init.copy()
    q[:3] = R = rng.normal(size=3)
    q[3:7] = quat_from_rotvec(rng.normal(size=3))
    u = rng.normal(size=6)
    omega = body.angular_velocity(q, u)
    for contour, args in ((surface, (0.3, 0.7)), (curve, (0.45,))):
        contour.update(q, u)
        point = contour.evaluate(contour.new_point(), *args, velocity=True, jacobians=True)
        assert np.allclose(point.v, u[:3] + np.cross(omega, point.r - R), atol=1e-12)
        assert np.allclose(point.J_T @ u, point.v, atol=1e-12)
    A = quat_to_matrix(q[3:7])
    assert np.allclose(surface.position(0, 0), R + A @ grid[0, 0], atol=1e-14)


def test_frame_kernels_match_the_formulas():
    """eq. 3.27–3.29 written in numpy against the numba kernels."""
    rng = np.random.default_rng(16)
    D = rng.normal(size=(6, 3))
    F = np.zeros((3, 3))
    K.frame_2s(D, -1.0, F)
    n = -np.cross(D[1], D[2])
    n /= np.linalg.norm(n)
    t1 = D[1] / np.linalg.norm(D[1])
    assert np.allclose(F, np.column_stack([t1, np.cross(n, t1), n]), atol=1e-14)
    n_ref = rng.normal(size=3)
    K.frame_1s(D, n_ref, F)
    n = n_ref - (n_ref @ t1) * t1
    n /= np.linalg.norm(n)
    assert np.allclose(F, np.column_stack([t1, np.cross(n, t1), n]), atol=1e-14)


def test_contraction_kernels_match_the_reference_basis(beam, top):
    e = top.space.eta
    P = np.random.default_rng(17).normal(size=(e.n_ctrl, 5))
    out = np.zeros((6, 5))
    for t in (0.0, 0.123, 0.5, 1.0):
        e.locate(t)
        K.contract_curve(e.B, e.span, e.p, P, 6, out)
        ref = curve_point(e.knots, e.p, P, t, nd=2)
        assert np.allclose(out[[0, 1, 3]], ref, atol=1e-12)


def test_bad_input_gives_clear_errors(beam, beam_data):
    with pytest.raises(ModelError, match="group"):
        Contour2sNeutralFFR(beam, "nope")
    with pytest.raises(ModelError, match="sign"):
        Contour2sNeutralFFR(beam, "y1", outward=2)
    with pytest.raises(ModelError, match="normal"):
        Contour1sNeutralFFR(beam, [0, 1, 2, 3], normal=(0, 0, 0))
    contour = Contour2sNeutralFFR(beam, "y1")
    contour.update(beam.q_init)
    with pytest.raises(ModelError, match="velocity"):
        contour.velocity(0.5, 0.5)
    coarse = FlexibleBodyFFR(build_body(box(L, H, W, None, order=1, divisions=(10, 2, 2)),
                                        Material(920.0, 5e7, 0.3), n_modes=2), modes=2)
    with pytest.raises(ModelError, match="at least 4 points"):
        Contour2sNeutralFFR(coarse, "y1")
    assert Contour2sNeutralFFR(coarse, "y1", degree=(3, 2)).nodes.shape == (11, 3)


def test_a_body_with_no_modes_selected_moves_its_contour_rigidly(beam_data):
    body = FlexibleBodyFFR(beam_data, modes=0)
    contour = Contour2sNeutralFFR(body, "y1")
    q, u = body.q_init.copy(), np.random.default_rng(19).normal(size=6)
    contour.update(q, u)
    point = contour.evaluate(contour.new_point(), 0.5, 0.5, velocity=True, jacobians=True)
    assert np.allclose(point.r, [L / 2, H, W / 2], atol=1e-14)
    assert np.allclose(point.v, u[:3] + np.cross(u[3:], point.r), atol=1e-14)


def test_kernels_see_the_knots_as_plain_writable_arrays(beam, top):
    """numba types a read-only array apart from a writable one, so frozen knots handed to
    the kernels compile every kernel taking them a second time (once from the contour's
    own calls, once inside the fused detection): the arrays a space hands the kernels
    have the type of a plain float array, while the interpolation keeps its knots frozen."""
    import numba

    axis = Contour1sNeutralFFR.along_line(beam, (0, H / 2, W / 2), (1, 0, 0), normal=(0, 1, 0))
    plain = numba.typeof(np.zeros(3))
    for space in (top.space, axis.space):
        knots = [a for a in space.geometry if a.dtype == float][:-1]
        assert knots and all(numba.typeof(k) == plain for k in knots)
    assert not top.space.eta.interp.knots.flags.writeable
