"""numba kernels of the rigid-body motion (report Sec. 3.2, 3.4.2); the tests compare them
with an independent reference (scipy's ``solve_ivp`` on the quaternion form) and with
analytic motions.

State of the body frame B: centre of mass ρ and its velocity v in G, orientation R
(B → G) and angular velocity Ω in B axes. On a grid interval of length h the loads are
constant: body-frame resultant F_B and torque T_B, inertial resultant F_G (including
gravity), and the first moments B_G = Σ b_i f_iᵀ of inertial-frame nodal forces, whose
torque in B is T_G(R) = axial part of B_G R (see ``inertial_torque``). Equations:

    ρ̇ = v,   v̇ = (R F_B + F_G)/m,   Ṙ = R Ω̃,   Î Ω̇ = T_B + T_G(R) − Ω × Î Ω   (eq. 16, 20).

Eq. 20 as printed, α = Î⁻¹T − (Î⁻¹ × Ω) × Ω, is a typo for Euler's equation
α = Î⁻¹(T − Ω × ÎΩ), which is what we integrate.

Schemes (``scheme``):
0  the report's explicit scheme (eq. 26–28) with its typos corrected: v gains h F_G/m
   (eq. 26 prints h F/(2m)), ρ_{n+1} = ρ_n + h v_n + h² a_n/2 (eq. 27 drops ρ_n), and
   R_{n+1} = R_n R(Δθ) because Δθ = hΩ + h²α/2 is in B axes (eq. 28's R(Δθ) R_n holds
   for a G-axes increment). First order in h (Ω_{n+1} = Ω_n + h α_n).
1  Runge–Kutta–Munthe-Kaas of order 4: classical RK4 on (ρ, v, θ, Ω) with
   R = R_n exp(θ̃) and θ̇ = J_r(θ)⁻¹ Ω (the inverse right Jacobian of SO(3)), then
   R_{n+1} = R_n exp(θ̃). Fourth order; R stays orthogonal to round-off.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def so3_exp(th, out):
    """R(θ) of report eq. 23 (Rodrigues) into ``out`` (3, 3)."""
    a = np.sqrt(th[0] * th[0] + th[1] * th[1] + th[2] * th[2])
    if a < 1e-8:
        s, c = 1.0 - a * a / 6.0, 0.5 - a * a / 24.0
    else:
        s, c = np.sin(a) / a, (1.0 - np.cos(a)) / (a * a)
    x, y, z = th[0], th[1], th[2]
    out[0, 0] = 1.0 - c * (y * y + z * z)
    out[1, 1] = 1.0 - c * (x * x + z * z)
    out[2, 2] = 1.0 - c * (x * x + y * y)
    out[0, 1] = -s * z + c * x * y
    out[1, 0] = s * z + c * x * y
    out[0, 2] = s * y + c * x * z
    out[2, 0] = -s * y + c * x * z
    out[1, 2] = -s * x + c * y * z
    out[2, 1] = s * x + c * y * z


@njit(cache=True)
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def _jr_inv(th, w, out):
    """θ̇ = J_r(θ)⁻¹ ω = ω + ½ θ × ω + κ θ × (θ × ω), κ = 1/a² − (1 + cos a)/(2 a sin a)."""
    a2 = th[0] * th[0] + th[1] * th[1] + th[2] * th[2]
    if a2 < 1e-8:
        k = 1.0 / 12.0 + a2 / 720.0
    else:
        a = np.sqrt(a2)
        k = 1.0 / a2 - (1.0 + np.cos(a)) / (2.0 * a * np.sin(a))
    t1 = np.empty(3)
    t2 = np.empty(3)
    _cross(th, w, t1)
    _cross(th, t1, t2)
    for i in range(3):
        out[i] = w[i] + 0.5 * t1[i] + k * t2[i]


@njit(cache=True)
def inertial_torque(B_G, R, out):
    """Torque in B axes of inertial-frame nodal forces: Σ b_i × (Rᵀ f_i) = axial part of
    Y = B_G R with B_G = Σ b_i f_iᵀ: (Y₁₂ − Y₂₁, Y₂₀ − Y₀₂, Y₀₁ − Y₁₀)."""
    Y = B_G @ R
    out[0] = Y[1, 2] - Y[2, 1]
    out[1] = Y[2, 0] - Y[0, 2]
    out[2] = Y[0, 1] - Y[1, 0]


@njit(cache=True)
def _accelerations(R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv, acc, alpha):
    """v̇ = (R F_B + F_G)/m and α = Î⁻¹(T − Ω × ÎΩ) into ``acc``, ``alpha``."""
    T = np.empty(3)
    inertial_torque(B_G, R, T)
    IOm = I @ Om
    g = np.empty(3)
    _cross(Om, IOm, g)
    for i in range(3):
        acc[i] = (R[i, 0] * F_B[0] + R[i, 1] * F_B[1] + R[i, 2] * F_B[2] + F_G[i]) / mass
        T[i] += T_B[i] - g[i]
    for i in range(3):
        alpha[i] = Iinv[i, 0] * T[0] + Iinv[i, 1] * T[1] + Iinv[i, 2] * T[2]


@njit(cache=True)
def _step_report(h, rho, v, R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv):
    acc = np.empty(3)
    alpha = np.empty(3)
    _accelerations(R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv, acc, alpha)
    dth = np.empty(3)
    for i in range(3):
        rho[i] += h * v[i] + 0.5 * h * h * acc[i]
        v[i] += h * acc[i]
        dth[i] = h * Om[i] + 0.5 * h * h * alpha[i]
        Om[i] += h * alpha[i]
    E = np.empty((3, 3))
    so3_exp(dth, E)
    R[:, :] = R @ E


@njit(cache=True)
def _rhs(Rn, y, F_B, T_B, F_G, B_G, mass, I, Iinv, dy):
    """d/dt of y = (ρ, v, θ, Ω) with R = R_n exp(θ̃)."""
    E = np.empty((3, 3))
    so3_exp(y[6:9], E)
    R = Rn @ E
    acc = np.empty(3)
    alpha = np.empty(3)
    _accelerations(R, y[9:12].copy(), F_B, T_B, F_G, B_G, mass, I, Iinv, acc, alpha)
    th_dot = np.empty(3)
    _jr_inv(y[6:9].copy(), y[9:12].copy(), th_dot)
    for i in range(3):
        dy[i] = y[3 + i]
        dy[3 + i] = acc[i]
        dy[6 + i] = th_dot[i]
        dy[9 + i] = alpha[i]


@njit(cache=True)
def _step_rkmk4(h, rho, v, R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv):
    y = np.zeros(12)
    y[0:3] = rho
    y[3:6] = v
    y[9:12] = Om
    k1 = np.empty(12)
    k2 = np.empty(12)
    k3 = np.empty(12)
    k4 = np.empty(12)
    _rhs(R, y, F_B, T_B, F_G, B_G, mass, I, Iinv, k1)
    _rhs(R, y + 0.5 * h * k1, F_B, T_B, F_G, B_G, mass, I, Iinv, k2)
    _rhs(R, y + 0.5 * h * k2, F_B, T_B, F_G, B_G, mass, I, Iinv, k3)
    _rhs(R, y + h * k3, F_B, T_B, F_G, B_G, mass, I, Iinv, k4)
    y += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    rho[:] = y[0:3]
    v[:] = y[3:6]
    Om[:] = y[9:12]
    E = np.empty((3, 3))
    so3_exp(y[6:9].copy(), E)
    R[:, :] = R @ E


@njit(cache=True)
def rigid_motion(grid, F_B, T_B, F_G, B_G, mass, I, Iinv, rho0, v0, R0, Om0, scheme,
                 rho, v, R, Om):
    """Integrate over ``grid`` (n_g,) [s]; loads per interval (n_g − 1, 3) / (n_g − 1, 3, 3);
    fills the states at the grid points: ``rho``, ``v``, ``Om`` (n_g, 3), ``R`` (n_g, 3, 3).
    Returns the index of the first non-finite state, or −1."""
    rho[0] = rho0
    v[0] = v0
    R[0] = R0
    Om[0] = Om0
    r_ = rho0.copy()
    v_ = v0.copy()
    R_ = R0.copy()
    O_ = Om0.copy()
    for k in range(grid.shape[0] - 1):
        h = grid[k + 1] - grid[k]
        if scheme == 0:
            _step_report(h, r_, v_, R_, O_, F_B[k], T_B[k], F_G[k], B_G[k], mass, I, Iinv)
        else:
            _step_rkmk4(h, r_, v_, R_, O_, F_B[k], T_B[k], F_G[k], B_G[k], mass, I, Iinv)
        rho[k + 1] = r_
        v[k + 1] = v_
        R[k + 1] = R_
        Om[k + 1] = O_
        if not (np.isfinite(R_).all() and np.isfinite(O_).all() and np.isfinite(r_).all()):
            return k + 1
    return -1
