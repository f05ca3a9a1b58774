"""The per-step trace rows (mbs.integrators.step_trace): what goes in comes out, bit for
bit, with the integer columns as integers; loading columns back restores the rows."""

import numpy as np

from mbs.integrators.step_trace import StepTrace

from numpy_allocations import NumpyAllocations


def test_rows_come_back_bit_for_bit_and_load_restores_them():
    rng = np.random.default_rng(4)
    trace = StepTrace(("t", "closed", "energy"), {"closed": np.int64})
    rows = [(float(t), int(c), float(e)) for t, c, e in zip(rng.random(3000), rng.integers(0, 2**40, 3000),
                                                             rng.normal(size=3000) * 1e-300)]
    for row in rows:
        trace.append(row)
    assert len(trace) == 3000
    cols = trace.columns(1000)
    assert cols["closed"].dtype == np.int64 and cols["t"].dtype == np.float64
    np.testing.assert_array_equal(cols["closed"], [r[1] for r in rows[1000:]])
    np.testing.assert_array_equal(cols["energy"], [r[2] for r in rows[1000:]])
    trace.append((1.0, 2, 3.0))                     # the buffer still grows after being read
    other = StepTrace(trace.keys, trace.dtypes)
    other.load(trace.columns())
    assert len(other) == 3001
    for key in trace.keys:
        np.testing.assert_array_equal(other.columns()[key], trace.columns()[key])


def test_appending_a_row_allocates_no_numpy_array():
    trace = StepTrace(("t", "closed"), {"closed": np.int64})
    with NumpyAllocations() as count:
        for k in range(5000):
            trace.append((0.5 * k, k))
    assert count.sizes == []
