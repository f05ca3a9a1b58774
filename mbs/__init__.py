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

from .body import Body, Frame, ground_frame
from .flexible_body import FlexibleBodyFFR
from .floating_frame import PrescribedFrameMotion
from .joints import Joint
from .force_file import read_force_file, write_force_file
from .loads import DistributedForce, Force, NodalForces, Tabulated, Torque
from .moving_force import MovingContourForce
from .registry import BODIES, INTEGRATORS, JOINTS, LOADS, ROTATIONS
from .result import Result
from .rigid_body import PointMass, RigidBody
from .springs import SpringDamper
from .system import System

__all__ = ["BODIES", "Body", "DistributedForce", "FlexibleBodyFFR", "Force", "Frame", "INTEGRATORS", "JOINTS", "Joint", "LOADS", "MovingContourForce", "NodalForces",
           "PointMass", "PrescribedFrameMotion", "ROTATIONS", "Result", "RigidBody", "SpringDamper", "System",
           "Tabulated", "Torque", "ground_frame", "read_force_file", "write_force_file"]
