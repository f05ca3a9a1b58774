"""ffrmbs: flexible multibody dynamics with sliding contacts — the bottom layer.

This package holds only what every other package shares: the version, the exception
hierarchy (:mod:`ffrmbs.errors`) and the registry of kinds by name
(:mod:`ffrmbs.registry`). It imports nothing of ours at import time; :func:`sweep`
imports the application's sweep (:mod:`ffrmbs_app.sweep`) when called. The library lives in
``preprocess``, ``contours``, ``contact`` and ``mbs``; the application (command line,
jobs, scene files, built-in scenes, export, plots) in ``ffrmbs_app``; the validation
cases, benchmarks and stability suite in ``validation``.
"""

__version__ = "0.1.0"


def sweep(scene, grid, out, client=None, **options):
    """Run a parameter sweep of the TOML scene file ``scene`` on a Dask cluster: one run
    per set of overrides of ``grid`` ({KEY: [values]}, e.g. {"scene.dt": [1e-5, 5e-6],
    "body.beam.modes": [10, 20]}), each writing ``out/runs/<run>.h5``; returns the table
    (a list of dicts, or a pandas DataFrame with ``as_frame=True``) also written as
    ``out/sweep.csv``, ``.json`` and ``.md``. ``client``: the caller's
    ``distributed.Client`` (e.g. in a notebook, or on a dask-jobqueue cluster); without
    one a local cluster is made and closed. The options and the columns:
    :func:`ffrmbs_app.sweep.sweep`.

    This bottom layer imports the application only when called (the one such import)."""
    from ffrmbs_app.sweep import sweep as run_sweep

    return run_sweep(scene, grid, out, client=client, **options)
