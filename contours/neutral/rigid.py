"""The rigid family of neutral contours: concrete factories for :class:`mbs.RigidBody`.

A second product family plugged into the same abstract factories without touching the
FFR family (thesis Sec. 4.4.1: "for every new body model, only two new classes"): a
rigid body has no nodes and no modes, so the contour interpolates given body-frame
points once and its local position never changes; position and velocity are the shared
products, J_T = [1, −A ũ T] and J_R = [0, A T] come from the body.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError
from contours.nurbs import Interpolation1D, SurfaceInterpolation

from .factory import Contour1sNeutralFactory, Contour2sNeutralFactory
from .products import NeutralNurbsLocalPosition, NeutralNurbsPosition, NeutralNurbsVelocity
from .space import CurveSpace, SurfaceSpace, as_pair


class _RigidProducts:
    """Product creation of the rigid family: a constant shape, no mode shapes."""

    def create_mode_shapes(self, nodal_phi):
        return None

    def create_local_position(self, nodal_u0, modes):
        return NeutralNurbsLocalPosition(self.space, nodal_u0)

    def create_position(self):
        return NeutralNurbsPosition(self.space)

    def create_velocity(self):
        return NeutralNurbsVelocity(self.space)


def _points(points, ndim, name):
    P = np.asarray(points, dtype=float)
    if P.ndim != ndim or P.shape[-1] != 3 or not np.isfinite(P).all():
        raise ModelError(f"{name}: points must be a finite array of shape {'(k, 3)' if ndim == 2 else '(k_eta, k_xi, 3)'}, got {P.shape}")
    return P


class Contour1sNeutralRigid(_RigidProducts, Contour1sNeutralFactory):
    """A curve through body-frame ``points`` (k, 3) [m] of a rigid body; ``normal`` the
    body-frame reference normal; degree, closed, method and compiled as for the FFR family."""

    def __init__(self, body, points, normal, degree=3, closed=False, method="chord", name="rigid 1s",
                 compiled=True):
        P = self.points = _points(points, 2, name)           # the body-frame points it runs through
        interp = Interpolation1D.from_points(P, degree, closed, method)
        super().__init__(body, CurveSpace(interp), P, None, normal, name, compiled)


class Contour2sNeutralRigid(_RigidProducts, Contour2sNeutralFactory):
    """A surface through a body-frame point grid (k_eta, k_xi, 3) [m] of a rigid body;
    ``outward`` = +1 if t_η × t_ξ points out of the material, else -1; ``compiled`` as for
    the FFR family."""

    def __init__(self, body, grid, degree=3, closed=False, method="chord", outward=1, name="rigid 2s",
                 compiled=True):
        G = self.points = _points(grid, 3, name)             # the body-frame grid it runs through
        interp = SurfaceInterpolation.from_grid(G, as_pair(degree, "degree"), as_pair(closed, "closed"), method)
        super().__init__(body, SurfaceSpace(interp), G, None, outward, name, compiled)
