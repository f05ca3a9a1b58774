"""The run state of the contours and contacts, as two vectors of Data.

Each contour, contact point, contact kinematics, search and contact names the arrays of
its run state — what a step writes and a later step reads: a contour's state vector and
span cache, a kinematics' gap, frame and Jacobian pieces, a contact point's coordinates
and fields, a search's warm start, counters and length scale — in a class attribute
``state_slots``: attribute names of float64 or int64 arrays, or of objects with their own
``state_slots`` (a kinematics' points and search, an offset contour's neutral curve).

:class:`ContactState` lays those arrays end to end in one float64 and one int64 vector,
which Data holds (``Data.contact_f``, ``Data.contact_i``), and :meth:`~ContactState.bind`
makes every slot a view of them, then calls each object's ``bind_views`` (its named views
and kernel tuples made again on the moved arrays) and each fused detection's ``refresh``
(its argument tuple). So the kernels and the Python path read and write Data: a
checkpoint of Data holds the whole contact state, and a step taken back (adaptive Moreau)
puts it back by copying Data's vectors. A new Data starts from the values the slots held
when they were first laid out (:meth:`~ContactState.pools`), so the runs of one Model, one
Data each, start alike, and so do the runs of a System compiled again. An array that
views another slot (a point's centre, its point's position) is no slot of its own; its
owner's ``bind_views`` derives it again.

:meth:`~ContactState.bind` checks that no array of the objects and fused detections is
left on the old memory (a view a ``bind_views`` forgot would go on reading a copy that
the run no longer writes) and raises if one is.
"""

from __future__ import annotations

import bisect

import numpy as np

POOLS = (np.float64, np.int64)      # the two vectors: contact_f, contact_i


class ContactState:
    """The slots of the run state of ``roots`` (contours and contacts, each walked once
    with what its ``state_slots`` name) in two vectors (module docstring).

    Attributes
    ----------
    objects : list
        Every object with state slots, each after those it holds (their views first).
    slots : list of (object, name, pool, offset, shape)
        Each array's place: pool 0 (float64) or 1 (int64), its offset and shape.
    sizes : (int, int)
        Lengths of the two vectors.
    """

    def __init__(self, roots):
        self.objects, self.slots = [], []
        sizes, seen, spans = [0, 0], set(), _Spans()

        def walk(obj):
            if id(obj) in seen:
                return
            seen.add(id(obj))
            for name in type(obj).state_slots:
                value = getattr(obj, name)
                if hasattr(type(value), "state_slots"):
                    walk(value)
                    continue
                if not isinstance(value, np.ndarray) or value.dtype.type not in POOLS:
                    raise TypeError(f"{type(obj).__name__}.{name}: run state must be a float64 or int64 array, "
                                    f"got {type(value).__name__} {getattr(value, 'dtype', '')}")
                if value.size and spans.inside(value):
                    continue                    # a view of another slot: bind_views derives it
                pool = POOLS.index(value.dtype.type)
                self.slots.append((obj, name, pool, sizes[pool], value.shape))
                sizes[pool] += value.size
                if value.size:
                    spans.add(value, f"{type(obj).__name__}.{name}")
            self.objects.append(obj)

        for root in roots:
            walk(root)
        self.sizes = tuple(sizes)
        self.initial = tuple(np.zeros(n, dtype=dtype) for n, dtype in zip(self.sizes, POOLS))
        for obj, name, pool, at, shape in self.slots:
            value = _first_value(obj, name)
            self.initial[pool][at:at + value.size] = value.ravel()

    def pools(self) -> tuple:
        """(float64 vector, int64 vector) holding the slots' values when the objects were
        first laid out (their first Model compiled): the contact state a run starts from."""
        return tuple(v.copy() for v in self.initial)

    def bind(self, contact_f, contact_i, fused=()) -> None:
        """Make every slot a view of ``contact_f``/``contact_i`` (with the values they
        hold), the objects' derived views and the ``fused`` detections' tables again on
        them; RuntimeError if an array is left on the old memory."""
        pools = (contact_f, contact_i)
        old = [_owner(getattr(obj, name)) for obj, name, *_ in self.slots]     # alive until checked
        for obj, name, pool, at, shape in self.slots:
            setattr(obj, name, pools[pool][at:at + int(np.prod(shape))].reshape(shape))
        for obj in self.objects:
            bind_views = getattr(obj, "bind_views", None)
            if bind_views is not None:
                bind_views()
        fused = [f for f in fused if f is not None]
        for f in fused:
            f.refresh()
        left = _left_on(self.objects + fused, old)
        if left:
            raise RuntimeError(f"run state left outside Data after binding: {', '.join(left)}")


def _first_value(obj, name) -> np.ndarray:
    """A copy of slot ``name`` of ``obj`` as it was when first laid out (kept on the object
    as ``_first_state``): a System compiled again after a run starts where its first run
    did, not from that run's last warm starts and counters."""
    kept = vars(obj).setdefault("_first_state", {})
    if name not in kept:
        kept[name] = getattr(obj, name).copy()
    return kept[name]


class _Spans:
    """The memory of the slots found so far, as disjoint address intervals: an array
    inside one views that slot — whether the slots are arrays of their own (a Model's
    first compile) or views of a Data's vectors (the System compiled again after a run)."""

    def __init__(self):
        self._starts, self._ends = [], []

    @staticmethod
    def _interval(array):
        start = array.__array_interface__["data"][0]
        return start, start + array.nbytes

    def inside(self, array) -> bool:
        start, end = self._interval(array)
        k = bisect.bisect_right(self._starts, start) - 1
        return k >= 0 and end <= self._ends[k]

    def add(self, array, name) -> None:
        start, end = self._interval(array)
        k = bisect.bisect_right(self._starts, start)
        if (k > 0 and self._ends[k - 1] > start) or (k < len(self._starts) and self._starts[k] < end):
            raise TypeError(f"{name}: run state overlapping another slot (a slot must be named before "
                            "the views of it)")
        self._starts.insert(k, start)
        self._ends.insert(k, end)


def _left_on(objects, old) -> list:
    """Names "Class.attribute" of the arrays of ``objects`` (attributes, also inside
    tuples and lists) that view the memory of an array of ``old`` (the arrays owning the
    slots' memory before)."""
    old_ids, left = {id(a) for a in old}, []

    def arrays(value):
        if isinstance(value, np.ndarray):
            yield value
        elif isinstance(value, (tuple, list)):
            for v in value:
                yield from arrays(v)

    for obj in objects:
        for name, value in vars(obj).items():
            if any(id(_owner(a)) in old_ids for a in arrays(value)):
                left.append(f"{type(obj).__name__}.{name}")
    return left


def _owner(array):
    """The array that owns ``array``'s memory (numpy's ``base`` of a view is its owner)."""
    return array if array.base is None else array.base
