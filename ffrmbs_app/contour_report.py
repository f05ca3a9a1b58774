"""``ffrmbs contour``: a 2s contour fitted to a face group of a body, its fit report, a PNG
and ParaView files.

:func:`fit_group` fits the node group the way a 2s contour on a group that is not a
structured grid is fitted (:func:`contours.fitting.surface_fit`: the patch's nodes mapped
onto the unit square, a least-squares cubic B-spline surface S(η, ξ)) and reports the
fit (:func:`contours.fitting.fit_report`: distances of S from the FE surface at the nodes
and triangle mid-points, the normal's angle error, each mode shape's fit error). It also
tells whether the group is a planar structured grid (:func:`contours.node_matrix`), which a
2s contour interpolates exactly instead (thesis eq. 3.24); the fit is reported either way.

:func:`write_contour_files` writes into the output directory, for a group named G (its
characters other than letters, digits, ``_`` and ``-`` replaced by ``_``, so that the
files stay inside the directory):

* ``G-fit.png`` — the patch's FE surface triangles coloured by the mid-point distance
  |S(η_m, ξ_m) − x_m| of each triangle, the contour's knot lines (η and ξ constant at the
  knots: the boundaries of its polynomial pieces; every k-th of them when there are over
  :data:`MAX_LINES`) drawn over it, equal axis scales;
* ``G-fit.vtu`` — the FE surface triangles of the patch (VTK ``triangle``, or
  ``triangle6`` for tet10 bodies) with point data ``deviation`` = |S(η_i, ξ_i) − x_i| [m],
  ``eta``, ``xi`` (the node's parameters) and ``node`` (FE node number), and cell data
  ``mid_deviation`` [m] (at the triangle's mid-point);
* ``G-contour.vtu`` — the contour itself: S sampled on a grid of
  :data:`SAMPLES_PER_SPAN` points per knot span in each direction, as quads (on a face
  with holes those whose centre lies in a hole left out: the trim), with point data
  ``eta`` and ``xi``.

A face with holes (several boundary loops, not a band closing around an axis) is fitted
over its outer loop's square and trimmed to its material (:mod:`contours.fitting.trim`);
:meth:`GroupFit.describe` names the trim and the face's rims — its outer edge and each
hole's rim, the edge contours of :meth:`contours.Contour2sNeutralFFR.rims` — with their
node counts, lengths and (holes) centres and mean radii.

Open both ``.vtu`` files in ParaView to see the contour over the FE surface. Lengths are
in m (the body's undeformed body-frame positions ū0). Each file is written to a temporary
name in the directory and renamed into place, replacing an earlier file of the same name;
a refused input writes nothing.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from contours import node_matrix
from contours.fitting import SMOOTHING, Trim, fit_report, surface_fit
from ffrmbs.errors import FfrmbsError, ModelError, OutputFileError, os_reason
from ffrmbs_app.output_dirs import new_directories

DEGREE = 3               #: the contour's degree in both directions (C²)
SAMPLES_PER_SPAN = 4     #: contour samples per knot span and direction (the .vtu grid, the PNG's lines)
MAX_LINES = 25           #: knot lines per direction drawn on the PNG at most
LENGTH_UNITS = ((1.0, "m"), (1e-3, "mm"), (1e-6, "µm"), (1e-9, "nm"))
TRIANGLE_CELLS = {3: "triangle", 6: "triangle6"}


def parse_control_points(text):
    """``--control-points``: None (the default counts), ``"N"`` -> N or ``"NE,NX"`` ->
    (NE, NX), each an integer of at least DEGREE + 1; FfrmbsError otherwise."""
    if text is None:
        return None
    parts = str(text).split(",")
    counts = []
    for part in parts:
        try:
            n = int(part.strip())
        except ValueError:
            n = None
        if n is None or n < DEGREE + 1 or len(parts) > 2:
            raise FfrmbsError(f"--control-points: expected N or NE,NX with integers >= {DEGREE + 1} (a cubic "
                              f"contour needs {DEGREE + 1} control points per direction), got {text!r}")
        counts.append(n)
    return counts[0] if len(counts) == 1 else tuple(counts)


def parse_smoothing(text) -> float:
    """``--smoothing``: a finite number >= 0 (the dimensionless thin-plate weight of
    :mod:`contours.fitting.bspline_fit`); FfrmbsError otherwise."""
    if text is None:
        return SMOOTHING
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 0:
        raise FfrmbsError(f"--smoothing: expected a finite number >= 0, got {text!r}")
    return value


@dataclass
class GroupFit:
    """A node group's fitted contour and its errors (lengths in m).

    - group : the node group's name.
    - fit, patch : the :class:`~contours.fitting.SurfaceFit` and
      :class:`~contours.fitting.SurfacePatch`.
    - report : the :class:`~contours.fitting.FitReport` (geometry and every mode; its
      ``ctrl``, ``node_deviation`` and ``mid_deviation`` are drawn and written).
    - grid : (n_η, n_ξ) of the node matrix O when the group is a planar structured grid, else None.
    - trim : the :class:`~contours.fitting.Trim` of a face with holes, else None.
    """

    group: str
    fit: object
    patch: object
    report: object
    grid: tuple | None
    trim: object = None

    def surface(self, params) -> np.ndarray:
        """(m, 3) S(η, ξ) at the parameters ``params`` (m, 2) [m]."""
        return self.fit.collocation(params) @ self.report.ctrl

    def describe(self) -> str:
        """Lines naming the patch and the route a 2s contour on the group takes."""
        p = self.patch
        kind = "6-node (tet10)" if p.order == 2 else "3-node (tet4)"
        if self.fit.eta.closed:
            shape = "a closed band, periodic in eta"
        elif self.trim is not None:
            holes = len(self.trim.polygons)
            shape = f"a face with {holes} hole{'s' if holes > 1 else ''}"
        else:
            shape = "a face"
        lines = [f"node group {self.group!r}: {p.k} nodes on {len(p.triangles)} {kind} surface triangles, {shape}"]
        if self.trim is not None:
            lines.append("trimmed: the surface is fitted over the outer edge's square on the material's nodes (the "
                         "holes filled smoothly) and trimmed to the material: a contact point in a hole is no contact")
            lines += self._rims()
        if self.grid is not None:
            lines.append(f"a structured grid of {self.grid[0]} x {self.grid[1]} nodes: a 2s contour on it "
                         f"interpolates the nodes exactly (node matrix O, thesis eq. 3.24); given control points "
                         f"it is fitted as reported below")
        else:
            lines.append("not a structured grid: a 2s contour on it is fitted by least squares as reported below")
        return "\n".join(lines)


    def _rims(self) -> list:
        """One line per rim of a face with holes: the outer edge, then each hole."""
        outer, holes = self.patch.outer_and_holes()
        lines = ["rims (edge contours: Contour2sNeutralFFR.rims(), a sphere meets them as edges):"]
        for i, loop in enumerate([outer] + holes):
            x = self.patch.points[loop]
            length = float(np.linalg.norm(x - np.roll(x, 1, axis=0), axis=1).sum())
            what = "outer edge" if i == 0 else f"rim {i}"
            line = f"  {what}: {len(loop)} nodes, length {length:.4g} m"
            if i:
                centre = x.mean(axis=0)
                radius = np.linalg.norm(x - centre, axis=1).mean()
                line += (f", centre ({centre[0]:.4g}, {centre[1]:.4g}, {centre[2]:.4g}) m, mean radius "
                         f"{radius:.4g} m")
            lines.append(line)
        return lines


def fit_group(body, group, control_points=None, smoothing=SMOOTHING, source="the body") -> GroupFit:
    """Fit the node ``group`` of ``body`` (a :class:`preprocess.BodyData`) and report it.

    control_points : None (:func:`contours.fitting.default_control_points`), N or (n_η, n_ξ).
    smoothing : the dimensionless thin-plate weight.
    source : how to name the body in an error (its path).

    Raises ModelError: an unknown group (the known ones listed), a body without surface
    triangles, a group that is not one connected face or band of the surface, a singular fit.
    """
    groups = body.node_groups
    if group not in groups:
        known = ", ".join(sorted(groups)) or "none (text body files hold none: give the body.h5)"
        raise ModelError(f"no node group {group!r} in {source}; node groups: {known}")
    if body.surface_triangles is None:
        raise ModelError(f"{source} holds no surface triangles (text body files have none: give the body.h5)")
    nodes = groups[group]
    fit, patch = surface_fit(body.u0, body.surface_triangles, nodes, control_points, DEGREE, smoothing,
                             f"node group {group!r}")
    phi = body.phi.reshape(body.n_nodes, 3, body.n_modes)[patch.nodes]
    report = fit_report(fit, patch, phi, group)
    try:
        grid = node_matrix(body.u0, nodes).shape
    except ModelError:
        grid = None
    return GroupFit(group, fit, patch, report, grid, Trim.of_fit(fit, patch))


# --------------------------------------------------------------------------- sampling


def knot_values(direction) -> np.ndarray:
    """The distinct knots of a :class:`~contours.fitting.FitDirection` in its domain
    [0, 1] ([0, 1) when closed: 1 is 0)."""
    k = np.unique(direction.knots[(direction.knots >= 0.0) & (direction.knots <= 1.0)])
    return k[:-1] if direction.closed else k


def samples(direction) -> np.ndarray:
    """:data:`SAMPLES_PER_SPAN` parameters per knot span over [0, 1] (closed: [0, 1), the
    seam once)."""
    spans = knot_values(direction).size - (0 if direction.closed else 1)
    n = SAMPLES_PER_SPAN * spans
    return np.arange(n) / n if direction.closed else np.linspace(0.0, 1.0, n + 1)


def contour_grid(gf: GroupFit):
    """(points (n_η n_ξ, 3) [m], quads (Q, 4), params (n_η n_ξ, 2)): S sampled on
    :func:`samples` of each direction, η-major, quads wrapping across a closed seam; on a
    face with holes the quads whose centre lies in a hole left out."""
    eta, xi = samples(gf.fit.eta), samples(gf.fit.xi)
    params = np.stack(np.meshgrid(eta, xi, indexing="ij"), axis=-1).reshape(-1, 2)
    ne, nx = eta.size, xi.size
    idx = np.arange(ne * nx).reshape(ne, nx)
    if gf.fit.eta.closed:
        idx = np.vstack([idx, idx[:1]])
    if gf.fit.xi.closed:
        idx = np.hstack([idx, idx[:, :1]])
    quads = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], axis=-1).reshape(-1, 4)
    if gf.trim is not None:
        quads = quads[gf.trim.contains_many(params[quads].mean(axis=1))]
    return gf.surface(params), quads, params


# --------------------------------------------------------------------------- figure


def length_unit(value):
    """(scale, name) of the largest unit of :data:`LENGTH_UNITS` in which ``value`` [m] is
    at least 1 (nm for anything smaller)."""
    for scale, name in LENGTH_UNITS:
        if value >= scale:
            return scale, name
    return LENGTH_UNITS[-1]


def fit_figure(gf: GroupFit):
    """The matplotlib Figure (Agg canvas attached) of ``G-fit.png`` (module docstring)."""
    from matplotlib import colormaps
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    patch, report = gf.patch, gf.report
    geometry = report.rows[0]
    scale, unit = length_unit(max(geometry["node_max"], geometry["mid_max"]))
    fig = Figure(figsize=(8.0, 7.0), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    ax.computed_zorder = False                   # the knot lines stay above the surface

    per_triangle = len(patch.linear) // len(patch.triangles)          # 4 sub-triangles of a 6-node one
    colour = np.repeat(gf.report.mid_deviation, per_triangle) / scale
    norm = Normalize(0.0, colour.max() if colour.max() > 0 else 1.0)
    cmap = colormaps["viridis"]
    ax.add_collection3d(Poly3DCollection(patch.points[patch.linear], facecolors=cmap(norm(colour)),
                                         edgecolors=(0, 0, 0, 0.15), linewidths=0.3, zorder=1))
    legend = []
    for direction, other, column in ((gf.fit.eta, gf.fit.xi, 0), (gf.fit.xi, gf.fit.eta, 1)):
        values = knot_values(direction)
        stride = max(1, math.ceil(values.size / MAX_LINES))
        values = values[::stride]
        legend.append(("eta white" if column == 0 else "xi black") + (f" (every {stride})" if stride > 1 else ""))
        along = samples(other)
        if other.closed:
            along = np.append(along, 1.0)
        for v in values:
            params = np.empty((along.size, 2))
            params[:, column], params[:, 1 - column] = v, along
            x = gf.surface(params)
            ax.plot(x[:, 0], x[:, 1], x[:, 2], color="white" if column == 0 else "black", lw=0.8, zorder=2)

    lo, hi = patch.points.min(axis=0), patch.points.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo).max()
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    bar = fig.colorbar(ScalarMappable(norm, cmap), ax=ax, shrink=0.7, pad=0.1)
    bar.set_label(f"mid-point distance of the contour from the FE surface [{unit}]")
    ne, nx = report.control_points
    fig.suptitle(f"node group {gf.group!r}: fitted 2s contour, {ne} x {nx} control points "
                 f"(knot lines: {', '.join(legend)})\n"
                 f"distance to the FE surface [{unit}]: nodes max {geometry['node_max'] / scale:.3g}, "
                 f"RMS {geometry['node_rms'] / scale:.3g}; mid-points max {geometry['mid_max'] / scale:.3g}, "
                 f"RMS {geometry['mid_rms'] / scale:.3g}", fontsize=10)
    return fig


# --------------------------------------------------------------------------- ParaView


def fit_mesh(gf: GroupFit):
    """The meshio Mesh of ``G-fit.vtu``: the FE surface triangles of the patch with the
    fit's deviations (module docstring)."""
    import meshio

    p = gf.patch
    return meshio.Mesh(p.points, [(TRIANGLE_CELLS[p.triangles.shape[1]], p.triangles)],
                       point_data={"deviation": gf.report.node_deviation, "eta": gf.fit.params[:, 0],
                                   "xi": gf.fit.params[:, 1], "node": p.nodes},
                       cell_data={"mid_deviation": [gf.report.mid_deviation]})


def contour_mesh(gf: GroupFit):
    """The meshio Mesh of ``G-contour.vtu``: the contour sampled on quads (module docstring)."""
    import meshio

    points, quads, params = contour_grid(gf)
    return meshio.Mesh(points, [("quad", quads)], point_data={"eta": params[:, 0], "xi": params[:, 1]})


def file_stem(group: str) -> str:
    """The group's name as a file-name stem: every character other than a letter, digit,
    ``_`` or ``-`` replaced by ``_`` (no path separator, no ``..``)."""
    return re.sub(r"[^A-Za-z0-9_-]", "_", group) or "_"


def write_contour_files(gf: GroupFit, out_dir) -> list[Path]:
    """Write ``G-fit.png``, ``G-fit.vtu`` and ``G-contour.vtu`` into ``out_dir`` (created
    with its missing parents; module docstring); return their paths. OutputFileError when
    they cannot be written: then none of them is left half-written and the directories
    created are removed."""
    import meshio

    out_dir = Path(out_dir)
    stem = file_stem(gf.group)
    writers = {f"{stem}-fit.png": lambda path: fit_figure(gf).savefig(path, format="png"),
               f"{stem}-fit.vtu": lambda path: meshio.write(path, fit_mesh(gf), file_format="vtu"),
               f"{stem}-contour.vtu": lambda path: meshio.write(path, contour_mesh(gf), file_format="vtu")}
    temporaries = []
    try:
        with new_directories(out_dir):
            try:
                for name, write in writers.items():
                    tmp = out_dir / f".{name}.tmp-{os.getpid()}"
                    temporaries.append(tmp)
                    write(tmp)
                for tmp, name in zip(temporaries, writers):
                    os.replace(tmp, out_dir / name)
            except BaseException:
                for tmp in temporaries:
                    tmp.unlink(missing_ok=True)
                raise
    except OSError as exc:
        raise OutputFileError(out_dir, f"cannot write the contour files: {os_reason(exc)}") from None
    return [out_dir / name for name in writers]
