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
    with pytest.raises(ModelError, match="the face must be a neutral 1s or 2s contour of a flexible or a rigid body, not a PointContour"):
        FaceContact(PointContour(PointMass(1.0).point), PlaneContour(ground_frame()), UnilateralNewtonImpact(0.0))
    rim = Contour1sEdgeFFR.along_line(body, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), normal=(0.0, -1.0, 0.0), degree=3)
    with pytest.raises(ModelError, match="its points cannot touch a contour of kind .edge."):
        connect(Contour2sNeutralFFR(body, "y1"), rim, "impact", name="x")


def test_a_rigid_block_lands_flat_on_a_corrected_plate():
    """A rigid block's bottom face (a rigid 2s contour through a 5 × 5 grid: 25 points at its
    grid points, quarter-cell areas summing to the face) lands at 0.5 m/s on a clamped
    plate whose top face carries its residual flexibility, e = 0: one contact interval,
    the recorded resultant integrates to the block's change of momentum (a sample per
    step), and the energy after the contact is the energy before it within 1 %
    (the plate's springs return what they store; O(Δt) at the releases)."""
    from contours import Contour2sNeutralRigid
    from mbs import PrescribedFrameMotion, RigidBody, System

    plate_data = build_body(box(0.2, 0.1, 0.01, None, order=1, divisions=(20, 10, 2)), Material(2700.0, 7e10, 0.33),
                            n_modes=10, clamp="x0")
    system = System()
    plate = system.add(FlexibleBodyFFR(plate_data, modes=10, frame=PrescribedFrameMotion.fixed(), name="plate"))
    mass, a, h = 0.03645, 0.03, 0.015                               # [kg], [m], [m]: 30 x 30 x 15 mm
    block = RigidBody(mass, np.diag([mass * (a * a + h * h) / 12] * 2 + [mass * a * a / 6]), name="block")
    block.q_init[:3], block.u_init[2] = (0.135, 0.05, 0.01 + h / 2 + 2e-6), -0.5   # its face 2 µm above the plate
    system.add(block)
    x = np.linspace(-0.015, 0.015, 5)
    grid = np.stack(np.meshgrid(x, x, [-h / 2], indexing="ij"), axis=-1)[:, :, 0]   # its bottom face (frame: centre)
    face = system.add(connect(Contour2sNeutralRigid(block, grid, outward=-1), Contour2sNeutralFFR(
        plate, "z1", residual_flexibility=True), UnilateralNewtonImpact(0.0), name="bottom"))
    assert len(face.points) == 25 and face.nodes is None
    assert face.areas.sum() == pytest.approx(a * a, rel=1e-12) and face.areas.max() == pytest.approx((a / 4) ** 2)
    dt, t_end = 5e-7, 1.2e-4
    res = system.simulate(t_end, dt, integrator="moreau", t_out=np.linspace(0.0, t_end, 241), contacts=True,
                          energies=True, trace=True,
                          outputs={"p_z": lambda t, q, u: system.linear_momentum(t, q, u)[2]})
    pressed = res.trace["pressed"] > 0
    assert pressed.any() and np.count_nonzero(np.diff(pressed.astype(int)) == 1) == 1 and not pressed[-1]
    force, _ = face.resultant(res)
    block_p = mass * res.u[:, block.u_slice.start + 2]
    assert force[:, 2].sum() * dt == pytest.approx(block_p[-1] - block_p[0], rel=1e-6)
    energy = res.energy["kinetic"] + res.energy["potential"]
    assert abs(energy[-1] / energy[0] - 1.0) < 1e-2 and block_p[-1] > 0.0
