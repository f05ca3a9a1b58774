"""The parametric space of a neutral contour: fixed knots, the interpolation factored
once, and the basis tables at the point being evaluated.

A :class:`CurveSpace` (1s, coordinate η) or :class:`SurfaceSpace` (2s, η and ξ) wraps
the interpolation of :mod:`contours.nurbs` built on the undeformed node grid (thesis
Sec. 3.2.2: "the knot vectors for all above NURBS interpolations has to be same",
computed from the undeformed local positions). Every field of the contour is a
control-point array on this space; :meth:`locate` computes the basis functions and
their derivatives at (η, ξ) once, then :meth:`contract` combines any number of
control-point arrays with them (numba kernels in :mod:`._kernels`). ``geometry`` holds
the same knots, degrees and domains as arrays for the span-local kernels
(:func:`._kernels.evaluate_1s`, :func:`._kernels.evaluate_2s`), which locate by
themselves.
"""

from __future__ import annotations

import numpy as np

from ffrmbs.errors import ModelError
from contours.nurbs import Interpolation1D, SurfaceInterpolation

from . import _kernels as K


def as_pair(value, what) -> tuple:
    """One value for both surface coordinates, or a pair (η, ξ)."""
    pair = tuple(value) if isinstance(value, (tuple, list)) else (value, value)
    if len(pair) != 2:
        raise ModelError(f"{what} must be one value or a pair (eta, xi), got {value!r}")
    return pair


class _Direction:
    """One parametric direction: knots, degree, closedness and its basis table."""

    def __init__(self, interp: Interpolation1D):
        self.interp = interp
        self.knots = np.array(interp.knots, dtype=float)    # writable: numba types a read-only
                                                            # array apart (each kernel compiled twice)
        self.p = interp.degree
        self.n_ctrl = interp.n_ctrl
        self.closed = bool(interp.closed)
        self.a, self.b = (float(x) for x in interp.domain)
        self.B = np.zeros((3, self.p + 1))
        self.span = self.p

    def locate(self, t):
        self.span = K.locate(self.knots, self.p, self.n_ctrl, self.closed, self.a, self.b, float(t), self.B)


class CurveSpace:
    """1s space on an :class:`~contours.nurbs.Interpolation1D`."""

    dim = 1

    def __init__(self, interp: Interpolation1D):
        self.eta = _Direction(interp)
        self.domain = (self.eta.a, self.eta.b)
        self.closed = (self.eta.closed,)
        self.ctrl_shape = (interp.n_ctrl,)
        d = self.eta
        self.geometry = (d.knots, np.array([d.p, d.n_ctrl, d.closed], dtype=np.int64), np.array([d.a, d.b]))

    def interpolate(self, values) -> np.ndarray:
        """Control points (n_ctrl, ...) of nodal values (k, ...) (eq. 3.22)."""
        return self.eta.interp.control_points(values)

    def locate(self, eta, xi=0.0):
        self.eta.locate(eta)

    def contract(self, ctrl, nrows, out):
        """out[:nrows] ← rows of :data:`contours.base` layout from ctrl (n_ctrl, m)."""
        d = self.eta
        K.contract_curve(d.B, d.span, d.p, ctrl, nrows, out)

    def contract_state(self, ctrl0, phi, state, span, nrows, out):
        """out[:nrows] ← rows of ū (6, 3) [m] from P_ū0 + P_Φ q_f over the located span
        only (:func:`._kernels.local_rows_1s`)."""
        d = self.eta
        K.local_rows_1s(d.B, d.span, d.p, ctrl0, phi, state, span, nrows, out)


class SurfaceSpace:
    """2s space on a :class:`~contours.nurbs.SurfaceInterpolation` (tensor product, eq. 3.23)."""

    dim = 2

    def __init__(self, interp: SurfaceInterpolation):
        self.eta = _Direction(interp.eta)
        self.xi = _Direction(interp.xi)
        self.interp = interp
        self.domain = ((self.eta.a, self.eta.b), (self.xi.a, self.xi.b))
        self.closed = (self.eta.closed, self.xi.closed)
        self.ctrl_shape = (interp.eta.n_ctrl, interp.xi.n_ctrl)
        e, x = self.eta, self.xi
        ints = np.array([e.p, e.n_ctrl, e.closed, x.p, x.n_ctrl, x.closed], dtype=np.int64)
        self.geometry = (e.knots, x.knots, ints, np.array([e.a, e.b, x.a, x.b]))

    def interpolate(self, values) -> np.ndarray:
        """Control points (n_eta, n_xi, ...) of nodal values (k_eta, k_xi, ...)."""
        return self.interp.control_points(values)

    def locate(self, eta, xi=0.0):
        self.eta.locate(eta)
        self.xi.locate(xi)

    def contract(self, ctrl, nrows, out):
        """out[:nrows] ← S, S_η, S_ξ, S_ηη, S_ηξ, S_ξξ from ctrl (n_eta, n_xi, m)."""
        e, x = self.eta, self.xi
        K.contract_surface(e.B, e.span, e.p, x.B, x.span, x.p, ctrl, nrows, out)

    def contract_state(self, ctrl0, phi, state, span, nrows, out):
        """out[:nrows] ← rows of ū (6, 3) [m] from P_ū0 + P_Φ q_f over the located span
        only (:func:`._kernels.local_rows_2s`)."""
        e, x = self.eta, self.xi
        K.local_rows_2s(e.B, e.span, e.p, x.B, x.span, x.p, ctrl0, phi, state, span, nrows, out)
