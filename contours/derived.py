"""Contours built on a 1s neutral contour (thesis Sec. 4.4, Fig. 4.4; band: Sec. 5.2).

A derived point sits at a fixed offset in the neutral curve's frame,

    r(η, ·) = R + A (ū(η) + d̄),   d̄ = α n̄(η) + β t̄2(η),

with the body-frame frame of the neutral curve: t̄ = ū_η/|ū_η|, n̄ the reference normal
n̄0 made perpendicular to t̄, t̄2 = n̄ × t̄ (the neutral's t1, n, t2 in body axes).
``FlexibleBand``: (α, β) = (offset, ξ), ξ ∈ [−w/2, w/2]; ``FlexibleCylinder``:
(α, β) = ρ (cos φ, sin φ), φ ∈ [0, 2π). The frame follows the deformation through
ū_η = Σ N'_i (P_ū0 + P_Φ q_f)_i, so with G = ∂d̄/∂ū_η (3, 3)

    r_η = A (ū_η + G ū_ηη),   J_T = [1, −A (ū + d̄)~ T, A (Φ + G Φ_η)],
    ṙ = v + A (ω̄ × (ū + d̄) + (Φ + G Φ_η) q̇_f)

exactly (J_R is the body's). Continuity: the frame follows the tangent ū_η, so off the
neutral line the surface is one order less smooth than ū_η: C^{p−2} in η on a degree-p
neutral curve. A C² band or cylinder (thesis Sec. 3.2: sliding needs C²) needs a neutral
curve of degree ≥ 4; a lower degree is accepted with a warning. Second derivatives: r_ξξ, r_ηξ exact; r_ηη = A ū_ηη
neglects the offset's second derivative along the curve (O(|d̄| · |∂²G/∂η²|); zero on
a straight undeformed neutral line).

``compiled=True`` (default) evaluates all of this in one numba kernel over the neutral
curve's span-local state (:mod:`._offset_kernels`, G applied to vectors, never formed);
``compiled=False`` is the numpy reference over :func:`offset_frame`.
"""

from __future__ import annotations

import warnings
from abc import abstractmethod

import numpy as np

from ffrmbs.errors import ModelError

from . import _offset_kernels as OK
from .base import D_ETA, D_ETA_ETA, D_ETA_XI, D_XI, D_XI_XI, VALUE, Contour
from .neutral import _kernels as K
from .neutral.factory import Contour1sNeutralFactory


def offset_frame(a, n0):
    """Body-frame frame of the neutral curve and its derivatives with respect to the
    tangent a = ū_η (3,): returns (t̄, t̄2, n̄, Dt2, Dn) with Dx = ∂x/∂a (3, 3)."""
    la = np.linalg.norm(a)
    t = a / la
    Dt = (np.eye(3) - np.outer(t, t)) / la
    c = n0 - (n0 @ t) * t
    lc = np.linalg.norm(c)
    n = c / lc
    Dc = -(np.outer(t, n0) + (n0 @ t) * np.eye(3)) @ Dt
    Dn = (np.eye(3) - np.outer(n, n)) @ Dc / lc
    t2 = np.cross(n, t)
    Dt2 = np.cross(n, Dt, axisb=0, axisc=0) - np.cross(t, Dn, axisb=0, axisc=0)   # ñ Dt − t̃ Dn
    return t, t2, n, Dt2, Dn


class OffsetContour(Contour):
    """A 2s contour at offsets (α, β)(ξ) in the frame of a 1s neutral contour.

    ``compiled`` True (default): :meth:`evaluate` is the numba kernel
    :func:`._offset_kernels.evaluate_offset`, which reads the neutral curve span-locally
    from its ``kernel_data`` and allocates nothing; False: the numpy reference
    (:meth:`_evaluate_reference`, over :func:`offset_frame` and the neutral's
    ``local_fields``). Both give the same fields up to rounding.
    """

    dim = 2
    state_slots = ("neutral",)  # its run state is the neutral contour's (mbs.run.contact_state)

    def __init__(self, neutral: Contour1sNeutralFactory, xi_domain, closed_xi, reach, name, compiled=True):
        if not isinstance(neutral, Contour1sNeutralFactory):
            raise ModelError(f"{name}: needs a 1s neutral contour, got {type(neutral).__name__}")
        super().__init__(neutral.body, name)
        if neutral.space.eta.p < 4:
            warnings.warn(f"{name}: on a degree-{neutral.space.eta.p} neutral curve the offset surface is only "
                          f"C^{neutral.space.eta.p - 2} along the curve; build the neutral contour with degree >= 4 "
                          "for a C2 contour", stacklevel=3)
        self.neutral = neutral
        self.domain = (neutral.domain, xi_domain)
        self.closed = (neutral.closed[0], closed_xi)
        self.reach = reach  # largest |d̄| [m]
        self.compiled = bool(compiled)
        n_f = neutral.n_modes
        self._B, self._local_rows, self._rows, self._frame = self.kernel_workspace()[:4]
        self._phi_rows = np.zeros((3, 3 * n_f))   # Φ, Φ_η at the neutral point (row 2 work)
        self._phi_point = np.zeros(3 * n_f)       # Φ_P = Φ + G Φ_η, row-major (3, n_f)
        self._phi_point_rows = self._phi_point.reshape(3, n_f)

    def kernel_workspace(self):
        """Fresh work arrays of :func:`._offset_kernels.offset_fields` (also for the
        compiled search of :mod:`contact.search`): the neutral's basis table B (3, p+1), its
        ū rows (6, 3), the offset point's body-frame rows (6, 3), the neutral frame t̄, n̄,
        t̄2 (3, 3) and the rows of r (6, 3)."""
        rows = np.zeros((3, 6, 3))
        return self.neutral.kernel_workspace()[0], rows[0], rows[1], np.zeros((3, 3)), rows[2]

    @property
    def evaluate_work(self):
        """The work arrays :meth:`evaluate` fills (the neutral's basis table, its ū rows,
        the offset point's rows, the neutral frame, the Φ rows, Φ_P), as
        :func:`._offset_kernels.evaluate_offset` takes them (a fused detection,
        :mod:`mbs.run.fused_detection`, fills them as :meth:`evaluate` does)."""
        return self._B, self._local_rows, self._rows, self._frame, self._phi_rows, self._phi_point

    @property
    @abstractmethod
    def offset_law(self):
        """(law, size) of :func:`._offset_kernels.offsets`: the offsets (α, β)(ξ), one
        law for the evaluation (both routes) and the compiled search."""

    def _offsets(self, xi):
        """(α, β), (α_ξ, β_ξ), (α_ξξ, β_ξξ) [m] at ξ: the law of :attr:`offset_law`."""
        al, be, al1, be1, al2, be2 = OK.offsets(*self.offset_law, float(xi))
        return (al, be), (al1, be1), (al2, be2)

    def update(self, q, u=None, t=0.0) -> None:
        self.neutral.update(q, u, t)

    def evaluate(self, point, eta, xi=0.0, velocity=False, jacobians=False):
        """Fields at (η, ξ) (see :meth:`Contour.evaluate`; the equations in the module
        docstring): the kernel when :attr:`compiled`, else :meth:`_evaluate_reference`."""
        if not self.compiled:
            return self._evaluate_reference(point, eta, xi, velocity, jacobians)
        nc = self.neutral
        if velocity:
            nc.require_velocity()
        (al, be), (al1, be1), (al2, be2) = self._offsets(xi)
        point.eta, point.xi = eta, xi
        OK.evaluate_offset(eta, *nc.kernel_data, nc.normal_ref, al, be, al1, be1, al2, be2, velocity or jacobians,
                           velocity, self._B, self._local_rows, self._rows, self._frame, self._phi_rows,
                           self._phi_point, point.derivs, point.frame, point.v)
        if jacobians:
            nc.body.fill_J_T(nc.A, nc.T, self._rows[VALUE], self._phi_point_rows, point.J_T)
            nc.body.fill_J_R(nc.A, nc.T, point.J_R)
        return point

    def _evaluate_reference(self, point, eta, xi, velocity, jacobians):
        """The numpy reference of :meth:`evaluate`: :func:`offset_frame` and matrix products."""
        nc = self.neutral
        nc.space.locate(eta)
        ub, phi = nc.local_fields(6)
        t, t2, n, Dt2, Dn = offset_frame(ub[D_ETA], nc.normal_ref)
        (al, be), (al1, be1), (al2, be2) = self._offsets(xi)
        d = al * n + be * t2
        G = al * Dn + be * Dt2
        A, R = nc.A, nc.R
        point.eta, point.xi = eta, xi
        D = point.derivs
        D[VALUE] = R + A @ (ub[VALUE] + d)
        D[D_ETA] = A @ (ub[D_ETA] + G @ ub[D_ETA_ETA])
        D[D_XI] = A @ (al1 * n + be1 * t2)
        D[D_ETA_ETA] = A @ ub[D_ETA_ETA]
        D[D_ETA_XI] = A @ ((al1 * Dn + be1 * Dt2) @ ub[D_ETA_ETA])
        D[D_XI_XI] = A @ (al2 * n + be2 * t2)
        K.frame_2s(D, 1.0, point.frame)
        if velocity or jacobians:
            m = nc.n_modes
            phi_point = phi[VALUE].reshape(3, m) + G @ phi[D_ETA].reshape(3, m)
            if velocity:
                nc.require_velocity()
                point.v[:] = nc.v + A @ (np.cross(nc.w, ub[VALUE] + d) + phi_point @ nc.qdot_f)
            if jacobians:
                nc.body.fill_J_T(A, nc.T, ub[VALUE] + d, phi_point, point.J_T)
                nc.body.fill_J_R(A, nc.T, point.J_R)
        return point

    def bounding_box(self, out=None) -> np.ndarray:
        """The neutral curve's box grown by the largest offset (conservative)."""
        box = self.neutral.bounding_box(out)
        box[0] -= self.reach
        box[1] += self.reach
        return box


class FlexibleBand(OffsetContour):
    """A band of ``width`` [m] at ``offset`` [m] along the neutral normal n (thesis
    Sec. 5.2, MBSim's ``FlexibleBand``): ξ ∈ [−w/2, w/2] runs along t2 = n × t1, the
    band's normal is the surface normal r_η × r_ξ (= n on an undeformed straight line).
    Put it on the side the neutral's reference normal points to (offset ≥ 0).
    ``residual_flexibility``: as for the neutral contours (:mod:`contours.residual`)."""

    def __init__(self, neutral, width, offset=0.0, name="band", compiled=True, residual_flexibility=False):
        self.residual_flexibility = bool(residual_flexibility)
        if not width > 0:
            raise ModelError(f"{name}: width must be positive, got {width}")
        self.width, self.offset = float(width), float(offset)
        super().__init__(neutral, (-0.5 * width, 0.5 * width), False, np.hypot(offset, 0.5 * width), name,
                         compiled)

    @property
    def offset_law(self):
        return OK.BAND, self.offset


class FlexibleCylinder(OffsetContour):
    """A cylinder of ``radius`` [m] around the neutral curve (MBSim's
    ``CylinderFlexible``): ξ = φ ∈ [0, 2π) from n towards t2, outward normal radial.
    ``residual_flexibility``: as for the neutral contours (:mod:`contours.residual`)."""

    def __init__(self, neutral, radius, name="cylinder", compiled=True, residual_flexibility=False):
        self.residual_flexibility = bool(residual_flexibility)
        if not radius > 0:
            raise ModelError(f"{name}: radius must be positive, got {radius}")
        self.radius = float(radius)
        super().__init__(neutral, (0.0, 2.0 * np.pi), True, self.radius, name, compiled)

    @property
    def offset_law(self):
        return OK.CYLINDER, self.radius
