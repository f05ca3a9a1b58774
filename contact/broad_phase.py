"""Broad phase: contour pairs whose axis-aligned bounding boxes overlap.

Stage 4 of a step (DESIGN.md) starts here: only pairs whose boxes, grown by a margin,
overlap go on to the search of :mod:`contact.search`. Boxes are the contours'
``bounding_box()`` (2, 3) [m] (rows min, max; a plane's is infinite and overlaps
everything), taken after the caller has updated the contours. The test itself is the
numba kernel :func:`._detection_kernels.boxes_overlap` (a :class:`~contact.Contact`
calls it on preallocated boxes).
"""

from __future__ import annotations

import numpy as np

from ._detection_kernels import boxes_overlap


def overlapping(box1, box2, margin=0.0) -> bool:
    """True if the boxes (2, 3) [m] (rows min, max), each grown by ``margin`` [m] on
    every side, overlap: lo1 − m ≤ hi2 + m and lo2 − m ≤ hi1 + m on every axis
    (infinite bounds allowed)."""
    return bool(boxes_overlap(np.asarray(box1, dtype=float), np.asarray(box2, dtype=float), float(margin)))


def _contours(pair):
    """(contour1, contour2) of a 2-tuple or of an object with contour1, contour2."""
    return (pair.contour1, pair.contour2) if hasattr(pair, "contour1") else tuple(pair)


class BroadPhase:
    """The candidate pairs among ``pairs`` — 2-tuples of contours or contact kinematics
    objects (anything with ``contour1``, ``contour2``) — whose bounding boxes, each grown
    by ``margin`` [m], overlap. Each contour's box is computed once per call."""

    def __init__(self, pairs, margin=0.0):
        self.pairs = list(pairs)
        self.margin = float(margin)

    def candidates(self) -> list:
        """The pairs (the same objects, in order) whose grown boxes overlap."""
        boxes = {}

        def box(contour):
            key = id(contour)
            if key not in boxes:
                boxes[key] = contour.bounding_box()
            return boxes[key]

        return [pair for pair in self.pairs
                if overlapping(*(box(c) for c in _contours(pair)), margin=self.margin)]
