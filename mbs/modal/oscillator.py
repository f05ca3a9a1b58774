"""Exact response of uncoupled modal oscillators to step loads (report eq. 6–12).

Each mode obeys r̈ + 2σ ṙ + ω² r = 𝓕(t) (eq. 6; σ = ζω adds the Rayleigh damping
of report Sec. 7.1, σ = (a + b ω²)/2 for C = aM + bK). With 𝓕 constant on
[s_k, s_{k+1}) the state x = (r, ṙ) moves exactly by

    x(s_k + τ) = C(τ) x(s_k) + g(τ) 𝓕_k,
    C(τ) = e^{−στ} [[c + σ s, s], [−ω² s, c − σ s]],   g = ((1 − C₁₁)/ω², e^{−στ} s),

with ν² = ω² − σ², c = cos ντ, s = sin(ντ)/ν (cosh / sinh over μ = √(σ² − ω²) when
overdamped, 1 and τ when critical). Undamped, this is eq. 10: the homogeneous part
A sin(ωt + φ) plus Σ_j Δ𝓕^(j)/ω² (1 − cos ω(t − t^(j))). Rigid modes (ω² = 0, eq. 13)
move by C = [[1, τ], [0, 1]], g = (τ²/2, τ) and are not damped.

The report's recursion (eq. 11–12) carries an amplitude α^(n) and phase β^(n) per load
step, so each step costs O(1) instead of a sum over the whole load history. We carry
the same information as the state x at the load times, in time measured from the
load time: this is the recursion of eq. 12 with the phase referred to t^(n), which
keeps ωt small (eq. 12's absolute phases ω t lose digits as t grows) and covers
damping. Two typos in the report are corrected by this derivation: eq. 11 must read
β = atan2(C, D) (not atan2(C, α)), and the new term of eq. 12 is
−Δ𝓕^(n)/ω² cos(ω(t − t^(n))), i.e. θ = −ω t^(n). Eq. 8's φ = asin(r₀/A) also loses
the sign of ṙ₀; the right phase is φ = atan2(r₀, ṙ₀/ω).
"""

from __future__ import annotations

import numpy as np

_SERIES = 1e-8   # |ν²| τ² below this: use the series of c and s


def transition(omega2, sigma, tau):
    """(C11, C12, C21, C22, g1, g2) of the exact step (module docstring), broadcast over
    ``omega2`` [rad²/s²], ``sigma`` [1/s] (modes) and ``tau`` [s] (times)."""
    omega2, sigma, tau = np.broadcast_arrays(np.asarray(omega2, float), np.asarray(sigma, float),
                                             np.asarray(tau, float))
    rigid = omega2 == 0.0
    sig = np.where(rigid, 0.0, sigma)
    nu2 = omega2 - sig * sig
    x = nu2 * tau * tau
    a = np.sqrt(np.abs(nu2))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        # e^{−στ} c and e^{−στ} s, stable also for heavily overdamped modes
        under = x > _SERIES
        over = x < -_SERIES
        ec_u = np.exp(-sig * tau) * np.cos(a * tau)
        es_u = np.exp(-sig * tau) * np.sin(a * tau) / a
        ep = np.exp((a - sig) * tau)
        em = np.exp(-(a + sig) * tau)
        ec_o = 0.5 * (ep + em)
        es_o = 0.5 * (ep - em) / a
        ser_c = np.exp(-sig * tau) * (1.0 - x / 2.0 + x * x / 24.0)
        ser_s = np.exp(-sig * tau) * tau * (1.0 - x / 6.0 + x * x / 120.0)
        ec = np.where(under, ec_u, np.where(over, ec_o, ser_c))
        es = np.where(under, es_u, np.where(over, es_o, ser_s))
    C11 = ec + sig * es
    C12 = es
    C21 = -omega2 * es
    C22 = ec - sig * es
    with np.errstate(divide="ignore", invalid="ignore"):
        # undamped: 1 − cos ντ = 2 sin²(ντ/2) avoids the cancellation for small ντ
        g1_undamped = 2.0 * np.sin(0.5 * a * tau) ** 2 / np.where(rigid, 1.0, omega2)
        g1_general = (1.0 - C11) / np.where(rigid, 1.0, omega2)
    g1 = np.where(rigid, 0.5 * tau * tau, np.where(sig == 0.0, g1_undamped, g1_general))
    g2 = es
    return C11, C12, C21, C22, g1, g2


class StepResponse:
    """The exact response of n modal oscillators to step loads, evaluated anywhere.

    Parameters
    ----------
    omega2 : (n,) [rad²/s²], ω² >= 0 (0: rigid mode, eq. 13).
    sigma : (n,) [1/s], decay rates σ = ζω (0: undamped).
    starts : (K,) [s], strictly increasing segment starts s_k; s_0 is the initial time.
    forces : (K, n), the modal force 𝓕_k on [s_k, s_{k+1}) (the last holds for ever).
    r0, v0 : (n,), modal displacement and velocity at s_0.

    Notes
    -----
    The constructor runs the recursion once: O(K n). ``__call__(t)`` then costs
    O(len(t) n), whatever the time since the last load change.
    """

    def __init__(self, omega2, sigma, starts, forces, r0, v0):
        self.omega2 = np.asarray(omega2, dtype=float)
        self.sigma = np.broadcast_to(np.asarray(sigma, dtype=float), self.omega2.shape).copy()
        self.starts = np.asarray(starts, dtype=float)
        self.forces = np.asarray(forces, dtype=float)
        K, n = self.forces.shape
        r = np.empty((K, n))
        v = np.empty((K, n))
        r[0], v[0] = r0, v0
        C11, C12, C21, C22, g1, g2 = transition(self.omega2, self.sigma, np.diff(self.starts)[:, None])
        for k in range(K - 1):
            r[k + 1] = C11[k] * r[k] + C12[k] * v[k] + g1[k] * self.forces[k]
            v[k + 1] = C21[k] * r[k] + C22[k] * v[k] + g2[k] * self.forces[k]
        self.r, self.v = r, v

    def __call__(self, t):
        """(r, ṙ) at times ``t`` (m,) >= s_0: arrays (m, n)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if t.size and t.min() < self.starts[0]:
            raise ValueError(f"StepResponse: time {t.min()} s is before the initial time {self.starts[0]} s")
        k = np.searchsorted(self.starts, t, side="right") - 1
        C11, C12, C21, C22, g1, g2 = transition(self.omega2, self.sigma, (t - self.starts[k])[:, None])
        F = self.forces[k]
        r = C11 * self.r[k] + C12 * self.v[k] + g1 * F
        v = C21 * self.r[k] + C22 * self.v[k] + g2 * F
        return r, v

    def amplitude_phase(self):
        """The report's (α^(k), β^(k)) of eq. 12 per segment for the undamped elastic
        modes: r(t) = α sin(ω t + β) + 𝓕_k/ω² on [s_k, s_{k+1}), (K, n) each; phases
        refer to absolute time like the report's (NaN for rigid modes)."""
        w = np.sqrt(np.where(self.omega2 > 0, self.omega2, np.nan))
        d = self.r - self.forces / w ** 2
        alpha = np.hypot(d, self.v / w)
        beta = np.arctan2(d, self.v / w) - w * self.starts[:, None]
        return alpha, np.angle(np.exp(1j * beta))
