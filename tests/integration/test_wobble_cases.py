"""The wobble_* validation cases (report Sec. 5.2, 5.5, 5.7.1, 6.2) in quick mode, run once
through the harness, asserted against their independent references: eq. 37's analytic
solution, energy conservation, beam theory and the FE static solution, and the identity
of boundary-approach results."""

import math

import numpy as np
import pytest

from validation.cases import wobble_boundary, wobble_energy, wobble_shear, wobble_step

from case_rows import quick_rows_by_case, select

pytestmark = pytest.mark.slow   # seconds each: left out of the fast subset (-m "not slow")

CASES = (wobble_step, wobble_energy, wobble_shear, wobble_boundary)


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    """{case name: rows} of one quick harness run of the four cases."""
    return quick_rows_by_case(tmp_path_factory.mktemp("wobble"), CASES)


def test_harness_accepts_all_four(rows):
    assert set(rows) == {case.NAME for case in CASES}
    for case_rows in rows.values():
        assert case_rows and all(math.isfinite(r["cpu_s"]) and r["cpu_s"] >= 0 for r in case_rows)


@pytest.mark.parametrize("forcing", ["non-resonant", "resonant"])
def test_step_midpoint_sampling_is_second_order(rows, forcing):
    """A midpoint step holds cos at the midpoint while the interval mean of cos is
    sinc(ω_F h/2) times it, so the leading error is (ω_F h)²/24 = (2π/n)²/24: 4.0e-4 at
    n = 64 steps per period (both cases measure 4.01e-4); bound 5e-4. Quartering h
    divides the error by 16 (second order) and the left-end error by 4 (first order)."""
    case = rows["wobble_step"]
    mid = {r["config"]["steps_per_period"]: r["error"] for r in select(case, forcing=forcing, rule="midpoint")}
    left = {r["config"]["steps_per_period"]: r["error"] for r in select(case, forcing=forcing, rule="left")}
    assert mid[64] < 5e-4
    assert 14.0 < mid[16] / mid[64] < 18.0
    assert 3.5 < left[16] / left[64] < 4.5
    assert left[64] > 20 * mid[64]


def test_step_response_cost_and_accuracy_independent_of_duration(rows):
    pulse = select(rows["wobble_step"], forcing="pulse")
    assert {r["config"]["T_start"] for r in pulse} == set(wobble_step.DURATIONS)
    assert all(r["error"] < 1e-14 for r in pulse)
    cpu = {r["config"]["T_start"]: r["cpu_s"] for r in pulse}
    # 1 s and 1000 s after the load change cost the same; at 1e6 s (ω t ~ 1e9 rad) libm's
    # argument reduction makes sin/cos slower, still far from a factor 1e6
    assert cpu[1e3] < 2.0 * cpu[1.0] and cpu[1e6] < 3.0 * cpu[1.0]


def test_single_mode_energy_bounds_at_round_off(rows):
    single = select(rows["wobble_energy"], part="single mode")
    assert len(single) == 3
    assert all(r["error"] < 1e-13 for r in single)


def test_simple_rb_spin_conserves_energy_and_coupled_rb_stays_bounded(rows):
    spin = rows["wobble_energy"]
    rkmk4 = select(spin, solver="SimpleRB", scheme="rkmk4")
    assert len(rkmk4) == 1 and rkmk4[0]["error"] < 1e-13
    coupled = select(spin, solver="CoupledRB")
    assert coupled and all(r["error"] < 1e-5 for r in coupled)


def test_shear_against_timoshenko_and_fe(rows):
    shear = rows["wobble_shear"]
    for quantity in ("ω1 (tip response)", "u(L)"):
        timoshenko = [r for r in select(shear, quantity=quantity) if r["reference"].startswith("Timoshenko")]
        assert {r["config"]["n_modes"] for r in timoshenko} == {1, 2, 4, 10}
        assert all(abs(r["error"]) < 0.05 for r in timoshenko)
    fe = {(r["config"]["quantity"], r["config"]["n_modes"]): r["error"] for r in shear
          if r["reference"].startswith("FE") and "n_modes" in r["config"]}
    # the response oscillates at the body's first eigenvalue; its mean converges to the FE static solution
    assert all(abs(fe[("ω1 (tip response)", n)]) < 1e-4 for n in (1, 2, 4, 10))
    assert abs(fe[("u(L)", 10)]) < abs(fe[("u(L)", 4)]) < abs(fe[("u(L)", 1)]) < 0.05
    assert abs(fe[("u(L)", 10)]) < 5e-3


def test_boundary_results_identical_to_all_nodes(rows):
    boundary = rows["wobble_boundary"]
    assert {r["config"]["mesh"] for r in boundary} == set(wobble_boundary.MESHES)
    assert all(r["error"] <= 1e-12 for r in boundary)
    assert all(r["surface_nodes"] < r["config"]["nodes"] for r in boundary)
    nodes = sorted({r["config"]["nodes"] for r in boundary})
    assert nodes[0] < 300 < 500 < nodes[1] < 700 < 1000 < nodes[2]
    assert np.all(np.isfinite([r["cpu_std"] for r in boundary]))
