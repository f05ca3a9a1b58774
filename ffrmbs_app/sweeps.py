"""Parameter sweeps of a scene file on a Dask cluster (``ffrmbs sweep``, :func:`ffrmbs_app.sweep`).

A sweep runs one scene file many times, each run with its own set of overrides
(``KEY=VALUE``, as :func:`ffrmbs_app.scene_loader.load_scene` takes them: KEY a dotted path into the
scene file, ``scene.dt``, ``body.beam.modes``, ``contact.impact.e``; VALUE TOML text). The
sets are the Cartesian product of the grid's value lists, or with ``zip=True`` the lists
taken side by side.

Each run is one Dask task (:func:`run_one`): it loads the scene with its overrides and runs
it as a job (:func:`ffrmbs_app.job.run_scene`, no plot, no ParaView export, no checkpoints),
single-threaded, writing its own result file ``DIR/runs/<key>.h5`` (:func:`run_key`: a
readable, filesystem-safe name of its overrides), so no HDF5 file is ever written by two
processes. A run that fails (a bad override, a diverging integration, a crashed worker) is
a row with its error message; the sweep goes on. Re-running the same sweep into the same
DIR skips the runs whose result files are complete (status "complete" and the job's
summary written): only the missing, failed or interrupted runs run again.

The table (one row per run: the overrides, status, error, the accuracy estimate of the
job's Δt/2 check if asked for, the last sample of each output, the run's cost) is returned
and written as ``DIR/sweep.csv``, ``DIR/sweep.json`` and ``DIR/sweep.md``; when the runs
carry error estimates, ``DIR/sweep.png`` plots the work-precision diagram (estimated
error against CPU seconds, a line along the step size per value of the other varied keys);
``DIR/sweep-outputs.png`` plots each output's last sample against each varied key, one
line per value of the other varied keys (:func:`plot_sweep`).

Without a client the sweep starts a LocalCluster of ``workers`` (default 2) single-threaded
worker processes and closes it at the end; ``scheduler`` connects to a running scheduler
instead (``tcp://host:8786``); ``client`` uses the caller's (a notebook's, a
dask-jobqueue cluster's). Workers need the scene file and its inputs at the same paths
(a shared file system) and write into DIR.
"""

from __future__ import annotations

import csv
import hashlib
import itertools
import json
import math
import os
import re
import time
import tomllib
from pathlib import Path

from ffrmbs.errors import FfrmbsError, first_line
from ffrmbs_app.scene_file.overrides import split_override
from ffrmbs_app.scene_file.reading import key_parts

RESOLUTION_KEYS = ("dt", "modes", "tol", "tolerance")    # last key parts that set a resolution
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                     "NUMBA_NUM_THREADS": "1"}
#: Dask settings of the workers a sweep starts: no statistical profiler (a thread that samples
#: the task's stack every 10 ms and competes with it for the GIL)
QUIET_WORKER_CONFIG = {"distributed.worker.profile.enabled": False}
_zip = zip                    # the builtin, for functions whose argument ``zip`` hides it
_SAFE = re.compile(r"[^A-Za-z0-9._+=,-]")
KEY_MAX = 80                  # characters of a run's readable name before its hash


# --- the grid ----------------------------------------------------------------------------------
def split_values(text) -> list[str]:
    """The comma-separated values of ``--set KEY=V1,V2,...``: split at commas outside
    brackets, braces and quotes, so a TOML list ``[1, 2]`` or a string ``"a,b"`` stays
    one value. An empty value or unbalanced brackets or quotes is a FfrmbsError."""
    values, depth, quote, start = [], 0, None, 0
    for i, c in enumerate(text):
        if quote:
            if c == quote:
                quote = None
        elif c in "\"'":
            quote = c
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
            if depth < 0:
                raise FfrmbsError(f"values {text!r}: a closing {c!r} without its opening bracket")
        elif c == "," and depth == 0:
            values.append(text[start:i])
            start = i + 1
    if quote or depth:
        raise FfrmbsError(f"values {text!r}: an unclosed {'quote' if quote else 'bracket'}")
    values.append(text[start:])
    values = [v.strip() for v in values]
    if not all(values):
        raise FfrmbsError(f"values {text!r}: an empty value (two commas, or one at an end)")
    return values


def parse_set(items) -> dict:
    """The grid {KEY: [value text, ...]} of the ``--set KEY=V1,V2,...`` options
    (:func:`split_values`); a KEY given twice or an item without ``=`` is a FfrmbsError."""
    grid = {}
    for item in items:
        try:
            key, values = split_override(item)          # at the first "=" outside quotes
        except ValueError:
            key = ""
        if not key:
            raise FfrmbsError(f"--set {item!r}: expected KEY=V1,V2,... (e.g. scene.dt=1e-5,5e-6)")
        if key in grid:
            raise FfrmbsError(f"--set: the key {key} is given twice; list all its values in one --set")
        grid[key] = split_values(values)
    return grid


def toml_text(value) -> str:
    """A grid value as TOML text: a str is taken as TOML text already (a bare word is a
    string to :func:`~ffrmbs_app.scene_loader.load_scene`); bool, int, float and lists of them are
    written in TOML."""
    if isinstance(value, str):
        return value.strip()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ("nan" if value != value else ("inf" if value > 0 else "-inf"))
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_text(v) for v in value) + "]"
    raise FfrmbsError(f"grid value {value!r}: give TOML text, a number, a bool or a list of them")


def grid_text(grid) -> dict:
    """{KEY: [value as TOML text, ...]} of ``grid`` ({KEY: a list of values, or one
    value}); an empty grid or value list is a FfrmbsError."""
    if not isinstance(grid, dict) or not grid:
        raise FfrmbsError("the sweep's grid is empty: give at least one KEY with its values")
    text = {}
    for key, values in grid.items():
        if not isinstance(values, (list, tuple)):
            values = [values]
        if not values:
            raise FfrmbsError(f"the sweep's grid gives no value for {key}")
        text[key] = [toml_text(v) for v in values]
    return text


def override_sets(grid, zip=False) -> list[tuple[str, ...]]:
    """The runs of ``grid`` (:func:`grid_text`) as tuples of "KEY=VALUE" overrides: the
    Cartesian product of the value lists, or (``zip``) the lists side by side (of equal
    lengths). Unequal lengths with ``zip`` or a run listed twice is a FfrmbsError."""
    text = grid_text(grid)
    keys, lists = list(text), list(text.values())
    if zip:
        lengths = {key: len(v) for key, v in _zip(keys, lists)}
        if len(set(lengths.values())) > 1:
            raise FfrmbsError("zip needs value lists of equal lengths, got "
                              + ", ".join(f"{k}: {n}" for k, n in lengths.items()))
        combos = list(_zip(*lists))
    else:
        combos = list(itertools.product(*lists))
    runs = [tuple(f"{k}={v}" for k, v in _zip(keys, combo)) for combo in combos]
    if len({run_key(r) for r in runs}) != len(runs):
        raise FfrmbsError("the sweep lists a run twice (a value repeated in the grid)")
    return runs


def short_labels(keys) -> dict:
    """{KEY: label}: the shortest dotted suffix of each key that no other key shares
    ("body.beam.modes" -> "modes", unless another key ends in "modes" too)."""
    parts = {key: key_parts(key) for key in keys}
    labels = {}
    for key, mine in parts.items():
        for n in range(1, len(mine) + 1):
            if not any(o != key and theirs[-n:] == mine[-n:] for o, theirs in parts.items()):
                break
        labels[key] = ".".join(mine[-n:])
    return labels


def _pairs(overrides) -> list[tuple[str, str]]:
    """(KEY, VALUE) of each "KEY=VALUE" override (split at the first "=" outside quotes)."""
    return [split_override(o) for o in overrides]


def value_name(text) -> str:
    """A value's TOML text as a run's name shows it: a quoted string without its quotes
    ("penalty"), a list as its items joined by "_" ("[0.05, 0.02]" -> "0.05_0.02"), any
    other value as written ("1e-5")."""
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text.strip()
    if isinstance(value, str):
        return value
    if isinstance(value, list):
        inner = text.strip()[1:-1].strip()
        return "_".join(value_name(item) for item in split_values(inner)) if inner else "empty"
    return text.strip()


def run_key(overrides) -> str:
    """A run's name in DIR/runs: "dt=5e-06,modes=50", "e=0.2,position=0.05_0.02_0.025"
    from its overrides (keys shortened by :func:`short_labels`, values by
    :func:`value_name`). Characters outside [A-Za-z0-9._+=,-] become "_", and then, or
    when the name is longer than KEY_MAX, "-" and 8 hex digits of the overrides' SHA-1
    follow, so different runs never share a name."""
    pairs = _pairs(overrides)
    labels = short_labels([k for k, _ in pairs])
    text = ",".join(f"{labels[k]}={value_name(v)}" for k, v in pairs)
    safe = _SAFE.sub("_", text)
    if safe != text or len(safe) > KEY_MAX or safe.startswith("."):
        digest = hashlib.sha1("\n".join(overrides).encode()).hexdigest()[:8]
        safe = f"{safe[:KEY_MAX].lstrip('.')}-{digest}"
    return safe


# --- one run (a Dask task) -----------------------------------------------------------------------
def run_one(scene, overrides, result, check=False) -> dict:
    """Load ``scene`` (a scene file path) with ``overrides`` and run it as a job into the
    result file ``result``, single-threaded; never raises. Returns {"status": "complete",
    "summary": the job's summary} or {"status": "failed", "error": one line}, with
    "task_wall_s" [s], the task's own wall time (loading, compiling, running)."""
    os.environ.update(SINGLE_THREAD_ENV)          # for anything that starts threads later
    t0 = time.perf_counter()
    try:
        from threadpoolctl import threadpool_limits

        from ffrmbs_app.job import run_scene
        from ffrmbs_app.scene_loader import load_scene

        with threadpool_limits(1):
            summary = run_scene(lambda: load_scene(scene, overrides=overrides), Path(result).parent, check=check,
                                checkpoint_every=None, export=False, plot=False, log=lambda line: None,
                                result=result)
        out = {"status": "complete", "summary": summary}
    except FfrmbsError as exc:
        out = {"status": "failed", "error": first_line(exc, 300)}
    except Exception as exc:                      # a bug or a library's error: still only this run's row
        out = {"status": "failed", "error": f"{type(exc).__name__}: {first_line(exc, 300)}"}
    out["task_wall_s"] = time.perf_counter() - t0
    return out


def completed_summary(path) -> dict | None:
    """The job summary of a complete result file (status "complete", summary written),
    else None (missing, unreadable, failed, interrupted or still running)."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("status") != "complete" or "summary" not in f.attrs:
                return None
            return json.loads(f.attrs["summary"])
    except (OSError, ValueError):
        return None


# --- the sweep --------------------------------------------------------------------------------------
def sweep(scene, grid, out, client=None, zip=False, workers=None, scheduler=None, check=False, progress=None,
          as_frame=False):
    """Run the sweep of ``scene`` over ``grid`` into directory ``out`` (module docstring).

    Parameters
    ----------
    scene : str or Path
        A TOML scene file.
    grid : dict
        {KEY: [values]}: each value TOML text ("5e-6", "[1, 2]", "penalty") or a Python
        number, bool or list.
    out : str or Path
        The sweep's directory: runs/<key>.h5, sweep.csv, sweep.json, sweep.md, sweep.png.
    client : distributed.Client, optional
        Run on this client's cluster (left open).
    zip : bool
        Runs from the value lists side by side instead of their Cartesian product.
    workers : int, optional
        Worker processes of the LocalCluster made when neither client nor scheduler is
        given (default 2; one thread each).
    scheduler : str, optional
        Address of a running Dask scheduler ("tcp://host:8786").
    check : bool
        Each run's job also runs at Δt/2 for its accuracy estimate (twice the cost).
    progress : callable, optional
        Called with one line after each finished run ("done/running/failed"); default a
        tqdm bar on stderr, drawn only on a terminal (:mod:`ffrmbs_app.progress`).
    as_frame : bool
        Return a pandas DataFrame (pandas must be installed) instead of a list of dicts.

    Notes
    -----
    Returns the table: one dict per run (:func:`rows`'s columns), in grid order.
    """
    if client is not None and (workers is not None or scheduler is not None):
        raise FfrmbsError("give a client, or workers or a scheduler for the sweep to connect to, not both")
    if workers is not None and scheduler is not None:
        raise FfrmbsError("--workers makes a local cluster, --scheduler uses a running one: give one of them")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise FfrmbsError(f"workers must be a whole number >= 1, got {workers!r}")
    if as_frame:
        try:
            import pandas
        except ImportError:
            raise FfrmbsError("as_frame=True needs pandas, which is not installed") from None
    from preprocess.inputfiles import regular_file

    scene = regular_file(scene).resolve()
    runs = override_sets(grid, zip=zip)
    out = Path(out).resolve()
    if out.exists() and not out.is_dir():
        raise FfrmbsError(f"{out} exists and is not a directory")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    keys = [run_key(r) for r in runs]
    w0 = time.perf_counter()
    results = {}
    todo = []
    for i, key in enumerate(keys):
        summary = completed_summary(out / "runs" / f"{key}.h5")
        if summary is None:
            todo.append(i)
        else:
            results[i] = {"status": "complete", "summary": summary, "reused": True}
    if todo:
        with dask_client(client, scheduler, workers) as c:
            _gather(c, scene, runs, keys, todo, out, check, results, progress)
    table = rows(runs, keys, results, out)
    write_table(table, out, {"scene": str(scene), "grid": grid_text(grid), "zip": bool(zip), "check": bool(check),
                             "runs": len(runs), "ran": len(todo), "wall_s": time.perf_counter() - w0})
    if as_frame:
        return pandas.DataFrame(table)
    return table


class dask_client:
    """The client to use: the caller's (left open), one of a running scheduler, or a
    LocalCluster of single-threaded worker processes made and closed here."""

    def __init__(self, client, scheduler, workers):
        self.given, self.scheduler, self.workers = client, scheduler, workers
        self.made = []

    def __enter__(self):
        if self.given is not None:
            return self.given
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise FfrmbsError("sweeps and validate --workers run on Dask, which is not installed: "
                              "pip install '.[sweep]'") from None

        if self.scheduler is not None:
            try:
                c = Client(self.scheduler, timeout="10s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise FfrmbsError(f"cannot connect to the Dask scheduler {self.scheduler}: {first_line(exc)}") from None
            self.made.append(c)
            return c
        import dask

        with dask.config.set(QUIET_WORKER_CONFIG):
            cluster = LocalCluster(n_workers=self.workers or 2, threads_per_worker=1, processes=True,
                                   dashboard_address=None, env=dict(SINGLE_THREAD_ENV))
        self.made.append(cluster)
        c = Client(cluster)
        self.made.append(c)
        return c

    def __exit__(self, *exc):
        for thing in reversed(self.made):
            thing.close()
        return False


def _gather(client, scene, runs, keys, todo, out, check, results, progress):
    """Submit the runs ``todo`` (indices) and collect their outcomes into ``results`` as
    they finish, reporting progress."""
    from distributed import as_completed

    from ffrmbs_app.progress import ProgressBar

    futures = {client.submit(run_one, str(scene), runs[i], str(out / "runs" / f"{keys[i]}.h5"), check, pure=False,
                             key=f"ffrmbs-run-{keys[i]}-{os.urandom(4).hex()}"): i for i in todo}
    slots = max(sum(client.nthreads().values()), 1)
    done = failed = 0
    bar = ProgressBar(len(todo), "sweep", unit="run", enabled=None if progress is None else False)
    try:
        for future in as_completed(futures):
            i = futures[future]
            try:
                results[i] = future.result()
            except Exception as exc:              # the task itself was lost (a worker died, ...)
                results[i] = {"status": "failed", "error": f"{type(exc).__name__}: {first_line(exc, 300)}"}
            done += 1
            failed += results[i]["status"] != "complete"
            pending = len(todo) - done
            line = (f"sweep: {done}/{len(todo)} done, {min(pending, slots)} running, {failed} failed "
                    f"({keys[i]}: {results[i]['status']}"
                    + (f": {results[i]['error']})" if results[i]["status"] != "complete" else ")"))
            if progress is not None:
                progress(line)
            bar.update(1)
            bar.postfix(f"{min(pending, slots)} running, {failed} failed")
    finally:
        bar.close(complete=False)


# --- the table -----------------------------------------------------------------------------------------
def rows(runs, keys, results, out) -> list[dict]:
    """One dict per run: "run" (its key), each override's KEY with its value text,
    "status", "error", "error_estimate" (the largest relative error estimate over the
    outputs from the Δt/2 check, None without), "error:<output>" [output unit],
    "final:<output>" (its last sample), "steps", "wall_s", "cpu_s" [s] (the run's own,
    compilation excluded), "compile_s" [s], "task_wall_s" [s] (the task's whole time),
    "reused" (a complete result file kept from an earlier sweep), "result_file" (relative
    to the sweep's directory)."""
    table = []
    for i, (overrides, key) in enumerate(_zip(runs, keys)):
        r = results[i]
        s = r.get("summary") or {}
        row = {"run": key, **dict(_pairs(overrides)),
               "status": r["status"], "error": r.get("error")}
        est = s.get("error_estimate")
        rel = [e["relative_to_range"] for e in (est or {}).values() if e["relative_to_range"] is not None]
        row["error_estimate"] = max(rel) if rel else None
        for name, e in (est or {}).items():
            row[f"error:{name}"] = e["max_abs"]
        for name, v in s.get("final", {}).items():
            row[f"final:{name}"] = v
        for k in ("steps", "wall_s", "cpu_s", "compile_s"):
            row[k] = s.get(k)
        row["task_wall_s"] = r.get("task_wall_s")
        row["reused"] = bool(r.get("reused", False))
        path = out / "runs" / f"{key}.h5"
        row["result_file"] = str(path.relative_to(out)) if path.exists() else None
        table.append(row)
    return table


def _columns(table) -> list[str]:
    cols = []
    for row in table:
        cols += [c for c in row if c not in cols]
    return cols


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value)


def write_table(table, out, meta) -> list[Path]:
    """Write ``out``/sweep.csv, sweep.json ({meta, "rows"}) and sweep.md, and the plots
    of :func:`plot_sweep`; returns the paths written."""
    out = Path(out)
    cols = _columns(table)
    with open(out / "sweep.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        w.writerows([[_cell(row.get(c)) for c in cols] for row in table])
    (out / "sweep.json").write_text(json.dumps({**meta, "rows": table}, indent=1, default=float) + "\n")
    lines = [f"# Sweep of {meta['scene']}", "",
             f"{meta['runs']} runs ({meta['ran']} run now, the others kept from complete result files), "
             f"{sum(r['status'] == 'complete' for r in table)} complete; sweep wall time {meta['wall_s']:.2f} s. "
             "wall_s and cpu_s: each run's own cost [s], compilation excluded; error_estimate: the largest "
             "max |x(dt) - x(dt/2)| over the outputs, relative to the output's range (with check).", "",
             "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(_cell(row.get(c)).replace("|", "\\|") for c in cols) + " |" for row in table]
    (out / "sweep.md").write_text("\n".join(lines) + "\n")
    written = [out / "sweep.csv", out / "sweep.json", out / "sweep.md"]
    return written + plot_sweep(table, meta["grid"], out)


def resolution_keys(keys) -> list[str]:
    """The keys that set a resolution: their last part is one of RESOLUTION_KEYS."""
    return [k for k in keys if key_parts(k)[-1:] and key_parts(k)[-1] in RESOLUTION_KEYS]


def varied_keys(grid) -> list[str]:
    """The keys of ``grid`` given more than one value."""
    return [k for k, values in grid.items() if len(values) > 1]


def line_key(grid) -> str | None:
    """The varied resolution key a work-precision line follows: the step size when it
    varies, else the first varied resolution key; None when no resolution key varies."""
    keys = resolution_keys(varied_keys(grid))
    steps = [k for k in keys if key_parts(k)[-1] == "dt"]
    return (steps or keys or [None])[0]


def _series(rows, keys, labels):
    """{legend text: rows} with one entry per value combination of ``keys`` ("modes = 20,
    e = 0.5" by their short ``labels``; "" without keys), in grid order."""
    from ffrmbs_app.ticks import series_label

    series = {}
    for r in rows:
        series.setdefault(series_label([labels[k] for k in keys], [r[k] for k in keys]), []).append(r)
    return series


def _numbers(texts):
    """The values as floats, or None when one is not a number."""
    try:
        return [float(t) for t in texts]
    except (TypeError, ValueError):
        return None


def _figure(width, height):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _legend(ax):
    if any(line.get_label() and not line.get_label().startswith("_") for line in ax.get_lines()):
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)


def work_precision_figure(table, grid):
    """The work-precision Figure: each complete run's error estimate (relative to the
    output's range) against its CPU seconds, log-log; a line along the step size (or the
    varied resolution key, :func:`line_key`) per value of the other varied keys, the
    legend naming them; markers only when no resolution key varies. None when fewer than
    two runs carry an estimate."""
    points = [r for r in table if r["status"] == "complete" and r["error_estimate"] and r["cpu_s"]]
    if len(points) < 2:
        return None
    from ffrmbs_app.ticks import label_log_axis

    labels = short_labels(list(grid))
    along = line_key(grid)
    others = [k for k in varied_keys(grid) if k != along]
    fig = _figure(8.5, 4.8)
    ax = fig.add_subplot()
    for i, (label, rs) in enumerate(_series(points, others, labels).items()):
        if along is not None:
            rs = sorted(rs, key=lambda r: grid[along].index(r[along]))
        ax.loglog([r["cpu_s"] for r in rs], [r["error_estimate"] for r in rs], "o-" if along else "o",
                  label=label or None, color=f"C{i % 10}")
        if along is not None:
            for r in rs:
                ax.annotate(f"{labels[along]} = {r[along]}", (r["cpu_s"], r["error_estimate"]), fontsize=7,
                            xytext=(3, 3), textcoords="offset points")
    label_log_axis(ax, "x")
    label_log_axis(ax, "y")
    ax.set_xlabel("CPU time of the run [s]")
    ax.set_ylabel("error estimate, relative to the output's range [-]")
    ax.set_title("work precision" + (f" along {labels[along]}" if along else ""))
    ax.grid(True, which="both", alpha=0.3)
    _legend(ax)
    return fig


def output_names(table) -> list[str]:
    """The "final:<output>" columns of the complete runs that hold numbers (scalar
    outputs), in table order."""
    done = [r for r in table if r["status"] == "complete"]
    return [c for c in _columns(done) if c.startswith("final:") and _numbers([r.get(c) for r in done])]


def outputs_figure(table, grid):
    """The outputs Figure: a panel per output (its last sample, a row of panels) and per
    varied key (a column): the output against the key's values, one line per value of
    the other varied keys, the legend naming them. None when no key varies or no run
    completed."""
    done = [r for r in table if r["status"] == "complete"]
    names, keys = output_names(table), varied_keys(grid)
    if not done or not names or not keys:
        return None
    labels = short_labels(list(grid))
    fig = _figure(4.2 * len(keys) + 2.8, 0.6 + 2.8 * len(names))
    axes = fig.subplots(len(names), len(keys), squeeze=False)
    for row, name in enumerate(names):
        for col, key in enumerate(keys):
            _output_panel(axes[row, col], done, name, key, [k for k in keys if k != key], labels, grid)
    fig.suptitle("last sample of each output against each varied key")
    return fig


def _output_panel(ax, done, name, key, others, labels, grid):
    """One output against one key (:func:`outputs_figure`)."""
    from ffrmbs_app.ticks import label_log_axis, plain_axis

    order = grid[key]
    numeric = _numbers(order)
    for i, (label, rs) in enumerate(_series(done, others, labels).items()):
        rs = [r for r in rs if _numbers([r.get(name)]) is not None]
        rs.sort(key=lambda r: order.index(r[key]))
        x = [float(r[key]) for r in rs] if numeric else [order.index(r[key]) for r in rs]
        ax.plot(x, [float(r[name]) for r in rs], "o-", label=label or None, color=f"C{i % 10}")
    if numeric and min(numeric) > 0 and max(numeric) / min(numeric) > 20:
        ax.set_xscale("log")
        label_log_axis(ax, "x")
    elif numeric:
        plain_axis(ax.xaxis)
    else:
        ax.set_xticks(range(len(order)), order)
    plain_axis(ax.yaxis)
    ax.set_xlabel(labels[key])
    ax.set_ylabel(name[len("final:"):])
    ax.grid(True, alpha=0.3)
    _legend(ax)


def plot_sweep(table, grid, out) -> list[Path]:
    """Write ``out``/sweep.png (:func:`work_precision_figure`) and sweep-outputs.png
    (:func:`outputs_figure`) when they have something to show; a stale one is removed.
    Returns the paths written."""
    written = []
    for name, make in (("sweep.png", work_precision_figure), ("sweep-outputs.png", outputs_figure)):
        path = Path(out) / name
        fig = make(table, grid)
        if fig is None:
            path.unlink(missing_ok=True)
            continue
        fig.savefig(path, dpi=100)
        written.append(path)
    return written
