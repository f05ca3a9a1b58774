"""The stability suite's contact cases (issue 8, part 1): stiff penalty contact, grazing,
contour edges, closed-contour seams, redundant contacts, Zeno bouncing, extreme mass ratios.

Every case builds its scene with the public API (``mbs``, ``contact``, ``contours``),
simulates with Moreau time-stepping and measures against an analytic reference derived
below. SI units throughout; g = 9.81 m/s² along −z where gravity acts. Each row says
what it expects; a row passes when the outcome is the expected one (see
:mod:`validation.stability.core`).

Penalty contact (``penalty_*``)
-------------------------------
A point mass m = 1 kg falls onto the rigid plane z = 0 under gravity; contact law
:class:`contact.laws.LinearRegularizedUnilateralConstraint` with stiffness k, no damping:
F_N = −k z for z < 0. It reaches the plane at v0 = 1 m/s (started at height z0 with the
downward speed sqrt(v0² − 2 g z0), so the first touch is at t_hit = (v0 − v_s)/g).
Inside the contact (x = z < 0, τ = t − t_hit):

    m ẍ = −k x − m g  ⇒  x(τ) = −x_s (1 − cos ωτ) − (v0/ω) sin ωτ,   ω = sqrt(k/m), x_s = g/ω²,

so with C = sqrt(x_s² + (v0/ω)²) the largest penetration is δ = x_s + C [m], the contact
lasts τ_c = (π + 2 arctan(g/(ω v0)))/ω [s] (x = 0 again where cos(ωτ + φ) = x_s/C,
tan φ = v0/(ω x_s)), and the energy E = ½ m ż² + m g z + ½ k min(z, 0)² is conserved, so
the mass leaves at the rebound speed v0. Without gravity these become the textbook
π sqrt(m/k), v0 sqrt(m/k) and v0.

Moreau evaluates the penalty force explicitly at the midpoint q_m = q_k + Δt/2 u_k and
updates u with it: in contact this is the Störmer–Verlet (leapfrog) step of the
oscillator, stable only for ω Δt < 2. Its errors for ω Δt < 1: the force switches on and
off at a midpoint instead of at z = 0, so up to half a step of travel v0 Δt/2 of
spring compression is missed or added at entry and at exit, each worth at most
½ k (v0 Δt/2)² = ½ m v0² (ω Δt/2)²: |ΔE|/E ≤ (ω Δt)²/2 and |v_out/v0 − 1| ≤ (ω Δt)²/4;
the leapfrog's modified frequency (2/Δt) arcsin(ω Δt/2) shifts τ_c by (ω Δt)²/24
relative, and entry/exit timing by less than one step, so |τ − τ_c| ≤ Δt + τ_c (ω Δt)²/12;
its modified energy ½ m v² + ½ k x² (1 − (ω Δt/2)²) inflates the amplitude by
(ω Δt)²/8, and the samples (midpoints and step ends) miss the peak by at most
(ω Δt/2)²/2 relative, so |δ_num/δ − 1| ≤ (ω Δt)²/2. These are the pass bounds of the
stable rows, together with an energy drift (E above, relative to ½ m v0²) ≤ (ω Δt)²/2;
each row sweeps the phase of the step grid against the impact (start height
z0 + φ v0 Δt, φ on a uniform grid: 3 phases quick, 8 full) and reports the worst.

For ω Δt > 2 nothing bounds the step: the row expects the run to *stop gracefully*
with a :class:`~ffrmbs.errors.SimulationError` — here through Moreau's
``penetration_bound`` set to 2 δ (the stable rows stay below 1.05 δ): a rebound that
gained energy hits the plane faster next time and penetrates deeper. Those rows sweep
the phase of the step grid against the impact (start height z0 + φ v0 Δt, φ on a uniform
grid) and run 1 s (several bounces); every phase must stop. "Δt from sqrt(m/k)" rows
take Δt = 0.2 sqrt(m/k) (ω Δt = 0.2) and must pass the stable bounds; the adaptive rows
run ``moreau-adaptive`` (k = 1e12) with the coarse largest step 1e-4 s, atol = 1e-3 δ,
rtol = 0, without and with ``penetration_bound`` = 2 δ, and must give the rebound speed
to 1 % and δ to 2 % in every phase (the error control is meant to resolve the contact).

Grazing (``grazing``)
---------------------
No gravity. A ball (point mass 0.3 kg with a sphere of radius r = 0.02 m) moves at
v = 1 m/s along x on the straight line z = R_t + δ past a fixed sphere of radius
R_s = 0.08 m at the origin (R_t = R_s + r). For δ = 0 its path touches the sphere at
x = 0 with g_N = 0 and ġ_N = 0; for δ >= 0 the contact-free straight line is the exact
motion (no impulse, no energy change); for δ < 0 the ball meets the sphere where
cos θ = (R_t + δ)/R_t (θ the normal's angle from the vertical) and Newton's law (e = 0.5)
gives u⁺ = u − (1 + e)(u·n) n = v (1 − (1 + e) sin²θ, 0, (1 + e) sinθ cosθ), after which
the straight path leaves the convex sphere. Moreau closes the contact at the first
midpoint inside, whose normal is tilted less than the exact one by at most the angle
of one step's travel, v Δt/R_t (or not at all, if the contact region 2 R_t sinθ is
shorter than a step, when θ < v Δt/(2 R_t)); so |u⁺_num − u⁺| ≤ (1 + e) v · v Δt/R_t.
The variants δ = 0 (a midpoint exactly at the tangency, and a grid shifted off it),
δ = +1e-9, +1e-6 m must keep u to rounding (1e-14 v) with zero impulse work; δ = −1e-9,
−1e-6, −1e-4, −1e-3 m must lie within that bound: the deflection is continuous in δ.

Contour edge (``contour_edge``)
-------------------------------
No gravity unless stated. A rigid plate (RigidBody welded to the ground by
``Joint.fixed``) carries an open flat 2s NURBS contour (``Contour2sNeutralRigid``, a
6 × 4 grid on [0, L] × [0, W], L = 0.2 m, W = 0.1 m, z = 0, degree 3) or an open 1s
contour along its centre line. A point mass (0.5 kg) falls straight at v0 = 1 m/s
(Newton e = 0.5) at x = L − ε (inside, ε = 1e-3 L, 1e-6 L) or x = L + ε (outside).
Inside: the rebound is exactly e v0 (one impulse solves Newton's law for a single
contact), and the height after the impact misses the exact e v0 (t − t_imp) by
(1 + e) d with d < v0 Δt the midpoint depth at closing; outside: exact free flight, no
contact step at all. Sliding off (gravity on, e = 0): a mass resting on the surface at
x = L − 0.01 m, sliding at 1 m/s toward the edge, stays at z = 0 until
t_e = 0.01 s, then falls: z = −g (t − t_e)²/2; Moreau's free flight is exact, so with
the edge crossing located to one step, |z_num(T) − z(T)| ≤ g (T − t_e) Δt; the sliding
speed must stay 1 m/s exactly (no spurious tangential impulse at the edge).

Closed seams (``closed_seam_cylinder``, ``closed_seam_ring``)
-------------------------------------------------------------
Cylinder ("wall of death"): no gravity; a point mass moves at v inside a rigid closed
cylinder of radius R (a 2s NURBS contour through 64 × 4 points, closed in η, normal
inward), frictionless, e = 0. Exact motion: the circle r = R at constant speed v, the
contact closed throughout, the parameter η crossing its seam once per revolution.
Moreau on velocity level keeps γ⁺_N = 0 at the midpoint normal: with u_{k+1} ⟂ q_m
(the radial normal), |q_m|² grows by exactly v² Δt² per step (q_{k+1} = q_m + Δt/2 u_{k+1},
next q_m = q_{k+1} + Δt/2 u_{k+1}), so the radius drifts outward at v² Δt/(2R) [m/s], and
the speed is projected onto a tangent turned by v Δt/R each step:
v(T) = v0 exp(−v² Δt T/(2 R²)) to leading order. Pass bounds (first order in Δt):
|r − R| ≤ v² Δt T/R + e_shape, |v(T)/v0 − 1| ≤ v² Δt T/R² (twice the predicted
drifts), the angle of the position within 1.5 (v T/R)(v² Δt T/(2 R²)) rad of v t/R (the
angular rate v/r falls by v² Δt t/R² relative, half from the speed, half from the
radius, so the phase lags by (v T/R)(v² Δt T/(2 R²)) to leading order), z = 0 to
rounding; e_shape is the NURBS circle's largest radial deviation, measured by dense
sampling. The seam: η unwrapped must advance monotonically, every step by at most
1.5 v Δt/(2π R) (the interpolation is chord-length, so η ≈ φ/2π), and wrap floor of the
revolutions times.

Ring: gravity on; a rigid ring (radius 0.1 m, 24 points, closed 1s contour in its xy
plane, reference normal z) spins at Ω = 20 rad/s about z on a revolute joint; a point
mass (0.2 kg) rests on it (frictionless, e = 0). Exact: the mass stays at rest, the
contact force is (0, 0, m g), the ring keeps Ω, and the contact point's η moves by
−Ω t/(2π) across the seam (~3 times in 1 s). Checked: position and velocity of the
mass to 1e-12, force to 1e-9 relative, Ω to 1e-9, the contact closed every step, η
against a brute-force closest point of the curve (dense sampling plus golden-section
refinement) to 1e-7, the number of wraps, monotone η.

Redundant contacts (``redundant_contacts_4``, ``redundant_contacts_8_newton``,
``redundant_contacts_friction``)
---------------------------------------------------------------------------------
A rigid box (0.2 × 0.1 × 0.05 m, 2 kg) with contact points at its 4 bottom corners (or
8: corners and edge midpoints) against the ground plane, e = 0: 4 or 8 rows acting on 3
DOF (z, roll, pitch), the Delassus matrix has rank 3. Dropped flat from h = 0.01 m it
lands at t1 = sqrt(2h/g) and must then rest: Σ F_N = m g (1e-8 relative), no drift of
height and orientation (1e-12), the penetration (the landing step's midpoint depth,
< v1 Δt) not growing, the contact problem solved every step (the run finishes), the
first closed step the first whose midpoint is at or after t1. With
Coulomb friction μ = 0.4 (4 corners, redundant tangentially too) and an initial sliding
velocity V = (1, 0.3) m/s the box stops after V/(μ g) at the distance V²/(2 μ g); the
sampled velocity must follow V − μ g t to 1e-9 and the distance must agree within
V Δt. The normal impulses are non-unique; only their sums are checked.

Zeno (``zeno``, ``zeno_adaptive``)
----------------------------------
A ball (1 kg, radius 0.05 m) dropped from H = 0.5 m onto the plane, e = 0.5. Impact k
(k = 1, 2, …) at t_k = t1 (1 + 2 Σ_{j=1}^{k−1} e^j), t1 = sqrt(2H/g), flight k reaches
e^{2k} H, and the impacts accumulate at t_Z = t1 (1 + 2e/(1 − e)) = t1 (1 + e)/(1 − e)
(0.958 s); after t_Z the ball rests, E = m g R. Checks: (i) the numerical Zeno time
t_Z,num (end of the last step with the contact open) within (1 + 1/e) Σ Δt_i of t_Z,
summed over the impact steps (the first closed step of each contact phase): each
impact is detected less than one step late and its launch from the penetrated depth
delays the surfacing by at most Δt/e; (ii) no energy growth beyond the velocity-level
law's own bound: a closed contact with a separating pre-velocity 0 < γ⁻ < g Δt/(1 + e)
receives Λ = m (g Δt − (1 + e) γ⁻) and does work ½ Λ (1 − e) γ⁻ >= 0, at most
m (g Δt)² (1 − e)/(8 (1 + e)) per step; every step's energy change (trace, exact
impulse work under constant gravity) must stay below that, and E(T) <= E(0); (iii)
after t_Z the residual velocity decays by the factor e per step (γ⁺ = −e γ⁻ while
closed), so the height settles: the spread of z over the last half of the rest phase is
<= 1e-9 m and the penetration is not deeper than the largest midpoint penetration of
the run; (iv) the first four impact times within 3 steps (largest step near them) of
t_k. Energy dissipation is by design (e < 1): energy_drift is None, and the energy
error is |E(T) − m g R| relative to E0 = m g (H + R).

Mass ratios (``mass_ratio_1e-6``, ``mass_ratio_1e6``, ``mass_ratio_stack_*``)
-----------------------------------------------------------------------------
Collision: no gravity, a ball of m1 = 1 kg at v1 = 1 m/s hits a ball of m2 = 1e-6 kg
or 1e6 kg at rest, radii 0.05 m, e = 0.8. Momentum and Newton's law give
v1⁺ = (m1 v1 − m2 e v1)/(m1 + m2), v2⁺ = m1 (1 + e) v1/(m1 + m2) and the kinetic energy
loss ½ μ (1 − e²) v1², μ = m1 m2/(m1 + m2). Moreau solves a single impact exactly: the
velocities must match to 1e-9 relative (both balls' scales), momentum to 1e-12.
Stack: gravity on; a ball of m_top rests on a ball of m_bottom resting on the plane
(radii 0.05 m, e = 0), both contacts touching at t = 0. Exact: rest, contact forces
m_top g and (m_top + m_bottom) g. The Delassus matrix of the two contacts,
G = [[1/m_b, −1/m_b], [−1/m_b, 1/m_b + 1/m_t]], gives projected Gauss–Seidel the
contraction factor G12²/(G11 G22) = m_t/(m_t + m_b): light on heavy (m_t/m_b = 1e-6)
converges at once; heavy on light (1e6) needs ~1e7 plain sweeps, so the ``_gs`` row,
plain projected Gauss–Seidel (``subspace_every=0``) with Moreau's 2000 iterations,
expects a graceful stop naming the residual (the default Gauss–Seidel with its subspace
steps solves the stack in ~20 iterations, ``tests/unit/contact/test_contact_solver.py``); the semismooth Newton solver is
insensitive to the ratio and is expected to hold the stack at rest: forces within 1e-6
relative, no drift (1e-9 m), no contact opening, penetration not growing. (Its
solution is exact only to cond(G) ε |c| ~ 1e-12 m/s in the relative velocity, with the
same rounding every step; the gap walked off by ~1e-15 m per step and the contact
opened after ~840 steps until Moreau let a pressed contact close a gap within
closing_tol.)
"""

from __future__ import annotations

import math

import numpy as np

from contact import (Contact, ContactKinematicsPointContour1s, ContactKinematicsPointContour2s,
                     ContactKinematicsPointPlane, ContactKinematicsSpherePlane, ContactKinematicsSphereSphere,
                     LinearRegularizedUnilateralConstraint, ProxSolver, UnilateralCoulombContact,
                     UnilateralNewtonImpact)
from contours import Contour1sNeutralRigid, Contour2sNeutralRigid, PlaneContour, PointContour, SphereContour
from ffrmbs.errors import SimulationError
from mbs import Joint, PointMass, RigidBody, System, ground_frame

from .core import StabilityRow, Stopwatch, graceful_row, stability_case

G = 9.81                     # [m/s²]


def _outcome(failures):
    """(passed, outcome text) from the list of failed checks."""
    return (not failures), ("passed" if not failures else "FAILED: " + "; ".join(failures))


def _check(failures, ok, text):
    """Record ``text`` as a failed check unless ``ok``."""
    if not ok:
        failures.append(text)


def _plane():
    return PlaneContour(ground_frame())


def _run(system, t_end, dt, **options):
    """(Result or the SimulationError that stopped the run, Stopwatch of the simulate call)."""
    with Stopwatch() as sw:
        try:
            res = system.simulate(t_end, dt, **options)
        except SimulationError as err:
            res = err
    return res, sw


# =====================================================================================
# penalty contact
# =====================================================================================

PEN_M, PEN_V0 = 1.0, 1.0     # [kg], impact speed [m/s]


def penalty_reference(k, m=PEN_M, v0=PEN_V0, g=G):
    """Analytic linear-spring contact under gravity (module docstring): dict with ω
    [rad/s], δ (largest penetration) [m], τ_c (duration) [s], v_out (rebound speed) [m/s]."""
    w = math.sqrt(k / m)
    xs = g / w ** 2
    return {"omega": w, "delta": xs + math.hypot(xs, v0 / w),
            "tau": (math.pi + 2.0 * math.atan(g / (w * v0))) / w, "v_out": v0}


def _penalty_scene(k, z0, m=PEN_M, v0=PEN_V0):
    """A point mass at height z0 [m] moving down so that it reaches z = 0 at v0; the
    penalty plane. Returns (system, t_hit [s])."""
    v_s = math.sqrt(v0 ** 2 - 2.0 * G * z0)
    system = System(gravity=(0.0, 0.0, -G))
    p = system.add(PointMass(m, position=(0.0, 0.0, z0), velocity=(0.0, 0.0, -v_s)))
    system.add(Contact(ContactKinematicsPointPlane(PointContour(p.point), _plane()),
                       LinearRegularizedUnilateralConstraint(k), name="penalty"))
    return system, (v0 - v_s) / G


def _first_rebound(res):
    """(rebound speed at the surface [m/s], launch time [s]) of the first contact phase,
    from the first sample after it with z > 0 (it lies on an exact free-flight parabola:
    the Moreau step under constant gravity is exact in free flight); (nan, nan) if the
    samples hold no such point."""
    tr = res.trace
    pen = tr["penetration"]
    if not np.any(pen > 0.0):
        return math.nan, math.nan
    first = int(np.argmax(pen > 0.0))
    after = np.flatnonzero(pen[first:] == 0.0)
    if after.size == 0:
        return math.nan, math.nan
    t_end_contact = tr["t"][first + after[0] - 1]
    z, w = res.q[:, 2], res.u[:, 2]
    cand = np.flatnonzero((res.t > t_end_contact + 1e-15) & (z > 0.0) & (w > 0.0))
    if cand.size == 0:
        return math.nan, math.nan
    j = cand[0]
    s = math.sqrt(w[j] ** 2 + 2.0 * G * z[j])
    return s, res.t[j] - (2.0 * G * z[j] / (s + w[j])) / G     # s − ż without cancellation


def _penalty_energy(res, k, m=PEN_M):
    """E = ½ m ż² + m g z + ½ k min(z, 0)² [J] at the samples (plane at z = 0)."""
    z, w = res.q[:, 2], res.u[:, 2]
    return 0.5 * m * w ** 2 + m * G * z + 0.5 * k * np.minimum(z, 0.0) ** 2


def _penalty_stable(name, k, dt, integrator, quick, bound=True, **options):
    """Runs expected to be stable: one impact each, over phases φ of the step grid against
    the impact (start height z0 + φ v0 Δt), measured against the analytic contact; the
    row reports the worst phase. ``bound``: with Moreau's penetration_bound = 2 δ."""
    ref = penalty_reference(k)
    wdt = ref["omega"] * dt
    phases = np.arange(3) / 3 if quick else np.arange(8) / 8
    reference = "analytic linear-spring contact under gravity (rebound v0, τ_c, δ)"
    E0 = 0.5 * PEN_M * PEN_V0 ** 2
    runs, seconds = [], 0.0
    for phi in phases:
        z0 = (10.5 if integrator == "moreau" else 5.0) * PEN_V0 * dt + phi * PEN_V0 * dt
        system, t_hit = _penalty_scene(k, z0)
        res, sw = _run(system, t_hit + ref["tau"] + 30.0 * dt, dt, integrator=integrator, trace=True,
                       penetration_bound=2.0 * ref["delta"] if bound else None, **options)
        seconds += sw.seconds
        if isinstance(res, SimulationError):
            row = graceful_row(name, res, seconds, reference, expected=False,
                               note=f"k = {k:g} N/m, {integrator}, Δt = {dt:g} s (largest), phase {phi:g}, "
                                    f"penetration_bound = 2 δ = {2 * ref['delta']:.3g} m")
            if integrator != "moreau":
                row.outcome = ("FAILED: " + row.outcome + " — the bound is checked inside every trial step "
                               "(MoreauTimeStepping.step raises StepFailure), so a trial step that the step-size "
                               "control would have rejected and retaken smaller ends the run")
            return row
        v_out, t_launch = _first_rebound(res)
        pen = max(res.stats["max_penetration"], -float(res.q[:, 2].min()))
        runs.append({"phase": float(phi), "v_out": v_out, "tau": t_launch - t_hit, "delta": pen,
                     "energy_drift": float(np.abs(_penalty_energy(res, k) - E0).max() / E0),
                     "steps": res.stats["steps"], "rejected_steps": res.stats.get("rejected_steps", 0),
                     "smallest_dt": res.stats.get("smallest_dt", dt)})
    err_v = max(abs(r["v_out"] / PEN_V0 - 1.0) for r in runs)
    err_tau = max(abs(r["tau"] - ref["tau"]) for r in runs)
    err_pen = max(abs(r["delta"] / ref["delta"] - 1.0) for r in runs)
    drift = max(r["energy_drift"] for r in runs)
    worst = max(runs, key=lambda r: abs(r["v_out"] / PEN_V0 - 1.0))
    failures = []
    if integrator == "moreau":
        _check(failures, err_v <= wdt ** 2 / 4, f"rebound speed error {err_v:.2e} > (ω Δt)²/4 = {wdt ** 2 / 4:.2e}")
        tol_tau = dt + ref["tau"] * wdt ** 2 / 12
        _check(failures, err_tau <= tol_tau, f"duration error {err_tau:.2e} s > {tol_tau:.2e} s")
        _check(failures, err_pen <= wdt ** 2 / 2, f"penetration error {err_pen:.2e} > (ω Δt)²/2")
        _check(failures, drift <= wdt ** 2 / 2, f"energy drift {drift:.2e} > (ω Δt)²/2")
        bounds = "bounds (ω Δt)²/4 (speed), Δt + τ_c (ω Δt)²/12 (duration), (ω Δt)²/2 (penetration, energy)"
    else:
        _check(failures, err_v <= 1e-2, f"rebound speed up to {worst['v_out'] / PEN_V0:.4f} v0 (phase "
                                        f"{worst['phase']:g}): error {err_v:.2e} > 1e-2")
        _check(failures, err_pen <= 2e-2, f"penetration error up to {err_pen:.2e} > 2e-2")
        bounds = "bounds 1e-2 (speed), 2e-2 (penetration)"
    passed, outcome = _outcome(failures)
    if integrator != "moreau" and failures:
        outcome += (" — the step entering the penalty contact is not controlled: Moreau applies the force only "
                    "from the first midpoint below z = 0, and neither the step-doubling error (both solutions "
                    "are the same free flight) nor the gap control (set-valued contacts only, "
                    "AdaptiveMoreauTimeStepping.unilateral) sees the spring compression skipped by that step")
    stable_bound = wdt ** 2 / 2 if integrator == "moreau" else 2e-2
    return StabilityRow(
        name, finished=True, stable=drift <= stable_bound, energy_drift=drift,
        max_penetration=max(r["delta"] for r in runs),
        error=err_v, reference=reference, run_time_s=seconds, passed=passed, outcome=outcome,
        note=(f"k = {k:g} N/m, m = {PEN_M:g} kg, v0 = {PEN_V0:g} m/s, {integrator}, Δt = {dt:.3g} s "
              f"{'(largest) ' if integrator != 'moreau' else ''}(ω Δt = {wdt:.3g}); {len(runs)} phases of the step "
              f"grid, worst reported; error = |v_out/v0 − 1|; {bounds}"),
        details={"k": k, "dt": dt, "omega_dt": wdt, "v_out": worst["v_out"], "tau_exact": ref["tau"],
                 "tau_error_s": err_tau, "delta_exact": ref["delta"], "delta_error": err_pen, "runs": runs})


def _penalty_unstable(name, k, dt, quick):
    """ω Δt > 2: every phase of the step grid must stop with a SimulationError."""
    ref = penalty_reference(k)
    wdt = ref["omega"] * dt
    phases = np.arange(5) / 5 if quick else np.arange(10) / 10
    reference = "explicit penalty step unstable for ω Δt > 2: graceful stop expected (penetration_bound = 2 δ)"
    runs, seconds = [], 0.0
    for phi in phases:
        system, t_hit = _penalty_scene(k, 1e-3 + phi * PEN_V0 * dt)
        with Stopwatch() as sw:
            try:
                res = system.simulate(1.0, dt, integrator="moreau", trace=True, penetration_bound=2.0 * ref["delta"])
                err = None
            except SimulationError as e:
                err, res = e, e.result
        seconds += sw.seconds
        v_out, _ = _first_rebound(res) if len(res.t) else (math.nan, math.nan)
        runs.append({"phase": float(phi), "stopped": err is not None, "t_stop": None if err is None else err.t,
                     "step": None if err is None else err.step, "cause": None if err is None else err.cause,
                     "first_rebound_v_over_v0": v_out / PEN_V0,
                     "max_penetration": res.stats.get("max_penetration", math.nan),
                     "max_upward_speed": float(res.u[:, 2].max()) if len(res.t) else math.nan})
    stopped = [r for r in runs if r["stopped"]]
    silent = [r for r in runs if not r["stopped"]]
    causes_ok = all(any(k in r["cause"] for k in ("penetration", "NaN", "too stiff for the step")) for r in stopped)
    failures = []
    if silent:
        worst = max(silent, key=lambda r: r["max_upward_speed"])
        failures.append(f"{len(silent)} of {len(runs)} step-grid phases finished without any error although "
                        f"unstable: e.g. phase {worst['phase']:g}: upward speed up to "
                        f"{worst['max_upward_speed']:.3g} m/s = {worst['max_upward_speed'] / PEN_V0:.3g} v0 "
                        f"(energy × {(worst['max_upward_speed'] / PEN_V0) ** 2:.3g}); Moreau has no guard for an "
                        "explicit penalty force with ω Δt > 2")
    _check(failures, causes_ok, "a stop had an unexpected cause: " + "; ".join(str(r["cause"]) for r in stopped))
    passed, outcome = _outcome(failures)
    if passed:
        first = stopped[0]
        outcome = (f"failed gracefully (expected) in all {len(runs)} phases, e.g. at t = {first['t_stop']:.4g} s "
                   f"(step {first['step']}): {first['cause']}")
    rebounds = [r["first_rebound_v_over_v0"] for r in runs if math.isfinite(r["first_rebound_v_over_v0"])]
    return StabilityRow(
        name, finished=bool(silent), stable=False, energy_drift=None,
        max_penetration=max((r["max_penetration"] for r in runs), default=None), error=None,
        reference=reference, run_time_s=seconds, passed=passed, outcome=outcome,
        note=(f"k = {k:g} N/m, Δt = {dt:g} s, ω Δt = {wdt:.3g} > 2; {len(runs)} phases of the step grid, 1 s each "
              f"(finished: some phase reached t_end); "
              f"first rebounds (where one completed) {', '.join(f'{v:.3g}' for v in rebounds) or 'none'} v0"),
        details={"runs": runs, "omega_dt": wdt, "delta_exact": ref["delta"]})


def _register_penalty():
    dt_coarse = 1e-4
    for k, label in ((1e5, "1e5"), (1e7, "1e7")):
        stability_case(f"penalty_k{label}", f"penalty contact k = {label} N/m, Δt = 1e-4 s (ω Δt < 1): stable")(
            lambda quick, k=k, label=label: _penalty_stable(f"penalty_k{label}", k, dt_coarse, "moreau", quick))
    for k, label in ((1e9, "1e9"), (1e12, "1e12")):
        stability_case(f"penalty_k{label}",
                       f"penalty contact k = {label} N/m, Δt = 1e-4 s (ω Δt > 2): graceful stop expected")(
            lambda quick, k=k, label=label: _penalty_unstable(f"penalty_k{label}", k, dt_coarse, quick))
        stability_case(f"penalty_k{label}_dt_omega",
                       f"penalty contact k = {label} N/m, Δt = 0.2 sqrt(m/k): stable")(
            lambda quick, k=k, label=label: _penalty_stable(f"penalty_k{label}_dt_omega", k,
                                                            0.2 / penalty_reference(k)["omega"], "moreau", quick))
    atol = 1e-3 * penalty_reference(1e12)["delta"]
    stability_case("penalty_k1e12_adaptive",
                   "penalty contact k = 1e12 N/m, moreau-adaptive (largest step 1e-4 s, atol 1e-3 δ)")(
        lambda quick: _penalty_stable("penalty_k1e12_adaptive", 1e12, dt_coarse, "moreau-adaptive", quick,
                                      bound=False, atol=atol, rtol=0.0))
    stability_case("penalty_k1e12_adaptive_bound",
                   "penalty contact k = 1e12 N/m, moreau-adaptive with penetration_bound = 2 δ")(
        lambda quick: _penalty_stable("penalty_k1e12_adaptive_bound", 1e12, dt_coarse, "moreau-adaptive", quick,
                                      bound=True, atol=atol, rtol=0.0))


_register_penalty()


# =====================================================================================
# grazing
# =====================================================================================

GR_RS, GR_R, GR_V, GR_E, GR_M = 0.08, 0.02, 1.0, 0.5, 0.3     # [m], [m], [m/s], [-], [kg]


def grazing_reference(delta, v=GR_V, e=GR_E):
    """Exact velocity (3,) [m/s] after passing the fixed sphere on the line z = R_t + δ
    (module docstring)."""
    Rt = GR_RS + GR_R
    if delta >= 0.0:
        return np.array([v, 0.0, 0.0])
    c = (Rt + delta) / Rt
    s = math.sqrt(1.0 - c * c)
    return v * np.array([1.0 - (1.0 + e) * s * s, 0.0, (1.0 + e) * s * c])


def _grazing_run(delta, dt, phase, n):
    """Ball on z = R_t + δ, starting (n + phase) steps before x = 0; runs 2n steps."""
    Rt = GR_RS + GR_R
    system = System()
    ball = system.add(PointMass(GR_M, position=(-GR_V * (n + phase) * dt, 0.0, Rt + delta), velocity=(GR_V, 0.0, 0.0)))
    kin = ContactKinematicsSphereSphere(SphereContour(ball.point, GR_R), SphereContour(ground_frame(), GR_RS))
    system.add(Contact(kin, UnilateralNewtonImpact(GR_E), name="graze"))
    return _run(system, 2 * n * dt, dt, integrator="moreau", trace=True, t_out=[2 * n * dt])


@stability_case("grazing", "grazing contact: a ball skimming the top of a fixed sphere (g_N = ġ_N = 0), ± offsets")
def grazing(quick: bool) -> StabilityRow:
    dt = 1e-4 if quick else 2e-5
    n = int(round(0.03 / (GR_V * dt)))     # start 0.03 m before the top: outside the contact region of every δ
    Rt = GR_RS + GR_R
    variants = [(0.0, 0.5), (0.0, 0.25), (1e-9, 0.5), (1e-6, 0.5), (-1e-9, 0.5), (-1e-6, 0.5), (-1e-4, 0.5),
                (-1e-3, 0.5)]
    bound = (1.0 + GR_E) * GR_V * GR_V * dt / Rt
    failures, runs, seconds, pen = [], [], 0.0, 0.0
    for delta, phase in variants:
        res, sw = _grazing_run(delta, dt, phase, n)
        seconds += sw.seconds
        if isinstance(res, SimulationError):
            failures.append(f"δ = {delta:g}: {res}")
            continue
        u = res.u[-1]
        exact = grazing_reference(delta)
        err = float(np.abs(u - exact).max())
        work = float(res.trace["impulse_work"].sum())
        closed = int(res.trace["closed"].sum())
        pen = max(pen, res.stats["max_penetration"])
        runs.append({"delta": delta, "phase": phase, "u_after": u.tolist(), "u_exact": exact.tolist(),
                     "error": err, "closed_steps": closed, "impulse_work": work})
        if delta >= 0.0:
            _check(failures, err <= 1e-14 * GR_V and abs(work) <= 1e-14 * 0.5 * GR_M * GR_V ** 2,
                   f"δ = {delta:g} (phase {phase}): spurious change of velocity {err:.2e} m/s, "
                   f"impulse work {work:.2e} J")
            x_end = -GR_V * (n + phase) * dt + GR_V * 2 * n * dt
            _check(failures, abs(res.q[-1, 0] - x_end) <= 1e-12 and abs(res.q[-1, 2] - (Rt + delta)) <= 1e-15,
                   f"δ = {delta:g}: not on the straight line")
        else:
            _check(failures, err <= bound, f"δ = {delta:g}: deflection error {err:.2e} m/s > (1 + e) v² Δt/R_t = "
                                           f"{bound:.2e}")
    passed, outcome = _outcome(failures)
    worst = max((r["error"] for r in runs), default=None)
    return StabilityRow(
        "grazing", finished=len(runs) == len(variants), stable=not failures, energy_drift=None, max_penetration=pen,
        error=None if worst is None else worst / GR_V, reference="contact-free straight line (δ >= 0); analytic "
        "Newton-impact deflection at the first touch (δ < 0)", run_time_s=seconds, passed=passed, outcome=outcome,
        note=(f"ball r = {GR_R} m past a fixed sphere R_s = {GR_RS} m at v = {GR_V} m/s, e = {GR_E}, Δt = {dt:g} s; "
              f"offsets δ = {', '.join(f'{d:g}' for d, _ in variants)} m; error = max |u⁺ − u⁺_exact|/v; "
              f"bound for δ < 0: (1 + e) v Δt/R_t = {bound / GR_V:.2e}; energy dissipation by design (e < 1) "
              "for δ < 0"),
        details={"runs": runs, "bound": bound})


# =====================================================================================
# contour edge
# =====================================================================================

ED_L, ED_W, ED_V0, ED_E, ED_M = 0.2, 0.1, 1.0, 0.5, 0.5


def _plate(system, dim):
    """A rigid plate welded to the ground carrying a flat open contour on z = 0 over
    [0, L] × [0, W] (2s) or along y = W/2 (1s)."""
    plate = system.add(RigidBody(10.0, 0.1 * np.eye(3), name="plate"))
    system.add(Joint.fixed(ground_frame(), plate.origin))
    if dim == 2:
        grid = np.array([[(x, y, 0.0) for y in np.linspace(0.0, ED_W, 4)] for x in np.linspace(0.0, ED_L, 6)])
        return plate, Contour2sNeutralRigid(plate, grid)
    pts = np.array([(x, 0.5 * ED_W, 0.0) for x in np.linspace(0.0, ED_L, 6)])
    return plate, Contour1sNeutralRigid(plate, pts, normal=(0.0, 0.0, 1.0))


def _edge_scene(dim, x, z0, v, e, gravity):
    system = System(gravity=(0.0, 0.0, -G if gravity else 0.0))
    plate, surface = _plate(system, dim)
    p = system.add(PointMass(ED_M, position=(x, 0.5 * ED_W, z0), velocity=v))
    kin = (ContactKinematicsPointContour2s if dim == 2 else ContactKinematicsPointContour1s)(PointContour(p.point),
                                                                                             surface)
    system.add(Contact(kin, UnilateralNewtonImpact(e), name="edge"))
    return system, plate, p


@stability_case("contour_edge", "a point mass hitting an open NURBS contour just inside / outside its end; "
                                "sliding off the edge")
def contour_edge(quick: bool) -> StabilityRow:
    dt = 1e-4 if quick else 1e-5
    z0 = 40.5 * ED_V0 * dt                  # the impact after 40.5 steps
    T = 100 * dt
    t_imp = z0 / ED_V0
    failures, runs, seconds, pen = [], [], 0.0, 0.0
    for dim in (2, 1):
        for eps in (-1e-3 * ED_L, -1e-6 * ED_L, 1e-6 * ED_L, 1e-3 * ED_L):
            system, plate, p = _edge_scene(dim, ED_L + eps, z0, (0.0, 0.0, -ED_V0), ED_E, False)
            res, sw = _run(system, T, dt, integrator="moreau", trace=True)
            seconds += sw.seconds
            tag = f"{dim}s, x = L {'+' if eps > 0 else '−'} {abs(eps):g} m"
            if isinstance(res, SimulationError):
                failures.append(f"{tag}: {res}")
                continue
            u, z = res.u[-1, p.u_slice], res.q[-1, p.q_slice][2]
            plate_speed = float(np.abs(res.u[:, plate.u_slice]).max())
            closed = int(res.trace["closed"].sum())
            pen = max(pen, res.stats["max_penetration"])
            if eps < 0:
                z_exact = ED_E * ED_V0 * (T - t_imp)
                err_u = abs(u[2] - ED_E * ED_V0) / ED_V0
                err_z = abs(z - z_exact)
                _check(failures, err_u <= 1e-9 and abs(u[0]) + abs(u[1]) <= 1e-12,
                       f"{tag}: rebound {u} instead of (0, 0, {ED_E * ED_V0})")
                _check(failures, err_z <= (1 + ED_E) * ED_V0 * dt,
                       f"{tag}: height error {err_z:.2e} m > (1 + e) v0 Δt")
            else:
                z_exact = z0 - ED_V0 * T
                err_u, err_z = float(np.abs(u - (0.0, 0.0, -ED_V0)).max()) / ED_V0, abs(z - z_exact)
                _check(failures, closed == 0 and err_u == 0.0 and err_z <= 1e-14,
                       f"{tag}: spurious contact ({closed} closed steps, velocity error {err_u:.2e})")
            _check(failures, plate_speed <= 1e-9, f"{tag}: the welded plate moved at {plate_speed:.2e}")
            runs.append({"contour": f"{dim}s", "x_minus_L": eps, "u_after": u.tolist(), "z_end": float(z),
                         "z_exact": z_exact, "velocity_error": err_u, "height_error": err_z, "closed_steps": closed})
    # sliding off the edge (2s), gravity on, e = 0
    v_s = 1.0
    x_s = ED_L - 40.5 * v_s * dt            # the edge after 40.5 steps
    t_e = (ED_L - x_s) / v_s
    system, plate, p = _edge_scene(2, x_s, 0.0, (v_s, 0.0, 0.0), 0.0, True)
    res, sw = _run(system, T, dt, integrator="moreau", trace=True)
    seconds += sw.seconds
    slide = None
    if isinstance(res, SimulationError):
        failures.append(f"sliding off: {res}")
    else:
        qp, up = res.q[:, p.q_slice], res.u[:, p.u_slice]
        z_exact = -0.5 * G * (T - t_e) ** 2
        err_z = abs(qp[-1, 2] - z_exact)
        on = res.t < t_e - dt
        slide = {"z_end": float(qp[-1, 2]), "z_exact": z_exact, "height_error": err_z,
                 "max_|z|_on_surface": float(np.abs(qp[on, 2]).max()),
                 "max_|u_x − v|": float(np.abs(up[:, 0] - v_s).max()), "max_|u_y|": float(np.abs(up[:, 1]).max())}
        pen = max(pen, res.stats["max_penetration"])
        _check(failures, err_z <= G * (T - t_e) * dt, f"sliding off: height error {err_z:.2e} m > g (T − t_e) Δt")
        _check(failures, slide["max_|z|_on_surface"] <= 1e-12, f"sliding off: left the surface early or sank "
                                                               f"({slide['max_|z|_on_surface']:.2e} m)")
        _check(failures, slide["max_|u_x − v|"] <= 1e-12 and slide["max_|u_y|"] <= 1e-12,
               "sliding off: spurious tangential impulse at the edge")
    passed, outcome = _outcome(failures)
    errs = [r["height_error"] for r in runs] + ([slide["height_error"]] if slide else [])
    return StabilityRow(
        "contour_edge", finished=len(runs) == 8 and slide is not None, stable=not failures, energy_drift=None,
        max_penetration=pen, error=max(errs) if errs else None,
        reference="inside: exact rebound e v0 and height e v0 (t − t_imp); outside: exact free flight; "
                  "sliding off: z = 0 until t_e, then −g (t − t_e)²/2",
        run_time_s=seconds, passed=passed, outcome=outcome,
        note=(f"flat open 2s (6 × 4 points) and 1s (6 points) NURBS contours of a welded rigid plate, L = {ED_L} m; "
              f"point mass falling at {ED_V0} m/s at x = L ∓ 1e-3 L, L ∓ 1e-6 L, e = {ED_E}; Δt = {dt:g} s; "
              "error = "
              f"largest height error [m] (bounds (1 + e) v0 Δt inside, 1e-14 outside, g (T − t_e) Δt sliding off); "
              "energy dissipation by design (e < 1)"),
        details={"runs": runs, "slide_off": slide})


# =====================================================================================
# closed seams
# =====================================================================================

CY_R, CY_H, CY_V, CY_M, CY_N = 0.05, 0.04, 1.0, 0.2, 64     # [m], [m], [m/s], [kg], points around


def _unwrap(eta, period=1.0):
    """Unwrapped parameter (n,) and the number of wraps of a periodic parameter."""
    d = np.diff(eta)
    jumps = np.round(d / period)
    return np.concatenate(([eta[0]], eta[0] + np.cumsum(d - jumps * period))), int(np.abs(jumps).sum())


@stability_case("closed_seam_cylinder", "a point mass circling inside a closed 2s NURBS cylinder across its seam")
def closed_seam_cylinder(quick: bool) -> StabilityRow:
    dt, T = (2e-4, 0.7) if quick else (1e-4, 1.0)
    R, v = CY_R, CY_V
    system = System()
    drum = system.add(RigidBody(10.0, 0.1 * np.eye(3), name="drum"))
    system.add(Joint.fixed(ground_frame(), drum.origin))
    phis = 2.0 * np.pi * np.arange(CY_N) / CY_N
    grid = np.array([[(R * math.cos(f), R * math.sin(f), z) for z in np.linspace(-CY_H / 2, CY_H / 2, 4)]
                     for f in phis])
    wall = Contour2sNeutralRigid(drum, grid, closed=(True, False), outward=-1)   # normal towards the axis
    p = system.add(PointMass(CY_M, position=(R, 0.0, 0.0), velocity=(0.0, v, 0.0)))
    kin = ContactKinematicsPointContour2s(PointContour(p.point), wall)
    system.add(Contact(kin, UnilateralNewtonImpact(0.0), name="wall"))
    # the NURBS circle's own radial deviation, by dense sampling (η on 20 001 points, ξ = ½)
    point = wall.new_point()
    shape = max(abs(math.hypot(*wall.evaluate(point, float(eta), 0.5).r[:2]) - R)
                for eta in np.linspace(0.0, 1.0, 20001)[:-1])
    res, sw = _run(system, T, dt, integrator="moreau", trace=True,
                   outputs={"eta": lambda t, q, u: np.array([kin.point2.eta])})
    reference = "circle r = R at constant speed v, angle v t/R (frictionless, contact closed throughout)"
    if isinstance(res, SimulationError):
        return graceful_row("closed_seam_cylinder", res, sw.seconds, reference, expected=False)
    qp, up = res.q[:, p.q_slice], res.u[:, p.u_slice]
    r = np.hypot(qp[:, 0], qp[:, 1])
    speed = np.linalg.norm(up, axis=1)
    phi_num, _ = _unwrap(np.arctan2(qp[:, 1], qp[:, 0]), 2.0 * np.pi)
    phi_err = float(np.abs(phi_num - v * res.t / R).max())
    eta_u, wraps = _unwrap(res["eta"][1:, 0])
    d_eta = np.diff(eta_u)
    revolutions = v * T / (2.0 * np.pi * R)
    closed = res.trace["closed"]
    err_r = float(np.abs(r - R).max())
    err_v = abs(speed[-1] / v - 1.0)
    drift_bound = v * v * dt * T / R
    failures = []
    _check(failures, bool(np.all(closed == 1)), f"the contact opened in {int(np.sum(closed == 0))} steps")
    _check(failures, err_r <= drift_bound + shape, f"radius error {err_r:.2e} m > v² Δt T/R + e_shape = "
                                                   f"{drift_bound + shape:.2e} m")
    _check(failures, err_v <= v * v * dt * T / R ** 2, f"speed error {err_v:.2e} > v² Δt T/R² = "
                                                       f"{v * v * dt * T / R ** 2:.2e}")
    phi_bound = 1.5 * (v * T / R) * (v * v * dt * T / (2 * R * R))
    _check(failures, phi_err <= phi_bound, f"angle error {phi_err:.2e} rad > {phi_bound:.2e} rad")
    _check(failures, float(np.abs(qp[:, 2]).max()) <= 1e-12, "the mass left the plane z = 0")
    _check(failures, wraps == math.floor(revolutions), f"η wrapped {wraps} times in {revolutions:.2f} revolutions")
    step_bound = 1.5 * v * dt / (2.0 * np.pi * R)
    _check(failures, bool(np.all(d_eta > 0.0)) and float(d_eta.max()) <= step_bound,
           f"η not monotone or jumping: steps in [{d_eta.min():.3g}, {d_eta.max():.3g}], bound {step_bound:.3g}")
    passed, outcome = _outcome(failures)
    E = 0.5 * CY_M * speed ** 2
    drift = float(np.abs(E / E[0] - 1.0).max())
    return StabilityRow(
        "closed_seam_cylinder", finished=True, stable=drift <= 2 * v * v * dt * T / R ** 2, energy_drift=drift,
        max_penetration=res.stats["max_penetration"], error=err_r / R, reference=reference, run_time_s=sw.seconds,
        passed=passed, outcome=outcome,
        note=(f"R = {R} m (NURBS, {CY_N} × 4 points, closed in η; radial shape error {shape:.1e} m), v = {v} m/s, "
              f"e = 0, Δt = {dt:g} s, T = {T} s = {revolutions:.2f} revolutions; error = max |r − R|/R; the "
              f"velocity-level scheme's first-order drift: radius +v² Δt/(2R) per second, speed factor "
              f"exp(−v² Δt t/(2R²)) (energy loss, the drift column); η wrapped {wraps} times"),
        details={"radius_error_m": err_r, "shape_error_m": shape, "speed_error": err_v, "angle_error_rad": phi_err,
                 "wraps": wraps, "revolutions": revolutions, "d_eta_range": [float(d_eta.min()), float(d_eta.max())],
                 "predicted_radius_drift_m": v * v * dt * T / (2 * R),
                 "predicted_speed_loss": 1.0 - math.exp(-v * v * dt * T / (2 * R * R)), "steps": res.stats["steps"]})


RG_R, RG_OMEGA, RG_M, RG_N, RG_PHI0 = 0.1, 20.0, 0.2, 24, 1.0    # [m], [rad/s], [kg], points, [rad]


def _closest_eta(curve, x_local, n=4001):
    """Brute-force closest parameter of a closed 1s contour to the body-frame point
    ``x_local``: dense sampling, then golden-section refinement on the bracketing cells."""
    etas = np.linspace(0.0, 1.0, n)[:-1]
    d2 = [float(np.sum((curve.local_position_at(float(e)) - x_local) ** 2)) for e in etas]
    i = int(np.argmin(d2))
    a, b = etas[i] - 1.0 / (n - 1), etas[i] + 1.0 / (n - 1)
    f = lambda e: float(np.sum((curve.local_position_at(float(e % 1.0)) - x_local) ** 2))
    gr = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(60):
        c, d = b - gr * (b - a), a + gr * (b - a)
        if f(c) < f(d):
            b = d
        else:
            a = c
    return (0.5 * (a + b)) % 1.0


@stability_case("closed_seam_ring", "a point mass resting on a spinning closed 1s NURBS ring: the contact "
                                    "point crosses the seam")
def closed_seam_ring(quick: bool) -> StabilityRow:
    dt, T = (1e-3, 0.5) if quick else (2e-4, 1.0)
    system = System(gravity=(0.0, 0.0, -G))
    ring = system.add(RigidBody(2.0, np.diag([0.01, 0.01, 0.02]), name="ring"))
    ring.set_initial(omega=(0.0, 0.0, RG_OMEGA))
    system.add(Joint.revolute(ground_frame(), ring.origin, axis=(0.0, 0.0, 1.0)))
    phis = 2.0 * np.pi * np.arange(RG_N) / RG_N
    curve = Contour1sNeutralRigid(ring, np.array([(RG_R * math.cos(f), RG_R * math.sin(f), 0.0) for f in phis]),
                                  normal=(0.0, 0.0, 1.0), closed=True)
    x0 = np.array([RG_R * math.cos(RG_PHI0), RG_R * math.sin(RG_PHI0), 0.0])
    p = system.add(PointMass(RG_M, position=x0))
    kin = ContactKinematicsPointContour1s(PointContour(p.point), curve)
    system.add(Contact(kin, UnilateralNewtonImpact(0.0), name="ring"))
    res, sw = _run(system, T, dt, integrator="moreau", trace=True, contacts=True,
                   outputs={"eta": lambda t, q, u: np.array([kin.point2.eta])})
    reference = "mass at rest, force (0, 0, m g), ring at Ω, η = closest point of the rotating ring"
    if isinstance(res, SimulationError):
        return graceful_row("closed_seam_ring", res, sw.seconds, reference, expected=False)
    qp, up = res.q[:, p.q_slice], res.u[:, p.u_slice]
    F = res.contacts["ring"]["force"][1:]
    omega = res.u[:, ring.u_slice][:, 3:6]
    failures = []
    moved = float(np.abs(qp - x0).max())
    speed = float(np.abs(up).max())
    f_err = float(np.abs(F - (0.0, 0.0, RG_M * G)).max() / (RG_M * G))
    w_err = float(np.abs(omega - (0.0, 0.0, RG_OMEGA)).max() / RG_OMEGA)
    closed = res.trace["closed"]
    _check(failures, moved <= 1e-12 and speed <= 1e-12, f"the mass moved by {moved:.2e} m (speed {speed:.2e})")
    _check(failures, f_err <= 1e-9, f"contact force error {f_err:.2e} of m g")
    _check(failures, w_err <= 1e-9, f"ring spin error {w_err:.2e}")
    _check(failures, bool(np.all(closed == 1)), f"the contact opened in {int(np.sum(closed == 0))} steps")
    # η at the recorded times is that of the last step's midpoint: compare with the brute-force
    # closest point at the midpoint orientation (the ring turned by Ω (t − Δt/2))
    eta = res["eta"][1:, 0]
    t = res.t[1:]
    check_at = np.linspace(0, len(t) - 1, 12).astype(int)
    eta_err = 0.0
    for i in check_at:
        ang = RG_OMEGA * (t[i] - 0.5 * dt)
        c, s = math.cos(ang), math.sin(ang)
        x_local = np.array([c * x0[0] + s * x0[1], -s * x0[0] + c * x0[1], x0[2]])   # Aᵀ x0
        e_bf = _closest_eta(curve, x_local)
        eta_err = max(eta_err, abs((eta[i] - e_bf + 0.5) % 1.0 - 0.5))
    _check(failures, eta_err <= 1e-7, f"η differs from the brute-force closest point by {eta_err:.2e}")
    eta_u, wraps = _unwrap(eta)
    # η ≈ φ/2π of the contact point in ring axes, from φ0 − Ω Δt/2 down to φ0 − Ω (T − Δt/2):
    # one wrap per integer crossed
    exact_wraps = (math.floor((RG_PHI0 - 0.5 * RG_OMEGA * dt) / (2 * math.pi))
                   - math.floor((RG_PHI0 - RG_OMEGA * (T - 0.5 * dt)) / (2 * math.pi)))
    d_eta = np.diff(eta_u)
    step = RG_OMEGA * dt / (2 * math.pi)
    _check(failures, wraps == exact_wraps, f"η wrapped {wraps} times, expected {exact_wraps}")
    _check(failures, bool(np.all(d_eta < 0.0)) and float(np.abs(d_eta).max()) <= 1.5 * step,
           f"η not monotone or jumping: steps in [{d_eta.min():.3g}, {d_eta.max():.3g}]")
    passed, outcome = _outcome(failures)
    E = res.trace["energy"]
    drift = float(np.abs(E - E[0]).max() / abs(E[0]))
    return StabilityRow(
        "closed_seam_ring", finished=True, stable=drift <= 1e-9, energy_drift=drift,
        max_penetration=res.stats["max_penetration"], error=max(moved / RG_R, f_err, eta_err), reference=reference,
        run_time_s=sw.seconds, passed=passed, outcome=outcome,
        note=(f"ring R = {RG_R} m ({RG_N} points, closed 1s, normal z) spinning at Ω = {RG_OMEGA} rad/s on a "
              f"revolute joint, mass {RG_M} kg resting on it, e = 0, Δt = {dt:g} s, T = {T} s; η wrapped {wraps} "
              f"times; error = max(displacement/R, force error/(m g), η error)"),
        details={"displacement_m": moved, "force_error": f_err, "spin_error": w_err, "eta_error": eta_err,
                 "wraps": wraps, "steps": res.stats["steps"]})


# =====================================================================================
# redundant contacts
# =====================================================================================

BX_A, BX_B, BX_C, BX_M, BX_H = 0.2, 0.1, 0.05, 2.0, 0.01     # box [m], mass [kg], drop height [m]


def _box(npts, law, R0, v0=(0.0, 0.0, 0.0)):
    """The box on the ground plane with contact points at its bottom corners (4) or
    corners and edge midpoints (8), each with ``law``. Returns (system, box, names)."""
    I = BX_M / 12.0 * np.diag([BX_B ** 2 + BX_C ** 2, BX_A ** 2 + BX_C ** 2, BX_A ** 2 + BX_B ** 2])
    system = System(gravity=(0.0, 0.0, -G))
    box = system.add(RigidBody(BX_M, I, name="box"))
    box.set_initial(R=R0, v=v0)
    pts = [(sx * BX_A / 2, sy * BX_B / 2, -BX_C / 2) for sx in (-1, 1) for sy in (-1, 1)]
    if npts == 8:
        pts += [(0.0, sy * BX_B / 2, -BX_C / 2) for sy in (-1, 1)] + [(sx * BX_A / 2, 0.0, -BX_C / 2) for sx in (-1, 1)]
    names = [f"corner {i}" for i in range(len(pts))]
    for name, pt in zip(names, pts):
        system.add(Contact(ContactKinematicsPointPlane(PointContour(box.frame_at(pt)), _plane()), law, name=name))
    return system, box, names


def _redundant_rest(name, npts, solver, quick):
    """The box dropped flat from h: lands at t1 and rests (module docstring)."""
    dt = 1e-3 if quick else 2e-4
    T = 0.3 if quick else 0.5
    system, box, names = _box(npts, UnilateralNewtonImpact(0.0), (0.0, 0.0, BX_C / 2 + BX_H))
    res, sw = _run(system, T, dt, integrator="moreau", trace=True, contacts=True, energies=True, solver=solver)
    reference = "static equilibrium after the landing at t1 = sqrt(2h/g): Σ F_N = m g, no drift"
    if isinstance(res, SimulationError):
        return graceful_row(name, res, sw.seconds, reference, expected=False,
                            note=f"{npts} contact points on 3 DOF, solver {solver}")
    t1 = math.sqrt(2 * BX_H / G)
    v1 = G * t1
    rest = res.t > t1 + 2 * dt
    Fz = sum(res.contacts[n]["force"][:, 2] for n in names)
    f_err = float(np.abs(Fz[rest] / (BX_M * G) - 1.0).max())
    z = res.q[rest, 2]
    quat_vec = float(np.abs(res.q[rest, 4:7]).max())
    tr = res.trace
    pen_rest = tr["penetration"][tr["t"] > t1 + 2 * dt]
    pen_growth = float(pen_rest.max() - pen_rest[0])
    land = float(tr["t"][np.argmax(tr["closed"] > 0)])
    failures = []
    _check(failures, f_err <= 1e-8, f"Σ F_N differs from m g by {f_err:.2e} (relative)")
    _check(failures, float(np.ptp(z)) <= 1e-12 and quat_vec <= 1e-12,
           f"drift at rest: height spread {np.ptp(z):.2e} m, orientation {quat_vec:.2e}")
    _check(failures, res.stats["max_penetration"] < v1 * dt and pen_growth <= 1e-12,
           f"penetration {res.stats['max_penetration']:.2e} m (bound v1 Δt = {v1 * dt:.2e}), growth {pen_growth:.2e}")
    # the first closed step is the first whose midpoint t_end − Δt/2 lies at or after t1
    _check(failures, 0.5 * dt - 1e-12 <= land - t1 < 1.5 * dt,
           f"landing step ending at {land:.5f} s, t1 = {t1:.5f} s")
    passed, outcome = _outcome(failures)
    E = res.energy["kinetic"] + res.energy["potential"]
    E_err = abs(E[-1] - BX_M * G * BX_C / 2) / (BX_M * G * BX_H)
    return StabilityRow(
        name, finished=True, stable=not failures, energy_drift=None, max_penetration=res.stats["max_penetration"],
        error=f_err, reference=reference, run_time_s=sw.seconds, passed=passed, outcome=outcome,
        note=(f"box {BX_A} × {BX_B} × {BX_C} m, {BX_M} kg, {npts} contact points (Delassus rank 3), e = 0, solver "
              f"{solver}, Δt = {dt:g} s, T = {T} s; error = max |Σ F_N/(m g) − 1| at rest; energy loss by design "
              f"(e = 0): final energy within {E_err:.1e} m g h of the resting m g c/2; solver iterations ≤ "
              f"{int(tr['iterations'].max())}, residual ≤ {tr['residual'].max():.1e} m/s"),
        details={"force_error": f_err, "height_spread_m": float(np.ptp(z)), "orientation_drift": quat_vec,
                 "penetration_growth_m": pen_growth, "landing_step_t": land, "t1": t1,
                 "max_iterations": int(tr["iterations"].max()), "max_residual": float(tr["residual"].max()),
                 "energy_error_vs_rest": E_err})


@stability_case("redundant_contacts_4", "rigid box on 4 corner contacts (rank-deficient Delassus), Gauss–Seidel")
def redundant_contacts_4(quick: bool) -> StabilityRow:
    return _redundant_rest("redundant_contacts_4", 4, "gauss-seidel", quick)


@stability_case("redundant_contacts_8_newton", "rigid box on 8 contacts (rank 3 of 8), semismooth Newton")
def redundant_contacts_8_newton(quick: bool) -> StabilityRow:
    return _redundant_rest("redundant_contacts_8_newton", 8, "newton", quick)


@stability_case("redundant_contacts_friction", "rigid box sliding to rest on 4 Coulomb corner contacts")
def redundant_contacts_friction(quick: bool) -> StabilityRow:
    dt = 1e-3 if quick else 2e-4
    mu, V = 0.4, np.array([1.0, 0.3])
    speed0 = float(np.hypot(*V))
    t_stop = speed0 / (mu * G)
    T = t_stop + 0.1
    system, box, names = _box(4, UnilateralCoulombContact(0.0, mu), (0.0, 0.0, BX_C / 2), (V[0], V[1], 0.0))
    res, sw = _run(system, T, dt, integrator="moreau", trace=True, contacts=True)
    reference = "Coulomb sliding: speed V − μ g t, stop at V/(μ g) after V²/(2 μ g)"
    if isinstance(res, SimulationError):
        return graceful_row("redundant_contacts_friction", res, sw.seconds, reference, expected=False)
    u = res.u[:, :2]
    sliding = res.t < t_stop - 2 * dt
    direction = V / speed0
    u_exact = np.outer(np.maximum(speed0 - mu * G * res.t, 0.0), direction)
    v_err = float(np.abs(u[sliding] - u_exact[sliding]).max())
    dist = float(np.hypot(*res.q[-1, :2]))
    dist_exact = speed0 ** 2 / (2 * mu * G)
    Fz = sum(res.contacts[n]["force"][1:, 2] for n in names)
    f_err = float(np.abs(Fz / (BX_M * G) - 1.0).max())
    stopped = float(np.abs(res.u[res.t > t_stop + 2 * dt]).max())
    failures = []
    _check(failures, v_err <= 1e-9, f"sliding velocity error {v_err:.2e} m/s")
    _check(failures, abs(dist - dist_exact) <= speed0 * dt, f"stopping distance {dist:.6f} m vs {dist_exact:.6f} m")
    _check(failures, stopped <= 1e-9, f"still moving after the stop ({stopped:.2e})")
    _check(failures, f_err <= 1e-8, f"Σ F_N differs from m g by {f_err:.2e}")
    tipped = float(np.abs(res.q[:, 4:7]).max())
    lifted = float(np.abs(res.q[:, 2] - BX_C / 2).max())
    _check(failures, tipped <= 1e-10 and lifted <= 1e-12, f"the box tipped ({tipped:.2e}) or left the plane "
                                                          f"({lifted:.2e} m)")
    passed, outcome = _outcome(failures)
    return StabilityRow(
        "redundant_contacts_friction", finished=True, stable=not failures, energy_drift=None,
        max_penetration=res.stats["max_penetration"], error=abs(dist - dist_exact) / dist_exact, reference=reference,
        run_time_s=sw.seconds, passed=passed, outcome=outcome,
        note=(f"box on 4 Coulomb corner contacts, μ = {mu}, V = {speed0:.3f} m/s, Δt = {dt:g} s; error = relative "
              f"stopping-distance error; sliding velocity within {v_err:.1e} m/s, Σ F_N within {f_err:.1e} of m g; "
              f"dissipation by design (friction)"),
        details={"velocity_error": v_err, "distance": dist, "distance_exact": dist_exact, "force_error": f_err,
                 "max_iterations": int(res.trace["iterations"].max())})


# =====================================================================================
# Zeno
# =====================================================================================

ZN_H, ZN_R, ZN_E, ZN_M = 0.5, 0.05, 0.5, 1.0


def zeno_reference(e=ZN_E, H=ZN_H, n=4):
    """(t_Z [s], first n impact times [s]) of the analytic bouncing ball."""
    t1 = math.sqrt(2 * H / G)
    times = t1 + np.concatenate(([0.0], np.cumsum(2 * t1 * e ** np.arange(1, n))))
    return t1 * (1 + e) / (1 - e), times


def _zeno(name, integrator, dt, quick, **options):
    T = 1.5
    system = System(gravity=(0.0, 0.0, -G))
    ball = system.add(PointMass(ZN_M, position=(0.0, 0.0, ZN_H + ZN_R)))
    system.add(Contact(ContactKinematicsSpherePlane(SphereContour(ball.point, ZN_R), _plane()),
                       UnilateralNewtonImpact(ZN_E), name="ground"))
    res, sw = _run(system, T, dt, integrator=integrator, trace=True, **options)
    reference = "analytic bouncing ball: impact times, t_Z = t1 (1 + e)/(1 − e), rest after t_Z"
    if isinstance(res, SimulationError):
        return graceful_row(name, res, sw.seconds, reference, expected=False)
    tr = res.trace
    t_Z, t_imp = zeno_reference()
    closed = tr["closed"] > 0
    opened = np.flatnonzero(~closed)
    t_Z_num = float(tr["t"][opened[-1]]) if opened.size else 0.0
    first = np.flatnonzero(closed & np.concatenate(([True], ~closed[:-1])))     # first closed step of each phase
    impact_t = tr["t"][first] - tr["dt"][first]                                  # the impact steps' starts
    tol_Z = (1 + 1 / ZN_E) * float(tr["dt"][first].sum())
    err_Z = abs(t_Z_num - t_Z)
    n = min(len(t_imp), len(first))
    err_imp = float(np.abs(impact_t[:n] - t_imp[:n]).max()) if n else math.inf
    tol_imp = 3.0 * float(tr["dt"][first[:n]].max()) if n else 0.0
    E = tr["energy"]
    E0 = ZN_M * G * (ZN_H + ZN_R)
    dE = np.diff(np.concatenate(([E0], E)))
    gain_bound = ZN_M * (G * tr["dt"]) ** 2 * (1 - ZN_E) / (8 * (1 + ZN_E)) + 1e-13 * E0
    gain_ratio = float(np.max(dE / gain_bound))
    z = res.q[:, 2] - ZN_R
    late = res.t > 0.5 * (t_Z_num + T)
    spread = float(np.ptp(z[late]))
    rest_pen = float(-z[late].min())
    failures = []
    _check(failures, err_Z <= tol_Z, f"Zeno time {t_Z_num:.5f} s vs {t_Z:.5f} s: error {err_Z:.2e} > {tol_Z:.2e}")
    _check(failures, n == len(t_imp) and err_imp <= tol_imp, f"impact times off by {err_imp:.2e} s > {tol_imp:.2e}")
    _check(failures, gain_ratio <= 1.0, f"a step gained {gain_ratio:.3g} × the velocity-level law's bound")
    _check(failures, E[-1] <= E0, "energy grew over the run")
    _check(failures, spread <= 1e-9 and rest_pen <= res.stats["max_penetration"] + 1e-15,
           f"not at rest: height spread {spread:.2e} m, penetration {rest_pen:.2e} m")
    passed, outcome = _outcome(failures)
    E_err = abs(E[-1] - ZN_M * G * ZN_R) / E0
    return StabilityRow(
        name, finished=True, stable=gain_ratio <= 1.0 and E[-1] <= E0, energy_drift=None,
        max_penetration=res.stats["max_penetration"], error=err_Z / t_Z, reference=reference, run_time_s=sw.seconds,
        passed=passed, outcome=outcome,
        note=(f"ball R = {ZN_R} m from H = {ZN_H} m, e = {ZN_E}, {integrator}, Δt = {dt:g} s"
              f"{' (largest), ' + ', '.join(f'{k} = {v:g}' for k, v in options.items()) if options else ''}; "
              f"{len(first)} numerical impacts, {res.stats['steps']} steps; error = |t_Z,num − t_Z|/t_Z "
              f"(t_Z = {t_Z:.5f} s, bound (1 + 1/e) Σ Δt_impact = {tol_Z:.2e} s); energy dissipation by design "
              f"(e < 1): final energy within {E_err:.1e} E0 of the resting m g R; largest step energy gain "
              f"{gain_ratio:.2f} × the bound m (g Δt)² (1 − e)/(8 (1 + e)); rest spread {spread:.1e} m"),
        details={"t_Z": t_Z, "t_Z_num": t_Z_num, "impact_time_error_s": err_imp, "impacts": int(len(first)),
                 "energy_gain_over_bound": gain_ratio, "rest_spread_m": spread, "rest_penetration_m": rest_pen,
                 "energy_error_vs_rest": E_err, "steps": res.stats["steps"]})


@stability_case("zeno", "Zeno bouncing ball, e = 0.5, fixed step")
def zeno(quick: bool) -> StabilityRow:
    return _zeno("zeno", "moreau", 1e-3 if quick else 1e-4, quick)


@stability_case("zeno_adaptive", "Zeno bouncing ball, e = 0.5, moreau-adaptive")
def zeno_adaptive(quick: bool) -> StabilityRow:
    return _zeno("zeno_adaptive", "moreau-adaptive", 1e-2, quick, atol=1e-6 if quick else 1e-8, rtol=0.0)


# =====================================================================================
# mass ratios
# =====================================================================================

MR_R, MR_E = 0.05, 0.8


def collision_reference(m1, m2, v1, e=MR_E):
    """(v1⁺, v2⁺) [m/s] of a 1D Newton impact of m1 at v1 on m2 at rest."""
    return (m1 * v1 - m2 * e * v1) / (m1 + m2), m1 * (1 + e) * v1 / (m1 + m2)


def _collision(name, m2, quick):
    m1, v1 = 1.0, 1.0
    dt = 1e-4 if quick else 1e-5
    system = System()
    a = system.add(PointMass(m1, position=(-MR_R - 40.5 * v1 * dt, 0.0, 0.0), velocity=(v1, 0.0, 0.0), name="a"))
    b = system.add(PointMass(m2, position=(MR_R, 0.0, 0.0), name="b"))
    system.add(Contact(ContactKinematicsSphereSphere(SphereContour(a.point, MR_R), SphereContour(b.point, MR_R)),
                       UnilateralNewtonImpact(MR_E), name="ab"))
    res, sw = _run(system, 100 * dt, dt, integrator="moreau", trace=True, energies=True)
    reference = "momentum conservation + Newton's impact law (1D)"
    if isinstance(res, SimulationError):
        return graceful_row(name, res, sw.seconds, reference, expected=False)
    ua, ub = res.u[-1, a.u_slice][0], res.u[-1, b.u_slice][0]
    ea, eb = collision_reference(m1, m2, v1)
    err_a = abs(ua - ea) / max(abs(ea), abs(ub) * min(1.0, m2 / m1), 1e-300)
    err_b = abs(ub - eb) / abs(eb)
    p_err = abs(m1 * ua + m2 * ub - m1 * v1) / (m1 * v1)
    mu = m1 * m2 / (m1 + m2)
    dT_exact = -0.5 * mu * (1 - MR_E ** 2) * v1 ** 2
    T0 = 0.5 * m1 * v1 ** 2
    T1 = 0.5 * m1 * ua ** 2 + 0.5 * m2 * ub ** 2
    dT_err = abs((T1 - T0) - dT_exact) / T0
    failures = []
    _check(failures, err_a <= 1e-9 and err_b <= 1e-9, f"post-impact velocities ({ua:.12g}, {ub:.12g}) vs "
                                                      f"({ea:.12g}, {eb:.12g})")
    _check(failures, p_err <= 1e-12, f"momentum error {p_err:.2e}")
    _check(failures, dT_err <= 1e-9, f"kinetic energy loss error {dT_err:.2e} of T0")
    passed, outcome = _outcome(failures)
    return StabilityRow(
        name, finished=True, stable=T1 <= T0, energy_drift=None, max_penetration=res.stats["max_penetration"],
        error=max(err_a, err_b), reference=reference, run_time_s=sw.seconds, passed=passed, outcome=outcome,
        note=(f"ball {m1:g} kg at {v1:g} m/s hits a ball of {m2:g} kg at rest (mass ratio {m2 / m1:g}), e = {MR_E}, "
              f"Δt = {dt:g} s, G = 1/m1 + 1/m2 = {1 / m1 + 1 / m2:.3g} 1/kg; error = velocity error relative to each "
              f"ball's scale; energy loss by design (e < 1) matches ½ μ (1 − e²) v² to {dT_err:.1e} T0; momentum "
              f"to {p_err:.1e}"),
        details={"v1_after": ua, "v2_after": ub, "v1_exact": ea, "v2_exact": eb, "momentum_error": p_err,
                 "energy_loss_error": dT_err, "iterations": int(res.trace["iterations"].max())})


@stability_case("mass_ratio_1e-6", "1D impact of a 1 kg ball on a 1e-6 kg ball")
def mass_ratio_small(quick: bool) -> StabilityRow:
    return _collision("mass_ratio_1e-6", 1e-6, quick)


@stability_case("mass_ratio_1e6", "1D impact of a 1 kg ball on a 1e6 kg ball")
def mass_ratio_large(quick: bool) -> StabilityRow:
    return _collision("mass_ratio_1e6", 1e6, quick)


def _stack(name, m_bottom, m_top, solver, expect_stop, quick):
    dt = 1e-3
    T = 0.2 if quick else 1.0
    system = System(gravity=(0.0, 0.0, -G))
    a = system.add(PointMass(m_bottom, position=(0.0, 0.0, MR_R), name="bottom"))
    b = system.add(PointMass(m_top, position=(0.0, 0.0, 3 * MR_R), name="top"))
    system.add(Contact(ContactKinematicsSpherePlane(SphereContour(a.point, MR_R), _plane()),
                       UnilateralNewtonImpact(0.0), name="ground"))
    system.add(Contact(ContactKinematicsSphereSphere(SphereContour(b.point, MR_R), SphereContour(a.point, MR_R)),
                       UnilateralNewtonImpact(0.0), name="between"))
    ratio = m_top / m_bottom
    method = solver if isinstance(solver, str) else f"{solver.method} (subspace_every = {solver.subspace_every})"
    res, sw = _run(system, T, dt, integrator="moreau", trace=True, contacts=True, solver=solver)
    contraction = ratio / (1 + ratio)
    setup = (f"ball of {m_top:g} kg on a ball of {m_bottom:g} kg on the plane (top/bottom = {ratio:g}), e = 0, "
             f"solver {method}, Δt = {dt:g} s, T = {T} s; Gauss–Seidel contraction factor m_t/(m_t + m_b) = "
             f"{contraction:.6g}")
    reference = "rest: forces m_top g (between) and (m_top + m_bottom) g (ground)"
    if isinstance(res, SimulationError):
        ok = expect_stop and "not solved" in res.cause
        row = graceful_row(name, res, sw.seconds, reference, expected=ok, note=setup)
        if not ok:
            row.outcome = "FAILED: " + row.outcome
        return row
    if expect_stop:
        return StabilityRow(name, finished=True, stable=True, energy_drift=None,
                            max_penetration=res.stats["max_penetration"], error=None, reference=reference,
                            run_time_s=sw.seconds, passed=False,
                            outcome="FAILED: expected the Gauss–Seidel iteration to stop without convergence",
                            note=setup)
    Fg = res.contacts["ground"]["force"][1:, 2] / ((m_top + m_bottom) * G)
    Fb = res.contacts["between"]["force"][1:, 2] / (m_top * G)
    f_err = float(max(np.abs(Fg - 1.0).max(), np.abs(Fb - 1.0).max()))
    za, zb = res.q[:, a.q_slice][:, 2] - MR_R, res.q[:, b.q_slice][:, 2] - 3 * MR_R
    drift = float(max(np.abs(za).max(), np.abs(zb).max()))
    pen = res.trace["penetration"]
    opened = int(np.sum(res.trace["closed"] < 2))
    failures = []
    _check(failures, f_err <= 1e-6, f"contact forces off by up to {f_err:.3g} of the weights")
    _check(failures, drift <= 1e-9, f"the stack moved by {drift:.2e} m")
    _check(failures, opened == 0, f"a contact opened in {opened} steps")
    _check(failures, float(pen.max()) <= 1e-9, f"penetration grew to {pen.max():.2e} m")
    passed, outcome = _outcome(failures)
    if failures and solver == "newton":
        outcome += (" — the Delassus matrix has condition ~m_top/m_bottom, so the relative velocity is exact "
                    "only to ~1e-12 m/s with the same rounding every step; Moreau keeps the gap from walking "
                    "off by letting a pressed contact close a gap within closing_tol (law on γ⁺ + g_N/Δt, "
                    "mbs/integrators/moreau.py)")
    return StabilityRow(
        name, finished=True, stable=drift <= 1e-9, energy_drift=None, max_penetration=res.stats["max_penetration"],
        error=f_err, reference=reference, run_time_s=sw.seconds, passed=passed, outcome=outcome,
        note=setup + f"; error = max relative force error; contact open in {opened} of {len(pen)} steps",
        details={"force_error": f_err, "displacement_m": drift, "steps_with_an_open_contact": opened,
                 "max_penetration_m": float(pen.max()), "max_iterations": int(res.trace["iterations"].max())})


@stability_case("mass_ratio_stack_1e-6", "a 1e-6 kg ball resting on a 1 kg ball on the plane (Gauss–Seidel)")
def mass_ratio_stack_light_on_heavy(quick: bool) -> StabilityRow:
    return _stack("mass_ratio_stack_1e-6", 1.0, 1e-6, "gauss-seidel", False, quick)


@stability_case("mass_ratio_stack_1e6_gs", "a 1e6 kg ball on a 1 kg ball (plain projected Gauss–Seidel): "
                                           "graceful stop expected")
def mass_ratio_stack_heavy_on_light_gs(quick: bool) -> StabilityRow:
    plain = ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000, subspace_every=0)
    return _stack("mass_ratio_stack_1e6_gs", 1.0, 1e6, plain, True, quick)


@stability_case("mass_ratio_stack_1e6_newton", "a 1e6 kg ball on a 1 kg ball (semismooth Newton): rest expected")
def mass_ratio_stack_heavy_on_light_newton(quick: bool) -> StabilityRow:
    return _stack("mass_ratio_stack_1e6_newton", 1.0, 1e6, "newton", False, quick)
