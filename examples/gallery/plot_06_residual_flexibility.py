"""
Residual flexibility: the static compliance of the modes left out
=================================================================

A reduced body keeps a few global modes, but an impact loads one point: the local
compliance under it lives in the modes left out. A contour built with
``residual_flexibility=True`` (a scene file's ``residual_flexibility = true``) gives every
contact on it the exact static compliance of all the modes its body leaves out, as a
massless spring in series with the contact, with no extra coordinates.

The sharpest test keeps **no** modes at all: the contour then carries the beam's whole
static compliance c, and a mass m dropped at speed v₀ meets a spring of stiffness 1/c —
a half sine of duration π √(m c), deepest deflection v₀ √(m c), rebound speed v₀.

Check: c is computed here independently, by a direct sparse solve of the full FE
stiffness K_ff u = f at the node under the mass, and the run's contact duration, depth
and rebound speed are compared with the half sine.
"""

import matplotlib.pyplot as plt
import numpy as np
import scipy.sparse.linalg as sla

from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact
from contours import Contour2sNeutralFFR, PointContour
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from preprocess import Material, box, build_body

# %%
# The beam of the thesis (Sec. 5.2) with no modes kept
# ----------------------------------------------------
top, v0, m = 0.05, 0.2, 0.5                        # top face y [m], impact speed [m/s], mass [kg]
data = build_body(box(0.25, top, 0.05, None, order=1, divisions=(10, 4, 4)), Material(920.0, 5e7, 0.3),
                  n_modes=5, clamp="x0")
system = System()
beam = system.add(FlexibleBodyFFR(data, modes=0, frame=PrescribedFrameMotion.fixed()))
mass = system.add(PointMass(m, position=(0.2, top + 1e-5, 0.025), velocity=(0, -v0, 0)))
face = Contour2sNeutralFFR(beam, "y1", residual_flexibility=True)
system.add(Contact(ContactKinematicsPointContour2s(PointContour(mass.point), face), UnilateralNewtonImpact(0.0)))

# %%
# The full FE model's compliance at the node under the mass
# ---------------------------------------------------------
# The contour interpolates the face's nodes, so at a node a point force loads that node
# alone: c = (K_ff⁻¹)_yy of that node.
node = data.node_at((0.2, top, 0.025))
K = data.stiffness.tocsc()
free = np.ones(K.shape[0], dtype=bool)
free[(3 * data.node_groups["x0"][:, None] + np.arange(3)).ravel()] = False
load = np.zeros(K.shape[0])
load[3 * node + 1] = 1.0
c = sla.spsolve(K[free][:, free], load[free])[np.flatnonzero(free) == 3 * node + 1][0]    # [m/N]
duration, depth = np.pi * np.sqrt(m * c), v0 * np.sqrt(m * c)
print(f"static compliance {c:.4e} m/N: half sine of {duration * 1e3:.3f} ms, {depth * 1e3:.4f} mm deep")

# %%
# The drop
# --------
dt = 1e-5
res = system.simulate(1.3 * duration, dt, integrator="moreau", theta=0.5, trace=True,
                      t_out=np.linspace(0.0, 1.3 * duration, 401),
                      outputs={"y": lambda t, q, u: q[mass.q_slice][1], "vy": lambda t, q, u: u[mass.u_slice][1]})
pressed = res.trace["pressed"] > 0                               # steps that transmitted a force
closed = res.trace["dt"][pressed].sum()
step = res.trace["dt"].max()                  # Δt ≤ 1e-5 s: the steps end on the output times
lowest = top - res["y"].min()
print(f"contact {closed * 1e3:.3f} ms, deepest {lowest * 1e3:.4f} mm, rebound {res['vy'][-1]:.6f} m/s")
assert abs(closed / duration - 1.0) < 3 * step / duration
assert abs(lowest / depth - 1.0) < 2 * v0 * step / depth
assert abs(res["vy"][-1] / v0 - 1.0) < 1e-5

t_hit = 1e-5 / v0
inside = (res.t > t_hit) & (res.t < t_hit + duration)
fig, ax = plt.subplots(figsize=(6, 3.2))
ax.plot(res.t * 1e3, (res["y"] - top) * 1e3, label="ffrmbs, 0 modes + residual flexibility")
ax.plot(res.t[inside] * 1e3, -depth * 1e3 * np.sin((res.t[inside] - t_hit) / np.sqrt(m * c)), "--",
        label="half sine of the full FE compliance")
ax.set_xlabel("t [ms]")
ax.set_ylabel("y of the mass − top face [mm]")
ax.legend()
fig.tight_layout()
