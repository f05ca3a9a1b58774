"""A mechanism with every registered body kind, rotation parametrization, joint kind and
load kind, and no contact (every integrator runs it)."""

import numpy as np

from ffrmbs_app.scenes import point_mass_beam as pmb
from mbs import (DistributedForce, FlexibleBodyFFR, Force, Joint, NodalForces, PointMass, RigidBody, SpringDamper,
                 System, Torque, ground_frame)

SWITCH = 5e-4        # [s] the tip's nodal forces step from their first row to their second


def mechanism():
    """Every registered body kind, rotation parametrization, joint kind and load kind in
    one mechanism under gravity −y (no contact: every integrator runs it): the default
    beam (4 modes, Cardan angles) hinged to the ground at its frame origin about z, its top
    face pulled down by a distributed force and its tip by nodal forces that step at
    ``SWITCH``; a block (quaternion) on a ball joint at the beam's tip, a plate welded to
    the block and twisted by a torque; a slider (Cardan angles) on a prismatic joint along
    x 0.1 m below the hinge, pushed by a force; a point mass hanging from the slider on a
    spring."""
    system = System(gravity=(0.0, -9.81, 0.0))
    beam = system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=4, rotation="cardan", name="beam"))
    system.add(Joint.revolute(system.ground, beam.origin, axis=(0.0, 0.0, 1.0)))
    top = beam.node_group("y1")
    system.add(DistributedForce(beam, top, np.full(top.size, 1.0 / top.size), (0.0, -0.5, 0.0)))
    tip = int(np.argmax(beam.data.u0[:, 0]))
    forces = np.zeros((2, beam.data.n_nodes, 3))
    forces[:, tip] = [(0.0, 0.2, 0.0), (0.1, -0.3, 0.05)]
    system.add(NodalForces(beam, (0.0, SWITCH), forces))
    at_tip = beam.data.u0[tip]
    block = system.add(RigidBody(0.1, 1e-4 * np.eye(3), name="block").set_initial(R=at_tip))
    system.add(Joint.spherical(beam.node(tip), block.origin))
    plate = system.add(RigidBody(0.05, 2e-5 * np.eye(3), name="plate").set_initial(R=at_tip))
    system.add(Joint.fixed(block.origin, plate.origin))
    system.add(Torque(plate.origin, (0.0, 0.0, 1e-3)))
    slider = system.add(RigidBody(0.2, 1e-4 * np.eye(3), rotation="cardan", name="slider")
                        .set_initial(R=(0.0, -0.1, 0.0)))
    system.add(Joint.prismatic(ground_frame((0.0, -0.1, 0.0)), slider.origin, axis=(1.0, 0.0, 0.0)))
    system.add(Force(slider.origin, (0.5, 0.0, 0.0)))
    bob = system.add(PointMass(0.05, position=(0.0, -0.2, 0.0), name="bob"))
    system.add(SpringDamper(slider.origin, bob.point, 100.0, 0.1, free_length=0.1))
    return system, {"tip": beam.node(tip), "plate": plate.origin, "slider": slider.origin, "bob": bob.point}
