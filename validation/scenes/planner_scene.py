"""A scene for the planner (:mod:`mbs.run.plan`): every rule has something to do.

Built on the point mass dropped on the clamped beam (thesis Sec. 5.2, setup A,
:mod:`ffrmbs_app.scenes.point_mass_beam`, 20 modes, Moreau), plus

- a second point mass 1 m beside the beam, drifting at 0.1 m/s, with a contact pair
  against the same beam contour: **far from any contact**, the broad phase prunes the
  pair every step, so neither the search nor a contour update runs for it;
- a second beam of the same body data, **frame-fixed** 0.5 m behind the first and in no
  contact, built with all 750 modes (``modes=None``: not fixed by the user) and loaded at
  its tip node by a step force of (0, −5, 0) N held for 5 ms: the planner solves it by exact
  modal propagation (PureMA) on the modes holding 99 % of the load's effective mass.
"""

from __future__ import annotations

from dataclasses import dataclass

from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact
from contours import PointContour
from mbs import FlexibleBodyFFR, Force, PointMass, PrescribedFrameMotion, Tabulated

from ffrmbs_app.scenes import point_mass_beam as pmb

FAR_POSITION, FAR_VELOCITY = (0.1, 1.05, 0.025), (0.1, 0.0, 0.0)     # [m], [m/s]
SECOND_BEAM_AT = (0.0, 0.0, -0.5)                                     # [m], its frame origin
TIP_LOAD, LOAD_TIME = (0.0, -5.0, 0.0), 5e-3                          # [N], [s]


@dataclass
class PlannerScene:
    """The built scene: the point-mass-beam scene and the two extra bodies."""

    base: pmb.Scene
    far_mass: PointMass
    far_contact: Contact
    second_beam: FlexibleBodyFFR

    @property
    def system(self):
        return self.base.system

    def outputs(self):
        """The base scene's outputs, the far mass's x [m] and the second beam's tip
        displacement u_y [m] (node 19)."""
        beam, j, far = self.second_beam, self.base.node, self.far_mass
        return {**self.base.outputs(), "far_x": lambda t, q, u: q[far.q_slice][0],
                "tip2_y": lambda t, q, u: beam.phi_nodes[j][1] @ q[beam.q_slice]}


def build(modes=20, data=None) -> PlannerScene:
    """The scene with ``modes`` on the contact beam (the second beam keeps all modes for
    the planner to choose from); ``data`` the beam's body data (default: cached)."""
    data = pmb.default_beam_data() if data is None else data
    base = pmb.build("A", modes=modes, data=data)
    system = base.system
    far = system.add(PointMass(pmb.MASS, position=FAR_POSITION, velocity=FAR_VELOCITY, name="far point mass"))
    surface = base.contact.kinematics.contour2
    far_contact = system.add(Contact(ContactKinematicsPointContour2s(PointContour(far.point), surface),
                                     UnilateralNewtonImpact(0.0), name="far contact"))
    second = system.add(FlexibleBodyFFR(data, modes=None, frame=PrescribedFrameMotion.fixed(SECOND_BEAM_AT),
                                        name="second beam"))
    system.add(Force(second.node(base.node), Tabulated([0.0, LOAD_TIME], [TIP_LOAD, (0.0, 0.0, 0.0)])))
    return PlannerScene(base, far, far_contact, second)
