"""Face contacts (contact.face): the tributary areas of a face's nodes sum to the face's
area (tet4 and tet10, whose triangles are cut into their four corner triangles) and give
each interior node of a structured face its cell's area; what cannot be a face, or
cannot be touched by a point, is refused with one clear line."""

import numpy as np
import pytest

from contact import FaceContact, UnilateralNewtonImpact, connect
from contact.face import tributary_areas
from contours import Contour1sEdgeFFR, Contour2sNeutralFFR, PlaneContour, PointContour
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, PointMass, ground_frame
from preprocess import Material, build_body
from preprocess.geometry import box

STEEL = Material(7850.0, 2.1e11, 0.3)


@pytest.mark.parametrize("order", [1, 2])
def test_the_tributary_areas_sum_to_the_face(order):
    data = build_body(box(0.04, 0.02, 0.03, None, order=order, divisions=(4, 2, 3)), STEEL, n_modes=3)
    nodes = data.node_groups["y0"]
    areas = tributary_areas(data, nodes)
    assert areas.shape == nodes.shape and (areas > 0).all()
    assert areas.sum() == pytest.approx(0.04 * 0.03, rel=1e-12)
    if order == 1:              # an interior node of the structured 4 x 3 grid: a cell of 1 cm x 1 cm
        interior = [j for j, (x, _, z) in zip(nodes, data.u0[nodes]) if 0.0 < x < 0.04 and 0.0 < z < 0.03]
        np.testing.assert_allclose(tributary_areas(data, nodes)[np.isin(nodes, interior)], 1e-4, rtol=1e-12)


def test_what_is_no_face_or_cannot_be_touched_is_refused():
    data = build_body(box(0.04, 0.02, 0.03, None, order=1, divisions=(4, 2, 3)), STEEL, n_modes=3)
    body = FlexibleBodyFFR(data, modes=3)
    with pytest.raises(ModelError, match="the face must be a neutral 1s or 2s contour of a flexible body"):
        FaceContact(PointContour(PointMass(1.0).point), PlaneContour(ground_frame()), UnilateralNewtonImpact(0.0))
    rim = Contour1sEdgeFFR.along_line(body, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), normal=(0.0, -1.0, 0.0), degree=3)
    with pytest.raises(ModelError, match="its points cannot touch a contour of kind .edge."):
        connect(Contour2sNeutralFFR(body, "y1"), rim, "impact", name="x")
