"""Tick labels that always read as numbers and legend texts that say what varies (matplotlib):
the run plots, the sweep plots and the validation report's work-precision plots.

* :class:`PlainFormatter` labels each tick with as few significant digits as give its
  value to a millionth of the tick spacing (``0.10001``, ``0.10002``; ``0.125``), in positional notation from 1e-4 to 1e6 and in
  e-notation outside; it never draws an offset or a multiplier above the axis (matplotlib's
  default draws ``1e−5+1e−1`` there when the values differ little from a large one).
* :func:`label_log_axis` keeps a log axis labelled when it spans less than a decade: its
  decade ticks then miss the view, so the axis gets a few round ticks inside it (1, 2, 5
  times a power of ten when they fit), in plain numbers.
"""

from __future__ import annotations

import math
import re

import numpy as np
from matplotlib.ticker import FixedLocator, Formatter, NullFormatter

MAX_DIGITS = 15
PLAIN_RANGE = (1e-4, 1e6)       # |value| written positionally in this range, else in e-notation
LOG_TICKS = 4                   # ticks of a log axis that spans less than a decade


def number_text(value, digits) -> str:
    """``value`` to ``digits`` significant digits: positional in PLAIN_RANGE or at 0
    ("0.00012", "250"), else e-notation without padding ("1.5e-7", "3e8")."""
    if value == 0 or not math.isfinite(value):
        return "0" if value == 0 else str(value)
    if PLAIN_RANGE[0] <= abs(value) < PLAIN_RANGE[1]:
        return np.format_float_positional(value, precision=digits, unique=False, fractional=False, trim="-")
    mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
    if "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{int(exponent)}"


class PlainFormatter(Formatter):
    """Tick labels in plain numbers, the fewest significant digits that give each tick's
    value (to 1e-6 of the spacing); no offset or multiplier text (module docstring)."""

    def __call__(self, x, pos=None):
        return number_text(x, 6)

    def format_ticks(self, values):
        values = [float(v) for v in values]
        scale = max((abs(v) for v in values), default=0.0)
        values = [0.0 if abs(v) <= 1e-12 * scale else v for v in values]     # 1.4e-17 of a linspace is 0
        steps = [abs(b - a) for a, b in zip(values, values[1:]) if b != a]
        tolerance = 1e-6 * (min(steps) if steps else scale)
        for digits in range(1, MAX_DIGITS + 1):
            labels = [number_text(v, digits) for v in values]
            if all(abs(float(t) - v) <= tolerance for t, v in zip(labels, values)):
                return labels
        return labels

    def get_offset(self):
        return ""


def plain_axis(axis):
    """Label a linear ``axis`` (ax.xaxis, ax.yaxis) with :class:`PlainFormatter`."""
    axis.set_major_formatter(PlainFormatter())


def _decades_in(lo, hi) -> int:
    """The number of powers of ten in [lo, hi] (0 < lo <= hi)."""
    return math.floor(math.log10(hi) * (1 + 1e-12)) - math.ceil(math.log10(lo) * (1 - 1e-12)) + 1


def log_ticks(lo, hi) -> list[float]:
    """Ticks for a log axis over [lo, hi] that holds fewer than two powers of ten: the
    first of {1, 2, 5}·10^k, {1, ..., 9}·10^k that puts two to eight ticks in it, else
    LOG_TICKS values spread geometrically, rounded to the fewest significant digits (two
    or more) that keep them apart."""
    decades = range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
    for mantissas in ((1, 2, 5), range(1, 10)):
        ticks = [m * 10.0 ** k for k in decades for m in mantissas if lo <= m * 10.0 ** k <= hi]
        if 2 <= len(ticks) <= 8:
            return ticks
    inner = np.geomspace(lo, hi, LOG_TICKS + 2)[1:-1]
    for digits in range(2, MAX_DIGITS + 1):
        ticks = sorted({float(f"{v:.{digits}g}") for v in inner})
        if len(ticks) == len(inner):
            return ticks
    return list(inner)


def label_log_axis(ax, which):
    """Keep the log axis ``which`` ("x" or "y") of ``ax`` labelled: with two or more powers
    of ten in its view the decades carry the labels (minor ticks unlabelled); with fewer,
    the ticks of :func:`log_ticks`, labelled by :class:`PlainFormatter`. Call after the
    data are drawn."""
    ax.autoscale_view()
    axis = ax.xaxis if which == "x" else ax.yaxis
    lo, hi = sorted(ax.get_xlim() if which == "x" else ax.get_ylim())
    if lo <= 0 or _decades_in(lo, hi) >= 2:
        axis.set_minor_formatter(NullFormatter())
        return
    axis.set_major_locator(FixedLocator(log_ticks(lo, hi)))
    axis.set_major_formatter(PlainFormatter())
    axis.set_minor_formatter(NullFormatter())


def value_text(value) -> str:
    """A swept value as a legend shows it: "on"/"off" for bools, "20×2×1" for a mesh
    ("20x2x1" or a list), numbers in %g."""
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, (list, tuple)):
        return "×".join(value_text(v) for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return re.sub(r"(?<=\d)x(?=\d)", "×", str(value))


def series_label(keys, values) -> str:
    """"modes = 20, mesh = 20×2×1": each key (underscores as spaces) with its value."""
    return ", ".join(f"{key.replace('_', ' ')} = {value_text(v)}" for key, v in zip(keys, values))
