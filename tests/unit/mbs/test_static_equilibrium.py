"""Static equilibrium as the initial state (issue 30, item 16; :mod:`mbs.run.static`).

Oracles: the clamped beam's modal static deflection K_ff q_f = Φᵀ f (f the nodes' lumped
weights, from the body data), the full FE static solve K u = f with the body's own K, and
beam theory w L⁴ / (8 E I); hand calculations for a mass on a spring (m g / k), a body
hanging from a ball joint (centre of mass below the joint) and a block on four points
(the normal forces sum to m g). From the static state a run stays at rest."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from contact import LinearRegularizedUnilateralConstraint, UnilateralCoulombContact, connect
from contours import PlaneContour, PointContour
from ffrmbs.errors import InputFileError, ModelError
from ffrmbs_app.scene_file import read_scene
from mbs import FlexibleBodyFFR, Joint, PointMass, PrescribedFrameMotion, RigidBody, SpringDamper, System, ground_frame
from preprocess import Material, build_body, write_body
from preprocess.geometry import box
from qa.fixtures import fixture_text

G = 9.81                                     # [m/s²]
L, H = 0.2, 0.02                             # beam length and square section [m]
RHO, E, NU = 1200.0, 2e9, 0.3                # [kg/m³], [Pa]
MODES = 10


@pytest.fixture(scope="module")
def beam_data():
    """A cantilever 200 x 20 x 20 mm, tet10 (10 x 2 x 2 divisions), clamped at x = 0."""
    return build_body(box(L, H, H, None, order=2, divisions=(10, 2, 2)), Material(RHO, E, NU), n_modes=MODES,
                      clamp="x0")


def cantilever(data):
    system = System(gravity=(0.0, -G, 0.0))
    beam = system.add(FlexibleBodyFFR(data, frame=PrescribedFrameMotion.fixed(), name="beam"))
    return system, beam


def tip_deflection(data, displacement):
    """The mean y displacement [m] of the tip face's nodes from the (3N,) field."""
    return float(displacement.reshape(-1, 3)[data.node_groups["x1"], 1].mean())


def test_a_clamped_beam_takes_its_static_deflection_under_its_weight(beam_data):
    data = beam_data
    system, beam = cantilever(data)
    q, u = system.static_equilibrium()
    assert not u.any()
    np.testing.assert_array_equal(beam.q_init, q)                 # the initial state
    f = np.zeros((data.n_nodes, 3))
    f[:, 1] = -data.masses * G                                    # the nodes' lumped weights [N]
    f = f.ravel()
    phi = data.phi
    modal = np.linalg.solve(phi.T @ (data.stiffness @ phi), phi.T @ f)
    np.testing.assert_allclose(q, modal, rtol=1e-9, atol=1e-12 * np.abs(modal).max())
    free = np.setdiff1d(np.arange(3 * data.n_nodes), (3 * data.node_groups["x0"][:, None] + np.arange(3)).ravel())
    full = np.zeros(3 * data.n_nodes)
    full[free] = spla.spsolve(data.stiffness[free][:, free].tocsc(), f[free])
    tip, tip_fe = tip_deflection(data, phi @ q), tip_deflection(data, full)
    beam_theory = -RHO * H * H * G * L ** 4 / (8 * E * H ** 4 / 12)
    assert abs(tip / tip_fe - 1.0) < 0.01           # modal truncation (10 modes)
    assert abs(tip_fe / beam_theory - 1.0) < 0.03   # mesh and shear (L/H = 10)


def test_a_run_from_the_static_state_stays_at_rest(beam_data):
    """Started undeformed the tip rings by the full deflection; started from the static
    state it moves by less than 1e-3 of it."""
    data = beam_data
    system, beam = cantilever(data)
    tip = data.node_groups["x1"]

    def tip_y(t, q, u):
        return float((data.phi @ q).reshape(-1, 3)[tip, 1].mean())

    t_out = np.linspace(0.0, 0.01, 51)
    ringing = system.simulate(0.01, 2e-5, integrator="moreau", t_out=t_out, outputs={"y": tip_y}, plan=False)["y"]
    q, _ = system.static_equilibrium()
    deflection = tip_y(0.0, q, None)
    rest = system.simulate(0.01, 2e-5, integrator="moreau", t_out=t_out, outputs={"y": tip_y}, plan=False)["y"]
    assert np.ptp(ringing) > 1.5 * abs(deflection)
    assert np.abs(rest - deflection).max() < 1e-3 * abs(deflection)


def test_a_mass_on_a_spring_and_a_body_on_a_ball_joint_hang_at_rest():
    """Hand calculation: the spring stretches by m g / k; the rigid body, started tilted
    by 30°, hangs with its centre of mass under the joint; the ball joint carries m g."""
    k, m, l0 = 200.0, 0.5, 0.3
    system = System(gravity=(0.0, 0.0, -G))
    bob = system.add(PointMass(m, position=(0.0, 0.0, -0.25), velocity=(0.1, 0.0, 0.0), name="bob"))
    system.add(SpringDamper(ground_frame((0.0, 0.0, 0.0)), bob.point, k, 0.0, free_length=l0))
    tilt = np.radians(30.0)
    A = np.array([[np.cos(tilt), 0.0, np.sin(tilt)], [0.0, 1.0, 0.0], [-np.sin(tilt), 0.0, np.cos(tilt)]])
    body = system.add(RigidBody(2.0, np.diag([0.02, 0.03, 0.04]), com=(0.0, 0.0, -0.1), name="body")
                      .set_initial(R=(1.0, 0.0, 0.0), A=A))
    system.add(Joint.spherical(ground_frame((1.0, 0.0, 0.0)), body.origin))
    q, u = system.static_equilibrium()
    assert not u.any()
    np.testing.assert_allclose(q[bob.q_slice], [0.0, 0.0, -(l0 + m * G / k)], rtol=0, atol=1e-12)
    com = body.com_frame().position(q[body.q_slice])
    np.testing.assert_allclose(com, [1.0, 0.0, -0.1], rtol=0, atol=1e-10)
    result = system.simulate(0.2, 1e-3, integrator="generalized-alpha", t_out=[0.0, 0.2], outputs={}, plan=False)
    np.testing.assert_allclose(result.q[-1], q, rtol=0, atol=1e-9)


BLOCK_POINTS = [(-0.04, -0.04), (0.04, -0.04), (0.0, 0.04)]


def block_on_points(law="impact", z=0.05):
    """A 2 kg block, its bottom plane (half height 0.05 m) on three ground points at z = 0."""
    system = System(gravity=(0.0, 0.0, -G))
    block = system.add(RigidBody(2.0, np.diag([0.01, 0.01, 0.01]), name="block").set_initial(R=(0.0, 0.0, z)))
    down = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])       # normal -z
    plane = PlaneContour(block.frame_at((0.0, 0.0, -0.05), down))
    for i, (x, y) in enumerate(BLOCK_POINTS):
        system.add(connect(PointContour(ground_frame((x, y, 0.0))), plane, law, name=f"p{i}"))
    return system, block


@pytest.mark.parametrize("law", ["impact", UnilateralCoulombContact(0.0, 0.3)])
def test_a_block_rests_on_three_points(law):
    """Hand calculation (moments about the centre of mass): the front points carry m g / 4
    each, the back one m g / 2; frictionless (impact law) or sticking (Coulomb law: no
    net friction force needed; the run's friction forces between the sticking points
    are not unique, they cancel)."""
    system, block = block_on_points(law)
    q, u = system.static_equilibrium()
    np.testing.assert_allclose(q[block.q_slice][:3], [0.0, 0.0, 0.05], rtol=0, atol=1e-15)
    result = system.simulate(0.05, 1e-4, integrator="moreau", t_out=[0.0, 0.05], outputs={}, plan=False,
                             contacts=True)
    np.testing.assert_allclose(result.q[-1], q, rtol=0, atol=1e-12)
    forces = np.array([result.contacts[f"p{i}"]["force"][-1] for i in range(3)])    # on the ground points
    np.testing.assert_allclose(forces[:, 2], [-2.0 * G * share for share in (0.25, 0.25, 0.5)], rtol=1e-8)
    np.testing.assert_allclose(forces[:, :2].sum(axis=0), 0.0, rtol=0, atol=1e-8)
    if law == "impact":
        np.testing.assert_allclose(forces[:, :2], 0.0, rtol=0, atol=1e-8)


@pytest.mark.parametrize("make, fragment", [
    (lambda: block_on_points(z=0.06), "body 'block' has none: nothing holds it"),            # above the points
    (lambda: block_on_points(law=LinearRegularizedUnilateralConstraint(1e5, 0.0)),
     "contact 'p0' is a closed contact with a single-valued"),
])
def test_unsupported_states_are_named(make, fragment):
    system, _ = make()
    with pytest.raises(ModelError) as info:
        system.static_equilibrium()
    assert fragment in str(info.value)


# --- scene files: initial = "static" -------------------------------------------------------------------

SCENE = fixture_text("scenes/static_beam_and_bob.toml")


@pytest.fixture(scope="module")
def scene_path(beam_data, tmp_path_factory):
    directory = tmp_path_factory.mktemp("static")
    write_body(directory / "beam", beam_data)
    path = directory / "static.toml"
    path.write_text(SCENE)
    return path


def test_initial_static_in_a_scene_file_is_the_python_static_state(beam_data, scene_path):
    """The beam and the bob at rest as System.static_equilibrium puts them (the bob at
    l0 + m g / k below the spring's anchor); the ball keeps its given state."""
    scene = read_scene(scene_path)
    system, beam = cantilever(beam_data)
    bob = system.add(PointMass(0.5, position=(0.0, -0.25, 0.0), name="bob"))
    system.add(SpringDamper(ground_frame((0.0, 0.0, 0.0)), bob.point, 200.0, 0.0, free_length=0.3))
    ball = system.add(PointMass(0.1, position=(0.1, 0.05, 0.01), velocity=(0.0, -1.0, 0.0), name="ball"))
    system.static_equilibrium(bodies=[beam, bob])
    q, u = scene.system.initial_state()
    np.testing.assert_array_equal((q, u), system.initial_state())
    np.testing.assert_allclose(q[bob.q_slice], [0.0, -(0.3 + 0.5 * G / 200.0), 0.0], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(u[ball.u_slice], [0.0, -1.0, 0.0])


@pytest.mark.parametrize("old, new, fragment, line", [
    ('position = [0.0, -0.25, 0.0]\ninitial = "static"',
     'position = [0.0, -0.25, 0.0]\ninitial = "static"\nvelocity = [0.0, 0.1, 0.0]',
     "body 'bob': 'velocity' is computed by initial = \"static\"", "velocity = [0.0, 0.1, 0.0]"),
    ('velocity = [0.0, -1.0, 0.0]\n', 'initial = "static"\n',
     "body 'ball': initial = \"static\": static equilibrium: body 'ball' has none: nothing holds it",
     'initial = "static"'),
    ('frame = "fixed"\ninitial = "static"', 'frame = "fixed"\ninitial = "rest"',
     "'initial' must be one of 'given', 'static'", 'initial = "rest"'),
])
def test_faults_of_initial_static_name_the_body_and_line(scene_path, old, new, fragment, line):
    text = SCENE
    assert text.count(old) == 1
    path = scene_path.parent / "fault.toml"
    path.write_text(text.replace(old, new))
    with pytest.raises(InputFileError) as info:
        read_scene(path)
    assert fragment in str(info.value)
    assert path.read_text().splitlines()[info.value.line - 1] == line
