"""The stability suite's contact cases (validation/stability/contact_cases.py) in quick mode.

Each case measures against its own analytic reference (derivations in the module
docstring); the tests assert that the row reports the expected outcome and the case's
quantitative claim.
"""

import math

import numpy as np
import pytest

from validation.stability import contact_cases as cc
from validation.stability.core import CASES, StabilityRow

pytestmark = pytest.mark.stability


def run(name) -> StabilityRow:
    row = CASES[name].run(True)
    assert isinstance(row, StabilityRow) and row.case == name
    assert row.run_time_s >= 0.0
    return row


def test_every_contact_case_has_a_test():
    ours = {n for n, c in CASES.items() if getattr(c.run, "__module__", "") == cc.__name__}
    tested = {"penalty_k1e5", "penalty_k1e7", "penalty_k1e9", "penalty_k1e12", "penalty_k1e9_dt_omega",
              "penalty_k1e12_dt_omega", "penalty_k1e12_adaptive", "penalty_k1e12_adaptive_bound", "grazing",
              "contour_edge", "closed_seam_cylinder", "closed_seam_ring", "redundant_contacts_4",
              "redundant_contacts_8_newton", "redundant_contacts_friction", "zeno", "zeno_adaptive",
              "mass_ratio_1e-6", "mass_ratio_1e6", "mass_ratio_stack_1e-6", "mass_ratio_stack_1e6_gs",
              "mass_ratio_stack_1e6_newton"}
    assert ours == tested


def test_penalty_reference_limits():
    """Without gravity's share (g/(ω v0) → 0) the contact is the half oscillation:
    τ_c → π/ω, δ → v0/ω; with gravity both grow (the spring also carries the weight)."""
    ref = cc.penalty_reference(1e12)
    w = ref["omega"]
    assert ref["tau"] == pytest.approx(math.pi / w, rel=2e-5) and ref["tau"] > math.pi / w
    assert ref["delta"] == pytest.approx(1.0 / w, rel=2e-5) and ref["delta"] > 1.0 / w
    soft = cc.penalty_reference(1e2)              # ω = 10 rad/s: g/(ω v0) ≈ 0.98
    x_s = 9.81 / 100.0
    assert soft["delta"] == pytest.approx(x_s + math.hypot(x_s, 0.1))
    assert soft["tau"] == pytest.approx((math.pi + 2 * math.atan(0.981)) / 10.0)


@pytest.mark.parametrize("name", ["penalty_k1e5", "penalty_k1e7"])
def test_penalty_stable_at_the_coarse_step(name):
    row = run(name)
    d = row.details
    wdt = d["omega_dt"]
    assert wdt < 1.0
    assert row.passed and row.finished and row.stable, row.outcome
    assert abs(d["v_out"] - 1.0) <= wdt ** 2 / 4                    # rebound speed = v0
    assert d["tau_error_s"] <= d["dt"] + d["tau_exact"] * wdt ** 2 / 12
    assert d["delta_error"] <= wdt ** 2 / 2 and row.energy_drift <= wdt ** 2 / 2


@pytest.mark.parametrize("name", ["penalty_k1e9_dt_omega", "penalty_k1e12_dt_omega"])
def test_penalty_stiff_with_the_step_from_sqrt_m_over_k(name):
    row = run(name)
    assert row.details["omega_dt"] == pytest.approx(0.2)
    assert row.passed and row.stable, row.outcome
    assert row.error <= 0.01 and row.details["delta_error"] <= 0.02


def test_penalty_1e12_at_the_coarse_step_stops_gracefully_in_every_phase():
    row = run("penalty_k1e12")
    assert row.passed and not row.finished, row.outcome
    runs = row.details["runs"]
    assert len(runs) == 5 and all(r["stopped"] for r in runs)
    assert all("too stiff for the step" in r["cause"] and r["t_stop"] < 2e-3 for r in runs)   # at the first impact


def test_penalty_1e9_at_the_coarse_step_stops_gracefully_in_every_phase():
    row = run("penalty_k1e9")
    assert row.details["omega_dt"] > 2.0
    assert row.passed, row.outcome


def test_penalty_1e12_adaptive_gives_the_rebound_speed():
    row = run("penalty_k1e12_adaptive")
    assert row.passed and row.error <= 1e-2, row.outcome


def test_penalty_1e12_adaptive_with_a_penetration_bound_finishes():
    row = run("penalty_k1e12_adaptive_bound")
    assert row.passed and row.finished, row.outcome


def test_grazing_is_contact_free_at_zero_offset_and_continuous_below():
    row = run("grazing")
    assert row.passed, row.outcome
    bound = row.details["bound"]
    for r in row.details["runs"]:
        if r["delta"] >= 0:
            assert r["error"] <= 1e-14 and r["u_after"][0] == pytest.approx(1.0, abs=1e-15)
        else:
            assert r["error"] <= bound
    deep = [r for r in row.details["runs"] if r["delta"] == -1e-3][0]
    assert deep["u_after"][2] == pytest.approx(cc.grazing_reference(-1e-3)[2], rel=0.01)


def test_contour_edge_inside_rebounds_outside_flies_free():
    row = run("contour_edge")
    assert row.passed and row.finished, row.outcome
    for r in row.details["runs"]:
        if r["x_minus_L"] < 0:
            assert r["u_after"][2] == pytest.approx(cc.ED_E * cc.ED_V0, rel=1e-9) and r["closed_steps"] >= 1
        else:
            assert r["closed_steps"] == 0 and r["u_after"] == [0.0, 0.0, -cc.ED_V0]
    slide = row.details["slide_off"]
    assert slide["max_|u_x − v|"] <= 1e-12 and slide["max_|z|_on_surface"] <= 1e-12
    assert slide["height_error"] <= 9.81 * 59.5e-4 * 1e-4          # g (T − t_e) Δt, quick Δt = 1e-4 s


def test_closed_cylinder_seam_keeps_the_circle():
    row = run("closed_seam_cylinder")
    assert row.passed, row.outcome
    d = row.details
    assert d["wraps"] == 2 and d["revolutions"] > 2
    assert d["radius_error_m"] <= 2 * d["predicted_radius_drift_m"] + d["shape_error_m"]
    assert d["speed_error"] <= 2 * d["predicted_speed_loss"]


def test_closed_ring_seam_keeps_the_mass_at_rest():
    row = run("closed_seam_ring")
    assert row.passed, row.outcome
    d = row.details
    assert d["wraps"] == 2 and d["eta_error"] <= 1e-7 and d["force_error"] <= 1e-9 and d["displacement_m"] <= 1e-12


@pytest.mark.parametrize("name", ["redundant_contacts_4", "redundant_contacts_8_newton"])
def test_redundant_contacts_hold_the_weight(name):
    row = run(name)
    assert row.passed, row.outcome
    d = row.details
    assert row.error <= 1e-8 and d["height_spread_m"] <= 1e-12 and d["penetration_growth_m"] <= 1e-12
    assert 0.5e-3 <= d["landing_step_t"] - d["t1"] < 1.5e-3          # first midpoint after t1, Δt = 1e-3 s


def test_redundant_frictional_contacts_stop_the_box_at_the_coulomb_distance():
    row = run("redundant_contacts_friction")
    assert row.passed, row.outcome
    assert abs(row.details["distance"] - row.details["distance_exact"]) <= 1.05 * 1e-3


@pytest.mark.parametrize("name, rel", [("zeno", 0.01), ("zeno_adaptive", 0.005)])
def test_zeno_time_rest_and_no_energy_gain(name, rel):
    row = run(name)
    assert row.passed and row.stable, row.outcome
    d = row.details
    t_Z = math.sqrt(2 * 0.5 / 9.81) * (1 + 0.5) / (1 - 0.5)      # t1 (1 + e)/(1 − e), H = 0.5 m, e = 0.5
    assert d["t_Z"] == pytest.approx(t_Z)
    assert abs(d["t_Z_num"] - t_Z) <= rel * t_Z
    assert d["energy_gain_over_bound"] <= 1.0 and d["rest_spread_m"] <= 1e-9


@pytest.mark.parametrize("name, m2", [("mass_ratio_1e-6", 1e-6), ("mass_ratio_1e6", 1e6)])
def test_mass_ratio_impact_velocities(name, m2):
    row = run(name)
    assert row.passed, row.outcome
    d = row.details
    v1 = (1.0 - m2 * 0.8) / (1.0 + m2)                 # momentum + restitution, m1 = 1 kg at 1 m/s
    v2 = 1.8 / (1.0 + m2)
    assert d["v1_after"] == pytest.approx(v1, rel=1e-9, abs=1e-12)
    assert d["v2_after"] == pytest.approx(v2, rel=1e-9)
    assert d["momentum_error"] <= 1e-12


def test_light_on_heavy_stack_rests():
    row = run("mass_ratio_stack_1e-6")
    assert row.passed and row.error <= 1e-6 and row.details["displacement_m"] <= 1e-9, row.outcome


def test_heavy_on_light_stack_stops_gauss_seidel_gracefully():
    row = run("mass_ratio_stack_1e6_gs")
    assert row.passed and not row.finished, row.outcome
    assert "not solved" in row.details["cause"] and row.details["step"] == 1


def test_heavy_on_light_stack_rests_with_newton():
    row = run("mass_ratio_stack_1e6_newton")
    assert row.passed, row.outcome
    assert row.details["steps_with_an_open_contact"] == 0 and np.isfinite(row.error)
