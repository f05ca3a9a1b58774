"""Contact kinematics: normal gap, contact frame, relative velocity and Jacobians.

A contact joins contour 1 (the point side: a point or a sphere) and contour 2 (the
surface side: a 2s or 1s contour, a plane or a sphere) at the contact points C1, C2
(thesis Sec. 3.1, eq. 3.2–3.8). With n the outward unit normal of contour 2 at C2 and
T = (t1, t2) its tangents (contour 2's frame),

    g_N = nᵀ (r_C1 − r_C2)             [m]    (eq. 3.4, > 0 when apart)
    ġ_N = nᵀ (v_C1 − v_C2)             [m/s]  (eq. 3.8)
    ġ_T = Tᵀ (v_C1 − v_C2)             [m/s]  (eq. 3.8)
    W_N = J_T1ᵀ n − J_T2ᵀ n            (nu_total,),   ġ_N = W_Nᵀ u
    W_T = J_T1ᵀ T − J_T2ᵀ T            (nu_total, 2), ġ_T = W_Tᵀ u

with J_Ti = ∂v_Ci/∂u of contour i's body at Ci (thesis eq. 2.70) in that body's slice of
the global u (the ground contributes nothing). Sign: the thesis's eq. 3.4 writes
g_N = n2ᵀ (r2 − r1), which with the outward n2 of eq. 3.5 is negative when the bodies
are apart — a sign typo; here g_N = n2ᵀ (r1 − r2), positive when apart, and eq. 3.8
likewise with (v1 − v2).

C2 solves eq. 3.6 (found by the search of :mod:`contact.search`, or analytically for a
plane or a sphere); C1 is the point itself or, for a sphere of radius ρ and centre c,
c − ρ n (its velocity and J_T1 are those of the sphere's material point there). At a
closest point r_C1 − r_C2 ∥ n on a 2s contour, so ġ_N is the exact time derivative of
g_N and W_N its exact gradient (in the velocity increments, q ⊕ Δu). On a 1s contour the
point may also lie off the curve's normal along t2; then ġ_N misses the term
(t2-offset) · t2ᵀ ṅ (exact when that offset is zero).

Contours are updated by the caller (``contour.update(q_body, u_body, t)``) before
:meth:`ContactKinematics.update`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ffrmbs.errors import ModelError

from contours.base import BufferSlot
from contours.rigid import PlaneContour, PointContour, SphereContour, sphere_angles

from . import _detection_kernels as K
from .search import Contact1sSearch, Contact2sSearch

G_N_AT, GD_N_AT, ACTIVE_AT = 0, 1, 2       # the scalars at the head of ContactKinematics.buffer


class ContactKinematics(ABC):
    """Normal gap, contact frame, relative velocity and Jacobians of a contact between
    contour1 (point side) and contour2 (surface side), thesis eq. 3.2–3.8 (see the module
    docstring). The attributes are filled by :meth:`update`.

    Parameters
    ----------
    contour1, contour2 : Contour
    nu_total : int or None
        Length of the global u. Bodies take their ``u_slice`` from the System; bodies in
        no System get a local layout (body 1, then body 2) and nu_total defaults to its
        length.

    Attributes
    ----------
    point1, point2 : ContourPoint
        C1 and C2 (positions, frames; velocities and J_T when asked for).
    active : bool
        A contact point was found inside contour 2's domain; the rest is valid only then.
    g_N, gd_N : float
        Normal gap [m] and its rate [m/s].
    n, T : (3,), (3, 2)
        Normal and tangents of contour 2 at C2.
    gd_T : (2,)
        Tangential relative velocity [m/s].
    w_N1, w_N2 : (nu1,), (nu2,)
        Point-local Jacobian pieces J_T1ᵀ n and −J_T2ᵀ n in the bodies' own u.
    w_T1, w_T2 : (nu1, 2), (nu2, 2)
        J_T1ᵀ T and −J_T2ᵀ T.
    buffer : (14 + 3 (nu1 + nu2),)
        g_N, ġ_N, active (1.0 or 0.0) at ``G_N_AT``, ``GD_N_AT``, ``ACTIVE_AT``, then n, T
        (row-major), gd_T, w_N1, w_N2, w_T1, w_T2 (row-major) as views of this one vector,
        in this order (offsets :func:`buffer_layout`), so that a compiled kernel takes and
        writes them as one array.
    """

    #: what update() wrote (the run state, :mod:`mbs.run.contact_state`)
    state_slots = ("buffer", "point1", "point2")
    g_N, gd_N, active = BufferSlot(G_N_AT), BufferSlot(GD_N_AT), BufferSlot(ACTIVE_AT, bool)

    def __init__(self, contour1, contour2, nu_total=None):
        self.contour1, self.contour2 = contour1, contour2
        self.point1, self.point2 = contour1.new_point(), contour2.new_point()
        self._nu_total = nu_total
        self.buffer = np.zeros(buffer_layout(contour1.nu, contour2.nu)[-1])
        self.buffer[G_N_AT] = self.buffer[GD_N_AT] = np.nan
        self.bind_views()

    def bind_views(self) -> None:
        """The named views of :attr:`buffer` (again after it moved into a run's state)."""
        nu1, nu2 = self.contour1.nu, self.contour2.nu
        n_at, T_at, gd_T_at, w_N1_at, w_N2_at, w_T1_at, w_T2_at, size = buffer_layout(nu1, nu2)
        b = self.buffer
        self.n = b[n_at:T_at]
        self.T = b[T_at:gd_T_at].reshape(3, 2)
        self.gd_T = b[gd_T_at:w_N1_at]
        self.w_N1, self.w_N2 = b[w_N1_at:w_N2_at], b[w_N2_at:w_T1_at]
        self.w_T1, self.w_T2 = b[w_T1_at:w_T2_at].reshape(nu1, 2), b[w_T2_at:size].reshape(nu2, 2)

    @abstractmethod
    def _locate(self, velocity, jacobians) -> bool:
        """Find C1 and C2, fill point1, point2 (with velocities and J_T when asked for)
        and g_N; True if a contact point exists."""

    def update(self, velocity=True, jacobians=True) -> bool:
        """Search the contact points and fill g_N, n, T, and (if asked for) ġ_N, ġ_T and
        the point-local Jacobians; returns :attr:`active`. The contours must have been
        updated at this state (with u for ``velocity``)."""
        self.active = self._locate(velocity, jacobians)
        if not self.active:
            return False
        p1, p2 = self.point1, self.point2
        gd_N = K.frame_rates_jacobians(p2.frame, p1.v, p2.v, p1.J_T, p2.J_T, velocity, jacobians, self.n, self.T,
                                       self.gd_T, self.w_N1, self.w_N2, self.w_T1, self.w_T2)
        if velocity:
            self.gd_N = gd_N
        return True

    # --- assembly in the global u ---------------------------------------------------------
    def u_slices(self):
        """(slice of body 1, slice of body 2) in the global u; None for the ground."""
        b1, b2 = self.contour1.body, self.contour2.body
        s1 = None if b1 is None else b1.u_slice
        s2 = None if b2 is None else b2.u_slice
        in_system1, in_system2 = b1 is None or s1 is not None, b2 is None or s2 is not None
        if in_system1 and in_system2:
            return s1, s2
        if (b1 is not None and in_system1) or (b2 is not None and in_system2):
            raise ModelError(f"{self!r}: one body belongs to a System and the other not")
        s1 = None if b1 is None else slice(0, b1.nu)
        if b2 is None:
            return s1, None
        if b2 is b1:
            return s1, s1
        start = 0 if s1 is None else s1.stop
        return s1, slice(start, start + b2.nu)

    @property
    def nu_total(self) -> int:
        """Length of the global u."""
        if self._nu_total is not None:
            return self._nu_total
        return max((s.stop for s in self.u_slices() if s is not None), default=0)

    def local_blocks(self):
        """[(u_slice, w_N (nu_b,), w_T (nu_b, 2))] per non-ground body, to assemble W_N,
        W_T sparse or blocked (add the blocks: both contours may sit on one body)."""
        s1, s2 = self.u_slices()
        blocks = []
        if s1 is not None:
            blocks.append((s1, self.w_N1, self.w_T1))
        if s2 is not None:
            blocks.append((s2, self.w_N2, self.w_T2))
        return blocks

    def W_N(self, out=None):
        """W_N (nu_total,) into ``out`` (zero outside the bodies' slices); ġ_N = W_Nᵀ u."""
        return self._assemble(np.zeros(self.nu_total) if out is None else out, self.w_N1, self.w_N2)

    def W_T(self, out=None):
        """W_T (nu_total, 2) into ``out`` (zero outside the bodies' slices); ġ_T = W_Tᵀ u."""
        return self._assemble(np.zeros((self.nu_total, 2)) if out is None else out, self.w_T1, self.w_T2)

    def fill_W(self, out, col=0, dim=None) -> None:
        """W = [W_N] (dim 1) or [W_N, W_T] (dim 3) into the columns col..col + dim of ``out``
        (nu_total, ·) (zero outside the bodies' slices; dim None: all of out's columns), the
        columns of :meth:`W_N` and :meth:`W_T` in one kernel
        (:func:`._detection_kernels.assemble_W`)."""
        s1, s2 = self.u_slices()
        K.assemble_W(out, col, out.shape[1] - col if dim is None else dim, -1 if s1 is None else s1.start,
                     self.w_N1, self.w_T1, -1 if s2 is None else s2.start, self.w_N2, self.w_T2)

    def _assemble(self, out, w1, w2):
        """out ← the blocks w1, w2 added at the bodies' slices of the global u (both
        contours may sit on one body)."""
        out[...] = 0.0
        s1, s2 = self.u_slices()
        if s1 is not None:
            out[s1] += w1
        if s2 is not None:
            out[s2] += w2
        return out

    def __repr__(self):
        return f"{type(self).__name__}({self.contour1!r}, {self.contour2!r})"


def buffer_layout(nu1, nu2):
    """Offsets of n, T, gd_T, w_N1, w_N2, w_T1, w_T2 in :attr:`ContactKinematics.buffer`
    for bodies with nu1, nu2 velocities, and its length."""
    w_N1 = 14
    return 3, 6, 12, w_N1, w_N1 + nu1, w_N1 + nu1 + nu2, w_N1 + 3 * nu1 + nu2, w_N1 + 3 * (nu1 + nu2)


def _require(contour, kind, what):
    if not isinstance(contour, kind):
        raise ModelError(f"expected {what}, got {contour!r}")
    return contour


def _require_dim(contour, dim):
    if getattr(contour, "dim", None) != dim:
        raise ModelError(f"expected a {dim}s contour, got {contour!r}")
    return contour


class _CentreContact(ContactKinematics):
    """Contour 1 is a point (``side1 = PointContour``, radius 0) or a sphere
    (``side1 = SphereContour``): its centre c is projected onto contour 2
    (``_project``), g_N = nᵀ (c − r_C2) − ρ and C1 = c − ρ n.

    Attributes (besides :class:`ContactKinematics`'): ``radius`` ρ [m] (0 for a point),
    ``centre`` c (3,) [m] at the last update (a view of point1's position for a point),
    ``axes1`` the sphere's axes (3, 3) at the last update (identity for a point)."""

    side1: type
    state_slots = ContactKinematics.state_slots + ("centre", "axes1")     # a point's centre: a view of point1

    def __init__(self, contour1, contour2, nu_total):
        _require(contour1, self.side1, f"a {self.side1.__name__}")
        super().__init__(contour1, contour2, nu_total)
        self.radius = contour1.radius if self.side1 is SphereContour else 0.0
        self.centre = self.point1.r if self.side1 is PointContour else np.zeros(3)
        self.axes1 = np.eye(3)

    def bind_views(self) -> None:
        super().bind_views()
        if self.side1 is PointContour:
            self.centre = self.point1.r

    @abstractmethod
    def _project(self, c, velocity, jacobians) -> bool:
        """Fill point2 at the contact point of contour 2 for the centre c; False if none."""

    def _locate(self, velocity, jacobians):
        p1, c1 = self.point1, self.contour1
        if self.side1 is PointContour:
            c1.evaluate(p1, velocity=velocity, jacobians=jacobians)
        else:
            self.axes1[:] = c1.axes
            self.centre[:] = c1.centre
        if not self._project(self.centre, velocity, jacobians):
            return False
        p2 = self.point2
        self.g_N = K.normal_gap(p2.frame, self.centre, p2.derivs, self.radius)
        if self.side1 is SphereContour:
            c1.evaluate(p1, *sphere_angles(self.axes1, -p2.n), velocity=velocity, jacobians=jacobians)
        return True


class _SearchContact(_CentreContact):
    """Contour 2 located by ``search_class`` (or a given search on it), warm-started at
    the last contact point: ``start`` ((η, ξ) on a 2s contour, (η,) on a 1s one; NaN
    when there is none, before the first search or after a search found nothing; the
    search's ``hole`` when the nearest point lay in a trimmed contour's hole)."""

    search_class: type
    state_slots = _CentreContact.state_slots + ("search", "start")     # the search and its warm start

    def __init__(self, contour1, contour2, search, nu_total):
        super().__init__(contour1, _require_dim(contour2, self.search_class.dim), nu_total)
        if search is not None and search.contour is not contour2:
            raise ModelError(f"{type(self).__name__}: the search runs on {search.contour!r}, not on {contour2!r}")
        self.search = self.search_class(contour2) if search is None else search
        self.start = np.full(self.search.dim, np.nan)

    def _project(self, c, velocity, jacobians):
        start = self.start
        if np.isnan(start[0]):
            start = None
        elif self.search.dim == 1:
            start = start[0]
        found = self.search.solve(c, start)
        if found is None:
            self.start[:] = self.search.hole             # NaN, or a point in a trimmed contour's hole
            return False
        self.start[:] = found
        coords = found if self.search.dim == 2 else (found,)
        self.contour2.evaluate(self.point2, *coords, velocity=velocity, jacobians=jacobians)
        return True


class ContactKinematicsPointContour2s(_SearchContact):
    """A point (PointContour) against a 2s contour (neutral 2s, band, cylinder, sphere,
    plane): C2 from eq. 3.6 by :class:`~contact.search.Contact2sSearch` (thesis Sec. 3.3),
    warm-started at the last contact point; g_N by eq. 3.4, ġ by eq. 3.8 (signs: module
    docstring). ``search``: a configured Contact2sSearch on ``surface`` (default grid
    8 × 8). Inactive when the point's foot lies outside an open contour's domain."""

    side1, search_class = PointContour, Contact2sSearch

    def __init__(self, point, surface, search=None, nu_total=None):
        super().__init__(point, surface, search, nu_total)


class ContactKinematicsSphereContour2s(_SearchContact):
    """A sphere (SphereContour, radius ρ) against a 2s contour: its centre c is searched
    as a point (eq. 3.6), g_N = nᵀ (c − r_C2) − ρ (eq. 3.4), C1 = c − ρ n, ġ by eq. 3.8
    with the sphere's material velocity at C1."""

    side1, search_class = SphereContour, Contact2sSearch

    def __init__(self, sphere, surface, search=None, nu_total=None):
        super().__init__(sphere, surface, search, nu_total)


class ContactKinematicsPointContour1s(_SearchContact):
    """A point against a 1s contour (curve): C2 from t_ηᵀ (r_P − r(η)) = 0 by
    :class:`~contact.search.Contact1sSearch`; the contact normal is the curve's n (its
    reference normal made perpendicular to the tangent), T = (t1, t2) its frame;
    g_N = nᵀ (r_P − r_C2) (eq. 3.4), ġ by eq. 3.8. The offset along t2 does not count
    (a planar contact, thesis Sec. 5.3)."""

    side1, search_class = PointContour, Contact1sSearch

    def __init__(self, point, curve, search=None, nu_total=None):
        super().__init__(point, curve, search, nu_total)


class ContactKinematicsSphereContour1s(_SearchContact):
    """A sphere against a 1s contour: its centre c is searched as a point,
    g_N = nᵀ (c − r_C2) − ρ with the curve's normal n, C1 = c − ρ n, ġ by eq. 3.8."""

    side1, search_class = SphereContour, Contact1sSearch

    def __init__(self, sphere, curve, search=None, nu_total=None):
        super().__init__(sphere, curve, search, nu_total)


class _EdgeFrame:
    """The frame of a contact on an edge (:class:`contours.Contour1sEdgeFFR`, a face's
    rim): the centre c (a point, or a sphere's centre) is searched as a point on the curve
    (closest point r_C2), the normal points from the edge to the centre, n = (c − r_C2)/|c
    − r_C2|, t1 the curve's tangent, t2 = n × t1 (:func:`._detection_kernels.edge_frame`);
    g_N = |c − r_C2| − ρ (eq. 3.4 with that n), C1 = c − ρ n, ġ by eq. 3.8 — exact: at the
    closest point c − r_C2 ⟂ t1. Inactive when c lies on the curve."""

    def _project(self, c, velocity, jacobians):
        return super()._project(c, velocity, jacobians) and K.edge_frame(self.point2.frame, c, self.point2.derivs)


class ContactKinematicsSphereEdge(_EdgeFrame, ContactKinematicsSphereContour1s):
    """A sphere against an edge (see :class:`_EdgeFrame`): a ball on a hole's rim."""


class _PlaneProjection(_CentreContact):
    """Contour 2 a PlaneContour: C2 is the orthogonal projection of c onto the plane,
    (η, ξ) = (x, y)ᵀ (c − O) in the plane's axes. The plane is unbounded for contact (its
    ``size`` only limits drawing), so the contact is always active."""

    def __init__(self, contour1, plane, nu_total):
        super().__init__(contour1, _require(plane, PlaneContour, "a PlaneContour"), nu_total)

    def _project(self, c, velocity, jacobians):
        self.contour2.evaluate(self.point2, *self.contour2.coordinates(c), velocity=velocity, jacobians=jacobians)
        return True


class ContactKinematicsPointPlane(_PlaneProjection):
    """A point against a plane, analytic (no search): C2 = r_P − g_N n, n the plane's z
    axis, g_N = nᵀ (r_P − O) (eq. 3.4), ġ by eq. 3.8."""

    side1 = PointContour

    def __init__(self, point, plane, nu_total=None):
        super().__init__(point, plane, nu_total)


class ContactKinematicsSpherePlane(_PlaneProjection):
    """A sphere against a plane, analytic: g_N = nᵀ (c − O) − ρ, C2 the projection of the
    centre c, C1 = c − ρ n (eq. 3.4, 3.8)."""

    side1 = SphereContour

    def __init__(self, sphere, plane, nu_total=None):
        super().__init__(sphere, plane, nu_total)


class _SphereProjection(_CentreContact):
    """Contour 2 a SphereContour, analytic: n = (c − c2)/|c − c2| along the line from its
    centre c2 to the centre c of side 1, C2 = c2 + ρ2 n, g_N = |c − c2| − ρ2 − ρ (eq. 3.4);
    T from sphere 2's frame at C2, ġ by eq. 3.8. Inactive when the centres coincide (no
    normal). ``axes2``: sphere 2's axes at the last update."""

    state_slots = _CentreContact.state_slots + ("axes2",)

    def __init__(self, contour1, sphere2, nu_total):
        super().__init__(contour1, _require(sphere2, SphereContour, "a SphereContour"), nu_total)
        self.axes2 = np.eye(3)

    def _project(self, c, velocity, jacobians):
        p2 = self.point2
        self.axes2[:] = self.contour2.axes
        d = c - self.contour2.centre
        dist = np.linalg.norm(d)
        if dist == 0.0:
            return False
        self.contour2.evaluate(p2, *sphere_angles(self.axes2, d / dist), velocity=velocity, jacobians=jacobians)
        return True


class ContactKinematicsPointSphere(_SphereProjection):
    """A point against a sphere, analytic (:class:`_SphereProjection` with ρ = 0):
    g_N = |r_P − c2| − ρ2, C2 = c2 + ρ2 n, C1 the point."""

    side1 = PointContour

    def __init__(self, point, sphere, nu_total=None):
        super().__init__(point, sphere, nu_total)


class ContactKinematicsSphereSphere(_SphereProjection):
    """Two spheres, analytic (:class:`_SphereProjection`): n = (c1 − c2)/|c1 − c2| along
    the centre line, g_N = |c1 − c2| − ρ1 − ρ2, C2 = c2 + ρ2 n, C1 = c1 − ρ1 n (eq. 3.4);
    T from sphere 2's frame at C2, ġ by eq. 3.8. Inactive when the centres coincide."""

    side1 = SphereContour

    def __init__(self, sphere1, sphere2, nu_total=None):
        super().__init__(sphere1, sphere2, nu_total)


class PointOnCurveConstraint(ContactKinematicsPointContour1s):
    """Bilateral "point stays on a curve" (the sliding ball of thesis Sec. 5.3): at the
    closest curve point η* (t_ηᵀ (r_P − r(η*)) = 0, eq. 3.6) the two normal-plane
    components of d = r_P − r(η*) in the curve frame,

        g = (nᵀ d, t2ᵀ d)        (2,) [m],
        ġ = (n, t2)ᵀ (v_P − v_C)  (2,) [m/s],   W = [W_N, W_T[:, 1]]  (nu_total, 2),

    with ġ = Wᵀ u. W is the exact gradient of g on the constraint manifold g = 0 (off it,
    the rotation of (n, t2) adds terms of order |g|). Valid while :attr:`active` (η*
    inside an open curve's domain).
    """

    state_slots = ContactKinematicsPointContour1s.state_slots + ("g", "gd")

    def __init__(self, point, curve, search=None, nu_total=None):
        super().__init__(point, curve, search, nu_total)
        self.g = np.zeros(2)
        self.gd = np.zeros(2)

    def update(self, velocity=True, jacobians=True) -> bool:
        """As :meth:`ContactKinematics.update`, then g and (with velocity) ġ."""
        if not super().update(velocity, jacobians):
            return False
        self.g[0] = self.g_N
        self.g[1] = self.T[:, 1] @ (self.point1.r - self.point2.r)
        if velocity:
            self.gd[0], self.gd[1] = self.gd_N, self.gd_T[1]
        return True

    def W(self, out=None):
        """W (nu_total, 2) into ``out`` (zero outside the bodies' slices); ġ = Wᵀ u."""
        out = np.zeros((self.nu_total, 2)) if out is None else out
        out.fill(0.0)               # (assigning a scalar to a strided view allocates a buffer)
        for s, w_N, w_T in self.local_blocks():
            out[s, 0] += w_N
            out[s, 1] += w_T[:, 1]
        return out
