"""Run a scene as a job (``ffrmbs run``): stream the result file, take checkpoints,
resume a killed run, estimate the accuracy, report the cost, write the plot and the
ParaView export.

The job, for a scene (:class:`ffrmbs_app.scene.Scene`) built by ``make_scene()`` and
compiled once (:func:`compiled`: its Model serves the warm-up, the run and the Δt/2 check,
each with a new Data from the same start, as a fresh build would give):

0. the checks, before anything is written: the options, the step count and memory
   (:mod:`ffrmbs_app.limits`), the lock ``OUT/<scene>.lock`` held for the job
   (:mod:`ffrmbs_app.output_lock`: one job per result file); a result file already at
   ``OUT/<scene>.h5`` of another scene (the default scene and a scene file, or two scene
   files, that name their results alike) is named in a warning before this run replaces
   it (:func:`warn_another_scene`);
1. warm-up (the scene's ``warmup`` run, if any): a short run that compiles the numba
   kernels (or loads them from numba's disk cache) before the timed run. Compilation
   anywhere in the job is announced on its own line and measured apart
   (:class:`ffrmbs_app.compile_clock.CompileClock`); it is reported as such and subtracted from
   the run's wall and CPU seconds, so the per-step cost never contains it;
2. the run, streamed to ``OUT/<scene>.h5`` (:mod:`mbs.results.result_file`; starting it removes
   the plot and ParaView export of the run before, and what an export killed mid-write
   left, so that none can be taken for this run's, :class:`JobRecorder`) with a checkpoint
   every ``checkpoint_every`` seconds of wall time; SIGINT and SIGTERM stop it at its next
   output sample with a checkpoint and a cleanly closed file (status "interrupted"); a
   second signal stops it after the current step. ``resume=True`` continues a killed or
   interrupted run from its checkpoint (refused if an input file changed since): the
   scene is made again from its inputs and the run's state loaded from the checkpoint's
   arrays (:mod:`mbs.results.checkpoint`); the result equals the uninterrupted run's bit for bit;
3. the accuracy: the same scene once more at Δt/2 (``check``); max |x(Δt) − x(Δt/2)| over
   every output estimates the time-discretization error (the error of the Δt/2 run is
   about half of it for a first-order scheme across impacts), reported in the output's
   unit and relative to its range over the run (:func:`error_estimate`); likewise each
   of the scene's ``variants`` (e.g. twice the modes, another mesh) estimates the part of
   the error its modelling choice makes;
4. the summary (in the file's ``summary`` attribute and printed): steps, wall and CPU
   seconds, µs per step; the energy E = T + V of every body at the first and last output
   sample (``energy_J``; V: elastic, gravity, springs, compliant contacts' springs); for
   Moreau runs with a trace the intervals in which a contact transmits a force (non-zero
   impulse or force, not a merely touching gap: :func:`contact_intervals`), the largest
   penetration and the energy balance over the steps (:func:`energy_balance`,
   :mod:`mbs.run.step_work`)

       E(t) − E(0) = W_loads − D_damping + W_impulses + residual,

   each term summed step by step — the applied loads' work, the energy the damping of
   bodies and spring-dampers takes out, the work of the contact and joint impulses —
   gravity's work being in E as its potential; the residual, the integrator's own energy
   error, relative to the largest of |E(t) − E(0)| and the terms. Bodies the plan solves
   apart (exact modal propagation) are not integrated and not in the balance (they are
   named; a scene of such bodies only takes no step and gives the sampled energies);
   the final outputs; the error estimate;
5. ``OUT/<scene>.png`` (the outputs against time, :mod:`ffrmbs_app.plot`; rewritten by
   each run) and the ParaView series ``OUT/<scene>-paraview/`` (:mod:`ffrmbs_app.export`),
   written in a second process while step 3 runs (:mod:`ffrmbs_app.side_process`; the
   summary goes into the result file once that process is done), in the job's own process
   without checks, without a second CPU, or when the second process failed.
"""

from __future__ import annotations

import contextlib
import json
import math
import signal
import threading
import time
import warnings
from pathlib import Path

import numpy as np

from ffrmbs_app import side_process
from ffrmbs_app.compile_clock import CompileClock
from ffrmbs.errors import InputFileError, ModelError
from ffrmbs_app.limits import check_resources
from ffrmbs_app.output_dirs import shown
from ffrmbs_app.output_lock import output_lock
from ffrmbs_app.scene import MOREAU
from mbs.integrators import driver
from mbs.results.result_file import ResultRecorder, attribute, open_result_file, resume_checkpoint


def contact_intervals(t, dt, counts):
    """[(t_start, t_end)] [s] of the runs of steps with a count > 0 (trace arrays: step
    end times, step sizes, per-step counts: the summary passes ``pressed``, the contacts
    that transmitted a force — non-zero impulse or force, not merely a touching gap;
    ``closed`` gives the steps with a closed gap)."""
    on = np.asarray(counts) > 0
    edges = np.flatnonzero(np.diff(np.concatenate(([0], on.view(np.int8), [0]))))
    starts, stops = edges[::2], edges[1::2] - 1
    return [(float(t[a] - dt[a]), float(t[b])) for a, b in zip(starts, stops)]


BALANCE_TERMS = ("load_work", "damping_loss", "impulse_work")


def energy_balance(trace, initial) -> dict | None:
    """The energy balance of a Moreau run with ``trace=True`` (:mod:`mbs.run.step_work`):

        E(t) − E(0) = W_loads − D_damping + W_impulses + residual

    E(0) = ``initial`` [J] (``Result.stats["initial_energy"]``), E(t) the trace's last
    energy (E = T + V; gravity, springs and closed compliant contacts' springs are in V,
    so gravity's work is no term), the terms summed over the steps [J]. W_impulses is
    the work at the contact laws: the impulses' work on the bodies Σ Λᵀ(γ⁺ + γ⁻)/2 plus
    the energy the compliant contacts' springs hold at the end (none at the start): a
    spring charged by the bodies is in E, not lost. ``largest``:
    the name of the largest of |ΔE|, |W_loads|, D_damping, |W_impulses| and
    ``relative``: |residual| / that term (None when every term is zero). None when
    the run took no step (every body solved apart by the plan)."""
    energy = trace["energy"]
    if not len(energy):
        return None
    b = {"initial": float(initial), "final": float(energy[-1]), **{k: float(trace[k].sum()) for k in BALANCE_TERMS}}
    b["impulse_work"] += float(trace["contact_springs"][-1])
    b["change"] = b["final"] - b["initial"]
    b["residual"] = b["change"] - (b["load_work"] - b["damping_loss"] + b["impulse_work"])
    sizes = {k: abs(b[k]) for k in ("change", *BALANCE_TERMS)}
    b["largest"] = max(sizes, key=sizes.get)
    b["relative"] = abs(b["residual"]) / sizes[b["largest"]] if sizes[b["largest"]] > 0 else None
    return b


def _options(scene) -> dict:
    """The integrator options of ``scene``'s runs (a Moreau run keeps its trace when the
    scene asks for what needs it)."""
    options = dict(scene.options)
    if scene.integrator in MOREAU:
        options["trace"] = scene.keeps_trace()
    return options


def compiled(scene):
    """The compiled Model of ``scene``'s run (:meth:`mbs.System.compile`, planned for its
    t_end), on which the warm-up, the run and the Δt/2 check run, each with a new Data."""
    return scene.system.compile(scene.t_end, integrator=scene.integrator, plan=scene.plan,
                                tolerance=scene.tolerance, outputs=scene.outputs, **_options(scene))[0]


def _simulate(scene, dt=None, t_end=None, n_out=None, **extra):
    t_end = scene.t_end if t_end is None else t_end
    n_out = scene.n_out if n_out is None else n_out
    return scene.system.simulate(t_end, scene.dt if dt is None else dt, integrator=scene.integrator,
                                 t_out=np.linspace(0.0, t_end, n_out), outputs=scene.outputs,
                                 energies=scene.energies, plan=scene.plan, tolerance=scene.tolerance,
                                 **_options(scene), **extra)


def warm_up(scene, model=None) -> tuple:
    """Run ``scene``'s warm-up (``scene.warmup`` = (t_end, dt) [s], two output samples), so
    that the kernels it calls are compiled or loaded from numba's cache (on ``model``, the
    run's compiled Model, when given); returns ``scene.warmup``."""
    t_end, dt = scene.warmup
    _simulate(scene, dt=dt, t_end=t_end, n_out=2, model=model)
    return scene.warmup


@contextlib.contextmanager
def _stop_on_signals(log):
    """SIGINT/SIGTERM → :func:`mbs.integrators.driver.request_stop` while the run goes
    (in the main thread only: Python takes signals there; a run in another thread, e.g.
    a Dask worker's task, leaves the handlers to its host)."""
    if threading.current_thread() is not threading.main_thread():
        driver.clear_stop()
        try:
            yield
        finally:
            driver.clear_stop()
        return

    def handler(signum, frame):
        name = signal.Signals(signum).name
        driver.request_stop(f"{name} received")
        log(f"{name}: stopping at the next output sample (again: after the current step)")

    old = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    driver.clear_stop()
    try:
        yield
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)
        driver.clear_stop()


def result_path(scene, out) -> Path:
    return Path(out) / f"{scene.name}.h5"


SOURCES = ("scene file", "model script")       # the inputs that say which scene a result file is of


def scene_source(inputs: dict) -> str:
    """Which scene a run is of, from its ``inputs`` ({label: path}, as a Scene has them, or
    {label: {"path", "sha256"}} as a result file records them): "scene file <absolute
    path>", "model script <absolute path>", or "the default scene" (no such file)."""
    for label in SOURCES:
        entry = inputs.get(label)
        if entry is not None:
            path = entry.get("path") if isinstance(entry, dict) else entry
            return f"{label} {Path(str(path)).absolute()}"
    return "the default scene"


def warn_another_scene(path, scene) -> None:
    """A warning (one line; the command line prints ``ffrmbs: warning: …``) if ``path``
    holds the result file of another scene than ``scene`` (:func:`scene_source`), which
    this run replaces: two scenes whose results have the same name (the default scene
    and ``examples/scenes/point_mass_beam.toml``) do not overwrite each other's unsaid.
    A missing, unreadable or foreign file says nothing (the recorder replaces it)."""
    path = Path(path)
    if not path.is_file():
        return
    try:
        with open_result_file(path) as f:
            theirs = scene_source(json.loads(attribute(f, "inputs", "{}")))
    except (InputFileError, ValueError, TypeError, AttributeError):
        return
    ours = scene_source(scene.inputs)
    if theirs != ours:
        warnings.warn(f"{path} held the result of {theirs}; this run of {ours} replaces it (its plot and ParaView "
                      "export too; another --out keeps both)", stacklevel=2)


class JobRecorder(ResultRecorder):
    """The job's result recorder: starting a new result file first removes the outputs
    derived from the run before — its plot ``<stem>.png``, its ParaView export
    ``<stem>-paraview/`` and what exports killed mid-write left beside it — so that a
    killed or failed run leaves no older plot or export next to its result file."""

    def begin(self, integ):
        from ffrmbs_app.export import default_export_dir, remove_export

        self.path.with_suffix(".png").unlink(missing_ok=True)
        remove_export(default_export_dir(self.path))
        super().begin(integ)


def run_scene(make_scene, out, check=True, resume=False, checkpoint_every=60.0, flush_every=2.0,
              export=True, plot=True, log=print, no_limits=False, result=None) -> dict:
    """Run the job (module docstring) on the Scene ``make_scene()`` builds (called once);
    returns the summary. A diverging run raises SimulationError after closing the file
    with its samples so far (status "failed: …"); an interrupted one RunInterrupted.

    Refused before anything is written (ModelError): ``checkpoint_every`` [s] not a
    finite number > 0 (None: no checkpoints), or a scene over the step or memory limits
    of :mod:`ffrmbs_app.limits` unless ``no_limits``. One job at a time writes a result file
    (:mod:`ffrmbs_app.output_lock`); another is refused. ``result``: the result file's
    path (default :func:`result_path`, ``OUT/<scene>.h5``; a sweep names its runs)."""
    scene = make_scene()                      # a bad scene stops here, before anything is written
    if checkpoint_every is not None and not (isinstance(checkpoint_every, (int, float))
                                             and math.isfinite(checkpoint_every) and checkpoint_every > 0):
        raise ModelError(f"checkpoint_every (--checkpoint-every) must be a finite number of seconds > 0, "
                         f"got {checkpoint_every!r}")
    check_resources(scene, check, no_limits)
    path = result_path(scene, out) if result is None else Path(result)
    with output_lock(path):
        if not resume:
            warn_another_scene(path, scene)
        return _run(scene, path, check, resume, checkpoint_every, flush_every, export, plot, log)


def _run(scene, path, check, resume, checkpoint_every, flush_every, export, plot, log) -> dict:
    log(header(scene))
    units = scene.output_units()
    recorder = JobRecorder(path, {"scene": scene.name, "description": scene.description, "inputs": scene.inputs,
                                  "overrides": scene.overrides, "units": units, "labels": scene.labels},
                         flush_every=flush_every, checkpoint_every=checkpoint_every)
    warm_s = 0.0
    with CompileClock(log) as clock:
        model = compiled(scene)
        if scene.warmup is not None:
            w0 = time.perf_counter()
            t_w, dt_w = warm_up(scene, model)
            warm_s = time.perf_counter() - w0
            log(f"warm-up run (compiles the kernels or loads them from numba's cache, then runs {t_w:g} s of "
                f"simulated time at dt = {dt_w:g} s; not counted in the cost): {warm_s:.2f} s")
        compiling_before, compiling_cpu_before = clock.seconds, clock.cpu_seconds
        progress = _progress(scene.t_end)
        c0, w0 = time.process_time(), time.perf_counter()
        with _stop_on_signals(log), progress as bar:
            if resume:
                log(f"resuming {shown(path)} from its checkpoint")
                checkpoint = resume_checkpoint(recorder, inputs=scene.inputs, overrides=scene.overrides)
                res = _simulate(scene, recorder=recorder, progress=bar.update_to, contacts=True, checkpoint=checkpoint,
                                model=model)
            else:
                res = _simulate(scene, recorder=recorder, progress=bar.update_to, contacts=True, model=model)
        in_run = clock.seconds - compiling_before       # compilation inside the run: not its cost
        wall = max(time.perf_counter() - w0 - in_run, 0.0)
        cpu = max(time.process_time() - c0 - (clock.cpu_seconds - compiling_cpu_before), 0.0)
    log(clock.describe())
    summary = _summary(scene, res, wall, cpu, warm_s)
    summary.update(compile_s=clock.seconds, kernels_compiled=clock.compiled)
    side = side_process.start(lambda: _derived_files(path, plot, export)) if check and (plot or export) else None
    try:
        if check:
            _check(model, scene, res, units, summary)
        written = side is not None and side.join()
    except BaseException:
        if side is not None:
            side.stop()
        raise
    recorder.write_summary(summary)         # the result file is free again: the side process read it
    _report(summary, log)
    summary.update(_derived_files(path, plot, export) if not written else _derived_paths(path, plot, export))
    summary["result_file"] = str(path)
    return summary


def _check(model, scene, res, units, summary) -> None:
    """Step 3 of the job (module docstring): the error estimates into ``summary`` (the
    Δt/2 run on the run's ``model``)."""
    half = _simulate(scene, dt=0.5 * scene.dt, model=model)
    summary["error_estimate"] = {name: error_estimate(res[name], half[name], units[name]) for name in res.outputs}
    summary["error_parts"] = {}
    for label, (what, make) in scene.variants.items():
        other = _simulate(make())
        summary["error_parts"][label] = {"against": what, "outputs": {
            name: error_estimate(res[name], other[name], units[name]) for name in res.outputs}}


def _derived_files(path, plot, export) -> dict:
    """Step 5 of the job (module docstring): the plot and the ParaView export of the result
    file ``path`` (as asked); their paths under "plot", "paraview"."""
    if plot:
        from ffrmbs_app.plot import plot_result

        plot_result(path, out=path.with_suffix(".png"))
    if export:
        from ffrmbs_app.export import export_paraview

        export_paraview(path)
    return _derived_paths(path, plot, export)


def _derived_paths(path, plot, export) -> dict:
    """The paths :func:`_derived_files` writes."""
    from ffrmbs_app.export import collection_path

    paths = {}
    if plot:
        paths["plot"] = str(path.with_suffix(".png"))
    if export:
        paths["paraview"] = str(collection_path(path))
    return paths


def header(scene) -> str:
    """The job's first line: the scene's name and description; with ``--set`` overrides
    it says the description is the file's and lists the values set instead."""
    line = f"scene {scene.name}" + (f": {scene.description}" if scene.description else "")
    if scene.overrides and scene.description:
        return f"{line}\n  (the file's description; overridden by --set {', '.join(scene.overrides)})"
    if scene.overrides:
        return f"{line}, overridden by --set {', '.join(scene.overrides)}"
    return line


def error_estimate(run, half, unit) -> dict:
    """The time-step error estimate of one output: max |run(Δt) − run(Δt/2)| over samples
    and components (``max_abs``, in ``unit``), the output's range over the run (the
    largest max − min of its components, ``range``) and their ratio
    (``relative_to_range``; None for a constant output)."""
    run = np.asarray(run, dtype=float).reshape(len(run), -1)
    err = float(np.nanmax(np.abs(run - np.asarray(half, dtype=float).reshape(run.shape))))
    spread = float(np.nanmax(np.nanmax(run, axis=0) - np.nanmin(run, axis=0)))
    return {"max_abs": err, "unit": unit, "range": spread, "relative_to_range": err / spread if spread > 0 else None}


def _estimate_text(name, e) -> str:
    """"y 1.2e-07 m (3.4e-06 of its range 0.035 m)"."""
    unit = f" {e['unit']}" if e["unit"] else ""
    if e["relative_to_range"] is None:
        return f"{name} {e['max_abs']:.2e}{unit} (constant over the run)"
    return f"{name} {e['max_abs']:.2e}{unit} ({e['relative_to_range']:.2e} of its range {e['range']:.3g}{unit})"


def _progress(t_end):
    from ffrmbs_app.progress import progress_bar

    return progress_bar(t_end, "simulating", unit="s")


def _summary(scene, res, wall, cpu, warm_s) -> dict:
    steps = int(res.stats["steps"])
    timed = steps - int(res.stats.get("resumed_steps", 0))     # the steps of this process
    s = {"scene": scene.name, "integrator": scene.integrator, "dt_s": scene.dt, "t_end_s": scene.t_end,
         "steps": steps, "timed_steps": timed, "wall_s": wall, "cpu_s": cpu, "warmup_s": warm_s,
         "us_per_step": 1e6 * wall / max(timed, 1),
         "final": {name: np.asarray(v[-1]).tolist() for name, v in res.outputs.items()},
         "units": scene.output_units()}
    if res.stats.get("resumed_at"):
        s["resumed_at_s"] = res.stats["resumed_at"]
        s["note"] = "resumed: wall and CPU seconds and the cost per step are those of the last process only"
    if res.energy:
        E = res.total_energy()
        s["energy_J"] = {"initial": float(E[0]), "final": float(E[-1])}
    if res.stats.get("solved_apart"):
        s["solved_apart"] = list(res.stats["solved_apart"])
    tr = res.trace
    if scene.integrator in MOREAU and tr:
        if scene.system.contacts:
            s["contact_intervals_s"] = contact_intervals(tr["t"], tr["dt"], tr["pressed"])
            s["max_penetration_m"] = float(res.stats["max_penetration"])
        balance = energy_balance(tr, res.stats["initial_energy"]) if "initial_energy" in res.stats else None
        if balance is not None:
            s["energy_balance_J"] = balance
    return s


BALANCE_NAMES = {"change": "E(t) - E(0)", "load_work": "W_loads", "damping_loss": "D_damping",
                 "impulse_work": "W_impulses"}


def _balance_text(b, solved_apart=()) -> str:
    """"energy balance [J]: E(t) - E(0) = W_loads - D_damping + W_impulses + residual: ..."."""
    whose = (f" of the integrated bodies ({', '.join(repr(n) for n in solved_apart)} solved apart by the plan, "
             "exactly, and left out)" if solved_apart else "")
    rel = ("every term is zero" if b["relative"] is None
           else f"{b['relative']:.2e} of the largest term, {BALANCE_NAMES[b['largest']]}")
    terms = ", ".join(f"{BALANCE_NAMES[k]} = {b[k]:.6g}" for k in ("change", *BALANCE_TERMS))
    return (f"energy balance{whose} [J]: E(t) - E(0) = W_loads - D_damping + W_impulses + residual with {terms}, "
            f"residual = {b['residual']:.3g} ({rel}); E(0) = {b['initial']:.6g}, E(t) = {b['final']:.6g} "
            "(E = kinetic + elastic + gravity + springs + contact springs)")


def _report(s, log):
    if "contact_intervals_s" in s:
        iv = s["contact_intervals_s"]
        log(f"contact: force transmitted in {len(iv)} interval(s)"
            + (": " + ", ".join(f"{1e3 * a:.3f}-{1e3 * b:.3f} ms" for a, b in iv[:5]) + (" ..." if len(iv) > 5 else "")
               if iv else ""))
        log(f"maximum penetration: {s['max_penetration_m']:.3g} m")
    e, b = s.get("energy_J"), s.get("energy_balance_J")
    if e is not None and (b is None or "solved_apart" in s):
        log(f"energy (kinetic + potential of every body, at the output samples): initial {e['initial']:.6g} J, "
            f"final {e['final']:.6g} J")
    if b is not None:
        log(_balance_text(b, s.get("solved_apart", ())))
    elif s["steps"] == 0 and "solved_apart" in s:
        log("energy balance: no time step taken (the plan solves every body apart, by exact modal propagation); "
            "plan = false in [scene] integrates them and gives the balance")
    for name, value in s["final"].items():
        log(f"at t = {s['t_end_s']:g} s: {name} = {np.array2string(np.asarray(value), precision=6)} "
            f"{s['units'][name]}")
    if "error_estimate" in s:
        est = ", ".join(_estimate_text(name, e) for name, e in s["error_estimate"].items())
        log(f"accuracy (time step: max |run(dt) - run(dt/2)| per output, absolute and relative to the output's "
            f"range over the run): {est}")
    for label, part in s.get("error_parts", {}).items():
        est = ", ".join(_estimate_text(name, e) for name, e in part["outputs"].items())
        log(f"accuracy ({label}: max |run - run with {part['against']}|): {est}")
    if s["timed_steps"] == 0:
        log(f"cost: no time step, {s['wall_s']:.2f} s wall ({s['cpu_s']:.2f} s CPU)")
        return
    log(f"cost: {s['timed_steps']} steps in {s['wall_s']:.2f} s wall ({s['cpu_s']:.2f} s CPU), "
        f"{s['us_per_step']:.0f} µs per step" + (f" (resumed: {s['steps']} steps in all)" if "note" in s else ""))
