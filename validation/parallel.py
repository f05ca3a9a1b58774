"""The validation cases as Dask tasks (``ffrmbs validate --workers N | --scheduler ADDRESS``).

Each case is one task: the worker imports the case's module by name, runs it on one
thread (BLAS and numba pools limited to one) and returns the same outcome the serial run
makes in-process — rows, skipped lines, notes and figures (pickled by Dask's cloudpickle)
and the CPU time measured inside the task (:func:`validation.harness.run_case`).
:func:`validation.report.run_validation` then writes the same report and results.json as
a serial run. Clients: :func:`ffrmbs_app.sweeps.dask_client` (the caller's
client, a running scheduler, or a LocalCluster of single-threaded worker processes).

The cases are submitted longest first (LPT scheduling: the long cases start while the
short ones fill the gaps) by the CPU seconds each took in the last run on this machine,
kept in ``case-times.json`` of :func:`ffrmbs_app.scenes.cache.cache_dir` (quick and
full apart); a case never timed counts as the longest.
"""

from __future__ import annotations

import importlib
import json

from ffrmbs_app.scenes.cache import cache_dir
from validation.harness import outcome_line, run_case

TIMES_FILE = "case-times.json"


def run_cases(registry, names, quick, say, client=None, scheduler=None, workers=None) -> list:
    """The outcomes of the cases ``names`` of ``registry`` (name -> module), in that order,
    each run as one Dask task; ``say`` receives a line as each case finishes."""
    from ffrmbs_app.sweeps import dask_client

    done = {}
    times = case_times(quick)
    order = sorted(names, key=lambda name: -times.get(name, float("inf")))
    with dask_client(client, scheduler, workers) as dask:
        from distributed import as_completed

        futures = {dask.submit(run_case_task, registry[name].__name__, name, quick, pure=False,
                               priority=len(order) - rank): name
                   for rank, name in enumerate(order)}
        say(f"{len(names)} cases submitted to {len(dask.scheduler_info().get('workers', {}))} Dask workers")
        for future in as_completed(futures):
            outcome = future.result()
            done[outcome.name] = outcome
            say(f"[{len(done)}/{len(names)}] {outcome_line(outcome)}")
    record_case_times(quick, {name: o.cpu_s for name, o in done.items()})
    return [done[name] for name in names]


def case_times(quick) -> dict:
    """{case: CPU seconds of its last run} in quick or full mode ({} if none recorded)."""
    try:
        data = json.loads((cache_dir() / TIMES_FILE).read_text())
        times = data.get("quick" if quick else "full", {})
        return {str(k): float(v) for k, v in times.items()}
    except (OSError, ValueError, TypeError, AttributeError):
        return {}


def record_case_times(quick, times) -> None:
    """Merge ``times`` {case: CPU seconds} into the record of :func:`case_times`."""
    path = cache_dir() / TIMES_FILE
    try:
        data = json.loads(path.read_text())
        data = data if isinstance(data, dict) else {}
    except (OSError, ValueError):
        data = {}
    mode = "quick" if quick else "full"
    data[mode] = {**(data.get(mode) if isinstance(data.get(mode), dict) else {}), **times}
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(data, indent=1, sort_keys=True))
        tmp.replace(path)
    except OSError:
        pass           # a cache that cannot be written only costs the ordering


def run_case_task(module_name, name, quick):
    """One case in a worker: its module imported by name and run on one thread."""
    from threadpoolctl import threadpool_limits

    module = importlib.import_module(module_name)
    with threadpool_limits(1):
        return run_case({name: module}, name, quick)
