"""The ``ffrmbs`` command line.

Subcommands
-----------
- ``preprocess``  mesh -> FE model -> modes -> body files (thesis Sec. 4.2.1 text files and body.h5)
- ``info``        summary of a body (text-file directory or HDF5 file)
- ``validate``    validation cases: error against run time (see ../DESIGN.md)
- ``run``         a scene as a job (result file streamed, checkpoints, ``--resume``, plot,
  ParaView export): the default point mass on the flexible beam (thesis
  Sec. 5.2), a TOML scene file or a Python model script
- ``sweep``       a scene file over a grid of overrides, one run per Dask task: table, work-precision plot
- ``bench``       every benchmark in one process: tables, target verdicts, JSON (validation.bench)
- ``plot``        outputs, energy and contacts of a result file against time, as a PNG (ffrmbs_app.plot)
- ``export``      a result file to ParaView: deformed surfaces over time, .pvd + .vtu (ffrmbs_app.export)
- ``contour``     a 2s contour fitted to a face group of a body: fit report, PNG, .vtu (ffrmbs_app.contour_report)

Progress bars (preprocessing stages, export) are drawn on stderr only when it is a
terminal; ``FFRMBS_PROGRESS=1`` forces them on, ``FFRMBS_PROGRESS=0`` off (ffrmbs_app.progress).

Errors the user can cause (:class:`ffrmbs.errors.FfrmbsError`) are printed as one
line ``ffrmbs: error: …`` and exit with status 2, without a traceback. A reader that
closes the pipe early (``ffrmbs info … | head``) ends the command quietly (status 141).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
import warnings
from pathlib import Path

from ffrmbs import __version__
from ffrmbs.errors import FfrmbsError, RunInterrupted
from ffrmbs_app.output_dirs import shown

DEFAULT_MODES = 10  # modes printed by the main job


def output_dir(text):
    """argparse type of an ``--out`` directory: refused at once when it names an existing
    file (the command would fail after its work, or half-way through writing)."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} exists and is not a directory")
    return text


def _say(msg):
    """One line of a job's report on stdout (kept clear of a progress bar being drawn)."""
    from ffrmbs_app.progress import write

    write(msg, sys.stdout)


def _log(msg):
    from ffrmbs_app.progress import write

    write(msg, sys.stderr)      # print(..., flush=True), or above a progress bar being drawn


def _stage(label, fn, *args, announce_in=None, on_start=None, **kwargs):
    """Run one long step, telling the user what happens and how long it took; ``on_start``
    (no arguments, e.g. a progress bar's next stage) is called as it starts. With
    ``announce_in`` (a keyword argument of ``fn`` taking a callback) ``fn`` announces the
    step itself once its checks pass, so a refused input prints no stage line."""
    def announce():
        if on_start is not None:
            on_start()
        _log(f"{label} ...")

    t0 = time.perf_counter()
    if announce_in is None:
        announce()
    else:
        kwargs[announce_in] = announce
    out = fn(*args, **kwargs)
    _log(f"{label}: done in {time.perf_counter() - t0:.2f} s")
    return out


def _preprocess(spec, modes, clamp, units, density, young, poisson, order, mesh_size, out, check_limits=True,
                structured=None, geometric_stiffness=False, mass="lumped", groups=None):
    """``ffrmbs preprocess``: mesh, body data, body files in ``out``; prints the mesh
    statistics, the total mass and the frequencies, and warns of a density, Young's
    modulus or mass outside the ranges of :mod:`preprocess.plausible` (units mistakes)."""
    from preprocess import plausible
    from preprocess.bodyfiles import write_body
    from preprocess.pipeline import Material, build_body, check_mass_kind, check_n_modes, mesh_source, \
        mesh_statistics

    from ffrmbs_app.progress import stage_bar, write

    material = Material(density, young, poisson)        # every option checked before meshing:
    check_n_modes(modes)                                # these here, the mesh options by mesh_source
    check_mass_kind(mass)
    for message in plausible.material_warnings(density, young, units):
        warnings.warn(message, stacklevel=2)
    with stage_bar(3 + (out is not None) + bool(geometric_stiffness), "preprocess") as bar:
        mesh = _stage(f"meshing {spec}", mesh_source, spec, order, mesh_size, check_limits,
                      announce_in="announce", on_start=lambda: bar.stage("meshing"), structured=structured,
                      units=units, groups=groups)
        write(mesh_statistics(mesh), sys.stdout)
        params = dict(input=spec, mesh_size=mesh_size, structured=structured)
        body = build_body(mesh, material, modes, clamp=clamp, units=units, params=params, log=_log,
                          progress=bar.stage, check_limits=check_limits, geometric_stiffness=geometric_stiffness,
                          mass=mass)
        if out is not None:
            bar.stage("writing body files")
            _stage(f"writing body files to {out}", write_body, out, body)
    print(body.mass_line())
    for message in plausible.mass_warnings(body.total_mass, units):
        warnings.warn(message, stacklevel=2)
    print(body.frequency_table())
    return body


def cmd_preprocess(args):
    _preprocess(args.input, args.modes, None if args.free else args.clamp, args.units,
                args.density, args.young, args.poisson, args.order, args.mesh_size, args.out, not args.no_limits,
                args.structured, args.geometric_stiffness, args.mass, args.group)


def cmd_info(args):
    from preprocess.bodyfiles import read_body

    print(read_body(args.path, units=args.units).summary())


def cmd_validate(args):
    if args.workers is not None and args.workers < 1:
        raise FfrmbsError(f"--workers must be at least 1, not {args.workers}")
    if args.stability:    # the stability suite (validation.stability); a case that did not pass is an error
        if args.workers is not None or args.scheduler is not None:
            raise FfrmbsError("--workers and --scheduler run the validation cases on Dask; the stability suite "
                              "runs in this process")
        from validation.stability.runner import run_stability

        run_stability(args.out, quick=args.quick, only=args.only or None, progress=_log)
        out = Path(args.out)
        print(f"wrote {shown(out / 'stability.json')} and {shown(out / 'report.md')}")
        return
    from validation import run_validation

    run_validation(args.out, quick=args.quick, only=args.only or None, progress=_log, workers=args.workers,
                   scheduler=args.scheduler)
    out = Path(args.out)
    print(f"wrote {shown(out / 'results.json')}, {shown(out / 'report.md')} and one plot per case")


def cmd_run(args):
    """A scene as a job (:mod:`ffrmbs_app.job`): the default scene — the point mass dropped on
    the flexible beam (:mod:`ffrmbs_app.main_job`) — or a TOML scene file / Python model
    script (:mod:`ffrmbs_app.scene_loader`)."""
    from ffrmbs_app.job import run_scene
    from ffrmbs_app.main_job import JobSettings, run_job

    given = {k: getattr(args, k) for k in DEFAULT_SCENE_OPTIONS if getattr(args, k) is not None}
    common = dict(resume=args.resume, checkpoint_every=args.checkpoint_every, export=not args.no_export,
                  no_limits=args.no_limits)
    if args.scene is None:
        if args.set:
            raise FfrmbsError("--set sets values of a scene file; the default scene takes --setup, --modes, ... "
                              "(its scene file is examples/scenes/point_mass_beam.toml)")
        settings = JobSettings(**given, check=not args.no_check)
        summary = run_job(settings, args.out, log=_say, **common)
    else:
        if given:
            raise FfrmbsError(f"--{', --'.join(k.replace('_', '-') for k in given)}: options of the default "
                              f"scene; a scene file sets its own (or --set KEY=VALUE)")
        from ffrmbs_app.scene_loader import load_scene

        overrides = tuple(args.set or ())
        summary = run_scene(lambda: load_scene(args.scene, overrides), args.out, check=not args.no_check, log=_say,
                            **common)
    written = [summary["result_file"]] + [summary[k] for k in ("plot", "paraview") if k in summary]
    print("wrote " + ", ".join(shown(p) for p in written))


def cmd_sweep(args):
    """A parameter sweep of a scene file on a Dask cluster (:mod:`ffrmbs_app.sweeps`)."""
    from ffrmbs_app.sweeps import parse_set, sweep

    table = sweep(args.scene, parse_set(args.set), args.out, zip=args.zip, workers=args.workers,
                  scheduler=args.scheduler, check=args.check, progress=_log)
    failed = [row["run"] for row in table if row["status"] != "complete"]
    out = Path(args.out)
    plots = [name for name in ("sweep.png", "sweep-outputs.png") if (out / name).exists()]
    print(f"wrote {shown(out / 'sweep.csv')}, " + ", ".join(["sweep.json", "sweep.md"] + plots)
          + f" and {shown(out / 'runs')}/")
    if failed:      # the table is written; the status tells a script that not every run completed
        raise FfrmbsError(f"{len(failed)} of {len(table)} runs failed: {', '.join(failed)} (their errors are in "
                          f"{shown(out / 'sweep.csv')}; a second sweep into {shown(out)} runs only those again)")


DEFAULT_SCENE_OPTIONS = ("setup", "modes", "law", "e", "contour", "residual_flexibility", "t_end", "dt")


def cmd_bench(args):
    """All benchmarks in one process (:mod:`validation.bench.runner`); a failed one is an error."""
    from validation.bench.runner import run_benchmarks, split_names

    try:
        summary = run_benchmarks(args.out, args.quick, split_names(args.only))
    except ValueError as exc:
        raise FfrmbsError(str(exc)) from None
    failed = [name for name, entry in summary["benches"].items() if entry["status"] == "failed"]
    if failed:
        raise FfrmbsError(f"benchmark(s) failed: {', '.join(failed)} (see {summary['json']})")


def cmd_plot(args):
    """Plot a result file's outputs, energy and contacts against time (:mod:`ffrmbs_app.plot`)."""
    from ffrmbs_app.plot import plot_result

    print(f"wrote {shown(plot_result(args.result, args.names or None, args.out, overwrite=args.overwrite))}")


def cmd_export(args):
    """Export a result file to ParaView (:mod:`ffrmbs_app.export`)."""
    from ffrmbs_app.export import export_paraview

    pvd = export_paraview(args.result, args.out, every=args.every, bodies=args.body, compress=args.compress)
    print(f"wrote {shown(pvd)} (open it in ParaView: File > Open, Apply, then play)")


def cmd_contour(args):
    """Fit a 2s contour to a face group of a body; print the fit report, write a PNG and
    ParaView files (:mod:`ffrmbs_app.contour_report`)."""
    from preprocess.bodyfiles import read_body

    from ffrmbs_app.contour_report import fit_group, parse_control_points, parse_smoothing, write_contour_files

    control_points = parse_control_points(args.control_points)
    smoothing = parse_smoothing(args.smoothing)
    gf = fit_group(read_body(args.body), args.group, control_points, smoothing, source=args.body)
    print(gf.describe())
    print(gf.report.text())
    print("wrote " + ", ".join(shown(p) for p in write_contour_files(gf, args.out)))


def plain_text(text) -> str:
    """``text`` without reST markup, as a terminal shows it: ``ffrmbs`` and :func:`x`
    become ffrmbs and x."""
    return re.sub(r"(?::[a-z]+:)?`{1,2}([^`]+)`{1,2}", r"\1", text)


def _percent(share) -> str:
    """``share`` (a fraction) as a percentage for an argparse help text (% escaped)."""
    return f"{share:.0%}".replace("%", "%%")


def build_parser():
    from preprocess import limits as mesh_limits
    from preprocess.pipeline import BUILTINS

    from ffrmbs_app import limits as run_limits

    p = argparse.ArgumentParser(prog="ffrmbs", description=plain_text(__doc__.split("\n")[0]))
    p.add_argument("--version", action="version", version=f"ffrmbs {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    pre = sub.add_parser("preprocess", help="mesh -> FE model -> modes -> body files")
    pre.add_argument("input", help="mesh or geometry file (.geo, .step/.stp, .iges/.igs, .msh, .inp) or built-in "
                                   "geometry: "
                                   f"{', '.join(BUILTINS[:-1])} or {BUILTINS[-1]} (input units)")
    pre.add_argument("--modes", type=int, required=True, help="number of elastic modes")
    bc = pre.add_mutually_exclusive_group(required=True)
    bc.add_argument("--clamp", metavar="GROUP", help="clamp this node group (e.g. z0)")
    bc.add_argument("--free", action="store_true", help="free-free modes, rigid-body modes removed")
    pre.add_argument("--units", choices=("si", "si-mm"), default="si",
                     help="units of the input geometry and material (written files are SI); a STEP or IGES "
                          "file is converted from the length unit it states to m (si) or mm (si-mm)")
    pre.add_argument("--density", type=float, required=True, help="kg/m^3 (t/mm^3 for si-mm)")
    pre.add_argument("--young", type=float, required=True, help="Pa (N/mm^2 for si-mm)")
    pre.add_argument("--poisson", type=float, required=True, help="Poisson's ratio, in (-1, 0.5)")
    pre.add_argument("--order", type=int, choices=(1, 2),
                     help="tet4 (1) or tet10 (2) elements for a built-in geometry, a .geo, STEP or IGES file "
                          "(default 2); a .msh or .inp mesh keeps its own order")
    pre.add_argument("--mesh-size", type=float, help="maximum element size, input units (built-in geometries, "
                                                     ".geo, STEP and IGES files; default: half the smallest "
                                                     "dimension of a built-in geometry, 5 for stepped-beam)")
    pre.add_argument("--structured", metavar="NX,NY,NZ",
                     help="box:LX,LY,LZ only: a structured (transfinite) mesh of NX x NY x NZ cells along x, y, z "
                          "(6 tetrahedra each) instead of --mesh-size; every face's nodes then form a grid "
                          "(exact contour interpolation)")
    pre.add_argument("--group", action="append", metavar="NAME=XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
                     help="STEP/IGES only, repeatable: a node group NAME of the CAD faces inside the box (input "
                          "units; e.g. clamp=-1,-1,-1,0.001,1,1 for the faces on x = 0). Named CAD entities and "
                          "the bounding planes x0 .. z1 that hold a face are groups too")
    pre.add_argument("--geometric-stiffness", action="store_true",
                     help="also store the geometric stiffness of the frame's inertia loads (for bodies that spin: "
                          "geometric_stiffening in the FFR body); in body.h5 only")
    pre.add_argument("--mass", choices=("lumped", "consistent"), default="lumped",
                     help="inertia from lumped node masses (default) or the consistent mass matrix "
                          "(written to body.h5 only: the text files hold node masses)")
    pre.add_argument("--out", type=output_dir, required=True, help="output directory")
    pre.add_argument("--no-limits", action="store_true",
                     help=f"mesh and solve even when the mesh is estimated over {mesh_limits.MAX_NODES:.0e} nodes "
                          f"or {_percent(mesh_limits.MEMORY_SHARE)} of the physical memory (preprocess.limits)")
    pre.set_defaults(func=cmd_preprocess)

    info = sub.add_parser("info", help="summary of a body file or directory")
    info.add_argument("path", help="a body: its directory of text files (thesis Sec. 4.2.1) or its body.h5")
    info.add_argument("--units", choices=("si", "si-mm"), default="si", help="units of text files")
    info.set_defaults(func=cmd_info)

    val = sub.add_parser("validate", help="run the validation cases")
    val.add_argument("--quick", action="store_true", help="coarse sweeps (minutes)")
    val.add_argument("--only", action="append", metavar="NAME", help="run only this case (repeatable)")
    val.add_argument("--out", type=output_dir, required=True, help="output directory")
    where = val.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="run the cases as Dask tasks on a local cluster of N single-threaded worker processes")
    where.add_argument("--scheduler", metavar="ADDRESS", help="run the cases on a running Dask scheduler "
                                                               "(e.g. tcp://host:8786)")
    val.add_argument("--stability", action="store_true",
                     help="run the stability suite instead (stiff and extreme cases): stability.json, report.md")
    val.set_defaults(func=cmd_validate)

    run = sub.add_parser("run", help="run a scene: the default (a point mass dropped on a flexible beam, "
                                     "thesis Sec. 5.2), a TOML scene file or a Python model script")
    run.add_argument("scene", nargs="?", help="scene file (.toml) or model script (.py defining scene()); "
                                              "default: the embedded point-mass-on-beam scene")
    run.add_argument("--out", type=output_dir, default="ffrmbs-run", help="output directory (default: ffrmbs-run)")
    run.add_argument("--set", action="append", metavar="KEY=VALUE",
                     help="set a value of the scene file (repeatable): a dotted key such as scene.dt, "
                          "body.beam.modes or contact.impact.e, a TOML value")
    run.add_argument("--resume", action="store_true",
                     help="continue a killed or interrupted run from its checkpoint (OUT/<scene>.h5.ckpt)")
    run.add_argument("--checkpoint-every", type=float, default=60.0, metavar="SECONDS",
                     help="wall seconds between checkpoints (default 60)")
    run.add_argument("--no-check", action="store_true",
                     help="skip the accuracy check: the second run at dt/2 and, for the default scene, the runs "
                          "with twice the modes and with the coarser mesh (the error estimates)")
    run.add_argument("--no-export", action="store_true", help="skip the ParaView export")
    run.add_argument("--no-limits", action="store_true",
                     help=f"run even beyond {run_limits.MAX_STEPS:.0e} time steps or "
                          f"{_percent(run_limits.MEMORY_SHARE)} of the physical memory (ffrmbs_app.limits)")
    default = run.add_argument_group("default scene")
    default.add_argument("--setup", choices=("A", "B"), help="initial position of the point mass (default A)")
    default.add_argument("--modes", type=int, help="elastic modes of the beam (1..40, default 20)")
    default.add_argument("--law", choices=("impact", "penalty"),
                         help="set-valued Newton impact (default) or linear penalty k = 1e7 N/m")
    default.add_argument("--e", type=float, help="coefficient of restitution of the impact law (default 0)")
    default.add_argument("--contour", choices=("2s", "band"), help="top-face contour (default 2s)")
    default.add_argument("--no-residual-flexibility", dest="residual_flexibility", action="store_false",
                         default=None, help="leave out the dropped modes' static compliance at the contact "
                                            "(on by default with the impact law)")
    default.add_argument("--t-end", type=float, help="simulated time [s] (default 0.1)")
    default.add_argument("--dt", type=float, help="time step [s] (default 1e-5)")
    run.set_defaults(func=cmd_run)

    sw = sub.add_parser("sweep", help="run a scene file over a grid of overrides, one run per Dask task "
                                      "(a local cluster, or a running scheduler): table and work-precision plot")
    sw.add_argument("scene", help="scene file (.toml)")
    sw.add_argument("--set", action="append", required=True, metavar="KEY=V1,V2,...",
                    help="a key of the scene file and its values (TOML; commas inside [] or quotes stay), "
                         "e.g. scene.dt=1e-5,5e-6 or body.beam.modes=10,20; repeat for more keys")
    sw.add_argument("--zip", action="store_true",
                    help="take the value lists side by side (equal lengths) instead of every combination")
    sw.add_argument("--out", type=output_dir, required=True,
                    help="output directory: runs/<run>.h5, sweep.csv, sweep.json, sweep.md, sweep.png; "
                         "complete runs in it are kept on a second sweep")
    where = sw.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help="worker processes of a local cluster (default 2)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://host:8786")
    sw.add_argument("--check", action="store_true", help="estimate each run's error with a second run at dt/2")
    sw.set_defaults(func=cmd_sweep)

    bench = sub.add_parser("bench", help="run the benchmarks: tables, target verdicts, JSON")
    bench.add_argument("--out", type=output_dir, default="out/bench", help="output directory (default: out/bench)")
    bench.add_argument("--quick", action="store_true", help="coarse settings of every benchmark")
    bench.add_argument("--only", action="append", metavar="NAME[,NAME]",
                       help="run only these benchmarks (comma-separated or repeated)")
    bench.set_defaults(func=cmd_bench)

    plot = sub.add_parser("plot", help="plot a result file's outputs, energy and contacts against time")
    plot.add_argument("result", help="result file (.h5) of a run")
    plot.add_argument("names", nargs="*", metavar="NAME",
                      help="output names, 'energy' or 'contact:NAME' (default: all outputs and energy)")
    plot.add_argument("--out", help="PNG to write, replaced if it exists (default: a new RESULT-stem-plot.png, "
                                    "-plot-2.png, ... beside RESULT)")
    plot.add_argument("--overwrite", action="store_true", help="without --out: replace RESULT-stem-plot.png")
    plot.set_defaults(func=cmd_plot)

    export = sub.add_parser("export", help="export a result file to ParaView (.pvd + .vtu per sample)")
    export.add_argument("result", help="result file (.h5) of a run")
    export.add_argument("--out", type=output_dir,
                        help="output directory (default: RESULT stem + '-paraview' beside it)")
    export.add_argument("--every", type=int, default=1, metavar="N", help="every N-th sample (default: 1)")
    export.add_argument("--body", action="append", metavar="NAME", help="only this body (repeatable)")
    export.add_argument("--compress", action="store_true", help="zlib-compress the .vtu files (smaller, slower)")
    export.set_defaults(func=cmd_export)

    contour = sub.add_parser("contour", help="fit a 2s contour to a face group of a body: fit report, a PNG of "
                                             "the deviation, ParaView .vtu files")
    contour.add_argument("body", help="body directory or body.h5 (as for ffrmbs info)")
    contour.add_argument("group", help="a node group of the body's surface (ffrmbs info lists them)")
    contour.add_argument("--control-points", metavar="N|NE,NX",
                         help="distinct control points per direction, >= 4 (default: a knot span of about two "
                              "node spacings)")
    contour.add_argument("--smoothing", metavar="S", help="dimensionless thin-plate weight of the fit, >= 0 "
                                                          "(default 1e-6)")
    contour.add_argument("--out", type=output_dir, default="ffrmbs-contour",
                         help="output directory (default: ffrmbs-contour); GROUP-fit.png, GROUP-fit.vtu and "
                              "GROUP-contour.vtu in it are replaced")
    contour.set_defaults(func=cmd_contour)
    return p


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            args.func(args)
    except RunInterrupted as exc:
        print(f"ffrmbs: {exc}; the result file is closed, continue with --resume", file=sys.stderr)
        return 130
    except FfrmbsError as exc:
        print(f"ffrmbs: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ffrmbs: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return _reader_gone()
    try:
        sys.stdout.flush()             # a reader that left after our last line (`| head`)
    except BrokenPipeError:
        return _reader_gone()
    return 0


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A warning as the command line shows it, one line: ``ffrmbs: warning: <message>``."""
    print(f"ffrmbs: warning: {message}", file=sys.stderr if file is None else file)


def _reader_gone():
    """The reader of stdout closed the pipe (``ffrmbs info ... | head``): stop quietly,
    as other command-line tools do, with the shell's status for SIGPIPE (128 + 13).
    stdout is pointed at /dev/null so that the interpreter's final flush cannot fail."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return 141


if __name__ == "__main__":
    sys.exit(main())
