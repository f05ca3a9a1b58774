"""The ``ffrmbs`` command line.

Subcommands
-----------
``preprocess``  mesh -> FE model -> modes -> body files (thesis Sec. 4.2.1 text files and body.h5)
``info``        summary of a body (text-file directory or HDF5 file)
``validate``    validation cases: error against run time (see ../DESIGN.md)
``run``         the main job: the point mass dropped on the flexible beam (thesis Sec. 5.2)
``bench``       every benchmark in one process: tables, target verdicts, JSON (validation.bench)

Errors the user can cause (:class:`ffrmbs.errors.FfrmbsError`) are printed as one
line ``ffrmbs: error: …`` and exit with status 2, without a traceback.
"""

from __future__ import annotations

import argparse
import sys
import time

from ffrmbs import __version__
from ffrmbs.errors import FfrmbsError

DEFAULT_MODES = 10  # modes printed by the main job


def _log(msg):
    print(msg, file=sys.stderr, flush=True)


def _stage(label, fn, *args, **kwargs):
    """Run one long step, telling the user what happens and how long it took."""
    _log(f"{label} ...")
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    _log(f"{label}: done in {time.perf_counter() - t0:.2f} s")
    return out


def _preprocess(spec, modes, clamp, units, density, young, poisson, order, mesh_size, out):
    from preprocess.bodyfiles import write_body
    from preprocess.pipeline import Material, build_body, mesh_source, mesh_statistics

    mesh = _stage(f"meshing {spec}", mesh_source, spec, order, mesh_size)
    print(mesh_statistics(mesh))
    params = dict(input=spec, mesh_size=mesh_size)
    body = build_body(mesh, Material(density, young, poisson), modes, clamp=clamp,
                      units=units, params=params, log=_log)
    if out is not None:
        _stage(f"writing body files to {out}", write_body, out, body)
    print(body.frequency_table())
    return body


def cmd_preprocess(args):
    _preprocess(args.input, args.modes, None if args.free else args.clamp, args.units,
                args.density, args.young, args.poisson, args.order, args.mesh_size, args.out)


def cmd_info(args):
    from preprocess.bodyfiles import read_body

    print(read_body(args.path, units=args.units).summary())


def cmd_validate(args):
    from validation import run_validation

    run_validation(args.out, quick=args.quick, only=args.only or None, progress=_log)
    print(f"wrote {args.out}/results.json, {args.out}/report.md and one plot per case")


def cmd_run(args):
    """Main job: the point mass dropped on the flexible beam (:mod:`ffrmbs.main_job`)."""
    from ffrmbs.main_job import JobSettings, run_job

    settings = JobSettings(setup=args.setup, modes=args.modes, law=args.law, e=args.e, contour=args.contour,
                           t_end=args.t_end, dt=args.dt, check=not args.no_check)
    run_job(settings, args.out, log=print)
    print(f"wrote {args.out}/point_mass_beam.h5 and {args.out}/point_mass_beam.png")


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


def build_parser():
    p = argparse.ArgumentParser(prog="ffrmbs", description=__doc__.split("\n")[0])
    p.add_argument("--version", action="version", version=f"ffrmbs {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    pre = sub.add_parser("preprocess", help="mesh -> FE model -> modes -> body files")
    pre.add_argument("input", help="mesh file (.geo, .msh, .inp) or built-in geometry: "
                                   "box:LX,LY,LZ or stepped-beam")
    pre.add_argument("--modes", type=int, required=True, help="number of elastic modes")
    bc = pre.add_mutually_exclusive_group(required=True)
    bc.add_argument("--clamp", metavar="GROUP", help="clamp this node group (e.g. z0)")
    bc.add_argument("--free", action="store_true", help="free-free modes, rigid-body modes removed")
    pre.add_argument("--units", choices=("si", "si-mm"), default="si",
                     help="units of the input geometry and material (written files are SI)")
    pre.add_argument("--density", type=float, required=True, help="kg/m^3 (t/mm^3 for si-mm)")
    pre.add_argument("--young", type=float, required=True, help="Pa (N/mm^2 for si-mm)")
    pre.add_argument("--poisson", type=float, required=True)
    pre.add_argument("--order", type=int, choices=(1, 2), default=2, help="tet4 (1) or tet10 (2)")
    pre.add_argument("--mesh-size", type=float, help="maximum element size, input units")
    pre.add_argument("--out", required=True, help="output directory")
    pre.set_defaults(func=cmd_preprocess)

    info = sub.add_parser("info", help="summary of a body file or directory")
    info.add_argument("path")
    info.add_argument("--units", choices=("si", "si-mm"), default="si", help="units of text files")
    info.set_defaults(func=cmd_info)

    val = sub.add_parser("validate", help="run the validation cases")
    val.add_argument("--quick", action="store_true", help="coarse sweeps (minutes)")
    val.add_argument("--only", action="append", metavar="NAME", help="run only this case (repeatable)")
    val.add_argument("--out", required=True, help="output directory")
    val.set_defaults(func=cmd_validate)

    run = sub.add_parser("run", help="the main job: a point mass dropped on a flexible beam (thesis Sec. 5.2)")
    run.add_argument("--out", default="ffrmbs-run", help="output directory (default: ffrmbs-run)")
    run.add_argument("--setup", choices=("A", "B"), default="A", help="initial position of the point mass")
    run.add_argument("--modes", type=int, default=20, help="elastic modes of the beam (1..750)")
    run.add_argument("--law", choices=("impact", "penalty"), default="impact",
                     help="set-valued Newton impact or linear penalty k = 1e7 N/m")
    run.add_argument("--e", type=float, default=0.0, help="coefficient of restitution of the impact law")
    run.add_argument("--contour", choices=("2s", "band"), default="2s", help="top-face contour")
    run.add_argument("--t-end", type=float, default=0.1, help="simulated time [s]")
    run.add_argument("--dt", type=float, default=1e-5, help="time step [s]")
    run.add_argument("--no-check", action="store_true", help="skip the second run at dt/2 (error estimate)")
    run.set_defaults(func=cmd_run)

    bench = sub.add_parser("bench", help="run the benchmarks: tables, target verdicts, JSON")
    bench.add_argument("--out", default="out/bench", help="output directory (default: out/bench)")
    bench.add_argument("--quick", action="store_true", help="coarse settings of every benchmark")
    bench.add_argument("--only", action="append", metavar="NAME[,NAME]",
                       help="run only these benchmarks (comma-separated or repeated)")
    bench.set_defaults(func=cmd_bench)
    return p


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except FfrmbsError as exc:
        print(f"ffrmbs: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ffrmbs: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
