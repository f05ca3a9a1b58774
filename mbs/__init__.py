"""Multibody core: FFR bodies, rigid bodies, point masses, links, System, integrators.

Public API (model scripts use only these)::

    from mbs import System, FlexibleBodyFFR, RigidBody, PointMass, PrescribedFrameMotion
"""

from .body import Body, Frame, ground_frame
from .flexible_body import FlexibleBodyFFR
from .floating_frame import PrescribedFrameMotion
from .result import Result
from .rigid_body import PointMass, RigidBody
from .system import System

__all__ = ["Body", "FlexibleBodyFFR", "Frame", "PointMass", "PrescribedFrameMotion", "Result",
           "RigidBody", "System", "ground_frame"]
