"""Multibody core: FFR bodies, rigid bodies, point masses, links, System, integrators.

Public API (model scripts use only these)::

    from mbs import System, FlexibleBodyFFR, RigidBody, PointMass, Joint, Force, SpringDamper

A System holds bodies (``FlexibleBodyFFR``, ``RigidBody``, ``PointMass``), force elements
(``Force``, ``Torque``, ``DistributedForce``, ``NodalForces``, ``SpringDamper``,
``MovingContourForce``; gravity is the System's own), constraints (``Joint``) and
contacts (:mod:`contact`); ``System.simulate`` integrates with generalized-α (implicit),
RK4 (explicit) or Moreau time-stepping (contacts, impacts; fixed or adaptive step) and
returns a ``Result``. The kinds by name (bodies, joints, loads, integrators, rotations) are
in :mod:`mbs.registry`.
"""

from ffrmbs.caches import configure_numba

configure_numba()      # numba's cache directory, before any kernel is defined (ffrmbs.caches)

from mbs.bodies.body import Body, Frame, ground_frame
from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.bodies.floating_frame import PrescribedFrameMotion
from mbs.links.joints import Joint
from mbs.links.force_file import read_force_file, write_force_file
from mbs.links.loads import DistributedForce, Force, NodalForces, Tabulated, Torque
from mbs.links.moving_force import MovingContourForce
from mbs.registry import BODIES, INTEGRATORS, JOINTS, LOADS, ROTATIONS
from mbs.results.result import Result
from mbs.bodies.rigid_body import PointMass, RigidBody
from mbs.links.springs import SpringDamper
from mbs.system import System

__all__ = ["BODIES", "Body", "DistributedForce", "FlexibleBodyFFR", "Force", "Frame", "INTEGRATORS", "JOINTS", "Joint", "LOADS", "MovingContourForce", "NodalForces",
           "PointMass", "PrescribedFrameMotion", "ROTATIONS", "Result", "RigidBody", "SpringDamper", "System",
           "Tabulated", "Torque", "ground_frame", "read_force_file", "write_force_file"]
