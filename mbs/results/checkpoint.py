"""Checkpoints of a running simulation: the run's state written as named arrays in a
``.npz`` file — never a pickle — from which a run rebuilt from its inputs continues bit
for bit as if never stopped.

What a checkpoint holds (:func:`snapshot`), each entry an array under a path-like name:

- ``data/…``: every array and scalar of the run's :class:`~mbs.run.model.Data` (t, q, u,
  the contact flags and warm starts, the factors of a constant M̂, counters, …), the
  contours' and contacts' run state among them (``data/contact_f``, ``data/contact_i``:
  their state vectors, contact points, kinematics, searches' warm starts and counters,
  :mod:`mbs.run.contact_state`);
- ``integrator/…``: Moreau's per-step trace rows (:meth:`~mbs.integrators.driver.Integrator.collect`;
  what an integrator carries from step to step — counters, generalized-α's u̇, ā, λ, the
  adaptive step's next step size and last penetration — is Data's, ``data/integrator/…``);
- ``run/…``: where the sampling stands (:class:`~mbs.integrators.driver.RunState`: next
  landing, samples recorded, CPU seconds so far, earlier resumes) and ``result/…`` the
  samples so far (rows [0, recorded) of t, q, u, outputs, energies, contact records);
  ``monitor/…`` the spin warnings given;
- ``header``: JSON (as bytes) — the format and version, the kinds of the entries
  (:mod:`mbs.results.codec`), what identifies the run (integrator and options, Δt,
  t_end, output count, bodies with their coordinate counts, contacts, outputs, the
  scene plan) and the recorder's position (samples and trace rows in the result file).

Resuming (:meth:`Checkpoint.restore`) rebuilds nothing from the file: the caller makes
the run again from its inputs (the scene, its plan re-made deterministically, the Model
recompiled), and the arrays are loaded into the fresh Data and integrator, each checked by
name, shape and dtype against them; a checkpoint of another scene, integrator or mode
count is refused with one line naming the file and the first mismatch.

Integrity. The file is read with ``numpy.load(allow_pickle=False)``: only numeric,
boolean and text arrays, no object can be built, so nothing in a checkpoint runs code
when read (the signature older, pickled checkpoints needed is gone with the pickle).
Writes are atomic (temporary file, fsync, rename): a kill at any moment leaves the
previous checkpoint or the new one. A file cut short or damaged otherwise is refused by
the zip structure and the CRC-32 that zip keeps of every array; only uncompressed
members are accepted, so no entry inflates beyond the file's size. A deliberately
edited checkpoint can only set another state of the same run (names, shapes and dtypes
must fit): it can do no more than editing the scene can. An older checkpoint (the
pickled formats with the headers ``ffrmbs-checkpoint-1``/``-2``) is refused unread.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, quote
from preprocess.inputfiles import regular_file

from mbs.results import codec
from mbs.results.codec import StateMismatch, put

FORMAT, FORMAT_VERSION = "ffrmbs-checkpoint", 4
PICKLED_FORMATS = (b"ffrmbs-checkpoint-1\n", b"ffrmbs-checkpoint-2\n")    # the older formats: pickles
HEADER = "header"


def fingerprint(integ) -> dict:
    """What identifies a run (a checkpoint resumes only the same run): integrator and
    options, Δt [s], t_end [s], samples, bodies (name, nq, nu), contacts, outputs,
    energies and contact records kept, the scene plan (as JSON values)."""
    st, sys = integ.state, integ.system
    run = {"integrator": integ.name, "options": integ.options(), "dt": integ.dt, "t_end": float(st.times[-1]),
           "samples": len(st.times), "bodies": [[b.name, b.nq, b.nu] for b in sys.bodies],
           "contacts": [c.name for c in sys.contacts], "outputs": list(st.probes), "energies": st.energies,
           "contact_records": st.contacts, "plan": st.result.plan}
    return json.loads(json.dumps(run, default=str))


def snapshot(integ, recorder: dict) -> tuple[dict, dict]:
    """(header, arrays) of the run of ``integ`` at an output sample (module docstring);
    ``recorder``: its position {"samples", "trace_rows"} in the result file."""
    arrays, kinds = {}, {}
    st, res = integ.state, integ.state.result
    integ.data.collect("data", arrays, kinds)
    integ.collect("integrator", arrays, kinds)
    n = st.recorded
    run = {"run/next_landing": st.next_landing, "run/recorded": n, "run/cpu_s": st.cpu_s,
           "run/resumed_steps": st.resumed_steps, "run/resumed_at": np.array(st.resumed_at, dtype=float),
           "result/modal_cpu_s": res.stats.get("modal_cpu_s", 0.0),
           "result/t": res.t[:n], "result/q": res.q[:n], "result/u": res.u[:n]}
    run.update({f"result/outputs/{name}": v[:n] for name, v in res.outputs.items()})
    run.update({f"result/energy/{key}": v[:n] for key, v in res.energy.items()})
    run.update({f"result/contacts/{name}/{key}": v[:n] for name, rec in res.contacts.items() for key, v in rec.items()})
    events = integ.monitor.events
    run.update({"monitor/t": np.array([e[0] for e in events], dtype=float),
                "monitor/body": np.array([e[1] for e in events], dtype=str),
                "monitor/spin": np.array([e[2] for e in events], dtype=float),
                "monitor/omega1": np.array([e[3] for e in events], dtype=float)})
    for key, value in run.items():
        put(key, value, arrays, kinds)
    header = {"format": FORMAT, "format_version": FORMAT_VERSION, "run": fingerprint(integ), "kinds": kinds,
              "recorder": dict(recorder)}
    return header, arrays


def write_checkpoint(path, integ, recorder: dict) -> None:
    """Write the :func:`snapshot` of ``integ`` to ``path`` atomically (``.npz``,
    uncompressed)."""
    path = Path(path)
    header, arrays = snapshot(integ, recorder)
    arrays[HEADER] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


class Checkpoint:
    """A checkpoint read by :func:`read_checkpoint`: ``path``, ``header`` (dict) and
    ``arrays`` ({name: array})."""

    def __init__(self, path, header, arrays):
        self.path, self.header, self.arrays = Path(path), header, arrays

    @property
    def recorder(self) -> dict:
        """The recorder's position when it was taken: {"samples", "trace_rows"}."""
        return self.header.get("recorder", {})

    def refuse(self, why) -> InputFileError:
        return InputFileError(self.path, None, f"a checkpoint of another run: {why}; restart the run")

    def restore(self, integ) -> None:
        """Load the state into ``integ``, whose run was just prepared from the same
        inputs (compiled Model, fresh Data, sampling plan; not yet started).
        InputFileError (one line: the file and the first mismatch) if it is another run."""
        ours, theirs = fingerprint(integ), self.header.get("run", {})
        for key, value in ours.items():
            if theirs.get(key) != value:
                raise self.refuse(f"its {key} is {quote(json.dumps(theirs.get(key)), 60)}, this run's "
                                  f"{quote(json.dumps(value), 60)}")
        try:
            integ.data.restore("data", self.arrays, self.kinds)
            integ.start(integ.t, integ.q, integ.u)       # the integrator's workspaces, at the saved state
            integ.data.restore("data", self.arrays, self.kinds)     # what starting changed, back as saved
            integ.restore("integrator", self.arrays, self.kinds)
            self._run(integ)
        except StateMismatch as exc:
            raise self.refuse(str(exc)) from None

    @property
    def kinds(self) -> dict:
        return self.header.get("kinds", {})

    def _run(self, integ):
        """RunState, the samples so far and the spin warnings."""
        take = lambda key, current=None: codec.take(key, current, self.arrays, self.kinds)  # noqa: E731
        st, res = integ.state, integ.state.result
        st.next_landing, st.recorded = take("run/next_landing", 0), take("run/recorded", 0)
        st.cpu_s, st.resumed_steps = take("run/cpu_s", 0.0), take("run/resumed_steps", 0)
        st.resumed_at = take("run/resumed_at").tolist()
        res.stats["modal_cpu_s"] = take("result/modal_cpu_s", 0.0)
        n, total = st.recorded, len(st.times)
        if not 0 <= n <= total or not 0 <= st.next_landing <= len(st.landings):
            raise StateMismatch(f"{n} samples recorded of {total}")
        for name, rows in (("t", res.t), ("q", res.q), ("u", res.u)):
            _rows(f"result/{name}", take(f"result/{name}"), rows, n)
        for group, store in (("outputs", res.outputs), ("energy", res.energy)):
            at = f"result/{group}/"
            for key in (k for k in self.kinds if k.startswith(at)):
                saved = take(key)
                store[key[len(at):]] = np.full((total,) + saved.shape[1:], np.nan)
                _rows(key, saved, store[key[len(at):]], n)
        for name, rec in res.contacts.items():
            for key, rows in rec.items():
                _rows(f"result/contacts/{name}/{key}", take(f"result/contacts/{name}/{key}"), rows, n)
        integ.monitor.restore([(float(t), str(b), float(w), float(w1)) for t, b, w, w1 in
                               zip(take("monitor/t"), take("monitor/body"), take("monitor/spin"),
                                   take("monitor/omega1"))])


def _rows(key, saved, rows, n):
    """rows[:n] = saved, after checking its shape and dtype."""
    if saved.shape != (n,) + rows.shape[1:] or saved.dtype != rows.dtype:
        raise StateMismatch(f"{key} has shape {saved.shape} {saved.dtype}, this run's {(n,) + rows.shape[1:]} "
                            f"{rows.dtype}")
    rows[:n] = saved


def read_checkpoint(path) -> Checkpoint:
    """The checkpoint at ``path``; InputFileError (one line) if it is missing, not a
    regular file, an older pickled checkpoint (refused unread), damaged or not an ffrmbs
    checkpoint. Nothing in the file is executed (module docstring)."""
    path = regular_file(path)
    try:
        with open(path, "rb") as f:
            head = f.read(max(len(m) for m in PICKLED_FORMATS))
        if head.startswith(PICKLED_FORMATS):
            raise InputFileError(path, None, f"a pickled checkpoint of an older ffrmbs "
                                             f"({head.decode().strip()}): refused unread (unpickling could run "
                                             "code); restart the run")
        with np.load(path, allow_pickle=False) as npz:
            if not isinstance(npz, np.lib.npyio.NpzFile):
                raise ValueError("a single array")
            for info in npz.zip.infolist():
                if info.compress_type != zipfile.ZIP_STORED:
                    raise ValueError(f"compressed member {info.filename!r}")
            arrays = {name: npz[name] for name in npz.files}
        header = json.loads(bytes(arrays.pop(HEADER)).decode()) if HEADER in arrays else {}
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read the checkpoint ({exc.strerror or exc})") from None
    except (ValueError, KeyError, EOFError, zipfile.BadZipFile, UnicodeDecodeError) as exc:
        raise InputFileError(path, None, f"not an ffrmbs checkpoint, or damaged ({type(exc).__name__}: "
                                         f"{quote(exc, 60)})") from None
    if not (isinstance(header, dict) and header.get("format") == FORMAT):
        raise InputFileError(path, None, "not an ffrmbs checkpoint (no header)")
    if header.get("format_version") != FORMAT_VERSION:
        raise InputFileError(path, None, f"a checkpoint of format version {quote(header.get('format_version'))}, "
                                         f"this ffrmbs reads {FORMAT_VERSION}; restart the run")
    return Checkpoint(path, header, arrays)
