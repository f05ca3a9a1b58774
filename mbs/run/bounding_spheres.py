"""Bounding spheres of contours at the global state, for the planned broad phase of the
contour stage (:mod:`mbs.run.plan`: a contact is searched only while its two contours'
spheres come within its margin).

:func:`contour_sphere` gives a callable (q, t) -> (centre (3,) [m], radius [m]) that
writes its centre into its own array: a point or sphere contour about its frame's
position (a frame on a point mass: r = q + ū0, no temporary); a neutral contour of a
flexible body within its body's sphere (:meth:`mbs.bodies.body.Body.bounding_sphere`:
centre R + A c, radius max_j |ū0_j − c| + Σ_k max_j |Φ_jk| |q_f,k|; for a frame fixed
in space the centre is constant and the radius is computed in place). Anything else
(planes, derived contours) cannot be bounded: None.

:class:`SphereTable` holds the distinct spheres of all prunable contacts of a run as
arrays and prunes every pair in one call of the kernels of :mod:`._sphere_kernels`
(the spheres of point masses, of flexible bodies at rest and of bodies on a free
quaternion frame computed there, the others by their callables), so the cost per
far-apart pair is a few array reads.
"""

from __future__ import annotations

import numpy as np

from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, PointContour, SphereContour

from mbs.run import _sphere_kernels as K
from mbs.bodies.rigid_body import PointMass, RigidBody

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
        f = body.q_f_slice
        self._f = slice(body.q_slice.start + f.start, body.q_slice.start + f.stop)
        self._abs = np.zeros(body.n_modes)
        self._rest_centre = None        # the constant centre of a body at rest, once known

    def __call__(self, q, t):
        b = self.body
        if not b.frame_at_rest:
            return b.bounding_sphere(q[b.q_slice], t)
        np.abs(q[self._f], out=self._abs)
        radius = b.rest_radius + b.mode_reach @ self._abs
        if self._rest_centre is None:
            self._rest_centre = b.bounding_sphere(q[b.q_slice], t)[0]
        return self._rest_centre, radius


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


class SphereTable:
    """The bounding spheres of the prunable contacts of a run (module docstring).

    Parameters
    ----------
    contacts : sequence
        The System's contacts; those with a :func:`sphere_pair` are pruned.

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
        Each prunable contact's margin [m].
    ints, floats : int and float vectors
        The arrays above are views of these two (layout of
        :func:`._sphere_kernels.prune`), which the kernel takes.
    """

    def __init__(self, contacts):
        self.spheres, index, pairs = [], {}, []
        for i, c in enumerate(contacts):
            pair = sphere_pair(c)
            if pair is None:
                continue
            ids = []
            for sphere in pair:
                key = _identity(sphere)
                if key not in index:
                    index[key] = len(self.spheres)
                    self.spheres.append(sphere)
                ids.append(index[key])
            pairs.append((i, ids[0], ids[1], c.margin))
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
            if isinstance(sphere, FrameSphere) and sphere._offset is not None:
                self.kind[s], self.at[s] = K.POINT, sphere.body.q_slice.start
                self.offset[s], self.radius0[s] = sphere._offset, sphere.radius
            elif isinstance(sphere, FlexibleBodySphere) and sphere.body.frame_at_rest:
                b = sphere.body
                self.kind[s], self.at[s] = K.AT_REST, sphere._f.start
                self.radius0[s], self.n_reach[s] = b.rest_radius, b.n_modes
                self.reach[s, :b.n_modes] = b.mode_reach
            elif isinstance(sphere, FlexibleBodySphere) and sphere.body.free_quaternion:
                b = sphere.body
                self.kind[s], self.at[s] = K.FREE, b.q_slice.start
                self.offset[s], self.radius0[s], self.n_reach[s] = b.box_centre, b.rest_radius, b.n_modes
                self.reach[s, :b.n_modes] = b.mode_reach
            elif isinstance(sphere, FrameSphere) and isinstance(sphere.body, RigidBody) and sphere.body.free_quaternion:
                self.kind[s], self.at[s] = K.FREE, sphere.body.q_slice.start
                self.offset[s], self.radius0[s] = sphere.frame.u0, sphere.radius
        self.called = [s for s in range(n) if self.kind[s] == K.CALLED]
        self.at_rest = [s for s in range(n) if self.kind[s] == K.AT_REST]
        for p, (i, s1, s2, margin) in enumerate(pairs):
            self.contact[p], self.sphere1[p], self.sphere2[p], self.margin[p] = i, s1, s2, margin

    def __len__(self):
        return len(self.contact)

    def start(self, q, t, centres, radii) -> None:
        """The constant centres of the spheres at rest at (q, t) into ``centres`` (once per
        run, before :meth:`prune`)."""
        for s in self.at_rest:
            centres[s] = self.spheres[s](q, t)[0]

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


def _identity(sphere):
    """What makes two sphere callables the same sphere: the frame (radius) or the body."""
    if isinstance(sphere, FrameSphere):
        return ("frame", id(sphere.frame), id(sphere.body), sphere.radius)
    return ("body", id(sphere.body))
