"""The resources of a job, bounded before anything is allocated: the number of time steps
and the memory of the sample buffers and the per-step trace.

A job (:func:`ffrmbs_app.job.run_scene`) keeps in memory, for its run and for the accuracy
check at Δt/2 (when ``check``): per output sample t, q, u, the outputs, the energies and
each contact's record (active, gap, point, normal, force) — 8 bytes a number; per step
of a Moreau run with ``trace`` the TRACE_KEYS records, each a Python float in a list and
later a copy in an array (TRACE_BYTES each). :func:`check_resources` refuses a job of more
than MAX_STEPS steps or of more memory than MEMORY_SHARE of the machine's physical
memory, saying the numbers and how to lift the limits (``ffrmbs run --no-limits``,
``no_limits=True``; :func:`preprocess.limits.lift`).
"""

from __future__ import annotations

import math

import numpy as np

from ffrmbs.errors import ModelError
from preprocess.limits import lift, physical_memory

MAX_STEPS = 10 ** 8
MEMORY_SHARE = 0.25
TRACE_BYTES = 8 + 24 + 8          # list slot + float object + array entry [bytes]
CONTACT_NUMBERS = 1 + 3 + 3 + 3    # gap, point, normal, force per sample (+ 1 byte "active")
LIFT = lift("no_limits=True")


def estimate(scene, check=True) -> dict:
    """{"steps": time steps of the run (t_end / dt, float: may be huge), "sample_bytes":
    one output sample, "bytes": everything the job holds [bytes]} of a
    :class:`ffrmbs_app.scene.Scene`."""
    from mbs.bodies.body import Frame
    from mbs.integrators.moreau import TRACE_KEYS

    system = scene.system
    steps = scene.t_end / scene.dt
    q0, u0 = system.initial_state()
    outputs = sum(3 if isinstance(spec, Frame) else int(np.size(spec(0.0, q0, u0)))
                  for spec in scene.outputs.values())
    contacts = len(system.contacts)
    numbers = 1 + system.nq + system.nu + outputs + 2 * bool(scene.energies) + CONTACT_NUMBERS * contacts
    sample_bytes = 8 * numbers + contacts
    step_bytes = len(TRACE_KEYS) * TRACE_BYTES if scene.keeps_trace() else 0
    runs = (1, 2) if check else (1,)             # the run at dt, the check at dt/2 (twice the steps)
    total = sum(scene.n_out * sample_bytes + k * steps * step_bytes for k in runs)
    return {"steps": steps, "sample_bytes": sample_bytes, "step_bytes": step_bytes, "bytes": total}


def check_resources(scene, check=True, no_limits=False) -> dict:
    """The :func:`estimate`; ModelError naming the numbers when it is over a limit (module
    docstring) and ``no_limits`` is False."""
    e = estimate(scene, check)
    if no_limits:
        return e
    if not e["steps"] <= MAX_STEPS:
        raise ModelError(f"scene {scene.name!r}: {e['steps']:.3g} time steps (t_end / dt = {scene.t_end:g} s / "
                         f"{scene.dt:g} s) exceed the limit of {MAX_STEPS:.0e}; shorten t_end, raise dt, or {LIFT}")
    memory = physical_memory()
    if memory is not None and e["bytes"] > MEMORY_SHARE * memory:
        raise ModelError(f"scene {scene.name!r}: the run would hold about {_gb(e['bytes'])} in memory "
                         f"({scene.n_out} samples x {e['sample_bytes']} bytes"
                         + (f", {e['steps']:.3g} steps x {e['step_bytes']} bytes of trace" if e["step_bytes"] else "")
                         + (", for the run and its check at dt/2" if check else "")
                         + f"), over {MEMORY_SHARE:.0%} of the machine's {_gb(memory)}; lower n_out, shorten t_end, "
                         f"or {LIFT}")
    return e


def _gb(n) -> str:
    return f"{n / 1e9:.3g} GB" if math.isfinite(n) else f"{n} bytes"
