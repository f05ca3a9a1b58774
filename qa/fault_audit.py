"""The fault audit: bad inputs through the command line, each classified by what the user sees.

``python3 -m qa.fault_audit --out DIR [--only KIND] [--jobs N] [--timeout S]`` (from the
repository's root) writes over a hundred bad inputs (:mod:`qa.fault_cases`) into
``DIR/cases/<case>/`` and runs each through ``python3 -m ffrmbs_app.cli ...`` in its own
process group (``FFRMBS_PROGRESS=0``, a time limit and an address-space limit of
:data:`MEMORY_LIMIT` bytes, so that a run that would eat the machine dies instead). Each
case is classified (:func:`classify`) as

``clear``      exit status non-zero, no ``Traceback`` on stderr, and stderr's last non-empty
               line is one message of at most :data:`MAX_MESSAGE` characters starting with
               ``ffrmbs: error:`` (or argparse's ``ffrmbs <command>: error:``) that names
               the file or key at fault (one of the case's expected substrings);
``traceback``  a Python traceback on stderr;
``unclear``    non-zero exit otherwise (a multi-line, long or unspecific message, a signal);
``silent``     exit status 0: the bad input was accepted;
``hang``       no exit within the time limit (the process group is killed).

A case that plants code (a pickle whose ``__reduce__`` runs ``touch MARKER``) is
``silent`` whenever the marker exists afterwards, whatever the exit status, and is flagged
``EXECUTED``.

Valid controls run first (:func:`qa.fault_cases.controls`): the base scene, body and meshes
each run cleanly, so a case's outcome is due to its one fault. Results: a table and counts
on stdout, ``DIR/audit.json`` and ``DIR/audit.md``. Exit status 0 when every case is
``clear`` and every control passed, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from qa.fault_cases import KINDS, Case, all_cases, build_shared, controls
from validation.report import cell, write_atomic

OUTCOMES = ("clear", "traceback", "unclear", "silent", "hang")
TIMEOUT = 60.0                  # [s] per case
MEMORY_LIMIT = 4 << 30          # [bytes] address space per case
MAX_MESSAGE = 300               # [characters] of a clear message
ERROR_PREFIX = "ffrmbs: error:"


# --- the classification ----------------------------------------------------------------------

@dataclass
class Outcome:
    """The result of one case: its classification, exit status, wall seconds and the
    message (stderr's last non-empty line)."""

    case: str
    kind: str
    outcome: str
    returncode: int | None
    seconds: float
    message: str
    argv: list = field(default_factory=list)
    executed: bool = False


def classify(returncode, stderr: str, expect, timed_out=False, executed=False, case_dir="") -> tuple[str, str]:
    """(outcome, message) of one case (module docstring): ``returncode`` of the process (None
    when it timed out), its ``stderr`` text, ``expect`` the substrings a clear message
    names, ``executed`` whether planted code ran. The message's length is counted with the
    case's directory ``case_dir`` (part of every path it names) left out, so that the
    outcome does not depend on where the audit writes."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    message = lines[-1] if lines else ""
    if executed:
        return "silent", "EXECUTED: planted code ran; " + message
    if timed_out:
        return "hang", message
    if returncode == 0:
        return "silent", message
    if "Traceback" in stderr:
        return "traceback", message
    prefix = message.split(":", 1)[0] + ":" if ":" in message else ""
    argparse_error = prefix.startswith("ffrmbs ") and message[len(prefix):].startswith(" error:")
    if returncode < 0:
        return "unclear", f"killed by {signal.Signals(-returncode).name}; " + message
    length = len(message.replace(str(case_dir).rstrip("/") + "/", "")) if case_dir else len(message)
    clear = ((message.startswith(ERROR_PREFIX) or argparse_error) and length <= MAX_MESSAGE
             and any(_words(e.lstrip("-")) in _words(message) for e in expect))
    return ("clear" if clear else "unclear"), message


def _words(s: str) -> str:
    """``s`` lower-cased with '-' and '_' as spaces, so that "mesh-size" (of "--mesh-size"),
    "mesh_size" and "Mesh size" match."""
    return s.lower().replace("-", " ").replace("_", " ")


# --- running ---------------------------------------------------------------------------------

LAUNCH = ("import resource, runpy; resource.setrlimit(resource.RLIMIT_AS, ({0}, {0})); "
          "runpy.run_module('ffrmbs_app.cli', run_name='__main__', alter_sys=True)").format(MEMORY_LIMIT)
"""``python3 -c LAUNCH ARGS`` is ``python3 -m ffrmbs_app.cli ARGS`` with the address space bounded
(set in the child itself: ``preexec_fn`` is unsafe beside the runner's threads)."""


def run_case(case: Case, root: Path, timeout=TIMEOUT) -> Outcome:
    """Build ``case``'s files under ``root/cases/<name>/``, run it and classify it."""
    where = case.paths(root)
    case_dir = Path(where["case"])
    shared = Path(where["shared"])
    case_dir.mkdir(parents=True)
    for rel, build in case.files:
        build(case_dir / rel, shared)
    argv = [a.format(**where) for a in case.argv]
    env = dict(os.environ, FFRMBS_PROGRESS="0")
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-c", LAUNCH, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, env=env, start_new_session=True, cwd=case_dir)
    try:
        _, err = proc.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        _, err = proc.communicate()
        timed_out = True
    seconds = time.perf_counter() - t0
    stderr = err.decode("utf-8", errors="replace")
    executed = case.marker is not None and (case_dir / case.marker).exists()
    outcome, message = classify(None if timed_out else proc.returncode, stderr, case.expect, timed_out, executed,
                                case_dir)
    return Outcome(case.name, case.kind, outcome, None if timed_out else proc.returncode, seconds, message, argv,
                   executed)


def run_audit(root, only=None, jobs=2, timeout=TIMEOUT, log=print) -> dict:
    """Run the controls, then every case (of kind ``only`` if given) on ``jobs`` processes;
    write ``root/audit.json`` and ``root/audit.md``; return the document."""
    root = Path(root).resolve()
    for sub in ("cases", "shared"):
        shutil.rmtree(root / sub, ignore_errors=True)
    (root / "shared").mkdir(parents=True)
    build_shared(root / "shared")
    chosen = [c for c in all_cases() if only is None or c.kind == only]
    first, *rest = controls()
    checks = [run_case(first, root, timeout)]          # the seed result file, before the cases copying it
    if checks[0].returncode != 0:
        raise SystemExit(f"fault audit: the default scene does not run cleanly ({checks[0].message}); "
                         f"nothing audited")
    with ThreadPoolExecutor(max(1, jobs)) as pool:
        checks += list(pool.map(lambda c: run_case(c, root, timeout), rest))
        for check in checks:
            check.outcome = "ok" if check.returncode == 0 else "failed"
            log(f"control {check.case}: {check.outcome} ({check.seconds:.1f} s) {check.message[:100]}")
        results = []
        for result in pool.map(lambda c: run_case(c, root, timeout), chosen):
            results.append(result)
            log(f"{result.case:44s} {result.kind:6s} {result.outcome:9s} {result.message[:100]}")
    doc = {"counts": dict(Counter(r.outcome for r in results)), "tried": len(results),
           "by_kind": {kind: dict(Counter(r.outcome for r in results if r.kind == kind))
                       for kind in KINDS if any(r.kind == kind for r in results)},
           "executed": [r.case for r in results if r.executed],
           "controls": [vars(c) for c in checks], "cases": [vars(r) for r in results],
           "limits": {"timeout_s": timeout, "memory_bytes": MEMORY_LIMIT}}
    doc["counts"] = {k: doc["counts"].get(k, 0) for k in OUTCOMES}
    write_atomic(root / "audit.json", lambda f: f.write(json.dumps(doc, indent=1).encode()))
    write_atomic(root / "audit.md", lambda f: f.write(markdown(doc).encode()))
    return doc


def summary_line(doc) -> str:
    c = doc["counts"]
    return (f"bad inputs tried {doc['tried']}: clear {c['clear']}, traceback {c['traceback']}, "
            f"unclear {c['unclear']}, silent {c['silent']}, hang {c['hang']}"
            + (f"; EXECUTED planted code: {', '.join(doc['executed'])}" if doc["executed"] else ""))


def markdown(doc) -> str:
    lines = ["# Fault audit", "", summary_line(doc), "",
             f"Limits per case: {doc['limits']['timeout_s']:g} s, {doc['limits']['memory_bytes'] / 2**30:g} GiB "
             "address space.", "", "| kind | " + " | ".join(OUTCOMES) + " |", "|---" * (len(OUTCOMES) + 1) + "|"]
    lines += [f"| {kind} | " + " | ".join(str(counts.get(o, 0)) for o in OUTCOMES) + " |"
              for kind, counts in doc["by_kind"].items()]
    failed = [c for c in doc["controls"] if c["outcome"] != "ok"]
    lines += ["", f"Controls (valid inputs): {len(doc['controls']) - len(failed)} of {len(doc['controls'])} ran cleanly"
              + (": failed " + ", ".join(c["case"] for c in failed) if failed else "."), "",
              "| case | kind | outcome | exit | s | message |", "|---|---|---|---|---|---|"]
    lines += [f"| {cell(r['case'])} | {r['kind']} | {r['outcome']} | {cell(r['returncode'])} | {r['seconds']:.1f} | "
              f"{cell(r['message'][:100])} |" for r in doc["cases"]]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python3 -m qa.fault_audit", description=__doc__.split("\n")[0])
    p.add_argument("--out", required=True, help="directory for the cases, audit.json and audit.md")
    p.add_argument("--only", choices=KINDS, help="run only the cases of this kind")
    p.add_argument("--jobs", type=int, default=2, help="cases run at once (default 2)")
    p.add_argument("--timeout", type=float, default=TIMEOUT, help=f"seconds per case (default {TIMEOUT:g})")
    args = p.parse_args(argv)
    doc = run_audit(args.out, args.only, args.jobs, args.timeout)
    print(summary_line(doc))
    print(f"wrote {Path(args.out) / 'audit.json'} and {Path(args.out) / 'audit.md'}")
    failed = [c for c in doc["controls"] if c["outcome"] != "ok"]
    if failed:
        print(f"controls failed: {', '.join(c['case'] for c in failed)}: the audit's outcomes are not meaningful")
    return 0 if not failed and doc["counts"]["clear"] == doc["tried"] else 1


if __name__ == "__main__":
    sys.exit(main())
