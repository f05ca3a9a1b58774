"""The complex-forcing scene (report Fig. 6c) obeys the momentum balances: dP/dt equals
the body-fixed load resultant turned into the inertial frame, and the elastic output
of a frame is its Φ q_f."""

import numpy as np
import pytest

from mbs import DistributedForce, FlexibleBodyFFR, System
from preprocess import box, build_body
from validation.cases import ffr_free_flight as case


@pytest.fixture(scope="module")
def scene():
    mesh = box(1.0, 1.0, 5.0, 1.0, order=2)
    data = build_body(mesh, case.MATERIAL, 6, clamp=None)
    return mesh, data


def test_linear_momentum_balance_with_body_fixed_face_loads(scene):
    mesh, data = scene
    weights = case.face_weights(mesh)
    switch = 0.05
    mags = lambda t: (-100.0, 100.0) if t < switch else (500.0, 300.0)
    system = System()
    beam = system.add(FlexibleBodyFFR(data, 6))
    for k, group in enumerate(("z1", "z0")):
        nodes, w = weights[group]
        system.add(DistributedForce(beam, nodes, w, lambda t, k=k: (0.0, mags(t)[k], 0.0)))
    t_out = np.linspace(0.0, 0.1, 401)
    res = system.simulate(0.1, 2.5e-5, integrator="rk4", t_out=t_out, breakpoints=[switch])
    P = np.array([system.linear_momentum(t, q, u) for t, q, u in zip(res.t, res.q, res.u)])
    A = np.array([beam.orientation(q[beam.q_slice]) for q in res.q])
    resultant = lambda t: np.array([0.0, sum(mags(t)), 0.0])
    # trapezoidal impulse per output interval, the load taken as its right limit at the
    # interval start and its left limit at the interval end (the switch is an output time)
    start = np.array([A[i] @ resultant(t) for i, t in enumerate(res.t[:-1])])
    end = np.array([A[i + 1] @ resultant(t - 1e-12) for i, t in enumerate(res.t[1:])])
    impulse = np.vstack([np.zeros(3), np.cumsum(0.5 * (start + end) * np.diff(res.t)[:, None], axis=0)])
    assert np.abs(P - impulse).max() < 1e-6 * np.abs(P).max()
    assert P[-1, 1] > 0.99 * 800.0 * (0.1 - switch)   # −100 + 100 N first, then 800 N along y


def test_elastic_output_is_phi_q(scene):
    mesh, data = scene
    body = FlexibleBodyFFR(data, 6)
    q = body.q_init.copy()
    q[-6:] = np.arange(1, 7) * 1e-3
    node = case.node_a(mesh)
    np.testing.assert_allclose(body.node(node).elastic_displacement(q),
                               data.phi[3 * node:3 * node + 3] @ q[-6:], rtol=1e-14)
