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

import numpy as np

from contact import UnilateralNewtonImpact, connect
from contours import Contour2sNeutralFFR, SphereContour
from contours.fitting import fit_report
from ffrmbs_app.scenes.cache import cached_body
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from preprocess import Material, build_body
from preprocess.geometry import gmsh_session, mesh_from_gmsh_model
from validation import CaseResult, make_row, timed

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
    top = Contour2sNeutralFFR(plate, "top")
    ball = system.add(PointMass(BALL_MASS, position=position, velocity=velocity, name="ball"))
    sphere = SphereContour(ball.point, BALL_RADIUS)
    system.add(connect(sphere, top, UnilateralNewtonImpact(0.0), name="face"))
    rim_contacts = []
    if rims:
        for i, rim in enumerate(top.rims()[1:]):
            rim_contacts.append(system.add(connect(sphere, rim, UnilateralNewtonImpact(0.0), name=f"rim {i + 1}")))
    return system, ball, top, rim_contacts
