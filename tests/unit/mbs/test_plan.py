"""The scene planner (mbs.run.plan): each rule fires on a scene built for it, and the planned
run matches the unplanned one (or an independent oracle) within the plan's tolerance."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from mbs import DistributedForce, FlexibleBodyFFR, Force, PrescribedFrameMotion, System, Tabulated
from mbs.run.plan import INTEGRATED, MODAL_EXACT, SIMPLE_RB
from validation.cases import _wobble as wb
from validation.cases import ffr_free_flight as ff
from validation.scenes import planner_scene as ps
from ffrmbs_app.scenes import point_mass_beam as pmb

TIP_LOAD, OFF = np.array([0.0, -5.0, 0.0]), 5e-3          # [N], [s]


@pytest.fixture(scope="module")
def beam_data():
    return pmb.default_beam_data()


@pytest.fixture(scope="module")
def free_beam():
    mesh, data = wb.beam(n_modes=10)
    return mesh, data, ff.face_weights(mesh), ff.node_a(mesh)


def clamped_beam(data, modes=None):
    system = System()
    beam = system.add(FlexibleBodyFFR(data, modes, frame=PrescribedFrameMotion.fixed(), name="beam"))
    tip = data.node_at(pmb.NODE_19)
    system.add(Force(beam.node(tip), Tabulated([0.0, OFF], [TIP_LOAD, (0.0, 0.0, 0.0)])))
    return system, beam, tip


def step_response_oracle(data, tip, times):
    """Tip u_y by the analytic undamped modal step response over all modes, written out
    here: r_k(t) = a_k (1 − cos ω_k t) − a_k (1 − cos ω_k (t − t_off)) H(t − t_off)."""
    omega = np.sqrt(data.modal_eigenvalues())
    a = (data.phi[3 * tip:3 * tip + 3].T @ TIP_LOAD) / omega ** 2
    t = times[:, None]
    r = a * (1 - np.cos(omega * t)) - a * (1 - np.cos(omega * (t - OFF))) * (t >= OFF)
    return r @ data.phi[3 * tip + 1]


@pytest.mark.slow
def test_frame_fixed_body_without_contact_is_propagated_exactly_on_fewer_modes(beam_data):
    system, beam, tip = clamped_beam(beam_data)
    plan = system.plan(0.02)
    (bp,) = plan.bodies
    assert bp.formulation == MODAL_EXACT
    assert 0 < bp.modes.size < beam.n_modes                     # modes=None: the planner chose
    assert "modes" in str(plan) and "exact modal propagation" in str(plan)
    times = np.linspace(0.0, 0.02, 401)
    out = {"tip": lambda t, q, u: beam.phi_nodes[tip][1] @ q[beam.q_slice]}
    res = system.simulate(0.02, 1e-3, integrator="moreau", t_out=times, outputs=out)  # Δt does not matter
    assert res.stats["steps"] == 0
    oracle = step_response_oracle(beam_data, tip, times)
    assert np.abs(res["tip"] - oracle).max() <= plan.tolerance
    # the unplanned Moreau run converges to the same history (its own time error only:
    # measured 1.5e-6 m at Δt = 1e-5 s, 1.1e-6 at 5e-6, 5.8e-7 at 2.5e-6)
    ref = system.simulate(0.02, 1e-5, integrator="moreau", theta=0.5, t_out=times, outputs=out, plan=False)
    assert np.abs(ref["tip"] - oracle).max() < 2e-6 < 0.01 * np.abs(oracle).max()


def test_modes_fixed_by_the_user_are_kept(beam_data):
    system, beam, _ = clamped_beam(beam_data, modes=20)
    (bp,) = system.plan(0.02).bodies
    assert bp.formulation == MODAL_EXACT and bp.modes.size == 20


def free_flight_system(free_beam, omega=(0.0, 0.0, 0.0), scale=1.0):
    mesh, data, weights, probe = free_beam
    system = System()
    beam = system.add(FlexibleBodyFFR(data, 10, name="beam").set_initial(omega=omega))
    for k, group in enumerate(("z1", "z0")):
        nodes, w = weights[group]
        rows = [(0.0, scale * ff.magnitudes(t)[k], 0.0) for t in (0.0, ff.T_SWITCH)]
        system.add(DistributedForce(beam, nodes, w, Tabulated([0.0, ff.T_SWITCH], rows)))
    return system, beam, beam.node(probe)


@pytest.mark.slow
def test_free_body_with_negligible_coupling_runs_simple_rb_and_matches_full_ffr(free_beam):
    system, beam, node = free_flight_system(free_beam)
    plan = system.plan(0.6)
    assert plan.bodies[0].formulation == SIMPLE_RB
    times = np.linspace(0.0, 0.6, 61)
    out = {"A": node, "elastic": lambda t, q, u: node.elastic_displacement(q[beam.q_slice])}
    fast = system.simulate(0.6, 1e-3, t_out=times, outputs=out)
    # rk4's own error at Δt = 2e-4 s: 3.9e-9 m against its Δt = 5e-5 run (4th order: 3.5e-10
    # at 1e-4), far below plan.tolerance = 1e-6 m; ω_max Δt = 1.2 of rk4's 2.8
    full = system.simulate(0.6, 2e-4, integrator="rk4", t_out=times, outputs=out, plan=False)
    assert fast.stats["steps"] == 0 and full.stats["steps"] == 3_000
    assert np.abs(fast["A"] - full["A"]).max() <= plan.tolerance
    assert np.abs(fast["elastic"] - full["elastic"]).max() <= plan.tolerance
    assert np.abs(fast["elastic"]).max() > 1e-7          # the deformation is there to compare


def test_free_body_spinning_fast_keeps_the_full_ffr_equations(free_beam):
    system, _, _ = free_flight_system(free_beam, omega=(0.0, 0.0, 30.0))
    (bp,) = system.plan(0.6).bodies
    assert bp.formulation == INTEGRATED and "α–Ω criterion" in bp.reasons[0] and ">" in bp.reasons[0]


def test_far_contact_is_pruned_and_the_planned_run_matches_the_unplanned(beam_data):
    t_end, times = 0.013, np.linspace(0.0, 0.013, 27)        # the contact closes at 10 ms
    runs = {}
    for plan in (True, False):
        scene = ps.build(data=beam_data)
        runs[plan] = scene.system.simulate(t_end, 1e-5, integrator="moreau", theta=0.5, t_out=times,
                                           outputs=scene.outputs(), plan=plan)
    planned, unplanned = runs[True], runs[False]
    assert planned.stats["pruned_contacts"] >= 1300 and unplanned.stats["pruned_contacts"] == 0
    assert planned.stats["closed_contacts"] == unplanned.stats["closed_contacts"] > 0
    for name in ("y", "vy", "node19", "far_x"):
        scale = np.abs(unplanned[name]).max()
        assert np.abs(planned[name] - unplanned[name]).max() <= 1e-10 * scale, name
    # the frame-fixed second beam: exact modal propagation against Moreau's Δt = 1e-5 run
    assert np.abs(planned["tip2_y"] - unplanned["tip2_y"]).max() < 0.005 * np.abs(unplanned["tip2_y"]).max()
    assert MODAL_EXACT in planned.plan and "far contact" in planned.plan


def test_plan_is_logged_and_lists_outputs_and_vanishing_terms(beam_data, caplog):
    system, beam, tip = clamped_beam(beam_data, modes=10)
    with caplog.at_level(logging.INFO, logger="ffrmbs.plan"):
        res = system.simulate(0.002, 1e-4, integrator="moreau", outputs={"tip": beam.node(tip)})
    assert res.plan in caplog.text
    assert "Q_v (frame at rest)" in res.plan and "D q̇_f (no damping)" in res.plan and "tip" in res.plan


def test_undamped_body_skips_damping_without_changing_forces(beam_data):
    rng = np.random.default_rng(1)
    q, u = rng.normal(size=10), rng.normal(size=10)
    fixed = PrescribedFrameMotion.fixed()
    plain = FlexibleBodyFFR(beam_data, 10, frame=fixed)
    damped = FlexibleBodyFFR(beam_data, 10, frame=fixed, rayleigh=(3.0, 1e-4))
    assert not plain.damped and damped.damped
    np.testing.assert_allclose(plain.h(q, u), -plain.K_ff @ q, rtol=1e-14)
    np.testing.assert_allclose(damped.h(q, u), -damped.K_ff @ q - damped.D_ff @ u, rtol=1e-14)
