"""TOML scene files (ffrmbs_app.scene_file): the same System as the Python API, and
errors that name the file, the line and the key."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

import mbs
from contact import (ContactKinematicsPointContour2s, ContactKinematicsPointPlane, ContactKinematicsSphereContour2s,
                     ContactKinematicsSpherePlane, ContactKinematicsSphereSphere, CurveConstraint,
                     LinearRegularizedUnilateralConstraint, PointOnCurveConstraint, RegularizedCoulombFriction,
                     UnilateralCoulombContact, UnilateralNewtonImpact)
from contours import Contour1sNeutralFFR, Contour2sNeutralFFR, FlexibleBand, FlexibleCylinder, PlaneContour
from ffrmbs.errors import InputFileError
from ffrmbs_app.scene import Scene
from ffrmbs_app.scene_loader import load_scene
from ffrmbs_app.scene_file import read_scene
from mbs import (DistributedForce, FlexibleBodyFFR, Force, Joint, NodalForces, PointMass, PrescribedFrameMotion,
                 RigidBody, SpringDamper, System, Tabulated, Torque, ground_frame, write_force_file)
from preprocess import Material, build_body, read_body, write_body
from preprocess.geometry import box
from qa.fixtures import edited, fixture_text

from gmsh_parts import LENGTH, RADIUS, cylinder_mesh

import paths

EXAMPLES = paths.EXAMPLES / "scenes"


# --- the example scene against the Python-built one ---------------------------------------------------

def simulate(scene: Scene, outputs, t_end, n_out):
    """Run ``scene`` as the job would, to ``t_end`` [s] with ``n_out`` samples."""
    return scene.system.simulate(t_end, scene.dt, integrator=scene.integrator, t_out=np.linspace(0.0, t_end, n_out),
                                 outputs=outputs, energies=scene.energies, plan=scene.plan,
                                 tolerance=scene.tolerance, **scene.options)


def test_example_scene_is_bitwise_the_python_scene():
    """examples/scenes/point_mass_beam.toml and model_script.py against
    ffrmbs_app.scenes.point_mass_beam.build("A", 20, "impact", 0.0, contour="2s") on the
    main job's tet10 beam with residual flexibility, run as the main job runs it (Moreau,
    θ = 0.5) for 15 ms. The point mass reaches the beam at about 10 ms, so the run covers
    free flight and impact."""
    from ffrmbs_app.scenes import point_mass_beam as pmb

    t_end, n_out = 0.015, 31
    reference = pmb.build("A", 20, "impact", 0.0, contour="2s", data=pmb.TET10.default_beam_data(),
                          residual_flexibility=True)
    expected = reference.system.simulate(t_end, 1e-5, integrator="moreau", t_out=np.linspace(0.0, t_end, n_out),
                                         outputs=reference.outputs(), energies=True, theta=0.5, trace=True)
    assert expected.trace["closed"].sum() > 100            # the impact is inside the window
    assert np.abs(expected["node19"][-1]).max() > 1e-5
    for path in (EXAMPLES / "point_mass_beam.toml", EXAMPLES / "model_script.py"):
        scene = load_scene(path)
        result = simulate(scene, scene.outputs, t_end, n_out)
        np.testing.assert_array_equal(result.t, expected.t)
        np.testing.assert_array_equal(result.q, expected.q)
        np.testing.assert_array_equal(result.u, expected.u)
        np.testing.assert_array_equal(result["y"], expected["y"])
        np.testing.assert_array_equal(result["vy"], expected["vy"])
        # node 19's displacement in all three (issue 18: one meaning of node19), not zero after the impact
        np.testing.assert_array_equal(result["node19"], expected["node19"])
        np.testing.assert_array_equal(result.trace["closed"], expected.trace["closed"])


def test_load_scene_reads_the_example_file_and_script():
    toml, script = load_scene(EXAMPLES / "point_mass_beam.toml"), load_scene(EXAMPLES / "model_script.py")
    for scene in (toml, script):
        assert isinstance(scene, Scene)
        assert (scene.name, scene.t_end, scene.dt, scene.integrator, scene.n_out) == \
            ("point_mass_beam", 0.1, 1e-5, "moreau", 1001)
        assert scene.options == {"theta": 0.5, "trace": True}
        assert sorted(scene.outputs) == ["node19", "vy", "y"]
        assert [b.name for b in scene.system.bodies] == ["beam", "point mass"]
    assert toml.inputs["scene file"] == str(EXAMPLES / "point_mass_beam.toml")
    body_file = Path(toml.inputs["body 'beam'"])
    assert body_file.name == "body.h5" and body_file.is_file()
    assert read_body(body_file).n_modes == 40
    assert script.inputs["model script"] == str(EXAMPLES / "model_script.py")


# --- every kind of entry, against the same System built in Python ----------------------------------

@pytest.fixture(scope="module")
def body_dir(tmp_path_factory):
    """A small clamped beam, 250 x 50 x 50 mm tet4 (5 x 2 x 2 divisions, 54 nodes, 6 modes),
    written as text files and body.h5 into one directory."""
    data = build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(5, 2, 2)), Material(920.0, 5e7, 0.3),
                      n_modes=6, clamp="x0")
    directory = tmp_path_factory.mktemp("scene") / "body"
    write_body(directory, data)
    return directory


@pytest.fixture(scope="module")
def force_file(body_dir):
    """A force file (report Appendix A) for the text body: a step load at the x1 face's
    nodes, the x0 nodes blocked. Returns (path, times, forces, blocked nodes)."""
    data = read_body(body_dir / "body.h5")
    times = np.array([0.0, 5e-4])
    forces = np.zeros((2, data.n_nodes, 3))
    forces[0, data.node_groups["x1"], 1] = 0.1
    forces[1, data.node_groups["x1"], 2] = -0.2
    blocked = data.node_groups["x0"]
    path = body_dir.parent / "loads.txt"
    write_force_file(path, times, forces, (3 * blocked[:, None] + np.arange(3)).ravel())
    return path, times, forces, blocked


@pytest.fixture(scope="module")
def sink_text(force_file):
    """The kitchen-sink scene with the nodal load's blocked nodes of ``force_file``."""
    return edited(fixture_text("scenes/kitchen_sink.toml"), ("blocked = []", f"blocked = {force_file[3].tolist()}"))


@pytest.fixture(scope="module")
def sink_path(body_dir, sink_text):
    path = body_dir.parent / "sink.toml"
    path.write_text(sink_text)
    return path


def python_sink(body_dir, force_file):
    """The sink scene written with the Python API, entry by entry."""
    h5, text = read_body(body_dir / "body.h5"), read_body(body_dir)
    system = System(gravity=(0.0, -9.81, 0.0))
    beam = FlexibleBodyFFR(h5, modes=[0, 2, 3], rotation="cardan", rayleigh=(0.1, 1e-4), name="beam")
    beam.set_initial(R=(0.1, 0.2, 0.3), A=[[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], v=(0.01, 0.0, 0.0),
                     omega=(0.0, 0.0, 0.5))
    beam.set_initial(q_f=[1e-4, 0.0, -1e-4], qdot_f=[0.0, 1e-3, 0.0])
    system.add(beam)
    clamped = system.add(FlexibleBodyFFR(text, modes=4, frame=PrescribedFrameMotion.fixed((0.0, 1.0, 0.0)),
                                         modal_damping=0.02, name="clamped"))
    block = system.add(RigidBody(2.0, np.diag([0.01, 0.02, 0.03]), (0.0, 0.0, 0.01), name="block")
                       .set_initial(R=(1.0, 0.0, 0.0), omega=(0.1, 0.2, 0.3)))
    bob = system.add(PointMass(0.3, position=(0.0, -0.5, 0.0), velocity=(0.1, 0.0, 0.0), name="bob"))
    system.add(SpringDamper(ground_frame((0.0, 0.0, 0.0)), bob.point, 100.0, 0.5, free_length=0.4))
    system.add(Joint.spherical(ground_frame((1.0, 0.0, 0.0)), block.origin))
    system.add(Force(beam.node(7), Tabulated([0.0, 0.001], [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]])))
    system.add(Torque(block.origin, (0.0, 0.0, 0.01), frame_fixed=True))
    x1 = h5.node_groups["x1"]
    system.add(DistributedForce(beam, "x1", np.full(x1.size, 1.0 / x1.size), (0.5, 0.0, 0.0)))
    _, times, forces, _ = force_file
    system.add(NodalForces(clamped, times, forces))
    return system, beam, clamped, block, bob


def test_every_entry_maps_onto_the_python_api(body_dir, force_file, sink_path):
    scene = read_scene(sink_path)
    system, beam, clamped, block, bob = python_sink(body_dir, force_file)
    assert (scene.name, scene.t_end, scene.dt, scene.integrator, scene.n_out, scene.plan) == \
        ("sink", 0.002, 1e-4, "generalized-alpha", 5, False)
    assert scene.options == {"rho_inf": 0.8}
    np.testing.assert_array_equal(scene.system.gravity, [0.0, -9.81, 0.0])
    assert [type(f) for f in scene.system.forces] == [SpringDamper, Force, Torque, DistributedForce, NodalForces]
    assert [c.kind for c in scene.system.constraints] == ["spherical"]
    q0, u0 = scene.system.initial_state()
    q1, u1 = system.initial_state()
    np.testing.assert_array_equal(q0, q1)
    np.testing.assert_array_equal(u0, u1)

    result = simulate(scene, scene.outputs, scene.t_end, scene.n_out)
    expected = system.simulate(scene.t_end, 1e-4, integrator="generalized-alpha", t_out=scene.t_out(), plan=False,
                               rho_inf=0.8)
    np.testing.assert_array_equal(result.q, expected.q)
    np.testing.assert_array_equal(result.u, expected.u)
    assert np.abs(result.q[-1] - result.q[0]).max() > 1e-6       # things moved

    # the outputs, from the states by hand
    tip = h5_node = read_body(body_dir / "body.h5").node_at((0.25, 0.05, 0.05))
    for k, (q, u) in enumerate(zip(expected.q, expected.u)):
        qb, ub = q[beam.q_slice], u[beam.u_slice]
        R, theta, q_f = qb[:3], qb[3:6], qb[6:]
        A = beam.param.matrix(theta)
        np.testing.assert_allclose(result["tip"][k], R + A @ (beam.data.u0[tip] + beam.phi_nodes[h5_node] @ q_f),
                                   rtol=0, atol=1e-15)
        np.testing.assert_allclose(result["tip_v"][k], beam.node(7).velocity(qb, ub), rtol=0, atol=1e-15)
        np.testing.assert_array_equal(result["modal"][k], q_f)
        assert result["tip_u"][k] == pytest.approx(clamped.phi_nodes[7][1] @ q[clamped.q_slice], rel=1e-14, abs=0)
        np.testing.assert_allclose(result["spin"][k], block.angular_velocity(q[block.q_slice], u[block.u_slice]),
                                   rtol=0, atol=1e-15)
        np.testing.assert_array_equal(result["bob"][k], q[bob.q_slice] + [0.0, 0.0, 0.1])
    assert np.abs(result["tip_u"]).max() > 0                      # the nodal forces bent it


def test_inputs_list_the_scene_body_and_force_files(body_dir, sink_path):
    scene = read_scene(sink_path)
    files = {label: Path(p) for label, p in scene.inputs.items()}
    assert files["scene file"] == sink_path
    assert files["body 'beam'"] == body_dir / "body.h5"
    assert files["body 'clamped'"] == body_dir / "body.h5"            # a directory: its body.h5
    assert files["load #4 (nodal) force file"] == body_dir.parent / "loads.txt"
    assert all(p.is_file() for p in files.values())


CONTACTS = fixture_text("scenes/beam_block_bob.toml") + """
[[contact]]
name = "top"
contour1 = { kind = "point", body = "bob" }
contour2 = { kind = "2s", body = "beam", nodes = MATRIX, degree = [3, 2], outward = 1 }
law = "impact"
e = 0.5
margin = 0.01

[[contact]]
name = "band"
contour1 = { kind = "sphere", body = "block", radius = 0.05 }
contour2.kind = "band"
contour2.body = "beam"
contour2.start = [0.0, 0.05, 0.025]
contour2.direction = [1.0, 0.0, 0.0]
contour2.normal = [0.0, 1.0, 0.0]
contour2.degree = 4
contour2.width = 0.05
law = "coulomb"
e = 0.2
mu = 0.3

[[contact]]
name = "cylinder"
contour1 = { kind = "point", body = "bob", point = [0.0, 0.0, 0.1] }
law = "penalty"
k = 1e5
d = 10.0
mu = 0.4
v_eps = 1e-3
[contact.contour2]                      # the same as an inline table
kind = "cylinder"
body = "beam"
start = [0.0, 0.025, 0.025]
direction = [1.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
degree = 4
radius = 0.01

[[contact]]
name = "floor"
contour1 = { kind = "point", body = "bob" }
contour2 = { kind = "plane", point = [0.0, -1.0, 0.0], normal = [0.0, 2.0, 0.0] }
law = "impact"
margin = "off"

[[contact]]
name = "balls"
contour1 = { kind = "sphere", body = "bob", radius = 0.02 }
contour2 = { kind = "sphere", body = "block", radius = 0.05 }
law = "penalty"
k = 1e4

[[contact]]
name = "ball on floor"
contour1 = { kind = "sphere", body = "block", radius = 0.05 }
contour2 = { kind = "plane", body = "beam", node = 3, normal = [1.0, 0.0, 0.0] }
law = "impact"

[[contact]]
name = "on axis"
contour1 = { kind = "point", body = "bob" }
contour2 = { kind = "1s", body = "beam", nodes = [NODES], normal = [0.0, 1.0, 0.0] }
law = "bilateral"
"""


def test_contact_entries_map_onto_kinematics_and_laws(body_dir):
    data = read_body(body_dir / "body.h5")
    from contact.contact import _auto_margin
    from contours.node_grid import node_line, node_matrix

    axis = node_line(data.u0, (0.0, 0.025, 0.025), (1.0, 0.0, 0.0))
    top_face = node_matrix(data.u0, data.node_groups["y1"])
    path = body_dir.parent / "contacts.toml"
    path.write_text(CONTACTS.replace("NODES", ", ".join(map(str, axis.tolist())))
                    .replace("MATRIX", str(top_face.tolist())))
    scene = read_scene(path)
    c = {contact.name: contact for contact in scene.system.contacts}
    assert list(c) == ["top", "band", "cylinder", "floor", "balls", "ball on floor", "on axis"]

    top = c["top"]
    assert type(top.kinematics) is ContactKinematicsPointContour2s
    assert isinstance(top.kinematics.contour2, Contour2sNeutralFFR)
    np.testing.assert_array_equal(top.kinematics.contour2.nodes, top_face)
    assert top.kinematics.contour2.sign == 1
    assert top.law == UnilateralNewtonImpact(0.5) and top.margin == 0.01

    band = c["band"]
    assert type(band.kinematics) is ContactKinematicsSphereContour2s
    assert isinstance(band.kinematics.contour2, FlexibleBand) and band.kinematics.contour2.width == 0.05
    assert band.kinematics.contour1.radius == 0.05
    assert band.law == UnilateralCoulombContact(0.2, 0.3) and band.friction is None
    assert band.margin == _auto_margin(band.kinematics.contour2) > 0    # "auto" (the default)

    cylinder = c["cylinder"]
    assert isinstance(cylinder.kinematics.contour2, FlexibleCylinder) and cylinder.kinematics.contour2.radius == 0.01
    assert cylinder.law == LinearRegularizedUnilateralConstraint(1e5, 10.0)
    assert cylinder.friction == RegularizedCoulombFriction(0.4, 1e-3)
    np.testing.assert_array_equal(cylinder.kinematics.contour1.frame_ref.u0, [0.0, 0.0, 0.1])

    floor = c["floor"]
    assert type(floor.kinematics) is ContactKinematicsPointPlane and floor.margin is None
    plane = floor.kinematics.contour2
    assert isinstance(plane, PlaneContour) and plane.body is None
    np.testing.assert_array_equal(plane.frame_ref.u0, [0.0, -1.0, 0.0])
    np.testing.assert_allclose(plane.frame_ref.A_rel[:, 2], [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(plane.frame_ref.A_rel.T @ plane.frame_ref.A_rel, np.eye(3), atol=1e-15)
    assert np.linalg.det(plane.frame_ref.A_rel) == pytest.approx(1.0)

    assert type(c["balls"].kinematics) is ContactKinematicsSphereSphere
    assert c["balls"].law == LinearRegularizedUnilateralConstraint(1e4, 0.0)
    on_beam = c["ball on floor"].kinematics
    assert type(on_beam) is ContactKinematicsSpherePlane and on_beam.contour2.frame_ref.node_index == 3
    np.testing.assert_allclose(on_beam.contour2.frame_ref.A_rel[:, 2], [1.0, 0.0, 0.0], atol=1e-15)

    constraint = c["on axis"]
    assert isinstance(constraint, CurveConstraint) and type(constraint.kinematics) is PointOnCurveConstraint
    curve = constraint.kinematics.contour2
    assert type(curve) is Contour1sNeutralFFR
    np.testing.assert_array_equal(curve.nodes, axis)


@pytest.mark.parametrize("old, new, fragment", [
    ("radius = 0.01", "radius = -0.01", "contact 'cylinder': contour2 (cylinder): 'radius' must be > 0 [m]"),
    ("contour2.width = 0.05", "contour2.width = true", "contact 'band': contour2 (band): 'width' must be a number"),
    ("contour2.degree = 4", "contour2.degre = 4", "contact 'band': contour2 (band): unknown key 'degre'"),
    ("v_eps = 1e-3", "v_eps = 0.0", "contact 'cylinder': RegularizedCoulombFriction(mu=0.4, v_eps=0.0): v_eps must"),
])
def test_faults_in_sub_tables_and_dotted_keys_have_their_line(body_dir, old, new, fragment):
    text = CONTACTS.replace("NODES", "0, 1, 2, 3").replace("MATRIX", '"y1"')
    assert_fault_at(body_dir.parent / "contacts-fault.toml", text, old, new, fragment, new)


def assert_fault_at(path, text, old, new, fragment, line):
    """``text`` with its one ``old`` replaced by ``new``, written to ``path``, is refused
    with ``fragment`` in the fault, at the line that reads ``line``."""
    assert text.count(old) == 1
    path.write_text(text.replace(old, new))
    with pytest.raises(InputFileError) as info:
        read_scene(path)
    assert fragment in info.value.fault
    assert path.read_text().splitlines()[info.value.line - 1] == line


# --- faults -------------------------------------------------------------------------------------------

# (what, the text replaced, its replacement, message fragments, text on the faulty line)
FAULTS = [
    ("stiffening without the data", "modal_damping = 0.02", "modal_damping = 0.02\ngeometric_stiffening = true",
     ["body 'clamped'", "preprocess it with --geometric-stiffness"], "geometric_stiffening"),
    ("unknown key", "modal_damping = 0.02", "modal_dampin = 0.02",
     ["body 'clamped'", "unknown key 'modal_dampin'", "allowed: name, kind, source"], "modal_dampin"),
    ("missing key", "mass = 2.0\n", "\n", ["body 'block'", "missing required key 'mass'"], "[[body]]"),
    ("string for a number", "stiffness = 100.0", 'stiffness = "100"',
     ["spring #1", "'stiffness' must be a number [N/m], got a string ('100')"], "stiffness"),
    ("unknown body", 'frame2 = { body = "bob" }', 'frame2 = { body = "Bob" }',
     ["spring #1: 'frame2'", "unknown body 'Bob' (bodies: ground, beam, clamped, block, bob)"], "frame2"),
    ("unknown output body", 'spin = { body = "block"', 'spin = { body = "blok"',
     ["output 'spin'", "unknown body 'blok'"], "spin ="),
    ("enum", 'kind = "spherical"', 'kind = "ball"',
     ["joint #1", "'kind' must be one of 'fixed', 'spherical', 'revolute', 'prismatic'"], "ball"),
    ("negative mass", "mass = 0.3", "mass = -0.3", ["body 'bob'", "'mass' must be > 0 [kg], got -0.3"], "mass"),
    ("negative step", "dt = 1e-4", "dt = -1e-4", ["[scene]", "'dt' must be > 0 [s]"], "dt ="),
    ("zero samples", "n_out = 5", "n_out = 1", ["'n_out' must be >= 2"], "n_out"),
    ("wrong length", "velocity = [0.1, 0.0, 0.0]", "velocity = [0.1, 0.0]",
     ["body 'bob'", "'velocity' must be an array of 3 numbers [m/s]"], "velocity"),
    ("non-finite", "free_length = 0.4", "free_length = nan", ["'free_length' must be finite"], "free_length"),
    ("body file", 'source = "body"', 'source = "nobody"',
     ["body 'clamped'", "nobody' not found (source 'nobody', relative to the scene file's directory"], "nobody"),
    ("node range", "node = 7\n", "node = 54\n", ["load #1 (force)", "'node' must be in 0..53, got 54"], "node = 54"),
    ("no node there", "at = [0.25, 0.05, 0.05]", "at = [0.25, 0.05, 0.06]",
     ["output 'tip'", "no node at (0.25, 0.05, 0.06) m"], "tip ="),
    ("node group", 'nodes = "x1"', 'nodes = "x2"',
     ["load #3 (distributed)", "no node group 'x2' (groups: body, x0, x1, y0, y1, z0, z1)"], "x2"),
    ("mode count", "q_f = [1e-4, 0.0, -1e-4]", "q_f = [1e-4, 0.0]",
     ["body 'beam'", "'q_f' needs one value per selected mode (3), got 2"], "q_f"),
    ("mode index", "modes = [0, 2, 3]", "modes = [0, 2, 6]", ["body 'beam'", "mode list [0, 2, 6]"], "modes"),
    ("rotation matrix", "[0.0, 0.0, 1.0]]", "[0.0, 0.0, 2.0]]", ["'orientation' must be a rotation matrix"],
     "orientation"),
    ("free-frame key", "modal_damping = 0.02", "modal_damping = 0.02\nangular_velocity = [0.0, 0.0, 1.0]",
     ["body 'clamped'", "'angular_velocity' applies to a free frame only"], "angular_velocity"),
    ("integrator option", "rho_inf = 0.8", "theta = 0.8",
     ["options of integrator 'generalized-alpha'", "unknown key 'theta' (allowed: rho_inf, tol, max_iter)"], "theta"),
    ("option range", "rho_inf = 0.8", "rho_inf = 1.5", ["rho_inf must lie in [0, 1], got 1.5"], "rho_inf"),
    ("integrator", 'integrator = "generalized-alpha"', 'integrator = "euler"',
     ["'integrator' must be one of 'moreau', 'moreau-adaptive', 'generalized-alpha', 'rk4'"], "euler"),
    ("component", 'component = "y"', 'component = "w"', ["output 'tip_u'", "'component' must be one of 'x', 'y', 'z'"],
     "tip_u"),
    ("table rows", "values = [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]]", "values = [[0.0, 1.0, 0.0]]",
     ["load #1 (force): 'force' table", "1 rows of 'values' for 2 'times'"], "values"),
    ("joint axis", 'kind = "spherical"', 'kind = "spherical"\naxis = [1.0, 0.0, 0.0]',
     ["joint #1", "a spherical joint takes no 'axis'"], "axis"),
    ("duplicate body", 'name = "bob"', 'name = "block"', ["a second body named 'block'"], 'name = "block"'),
    ("top-level key", "[outputs]", "[output]", ["unknown key 'output' (allowed: scene, body, spring"], "[output]"),
    ("array of tables", "[[spring]]", "[spring]",
     ["'spring' must be an array of tables: write each spring as [[spring]]"], "[spring]"),
    ("node on a rigid body", 'frame2 = { body = "block" }', 'frame2 = { body = "block", node = 1 }',
     ["joint #1: 'frame2'", "'node' needs a flexible body; 'block' is a rigid body (use 'point')"], "frame2"),
    ("inertia", "inertia = [0.01, 0.02, 0.03]", "inertia = [[0.01, 0.0, 0.0], [0.001, 0.02, 0.0], [0.0, 0.0, 0.03]]",
     ["body 'block'", "'inertia' must be symmetric"], "inertia"),
]


@pytest.mark.parametrize("what, old, new, fragments, on_line", FAULTS, ids=[f[0] for f in FAULTS])
def test_faults_name_file_line_and_key(body_dir, sink_text, what, old, new, fragments, on_line):
    assert sink_text.count(old) == 1, f"fixture text {old!r} is not unique"
    text = sink_text.replace(old, new)
    path = body_dir.parent / "faulty.toml"
    path.write_text(text)
    with pytest.raises(InputFileError) as info:
        read_scene(path)
    error = info.value
    assert error.path == str(path)
    for fragment in fragments:
        assert fragment in error.fault, error.fault
    assert error.line is not None and on_line in text.splitlines()[error.line - 1], (error.line, str(error))


def test_syntax_errors_carry_the_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[scene]\nt_end = 1.0\ndt = 1e-3 1e-4\n')
    with pytest.raises(InputFileError, match=r"bad.toml, line 3: TOML syntax error") as info:
        read_scene(path)
    assert info.value.line == 3
    path.write_text('[scene]\nt_end = 1.0\n[scene]\n')
    with pytest.raises(InputFileError, match="TOML syntax error") as info:
        read_scene(path)
    assert info.value.line == 3
    path.write_bytes(b'[scene]\nname = "caf\xe9"\n')
    with pytest.raises(InputFileError, match="not UTF-8") as info:
        read_scene(path)
    assert info.value.line == 2
    with pytest.raises(InputFileError, match="file not found"):
        read_scene(tmp_path / "none.toml")
    with pytest.raises(InputFileError, match="file not found"):
        load_scene(tmp_path / "none.toml")


def test_scene_table_and_a_body_are_required(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[[body]]\nname = "p"\nkind = "point_mass"\nmass = 1.0\n')
    with pytest.raises(InputFileError, match=r"missing required table 'scene'"):
        read_scene(path)
    path.write_text('[scene]\nt_end = 1.0\ndt = 0.1\n')
    with pytest.raises(InputFileError, match=r"no bodies: 'body' needs at least one \[\[body\]\] table"):
        read_scene(path)
    path.write_text('[scene]\nt_end = 1.0\ndt = 0.1\n[[body]]\nname = "p"\nkind = "point_mass"\nmass = 1.0\n')
    scene = read_scene(path)
    assert (scene.name, scene.integrator, scene.n_out, scene.energies, scene.plan, scene.tolerance) == \
        ("s", "moreau", 101, True, True, None)          # the documented defaults


def test_a_bad_body_file_is_named_with_its_line_and_the_scene(tmp_path, body_dir):
    import shutil

    copy = tmp_path / "body"
    shutil.copytree(body_dir, copy)
    (copy / "body.h5").unlink()                         # the text files are read
    lines = (copy / "mij.dat").read_text().splitlines()
    lines[4] = "heavy\t% node: 5"
    (copy / "mij.dat").write_text("\n".join(lines) + "\n")
    path = tmp_path / "s.toml"
    path.write_text('[scene]\nt_end = 1.0\ndt = 0.1\n[[body]]\nname = "b"\nkind = "flexible"\nsource = "body"\n')
    with pytest.raises(InputFileError) as info:
        read_scene(path)
    assert info.value.path == str(copy / "mij.dat") and info.value.line == 5
    assert "cannot parse number 'heavy'" in info.value.fault and f"body 'b' of scene file {path}" in info.value.fault


def test_nothing_is_built_when_a_late_entry_is_wrong(body_dir, sink_text, monkeypatch):
    """A fault in the last table stops the reading before any body, link or contour is
    made."""
    made = []
    for name in ("FlexibleBodyFFR", "RigidBody", "PointMass", "SpringDamper", "Joint", "Force"):
        cls = getattr(mbs, name)
        monkeypatch.setattr(cls, "__init__", lambda self, *a, _o=cls.__init__, _n=name, **k:
                            made.append(_n) or _o(self, *a, **k))
    path = body_dir.parent / "late.toml"
    path.write_text(sink_text.replace('quantity = "q_f"', 'quantity = "modes"'))
    with pytest.raises(InputFileError, match="'quantity' must be one of"):
        read_scene(path)
    assert made == []
    path.write_text(sink_text)
    read_scene(path)
    assert made.count("FlexibleBodyFFR") == 2 and "SpringDamper" in made      # the counting works


# --- 1s contours on a feature edge of an unstructured mesh (issue 20) ------------------------------


@pytest.fixture(scope="module")
def rim_scene(tmp_path_factory):
    """A steel cylinder (radius 50 mm, length 100 mm, unstructured tet4, 3 free-free modes,
    frame fixed) and a ball of radius 5 mm falling at 0.2 m/s from 1 mm above the band on
    its top rim ``rim1`` (a gmsh physical curve), 2 mm inside the rim. Returns (the scene
    file's text, its path, the rest height of the ball's centre [m]). The same body without
    its surface triangles is written to ``bare/``."""
    directory = tmp_path_factory.mktemp("rim")
    data = build_body(cylinder_mesh(0.02, 1), Material(7800.0, 2.1e11, 0.3), n_modes=3)
    write_body(directory / "rim", data)
    write_body(directory / "bare", dataclasses.replace(data, surface_triangles=None))    # no surface to walk
    text = fixture_text("scenes/ball_on_cylinder_rim.toml")
    doc = tomllib.loads(text)
    rest = LENGTH + doc["contact"][0]["contour1"]["radius"]
    assert doc["body"][1]["position"] == pytest.approx([RADIUS - 0.002, 0.0, rest + 1e-3])     # as said above
    path = directory / "rim.toml"
    path.write_text(text)
    return text, path, rest


def test_band_on_an_unstructured_rim_catches_a_ball(rim_scene):
    """The group ``rim1`` is walked into a closed band; the ball lands on it (at about 5 ms)
    and rests at the height of a sphere on the flat top face, one radius above z = LENGTH
    (the band is exact in that plane; the steel deflects by nanometres), within the
    impact step's travel v·Δt (Moreau closes the contact at the midpoint of the step,
    after up to one step of penetration); free fall would have taken it 2 mm below."""
    _, path, rest = rim_scene
    scene = read_scene(path)
    (contact,) = scene.system.contacts
    band = contact.kinematics.contour2
    assert isinstance(band, FlexibleBand) and band.neutral.space.eta.interp.closed
    result = simulate(scene, scene.outputs, scene.t_end, scene.n_out)
    z = result["ball"][:, 2]
    free_fall = rest + 1e-3 - 0.2 * scene.t_end - 0.5 * 9.81 * scene.t_end ** 2
    assert free_fall < rest - 2e-3
    v_impact = np.hypot(0.2, np.sqrt(2.0 * 9.81 * 1e-3))
    assert z[-1] == pytest.approx(rest, abs=v_impact * scene.dt)
    assert z[-1] == pytest.approx(z[-2], abs=1e-9)                     # at rest from t = 10 ms


@pytest.mark.parametrize("old, new, fragment, line", [
    ('contour2.nodes = "rim1"', 'contour2.nodes = "base"',
     "contact 'on the rim': contour2 (band): node group 'base' is not a line of surface nodes: node",
     'contour2.nodes = "base"'),
    ('source = "rim/body.h5"', 'source = "bare/body.h5"',
     "contact 'on the rim': contour2 (band): body 'cylinder' has no surface triangles in its body file, so node "
     "group 'rim1' cannot be ordered", 'contour2.nodes = "rim1"'),
    ('contour2.width = 0.01', 'contour2.width = 0.01\ncontour2.closed = false',
     "contact 'on the rim': contour2 (band): 'closed = false' but node group 'rim1' is a closed loop of surface "
     "edges: omit 'closed'", "contour2.closed = false"),
    ('kind = "sphere", body = "ball", radius = 0.005 }\ncontour2.kind = "band"\ncontour2.body = "cylinder"\n'
     'contour2.nodes = "rim1"\ncontour2.normal = [0.0, 0.0, 1.0]\ncontour2.degree = 4\ncontour2.width = 0.01',
     'kind = "point", body = "ball" }\ncontour2.kind = "edge"\ncontour2.body = "cylinder"\n'
     'contour2.nodes = "rim1"\ncontour2.normal = [0.0, 0.0, 1.0]',
     "contact 'on the rim': law 'impact' has no kinematics for contour1 kind 'point' and contour2 kind 'edge' "
     "(contour1/contour2 kinds it takes:", 'law = "impact"'),     # a point never touches an edge: a sphere does
])
def test_faults_of_an_edge_group_name_their_key(rim_scene, old, new, fragment, line):
    text, path, _ = rim_scene
    assert_fault_at(path.with_name("rim-fault.toml"), text, old, new, fragment, line)


def test_outputs_say_what_they_are(body_dir, sink_path):
    """Each output's label names the body, the node (the one nearest to ``at``), the point,
    the quantity and the component, as the plot's panel titles show them."""
    scene = read_scene(sink_path)
    u0 = read_body(body_dir / "body.h5").u0
    nearest = int(np.argmin(np.linalg.norm(u0 - [0.25, 0.05, 0.05], axis=1)))
    assert scene.labels == {"tip": f"beam node {nearest} (nearest to (0.25, 0.05, 0.05) m) position", "tip_v": "beam node 7 velocity",
                            "tip_u": "clamped node 7 displacement y", "spin": "block angular velocity",
                            "modal": "beam modal coordinates q_f", "bob": "bob point (0, 0, 0.1) m position"}


NODE_POINT = fixture_text("scenes/beam_block_bob.toml") + """
[[contact]]
name = "tip on floor"
contour1 = { kind = "point", body = "beam", node = 5, residual_flexibility = true }
contour2 = { kind = "plane", point = [0.0, -1.0, 0.0], normal = [0.0, 1.0, 0.0] }
law = "impact"

[[contact]]
name = "ball at a node"
contour1 = { kind = "sphere", body = "beam", at = [0.25, 0.05, 0.05], radius = 0.01, residual_flexibility = true }
contour2 = { kind = "plane", point = [0.0, 1.0, 0.0], normal = [0.0, -1.0, 0.0] }
law = "impact"
"""


def test_a_point_or_sphere_at_a_node_takes_residual_flexibility(body_dir):
    from contours.residual import NodeCompliance
    from mbs.run.residual_contact import ResidualContacts

    path = body_dir.parent / "node-points.toml"
    path.write_text(NODE_POINT)
    contacts = read_scene(path).system.contacts[-2:]
    tip, ball = (c.kinematics.contour1 for c in contacts)
    assert tip.residual_flexibility and tip.frame_ref.node_index == 5
    assert ball.residual_flexibility and ball.frame_ref.node_index is not None
    compliances = ResidualContacts(contacts, [True, True]).compliances
    assert all(isinstance(compliances[id(c)], NodeCompliance) for c in (tip, ball))
    assert_fault_at(body_dir.parent / "node-points-fault.toml", NODE_POINT,
                    'body = "beam", node = 5, residual_flexibility = true',
                    'body = "beam", point = [0.25, 0.05, 0.0], residual_flexibility = true',
                    "contact 'tip on floor': contour1 (point): residual flexibility needs the point at a 'node'",
                    'contour1 = { kind = "point", body = "beam", point = [0.25, 0.05, 0.0], '
                    'residual_flexibility = true }')
