"""Output probes (mbs.results.probes): a frame's position written in place equals the frames'
own numpy formulas, on every kind of body, and sampling it allocates no array."""

from __future__ import annotations

import numpy as np
import pytest

from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, RigidBody, System, ground_frame
from mbs.bodies import _kernels as kern
from mbs.results.probes import FREE_QUATERNION, GENERIC, POINT_MASS, FramePosition, probe
from preprocess import box, build_body
from validation.cases.cantilever import MATERIAL

from numpy_allocations import NumpyAllocations

N_F = 4


@pytest.fixture(scope="module")
def data():
    return build_body(box(1.0, 1.0, 5.0, 1.0, order=2), MATERIAL, N_F, clamp=None)


def reference_position(body, q_b, frame):
    """r = R + A (ū0 + Φ q_f) from the quaternion's rotation matrix (thesis eq. 2.24)."""
    p0, p1, p2, p3 = q_b[3:7]
    A = np.array([[p0 * p0 + p1 * p1 - p2 * p2 - p3 * p3, 2 * (p1 * p2 - p0 * p3), 2 * (p1 * p3 + p0 * p2)],
                  [2 * (p1 * p2 + p0 * p3), p0 * p0 - p1 * p1 + p2 * p2 - p3 * p3, 2 * (p2 * p3 - p0 * p1)],
                  [2 * (p1 * p3 - p0 * p2), 2 * (p2 * p3 + p0 * p1), p0 * p0 - p1 * p1 - p2 * p2 + p3 * p3]])
    q_f = q_b[7:]
    return q_b[:3] + A @ (frame.u0 + frame.phi @ q_f)


def mixed(data):
    system = System()
    system.add(PointMass(2.0, position=(0.1, 0.2, 0.3), name="p"))
    beam = system.add(FlexibleBodyFFR(data, N_F, name="beam"))
    rigid = system.add(RigidBody(3.0, np.diag([1.0, 2.0, 3.0]), name="rigid"))
    fixed = system.add(FlexibleBodyFFR(data, N_F, frame=PrescribedFrameMotion.fixed((1.0, 0.0, 0.0)), name="fixed"))
    return system, beam, rigid, fixed


def random_state(system, rng):
    q = rng.normal(size=system.nq)
    for b in system.bodies:
        if getattr(b, "free_quaternion", False):
            s = b.q_slice.start + 3
            q[s:s + 4] /= np.linalg.norm(q[s:s + 4])
    return q


@pytest.mark.parametrize("seed", range(4))
def test_free_point_position_kernel_equals_the_formula(data, seed):
    rng = np.random.default_rng(seed)
    system, beam, rigid, _ = mixed(data)
    q = random_state(system, rng)
    for body, frame in ((beam, beam.node(7)), (beam, beam.frame_at((0.3, -0.2, 1.0))), (rigid, rigid.origin)):
        out = np.empty(3)
        kern.free_point_position_into(q, body.q_slice.start, frame.u0, frame.phi, out)
        ref = reference_position(body, q[body.q_slice], frame)
        assert np.abs(out - ref).max() <= 1e-14 * max(1.0, np.abs(ref).max())


@pytest.mark.parametrize("seed", range(3))
def test_frame_position_in_place_equals_frame_position_on_every_body(data, seed):
    rng = np.random.default_rng(seed)
    system, beam, rigid, fixed = mixed(data)
    q = random_state(system, rng)
    point = system.bodies[0]
    frames = {FREE_QUATERNION: [beam.node(3), rigid.frame_at((0.5, 0.0, 0.1))],
              POINT_MASS: [point.point],
              GENERIC: [fixed.node(5), ground_frame((1.0, 2.0, 3.0))]}
    for kind, fs in frames.items():
        for frame in fs:
            p = probe(frame)
            assert isinstance(p, FramePosition) and p.kind == kind
            out = np.full(3, np.nan)
            p.into(0.2, q, out)
            ref = frame.position(None if frame.body is None else q[frame.body.q_slice], 0.2)
            assert np.abs(out - ref).max() <= 1e-14 * max(1.0, np.abs(ref).max())
            np.testing.assert_array_equal(p(0.2, q, None), ref)


def test_sampling_a_node_position_allocates_no_array(data):
    system, beam, _, _ = mixed(data)
    q = random_state(system, np.random.default_rng(0))
    p, out = probe(beam.node(2)), np.zeros(3)
    p.into(0.0, q, out)
    with NumpyAllocations() as count:
        for _ in range(20):
            p.into(0.0, q, out)
    assert count.n == 0


def test_finite_sum_flags_nan_and_inf_as_numpy():
    rng = np.random.default_rng(1)
    q, u = rng.normal(size=9), rng.normal(size=7)
    assert np.isclose(kern.finite_sum(q, u), q.sum() + u.sum(), rtol=1e-13)
    for bad in (np.nan, np.inf, -np.inf):
        u[3] = bad
        assert not np.isfinite(kern.finite_sum(q, u)) and not np.isfinite(q.sum() + u.sum())
