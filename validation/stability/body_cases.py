"""The stability suite's body cases (issue 8, part 1): stiff elastic modes, long spins,
the intermediate-axis flip, the Cardan singularity and spin near the first bending
frequency. Each case builds its bodies with :mod:`preprocess` (or as rigid bodies),
integrates every body (``plan=False``: the planner would solve frame-fixed modal bodies
exactly and nothing would be tested) and measures against a reference that does not
come from the integrators: the exact modal solution, analytic rigid rotations, Jacobi's
elliptic solution of Euler's equations (cross-checked by an RK4 written here), the
analytic spin-up time.

Registered names: ``stiff_modes/moreau-theta1``, ``stiff_modes/moreau-theta0.5``,
``stiff_modes/generalized-alpha``, ``hundred_revolutions``, ``tennis_racket``,
``cardan_singularity``, ``spin_near_bending``. ``quick=True`` shortens every case
(fewer periods or revolutions, fewer bodies), keeping its extreme setting.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.special import ellipk

from ffrmbs.errors import SimulationError
from mbs import FlexibleBodyFFR, PrescribedFrameMotion, RigidBody, System
from mbs.bodies.rotations import rotvec_from_matrix
from mbs.bodies.validity import SPIN_RATIO, FFRValidityWarning, SpinMonitor
from preprocess import Material, box, build_body
from validation.stability.core import StabilityRow, Stopwatch, graceful_row, stability_case

STEEL = Material(7850.0, 210e9, 0.3)      # kg/m³, Pa, -


def _verdict(failures: list[str]) -> tuple[bool, str]:
    """(passed, outcome) from the list of criteria a case missed."""
    if not failures:
        return True, "passed"
    return False, "FAILED: " + "; ".join(failures)


def _rotation_angle(A, B) -> float:
    """The angle [rad] of the rotation Aᵀ B (0 when A = B)."""
    return float(np.linalg.norm(rotvec_from_matrix(A.T @ B)))


def node_mass_inertia(data):
    """(mass [kg], centre of mass c (3,) [m], inertia J (3, 3) [kg m²] about c) of a body's
    lumped node masses: J = Σ m_j (|r_j|² 1 − r_j r_jᵀ), r_j = ū0_j − c — computed from the
    FE data directly, not from the shape integrals the FFR equations use."""
    m = data.masses
    c = m @ data.u0 / m.sum()
    r = data.u0 - c
    J = np.eye(3) * np.einsum("j,jk,jk->", m, r, r) - np.einsum("j,jk,jl->kl", m, r, r)
    return float(m.sum()), c, J


def _grid(duration, dt, samples):
    """(t_end [s], t_out [s]) for a run of at least ``duration`` in steps of exactly ``dt``:
    t_end = n dt with n = ceil(duration/dt), about ``samples`` outputs on multiples of the
    step (the driver lands on every output time, so outputs between steps would shorten
    them and the step a case claims would not be the step it ran)."""
    n = int(math.ceil(duration / dt - 1e-9))
    stride = max(1, n // samples)
    idx = np.arange(0, n + 1, stride)
    if idx[-1] != n:
        idx = np.append(idx, n)
    return n * dt, idx * dt


# ---------------------------------------------------------------------------------------
# stiff_modes: ω_max Δt = 1e2, 1e3, 1e4 on a frame-fixed slender cantilever
# ---------------------------------------------------------------------------------------

STIFF_BEAM = ((0.003, 0.003, 2.0), (1, 1, 60))   # a 3 mm x 3 mm x 2 m steel wire, tet4, clamped at z = 0
STIFF_STEPS = (1e2, 1e3, 1e4)                   # ω_max Δt
RESOLVED = 0.1                                  # a mode is resolved when ω Δt <= 0.1
MODAL_VELOCITY = 0.1                            # initial q̇_f of every retained mode [kg^½ m/s]


@functools.lru_cache(maxsize=None)
def stiff_beam_data():
    """The wire's FE model with all its clamped modes but two (ARPACK needs k < n): the
    lowest bending mode at 40 rad/s, the highest (through the thickness) at 6.2e6 rad/s."""
    (lx, ly, lz), div = STIFF_BEAM
    mesh = box(lx, ly, lz, None, order=1, divisions=div)
    n_free = 3 * (mesh.points.shape[0] - len(mesh.group("z0")))
    return build_body(mesh, STEEL, n_free - 2, clamp="z0")


def stiff_mode_selection(data) -> list[int]:
    """The three lowest and the three highest modes: a spread ω_max/ω1 ≈ 1.5e5, so that at
    ω_max Δt = 1e4 the first mode is still resolved (ω1 Δt ≈ 0.065)."""
    n = data.n_modes
    return [0, 1, 2, n - 3, n - 2, n - 1]


def run_stiff_modes(integrator, options, quick, steps=STIFF_STEPS, order=2):
    """Integrate the frame-fixed wire from q_f = 0, q̇_f = 0.1 (every mode: impact-like)
    for 2 periods of the first mode (1 when quick) at each ω_max Δt of ``steps``.

    Reference: each mode is an undamped oscillator, q_i(t) = v_i/ω_i sin(ω_i t) exactly
    (thesis Sec. 5.1: frame fixed, M_ff = 1, K_ff = diag ω_i²), ω_i² the eigenvalues
    preprocess computed. Per run: the energy growth max_t E(t)/E(0) − 1 (must not be
    positive beyond rounding, 1e-9), the error of each resolved mode (ω_i Δt <= 0.1)
    max_t |q_i − q_i^exact| ω_i / v_i against the bound (ω_i Δt)^order ω_i t_end: the
    global error of a method of that order with unit constant. (Moreau with θ = 1/2 is
    the trapezoidal rule on the modes, relative phase error s²/12 per step, s = ω Δt;
    with θ = 1 it is implicit Euler, first order: the amplitude decays by ≈ s²/2 per
    step, (ωΔt) ω t_end / 2 over the run.) Also the largest amplitude of the stiff modes
    relative to their exact one.
    """
    data = stiff_beam_data()
    sel = stiff_mode_selection(data)
    omega = np.sqrt(data.modal_eigenvalues()[sel])
    v0 = np.full(len(sel), MODAL_VELOCITY)
    amp = v0 / omega
    duration = (1 if quick else 2) * 2 * np.pi / omega[0]
    runs, total, failures = [], 0.0, []
    for s in steps:
        dt = s / omega.max()
        t_end, t_out = _grid(duration, dt, 400)
        system = System()
        body = system.add(FlexibleBodyFFR(data, sel, frame=PrescribedFrameMotion.fixed(), name="wire"))
        body.set_initial(qdot_f=v0)
        with Stopwatch() as w:
            res = system.simulate(t_end, dt, integrator=integrator, t_out=t_out,
                                  energies=True, plan=False, **options)
        total += w.seconds
        E = res.total_energy()
        growth = float(E.max() / E[0] - 1.0)
        err = np.abs(res.q - amp * np.sin(np.outer(res.t, omega))).max(axis=0) / amp
        resolved = np.flatnonzero(omega * dt <= RESOLVED)
        bound = (omega * dt) ** order * omega * t_end
        stiff = np.flatnonzero(omega * dt > 1.0)
        stiff_ratio = float((np.abs(res.q[:, stiff]).max(axis=0) / amp[stiff]).max()) if stiff.size else None
        run = {"omega_max_dt": s, "dt": dt, "steps": res.stats["steps"], "omega1_dt": float(omega[0] * dt),
               "omega_max_dt_run": float(omega.max() * t_end / res.stats["steps"]),   # the mean step taken
               "energy_growth": growth, "energy_end_ratio": float(E[-1] / E[0]),
               "energy_drift": res.energy_drift(), "finite": bool(np.isfinite(res.q).all()),
               "resolved_modes": resolved.tolist(), "resolved_error": err[resolved].tolist(),
               "resolved_bound": bound[resolved].tolist(),
               "stiff_amplitude_ratio": stiff_ratio, "run_time_s": w.seconds}
        runs.append(run)
        if not run["finite"]:
            failures.append(f"state not finite at ω_maxΔt = {s:g}")
        if growth > 1e-9:
            failures.append(f"energy grew by a factor {1 + growth:.3g} at ω_maxΔt = {s:g} "
                            f"(stiff modes at {run['stiff_amplitude_ratio']:.3g} x their exact amplitude)")
        for i, e, b in zip(resolved, err[resolved], bound[resolved]):
            if not e <= b:
                failures.append(f"mode {i} (ωΔt = {omega[i] * dt:.3g}) error {e:.3g} > bound {b:.3g} "
                                f"at ω_maxΔt = {s:g}")
    return runs, total, failures, omega


def _worst_ratio(run) -> float:
    """max over the resolved modes of error / bound (nan when none is resolved)."""
    return max((e / b for e, b in zip(run["resolved_error"], run["resolved_bound"])), default=float("nan"))


def _stiff_row(name, integrator, options, label, quick, order=2):
    runs, total, failures, omega = run_stiff_modes(integrator, options, quick, order=order)
    passed, outcome = _verdict(failures)
    resolved_err = [e for r in runs for e in r["resolved_error"]]
    worst_growth = max(r["energy_growth"] for r in runs)
    per_run = "; ".join(
        f"ω_maxΔt={r['omega_max_dt']:.0e} (ω1Δt={r['omega1_dt']:.2g}, {r['steps']} steps): "
        f"max E/E0 − 1 = {r['energy_growth']:.2g}, E(end)/E0 = {r['energy_end_ratio']:.3g}, "
        f"resolved modes {r['resolved_modes']}: error {max(r['resolved_error'], default=float('nan')):.2g}, "
        f"worst error/bound {_worst_ratio(r):.2g}" for r in runs)
    note = (f"{label}; frame-fixed 3 mm x 3 mm x 2 m steel wire, modes 1-3 and the 3 highest "
            f"(ω = {omega[0]:.3g} … {omega.max():.3g} rad/s), all started at q̇_f = {MODAL_VELOCITY}; "
            f"ω_maxΔt reached {max(r['omega_max_dt_run'] for r in runs):.4g} (mean step of the run). {per_run}")
    return StabilityRow(name, finished=True, stable=all(r["finite"] for r in runs) and worst_growth <= 1e-9,
                        energy_drift=max(r["energy_drift"] for r in runs), max_penetration=None,
                        error=max(resolved_err) if resolved_err else None,
                        reference="exact modal solution (resolved modes, ωΔt <= 0.1)", run_time_s=total,
                        passed=passed, outcome=outcome, note=note,
                        details={"integrator": integrator, "options": options, "runs": runs,
                                 "omega": omega.tolist(), "worst_energy_growth": worst_growth})


@stability_case("stiff_modes/moreau-theta1", "stiff modes, ω_maxΔt up to 1e4: Moreau θ = 1")
def stiff_modes_moreau_theta1(quick: bool) -> StabilityRow:
    return _stiff_row("stiff_modes/moreau-theta1", "moreau", {"theta": 1.0}, "Moreau, θ = 1 (first order)", quick,
                      order=1)


@stability_case("stiff_modes/moreau-theta0.5", "stiff modes, ω_maxΔt up to 1e4: Moreau θ = 0.5")
def stiff_modes_moreau_theta05(quick: bool) -> StabilityRow:
    return _stiff_row("stiff_modes/moreau-theta0.5", "moreau", {"theta": 0.5}, "Moreau, θ = 0.5", quick)


@stability_case("stiff_modes/generalized-alpha", "stiff modes, ω_maxΔt up to 1e4: generalized-α ρ∞ = 0.5")
def stiff_modes_generalized_alpha(quick: bool) -> StabilityRow:
    return _stiff_row("stiff_modes/generalized-alpha", "generalized-alpha", {"rho_inf": 0.5},
                      "generalized-α, ρ∞ = 0.5", quick)


# ---------------------------------------------------------------------------------------
# hundred_revolutions: a free stiff steel block spinning about its major principal axis
# ---------------------------------------------------------------------------------------

BLOCK = (0.1, 0.2, 0.4)      # m, steel, tet10 mesh size 0.1, free-free; the mesh (and frame) origin is a corner
SPIN = 1.0                   # rad/s: Ω/ω1 ≈ 6e-5, the rigid rotation is the reference
STEPS_PER_REV = 100
VIBRATION = 1e-8             # m: mode i starts at q̇_f,i = ω_i 1e-8 m / max_j |Φ_ji| (largest node amplitude 10 nm)
REVOLUTION_BOUNDS = {"energy": 1e-4, "momentum": 1e-4, "orientation": 1e-2, "com": 1e-3}


@functools.lru_cache(maxsize=None)
def block_data(modes=6):
    """The free-free steel block 0.1 x 0.2 x 0.4 m (tet10, mesh size 0.1), ``modes`` modes."""
    return build_body(box(*BLOCK, 0.1, order=2), STEEL, modes, clamp=None)


def run_hundred_revolutions(revolutions, rho_inf=0.9, steps_per_rev=STEPS_PER_REV):
    """Spin the block about its major principal axis through its centre of mass (which
    stays at rest: the frame origin, a corner of the block, starts at v = −ω × c) at
    Ω = 1 rad/s for ``revolutions`` turns with generalized-α, with a small elastic
    vibration. Reference: the rigid rotation A(t) = exp(Ω t ẽ) (A0 = 1); the elastic
    body deviates from it by the centrifugal change of its inertia, ~ (Ω/ω1)² Ω t ≈ 2e-6
    rad after 100 turns. Measured: energy drift (Result.energy_drift), angular-momentum
    drift max |L(t) − L(0)|/|L(0)| (about the inertial origin; with the centre of mass at
    rest the same as about it), orientation error max_t ∠(A_exact(t)ᵀ A(t)) [rad], and
    the centre of mass's displacement relative to the lever arm |c⊥| of the frame origin
    about the spin axis (it must stay put)."""
    data = block_data()
    mass, c, J = node_mass_inertia(data)
    w2, P = np.linalg.eigh(J)
    axis = P[:, 2]                             # the major principal axis: stable spin
    omega = SPIN * axis
    system = System()
    body = system.add(FlexibleBodyFFR(data, 6, name="block"))
    w_modes = np.sqrt(data.modal_eigenvalues())
    reach = np.linalg.norm(data.phi.reshape(data.n_nodes, 3, -1), axis=1).max(axis=0)
    qdot_f = VIBRATION * w_modes / reach
    body.set_initial(v=-np.cross(omega, c), omega=omega, qdot_f=qdot_f)
    dt = 2 * np.pi / SPIN / steps_per_rev
    t_end, t_out = _grid(revolutions * 2 * np.pi / SPIN, dt, 20 * revolutions)
    with Stopwatch() as w:
        res = system.simulate(t_end, dt, t_out=t_out, energies=True,
                              plan=False, rho_inf=rho_inf)
    L = np.array([system.angular_momentum(t, q, u) for t, q, u in zip(res.t, res.q, res.u)])
    com_frame = body.com_frame()
    com = np.array([body.point_position(q[body.q_slice], com_frame) for q in res.q])
    P_lin = np.array([system.linear_momentum(t, q, u) for t, q, u in zip(res.t, res.q, res.u)])
    L_com = L - np.cross(com, P_lin)          # about the (discrete) centre of mass
    lever = float(np.linalg.norm(c - (c @ axis) * axis))
    rot_err = [_rotation_angle(Rotation.from_rotvec(SPIN * t * axis).as_matrix(), body.orientation(q[body.q_slice]))
               for t, q in zip(res.t, res.q)]
    E = res.total_energy()
    e_rot = 0.5 * SPIN ** 2 * w2[2]
    e_vib = 0.5 * float(qdot_f @ qdot_f)       # M_ff = 1 (mass-normalized modes)
    return {"revolutions": revolutions, "t_end": t_end, "dt": dt, "omega_dt": SPIN * dt, "rho_inf": rho_inf,
            "steps": res.stats["steps"], "run_time_s": w.seconds,
            "energy_drift": res.energy_drift(), "energy_growth": float(E.max() / E[0] - 1.0),
            "momentum_drift": float(np.linalg.norm(L - L[0], axis=1).max() / np.linalg.norm(L[0])),
            "momentum_drift_about_com": float(np.linalg.norm(L_com - L_com[0], axis=1).max()
                                              / np.linalg.norm(L_com[0])),
            "linear_momentum_max": float(np.linalg.norm(P_lin, axis=1).max()),
            "orientation_error": float(max(rot_err)), "orientation_error_end": float(rot_err[-1]),
            "com_drift_m": float(np.linalg.norm(com - com[0], axis=1).max()), "lever_m": lever,
            "omega1": float(w_modes[0]), "vibration_energy_fraction": e_vib / e_rot,
            "finite": bool(np.isfinite(res.q).all())}


@stability_case("hundred_revolutions", "100 revolutions of a free flexible block about its major axis")
def hundred_revolutions(quick: bool) -> StabilityRow:
    """Bounds (engineering tolerances): energy drift <= 1e-4, angular-momentum drift about
    the moving centre of mass <= 1e-4, orientation error <= 1e-2 rad (0.6° after 100
    turns; the elastic part adds ~2e-6 rad). The centre of mass should stay at rest, but
    generalized-α advances the frame origin in R³ apart from the rotation (R³ x SO(3)):
    with the origin off the centre of mass by |c⊥| the discrete centre of mass drifts at
    ≈ (ΩΔt)² Ω |c⊥| / 12 per unit time, and the angular momentum about the inertial origin
    with it. That is the scheme's second-order error, not an instability: the case runs
    again at half the step and requires both to fall by at least 3 (4 for second order).
    Quick: 10 revolutions."""
    revs = 10 if quick else 100
    m = run_hundred_revolutions(revs)
    fine = run_hundred_revolutions(revs, steps_per_rev=2 * STEPS_PER_REV)
    m["run_time_s"] += fine["run_time_s"]
    b = REVOLUTION_BOUNDS
    com_rel = m["com_drift_m"] / m["lever_m"]
    order_com = m["com_drift_m"] / fine["com_drift_m"]
    order_L = m["momentum_drift"] / fine["momentum_drift"]
    m.update(com_drift_half_step_m=fine["com_drift_m"], momentum_drift_half_step=fine["momentum_drift"],
             com_drift_ratio=order_com, momentum_drift_ratio=order_L)
    failures = []
    if not m["energy_drift"] <= b["energy"]:
        failures.append(f"energy drift {m['energy_drift']:.3g} > {b['energy']:g}")
    if not m["momentum_drift_about_com"] <= b["momentum"]:
        failures.append(f"angular-momentum drift about the centre of mass {m['momentum_drift_about_com']:.3g} "
                        f"> {b['momentum']:g}")
    if not m["orientation_error"] <= b["orientation"]:
        failures.append(f"orientation error {m['orientation_error']:.3g} rad > {b['orientation']:g} rad")
    if not (order_com >= 3.0 and order_L >= 3.0):
        failures.append(f"the centre-of-mass drift ({m['com_drift_m']:.3g} → {fine['com_drift_m']:.3g} m) and the "
                        f"angular-momentum drift ({m['momentum_drift']:.3g} → {fine['momentum_drift']:.3g}) do not "
                        f"fall by 3 at half the step")
    passed, outcome = _verdict(failures)
    note = (f"steel block {BLOCK} m, frame origin at a corner; {revs} revolutions at Ω = {SPIN} rad/s about the major "
            f"axis (Ω/ω1 = {SPIN / m['omega1']:.2g}), generalized-α ρ∞ = {m['rho_inf']}, "
            f"{STEPS_PER_REV} steps per revolution (ΩΔt = {m['omega_dt']:.3g}, {m['steps']} steps); vibration energy "
            f"{m['vibration_energy_fraction']:.2g} of the rotational energy. Energy drift {m['energy_drift']:.2g}, "
            f"angular-momentum drift {m['momentum_drift']:.2g} (about the moving centre of mass "
            f"{m['momentum_drift_about_com']:.2g}), orientation error {m['orientation_error']:.2g} rad "
            f"(at the end {m['orientation_error_end']:.2g}), centre-of-mass displacement {m['com_drift_m']:.2g} m "
            f"({com_rel:.2g} of the lever arm; {fine['com_drift_m']:.2g} m at half the step, ratio {order_com:.2f}; "
            f"angular-momentum drift ratio {order_L:.2f}: second-order error of the R³ x SO(3) update); bounds "
            f"{b['energy']:g}, {b['momentum']:g}, {b['orientation']:g} rad, drift ratios >= 3")
    m["com_drift_relative"] = com_rel
    return StabilityRow("hundred_revolutions", finished=True, stable=m["finite"] and m["energy_growth"] <= b["energy"],
                        energy_drift=m["energy_drift"], max_penetration=None, error=m["orientation_error"],
                        reference="analytic rigid rotation [rad]", run_time_s=m["run_time_s"], passed=passed,
                        outcome=outcome, note=note, details=m)


# ---------------------------------------------------------------------------------------
# tennis_racket: spin near the intermediate principal axis
# ---------------------------------------------------------------------------------------

RACKET = (0.1, 0.2, 0.3)    # m: the block's sides
RACKET_SPIN = 1.0           # rad/s about the intermediate axis
RACKET_TILT = 0.01          # ω3(0) / ω2(0)


def flip_period(I, w0) -> tuple[float, float, float]:
    """Jacobi's solution of torque-free rotation (Landau & Lifshitz, Mechanics, §37).

    Principal moments I = (I1, I2, I3) with I1 < I2 < I3 [kg m²] and initial principal
    angular velocity w0 = (0, ω2, ω3) [rad/s] (spin near the intermediate axis, tilted
    towards axis 3). With 2E = Σ I_i ω_i², L² = Σ I_i² ω_i², here L² − 2E I2 =
    I3 (I3 − I2) ω3² > 0, so

        ω1 = √((2E I3 − L²)/(I1 (I3 − I1))) cn τ,   ω2 = √((2E I3 − L²)/(I2 (I3 − I2))) sn τ,
        ω3 = √((L² − 2E I1)/(I3 (I3 − I1))) dn τ,
        τ = ω_p (t − t0),   ω_p = √((I3 − I2)(L² − 2E I1)/(I1 I2 I3)),
        m = k² = (I2 − I1)(2E I3 − L²) / ((I3 − I2)(L² − 2E I1)),

    (ω1 = 0 at t = 0 puts t0 = −K/ω_p). sn has period 4K(m) in τ: ω2 changes sign (the
    body flips) at t = (2j + 1) K/ω_p, and the motion repeats after T = 4K(m)/ω_p, two
    flips. Returns (T [s], ω_p [rad/s], m).
    """
    I1, I2, I3 = I
    if not I1 < I2 < I3:
        raise ValueError(f"need I1 < I2 < I3, got {I}")
    w1, w2, w3 = w0
    if w1 != 0.0:
        raise ValueError("this closed form takes ω1(0) = 0")
    E2 = I1 * w1 ** 2 + I2 * w2 ** 2 + I3 * w3 ** 2
    L2 = (I1 * w1) ** 2 + (I2 * w2) ** 2 + (I3 * w3) ** 2
    if not L2 > E2 * I2:
        raise ValueError("this closed form takes L² > 2E I2 (tilt towards axis 3)")
    wp = math.sqrt((I3 - I2) * (L2 - E2 * I1) / (I1 * I2 * I3))
    m = (I2 - I1) * (E2 * I3 - L2) / ((I3 - I2) * (L2 - E2 * I1))
    return 4.0 * float(ellipk(m)) / wp, wp, m


def euler_rk4_crossings(I, w0, t_end, h):
    """Zero crossings of ω2(t) of the torque-free Euler equations I_i ω̇_i = (I_j − I_k) ω_j ω_k
    (cyclic), integrated with the classical RK4 at step ``h`` [s] in plain floats,
    independently of :mod:`mbs`. Each crossing is located on the cubic Hermite interpolant
    of ω2 between steps (ω̇2 from the equations), so its error is O(h⁴) like the steps'."""
    I1, I2, I3 = I
    a1, a2, a3 = (I2 - I3) / I1, (I3 - I1) / I2, (I1 - I2) / I3

    def f(x, y, z):
        return a1 * y * z, a2 * z * x, a3 * x * y

    x, y, z = (float(v) for v in w0)
    t, out = 0.0, []
    n = int(math.ceil(t_end / h))
    for _ in range(n):
        k1 = f(x, y, z)
        k2 = f(x + 0.5 * h * k1[0], y + 0.5 * h * k1[1], z + 0.5 * h * k1[2])
        k3 = f(x + 0.5 * h * k2[0], y + 0.5 * h * k2[1], z + 0.5 * h * k2[2])
        k4 = f(x + h * k3[0], y + h * k3[1], z + h * k3[2])
        x1 = x + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        y1 = y + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        z1 = z + h / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
        if y == 0.0 or (y > 0) != (y1 > 0):
            d0, d1 = k1[1], a2 * z1 * x1
            s = y / (y - y1) if y != y1 else 0.0          # Newton on the Hermite cubic from the secant
            for _ in range(8):
                h00, h10 = 2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s
                h01, h11 = -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2
                p = h00 * y + h10 * h * d0 + h01 * y1 + h11 * h * d1
                dp = (6 * s * s - 6 * s) * y + (3 * s * s - 4 * s + 1) * h * d0 + \
                     (-6 * s * s + 6 * s) * y1 + (3 * s * s - 2 * s) * h * d1
                s -= p / dp
            out.append(t + s * h)
        x, y, z = x1, y1, z1
        t += h
    return out


def zero_crossings(t, y) -> list[float]:
    """Sign changes of sampled y(t), located by linear interpolation (at a flip ω2 has an
    inflection point, sn'' = 0 at sn = 0, so the interpolation error is third order)."""
    idx = np.flatnonzero(np.signbit(y[:-1]) != np.signbit(y[1:]))
    return [float(t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])) for i in idx]


def periods_from_flips(crossings) -> list[float]:
    """Full periods from flip times: sn's zeros are equally spaced by 2K, so each interval
    between successive flips is half a period, T = 2 (t_{j+1} − t_j)."""
    return [2.0 * (b - a) for a, b in zip(crossings[:-1], crossings[1:])]


def run_tennis_racket(body_kind, flips, dt_per_rad=0.01, rho_inf=1.0):
    """Spin a body about its intermediate principal axis at 1 rad/s, tilted by ω3 = 0.01 ω2
    towards the major axis, with generalized-α (ρ∞ = 1: no numerical damping of the rigid
    rotation) at Δt = ``dt_per_rad``/Ω, long enough for ``flips`` flips; measure the flip
    times (sign changes of ω2 in principal axes) and the period T = 2 (t_{j+1} − t_j).

    ``body_kind``: "rigid" (a RigidBody with the node-mass inertia of the steel block) or
    "ffr" (the block as a free FFR body with 6 free-free modes, Ω/ω1 ≈ 1e-4).
    Reference: T = 4K(m)/ω_p (:func:`flip_period`), cross-checked by
    :func:`euler_rk4_crossings` at two step sizes."""
    data = block_data()
    mass, c, J = node_mass_inertia(data)
    I, P = np.linalg.eigh(J)
    w0 = np.array([0.0, RACKET_SPIN, RACKET_TILT * RACKET_SPIN])
    T, wp, m = flip_period(I, w0)
    K = float(ellipk(m))
    duration = (2 * flips + 0.5) * K / wp
    omega_body = P @ w0
    system = System()
    if body_kind == "rigid":
        body = system.add(RigidBody(mass, J, com=c, name="racket"))
    else:
        body = system.add(FlexibleBodyFFR(data, 6, name="racket"))
    body.set_initial(v=-np.cross(omega_body, c), omega=omega_body)
    dt = dt_per_rad / RACKET_SPIN
    t_end, t_out = _grid(duration, dt, 10 ** 9)      # every step
    with Stopwatch() as w:
        res = system.simulate(t_end, dt, t_out=t_out, energies=True, plan=False, rho_inf=rho_inf)
    w_principal = np.array([P.T @ (body.orientation(q[body.q_slice]).T
                                   @ body.angular_velocity(q[body.q_slice], u[body.u_slice]))
                            for q, u in zip(res.q, res.u)])
    flips_t = zero_crossings(res.t, w_principal[:, 1])
    periods = periods_from_flips(flips_t)
    return {"body": body_kind, "I": I.tolist(), "T_analytic": T, "omega_p": wp, "m": m, "K": K,
            "flip_times": flips_t, "flip_times_analytic": [(2 * j + 1) * K / wp for j in range(flips)],
            "periods": periods, "dt": dt, "steps": res.stats["steps"], "t_end": t_end,
            "energy_drift": res.energy_drift(), "run_time_s": w.seconds,
            "finite": bool(np.isfinite(res.q).all()), "w_max_principal_1": float(np.abs(w_principal[:, 0]).max())}


@stability_case("tennis_racket", "intermediate-axis flip (Dzhanibekov): period vs Jacobi's elliptic solution")
def tennis_racket(quick: bool) -> StabilityRow:
    """Pass: every measured period within 1e-3 of 4K(m)/ω_p (rigid and stiff FFR body),
    the RK4 cross-check of the closed form within 1e-7, energy drift <= (ΩΔt)² (the
    global error of a second-order method with unit constant). Quick: the rigid body, 2
    flips, ΩΔt = 0.02; full: both bodies, 5 flips, ΩΔt = 0.01."""
    kinds = ("rigid",) if quick else ("rigid", "ffr")
    flips = 2 if quick else 5
    dt_per_rad = 0.02 if quick else 0.01
    runs, failures, total = [], [], 0.0
    for kind in kinds:
        r = run_tennis_racket(kind, flips, dt_per_rad)
        total += r["run_time_s"]
        runs.append(r)
        if len(r["periods"]) < 1:
            failures.append(f"{kind}: {len(r['flip_times'])} flips, no full period measured")
        r["period_error"] = max((abs(p / r["T_analytic"] - 1) for p in r["periods"]), default=float("inf"))
        if not r["period_error"] <= 1e-3:
            failures.append(f"{kind}: flip period error {r['period_error']:.3g} > 1e-3")
        r["energy_bound"] = (RACKET_SPIN * r["dt"]) ** 2
        if not r["energy_drift"] <= r["energy_bound"]:
            failures.append(f"{kind}: energy drift {r['energy_drift']:.3g} > (ΩΔt)² = {r['energy_bound']:.3g}")
    # the closed form against RK4 at two steps (the same inertia and initial state)
    r0 = runs[0]
    I, w0 = r0["I"], (0.0, RACKET_SPIN, RACKET_TILT * RACKET_SPIN)
    with Stopwatch() as w:
        rk = [periods_from_flips(euler_rk4_crossings(I, w0, r0["t_end"], h)) for h in (0.02, 0.01)]
    rk_conv = max(abs(a - b) / r0["T_analytic"] for a, b in zip(*rk))
    rk_err = max(abs(p / r0["T_analytic"] - 1) for p in rk[1])
    if not (rk_conv <= 1e-8 and rk_err <= 1e-7):
        failures.append(f"reference check: RK4 period differs from 4K(m)/ω_p by {rk_err:.3g} "
                        f"(RK4 h vs h/2: {rk_conv:.3g})")
    passed, outcome = _verdict(failures)
    note = (f"I = {np.round(I, 5).tolist()} kg m² (steel block {RACKET}, node masses); ω(0) = (0, 1, 0.01) rad/s "
            f"in principal axes; m = {r0['m']:.6f}, ω_p = {r0['omega_p']:.5f} rad/s, T = 4K/ω_p = "
            f"{r0['T_analytic']:.5f} s; RK4 (h = 0.01 s) period error {rk_err:.2g}. "
            + "; ".join(f"{r['body']}: flips at {np.round(r['flip_times'], 3).tolist()} s, period error "
                        f"{r['period_error']:.2g}, energy drift {r['energy_drift']:.2g} ({r['steps']} steps, "
                        f"generalized-α ρ∞ = 1, Δt = {r['dt']:g} s)" for r in runs))
    return StabilityRow("tennis_racket", finished=True, stable=all(r["finite"] for r in runs),
                        energy_drift=max(r["energy_drift"] for r in runs), max_penetration=None,
                        error=max(r["period_error"] for r in runs), reference="flip period 4K(m)/ω_p",
                        run_time_s=total, passed=passed, outcome=outcome, note=note,
                        details={"runs": runs, "rk4_period_error": rk_err, "rk4_convergence": rk_conv,
                                 "rk4_time_s": w.seconds})


# ---------------------------------------------------------------------------------------
# cardan_singularity: a symmetric top whose symmetry axis sweeps through β = ±90°
# ---------------------------------------------------------------------------------------

TOP_INERTIA = (2.0, 2.0, 1.0)      # kg m², symmetric about body z
TOP_OMEGA = (2.0, 0.0, 10.0)       # ω̄(0) [rad/s] in body axes
TOP_MASS = 6.0


def symmetric_top(t, A0, I=TOP_INERTIA, w0=TOP_OMEGA):
    """Torque-free rotation of a symmetric top (I1 = I2, symmetry axis body z), analytic:
    with L̄ = I ω̄ constant in space, L = A0 L̄(0), and λ = (I3 − I1) ω3/I1,

        ω̄(t) = L̄(t)/I1 − λ e3   ⇒   A(t) = exp(t |L|/I1 L̂~) A0 exp(−λ t ẽ3)

    (a steady rotation about the fixed L at |L|/I1 composed with a body-fixed one about e3
    at −λ: Ȧ Aᵀ = (|L|/I1) L̂~ − λ (A e3)~, so ω̄ = Aᵀ ω = L̄/I1 − λ e3, which is the top's
    ω̄ since L̄ = (I1 ω̄1, I1 ω̄2, I3 ω̄3)). Returns A(t) (3, 3)."""
    I1, _, I3 = I
    w0 = np.asarray(w0, dtype=float)
    L = A0 @ (np.asarray(I) * w0)
    lam = (I3 - I1) * w0[2] / I1
    P = Rotation.from_rotvec(t * L / I1).as_matrix()
    Q = Rotation.from_rotvec([0.0, 0.0, -lam * t]).as_matrix()
    return P @ A0 @ Q


def top_initial_orientation(I=TOP_INERTIA, w0=TOP_OMEGA, lead=0.25):
    """A0 such that the symmetry axis A(t) e3, which sweeps the cone of half-angle ϑ
    (cos ϑ = I3 ω3/|L|) about L, passes through the inertial x axis — where the Cardan
    angle β of thesis eq. 2.22 reaches 90° (A[0, 2] = sin β = 1) — a fraction ``lead`` of
    a precession period after t = 0: L is put at angle ϑ from x in the x–y plane.
    Returns (A0, t_singular [s], precession period [s])."""
    I = np.asarray(I, dtype=float)
    w0 = np.asarray(w0, dtype=float)
    Lb = I * w0
    cos_t = Lb[2] / np.linalg.norm(Lb)
    theta = math.acos(cos_t)
    L_hat = np.array([math.cos(theta), math.sin(theta), 0.0])
    B = Rotation.align_vectors([L_hat], [Lb / np.linalg.norm(Lb)])[0].as_matrix()
    a = B @ np.array([0.0, 0.0, 1.0])                   # the axis at t = 0 before phasing
    # the angle ψ about L̂ that takes a to x̂ (both at angle ϑ from L̂)
    e1 = a - (a @ L_hat) * L_hat
    x = np.array([1.0, 0.0, 0.0])
    e2 = x - (x @ L_hat) * L_hat
    psi = math.atan2(np.cross(e1, e2) @ L_hat, e1 @ e2)
    rate = np.linalg.norm(Lb) / I[0]
    period = 2 * np.pi / rate
    A0 = Rotation.from_rotvec((psi - 2 * np.pi * lead) * L_hat).as_matrix() @ B
    return A0, lead * period, period


def run_top(rotation, periods, dt):
    """Integrate the top (a RigidBody, parametrization ``rotation``) with generalized-α
    (default ρ∞) for ``periods`` precession periods; (Result or SimulationError, body,
    A0, max orientation error [rad] against :func:`symmetric_top`, the smallest |cos β|
    met by the exact motion at the samples, run seconds)."""
    A0, t_sing, period = top_initial_orientation()
    system = System()
    body = system.add(RigidBody(TOP_MASS, np.diag(TOP_INERTIA), rotation=rotation, name="top"))
    body.set_initial(A=A0, omega=A0 @ np.array(TOP_OMEGA))
    t_end, t_out = _grid(periods * period, dt, int(round(400 * periods)))
    with Stopwatch() as w:
        try:
            res = system.simulate(t_end, dt, t_out=t_out, plan=False)
        except SimulationError as err:
            return err, body, A0, None, w, t_sing
    err = max(_rotation_angle(symmetric_top(t, A0), body.orientation(q[body.q_slice])) for t, q in zip(res.t, res.q))
    return res, body, A0, err, w, t_sing


@stability_case("cardan_singularity", "symmetric top through the Cardan singularity: quaternion vs Cardan")
def cardan_singularity(quick: bool) -> StabilityRow:
    """The quaternion default must follow the analytic motion through β = ±90° with error
    <= 1e-3 rad at Δt = 1e-3 s and converge at second order (error ratio at Δt and Δt/2
    within 4 ± 1.2); the Cardan run (thesis eq. 2.22, 2.31: Ḡ singular at cos β = 0)
    must either stop with a SimulationError or be visibly wrong (error > 1e-2 rad) — the
    row says which."""
    periods = 0.5 if quick else 2.0
    dt = 1e-3
    failures, total, details = [], 0.0, {}
    errs = []
    for h in (dt, dt / 2):
        res, body, A0, err, w, t_sing = run_top("quaternion", periods, h)
        total += w.seconds
        if isinstance(res, SimulationError):
            return graceful_row("cardan_singularity", res, total, "analytic symmetric-top rotation", expected=False,
                                note="the quaternion run stopped: it should pass the Cardan singularity")
        errs.append(err)
        details[f"quaternion_dt_{h:g}"] = {"error_rad": err, "steps": res.stats["steps"]}
    order = math.log2(errs[0] / errs[1]) if errs[1] > 0 else float("inf")
    if not errs[0] <= 1e-3:
        failures.append(f"quaternion error {errs[0]:.3g} rad > 1e-3 rad")
    if not 2 ** 2 - 1.2 <= errs[0] / errs[1] <= 2 ** 2 + 1.2:
        failures.append(f"quaternion convergence ratio {errs[0] / errs[1]:.3g} (order {order:.2f}), expected ≈ 4")
    res_c, body_c, _, err_c, w, _ = run_top("cardan", periods, dt)
    total += w.seconds
    if isinstance(res_c, SimulationError):
        cardan = (f"Cardan stopped gracefully at t = {res_c.t:.4g} s (step {res_c.step}; the exact motion is "
                  f"singular at t = {t_sing:.4g} s): {res_c.cause}")
        details["cardan"] = {"stopped": True, "t": res_c.t, "step": res_c.step, "cause": res_c.cause}
    else:
        cardan = f"Cardan finished but lost accuracy: error {err_c:.3g} rad"
        details["cardan"] = {"stopped": False, "error_rad": err_c, "steps": res_c.stats["steps"]}
        if not err_c > 1e-2:
            failures.append(f"Cardan neither stopped nor lost accuracy (error {err_c:.3g} rad): "
                            "did the motion miss the singularity?")
    passed, outcome = _verdict(failures)
    if passed:
        outcome = f"passed; {cardan}"
    note = (f"rigid symmetric top I = {TOP_INERTIA} kg m², ω̄(0) = {TOP_OMEGA} rad/s, its axis passes inertial x "
            f"(β = 90°) at t = {t_sing:.4g} s and once per precession period; {periods:g} period(s), generalized-α "
            f"ρ∞ = 0.9. Quaternion error {errs[0]:.2g} rad at Δt = {dt:g} s, {errs[1]:.2g} at Δt/2 (order "
            f"{order:.2f}). {cardan}")
    details["t_singular"] = t_sing
    return StabilityRow("cardan_singularity", finished=True, stable=True, energy_drift=None, max_penetration=None,
                        error=errs[0], reference="analytic symmetric-top rotation [rad]", run_time_s=total,
                        passed=passed, outcome=outcome, note=note, details=details)


# ---------------------------------------------------------------------------------------
# spin_near_bending: a cantilever spun up towards its first bending frequency
# ---------------------------------------------------------------------------------------

SPUN_BEAM = ((0.05, 0.05, 1.0), (2, 2, 20))     # steel, tet4, clamped at z = 0 (the hub)


@functools.lru_cache(maxsize=None)
def spun_beam_data():
    """A 50 x 50 mm x 1 m steel cantilever (tet4, structured), 4 clamped modes."""
    (lx, ly, lz), div = SPUN_BEAM
    return build_body(box(lx, ly, lz, None, order=1, divisions=div), STEEL, 4, clamp="z0")


def spin_up(alpha):
    """The prescribed frame of a hub spun up about body x at constant angular acceleration
    α [rad/s²] from rest: A(t) = R_x(α t²/2), ω̄ = (α t, 0, 0), ω̄̇ = (α, 0, 0)."""
    zero = np.zeros(3)

    def rotation(t):
        return (Rotation.from_rotvec([0.5 * alpha * t * t, 0.0, 0.0]).as_matrix(),
                np.array([alpha * t, 0.0, 0.0]), np.array([alpha, 0.0, 0.0]))
    return PrescribedFrameMotion(lambda t: (zero, zero, zero), rotation)


def run_spin_up(final_ratio, alpha_periods=10, samples=501):
    """Spin the cantilever up to |Ω| = final_ratio ω1 in ``alpha_periods`` periods of its
    first bending mode (generalized-α, Δt = T1/100) and collect the validity warnings:
    from the driver's hook (``result.stats["validity_warnings"]``) when it exists, else by
    running :class:`~mbs.bodies.validity.SpinMonitor` over the result's samples (what the hook
    does). Returns a dict with the events, the warnings seen, ω1 and the analytic
    crossing time t* = ratio ω1/α."""
    data = spun_beam_data()
    w1 = float(np.sqrt(data.modal_eigenvalues()[0]))      # preprocess's eigenvalue: independent of the monitor
    T1 = 2 * np.pi / w1
    t_end, t_out = _grid(alpha_periods * T1, T1 / 100, samples - 1)
    alpha = final_ratio * w1 / t_end
    system = System()
    system.add(FlexibleBodyFFR(data, 4, frame=spin_up(alpha), name="spun beam"))
    with warnings.catch_warnings(record=True) as seen, Stopwatch() as w:
        warnings.simplefilter("always", FFRValidityWarning)
        res = system.simulate(t_end, T1 / 100, t_out=t_out, plan=False)
        if "validity_warnings" in res.stats:      # the driver's hook ran the monitor and it warned
            source, events = "driver", list(res.stats["validity_warnings"])
        else:                                      # no hook, or the hook saw nothing: check the samples here
            source, monitor = "case", SpinMonitor(system)
            for t, q, u in zip(res.t, res.q, res.u):
                monitor.check(t, q, u)
            events = monitor.events
    warned = [x for x in seen if issubclass(x.category, FFRValidityWarning)]
    return {"events": [list(e) for e in events], "warnings": [str(x.message) for x in warned], "source": source,
            "omega1": w1, "alpha": alpha, "t_cross": SPIN_RATIO * w1 / alpha, "t_end": t_end,
            "sample_dt": float(np.diff(t_out).max()), "run_time_s": w.seconds, "steps": res.stats["steps"],
            "finite": bool(np.isfinite(res.q).all()), "omega_end": alpha * t_end}


@stability_case("spin_near_bending", "spin-up towards the first bending frequency: the FFR validity warning")
def spin_near_bending(quick: bool) -> StabilityRow:
    """Two spin-ups of a clamped cantilever about an axis normal to it: to 0.5 · ratio · ω1
    (no warning allowed) and to 1.5 · ratio · ω1 (exactly one FFRValidityWarning and one
    event, first sampled at or after the analytic crossing t* = ratio ω1/α and within one
    output interval of it). ratio = mbs.bodies.validity.SPIN_RATIO."""
    periods = 6 if quick else 20
    below = run_spin_up(0.5 * SPIN_RATIO, periods)
    above = run_spin_up(1.5 * SPIN_RATIO, periods)
    failures = []
    if below["events"] or below["warnings"]:
        failures.append(f"warned below the ratio: {below['events']}")
    if len(above["events"]) != 1 or len(above["warnings"]) != 1:
        failures.append(f"expected exactly one warning above the ratio, got {len(above['warnings'])} warnings and "
                        f"{len(above['events'])} events")
    err = None
    if above["events"]:
        t_warn = above["events"][0][0]
        err = (t_warn - above["t_cross"]) / above["t_cross"]
        if not 0.0 <= t_warn - above["t_cross"] <= above["sample_dt"] * (1 + 1e-9):
            failures.append(f"warning at t = {t_warn:.5g} s, the spin crosses {SPIN_RATIO} ω1 at "
                            f"t* = {above['t_cross']:.5g} s (sample interval {above['sample_dt']:.3g} s)")
    passed, outcome = _verdict(failures)
    w1 = above["omega1"]
    t_warn = above["events"][0][0] if above["events"] else float("nan")
    note = (f"steel cantilever 50 x 50 mm x 1 m, ω1 = {w1:.4g} rad/s, spun about body x from rest at α = "
            f"{above['alpha']:.4g} rad/s² to {above['omega_end'] / w1:.2f} ω1 (and a second run to "
            f"{below['omega_end'] / w1:.2f} ω1: {len(below['warnings'])} warnings); ratio {SPIN_RATIO}; "
            f"t* = {above['t_cross']:.5g} s, warned at {t_warn:.5g} s "
            f"(events reported by the {above['source']}); "
            f"linear FFR predicts the in-plane bending frequency √(ω1² − Ω²) = "
            f"{math.sqrt(1 - (above['omega_end'] / w1) ** 2):.3f} ω1 at the end, the stiffened beam lies above ω1")
    return StabilityRow("spin_near_bending", finished=True, stable=above["finite"] and below["finite"],
                        energy_drift=None, max_penetration=None, error=err,
                        reference="analytic crossing time t* = ratio ω1/α (relative)",
                        run_time_s=above["run_time_s"] + below["run_time_s"], passed=passed, outcome=outcome,
                        note=note, details={"below": below, "above": above, "ratio": SPIN_RATIO})
