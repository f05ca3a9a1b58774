"""Result of a simulation: states and requested outputs sampled at the output times."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Result:
    """Sampled results of ``System.simulate``.

    t (n,) [s]; q (n, nq); u (n, nu); outputs {name: (n, ...)}; energy {"kinetic",
    "potential"} (n,) [J] when requested; stats: steps, Newton iterations, CPU and wall
    seconds of the integration, integrator name and options; trace: per-step records
    {name: (steps,)} of integrators asked for them (Moreau's ``trace=True``), else {};
    plan: the printed scene plan of a planned run (:mod:`mbs.run.plan`), else "";
    contacts: {contact name: {"active" (n,) int8, "gap" (n,) [m], "point" (n, 3) [m],
    "normal" (n, 3), "deflection" (n,) [m], "force" (n, 3) [N]}} when asked for
    (``simulate(contacts=True)``; what each is: :mod:`mbs.results.contact_record`): a closed
    contact at the last step's midpoint, an open one's geometry at the sample time, the
    force on its first contour's body.
    """

    t: np.ndarray
    q: np.ndarray
    u: np.ndarray
    outputs: dict = field(default_factory=dict)
    energy: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)
    trace: dict = field(default_factory=dict)
    plan: str = ""
    contacts: dict = field(default_factory=dict)

    def __getitem__(self, name):
        return self.outputs[name]

    def truncated(self, n: int) -> "Result":
        """The first ``n`` samples (what a diverging run computed before it stopped)."""
        return Result(self.t[:n], self.q[:n], self.u[:n],
                      {k: v[:n] for k, v in self.outputs.items()},
                      {k: v[:n] for k, v in self.energy.items()}, dict(self.stats), dict(self.trace), self.plan,
                      {c: {k: v[:n] for k, v in rec.items()} for c, rec in self.contacts.items()})

    def total_energy(self) -> np.ndarray:
        return self.energy["kinetic"] + self.energy["potential"]

    def energy_drift(self) -> float:
        """max |E(t) − E(0)| / max(|E(0)|, max kinetic energy): relative drift of the total energy."""
        E = self.total_energy()
        scale = max(abs(E[0]), np.abs(self.energy["kinetic"]).max(), 1e-300)
        return float(np.abs(E - E[0]).max() / scale)
