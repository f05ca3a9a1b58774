"""Contact on a face with a hole (issue 30, item 11): the trimmed 2s contour and the rim.

A steel plate 200 x 40 x 10 mm (ρ = 7800 kg/m³, E = 210 GPa, ν = 0.3) with a through hole
of radius 6 mm at (100, 20) mm, unstructured tet10 (gmsh, mid-edge nodes on the hole),
bottom face clamped, body frame fixed, 6 modes (a nearly rigid support). Its top face
``top`` has two boundary loops (the rectangle and the hole's rim): it is fitted over the
rectangle's square, the hole filled smoothly, and trimmed to the material
(:mod:`contours.fitting.trim`); the hole's rim is a 1s edge contour
(:meth:`contours.Contour2sNeutralFFR.rims`, pair kind sphere–edge). A steel ball (point
mass 5 g with a sphere contour r = 4 mm), gravity 9.81 m/s² along −z, Moreau θ = 0.5,
Newton impact e = 0, frictionless.

Checks (rows: error against CPU seconds of the simulation):

1. **Fit** — the top face's fit with and without the hole (same mesh size): the largest
   distance of the fitted surface from the exact face z = lz over the material (the nodes
   and a grid of points in the trimmed domain: |S_z − lz|, the face being flat any
   in-plane offset is no error), against the face without the hole; and the fit report's
   parametric node and mid-point bounds (:func:`contours.fitting.fit_report`; with curved
   tet10 rim edges the mid-point bound holds an in-plane offset of the quadratic
   triangles' mid-points, not a distance from the face).
2. **Beside the hole** — the ball released 1 mm above the top at (60, 20) mm: rest height
   z = lz + r. Error |z_settled − (lz + r)| / r, bound as in
   :mod:`validation.cases.contact_unstructured` (the closing step's offset v Δt plus
   the fit bound).
3. **Over the hole** — released over the hole's centre: it falls through (no contact with
   the face, none with the rim: r < the hole's radius). Error: the ball's z after
   the time of free fall to z = −2 r compared with free fall, |z − z_free| / r (0: it
   fell freely); column ``contacts_closed``: steps with a closed contact (0).
4. **Rolling into the hole** — the ball on the top, frictionless, sliding at v = 0.1 m/s
   along +x towards the hole from x = 80 mm: once the centre passes over the rim its
   face contact opens and the rim takes over; the rim contact's normal at its first
   closed step must point from the rim point to the ball's centre, (c − r_rim)/|c − r_rim|
   (error: 1 − nᵀ (c − r_rim)/|c − r_rim|), and the ball ends below the top (it dropped
   into the hole; column ``z_end_below_top_m``).
"""

from __future__ import annotations

import warnings

import numpy as np

from contact import UnilateralNewtonImpact, connect
from contours import Contour2sNeutralFFR, SphereContour
from contours.fitting import Trim, fit_report, surface_fit
from contours.fitting.report import midpoints
from ffrmbs_app.scenes.cache import cached_body
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from preprocess import Material, build_body
from preprocess.geometry import gmsh_session, mesh_from_gmsh_model
from validation import CaseResult, make_row, timed
from validation.cases.contact_unstructured import closing_offset

NAME = "contact_hole"
DESCRIPTION = ("contact on a face with a hole: trimmed fit against the face without the hole, ball resting "
               "beside the hole, falling through it, rolling over its rim")

G = 9.81                                          # [m/s²]
STEEL = Material(7800.0, 2.1e11, 0.3)             # [kg/m³], [Pa], [-]
MODES = 6
PLATE = (0.2, 0.04, 0.01)                         # [m] box [0, lx] x [0, ly] x [0, lz]
HOLE = (0.1, 0.02, 0.006)                         # [m] hole centre x, y and radius
MESH = 0.006                                      # [m] element size
BALL_MASS, BALL_RADIUS = 0.005, 0.004             # [kg], [m]
DROP = 1e-3                                       # [m] initial gap
BESIDE = (0.06, 0.02)                             # [m] drop point beside the hole
ROLL_X0, ROLL_V = 0.08, 0.1                       # [m], [m/s] the ball sliding towards the hole


def plate_hole_mesh(size=MESH, order=2, hole=True):
    """The plate [0, lx] x [0, ly] x [0, lz] (PLATE) with a through hole along z (HOLE;
    ``hole=False``: without), tetrahedra of ``order`` at element size ``size`` [m],
    mid-edge nodes on the hole. Node groups: ``top`` (z = lz), ``bottom`` (z = 0),
    ``clamp`` (x = 0), ``body``."""
    lx, ly, lz = PLATE
    eps = 1e-6
    with gmsh_session() as gmsh:
        occ = gmsh.model.occ
        volume = occ.addBox(0.0, 0.0, 0.0, lx, ly, lz)
        if hole:
            cut = occ.addCylinder(HOLE[0], HOLE[1], -lz, 0.0, 0.0, 3 * lz, HOLE[2])
            (volume,), _ = occ.cut([(3, volume)], [(3, cut)])
            volume = volume[1]
        occ.synchronize()
        for name, lo, hi in (("top", (0, 0, lz), (lx, ly, lz)), ("bottom", (0, 0, 0), (lx, ly, 0)),
                             ("clamp", (0, 0, 0), (0, ly, lz))):
            faces = gmsh.model.getEntitiesInBoundingBox(*(c - eps for c in lo), *(c + eps for c in hi), 2)
            gmsh.model.addPhysicalGroup(2, [tag for _, tag in faces], name=name)
        gmsh.model.addPhysicalGroup(3, [volume], name="body")
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
        gmsh.model.mesh.generate(3)
        if order == 2:
            gmsh.model.mesh.setOrder(2)
        return mesh_from_gmsh_model(gmsh, "<plate with a hole>")


def plate_body(hole=True):
    """Body data of the steel plate (cached), bottom face clamped, MODES modes."""
    recipe = {"scene": "contact_hole_plate", "hole": hole, "mesh": MESH, "modes": MODES, "version": 1}
    return cached_body(recipe, lambda: build_body(plate_hole_mesh(hole=hole), STEEL, n_modes=MODES,
                                                  clamp="bottom", params=recipe))


def scene(data, position, velocity=(0.0, 0.0, 0.0), rims=True):
    """(system, ball, top contour, rim contacts): the ball at ``position`` [m] with
    ``velocity`` [m/s] against the trimmed top face and (``rims``) the hole's rim."""
    system = System(gravity=(0.0, 0.0, -G))
    plate = system.add(FlexibleBodyFFR(data, modes=MODES, frame=PrescribedFrameMotion.fixed(), name="plate"))
    with warnings.catch_warnings():
        # the clamped plate's mode shapes fit to 2-3.5 % with or without the hole (the
        # notes); the nearly rigid plate's modes do not enter these checks
        warnings.simplefilter("ignore", UserWarning)
        top = Contour2sNeutralFFR(plate, "top")
    ball = system.add(PointMass(BALL_MASS, position=position, velocity=velocity, name="ball"))
    sphere = SphereContour(ball.point, BALL_RADIUS)
    system.add(connect(sphere, top, UnilateralNewtonImpact(0.0), name="face"))
    rim_contacts = []
    if rims:
        for i, rim in enumerate(top.rims()[1:]):
            rim_contacts.append(system.add(connect(sphere, rim, UnilateralNewtonImpact(0.0), name=f"rim {i + 1}")))
    return system, ball, top, rim_contacts


# --- 1. the fit, with and without the hole ------------------------------------------------

def face_deviation(hole, size=MESH):
    """(max |S_z − lz| [m] on the material, fit report, cpu [s]) of the top face's fit: at
    the nodes, at the report's mid-point parameters and on a 51 x 51 grid of the domain,
    grid points in a hole left out (the trim)."""
    mesh = plate_hole_mesh(size, hole=hole)
    (fit, patch), cpu = timed(surface_fit, mesh.points, mesh.surface_triangles(), mesh.node_groups["top"],
                              name="top")
    report = fit_report(fit, patch, name="top")
    trim = Trim.of_fit(fit, patch)
    grid = np.stack(np.meshgrid(*(np.linspace(0.0, 1.0, 51),) * 2, indexing="ij"), -1).reshape(-1, 2)
    if trim is not None:
        grid = grid[trim.contains_many(grid)]
    _, mid_params = midpoints(patch, patch.points, fit.params)
    params = np.concatenate([fit.params, mid_params, grid])
    z = fit.collocation(params) @ report.ctrl[:, 2]
    return float(np.abs(z - PLATE[2]).max()), report, cpu


def _fit_rows(result, quick) -> float:
    """Rows of check 1; returns the fit bound [m] of the face with the hole at MESH (the
    report's node maximum)."""
    table = ["| mesh | hole | nodes | control points | max abs(S_z − lz) on the material [m] | report node max [m] | "
             "report mid max [m] |", "|---|---|---|---|---|---|---|"]
    for size in (MESH,) if quick else (MESH, MESH / 2):
        for hole in (True, False):
            err, report, cpu = face_deviation(hole, size)
            geometry = report.rows[0]
            if hole and size == MESH:
                bound = geometry["node_max"]
            mesh = f"unstructured tet10 h={size * 1e3:g} mm"
            result.rows.append(make_row(
                NAME, {"check": "fit", "hole": "yes" if hole else "no", "mesh": mesh}, cpu, err,
                "max |S_z − lz| on the material [m]", "the exact face z = lz", patch_nodes=report.k,
                node_max_m=geometry["node_max"], mid_max_m=geometry["mid_max"],
                control_points=list(report.control_points)))
            table.append(f"| {mesh} | {'yes' if hole else 'no'} | {report.k} | {report.control_points[0]} x "
                         f"{report.control_points[1]} | {err:.2e} | {geometry['node_max']:.2e} | "
                         f"{geometry['mid_max']:.2e} |")
    result.notes.append(
        "1. Fit of the top face with and without the hole: the distance of the fitted surface from the exact face "
        "z = lz at the nodes, the triangles' mid-points and a grid over the trimmed domain (rounding, with or "
        "without the hole). The report's mid-point bound is parametric: with the hole's curved tet10 edges it "
        "holds the in-plane offset between a quadratic triangle's mid-point and its middle sub-triangle's "
        "centroid, not a distance from the face.\n\n" + "\n".join(table))
    return bound


# --- 2.-4. the ball beside the hole, over it, rolling into it ------------------------------

def drop(data, xy, dt, t_end):
    """(result with ``z`` [m] and the trace, cpu [s]): the ball released DROP above the top at ``xy``."""
    system, ball, _, _ = scene(data, (*xy, PLATE[2] + BALL_RADIUS + DROP))
    return timed(system.simulate, t_end, dt, integrator="moreau", theta=0.5, trace=True,
                 outputs={"z": lambda t, q, u: q[ball.q_slice][2]})


def _beside_rows(result, data, steps, fit_bound):
    t_end = 0.03                                   # [s] the contact closes at 14 ms
    table = ["| Δt [s] | z settled − (lz + r) [m] | Moreau closing offset [m] | bound [m] |", "|---|---|---|---|"]
    for dt in steps:
        res, cpu = drop(data, BESIDE, dt, t_end)
        z = float(res["z"][res.t >= 0.75 * t_end].mean())
        err = z - (PLATE[2] + BALL_RADIUS)
        bound = fit_bound + np.sqrt(2 * G * DROP) * dt
        result.rows.append(make_row(
            NAME, {"check": "rest beside the hole", "dt": dt, "mesh": f"tet10 h={MESH * 1e3:g} mm"}, cpu,
            abs(err) / BALL_RADIUS, "|z settled − (lz + r)| / r", "analytic rest height lz + r",
            bound_rel=bound / BALL_RADIUS, closing_offset_m=closing_offset(dt), z_settled_m=z))
        table.append(f"| {dt:g} | {err:+.3e} | {closing_offset(dt):+.3e} | {bound:.2e} |")
    result.notes.append(f"2. Ball released {DROP * 1e3:g} mm above the top at {tuple(x * 1e3 for x in BESIDE)} mm "
                        "(beside the hole): rest height against lz + r; the error is the closing step's "
                        "offset (contact_unstructured (a)).\n\n" + "\n".join(table))


def _through_rows(result, data, steps):
    t_end = 0.06                                   # [s] the centre falls 17.7 mm: 1.7 mm below the bottom face
    table = ["| Δt [s] | z(t_end) [m] | free fall [m] | steps with a closed contact |", "|---|---|---|---|"]
    for dt in steps:
        res, cpu = drop(data, HOLE[:2], dt, t_end)
        z_free = PLATE[2] + BALL_RADIUS + DROP - 0.5 * G * res.t[-1] ** 2
        closed = int(np.count_nonzero(res.trace["closed"]))
        err = abs(res["z"][-1] - z_free) / BALL_RADIUS
        result.rows.append(make_row(
            NAME, {"check": "fall through the hole", "dt": dt, "mesh": f"tet10 h={MESH * 1e3:g} mm"}, cpu, err,
            "|z − z_free| / r at t_end", "free fall", contacts_closed=closed, z_end_m=float(res["z"][-1])))
        table.append(f"| {dt:g} | {res['z'][-1]:.6e} | {z_free:.6e} | {closed} |")
    result.notes.append("3. Ball released over the hole's centre: it falls through freely (no contact closes: "
                        "r < the hole's radius).\n\n" + "\n".join(table))


def roll(data, dt, t_end=0.19):
    """(samples (m, 11): q (3), u (3), rim active, rim g_N, rim n (3); cpu [s]) of the
    ball sliding along +x from ROLL_X0 at ROLL_V on the top into the hole."""
    system, ball, _, (rim,) = scene(data, (ROLL_X0, HOLE[1], PLATE[2] + BALL_RADIUS), (ROLL_V, 0.0, 0.0))
    k = rim.kinematics

    def sample(t, q, u):
        return np.concatenate([q[ball.q_slice], u[ball.u_slice], [float(k.active), k.g_N], k.n])

    res, cpu = timed(system.simulate, t_end, dt, integrator="moreau", theta=0.5, outputs={"s": sample})
    return res["s"], cpu


def rim_normal_error(s, dt) -> tuple:
    """(max angle [rad] between the rim contact's normal and (c − r*)/|c − r*| over the
    steps in which it is closed, steps closed): c the ball's centre at the step's midpoint
    (q_m = q_k+1 − Δt/2 u_k+1, Moreau), r* its closest point on the exact circle."""
    q, u, active, g_N, n = s[:, :3], s[:, 3:6], s[:, 6] > 0, s[:, 7], s[:, 8:11]
    closed = active & (g_N <= 1e-6)
    c = q[closed] - 0.5 * dt * u[closed]
    radial = c[:, :2] - HOLE[:2]
    star = np.column_stack([HOLE[:2] + HOLE[2] * radial / np.linalg.norm(radial, axis=1)[:, None],
                            np.full(len(c), PLATE[2])])
    exact = (c - star) / np.linalg.norm(c - star, axis=1)[:, None]
    if not closed.any():
        return np.nan, 0
    cos = np.clip(np.einsum("ij,ij->i", exact, n[closed]), -1.0, 1.0)
    return float(np.arccos(cos).max()), int(closed.sum())


def _roll_rows(result, data, steps):
    table = ["| Δt [s] | rim closed steps | max normal angle error [rad] | z_end − lz [m] | rim normal: first | "
             "last |", "|---|---|---|---|---|---|"]
    for dt in steps:
        s, cpu = roll(data, dt)
        err, closed = rim_normal_error(s, dt)
        on_rim = np.flatnonzero((s[:, 6] > 0) & (s[:, 7] <= 1e-6))
        first, last = (s[on_rim[0], 8:11], s[on_rim[-1], 8:11]) if closed else (np.full(3, np.nan),) * 2
        z_below = float(PLATE[2] - s[-1, 2])
        result.rows.append(make_row(
            NAME, {"check": "roll into the hole", "dt": dt, "mesh": f"tet10 h={MESH * 1e3:g} mm"}, cpu, err,
            "max angle(n_rim, (c − r*)/|c − r*|) [rad]", "exact circle's closest point r*",
            rim_closed_steps=closed, z_end_below_top_m=z_below, first_rim_normal=[float(x) for x in first],
            last_rim_normal=[float(x) for x in last]))
        table.append(f"| {dt:g} | {closed} | {err:.2e} | {-z_below:+.3e} | "
                     f"({first[0]:+.3f}, {first[1]:+.3f}, {first[2]:+.3f}) | "
                     f"({last[0]:+.3f}, {last[1]:+.3f}, {last[2]:+.3f}) |")
    result.notes.append(
        f"4. Ball sliding (frictionless) at {ROLL_V:g} m/s along +x from x = {ROLL_X0 * 1e3:g} mm towards the hole: "
        "the rim contact closes as the centre reaches the rim, the face contact opens once the centre is over the "
        "hole, and the ball tips over the edge into the hole (z_end below the top). The rim's normal points from "
        "the rim to the ball's centre: first nearly up (the centre still over the face), then tilting towards the "
        "hole's centre (+x) as the ball tips over; against the exact circle's normal within the rim curve's "
        "distance from the circle.\n\n" + "\n".join(table))


def run(quick: bool) -> CaseResult:
    result = CaseResult(plot_groups=("check", "hole", "mesh"))
    fit_bound = _fit_rows(result, quick)
    data = plate_body()
    steps = (1e-4,) if quick else (2e-4, 1e-4, 5e-5)
    drop(data, BESIDE, 1e-4, 1e-3)                 # compile
    _beside_rows(result, data, steps, fit_bound)
    _through_rows(result, data, steps)
    _roll_rows(result, data, (2e-4,) if quick else (2e-4, 1e-4, 5e-5))
    return result
