"""numba kernels of the step's bookkeeping (:mod:`mbs.stages`): which contours and
contacts the contour and detection stages visit, in one call each instead of a Python
loop over every contact (far-apart pairs cost nothing per step).

Plain-Python references in the docstrings; ``tests/test_stages.py`` compares them.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def contours_in_use(owner_at, owners, live, out):
    """Indices of the contours with a live owner into ``out``; returns their number.
    Contour k's owning contacts are owners[owner_at[k]:owner_at[k + 1]]. Reference:
    ``[k for k in range(n) if any(live[i] for i in owners of k)]``."""
    n = 0
    for k in range(owner_at.shape[0] - 1):
        for j in range(owner_at[k], owner_at[k + 1]):
            if live[owners[j]]:
                out[n] = k
                n += 1
                break
    return n


@njit(cache=True)
def live_contacts(live, out):
    """Indices i of the live contacts (live[i] True) into ``out``, in order; returns
    their number. Reference: ``np.flatnonzero(live)``."""
    n = 0
    for i in range(live.shape[0]):
        if live[i]:
            out[n] = i
            n += 1
    return n
