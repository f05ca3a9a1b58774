"""The abstract factories of the neutral contours (thesis Sec. 4.4.1, Fig. 4.5–4.7).

:class:`Contour1sNeutralFactory` and :class:`Contour2sNeutralFactory` declare the
interpolation products a neutral contour is made of (``create_local_position``,
``create_mode_shapes``, ``create_position``, ``create_velocity``) and implement the
contour interface of :mod:`contours.base` on top of them: the update once per step, the
fields at (η, ξ), the frame (1s: curve tangent and a reference normal; 2s: eq. 3.27–3.29
with the outward sign) and the Jacobians. A body model plugs in with one concrete
factory per dimension that creates its products from its nodal data (the FFR family in
:mod:`.ffr`, the rigid family in :mod:`~contours.neutral.rigid`); other contours (band, cylinder) are
built on the neutral ones and serve every family unchanged.

The per-step path does not go through the products (``compiled=True``, the default):
``update`` stores the body state, O(n_f), and the fields at a point come from
span-local numba kernels over P_ū0 and P_Φ (:mod:`._kernels`), O((p + 1)^dim n_f),
whatever the number of nodes. The products' full control points are brought up to date
on demand only: the reference route (``compiled=False``), geomdl export, plots.

Body protocol used (all floating-frame bodies offer it): ``frame_state(q, u, t)``,
``elastic_coordinates(q)``, ``elastic_velocities(u)``, ``fill_J_T``, ``fill_J_R``, ``nu``.
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np

from ffrmbs.errors import ModelError
from contours.nurbs.geomdl_io import to_geomdl_curve, to_geomdl_surface

from ..base import BufferSlot, Contour, ContourPoint
from . import _kernels as K
from .products import NeutralNurbsLocalPosition, NeutralNurbsModeShapes, NeutralNurbsPosition, NeutralNurbsVelocity


HAS_U, FIELDS_STAMP, VELOCITY_STAMP, HAS_T = range(4)     # NeutralContour._flags


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
    compiled : bool
        True (default): :meth:`update` stores the body state (O(n_f)) and
        :meth:`evaluate`, :meth:`local_fields` and :meth:`bounding_box` are span-local
        numba kernels (:mod:`._kernels`): a point costs O((p + 1)^dim n_f) whatever the
        number of control points. False: the reference route — the products' control
        points (:attr:`position_field`, …) follow the state in full on first use after an
        update (O(control points × n_f)) and are contracted at the point.

    Attributes
    ----------
    R, A, v, w, q_f, qdot_f :
        The body state of the last update (views of one state vector): origin [m],
        orientation (3, 3), origin velocity [m/s], body-frame angular velocity [rad/s],
        elastic coordinates and velocities (v, w, qdot_f valid when update had u).
    T : (3, 3) or None
        ω̄ = T u_r of a free frame (None on a prescribed one), from the body.
    kernel_data : tuple
        ``space.geometry`` + (P_ū0, P_Φ, state, span cache): the arrays of the span-local
        kernels (also for the compiled search of :mod:`contact.search`); constant but for
        the state and the cache.
    """

    #: what update() and the lazy products wrote (the run state, :mod:`mbs.run.contact_state`)
    state_slots = ("_state", "_span", "_flags", "_T", "_local_position", "_position_field", "_velocity_field")
    #: entries of ``_flags``: update() was given u; the state stamps the products were
    #: synced at; a free frame's T is set
    _has_u = BufferSlot(HAS_U, bool, "_flags")
    _fields_stamp = BufferSlot(FIELDS_STAMP, float, "_flags")
    _velocity_stamp = BufferSlot(VELOCITY_STAMP, float, "_flags")

    def __init__(self, body, space, nodal_u0, nodal_phi, name, compiled=True):
        super().__init__(body, name)
        self.space = space
        self.dim = space.dim
        self.domain = space.domain
        self.closed = space.closed
        self.compiled = bool(compiled)
        self.mode_shapes = self.create_mode_shapes(nodal_phi)
        self._local_position = self.create_local_position(nodal_u0, self.mode_shapes)
        self._position_field = self.create_position()
        self._velocity_field = self.create_velocity()
        n_f = 0 if self.mode_shapes is None else self.mode_shapes.n_modes
        self.n_modes = n_f
        self._alloc_state(n_f)
        self._alloc_kernel_data(n_f)
        self._local_rows = np.zeros((6, 3))
        self._phi_rows = np.zeros((6, 3 * n_f))
        self._phi_value = self._phi_rows[0].reshape(3, n_f)   # Φ (3, n_f) at the point
        self._vel_rows = np.zeros((6, 3))
        self.update(body.q_init, body.u_init)

    def _alloc_state(self, n_f):
        """The state vector (layout of :mod:`._kernels`), the flags and a free frame's T."""
        self._state = np.zeros(K.Q_AT + 2 * n_f)
        self._flags = np.array([0.0, -1.0, -1.0, 0.0])
        self._T = np.zeros((3, 3))

    def _alloc_kernel_data(self, n_f):
        """The kernels' arrays (P_ū0, P_Φ, state, span cache), the constants of the O(n_f)
        bounding box and the basis tables of :meth:`evaluate`."""
        ctrl0 = self._local_position.ctrl0
        self._phi = self.mode_shapes.ctrl if n_f else np.zeros(self.space.ctrl_shape + (0,))
        self._span = np.full(K.SPAN_KEY + 3 * int(np.prod([d.p + 1 for d in self._directions()])), -1.0)
        self.bind_views()
        P0 = ctrl0.reshape(-1, 3)
        self._box0 = (P0.min(axis=0), P0.max(axis=0))
        self._phi_bound = np.abs(self._phi.reshape(-1, 3, n_f)).max(axis=0) if n_f else np.zeros((3, 0))
        self._B = self.kernel_workspace()[0]

    def bind_views(self) -> None:
        """The named views of the state vector (R, A, v, ω̄, q_f, q̇_f) and
        :attr:`kernel_data` (again after the state moved into a run's state)."""
        s, n_f = self._state, (self._state.size - K.Q_AT) // 2
        self.R, self.v, self.w = s[K.R_AT:K.R_AT + 3], s[K.V_AT:K.V_AT + 3], s[K.W_AT:K.W_AT + 3]
        self.A = s[K.A_AT:K.A_AT + 9].reshape(3, 3)
        self.q_f, self.qdot_f = s[K.Q_AT:K.Q_AT + n_f], s[K.Q_AT + n_f:]
        self.kernel_data = self.space.geometry + (self._local_position.ctrl0, self._phi, s, self._span)

    @property
    def T(self):
        """ω̄ = T u_r of a free frame (3, 3), from the body's last update; None on a
        prescribed frame."""
        return self._T if self._flags[HAS_T] else None

    @T.setter
    def T(self, value):
        self._flags[HAS_T] = value is not None
        if value is not None:
            self._T[...] = value

    def _directions(self):
        return (self.space.eta,) if self.dim == 1 else (self.space.eta, self.space.xi)

    def kernel_workspace(self):
        """Fresh work arrays (basis tables, ū rows (6, 3), r rows (6, 3)) for the
        span-local kernels: B (3, p+1) on a curve, (2, 3, max p + 1) on a surface."""
        B = np.zeros((self.dim, 3, max(d.p for d in self._directions()) + 1))
        return (B[0] if self.dim == 1 else B), np.zeros((6, 3)), np.zeros((6, 3))

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

    @abstractmethod
    def _evaluate_local(self, point, eta, xi, velocity, modal) -> None:
        """The span-local kernel: point.derivs, point.frame, with ``modal`` Φ at the point
        into _phi_rows[0] and with ``velocity`` point.v; ū rows into _local_rows."""

    # --- products at the current state (on demand) --------------------------------------
    @property
    def local_position(self) -> NeutralNurbsLocalPosition:
        """The ū product, its control points at the state of the last update."""
        self._sync_fields()
        return self._local_position

    @property
    def position_field(self) -> NeutralNurbsPosition:
        """The r product, its control points at the state of the last update."""
        self._sync_fields()
        return self._position_field

    @property
    def velocity_field(self) -> NeutralNurbsVelocity:
        """The ṙ product, its control points at the state of the last update (if it had u)."""
        if self._has_u and self._velocity_stamp != self._state[K.STAMP_AT]:
            self._velocity_field.update(self.v, self.A, self.w, self.local_position, self.qdot_f)
            self._velocity_stamp = self._state[K.STAMP_AT]
        return self._velocity_field

    def _sync_fields(self):
        """P_ū = P_ū0 + P_Φ q_f and P_r = R + A P_ū over all control points, once per
        update (per stamp of the state: whoever writes the state stamps it)."""
        if self._fields_stamp != self._state[K.STAMP_AT]:
            self._local_position.update(self.q_f)
            self._position_field.update(self.R, self.A, self._local_position)
            self._fields_stamp = self._state[K.STAMP_AT]

    def require_velocity(self):
        """ModelError unless the last :meth:`update` was given the velocities u."""
        if not self._has_u:
            raise ModelError(f"{self.name}: velocity asked for, but update() was given no u")

    # --- contour interface ----------------------------------------------------------------
    def update(self, q, u=None, t=0.0) -> None:
        """Store the body state (R, A, q_f and, with u, v, ω̄, q̇_f): O(n_f). The
        products' control points follow on first use (reference route, geomdl export)."""
        R, A, v, w, self.T = self.body.frame_state(q, u, t)
        body = self.body
        K.store_state(self._state, R, A, body.elastic_coordinates(q))
        self._has_u = u is not None
        if self._has_u:
            K.store_velocity(self._state, v, w, body.elastic_velocities(u))

    def kernel_updated(self, velocity=True) -> None:
        """Note that a compiled kernel wrote the body state into the state vector of
        :attr:`kernel_data` as :meth:`update` does (R, A, q_f and, with ``velocity``, v, ω̄,
        q̇_f), e.g. the fused detection of :mod:`mbs.run.fused_detection`."""
        self._flags[HAS_U] = 1.0 if velocity else 0.0

    def evaluate(self, point, eta, xi=0.0, velocity=False, jacobians=False):
        """Fields at (η, ξ) (see :meth:`Contour.evaluate`); J_T = [1, −A ũ T, A Φ] and
        J_R from the body (thesis eq. 2.70, 2.72) with the interpolated ū and Φ."""
        if velocity:
            self.require_velocity()
        point.eta, point.xi = eta, xi
        if self.compiled:
            self._evaluate_local(point, eta, xi, velocity, velocity or jacobians)
        else:
            self._evaluate_reference(point, eta, xi, velocity, jacobians)
        if jacobians:
            self.body.fill_J_T(self.A, self.T, self._local_rows[0], self._phi_value, point.J_T)
            self.body.fill_J_R(self.A, self.T, point.J_R)
        return point

    @property
    def evaluate_work(self):
        """The work arrays the compiled :meth:`evaluate` fills (the basis table, the ū rows
        (6, 3), the Φ rows (6, 3 n_f)), for a fused detection (:mod:`mbs.run.fused_detection`)."""
        return self._B, self._local_rows, self._phi_rows

    def _evaluate_reference(self, point, eta, xi, velocity, jacobians):
        """The reference route of :meth:`evaluate`: contract the products' control points
        (brought up to date in full on first use after an update)."""
        self.space.locate(eta, xi)
        self.position_field.contract(6, point.derivs)
        self._fill_frame(point)
        if velocity:
            self.velocity_field.contract(1, self._vel_rows)
            point.v[:] = self._vel_rows[0]
        if jacobians:
            self.local_fields(1)

    def local_fields(self, nrows):
        """(ū rows (6, 3) [m], Φ rows (6, 3 n_f)) at the point last located by
        ``space.locate``, body frame: the first ``nrows`` rows are valid (value, ∂/∂η,
        ∂/∂ξ, second derivatives). The Φ rows reshape to (3, n_f) per row. Workspace
        arrays: copy to keep."""
        if self.compiled:
            self.space.contract_state(*self.kernel_data[-4:], nrows, self._local_rows)
        else:
            self.local_position.contract(nrows, self._local_rows)
        if self.n_modes:
            self.mode_shapes.contract(nrows, self._phi_rows)
        return self._local_rows, self._phi_rows

    def local_position_at(self, eta, xi=0.0) -> np.ndarray:
        """ū(η, ξ) (3,) [m] in body-frame components (allocates)."""
        self.space.locate(eta, xi)
        return self.local_fields(1)[0][0].copy()

    def to_geomdl(self, field="position"):
        """The current ``field`` ("position", "velocity" or "local_position") as a geomdl
        ``BSpline.Curve`` (1s) or ``BSpline.Surface`` (2s, u = η, v = ξ), e.g. to plot,
        export or check it with NURBS-Python."""
        products = {"position": "position_field", "velocity": "velocity_field", "local_position": "local_position"}
        if field not in products:
            raise ModelError(f"{self.name}: field must be one of {sorted(products)}, not {field!r}")
        if field == "velocity":
            self.require_velocity()
        ctrl, e = getattr(self, products[field]).ctrl, self.space.eta
        if self.dim == 1:
            return to_geomdl_curve(e.knots, e.p, ctrl)
        x = self.space.xi
        return to_geomdl_surface(e.knots, e.p, x.knots, x.p, ctrl)

    @property
    def rest_box(self) -> tuple:
        """(lo (3,), hi (3,)) [m]: the box of the undeformed position control points P_ū0
        in the body frame, the box of :meth:`bounding_box` at q_f = 0."""
        return self._box0

    @property
    def mode_box_growth(self) -> np.ndarray:
        """(3, n_f) [m per unit q_f,k]: max_i |P_Φ,i,ck|, how far mode k moves a control
        point along body axis c at most; :meth:`bounding_box` grows :attr:`rest_box` by
        Σ_k mode_box_growth[c, k] |q_f,k| along axis c."""
        return self._phi_bound

    def bounding_box(self, out=None) -> np.ndarray:
        """A box (2, 3) [m] around the position control points: a B-spline lies in their
        convex hull, so it contains the contour. Compiled: O(n_f), from the undeformed
        control points and a bound of P_Φ q_f (:func:`._kernels.bounding_box`);
        reference: the control points' own box, O(control points)."""
        out = np.empty((2, 3)) if out is None else out
        if self.compiled:
            K.bounding_box(*self._box0, self._phi_bound, self._state, out)
        else:
            P = self.position_field.rows()
            P.min(axis=0, out=out[0])
            P.max(axis=0, out=out[1])
        return out


class Contour1sNeutralFactory(NeutralContour):
    """Abstract 1s neutral contour: a curve along η with the frame t1 = t_η/|t_η|,
    n = the body-frame reference direction ``normal`` (rotated with the body, made
    perpendicular to t1), t2 = n × t1."""

    state_slots = NeutralContour.state_slots + ("_n_ref",)

    def __init__(self, body, space, nodal_u0, nodal_phi, normal, name, compiled=True):
        normal = np.asarray(normal, dtype=float).reshape(3)
        if not np.linalg.norm(normal) > 0:
            raise ModelError(f"{name}: the reference normal must be a nonzero vector, got {normal}")
        self.normal_ref = normal / np.linalg.norm(normal)
        self._n_ref = np.zeros(3)       # A n̄_ref of the last update
        super().__init__(body, space, nodal_u0, nodal_phi, name, compiled)

    def update(self, q, u=None, t=0.0) -> None:
        super().update(q, u, t)
        np.dot(self.A, self.normal_ref, out=self._n_ref)

    @property
    def n_ref(self) -> np.ndarray:
        """A n̄_ref (3,), the reference normal in world axes at the last update (a view)."""
        return self._n_ref

    def _fill_frame(self, point):
        K.frame_1s(point.derivs, self._n_ref, point.frame)

    def _evaluate_local(self, point, eta, xi, velocity, modal):
        K.evaluate_1s(float(eta), *self.kernel_data, self._n_ref, modal, velocity, self._B, self._local_rows,
                      self._phi_rows, point.derivs, point.frame, point.v)


class Contour2sNeutralFactory(NeutralContour):
    """Abstract 2s neutral contour: a surface in (η, ξ) with n = sign · t_η × t_ξ/|…|
    (eq. 3.27; ``sign`` ±1 makes it point out of the material), t1, t2 by eq. 3.28–3.29."""

    def __init__(self, body, space, nodal_u0, nodal_phi, sign, name, compiled=True):
        if sign not in (1, -1):
            raise ModelError(f"{name}: the normal sign must be +1 or -1, got {sign!r}")
        self.sign = float(sign)
        super().__init__(body, space, nodal_u0, nodal_phi, name, compiled)

    def _fill_frame(self, point):
        K.frame_2s(point.derivs, self.sign, point.frame)

    def _evaluate_local(self, point, eta, xi, velocity, modal):
        K.evaluate_2s(float(eta), float(xi), *self.kernel_data, self.sign, modal, velocity, self._B, self._local_rows,
                      self._phi_rows, point.derivs, point.frame, point.v)
