"""The stability suite's body cases in quick mode: each row against its own criteria, plus
the references themselves checked independently (the flip period against scipy's
DOP853, the symmetric top against Euler's equations by finite differences).

Two cases do not pass today and are marked xfail(strict=True) with the reason: Moreau's
stiff modes gain energy when started with a velocity (the midpoint position update is
explicit in u_k; see the report of issue 8), and a free body whose frame origin is off
its centre of mass drifts (generalized-α on R³ × SO(3)). The claims of those cases that
do hold are asserted in separate tests. When mbs is fixed the xfail tests fail (XPASS
strict) and should become plain tests.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from validation.stability import CASES
from validation.stability import body_cases as bc

pytestmark = pytest.mark.stability

_rows = {}


def row_of(name):
    """The quick row of a case, run once per test session."""
    if name not in _rows:
        _rows[name] = CASES[name].run(True)
    return _rows[name]


# --- stiff modes -------------------------------------------------------------------------

def test_stiff_modes_generalized_alpha():
    """ρ∞ = 0.5 at ω_maxΔt = 1e2, 1e3, 1e4: energy never above E(0), the stiff modes
    damped, the resolved modes within (ωΔt)² ω t_end of the exact modal solution."""
    row = row_of("stiff_modes/generalized-alpha")
    assert row.passed, row.outcome
    runs = row.details["runs"]
    assert max(r["omega_max_dt"] for r in runs) == 1e4
    omega = np.array(row.details["omega"])
    for r in runs:
        assert r["omega_max_dt"] == pytest.approx(omega.max() * r["dt"], rel=1e-12)
        assert r["omega_max_dt_run"] == pytest.approx(r["omega_max_dt"], rel=1e-9)     # every step was Δt
        assert r["energy_growth"] <= 1e-9 and r["stiff_amplitude_ratio"] < 1.0
        assert r["resolved_modes"] and all(e <= b for e, b in zip(r["resolved_error"], r["resolved_bound"]))


@pytest.mark.parametrize("name", ["stiff_modes/moreau-theta1", "stiff_modes/moreau-theta0.5"])
def test_stiff_modes_moreau_stays_finite_and_resolves_the_low_modes(name):
    row = row_of(name)
    assert row.finished
    for r in row.details["runs"]:
        assert r["finite"] and r["resolved_modes"]
        assert all(e <= b for e, b in zip(r["resolved_error"], r["resolved_bound"])), r


@pytest.mark.parametrize("name", ["stiff_modes/moreau-theta1", "stiff_modes/moreau-theta0.5"])
def test_stiff_modes_moreau_energy_does_not_grow(name):
    """M̂ = M + θΔt D + θ²Δt² K with the θ-method's position update: energy never above
    E(0) at ω_maxΔt up to 1e4; θ = 1/2 conserves it, θ = 1 damps the stiff modes."""
    row = row_of(name)
    assert row.passed, row.outcome
    for r in row.details["runs"]:
        assert r["energy_growth"] <= 1e-9
        if name.endswith("0.5"):
            assert r["energy_end_ratio"] == pytest.approx(1.0, abs=1e-6)
        else:
            assert r["energy_end_ratio"] < 0.9


# --- hundred revolutions -----------------------------------------------------------------

def test_hundred_revolutions_energy_and_orientation():
    m = row_of("hundred_revolutions").details
    assert m["revolutions"] == 10 and m["finite"]
    assert m["energy_drift"] <= bc.REVOLUTION_BOUNDS["energy"]
    assert m["orientation_error"] <= bc.REVOLUTION_BOUNDS["orientation"]


def test_hundred_revolutions_drift_is_second_order_error():
    """The centre-of-mass drift of the R³ x SO(3) update, ≈ (ΩΔt)² Ω |c⊥| t / 12, falls by
    ~4 at half the step (an error, not an instability)."""
    row = row_of("hundred_revolutions")
    assert row.passed, row.outcome
    m = row.details
    assert 3.0 <= m["com_drift_ratio"] <= 5.0 and 3.0 <= m["momentum_drift_ratio"] <= 5.0
    predicted = m["omega_dt"] ** 2 * bc.SPIN * m["lever_m"] * m["t_end"] / 12
    assert m["com_drift_m"] == pytest.approx(predicted, rel=0.5)


# --- tennis racket -----------------------------------------------------------------------

def test_tennis_racket_flip_period():
    row = row_of("tennis_racket")
    assert row.passed, row.outcome
    run = row.details["runs"][0]
    assert run["periods"] and row.error <= 1e-3
    assert all(abs(a - b) <= 1e-3 * run["T_analytic"] for a, b in zip(run["flip_times"], run["flip_times_analytic"]))
    assert row.details["rk4_period_error"] <= 1e-7


def test_flip_period_against_dop853():
    """The closed form for other moments and tilt, against scipy's DOP853 (not our RK4)."""
    I = (1.0, 2.5, 3.0)
    w0 = (0.0, 2.0, 0.05)
    T, wp, m = bc.flip_period(I, w0)

    def euler(t, w):
        return [(I[1] - I[2]) / I[0] * w[1] * w[2], (I[2] - I[0]) / I[1] * w[2] * w[0],
                (I[0] - I[1]) / I[2] * w[0] * w[1]]

    def flip(t, w):
        return w[1]
    sol = solve_ivp(euler, (0.0, 2.2 * T), w0, method="DOP853", rtol=1e-12, atol=1e-12, events=flip)
    flips = sol.t_events[0]
    assert len(flips) >= 4
    np.testing.assert_allclose(np.diff(flips), T / 2, rtol=1e-8)
    assert bc.periods_from_flips(bc.euler_rk4_crossings(I, w0, 2.2 * T, 1e-3)) == pytest.approx([T] * 3, rel=1e-8)


# --- Cardan singularity ------------------------------------------------------------------

def test_cardan_singularity():
    row = row_of("cardan_singularity")
    assert row.passed, row.outcome
    q1, q2 = row.details["quaternion_dt_0.001"]["error_rad"], row.details["quaternion_dt_0.0005"]["error_rad"]
    assert q1 <= 1e-3 and 2.8 <= q1 / q2 <= 5.2                 # second order through β = 90°
    cardan = row.details["cardan"]
    assert cardan["stopped"] or cardan["error_rad"] > 1e-2
    if cardan["stopped"]:
        assert "Cardan stopped gracefully" in row.outcome and cardan["t"] <= row.details["t_singular"] + 0.01


def test_symmetric_top_reference_solves_euler_and_meets_the_singularity():
    """The analytic top against Euler's equations (ω̄ from central differences of A(t)) and
    its axis through inertial x (sin β = A[0, 2] = 1) at the time top_initial_orientation says."""
    A0, t_sing, period = bc.top_initial_orientation()
    I = np.array(bc.TOP_INERTIA)
    h = 1e-5

    def w_bar(t):
        A = bc.symmetric_top(t, A0)
        S = A.T @ (bc.symmetric_top(t + h, A0) - bc.symmetric_top(t - h, A0)) / (2 * h)     # ω̄~ = Aᵀ Ȧ
        return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])  # its axial vector
    np.testing.assert_allclose(w_bar(0.0), bc.TOP_OMEGA, atol=1e-8)
    for t in np.linspace(0.1, period, 7):
        wd = (w_bar(t + 1e-4) - w_bar(t - 1e-4)) / 2e-4
        w = w_bar(t)
        np.testing.assert_allclose(I * wd + np.cross(w, I * w), 0.0, atol=1e-5)
    assert bc.symmetric_top(t_sing, A0)[0, 2] == pytest.approx(1.0, abs=1e-12)
    assert bc.symmetric_top(0.0, A0)[0, 2] < 0.99


# --- spin near the first bending frequency -----------------------------------------------

def test_spin_near_bending_warns_once_at_the_crossing():
    row = row_of("spin_near_bending")
    assert row.passed, row.outcome
    above, below = row.details["above"], row.details["below"]
    assert below["events"] == [] and below["warnings"] == []
    assert len(above["events"]) == 1 and len(above["warnings"]) == 1
    t_warn = above["events"][0][0]
    assert above["t_cross"] <= t_warn <= above["t_cross"] + above["sample_dt"] * (1 + 1e-9)
    assert above["events"][0][2] == pytest.approx(above["alpha"] * t_warn, rel=1e-9)   # |Ω| = α t
