"""The per-step records of a run (Moreau's ``trace=True``): one row of numbers per
accepted step, appended without a Python list per key.

The rows live in one flat ``array.array`` of doubles, row after row; appending a row is
one ``extend`` (the buffer grows geometrically in C, no numpy array is made). Integer
columns (counts) are held as doubles, exact up to 2⁵³, and handed out with their own
dtype. :meth:`StepTrace.columns` copies the rows out as one array per key;
:meth:`StepTrace.load` puts such columns back (a checkpoint's trace), bit for bit.
"""

from __future__ import annotations

from array import array

import numpy as np


class StepTrace:
    """Rows of ``len(keys)`` numbers, one per accepted step.

    Parameters
    ----------
    keys : tuple of str
        The column names, in the order of the values :meth:`append` gets.
    dtypes : dict
        {key: numpy dtype} of the columns that are not float64 (integer counts).
    """

    def __init__(self, keys, dtypes):
        self.keys = tuple(keys)
        self.dtypes = dict(dtypes)
        self._rows = array("d")

    def __len__(self) -> int:
        return len(self._rows) // len(self.keys)

    def append(self, values) -> None:
        """Append one row: ``values`` holds one number per key, in the keys' order."""
        self._rows.extend(values)

    def columns(self, start=0) -> dict:
        """{key: (rows − start,) array} of the rows from ``start`` on (copies)."""
        table = np.frombuffer(self._rows, dtype=np.float64).reshape(-1, len(self.keys))[start:]
        out = {key: table[:, j].astype(self.dtypes.get(key, np.float64)) for j, key in enumerate(self.keys)}
        del table       # the buffer export ends here, so the array can grow again
        return out

    def load(self, columns) -> None:
        """Replace the rows by ``columns`` {key: (n,) array} (every key, equal lengths)."""
        table = np.column_stack([np.asarray(columns[key], dtype=np.float64) for key in self.keys])
        self._rows = array("d", table.ravel().tobytes()) if table.size else array("d")
