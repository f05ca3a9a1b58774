"""α–Ω decision boundaries (report Sec. 4.1 eq. 32, Sec. 5.4 Fig. 9) against an independent
simulation: the difference CoupledRB − SimpleRB on the report's free beam is the effect of the
fictitious forces SimpleRB neglects (validation case ``wobble_decoupling``)."""

import numpy as np
import pytest

from mbs.modal import ModalBasis
from validation.cases import _wobble as wb
from validation.cases import wobble_decoupling as case

X = np.array([1.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def beam():
    mesh, data = wb.beam(n_modes=10)
    basis = ModalBasis.from_body(data)
    return mesh, basis, case.boundaries(basis)


@pytest.mark.parametrize("omega", [0.1, 30.0])
def test_sudden_spin_stays_below_the_prediction(beam, omega):
    """Spin about x from rest, 0.05 s (9 first-mode periods): the measured coupling
    displacement [m] is at most the boundaries' k_dyn (d_omega |Ω|²), and close to it (the
    axial mode's step response peaks at twice its static value)."""
    _, basis, bounds = beam
    cmp = case.compare(basis, bounds, omega0=omega * X, t_end=0.05)
    assert cmp.omega == pytest.approx(omega, rel=1e-6)
    assert 0.9 < cmp.ratio <= 1.0


def test_recommendation_matches_the_measured_difference(beam):
    """SimpleRB is recommended for a slow spin and the simulated difference is indeed below
    d_negligible = 1 µm; a fast spin is not recommended SimpleRB and its difference exceeds 1 µm."""
    _, basis, bounds = beam
    slow = case.compare(basis, bounds, omega0=0.1 * X, t_end=0.05)
    fast = case.compare(basis, bounds, omega0=30.0 * X, t_end=0.05)
    assert slow.recommendation == "SimpleRB" and slow.measured < bounds.d_negligible
    assert fast.recommendation != "SimpleRB" and fast.measured > bounds.d_negligible


def test_couple_is_quasi_static(beam):
    """±100 kN couple (α ≈ 5.7 rad/s², report Fig. 6b): only the centrifugal load of the slowly
    growing Ω = α t deforms the free beam (d_alpha = 0 by inertia relief), without the dynamic
    amplification, so the measured difference is about half the prediction."""
    mesh, basis, bounds = beam
    cmp = case.compare(basis, bounds, loads=[wb.rotation_loads(mesh, 1e5)], t_end=0.05)
    assert bounds.d_alpha < 1e-12 * bounds.d_omega
    assert cmp.alpha == pytest.approx(5 * 1e5 / basis.inertia[0, 0], rel=0.01)
    assert 0.4 < cmp.ratio < 0.6
