"""
From a part to a body
=====================

A flexible body is a preprocessed finite-element model: its nodes, lumped masses, a few
mode shapes and the shape integrals of the floating frame of reference. Here the
report's 1 × 1 × 5 m steel beam (report Sec. 5.1) becomes a body in Python, and a plate
with a hole written as a STEP file becomes one with ``ffrmbs preprocess``.

Checks: the total mass is ρV, and the first bending frequency lies a little below
Euler–Bernoulli theory (shear and rotary inertia lower it, Timoshenko).
"""

# %%
# A body from Python
# ------------------
# ``box`` meshes with gmsh (tet10 by default); ``build_body`` assembles K and the
# lumped masses and computes the clamped modes (shift-invert Lanczos, Φᵀ M Φ = I).
import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ffrmbs_app.cli import main as command_line
from preprocess import Material, box, build_body, read_body, write_body

steel = Material(density=8000.0, young=200e9, poisson=0.0)
mesh = box(1.0, 1.0, 5.0, mesh_size=0.5)
body = build_body(mesh, steel, n_modes=10, clamp="z0")
work = Path(tempfile.mkdtemp())
write_body(work / "beam", body)                  # the thesis's text files and body.h5
print(read_body(work / "beam" / "body.h5").summary())

# %%
# Against beam theory
# -------------------
# The first bending frequency of a clamped Euler–Bernoulli beam is
# ω₁ = 1.8751² √(EI / (ρA L⁴)); the solid's is lower by shear and rotary inertia.
omega = np.sqrt(body.modal_eigenvalues())
length, side = 5.0, 1.0
omega_eb = 1.8751 ** 2 * np.sqrt(200e9 * side ** 4 / 12 / (8000.0 * side ** 2 * length ** 4))
print(f"mass {body.masses.sum():.1f} kg (rho V = {8000.0 * 5.0:.1f} kg)")
print(f"first frequency {omega[0]:.2f} rad/s, Euler-Bernoulli {omega_eb:.2f} rad/s")
assert abs(body.masses.sum() / (8000.0 * 5.0) - 1.0) < 1e-12
assert 0.95 < omega[0] / omega_eb < 1.0

fig, ax = plt.subplots(figsize=(6, 3))
ax.plot(np.arange(1, omega.size + 1), omega / (2 * np.pi), "o")
ax.axhline(omega_eb / (2 * np.pi), color="0.5", linestyle="--", label="Euler–Bernoulli, first mode")
ax.set_xlabel("mode")
ax.set_ylabel("frequency [Hz]")
ax.legend()
fig.tight_layout()

# %%
# A CAD part from the command line
# --------------------------------
# A 200 × 40 × 10 mm aluminium plate with a 12 mm through hole, written as STEP by
# gmsh's OpenCASCADE kernel and preprocessed in SI(mm): lengths in mm, densities in
# t/mm³, moduli in MPa (thesis Table 5.1). ``--group`` names the faces inside a box.
import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
occ = gmsh.model.occ
occ.cut([(3, occ.addBox(0, 0, 0, 200, 40, 10))], [(3, occ.addCylinder(100, 20, -1, 0, 0, 12, 6))])
occ.synchronize()
gmsh.write(str(work / "plate_hole.step"))
gmsh.finalize()

# ``ffrmbs preprocess plate_hole.step --units si-mm ...`` on the command line; here the same
# command line runs in this process.
os.environ["FFRMBS_PROGRESS"] = "0"
status = command_line(["preprocess", str(work / "plate_hole.step"), "--units", "si-mm", "--mesh-size", "8",
                       "--modes", "4", "--clamp", "x0", "--group", "top=-1,-1,9.99,201,41,10.01", "--density",
                       "2.7e-9", "--young", "70000", "--poisson", "0.33", "--out", str(work / "plate")])
assert status in (0, None)

# %%
# The plate's mass against the hand calculation ρ (V_box − π r² t):
plate = read_body(work / "plate" / "body.h5")
by_hand = 2700.0 * (0.2 * 0.04 * 0.01 - np.pi * 0.006 ** 2 * 0.01)
print(f"plate mass {plate.masses.sum():.5f} kg, by hand {by_hand:.5f} kg")
assert abs(plate.masses.sum() / by_hand - 1.0) < 2e-3
