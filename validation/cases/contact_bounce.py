"""Bouncing ball on a rigid plane with Newton's impact law: Moreau time-stepping, fixed and adaptive.

Setup: a point mass m = 1 kg carrying a sphere of radius R = 0.1 m
(:class:`contours.SphereContour`) above the rigid plane z = 0
(:class:`contours.PlaneContour` on :func:`mbs.ground_frame`), gravity g = 9.81 m/s² along
−z, released from rest with its lowest point at height H = 1 m (centre at H + R).
Contact law :class:`contact.laws.UnilateralNewtonImpact` with restitution e = 0, 0.7, 1.

Analytic reference (z the height of the lowest point, z = q_z − R [m]). The first
impact is at t_1 = sqrt(2H/g) with speed v_1 = g t_1; impact k leaves at e^(k−1) v_1, so
flight k (between impacts k and k+1) lasts 2 e^k t_1 and reaches the apex height

    h_k = e^(2k) H,        t_(k+1) = t_k + 2 e^k t_1,

and for e < 1 the impacts accumulate at the Zeno time
t_∞ = t_1 (1 + 2e/(1 − e)) (t_∞ = 2.5586 s for e = 0.7), after which the ball rests on
the plane: z = 0, ż = 0. For e = 0 it rests from t_1 on. Total energy never grows.

Measurement. Between contacts both integrators are exact: a Moreau step under constant
gravity is the trapezoidal rule on the positions with the exact velocity update, so the
numerical free flight is a parabola through each output sample (t_i, z_i, ż_i) with
z_i > 0. Its roots give the numerical ball's landing time t_i + (s + ż_i)/g and launch
time t_i − (s − ż_i)/g, s = sqrt(ż_i² + 2 g z_i), and its apex z_i + ż_i²/(2g), all
independent of the output grid (samples of one flight share them; a new launch time
starts a new flight). Flight 0 is the drop; impact k is the landing of flight k−1 and
the launch of flight k.

Errors (one error kind each):

- "impact time [s]": max over the first K impacts (K = 3 for e = 1, 5 for e = 0.7) of
  max(|t_landing − t_k|, |t_launch − t_k|), absolute [s]: the mistimed interval of the
  numerical impact (the ball's numerical contact lasts from its landing to its launch).
  Not reported for e = 0 (no launch; the landing itself is exact, see above).
- "apex height (rel.)": max over flights 1..K of |h_num/h_k − 1| [-] (e > 0).
- "resting |z − R| [m]": max |q_z − R| at the output times after t_1 + 0.1 s (e = 0) or
  t_∞ + 0.1 s (e = 0.7): sinking into the plane (or still hopping) when the ball
  should rest on it.

Extra columns: "energy_gain" = max_t (E(t) − E(0))/E(0) at the output times [-] (must be
<= 0 up to rounding for e <= 1), "rest_speed" max |ż| after rest [m/s], accepted "steps",
"rejected" steps and the smallest step [s] of the adaptive runs, largest midpoint
penetration "max_penetration" [m].

Swept: fixed step ``integrator="moreau"`` with Δt = 1e-2 … 1e-4 s (quick: 1e-2 … 1e-3);
``integrator="moreau-adaptive"`` (step doubling) with the largest step 1e-2 s (its
output grid too), rtol = 0 and atol = 1e-3 … 1e-6 m (quick: 1e-3, 1e-5). CPU time: one
``System.simulate`` call (a short warm-up run per integrator first).
"""

from __future__ import annotations

import math

import numpy as np

from contact.contact import Contact
from contact.kinematics import ContactKinematicsSpherePlane
from contact.laws import UnilateralNewtonImpact
from contours import PlaneContour, SphereContour
from mbs import PointMass, System, ground_frame
from validation import CaseResult, make_row, timed

NAME = "contact_bounce"
DESCRIPTION = ("ball dropped on a rigid plane, Newton impact e = 0, 0.7, 1: impact times, apex heights, "
               "Zeno rest vs the analytic bouncing ball; Moreau fixed step vs adaptive")

G, H, R, MASS = 9.81, 1.0, 0.1, 1.0       # [m/s²], [m], [m], [kg]
RESTITUTIONS = (0.0, 0.7, 1.0)
N_IMPACTS = {0.0: 1, 0.7: 5, 1.0: 3}      # impacts compared (K)
T_END = {0.0: 1.0, 0.7: 3.2, 1.0: 2.5}    # [s]
REST_MARGIN = 0.1                          # [s] after t_1 (e = 0) or t_∞ (e = 0.7)
DT_FIXED = {True: (1e-2, 3e-3, 1e-3), False: (1e-2, 3e-3, 1e-3, 3e-4, 1e-4)}      # [s]
ATOLS = {True: (1e-3, 1e-5), False: (1e-3, 1e-4, 1e-5, 1e-6)}                      # [m]
DT_MAX = 1e-2                              # largest step and output spacing of the adaptive runs [s]
FLIGHT_TOL = 1e-9                          # [s] launch times of one flight agree to this

KIND_TIME = "impact time [s]"
KIND_APEX = "apex height (rel.)"
KIND_REST = "resting |z − R| [m]"


def t_first():
    """t_1 = sqrt(2H/g) [s]: the first impact."""
    return math.sqrt(2.0 * H / G)


def exact_impact_times(e, n):
    """t_1 … t_n [s] of the analytic bouncing ball: t_(k+1) = t_k + 2 e^k t_1."""
    t1 = t_first()
    return t1 + np.concatenate(([0.0], np.cumsum(2.0 * t1 * e ** np.arange(1, n))))


def exact_apex(e, k):
    """Apex height h_k = e^(2k) H [m] of flight k (k = 0: the drop)."""
    return e ** (2 * np.asarray(k)) * H


def t_zeno(e):
    """t_∞ = t_1 (1 + 2e/(1 − e)) [s], e < 1: where the impact times accumulate."""
    return t_first() * (1.0 + 2.0 * e / (1.0 - e))


def rest_start(e):
    """Time [s] after which the ball must rest (None for e = 1)."""
    if e == 0.0:
        return t_first() + REST_MARGIN
    if e < 1.0:
        return t_zeno(e) + REST_MARGIN
    return None


def scene(e):
    """The System: ball (point mass + sphere) above the ground plane, Newton impact ``e``."""
    system = System(gravity=(0.0, 0.0, -G))
    ball = system.add(PointMass(MASS, position=(0.0, 0.0, H + R)))
    kin = ContactKinematicsSpherePlane(SphereContour(ball.point, R), PlaneContour(ground_frame()))
    system.add(Contact(kin, UnilateralNewtonImpact(e)))
    return system


def simulate(e, t_end, integrator, dt, **options):
    """(Result with energies, CPU seconds of the simulate call)."""
    system = scene(e)
    return timed(system.simulate, t_end, dt, integrator=integrator, energies=True, **options)


def flights(t, z, w):
    """Free flights seen in the samples: list of (launch [s], landing [s], apex [m]).

    ``t`` (n,) [s], ``z`` (n,) height of the lowest point [m], ``w`` (n,) vertical
    velocity [m/s]. Every sample with z > 0 lies on its flight's parabola (module
    docstring); consecutive samples with the same launch time (to FLIGHT_TOL) form one
    flight. The root differences s ∓ ż are taken in the form without cancellation.
    """
    out = []
    for ti, zi, wi in zip(t, z, w):
        if not zi > 0.0:
            continue
        s = math.sqrt(wi * wi + 2.0 * G * zi)
        up = 2.0 * G * zi / (s + wi) if wi > 0 else s - wi        # s − ż
        down = 2.0 * G * zi / (s - wi) if wi < 0 else s + wi      # s + ż
        launch, landing, apex = ti - up / G, ti + down / G, zi + wi * wi / (2.0 * G)
        if out and abs(launch - out[-1][0]) <= FLIGHT_TOL:
            continue
        out.append((launch, landing, apex))
    return out


def measure(res, e):
    """The errors of one run (module docstring): dict with keys impact_time, apex, rest,
    energy_gain, rest_speed, n_flights; NaN where a measure does not apply or the run
    has too few flights."""
    t, z, w = res.t, res.q[:, 2] - R, res.u[:, 2]
    fl = flights(t, z, w)
    n = N_IMPACTS[e]
    out = {"impact_time": math.nan, "apex": math.nan, "rest": math.nan, "rest_speed": math.nan,
           "n_flights": len(fl)}
    if e > 0.0 and len(fl) > n:
        t_exact = exact_impact_times(e, n)
        landing = np.array([fl[k - 1][1] for k in range(1, n + 1)])
        launch = np.array([fl[k][0] for k in range(1, n + 1)])
        out["impact_time"] = float(max(np.abs(landing - t_exact).max(), np.abs(launch - t_exact).max()))
        apex = np.array([fl[k][2] for k in range(1, n + 1)])
        out["apex"] = float(np.abs(apex / exact_apex(e, np.arange(1, n + 1)) - 1.0).max())
    start = rest_start(e)
    if start is not None:
        rest = t > start
        out["rest"] = float(np.abs(z[rest]).max())
        out["rest_speed"] = float(np.abs(w[rest]).max())
    E = res.energy["kinetic"] + res.energy["potential"]
    out["energy_gain"] = float((E - E[0]).max() / E[0])
    return out


def _runs(quick):
    """(config, integrator, dt, options) of the sweep."""
    runs = [({"integrator": "moreau", "dt": dt}, "moreau", dt, {}) for dt in DT_FIXED[quick]]
    runs += [({"integrator": "moreau-adaptive", "atol": atol, "dt_max": DT_MAX}, "moreau-adaptive", DT_MAX,
              {"atol": atol, "rtol": 0.0}) for atol in ATOLS[quick]]
    return runs


def _fmt(x, spec=".2e"):
    return "n/a" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("e", "integrator", "error_kind"))
    for integrator in ("moreau", "moreau-adaptive"):     # warm-up through an impact: first-call costs
        simulate(0.7, 0.6, integrator, 1e-2)             # (imports, compiled kernels) not timed
    table = ["| e | integrator | Δt or atol | steps (rejected) | smallest step [s] | impact time [s] | "
             "apex (rel.) | resting \\|z − R\\| [m] | energy gain | CPU [s] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for e in RESTITUTIONS:
        for config, integrator, dt, options in _runs(quick):
            res, cpu = simulate(e, T_END[e], integrator, dt, **options)
            m = measure(res, e)
            st = res.stats
            extra = {"energy_gain": m["energy_gain"], "steps": st["steps"],
                     "rejected": st.get("rejected_steps", 0),
                     "smallest_dt": st.get("smallest_dt", dt), "max_penetration": st["max_penetration"],
                     "rest_speed": m["rest_speed"]}
            cfg = {"e": e, **config}
            if e > 0.0:
                result.rows.append(make_row(NAME, cfg, cpu, m["impact_time"], KIND_TIME,
                                            f"analytic t_k, first {N_IMPACTS[e]} impacts", **extra))
                result.rows.append(make_row(NAME, cfg, cpu, m["apex"], KIND_APEX,
                                            f"analytic e^(2k) H, flights 1..{N_IMPACTS[e]}", **extra))
            if e < 1.0:
                where = "t_1" if e == 0.0 else "t_∞"
                result.rows.append(make_row(NAME, cfg, cpu, m["rest"], KIND_REST,
                                            f"rest on the plane after {where} + {REST_MARGIN:g} s", **extra))
            knob = f"Δt = {dt:g}" if integrator == "moreau" else f"atol = {options['atol']:g}"
            table.append(f"| {e:g} | {integrator} | {knob} | {st['steps']} ({extra['rejected']}) | "
                         f"{extra['smallest_dt']:.2e} | {_fmt(m['impact_time'])} | {_fmt(m['apex'])} | "
                         f"{_fmt(m['rest'])} | {m['energy_gain']:.1e} | {cpu:.3f} |")
    result.notes.append(
        f"Ball (R = {R:g} m, m = {MASS:g} kg) dropped from H = {H:g} m onto a rigid plane, g = {G:g} m/s²; "
        f"t_1 = {t_first():.4f} s, t_∞ = {t_zeno(0.7):.4f} s for e = 0.7. Free flight is integrated exactly "
        "by the Moreau midpoint step, so all error comes from the steps that contain an impact: the contact "
        "closes only where the midpoint penetrates (g_N(q_m) <= 0), i.e. up to one step late, and the "
        "rebound starts from the penetrated position. Fixed steps: impact-time error O(Δt), apex error "
        "O(Δt) for 0 < e < 1 (the rebound leaves from q_m + Δt/2 e v instead of the surface) and zero for "
        "e = 1 (the step maps (q_k, −v) to (q_k, +v) exactly: no energy change); the resting penetration "
        "for e = 0 is up to v_1 Δt/2 (it keeps the midpoint depth at which it closed), for the Zeno rest "
        "much smaller, because the last impacts are slow. Adaptive: step doubling with gap control, largest "
        "step 1e-2 s, rtol = 0; it shrinks the step only around the impacts. The energy gain is at most "
        "rounding in every run (Newton's law with one contact cannot create energy).\n\n" + "\n".join(table))
    return result
