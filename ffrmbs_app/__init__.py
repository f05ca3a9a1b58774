"""The ffrmbs application: the ``ffrmbs`` command line (:mod:`ffrmbs_app.cli`), jobs
(:mod:`ffrmbs_app.job`), scene files (:mod:`ffrmbs_app.scene_file`), the built-in scenes
and their body cache (:mod:`ffrmbs_app.scenes`), export, plots and progress bars.

It uses the library (``preprocess``, ``contours``, ``contact``, ``mbs``) and nothing
imports it but itself, ``validation`` and the tests.
"""
