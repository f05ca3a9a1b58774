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
def _jr_inv(th, w, out):
    """θ̇ = J_r(θ)⁻¹ ω = ω + ½ θ × ω + κ θ × (θ × ω), κ = 1/a² − (1 + cos a)/(2 a sin a)."""
    a2 = th[0] * th[0] + th[1] * th[1] + th[2] * th[2]
    if a2 < 1e-8:
        k = 1.0 / 12.0 + a2 / 720.0
    else:
        a = np.sqrt(a2)
        k = 1.0 / a2 - (1.0 + np.cos(a)) / (2.0 * a * np.sin(a))
    t1x = th[1] * w[2] - th[2] * w[1]
    t1y = th[2] * w[0] - th[0] * w[2]
    t1z = th[0] * w[1] - th[1] * w[0]
    out[0] = w[0] + 0.5 * t1x + k * (th[1] * t1z - th[2] * t1y)
    out[1] = w[1] + 0.5 * t1y + k * (th[2] * t1x - th[0] * t1z)
    out[2] = w[2] + 0.5 * t1z + k * (th[0] * t1y - th[1] * t1x)


@njit(cache=True)
def inertial_torque(B_G, R, out):
    """Torque in B axes of inertial-frame nodal forces: Σ b_i × (Rᵀ f_i) = axial part of
    Y = B_G R with B_G = Σ b_i f_iᵀ: (Y₁₂ − Y₂₁, Y₂₀ − Y₀₂, Y₀₁ − Y₁₀)."""
    for a, b, c in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        y_bc = B_G[b, 0] * R[0, c] + B_G[b, 1] * R[1, c] + B_G[b, 2] * R[2, c]
        y_cb = B_G[c, 0] * R[0, b] + B_G[c, 1] * R[1, b] + B_G[c, 2] * R[2, b]
        out[a] = y_bc - y_cb


@njit(cache=True)
def _accelerations(R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv, acc, alpha, T):
    """v̇ = (R F_B + F_G)/m and α = Î⁻¹(T − Ω × ÎΩ) into ``acc``, ``alpha`` (``T`` scratch)."""
    inertial_torque(B_G, R, T)
    L0 = I[0, 0] * Om[0] + I[0, 1] * Om[1] + I[0, 2] * Om[2]
    L1 = I[1, 0] * Om[0] + I[1, 1] * Om[1] + I[1, 2] * Om[2]
    L2 = I[2, 0] * Om[0] + I[2, 1] * Om[1] + I[2, 2] * Om[2]
    T[0] += T_B[0] - (Om[1] * L2 - Om[2] * L1)
    T[1] += T_B[1] - (Om[2] * L0 - Om[0] * L2)
    T[2] += T_B[2] - (Om[0] * L1 - Om[1] * L0)
    for i in range(3):
        acc[i] = (R[i, 0] * F_B[0] + R[i, 1] * F_B[1] + R[i, 2] * F_B[2] + F_G[i]) / mass
        alpha[i] = Iinv[i, 0] * T[0] + Iinv[i, 1] * T[1] + Iinv[i, 2] * T[2]


@njit(cache=True)
def _copy_into(src, dst):
    """dst[...] = src for C-contiguous arrays of the same shape, element by element (views,
    no allocation): an array slice assignment makes numba compile its shape-mismatch error
    message, seconds per kernel."""
    s, d = src.reshape(-1), dst.reshape(-1)
    for i in range(s.shape[0]):
        d[i] = s[i]


@njit(cache=True)
def _matmul3(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(cache=True)
def report_step(h, rho, v, R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv, alpha, ws):
    """One step of the report's explicit scheme (eq. 26–28, corrected; module docstring):
    ρ, v, R, Ω updated in place, the α of the step (eq. 20) written to ``alpha`` (3,);
    ``ws`` scratch as allocated in :func:`rigid_motion`. CoupledRB calls it with the
    deformed body's Î(r) and torque."""
    acc, T, dth, E, R2 = ws[0], ws[2], ws[3], ws[4], ws[5]
    _accelerations(R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv, acc, alpha, T)
    for i in range(3):
        rho[i] += h * v[i] + 0.5 * h * h * acc[i]
        v[i] += h * acc[i]
        dth[i] = h * Om[i] + 0.5 * h * h * alpha[i]
        Om[i] += h * alpha[i]
    so3_exp(dth, E)
    _matmul3(R, E, R2)
    _copy_into(R2, R)


@njit(cache=True)
def _rhs(Rn, y, F_B, T_B, F_G, B_G, mass, I, Iinv, dy, ws):
    """d/dt of y = (ρ, v, θ, Ω) with R = R_n exp(θ̃)."""
    acc, alpha, T, th, E, R = ws[0], ws[1], ws[2], ws[3], ws[4], ws[5]
    so3_exp(y[6:9], E)
    _matmul3(Rn, E, R)
    _accelerations(R, y[9:12], F_B, T_B, F_G, B_G, mass, I, Iinv, acc, alpha, T)
    _jr_inv(y[6:9], y[9:12], th)
    for i in range(3):
        dy[i] = y[3 + i]
        dy[3 + i] = acc[i]
        dy[6 + i] = th[i]
        dy[9 + i] = alpha[i]


@njit(cache=True)
def _step_rkmk4(h, rho, v, R, Om, F_B, T_B, F_G, B_G, mass, I, Iinv, ws, ys):
    y, ya, k1, k2, k3, k4 = ys[0], ys[1], ys[2], ys[3], ys[4], ys[5]
    for i in range(3):
        y[i] = rho[i]
        y[3 + i] = v[i]
        y[6 + i] = 0.0
        y[9 + i] = Om[i]
    _rhs(R, y, F_B, T_B, F_G, B_G, mass, I, Iinv, k1, ws)
    for i in range(12):
        ya[i] = y[i] + 0.5 * h * k1[i]
    _rhs(R, ya, F_B, T_B, F_G, B_G, mass, I, Iinv, k2, ws)
    for i in range(12):
        ya[i] = y[i] + 0.5 * h * k2[i]
    _rhs(R, ya, F_B, T_B, F_G, B_G, mass, I, Iinv, k3, ws)
    for i in range(12):
        ya[i] = y[i] + h * k3[i]
    _rhs(R, ya, F_B, T_B, F_G, B_G, mass, I, Iinv, k4, ws)
    for i in range(12):
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    for i in range(3):
        rho[i] = y[i]
        v[i] = y[3 + i]
        Om[i] = y[9 + i]
    E, R2 = ws[4], ws[5]
    so3_exp(y[6:9], E)
    _matmul3(R, E, R2)
    _copy_into(R2, R)


@njit(cache=True)
def workspace():
    """Scratch arrays of the steps: (acc, α, T, θ (3,) each, E, R (3, 3) each)."""
    return (np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty((3, 3)), np.empty((3, 3)))


@njit(cache=True)
def rigid_motion(grid, F_B, T_B, F_G, B_G, mass, I, Iinv, rho0, v0, R0, Om0, scheme,
                 rho, v, R, Om):
    """Integrate over ``grid`` (n_g,) [s]; loads per interval (n_g − 1, 3) / (n_g − 1, 3, 3);
    fills the states at the grid points: ``rho``, ``v``, ``Om`` (n_g, 3), ``R`` (n_g, 3, 3).
    Returns the index of the first non-finite state, or −1. Scratch arrays are allocated
    once here; the steps allocate nothing."""
    _copy_into(rho0, rho[0])
    _copy_into(v0, v[0])
    _copy_into(R0, R[0])
    _copy_into(Om0, Om[0])
    r_ = rho0.copy()
    v_ = v0.copy()
    R_ = R0.copy()
    O_ = Om0.copy()
    ws = workspace()
    ys = (np.empty(12), np.empty(12), np.empty(12), np.empty(12), np.empty(12), np.empty(12))
    for k in range(grid.shape[0] - 1):
        h = grid[k + 1] - grid[k]
        if scheme == 0:
            report_step(h, r_, v_, R_, O_, F_B[k], T_B[k], F_G[k], B_G[k], mass, I, Iinv, ws[1], ws)
        else:
            _step_rkmk4(h, r_, v_, R_, O_, F_B[k], T_B[k], F_G[k], B_G[k], mass, I, Iinv, ws, ys)
        _copy_into(r_, rho[k + 1])
        _copy_into(v_, v[k + 1])
        _copy_into(R_, R[k + 1])
        _copy_into(O_, Om[k + 1])
        if not (np.isfinite(R_).all() and np.isfinite(O_).all() and np.isfinite(r_).all()):
            return k + 1
    return -1


@njit(cache=True)
def place_nodes(rho, R, b, U, offset, out):
    """out[t, i] = ρ_t + R_t (b_i + U_ti) − offset_i (eq. 24 minus a reference position):
    node positions (offset 0) or displacements (offset ū0) of k nodes at n_t times from
    ``rho`` (n_t, 3), ``R`` (n_t, 3, 3), ``b`` (k, 3), ``U`` (n_t, k, 3); O(n_t k), one pass."""
    for t in range(U.shape[0]):
        for i in range(U.shape[1]):
            x0 = b[i, 0] + U[t, i, 0]
            x1 = b[i, 1] + U[t, i, 1]
            x2 = b[i, 2] + U[t, i, 2]
            for a in range(3):
                out[t, i, a] = rho[t, a] + R[t, a, 0] * x0 + R[t, a, 1] * x1 + R[t, a, 2] * x2 - offset[i, a]
