"""Plots read by a user: one axis per error kind, legends of what varies placed outside the
data, tick labels always present, no offset text (structure of the matplotlib Figures)."""


import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ffrmbs_app.ticks import PlainFormatter, log_ticks, number_text
from validation import make_row
from validation.report import work_precision_figure


def tick_texts(axis):
    """The texts of the tick labels drawn inside the axis's view (after a draw)."""
    lo, hi = sorted(axis.get_view_interval())
    ticks = [t for t in axis.get_major_ticks() + axis.get_minor_ticks()
             if lo * (1 - 1e-9) <= t.get_loc() <= hi * (1 + 1e-9) and t.label1.get_visible()]
    return [t.label1.get_text() for t in ticks if t.label1.get_text()]


def offset_texts(fig):
    return [a.get_offset_text().get_text() for ax in fig.axes for a in (ax.xaxis, ax.yaxis)]


def rows_of_three_kinds():
    """A case like contact_bounce: errors in s, in m and relative, over (e, integrator, modes, mesh)."""
    rows = []
    for kind, scale in (("impact time [s]", 1e-4), ("resting |z - R| [m]", 1e-6), ("apex height (rel.)", 1e-2)):
        for modes, mesh in ((10, [20, 2, 1]), (20, "40x4x2")):       # a list, as results.json has it
            for dt in (1e-3, 5e-4, 2.5e-4):
                rows.append(make_row("c", {"modes": modes, "mesh": mesh, "residual_flexibility": True, "dt": dt},
                                     0.1 / dt * 1e-3, scale * dt * 1e3, kind, "analytic"))
    return rows


def test_one_panel_per_error_kind_with_its_unit():
    fig = work_precision_figure("c", rows_of_three_kinds(), ("modes", "mesh", "residual_flexibility", "error_kind"))
    assert len(fig.axes) == 3
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["|error| [s]", "|error| [m]", "|error| [-]"]
    for ax in fig.axes:
        assert len(ax.get_lines()) == 2                # one series per (modes, mesh); the constant key is not one
        y = np.concatenate([line.get_ydata() for line in ax.get_lines()])
        kind = ax.get_title().split("\n")[0]
        assert {"impact time [s]": 1e-4, "resting |z - R| [m]": 1e-6, "apex height (rel.)": 1e-2}[kind] * 0.25 <= y.min()


def test_legend_names_what_varies_and_sits_outside_the_data():
    fig = work_precision_figure("c", rows_of_three_kinds(), ("modes", "mesh", "residual_flexibility", "error_kind"))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        legend = ax.get_legend()
        assert [t.get_text() for t in legend.get_texts()] == ["modes = 10, mesh = 20×2×1",
                                                              "modes = 20, mesh = 40×4×2"]
        assert "residual flexibility = on" in ax.get_title()      # the constant of the panel
        box, data = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
        assert box.x0 >= data.x1                       # right of the axes: no data under it
        assert box.x1 <= fig.bbox.x1 + 1               # and inside the figure


@pytest.mark.parametrize("lo, hi", [(0.012, 0.019), (2.1e-5, 3.4e-5), (1e-3, 1e-1), (3.0, 3.0001)])
def test_log_axes_keep_labels_whatever_their_span(lo, hi):
    rows = [make_row("c", {"n": n}, cpu, err, "e [m]", "r")
            for n, (cpu, err) in enumerate(zip(np.geomspace(lo, hi, 4), np.geomspace(hi, lo, 4)))]
    fig = work_precision_figure("c", rows, ("n",))
    fig.canvas.draw()
    ax = fig.axes[0]
    for axis in (ax.xaxis, ax.yaxis):
        texts = tick_texts(axis)
        assert len(texts) >= 2 and len(set(texts)) == len(texts), texts
    assert offset_texts(fig) == ["", ""]


def test_plain_formatter_labels_close_values_without_offset():
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot([0, 1], [0.1, 0.1 + 3e-5])                 # matplotlib's default draws "1e-5+1e-1" above this axis
    ax.yaxis.set_major_formatter(PlainFormatter())
    fig.canvas.draw()
    texts = tick_texts(ax.yaxis)
    assert ax.yaxis.get_offset_text().get_text() == ""
    assert len(set(texts)) == len(texts) >= 3
    assert all(abs(float(t) - 0.1) <= 4e-5 for t in texts)


def test_number_text():
    assert number_text(0.10001, 5) == "0.10001"
    assert number_text(250.0, 2) == "250"
    assert number_text(1.5e-7, 2) == "1.5e-7"
    assert number_text(3e8, 3) == "3e8"
    assert PlainFormatter().format_ticks([0.0 + 1.4e-17, 0.5, 1.0]) == ["0", "0.5", "1"]
    assert log_ticks(0.019, 0.3) == pytest.approx([0.02, 0.05, 0.1, 0.2])
    for lo, hi in ((0.012, 0.019), (3.0, 3.0001)):
        ticks = log_ticks(lo, hi)
        assert len(set(ticks)) == len(ticks) >= 2 and all(lo <= t <= hi for t in ticks)
    assert PlainFormatter().format_ticks([0.1, 0.125, 0.15, 0.175]) == ["0.1", "0.125", "0.15", "0.175"]
