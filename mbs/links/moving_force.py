"""A force at a moving point of a 1s contour (a moving load; thesis eq. 2.76 at η(t)).

:class:`MovingContourForce` applies an inertial force F(t) [N] at the contour point
η(t) of a curve (e.g. the neutral axis of an FFR beam, a
:class:`contours.Contour1sNeutralFFR`). Its generalized force is thesis eq. 2.76 with the
contour's interpolated Jacobian (thesis Sec. 3.2.2, J_T = [1, −A ũ T, A Φ] with ū and Φ
interpolated at η):

    Q(t, q) = J_T(η(t), q)ᵀ F(t)        (nu_body,) [N, N m, N kg^½ ...],

added into the body's block of h. It is the load of a moving-load problem (a constant
force travelling along a beam, :mod:`validation.moving_load`), or of anything that
drags a point force along a contour by a prescribed law η(t).

The element reads the contour through its public interface only (``update``,
``evaluate(..., jacobians=True)``, ``domain``); it updates the contour at the state it is
given before evaluating, so it may share a contour with contacts (which update it again
at their own stage of the step). Like :class:`mbs.Force` the load is not conservative:
no potential energy and no tangents (the stiffness of a follower load on a moving frame
is neglected by implicit integrators; with a prescribed frame J_T = A Φ(η) does not
depend on q and there is none).
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError

from mbs.links.link import ForceElement


class MovingContourForce(ForceElement):
    """An inertial force ``force`` [N] at the point η = ``eta(t)`` of a 1s ``contour``.

    Parameters
    ----------
    contour : 1s contour on a body of the System (``contour.dim == 1``)
    eta : callable t [s] -> η
        The contour coordinate of the point of application (inside ``contour.domain``
        while the load acts; outside it a ModelError is raised, time and η named).
    force : (3,) [N] or callable t -> (3,)
        Inertial components.
    """

    def __init__(self, contour, eta, force):
        if getattr(contour, "dim", None) != 1:
            raise ModelError(f"MovingContourForce needs a 1s contour, got {contour!r}")
        if contour.body is None:
            raise ModelError("MovingContourForce: the contour is fixed in the inertial frame; "
                             "a load there does nothing")
        if not callable(eta):
            raise ModelError("MovingContourForce: eta must be a callable t -> η")
        self.contour, self.eta = contour, eta
        if callable(force):
            self.force = force
        else:
            F = np.asarray(force, dtype=float).reshape(3)
            self.force = lambda t: F
        self._point = contour.new_point()

    def bodies(self):
        return [self.contour.body]

    def point(self, t, q):
        """The contour point (a ContourPoint workspace: r, frame, J_T) at time t [s] and
        global positions q, η = eta(t)."""
        body, c = self.contour.body, self.contour
        eta = float(self.eta(t))
        lo, hi = c.domain
        if not lo - 1e-12 * (hi - lo) <= eta <= hi + 1e-12 * (hi - lo):
            raise ModelError(f"MovingContourForce: η({t:.6g} s) = {eta:.6g} left the contour's "
                             f"domain [{lo:.6g}, {hi:.6g}]")
        c.update(q[body.q_slice], None, t)
        return c.evaluate(self._point, min(max(eta, lo), hi), jacobians=True)

    def add_forces(self, t, q, u, h):
        """h[body] += J_T(η(t))ᵀ F(t)."""
        p = self.point(t, q)
        h[self.contour.body.u_slice] += p.J_T.T @ np.asarray(self.force(t), dtype=float)
