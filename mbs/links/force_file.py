"""Force files (report Appendix A, "Inputting Forces"): nodal forces of a flexible body as
step functions of time (report eq. 9).

The first row holds the times [s]; each further row the forces [N] of one unblocked degree
of freedom at those times, DOF 3j + k for node j (0-based) and direction k = x, y, z, in
increasing order; values separated by blanks. Each column holds from its time until the
next. :class:`mbs.links.loads.NodalForces` and :class:`mbs.modal.StepLoads` read them.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from ffrmbs.errors import InputFileError, ModelError, quote
from preprocess.textfiles import read_text

from mbs.links.step_times import check_times


def _free_dofs(n_nodes, blocked_dofs) -> np.ndarray:
    """Indices of the unblocked DOFs among 0..3N−1 (increasing). ``blocked_dofs``: None,
    a boolean mask (3N,) (True = blocked) or integer DOF indices 3j + k."""
    n_dof = 3 * int(n_nodes)
    if blocked_dofs is None:
        return np.arange(n_dof)
    blocked = np.asarray(blocked_dofs)
    mask = np.zeros(n_dof, dtype=bool)
    if blocked.dtype == bool:
        if blocked.shape != (n_dof,):
            raise ModelError(f"blocked_dofs: a boolean mask needs 3 x {n_nodes} = {n_dof} "
                             f"entries, got shape {blocked.shape}")
        mask = blocked
    elif blocked.size:
        if not np.issubdtype(blocked.dtype, np.integer):
            raise ModelError("blocked_dofs must be a boolean mask or integer DOF indices 3j + k, "
                             f"got dtype {blocked.dtype}")
        if blocked.min() < 0 or blocked.max() >= n_dof:
            raise ModelError(f"blocked_dofs: DOF indices must lie in 0..{n_dof - 1}")
        mask[blocked.ravel()] = True
    return np.flatnonzero(~mask)


def _parse_row(path, lineno, tokens) -> np.ndarray:
    """The numbers of one data line; InputFileError naming the first bad entry."""
    row = np.empty(len(tokens))
    for col, token in enumerate(tokens):
        try:
            row[col] = float(token)
        except ValueError:
            raise InputFileError(path, lineno, f"entry {col + 1} ({quote(token)}) is not a number") from None
    bad = np.flatnonzero(~np.isfinite(row))
    if bad.size:
        raise InputFileError(path, lineno, f"entry {bad[0] + 1} ({quote(tokens[bad[0]])}) is not finite")
    return row


def read_force_file(path, n_nodes, blocked_dofs=None):
    """Read a force file (report Appendix A, "Inputting Forces"; format in the module
    docstring) of a body with ``n_nodes`` nodes.

    ``blocked_dofs``: None, a boolean mask (3N,) (True = blocked) or integer DOF indices
    3j + k; the file holds one row per unblocked DOF, and blocked DOFs get zero force.
    Blanks and tabs in any number separate values; blank lines are skipped.

    Returns ``(times (n_t,) [s], forces (n_t, N, 3) [N])``. Raises
    :class:`~ffrmbs.errors.InputFileError` (path, 1-based line, fault) for a missing or
    empty file, a non-numeric or non-finite entry, a row whose length differs from the
    times row, a wrong number of rows (1 + unblocked DOFs) and non-increasing times.
    """
    path = Path(path)
    free = _free_dofs(n_nodes, blocked_dofs)
    text = read_text(path)
    lines = [(n, line.split()) for n, line in enumerate(text.splitlines(), start=1) if line.strip()]
    if not lines:
        raise InputFileError(path, None, "empty file: expected a row of times and one row "
                             "of forces per unblocked DOF")
    n_t = len(lines[0][1])
    rows = []
    for lineno, tokens in lines:
        row = _parse_row(path, lineno, tokens)
        if row.size != n_t:
            raise InputFileError(path, lineno, f"{row.size} entries, but the times row "
                                 f"(line {lines[0][0]}) has {n_t}")
        rows.append(row)
    expected = 1 + free.size
    counted = (f"expected 1 row of times + {free.size} rows of forces (3 x {n_nodes} nodes "
               f"- {3 * n_nodes - free.size} blocked DOFs)")
    if len(rows) > expected:
        raise InputFileError(path, lines[expected][0], f"{len(rows) - expected} row(s) too many: {counted}")
    if len(rows) < expected:
        raise InputFileError(path, lines[-1][0] + 1, f"the file ends after {len(rows) - 1} "
                             f"rows of forces: {counted}")
    times = rows[0]
    bad = np.flatnonzero(np.diff(times) <= 0.0)
    if bad.size:
        i = bad[0]
        raise InputFileError(path, lines[0][0], f"times must increase strictly, but entry {i + 2} "
                             f"({float(times[i + 1])!r}) follows entry {i + 1} ({float(times[i])!r})")
    full = np.zeros((3 * n_nodes, n_t))
    full[free] = rows[1:]
    return times, np.ascontiguousarray(full.T.reshape(n_t, n_nodes, 3))


def write_force_file(path, times, forces, blocked_dofs=None) -> None:
    """Write ``times`` (n_t,) [s] and nodal ``forces`` (n_t, N, 3) [N] as a force file
    (report Appendix A; format in the module docstring), leaving out the rows of
    ``blocked_dofs`` (as for :func:`read_force_file`), whose forces must be zero.

    Numbers are written in their shortest exact form, so reading gives back the same
    floats. Atomic: a temporary file in the same directory replaces ``path`` at the end.
    """
    times = check_times(times, "write_force_file")
    forces = np.asarray(forces, dtype=float)
    if forces.ndim != 3 or forces.shape[0] != times.size or forces.shape[2] != 3:
        raise ModelError(f"write_force_file: forces must have shape ({times.size}, N, 3), "
                         f"got {forces.shape}")
    if not np.isfinite(forces).all():
        raise ModelError("write_force_file: forces must be finite")
    n_nodes = forces.shape[1]
    free = _free_dofs(n_nodes, blocked_dofs)
    by_dof = forces.reshape(times.size, 3 * n_nodes).T
    blocked = np.setdiff1d(np.arange(3 * n_nodes), free)
    if np.any(by_dof[blocked] != 0.0):
        dof = blocked[np.flatnonzero(np.any(by_dof[blocked] != 0.0, axis=1))[0]]
        raise ModelError(f"write_force_file: DOF {dof} (node {dof // 3}, direction "
                         f"{'xyz'[dof % 3]}) is blocked but carries a force, which the file "
                         "cannot hold")
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            for row in (times, *by_dof[free]):
                f.write(" ".join(map(repr, row.tolist())) + "\n")
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
