"""
A flexible pendulum: a model script
===================================

A 0.1 × 0.1 × 1 m steel beam with free-free modes swings on a revolute joint under
gravity. The joint holds the FE node at the corner (0, 0, 0) of the face z = 0 — a node
frame (``beam.node(j)``), which deforms with the beam; a joint at ``beam.origin`` would
hold the body frame (the mean axes), not material. Released with its axis horizontal
(gravity along −y), the beam swings down and bends by micrometres.

Checks: the energy of this conservative system is kept (generalized-α with ρ∞ = 1), and
the largest elastic tip displacement is within a factor 3 of twice the static deflection
of Euler–Bernoulli theory for a pinned beam under its weight less the inertia of the
swing, q₀ L⁴/(560 EI) (the derivation is in ``tests/e2e/test_examples.py``).
"""

import sys
import tempfile

import numpy as np

from mbs import FlexibleBodyFFR, Joint, System
from preprocess import Material, box, build_body, write_body


def main(t_end=0.5, dt=1e-3, modes=6, out=sys.stdout):
    """Build and run the pendulum; returns (system, result) with the outputs ``tip`` [m]
    (position) and ``tip_elastic`` [m] (elastic displacement of the tip node)."""
    steel = Material(density=7850.0, young=210e9, poisson=0.3)
    with tempfile.TemporaryDirectory() as tmp:
        write_body(tmp, build_body(box(0.1, 0.1, 1.0, mesh_size=0.05), steel, n_modes=modes))
        beam = FlexibleBodyFFR.from_file(f"{tmp}/body.h5", modes=modes, name="beam")

    system = System(gravity=(0.0, -9.81, 0.0))
    system.add(beam)
    u0 = beam.data.u0
    corner = int(np.argmin(np.linalg.norm(u0 - u0.min(axis=0), axis=1)))    # the node at (0, 0, 0)
    pivot = beam.node(corner, name="pivot")
    system.add(Joint.revolute(system.ground, pivot, axis=(1.0, 0.0, 0.0)))
    tip = beam.node(int(np.argmax(beam.data.u0[:, 2])), name="tip")

    result = system.simulate(t_end=t_end, dt=dt, integrator="generalized-alpha", rho_inf=1.0,
                             outputs={"tip": tip,
                                      "tip_elastic": lambda t, q, u: tip.elastic_displacement(q[beam.q_slice])},
                             energies=True)
    print(f"{beam.data.n_nodes} nodes, {beam.n_modes} modes, {result.stats['steps']} steps "
          f"in {result.stats['cpu_s']:.2f} s CPU", file=out)
    print(f"tip at t = {t_end} s: {result['tip'][-1]} m; largest elastic tip displacement "
          f"{np.linalg.norm(result['tip_elastic'], axis=1).max():.3e} m", file=out)
    print(f"relative energy drift {result.energy_drift():.2e} (a conservative system)", file=out)
    return system, result


# %%
# Run it and compare with beam theory
# -----------------------------------
if __name__ == "__main__":
    import matplotlib.pyplot as plt

    system, result = main(t_end=0.2)
    rho, young, g, side, length = 7850.0, 210e9, 9.81, 0.1, 1.0
    estimate = 2 * rho * side ** 2 * g * length ** 4 / (560 * young * side ** 4 / 12)
    largest = np.linalg.norm(result["tip_elastic"], axis=1).max()
    print(f"beam theory: about {estimate:.2e} m")
    assert result.energy_drift() < 1e-5
    assert estimate / 3 < largest < 3 * estimate

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.2))
    ax1.plot(result["tip"][:, 2], result["tip"][:, 1])
    ax1.set_xlabel("tip z [m]")
    ax1.set_ylabel("tip y [m]")
    ax1.set_aspect("equal")
    ax2.plot(result.t, 1e6 * np.linalg.norm(result["tip_elastic"], axis=1), label="FFR")
    ax2.axhline(1e6 * estimate, color="0.5", linestyle="--", label="2 × static, beam theory")
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("|elastic tip displacement| [µm]")
    ax2.legend()
    fig.tight_layout()
