"""The contact validation cases (contact_bounce, contact_friction) in quick mode, run once
through the harness and asserted against the analytic bouncing ball and the analytic
block on an incline, with tolerances derived from the step size (no values taken from
our own output)."""

import math

import pytest

from validation.cases import contact_bounce, contact_friction

from case_rows import quick_rows_without_files, select

pytestmark = pytest.mark.slow   # seconds each: left out of the fast subset (-m "not slow")

CASES = (contact_bounce, contact_friction)
G = 9.81
V1 = math.sqrt(2.0 * G * contact_bounce.H)      # impact speed of the first impact [m/s]


@pytest.fixture(scope="module")
def rows():
    """{case name: rows} of both cases run quick as the harness runs them (no plots)."""
    return quick_rows_without_files(CASES)


def one(rows, **config):
    found = select(rows, **config)
    assert len(found) == 1, (config, len(found))
    return found[0]


def test_both_cases_run_both_integrators(rows):
    assert set(rows) == {case.NAME for case in CASES}
    for case_rows in rows.values():
        assert all(math.isfinite(r["cpu_s"]) and r["cpu_s"] > 0 for r in case_rows)
        assert {r["config"]["integrator"] for r in case_rows} == {"moreau", "moreau-adaptive"}
    bounce = rows["contact_bounce"]
    assert {r["error_kind"] for r in select(bounce, e=0.7)} == {
        contact_bounce.KIND_TIME, contact_bounce.KIND_APEX, contact_bounce.KIND_REST}
    assert {r["error_kind"] for r in select(bounce, e=1.0)} == {contact_bounce.KIND_TIME, contact_bounce.KIND_APEX}
    assert {r["error_kind"] for r in select(bounce, e=0.0)} == {contact_bounce.KIND_REST}
    assert all(math.isfinite(r["error"]) for r in bounce)


def test_analytic_reference_of_the_bounce():
    t1 = math.sqrt(2.0 * contact_bounce.H / G)
    t = contact_bounce.exact_impact_times(0.5, 3)
    assert t == pytest.approx([t1, 2.0 * t1, 2.5 * t1])          # flights 2 e t1, 2 e² t1
    assert contact_bounce.t_zeno(0.7) == pytest.approx(t1 + 2.0 * t1 * 0.7 / 0.3)
    # a sample of an exact parabola returns its launch, landing and apex
    launch, v = 0.3, 2.0
    ti = launch + 0.1
    zi, wi = v * 0.1 - 0.5 * G * 0.01, v - G * 0.1
    (fl,) = contact_bounce.flights([ti], [zi], [wi])
    assert fl == pytest.approx((launch, launch + 2.0 * v / G, v * v / (2.0 * G)), rel=1e-13)


@pytest.mark.parametrize("e", [0.7, 1.0])
def test_bounce_impact_times_within_the_step_bound_and_converging(rows, e):
    """The contact closes at the first midpoint below the plane, less than Δt after the
    crossing, and the rebound leaves from there: each impact delays the launch by less
    than 2Δt, so K impacts are mistimed by less than 2KΔt. First order: ten times
    smaller steps give a clearly smaller error."""
    fixed = select(rows["contact_bounce"], e=e, integrator="moreau", error_kind=contact_bounce.KIND_TIME)
    assert len(fixed) == len(contact_bounce.DT_FIXED[True])
    K = contact_bounce.N_IMPACTS[e]
    for r in fixed:
        assert 0.0 < r["error"] < 2 * K * r["config"]["dt"]
    err = {r["config"]["dt"]: r["error"] for r in fixed}
    assert err[1e-3] < err[1e-2] / 3


def test_elastic_bounce_keeps_the_apex_and_partial_restitution_converges(rows):
    """e = 1: the impact step maps (q_k, −v) to (q_k, +v), so the apex is exact to
    rounding. e = 0.7: the rebound leaves from the penetrated position, O(Δt)."""
    bounce = rows["contact_bounce"]
    for r in select(bounce, e=1.0, error_kind=contact_bounce.KIND_APEX):
        assert r["error"] < 1e-12
    apex = {r["config"]["dt"]: r["error"] for r in
            select(bounce, e=0.7, integrator="moreau", error_kind=contact_bounce.KIND_APEX)}
    assert apex[1e-3] < apex[1e-2] / 5 and apex[1e-3] < 0.05


def test_bounce_never_gains_energy(rows):
    for r in rows["contact_bounce"]:
        assert r["energy_gain"] < 1e-12, r["config"]


def test_plastic_impact_rests_within_one_steps_travel(rows):
    """e = 0: the ball stops at the depth its midpoint had when the contact closed, at most
    one step's travel v_1 Δt; adaptive: the gap control lets an accepted step deepen the
    penetration by at most gap_tol = atol, and it deepens in at most two steps: one that
    ends below the plane with its midpoint still above, and the one that closes it."""
    for r in select(rows["contact_bounce"], e=0.0):
        assert r["rest_speed"] < 1e-12
        if r["config"]["integrator"] == "moreau":
            assert r["error"] < V1 * r["config"]["dt"]
        else:
            assert r["error"] <= 2 * r["config"]["atol"]


def test_zeno_bounce_rests_without_sinking(rows):
    """e = 0.7, after t_∞: the ball comes to rest once its rebound speed drops below the
    gravity increment g Δt of a step, so it rests less than g Δt² deep; adaptive: the last
    closing deepens the penetration in at most two steps of at most gap_tol = atol each
    (see the plastic case)."""
    zeno = select(rows["contact_bounce"], e=0.7, error_kind=contact_bounce.KIND_REST)
    for r in zeno:
        if r["config"]["integrator"] == "moreau":
            assert r["error"] < G * r["config"]["dt"] ** 2
        else:
            assert r["error"] < 2 * r["config"]["atol"]
    finest = one(zeno, integrator="moreau", dt=1e-3)
    assert finest["rest_speed"] < 1e-9


@pytest.mark.parametrize("e", [0.0, 0.7, 1.0])
def test_adaptive_beats_the_finest_fixed_step(rows, e):
    """The tightest adaptive run is more accurate than the finest fixed step and takes
    fewer accepted steps (it refines only around the impacts)."""
    bounce = select(rows["contact_bounce"], e=e)
    kind = contact_bounce.KIND_REST if e == 0.0 else contact_bounce.KIND_TIME
    fixed = one(bounce, integrator="moreau", dt=min(contact_bounce.DT_FIXED[True]), error_kind=kind)
    adaptive = one(bounce, integrator="moreau-adaptive", atol=min(contact_bounce.ATOLS[True]), error_kind=kind)
    assert adaptive["error"] < fixed["error"]
    assert adaptive["steps"] < fixed["steps"]


def test_friction_reference():
    a = G * (math.sin(contact_friction.ALPHA) - 0.2 * math.cos(contact_friction.ALPHA))
    assert contact_friction.deceleration("slip") == pytest.approx(a)
    v0, mu = 1.0, 0.5                                   # down the slope: decelerates at g(μ cos α − sin α)
    a_down = G * (mu * math.cos(contact_friction.ALPHA) - math.sin(contact_friction.ALPHA))
    assert contact_friction.stop_position("down") == pytest.approx(v0 ** 2 / (2 * a_down))
    assert contact_friction.stop_position("up") < 0.0
    assert math.tan(contact_friction.ALPHA) < contact_friction.MU_STICK
    assert math.tan(contact_friction.ALPHA) > contact_friction.MU_SLIP


def _set_valued(rows, scene):
    return select(rows["contact_friction"], scene=scene, law="set-valued")


def test_stick_and_slip_are_exact_without_rounding_in_the_normal(rows):
    """Tilted gravity on a flat plane: the midpoint rule integrates the constant
    acceleration exactly, so the block sticks exactly and slips along ½ a t²."""
    rows_ = _set_valued(rows, "tilted gravity")
    stick, slip = select(rows_, motion="stick"), select(rows_, motion="slip")
    assert len(stick) == len(slip) == len(contact_friction.DT_FIXED[True]) + len(contact_friction.ATOLS[True])
    assert all(r["error"] <= 1e-12 and r["normal_drift"] <= 1e-12 for r in stick)
    assert all(r["error"] <= 1e-12 and r["normal_drift"] <= 1e-12 for r in slip)


@pytest.mark.parametrize("motion", ["up", "down"])
def test_sliding_stops_within_a_h2_over_8_and_stays(rows, motion):
    """The stop is the only inexact step: it travels v h/2 instead of v τ/2 (τ < h), an
    error v (h − τ)/2 <= a h²/8. Step doubling compares the step with two halves, whose
    difference bounds the half-step solution's stop error, so the adaptive error <= atol."""
    a = contact_friction.deceleration(motion)
    for r in select(_set_valued(rows, "tilted gravity"), motion=motion):
        assert r["speed_after_stop"] <= 1e-12
        if r["config"]["integrator"] == "moreau":
            assert r["error"] <= a * r["config"]["dt"] ** 2 / 8 + 1e-15
        else:
            assert r["error"] <= r["config"]["atol"]


def test_block_sticks_exactly_on_a_tilted_plane(rows):
    """Same mechanics as the tilted-gravity scene: the block must not move at all."""
    for r in select(_set_valued(rows, "tilted plane"), motion="stick"):
        assert r["error"] <= 1e-12 and r["normal_drift"] <= 1e-12


def test_regularized_friction_creeps_at_v_eps_tan_alpha_over_mu(rows):
    """Below v_eps the regularized friction force is viscous, μ F_N v / v_eps; it balances
    m g sin α at v = v_eps tan α / μ with F_N = m g cos α, so a block that should stick
    creeps, and its displacement over the run scales with v_eps. The displacement also
    holds the penalty law's static penetration m g cos α / k (critically damped)."""
    reg = select(rows["contact_friction"], law="regularized", motion="stick")
    ratio = math.tan(contact_friction.ALPHA) / contact_friction.MU_STICK
    assert {r["config"]["v_eps"] for r in reg} == set(contact_friction.V_EPS[True])
    for r in reg:
        assert r["error_kind"] == contact_friction.KIND_STICK
        assert r["creep_over_v_eps"] == pytest.approx(ratio, rel=1e-3)
        assert r["creep_rel_error"] < 1e-3
    disp = {r["config"]["v_eps"]: r["error"] for r in reg}
    T = contact_friction.T_STICK
    static = contact_friction.MASS * G * math.cos(contact_friction.ALPHA) / contact_friction.K_PENALTY
    for v_eps, d in disp.items():
        assert 0.5 * ratio * v_eps * T < d < ratio * v_eps * T + 1.1 * static
    assert disp[1e-2] / disp[1e-1] == pytest.approx(0.1, rel=0.05)


def test_regularized_slip_approaches_coulomb_as_v_eps_shrinks(rows):
    reg = {r["config"]["v_eps"]: r["error"] for r in
           select(rows["contact_friction"], law="regularized", motion="slip")}
    assert reg[1e-2] < reg[1e-1] / 5
    assert reg[1e-2] < 0.01
