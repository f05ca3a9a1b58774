"""α–Ω decision boundaries against the neglected coupling (report Sec. 4.1 eq. 29–32, Sec. 5.4 Fig. 9).

The boundaries (:func:`mbs.modal.decision.decision_boundaries`) predict, from the modes
alone, the largest node displacement that the fictitious forces of eq. 29 cause for an
angular acceleration α and velocity Ω: k_dyn (d_alpha |α| + d_omega |Ω|²) with k_dyn = 2
(a suddenly applied load). SimpleRB drops those forces, CoupledRB integrates them, so
the difference of the two simulations of the same scene is the effect of the neglected
coupling, measured independently of the boundaries. Report Sec. 5.4's two tests on the
free beam (:func:`_wobble.beam`, 579 nodes, 10 elastic modes), each from rest
(undeformed, r = ṙ = 0):

* spin: no load, initial angular velocity Ω0 [rad/s] about x, about the long axis z
  (whose centrifugal load barely deforms the beam) and about the direction that
  maximises the boundaries' centrifugal response (``omega_direction``, "worst": off the
  principal axes, so the body also tumbles);
* couple: +F along y on the face z = 5 and −F on z = 0 [N] (:func:`_wobble.rotation_loads`,
  report Fig. 6b), a torque 5F [N m] about x: constant α, Ω = α t grows from 0.

Measured: max over all nodes and output times (every 0.1 ms) of |P (r_coupled − r_simple)|,
the elastic displacement in the body frame B (eq. 4) [m] — the quantity eq. 32 bounds.
The difference of the total displacements in G (eq. 24) is recorded too
(``measured_G``): it adds the rigid-body part of the coupling (inertia Î(r) and torque
lever arms updated with the deformation), which the boundaries do not address; here it
is within 1 % of the elastic one except for the tumbling "worst" spin (+11 % at 30 rad/s)
and the z spin at 30 rad/s (+4 %). Predicted: ``displacement(α, Ω)`` with
|α| the largest mean angular acceleration over an output interval,
max_j |Ω(t_j+1) − Ω(t_j)| / (t_j+1 − t_j) [rad/s²], and |Ω| the largest angular speed,
both of the CoupledRB run. Error column: measured / predicted — at most 1 when the
boundaries are conservative.

CoupledRB steps with dt = 1e-4 s (the first elastic period is 5.5 ms, the tenth 1.1 ms);
every run is repeated with dt/2 and the relative change of the measured difference is
recorded (``dt_half_change``). SimpleRB uses RKMK4 with a 1 ms rigid step (its modal
response is exact). CPU time: CoupledRB + SimpleRB solves (``stats["cpu_s"]``).

The notes also reproduce the report's numbers from its literal eq. 32 (the magnitudes
m_n|b_n| projected as a force on every coordinate, largest nodal coordinate), and bound
how far the undamped multi-mode step response can exceed k_dyn = 2 times the static one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mbs.modal import CoupledRB, ModalBasis, SimpleRB
from mbs.modal.decision import SIMPLE, DecisionBoundaries, decision_boundaries
from validation import CaseResult, make_row
from validation.cases import _wobble as wb

NAME = "wobble_decoupling"
DESCRIPTION = ("α–Ω decision boundaries (report eq. 32, Fig. 9) vs CoupledRB − SimpleRB on the free beam: "
               "free spin about x, z and the worst axis, ±F couple")

DT = 1e-4                    # CoupledRB step and output spacing [s]
SIMPLE_DT = 1e-3             # SimpleRB rigid step (RKMK4) [s]
REPORT_SUM_LIMITS = (1.19, 59570.0)   # report Sec. 5.4: |α| + |Ω|² at 1 µm and 5 cm [1/s²]
ERROR_KIND = "measured / predicted coupling displacement"
REFERENCE = "decision boundaries (eq. 32 derived)"


@dataclass(frozen=True)
class Comparison:
    """One scene run by CoupledRB and SimpleRB (module docstring).

    alpha [rad/s²], omega [rad/s]: max |α| and max |Ω| of the CoupledRB run;
    measured, measured_G [m]: max |Δu| of the elastic displacements in B and of the
    total displacements in G; predicted [m]: ``displacement(alpha, omega)``;
    cpu_s [s]: CoupledRB + SimpleRB solve time.
    """

    alpha: float
    omega: float
    measured: float
    measured_G: float
    predicted: float
    recommendation: str
    cpu_s: float

    @property
    def ratio(self) -> float:
        """measured / predicted: at most 1 when the boundaries are conservative."""
        return self.measured / self.predicted


def boundaries(basis: ModalBasis) -> DecisionBoundaries:
    """The displacement-limited boundaries of ``basis`` (1 µm, 5 cm, k_dyn = 2; report Sec. 5.4)."""
    return decision_boundaries(basis.u0, basis.masses, basis.P.reshape(-1, basis.n_modes), basis.omega2)


def compare(basis, bounds, omega0=(0.0, 0.0, 0.0), loads=(), t_end=0.1, dt=DT) -> Comparison:
    """Run CoupledRB (step ``dt`` [s]) and SimpleRB on [0, ``t_end``] [s] from rest with the
    initial angular velocity ``omega0`` (3,) [rad/s] in B axes and the body-frame ``loads``;
    compare them at outputs every ``DT``."""
    t_out = np.linspace(0.0, t_end, int(round(t_end / DT)) + 1)
    c = CoupledRB(basis, loads, angular_velocity=omega0, dt=dt).solve(t_out)
    s = SimpleRB(basis, loads, angular_velocity=omega0, dt=SIMPLE_DT).solve(t_out)
    measured = np.linalg.norm(c.elastic_displacement() - s.elastic_displacement(), axis=2).max()
    measured_g = np.linalg.norm(c.displacements() - s.displacements(), axis=2).max()
    alpha = (np.linalg.norm(np.diff(c.Omega, axis=0), axis=1) / np.diff(t_out)).max()
    omega = np.linalg.norm(c.Omega, axis=1).max()
    return Comparison(float(alpha), float(omega), float(measured), float(measured_g),
                      bounds.displacement(alpha, omega), bounds.recommend(alpha, omega),
                      c.stats["cpu_s"] + s.stats["cpu_s"])


def report_eq32_limits(basis, d_lims=(1e-6, 0.05)) -> tuple:
    """|α| + |Ω|² limits [1/s²] by the report's literal eq. 32: d_lim / max(P (Pᵀ ⊙ 1/ω²) m|b|),
    with m_n|b_n| [kg m] put on all three coordinates of node n and the max over all
    coordinates (this reading reproduces the report's 1.19 and 59570)."""
    mb = np.repeat(basis.masses * np.linalg.norm(basis.b0, axis=1), 3)
    P = basis.P.reshape(-1, basis.n_modes)
    denom = np.abs(P @ ((P.T @ mb) / basis.omega2)).max()
    return tuple(d / denom for d in d_lims)


def step_peak_bound(basis, bounds, direction) -> float:
    """Upper bound of measured / predicted for a sudden spin about ``direction`` (3,).

    The undamped response of node n to the centrifugal load switched on at t = 0 is
    u_n(t) = Σ_k P_nk c_k (1 − cos ω_k t) |Ω|², c_k = F_k / ω_k², F = Pᵀ f with
    f_n = m_n (b_n − (Ω̂·b_n) Ω̂) (eq. 29 per |Ω|², eq. 10–12), so every coordinate obeys
    |u_n,i| <= 2 Σ_k |P_n,ik c_k| |Ω|². Returns max_n of the norm of that bound over
    k_dyn d_omega (k_dyn = 2): above 1, the one-mode amplification 2 can be exceeded
    when the modes' phases line up.
    """
    w = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    f = basis.masses[:, None] * (basis.b0 - (basis.b0 @ w)[:, None] * w[None])
    c = np.einsum("nak,na->k", basis.P, f) / basis.omega2
    peak = 2.0 * np.linalg.norm(np.abs(basis.P * c).sum(axis=2), axis=1).max()
    return float(peak / (bounds.k_dyn * bounds.d_omega))


def run(quick: bool) -> CaseResult:
    """Spins (quick: 0.1, 1, 30 rad/s about x and z, 0.05 s) and couples (quick: 100 N, 100 kN)."""
    mesh, data = wb.beam(n_modes=10)
    basis = ModalBasis.from_body(data)
    bounds = boundaries(basis)
    wb.warm_up()
    t_end = 0.05 if quick else 0.1
    axes = {"x": np.array([1.0, 0.0, 0.0]), "z": np.array([0.0, 0.0, 1.0])}
    if not quick:
        axes["worst"] = bounds.omega_direction
    scenes = [("spin", axis, w, dict(omega0=w * d)) for axis, d in axes.items()
              for w in ((0.1, 1.0, 30.0) if quick else (0.1, 0.3, 1.0, 3.0, 10.0, 30.0))]
    scenes += [("couple", "x", F, dict(loads=[wb.rotation_loads(mesh, F)]))
               for F in ((1e2, 1e5) if quick else (1e2, 1e3, 1e4, 1e5, 1e6))]
    result = CaseResult(plot_groups=["scene", "axis"])
    lines = ["| scene | axis | Ω0 [rad/s] or F [N] | max \\|α\\| [rad/s²] | max \\|Ω\\| [rad/s] | measured B [m] "
             "| measured G [m] | predicted [m] | measured / predicted | recommendation | measured in region "
             "| dt/2 change | CPU s |", "|" + "---|" * 13]
    ratios, changes = {}, []
    unsafe = 0
    for scene, axis, value, kw in scenes:
        cmp = compare(basis, bounds, t_end=t_end, **kw)
        half = compare(basis, bounds, t_end=t_end, dt=DT / 2, **kw)
        change = abs(half.measured / cmp.measured - 1.0)
        changes.append(change)
        region = bounds.region(cmp.measured)
        unsafe += cmp.recommendation == SIMPLE and region != SIMPLE
        ratios.setdefault((scene, axis), []).append(cmp.ratio)
        config = {"scene": scene, "axis": axis, ("omega0" if scene == "spin" else "force"): value,
                  "t_end": t_end, "dt": DT}
        result.rows.append(make_row(NAME, config, cmp.cpu_s, cmp.ratio, ERROR_KIND, REFERENCE,
                                    alpha=cmp.alpha, omega=cmp.omega, measured=cmp.measured,
                                    measured_G=cmp.measured_G, predicted=cmp.predicted,
                                    recommendation=cmp.recommendation, measured_region=region,
                                    dt_half_change=change))
        lines.append(f"| {scene} | {axis} | {value:g} | {cmp.alpha:.3g} | {cmp.omega:.3g} | {cmp.measured:.3e} "
                     f"| {cmp.measured_G:.3e} | {cmp.predicted:.3e} | {cmp.ratio:.3f} | {cmp.recommendation} "
                     f"| {region} | {change:.1e} | {cmp.cpu_s:.2f} |")
    s_neg, s_lin = bounds.sum_limits
    r_neg, r_lin = report_eq32_limits(basis)
    peak = {axis: step_peak_bound(basis, bounds, d) for axis, d in axes.items()}
    all_r = [r for rs in ratios.values() for r in rs]
    result.notes.append(
        f"**Runs** ({t_end:g} s each, CoupledRB dt = {DT:g} s, outputs every {DT:g} s; measured = max |Δu| of "
        "the elastic displacement in B; dt/2 change = relative change of it when CoupledRB's step is "
        f"halved, at most {max(changes):.1e}):\n\n" + "\n".join(lines))
    result.notes.append(
        f"**Boundaries** (10 modes, 1 µm / 5 cm, k_dyn = {bounds.k_dyn:g}): d_alpha = {bounds.d_alpha:.3e} m s² "
        f"(zero to rounding: the free modes are mass-orthogonal to the rigid rotations, so the d'Alembert "
        f"load of α does not deform the body), d_omega = {bounds.d_omega:.4e} m s² about "
        f"Ω̂ = ({', '.join(f'{x:.3f}' for x in bounds.omega_direction)}). sum_limits |α| + |Ω|² = "
        f"{s_neg:.3g} and {s_lin:.6g} 1/s² (report: {REPORT_SUM_LIMITS[0]:g} and {REPORT_SUM_LIMITS[1]:g}). "
        f"The report's literal eq. 32 on these modes gives {r_neg:.3g} and {r_lin:.6g}: it reproduces the "
        f"report's numbers and is {s_neg / r_neg:.2f}× more conservative than the derived bound, which "
        "counts the α part at zero as well.")
    result.notes.append(
        f"**How conservative**: measured / predicted ranges from {min(all_r):.3g} to {max(all_r):.3g}; by scene "
        "and axis " + "; ".join(f"{scene} {axis}: {min(r):.3g}–{max(r):.3g}" for (scene, axis), r in ratios.items())
        + ". A sudden spin about x (or the worst axis) comes within 1 % of the prediction: the dominant axial "
        "mode's step response peaks at twice its static value, as k_dyn = 2 assumes. About the long axis z the "
        "centrifugal load barely deforms the beam, so the direction-free bound is far above it. The couple's "
        "Ω = α t grows slowly against the 5.5 ms first period (quasi-static: amplification 1, not 2), hence about "
        "1/2; its α itself deforms nothing (d_alpha = 0). The undamped multi-mode step response can exceed twice "
        "the static one when the modes' phases line up; step_peak_bound bounds measured / predicted for a sudden "
        "spin by " + ", ".join(f"{a}: {p:.4f}" for a, p in peak.items()) + ", the margin by which the boundaries "
        f"can be exceeded in a long run. Runs recommended SimpleRB whose measured difference exceeds 1 µm: {unsafe}.")
    points = [(row["alpha"], row["omega"], "") for row in result.rows]
    result.figures["alpha_omega_boundaries"] = lambda path: bounds.plot(path, points=points)
    return result
