"""Loads: time tables, forces and torques on frames, distributed and nodal loads, force files.

Oracles: sums of Heaviside steps (report eq. 9) and np.interp for tables; virtual power
(Q·u = F·ṙ, Q·u = τ·ω with independently computed velocities) for single loads; the
brute-force per-node sum Σ_j J_T,jᵀ F_j for distributed and nodal loads; hand-written
files for the reader.
"""

import os

import numpy as np
import pytest

from ffrmbs.errors import InputFileError, ModelError
from mbs.bodies.body import ground_frame
from mbs.bodies.flexible_body import FlexibleBodyFFR
from mbs.bodies.floating_frame import PrescribedFrameMotion
from mbs.links.force_file import read_force_file, write_force_file
from mbs.links.loads import DistributedForce, Force, NodalForces, Tabulated, Torque
from mbs.bodies.rigid_body import RigidBody
from mbs.bodies.rotations import cardan_to_matrix
from mbs.system import System
from preprocess import box, build_body, face_load
from validation.cases.cantilever import MATERIAL

ROT_Z90 = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # e_x -> e_y


@pytest.fixture(scope="module")
def beam():
    """(mesh, BodyData) of a coarse free-free 1 x 1 x 5 m tet10 beam with 6 modes."""
    mesh = box(1.0, 1.0, 5.0, 1.0, order=2)
    return mesh, build_body(mesh, MATERIAL, 6, clamp=None)


def moving_frame():
    """A prescribed frame that translates and turns about a tilted axis."""
    axis = np.array([1.0, 2.0, 2.0]) / 3.0

    def rotation(t):
        a = 0.7 + 1.3 * t
        K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        A = np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
        return A, 1.3 * axis, np.zeros(3)

    return PrescribedFrameMotion(lambda t: (np.array([0.3, -0.2, 1.0 + t]), np.array([0, 0, 1.0]),
                                            np.zeros(3)), rotation)


def flexible_in_system(data, rotation="quaternion", frame="free", seed=0):
    """(system, body, q, u): the body alone in a System at a random state with small q_f."""
    rng = np.random.default_rng(seed)
    body = FlexibleBodyFFR(data, modes=6, rotation=rotation, frame=frame)
    q_f = 0.1 * rng.standard_normal(6)
    if body.is_free:
        body.set_initial(R=rng.standard_normal(3), A=cardan_to_matrix(rng.uniform(-1, 1, 3)), q_f=q_f)
    else:
        body.set_initial(q_f=q_f)
    system = System()
    system.add(body)
    q, _ = system.initial_state()
    return system, body, q, rng.standard_normal(system.nu)


def generalized_force(element, system, t, q, u=None):
    h = np.zeros(system.nu)
    element.add_forces(t, q, np.zeros(system.nu) if u is None else u, h)
    return h


def assert_rel(actual, expected, rtol):
    err = np.linalg.norm(actual - expected) / np.linalg.norm(expected)
    assert err <= rtol, f"relative error {err:.3e} > {rtol:.1e}"


# --- Tabulated --------------------------------------------------------------------------

def test_step_table_is_the_sum_of_heaviside_steps():
    times = np.array([0.0, 0.1, 0.25, 0.7])
    values = np.array([[1.0, -2.0], [3.0, 0.5], [-1.0, 4.0], [2.0, 2.0]])
    table = Tabulated(times, values, kind="step")
    jumps = np.diff(values, axis=0, prepend=np.zeros((1, 2)))        # Δf_j, f_{-1} = 0
    for t in [-0.5, 0.0, 0.05, 0.1, 0.2, 0.25, 0.69, 0.7, 3.0]:
        expected = np.zeros(2) + sum(dfj for tj, dfj in zip(times, jumps) if t >= tj)  # Σ h(t − t_j) Δf_j
        np.testing.assert_array_equal(table(t), expected)


def test_linear_table_interpolates_and_holds_the_ends():
    times = np.array([1.0, 2.0, 4.0])
    values = np.array([2.0, -1.0, 5.0])
    table = Tabulated(times, values, kind="linear")
    for t in [1.0, 1.3, 2.0, 3.1, 4.0, 9.0]:
        assert table(t) == pytest.approx(np.interp(t, times, values), rel=1e-15)
    assert table(0.5) == 0.0
    assert Tabulated(times, values, kind="linear", hold_first=True)(0.5) == 2.0
    assert Tabulated(times, values, kind="step", hold_first=True)(0.5) == 2.0


@pytest.mark.parametrize("times, values, kind, match", [
    ([0.0, 0.2, 0.2], [1.0, 2.0, 3.0], "step", "increase strictly"),
    ([0.0, 0.3, 0.2], [1.0, 2.0, 3.0], "step", r"times\[2\] = 0.2 s follows times\[1\] = 0.3"),
    ([0.0, 0.2], [1.0, 2.0, 3.0], "step", "to match the times"),
    ([0.0, 0.2], [1.0, 2.0], "cubic", "kind must be one of"),
])
def test_table_errors(times, values, kind, match):
    with pytest.raises(ModelError, match=match):
        Tabulated(times, values, kind=kind)


# --- Force and Torque on one frame ------------------------------------------------------

@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
def test_force_does_the_virtual_power_of_its_point(beam, rotation):
    """Q·u = F·ṙ for constant, callable and tabulated forces in inertial components."""
    system, body, q, u = flexible_in_system(beam[1], rotation)
    rigid = system.add(RigidBody(2.0, np.diag([1.0, 2.0, 3.0]), rotation=rotation))
    q = np.concatenate((q, rigid.q_init + np.r_[0.1, 0.2, 0.3, np.zeros(rigid.nq - 3)]))
    u = np.concatenate((u, np.ones(6)))
    node, point = body.node(17), rigid.frame_at((0.5, -0.2, 0.1))
    table = Tabulated([0.0, 1.0], [[1.0, 2.0, 3.0], [-4.0, 5.0, 0.5]])
    for frame, force, t, F in [
        (node, (3.0, -1.0, 2.0), 0.0, np.array([3.0, -1.0, 2.0])),
        (node, lambda t: np.array([np.sin(t), 0.0, t]), 0.4, np.array([np.sin(0.4), 0.0, 0.4])),
        (point, table, 1.5, np.array([-4.0, 5.0, 0.5])),
    ]:
        Q = generalized_force(Force(frame, force), system, t, q)
        v = frame.velocity(q[frame.body.q_slice], u[frame.body.u_slice])
        assert Q @ u == pytest.approx(F @ v, rel=1e-12)


def test_frame_fixed_force_and_torque_turn_with_the_body():
    """A body turned 90° about z: body-frame x components act along inertial y."""
    rigid = RigidBody(1.0, np.eye(3)).set_initial(A=ROT_Z90)
    system = System()
    system.add(rigid)
    q, _ = system.initial_state()
    frame = rigid.frame_at((0.3, 0.4, -0.2))
    np.testing.assert_allclose(generalized_force(Force(frame, (2.0, 0, 0), frame_fixed=True), system, 0, q),
                               generalized_force(Force(frame, (0, 2.0, 0)), system, 0, q), atol=1e-15)
    np.testing.assert_allclose(generalized_force(Torque(frame, (2.0, 0, 0), frame_fixed=True), system, 0, q),
                               generalized_force(Torque(frame, (0, 2.0, 0)), system, 0, q), atol=1e-15)


@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
def test_torque_does_the_virtual_power_of_the_rotation(rotation):
    """Q·u = τ·ω with τ = A τ̄ for body-axis components."""
    rigid = RigidBody(1.0, np.eye(3), rotation=rotation).set_initial(
        A=cardan_to_matrix((0.2, -0.4, 0.9)), omega=(0.3, -1.0, 2.0), v=(1.0, 0.0, 0.5))
    system = System()
    system.add(rigid)
    q, u = system.initial_state()
    A = cardan_to_matrix((0.2, -0.4, 0.9))
    omega = np.array([0.3, -1.0, 2.0])
    tau = np.array([1.0, -2.0, 0.7])
    assert generalized_force(Torque(rigid.origin, tau), system, 0, q) @ u == pytest.approx(tau @ omega)
    assert (generalized_force(Torque(rigid.origin, tau, frame_fixed=True), system, 0, q) @ u
            == pytest.approx((A @ tau) @ omega))


def test_load_errors():
    rigid = RigidBody(1.0, np.eye(3))
    with pytest.raises(ModelError, match="fixed in the inertial frame"):
        Force(ground_frame(), (1.0, 0, 0))
    with pytest.raises(ModelError, match="fixed in the inertial frame"):
        Torque(ground_frame(), (1.0, 0, 0))
    with pytest.raises(ModelError, match="3 finite components"):
        Force(rigid.origin, (1.0, 2.0))
    with pytest.raises(ModelError, match="3 values per time"):
        Force(rigid.origin, Tabulated([0.0], [1.0]))
    bad = Force(rigid.origin, lambda t: np.zeros(2))
    with pytest.raises(ModelError, match=r"returned shape \(2,\) at t = 0.5 s"):
        bad.force(0.5)


# --- DistributedForce ---------------------------------------------------------------------

@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
@pytest.mark.parametrize("frame_fixed", [True, False])
def test_distributed_force_equals_the_per_node_sum(beam, rotation, frame_fixed):
    mesh, data = beam
    system, body, q, _ = flexible_in_system(data, rotation, seed=3)
    nodes = body.node_group("z1")
    weights = face_load(mesh, nodes, [1.0, 0.0, 0.0])[nodes, 0]
    F = np.array([300.0, -120.0, 45.0])
    Q = generalized_force(DistributedForce(body, nodes, weights, F, frame_fixed), system, 0.0, q)
    qb = q[body.q_slice]
    F_in = body.orientation(qb) @ F if frame_fixed else F
    brute = sum(w * body.node(j).J_T(qb).T @ F_in for j, w in zip(nodes, weights))
    assert_rel(Q, brute, 1e-12)


def test_distributed_force_accepts_a_group_name(beam):
    system, body, q, _ = flexible_in_system(beam[1], seed=4)
    nodes = body.node_group("x1")
    weights = np.full(nodes.size, 1.0 / nodes.size)
    by_name = generalized_force(DistributedForce(body, "x1", weights, (0, 0, 5.0)), system, 0, q)
    by_index = generalized_force(DistributedForce(body, nodes, weights, (0, 0, 5.0)), system, 0, q)
    np.testing.assert_array_equal(by_name, by_index)


def test_distributed_force_errors(beam):
    body = FlexibleBodyFFR(beam[1], modes=6)
    nodes = body.node_group("z1")
    with pytest.raises(ModelError, match="sum to 2.0, not 1"):
        DistributedForce(body, nodes[:2], [1.5, 0.5], (1, 0, 0))
    with pytest.raises(ModelError, match=f"580 weights for {nodes.size} nodes"):
        DistributedForce(body, nodes, np.ones(580) / 580, (1, 0, 0))
    with pytest.raises(ModelError, match="node indices must lie in 0..579"):
        DistributedForce(body, [0, 580], [0.5, 0.5], (1, 0, 0))
    with pytest.raises(ModelError, match="acts on a FlexibleBodyFFR"):
        DistributedForce(RigidBody(1.0, np.eye(3)), [0], [1.0], (1, 0, 0))


# --- NodalForces ----------------------------------------------------------------------------

@pytest.mark.parametrize("rotation, frame", [("quaternion", "free"), ("cardan", "free"),
                                             ("quaternion", "moving")])
@pytest.mark.parametrize("frame_fixed", [True, False])
def test_nodal_forces_equal_the_per_node_sum(beam, rotation, frame, frame_fixed):
    data = beam[1]
    system, body, q, _ = flexible_in_system(data, rotation, moving_frame() if frame == "moving" else "free", seed=5)
    rng = np.random.default_rng(6)
    times = np.array([0.0, 0.2, 0.5])
    forces = rng.standard_normal((3, data.n_nodes, 3)) * [[[10.0, 1.0, 100.0]]]
    element = NodalForces(body, times, forces, frame_fixed)
    qb = q[body.q_slice]
    assert not generalized_force(element, system, -0.1, q).any()
    for t, row in [(0.0, 0), (0.3, 1), (0.5, 2), (7.0, 2)]:
        D = body.orientation(qb, t) if frame_fixed else np.eye(3)
        brute = sum(body.node(j).J_T(qb, t).T @ (D @ forces[row, j]) for j in range(data.n_nodes))
        assert_rel(generalized_force(element, system, t, q), brute, 1e-12)


def test_nodal_forces_shape_error(beam):
    body = FlexibleBodyFFR(beam[1], modes=6)
    with pytest.raises(ModelError, match=r"shape \(2, 580, 3\)"):
        NodalForces(body, [0.0, 1.0], np.zeros((2, 579, 3)))
    with pytest.raises(ModelError, match="increase strictly"):
        NodalForces(body, [1.0, 0.0], np.zeros((2, 580, 3)))


# --- force files ------------------------------------------------------------------------

def blocked_mask(n_nodes, clamped_nodes):
    mask = np.zeros(3 * n_nodes, dtype=bool)
    for j in clamped_nodes:
        mask[3 * j:3 * j + 3] = True
    return mask


def test_read_hand_written_file(tmp_path):
    """Two nodes, node 0 clamped in y: rows are DOFs 0 (x0), 2 (z0), 3, 4, 5; tabs,
    runs of blanks and trailing blank lines are tolerated."""
    path = tmp_path / "force.txt"
    path.write_text("0.0 0.5  1.0\n1 2 3\n4\t5 6\n  7 8 9  \n10 11 12\n13 14 15\n\n   \n")
    times, forces = read_force_file(path, 2, blocked_dofs=[1])
    np.testing.assert_array_equal(times, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(forces[:, 0], [[1, 0, 4], [2, 0, 5], [3, 0, 6]])
    np.testing.assert_array_equal(forces[:, 1], [[7, 10, 13], [8, 11, 14], [9, 12, 15]])


@pytest.mark.parametrize("blocked", [None, "mask", "indices"])
def test_force_file_round_trip(tmp_path, blocked):
    rng = np.random.default_rng(7)
    n_nodes = 6
    times = np.cumsum(rng.uniform(0.01, 0.1, 5))
    forces = rng.standard_normal((5, n_nodes, 3)) * 1e3
    mask = blocked_mask(n_nodes, [0, 4])
    mask[7] = True
    forces.reshape(5, -1)[:, mask] = 0.0
    blocked_dofs = {None: None, "mask": mask, "indices": np.flatnonzero(mask)}[blocked]
    path = tmp_path / "forces.txt"
    write_force_file(path, times, forces, blocked_dofs)
    n_rows = len(path.read_text().splitlines())
    assert n_rows == 1 + (3 * n_nodes if blocked is None else 3 * n_nodes - 7)
    times_back, forces_back = read_force_file(path, n_nodes, blocked_dofs)
    np.testing.assert_array_equal(times_back, times)
    np.testing.assert_array_equal(forces_back, forces)
    assert os.listdir(tmp_path) == ["forces.txt"]


def test_nodal_forces_from_file(tmp_path, beam):
    data = beam[1]
    system, body, q, _ = flexible_in_system(data, seed=8)
    rng = np.random.default_rng(9)
    forces = rng.standard_normal((2, data.n_nodes, 3))
    mask = blocked_mask(data.n_nodes, body.node_group("z0"))
    forces.reshape(2, -1)[:, mask] = 0.0
    write_force_file(tmp_path / "f.txt", [0.0, 0.1], forces, mask)
    from_file = NodalForces.from_file(body, tmp_path / "f.txt", mask)
    direct = NodalForces(body, [0.0, 0.1], forces)
    np.testing.assert_array_equal(generalized_force(from_file, system, 0.05, q),
                                  generalized_force(direct, system, 0.05, q))


@pytest.mark.parametrize("text, line, fault", [
    ("0 1\n1 2\n3 x\n4 5\n", 3, r"entry 2 \('x'\) is not a number"),
    ("0 1\n1 2\n3 nan\n4 5\n", 3, r"entry 2 \('nan'\) is not finite"),
    ("0 1\n1 2\n3 4 5\n4 5\n", 3, r"3 entries, but the times row \(line 1\) has 2"),
    ("0 1\n1 2\n3 4\n4 5\n6 7\n", 5, r"1 row\(s\) too many: expected 1 row of times \+ 3 rows"),
    ("0 1\n1 2\n\n3 4\n", 5, r"the file ends after 2 rows of forces: expected 1 row of times \+ 3"),
    ("0 1 1\n1 2 3\n3 4 5\n4 5 6\n", 1, r"times must increase strictly, but entry 3 \(1.0\) follows entry 2 \(1.0\)"),
    ("\n0 2 1\n1 2 3\n3 4 5\n4 5 6\n", 2, r"times must increase strictly"),
])
def test_force_file_errors_name_path_and_line(tmp_path, text, line, fault):
    """One node, nothing blocked: a row of times and 3 rows of forces expected."""
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(InputFileError, match=f"bad.txt, line {line}: {fault}") as info:
        read_force_file(path, 1)
    assert info.value.line == line and info.value.path == str(path)


def test_force_file_whole_file_errors(tmp_path):
    with pytest.raises(InputFileError, match="missing.txt: file not found"):
        read_force_file(tmp_path / "missing.txt", 1)
    (tmp_path / "empty.txt").write_text("\n  \n")
    with pytest.raises(InputFileError, match="empty.txt: empty file"):
        read_force_file(tmp_path / "empty.txt", 1)


def test_blocked_dofs_errors(tmp_path):
    (tmp_path / "f.txt").write_text("0\n1\n2\n3\n")
    with pytest.raises(ModelError, match=r"needs 3 x 1 = 3 entries, got shape \(2,\)"):
        read_force_file(tmp_path / "f.txt", 1, np.array([True, False]))
    with pytest.raises(ModelError, match=r"must lie in 0..2"):
        read_force_file(tmp_path / "f.txt", 1, [3])


def test_write_refuses_forces_on_blocked_dofs(tmp_path):
    forces = np.zeros((1, 2, 3))
    forces[0, 1, 2] = 5.0
    with pytest.raises(ModelError, match=r"DOF 5 \(node 1, direction z\) is blocked"):
        write_force_file(tmp_path / "f.txt", [0.0], forces, [5])
    assert os.listdir(tmp_path) == []
