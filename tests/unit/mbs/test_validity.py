"""mbs.bodies.validity.SpinMonitor against an independent ω1 and hand-set spins: no warning below
ratio · ω1, exactly one above, one event per body, frames that cannot rotate ignored."""

import logging
import warnings

import numpy as np
import pytest
import scipy.linalg
from scipy.spatial.transform import Rotation

from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, PrescribedFrameMotion, RigidBody, System
from mbs.bodies.validity import SPIN_RATIO, FFRValidityWarning, SpinMonitor
from preprocess import Material, box, build_body

STEEL = Material(7850.0, 210e9, 0.3)


@pytest.fixture(scope="module")
def beam_data():
    """A 50 x 50 mm x 1 m steel cantilever, tet4, 3 clamped modes."""
    return build_body(box(0.05, 0.05, 1.0, None, order=1, divisions=(1, 1, 10)), STEEL, 3, clamp="z0")


@pytest.fixture(scope="module")
def free_data():
    return build_body(box(0.05, 0.05, 1.0, None, order=1, divisions=(1, 1, 10)), STEEL, 3, clamp=None)


def omega1_independent(data, modes):
    """ω1 [rad/s] from Φᵀ K Φ and Φᵀ M Φ assembled here from the FE data (lumped M)."""
    phi = data.phi[:, modes]
    K = phi.T @ (data.stiffness @ phi)
    M = phi.T @ (np.repeat(data.masses, 3)[:, None] * phi)
    return float(np.sqrt(scipy.linalg.eigh(0.5 * (K + K.T), M, eigvals_only=True)[0]))


def constant_spin(omega):
    """Prescribed frame spinning at ω [rad/s] about body x."""
    zero = np.zeros(3)
    return PrescribedFrameMotion(lambda t: (zero, zero, zero),
                                 lambda t: (Rotation.from_rotvec([omega * t, 0, 0]).as_matrix(),
                                            np.array([omega, 0.0, 0.0]), zero))


def checks(monitor, system, times):
    q, u = system.initial_state()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        for t in times:
            monitor.check(t, q, u)
    return [w for w in seen if issubclass(w.category, FFRValidityWarning)]


def test_omega1_is_the_lowest_retained_frequency(beam_data):
    system = System()
    system.add(FlexibleBodyFFR(beam_data, [1, 2], frame=constant_spin(1.0), name="b"))
    monitor = SpinMonitor(system)
    expected = omega1_independent(beam_data, [1, 2])
    assert monitor.omega1["b"] == pytest.approx(expected, rel=1e-9)
    assert expected == pytest.approx(np.sqrt(beam_data.modal_eigenvalues()[1]), rel=1e-6)   # preprocess agrees


@pytest.mark.parametrize("factor, n_warnings", [(0.99, 0), (1.01, 1)])
def test_prescribed_spin_warns_once_above_the_ratio(beam_data, factor, n_warnings, caplog):
    w1 = omega1_independent(beam_data, [0, 1, 2])
    system = System()
    system.add(FlexibleBodyFFR(beam_data, 3, frame=constant_spin(factor * SPIN_RATIO * w1), name="spun"))
    monitor = SpinMonitor(system)
    with caplog.at_level(logging.WARNING, logger="ffrmbs.validity"):
        seen = checks(monitor, system, np.linspace(0.0, 1.0, 50))
    assert len(seen) == n_warnings and len(monitor.events) == n_warnings
    assert len([r for r in caplog.records if r.name == "ffrmbs.validity"]) == n_warnings
    if n_warnings:
        t, name, spin, w1_event = monitor.events[0]
        assert (t, name) == (0.0, "spun")
        assert spin == pytest.approx(factor * SPIN_RATIO * w1, rel=1e-12)
        assert w1_event == pytest.approx(w1, rel=1e-9)
        message = str(seen[0].message)
        assert "'spun'" in message and "t = 0 s" in message and f"{SPIN_RATIO:g} ω1" in message


@pytest.mark.parametrize("rotation", ["quaternion", "cardan"])
def test_free_body_spin_from_its_state(free_data, rotation):
    """A free frame: |Ω| from q, u (ω̄ itself for quaternions, Ḡ θ̇ for Cardan angles),
    set through set_initial with a tilted orientation and an oblique inertial ω."""
    w1 = omega1_independent(free_data, [0, 1, 2])
    direction = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    for factor, n_warnings in ((0.98, 0), (1.02, 1)):
        system = System()
        body = system.add(FlexibleBodyFFR(free_data, 3, rotation=rotation, name="free"))
        body.set_initial(A=Rotation.from_euler("XYZ", [0.3, 0.4, -0.2]).as_matrix(),
                         omega=factor * SPIN_RATIO * w1 * direction)
        monitor = SpinMonitor(system)
        seen = checks(monitor, system, [0.0, 0.1, 0.2])
        assert len(seen) == n_warnings and len(monitor.events) == n_warnings


def test_one_event_per_body_and_custom_ratio(beam_data):
    w1 = omega1_independent(beam_data, [0, 1, 2])
    system = System()
    system.add(FlexibleBodyFFR(beam_data, 3, frame=constant_spin(0.5 * w1), name="a"))
    system.add(FlexibleBodyFFR(beam_data, 3, frame=constant_spin(0.3 * w1), name="b"))
    monitor = SpinMonitor(system, ratio=0.4)
    seen = checks(monitor, system, np.linspace(0.0, 1.0, 20))
    assert [e[1] for e in monitor.events] == ["a"] and len(seen) == 1
    monitor = SpinMonitor(system, ratio=0.25)
    seen = checks(monitor, system, np.linspace(0.0, 1.0, 20))
    assert sorted(e[1] for e in monitor.events) == ["a", "b"] and len(seen) == 2


def test_a_restored_monitor_warns_only_the_bodies_that_had_not_warned(beam_data):
    """Events taken from a checkpoint (SpinMonitor.restore): the body that warned before
    the interruption stays silent, the other still warns once above its limit."""
    w1 = omega1_independent(beam_data, [0, 1, 2])
    system = System()
    system.add(FlexibleBodyFFR(beam_data, 3, frame=constant_spin(0.5 * w1), name="a"))
    system.add(FlexibleBodyFFR(beam_data, 3, frame=constant_spin(0.5 * w1), name="b"))
    before = (0.25, "a", 0.5 * w1, w1)
    monitor = SpinMonitor(system, ratio=0.4)
    monitor.restore([before])
    seen = checks(monitor, system, [0.5, 0.75])
    assert [e[1] for e in monitor.events] == ["a", "b"] and monitor.events[0] == before and len(seen) == 1
    assert "'b'" in str(seen[0].message)


def test_frames_that_cannot_rotate_and_rigid_bodies_are_not_watched(beam_data):
    system = System()
    system.add(FlexibleBodyFFR(beam_data, 3, frame=PrescribedFrameMotion.fixed(), name="fixed"))
    rigid = system.add(RigidBody(1.0, np.eye(3), name="rigid"))
    rigid.set_initial(omega=[1e6, 0.0, 0.0])
    monitor = SpinMonitor(system)
    assert monitor.watched == []
    assert checks(monitor, system, [0.0, 1.0]) == [] and monitor.events == []


def test_bad_ratio():
    with pytest.raises(ModelError, match="ratio"):
        SpinMonitor(System(), ratio=0.0)
