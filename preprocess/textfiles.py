"""The thesis's four text body files (Sec. 4.2.1, Listings 4.1-4.5).

A body of N nodes and n_f modes is stored in one directory as (indices 1-based):

``u0.dat`` (Listing 4.1)
    N rows ``x  y  z`` — undeformed node positions [length], row i = node i.
``modeShapeMatrix.dat`` (Listing 4.2)
    3N rows of n_f values — row 3(i-1)+k is node i, DOF k (k = 1, 2, 3); one
    column per mode; clamped nodes have zero rows.
``mij.dat`` (Listing 4.3)
    N rows — lumped node masses [mass].
``stiffnessMatrix.dat`` (Listings 4.4-4.5)
    rows ``a,b, c,d, e``: K[3(a-1)+b, 3(c-1)+d] = e [force/length] (1-based).

Reading is tolerant of files written by other tools: ``%`` and ``#`` comments
(whole-line or trailing), blank lines, tabs / spaces / commas in any mix as
separators, Fortran exponents (``1.0E+05``, ``1.0D+05``, ``1.0d-3``, ``1.0-100``).
Every value must be finite and at most :data:`~preprocess.body.MAX_MAGNITUDE` in
magnitude. The stiffness file may hold the lower triangle, the upper triangle or the
full matrix: an entry present on both sides must agree (relative tolerance 1e-9 of
max|K|); in a file holding one triangle each entry is mirrored, a file holding entries
of both triangles is full storage and must hold both entries of every pair (an entry
without its mirror there is a fault, not a guess). Only regular files are read
(:mod:`preprocess.inputfiles`). Every fault raises
:class:`~ffrmbs.errors.InputFileError` with the 1-based line (None for faults of the
whole file); file content in a message is a short sanitized quote
(:func:`ffrmbs.errors.quote`).

Units (see :mod:`preprocess.units`): with ``units="si-mm"`` positions are read in
mm, masses in t and K in N/mm, and converted to SI. Mode shapes carry no unit of
their own; the rule is: if the file's modes are mass-normalized in the file's
units (max|Φᵀ M Φ − I| < 1e-6, M = the file's lumped masses, each repeated for
its 3 DOFs), they are divided by sqrt(mass factor) (sqrt(1000) for si-mm) so that
they stay mass-normalized in SI; otherwise (e.g. displacement-normalized,
dimensionless) they are kept unchanged. Writing applies the inverse conversions.

Writing uses the listings' layout: tab-separated columns, a trailing comment
``% node: i`` (``% node: i, DOF: k`` for modes), numbers as ``repr(float)``
(shortest exact form, so text <-> BodyData round trips are bitwise exact in SI),
and the stiffness matrix's lower triangle (row >= column) column by column, as
Listing 4.5 shows.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ffrmbs.errors import InputFileError, ModelError, quote
from preprocess.body import MAX_MAGNITUDE, SYMMETRY_RTOL, BodyData, mass_normalized
from preprocess.inputfiles import regular_file
from preprocess.units import unit_system

U0_FILE = "u0.dat"
MODES_FILE = "modeShapeMatrix.dat"
MASSES_FILE = "mij.dat"
STIFFNESS_FILE = "stiffnessMatrix.dat"
TEXT_FILES = (U0_FILE, MODES_FILE, MASSES_FILE, STIFFNESS_FILE)


_NUMBER = re.compile(
    r"(?P<mantissa>[+-]?(?:\d+\.?\d*|\.\d+))(?:[eEdD](?P<exp>[+-]?\d+)|(?P<fortran>[+-]\d{3}))?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


def read_text(path: Path) -> str:
    """The text of the regular file ``path``; a missing, special or unreadable file
    raises InputFileError."""
    try:
        return regular_file(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputFileError(path, None, f"cannot read file: {exc.strerror}") from None


def _data_rows(path: Path) -> list[tuple[int, list[str]]]:
    """(1-based line number, tokens) of every data row of a text file; at least one."""
    text = read_text(path)
    rows = []
    for lineno, line in enumerate(text.split("\n"), start=1):
        tokens = line.split("%", 1)[0].split("#", 1)[0].replace(",", " ").split()
        if tokens:
            rows.append((lineno, tokens))
    if not rows:
        raise InputFileError(path, None, "no data rows (empty file)")
    return rows


def _number(token: str, path: Path, lineno: int) -> float:
    """A finite float from a (possibly Fortran-style) number token."""
    match = _NUMBER.fullmatch(token)
    if match is None:
        fault = ("non-finite value" if _NON_FINITE.fullmatch(token)
                 else "cannot parse number")
        raise InputFileError(path, lineno, f"{fault} {quote(token)}")
    exponent = match["exp"] or match["fortran"]
    value = float(match["mantissa"] + ("e" + exponent if exponent else ""))
    if not math.isfinite(value):
        raise InputFileError(path, lineno, f"non-finite value {quote(token)} (overflow)")
    return value


def _table(path, n_cols: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """All data rows as a float array (rows, n_cols) and their line numbers.

    ``n_cols=None`` requires every row to have the column count of the first row.
    Plain numbers are converted in one vectorized pass; only if that fails (Fortran
    exponents, faults) is each token parsed and checked on its own. A value beyond
    MAX_MAGNITUDE is refused with its line.
    """
    path = Path(path)
    rows = _data_rows(path)
    width = n_cols or len(rows[0][1])
    where = "" if n_cols else f" (as on line {rows[0][0]})"
    for lineno, tokens in rows:
        if len(tokens) != width:
            raise InputFileError(
                path, lineno, f"expected {width} columns{where}, found {len(tokens)}")
    lines = np.array([lineno for lineno, _ in rows])
    try:
        table = np.array([tokens for _, tokens in rows], dtype=np.float64)
        if not np.isfinite(table).all():
            raise ValueError("non-finite")
    except ValueError:
        table = np.array([[_number(t, path, lineno) for t in tokens] for lineno, tokens in rows])
    large = np.abs(table) > MAX_MAGNITUDE
    if large.any():
        r, c = np.argwhere(large)[0]
        raise InputFileError(path, int(lines[r]), f"value {table[r, c]:.3g} in column {c + 1} is out of range "
                                                  f"(|value| > {MAX_MAGNITUDE:g})")
    return table, lines


def parse_u0(path) -> np.ndarray:
    """Undeformed node positions of ``u0.dat`` (Listing 4.1), shape (N, 3), file units."""
    return _table(path, 3)[0]


def parse_masses(path) -> np.ndarray:
    """Lumped node masses of ``mij.dat`` (Listing 4.3), shape (N,), file units, all > 0."""
    table, lines = _table(path, 1)
    masses = table[:, 0]
    bad = np.flatnonzero(masses <= 0.0)
    if bad.size:
        first = bad[0]
        raise InputFileError(path, int(lines[first]), f"non-positive mass {float(masses[first])!r}")
    return masses


def parse_mode_shapes(path, n_nodes: int | None = None) -> np.ndarray:
    """Mode shapes of ``modeShapeMatrix.dat`` (Listing 4.2), shape (3N, n_f).

    Every row must have the same column count; the row count must be 3 * n_nodes
    when ``n_nodes`` is given, else a multiple of 3.
    """
    phi = _table(path)[0]
    rows = phi.shape[0]
    if n_nodes is not None and rows != 3 * n_nodes:
        raise InputFileError(path, None, f"{rows} mode-shape rows, but 3 x {n_nodes} nodes"
                                         f" = {3 * n_nodes} rows expected")
    if rows % 3:
        raise InputFileError(path, None, f"{rows} mode-shape rows is not 3 x nodes"
                                         " (not a multiple of 3)")
    return phi


def _stiffness_entries(path: Path, n_nodes: int | None):
    """0-based rows, columns, values and line numbers of the stiffness file's entries.

    Node indices must be whole numbers in 1..n_nodes (any >= 1 if n_nodes is None),
    DOF indices in 1..3.
    """
    table, lines = _table(path, 5)
    index = table[:, :4]
    high = np.array([n_nodes or np.inf, 3, n_nodes or np.inf, 3])
    bad = (index != np.round(index)) | (index < 1) | (index > high)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        what, value = ("node", "DOF")[c % 2], float(index[r, c])
        bound = "" if np.isinf(high[c]) else f"{high[c]:g}"
        fault = (f"{what} index {value:g} out of range 1..{bound}" if value == round(value)
                 else f"{what} index {value!r} is not a whole number")
        raise InputFileError(path, int(lines[r]), fault)
    index = index.astype(np.int64) - 1
    return 3 * index[:, 0] + index[:, 1], 3 * index[:, 2] + index[:, 3], table[:, 4], lines


def parse_stiffness(path, n_dof: int | None = None) -> sp.csr_matrix:
    """Stiffness matrix of ``stiffnessMatrix.dat`` (Listings 4.4-4.5), CSR, file units.

    ``n_dof`` = 3N if known (node indices are then checked against N); otherwise the
    size is 3 x the largest node index. Lower, upper or full storage is accepted
    (see the module docstring); the result is exactly symmetric, each off-diagonal
    pair taking the value stored at row >= column.
    """
    path = Path(path)
    rows, cols, values, lines = _stiffness_entries(path, None if n_dof is None else n_dof // 3)
    n = n_dof if n_dof is not None else 3 * (max(rows.max(), cols.max()) // 3 + 1)
    keys = rows * n + cols
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    repeats = np.flatnonzero(sorted_keys[1:] == sorted_keys[:-1])
    if repeats.size:
        second = order[repeats + 1].min()
        first = order[np.searchsorted(sorted_keys, keys[second])]
        raise InputFileError(path, int(lines[second]),
                             f"duplicate stiffness entry (row {rows[second] + 1}, column "
                             f"{cols[second] + 1}) first given on line {lines[first]}")
    pos = np.minimum(np.searchsorted(sorted_keys, cols * n + rows), len(keys) - 1)
    has_mirror = sorted_keys[pos] == cols * n + rows
    mirror = order[pos]
    mismatch = has_mirror & (np.abs(values - values[mirror])
                             > SYMMETRY_RTOL * np.abs(values).max())
    if mismatch.any():
        bad = np.flatnonzero(mismatch)
        i = bad[np.argmin(np.maximum(lines[bad], lines[mirror[bad]]))]
        j = mirror[i]
        later, earlier = (i, j) if lines[i] > lines[j] else (j, i)
        raise InputFileError(path, int(lines[later]),
                             f"non-symmetric stiffness: K[{rows[later] + 1},{cols[later] + 1}]"
                             f" = {float(values[later])!r} but K[{rows[earlier] + 1},"
                             f"{cols[earlier] + 1}] = {float(values[earlier])!r}"
                             f" on line {lines[earlier]}")
    lonely = ~has_mirror & (rows != cols)
    if lonely.any() and (rows > cols).any() and (rows < cols).any():
        i = np.flatnonzero(lonely)[np.argmax(lines[lonely])]       # the later one, as for a mismatch
        raise InputFileError(path, int(lines[i]),
                             f"K[{rows[i] + 1},{cols[i] + 1}] has no mirror K[{cols[i] + 1},{rows[i] + 1}] "
                             f"(a file of both triangles must give each pair twice)")
    keep = (rows >= cols) | ~has_mirror
    low_r = np.maximum(rows, cols)[keep]
    low_c = np.minimum(rows, cols)[keep]
    low_v = values[keep]
    off = low_r != low_c
    k = sp.coo_matrix((np.concatenate([low_v, low_v[off]]),
                       (np.concatenate([low_r, low_c[off]]), np.concatenate([low_c, low_r[off]]))),
                      shape=(n, n))
    return k.tocsr()


def read_text_body(directory, units: str = "si") -> BodyData:
    """The body stored as the four text files in ``directory``, converted to SI.

    Checks that the files agree: N masses for the N nodes of ``u0.dat``, 3N mode
    rows, node indices of the stiffness file within 1..N. Eigenvalues, node groups,
    surface, material and params are not stored in text files (left empty).
    """
    system = unit_system(units)
    directory = Path(directory)
    u0 = parse_u0(directory / U0_FILE)
    n_nodes = u0.shape[0]
    masses = parse_masses(directory / MASSES_FILE)
    if masses.size != n_nodes:
        raise InputFileError(directory / MASSES_FILE, None,
                             f"node count mismatch: {masses.size} masses but {n_nodes}"
                             f" nodes in {U0_FILE}")
    phi = parse_mode_shapes(directory / MODES_FILE, n_nodes)
    stiffness = parse_stiffness(directory / STIFFNESS_FILE, 3 * n_nodes)
    if system.mass != 1.0 and mass_normalized(phi, masses):
        phi = phi / math.sqrt(system.mass)
    return BodyData(u0=u0 * system.length, phi=phi, masses=masses * system.mass,
                    stiffness=(stiffness * system.stiffness).tocsr())


def _write_lines(path, lines) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.writelines(line + "\n" for line in lines)


def _row(values) -> str:
    return "\t".join(repr(v) for v in values)


def write_text_files(paths: dict, body: BodyData, units: str = "si") -> None:
    """Write the four text files of ``body`` to ``paths`` (TEXT_FILES name -> path).

    Values are converted from SI to ``units``; ModelError if K is zero, or not
    symmetric (relative tolerance 1e-9), since only its lower triangle is written, and
    for a body with a consistent mass matrix, which ``mij.dat`` (node masses) cannot hold.
    """
    if body.mass_matrix is not None:
        raise ModelError("a body with a consistent mass matrix cannot be written as text files: "
                         f"{MASSES_FILE} holds lumped node masses only; write body.h5 instead")
    system = unit_system(units)
    k = sp.csr_matrix(body.stiffness)
    if k.count_nonzero() == 0:
        raise ModelError("stiffness matrix is zero; a flexible body needs its stiffness")
    if abs(k - k.T).max() > SYMMETRY_RTOL * abs(k).max():
        raise ModelError("stiffness matrix is not symmetric; "
                         "the text files store its lower triangle only")
    phi = body.phi
    if system.mass != 1.0 and mass_normalized(phi, body.masses):
        phi = phi * math.sqrt(system.mass)
    u0 = (np.asarray(body.u0) / system.length).tolist()
    masses = (np.asarray(body.masses) / system.mass).tolist()
    _write_lines(paths[U0_FILE], (f"{_row(p)}\t% node: {i}" for i, p in enumerate(u0, 1)))
    _write_lines(paths[MODES_FILE], (f"{_row(p)}\t% node: {r // 3 + 1}, DOF: {r % 3 + 1}"
                                     for r, p in enumerate(np.asarray(phi).tolist())))
    _write_lines(paths[MASSES_FILE], (f"{m!r}\t% node: {i}" for i, m in enumerate(masses, 1)))
    lower = sp.tril(k / system.stiffness, format="csc")
    lower.eliminate_zeros()
    lower.sort_indices()
    cols = np.repeat(np.arange(lower.shape[1]), np.diff(lower.indptr))
    _write_lines(paths[STIFFNESS_FILE], (
        f"{r // 3 + 1},{r % 3 + 1}, {c // 3 + 1},{c % 3 + 1}, {v!r}"
        for r, c, v in zip(lower.indices.tolist(), cols.tolist(), lower.data.tolist())))


def write_text_body(directory, body: BodyData, units: str = "si") -> None:
    """Write ``body`` as the four text files into ``directory`` (created if missing).

    Not atomic; :func:`preprocess.bodyfiles.write_body` is.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    write_text_files({name: directory / name for name in TEXT_FILES}, body, units)
