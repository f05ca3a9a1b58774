"""A scene: one simulation job — a System with its initial state set, how to integrate it
and what to record — as built by the default scene, a TOML scene file
(:mod:`ffrmbs_app.scene_file`) or a Python model script (:mod:`ffrmbs_app.scene_loader`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ffrmbs.errors import ModelError, quote

NAME_CHARS, NAME_MAX = "A-Za-z0-9._-", 100
_NAME = re.compile(rf"[{NAME_CHARS}]{{1,{NAME_MAX}}}")


def name_fault(name) -> str | None:
    """Why ``name`` is not a scene name, or None. A scene name is a plain file stem (the
    result file, plot, ParaView directory and checkpoint are named after it inside the
    output directory): 1 to NAME_MAX characters of [A-Za-z0-9._-], not starting with '.'."""
    if not isinstance(name, str) or not _NAME.fullmatch(name) or name.startswith("."):
        return (f"the scene name {quote(name, 40)} is not a plain file stem: use 1 to {NAME_MAX} of the "
                f"characters {NAME_CHARS}, not starting with '.'")
    return None


MOREAU = ("moreau", "moreau-adaptive")      # the integrators keeping a per-step trace


@dataclass
class Scene:
    """A simulation job.

    system: the :class:`mbs.System`, initial state set on its bodies; t_end, dt [s]: end
    time and (largest) step; integrator: a name accepted by ``System.simulate``
    ("moreau", "moreau-adaptive", "generalized-alpha", "rk4"); options: integrator
    options (e.g. theta, tol, penetration_bound [m]); n_out: output samples, equally
    spaced over [0, t_end]; outputs: {name: Frame or callable (t, q, u) -> array}, the
    quantities recorded at each sample; energies: record kinetic and potential energy
    [J]; plan, tolerance [m]: the scene planner (:mod:`mbs.run.plan`); name: a plain file
    stem (:func:`name_fault`) naming the result file and its companions; inputs: {label: path} of the files the
    scene was built from (the result file records their SHA-256); description: one line
    for logs; warmup: (t_end, dt) [s] of a short run made first so that the numba kernels
    are compiled (or loaded from numba's cache) outside the timed run, or None; units:
    {output name: unit} written with the outputs and on plot axes (:meth:`output_units`);
    labels: {output name: what it is, e.g. "beam node 19 displacement"}, written with the
    outputs and titling their plot panels;
    variants: {label: (what, make)} — scenes that differ in one modelling choice (e.g.
    "modal truncation": (f"{2n} modes", a maker of the scene with twice the modes)),
    each run once more by the job's accuracy check to estimate that part of the error;
    overrides: the ``KEY=VALUE`` texts set in the scene file (``--set``), recorded in the
    result file.
    """

    system: object
    t_end: float
    dt: float
    integrator: str = "moreau"
    options: dict = field(default_factory=dict)
    n_out: int = 101
    outputs: dict = field(default_factory=dict)
    energies: bool = True
    plan: bool = True
    tolerance: float | None = None
    name: str = "scene"
    inputs: dict = field(default_factory=dict)
    description: str = ""
    warmup: tuple | None = None
    units: dict = field(default_factory=dict)
    labels: dict = field(default_factory=dict)
    variants: dict = field(default_factory=dict)
    overrides: tuple = ()

    def __post_init__(self):
        fault = name_fault(self.name)
        if fault:
            raise ModelError(fault)
        if not (0 < self.t_end < np.inf and 0 < self.dt < np.inf):
            raise ModelError(f"scene {self.name!r}: need finite t_end > 0 and dt > 0, got {self.t_end}, {self.dt}")
        if int(self.n_out) < 2:
            raise ModelError(f"scene {self.name!r}: need at least 2 output samples, got {self.n_out}")
        self.n_out = int(self.n_out)

    def keeps_trace(self) -> bool:
        """Whether the run keeps the per-step trace: a Moreau integrator (MOREAU) does
        unless ``options`` say ``trace=False``; the others keep none."""
        return self.integrator in MOREAU and bool(self.options.get("trace", True))

    def output_units(self) -> dict:
        """{output name: unit}: the unit given in ``units``, else "m" for a Frame output
        (its position), else "SI"."""
        from mbs import Frame

        return {name: self.units.get(name) or ("m" if isinstance(spec, Frame) else "SI")
                for name, spec in self.outputs.items()}

    def t_out(self) -> np.ndarray:
        """The output times [s], (n_out,)."""
        return np.linspace(0.0, self.t_end, self.n_out)
