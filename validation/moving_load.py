"""Analytic oracle: an Euler–Bernoulli cantilever under a constant force moving along it.

Independent of ffrmbs (numpy only, plus the cantilever roots of
:mod:`validation.beam_theory`). SI units: E [Pa], I [m⁴], ρ [kg/m³], A [m²], L [m],
force P [N], speed c [m/s], x [m], t [s], deflection w [m].

Beam: w(x, t) transverse deflection of a prismatic cantilever, clamped at x = 0
(w = w' = 0), free at x = L (w'' = w''' = 0), undamped, at rest at t = 0,

    ρA ẅ + EI w'''' = P δ(x − x_P(t)),      x_P(t) = x0 + c t,   0 <= x_P <= L.

Modal series (Rao, *Vibration of Continuous Systems*, 2nd ed. 2019, ch. 11.5 and the
moving-load problem of ch. 11.13; Frýba, *Vibration of Solids and Structures under
Moving Loads*, 1972, ch. 1): w = Σ_n φ_n(x) q_n(t) with the mass-normalized clamped–free
modes (∫_0^L ρA φ_m φ_n dx = δ_mn [-], φ_n [kg^-½])

    φ_n(x) = C [cosh βx − cos βx − σ_n (sinh βx − sin βx)],   C = (ρ A L)^-½,
    σ_n = (cosh β_nL + cos β_nL)/(sinh β_nL + sin β_nL),   cos β_nL cosh β_nL = −1,
    ω_n = β_n² (EI/(ρA))^½  [rad/s];

each modal coordinate obeys q̈_n + ω_n² q_n = P φ_n(x0 + c t) and, from rest, Duhamel's
integral q_n(t) = (1/ω_n) ∫_0^t sin ω_n(t − τ) P φ_n(x0 + c τ) dτ.

Closed form of the Duhamel integral. In overflow-free form

    φ_n(x)/C = a e^{β(x−L)} + b e^{−βx} + Re[(−1 − iσ) e^{iβx}],
    a = (1 − σ) e^{βL}/2 = (sin βL − cos βL − e^{−βL}) / (1 − e^{−2βL} + 2 e^{−βL} sin βL),
    b = (1 + σ)/2,

so the load P φ_n(x0 + cτ) is a sum of exponentials g e^{sτ} with s = βc, −βc, iβc
(the last term's real part). For each, q̈ + ω² q = e^{st} from rest gives

    (1/ω) ∫_0^t sin ω(t − τ) e^{sτ} dτ = [e^{st} − cos ωt − (s/ω) sin ωt] / (s² + ω²),

valid for complex s with s² ≠ −ω², i.e. away from the critical speeds c = ω_n/β_n
(at least 4.2 m/s for the beam of thesis Sec. 5.3; a ModelError is raised near one).
The series converges like 1/n⁴ for the deflection (the load's modal amplitude φ_n(x_P)
is bounded, ω_n² grows like n⁴); :func:`CantileverEB.moving_load_response` sums
``n_modes`` terms (default 60: the truncation error of the first tip deflection is below
1e-6 relative).

Static limit (c = 0, the load held at a): Σ_n φ_n(x) φ_n(a)/ω_n² P = the cantilever's
influence function P x² (3a − x)/(6 EI) for x <= a, P a² (3x − a)/(6 EI) for x >= a
(:func:`static_cantilever_deflection`); with c = 0 the response from rest is the static
deflection times (1 − cos ω_n t) per mode.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError
from validation.beam_theory import euler_bernoulli_cantilever_roots


def static_cantilever_deflection(x, a, P, E, I):
    """Deflection w(x) [m] of a cantilever (clamped at x = 0) under a static force P [N] at
    x = a [m]: P x²(3a − x)/(6EI) for x <= a, P a²(3x − a)/(6EI) for x >= a (Gere &
    Timoshenko, *Mechanics of Materials*, App. G, case 5)."""
    x = np.asarray(x, dtype=float)
    return np.where(x <= a, P * x**2 * (3 * a - x), P * a**2 * (3 * x - a)) / (6.0 * E * I)


class CantileverEB:
    """The first ``n_modes`` modes of a prismatic Euler–Bernoulli cantilever (module docstring).

    Attributes: ``beta`` (n,) [1/m], ``omega`` (n,) [rad/s], ``sigma``, ``a``, ``b`` (n,)
    the coefficients of the overflow-free mode shape, ``C`` [kg^-½].
    """

    def __init__(self, E, I, rho, A, L, n_modes=60):
        if min(E, I, rho, A, L) <= 0:
            raise ModelError("CantileverEB: E, I, rho, A and L must be positive")
        self.E, self.I, self.rho, self.A, self.L = map(float, (E, I, rho, A, L))
        bl = euler_bernoulli_cantilever_roots(int(n_modes))
        self.beta = bl / self.L
        self.omega = self.beta**2 * np.sqrt(self.E * self.I / (self.rho * self.A))
        e = np.exp(-bl)
        self.sigma = (1.0 + np.cos(bl) * 2 * e / (1 + e * e)) / (np.tanh(bl) + np.sin(bl) * 2 * e / (1 + e * e))
        self.a = (np.sin(bl) - np.cos(bl) - e) / (1.0 - e * e + 2.0 * e * np.sin(bl))
        self.b = 0.5 * (1.0 + self.sigma)
        self.C = 1.0 / np.sqrt(self.rho * self.A * self.L)

    @property
    def n_modes(self) -> int:
        return self.beta.size

    def mode_shapes(self, x, derivative=0) -> np.ndarray:
        """φ_n^(k)(x) (n_modes, len(x)) [kg^-½ m^-k], the k-th x-derivative (k >= 0) of the
        mass-normalized modes at x [m] in [0, L]."""
        x = np.atleast_1d(np.asarray(x, dtype=float))[None, :]
        k = int(derivative)
        be, a, b, s = (v[:, None] for v in (self.beta, self.a, self.b, self.sigma))
        trig = ((-1 - 1j * s) * (1j) ** k * np.exp(1j * be * x)).real
        return self.C * be**k * (a * np.exp(be * (x - self.L)) + (-1) ** k * b * np.exp(-be * x) + trig)

    def static_deflection(self, x, a, P) -> np.ndarray:
        """Σ_n φ_n(x) φ_n(a) P/ω_n² [m]: the truncated modal series of the static deflection
        at x under a force P [N] at a [m]."""
        phi_x = self.mode_shapes(x)
        phi_a = self.mode_shapes([a])[:, 0]
        return (phi_a / self.omega**2) @ phi_x * P

    def modal_response(self, t, P, c, x0=0.0) -> np.ndarray:
        """q_n(t) (len(t), n_modes) [kg^½ m] from rest under the force P [N] at
        x0 + c t (closed-form Duhamel integral, module docstring). The load must stay on
        the beam: 0 <= x0 + c t <= L for all t (else ModelError)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
        xp = x0 + c * t
        if t.min() < 0 or xp.min() < -1e-12 or xp.max() > self.L * (1 + 1e-12):
            raise ModelError(f"the load leaves the beam [0, {self.L}] m: x_P from {xp.min():.4g} "
                             f"to {xp.max():.4g} m (t >= 0 required)")
        be, w, a, b, s = self.beta, self.omega, self.a, self.b, self.sigma
        if np.any(np.abs((be * c) ** 2 / w**2 - 1.0) < 1e-9):
            raise ModelError(f"c = {c} m/s is a critical speed ω_n/β_n of the cantilever")
        wt = w * t
        cos_wt, sin_wt = np.cos(wt), np.sin(wt)
        # real exponent s = +βc, coefficient a e^{β(x0 − L)}: combine the exponents
        s1 = be * c
        q = a * (np.exp(be * (xp - self.L)) - np.exp(be * (x0 - self.L)) * (cos_wt + s1 / w * sin_wt)) \
            / (s1**2 + w**2)
        # s = −βc, coefficient b e^{−β x0}
        s2 = -be * c
        q += b * (np.exp(-be * xp) - np.exp(-be * x0) * (cos_wt + s2 / w * sin_wt)) / (s2**2 + w**2)
        # s = iβc, coefficient (−1 − iσ) e^{iβ x0}; the real part
        s3 = 1j * be * c
        g = (-1 - 1j * s) * np.exp(1j * be * x0)
        q += (g * (np.exp(s3 * t) - cos_wt - s3 / w * sin_wt) / (s3**2 + w**2)).real
        return P * self.C * q

    def moving_load_response(self, x, t, P, c, x0=0.0) -> np.ndarray:
        """w(x, t) (len(t), len(x)) [m]: the deflection at x [m] and times t [s] under the
        force P [N] (along +w) moving at c [m/s] from x0 [m] (module docstring)."""
        return self.modal_response(t, P, c, x0) @ self.mode_shapes(x)
