"""Run every benchmark in one process, print its tables and target verdicts, write JSON.

Usage::

    python3 -m validation.bench [--out out/bench] [--quick] [--only NAME[,NAME]]
    ffrmbs bench [--out out/bench] [--quick] [--only NAME[,NAME]]

``--quick`` runs each benchmark at its coarse settings (about 40 s in all here, against
about 4 minutes in full with the meshes cached, 8 with a fresh body cache); ``--only`` picks benchmarks by name
(comma-separated or repeated). Writes ``DIR/<name>.json`` per benchmark (its whole
document) and ``DIR/summary.json``: the machine, the options and per benchmark its status (``ok``, ``skipped`` — a peer code is not installed, ``not
available`` — the module is not written yet, ``failed``), wall seconds, target verdicts,
the path of its JSON and, on failure, the error with its traceback. A failing benchmark
does not stop the others; the command exits with status 2 if any failed.
``python3 -m validation.bench`` is ``ffrmbs bench`` (:mod:`ffrmbs_app.cli`), which calls
:func:`run_benchmarks`.

Registry and protocol: ``BENCHES`` maps a name to a module path; the module exposes
``run(quick: bool) -> dict`` whose dict has at least ``"table"`` (markdown str) and
``"rows"`` (list of dicts), and optionally ``"verdicts"`` (list of str, one per target,
ending in "met" or "NOT met") and ``"skipped"`` (str, why it did not run, e.g.
"skipped: akantu not installed"). Every key is saved to the benchmark's JSON.
"""

from __future__ import annotations

import importlib
import time
import traceback

from validation.bench.common import machine, write_json

BENCHES = {
    "point_mass_beam": "validation.bench.point_mass_beam",
    "exudyn_free_flight": "validation.bench.exudyn_free_flight",
    "akantu_case_study": "validation.bench.akantu_case_study",
    "planned_vs_unplanned": "validation.bench.planner",
    "ffr_evaluation": "validation.bench.ffr_evaluation",
    "contour_evaluation": "validation.bench.contour_evaluation",
    "step_cost": "validation.bench.step_cost",
    "scene_cost": "validation.bench.scene_cost",
    "pair_cost": "validation.bench.pair_cost",
    "geometric_stiffness_cost": "validation.bench.geometric_stiffness_cost",
}


def _protocol_error(doc) -> str | None:
    """Why ``doc`` does not follow the protocol, or None."""
    if not isinstance(doc, dict):
        return f"run() returned {type(doc).__name__}, not a dict"
    if not isinstance(doc.get("table"), str):
        return "its document has no markdown 'table' (str)"
    if not isinstance(doc.get("rows"), list):
        return "its document has no 'rows' (list of dicts)"
    return None


def run_bench(name, quick, out, log=print) -> dict:
    """Run the benchmark ``name`` of ``BENCHES``, print its table and verdicts, write its
    JSON to ``out``; its summary entry (status, wall_s, verdicts, json, error)."""
    path = BENCHES[name]
    entry = {"module": path, "status": "ok", "wall_s": 0.0, "verdicts": []}
    start = time.perf_counter()
    try:
        doc = importlib.import_module(path).run(quick)
        entry["wall_s"] = time.perf_counter() - start
        problem = _protocol_error(doc)
        if problem:
            raise TypeError(f"{path} does not follow the benchmark protocol: {problem}")
        entry["verdicts"] = [str(v) for v in doc.get("verdicts", [])]
        if doc.get("skipped"):
            entry.update(status="skipped", skipped=str(doc["skipped"]))
        log(doc["table"])
        log("\n".join(entry["verdicts"]))
        entry["json"] = write_json(doc, out, name)
    except Exception as exc:                    # one failing benchmark must not stop the others
        if isinstance(exc, ModuleNotFoundError) and exc.name == path:
            entry.update(status="not available", error=f"{path} is not written yet")
            log(f"{name}: not yet available ({path} does not exist)")
        else:
            entry.update(status="failed", wall_s=time.perf_counter() - start, error=f"{type(exc).__name__}: {exc}",
                         traceback=traceback.format_exc())
            log(f"{name}: FAILED: {entry['error']}")
    return entry


def run_benchmarks(out="out/bench", quick=False, only=None, log=print) -> dict:
    """Run the benchmarks named in ``only`` (all of ``BENCHES`` if None) in this process;
    write ``out/summary.json`` and return the summary. Unknown names raise ValueError."""
    names = list(BENCHES) if not only else list(only)
    unknown = [n for n in names if n not in BENCHES]
    if unknown:
        raise ValueError(f"unknown benchmark(s) {', '.join(unknown)}; choose from {', '.join(BENCHES)}")
    summary = {"machine": machine(), "quick": quick, "benches": {}}
    for name in names:
        log(f"\n## {name}\n")
        summary["benches"][name] = run_bench(name, quick, out, log)
    log("\n## summary\n")
    for name, entry in summary["benches"].items():
        log(f"{name}: {entry['status']} ({entry['wall_s']:.1f} s)")
        for line in entry["verdicts"]:
            log(f"  {line}")
    summary["json"] = write_json(summary, out, "summary")
    return summary


def split_names(values) -> list | None:
    """Benchmark names from ``--only`` values (repeated and/or comma-separated), or None."""
    if not values:
        return None
    return [n.strip() for v in values for n in v.split(",") if n.strip()]
