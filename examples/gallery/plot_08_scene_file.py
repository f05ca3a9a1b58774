"""
A scene file: run, result file, plot
====================================

A scene file (TOML) describes bodies, contacts, loads and outputs; ``ffrmbs run`` runs it
as a job that prints a summary (contact intervals, penetration, energy balance, the
outputs' last values, an accuracy estimate from a second run at Δt/2, the cost) and
writes into ``--out`` the result file, a plot and a ParaView series. The keys are listed in
the scene key reference. ``examples/scenes/bouncing_ball.toml`` drops a 1 kg ball 0.1 m
onto a rigid floor with Newton's impact law, e = 0.5.

Checks: the ball hits at t₁ = √(2h/g), bounces at e times the impact speed and rises to
e² h above the floor at t₁ (1 + e); the energy lost is that of the impacts.
"""

import os
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from ffrmbs_app.cli import main as command_line
from mbs.results.result_file import load_result

try:
    here = Path(__file__).resolve().parent
except NameError:                  # sphinx-gallery runs the script in its own directory
    here = Path.cwd()
scene = here.parent / "scenes" / "bouncing_ball.toml"                                # examples/scenes/
out = Path(tempfile.mkdtemp()) / "ball"
os.environ["FFRMBS_PROGRESS"] = "0"          # no progress bars in these pages


def ffrmbs(*args):
    """``ffrmbs ARGS``, run in this process: what the command prints, and its exit status checked."""
    status = command_line([str(a) for a in args])
    assert status in (0, None), f"ffrmbs {' '.join(map(str, args))} exited with {status}"


# %%
# Run it
# ------
ffrmbs("run", scene, "--out", out)
print(sorted(p.name for p in out.iterdir()))

# %%
# Read the result file
# --------------------
# ``OUT/<scene>.h5`` holds every sample (time, states, energies, outputs, contact states,
# the per-step trace), each dataset with its ``units`` attribute.
result, attributes = load_result(out / "bouncing_ball.h5")
print(attributes["status"])
t, z, vz = result.t, np.ravel(result["z"]), np.ravel(result["vz"])

g, h, e = 9.81, 0.1, 0.5
t1 = np.sqrt(2 * h / g)
apex = np.argmax(np.where((t > t1) & (t < t1 * (1 + 2 * e)), z, -np.inf))
print(f"first apex: z = {z[apex]:.5f} m at t = {t[apex]:.4f} s "
      f"(analytic {-h + e ** 2 * h:.5f} m at {t1 * (1 + e):.4f} s)")
assert attributes["status"] == "complete"
assert abs(z[apex] - (-h + e ** 2 * h)) < 3e-4         # the closing step's offset: v Δt = 1.4e-4 m
assert abs(t[apex] - t1 * (1 + e)) < 2e-3              # the output interval 4e-4 s, a flat apex

# %%
# Plot chosen outputs
# -------------------
# ``ffrmbs plot`` draws outputs, ``energy`` or ``contact:NAME`` into ``<stem>-plot.png``;
# here the same data are drawn from the result file.
ffrmbs("plot", out / "bouncing_ball.h5", "z", "energy", "contact:floor")
fig, ax = plt.subplots(figsize=(6, 3.2))
ax.plot(t, z, label="z of the ball")
ax.plot(t1 * (1 + e), -h + e ** 2 * h, "o", label="analytic first apex")
ax.axhline(-h, color="0.5", linestyle="--", label="floor")
ax.set_xlabel("t [s]")
ax.set_ylabel("z [m]")
ax.legend()
fig.tight_layout()
