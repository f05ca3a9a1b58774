"""``python3 -m validation.bench``: every benchmark in one process, the same as ``ffrmbs bench``.

Usage::

    python3 -m validation.bench [--out out/bench] [--quick] [--only NAME[,NAME]]
    ffrmbs bench [--out out/bench] [--quick] [--only NAME[,NAME]]

Benchmarks (:data:`validation.bench.runner.BENCHES`): point_mass_beam (mode and node
sweeps of the point mass on the beam), exudyn_free_flight, akantu_case_study,
planned_vs_unplanned, ffr_evaluation, contour_evaluation. ``--quick``: coarse settings;
``--only``: names, comma-separated or repeated; ``--out``: default out/bench. Prints each
table with its target verdicts; writes ``DIR/<name>.json`` per benchmark and
``DIR/summary.json``; exits with status 2 if a benchmark failed.
"""

import sys

from ffrmbs_app.cli import main

sys.exit(main(["bench", *sys.argv[1:]]))
