"""Estimate: Moreau's free-body step driven by the body stage, against ``moreau`` as it is.

The Exudyn free-flight scene (:mod:`validation.cases.ffr_free_flight`, 10 modes, plan
off) integrated by :class:`FreeMoreauStep`: Moreau–Jean's θ-method without contacts or
constraints (:mod:`mbs.integrators.moreau`, steps 1, 2, 6, 7),

    q_θ = q_k ⊕ θΔt u_k,   M̂ = M + θΔt D + θ²Δt² K at (t_k + θΔt, q_θ),
    u_{k+1} = u_k + M̂⁻¹ h Δt,   q_{k+1} = q_θ ⊕ Δt (θ u_{k+1} + (1 − 2θ) u_k),

with M, h, K, D, ⊕ from :class:`mbs.body_stage.BodyStage` into preallocated arrays and
M̂'s Cholesky factor from :mod:`mbs.linalg_kernels`. It runs through the same driver and
output sampling as the ``moreau`` integrator, side by side, and reports both µs per step
(median CPU of ``repeats`` runs) and the largest relative difference of the node-A
trajectories. An estimate of what the Moreau integrator's body stage can reach, not
that integrator.

Run::

    python3 -m validation.bench.moreau_free_step [--quick] [--out out/bench]
"""

from __future__ import annotations

import numpy as np

from mbs.body_stage import BodyStage
from mbs.integrators._kernels import moreau_iteration_matrix
from mbs.integrators.driver import Integrator, StepFailure
from mbs.linalg_kernels import cho_solve_vector, cholesky_into
from validation.bench.common import bench_main, machine
from validation.cases import _wobble as wb
from validation.cases import ffr_free_flight as ff

STEPS = (1e-3, 1e-4)        # [s]
FULL = {"steps": STEPS, "repeats": 5}
QUICK = {"steps": STEPS[:1], "repeats": 3}


class FreeMoreauStep(Integrator):
    """Moreau–Jean's θ-method for a system without contacts or constraints, on the body
    stage (module docstring). Option ``theta`` (0.5..1, default 0.5)."""

    name = "moreau-free-step"

    def __init__(self, system, theta=0.5):
        super().__init__(system)
        if system.n_c or system.contacts:
            raise ValueError("FreeMoreauStep: no constraints or contacts")
        self.theta = float(theta)

    def options(self):
        return {"theta": self.theta}

    def start(self, t, q, u):
        sys = self.system
        self.t, self.q, self.u = t, q.copy(), u.copy()
        self.bodies = BodyStage.of_system(sys)
        nu = sys.nu
        self.q_m = np.zeros(sys.nq)
        self.u_prev, self.du, self.h, self.rhs = (np.zeros(nu) for _ in range(4))
        self.M, self.K, self.D, self.L = (np.zeros((nu, nu)) for _ in range(4))

    def step(self, dt):
        b, th = self.bodies, self.theta
        t_m = self.t + th * dt
        np.multiply(self.u, th * dt, out=self.du)
        b.increment(self.q, self.du, self.q_m)
        b.normalize(self.q_m)
        b.mass_and_h(t_m, self.q_m, self.u, self.M, self.h)
        b.tangents(t_m, self.q_m, self.u, self.K, self.D)
        moreau_iteration_matrix(self.M, self.D, th * dt, self.K, th * th * dt * dt, self.L)
        if cholesky_into(self.L, self.L):
            raise StepFailure("M + θΔt D + θ²Δt² K is not positive definite")
        np.multiply(self.h, dt, out=self.rhs)
        cho_solve_vector(self.L, self.rhs, self.rhs)
        self.u, self.u_prev = self.u_prev, self.u
        np.add(self.u_prev, self.rhs, out=self.u)                  # u_{k+1} = u_free
        np.multiply(self.u, th * dt, out=self.du)
        if th != 0.5:
            self.du += (1.0 - 2.0 * th) * dt * self.u_prev
        b.increment(self.q_m, self.du, self.q)
        b.normalize(self.q)
        self.t += dt


def benchmark(steps, repeats, log=print) -> dict:
    """Both integrators at each step size: µs/step (median CPU) and the trajectory difference."""
    mesh, data = wb.beam(n_modes=10)
    probe, weights = ff.node_a(mesh), ff.face_weights(mesh)
    doc = {"benchmark": "moreau_free_step", "machine": machine(), "repeats": repeats, "rows": []}
    for dt in steps:
        runs = {"moreau": "moreau", "body stage (estimate)": FreeMoreauStep}
        out = {}
        for label, integrator in runs.items():
            ff.simulate(data, weights, 10, dt, integrator, probe, theta=0.5)      # compiles, untimed
            cpus, r = [], None
            for _ in range(repeats):
                _, r, _, cpu = ff.simulate(data, weights, 10, dt, integrator, probe, theta=0.5)
                cpus.append(cpu)
            out[label] = (1e6 * float(np.median(cpus)) / round(ff.T_END / dt), r)
        r_ref = out["moreau"][1]
        diff = float(np.abs(out["body stage (estimate)"][1] - r_ref).max() / np.abs(r_ref).max())
        for label, (us, _) in out.items():
            doc["rows"].append({"integrator": label, "dt": dt, "us_per_step": us,
                                "trajectory_difference": 0.0 if label == "moreau" else diff})
        log(f"h = {dt:g}: done")
    doc["table"] = "\n".join(
        ["| integrator | h [s] | µs/step | max rel. difference of r_A from moreau |", "|---|---|---|---|"]
        + [f"| {r['integrator']} | {r['dt']:g} | {r['us_per_step']:.1f} | {r['trajectory_difference']:.1e} |"
           for r in doc["rows"]])
    return doc


def run(quick: bool) -> dict:
    return benchmark(**(QUICK if quick else FULL))


def main(argv=None):
    return bench_main(argv, "moreau_free_step", run, __doc__, "h = 1e-3 s only, 3 repeats")


if __name__ == "__main__":
    main()
