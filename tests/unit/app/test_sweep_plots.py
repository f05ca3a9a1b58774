"""The sweep's plots and run names (ffrmbs_app.sweeps), from tables made here: one line per
value of the other varied keys, legends naming what varies (never a constant override), a
panel of each output against each varied key, and names a user can read."""

import itertools

import pytest

from ffrmbs.errors import FfrmbsError
from ffrmbs_app.sweeps import outputs_figure, override_sets, plot_sweep, run_key, work_precision_figure


def table_of(grid, error=True):
    """Complete rows of the grid's product: cpu ∝ modes / dt, error ∝ dt / modes, the
    output z = e × dt (so every line is known by hand)."""
    keys = list(grid)
    rows = []
    for combo in itertools.product(*grid.values()):
        v = dict(zip(keys, combo))
        dt, modes, e = float(v.get("scene.dt", "1e-3")), float(v.get("body.beam.modes", "10")), \
            float(v.get("contact.floor.e", "0.5"))
        rows.append({"run": "r", **v, "status": "complete", "error_estimate": dt / modes if error else None,
                     "cpu_s": modes / dt * 1e-4, "final:z": e * dt, "final:vz": -e})
    return rows


GRID = {"scene.dt": ["1e-3", "5e-4", "2.5e-4"], "body.beam.modes": ["10", "20"], "scene.integrator": ["moreau"]}


def legend_texts(ax):
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend else []


def test_work_precision_has_a_line_along_dt_per_modes_value():
    fig = work_precision_figure(table_of(GRID), GRID)
    ax = fig.axes[0]
    lines = ax.get_lines()
    assert len(lines) == 2                                         # dt and modes no longer in one line
    assert legend_texts(ax) == ["modes = 10", "modes = 20"]        # not the constant integrator
    for line, modes in zip(lines, (10, 20)):
        dt = [1e-3, 5e-4, 2.5e-4]
        assert list(line.get_xdata()) == pytest.approx([modes / d * 1e-4 for d in dt])
        assert list(line.get_ydata()) == pytest.approx([d / modes for d in dt])


def test_outputs_against_each_varied_key_even_without_a_resolution_key(tmp_path):
    grid = {"contact.floor.e": ["0.2", "0.5", "0.8"], "body.ball.position": ["[0, 0, 0.05]", "[0, 0, 0.1]"]}
    table = table_of(grid, error=False)
    written = plot_sweep(table, grid, tmp_path)
    assert [p.name for p in written] == ["sweep-outputs.png"]      # no estimates: no work-precision plot
    fig = outputs_figure(table, grid)
    assert len(fig.axes) == 4                                      # (z, vz) x (e, position)
    by_label = {(ax.get_ylabel(), ax.get_xlabel()): ax for ax in fig.axes}
    ax = by_label[("z", "e")]
    assert legend_texts(ax) == ["position = [0, 0, 0.05]", "position = [0, 0, 0.1]"]
    assert [list(line.get_xdata()) for line in ax.get_lines()] == [[0.2, 0.5, 0.8]] * 2
    assert list(ax.get_lines()[0].get_ydata()) == pytest.approx([0.2e-3, 0.5e-3, 0.8e-3])
    ax = by_label[("vz", "position")]
    assert legend_texts(ax) == ["e = 0.2", "e = 0.5", "e = 0.8"]
    fig.canvas.draw()
    assert [t.get_text() for t in ax.get_xticklabels()] == ["[0, 0, 0.05]", "[0, 0, 0.1]"]
    for ax in fig.axes:
        assert ax.yaxis.get_offset_text().get_text() == ""


def test_one_varied_key_gives_one_line_without_legend():
    grid = {"scene.dt": ["1e-3", "5e-4"]}
    fig = work_precision_figure(table_of(grid), grid)
    assert len(fig.axes[0].get_lines()) == 1 and fig.axes[0].get_legend() is None


def test_run_names_are_readable():
    assert run_key(("contact.floor.e=0.2", "body.ball.position=[-0.05, 0.02, 0.025]")) == \
        "e=0.2,position=-0.05_0.02_0.025"
    assert run_key(("contact.floor.law=\"penalty\"",)) == "law=penalty"
    assert run_key(("scene.dt=5e-06", "body.beam.modes=50")) == "dt=5e-06,modes=50"
    odd = run_key(('scene.name="a b/c"',))
    assert odd.startswith("name=a_b_c-") and "/" not in odd
    with pytest.raises(FfrmbsError, match="twice"):               # the same run written two ways
        override_sets({"body.ball.position": ["[0,0,0.05]", "[0, 0, 0.05]"]})
