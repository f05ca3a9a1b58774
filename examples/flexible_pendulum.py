"""A flexible steel beam swinging on a revolute joint under gravity: a model script.

The 0.1 × 0.1 × 1 m beam is preprocessed with free-free modes, written to body files and
read back as a FlexibleBodyFFR; a revolute joint about the inertial x axis holds the FE
node at the corner (0, 0, 0) of the z = 0 face, which deforms with the beam (a node frame,
``beam.node(j)``). Released with its axis horizontal (gravity along −y), it swings down
and bends by micrometres at the tip, as beam theory predicts for a pinned beam under its
weight less the inertia of the swing (the estimate is in tests/e2e/test_examples.py).
Run:  python3 examples/flexible_pendulum.py
"""

import sys
import tempfile

import numpy as np

from mbs import FlexibleBodyFFR, Joint, System
from preprocess import Material, box, build_body, write_body


def main(t_end=0.5, dt=1e-3, modes=6, out=sys.stdout):
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


if __name__ == "__main__":
    main()
