"""The abstract factories of the neutral contours (thesis Sec. 4.4.1, Fig. 4.5–4.7).

:class:`Contour1sNeutralFactory` and :class:`Contour2sNeutralFactory` declare the
interpolation products a neutral contour is made of (``create_local_position``,
``create_mode_shapes``, ``create_position``, ``create_velocity``) and implement the
contour interface of :mod:`contours.base` on top of them: the update once per step, the
fields at (η, ξ), the frame (1s: curve tangent and a reference normal; 2s: eq. 3.27–3.29
with the outward sign) and the Jacobians. A body model plugs in with one concrete
factory per dimension that creates its products from its nodal data (the FFR family in
:mod:`.ffr`, the rigid family in :mod:`.rigid`); other contours (band, cylinder) are
built on the neutral ones and serve every family unchanged.

Body protocol used (all floating-frame bodies offer it): ``frame_state(q, u, t)``,
``elastic_coordinates(q)``, ``elastic_velocities(u)``, ``fill_J_T``, ``fill_J_R``, ``nu``.
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np

from ffrmbs.errors import ModelError
from contours.nurbs.geomdl_io import to_geomdl_curve, to_geomdl_surface

from ..base import Contour, ContourPoint
from . import _kernels as K
from .products import NeutralNurbsLocalPosition, NeutralNurbsModeShapes, NeutralNurbsPosition, NeutralNurbsVelocity


class NeutralContour(Contour):
    """Shared machinery of the 1s and 2s neutral factories (see module docstring).

    Parameters
    ----------
    body : floating-frame body
    space : CurveSpace or SurfaceSpace
    nodal_u0 : node-grid shape + (3,) [m]
        Undeformed body-frame positions of the contour nodes.
    nodal_phi : node-grid shape + (3, n_f) or None
        Their mode-shape rows (None for a family without modes).
    """

    def __init__(self, body, space, nodal_u0, nodal_phi, name):
        super().__init__(body, name)
        self.space = space
        self.dim = space.dim
        self.domain = space.domain
        self.closed = space.closed
        self.mode_shapes = self.create_mode_shapes(nodal_phi)
        self.local_position = self.create_local_position(nodal_u0, self.mode_shapes)
        self.position_field = self.create_position()
        self.velocity_field = self.create_velocity()
        n_f = 0 if self.mode_shapes is None else self.mode_shapes.n_modes
        self.n_modes = n_f
        self._local_rows = np.zeros((6, 3))
        self._phi_rows = np.zeros((6, 3 * n_f))
        self._vel_rows = np.zeros((6, 3))
        self.R = self.A = self.v = self.w = self.T = self.qdot_f = None
        self._velocity_current = False
        self.update(body.q_init, body.u_init)

    # --- the products (abstract factory interface) --------------------------------------
    @abstractmethod
    def create_mode_shapes(self, nodal_phi) -> NeutralNurbsModeShapes | None:
        """Interpolate the mode shapes once (None: the family has none)."""

    @abstractmethod
    def create_local_position(self, nodal_u0, modes) -> NeutralNurbsLocalPosition:
        """The body-frame position field ū."""

    @abstractmethod
    def create_position(self) -> NeutralNurbsPosition:
        """The inertial position field r."""

    @abstractmethod
    def create_velocity(self) -> NeutralNurbsVelocity:
        """The inertial velocity field ṙ."""

    @abstractmethod
    def _fill_frame(self, point: ContourPoint) -> None:
        """(t1, t2, n) into point.frame from point.derivs."""

    # --- contour interface ----------------------------------------------------------------
    def update(self, q, u=None, t=0.0) -> None:
        """Control points of ū and r from the body state (O(control points × n_f)); the
        velocity's follow on first use in the step."""
        self.R, self.A, self.v, self.w, self.T = self.body.frame_state(q, u, t)
        self.local_position.update(self.body.elastic_coordinates(q))
        self.position_field.update(self.R, self.A, self.local_position)
        self.qdot_f = None if u is None else self.body.elastic_velocities(u)
        self._velocity_current = False

    def evaluate(self, point, eta, xi=0.0, velocity=False, jacobians=False):
        self.space.locate(eta, xi)
        point.eta, point.xi = eta, xi
        self.position_field.contract(6, point.derivs)
        self._fill_frame(point)
        if velocity:
            self._update_velocity()
            self.velocity_field.contract(1, self._vel_rows)
            point.v[:] = self._vel_rows[0]
        if jacobians:
            ub, phi = self.local_fields(1)
            self.body.fill_J_T(self.A, self.T, ub[0], phi[0].reshape(3, self.n_modes), point.J_T)
            self.body.fill_J_R(self.A, self.T, point.J_R)
        return point

    def local_fields(self, nrows):
        """(ū rows (6, 3) [m], Φ rows (6, 3 n_f)) at the point last located, body frame:
        the first ``nrows`` rows are valid (value, ∂/∂η, ∂/∂ξ, second derivatives).
        The Φ rows reshape to (3, n_f) per row. Workspace arrays: copy to keep."""
        self.local_position.contract(nrows, self._local_rows)
        if self.n_modes:
            self.mode_shapes.contract(nrows, self._phi_rows)
        return self._local_rows, self._phi_rows

    def local_position_at(self, eta, xi=0.0) -> np.ndarray:
        """ū(η, ξ) (3,) [m] in body-frame components (allocates)."""
        self.space.locate(eta, xi)
        return self.local_fields(1)[0][0].copy()

    def _update_velocity(self):
        if not self._velocity_current:
            if self.v is None:
                raise ModelError(f"{self.name}: velocity asked for, but update() was given no u")
            self.velocity_field.update(self.v, self.A, self.w, self.local_position, self.qdot_f)
            self._velocity_current = True

    def to_geomdl(self, field="position"):
        """The current ``field`` ("position", "velocity" or "local_position") as a geomdl
        ``BSpline.Curve`` (1s) or ``BSpline.Surface`` (2s, u = η, v = ξ), e.g. to plot,
        export or check it with NURBS-Python."""
        fields = {"position": self.position_field, "velocity": self.velocity_field,
                  "local_position": self.local_position}
        if field not in fields:
            raise ModelError(f"{self.name}: field must be one of {sorted(fields)}, not {field!r}")
        if field == "velocity":
            self._update_velocity()
        ctrl, e = fields[field].ctrl, self.space.eta
        if self.dim == 1:
            return to_geomdl_curve(e.knots, e.p, ctrl)
        x = self.space.xi
        return to_geomdl_surface(e.knots, e.p, x.knots, x.p, ctrl)

    def bounding_box(self) -> np.ndarray:
        """Min and max of the position control points: a B-spline lies in the convex hull
        of its control points, so the box contains the contour (O(control points))."""
        P = self.position_field.rows()
        return np.array([P.min(axis=0), P.max(axis=0)])


class Contour1sNeutralFactory(NeutralContour):
    """Abstract 1s neutral contour: a curve along η with the frame t1 = t_η/|t_η|,
    n = the body-frame reference direction ``normal`` (rotated with the body, made
    perpendicular to t1), t2 = n × t1."""

    def __init__(self, body, space, nodal_u0, nodal_phi, normal, name):
        normal = np.asarray(normal, dtype=float).reshape(3)
        if not np.linalg.norm(normal) > 0:
            raise ModelError(f"{name}: the reference normal must be a nonzero vector, got {normal}")
        self.normal_ref = normal / np.linalg.norm(normal)
        self._n_ref = np.zeros(3)
        super().__init__(body, space, nodal_u0, nodal_phi, name)

    def update(self, q, u=None, t=0.0) -> None:
        super().update(q, u, t)
        np.dot(self.A, self.normal_ref, out=self._n_ref)

    def _fill_frame(self, point):
        K.frame_1s(point.derivs, self._n_ref, point.frame)


class Contour2sNeutralFactory(NeutralContour):
    """Abstract 2s neutral contour: a surface in (η, ξ) with n = sign · t_η × t_ξ/|…|
    (eq. 3.27; ``sign`` ±1 makes it point out of the material), t1, t2 by eq. 3.28–3.29."""

    def __init__(self, body, space, nodal_u0, nodal_phi, sign, name):
        if sign not in (1, -1):
            raise ModelError(f"{name}: the normal sign must be +1 or -1, got {sign!r}")
        self.sign = float(sign)
        super().__init__(body, space, nodal_u0, nodal_phi, name)

    def _fill_frame(self, point):
        K.frame_2s(point.derivs, self.sign, point.frame)
