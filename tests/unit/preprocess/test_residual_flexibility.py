"""Residual flexibility of contours (preprocess.residual, contours.residual) against the
full FE static solution.

Oracle: for a force f at a contour point, the full FE model's static deflection of that
point is Tₚᵀ G Tₚ f with Tₚ the point's nodal load pattern and G = K_ff⁻¹ (clamped, a
direct sparse solve) or Σ_elastic φ φᵀ/ω² over ALL elastic modes of a dense eigensolve
(free-free, inertia relief). The reduced model's is Tₚᵀ Φ K_n⁻¹ Φᵀ Tₚ f plus the residual
compliance c f; they must agree to rounding for n = 5 … 50 modes, at nodes and between
them, on 2s (interpolated and fitted), 1s and band contours. The load pattern itself is
checked against the contour's own evaluation of a modal displacement.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, FlexibleBand, FlexibleCylinder
from contours._offset_kernels import offsets
from contours.derived import offset_frame
from contours.neutral import _kernels as NK
from contours._residual_kernels import compliance_between, compliance_between_reference
from contours.residual import residual_compliance, residual_compliances, transfer_matrix
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, PrescribedFrameMotion
from preprocess import Material, build_body
from preprocess.geometry import box
from preprocess.modes import all_modes, clamped_dofs
from preprocess import residual
from preprocess.residual import StaticFlexibility, clamped_nodes_of

RTOL = 1e-8


@pytest.fixture(scope="module")
def clamped_data():
    """A clamped tet4 beam 100 x 20 x 20 mm (x = 0 clamped) with all its modes."""
    mesh = box(0.1, 0.02, 0.02, None, order=1, divisions=(6, 3, 4))
    data = build_body(mesh, Material(920.0, 5e7, 0.3), n_modes=1, clamp="x0")
    data.eigenvalues, data.phi = all_modes(data.stiffness, data.masses, data.node_groups["x0"])
    return data


@pytest.fixture(scope="module")
def free_data():
    """A free-free tet4 block 60 x 20 x 20 mm with all its elastic modes."""
    mesh = box(0.06, 0.02, 0.02, None, order=1, divisions=(4, 3, 4))
    data = build_body(mesh, Material(920.0, 5e7, 0.3), n_modes=1)
    data.eigenvalues, data.phi = all_modes(data.stiffness, data.masses, u0=data.u0)
    return data


def full_flexibility(data):
    """G (3N, 3N) of the full model by an independent route: K_ff⁻¹ by a sparse solve
    (clamped) or Σ φ φᵀ/ω² over all elastic modes (free-free)."""
    clamped = clamped_nodes_of(data)
    if clamped.size:
        K = data.stiffness.tocsc()
        free = ~clamped_dofs(K.shape[0], clamped)
        G = np.zeros(K.shape)
        G[np.ix_(free, free)] = sla.splu(K[free][:, free].tocsc()).solve(np.eye(free.sum()))
        return G
    return data.phi @ np.diag(1.0 / data.eigenvalues) @ data.phi.T


def contours_of(beam, kinds):
    """The contours of the top face y = 0.02 of ``beam``, by kind."""
    made = {}
    if "2s" in kinds:
        made["2s"] = Contour2sNeutralFFR(beam, "y1")
    if "fitted" in kinds:
        made["fitted"] = Contour2sNeutralFFR(beam, "y1", control_points=(5, 4))
    if "1s" in kinds or "band" in kinds:
        axis = Contour1sNeutralFFR.along_line(beam, (0.0, 0.02, 0.01), (1, 0, 0), normal=(0, 1, 0), degree=4)
        made["1s"] = axis
        made["band"] = FlexibleBand(axis, width=0.02)
    return made


def points_of(contour):
    """(η, ξ) of nodes (the interpolation's parameters) and of points between them."""
    space = contour.neutral.space if hasattr(contour, "neutral") else contour.space
    (a, b) = space.domain if space.dim == 1 else space.domain[0]
    pts = [(a + 0.37 * (b - a), 0.0), (a + 0.91 * (b - a), 0.0)]
    if space.dim == 2:
        (c, d) = space.domain[1]
        pts = [(e, c + f * (d - c)) for (e, _), f in zip(pts, (0.23, 0.71))]
    interp = space.eta.interp
    if hasattr(interp, "params"):           # an interpolated direction: a node parameter
        node = float(interp.params[len(interp.params) // 2])
        pts.append((node, 0.0 if space.dim == 1 else float(space.xi.interp.params[1])))
    if contour.name == "band":
        pts = [(e, 0.004) for e, _ in pts]
    return pts


def point_pattern(rc, T, eta, xi):
    """Tₚ (3N, 3): the nodal loads of a unit force along each body axis at (η, ξ)."""
    blocks, index = np.zeros((16, 3, 3)), np.zeros(16, dtype=np.int64)
    k = rc.weights(eta, xi, blocks, index)
    return sum(T[:, 3 * index[i]:3 * index[i] + 3] @ blocks[i].T for i in range(k))


@pytest.mark.filterwarnings("ignore:neutral 2s")      # the coarse fit's report: not what is tested here
@pytest.mark.parametrize("support", ["clamped", "free"])
@pytest.mark.parametrize("n", [5, 10, 20, 50])
def test_static_deflection_equals_full_fe(support, n, clamped_data, free_data):
    data = clamped_data if support == "clamped" else free_data
    frame = PrescribedFrameMotion.fixed() if support == "clamped" else "free"
    beam = FlexibleBodyFFR(data, modes=n, frame=frame)
    G = full_flexibility(data)
    kinds = ("2s", "fitted", "1s", "band") if support == "clamped" else ("2s", "1s", "band")
    for name, contour in contours_of(beam, kinds).items():
        rc = residual_compliance(contour)
        T = transfer_matrix(contour).toarray()
        for eta, xi in points_of(contour):
            Tp = point_pattern(rc, T, eta, xi)
            full = Tp.T @ G @ Tp
            PT = beam.phi.T @ Tp
            modal = PT.T @ np.linalg.solve(beam.K_ff, PT)
            err = np.abs(modal + rc.at(eta, xi) - full).max() / np.abs(full).max()
            assert err < RTOL, (name, eta, xi, err)
            assert np.abs(rc.at(eta, xi)).max() > 1e-3 * np.abs(full).max()     # a correction that matters


def test_cross_compliance_between_contours_and_points(clamped_data):
    """c(a, b) of two contours of one body (built together) and of two points of one
    contour equals the full model's Tₐᵀ G_res T_b; it is symmetric: c(a, b) = c(b, a)ᵀ."""
    beam = FlexibleBodyFFR(clamped_data, modes=10, frame=PrescribedFrameMotion.fixed())
    made = contours_of(beam, ("2s", "1s"))
    top, axis = residual_compliances([made["2s"], made["1s"]])
    G = full_flexibility(clamped_data)
    G_res = G - beam.phi @ np.linalg.solve(beam.K_ff, beam.phi.T)
    T = np.hstack([transfer_matrix(made["2s"]).toarray(), transfer_matrix(made["1s"]).toarray()])
    Ta, Tb = point_pattern(top, T, 0.08, 0.007), point_pattern(axis, T, 0.03, 0.0)
    c_ab = top.between(0.08, 0.007, 0.03, 0.0, other=axis)
    assert np.allclose(c_ab, Ta.T @ G_res @ Tb, rtol=0, atol=RTOL * np.abs(c_ab).max())
    assert np.allclose(c_ab, axis.between(0.03, 0.0, 0.08, 0.007, other=top).T, rtol=1e-12, atol=0)
    with pytest.raises(ModelError, match="cross-compliance"):
        residual_compliance(made["2s"]).between(0.08, 0.007, 0.03, 0.0, other=residual_compliance(made["1s"]))


@pytest.mark.parametrize("support", ["clamped", "free"])
@pytest.mark.parametrize("n", [5, 20])
def test_a_point_on_a_node_sees_the_full_fe_deflection_of_its_node(support, n, clamped_data, free_data):
    """Points and a sphere on node frames (contours.residual.NodeCompliance), built together
    with the top face's 2s contour: the modes' static deflection of node a under a force
    at node b plus c(a, b) is the full model's G[a, b]; between a node and the 2s contour's
    point (η, ξ), Tₐᵀ G T_b; c(a, b) = c(b, a)ᵀ."""
    from contours import PointContour, SphereContour

    data = clamped_data if support == "clamped" else free_data
    beam = FlexibleBodyFFR(data, modes=n, frame=PrescribedFrameMotion.fixed() if support == "clamped" else "free")
    top_nodes = data.node_groups["y1"]
    a, b = int(top_nodes[-1]), int(top_nodes[len(top_nodes) // 2])
    points = [PointContour(beam.node(a), residual_flexibility=True),
              SphereContour(beam.node(b), 0.002, residual_flexibility=True)]
    face = Contour2sNeutralFFR(beam, "y1")
    pa, pb, top = residual_compliances(points + [face])
    G = full_flexibility(data)
    G_res = G - beam.phi @ np.linalg.solve(beam.K_ff, beam.phi.T)
    for ca, j in ((pa, a), (pb, b)):
        for cb, k in ((pa, a), (pb, b)):
            c = ca.between(0.0, 0.0, 0.0, 0.0, other=cb)
            modal = beam.phi_nodes[j] @ np.linalg.solve(beam.K_ff, beam.phi_nodes[k].T)
            full = G[3 * j:3 * j + 3, 3 * k:3 * k + 3]
            assert np.abs(modal + c - full).max() < RTOL * np.abs(G[3 * a:3 * a + 3, 3 * a:3 * a + 3]).max()
    T = np.hstack([transfer_matrix(c).toarray() for c in points + [face]])       # G_P's columns, in order
    Tb = point_pattern(top, T, 0.05, 0.011)
    c_ab = pa.between(0.0, 0.0, 0.05, 0.011, other=top)
    assert np.allclose(c_ab, G_res[3 * a:3 * a + 3] @ Tb, rtol=0, atol=RTOL * np.abs(c_ab).max())
    assert np.allclose(c_ab, top.between(0.05, 0.011, 0.0, 0.0, other=pa).T, rtol=1e-12, atol=0)
    assert np.abs(pa.at()).max() > 1e-2 * np.abs(G[3 * a:3 * a + 3, 3 * a:3 * a + 3]).max()   # it matters


def test_a_point_off_a_node_cannot_carry_residual_flexibility(clamped_data):
    from contours import PointContour
    from mbs import Frame

    beam = FlexibleBodyFFR(clamped_data, modes=5, frame=PrescribedFrameMotion.fixed())
    with pytest.raises(ModelError, match="needs the frame of a node of a flexible body"):
        PointContour(Frame(beam, (0.05, 0.02, 0.01)), residual_flexibility=True)


@pytest.mark.filterwarnings("ignore:neutral 2s")
@pytest.mark.parametrize("kind", ["2s", "fitted", "1s", "band"])
def test_load_pattern_is_the_contours_displacement(kind, clamped_data):
    """Tₚᵀ Φ q equals the displacement of the contour point the contour itself evaluates
    for elastic coordinates q (virtual work: the load pattern is the transpose of the
    point's displacement map)."""
    beam = FlexibleBodyFFR(clamped_data, modes=6, frame=PrescribedFrameMotion.fixed())
    contour = contours_of(beam, (kind,))[kind]
    rc = residual_compliance(contour)
    T = transfer_matrix(contour).toarray()
    q_f = 1e-6 * np.random.default_rng(1).standard_normal(6)      # ~ 10 µm: the band is linear to ~1e-3
    for eta, xi in points_of(contour):
        Tp = point_pattern(rc, T, eta, xi)
        q = beam.q_init.copy()
        r0 = contour.evaluate(contour.new_point(), eta, xi).r.copy()
        q[beam.q_f_slice] = q_f
        contour.update(q, beam.u_init)
        r1 = contour.evaluate(contour.new_point(), eta, xi).r.copy()
        contour.update(beam.q_init, beam.u_init)
        if kind == "band":        # the offset's first-order change: Tₚ linearizes the frame
            assert np.allclose(r1 - r0, Tp.T @ beam.phi @ q_f, rtol=0, atol=1e-3 * np.abs(r1 - r0).max())
        else:
            assert np.allclose(r1 - r0, Tp.T @ beam.phi @ q_f, rtol=0, atol=1e-9 * np.abs(r1 - r0).max())   # rounding of r1 − r0


def test_kernel_matches_reference():
    rng = np.random.default_rng(3)
    G = rng.standard_normal((30, 30))
    Ba, Bb = rng.standard_normal((2, 6, 3, 3))
    ia, ib = rng.integers(0, 10, (2, 6))
    out = np.zeros((3, 3))
    compliance_between(G, Ba, ia, 5, Bb, ib, 4, out)
    assert np.allclose(out, compliance_between_reference(G, Ba, ia, 5, Bb, ib, 4), rtol=1e-13, atol=1e-13)


@pytest.mark.filterwarnings("ignore:neutral 2s")
def test_compiled_route_matches_blocks(clamped_data):
    """The compiled route of neutral contours equals eq. C2 over the blocks of
    ``weights`` (the numpy reference)."""
    beam = FlexibleBodyFFR(clamped_data, modes=7, frame=PrescribedFrameMotion.fixed())
    made = contours_of(beam, ("2s", "fitted", "1s"))
    for contour in made.values():
        rc = residual_compliance(contour)
        blocks, index = np.zeros((2, 16, 3, 3)), np.zeros((2, 16), dtype=np.int64)
        (a, b), (c, d) = points_of(contour)[:2]
        ka, kb = rc.weights(a, b, blocks[0], index[0]), rc.weights(c, d, blocks[1], index[1])
        ref = compliance_between_reference(rc.G_P, blocks[0], index[0], ka, blocks[1], index[1], kb)
        assert np.allclose(rc.between(a, b, c, d), ref, rtol=1e-13, atol=1e-13 * np.abs(ref).max())


@pytest.mark.parametrize("kind", ["band", "cylinder"])
def test_derived_blocks_equal_finite_differences_of_the_offset_point(clamped_data, kind):
    """The blocks B_i = N_i I + N'_i Ğ of a derived contour (eq. C1) — a band 3 mm off its
    curve, a cylinder of radius 4 mm — equal the change of the undeformed offset point
    ū(η) + α n̄ + β t̄2 when control point i moves: central differences in P_i, with the
    frame t̄, n̄, t̄2 of :func:`contours.derived.offset_frame` at ū_η = Σ N'_k P_k (not its
    derivatives)."""
    beam = FlexibleBodyFFR(clamped_data, modes=5, frame=PrescribedFrameMotion.fixed())
    axis = Contour1sNeutralFFR.along_line(beam, (0.0, 0.02, 0.01), (1, 0, 0), normal=(0, 1, 0), degree=4)
    contour = (FlexibleBand(axis, width=0.02, offset=0.003) if kind == "band"
               else FlexibleCylinder(axis, radius=0.004))
    rc = residual_compliance(contour)
    P0 = axis.kernel_data[-4].reshape(-1, 3)                 # the undeformed control points [m]
    d = axis.space.eta
    B = np.zeros((3, d.p + 1))
    blocks, index = np.zeros((16, 3, 3)), np.zeros(16, dtype=np.int64)
    (a, b), (c, e) = contour.domain
    h = 1e-7 * np.abs(P0).max()
    for eta, xi in [(a + 0.37 * (b - a), c + 0.2 * (e - c)), (a + 0.81 * (b - a), c + 0.9 * (e - c))]:
        k = rc.weights(eta, xi, blocks, index)
        NK.locate(d.knots, d.p, d.n_ctrl, d.closed, d.a, d.b, eta, B)
        al, be = offsets(*contour.offset_law, xi)[:2]
        points = index[:k] - rc.offset

        def offset(P):
            t, t2, n = offset_frame(B[1] @ P[points], axis.normal_ref)[:3]
            return al * n + be * t2

        assert abs(al) + abs(be) > 1e-3                      # an offset that makes Ğ matter
        for j in range(k):
            for col in range(3):
                Pp, Pm = P0.copy(), P0.copy()
                Pp[points[j], col] += h
                Pm[points[j], col] -= h
                expected = B[0, j] * np.eye(3)[col] + (offset(Pp) - offset(Pm)) / (2 * h)
                np.testing.assert_allclose(blocks[j][:, col], expected, rtol=0, atol=1e-6 * max(1.0, abs(B[1, j])))


def test_cache_is_reused_and_keyed(clamped_data, tmp_path):
    """The projected flexibility is written once and read back (same compliance, for any
    mode count); a file of the wrong shape under the key is recomputed."""
    beam = FlexibleBodyFFR(clamped_data, modes=8, frame=PrescribedFrameMotion.fixed())
    contour = Contour2sNeutralFFR(beam, "y1")
    first = residual_compliance(contour, cache_dir=tmp_path).at(0.05, 0.01)
    files = list(tmp_path.glob("residual-*.npy"))
    assert len(files) == 1
    assert np.array_equal(residual_compliance(contour, cache_dir=tmp_path).at(0.05, 0.01), first)
    np.save(files[0], np.zeros((2, 2)))
    assert np.array_equal(residual_compliance(contour, cache_dir=tmp_path).at(0.05, 0.01), first)
    assert not list(tmp_path.glob("*.tmp"))


def test_singular_supports_are_one_clear_error(clamped_data):
    K = clamped_data.stiffness
    with pytest.raises(ModelError, match="singular"):
        StaticFlexibility(K, clamped_data.masses, clamped_data.u0, clamped_nodes=np.array([0]))


def test_rigid_contour_is_refused(clamped_data):
    from contours import PlaneContour
    from contours.residual import neutral_of
    from mbs.bodies.body import ground_frame

    with pytest.raises(ModelError, match="neutral contour"):
        neutral_of(PlaneContour(ground_frame()))


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: BLAS has one thread anyway")
def test_projection_solves_on_one_blas_thread(clamped_data, monkeypatch):
    """The 1107-column projection of the default beam cost 47 CPU s on two BLAS threads of
    a loaded two-core machine and 5.5 s on one: each solve runs with one BLAS thread."""
    from threadpoolctl import threadpool_info

    from preprocess import residual

    threads = []
    solve = StaticFlexibility.solve

    def counting(self, forces):
        threads.extend(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
        return solve(self, forces)

    monkeypatch.setattr(StaticFlexibility, "solve", counting)
    data = clamped_data
    T = np.eye(3 * data.n_nodes)[:, :3 * residual.CHUNK + 1]
    residual.projected_flexibility(StaticFlexibility(data.stiffness, data.masses, data.u0,
                                                     clamped_nodes_of(data)), T)
    assert threads and set(threads) == {1}


def _dense_projection(data, T):
    """Tᵀ K_ff⁻¹ T by a dense solve of the clamped stiffness (the oracle)."""
    K = data.stiffness.toarray()
    free = ~clamped_dofs(K.shape[0], clamped_nodes_of(data))
    return T[free].T @ np.linalg.solve(K[np.ix_(free, free)], T[free])


@pytest.mark.parametrize("loads", ["face", "every DOF"])
def test_clamped_projection_from_the_schur_complement_equals_a_dense_solve(clamped_data, loads):
    """Eq. R4: Tᵀ G T from the trailing blocks of one factorization (the loaded DOFs last)
    equals Tᵀ K_ff⁻¹ T by a dense solve, for load patterns on the face y = 20 mm (random
    weights, more patterns than loaded DOFs) and for every DOF loaded (no interior)."""
    from preprocess.residual import clamped_projected_flexibility

    data = clamped_data
    n = 3 * data.n_nodes
    rng = np.random.default_rng(3)
    if loads == "face":
        face = np.flatnonzero(np.isclose(data.u0[:, 1], 0.02))
        T = np.zeros((n, 2 * 3 * face.size))
        T[(3 * face[:, None] + np.arange(3)).ravel()] = rng.standard_normal((3 * face.size, T.shape[1]))
    else:
        T = rng.standard_normal((n, 40))
    expected = _dense_projection(data, T)
    got = clamped_projected_flexibility(data.stiffness, clamped_nodes_of(data), T)
    assert np.allclose(got, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_trailing_inverse_of_a_reordered_factor():
    """The trailing block of A⁻¹ when SuperLU permutes (COLAMD, partial pivoting): the
    solves through the factor, equal to the dense inverse's block."""
    from preprocess.residual import _trailing_inverse

    rng = np.random.default_rng(4)
    A = rng.standard_normal((30, 30)) + 30 * np.eye(30)
    A[rng.random((30, 30)) < 0.7] = 0.0
    A += 30 * np.eye(30)
    lu = sla.splu(sp.csc_matrix(A))
    assert not np.array_equal(lu.perm_c, np.arange(30))
    assert np.allclose(_trailing_inverse(lu, 7), np.linalg.inv(A)[23:, 23:], rtol=1e-12, atol=1e-15)


def test_clamped_contour_projection_takes_no_solves(clamped_data, monkeypatch):
    """A clamped body's residual compliance comes from the factorization alone (eq. R4):
    no solve through the whole factor (before: one per load column, 1107 on the default
    beam), and the same compliance as the solves give."""
    data = clamped_data
    beam = FlexibleBodyFFR(data, modes=8, frame=PrescribedFrameMotion.fixed())
    contour = Contour2sNeutralFFR(beam, "y1")
    T = transfer_matrix(contour)
    by_solves = residual.projected_flexibility(StaticFlexibility(data.stiffness, data.masses, data.u0,
                                                                 clamped_nodes_of(data)), T)

    def refused(self, forces):
        raise AssertionError("solved through the whole factor")

    monkeypatch.setattr(StaticFlexibility, "solve", refused)
    got = residual_compliance(contour).G_P
    expected = residual.residual_flexibility(by_solves, contour.mode_shapes.ctrl.reshape(-1, 8).T, beam.K_ff)
    assert np.allclose(got, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_singular_supports_are_one_clear_error_of_the_schur_route(clamped_data):
    from preprocess.residual import clamped_projected_flexibility

    T = np.eye(3 * clamped_data.n_nodes)[:, :12]
    with pytest.raises(ModelError, match="singular"):
        clamped_projected_flexibility(clamped_data.stiffness, np.array([0]), T)
