"""The ffr_frequencies validation case (thesis Sec. 5.1, Table 5.2) against independent oracles.

Oracles: known parameters of synthetic damped sinusoids (the frequency estimator); the
exact discrete frequency of the trapezoidal rule, tan(ω_d h/2) = ω h/2, which
generalized-α with ρ∞ = 1 reduces to (Newmark β = ¼, γ = ½); and the thesis's 0.2 %.
"""

import math

import numpy as np
import pytest

from validation.cases import ffr_frequencies as case

pytestmark = pytest.mark.slow   # seconds each: left out of the fast subset (-m "not slow")


@pytest.mark.parametrize("theta, sigma_dt, phase", [(0.01, 0.0, 0.3), (0.4, 0.0, 1.0),
                                                    (0.02, 1e-4, -0.7), (2.0, 3e-3, 2.0)])
def test_measure_frequency_recovers_a_damped_sinusoid(theta, sigma_dt, phase):
    dt = 1e-5
    n = np.arange(int(20 * 2 * np.pi / theta) + 3)
    q = 0.37 * np.exp(-sigma_dt * n) * np.sin(theta * n + phase)
    omega_d, sigma, residual = case.measure_frequency(q, dt)
    assert omega_d == pytest.approx(theta / dt, rel=1e-11)
    assert sigma * dt == pytest.approx(sigma_dt, abs=1e-12)
    assert residual < 1e-9


@pytest.fixture(scope="module")
def quick():
    return case.run(quick=True)


@pytest.fixture(scope="module")
def omega_fe():
    return case.beam().frequencies()[0]


def series(result):
    """{(integrator, rho_inf): rows sorted by steps per period}."""
    out = {}
    for row in result.rows:
        cfg = row["config"]
        out.setdefault((cfg["integrator"], cfg.get("rho_inf")), []).append(row)
    return {k: sorted(v, key=lambda r: r["config"]["steps_per_period"]) for k, v in out.items()}


def test_rows_follow_the_protocol_and_cover_the_sweep(quick):
    assert {r["case"] for r in quick.rows} == {"ffr_frequencies"}
    assert {r["error_kind"] for r in quick.rows} == {"relative"}
    assert {r["reference"] for r in quick.rows} == {"FE eigenfrequencies"}
    assert set(series(quick)) == {("generalized-alpha", 1.0), ("generalized-alpha", 0.9), ("rk4", None)}
    for row in quick.rows:
        errs = [row[f"err_f{i}"] for i in range(1, 6)]
        assert row["error"] == pytest.approx(max(abs(e) for e in errs), rel=1e-15)
        assert row["cpu_s"] > 0


def test_errors_decrease_with_the_step(quick):
    for key, rows in series(quick).items():
        errors = [r["error"] for r in rows]
        assert len(errors) >= 3, key
        assert all(b < a for a, b in zip(errors, errors[1:])), (key, errors)


def test_finest_generalized_alpha_within_thesis_table_5_2(quick):
    for key, rows in series(quick).items():
        if key[0] == "generalized-alpha":
            assert rows[-1]["error"] < 2e-3, key


def test_rk4_unstable_step_skipped_not_dropped(quick):
    rk4 = series(quick)[("rk4", None)]
    assert all(r["h_omega5"] < case.RK4_LIMIT for r in rk4)
    assert min(r["config"]["steps_per_period"] for r in rk4) > 2
    assert any("rk4, N = 2: skipped" in s for s in quick.skipped)


def test_rho_1_matches_trapezoidal_period_elongation(quick, omega_fe):
    """Mode 1 (and the others): ω_d h = 2 arctan(ω h / 2) exactly for the trapezoidal rule."""
    for row in series(quick)[("generalized-alpha", 1.0)]:
        h = row["dt_s"]
        for i in range(5):
            w = omega_fe[i]
            exact = 2 * math.atan(w * h / 2) / (w * h) - 1
            assert row[f"err_f{i + 1}"] == pytest.approx(exact, rel=1e-5), (row["config"], i)


def test_observed_orders(quick):
    """Generalized-α period error O(h²), RK4 O(h⁴), between the two finest steps."""
    expected = {"generalized-alpha": 2.0, "rk4": 4.0}
    for key, rows in series(quick).items():
        (n0, e0), (n1, e1) = [(r["config"]["steps_per_period"], r["error"]) for r in rows[-2:]]
        order = math.log(e0 / e1) / math.log(n1 / n0)
        assert order == pytest.approx(rows[-1]["observed_order"], rel=1e-12)
        assert order == pytest.approx(expected[key[0]], abs=0.05), key
