"""Frame-fixed FFR beam excited in five modes: frequencies from q_f(t) (thesis Sec. 5.1, Table 5.2).

Setup (thesis Sec. 5.1.1): the thesis's complex beam, clamped at its left face, body frame
fixed in the inertial frame, no gravity, initial modal velocities
u_f(0:4) = [0.2, 0.17, 0.14, 0.1, 0.05] [kg^½ m/s] on the first five modes. The geometry
is the project's reading of the text (:func:`preprocess.stepped_beam`; the thesis's
Fig. 5.1 is not in it), steel in SI(mm) as in the thesis (ρ = 7.987e-9 t/mm³,
E = 210000 N/mm², ν = 0.3), tet10 mesh of size 5 mm, five clamped modes. The thesis
kept thirty modes and excited five; with the frame fixed the modes do not couple, so the
others would stay at rest and only set the highest frequency of the system (the RK4
step limit). We keep the five excited ones.

With the frame fixed, M = m_ff = Φᵀ M_FE Φ = 1, the identity (thesis eq. 2.18, 2.69,
mass-normalized modes), and h = Q_v − K q = −k_ff q_f (eq. 4.2; Q_v = 0 with the frame at
rest) with k_ff = Φᵀ K_FE Φ = diag(ω_i²) (eq. 2.19, 2.36), so each
q_f,i(t) = u_f,i(0)/ω_i sin(ω_i t) exactly: the frequency measured from the time series
differs from the FE eigenfrequency ω_i = sqrt(λ_i) only by the time integrator's period
error. The thesis measured it from the periods of u_f or q_f and found errors below
0.2 % (Table 5.2).

Measurement (:func:`measure_frequency`): a least-squares fit of the two-term linear
recurrence that every sampled damped sinusoid q_n = Re(c zⁿ), z = e^{(−σ + iω_d) Δ},
obeys, over the whole record. A linear one-step integrator applied to a linear
oscillator produces exactly such samples, so the fit returns the discrete solution's
frequency to rounding error, with no interpolation between samples (as timing zero
crossings would need).

Swept: integrator (generalized-α with ρ∞ = 1 and 0.9, RK4) and the number N of steps per
period of the highest mode, h = 2π/(N ω_5). RK4 runs only where h ω_5 < 2.8 (its
stability interval on the imaginary axis ends at 2√2); the others are listed as skipped.
Row error: max_i |ω_d,i/ω_i − 1| over the five modes; extra columns: the five signed
errors, h, h ω_5 and the observed order between a row and the previous (coarser) row
of its series. CPU time per row: the simulation (after a two-step warm-up run per
integrator, so that loading compiled kernels is not counted).
"""

from __future__ import annotations

import math

import numpy as np

from mbs import FlexibleBodyFFR, PrescribedFrameMotion, System
from preprocess import build_body, stepped_beam
from validation import CaseResult, make_row, timed
from validation.cases.complex_beam import MATERIAL_MM

NAME = "ffr_frequencies"
DESCRIPTION = ("thesis Sec. 5.1: frame-fixed complex beam (our reading of its geometry) excited in "
               "five modes; frequencies measured from q_f(t) vs the FE eigenfrequencies")

MESH_SIZE_MM = 5.0
N_MODES = 5
QDOT_F0 = np.array([0.2, 0.17, 0.14, 0.1, 0.05])   # u_f(0:4), thesis Sec. 5.1.1 [kg^½ m/s]
THESIS_ERROR = np.array([0.02433, 0.09336, -0.1673, 0.03872, 0.04727]) / 100  # Table 5.2, MBSim vs ABAQUS
INTEGRATORS = (("generalized-alpha", 1.0), ("generalized-alpha", 0.9), ("rk4", None))
EXPECTED_ORDER = {"generalized-alpha": 2, "rk4": 4}   # of the period error
RK4_LIMIT = 2.8                                       # h ω_max, below 2√2 = 2.83


def beam():
    """The body data of the setup: stepped beam, 5 mm tet10 mesh, five clamped modes (SI)."""
    return build_body(stepped_beam(MESH_SIZE_MM, order=2), MATERIAL_MM, N_MODES, clamp="x0",
                      units="si-mm")


def measure_frequency(q, dt):
    """Frequency of a sampled (damped) sinusoid by a least-squares linear-prediction fit.

    ``q`` (n,) samples at spacing ``dt`` [s] of q_n = Re(c zⁿ), z = r e^{iθ}, r = e^{−σ Δt},
    θ = ω_d Δt. Such samples satisfy q_{n+1} − 2 r cos θ q_n + r² q_{n−1} = 0 (Prony's
    recurrence), written with the second difference d_n = q_{n+1} − 2 q_n + q_{n−1} and
    the backward difference b_n = q_n − q_{n−1} as

        d_n = −|1 − z|² q_n − (1 − r²) b_n,

    whose two coefficients are fitted by linear least squares (columns q_n and b_n are
    a quarter period out of phase, so the fit stays well conditioned for θ ≪ 1). Then
    1 − cos θ = (|1 − z|² − (1 − r)²)/(2r) and θ = 2 arcsin sqrt((1 − cos θ)/2), which
    avoids the cancellation of arccos near 1. Requires 0 < θ < π (more than two samples
    per period).

    Returns (ω_d [rad/s], σ [1/s], relative residual ‖fit − d‖/‖d‖ [-]); the residual is
    zero up to rounding for an exact damped sinusoid.
    """
    q = np.asarray(q, dtype=float)
    d = q[2:] - 2.0 * q[1:-1] + q[:-2]
    X = np.column_stack((q[1:-1], q[1:-1] - q[:-2]))
    coef, *_ = np.linalg.lstsq(X, d, rcond=None)
    one_minus_z2, one_minus_r2 = -coef[0], -coef[1]
    r = math.sqrt(1.0 - one_minus_r2)
    one_minus_cos = (one_minus_z2 - (one_minus_r2 / (1.0 + r)) ** 2) / (2.0 * r)
    theta = 2.0 * math.asin(math.sqrt(one_minus_cos / 2.0))
    residual = np.linalg.norm(X @ coef - d) / np.linalg.norm(d)
    return theta / dt, -math.log(r) / dt, float(residual)


def simulate(data, integrator, rho_inf, dt, t_end):
    """Run the frame-fixed body from q_f = 0, q̇_f = QDOT_F0 with step ``dt`` [s] to
    ``t_end`` [s], output every step. Returns (Result, CPU seconds of the simulation)."""
    system = System()
    body = system.add(FlexibleBodyFFR(data, N_MODES, frame=PrescribedFrameMotion.fixed()))
    body.set_initial(qdot_f=QDOT_F0)
    options = {} if rho_inf is None else {"rho_inf": rho_inf}
    return timed(system.simulate, t_end, dt, integrator=integrator, plan=False, **options)


def run(quick: bool) -> CaseResult:
    data = beam()
    omega = data.frequencies()[0]
    steps_per_period = [2, 10, 20, 40, 80] if quick else [2, 5, 10, 20, 40, 80]
    periods = 5 if quick else 20          # record length in periods of mode 1
    result = CaseResult(plot_groups=("integrator", "rho_inf"))
    finest, orders, worst_residual, worst_trapezoidal = {}, {}, 0.0, 0.0
    for integrator, rho_inf in INTEGRATORS:
        label = integrator if rho_inf is None else f"{integrator}, ρ∞ = {rho_inf}"
        orders[label] = (EXPECTED_ORDER[integrator], [])
        h_warm = 2 * np.pi / (10 * omega[-1])
        simulate(data, integrator, rho_inf, h_warm, 2 * h_warm)   # load compiled kernels untimed
        previous = None
        for n in steps_per_period:
            dt = 2 * np.pi / (n * omega[-1])
            if integrator == "rk4" and dt * omega[-1] >= RK4_LIMIT:
                result.skipped.append(f"{label}, N = {n}: skipped: h ω_5 = {dt * omega[-1]:.3g} ≥ "
                                      f"{RK4_LIMIT}, outside RK4's stability interval")
                continue
            res, cpu = simulate(data, integrator, rho_inf, dt,
                                math.ceil(periods * omega[-1] / omega[0] * n) * dt)
            fits = [measure_frequency(res.q[:, i], dt) for i in range(N_MODES)]
            worst_residual = max([worst_residual] + [f[2] for f in fits])
            errors = np.array([f[0] for f in fits]) / omega - 1
            error = float(np.abs(errors).max())
            order = math.nan
            if previous is not None:
                order = math.log(previous[1] / error) / math.log(n / previous[0])
                orders[label][1].append((previous[0], n, order))
            if rho_inf == 1.0:
                trapezoidal = 2 * np.arctan(omega * dt / 2) / (omega * dt) - 1
                worst_trapezoidal = max(worst_trapezoidal, np.abs(errors / trapezoidal - 1).max())
            config = {"integrator": integrator, **({} if rho_inf is None else {"rho_inf": rho_inf}),
                      "steps_per_period": n}
            result.rows.append(make_row(
                NAME, config, cpu, error, "relative", "FE eigenfrequencies", dt_s=dt,
                h_omega5=dt * omega[-1], observed_order=order,
                **{f"err_f{i + 1}": float(e) for i, e in enumerate(errors)}))
            previous = (n, error)
            finest[label] = (n, errors)
    result.notes += [_setup_note(data, periods, worst_residual), _mode_table(omega, finest),
                     _order_note(orders, worst_trapezoidal)]
    return result


def _setup_note(data, periods, worst_residual):
    return (f"Stepped beam (geometry: **our reading** of thesis Fig. 5.1, see `complex_beam`), "
            f"{data.n_nodes} nodes, tet10, mesh size {MESH_SIZE_MM} mm, five clamped modes; frame "
            f"fixed; q̇_f(0) = {QDOT_F0.tolist()}. Record: {periods} periods of mode 1, output "
            f"every step; h = 2π/(N ω_5). Frequencies from a least-squares fit of Prony's "
            f"two-term recurrence to each q_f,i(t); worst relative fit residual over all runs "
            f"{worst_residual:.1e} (each q_f,i is one sinusoid, damped by the integrator).")


def _mode_table(omega, finest):
    """Markdown table: per mode the FE frequency and each integrator's error at its finest N."""
    labels = list(finest)
    head = "| mode | FE f [Hz] | " + " | ".join(f"{lab} (N = {finest[lab][0]})" for lab in labels) \
        + " | thesis Table 5.2 (MBSim vs ABAQUS) |"
    lines = ["Relative frequency errors ω_d/ω − 1 at the finest step of each integrator:", "",
             head, "|" + "---|" * (len(labels) + 3)]
    for i in range(N_MODES):
        cells = [f"{finest[lab][1][i]:+.3e}" for lab in labels]
        lines.append(f"| {i + 1} | {omega[i] / (2 * np.pi):.2f} | " + " | ".join(cells)
                     + f" | {THESIS_ERROR[i]:+.3e} |")
    return "\n".join(lines)


def _order_note(orders, worst_trapezoidal):
    """The observed orders p = ln(e_coarse/e_fine)/ln(N_fine/N_coarse) of each series, and
    how closely the ρ∞ = 1 errors follow the trapezoidal rule's (worst relative deviation)."""
    lines = ["Observed order of the frequency (period) error, p = ln(e_coarse/e_fine) / "
             "ln(N_fine/N_coarse) between consecutive N (expected: 2 for generalized-α, whose "
             "period error is O(h²) — for ρ∞ = 1 it is the trapezoidal rule, ω_d h = 2 arctan(ω h/2), "
             "error ≈ −(ω h)²/12; 4 for RK4):", ""]
    for label, (expected, pairs) in orders.items():
        steps = ", ".join(f"N {a}→{b}: {p:.3f}" for a, b, p in pairs)
        lines.append(f"- {label} (expected {expected}): {steps}")
    lines += ["", "Generalized-α with ρ∞ = 1 (α_m = α_f = ½, γ = ½, β = ¼) reduces to Newmark's "
              "average-acceleration (trapezoidal) rule: its measured errors, all modes and steps, equal 2 arctan(ω h/2)/(ω h) − 1 to "
              f"{worst_trapezoidal:.1e} of their own size."]
    return "\n".join(lines)
