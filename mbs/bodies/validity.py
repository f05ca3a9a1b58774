"""Validity monitors: detect and warn when a run leaves the range of linear FFR.

A :class:`~mbs.FlexibleBodyFFR` superposes the small deformation Φ q_f on a large frame
motion with the mode shapes and the stiffness K_ff of the *unloaded* structure (thesis
Sec. 2.4, eq. 2.24, 2.36). It has no geometric stiffness: the stiffening of a structure
under the centrifugal prestress of its own spin is missing. :class:`SpinMonitor` watches
the frame spin |Ω| of every FFR body whose frame can rotate and warns once per body when
|Ω| exceeds ``ratio`` ω1, ω1 the lowest frequency of the body's retained modes. A body
with ``geometric_stiffening`` (:mod:`mbs.bodies.geometric_stiffening`) carries that stiffness and
is not watched.
"""

from __future__ import annotations

import logging
import math
import warnings

import numpy as np
import scipy.linalg

from mbs.bodies.flexible_body import FlexibleBodyFFR

logger = logging.getLogger("ffrmbs.validity")

#: Default of SpinMonitor's ``ratio`` |Ω|/ω1 (derivation in :class:`SpinMonitor`).
SPIN_RATIO = 0.2


class FFRValidityWarning(UserWarning):
    """A run went where linear FFR (no geometric stiffening) is no longer accurate."""


class SpinMonitor:
    """Warn when a flexible body spins too fast for linear FFR.

    Parameters
    ----------
    system : mbs.System
        Its FFR bodies (:class:`~mbs.FlexibleBodyFFR` with at least one mode and without
        geometric stiffening) whose frame can rotate — a free frame, or a prescribed frame
        motion that is not :meth:`~mbs.PrescribedFrameMotion.fixed` — are watched.
    ratio : float
        Warn when |Ω| > ratio · ω1 [-]; default :data:`SPIN_RATIO` = 0.2.

    Notes
    -----
    For each watched body ω1 [rad/s] is the square root of the smallest eigenvalue of
    its retained modal problem K_ff ψ = ω² M_ff ψ (K_ff = Φᵀ K Φ, M_ff = m_ff of thesis
    eq. 2.69), computed once here. ``events`` lists (t [s], body name, |Ω| [rad/s],
    ω1 [rad/s]) of the warnings given, at most one per body.

    Why 0.2. Spin a beam about an axis normal to it at Ω. Linear FFR keeps the unloaded
    modes and adds only the inertia terms of the moving frame: the centrifugal term
    −Σ m Φᵀ Ω̃² Φ acts on a bending mode polarized in the plane of rotation as −Ω² M_ff,
    so linear FFR predicts that mode's frequency as ω² = ω1² − Ω² ("spin softening"),
    and leaves the out-of-plane mode at ω1. The centrifugal tension the linear model
    leaves out stiffens both: for the first mode of a uniform cantilever spun about its
    root ω² = ω1² + K_s Ω² out of plane and ω1² + (K_s − 1) Ω² in plane, with the
    Southwell coefficient K_s ≈ 1.19 (Southwell & Gough 1921; Wright, Smith, Thresher &
    Wang, J. Appl. Mech. 49 (1982) 197–202). Either way linear FFR misses K_s Ω² in ω²:
    a relative error of ≈ K_s Ω²/ω1² in ω² and ≈ ½ K_s Ω²/ω1² in ω. Kane, Ryan &
    Banerjee (J. Guid. Control Dyn. 10 (1987) 139–151) showed that spun up far enough
    the linear model even diverges (ω² ≤ 0 at Ω ≥ ω1) where the real beam stiffens;
    Wallrapp & Schwertassek (Int. J. Numer. Meth. Eng. 32 (1991) 1833–1850) give the
    geometric-stiffness remedy. At |Ω| = 0.2 ω1 the missing term is Ω²/ω1² = 4 % of ω1²
    (4.8 % with K_s), a frequency error of ≈ 2.4 %, and grows quadratically beyond: a
    few percent, where a model that claims a known error should say so. The report's
    α–Ω criterion (report Sec. 4.1, eq. 31–32) bounds the coupling deformation; this
    monitor bounds the stiffness the linear model omits, which eq. 32 does not see.

    ``check`` is called at every output sample: it reads three velocities per body (a
    quaternion frame's u holds ω̄ itself), compares squares and allocates nothing on the
    quaternion path; a body stops being checked once it has warned.
    """

    def __init__(self, system, ratio=SPIN_RATIO):
        if not ratio > 0:
            from ffrmbs.errors import ModelError

            raise ModelError(f"SpinMonitor ratio must be positive, got {ratio}")
        self.ratio = float(ratio)
        self.events: list[tuple[float, str, float, float]] = []
        self.omega1: dict[str, float] = {}
        self._watch = []           # [body, ω1, (ratio ω1)², reader of |Ω|²]
        for body in system.bodies:
            if not isinstance(body, FlexibleBodyFFR) or body.n_modes == 0:
                continue
            if (body.motion is not None and body.motion.at_rest) or body.geometric_stiffening:
                continue
            w2 = scipy.linalg.eigvalsh(body.K_ff, body.integrals.M_ff)
            w1 = math.sqrt(max(float(w2[0]), 0.0))
            if not w1 > 0:         # a rigid mode among the retained ones: no bending frequency
                continue
            self.omega1[body.name] = w1
            self._watch.append([body, w1, (self.ratio * w1) ** 2, _spin_squared(body)])

    @property
    def watched(self) -> list:
        """The bodies being watched (those that have not warned yet included)."""
        return [w[0] for w in self._watch]

    def restore(self, events) -> None:
        """Take the events of a checkpoint, (t [s], body name, |Ω| [rad/s], ω1 [rad/s]) each:
        a body that warned before is not checked again, as in the run that was interrupted."""
        self.events = list(events)
        warned = {event[1] for event in self.events}
        for entry in self._watch:
            if entry[0].name in warned:
                entry[2] = None

    def check(self, t, q, u) -> None:
        """Compare each watched body's |Ω| [rad/s] at (t, q, u) (system state arrays) with
        ratio · ω1; warn (FFRValidityWarning, and on the "ffrmbs.validity" logger) the
        first time it is exceeded, and record the event."""
        if not self._watch:
            return
        for entry in self._watch:
            body, w1, limit2, spin2 = entry
            if limit2 is None:
                continue
            s2 = spin2(t, q, u)
            if s2 > limit2:
                w = math.sqrt(s2)
                entry[2] = None           # warned: not checked again
                self.events.append((float(t), body.name, w, w1))
                msg = (f"body {body.name!r} at t = {t:.6g} s spins at |Ω| = {w:.4g} rad/s > {self.ratio:g} ω1 "
                       f"(ω1 = {w1:.4g} rad/s, its lowest retained elastic frequency): without geometric "
                       f"stiffening its bending frequencies are off by about Ω²/ω1² = {(w / w1) ** 2:.1%} "
                       f"in ω² and more as the spin grows; turn on geometric_stiffening (body file "
                       f"preprocessed with --geometric-stiffness)")
                logger.warning(msg)
                warnings.warn(FFRValidityWarning(msg), stacklevel=2)


def _spin_squared(body):
    """A function (t, q, u) -> |Ω|² [rad²/s²] of ``body`` from the system state arrays."""
    if body.motion is not None:                      # prescribed frame: ω̄(t) given
        rotation = body.motion.rotation

        def spin2(t, q, u):
            w = rotation(t)[1]
            return float(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        return spin2
    i = body.u_slice.start + 3                       # u = (Ṙ, u_r, q̇_f)
    if body.param.name == "quaternion":              # u_r = ω̄ and |Ω| = |A ω̄| = |ω̄|

        def spin2(t, q, u):
            return float(u[i] * u[i] + u[i + 1] * u[i + 1] + u[i + 2] * u[i + 2])
        return spin2
    param, r = body.param, slice(body.q_slice.start + 3, body.q_slice.start + 3 + body.param.nq)

    def spin2(t, q, u):                              # ω̄ = T(q_r) u_r (e.g. Cardan, thesis eq. 2.30)
        w = param.T(q[r]) @ u[i:i + 3]
        return float(np.dot(w, w))
    return spin2
