"""Spin-up beam (Kane, Ryan & Banerjee 1987): geometric stiffening against a nonlinear beam.

Setup: :mod:`validation.scenes.spin_up` — the 10 m cantilever as a tet10 solid (40
elements along x, 2 × 2 across, ν = 0) on a hub spun up to 6 rad/s in 15 s, 0–20 s, Moreau
time-stepping (θ = 0.5). Output: the tip's transverse displacement in the hub frame v_tip.

Reference: the geometrically exact planar beam of :mod:`validation.peers.spin_up_beam`
(ANCF cable elements in the inertial frame, converged in elements and step), which
shares no code with the FFR body: it has the axial stretch and the large rotation
exactly, where the FFR body has them through K_geo to first order in the load.

Swept: ``modes`` (clamped modes, first n: pairs of y/z bending modes of the square
section), ``geometric_stiffening`` on/off, ``dt``. Row error: RMS over 0–20 s of
v_tip − v_ref relative to max|v_ref| (samples every 0.05 s). Without stiffening v_tip
grows without bound after the spin passes ω1 = 3.80 rad/s (t ≈ 8.5 s; before that its
spin softening already doubles the lag): those rows carry the time |v_tip| first exceeds
10 m (``diverged_at_s``) and an error that reflects the blow-up. CPU per row: the
simulation only (the body is preprocessed once, kernels are warmed up before timing).
"""

from __future__ import annotations

import numpy as np

from validation import CaseResult, make_row, timed
from validation.peers import spin_up_beam as peer
from validation.scenes import spin_up as scene

NAME = "spin_up_beam"
DESCRIPTION = ("Kane's spin-up beam (3-D solid, prescribed hub spin to 6 rad/s): tip deflection with and "
               "without geometric stiffening against a geometrically exact beam")

SAMPLE = 0.05              # output interval [s]
DIVERGED = 10.0            # |v_tip| [m] taken as divergence (17 x the reference's peak)
ERROR_KIND = "RMS(v_tip − v_ref) / max|v_ref|, 0–20 s"
REFERENCE = "geometrically exact planar beam (ANCF, converged), validation/peers/spin_up_beam.py"


def simulate(data, modes, stiffening, dt):
    """(t (K,) [s], v_tip (K,) [m], CPU [s]) of the FFR run."""
    system, _, v_tip = scene.spin_up_system(data, modes, geometric_stiffening=stiffening)
    times = np.linspace(0.0, scene.T_END, round(scene.T_END / SAMPLE) + 1)
    result, cpu = timed(system.simulate, scene.T_END, dt, integrator="moreau", t_out=times,
                        outputs={"v_tip": v_tip})
    return result.t, np.asarray(result["v_tip"], dtype=float).ravel(), cpu


def compare(t, v, t_ref, v_ref):
    """(error, peak |v| [m], diverged_at [s] or None) against the reference at the samples t."""
    ref = np.interp(t, t_ref, v_ref)
    with np.errstate(over="ignore", invalid="ignore"):
        error = float(np.sqrt(np.mean((v - ref) ** 2)) / np.abs(v_ref).max())
    beyond = np.flatnonzero(~(np.abs(v) <= DIVERGED))
    return error, float(np.abs(v).max()), (float(t[beyond[0]]) if beyond.size else None)


def run(quick: bool) -> CaseResult:
    modes_list = (4, 10) if quick else (2, 4, 6, 10)
    steps = (4e-3,) if quick else (8e-3, 4e-3, 2e-3)
    data = scene.beam_body(max(modes_list))
    t_ref, v_ref = peer.reference()
    result = CaseResult(plot_groups=("geometric_stiffening", "modes"))
    histories = {}
    warm = scene.spin_up_system(data, 2)[0]
    warm.simulate(4e-3, 2e-3, integrator="moreau")          # compile outside the timings
    for stiffening in (True, False):
        for modes in (modes_list if stiffening else modes_list[-1:]):
            for dt in steps:
                t, v, cpu = simulate(data, modes, stiffening, dt)
                error, peak, diverged = compare(t, v, t_ref, v_ref)
                result.rows.append(make_row(NAME, {"modes": modes, "geometric_stiffening": stiffening, "dt": dt},
                                            cpu, error, ERROR_KIND, REFERENCE, peak_m=peak,
                                            diverged_at_s=diverged))
                histories[(modes, stiffening, dt)] = (t, v)
    result.notes.append(
        f"Reference: max|v_ref| = {np.abs(v_ref).max():.4g} m at t = {t_ref[np.argmax(np.abs(v_ref))]:.2f} s. "
        "Without geometric stiffening the linear FFR model diverges once the hub's spin passes the first "
        f"bending frequency ({np.sqrt(data.eigenvalues[0]):.3g} rad/s).")
    result.figures["history"] = lambda path: plot_history(path, histories, t_ref, v_ref)
    return result


def plot_history(path, histories, t_ref, v_ref):
    """The PNG of v_tip(t): the reference, the stiffened runs, the linear run (clipped)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.plot(t_ref, v_ref, "k-", lw=2.5, alpha=0.4, label="geometrically exact beam (reference)")
    for (modes, stiffening, dt), (t, v) in sorted(histories.items(), key=lambda kv: (not kv[0][1], kv[0])):
        if dt != min(d for (_, _, d) in histories):
            continue
        label = f"ffrmbs, {modes} modes, " + ("with geometric stiffening" if stiffening else "linear FFR (no stiffening)")
        shown = np.where(np.abs(v) <= 2.0, v, np.nan)
        ax.plot(t, shown, "-" if stiffening else "--", lw=1.2, label=label)
    ax.set_ylim(-1.0, 0.3)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("tip deflection in the hub frame v_tip [m]")
    ax.set_title("Spin-up beam (Kane et al. 1987): hub spun up to 6 rad/s in 15 s")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
