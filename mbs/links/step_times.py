"""The time axis of tabulated loads: a table's rows hold from their time until the next
(step functions of report eq. 9), used by :class:`mbs.links.loads.Tabulated`,
:class:`mbs.links.loads.NodalForces` and the force files of :mod:`mbs.links.force_file`."""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError


def check_times(times, what) -> np.ndarray:
    """``times`` [s] as a finite, strictly increasing (n_t,) float array, else a
    ModelError that starts with ``what`` (the table or function being checked)."""
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0:
        raise ModelError(f"{what}: times must be a non-empty 1-D array, got shape {times.shape}")
    if not np.isfinite(times).all():
        raise ModelError(f"{what}: times must be finite")
    bad = np.flatnonzero(np.diff(times) <= 0.0)
    if bad.size:
        i = bad[0]
        raise ModelError(f"{what}: times must increase strictly, but times[{i + 1}] = "
                         f"{float(times[i + 1])!r} s follows times[{i}] = {float(times[i])!r} s")
    return times


def step_index(times, t) -> int:
    """The row j with times[j] <= t < times[j+1] (the last row from times[-1] on), or −1
    before times[0]: the step functions of report eq. 9 with h(0) = 1."""
    return int(np.searchsorted(times, t, side="right")) - 1
