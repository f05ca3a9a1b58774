"""The contact_point_mass_beam case (thesis Sec. 5.2) in quick mode, run once through the
harness: energy balance of every set-valued run, the contact closing at the analytic
10 ms, reduced models near the all-modes reference, band and 2s contour agreeing."""

import math

import pytest

from validation.cases import contact_point_mass_beam as case
from validation.harness import run_validation
from ffrmbs_app.scenes import point_mass_beam as pmb

pytestmark = pytest.mark.slow   # seconds each: left out of the fast subset (-m "not slow")


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("pmb")
    rows = run_validation(out, quick=True, cases=[case], progress=None)
    assert (out / "contact_point_mass_beam_outputs.png").exists()
    return rows


def pick(rows, kind, **config):
    return [r for r in rows if r["error_kind"] == kind and all(r["config"].get(k) == v for k, v in config.items())]


def test_every_configuration_reports_three_errors_and_its_cost(rows):
    configs = {tuple(sorted(r["config"].items())) for r in rows}
    assert len(rows) == 3 * len(configs) and len(configs) >= 5
    assert all(math.isfinite(r["error"]) and r["cpu_s"] > 0 for r in rows)


def test_energy_balance_closes_with_the_impulse_work(rows):
    """E(T) − E(0) − Σ Λᵀ(γ⁺ + γ⁻)/2 is the integrator's own energy error: with θ = 0.5
    (no numerical damping of the modes) it stays far below the impact losses."""
    for r in rows:
        assert abs(r["energy_residual"]) < 1e-3, r["config"]


def test_reduced_models_follow_the_all_modes_reference(rows):
    """20 modes at Δt = 1e-5 against all 750 modes at a fine step: the point mass's
    path within 0.2 mm (of a 3 mm travel), node 19 within 10 % RMS of its peak."""
    for r in pick(rows, "y max [m]", modes=20):
        assert r["error"] < 2e-4, r["config"]
    for r in pick(rows, "node 19 RMS / peak", modes=20):
        assert r["error"] < 0.1, r["config"]


def test_adaptive_controls_the_penetration_by_its_tolerance(rows):
    for r in pick(rows, "y max [m]", integrator="moreau-adaptive"):
        assert r["max_penetration"] <= 2 * r["config"]["atol"] + 1e-12
        assert r["steps"] < 0.03 / 1e-5 / 2                  # fewer than half the fixed steps


def test_the_contact_closes_when_the_mass_has_fallen_two_millimetres():
    data = pmb.default_beam_data()
    scene, res, _ = case._simulate(data, t_end=0.0105)
    closed = res.trace["t"][res.trace["closed"] > 0]
    assert closed.size and abs(closed[0] - 0.010) <= 1e-5 + 1e-12


def test_band_and_2s_contour_agree_in_setup_a(rows):
    """Setup A lies on the band's centre line, where band and 2s contour describe the
    same surface to interpolation accuracy."""
    two, band = (pick(rows, "y max [m]", sweep="contour", contour=c)[0] for c in ("2s", "band"))
    assert abs(two["error"] - band["error"]) < 2e-5
