"""Rotations against scipy.spatial.transform and finite differences."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from mbs.bodies import rotations as rot
from mbs.bodies.parametrization import Cardan, Quaternion

angles = st.lists(st.floats(-3.1, 3.1), min_size=3, max_size=3).map(np.array)
quats = st.lists(st.floats(-1, 1), min_size=4, max_size=4).map(np.array).filter(
    lambda p: np.linalg.norm(p) > 0.1).map(lambda p: p / np.linalg.norm(p))


@given(quats)
def test_quaternion_matrix_matches_scipy(p):
    ref = Rotation.from_quat([p[1], p[2], p[3], p[0]]).as_matrix()
    np.testing.assert_allclose(rot.quat_to_matrix(p), ref, atol=1e-13)


@given(angles)
def test_cardan_matrix_is_intrinsic_xyz(theta):
    """Thesis eq. 2.22 equals successive rotations about x, y', z''."""
    ref = Rotation.from_euler("XYZ", theta).as_matrix()
    np.testing.assert_allclose(rot.cardan_to_matrix(theta), ref, atol=1e-13)


@given(angles, angles)
def test_cardan_G_bar_gives_body_angular_velocity(theta, theta_dot):
    """ω̄ = Ḡ θ̇ (eq. 2.30) equals the axial vector of Aᵀ Ȧ, Ȧ by central differences."""
    eps = 1e-6
    A = rot.cardan_to_matrix(theta)
    Ad = (rot.cardan_to_matrix(theta + eps * theta_dot) - rot.cardan_to_matrix(theta - eps * theta_dot)) / (2 * eps)
    W = A.T @ Ad
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    np.testing.assert_allclose(rot.cardan_G_bar(theta) @ theta_dot, omega, atol=1e-7 * (1 + np.abs(theta_dot).max()))


@given(angles, angles)
def test_cardan_G_bar_dot_by_finite_differences(theta, theta_dot):
    eps = 1e-6
    fd = (rot.cardan_G_bar(theta + eps * theta_dot) - rot.cardan_G_bar(theta - eps * theta_dot)) / (2 * eps)
    np.testing.assert_allclose(rot.cardan_G_bar_dot(theta, theta_dot), fd, atol=1e-7 * (1 + np.abs(theta_dot).max()))


@given(quats)
def test_quaternion_from_matrix_round_trip(p):
    back = rot.quat_from_matrix(rot.quat_to_matrix(p))
    assert np.allclose(back, p, atol=1e-12) or np.allclose(back, -p, atol=1e-12)


@pytest.mark.parametrize("axis", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -2, 3)])
def test_rotation_vector_recovered_at_pi(axis):
    """|θ| = π is where arccos(trace) based recoveries lose precision (report Sec. 7.2)."""
    n = np.asarray(axis, float) / np.linalg.norm(axis)
    for angle in (np.pi, np.pi - 1e-9, 1e-9, 2.0):
        A = Rotation.from_rotvec(angle * n).as_matrix()
        phi = rot.rotvec_from_matrix(A)
        np.testing.assert_allclose(Rotation.from_rotvec(phi).as_matrix(), A, atol=1e-12)
        assert abs(np.linalg.norm(phi) - angle) < 1e-9


@given(quats, st.lists(st.floats(-3, 3), min_size=3, max_size=3).map(np.array))
def test_quaternion_increment_is_exact_flow(p, w):
    """p ⊗ exp(ω̄ h / 2) solves ṗ = ½ p ⊗ (0, ω̄) for constant ω̄: A(t) = A0 exp(h ω̃)."""
    A1 = rot.quat_to_matrix(Quaternion.increment(p, 0.3 * w))
    ref = rot.quat_to_matrix(p) @ Rotation.from_rotvec(0.3 * w).as_matrix()
    np.testing.assert_allclose(A1, ref, atol=1e-12)


@given(quats, st.lists(st.floats(-3, 3), min_size=3, max_size=3).map(np.array))
def test_quaternion_rate_matches_body_angular_velocity(p, w):
    """Ȧ = A ω̃ with ṗ = Y_p ω̄ (thesis eq. 3.1a)."""
    eps = 1e-6
    pd = Quaternion.qdot(p, w)
    Ad = (rot.quat_to_matrix(p + eps * pd) - rot.quat_to_matrix(p - eps * pd)) / (2 * eps)
    np.testing.assert_allclose(Ad, rot.quat_to_matrix(p) @ rot.skew(w), atol=1e-7 * (1 + np.abs(w).max()))


@settings(max_examples=30)
@given(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.floats(-3, 3))
def test_cardan_coordinates_round_trip(a, b, g):
    theta = np.array([a, b, g])
    np.testing.assert_allclose(Cardan.coordinates(rot.cardan_to_matrix(theta)), theta, atol=1e-9)
