"""Bounding spheres of contours at the global state, for the planned broad phase of the
contour stage (:mod:`mbs.run.plan`: a contact is searched only while its two contours'
spheres come within its margin).

:func:`contour_sphere` gives a callable (q, t) -> (centre (3,) [m], radius [m]) that
writes its centre into its own array, for every contour kind of :data:`contours.CONTOURS`
but a plane on a moving frame:

- a point or sphere contour: about its frame's position (a frame on a point mass:
  r = q + ū0, no temporary); on the ground a sphere fixed in space;
- a neutral contour of a flexible body (1s, 2s, edge): within its body's sphere
  (:meth:`mbs.bodies.body.Body.bounding_sphere`: centre R + A c, radius
  max_j |ū0_j − c| + Σ_k max_j |Φ_jk| |q_f,k|; for a frame fixed in space the centre
  is constant and the radius is computed in place);
- a neutral contour of a rigid body (2s-rigid, 1s-rigid): about the body-frame centre c
  of its control points, radius max |P_ū0 − c| (a B-spline lies in the convex hull of
  its control points);
- an offset contour (band, cylinder): its neutral curve's sphere grown by the offset's
  reach (the largest |d̄|);
- a plane on the ground: not a sphere but the half-space behind it (:class:`GroundPlane`;
  its pairs are live while the other sphere reaches within the margin of the plane).

:class:`SphereTable` holds the distinct spheres of all prunable contacts of a run (two or
more: :func:`pruned`) as arrays and prunes every pair in one call of the kernels of :mod:`._sphere_kernels`
(the spheres of point masses, of flexible bodies at rest, of bodies on a free
quaternion frame and those fixed in space computed there, the others by their
callables), so the cost per far-apart pair is a few array reads.
"""

from __future__ import annotations

import numpy as np

from contours import (Contour1sNeutralFFR, Contour1sNeutralRigid, Contour2sNeutralFFR, Contour2sNeutralRigid,
                      PlaneContour, PointContour, SphereContour)
from contours.derived import OffsetContour

from mbs.run import _sphere_kernels as K
from mbs.bodies.rigid_body import PointMass, RigidBody

MIN_PAIRS = 2
# ^ a planned run prunes from two prunable contacts on: one contact's own detection tests
#   its contours' bounding boxes first, at about the cost of the spheres' test
NEUTRAL_FFR = (Contour1sNeutralFFR, Contour2sNeutralFFR)
NEUTRAL_RIGID = (Contour1sNeutralRigid, Contour2sNeutralRigid)


class FrameSphere:
    """The sphere of radius ``radius`` [m] about ``frame``'s origin on ``body``; ``key``
    what makes two of them the same sphere (default: the frame, body and radius)."""

    def __init__(self, frame, body, radius, key=None):
        self.frame, self.body, self.radius = frame, body, float(radius)
        self.centre = np.zeros(3)
        self._offset = frame.u0 if isinstance(body, PointMass) else None
        self.key = ("frame", id(frame), id(body), self.radius) if key is None else key

    def grown(self, reach) -> "FrameSphere":
        """The same sphere with ``reach`` [m] more radius."""
        return FrameSphere(self.frame, self.body, self.radius + reach, key=self.key[:-1] + (self.radius + reach,))

    def __call__(self, q, t):
        qb = q[self.body.q_slice]
        if self._offset is not None:               # a point mass's frame: r = q + ū0
            np.add(qb, self._offset, out=self.centre)
        else:
            self.centre[:] = self.frame.position(qb, t)
        return self.centre, self.radius


class FlexibleBodySphere:
    """The bounding sphere of a flexible body (:meth:`FlexibleBodyFFR.bounding_sphere`),
    its radius grown by ``reach`` [m] (an offset contour's)."""

    def __init__(self, body, reach=0.0):
        self.body, self.reach = body, float(reach)
        self.key = ("body", id(body), self.reach)
        f = body.q_f_slice
        self._f = slice(body.q_slice.start + f.start, body.q_slice.start + f.stop)
        self._abs = np.zeros(body.n_modes)
        self._rest_centre = None        # the constant centre of a body at rest, once known

    def __call__(self, q, t):
        b = self.body
        if not b.frame_at_rest:
            centre, radius = b.bounding_sphere(q[b.q_slice], t)
            return centre, radius + self.reach
        np.abs(q[self._f], out=self._abs)
        radius = b.rest_radius + self.reach + b.mode_reach @ self._abs
        if self._rest_centre is None:
            self._rest_centre = b.bounding_sphere(q[b.q_slice], t)[0]
        return self._rest_centre, radius

    def grown(self, reach) -> "FlexibleBodySphere":
        """The same body's sphere with ``reach`` [m] more radius."""
        return FlexibleBodySphere(self.body, self.reach + reach)


class FixedSphere:
    """A sphere fixed in space: centre (3,) [m], radius [m]."""

    def __init__(self, centre, radius):
        self.centre, self.radius = np.array(centre, dtype=float), float(radius)
        self.key = ("fixed", *self.centre.tolist(), self.radius)

    def __call__(self, q, t):
        return self.centre, self.radius


class GroundPlane:
    """The half-space behind a plane contour on the ground: ``centre`` its frame's origin
    p0 [m], ``normal`` its unit normal n (the frame's z axis). Called it gives (p0, 0);
    a pair with it is live while nᵀ(c1 − p0) <= r1 + margin (:func:`live_pair`)."""

    def __init__(self, frame):
        self.centre = np.array(frame.position(None), dtype=float)
        self.normal = np.array(frame.orientation(None), dtype=float)[:, 2]
        self.key = ("plane", *self.centre.tolist(), *self.normal.tolist())

    def __call__(self, q, t):
        return self.centre, 0.0


def contour_sphere(contour):
    """A callable (q, t) -> (centre (3,) [m], radius [m]) of a sphere holding ``contour``
    at the global state (a :class:`GroundPlane` for a plane on the ground), or None
    (module docstring)."""
    body = contour.body
    if isinstance(contour, OffsetContour):
        inner = contour_sphere(contour.neutral)
        return None if inner is None else inner.grown(contour.reach)
    if isinstance(contour, (PointContour, SphereContour)):
        radius = getattr(contour, "radius", 0.0)
        if body is None:
            return FixedSphere(contour.frame_ref.position(None), radius)
        return FrameSphere(contour.frame_ref, body, radius)
    if isinstance(contour, PlaneContour):
        return GroundPlane(contour.frame_ref) if body is None else None
    if isinstance(contour, NEUTRAL_FFR):
        return FlexibleBodySphere(body)
    if isinstance(contour, NEUTRAL_RIGID) and body is not None:
        P0 = contour.local_position.ctrl0.reshape(-1, 3)
        c = 0.5 * (P0.min(axis=0) + P0.max(axis=0))
        radius = float(np.sqrt(((P0 - c) ** 2).sum(axis=1).max()))
        return FrameSphere(body.frame_at(c), body, radius, key=("rigid", id(body), *c.tolist(), radius))
    return None


def live_pair(sphere1, sphere2, margin, q, t) -> bool:
    """Whether a pair of bounds comes within ``margin`` [m] at (q, t): the plain-Python
    reference of :func:`._sphere_kernels.prune_pairs`."""
    c1, r1 = sphere1(q, t)
    c1 = np.array(c1)
    c2, r2 = sphere2(q, t)
    d = c1 - c2
    if isinstance(sphere2, GroundPlane):
        return not float(sphere2.normal @ d) > r1 + margin
    reach = r1 + r2 + margin
    return not float(d @ d) > reach * reach


def pruned(contacts) -> list:
    """The contacts a planned run prunes: those with a :func:`sphere_pair`, when there
    are at least :data:`MIN_PAIRS` of them, else none."""
    prunable = [c for c in contacts if sphere_pair(c) is not None]
    return prunable if len(prunable) >= MIN_PAIRS else []


def sphere_pair(contact):
    """(sphere1, sphere2) of a prunable contact (unilateral, with a margin, both contours
    bounded), else None."""
    if not (contact.unilateral and contact.margin is not None):
        return None
    s1, s2 = contour_sphere(contact.kinematics.contour1), contour_sphere(contact.kinematics.contour2)
    return (s1, s2) if s1 is not None and s2 is not None else None


class SphereTable:
    """The bounding spheres of the prunable contacts of a run (module docstring).

    Parameters
    ----------
    contacts : sequence
        The System's contacts; those with a :func:`sphere_pair` are pruned, if there
        are at least :data:`MIN_PAIRS` of them (:func:`pruned`).

    Attributes
    ----------
    spheres : list of callables
        The distinct spheres (each once, shared between contacts).
    kind, at : (n_s,) int
        Kernel kind (:data:`._sphere_kernels.POINT`, ``AT_REST``, ``CALLED``) and the first
        index into the global q it reads (the point's position, the body's q_f).
    offset, radius0, reach, n_reach
        The constants of :func:`._sphere_kernels.sphere_states`: offset (n_s, 3) [m],
        radius0 (n_s,) [m], reach (n_s, max n_f) [m], n_reach (n_s,).
    contact, sphere1, sphere2 : (n_p,) int
        Each prunable contact's index and spheres.
    margin : (n_p,)
        Each prunable contact's margin plus its closing tolerance [m] (a contact resting
        within ``closing_tol`` of the surface stays live even with a zero margin).
    ints, floats : int and float vectors
        The arrays above are views of these two (layout of
        :func:`._sphere_kernels.prune`), which the kernel takes.
    """

    def __init__(self, contacts):
        self.spheres, index, pairs = [], {}, []
        kept = {id(c) for c in pruned(contacts)}
        for i, c in enumerate(contacts):
            pair = sphere_pair(c) if id(c) in kept else None
            if pair is None:
                continue
            ids = []
            for sphere in pair:
                key = sphere.key
                if key not in index:
                    index[key] = len(self.spheres)
                    self.spheres.append(sphere)
                ids.append(index[key])
            pairs.append((i, ids[0], ids[1], c.margin + c.closing_tol))   # closed up to closing_tol
        n, n_p = len(self.spheres), len(pairs)
        width = max((s.body.n_modes for s in self.spheres if isinstance(s, FlexibleBodySphere)), default=0)
        self.ints = np.zeros(K.INTS_AT + 3 * n + 3 * n_p, dtype=np.int64)
        self.ints[:K.INTS_AT] = n, n_p, width
        self.kind, self.at, self.n_reach, self.contact, self.sphere1, self.sphere2 = (
            self.ints[K.INTS_AT + a:K.INTS_AT + b] for a, b in _blocks((n, n, n, n_p, n_p, n_p)))
        self.floats = np.zeros((4 + width) * n + n_p + 9)    # the last 9: the kernel's work block
        offset, self.radius0, reach, self.margin = (self.floats[a:b] for a, b in _blocks((3 * n, n, width * n, n_p)))
        self.offset, self.reach = offset.reshape(n, 3), reach.reshape(n, width)
        self.kind[:] = K.CALLED
        for s, sphere in enumerate(self.spheres):
            if isinstance(sphere, FixedSphere):
                self.kind[s], self.radius0[s] = K.AT_REST, sphere.radius
            elif isinstance(sphere, GroundPlane):
                self.kind[s], self.offset[s] = K.PLANE, sphere.normal
            elif isinstance(sphere, FrameSphere) and sphere._offset is not None:
                self.kind[s], self.at[s] = K.POINT, sphere.body.q_slice.start
                self.offset[s], self.radius0[s] = sphere._offset, sphere.radius
            elif isinstance(sphere, FlexibleBodySphere) and sphere.body.frame_at_rest:
                b = sphere.body
                self.kind[s], self.at[s] = K.AT_REST, sphere._f.start
                self.radius0[s], self.n_reach[s] = b.rest_radius + sphere.reach, b.n_modes
                self.reach[s, :b.n_modes] = b.mode_reach
            elif isinstance(sphere, FlexibleBodySphere) and sphere.body.free_quaternion:
                b = sphere.body
                self.kind[s], self.at[s] = K.FREE, b.q_slice.start
                self.offset[s], self.radius0[s], self.n_reach[s] = b.box_centre, b.rest_radius + sphere.reach, b.n_modes
                self.reach[s, :b.n_modes] = b.mode_reach
            elif isinstance(sphere, FrameSphere) and isinstance(sphere.body, RigidBody) and sphere.body.free_quaternion:
                self.kind[s], self.at[s] = K.FREE, sphere.body.q_slice.start
                self.offset[s], self.radius0[s] = sphere.frame.u0, sphere.radius
        self.called = [s for s in range(n) if self.kind[s] == K.CALLED]
        self.at_rest = [s for s in range(n) if self.kind[s] in (K.AT_REST, K.PLANE)]
        for p, (i, s1, s2, margin) in enumerate(pairs):
            self.contact[p], self.sphere1[p], self.sphere2[p], self.margin[p] = i, s1, s2, margin

    def __len__(self):
        return len(self.contact)

    def start(self, q, t, centres, radii) -> None:
        """The constant centres of the spheres at rest (and the planes' points, radius 0)
        at (q, t) into ``centres`` (once per run, before :meth:`prune`)."""
        for s in self.at_rest:
            centres[s], radii[s] = self.spheres[s](q, t)

    def prune(self, q, t, centres, radii, live, closed, live_idx) -> tuple:
        """Every prunable contact live or not at (q, t) (:func:`._sphere_kernels.prune`:
        :func:`~._sphere_kernels.sphere_states`, then :func:`~._sphere_kernels.prune_pairs`),
        the live contacts' indices into ``live_idx``; ``centres`` (n_s, 3), ``radii``
        (n_s,) the spheres' workspaces. Returns (the number pruned, the number live)."""
        for s in self.called:
            centre, radii[s] = self.spheres[s](q, t)
            centres[s] = centre
        return K.prune(q, self.ints, self.floats, centres, radii, live, closed, live_idx)


def _blocks(sizes):
    """[(start, stop)] of consecutive blocks of the given sizes."""
    stops = np.cumsum(sizes)
    return list(zip(stops - np.asarray(sizes), stops))

