"""Analytic references for a prismatic cantilever (clamped at x = 0, free at x = L).

Independent oracles for the validation cases: they use no part of ffrmbs. SI units
throughout: E, G [Pa], I [m^4], rho [kg/m^3], A [m^2], L [m], F [N]; frequencies are
circular frequencies omega [rad/s], deflections [m].

References
----------
S. S. Rao, *Vibration of Continuous Systems*, 2nd ed., Wiley 2019: ch. 11.5
(Euler-Bernoulli cantilever, eq. cos(bL) cosh(bL) = -1) and ch. 11.14 (Timoshenko
beam equations).
G. R. Cowper, "The shear coefficient in Timoshenko's beam theory",
J. Appl. Mech. 33 (1966) 335-340 (shear coefficient of a rectangle).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

from ffrmbs.errors import ModelError


def _eb_characteristic(beta_L):
    """cos(bL) + 1/cosh(bL): the cantilever equation cos cosh = -1 divided by cosh."""
    return np.cos(beta_L) + 1.0 / np.cosh(beta_L)


def euler_bernoulli_cantilever_roots(n=5):
    """The first ``n`` roots beta_k L of cos(beta L) cosh(beta L) = -1.

    The k-th root lies in ((k-1) pi, k pi) (near (2k-1) pi / 2), where the scaled
    equation cos(bL) + 1/cosh(bL) = 0 changes sign; each is refined by Brent's method.
    Returns an array of shape (n,), dimensionless: 1.87510407, 4.69409113, 7.85475744, ...
    """
    return np.array([brentq(_eb_characteristic, (k - 1) * np.pi, k * np.pi, xtol=1e-15, rtol=1e-15)
                     for k in range(1, n + 1)])


def euler_bernoulli_cantilever_frequencies(E, I, rho, A, L, n=5):
    """First ``n`` bending eigenfrequencies omega_k [rad/s] of an Euler-Bernoulli cantilever.

    omega_k = (beta_k L)^2 sqrt(E I / (rho A L^4)), with beta_k L the roots of
    cos(beta L) cosh(beta L) = -1 (Rao 2019, ch. 11.5). Shear deformation and rotary
    inertia are neglected. Returns an array of shape (n,).
    """
    return euler_bernoulli_cantilever_roots(n) ** 2 * np.sqrt(E * I / (rho * A * L**4))


def _timoshenko_characteristic(Omega, r2, phi):
    """det of the free-end block of the transfer matrix of a clamped Timoshenko beam.

    Dimensionless state y = [w/L, psi, M L/(EI), Q L^2/(EI)] over xi = x/L obeys
    y' = A y with (Omega^2 = rho A omega^2 L^4/(EI), r2 = I/(A L^2), phi = EI/(kappa G A L^2))

        w' = psi + phi Q,  psi' = M,  M' = -Q - Omega^2 r2 psi,  Q' = -Omega^2 w.

    Clamped (w = psi = 0 at xi = 0), free (M = Q = 0 at xi = 1): a mode exists iff
    det T[2:, 2:] = 0 with T = expm(A). The function is entire and real in Omega^2,
    so simple roots are sign changes. ``Omega`` may be an array (vectorized).
    """
    Omega2 = np.asarray(Omega, dtype=float) ** 2
    system = np.zeros(Omega2.shape + (4, 4))
    system[..., 0, 1] = 1.0
    system[..., 0, 3] = phi
    system[..., 1, 2] = 1.0
    system[..., 2, 1] = -Omega2 * r2
    system[..., 2, 3] = -1.0
    system[..., 3, 0] = -Omega2
    return np.linalg.det(expm(system)[..., 2:, 2:])


def timoshenko_cantilever_frequencies(E, G, kappa, I, rho, A, L, n=5):
    """First ``n`` bending eigenfrequencies omega_k [rad/s] of a Timoshenko cantilever.

    Timoshenko beam with shear deformation and rotary inertia (Rao 2019, ch. 11.14),
    deflection w(x), cross-section rotation psi(x), harmonic in time at omega:

        kappa G A (w'' - psi') + rho A omega^2 w = 0,
        E I psi'' + kappa G A (w' - psi) + rho I omega^2 psi = 0,

    clamped at x = 0 (w = psi = 0), free at x = L (E I psi' = 0, kappa G A (w' - psi) = 0).
    The boundary-value problem is written as a first-order transfer matrix (see
    ``_timoshenko_characteristic``); the frequency equation det = 0 is scanned on a fine
    grid of sqrt(Omega) (= beta L in the Euler-Bernoulli limit) from 0 up to the n-th
    Euler-Bernoulli root, and each sign change is refined by Brent's method. The scan
    bound is safe: by the min-max principle each Timoshenko frequency lies below the
    Euler-Bernoulli one of the same index (infinite shear stiffness is a constraint,
    rotary inertia adds mass). ``kappa`` is the shear coefficient, e.g.
    :func:`rect_shear_coefficient`. Returns an array of shape (n,).
    """
    r2 = I / (A * L**2)
    phi = E * I / (kappa * G * A * L**2)
    beta_L_max = euler_bernoulli_cantilever_roots(n)[-1] * (1.0 + 1e-9)
    beta_L = np.linspace(1e-3, beta_L_max, int(np.ceil(beta_L_max / 2e-3)) + 1)
    values = _timoshenko_characteristic(beta_L**2, r2, phi)
    brackets = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[:n]
    Omega = np.array([brentq(_timoshenko_characteristic, beta_L[i] ** 2, beta_L[i + 1] ** 2,
                             args=(r2, phi), xtol=1e-14, rtol=1e-14) for i in brackets])
    if Omega.size < n:
        raise RuntimeError(f"found {Omega.size} of {n} Timoshenko frequencies below the "
                           "Euler-Bernoulli bound; the scan grid is too coarse")
    return Omega * np.sqrt(E * I / (rho * A * L**4))


def rect_shear_coefficient(nu):
    """Cowper's shear coefficient of a rectangular cross-section, kappa = 10(1+nu)/(12+11nu).

    Dimensionless; ``nu`` is Poisson's ratio (kappa = 5/6 for nu = 0). Cowper (1966), Table 1.
    """
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)


def cantilever_tip_deflection(F, E, I, L, G=None, kappa=None, A=None):
    """Static tip deflection [m] of a cantilever under a transverse tip force F [N].

    Euler-Bernoulli: delta = F L^3 / (3 E I). When the shear data G [Pa], kappa [-] and
    A [m^2] are all given, the Timoshenko shear part F L / (kappa G A) is added
    (Rao 2019, ch. 11.14; exact for the Timoshenko beam).
    """
    bending = F * L**3 / (3.0 * E * I)
    shear_data = (G, kappa, A)
    if all(v is None for v in shear_data):
        return bending
    if any(v is None for v in shear_data):
        raise ModelError("shear deflection needs all of G, kappa and A")
    return bending + F * L / (kappa * G * A)
