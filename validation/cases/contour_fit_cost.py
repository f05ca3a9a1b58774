"""Cost of a fitted 2s contour per step against the patch's node count, and its one-off fit.

Claim under test (issue 20, "Cost"): a contour fitted by least squares to an unstructured
face patch has control points P_ū0 = F ū0 and P_Φ = F Φ computed once
(:mod:`contours.fitting`), so per step it costs what an interpolated contour costs: the
compiled ``update(q, u, t)`` stores the body state, O(n_f), and an evaluation at (η, ξ) is
span-local, O((p + 1)² n_f) — both independent of the number of patch nodes and of
control points. The reference route's full control-point update (P_ū = P_ū0 + P_Φ q_f
and P_r = R + A P_ū over all control points, used on demand for geomdl export and plots)
is O(control points × n_f).

Setup: the top face ``z1`` of the plate [0, 0.2] x [0, 0.1] x [0, 0.005] m, gmsh default
unstructured meshes at decreasing mesh size (:data:`MESHES`: tet4 at the coarsest size for
about 100 patch nodes, then tet10; quick: up to about 2 000 patch nodes, full: up to about
8 000), steel, :data:`N_MODES` clamped modes (clamp ``x0``), a free body frame
(quaternion). The contour is fitted with the default control points (knot spans of about
two node spacings: control points grow with the patch nodes).

Timed with one BLAS thread (threadpoolctl, restored afterwards: process CPU time counts
every thread, and idle BLAS threads spinning after a small product would be counted) —
process CPU time per call, numba compilation excluded, after a warm-up: the
medians of :data:`REPEATS` batches of :data:`MIN_BATCH_S` CPU seconds each, by
:func:`validation.cpu_samples`; the batches of the operations of one mesh interleave, so
a change of the machine's load hits them alike; differences of a few µs between meshes
are such load):

* ``update``: ``contour.update(q, u, t)``, compiled (the step's contour stage);
* ``update_full``: ``update`` plus the full control-point update of the reference route
  (``contour.position_field`` brought up to date);
* ``evaluate``: ``contour.evaluate(point, η, ξ)`` — position, derivatives, frame — by the
  span-local compiled kernel, the route of the step's detection (:mod:`mbs.run.fused_detection`
  calls the same kernel inside numba);
* ``evaluate_J``: the same with ``jacobians=True`` (J_T, J_R: what a closed contact needs).

States are random (large rotation and translation, elastic displacements ~ 2 mm, random
velocities; :func:`validation.bench.common.moving_state`) and points (η, ξ) uniform at
random in [0, 1]², cycled from call to call. One-off (``timed`` once each): ``fit`` — the
whole contour construction (patch, map, factored fit, F ū0 and F Φ, material side);
extra columns ``patch_s`` (surface patch), ``map_s`` (mean-value map), ``factor_s``
(collocation, Gram matrices and sparse LU of the normal equations), ``products_s``
(F ū0 and F Φ, i.e. one solve with 3 + 3 n_f right-hand sides). The fit row's error is the
worst mode's max nodal fit error relative to its largest nodal value (fit report); the
per-step rows have no error (NaN).
"""

from __future__ import annotations

import math

import numpy as np
from threadpoolctl import threadpool_limits

from contours import Contour2sNeutralFFR
from contours.base import ContourPoint
from contours.fitting import SurfaceFit, SurfacePatch, default_control_points, fit_report, parameterize
from mbs import FlexibleBodyFFR
from preprocess import Material, build_body
from preprocess.geometry import box
from validation import CaseResult, cpu_samples, make_row, timed
from validation.bench.common import moving_state

NAME = "contour_fit_cost"
DESCRIPTION = ("fitted 2s contour on unstructured plate faces of ~100 to ~8 000 patch nodes: per-step update "
               "and evaluation cost (flat) and the one-off fit time")

MATERIAL = Material(7800.0, 2.1e11, 0.3)      # steel, SI
PLATE = (0.2, 0.1, 0.005)                     # lx, ly, lz [m]
N_MODES = 10
MESHES = {True: ((0.02, 1), (0.02, 2), (0.01, 2), (0.007, 2)),
          False: ((0.02, 1), (0.02, 2), (0.01, 2), (0.007, 2), (0.005, 2), (0.0035, 2))}   # (h [m], order)
REPEATS = {True: 7, False: 9}
MIN_BATCH_S = 0.05                            # CPU seconds per timed batch
N_STATES = 16
N_POINTS = 64
OPERATIONS = ("update", "update_full", "evaluate", "evaluate_J")
ERROR_KIND = "mode-shape fit error (max node, rel.)"


def plate_body(h, order):
    """A free FFR body of the plate meshed at size ``h`` [m] with tetrahedra of ``order``."""
    return FlexibleBodyFFR(build_body(box(*PLATE, h, order=order), MATERIAL, N_MODES, clamp="x0"), N_MODES)


def fit_pieces(body, group="z1"):
    """CPU seconds of the fit's steps on ``group``: (patch, map, factor, products)."""
    data = body.data
    patch, t_patch = timed(SurfacePatch, data.u0, data.surface_triangles, body.node_group(group))
    (params, closed), t_map = timed(parameterize, patch)
    counts = default_control_points(patch, params, (3, 3), closed)
    fit, t_factor = timed(SurfaceFit, params, counts, 3, closed)
    _, t_products = timed(lambda: (fit.control_points(data.u0[patch.nodes]),
                                   fit.control_points(body.phi_nodes[patch.nodes])))
    return t_patch, t_map, t_factor, t_products


def step_operations(body, contour, rng):
    """The per-step operations of the module docstring as functions of no argument."""
    states = [moving_state(body, rng) for _ in range(N_STATES)]
    points = rng.uniform(size=(N_POINTS, 2))
    point = ContourPoint(body.nu)
    counter = iter(range(10 ** 12))

    def update():
        contour.update(*states[next(counter) % N_STATES], 0.0)

    def update_full():
        update()
        return contour.position_field

    def evaluate(jacobians=False):
        eta, xi = points[next(counter) % N_POINTS]
        contour.evaluate(point, eta, xi, jacobians=jacobians)

    contour.update(*states[0], 0.0)
    return update, update_full, evaluate, lambda: evaluate(True)


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("operation",))
    rng = np.random.default_rng(0)
    warm = plate_body(*MESHES[quick][0])
    [fn() for fn in step_operations(warm, Contour2sNeutralFFR(warm, "z1"), rng)]   # load compiled kernels
    table = []
    for h, order in MESHES[quick]:
        body = plate_body(h, order)
        with threadpool_limits(limits=1, user_api="blas"):
            contour, t_fit = timed(Contour2sNeutralFFR, body, "z1")
            pieces = fit_pieces(body)
        k, fit = contour.patch.k, contour.fit
        ctrl0, phi = contour.kernel_data[-4], contour.kernel_data[-3]
        report = fit_report(fit, contour.patch, body.phi_nodes[contour.patch.nodes])
        mode_error = max(r["node_max"] for r in report.rows[1:])
        common = dict(mesh_size=h, order=order, body_nodes=body.data.n_nodes,
                      control_points=fit.eta.n_unique * fit.xi.n_unique, ctrl0_size=ctrl0.size, phi_size=phi.size)
        with threadpool_limits(limits=1, user_api="blas"):
            timings = cpu_samples(step_operations(body, contour, rng), REPEATS[quick], MIN_BATCH_S)
        for name, timing in zip(OPERATIONS, timings):
            result.rows.append(make_row(NAME, {"patch_nodes": k}, timing.median, None, ERROR_KIND,
                                        "nodal mode shapes", operation=name, **common))
        result.rows.append(make_row(NAME, {"patch_nodes": k}, t_fit, mode_error, ERROR_KIND, "nodal mode shapes",
                                    operation="fit", patch_s=pieces[0], map_s=pieces[1], factor_s=pieces[2],
                                    products_s=pieces[3], **common))
        table.append((k, common, [t.median for t in timings], t_fit, pieces, mode_error))
    result.notes += [_table(table), _slopes(table)]
    return result


def _table(table):
    lines = ["| patch nodes | body nodes | h [m] | order | control points | update [µs] | update_full [µs] | "
             "evaluate [µs] | evaluate_J [µs] | fit [s] | patch [s] | map [s] | factor [s] | F·(ū0, Φ) [s] | "
             "mode fit error |", "|" + "---|" * 15]
    for k, c, t, t_fit, pieces, err in table:
        lines.append(f"| {k} | {c['body_nodes']} | {c['mesh_size']:g} | {'tet10' if c['order'] == 2 else 'tet4'} | "
                     f"{c['control_points']} | " + " | ".join(f"{1e6 * x:.2f}" for x in t) +
                     f" | {t_fit:.3f} | " + " | ".join(f"{x:.3f}" for x in pieces) + f" | {err:.2e} |")
    return "\n".join(lines)


def _slopes(table):
    """Log-log slopes of each time against patch nodes and control points, smallest to
    largest patch: ~0 for a cost independent of them, ~1 for a linear one."""
    (k0, c0, t0, f0, _, _), (k1, c1, t1, f1, _, _) = table[0], table[-1]
    lk, lc = math.log(k1 / k0), math.log(c1["control_points"] / c0["control_points"])
    lines = [f"Log-log slopes from {k0} to {k1} patch nodes ({c0['control_points']} to {c1['control_points']} "
             "control points): d ln t / d ln(patch nodes), d ln t / d ln(control points) — 0 is flat, 1 linear:", ""]
    for name, a, b in list(zip(OPERATIONS, t0, t1)) + [("fit", f0, f1)]:
        lines.append(f"- {name}: {math.log(b / a) / lk:.2f}, {math.log(b / a) / lc:.2f} "
                     f"({1e6 * a:.3g} µs → {1e6 * b:.3g} µs)")
    n = np.array([row[1]["control_points"] for row in table], dtype=float)
    lines += ["", "Least-squares line t = t₀ + c · (control points) per operation (a constant Python overhead t₀ "
              "hides a linear part in the log-log slopes):", ""]
    for j, name in enumerate(OPERATIONS):
        c, t0 = np.polyfit(n, [row[2][j] for row in table], 1)
        lines.append(f"- {name}: t₀ = {1e6 * t0:.3g} µs, c = {1e9 * c:.3g} ns per control point")
    return "\n".join(lines)
