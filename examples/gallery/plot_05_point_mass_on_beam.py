"""
A point mass dropped on a flexible beam: contact
================================================

The thesis's benchmark (Sec. 5.2, setup A): a 0.5 kg point mass falls at 0.2 m/s onto
the top face of a clamped 250 × 50 × 50 mm beam (E = 50 MPa, ρ = 920 kg/m³). A contact
joins a point-side contour (the mass) and a surface-side contour (a C² NURBS surface
through the nodes of the face ``y1``) with Newton's impact law; Moreau time-stepping
integrates it. ``ffrmbs_app/scenes/point_mass_beam.py`` is the full scene of
``ffrmbs run``.

Checks: the first contact closes when free flight brings the mass to the face, at
t = 2 mm / 0.2 m/s = 0.01 s; the momentum the mass loses equals the impulse the contact
transmits (the recorded contact force summed over the steps); and with e = 0 the total
energy never grows.
"""

import matplotlib.pyplot as plt
import numpy as np

from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact
from contours import Contour2sNeutralFFR, PointContour
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from preprocess import Material, box, build_body

# %%
# The scene
# ---------
# A structured tet4 mesh, so that the top face y1 is a grid of nodes the contour
# interpolates (thesis eq. 3.24); 20 clamped modes; the body frame fixed in space.
data = build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(10, 4, 4)), Material(920.0, 5e7, 0.3),
                  n_modes=20, clamp="x0")
system = System()
beam = system.add(FlexibleBodyFFR(data, modes=20, frame=PrescribedFrameMotion.fixed()))
mass = system.add(PointMass(0.5, position=(0.235, 0.052, 0.025), velocity=(0, -0.2, 0)))
kin = ContactKinematicsPointContour2s(PointContour(mass.point), Contour2sNeutralFFR(beam, "y1"))
system.add(Contact(kin, UnilateralNewtonImpact(e=0.0), name="impact"))

# %%
# Run 0.03 s at Δt = 1e-5 s, sampling every step
# ----------------------------------------------
t_end, dt = 0.03, 1e-5
res = system.simulate(t_end, dt, integrator="moreau", theta=0.5, trace=True, energies=True, contacts=True,
                      t_out=np.linspace(0.0, t_end, round(t_end / dt) + 1),
                      outputs={"y": lambda t, q, u: q[mass.q_slice][1], "vy": lambda t, q, u: u[mass.u_slice][1]})
print(res.plan)
print(f"closed contact-steps {res.trace['closed'].sum()}, largest penetration {res.stats['max_penetration']:.2e} m, "
      f"{res.stats['cpu_s']:.2f} s CPU")

# %%
# Against free flight, momentum and energy
# ----------------------------------------
first = res.trace["t"][np.flatnonzero(res.trace["closed"])[0]]
impulse = res.contacts["impact"]["force"][1:, 1].sum() * dt           # [N s], y component
momentum = 0.5 * (res["vy"][-1] - res["vy"][0])
energy = res.total_energy()
print(f"first closed step at t = {first:.5f} s (free flight: 0.01 s)")
print(f"contact impulse {impulse:.6f} N s, momentum change of the mass {momentum:.6f} N s")
print(f"total energy from {energy[0]:.6f} J to {energy[-1]:.6f} J, largest {energy.max():.6f} J")
assert abs(first - 0.01) <= 2 * dt
assert abs(impulse - momentum) < 1e-6 * 0.5 * 0.2
assert energy.max() <= energy[0] * (1 + 1e-9)

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.2))
ax1.plot(res.t, 1e3 * res["y"])
ax1.axhline(50.0, color="0.5", linestyle="--", label="top face at rest")
ax1.set_xlabel("t [s]")
ax1.set_ylabel("y of the mass [mm]")
ax1.legend()
ax2.plot(res.t, res["vy"])
ax2.set_xlabel("t [s]")
ax2.set_ylabel("v_y of the mass [m/s]")
fig.tight_layout()
