"""The default scene (thesis Sec. 5.2, setup A) with another contact of the same point
mass: its point or a sphere about it, against the beam's top face (2s), its band, or a
curve along the top face's centre line (1s, or that line as a sharp edge) — one scene per
pair kind with a fused detection on a flexible body (mbs.run.fused_detection), for the
tests that compare or time them."""

import dataclasses

from contact import (Contact, ContactKinematicsPointContour1s, ContactKinematicsSphereContour1s,
                     ContactKinematicsSphereContour2s, ContactKinematicsSphereEdge)
from contours import Contour1sEdgeFFR, Contour1sNeutralFFR, PointContour, SphereContour

RADIUS = 0.01       # [m], the sphere on the point mass
PAIRS = [("point", "2s"), ("sphere", "2s"), ("point", "band"), ("sphere", "band"), ("point", "1s"),
         ("sphere", "1s"), ("sphere", "edge")]


def centre_scene(law="impact", side="point", contour="2s", modes=20):
    """The default scene (with its ``contour``, "2s" or "band", or "1s": a curve along the
    top face's centre line, or "edge": that line as a sharp edge); with ``side="sphere"``
    its contact made of a sphere of RADIUS about the point mass's point against the same
    contour, with the same law."""
    from ffrmbs_app.scenes import point_mass_beam as pmb

    scene = pmb.build("A", modes=modes, law=law, contour=contour if contour in ("2s", "band") else "2s")
    if side == "point" and contour != "1s":
        return scene
    old = scene.contact
    surface = old.kinematics.contour2
    if contour in ("1s", "edge"):
        curve = Contour1sEdgeFFR if contour == "edge" else Contour1sNeutralFFR
        surface = curve.along_line(scene.beam, (0.0, pmb.HEIGHT, pmb.WIDTH / 2), (1, 0, 0), normal=(0, 1, 0),
                                   degree=4)
    point = PointContour(scene.mass.point) if side == "point" else SphereContour(scene.mass.point, RADIUS)
    kinematics = {("point", "1s"): ContactKinematicsPointContour1s, ("sphere", "1s"): ContactKinematicsSphereContour1s,
                  ("sphere", "edge"): ContactKinematicsSphereEdge}
    kind = kinematics.get((side, contour), ContactKinematicsSphereContour2s)
    contact = Contact(kind(point, surface), old.law, name=f"{side} on {contour}")
    scene.system.contacts[scene.system.contacts.index(old)] = contact
    return dataclasses.replace(scene, contact=contact)
