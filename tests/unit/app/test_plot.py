"""Plots of result files: the PNG, the drawn data against the file's, names and errors."""

import struct

import h5py
import numpy as np
import pytest
from matplotlib.image import imread

from ffrmbs_app import cli
from ffrmbs.errors import InputFileError
from ffrmbs_app.plot import plot_result, result_figure

T = np.linspace(0.0, 0.4, 41)


def write_result(path, status="complete", energy=True):
    """A result file per mbs.results.result_file with two outputs, energies and one contact."""
    with h5py.File(path, "w") as f:
        f.attrs.update(format="ffrmbs-result", format_version=1, status=status, scene="drop test",
                       integrator="moreau", dt=1e-4, t_end=0.4, n_out=len(T))
        f["t"] = T
        tip = np.stack([np.cos(T), np.sin(T), 0.1 * T], axis=1)
        f["outputs/tip"] = tip
        f["outputs/tip"].attrs["unit"] = "m"
        f["outputs/vy"] = -9.81 * T
        if energy:
            f["energy/kinetic"] = 0.5 * (9.81 * T) ** 2
            f["energy/potential"] = 1.0 - 0.5 * (9.81 * T) ** 2 + 0.01 * T
        c = f.create_group("contacts/impact")
        c["active"] = (T > 0.2).astype(np.int8)
        gap = 0.2 - T
        gap[:3] = np.nan
        c["gap"] = gap
        normal = np.tile([0.0, 0.6, 0.8], (len(T), 1))
        normal[:3] = np.nan
        c["normal"] = normal
        force = np.zeros((len(T), 3))
        force[T > 0.2] = [1.0, 3.0, 4.0]          # f·n = 1.8 + 3.2 = 5 N
        c["force"] = force
        c["point"] = np.zeros((len(T), 3))
    return path


@pytest.fixture
def result(tmp_path):
    return write_result(tmp_path / "drop.h5")


def png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_default_plot_is_a_png_of_outputs_and_energy(result):
    out = plot_result(result)
    assert out == result.with_name("drop-plot.png")
    width, height = png_size(out)
    assert width == 900 and 800 <= height <= 900              # 9 in x (1.2 + 3 x 2.4) in at 100 dpi
    image = imread(out)
    assert image.shape[:2] == (height, width)
    assert len(np.unique(image.reshape(-1, image.shape[2]), axis=0)) > 50   # lines and text, not blank
    assert sorted(p.name for p in result.parent.iterdir()) == ["drop-plot.png", "drop.h5"]


def test_drawn_lines_are_the_file_data(result):
    fig = result_figure(result, ["tip", "vy", "energy", "contact:impact"])
    tip_ax, vy_ax, energy_ax, contact_ax = fig.axes[:4]
    assert [ln.get_label() for ln in tip_ax.get_lines()] == ["tip x", "tip y", "tip z"]
    np.testing.assert_array_equal(tip_ax.get_lines()[1].get_ydata(), np.sin(T))
    np.testing.assert_array_equal(tip_ax.get_lines()[1].get_xdata(), T)
    assert tip_ax.get_ylabel() == "tip [m]" and vy_ax.get_ylabel() == "vy"
    np.testing.assert_array_equal(vy_ax.get_lines()[0].get_ydata(), -9.81 * T)
    labels = [ln.get_label() for ln in energy_ax.get_lines()]
    assert labels == ["kinetic", "potential", "total"] and energy_ax.get_ylabel() == "energy [J]"
    np.testing.assert_allclose(energy_ax.get_lines()[2].get_ydata(), 1.0 + 0.01 * T, rtol=1e-12)
    gap = contact_ax.get_lines()[0].get_ydata()
    assert np.isnan(gap[:3]).all()
    np.testing.assert_allclose(gap[3:], 0.2 - T[3:])
    assert "gap g_N [m]" in contact_ax.get_ylabel()
    twin = fig.axes[4]                                         # the normal force on the twin axis
    np.testing.assert_allclose(twin.get_lines()[0].get_ydata(), np.where(T > 0.2, 5.0, 0.0))
    assert "[N]" in twin.get_ylabel()
    assert fig.axes[3].get_xlabel() == "t [s]"
    assert tip_ax.get_shared_x_axes().joined(tip_ax, contact_ax)


def test_title_names_scene_integrator_dt_and_an_unfinished_status(tmp_path, result):
    texts = [t.get_text() for t in result_figure(result).texts]   # the suptitle
    assert texts == ["drop test — moreau, Δt = 0.0001 s"]
    stopped = write_result(tmp_path / "stopped.h5", status="interrupted")
    texts = [t.get_text() for t in result_figure(stopped).texts]
    assert texts == ["drop test — moreau, Δt = 0.0001 s\ninterrupted at t = 0.4 s"]


def test_unknown_name_lists_the_available_ones(result):
    with pytest.raises(InputFileError, match=r"no 'tipp' in the file; available: tip, vy, energy, contact:impact"):
        plot_result(result, ["tip", "tipp"])
    assert not result.with_suffix(".png").exists()


def test_without_energy_and_explicit_out(tmp_path):
    path = write_result(tmp_path / "noenergy.h5", energy=False)
    with pytest.raises(InputFileError, match="available: tip, vy, contact:impact"):
        plot_result(path, ["energy"])
    out = plot_result(path, ["contact:impact"], out=tmp_path / "contact.png")
    assert png_size(out) == (900, 360)                          # (1.2 + 2.4) in high
    assert len(result_figure(path).axes) == 2                   # default: the two outputs


def test_not_a_result_file(tmp_path):
    bad = tmp_path / "bad.h5"
    with h5py.File(bad, "w") as f:
        f["t"] = T
    with pytest.raises(InputFileError, match="not an ffrmbs result file"):
        plot_result(bad)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.h5"]


def test_cli_plot(result, tmp_path, capsys):
    out = tmp_path / "energy.png"
    assert cli.main(["plot", str(result), "energy", "tip", "--out", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    assert png_size(out) == (900, 600)
    assert cli.main(["plot", str(result), "nothing"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ffrmbs: error: ") and "available: tip, vy, energy, contact:impact" in err


def test_panels_say_what_an_output_is_and_ticks_carry_no_offset(tmp_path):
    """A panel's title is the output's label and unit; values that differ little from a large
    one (0.1 + 3e-5 t) are labelled in plain numbers, never by an offset such as "1e-5+1e-1"."""
    path = write_result(tmp_path / "r.h5")
    with h5py.File(path, "a") as f:
        f["outputs/node19"] = np.stack([0.1 + 3e-5 * T, 2e-6 * np.sin(T), 0 * T], axis=1)
        f["outputs/node19"].attrs.update(units="m", label="beam node 19 displacement")
    fig = result_figure(path, ["node19", "vy", "energy", "contact:impact"])
    fig.canvas.draw()
    assert fig.axes[0].get_title(loc="left") == "node19: beam node 19 displacement [m]"
    assert fig.axes[1].get_title(loc="left") == "vy"                       # no label, no unit in the file
    assert len(fig.axes) == 5                                              # 4 panels, the contact's twin axis
    for axis in [ax.yaxis for ax in fig.axes] + [fig.axes[3].xaxis]:      # the shared t axis, at the bottom
        lo, hi = sorted(axis.get_view_interval())
        texts = [t.label1.get_text() for t in axis.get_major_ticks() if lo <= t.get_loc() <= hi]
        assert texts and all(texts) and len(set(texts)) == len(texts), texts
    assert [a.get_offset_text().get_text() for ax in fig.axes for a in (ax.xaxis, ax.yaxis)] == [""] * 10
    y_ticks = [float(t.get_text()) for t in fig.axes[0].yaxis.get_ticklabels() if t.get_text()]
    assert min(y_ticks) < 0.1 and max(y_ticks) > 0.1     # the values themselves, not their offset from 0.1
