"""The main job: the embedded default scene — the point mass dropped on the clamped
flexible beam (thesis Sec. 5.2, setup A; :mod:`ffrmbs_app.scenes.point_mass_beam`) on
its tet10 mesh of 12.5 mm (:data:`~ffrmbs_app.scenes.point_mass_beam.TET10`, 40 stored
modes) — run by ``ffrmbs run`` with no scene file, as a job of :mod:`ffrmbs_app.job`.

Moreau time-stepping (θ = 0.5: no numerical damping of the elastic forces), 1001
output samples of the point mass's y position ``y`` [m] and velocity ``vy`` [m/s], node
19's displacement ``node19`` [m], the kinetic and potential energy and the contact
``impact`` — the names of ``examples/scenes/point_mass_beam.toml``; a warm-up run of
12.5 ms at Δt = 1e-4 s (past the first contact) compiles the numba kernels first.
Written to ``out``: ``point_mass_beam.h5`` (the result file, :mod:`mbs.results.result_file`),
``point_mass_beam.png`` and ``point_mass_beam-paraview/``. On a first run the kernels are
compiled in a second process while the beam is preprocessed (:mod:`ffrmbs_app.precompile`).
The contour carries the residual flexibility of the modes left out (:mod:`contours.residual`;
with the impact law). The job's accuracy check runs the scene at Δt/2 (time step), with twice the
modes (modal truncation) and on the 25 mm tet10 mesh (mesh: the difference to a mesh
twice as coarse, which overstates the error of this one); the validation cases
``contact_point_mass_beam`` (modes against all of them) and ``contact_full_fe`` (against a
full-FE run of each mesh) measure these parts independently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ffrmbs.errors import ModelError

LAWS, CONTOURS = ("impact", "penalty"), ("2s", "band")


@dataclass
class JobSettings:
    setup: str = "A"
    modes: int = 20
    law: str = "impact"           # "impact" (Newton, e) or "penalty" (k = 1e7 N/m)
    e: float = 0.0
    contour: str = "2s"           # "2s" or "band"
    residual_flexibility: bool = True     # the contour carries the dropped modes' static compliance
                                          # (impact law only: a penalty law's spring is its own)
    t_end: float = 0.1            # [s]
    dt: float = 1e-5              # [s]
    theta: float = 0.5            # elastic forces trapezoidal: no numerical damping
    check: bool = True            # a second run at dt/2 for the error estimate
    n_out: int = 1001             # output samples

    def validate(self) -> None:
        """ModelError, one line naming every setting out of range: setup "A" or "B", modes
        >= 1 (at most the beam's modes, checked once it is built), law, contour, 0 <= e <=
        1, t_end [s] and dt [s] finite and > 0, dt < t_end, n_out >= 2."""
        from ffrmbs_app.scenes.point_mass_beam import SETUPS

        def count(n, low):
            return isinstance(n, int) and not isinstance(n, bool) and n >= low

        faults = [f"{key} must be one of {', '.join(map(repr, options))}, got {getattr(self, key)!r}"
                  for key, options in (("setup", tuple(SETUPS)), ("law", LAWS), ("contour", CONTOURS))
                  if getattr(self, key) not in options]
        if not count(self.modes, 1):
            faults.append(f"modes (elastic modes of the beam) must be an integer >= 1, got {self.modes!r}")
        if not 0.0 <= self.e <= 1.0:
            faults.append(f"e (coefficient of restitution) must be in [0, 1], got {self.e!r}")
        for key in ("t_end", "dt"):
            if not (math.isfinite(getattr(self, key)) and getattr(self, key) > 0):
                faults.append(f"{key} must be a finite time > 0 [s], got {getattr(self, key)!r}")
        if not faults and not self.dt < self.t_end:
            faults.append(f"dt must be smaller than t_end, got dt = {self.dt!r} s, t_end = {self.t_end!r} s")
        if not count(self.n_out, 2):
            faults.append(f"n_out (output samples) must be an integer >= 2, got {self.n_out!r}")
        if faults:
            raise ModelError("default scene: " + "; ".join(faults))


def default_scene(settings: JobSettings, data=None, beam=None):
    """The default scene as a :class:`~ffrmbs_app.scene.Scene` on ``beam`` (a
    :class:`~ffrmbs_app.scenes.point_mass_beam.Beam`, default the main job's TET10);
    ``data``: its body data, preprocessed and cached on first use when None."""
    from ffrmbs_app.scene import Scene
    from ffrmbs_app.scenes import point_mass_beam as pmb

    beam = pmb.TET10 if beam is None else beam
    data = beam.default_beam_data() if data is None else data
    if settings.modes > data.n_modes:
        raise ModelError(f"default scene: modes must be in 1..{data.n_modes} (the beam's modes), "
                         f"got {settings.modes}")
    residual = settings.residual_flexibility and settings.law == "impact"
    built = pmb.build(settings.setup, settings.modes, settings.law, settings.e, contour=settings.contour, data=data,
                      residual_flexibility=residual)
    description = (
        f"thesis Sec. 5.2 setup {settings.setup}: point mass {pmb.MASS} kg at "
        f"({', '.join(f'{1e3 * x:g}' for x in pmb.SETUPS[settings.setup])}) mm, v = {pmb.VELOCITY} m/s, on the "
        f"{1e3 * pmb.LENGTH:g} x {1e3 * pmb.HEIGHT:g} x {1e3 * pmb.WIDTH:g} mm beam clamped at x = 0 "
        f"(E = {pmb.YOUNG / 1e6:g} MPa, ρ = {pmb.DENSITY:g} kg/m³, ν = {pmb.POISSON}), "
        f"{'tet10' if beam.order == 2 else 'tet4'} of {1e3 * beam.element_size:g} mm; {settings.modes} of "
        f"{data.n_modes} modes" + (" with residual flexibility" if residual else "")
        + f", {settings.contour} contour, law {settings.law}"
        + (f" (e = {settings.e})" if settings.law == "impact" else f" (k = {pmb.PENALTY_K:g} N/m)")
        + f"; Moreau, dt = {settings.dt:g} s, θ = {settings.theta}, {settings.t_end:g} s")
    variants = {}
    more = min(2 * settings.modes, data.n_modes)
    if beam == pmb.TET10 and more > settings.modes:
        variants["modal truncation"] = (f"{more} modes", lambda: default_scene(replace(settings, modes=more), data))
    if beam == pmb.TET10:
        coarse = pmb.TET10_COARSE
        variants["mesh"] = (f"the {1e3 * coarse.element_size:g} mm mesh",
                            lambda: default_scene(settings, coarse.default_beam_data(), coarse))
    return Scene(built.system, settings.t_end, settings.dt, "moreau", {"theta": settings.theta},
                 n_out=settings.n_out, outputs=built.outputs(), energies=True, name="point_mass_beam",
                 description=description, warmup=(0.0125, 1e-4), units=dict(pmb.OUTPUT_UNITS),
                 labels=dict(pmb.OUTPUT_LABELS), variants=variants)


def run_job(settings: JobSettings, out, log=print, resume=False, checkpoint_every=60.0, export=True,
            no_limits=False, precompile=True) -> dict:
    """Run the default scene as a job (:func:`ffrmbs_app.job.run_scene`); return the summary.
    The settings are checked first (:meth:`JobSettings.validate`). When the beam is yet to
    be preprocessed (a first run) and ``precompile``, a second process compiles the
    scene's kernels meanwhile (:mod:`ffrmbs_app.precompile`)."""
    from ffrmbs_app import precompile as pre
    from ffrmbs_app.job import run_scene
    from ffrmbs_app.scenes import point_mass_beam as pmb
    from ffrmbs_app.scenes.cache import cached_body_path

    settings.validate()
    compiler = None
    if precompile and not cached_body_path(pmb.TET10.recipe()).exists():
        compiler = pre.start(settings, log)
    try:
        data = pmb.TET10.default_beam_data(log=log)
    except BaseException:
        if compiler is not None:
            compiler.stop()
        raise
    if compiler is not None:
        compiler.wait(log)
    return run_scene(lambda: default_scene(settings, data), out, check=settings.check, resume=resume,
                     checkpoint_every=checkpoint_every, export=export, log=log, no_limits=no_limits)
