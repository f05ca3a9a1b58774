"""Moreau time-stepping against the analytic bouncing ball and the sliding block:
impact times, rebound heights, Zeno rest without sinking, no energy gain for e <= 1,
Coulomb deceleration and stopping distance."""

import numpy as np
import pytest

from contact.contact import Contact
from contact.kinematics import ContactKinematicsPointPlane, ContactKinematicsSpherePlane, ContactKinematicsSphereSphere
from contact.laws import (LinearRegularizedUnilateralConstraint, RegularizedCoulombFriction,
                          UnilateralCoulombContact, UnilateralNewtonImpact)
from contours import PlaneContour, PointContour, SphereContour
from ffrmbs.errors import ModelError
from mbs import PointMass, System, ground_frame

G, H0, R = 9.81, 1.0, 0.1


def bouncing_ball(e, t_end, dt, integrator="moreau", **options):
    system = System(gravity=(0, 0, -G))
    ball = system.add(PointMass(1.0, position=(0, 0, H0 + R)))
    kin = ContactKinematicsSpherePlane(SphereContour(ball.point, R), PlaneContour(ground_frame()))
    system.add(Contact(kin, UnilateralNewtonImpact(e)))
    return system.simulate(t_end, dt, integrator=integrator, energies=True, **options)


@pytest.mark.parametrize("e", [0.0, 0.7, 1.0])
def test_bouncing_ball_matches_the_analytic_impacts_and_never_gains_energy(e):
    dt = 1e-3
    res = bouncing_ball(e, 2.0, dt)
    z = res.q[:, 2] - R
    v1 = np.sqrt(2 * G * H0)
    t1 = v1 / G
    first = res.t[np.argmax(res.u[:, 2] > 0)] if e > 0 else None
    if e > 0:
        assert abs(first - t1) < 2 * dt                       # the impact time
        t2 = t1 + 2 * e * v1 / G
        after = (res.t > t1 + 2 * dt) & (res.t < t2 - 2 * dt)
        assert np.isclose(z[after].max(), (e * v1) ** 2 / (2 * G), rtol=0, atol=2 * v1 * dt)   # rebound apex
    else:
        assert np.allclose(res.u[res.t > t1 + 2 * dt, 2], 0.0, atol=1e-12)    # plastic: stays
    E = res.energy["kinetic"] + res.energy["potential"]
    assert (E - E[0]).max() < 1e-10 * E[0]
    assert z.min() > -v1 * dt                                   # penetration at most one step's travel
    assert 0.0 < res.stats["max_penetration"] < v1 * dt and res.stats["closed_contacts"] > 0


def test_zeno_bounce_comes_to_rest_without_sinking():
    e = 0.7
    res = bouncing_ball(e, 4.0, 1e-3)
    t_zeno = np.sqrt(2 * H0 / G) * (1 + 2 * e / (1 - e))     # Σ of the geometric flight times
    rest = res.t > t_zeno + 0.05
    assert np.abs(res.u[rest, 2]).max() < 1e-9
    assert np.abs(res.q[rest, 2] - R).max() < 1e-5            # resting on the plane, not sinking
    assert np.ptp(res.q[rest, 2]) < 1e-9


@pytest.mark.parametrize("v0", [1.0, 3.0])
def test_block_slides_with_coulomb_deceleration_and_sticks(v0):
    mu, dt = 0.3, 1e-3
    system = System(gravity=(0, 0, -G))
    block = system.add(PointMass(2.0, velocity=(v0, 0.0, 0.0)))
    kin = ContactKinematicsPointPlane(PointContour(block.point), PlaneContour(ground_frame()))
    system.add(Contact(kin, UnilateralCoulombContact(e=0.0, mu=mu)))
    t_stop = v0 / (mu * G)
    res = system.simulate(t_stop + 0.3, dt, integrator="moreau")
    sliding = res.t < t_stop - 2 * dt
    assert np.allclose(res.u[sliding, 0], v0 - mu * G * res.t[sliding], atol=1e-9)
    assert np.allclose(res.u[res.t > t_stop + dt, 0], 0.0, atol=1e-9)
    assert np.isclose(res.q[-1, 0], v0 ** 2 / (2 * mu * G), atol=v0 * dt)
    assert np.abs(res.q[:, 2]).max() < 1e-12


def test_regularized_contact_settles_at_the_static_penetration_and_slides_at_mu_g():
    """Penalty law k, critical damping: at rest g_N = −m g / k; regularized Coulomb
    friction decelerates a sliding point at μ g while |v| > v_eps."""
    m, k, mu, v0 = 1.0, 1e5, 0.3, 1.0
    system = System(gravity=(0, 0, -G))
    block = system.add(PointMass(m, position=(0, 0, 0.01), velocity=(v0, 0, 0)))
    kin = ContactKinematicsPointPlane(PointContour(block.point), PlaneContour(ground_frame()))
    law = LinearRegularizedUnilateralConstraint(k, 2.0 * np.sqrt(k * m))
    system.add(Contact(kin, law, friction=RegularizedCoulombFriction(mu, 1e-4)))
    res = system.simulate(0.6, 1e-4, integrator="moreau")
    assert np.isclose(res.q[-1, 2], -m * G / k, rtol=1e-6)
    t_land = np.sqrt(2 * 0.01 / G)
    sliding = (res.t > t_land + 0.06) & (res.u[:, 0] > 0.05)   # landing transient decayed (ω t > 19)
    assert sliding.sum() > 100
    assert np.allclose(np.diff(res.u[sliding, 0]) / 1e-4, -mu * G, rtol=1e-3)


@pytest.mark.parametrize("atol", [1e-5, 1e-7])
def test_adaptive_steps_shrink_at_the_impact_and_bound_penetration_and_timing_by_atol(atol):
    """Free flight under gravity is exact for the midpoint scheme, so the step grows to
    dt; the impact at t1 = sqrt(2 H0 / g) makes it shrink until the penetration stays
    within gap_tol = atol; the rebound apex then misses (e v1)² / 2g by at most about the
    mistimed travel."""
    e = 0.7
    v1 = np.sqrt(2 * G * H0)
    t1 = v1 / G
    res = bouncing_ball(e, 0.8, 1e-2, integrator="moreau-adaptive", atol=atol, t_out=[0.4, 0.8], trace=True)
    tr = res.trace
    assert set(tr) == {"t", "dt", "closed", "penetration", "iterations", "residual", "impulse_work", "energy",
                       "pressed", "load_work", "damping_loss", "contact_springs"}
    assert len(tr["t"]) == res.stats["steps"] and np.isclose(tr["dt"].sum(), 0.8, rtol=1e-12)
    near = np.abs(tr["t"] - t1) < 1e-3
    assert tr["dt"][near].min() < 100 * atol / v1 and tr["dt"][tr["t"] < 0.4].min() == pytest.approx(1e-2)
    # gap control bounds the depth at step ends by gap_tol; the midpoint of the impact
    # step may lie up to that step's travel deeper
    i = np.argmax(tr["closed"] > 0)
    assert res.stats["max_penetration"] <= atol + v1 * tr["dt"][i] and res.stats["rejected_steps"] > 0
    assert tr["dt"][i] < 100 * atol / v1
    first = tr["t"][i]
    assert abs(first - t1) < 100 * atol / v1                    # impact located to the controlled step
    apex = (e * v1) ** 2 / (2 * G)
    assert np.isclose(res.q[-1, 2] - R, apex - 0.5 * G * (0.8 - t1 - e * v1 / G) ** 2, atol=50 * atol)
    E = tr["energy"]
    assert np.diff(E).max() < 1e-12 * E[0]                      # never gains energy


def test_adaptive_is_cheaper_than_the_fixed_step_of_equal_impact_accuracy():
    """Both meet the 1e-4 m height after the bounce: the fixed step at dt = 1e-4 s (the
    impact mistimed by up to v1 dt, measured 5e-5 m) and the adaptive one at atol = 1e-5
    (measured 6e-6 m) in less than a thirtieth of the fixed steps."""
    fixed = bouncing_ball(1.0, 1.0, 1e-4, t_out=[1.0])
    adaptive = bouncing_ball(1.0, 1.0, 1e-2, integrator="moreau-adaptive", atol=1e-5, t_out=[1.0])
    v1 = np.sqrt(2 * G * H0)
    z_exact = H0 - 0.5 * G * (1.0 - 2 * v1 / G) ** 2           # e = 1: the second fall, from H0
    assert abs(adaptive.q[-1, 2] - R - z_exact) < 1e-4 and abs(fixed.q[-1, 2] - R - z_exact) < 1e-4
    assert adaptive.stats["steps"] * 3 < fixed.stats["steps"] / 10


def test_trace_of_the_fixed_step_records_every_step():
    res = bouncing_ball(0.0, 0.6, 1e-3, trace=True, t_out=[0.6])
    tr = res.trace
    assert len(tr["t"]) == 600 and np.allclose(tr["dt"], 1e-3)
    t1 = np.sqrt(2 * H0 / G)
    assert np.all(tr["closed"][tr["t"] < t1 - 1e-3] == 0) and np.all(tr["closed"][tr["t"] > t1 + 1e-3] == 1)
    assert tr["penetration"].max() == res.stats["max_penetration"]
    # energy balance: under constant gravity the midpoint step changes kinetic plus
    # potential energy by exactly Λ (γ⁺ + γ⁻)/2; e = 0 takes out the ½ m v² of the approach
    # (m = 1, v ≈ sqrt(2 g H0) to one step's g dt)
    E0 = G * (H0 + R)
    assert np.isclose(tr["energy"][-1] - E0, tr["impulse_work"].sum(), rtol=1e-9)
    assert np.isclose(tr["impulse_work"].sum(), -G * H0, rtol=2 * 1e-3 * G / np.sqrt(2 * G * H0))
    assert bouncing_ball(0.0, 0.1, 1e-3).trace == {}


def test_bad_options():
    system = System()
    system.add(PointMass(1.0))
    with pytest.raises(ModelError, match="theta"):
        system.simulate(0.1, 0.01, integrator="moreau", theta=0.2)
    with pytest.raises(ModelError, match="atol"):
        system.simulate(0.1, 0.01, integrator="moreau-adaptive", atol=0.0)


def test_constant_iteration_matrix_is_factored_once_with_the_same_result(thesis_beam_data):
    """A point mass dropped on a frame-fixed FFR beam: M, K, D are constant, so Moreau
    factors M̂ once per step size; the states equal those of the general path (M̂ formed
    and factored every step) to rounding."""
    from contact import ContactKinematicsPointContour2s
    from contours import Contour2sNeutralFFR
    from mbs import FlexibleBodyFFR, PrescribedFrameMotion, SpringDamper

    def scene():
        system = System()
        beam = system.add(FlexibleBodyFFR(thesis_beam_data, modes=8, frame=PrescribedFrameMotion.fixed()))
        mass = system.add(PointMass(0.5, position=(0.2, 0.0502, 0.025), velocity=(0.0, -0.2, 0.0)))
        kin = ContactKinematicsPointContour2s(PointContour(mass.point), Contour2sNeutralFFR(beam, "y1"))
        system.add(Contact(kin, UnilateralNewtonImpact(0.5)))
        return system, beam, mass

    system, beam, mass = scene()
    assert system.constant_iteration_matrix
    fast = system.simulate(2e-3, 1e-5, integrator="moreau", theta=0.5, trace=True)
    slow_system = scene()[0]
    from mbs.integrators.moreau import MoreauTimeStepping

    class EveryStep(MoreauTimeStepping):
        def __init__(self, system, **kw):
            super().__init__(system, **kw)
            self._constant = False

    slow = slow_system.simulate(2e-3, 1e-5, integrator=EveryStep, theta=0.5)
    assert fast.trace["closed"].sum() >= 3                                  # the contact acted
    assert np.allclose(fast.q, slow.q, rtol=0, atol=1e-12 * np.abs(slow.q).max())
    assert np.allclose(fast.u, slow.u, rtol=0, atol=1e-10 * np.abs(slow.u).max())
    u_f = fast.u[-1, beam.u_slice]                       # kinetic energy: brute-force sum over nodes
    v_nodes = beam.phi_nodes @ u_f
    T_nodes = 0.5 * np.sum(thesis_beam_data.masses * np.sum(v_nodes ** 2, axis=1))
    assert np.isclose(beam.kinetic_energy(fast.q[-1, beam.q_slice], u_f), T_nodes, rtol=1e-12)
    system.add(SpringDamper(beam.node(0), mass.point, 10.0, free_length=0.1))
    assert not system.constant_iteration_matrix
    free = System()
    free.add(FlexibleBodyFFR(thesis_beam_data, modes=4))
    assert not free.constant_iteration_matrix


def test_adaptive_lands_on_output_times_without_sliver_steps():
    """Free fall is exact for the midpoint step, so nothing limits the step: 1 s at a
    largest step of 1e-2 s takes 100 steps, none shortened by the rounding of the rest."""
    system = System(gravity=(0, 0, -G))
    system.add(PointMass(1.0))
    res = system.simulate(1.0, 1e-2, integrator="moreau-adaptive", atol=1e-3, rtol=0.0, trace=True)
    assert res.stats["steps"] == 100 and res.trace["dt"].min() == pytest.approx(1e-2)
    assert np.isclose(res.q[-1, 2], -0.5 * G, rtol=1e-12)


@pytest.mark.parametrize("theta", [0.5, 1.0])
def test_a_pressed_contact_apart_within_closing_tol_closes_its_gap_and_a_penetration_stays(theta):
    """Gravity, ball at rest 0.4 µm above the plane, inside closing_tol = 1 µm: the
    first step closes the contact and stops the ball; from the second (resting) the law
    on γ⁺ + g/Δt lets it close the gap, and from the third step on it rests at z = R
    (θ = 1/2: u⁺ = −g/Δt, q⁺ = q + Δt/2 u⁺ leaves g/2, which the next midpoint
    q⁺ + Δt/2 u⁺ closes; θ = 1: q⁺ = q + Δt u⁺ = R). A ball penetrating by 0.4 µm is
    not pushed out. Without the term the first ball hovered 0.4 µm above the plane."""
    dt = 1e-3
    for z0, z_end in [(R + 4e-7, R), (R - 4e-7, R - 4e-7)]:
        system = System(gravity=(0, 0, -G))
        ball = system.add(PointMass(1.0, position=(0, 0, z0)))
        kin = ContactKinematicsSpherePlane(SphereContour(ball.point, R), PlaneContour(ground_frame()))
        system.add(Contact(kin, UnilateralNewtonImpact(0.0), closing_tol=1e-6))
        res = system.simulate(6 * dt, dt, integrator="moreau", theta=theta)
        assert np.allclose(res.q[3:, 2], z_end, rtol=0, atol=1e-15)
        assert np.allclose(res.u[4:, 2], 0.0, rtol=0, atol=1e-12)


def test_heavy_ball_on_a_light_one_rests_for_a_thousand_steps_with_newton():
    """1e6 kg on 1 kg on the plane: the Delassus matrix has condition ~1e6, so the
    relative velocity between the balls is exact only to ~1e-12 m/s, always with the same
    rounding; without closing the rounding gap the contact opened after ~840 steps and the
    top ball fell g Δt² into the bottom one. Exact: rest, forces m_top g and (m_top + m_b) g."""
    dt, m_b, m_t, r = 1e-3, 1.0, 1e6, 0.05
    system = System(gravity=(0, 0, -G))
    a = system.add(PointMass(m_b, position=(0, 0, r)))
    b = system.add(PointMass(m_t, position=(0, 0, 3 * r)))
    system.add(Contact(ContactKinematicsSpherePlane(SphereContour(a.point, r), PlaneContour(ground_frame())),
                       UnilateralNewtonImpact(0.0), name="ground"))
    system.add(Contact(ContactKinematicsSphereSphere(SphereContour(b.point, r), SphereContour(a.point, r)),
                       UnilateralNewtonImpact(0.0), name="between"))
    res = system.simulate(1.0, dt, integrator="moreau", solver="newton", trace=True, contacts=True)
    assert np.all(res.trace["closed"] == 2)
    assert np.abs(res.q[:, a.q_slice][:, 2] - r).max() < 1e-12
    assert np.abs(res.q[:, b.q_slice][:, 2] - 3 * r).max() < 1e-12
    assert np.allclose(res.contacts["between"]["force"][1:, 2], m_t * G, rtol=1e-6)
    assert np.allclose(res.contacts["ground"]["force"][1:, 2], (m_t + m_b) * G, rtol=1e-6)
