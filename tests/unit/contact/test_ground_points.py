"""Points on the ground against a surface on a body (issue 30, item 9): a part landing on
a rigid support, the compliant surface on the part. A flexible plate (a 2s contour on its
bottom face) and a rigid block (a plane on its bottom face) fall onto four ground points
each; the scene file gives the same run as the Python API, and the run agrees with the
hand calculation: free fall until the impact, then rest on the points (e = 0) at the
height where the gap closes, carried by contact forces that sum to the weight."""

from __future__ import annotations

import numpy as np
import pytest

from contact import UnilateralCoulombContact, connect
from contours import Contour2sNeutralFFR, PlaneContour, PointContour
from ffrmbs.errors import InputFileError, ModelError
from ffrmbs_app.scene_file import read_scene
from ffrmbs_app.scene_file.contacts import axes_with_normal
from mbs import FlexibleBodyFFR, RigidBody, System, ground_frame
from preprocess import Material, build_body, write_body
from preprocess.geometry import box

G = 9.81                                  # [m/s²]
LX, LY, LZ = 0.2, 0.04, 0.02              # plate [m]
DROP, V0 = 0.005, -0.5                    # bottom face above the points [m], initial velocity [m/s]
BLOCK_MASS, HALF = 2.0, 0.05              # block [kg], half its height [m]
T_END, DT, N_OUT = 0.12, 1e-4, 25
PLATE_POINTS = [(0.02, 0.01), (0.18, 0.01), (0.02, 0.03), (0.18, 0.03)]
BLOCK_POINTS = [(-0.04, -0.04), (0.04, -0.04), (-0.04, 0.04), (0.04, 0.04)]
BLOCK_GROUND, BLOCK_DROP = 0.5, 0.02      # the block's points at z = 0.5 m, its bottom 0.02 m above them

SCENE = """\
[scene]
name = "landing"
t_end = {t_end}
dt = {dt}
integrator = "moreau"
n_out = {n_out}
gravity = [0.0, 0.0, -9.81]
plan = false

[[body]]
name = "plate"
kind = "flexible"
source = "plate/body.h5"
position = [0.0, 0.0, {drop}]
velocity = [0.0, 0.0, {v0}]
modal_damping = 0.3

[[body]]
name = "block"
kind = "rigid"
mass = {block_mass}
inertia = [0.01, 0.01, 0.01]
position = [0.0, 0.0, {block_z}]
velocity = [0.0, 0.0, {v0}]
{contacts}
[outputs]
plate = {{ body = "plate", quantity = "velocity", component = "z" }}
block = {{ body = "block", quantity = "position", component = "z" }}
"""

PLATE_CONTACT = """
[[contact]]
name = "plate {i}"
contour1 = {{ kind = "point", body = "ground", point = [{x}, {y}, 0.0] }}
contour2 = {{ kind = "2s", body = "plate", nodes = "z0" }}
law = "impact"
"""

BLOCK_CONTACT = """
[[contact]]
name = "block {i}"
contour1 = {{ kind = "point", body = "ground", point = [{x}, {y}, {z}] }}
contour2 = {{ kind = "plane", body = "block", point = [0.0, 0.0, -{half}], normal = [0.0, 0.0, -1.0] }}
law = "impact"
"""


@pytest.fixture(scope="module")
def scene_path(tmp_path_factory):
    """The landing scene beside its plate (tet4, 10 x 3 x 1 divisions, free-free, 6
    modes, E = 2e9 Pa, ρ = 7800 kg/m³; modal damping ζ = 0.3 in the scene, so that it
    comes to rest)."""
    directory = tmp_path_factory.mktemp("landing")
    data = build_body(box(LX, LY, LZ, None, order=1, divisions=(10, 3, 1)), Material(7800.0, 2e9, 0.3), n_modes=6)
    write_body(directory / "plate", data)
    contacts = "".join(PLATE_CONTACT.format(i=i, x=x, y=y) for i, (x, y) in enumerate(PLATE_POINTS))
    contacts += "".join(BLOCK_CONTACT.format(i=i, x=x, y=y, z=BLOCK_GROUND, half=HALF)
                        for i, (x, y) in enumerate(BLOCK_POINTS))
    path = directory / "landing.toml"
    path.write_text(SCENE.format(t_end=T_END, dt=DT, n_out=N_OUT, drop=DROP, v0=V0, block_mass=BLOCK_MASS,
                                 block_z=BLOCK_GROUND + HALF + BLOCK_DROP, contacts=contacts))
    return path


def python_landing(body_file):
    """The landing scene written with the Python API: ground points against the plate's
    bottom face and against a plane on the block's."""
    system = System(gravity=(0.0, 0.0, -G))
    plate = system.add(FlexibleBodyFFR.from_file(body_file, modal_damping=0.3, name="plate").set_initial(R=(0.0, 0.0, DROP),
                                                                                     v=(0.0, 0.0, V0)))
    block = system.add(RigidBody(BLOCK_MASS, np.diag([0.01, 0.01, 0.01]), name="block")
                       .set_initial(R=(0.0, 0.0, BLOCK_GROUND + HALF + BLOCK_DROP), v=(0.0, 0.0, V0)))
    bottom = Contour2sNeutralFFR(plate, "z0")
    for i, (x, y) in enumerate(PLATE_POINTS):
        system.add(connect(PointContour(ground_frame((x, y, 0.0))), bottom, "impact", name=f"plate {i}"))
    plane = PlaneContour(block.frame_at((0.0, 0.0, -HALF), axes_with_normal(np.array([0.0, 0.0, -1.0]))))
    for i, (x, y) in enumerate(BLOCK_POINTS):
        system.add(connect(PointContour(ground_frame((x, y, BLOCK_GROUND))), plane, "impact", name=f"block {i}"))
    return system, plate, block


def run(system, outputs):
    return system.simulate(T_END, DT, integrator="moreau", t_out=np.linspace(0.0, T_END, N_OUT), outputs=outputs,
                           plan=False, contacts=True)


@pytest.fixture(scope="module")
def landing(scene_path):
    scene = read_scene(scene_path)
    return scene, run(scene.system, scene.outputs)


@pytest.mark.slow
def test_the_scene_file_is_the_python_scene(scene_path, landing):
    scene, result = landing
    system, plate, block = python_landing(scene_path.parent / "plate" / "body.h5")
    expected = run(system, {"plate": lambda t, q, u: u[plate.u_slice][2],
                            "block": lambda t, q, u: q[block.q_slice][2]})
    np.testing.assert_array_equal(result.q, expected.q)
    np.testing.assert_array_equal(result.u, expected.u)
    for name in [f"plate {i}" for i in range(4)] + [f"block {i}" for i in range(4)]:
        np.testing.assert_array_equal(result.contacts[name]["force"], expected.contacts[name]["force"])


@pytest.mark.slow
def test_parts_fall_then_rest_on_the_ground_points(scene_path, landing):
    """Hand calculation: free fall z(t) = z0 + v0 t − g t²/2 until the bottom face meets
    the points; after it (e = 0) the parts rest: no velocity, the block's bottom at the
    points' height (to the Moreau midpoint closing, |v_impact| Δt), and the four contact
    forces of each part summing to its weight m g (recorded on contour 1, the ground
    point: −m g along z)."""
    scene, result = landing
    t = result.t
    block_z0 = BLOCK_GROUND + HALF + BLOCK_DROP
    v_impact = np.sqrt(V0 ** 2 + 2 * G * BLOCK_DROP)
    t_impact = (v_impact + V0) / G
    free = t < t_impact - DT
    np.testing.assert_allclose(result["block"][free], block_z0 + V0 * t[free] - 0.5 * G * t[free] ** 2,
                               rtol=0, atol=1e-12)
    assert t_impact < 0.7 * T_END
    rest = t > 0.8 * T_END
    assert np.all(np.abs(result["block"][rest] - (BLOCK_GROUND + HALF)) <= v_impact * DT)
    assert np.all(np.abs(result["plate"][rest]) < 1e-6)          # the plate's frame velocity [m/s]
    plate_mass = scene.system.bodies[0].mass
    assert plate_mass == pytest.approx(7800.0 * LX * LY * LZ, rel=1e-12)
    for part, mass in (("plate", plate_mass), ("block", BLOCK_MASS)):
        total = sum(result.contacts[f"{part} {i}"]["force"][rest] for i in range(4))
        np.testing.assert_allclose(total[:, 2], -mass * G, rtol=1e-6)
        # sideways only by the tilt of the sagging plate's normals at the points (< 1e-4 rad)
        np.testing.assert_allclose(total[:, :2], 0.0, atol=1e-4 * mass * G)


def test_a_contact_with_both_contours_on_the_ground_is_refused(scene_path):
    text = scene_path.read_text()
    old = 'contour2 = { kind = "plane", body = "block", point = [0.0, 0.0, -0.05]'
    assert text.count(old) == 4
    path = scene_path.parent / "grounded.toml"
    path.write_text(text.replace(old, 'contour2 = { kind = "plane", body = "ground", point = [0.0, 0.0, -0.05]', 1))
    with pytest.raises(InputFileError) as info:
        read_scene(path)
    assert "contact 'block 0'" in str(info.value)
    assert "both contours are on the ground" in info.value.fault


def test_a_plate_cannot_start_sticking_on_points_that_hold_it_by_friction(scene_path):
    """Static equilibrium (issue 30, item 16) of the plate touching the points with the
    Coulomb law: sticking points pin its bottom face, and the bending would need
    horizontal forces far beyond μ λ_N (membrane action): a clear error naming the
    contact, not a state the run would leave at once."""
    system = System(gravity=(0.0, 0.0, -G))
    plate = system.add(FlexibleBodyFFR.from_file(scene_path.parent / "plate" / "body.h5", name="plate"))
    bottom = Contour2sNeutralFFR(plate, "z0")
    for i, (x, y) in enumerate(PLATE_POINTS):
        system.add(connect(PointContour(ground_frame((x, y, 0.0))), bottom,
                           UnilateralCoulombContact(0.0, 0.5), name=f"p{i}"))
    with pytest.raises(ModelError, match=r"contact 'p\d' would slide: friction .* N needed, mu lambda_N = .* N"):
        system.static_equilibrium()


@pytest.mark.slow
def test_the_part_lands_through_its_residual_flexibility(scene_path):
    """The compliant surface on the part: the plate's bottom face with residual
    flexibility (free-free, inertia relief) lands on the ground points and rests with the
    four forces summing to its weight (θ = 1; at θ = ½ the recorded force is θ times the
    real one, issue 30 item 3)."""
    system = System(gravity=(0.0, 0.0, -G))
    plate = system.add(FlexibleBodyFFR.from_file(scene_path.parent / "plate" / "body.h5", modal_damping=0.3,
                                                 name="plate").set_initial(R=(0.0, 0.0, DROP), v=(0.0, 0.0, V0)))
    bottom = Contour2sNeutralFFR(plate, "z0", residual_flexibility=True)
    for i, (x, y) in enumerate(PLATE_POINTS):
        system.add(connect(PointContour(ground_frame((x, y, 0.0))), bottom, "impact", name=f"p{i}"))
    result = system.simulate(T_END, DT, integrator="moreau", t_out=np.linspace(0.0, T_END, N_OUT),
                             outputs={"vz": lambda t, q, u: u[plate.u_slice][2]}, plan=False, contacts=True,
                             theta=1.0)
    rest = result.t > 0.8 * T_END
    assert np.all(np.abs(result["vz"][rest]) < 1e-6)
    total = sum(result.contacts[f"p{i}"]["force"][rest] for i in range(4))
    np.testing.assert_allclose(total[:, 2], -plate.mass * G, rtol=1e-6)
