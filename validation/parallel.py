"""The validation cases as Dask tasks (``ffrmbs validate --workers N | --scheduler ADDRESS``).

Each case is one task: the worker imports the case's module by name, runs it on one
thread (BLAS and numba pools limited to one) and returns the same outcome the serial run
makes in-process — rows, skipped lines, notes and figures (pickled by Dask's cloudpickle)
and the CPU time measured inside the task. The harness then writes the same report and
results.json as a serial run. Clients: :func:`ffrmbs_app.sweep.dask_client` (the caller's
client, a running scheduler, or a LocalCluster of single-threaded worker processes).
"""

from __future__ import annotations

import importlib


def run_cases(registry, names, quick, say, client=None, scheduler=None, workers=None) -> list:
    """The outcomes of the cases ``names`` of ``registry`` (name -> module), in that order,
    each run as one Dask task; ``say`` receives a line as each case finishes."""
    from distributed import as_completed

    from ffrmbs_app.sweep import dask_client
    from validation.harness import outcome_line

    done = {}
    with dask_client(client, scheduler, workers) as dask:
        futures = {dask.submit(run_case_task, registry[name].__name__, name, quick, pure=False): name
                   for name in names}
        say(f"{len(names)} cases submitted to {len(dask.scheduler_info().get('workers', {}))} Dask workers")
        for future in as_completed(futures):
            outcome = future.result()
            done[outcome.name] = outcome
            say(f"[{len(done)}/{len(names)}] {outcome_line(outcome)}")
    return [done[name] for name in names]


def run_case_task(module_name, name, quick):
    """One case in a worker: its module imported by name and run on one thread."""
    from threadpoolctl import threadpool_limits

    from validation.harness import run_case

    module = importlib.import_module(module_name)
    with threadpool_limits(1):
        return run_case({name: module}, name, quick)
