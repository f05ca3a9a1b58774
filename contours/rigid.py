"""Rigid contours on a :class:`mbs.Frame`: point, sphere and plane.

They work on any frame — of a point mass, a rigid body, a node of an FFR body or the
ground. A point at the inertial offset d from the frame origin moves with the frame's
body rotation, so (thesis eq. 2.70, 2.72)

    ṙ = ṙ_O + ω × d,   J_T = J_T,O − d̃ J_R,O,   J_R = J_R,O.

Surface coordinates: sphere (η, ξ) = (longitude, latitude) [rad] in the frame's axes;
plane (η, ξ) = coordinates [m] along the frame's x and y axes, normal along its z axis.

``update`` reads the frame through its methods (position, orientation, velocity, angular
velocity, J_T, J_R), each of which returns a new array. A frame on a body that only
translates (``body.translation_only``: a point mass) takes a shortcut that allocates
nothing: r = q + ū0, ṙ = u, with the constant orientation A_rel, ω = 0, J_T = 1 and
J_R = 0 set once (the same values the frame's methods give; compared in
``tests/unit/contact/test_compiled_contact.py``). ``evaluate`` runs the kernels of
:mod:`contours._rigid_kernels` on the state.

A point or a sphere on the frame of a node of a flexible body (``body.node(j)``) may
carry the static compliance of the modes its body leaves out at that node
(``residual_flexibility``, :class:`contours.residual.NodeCompliance`): a contact on it
then sees the node's own deflection, as a corrected neutral contour's contacts see theirs.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from . import _rigid_kernels as K
from ._rigid_kernels import A_AT, J_AT, R_AT, V_AT, W_AT, sphere_angles  # noqa: F401  (public: η, ξ of a direction)
from .base import Contour


class _FrameContour(Contour):
    """Shared state of the rigid contours: the frame's position, orientation, velocity
    and Jacobians, read once per update (views of one vector ``state``, layout
    ``R_AT`` … ``J_AT``, so that a compiled kernel takes them as one array)."""

    state_slots = ("state",)    # what update() wrote (the run state, mbs.run.contact_state)

    def __init__(self, frame, name, residual_flexibility=False):
        body = None if frame.is_ground else frame.body
        super().__init__(body, name)
        self.frame_ref = frame
        if residual_flexibility and (getattr(frame, "node_index", None) is None or not hasattr(body, "K_ff")):
            raise ModelError(f"{name}: residual flexibility needs the frame of a node of a flexible body "
                             "(body.node(j)), where the dropped modes' static compliance is that of the node")
        self.residual_flexibility = bool(residual_flexibility)
        self.state = np.zeros(J_AT + 6 * self.nu)
        self.bind_views()
        self._A[:] = np.eye(3)
        self._on_point_mass = body is not None and body.translation_only   # the shortcut of the module docstring
        if self._on_point_mass:
            self._A[:] = frame.A_rel
            self._J_T[:] = np.eye(3)
        self.update(None if body is None else body.q_init, None if body is None else body.u_init)

    def bind_views(self) -> None:
        """The named views of :attr:`state` (again after it moved into a run's state)."""
        s, nu = self.state, self.nu
        self._r = s[R_AT:A_AT]
        self._A = s[A_AT:V_AT].reshape(3, 3)
        self._v = s[V_AT:W_AT]
        self._w = s[W_AT:J_AT]
        self._J_T = s[J_AT:J_AT + 3 * nu].reshape(3, nu)
        self._J_R = s[J_AT + 3 * nu:].reshape(3, nu)

    @property
    def axes(self) -> np.ndarray:
        """Orientation of the frame (3, 3) at the last update (a view)."""
        return self._A

    def update(self, q, u=None, t=0.0) -> None:
        """The frame's position, orientation and Jacobians at (q, t) and, with u, its
        velocity and angular velocity."""
        if self._on_point_mass:
            np.add(q, self.frame_ref.u0, out=self._r)
            if u is not None:
                self._v[:] = u
            return
        f = self.frame_ref
        self._r[:] = f.position(q, t)
        self._A[:] = f.orientation(q, t)
        if u is not None:
            self._v[:] = f.velocity(q, u, t)
            self._w[:] = f.angular_velocity(q, u, t)
        if not f.is_ground:
            self._J_T[:] = f.J_T(q, t)
            self._J_R[:] = f.J_R(q, t)


class PointContour(_FrameContour):
    """The frame origin as a contour (dim 0): every (η, ξ) is the same point; its frame is
    the frame's orientation."""

    dim = 0
    domain = ()
    closed = ()

    def __init__(self, frame, name="point", residual_flexibility=False):
        super().__init__(frame, name, residual_flexibility)

    def evaluate(self, point, eta=0.0, xi=0.0, velocity=False, jacobians=False):
        point.eta, point.xi = eta, xi
        K.frame_point(self.state, bool(velocity), bool(jacobians), point.buffer)
        return point

    def bounding_box(self, out=None):
        out = np.empty((2, 3)) if out is None else out
        out[0] = self._r
        out[1] = self._r
        return out


class SphereContour(_FrameContour):
    """A sphere of ``radius`` [m] about the frame origin; n points outward."""

    dim = 2

    def __init__(self, frame, radius, name="sphere", residual_flexibility=False):
        if not radius > 0:
            raise ModelError(f"{name}: radius must be positive, got {radius}")
        self.radius = float(radius)
        self.domain = ((0.0, 2.0 * np.pi), (-0.5 * np.pi, 0.5 * np.pi))
        self.closed = (True, False)
        super().__init__(frame, name, residual_flexibility)

    def evaluate(self, point, eta, xi=0.0, velocity=False, jacobians=False):
        """The point at longitude η and latitude ξ [rad] in the frame's axes
        (:func:`contours._rigid_kernels.sphere_point`)."""
        point.eta, point.xi = eta, xi
        K.sphere_point(self.state, self.radius, float(eta), float(xi), bool(velocity), bool(jacobians), point.buffer)
        return point

    @property
    def centre(self) -> np.ndarray:
        """Inertial centre [m] at the last update (a view)."""
        return self._r

    def bounding_box(self, out=None):
        out = np.empty((2, 3)) if out is None else out
        np.subtract(self._r, self.radius, out=out[0])
        np.add(self._r, self.radius, out=out[1])
        return out


class PlaneContour(_FrameContour):
    """The plane through the frame origin spanned by its x and y axes, normal along z.

    ``size`` [m] (half edge) only bounds the patch drawn by :meth:`to_trimesh`; the
    bounding box is infinite (a plane overlaps everything in the broad phase).
    """

    dim = 2
    closed = (False, False)

    def __init__(self, frame, size=1.0, name="plane"):
        if not size > 0:
            raise ModelError(f"{name}: size must be positive, got {size}")
        self.domain = ((-float(size), float(size)), (-float(size), float(size)))
        super().__init__(frame, name)

    def evaluate(self, point, eta, xi=0.0, velocity=False, jacobians=False):
        """The point at (η, ξ) [m] along the frame's x and y axes
        (:func:`contours._rigid_kernels.plane_point`)."""
        point.eta, point.xi = eta, xi
        K.plane_point(self.state, float(eta), float(xi), bool(velocity), bool(jacobians), point.buffer)
        return point

    def coordinates(self, c) -> tuple:
        """(η, ξ) [m] of the foot of the point c (3,) [m] on the plane
        (:func:`contours._rigid_kernels.plane_coordinates`)."""
        return K.plane_coordinates(self.state, c)

    def bounding_box(self, out=None):
        out = np.empty((2, 3)) if out is None else out
        out[0] = -np.inf
        out[1] = np.inf
        return out
