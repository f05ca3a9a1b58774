"""A model script: the scene of ``point_mass_beam.toml`` written in Python.

``ffrmbs run model_script.py`` calls :func:`scene` (see :mod:`ffrmbs_app.scene_loader`). The script
shows what each entry of the TOML file maps to. The scene is the thesis's point mass
dropped on the clamped flexible beam (Sec. 5.2, setup A). SI units.
"""

from contact import Contact, ContactKinematicsPointContour2s, UnilateralNewtonImpact
from contours import Contour2sNeutralFFR, PointContour
from ffrmbs_app.scene import Scene
from mbs import FlexibleBodyFFR, PointMass, PrescribedFrameMotion, System
from ffrmbs_app.scenes.cache import cache_dir
from ffrmbs_app.scenes.point_mass_beam import TET10


def scene() -> Scene:
    """The scene: the beam (tet10 of 12.5 mm, 20 clamped modes, frame fixed in space) and
    the 0.5 kg point mass at (235, 52, 25) mm falling at 0.2 m/s. The point meets the top
    face's 2s contour, which carries the static compliance of the modes left out (residual
    flexibility, cached with the body data), under Newton's impact law (e = 0). Moreau
    time-stepping, Δt = 1e-5 s, 0.1 s."""
    system = System()
    system.cache_dir = cache_dir()
    beam = system.add(FlexibleBodyFFR(TET10.default_beam_data(), modes=20, frame=PrescribedFrameMotion.fixed(),
                                      name="beam"))
    mass = system.add(PointMass(0.5, position=(0.235, 0.052, 0.025), velocity=(0.0, -0.2, 0.0),
                                name="point mass"))
    top = Contour2sNeutralFFR(beam, "y1", residual_flexibility=True)
    kinematics = ContactKinematicsPointContour2s(PointContour(mass.point), top)
    system.add(Contact(kinematics, UnilateralNewtonImpact(e=0.0), name="impact"))
    node19 = beam.node(beam.data.node_at((0.25, 0.05, 0.025)))
    outputs = {
        "y": lambda t, q, u: q[mass.q_slice][1],                 # [m]
        "vy": lambda t, q, u: u[mass.u_slice][1],                # [m/s]
        "node19": lambda t, q, u: node19.elastic_displacement(q[beam.q_slice]),   # displacement [m]
    }
    return Scene(system, t_end=0.1, dt=1e-5, integrator="moreau", options={"theta": 0.5, "trace": True},
                 n_out=1001, outputs=outputs, name="point_mass_beam", units={"y": "m", "vy": "m/s", "node19": "m"},
                 description="thesis Sec. 5.2 setup A, written as a Python model script")
