"""
A parameter sweep on a Dask cluster
===================================

``ffrmbs sweep`` (or :func:`ffrmbs_app.sweep` from Python) runs one scene file over a grid of
overrides, each run a task on a Dask cluster: a local one, a running scheduler, or an
HPC queue's through dask-jobqueue (``SLURMCluster`` passed as ``Client(cluster)``). Each
run writes its own result file; the table (``sweep.csv``, ``.json``, ``.md``) has one row
per run with its overrides, status, the last sample of each output, steps and cost.

Here the bouncing ball of ``examples/scenes/bouncing_ball.toml`` runs with three
restitution coefficients, each to the top of its first rebound (``zip=True``: the value
lists side by side, not their product).

Check: each run ends at the analytic apex, −h + e² h at t₁ (1 + e).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import ffrmbs_app

try:
    here = Path(__file__).resolve().parent
except NameError:                  # sphinx-gallery runs the script in its own directory
    here = Path.cwd()
scene = here.parent / "scenes" / "bouncing_ball.toml"                                # examples/scenes/
g, h = 9.81, 0.1
t1 = np.sqrt(2 * h / g)
restitution = [0.3, 0.5, 0.8]
apex_times = [round(float(t1 * (1 + e)), 4) for e in restitution]      # Python floats: TOML values



def main():
    """The sweep on a local cluster of two single-threaded worker processes (``workers=2``;
    ``client=Client(cluster)`` runs it on your own cluster); the table."""
    return ffrmbs_app.sweep(scene, {"contact.floor.e": restitution, "scene.t_end": apex_times},
                            Path(tempfile.mkdtemp()) / "sweep", workers=2, zip=True, progress=print)


# %%
# Run it
# ------
# The worker processes import the script that starts them, so a script runs the sweep
# under ``if __name__ == "__main__":`` (a notebook needs no guard).
if __name__ == "__main__":
    table = main()
    for row in table:
        print(row["run"], row["status"], row["steps"], f"z = {row['final:z']:.5f} m")

# %%
# Against the analytic apex
# -------------------------
if __name__ == "__main__":
    expected = [-h + e ** 2 * h for e in restitution]
    for row, z in zip(table, expected):
        assert row["status"] == "complete"
        assert abs(row["final:z"] - z) < 3e-4            # the closing step's offset: v Δt = 1.4e-4 m

    fig, ax = plt.subplots(figsize=(5, 3.2))
    ax.plot(restitution, [row["final:z"] + h for row in table], "o", label="ffrmbs sweep")
    e = np.linspace(0.0, 1.0, 50)
    ax.plot(e, e ** 2 * h, "--", label="e² h")
    ax.set_xlabel("restitution e")
    ax.set_ylabel("rebound height [m]")
    ax.legend()
    fig.tight_layout()
