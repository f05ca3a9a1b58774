"""Kill -9 audit of ``ffrmbs run``: a run killed at any moment leaves a readable result
file, and resumes bit for bit whenever a checkpoint exists.

    python3 -m qa.kill_audit --kills 20 --out DIR [--t-end 0.6] [--seed 18]

First one uninterrupted run of the default scene (``ffrmbs run --no-check --no-export
--checkpoint-every 0.5 --t-end T`` in ``DIR/reference``) gives the oracle and the
timeline: when its result file appeared and when it ended (wall seconds from the
start of the process). Then, per kill, the same command in ``DIR/kill<k>`` is sent
SIGKILL at a random moment (``--seed``) counted from the moment its own result file
appears (start-up times vary most under load): uniform from one second before it to 0.9
of the reference's time from the file to the end, the first kill at the very moment the
file appears.
After each kill: is the file readable (:func:`mbs.results.result_file.load_result`) and
consistent (every per-sample dataset of one length), how many samples it holds, is
there a checkpoint; if there is, ``--resume`` finishes the run and its datasets are
compared bitwise with the reference's. ``--no-check`` and ``--no-export`` leave out the
Δt/2 run and the export, which start after the result file is complete.

Prints a table (moment [s], phase, readable, samples, checkpoint, resumed bit-identical),
writes it with the details to ``DIR/kill_audit.json`` and exits 1 if a file was
unreadable or a resumed run differs.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py

from ffrmbs.errors import FfrmbsError
from mbs.results.result_file import datasets, load_result, per_sample

NAME = "point_mass_beam.h5"
ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


def command(out: Path, t_end: float, *extra) -> list[str]:
    return [sys.executable, "-m", "ffrmbs_app.cli", "run", "--no-check", "--no-export", "--checkpoint-every", "0.5",
            "--t-end", repr(t_end), "--out", str(out), *extra]


def arrays(path) -> dict:
    """{name: array} of every dataset of an HDF5 file."""
    with h5py.File(path, "r") as f:
        return {name: obj[()] for name, obj in datasets(f)}


def bitwise_equal(a, b) -> bool:
    """The same datasets, dtypes, shapes and bytes in the two files."""
    da, db = arrays(a), arrays(b)
    return sorted(da) == sorted(db) and all(
        da[k].dtype == db[k].dtype and da[k].shape == db[k].shape and da[k].tobytes() == db[k].tobytes() for k in da)


def inspect(path: Path) -> dict:
    """Readable, consistent and how many samples: the state of a killed run's file."""
    if not path.exists():
        return {"readable": "no file", "samples": 0}
    try:
        res, attrs = load_result(path)
    except FfrmbsError as exc:
        return {"readable": f"NO: {exc}", "samples": 0}
    with h5py.File(path, "r") as f:
        lengths = {name: obj.shape[0] for name, obj in datasets(f) if per_sample(name)}
        trace = {obj.shape[0] for name, obj in datasets(f) if name.startswith("trace/")}
    consistent = set(lengths.values()) == {len(res.t)} and len(trace) <= 1
    return {"readable": "yes" if consistent else "NO: datasets of different lengths", "samples": len(res.t),
            "status": str(attrs.get("status"))}


def reference_run(out: Path, t_end: float) -> dict:
    """The uninterrupted run: its file and its timeline (file appeared, ended) [s]."""
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.monotonic()
    proc = subprocess.Popen(command(out, t_end), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=ENV)
    appeared = None
    while proc.poll() is None:
        if appeared is None and (out / NAME).exists():
            appeared = time.monotonic() - t0
        time.sleep(0.001)
    ended = time.monotonic() - t0
    if proc.returncode != 0:
        raise SystemExit(f"the reference run failed: {proc.stderr.read().decode()}")
    return {"path": out / NAME, "appeared_s": appeared, "ended_s": ended}


def kill_once(out: Path, t_end: float, moment: float, appeared: float, reference: Path) -> dict:
    """Start the run, SIGKILL it ``moment`` [s] after its result file appears (a negative
    moment: that long before the reference's file appeared, ``appeared`` [s] after the
    start), inspect the file, resume from a checkpoint and compare."""
    shutil.rmtree(out, ignore_errors=True)
    path, ckpt = out / NAME, out / (NAME + ".ckpt")
    t0 = time.monotonic()
    proc = subprocess.Popen(command(out, t_end), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    if moment < 0:
        time.sleep(max(0.0, appeared + moment))
    else:
        while not path.exists() and proc.poll() is None:
            time.sleep(0.0005)
        time.sleep(moment)
    finished = proc.poll() is not None
    if not finished:
        os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    row = {"moment_s": round(time.monotonic() - t0, 3), **inspect(path), "checkpoint": ckpt.exists()}
    row["phase"] = ("finished first" if finished else "before the file" if not path.exists()
                    else "before the first sample flush" if row["samples"] == 0 else "streaming")
    if row["checkpoint"]:
        res = subprocess.run(command(out, t_end, "--resume"), capture_output=True, text=True, env=ENV)
        row["resumed"] = ("yes" if bitwise_equal(reference, path) else "NO: differs") if res.returncode == 0 \
            else f"NO: exit {res.returncode}: {res.stderr.strip()[-200:]}"
    else:
        row["resumed"] = "-"
    return row


def table(rows) -> str:
    lines = ["| kill | moment [s from start] | phase | readable | samples | checkpoint | resumed bit-identical |",
             "|---|---|---|---|---|---|---|"]
    for k, r in enumerate(rows):
        lines.append(f"| {k} | {r['moment_s']:.3f} | {r['phase']} | {r['readable']} | {r['samples']} | "
                     f"{'yes' if r['checkpoint'] else 'no'} | {r['resumed']} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m qa.kill_audit", description=__doc__.split("\n")[0])
    p.add_argument("--kills", type=int, default=20, help="number of kills (default 20)")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--t-end", type=float, default=0.6, help="simulated time of the default scene [s] (default 0.6)")
    p.add_argument("--seed", type=int, default=18, help="seed of the random moments (default 18)")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ref = reference_run(out / "reference", args.t_end)
    print(f"reference: file appeared at {ref['appeared_s']:.2f} s, run ended at {ref['ended_s']:.2f} s", flush=True)
    rng = random.Random(args.seed)
    running = ref["ended_s"] - ref["appeared_s"]
    moments = [0.0] + [rng.uniform(-1.0, 0.9 * running) for _ in range(args.kills - 1)]
    rows = []
    for k, moment in enumerate(moments[:args.kills]):
        rows.append(kill_once(out / f"kill{k}", args.t_end, moment, ref["appeared_s"], ref["path"]))
        print(f"kill {k}: {rows[-1]}", flush=True)
    text = table(rows)
    print(text)
    (out / "kill_audit.json").write_text(json.dumps({"reference": {k: str(v) for k, v in ref.items()},
                                                     "t_end_s": args.t_end, "seed": args.seed, "kills": rows},
                                                    indent=1) + "\n")
    bad = [r for r in rows if r["readable"] not in ("yes", "no file") or r["resumed"].startswith("NO")]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
