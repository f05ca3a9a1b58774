"""Time integrators: smooth ones for scenes without set-valued contacts, and Moreau's
time-stepping (:class:`MoreauTimeStepping`, "moreau") for contacts and impacts.

* :class:`GeneralizedAlpha` (implicit, default): the generalized-α method of Chung and
  Hulbert in the Lie-group form of Arnold and Brüls for the index-3 equations
  M u̇ = h + C_qᵀ λ, g(q) = 0; positions updated by q ⊕ Δu (exponential map), Newton on
  (u̇, λ) with the iteration matrix M + βh²c K + γhc D, so stiff elastic modes do not
  limit the step; numerical damping set by ρ∞.
* :class:`RK4` (explicit): the classical Runge–Kutta method on q̇ = Y(q) u, u̇ from the
  index-1 equations, constraints stabilized by projection onto g = 0 and ġ = 0 after
  each step (and Baumgarte terms if asked).
"""

from __future__ import annotations

from ffrmbs.registry import Registry

from mbs.integrators.explicit import RK4
from mbs.integrators.generalized_alpha import GeneralizedAlpha
from mbs.integrators.moreau import AdaptiveMoreauTimeStepping, MoreauTimeStepping

INTEGRATORS = Registry("integrator")
INTEGRATORS.register("moreau", MoreauTimeStepping)
INTEGRATORS.register("moreau-adaptive", AdaptiveMoreauTimeStepping)
INTEGRATORS.register("generalized-alpha", GeneralizedAlpha)
INTEGRATORS.register("rk4", RK4)


def integrator_class(name):
    """The integrator class registered as ``name`` (or a class passed through)."""
    if isinstance(name, type):
        return name
    return INTEGRATORS[name]
