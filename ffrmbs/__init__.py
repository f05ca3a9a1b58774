"""ffrmbs: flexible multibody dynamics with sliding contacts — the bottom layer.

This package holds only what every other package shares: the version, the exception
hierarchy (:mod:`ffrmbs.errors`), the registry of kinds by name
(:mod:`ffrmbs.registry`) and the cache directories (:mod:`ffrmbs.caches`). It imports nothing of ours. The library lives in
``preprocess``, ``contours``, ``contact`` and ``mbs``; the application (command line,
jobs, scene files, built-in scenes, export, plots, sweeps: :func:`ffrmbs_app.sweep`) in
``ffrmbs_app``; the validation cases, benchmarks and stability suite in ``validation``.
"""

__version__ = "0.1.0"
