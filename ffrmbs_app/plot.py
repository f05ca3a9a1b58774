"""Plots of a result file against time (matplotlib, Agg; no pyplot global state).

:func:`plot_result` draws one subplot per requested name, all sharing the time axis t [s]:

* an output name (``/outputs/<name>``): a scalar output is one line; a vector output
  (n, 3) one line per component, labelled x, y, z; other shapes one line per component,
  labelled by index. The y label carries the dataset's ``units`` attribute when it has
  one (:mod:`mbs.results.result_file` writes one on every dataset); the panel's title says what
  the output is (its ``label`` attribute: "node19: beam node 19 displacement [m]");
* ``energy``: kinetic, potential and their sum, total [J] (``/energy``);
* ``contact:<name>``: the normal gap g_N [m] on the left axis and the normal force
  magnitude |f · n| [N] on a twin right axis (``/contacts/<name>``); the gap is NaN, so
  not drawn, while no contact point is located.

Tick labels are plain numbers without an offset or multiplier above the axis
(:class:`ffrmbs_app.ticks.PlainFormatter`). The title names the scene, the integrator and Δt, and the file's status when the run is
not complete ("interrupted at t = … s", "running at t = … s", "failed: …").
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ffrmbs.errors import FfrmbsError, InputFileError, OutputFileError, os_reason
from ffrmbs_app.result_reading import check_shape, dataset, group, open_result
from ffrmbs_app.ticks import plain_axis
from ffrmbs_app.output_dirs import remove_stale
from mbs.results.result_file import attribute

COMPONENTS = ("x", "y", "z")
SUBPLOT_HEIGHT = 2.4   # [in] per subplot
WIDTH = 9.0            # [in]
DPI = 100


def available_names(f) -> list[str]:
    """The names an open result file can plot: its outputs, ``energy`` when recorded, and
    ``contact:<name>`` per contact."""
    names = sorted(f["outputs"].keys()) if "outputs" in f else []
    if "energy" in f and any(k in f["energy"] for k in ("kinetic", "potential")):
        names.append("energy")
    if "contacts" in f:
        names += [f"contact:{c}" for c in sorted(f["contacts"].keys())]
    return names


def default_names(f) -> list[str]:
    """What :func:`plot_result` draws without names: every output and the energy; the
    contacts when the file has neither."""
    names = [n for n in available_names(f) if not n.startswith("contact:")]
    return names or available_names(f)


def _title(f, path, n) -> str:
    scene = attribute(f, "scene") or Path(path).stem
    parts = [str(scene)]
    integrator = attribute(f, "integrator")
    dt = attribute(f, "dt")
    run = ", ".join(x for x in (str(integrator) if integrator else "",
                                f"Δt = {dt:g} s" if isinstance(dt, (int, float)) else "") if x)
    if run:
        parts.append(run)
    title = " — ".join(parts)
    status = attribute(f, "status", "") or ""
    if status != "complete":
        t_last = float(f["t"][n - 1]) if n else 0.0
        if status.startswith("failed"):
            title += f"\n{status} (last sample t = {t_last:.6g} s)"
        else:
            title += f"\n{status or 'status unknown'} at t = {t_last:.6g} s"
    return title


def _unit(ds, default="") -> str:
    """" [<unit>]" from the dataset's ``units`` (or ``unit``) attribute, else ``default``."""
    unit = attribute(ds, "units") or attribute(ds, "unit") or default
    return f" [{unit}]" if unit else ""


def _components(name, shape):
    """Labels of the columns of an output of per-sample shape ``shape``."""
    if shape == (3,):
        return [f"{name} {c}" for c in COMPONENTS]
    if len(shape) == 2 and shape[1] == 3:
        return [f"{name}[{i}] {c}" for i in range(shape[0]) for c in COMPONENTS]
    return [f"{name}[{i}]" for i in range(int(np.prod(shape)))]


def _plot_output(ax, f, name, t, n):
    ds = f["outputs"][name]
    y = np.asarray(ds[:n], dtype=float)
    if y.shape[0] != n:
        raise InputFileError(f.filename, None, f"{ds.name} has {y.shape[0]} samples, /t has {n}")
    if y.ndim == 1:
        ax.plot(t, y, label=name)
    else:
        for label, col in zip(_components(name, y.shape[1:]), y.reshape(n, -1).T):
            ax.plot(t, col, label=label)
    ax.set_ylabel(f"{name}{_unit(ds)}")
    label = attribute(ds, "label")
    ax.set_title(f"{name}: {label}{_unit(ds)}" if label else f"{name}{_unit(ds)}", fontsize="medium", loc="left")
    if y.ndim > 1 and y[0].size <= 12:
        ax.legend(loc="best", fontsize="small")


def _plot_energy(ax, f, t, n):
    e = f["energy"]
    total, unit = np.zeros(n), " [J]"
    for key in ("kinetic", "potential"):
        if key in e:
            ds = dataset(e, key, f.filename)
            check_shape(ds, (None,), f.filename)
            y = np.asarray(ds[:n], dtype=float)
            ax.plot(t, y, label=key)
            total, unit = total + y, _unit(ds, "J")
    ax.plot(t, total, "k--", label="total")
    ax.set_ylabel(f"energy{unit}")
    ax.set_title(f"energy{unit}: kinetic, potential and their sum", fontsize="medium", loc="left")
    ax.legend(loc="best", fontsize="small")


def _plot_contact(ax, f, name, t, n):
    c = group(f["contacts"], name, f.filename)
    gap = dataset(c, "gap", f.filename)
    force = dataset(c, "force", f.filename)
    check_shape(gap, (None,), f.filename)
    check_shape(force, (None, 3), f.filename)
    g = np.asarray(gap[:n], dtype=float)
    fv = np.asarray(force[:n], dtype=float)
    if "normal" in c:
        nv = np.asarray(c["normal"][:n], dtype=float)
        fn = np.abs(np.einsum("ij,ij->i", fv, nv))
        fn[np.linalg.norm(fv, axis=1) == 0] = 0.0           # open contact: no force, normal may be NaN
        force_label = f"normal force |f·n|{_unit(force, 'N')}"
    else:
        fn = np.linalg.norm(fv, axis=1)
        force_label = f"contact force |f|{_unit(force, 'N')}"
    ax.plot(t, g, color="C0", label="gap")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_ylabel(f"{name}: gap g_N{_unit(gap, 'm')}", color="C0")
    twin = ax.twinx()
    twin.plot(t, fn, color="C3", label="normal force")
    twin.set_ylabel(force_label, color="C3")
    plain_axis(twin.yaxis)
    ax.set_title(f"contact {name}: normal gap and normal force", fontsize="medium", loc="left")


def result_figure(result_path, names=None):
    """The matplotlib Figure (Agg canvas attached) of :func:`plot_result`, unsaved."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = Path(result_path)
    with open_result(path) as f:
        available = available_names(f)
        if names is None or len(names) == 0:
            names = default_names(f)
            if not names:
                raise InputFileError(path, None, "nothing to plot: no outputs, energy or contacts")
        else:
            names = [names] if isinstance(names, str) else list(names)
            unknown = [nm for nm in names if nm not in available]
            if unknown:
                raise InputFileError(path, None, f"no {', '.join(map(repr, unknown))} in the file; "
                                                 f"available: {', '.join(available) or '(nothing)'}")
        n = f["t"].shape[0]
        if n == 0:
            raise InputFileError(path, None, "no samples written yet")
        t = np.asarray(f["t"][:n], dtype=float)

        fig = Figure(figsize=(WIDTH, 1.2 + SUBPLOT_HEIGHT * len(names)), dpi=DPI)
        FigureCanvasAgg(fig)
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
        for ax, name in zip(axes, names):
            if name == "energy":
                _plot_energy(ax, f, t, n)
            elif name.startswith("contact:"):
                _plot_contact(ax, f, name[len("contact:"):], t, n)
            else:
                _plot_output(ax, f, name, t, n)
            ax.grid(True, alpha=0.3)
            plain_axis(ax.yaxis)
            plain_axis(ax.xaxis)
        axes[-1].set_xlabel(f"t{_unit(f['t'], 's')}")
        fig.suptitle(_title(f, path, n))
    fig.tight_layout()
    return fig


def plot_result(result_path, names=None, out=None, overwrite=False) -> Path:
    """Plot outputs, energy and contacts of a result file against time; write a PNG.

    Parameters
    ----------
    result_path : str or os.PathLike
        An ffrmbs result file (layout in :mod:`mbs.results.result_file`).
    names : list of str, optional
        Output names (``/outputs/<name>``), ``energy`` or ``contact:<name>``; one subplot
        each, in this order. Default: every output plus ``energy`` when recorded (the
        contacts when the file has neither).
    out : str or os.PathLike, optional
        The PNG to write (replaced if it exists). Default: a new file beside the result
        file, ``<stem>-plot.png``, else ``<stem>-plot-2.png``, ``-3``, ... (the run's own
        ``<stem>.png`` is never touched).
    overwrite : bool
        Without ``out``: write ``<stem>-plot.png`` even if it exists.

    Returns
    -------
    Path
        The PNG written.

    Raises
    ------
    InputFileError
        Not an ffrmbs result file, a damaged one, a missing or malformed dataset, or an
        unknown name (the message lists the available ones). No PNG is written.
    OutputFileError
        The PNG cannot be written (a full disk, no permission); no partial file is left.
    """
    result_path = Path(result_path)
    out = Path(out) if out is not None else new_plot_path(result_path, overwrite)
    fig = result_figure(result_path, names)
    remove_stale(out.parent, f".{out.name}.tmp-")        # what a plot killed while writing left
    tmp = out.with_name(f".{out.name}.tmp-{os.getpid()}")
    try:
        if out.parent and not out.parent.exists():
            raise FfrmbsError(f"cannot write {out}: no directory {out.parent}")
        fig.savefig(tmp, format="png")
        os.replace(tmp, out)
    except OSError as exc:
        raise OutputFileError(out, f"cannot write the plot: {os_reason(exc)}") from None
    finally:
        if tmp.exists():
            tmp.unlink()
    return out


def new_plot_path(result_path, overwrite=False) -> Path:
    """``<stem>-plot.png`` beside the result file; unless ``overwrite``, the first of
    ``<stem>-plot-2.png``, ``-3``, ... that does not exist when it does."""
    result_path = Path(result_path)
    first = result_path.with_name(f"{result_path.stem}-plot.png")
    if overwrite or not first.exists():
        return first
    k = 2
    while (candidate := result_path.with_name(f"{result_path.stem}-plot-{k}.png")).exists():
        k += 1
    return candidate
