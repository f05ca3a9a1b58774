"""A contact in a System: contact kinematics plus a force law (thesis Sec. 3.1, 4.1, 4.5).

:class:`Contact` joins a :class:`~contact.kinematics.ContactKinematics` and a law of
:mod:`contact.laws`:

* set-valued (``UnilateralNewtonImpact``, ``UnilateralCoulombContact``): the contact is
  closed when g_N(q_m) <= ``closing_tol`` at the Moreau midpoint (default 1e-12 m: a
  resting contact whose gap is zero only to rounding, e.g. on an inclined plane, stays
  closed instead of opening for a step and letting the body fall; Moreau lets a pressed
  contact close such a gap, :mod:`mbs.integrators.moreau`); it then adds ``dim`` rows to
  the contact problem, W = [w_N] or [w_N, w_T1, w_T2] (thesis eq. 3.1, 4.1);
* single-valued (``LinearRegularizedUnilateralConstraint`` or any law with ``kind =
  "single-valued"``, ``force`` and ``derivatives``, optionally with
  ``RegularizedCoulombFriction``): a force W_N F_N + W_T F_T added to h.

:class:`CurveConstraint` keeps a point on a curve (bilateral, 2 rows; thesis Sec. 5.3).
The integrator updates every contour once per step before ``locate``
(:mod:`mbs.run.stages`).

Broad phase: ``locate`` first compares the two contours' bounding boxes (each contour's
``bounding_box()``, a plane's infinite), each grown by ``margin`` [m], in the kernel
:func:`contact._detection_kernels.boxes_overlap`; only overlapping pairs reach the search.
A planned run prunes far pairs before that by bounding spheres (:mod:`mbs.run.bounding_spheres`).
The margin must exceed the deepest penetration the scene can produce in one step (a
point below a flat contour lies outside its unpadded box); the default is a tenth of
the largest edge of contour 2's box at construction (for a plane, whose box is
infinite, the test always passes), and ``margin=None`` turns the broad phase off.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from ._detection_kernels import boxes_overlap
from .kinematics import ContactKinematics, PointOnCurveConstraint
from .laws import Bilateral, RegularizedCoulombFriction, UnilateralCoulombContact, UnilateralNewtonImpact

SET_VALUED = (UnilateralNewtonImpact, UnilateralCoulombContact)


class ContactElement:
    """What a System takes as a contact (the Moreau stages use nothing else): ``name``,
    ``kinematics``, ``law``; ``set_valued`` (rows in the contact problem) and
    ``unilateral``; ``dim`` (rows of Λ when set-valued); ``bodies()`` and ``contours()``;
    ``locate()`` (True when closed, after the contours were updated); ``jacobian(out)``
    (W (nu, dim) of a closed set-valued contact). Whether a contact is closed, and a
    single-valued law's force, are the run's (:class:`mbs.run.model.Data`), not the
    contact's."""

    set_valued: bool
    unilateral: bool
    dim: int

    def bodies(self):
        return [c.body for c in self.contours() if c.body is not None]

    def contours(self):
        return [self.kinematics.contour1, self.kinematics.contour2]


class Contact(ContactElement):
    """A unilateral contact: ``kinematics`` and a ``law`` (see module docstring);
    ``friction`` only with a single-valued normal law."""

    unilateral = True
    state_slots = ("kinematics",)   # the run state (mbs.run.contact_state); box1, box2: broad-phase workspaces

    def __init__(self, kinematics: ContactKinematics, law, friction=None, name="contact", margin="auto",
                 closing_tol=1e-12):
        self.set_valued = isinstance(law, SET_VALUED)
        if not (self.set_valued or _single_valued(law)):
            raise ModelError(f"{name}: unsupported contact law {law!r}")
        if friction is not None and not (isinstance(friction, RegularizedCoulombFriction) and not self.set_valued):
            raise ModelError(f"{name}: friction= takes a RegularizedCoulombFriction with a regularized "
                             "normal law; use UnilateralCoulombContact for set-valued friction")
        self.kinematics, self.law, self.friction, self.name = kinematics, law, friction, name
        self.dim = law.dim if self.set_valued else 0
        if not closing_tol >= 0.0:
            raise ModelError(f"{name}: closing_tol must be >= 0 [m], got {closing_tol!r}")
        self.closing_tol = float(closing_tol)
        self.margin = _auto_margin(kinematics.contour2) if isinstance(margin, str) and margin == "auto" else margin
        if self.margin is not None and not self.margin >= 0.0:
            raise ModelError(f"{name}: margin must be >= 0 [m], 'auto' or None, got {margin!r}")
        self.margin = None if self.margin is None else float(self.margin)
        self.box1, self.box2 = np.zeros((2, 3)), np.zeros((2, 3))     # broad-phase workspaces

    def locate(self) -> bool:
        """Locate the contact on the updated contours: False when the broad phase (the
        contours' bounding boxes grown by the margin) separates them; else the search,
        closed when found with g_N <= closing_tol. The kinematics hold the result."""
        k = self.kinematics
        if self.margin is not None and not boxes_overlap(k.contour1.bounding_box(self.box1),
                                                         k.contour2.bounding_box(self.box2), self.margin):
            return False
        return bool(k.update(velocity=not self.set_valued, jacobians=True)) and k.g_N <= self.closing_tol

    def jacobian(self, out, col=0) -> None:
        """W (nu, dim) = [W_N] or [W_N, W_T] of the closed contact into the columns
        col..col + dim of ``out`` (nu, ·)."""
        self.kinematics.fill_W(out, col, self.dim)

    def add_forces(self, h) -> float:
        """Single-valued law at the located, closed contact: h += W_N F_N (+ W_T F_T),
        body block by body block; returns F_N [N]."""
        k = self.kinematics
        force_N = float(self.law.force(k.g_N, k.gd_N))
        if force_N == 0.0:
            return 0.0
        F_T = self.friction.force(k.gd_T, force_N) if self.friction is not None else None
        for s, w_N, w_T in k.local_blocks():
            h[s] += force_N * w_N
            if F_T is not None:
                h[s] += w_T @ F_T
        return force_N


def _single_valued(law) -> bool:
    """Whether ``law`` is a single-valued normal law: ``kind == "single-valued"`` with
    ``force(g_N, gd_N)`` [N] and ``derivatives(g_N, gd_N)`` (:mod:`contact.laws`)."""
    return (getattr(law, "kind", None) == "single-valued" and callable(getattr(law, "force", None))
            and callable(getattr(law, "derivatives", None)))


def _auto_margin(contour) -> float:
    """A tenth of the largest finite edge of the contour's bounding box [m] (0 if none)."""
    edges = np.ptp(contour.bounding_box(), axis=0)
    edges = edges[np.isfinite(edges)]
    return 0.1 * float(edges.max()) if edges.size else 0.0


class CurveConstraint(ContactElement):
    """A point kept on a curve (bilateral, γ⁺ = 0 on the two normal-plane directions)."""

    set_valued = True
    unilateral = False
    dim = 2
    state_slots = ("kinematics",)   # the run state (mbs.run.contact_state); whether it is closed is the run's Data

    def __init__(self, kinematics: PointOnCurveConstraint, name="on curve"):
        if not isinstance(kinematics, PointOnCurveConstraint):
            raise ModelError(f"{name}: needs PointOnCurveConstraint kinematics")
        self.kinematics, self.law, self.name = kinematics, Bilateral(2), name

    def locate(self) -> bool:
        """Locate the point on the curve; ModelError when it left the curve's domain."""
        if not self.kinematics.update(velocity=False, jacobians=True):
            raise ModelError(f"{self.name}: the point left the curve's domain")
        return True

    def jacobian(self, out, col=0) -> None:
        """W (nu, 2) = [w_n, w_t2] of the point on the curve into the columns col, col + 1
        of ``out`` (nu, ·)."""
        self.kinematics.W(out[:, col:col + 2])
