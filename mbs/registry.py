"""The multibody kinds by name: bodies (:data:`BODIES`), joints (:data:`JOINTS`, the
kinds of :class:`mbs.Joint`), loads (:data:`LOADS`), integrators (:data:`INTEGRATORS`, the
``integrator=`` of ``System.simulate``) and rotation parametrizations (:data:`ROTATIONS`,
the ``rotation=`` of free bodies). A new kind is its class plus one registry line."""

from __future__ import annotations

from ffrmbs.registry import Registry

from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.integrators import INTEGRATORS
from mbs.links.joints import JOINTS
from mbs.links.loads import DistributedForce, Force, NodalForces, Torque
from mbs.bodies.parametrization import PARAMETRIZATIONS as ROTATIONS
from mbs.bodies.rigid_body import PointMass, RigidBody

BODIES = Registry("body kind")
BODIES.register("flexible", FlexibleBodyFFR)      # FFR body (thesis Sec. 2.3)
BODIES.register("rigid", RigidBody)
BODIES.register("point_mass", PointMass)

LOADS = Registry("load kind")
LOADS.register("force", Force)                    # on a frame [N]
LOADS.register("torque", Torque)                  # on a body [N m]
LOADS.register("distributed", DistributedForce)   # a resultant [N] shared by nodes
LOADS.register("nodal", NodalForces)              # a force file (report Appendix A)

__all__ = ["BODIES", "INTEGRATORS", "JOINTS", "LOADS", "ROTATIONS"]
