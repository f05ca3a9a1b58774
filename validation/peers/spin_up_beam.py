"""Geometrically nonlinear reference of the spin-up beam (Kane, Ryan & Banerjee 1987).

Problem (planar, no gravity)
----------------------------
A cantilever, L = 10 m, EI = 1.4e4 N m², EA = 2.8e7 N, ρA = 1.2 kg/m, is clamped at
x = 0 to a hub whose angle is prescribed [rad], with Ω_s = 6 rad/s, T_s = 15 s:

    (1)  θ(t) = (Ω_s/T_s) [t²/2 + (T_s/2π)² (cos(2πt/T_s) − 1)]     t ≤ T_s
         θ(t) = Ω_s (t − T_s/2)                                    t > T_s
    (2)  θ̇(t) = (Ω_s/T_s) [t − (T_s/2π) sin(2πt/T_s)]              (Ω_s after T_s)
    (3)  θ̈(t) = (Ω_s/T_s) [1 − cos(2πt/T_s)]                       (0 after T_s)

(θ, θ̇ and θ̈ are continuous at T_s). The beam starts at rest, undeformed, and is run for
0..20 s. The output is the tip's transverse displacement in the hub frame [m],

    (4)  v_tip = −sin θ r_x + cos θ r_y,

r_tip [m] in inertial axes, the hub frame's x axis the undeformed beam axis. A linear
modal model without geometric stiffening diverges once θ̇ passes ω1 = 3.80 rad/s (its
stiffness K_E − θ̇² M loses definiteness; Kane et al. 1987); this beam stays bounded and
lags (v_tip < 0 during the spin-up) by decimetres, not centimetres: the peak is −0.574 m
at 6.76 s, close to the quasi-static lag under the largest tangential inertia load
ρA θ̈_max x, θ̈_max = 2Ω_s/T_s = 0.8 rad/s², i.e. 11 ρA θ̈_max L⁵/(120 EI) = 0.63 m,
less the centrifugal stiffening (θ̇ = 3 rad/s at 7.5 s: ω² from 14.4 to 16.2 rad²/s²).

Element: planar ANCF cable (Berzeri & Shabana 2000; Gerstmayr & Irschik 2008)
------------------------------------------------------------------------------
Gradient-deficient Euler–Bernoulli element, as Exudyn's ObjectANCFCable2D. Node k has
the inertial coordinates (r_x, r_y, r_x', r_y') [m, m, 1, 1], ' = d/ds, s the reference
arc length; an element of length l = L/n interpolates

    (5)  r(s) = Σ_i h_i(ξ) e_i,   ξ = s/l,   e = (r_1, r_1', r_2, r_2')
         h = (1 − 3ξ² + 2ξ³, l(ξ − 2ξ² + ξ³), 3ξ² − 2ξ³, l(ξ³ − ξ²))

(cubic Hermite). Strains, with a = r', b = r'' (both per reference length):

    (6)  ε = |a| − 1                          (the exact axial strain, not Green's)
    (7)  κ = (a × b) / |a|^m                  m = 3 (geometric curvature, the default,
                                              ``curvature="exact"``) or m = 0 (the common
                                              approximation a × b, ``curvature="simple"``)
    (8)  U = ½ ∫ (EA ε² + EI κ²) ds   [J]     by 5-point Gauss–Legendre per element

Internal forces Q = ∂U/∂q [N] and the tangent K = ∂²U/∂q² [N/m] are analytic (the
derivatives of (6), (7) in a and b, chained through the constant matrices h' ⊗ I₂,
h'' ⊗ I₂). The mass matrix is constant and consistent, M = ρA ∫ h hᵀ ds ⊗ I₂ [kg], all in
the inertial frame, so there are no velocity-dependent inertia forces.

The root node's four coordinates are prescribed, c(t) = (0, 0, cos θ, sin θ); they are
eliminated and their known inertia and elastic coupling go to the right-hand side:

    (9)  M_ff q̈_f + Q_f(c(t), q_f) = −M_fc c̈(t) + f_f.

Time integration: generalized-α (Chung & Hulbert 1993), ρ∞ = 0.9
----------------------------------------------------------------
α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1), γ = ½ − α_m + α_f, β = ¼(1 − α_m + α_f)²;
(9) is enforced at the weighted state

    (10) M [(1 − α_m) a_{n+1} + α_m a_n] + Q((1 − α_f) q_{n+1} + α_f q_n) = f

with the root rows' a = c̈(t) exactly, and Newmark's update of q, q̇ from a. The scheme
is second-order accurate and unconditionally stable for linear problems. ρ∞ = 0.9 damps
the axial modes (32 elements: ω_max = 1.5e5 rad/s, ω_max Δt = 370 at Δt = 2.5 ms; the
amplification matrix's spectral radius there is 0.91) while a bending mode at ω Δt = 0.04
loses less than 1e-8 of its amplitude per step. It is needed: on this stiff, rotating,
nonlinear problem the (nearly) undissipative variants are not stable — ρ∞ = 0.99 and 1
(the midpoint-like case) fail at t ≈ 12 s with 8 elements, Δt = 10 ms (the Newton
iterations per step grow from 2 to 6 as the spin speeds up, then stop converging), and
ρ∞ = 0.9 itself fails at t ≈ 18.5 s with Δt = 20 ms (ρ∞ ≤ 0.8 runs there); Δt ≤ 10 ms
with ρ∞ = 0.9 runs. Violent motions need small steps too: released from a 2.25 m static
tip deflection (hub at rest), 8 elements need Δt ≤ 2 ms. Each step is solved by full
Newton iterations on q_{n+1} (predictor a_{n+1} = a_n) with the Jacobian
(1 − α_m)/(β Δt²) M_ff + (1 − α_f) K_ff (banded Cholesky, half-bandwidth 7) until
max |Δq| < 1e-11 m (3 iterations a step on the spin-up); a failed step raises
RuntimeError. Element loops, the Newton loop and the time loop are numba
(``@njit(cache=True)``); :func:`element_forces_numpy` is a plain-numpy version of the
element forces for the tests.

Outputs, convergence, cache
---------------------------
:func:`simulate` gives v_tip [m] every 0.01 s (cubic Hermite in the step values of v_tip
and dv_tip/dt, exact at step multiples). :func:`reference` is the run at
:data:`REFERENCE_SETTINGS` (32 elements, Δt = 2.5 ms), cached as
``spin_up_beam-<16 hex of sha256 of the JSON recipe>.npz``
(:mod:`validation.peers.result_cache`).
Measured (2 shared cores): the reference runs in 2.8 s (0.002 s from the cache); its
peak is v_tip = −0.5738 m at t = 6.76 s, after the spin-up |v_tip| ≤ 3.7 mm.
:func:`convergence_table` against the finest run (64 elements, Δt = 1.25 ms), as
fractions of max |v_tip| (RMS / max over 0..20 s):

    ======  =========  ==========  ==========
    n       Δt [ms]    RMS         max
    ======  =========  ==========  ==========
    8       10         3.6e-4      8.3e-4
    16      5          1.6e-4      3.8e-4
    32      2.5        3.4e-5      7.9e-5     (the reference)
    64      2.5        3.5e-5      8.1e-5
    32      1.25       7.4e-7      1.7e-6
    64      1.25       0           0          (the finest)
    ======  =========  ==========  ==========

so the error is the time step's (second order), the 32 elements are converged in space,
and halving Δt with doubling the elements changes the reference by 0.0034 % RMS
(< 0.05 %). :func:`curvature_check`: the simple curvature a × b instead of (7) with
m = 3 changes the reference by 6.4e-5 RMS, 1.5e-4 max (the factor |a|⁻³ ≈ 1 − 3ε with
the centrifugal strain ε ≤ 7.7e-5 — a constitutive, not a discretization, difference).
An independent check (tests): a linear Rayleigh–Ritz model of the beam WITH the
centrifugal tension (geometric stiffening) gives a peak of −0.5744 m at 6.76 s.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numba import njit
from scipy.interpolate import CubicHermiteSpline

from validation.peers import result_cache


NAME = "spin_up_beam"
CACHE_VERSION = 1
LENGTH = 10.0            # [m]
EI = 1.4e4               # [N m²]
EA = 2.8e7               # [N]
RHO_A = 1.2              # [kg/m]
OMEGA_S = 6.0            # [rad/s], final hub speed
T_S = 15.0               # [s], spin-up time
T_END = 20.0             # [s]
OUT_DT = 0.01            # [s], output interval
RHO_INF = 0.9            # generalized-α spectral radius at infinity
NEWTON_TOL = 1e-11       # [m], max |Δq| of the last Newton iteration
MAX_NEWTON = 30
CURVATURE_POWER = {"exact": 3, "simple": 0}
REFERENCE_SETTINGS = (32, 0.0025)   # (n_elements, Δt [s])
N_GAUSS = 5
_XG, _WG = np.polynomial.legendre.leggauss(N_GAUSS)
GAUSS_XI = 0.5 * (_XG + 1.0)        # on [0, 1]
GAUSS_W = 0.5 * _WG


# ---------------------------------------------------------------------------- hub angle
@njit(cache=True)
def _hub(t, omega_s, t_s):
    """(θ [rad], θ̇ [rad/s], θ̈ [rad/s²]) of (1)-(3) at t [s]."""
    if t > t_s:
        return omega_s * (t - 0.5 * t_s), omega_s, 0.0
    c = omega_s / t_s
    p = 2.0 * math.pi / t_s
    return (c * (0.5 * t * t + (math.cos(p * t) - 1.0) / (p * p)),
            c * (t - math.sin(p * t) / p),
            c * (1.0 - math.cos(p * t)))


def hub_angle(t, omega_s=OMEGA_S, t_s=T_S):
    """The prescribed hub motion (1)-(3): (θ [rad], θ̇ [rad/s], θ̈ [rad/s²]) at the times
    ``t`` [s] (scalar or array), each shaped like ``t`` (floats for a scalar)."""
    if np.ndim(t) == 0:
        return _hub(float(t), omega_s, t_s)
    t = np.asarray(t, dtype=float)
    out = np.array([_hub(float(x), omega_s, t_s) for x in t.ravel()]).reshape(t.shape + (3,))
    return out[..., 0], out[..., 1], out[..., 2]


# ---------------------------------------------------------------------- shape functions
def shape_functions(l, xi):
    """h, h' = dh/ds [1/m], h'' [1/m²] of (5) at ξ (array): three (len(ξ), 4) arrays."""
    xi = np.asarray(xi, dtype=float)
    h = np.stack([1 - 3 * xi**2 + 2 * xi**3, l * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3,
                  l * (xi**3 - xi**2)], axis=-1)
    d1 = np.stack([-6 * xi + 6 * xi**2, l * (1 - 4 * xi + 3 * xi**2), 6 * xi - 6 * xi**2,
                   l * (3 * xi**2 - 2 * xi)], axis=-1) / l
    d2 = np.stack([-6 + 12 * xi, l * (-4 + 6 * xi), 6 - 12 * xi, l * (6 * xi - 2)], axis=-1) / l**2
    return h, d1, d2


def mass_matrix(n_elements):
    """The consistent mass matrix M [kg] (4(n+1), 4(n+1)) of the whole beam, dense."""
    l = LENGTH / n_elements
    h, _, _ = shape_functions(l, GAUSS_XI)
    me = RHO_A * l * np.einsum("g,gi,gj->ij", GAUSS_W, h, h)
    me = np.kron(me, np.eye(2))
    m = np.zeros((4 * (n_elements + 1),) * 2)
    for e in range(n_elements):
        m[4 * e:4 * e + 8, 4 * e:4 * e + 8] += me
    return m


def straight_beam(n_elements, angle=0.0):
    """The undeformed beam along the direction ``angle`` [rad]: q (4(n+1),) [m, 1]."""
    s = np.linspace(0.0, LENGTH, n_elements + 1)
    d = np.array([math.cos(angle), math.sin(angle)])
    return np.concatenate([np.outer(s, d), np.tile(d, (n_elements + 1, 1))], axis=1).ravel()


# ------------------------------------------------------------------------- numba kernels
@njit(cache=True)
def _point(a, b, m):
    """ε, dε/da, d²ε/da², κ, dκ/da, dκ/db, d²κ/da², d²κ/dadb of (6), (7) at one point."""
    n = math.sqrt(a[0] * a[0] + a[1] * a[1])
    eps = n - 1.0
    de = a / n
    dde = np.empty((2, 2))
    for i in range(2):
        for j in range(2):
            dde[i, j] = ((1.0 if i == j else 0.0) - a[i] * a[j] / (n * n)) / n
    c = a[0] * b[1] - a[1] * b[0]
    dca = np.array([b[1], -b[0]])
    dcb = np.array([-a[1], a[0]])
    f = n ** (-m)
    dfa = -m * n ** (-m - 2) * a
    ka = f * dca + c * dfa
    kb = f * dcb
    kaa = np.empty((2, 2))
    kab = np.empty((2, 2))
    cab = np.array([[0.0, 1.0], [-1.0, 0.0]])
    for i in range(2):
        for j in range(2):
            ddf = -m * n ** (-m - 2) * (1.0 if i == j else 0.0) + m * (m + 2) * n ** (-m - 4) * a[i] * a[j]
            kaa[i, j] = dca[i] * dfa[j] + dfa[i] * dca[j] + c * ddf
            kab[i, j] = f * cab[i, j] + dfa[i] * dcb[j]
    return eps, de, dde, c * f, ka, kb, kaa, kab


@njit(cache=True)
def _element(qe, d1, d2, w, ea, ei, m, tangent):
    """Q_e (8,) [N] and, if ``tangent``, K_e (8, 8) [N/m] of one element; d1, d2 (G, 4)
    the h', h'' at the Gauss points, w (G,) their weights times l [m]."""
    qe_ = np.zeros(8)
    ke = np.zeros((8, 8))
    ga = np.empty(8)
    for g in range(w.shape[0]):
        a = np.zeros(2)
        b = np.zeros(2)
        for i in range(4):
            for k in range(2):
                a[k] += d1[g, i] * qe[2 * i + k]
                b[k] += d2[g, i] * qe[2 * i + k]
        eps, de, dde, kap, ka, kb, kaa, kab = _point(a, b, m)
        for i in range(4):
            for k in range(2):
                ga[2 * i + k] = ka[k] * d1[g, i] + kb[k] * d2[g, i]
                qe_[2 * i + k] += w[g] * (ea * eps * de[k] * d1[g, i] + ei * kap * ga[2 * i + k])
        if tangent:
            for i in range(4):
                for k in range(2):
                    for j in range(4):
                        for p in range(2):
                            ke[2 * i + k, 2 * j + p] += w[g] * (
                                ea * (de[k] * de[p] + eps * dde[k, p]) * d1[g, i] * d1[g, j]
                                + ei * (ga[2 * i + k] * ga[2 * j + p]
                                        + kap * (kaa[k, p] * d1[g, i] * d1[g, j] + kab[k, p] * d1[g, i] * d2[g, j]
                                                 + kab[p, k] * d2[g, i] * d1[g, j])))
    return qe_, ke


@njit(cache=True)
def _assemble(q, n_el, d1, d2, w, ea, ei, m, tangent):
    """Global Q (N,) [N] and the lower band of K, B[i, d] = K[i, i − d], d ≤ 7 [N/m]."""
    ndof = q.shape[0]
    qg = np.zeros(ndof)
    band = np.zeros((ndof, 8))
    for e in range(n_el):
        o = 4 * e
        qe, ke = _element(q[o:o + 8], d1, d2, w, ea, ei, m, tangent)
        for i in range(8):
            qg[o + i] += qe[i]
            if tangent:
                for j in range(i + 1):
                    band[o + i, i - j] += ke[i, j]
    return qg, band


@njit(cache=True)
def _band_matvec(band, x):
    """y = A x for the symmetric A with lower band ``band``."""
    n = x.shape[0]
    y = np.zeros(n)
    for i in range(n):
        for d in range(band.shape[1]):
            j = i - d
            if j < 0:
                break
            y[i] += band[i, d] * x[j]
            if d > 0:
                y[j] += band[i, d] * x[i]
    return y


@njit(cache=True)
def _band_solve(band, r):
    """x = A⁻¹ r for the symmetric positive definite A with lower band ``band`` (banded
    Cholesky); NaNs if A is not positive definite."""
    n, wb = band.shape
    lo = np.zeros((n, wb))
    for i in range(n):
        for d in range(min(i, wb - 1), -1, -1):
            j = i - d
            s = band[i, d]
            for k in range(max(0, i - wb + 1), j):
                s -= lo[i, i - k] * lo[j, j - k]
            if d == 0:
                if s <= 0.0:
                    return np.full(n, np.nan)
                lo[i, 0] = math.sqrt(s)
            else:
                lo[i, d] = s / lo[j, 0]
    y = np.empty(n)
    for i in range(n):
        s = r[i]
        for d in range(1, min(i, wb - 1) + 1):
            s -= lo[i, d] * y[i - d]
        y[i] = s / lo[i, 0]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        s = y[i]
        for d in range(1, min(n - 1 - i, wb - 1) + 1):
            s -= lo[i + d, d] * x[i + d]
        x[i] = s / lo[i, 0]
    return x


@njit(cache=True)
def _root(t, omega_s, t_s):
    """c, ċ, c̈ (4,) of the root node and θ, θ̇ at t."""
    th, om, al = _hub(t, omega_s, t_s)
    cs, sn = math.cos(th), math.sin(th)
    c = np.array([0.0, 0.0, cs, sn])
    cd = np.array([0.0, 0.0, -sn * om, cs * om])
    cdd = np.array([0.0, 0.0, -sn * al - cs * om * om, cs * al - sn * om * om])
    return c, cd, cdd, th, om


@njit(cache=True)
def _integrate(q0, v0, n_el, d1, d2, w, mband, ea, ei, m, dt, n_steps, omega_s, t_s, rho_inf, tol, max_it):
    """Generalized-α (10) from q0, v0 (full vectors, root rows overwritten by c(0)).
    Returns per step (n_steps + 1): tip (x, y, ẋ, ẏ), θ, θ̇, Newton iterations; the
    number of completed steps (< n_steps on a failed Newton solve)."""
    ndof = q0.shape[0]
    am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
    af = rho_inf / (rho_inf + 1.0)
    gam = 0.5 - am + af
    beta = 0.25 * (1.0 - am + af) ** 2
    out = np.zeros((n_steps + 1, 7))
    q = q0.copy()
    v = v0.copy()
    c, cd, cdd, th, om = _root(0.0, omega_s, t_s)
    q[:4] = c
    v[:4] = cd
    mff = mband[4:].copy()
    # consistent initial acceleration
    acc = np.zeros(ndof)
    acc[:4] = cdd
    qg, band = _assemble(q, n_el, d1, d2, w, ea, ei, m, np.bool_(False))
    rhs = -(_band_matvec(mband, acc)[4:] + qg[4:])
    acc[4:] = _band_solve(mff, rhs)
    out[0, :4] = q[-4], q[-3], v[-4], v[-3]
    out[0, 4], out[0, 5] = th, om
    cm = (1.0 - am) / (beta * dt * dt)
    for n in range(n_steps):
        t1 = (n + 1) * dt
        c1, cd1, cdd1, th1, om1 = _root(t1, omega_s, t_s)
        qn = q.copy()
        vn = v.copy()
        an = acc.copy()
        qp = qn + dt * vn + dt * dt * 0.5 * an        # predictor: a_{n+1} = a_n
        qp[:4] = c1
        it = 0
        done = False
        while it < max_it:
            it += 1
            a1 = (qp - qn - dt * vn - dt * dt * (0.5 - beta) * an) / (beta * dt * dt)
            a1[:4] = cdd1
            qbar = (1.0 - af) * qp + af * qn
            abar = (1.0 - am) * a1 + am * an
            qg, band = _assemble(qbar, n_el, d1, d2, w, ea, ei, m, np.bool_(True))
            res = _band_matvec(mband, abar)[4:] + qg[4:]
            jac = cm * mff + (1.0 - af) * band[4:]
            dq = _band_solve(jac, -res)
            if not np.isfinite(dq[0]):
                return out, n
            qp[4:] += dq
            if np.max(np.abs(dq)) < tol:
                done = True
                break
        if not done:
            return out, n
        a1 = (qp - qn - dt * vn - dt * dt * (0.5 - beta) * an) / (beta * dt * dt)
        a1[:4] = cdd1
        v = vn + dt * ((1.0 - gam) * an + gam * a1)
        v[:4] = cd1
        q = qp
        acc = a1
        out[n + 1, :4] = q[-4], q[-3], v[-4], v[-3]
        out[n + 1, 4], out[n + 1, 5], out[n + 1, 6] = th1, om1, it
    return out, n_steps


# ------------------------------------------------------------------------ python layer
class Beam:
    """The discretized beam: ``n_elements`` ANCF cable elements, curvature (7) ``"exact"``
    (m = 3) or ``"simple"`` (m = 0). Holds l [m], the Gauss data, M [kg] (dense and band)."""

    def __init__(self, n_elements, curvature="exact"):
        if curvature not in CURVATURE_POWER:
            raise ValueError(f"curvature must be one of {sorted(CURVATURE_POWER)}, not {curvature!r}")
        self.n = int(n_elements)
        self.m = CURVATURE_POWER[curvature]
        self.l = LENGTH / self.n
        _, self.d1, self.d2 = shape_functions(self.l, GAUSS_XI)
        self.w = GAUSS_W * self.l
        self.mass = mass_matrix(self.n)
        ndof = self.mass.shape[0]
        self.mband = np.array([[self.mass[i, i - d] if i - d >= 0 else 0.0 for d in range(8)]
                               for i in range(ndof)])

    def forces(self, q):
        """Q (N,) [N] = ∂U/∂q of (8) at q."""
        return _assemble(np.asarray(q, float), self.n, self.d1, self.d2, self.w, EA, EI, self.m, False)[0]

    def tangent(self, q):
        """K (N, N) [N/m] = ∂²U/∂q² at q, dense."""
        _, band = _assemble(np.asarray(q, float), self.n, self.d1, self.d2, self.w, EA, EI, self.m, True)
        k = np.zeros((band.shape[0],) * 2)
        for d in range(8):
            i = np.arange(d, band.shape[0])
            k[i, i - d] = band[i, d]
            k[i - d, i] = band[i, d]
        return k

    def static(self, tip_force, n_load_steps=10, tol=1e-10):
        """The static equilibrium Q_f(q) = f_f under ``tip_force`` (2,) [N] at the last
        node, root clamped at (0, 0, 1, 0); Newton with load stepping. Returns the full
        q [m, 1]."""
        q = straight_beam(self.n)
        f = np.zeros_like(q)
        for s in range(1, n_load_steps + 1):
            f[-4:-2] = np.asarray(tip_force, float) * s / n_load_steps
            for _ in range(MAX_NEWTON):
                dq = np.linalg.solve(self.tangent(q)[4:, 4:], f[4:] - self.forces(q)[4:])
                q[4:] += dq
                if np.max(np.abs(dq)) < tol:
                    break
            else:
                raise RuntimeError("static Newton iterations did not converge")
        return q


def element_forces_numpy(q, n_elements, curvature="exact"):
    """Plain-numpy Q (N,) [N] of (6)-(8), vectorized over elements and Gauss points."""
    m = CURVATURE_POWER[curvature]
    l = LENGTH / n_elements
    _, d1, d2 = shape_functions(l, GAUSS_XI)
    q = np.asarray(q, float)
    qe = np.stack([q[4 * e:4 * e + 8].reshape(4, 2) for e in range(n_elements)])   # (E, 4, 2)
    a = np.einsum("gi,eik->egk", d1, qe)
    b = np.einsum("gi,eik->egk", d2, qe)
    n = np.linalg.norm(a, axis=-1)
    eps = n - 1.0
    c = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    kap = c / n**m
    dca = np.stack([b[..., 1], -b[..., 0]], axis=-1)
    dcb = np.stack([-a[..., 1], a[..., 0]], axis=-1)
    ka = dca / n[..., None] ** m - m * (c / n ** (m + 2))[..., None] * a
    kb = dcb / n[..., None] ** m
    sa = EA * (eps / n)[..., None] * a + EI * kap[..., None] * ka      # ∂W/∂a
    sb = EI * kap[..., None] * kb                                       # ∂W/∂b
    fe = l * (np.einsum("g,gi,egk->eik", GAUSS_W, d1, sa) + np.einsum("g,gi,egk->eik", GAUSS_W, d2, sb))
    out = np.zeros_like(q)
    for e in range(n_elements):
        out[4 * e:4 * e + 8] += fe[e].ravel()
    return out


def _t_out_default():
    return np.round(np.arange(0.0, T_END + 0.5 * OUT_DT, OUT_DT), 10)


def run(beam: Beam, dt, t_end, q0=None, v0=None, omega_s=OMEGA_S, t_s=T_S, rho_inf=RHO_INF):
    """Integrate (9) with (10) from ``q0``, ``v0`` (default: straight, at rest) to
    ``t_end`` [s] (or the first step after it) with steps ``dt`` [s]. Returns t (K,) [s]
    and the step states (K, 7): tip r_x, r_y [m], ṙ_x, ṙ_y [m/s], θ [rad], θ̇ [rad/s],
    Newton iterations."""
    n_steps = int(math.ceil(t_end / dt - 1e-9))
    q0 = straight_beam(beam.n) if q0 is None else np.asarray(q0, float)
    v0 = np.zeros_like(q0) if v0 is None else np.asarray(v0, float)
    out, done = _integrate(q0, v0, beam.n, beam.d1, beam.d2, beam.w, beam.mband, EA, EI, beam.m, float(dt),
                           n_steps, float(omega_s), float(t_s), float(rho_inf), NEWTON_TOL, MAX_NEWTON)
    if done < n_steps:
        raise RuntimeError(f"Newton iterations failed at step {done + 1} (t = {(done + 1) * dt:.4f} s): "
                           "the step is too large for the nonlinearity; use a smaller dt")
    return np.arange(n_steps + 1) * dt, out


def simulate(n_elements, dt, t_out=None, curvature="exact", rho_inf=RHO_INF):
    """The spin-up run with ``n_elements`` elements and step ``dt`` [s]: (t (K,) [s],
    v_tip (K,) [m]) of (4) at ``t_out`` (default every 0.01 s on 0..20 s)."""
    t_out = _t_out_default() if t_out is None else np.asarray(t_out, float)
    t, s = run(Beam(n_elements, curvature), dt, float(np.max(t_out)), rho_inf=rho_inf)
    th, om = s[:, 4], s[:, 5]
    sn, cs = np.sin(th), np.cos(th)
    v = -sn * s[:, 0] + cs * s[:, 1]
    vd = -om * (cs * s[:, 0] + sn * s[:, 1]) - sn * s[:, 2] + cs * s[:, 3]
    return t_out, CubicHermiteSpline(t, v, vd)(t_out)


# ------------------------------------------------------------------ reference and cache
def recipe(n_elements, dt, curvature="exact", rho_inf=RHO_INF) -> dict:
    """The JSON-able cache key of a run."""
    return {"peer": NAME, "version": CACHE_VERSION, "length": LENGTH, "EI": EI, "EA": EA, "rhoA": RHO_A,
            "omega_s": OMEGA_S, "t_s": T_S, "t_end": T_END, "out_dt": OUT_DT, "n_elements": int(n_elements),
            "dt": float(dt), "curvature": curvature, "rho_inf": float(rho_inf), "gauss": N_GAUSS,
            "newton_tol": NEWTON_TOL}


def cache_path(key: dict) -> Path:
    """``cache_dir() / spin_up_beam-<first 16 hex of sha256(JSON key)>.npz``."""
    return result_cache.cache_path(NAME, key)


def cached_run(n_elements, dt, curvature="exact", rho_inf=RHO_INF):
    """:func:`simulate` at the default outputs, from the cache or run and stored."""
    key = recipe(n_elements, dt, curvature, rho_inf)
    path = cache_path(key)
    if (hit := result_cache.load(path, key)) is not None:
        return hit["t"], hit["v_tip"]
    t, v = simulate(n_elements, dt, curvature=curvature, rho_inf=rho_inf)
    result_cache.store(path, key, {"t": t, "v_tip": v})
    return t, v


def reference():
    """The converged spin-up run, :data:`REFERENCE_SETTINGS`: (t (2001,) [s], v_tip [m])
    every 0.01 s on 0..20 s, cached on disk."""
    return cached_run(*REFERENCE_SETTINGS)


CONVERGENCE_RUNS = ((8, 0.01), (16, 0.005), (32, 0.0025), (64, 0.0025), (32, 0.00125), (64, 0.00125))


def convergence_table(runs=CONVERGENCE_RUNS):
    """Rows (n_elements, Δt [s], RMS |v − v_finest| [m], max |v − v_finest| [m]) over
    0..20 s for ``runs``, the finest = the most elements, then the smallest Δt (cached)."""
    finest = max(runs, key=lambda r: (r[0], -r[1]))
    _, vf = cached_run(*finest)
    rows = []
    for n, dt in runs:
        _, v = cached_run(n, dt)
        d = v - vf
        rows.append((n, dt, float(np.sqrt(np.mean(d**2))), float(np.max(np.abs(d)))))
    return rows


def curvature_check():
    """(RMS, max) |v_simple − v_exact| [m] over 0..20 s at :data:`REFERENCE_SETTINGS`:
    the curvature a × b against (7) with m = 3 (cached)."""
    _, v = cached_run(*REFERENCE_SETTINGS, curvature="simple")
    _, vr = reference()
    d = v - vr
    return float(np.sqrt(np.mean(d**2))), float(np.max(np.abs(d)))
