"""Bounding spheres of contours at the global state, for the planned broad phase of the
contour stage (:mod:`mbs.plan`: a contact is searched only while its two contours'
spheres come within its margin).

:func:`contour_sphere` gives a callable (q, t) -> (centre (3,) [m], radius [m]) that
writes its centre into its own array: a point or sphere contour about its frame's
position (a frame on a point mass: r = q + ū0, no temporary); a neutral contour of a
flexible body within its body's sphere (:meth:`mbs.body.Body.bounding_sphere`:
centre R + A c, radius max_j |ū0_j − c| + Σ_k max_j |Φ_jk| |q_f,k|; for a frame fixed
in space the centre is constant and the radius is computed in place). Anything else
(planes, derived contours) cannot be bounded: None.
"""

from __future__ import annotations

import numpy as np

from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, PointContour, SphereContour

from .rigid_body import PointMass

NEUTRAL_FFR = (Contour1sNeutralFFR, Contour2sNeutralFFR)


class FrameSphere:
    """The sphere of radius ``radius`` [m] about ``frame``'s origin on ``body``."""

    def __init__(self, frame, body, radius):
        self.frame, self.body, self.radius = frame, body, float(radius)
        self.centre = np.zeros(3)
        self._offset = frame.u0 if isinstance(body, PointMass) else None

    def __call__(self, q, t):
        qb = q[self.body.q_slice]
        if self._offset is not None:               # a point mass's frame: r = q + ū0
            np.add(qb, self._offset, out=self.centre)
        else:
            self.centre[:] = self.frame.position(qb, t)
        return self.centre, self.radius


class FlexibleBodySphere:
    """The bounding sphere of a flexible body (:meth:`FlexibleBodyFFR.bounding_sphere`)."""

    def __init__(self, body):
        self.body = body
        self._f = slice(body.q_slice.start + body._f.start, body.q_slice.start + body._f.stop)
        self._abs = np.zeros(body.n_modes)

    def __call__(self, q, t):
        b = self.body
        if not b.frame_at_rest:
            return b.bounding_sphere(q[b.q_slice], t)
        np.abs(q[self._f], out=self._abs)
        radius = b._box_radius + b._phi_reach @ self._abs
        if b._rest_centre is None:
            b.bounding_sphere(q[b.q_slice], t)        # fixes the constant centre once
        return b._rest_centre, radius


def contour_sphere(contour):
    """A callable (q, t) -> (centre (3,) [m], radius [m]) of a sphere holding ``contour``
    at the global state, or None (module docstring)."""
    body = contour.body
    if isinstance(contour, (PointContour, SphereContour)) and body is not None:
        return FrameSphere(contour.frame_ref, body, getattr(contour, "radius", 0.0))
    if isinstance(contour, NEUTRAL_FFR):
        return FlexibleBodySphere(body)
    return None


def sphere_pair(contact):
    """(sphere1, sphere2) of a prunable contact (unilateral, with a margin, both contours
    bounded), else None."""
    if not (contact.unilateral and contact.margin is not None):
        return None
    s1, s2 = contour_sphere(contact.kinematics.contour1), contour_sphere(contact.kinematics.contour2)
    return (s1, s2) if s1 is not None and s2 is not None else None
