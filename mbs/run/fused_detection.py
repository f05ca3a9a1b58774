"""Fused detection: the contour update and the detection of one contact in one compiled
call per step (stages 3 and 4 of :mod:`mbs.run.stages` for the pair kinds that have one).

The Python path of a contact is ``contour.update`` of its two contours (contour stage)
and :meth:`contact.Contact.locate` (detection stage): a dozen numba calls glued by
Python. For the pair kinds below :func:`fused_detection` gives an object whose
:meth:`~CentreOnNeutral2s.locate` does both in one kernel
(:mod:`._fused_detection_kernels`), on the same objects' arrays, so that the contours,
the contact points, the kinematics (g_N, frame, Jacobian pieces), the search's warm
start and counters hold afterwards what the Python path leaves there. It returns to the
Python path whenever the kernel cannot finish the step: no warm start (the first
search, or the last one found nothing) or Newton from it failed — the Python path then
searches the coarse grid (:mod:`contact.search`).

Kinds with a fused detection:

* :class:`CentreOnNeutral2s`: a point (``PointContour``) or a sphere (``SphereContour``)
  against a compiled neutral 2s contour — nodal or fitted, trimmed or not (a root in a
  hole falls back to the Python path, which keeps the hole as the search does),
  :class:`~contours.neutral.factory.Contour2sNeutralFactory` — of a floating-frame body
  (an FFR body or a rigid one), ``ContactKinematicsPointContour2s`` or
  ``ContactKinematicsSphereContour2s`` with a compiled ``Contact2sSearch``, any law of
  :class:`contact.Contact`;
* :class:`CentreOnOffset`: the same against a band or a cylinder
  (:class:`~contours.derived.OffsetContour`) on a compiled 1s neutral curve;
* :class:`CentreOnNeutral1s`: the same against a compiled neutral 1s contour (a curve),
  ``ContactKinematicsPointContour1s``, ``ContactKinematicsSphereContour1s`` or
  ``ContactKinematicsSphereEdge`` (a sharp edge, a hole's rim) with a compiled
  ``Contact1sSearch``; :class:`PointKeptOnCurve`: a point kept on such a curve
  (a bilateral :class:`~contact.CurveConstraint`);
* :class:`CentreOnPlane`: a point or a sphere against a plane
  (``ContactKinematicsPointPlane``, ``ContactKinematicsSpherePlane``) and
  :class:`SphereOnSphere`: a point or a sphere against a sphere
  (``ContactKinematicsPointSphere``, ``ContactKinematicsSphereSphere``) — analytic,
  no search, so they never fall back.

The kernel writes the state of a point mass's frame itself, of side 1's frame at a node
of a flexible body on a free quaternion frame or a frame at rest (its position,
orientation, velocities and Jacobians: :func:`._fused_detection_kernels._node_frame`), and
of a neutral contour's free quaternion frame (R, A, v, ω̄ = u_r from the global q, u; a
curve's reference normal with them); a ground frame's is constant, so is a frame at
rest's. What moves by a Python function is updated in Python just before the kernel,
which does the rest: a frame contour on another body (a rigid body, a node of a body on
a prescribed moving or Cardan frame), a neutral contour on a prescribed frame (a
function of t) or a free Cardan frame (its R, A, v, ω̄ and the map T of ω̄ = T u_r,
which the Jacobians take).

The kernels leave the contact's state in arrays — the kinematics' buffer (g_N, ġ_N, the
active flag, n, T, …), the contact points' buffers ((η, ξ), r and its derivatives, …),
the warm start and the counters — so a located contact needs nothing written in Python.

Every registered pair kind has one (``tests/unit/mbs/test_checkpoint.py`` fails for a
kind registered without); a contour built for the reference route (``compiled=False``)
keeps the Python path, which stays the reference of the fused ones
(``tests/unit/contact/test_fused_detection.py``).
"""

from __future__ import annotations

import numpy as np

from contact.contact import Contact, CurveConstraint
from contact.kinematics import (ContactKinematicsPointContour1s, ContactKinematicsPointContour2s,
                                ContactKinematicsPointPlane, ContactKinematicsPointSphere,
                                ContactKinematicsSphereContour1s, ContactKinematicsSphereContour2s,
                                ContactKinematicsSphereEdge,
                                ContactKinematicsSpherePlane, ContactKinematicsSphereSphere, PointOnCurveConstraint,
                                buffer_layout)
from contact.search import Contact1sSearch, Contact2sSearch
from contours.base import DERIVS_AT
from contours.derived import OffsetContour
from contours.neutral.factory import Contour1sNeutralFactory, Contour2sNeutralFactory
from contours.rigid import PlaneContour, PointContour, SphereContour

from mbs.bodies.floating_frame import FloatingFrameBody
from mbs.run import _fused_detection_kernels as K


def fused_detection(contact):
    """The fused detection of ``contact`` (:class:`CentreOnNeutral2s`,
    :class:`CentreOnOffset`, :class:`CentreOnNeutral1s`, :class:`PointKeptOnCurve`,
    :class:`CentreOnPlane`, :class:`SphereOnSphere`) when its kind has one and its bodies
    belong to a System, else None (the Python path)."""
    for kind in (CentreOnNeutral2s, CentreOnOffset, CentreOnNeutral1s, PointKeptOnCurve, CentreOnPlane,
                 SphereOnSphere):
        if kind.applies(contact):
            return kind(contact)
    return None


ON_SURFACE = {ContactKinematicsPointContour2s: PointContour, ContactKinematicsSphereContour2s: SphereContour}
ON_CURVE = {ContactKinematicsPointContour1s: PointContour, ContactKinematicsSphereContour1s: SphereContour,
            ContactKinematicsSphereEdge: SphereContour}
# ^ the kinematics of a centre searched on a 2s contour / a curve and the contour of its side 1


def _frame_side(contour, itab, ftab, q_at, u_at, offset_at):
    """How a kernel gets the state of a frame contour (a point, a sphere, a plane): on a
    point mass the kernel writes it from the global q, u (its rows into ``itab[q_at]``,
    ``itab[u_at]``, the frame's offset ū0 into ``ftab[offset_at:+3]``); on the ground it
    is constant (set here); on another body (a rigid body, a node of an FFR body) its
    update writes it in Python before the kernel: returns (contour, q slice, u slice)
    then, else None."""
    body = contour.body
    itab[q_at] = itab[u_at] = -1
    if body is None:
        contour.update(None, None, 0.0)
        return None
    if body.translation_only:
        itab[q_at], itab[u_at] = body.q_slice.start, body.u_slice.start
        ftab[offset_at:offset_at + 3] = contour.frame_ref.u0
        return None
    return contour, body.q_slice, body.u_slice


def _node_side(side, itab, ftab):
    """Side 1 at a node of a flexible body on a free quaternion frame or a frame at rest
    (``side`` as :func:`_frame_side` returned it: (contour, q slice, u slice)): the kernel
    writes its frame (:func:`._fused_detection_kernels._node_frame`) from the rows, n_f,
    frame kind and the constants (R₀, A₀ at rest, the node's mode rows) set here, appended
    to ``ftab``. Returns (ftab, side): side None when the kernel writes it, else as given."""
    itab[K.NODE_Q] = itab[K.NODE_U] = -1
    if side is None:
        return ftab, side
    contour = side[0]
    frame, body = contour.frame_ref, contour.body
    if (frame.node_index is None or not isinstance(body, FloatingFrameBody) or not body.n_modes
            or not (body.free_quaternion or body.frame_at_rest) or not np.array_equal(frame.A_rel, np.eye(3))):
        return ftab, side
    R0, A0 = body.frame_state(body.q_init)[:2]
    itab[K.NODE_Q], itab[K.NODE_U] = body.q_slice.start, body.u_slice.start
    itab[K.NODE_NF], itab[K.NODE_FREE], itab[K.NODE_AT] = body.n_modes, body.free_quaternion, ftab.size
    ftab[K.OFFSET_AT:K.OFFSET_AT + 3] = frame.u0
    return np.concatenate((ftab, R0, np.ravel(A0), frame.phi.ravel())), None


def _python_updates(updates, q, u, t):
    """``contour.update`` of each (contour, q slice, u slice) at the global (q, u, t); a
    contour on the ground (slices None) at t."""
    for contour, qs, us in updates:
        if qs is None:
            contour.update(None, None, t)
        else:
            contour.update(q[qs], u[us], t)


class _Refreshed:
    """A fused detection made from its ``contact`` alone (its constructor's argument)."""

    def refresh(self) -> None:
        """The tables and the argument tuple made again on the contact's arrays, once
        they moved into a run's Data (:mod:`mbs.run.contact_state`)."""
        type(self).__init__(self, self.contact)


class _FusedCentre(_Refreshed):
    """What the fused detections of a centre (a point or a sphere on any body or the
    ground) on a surface of a floating-frame body share: the tables' common entries (the layouts of
    :mod:`._fused_detection_kernels`), Newton's settings, and :meth:`locate` around the
    kernel (:attr:`kernel` with the arguments :attr:`_args` after q and u), preceded on a
    moving frame by the surface's update (but a free quaternion frame: the kernel writes
    its state). ``neutral``: the neutral contour whose state the kernel writes (the
    surface, or a band's curve); ``offset_floats``: an offset contour's law size [m], ξ
    domain and reach [m], or a 1s contour's body-frame reference normal (ftab)."""

    kernel = None

    @staticmethod
    def _applies(contact, surface_ok, kinds=ON_SURFACE, search=Contact2sSearch, element=Contact) -> bool:
        """A contact (an ``element``, default :class:`~contact.Contact`) of a point or a
        sphere (``kinds``: {kinematics: side 1's contour}) against a contour for which
        ``surface_ok(contour)`` holds, on a floating-frame body, searched by a compiled
        ``search``, the bodies in a System (side 1 may be on the ground)."""
        if type(contact) is not element:
            return False
        k = contact.kinematics
        side1 = kinds.get(type(k))
        if side1 is None:
            return False
        point, surface = k.contour1, k.contour2
        body1, body2 = point.body, surface.body
        return (type(point) is side1 and surface_ok(surface) and isinstance(body2, FloatingFrameBody)
                and type(k.search) is search and k.search.compiled
                and (body1 is None or body1.q_slice is not None) and body2.q_slice is not None)

    def __init__(self, contact, neutral, offset_floats=(0.0, 0.0, 0.0, 0.0)):
        self.contact = contact
        k = self.kinematics = contact.kinematics
        point, surface = k.contour1, k.contour2
        self.search, self.neutral = k.search, neutral
        self.closing_tol = getattr(contact, "closing_tol", np.inf)      # a point kept on a curve: always closed
        margin = getattr(contact, "margin", None)
        body2 = surface.body
        n_f = neutral.n_modes
        itab = np.zeros(K.ITAB_SIZE, dtype=np.int64)
        ftab = np.concatenate((np.zeros(K.BOX_AT), *neutral.rest_box, neutral.mode_box_growth.ravel()))
        ftab, side1 = _node_side(_frame_side(point, itab, ftab, K.QP, K.UP, K.OFFSET_AT), itab, ftab)
        itab[K.QF] = body2.q_slice.start + body2.q_f_slice.start
        itab[K.UF] = body2.u_slice.start + body2.u_f_slice.start
        itab[K.NF], itab[K.NU1], itab[K.NU2] = n_f, point.nu, surface.nu
        itab[K.VELOCITY], itab[K.BOX] = not contact.set_valued, margin is not None       # ġ for a single-valued law
        itab[K.FREE] = body2.is_free
        itab[K.EDGE] = type(k) is ContactKinematicsSphereEdge
        frame_in_kernel = body2.free_quaternion         # its R, A, v, ω̄ written by the kernel
        itab[K.FRAME_Q] = body2.q_slice.start if frame_in_kernel else -1
        itab[K.FRAME_U] = body2.u_slice.start if frame_in_kernel else -1
        itab[K.KIN_AT:K.KIN_AT + 8] = buffer_layout(point.nu, surface.nu)
        ftab[K.MARGIN] = 0.0 if margin is None else margin
        ftab[K.RADIUS] = k.radius
        ftab[K.FLOATS_AT:K.FLOATS_AT + 4] = offset_floats
        self._itab, self._ftab = itab, ftab
        self._newton_settings()
        self._work = np.zeros(K.WORK_SIZE)
        self._points = (point.state, k.point1.buffer, k.point2.buffer, k.buffer, k.centre, k.axes1, k.start,
                        k.search.counts)
        self._updates = [(c, None, None) if c.body is None else (c, c.body.q_slice, c.body.u_slice)
                         for c in (point, surface)]                        # the Python path's
        moving = not (body2.frame_at_rest or frame_in_kernel)
        self._before = [side for side, python in ((side1, side1 is not None), (self._updates[1], moving)) if python]
        # ^ updated in Python before the kernel: side 1 on a body other than a point mass, the
        #   surface on a moving frame but a free quaternion one (the kernel's)
        self._free_T = None
        if frame_in_kernel:
            ftab[K.FRAME_T_AT:K.FRAME_T_AT + 9] = np.eye(3).ravel()             # ω̄ = u_r
        elif body2.is_free:
            self._free_T = ftab[K.FRAME_T_AT:K.FRAME_T_AT + 9].reshape(3, 3)    # the update's T, each step

    def _newton_settings(self):
        """Newton's step caps and tolerance from the search into the tables."""
        _newton_settings(self.search, self._itab, self._ftab)

    def locate(self, q, u, t) -> bool:
        """Both contours updated at the global (q, u, t) and the contact located, as
        ``contour.update`` then :meth:`Contact.locate` (the Python path when the kernel
        falls back): True when closed (g_N <= closing_tol)."""
        if self._before:
            _python_updates(self._before, q, u, t)
            if self._free_T is not None:
                self._free_T[...] = self.neutral.T
        outcome, g_N = type(self).kernel(q, u, *self._args)
        self.neutral.kernel_updated(velocity=True)
        if outcome == K.LOCATED:
            return self._located(g_N)
        if outcome != K.FALLBACK:           # apart, or no contact point (the kernel left it inactive)
            return False
        _python_updates(self._updates, q, u, t)
        closed = self.contact.locate()
        if np.isnan(self._ftab[K.TOL2]):
            self._newton_settings()
        return closed

    def _located(self, g_N) -> bool:
        """Closed when g_N [m] <= closing_tol, once the kernel located the contact."""
        return g_N <= self.closing_tol

    def probe(self) -> "Probe | None":
        """A :class:`Probe` of this contact; None when a contour is updated in Python (the
        probe's copies of the states hold the frames of their construction: the contact
        recorder then takes the Python path)."""
        return None if self._before else Probe(self)


def _newton_settings(search, itab, ftab) -> None:
    """Newton's step caps, tolerance and iterations from ``search`` into ``itab``,
    ``ftab`` (a NaN tolerance while its length scale is not known: the kernel falls back)."""
    settings = search.newton_settings()
    if settings is None:
        ftab[K.TOL2] = np.nan
        return
    steps, ftab[K.TOL2], ftab[K.EDGE2], itab[K.MAX_ITER] = settings
    ftab[K.MAX_STEP_E:K.MAX_STEP_E + len(steps)] = steps


def _copied(args):
    """The arrays of a kernel's argument tuple copied (nested tuples of work arrays too)."""
    return tuple(_copied(a) if isinstance(a, tuple) else a.copy() for a in args)


class Probe:
    """The gap of a contact with a fused detection at a given state, located into copies
    of the detection's arrays (contour states, contact points, kinematics, warm start,
    counters, work), so that the run's own stay as they are: what the contact recorder
    (:mod:`mbs.results.contact_record`) samples of an open contact, without the save and restore
    of the run state around the Python path. Newton starts from the run's last contact
    point, or, while the run has none (a contact never located, or lost), from the
    probe's own last one (:meth:`seed`: the recorder's Python path gives it one); the
    broad phase is left out (the recorder wants the gap however far).

    Parameters
    ----------
    fused : _FusedCentre
    """

    def __init__(self, fused):
        self.fused = fused
        self.args = _copied(fused._args)
        position = {id(a): i for i, a in enumerate(fused._args)}
        k = fused.kinematics
        self._start = self.args[position[id(k.start)]]
        self._point2 = self.args[position[id(k.point2.buffer)]]
        self._kin = self.args[position[id(k.buffer)]]

    def locate(self, q, u):
        """(g_N [m], contact point C2 (3,) [m], normal n (3,)) at the global (q, u) — views
        of the probe's arrays —, or None when the kernel cannot locate it from its warm
        start (then the caller takes the Python path)."""
        fused, args = self.fused, self.args
        itab, ftab = args[0], args[1]
        if not np.isnan(fused._ftab[K.TOL2]):           # else the settings of the last seed
            np.copyto(itab, fused._itab)
            np.copyto(ftab, fused._ftab)
        itab[K.BOX] = 0
        if not np.isnan(fused.kinematics.start[0]):
            np.copyto(self._start, fused.kinematics.start)
        outcome, g_N = type(fused).kernel(q, u, *args)
        if outcome != K.LOCATED:
            return None
        n_at = fused._itab[K.KIN_AT]
        return g_N, self._point2[DERIVS_AT:DERIVS_AT + 3], self._kin[n_at:n_at + 3]

    def seed(self) -> None:
        """Take the contact point and Newton's settings the run's kinematics and search
        hold now — a locate by the Python path at a sample, before its run state is put
        back — as the probe's own, for the samples while the run has none."""
        fused = self.fused
        np.copyto(self._start, fused.kinematics.start)
        np.copyto(self.args[0], fused._itab)
        np.copyto(self.args[1], fused._ftab)
        _newton_settings(fused.search, self.args[0], self.args[1])


class CentreOnNeutral2s(_FusedCentre):
    """Stages 3 and 4 of a point or a sphere against a neutral 2s contour
    on a floating-frame body (module docstring) in one call of
    :func:`._fused_detection_kernels.centre_on_neutral_2s`.

    Parameters
    ----------
    contact : Contact
        With ``ContactKinematicsPointContour2s`` or ``ContactKinematicsSphereContour2s``
        (:meth:`applies`).
    """

    kernel = K.centre_on_neutral_2s

    @staticmethod
    def applies(contact) -> bool:
        """True for a point or a sphere against a compiled neutral 2s contour on a
        floating-frame body (:meth:`_FusedCentre._applies`)."""
        return _FusedCentre._applies(contact, lambda s: isinstance(s, Contour2sNeutralFactory) and s.compiled)

    def __init__(self, contact):
        surface = contact.kinematics.contour2
        super().__init__(contact, surface)
        self._ftab[K.SIGN] = surface.sign
        trim = surface.trim
        holes = (np.zeros((0, 2)), np.zeros(1, dtype=np.int64)) if trim is None else (trim.vertices, trim.starts)
        self._args = (self._itab, self._ftab, *surface.kernel_data, *self._points, self._work, self.search.newton_work,
                      surface.evaluate_work, *holes)
        self._hole = None if trim is None else self.search.hole

    def _located(self, g_N) -> bool:
        if self._hole is not None:
            self._hole.fill(np.nan)             # as the search's solve: no hole once a root is on the material
        return g_N <= self.closing_tol


class CentreOnOffset(_FusedCentre):
    """Stages 3 and 4 of a point or a sphere against a band or a cylinder
    (:class:`~contours.derived.OffsetContour`) on a compiled 1s neutral curve of a
    floating-frame body, in one call of :func:`._fused_detection_kernels.centre_on_offset`."""

    kernel = K.centre_on_offset

    @staticmethod
    def applies(contact) -> bool:
        """True for a point or a sphere against a compiled offset contour
        on a compiled 1s neutral curve of a floating-frame body (:meth:`_FusedCentre._applies`)."""
        return _FusedCentre._applies(contact, lambda s: isinstance(s, OffsetContour) and s.compiled
                                     and isinstance(s.neutral, Contour1sNeutralFactory) and s.neutral.compiled)

    def __init__(self, contact):
        surface = contact.kinematics.contour2
        neutral = surface.neutral
        law, size = surface.offset_law
        xi_axis = contact.kinematics.search.axes[1]
        super().__init__(contact, neutral, (size, xi_axis.a, xi_axis.b, surface.reach))
        self._itab[K.LAW], self._itab[K.XI_CLOSED] = law, xi_axis.closed
        self._args = (self._itab, self._ftab, *neutral.kernel_data, neutral.normal_ref,
                      *self._points, self._work, self.search.newton_work, surface.evaluate_work)


class CentreOnNeutral1s(_FusedCentre):
    """Stages 3 and 4 of a point or a sphere against a compiled neutral 1s
    contour of a floating-frame body, in one call of :func:`._fused_detection_kernels.centre_on_neutral_1s`."""

    kernel = K.centre_on_neutral_1s

    @staticmethod
    def applies(contact) -> bool:
        """True for a point or a sphere against a compiled neutral 1s
        contour of a floating-frame body (:meth:`_FusedCentre._applies`)."""
        return _FusedCentre._applies(contact, lambda s: isinstance(s, Contour1sNeutralFactory) and s.compiled,
                                     ON_CURVE, Contact1sSearch)

    def __init__(self, contact):
        curve = contact.kinematics.contour2
        super().__init__(contact, curve, tuple(curve.normal_ref) + (0.0,))
        self._args = (self._itab, self._ftab, *curve.kernel_data, curve.n_ref,
                      *self._points, self._work, self.search.newton_work, curve.evaluate_work)


class PointKeptOnCurve(CentreOnNeutral1s):
    """A point kept on a compiled neutral 1s contour (:class:`~contact.CurveConstraint`,
    bilateral: :class:`~contact.kinematics.PointOnCurveConstraint`) located as
    :class:`CentreOnNeutral1s` locates a point, its gaps g = (g_N, t2ᵀ (r_P − r_C2))
    (:func:`._fused_detection_kernels.normal_plane_offset`) filled as its ``update`` fills
    them; always closed (the Python path says when the point left the curve)."""

    @staticmethod
    def applies(contact) -> bool:
        """True for a :class:`~contact.CurveConstraint` of a point against a compiled
        neutral 1s contour of a floating-frame body (:meth:`_FusedCentre._applies`)."""
        return _FusedCentre._applies(contact, lambda s: isinstance(s, Contour1sNeutralFactory) and s.compiled,
                                     {PointOnCurveConstraint: PointContour}, Contact1sSearch, CurveConstraint)

    def __init__(self, contact):
        super().__init__(contact)
        k = self.kinematics
        self._gap_args = (self._itab, k.buffer, k.point1.buffer, k.point2.buffer)

    def _located(self, g_N) -> bool:
        g = self.kinematics.g
        g[0] = g_N
        g[1] = K.normal_plane_offset(*self._gap_args)
        return True


class _FusedAnalytic(_Refreshed):
    """What the fused detections of the analytic pairs share (:class:`CentreOnPlane`,
    :class:`SphereOnSphere`): :meth:`applies` by the kinematics' type and the contours'
    types (``kinds``: {kinematics: (side 1's contour, side 2's contour)}), the tables
    (side i's point-mass rows and frame offset, or −1 and a Python update of its
    contour), and :meth:`locate` around the kernel (:attr:`kernel`, :attr:`_args` after q, u)."""

    kernel = None
    kinds = {}
    axes2 = False       # the kernel takes the kinematics' axes2 (sphere 2's axes)

    @classmethod
    def applies(cls, contact) -> bool:
        """True for a :class:`~contact.Contact` of one of :attr:`kinds` whose contours lie
        on the ground or on bodies in a System."""
        if type(contact) is not Contact:
            return False
        k = contact.kinematics
        sides = cls.kinds.get(type(k))
        return sides is not None and all(
            type(contour) is kind and (contour.body is None or contour.body.q_slice is not None)
            for contour, kind in zip((k.contour1, k.contour2), sides))

    def __init__(self, contact):
        self.contact = contact
        k = self.kinematics = contact.kinematics
        self.closing_tol = contact.closing_tol
        itab = np.zeros(K.ITAB_SIZE, dtype=np.int64)
        ftab = np.zeros(K.BOX_AT)
        side1 = _frame_side(k.contour1, itab, ftab, K.QP, K.UP, K.OFFSET_AT)
        side2 = _frame_side(k.contour2, itab, ftab, K.Q2, K.U2, K.OFFSET2_AT)
        ftab, side1 = _node_side(side1, itab, ftab)
        sides = (side1, side2)
        self._before = [side for side in sides if side is not None]     # updated in Python first
        itab[K.NU1], itab[K.NU2] = k.contour1.nu, k.contour2.nu
        itab[K.VELOCITY], itab[K.BOX] = not contact.set_valued, contact.margin is not None
        itab[K.KIN_AT:K.KIN_AT + 8] = buffer_layout(k.contour1.nu, k.contour2.nu)
        ftab[K.MARGIN] = 0.0 if contact.margin is None else contact.margin
        ftab[K.RADIUS] = k.radius
        ftab[K.RADIUS2] = getattr(k.contour2, "radius", 0.0)
        self._itab, self._ftab = itab, ftab
        self._work = np.zeros(K.WORK_SIZE)
        self._args = (itab, ftab, k.contour1.state, k.contour2.state, k.point1.buffer, k.point2.buffer, k.buffer,
                      k.centre, k.axes1, *((k.axes2,) if self.axes2 else ()), self._work)

    def locate(self, q, u, t) -> bool:
        """Both contours at the global (q, u, t) and the contact located, as
        ``contour.update`` then :meth:`Contact.locate` do: True when closed
        (g_N <= closing_tol)."""
        _python_updates(self._before, q, u, t)
        outcome, g_N = type(self).kernel(q, u, *self._args)
        return outcome == K.LOCATED and g_N <= self.closing_tol

    def probe(self):
        """None: the contact recorder locates an open analytic pair by the Python path."""
        return None


class CentreOnPlane(_FusedAnalytic):
    """Stages 3 and 4 of a point or a sphere against a plane in one call of
    :func:`._fused_detection_kernels.centre_on_plane` (module docstring)."""

    kernel = K.centre_on_plane
    kinds = {ContactKinematicsPointPlane: (PointContour, PlaneContour),
             ContactKinematicsSpherePlane: (SphereContour, PlaneContour)}


class SphereOnSphere(_FusedAnalytic):
    """Stages 3 and 4 of a point or a sphere against a sphere in one call of
    :func:`._fused_detection_kernels.sphere_on_sphere` (module docstring)."""

    kernel = K.sphere_on_sphere
    kinds = {ContactKinematicsPointSphere: (PointContour, SphereContour),
             ContactKinematicsSphereSphere: (SphereContour, SphereContour)}
    axes2 = True
