"""Contours on faces with holes (issue 30, items 4 and 11): a face whose boundary has
several loops is told from a closed band, fitted over its outer loop's domain and
trimmed to its material."""

from __future__ import annotations

import numpy as np
import pytest

import gmsh_parts
from contours.fitting import SurfacePatch, surface_fit
from ffrmbs.errors import ModelError


@pytest.fixture(scope="module")
def plate_hole():
    """The gmsh plate with a 12 mm through hole, tet10 at 5 mm."""
    return gmsh_parts.plate_hole_mesh(0.005, order=2)


def test_face_with_a_hole_is_no_band(plate_hole):
    """The top face of a plate with a through hole has two boundary loops like a band, but
    it is a graph over its plane: a face with one hole whose outer loop is the rectangle
    (the plate's 2 (lx + ly) perimeter), never a band periodic in eta."""
    mesh = plate_hole
    patch = SurfacePatch(mesh.points, mesh.surface_triangles(), mesh.node_groups["top"], "top")
    assert patch.topology() == "holes"
    outer, holes = patch.outer_and_holes()
    lx, ly, _ = gmsh_parts.PLATE
    perimeter = np.linalg.norm(np.diff(patch.points[np.append(outer, outer[0])], axis=0), axis=1).sum()
    assert perimeter == pytest.approx(2 * (lx + ly), rel=1e-9)
    (hole,) = holes
    r = np.linalg.norm(patch.points[hole, :2] - gmsh_parts.HOLE[:2], axis=1)
    assert np.allclose(r, gmsh_parts.HOLE[2], rtol=1e-6)


def test_band_stays_a_band():
    """A cylinder's lateral surface (two loops, normals all around): still a closed band."""
    mesh = gmsh_parts.cylinder_mesh(0.02, order=1)
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    side = np.flatnonzero(np.abs(r - gmsh_parts.RADIUS) < 1e-9)
    patch = SurfacePatch(mesh.points, mesh.surface_triangles(), side, "side")
    assert patch.topology() == "annulus"
    fit, _ = surface_fit(mesh.points, mesh.surface_triangles(), side)
    assert fit.eta.closed


def test_face_with_a_hole_is_not_fitted_as_a_band(plate_hole):
    """Never silently accepted as a band: refused with a line naming the holes."""
    mesh = plate_hole
    with pytest.raises(ModelError, match="1 hole"):
        surface_fit(mesh.points, mesh.surface_triangles(), mesh.node_groups["top"], name="top")
