"""The ffrmbs application: the ``ffrmbs`` command line (:mod:`ffrmbs_app.cli`), jobs
(:mod:`ffrmbs_app.job`), scene files (:mod:`ffrmbs_app.scene_file`), the built-in scenes
and their body cache (:mod:`ffrmbs_app.scenes`), parameter sweeps (:func:`sweep`,
:mod:`ffrmbs_app.sweeps`), export, plots and progress bars.

It uses the library (``preprocess``, ``contours``, ``contact``, ``mbs``) and nothing
imports it but itself, ``validation`` and the tests.
"""

__all__ = ["sweep"]


def sweep(scene, grid, out, client=None, **options):
    """Run a parameter sweep of the TOML scene file ``scene`` on a Dask cluster: one run
    per set of overrides of ``grid`` ({KEY: [values]}, e.g. {"scene.dt": [1e-5, 5e-6],
    "body.beam.modes": [10, 20]}), each writing ``out/runs/<run>.h5``; returns the table
    (a list of dicts, or a pandas DataFrame with ``as_frame=True``) also written as
    ``out/sweep.csv``, ``.json`` and ``.md``. ``client``: the caller's
    ``distributed.Client`` (e.g. in a notebook, or on a dask-jobqueue cluster); without
    one a local cluster is made and closed. The options and the columns:
    :func:`ffrmbs_app.sweeps.sweep`.

    :mod:`ffrmbs_app.sweeps` (and with it the library) is imported when this is called,
    so that ``import ffrmbs_app`` — which every module of the application, the command
    line's too, runs first — stays light."""
    from ffrmbs_app.sweeps import sweep as run_sweep

    return run_sweep(scene, grid, out, client=client, **options)
