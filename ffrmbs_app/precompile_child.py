"""The second process of :mod:`ffrmbs_app.precompile`, run as ``__main__`` with SETTINGS
(the :class:`~ffrmbs_app.main_job.JobSettings` as JSON;
:func:`~ffrmbs_app.precompile.child_command`): it runs the warm-up of the default scene on the 25 mm mesh, which compiles every kernel
it calls into numba's disk cache.
"""

from __future__ import annotations

import json
import sys

from ffrmbs_app.job import warm_up
from ffrmbs_app.main_job import JobSettings, default_scene
from ffrmbs_app.scenes import point_mass_beam as pmb


def compile_kernels(settings: JobSettings) -> None:
    """Run the warm-up of the default scene with ``settings`` on the 25 mm mesh
    (:data:`~ffrmbs_app.scenes.point_mass_beam.TET10_COARSE`): every kernel it calls is
    compiled into numba's disk cache."""
    coarse = pmb.TET10_COARSE
    warm_up(default_scene(settings, coarse.default_beam_data(), coarse))


if __name__ == "__main__":
    compile_kernels(JobSettings(**json.loads(sys.argv[1])))
