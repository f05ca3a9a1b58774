"""Interpolation products of the neutral contours (thesis Sec. 4.4.1, Fig. 4.6–4.7, Table 4.1).

Each product is one field interpolated on the contour's parametric space
(:mod:`.space`, 1s or 2s — the same classes serve both, the space carries the
dimension). The abstract product :class:`NeutralNurbs` owns the control points and the
shared ``compute`` (the thesis's ``computeCurve``: interpolate nodal values with the
factorization made once); concrete products say how their control points follow the
body state.

Linearity (thesis Sec. 3.2.2, taken further): the interpolation operator is linear and
the knots are fixed, so with ū = ū0 + Φ q_f at the nodes (thesis eq. 2.23)

    P_ū = P_ū0 + P_Φ q_f,   P_r = R + A P_ū,   P_ṙ = v + A (ω̄ × P_ū + P_Φ q̇_f)

exactly — a step combines control points and never re-interpolates. The compiled
neutral contours go one step further and form only the control points of the span they
evaluate (:mod:`.factory`); the products here are their reference and their export.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from . import _kernels as K


class NeutralNurbs(ABC):
    """Abstract product: a field with ``width`` components per control point on ``space``.

    ``ctrl`` has shape space.ctrl_shape + (width,).
    """

    state_slots = ("ctrl",)     # the control points at the last update (run state, mbs.run.contact_state)

    def __init__(self, space, width: int):
        self.space = space
        self.ctrl = np.zeros(space.ctrl_shape + (width,))

    def compute(self, nodal_values) -> None:
        """Interpolate nodal values (node-grid shape + (width,)) into ``ctrl`` (eq. 3.22)."""
        self.ctrl[...] = self.space.interpolate(nodal_values).reshape(self.ctrl.shape)

    def contract(self, nrows, out) -> None:
        """Value and derivatives at the located point into out[:nrows] (rows of :mod:`contours.base`)."""
        self.space.contract(self.ctrl, nrows, out)

    def rows(self) -> np.ndarray:
        """ctrl as (n_ctrl_total, width) (a view)."""
        return self.ctrl.reshape(-1, self.ctrl.shape[-1])

    @abstractmethod
    def update(self, *state) -> None:
        """Follow the body state (once per step)."""


class NeutralNurbsModeShapes(NeutralNurbs):
    """The mode shapes Φ_k (thesis Table 4.1), interpolated once: constant in time."""

    def __init__(self, space, nodal_phi):
        n_f = nodal_phi.shape[-1]
        super().__init__(space, 3 * n_f)
        self.n_modes = n_f
        self.compute(nodal_phi.reshape(nodal_phi.shape[:-2] + (3 * n_f,)))
        self.flat = self.ctrl.reshape(-1, n_f)  # (3 n_ctrl_total, n_f) view: the matrix P_Φ

    def update(self, *state) -> None:
        """Nothing: Φ does not change in time."""


class NeutralNurbsLocalPosition(NeutralNurbs):
    """ū = ū0 + Φ q_f in body-frame components [m]: ū0 interpolated once, then
    P_ū = P_ū0 + P_Φ q_f per step (``modes`` None for a rigid shape)."""

    def __init__(self, space, nodal_u0, modes: NeutralNurbsModeShapes | None = None):
        super().__init__(space, 3)
        self.compute(nodal_u0)
        self.ctrl0 = self.ctrl.copy()
        self.modes = modes
        self.bind_views()

    def bind_views(self) -> None:
        """The flat view of :attr:`ctrl` (again after it moved into a run's state)."""
        self._flat = self.ctrl.reshape(-1)

    def update(self, q_f) -> None:
        if self.modes is None or not self.modes.n_modes:
            return
        np.dot(self.modes.flat, q_f, out=self._flat)
        self.ctrl += self.ctrl0


class NeutralNurbsPosition(NeutralNurbs):
    """r = R + A ū, inertial [m] (thesis eq. 2.24)."""

    def __init__(self, space):
        super().__init__(space, 3)

    def update(self, R, A, local: NeutralNurbsLocalPosition) -> None:
        K.position_ctrl(R, A, local.rows(), self.rows())


class NeutralNurbsVelocity(NeutralNurbs):
    """ṙ = v + A (ω̄ × ū + Φ q̇_f), inertial [m/s] (thesis eq. 2.32)."""

    state_slots = ("ctrl", "_modal")

    def __init__(self, space):
        super().__init__(space, 3)
        self._modal = np.zeros_like(self.ctrl)  # control points of Φ q̇_f
        self.bind_views()

    def bind_views(self) -> None:
        """The flat view of ``_modal`` (again after it moved into a run's state)."""
        self._modal_flat = self._modal.reshape(-1)

    def update(self, v, A, w, local: NeutralNurbsLocalPosition, qdot_f) -> None:
        if local.modes is not None and local.modes.n_modes:
            np.dot(local.modes.flat, qdot_f, out=self._modal_flat)
        K.velocity_ctrl(v, A, w, local.rows(), self._modal.reshape(-1, 3), self.rows())
