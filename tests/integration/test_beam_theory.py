"""Tests of the analytic cantilever oracles in validation.beam_theory."""

import numpy as np
import pytest
from scipy.linalg import eigh

from ffrmbs.errors import ModelError
from validation.beam_theory import (
    cantilever_tip_deflection,
    euler_bernoulli_cantilever_frequencies,
    euler_bernoulli_cantilever_roots,
    rect_shear_coefficient,
    timoshenko_cantilever_frequencies,
)

# The report's steel beam: 1 x 1 x 5 m, nu = 0.
E, NU, RHO = 200e9, 0.0, 8000.0
G = E / (2 * (1 + NU))
KAPPA = rect_shear_coefficient(NU)


def section(h):
    """Area [m^2] and second moment [m^4] of a square h x h section."""
    return h * h, h**4 / 12


def timoshenko_fe_frequencies(E, G, kappa, I, rho, A, L, n_el=400, n=3):
    """Cantilever frequencies [rad/s] from a 1D Timoshenko finite-element model.

    Two-node elements with interdependent (Friedman-Kosmatka) interpolation: cubic w,
    quadratic psi, exact for the static Timoshenko beam; DOFs (w1, psi1, w2, psi2).
    Stiffness int EI psi'^2 + kappa G A (w' - psi)^2, consistent mass
    int rho A w^2 + rho I psi^2 (rotary inertia), both by 5-point Gauss quadrature.
    """
    le = L / n_el
    phi = 12 * E * I / (kappa * G * A * le**2)
    c = 1 / (1 + phi)
    gp, gw = np.polynomial.legendre.leggauss(5)
    xi, wq = (gp + 1) / 2, gw * le / 2
    one = np.ones_like(xi)
    Nw = c * np.array([2 * xi**3 - 3 * xi**2 - phi * xi + 1 + phi,
                       le * (xi**3 - (2 + phi / 2) * xi**2 + (1 + phi / 2) * xi),
                       -(2 * xi**3 - 3 * xi**2 - phi * xi),
                       le * (xi**3 - (1 - phi / 2) * xi**2 - phi / 2 * xi)])
    dNw = c / le * np.array([6 * xi**2 - 6 * xi - phi,
                             le * (3 * xi**2 - (4 + phi) * xi + 1 + phi / 2),
                             -(6 * xi**2 - 6 * xi - phi),
                             le * (3 * xi**2 - (2 - phi) * xi - phi / 2)])
    Np = c * np.array([6 / le * (xi**2 - xi),
                       3 * xi**2 - (4 + phi) * xi + 1 + phi,
                       -6 / le * (xi**2 - xi),
                       3 * xi**2 - (2 - phi) * xi])
    dNp = c / le * np.array([6 / le * (2 * xi - one),
                             6 * xi - (4 + phi) * one,
                             -6 / le * (2 * xi - one),
                             6 * xi - (2 - phi) * one])
    gamma = dNw - Np
    Ke = (E * I * dNp * wq) @ dNp.T + (kappa * G * A * gamma * wq) @ gamma.T
    Me = (rho * A * Nw * wq) @ Nw.T + (rho * I * Np * wq) @ Np.T
    ndof = 2 * (n_el + 1)
    K, M = np.zeros((ndof, ndof)), np.zeros((ndof, ndof))
    for e in range(n_el):
        s = slice(2 * e, 2 * e + 4)
        K[s, s] += Ke
        M[s, s] += Me
    free = slice(2, ndof)  # node 0 clamped: w = psi = 0
    lam = eigh(K[free, free], M[free, free], eigvals_only=True, subset_by_index=[0, n - 1])
    return np.sqrt(lam)


def test_euler_bernoulli_roots():
    roots = euler_bernoulli_cantilever_roots(3)
    np.testing.assert_allclose(roots, [1.87510407, 4.69409113, 7.85475744], atol=1e-7)
    assert np.all(np.abs(np.cos(roots) * np.cosh(roots) + 1) < 1e-9)


def test_euler_bernoulli_report_beam():
    A, I = section(1.0)
    omega = euler_bernoulli_cantilever_frequencies(E, I, RHO, A, 5.0, n=5)
    assert omega.shape == (5,)
    assert omega[0] == pytest.approx(203.0, abs=0.05)
    np.testing.assert_allclose(omega / omega[0], euler_bernoulli_cantilever_roots(5) ** 2 / 1.87510407**2,
                               rtol=1e-8)


def test_shear_coefficient():
    assert rect_shear_coefficient(0.0) == pytest.approx(5 / 6)
    assert rect_shear_coefficient(0.3) == pytest.approx(13 / 15.3)


def test_timoshenko_tends_to_euler_bernoulli_for_slender_beam():
    A, I = section(1.0)
    L = 1000.0
    eb = euler_bernoulli_cantilever_frequencies(E, I, RHO, A, L, n=3)
    timo = timoshenko_cantilever_frequencies(E, G, KAPPA, I, RHO, A, L, n=3)
    assert np.all(timo < eb)
    np.testing.assert_allclose(timo, eb, rtol=1e-4)


def test_timoshenko_correction_scales_with_slenderness_squared():
    A, I = section(1.0)
    d = [timoshenko_cantilever_frequencies(E, G, KAPPA, I, RHO, A, L, n=1)[0]
         / euler_bernoulli_cantilever_frequencies(E, I, RHO, A, L, n=1)[0] - 1 for L in (100.0, 200.0)]
    assert d[0] / d[1] == pytest.approx(4.0, rel=1e-2)


def test_timoshenko_stocky_beam_against_finite_elements():
    A, I = section(1.0)
    L = 5.0
    eb = euler_bernoulli_cantilever_frequencies(E, I, RHO, A, L, n=3)
    timo = timoshenko_cantilever_frequencies(E, G, KAPPA, I, RHO, A, L, n=3)
    fe = timoshenko_fe_frequencies(E, G, KAPPA, I, RHO, A, L, n_el=400, n=3)
    assert timo[0] < eb[0]
    np.testing.assert_allclose(timo, fe, rtol=1e-4)


def test_timoshenko_beyond_cutoff_against_finite_elements():
    """Very stocky beam (L/h = 2): higher modes above the cutoff sqrt(kappa G A/(rho I))."""
    A, I = section(1.0)
    L = 2.0
    timo = timoshenko_cantilever_frequencies(E, G, KAPPA, I, RHO, A, L, n=5)
    assert timo[-1] > np.sqrt(KAPPA * G * A / (RHO * I))
    fe = timoshenko_fe_frequencies(E, G, KAPPA, I, RHO, A, L, n_el=400, n=5)
    np.testing.assert_allclose(timo, fe, rtol=1e-4)


def test_tip_deflection():
    A, I = section(1.0)
    assert cantilever_tip_deflection(500.0, E, I, 5.0) == pytest.approx(1.25e-6, rel=1e-12)
    timo = cantilever_tip_deflection(500.0, E, I, 5.0, G=G, kappa=KAPPA, A=A)
    assert timo == pytest.approx(1.25e-6 + 500.0 * 5.0 / (KAPPA * G * A), rel=1e-12)
    with pytest.raises(ModelError):
        cantilever_tip_deflection(500.0, E, I, 5.0, G=G)
