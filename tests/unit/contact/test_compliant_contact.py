"""Contacts on contours with residual flexibility in the Moreau step (contact.compliance,
mbs.run.residual_contact), against analytic and full-FE oracles.

* A mass dropped on a beam kept with NO modes: the contour's residual compliance is then
  the beam's whole static compliance c, and the mass meets a massless spring of stiffness
  1/c: a half sine of duration π √(m c), deepest deflection v₀ √(m c), rebound speed v₀
  (for e = 0 as for e = 1: the law acts on the spring's end, which stores and returns the
  energy).
* A mass pressed with a constant force onto a beam with n modes plus the correction, with
  Coulomb friction holding it, settles where the full FE model's static solution puts the
  contact point (K_ff⁻¹, normal and tangential).
* e = 1 with 20 modes: kinetic + elastic + spring energy kept to rounding while closed.
* Kernels against their numpy references.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from contact import (Contact, ContactKinematicsPointContour2s, UnilateralCoulombContact, UnilateralNewtonImpact)
from contact.compliance import (compliant_problem, compliant_problem_reference, compliant_update,
                                compliant_update_reference)
from contact.search import Contact2sSearch
from contact.solver import ProxSolver
from contours import Contour2sNeutralFFR, PointContour
from contours.residual import residual_compliance, transfer_matrix
from ffrmbs.errors import ModelError
from mbs import FlexibleBodyFFR, Force, PointMass, PrescribedFrameMotion, System
from mbs.run import stages
from mbs.run.model import Data, compile_model
from mbs.run.residual_contact import spring_energy
from preprocess import Material, build_body
from preprocess.geometry import box
from preprocess.modes import all_modes, clamped_dofs
from preprocess.residual import clamped_nodes_of

TOP = 0.02          # the beam's top face y [m]


@pytest.fixture(scope="module")
def beam_data():
    """A clamped tet4 beam 100 x 20 x 20 mm (x = 0 clamped), soft (E = 50 MPa), all modes."""
    mesh = box(0.1, TOP, 0.02, None, order=1, divisions=(6, 3, 4))
    data = build_body(mesh, Material(920.0, 5e7, 0.3), n_modes=1, clamp="x0")
    data.eigenvalues, data.phi = all_modes(data.stiffness, data.masses, data.node_groups["x0"])
    return data


def scene(data, modes, law, position, velocity=(0.0, 0.0, 0.0), residual=True, force=None, mass=0.05):
    system = System()
    beam = system.add(FlexibleBodyFFR(data, modes=modes, frame=PrescribedFrameMotion.fixed(), name="beam"))
    point = system.add(PointMass(mass, position=position, velocity=velocity, name="mass"))
    top = Contour2sNeutralFFR(beam, "y1", residual_flexibility=residual)
    contact = system.add(Contact(ContactKinematicsPointContour2s(PointContour(point.point), top), law, name="c"))
    if force is not None:
        system.add(Force(point.point, force))
    return system, beam, point, top, contact


def run(system, t_end, dt, theta=0.5, every=None):
    """Step the Moreau stages by hand; returns the Data (and calls ``every(model, data)``)."""
    model = compile_model(system, None, theta=theta, solver=ProxSolver("gauss-seidel", tol=1e-13, max_iter=5000))
    data = Data(model)
    data.q[:], data.u[:] = system.initial_state()
    while data.t < t_end - 0.5 * dt:
        stages.step(model, data, dt)
        if every is not None:
            every(model, data)
    return model, data


@pytest.mark.parametrize("e", [0.0, 1.0])
def test_mass_on_the_whole_static_compliance_is_a_half_sine(e, beam_data):
    x, z, v0, m, dt = 0.085, 0.01, 0.2, 0.05, 2e-6
    system, beam, point, top, contact = scene(beam_data, 0, UnilateralNewtonImpact(e), (x, TOP + 1e-5, z),
                                              (0.0, -v0, 0.0), mass=m)
    eta, xi = Contact2sSearch(top).solve(np.array([x, TOP, z]), None)
    c = residual_compliance(top).at(eta, xi)[1, 1]
    duration, depth = np.pi * np.sqrt(m * c), v0 * np.sqrt(m * c)
    ys, closed = [], []

    def record(model, data):
        ys.append(data.q[point.q_slice][1])
        closed.append(data.closed[0])

    model, data = run(system, 1e-5 / v0 + 1.3 * duration, dt, every=record)
    assert abs(data.u[point.u_slice][1] / v0 - 1.0) < 1e-6
    assert abs((TOP - min(ys)) / depth - 1.0) < 2 * v0 * dt / depth   # closing at the midpoint: O(v₀ Δt)
    assert abs(np.count_nonzero(closed) * dt / duration - 1.0) < 3 * dt / duration
    assert c > 0


def settle(data_beam, modes, position, force, mu=1.0, t_end=0.5, dt=2e-3):
    """The pressed mass's position after ``t_end`` of implicit Euler (θ = 1, which damps
    the bodies and the contact's spring alike: ω Δt ≈ 0.7 for the mass on its spring)."""
    system, beam, point, top, contact = scene(data_beam, modes, UnilateralCoulombContact(0.0, mu), position,
                                              force=force, mass=0.05)
    model, data = run(system, t_end, dt, theta=1.0)
    return data.q[point.q_slice], top, model, data


@pytest.mark.parametrize("modes", [5, 10, 20, 50])
def test_pressed_mass_settles_at_the_full_fe_static_solution(modes, beam_data):
    """At rest the contact point has moved by the full model's K_ff⁻¹ f under the contact
    force f = the applied force (Coulomb friction holding the tangential part). The
    normal and tangents turn with the deflection, so the contact force in body axes is f
    only to the surface's rotation (~ deflection / beam height): with deflections of
    ~2e-8 m that is ~1e-6, the tolerance."""
    x, z = 0.085, 0.01
    f = np.array([2e-5, -1e-4, 1e-5])                  # [N]
    q, top, model, data = settle(beam_data, modes, (x, TOP, z), f)
    eta, xi = Contact2sSearch(top).solve(np.array([x, TOP, z]), None)
    rc = model.residual.compliances[id(top)]
    blocks, index = np.zeros((16, 3, 3)), np.zeros(16, dtype=np.int64)
    k = rc.weights(eta, xi, blocks, index)
    T = transfer_matrix(top).toarray()
    Tp = sum(T[:, 3 * index[i]:3 * index[i] + 3] @ blocks[i].T for i in range(k))
    K = beam_data.stiffness.tocsc()
    free = ~clamped_dofs(K.shape[0], clamped_nodes_of(beam_data))
    u = np.zeros(K.shape[0])
    u[free] = sla.spsolve(K[free][:, free], (Tp @ f)[free])
    expected = Tp.T @ u
    moved = q - np.array([x, TOP, z])
    assert np.abs(moved - expected).max() < 1e-6 * np.abs(expected).max(), (moved, expected)


def test_pressed_mass_without_correction_misses_the_static_solution(beam_data):
    """The same press without the correction stops short by the residual compliance."""
    x, z = 0.085, 0.01
    f = np.array([0.0, -1e-2, 0.0])
    with_c = settle(beam_data, 10, (x, TOP, z), f)[0][1] - TOP
    system, beam, point, top, contact = scene(beam_data, 10, UnilateralCoulombContact(0.0, 1.0), (x, TOP, z),
                                              force=f, residual=False)
    without = run(system, 0.5, 2e-3, theta=1.0)[1].q[point.q_slice][1] - TOP
    assert without > 1.2 * with_c                       # both negative: the uncorrected beam is too stiff


def bounce_energies(data, modes, dt, t_end, e=1.0):
    """Bounce (restitution ``e``) of the 0.05 kg mass at 0.2 m/s: per step (kinetic +
    elastic + ½ Fᵀδ [J], contact closed, end force F [N], compliance C [m/N] of the normal
    row)."""
    m, v0 = 0.05, 0.2
    system, beam, point, top, contact = scene(data, modes, UnilateralNewtonImpact(e), (0.085, TOP + 1e-5, 0.01),
                                              (0.0, -v0, 0.0), mass=m)
    rows = []

    def record(model, d):
        q_f, qd_f = d.q[beam.q_slice][beam._f], d.u[beam.u_slice][beam._fu]
        e = 0.5 * m * d.u[point.u_slice] @ d.u[point.u_slice] + 0.5 * qd_f @ qd_f + 0.5 * q_f @ beam.K_ff @ q_f
        rows.append((e + spring_energy(model, d), d.closed[0], d.comp_force[0], d.compliance(d.comp_r)[0, 0] if d.comp_r else 0.0))

    run(system, t_end, dt, every=record)
    return np.array(rows, dtype=float).T


def test_elastic_impacts_on_the_static_compliance_keep_energy(beam_data):
    """e = 1 on the whole static compliance (no modes): kinetic + spring energy is kept to
    rounding at every step while the spring pushes; the release step (the end force
    reaching zero within a step) changes it by O(Δt²)."""
    released = []
    for dt in (4e-6, 2e-6):
        E, closed, F, C = bounce_energies(beam_data, 0, dt, 0.04)
        e0 = E[0]
        pushing = (F[1:] > 0) & (F[:-1] > 0)
        assert pushing.sum() > 1000
        assert np.abs(np.diff(E)[pushing]).max() < 1e-13 * e0
        release = (F[:-1] > 0) & (F[1:] == 0)
        assert release.sum() == 1
        released.append(abs(np.diff(E)[release][0]) / e0)
    assert released[1] < 1e-6 and released[1] < released[0] / 3.0


def test_elastic_impacts_with_modes_exchange_only_the_sliding_energy(beam_data):
    """e = 1 with 20 modes plus the correction: the mass slides a little as the beam tilts,
    so the compliance C at the contact point changes; then per step (S2–S3, S6 of
    contact.compliance) E_{k+1} − E_k = −½ F_k (C_{k+1} − C_k) F_{k+1} exactly while the
    spring pushes, which checks the bodies' and the spring's energy exchange to rounding."""
    E, closed, F, C = bounce_energies(beam_data, 20, 2e-6, 0.012)
    e0 = E[0]
    pushing = (F[1:] > 0) & (F[:-1] > 0)
    assert pushing.sum() > 500
    exchange = -0.5 * F[:-1] * np.diff(C) * F[1:]
    assert np.abs(np.diff(E) - exchange)[pushing].max() < 1e-12 * e0
    assert np.abs(exchange[pushing]).max() > 1e-8 * e0          # the sliding term is there to be checked
    assert abs(E[-1] / e0 - 1.0) < 1e-3                           # with the releases and the sliding


def test_inelastic_impacts_through_the_spring_gain_at_most_the_sliding_exchange(beam_data):
    """e = 0 with 20 modes plus the correction: four bounces while the mass slides a little
    as the beam tilts. What the bodies plus the spring gain is bounded by the sliding
    exchange S = Σ −½ F_k (C_{k+1} − C_k) F_{k+1} (S6 of contact.compliance; the only
    term that does not vanish with Δt): E_end − E₀ − S <= 0 (the impacts lose, the
    releases' gain is O(Δt)), and S is the same at both steps."""
    e0 = 0.5 * 0.05 * 0.2 ** 2
    sliding = []
    for dt in (4e-6, 2e-6):
        E, closed, F, C = bounce_energies(beam_data, 20, dt, 0.02, e=0.0)
        pushing = (F[1:] > 0) & (F[:-1] > 0)
        S = (-0.5 * F[:-1] * np.diff(C) * F[1:])[pushing].sum()
        assert E[-1] - e0 - S <= 0.0, (E[-1] - e0, S)
        sliding.append(S / e0)
    assert 1e-5 < sliding[1] < 1e-3 and abs(sliding[0] / sliding[1] - 1.0) < 0.1, sliding


def _masses_on_a_plate(n_side=5, t_end=3e-4):
    """25 (n_side²) point masses landing side by side on a corrected clamped plate (below)."""
    data = build_body(box(0.2, 0.1, 0.01, None, order=1, divisions=(20, 10, 2)), Material(2700.0, 7e10, 0.33),
                      n_modes=10, clamp="x0")
    system = System()
    plate = system.add(FlexibleBodyFFR(data, modes=10, frame=PrescribedFrameMotion.fixed(), name="plate"))
    top = Contour2sNeutralFFR(plate, "z1", residual_flexibility=True)
    grid = np.linspace(0.0, 0.028, n_side)
    for k, (x, y) in enumerate((x, y) for x in grid for y in grid):
        mass = system.add(PointMass(0.036 / n_side ** 2, position=(0.121 + x, 0.021 + y, 0.0101),
                                    velocity=(0.0, 0.0, -0.5)))
        system.add(Contact(ContactKinematicsPointContour2s(PointContour(mass.point), top), UnilateralNewtonImpact(0.0),
                           name=f"mass {k}"))
    return system.simulate(t_end, 1e-6, integrator="moreau", t_out=np.linspace(0.0, t_end, 31), energies=True,
                           trace=True)


def test_the_compliance_kernel_is_the_pair_loop_on_a_corrected_face(monkeypatch):
    """Nine masses on the corrected plate: the compliance of the closed contacts assembled
    by the one kernel (residual_contact._table_blocks) gives the run of the reference pair
    loop over ``between`` bit for bit (the same weight blocks, the same sums)."""
    from mbs.run import residual_contact

    kernel = _masses_on_a_plate(3, 2.5e-4)
    monkeypatch.setattr(residual_contact, "_table_blocks", lambda rc, data, entries, n_e, C:
                        residual_contact.table_blocks_reference(entries, n_e, C, data.comp_c, data.comp_work))
    loop = _masses_on_a_plate(3, 2.5e-4)
    assert kernel.trace["pressed"].max() > 3
    assert np.array_equal(kernel.q, loop.q) and np.array_equal(kernel.u, loop.u)


def test_a_face_of_masses_on_a_corrected_plate_loses_energy_and_gains_none():
    """25 point masses (1.4 g each, 7 mm apart) land side by side at 0.5 m/s on a clamped
    aluminium plate's top face (tet4, 10 modes plus the correction), e = 0, Gauss–Seidel:
    the masses rebound and the energy after the contact lies within 1 % below the start
    (the impact's and the releases' O(Δt) changes). Closed contacts that carry no force
    while their points are deflected by the others' forces keep their deflection rate;
    zeroing it, as a released lone contact's, gained 41 % (contact.compliance)."""
    res = _masses_on_a_plate()
    energy = res.energy["kinetic"] + res.energy["potential"]
    assert res.trace["pressed"].max() > 10 and res.trace["pressed"][-1] == 0
    assert 0.99 < energy[-1] / energy[0] <= 1.0


@pytest.mark.parametrize("theta", [0.5, 0.7, 1.0])
def test_kernels_match_their_references(theta):
    rng = np.random.default_rng(7)
    m, rows = 7, np.array([1, 2, 3, 5], dtype=np.int64)
    normal = np.array([0, 0, 0, 3], dtype=np.int64)
    A = rng.standard_normal((m, m))
    G, C = A @ A.T, np.diag(rng.random(4)) * 1e-4
    xi, gp = rng.standard_normal((2, m))
    F, d, dd = rng.random(4), rng.random(4) * 1e-5, rng.standard_normal(4) * 1e-2
    F[3] = 0.0
    fresh = np.array([False, False, True, False])
    C[0, 2] = C[2, 0] = 1e-5                              # cross-compliance reaching the fresh row
    ref = compliant_problem_reference(G, xi, gp, rows, C, F, d, dd, fresh, 1e-4, theta)
    G2, xi2, gp2, lam0, d2 = G.copy(), xi.copy(), gp.copy(), np.zeros(4), d.copy()
    compliant_problem(G2, xi2, gp2, rows, C, F, d2, dd, fresh, 1e-4, theta, lam0)
    assert d2[2] == pytest.approx(C[2] @ F)               # the fresh row: the others' deflection
    assert len(ref) == 5
    for got, want in zip((G2, xi2, gp2, lam0, d2), ref):
        assert np.allclose(got, want, rtol=1e-14, atol=1e-14)
    lam, gplus = np.abs(rng.standard_normal((2, m)))
    lam[5] = 0.0
    ref = compliant_update_reference(lam, gplus, gp2, rows, normal, C, F, d2, dd, 1e-4, theta, lam0)
    lam3, gplus3, gp3, F3, d3, dd3 = lam.copy(), gplus.copy(), gp2.copy(), F.copy(), d2.copy(), dd.copy()
    compliant_update(lam3, gplus3, gp3, rows, normal, C, F3, d3, dd3, 1e-4, theta, lam0)
    for got, want in zip((lam3, gplus3, gp3, F3, d3, dd3), ref):
        assert np.allclose(got, want, rtol=1e-14, atol=1e-14)
    assert dd3[3] == 0.0                                  # released: no spring rate


def test_penalty_law_with_residual_flexibility_is_refused(beam_data):
    from contact import LinearRegularizedUnilateralConstraint

    system = scene(beam_data, 5, LinearRegularizedUnilateralConstraint(1e5, 0.0), (0.05, TOP, 0.01))[0]
    with pytest.raises(ModelError, match="set-valued"):
        compile_model(system)


def test_without_residual_flexibility_nothing_is_compiled(beam_data):
    system = scene(beam_data, 5, UnilateralNewtonImpact(0.0), (0.05, TOP, 0.01), residual=False)[0]
    assert compile_model(system).residual is None


def test_a_steady_compliant_step_allocates_no_numpy_array(beam_data):
    """200 steps with the compliant contact closed throughout, after warm-up steps."""
    from numpy_allocations import NumpyAllocations

    system = scene(beam_data, 20, UnilateralNewtonImpact(0.0), (0.085, TOP, 0.01), (0.0, -0.05, 0.0))[0]
    model, data = run(system, 2e-4, 1e-6)
    assert data.closed[0] and data.comp_r == 1
    with NumpyAllocations() as count:
        for _ in range(200):
            stages.step(model, data, 1e-6)
    assert data.closed[0]
    assert count.n == 0, count.sizes


def test_the_plan_says_which_contacts_use_the_correction(beam_data):
    on = scene(beam_data, 5, UnilateralNewtonImpact(0.0), (0.05, TOP, 0.01))[0].plan(0.01)
    off = scene(beam_data, 5, UnilateralNewtonImpact(0.0), (0.05, TOP, 0.01), residual=False)[0].plan(0.01)
    assert "residual flexibility: 5 of its FE model's" in str(on)
    assert "residual flexibility" not in str(off)


@pytest.mark.parametrize("theta", [0.5, 1.0])
@pytest.mark.parametrize("residual", [True, False])
def test_recorded_contact_force_carries_the_whole_impulse(theta, residual, beam_data):
    """The recorded force (the last step's impulse / Δt, sampled every step) summed over
    the run is the point mass's momentum change m (v_end − v₀), the only force on it being
    the contact's: with the correction the impulse is Λ₀ + Λ' (S2), not Λ' = θΔt F_{k+1}."""
    m, v0, dt = 0.05, 0.2, 4e-6
    system, beam, point, top, contact = scene(beam_data, 10, UnilateralNewtonImpact(0.0), (0.085, TOP + 1e-5, 0.01),
                                              (0.0, -v0, 0.0), residual=residual, mass=m)
    res = system.simulate(2e-3, dt, integrator="moreau", theta=theta, contacts=True, plan=False,
                          solver=ProxSolver("gauss-seidel", tol=1e-13, max_iter=5000))
    force = res.contacts["c"]["force"]
    assert res.contacts["c"]["active"].sum() > 20                  # the contact acted over many steps
    impulse = force[1:].sum(axis=0) * dt
    momentum = m * (res.u[-1, point.u_slice] - res.u[0, point.u_slice])
    assert np.abs(impulse - momentum).max() < 1e-9 * m * v0, (impulse, momentum)


@pytest.mark.parametrize("residual", [True, False])
def test_recorded_gap_follows_a_mass_far_from_the_surface(residual, beam_data):
    """A mass rising from 1 mm above the resting beam's flat top to 0.3 m: the recorded gap
    is y − TOP at every sample, t = 0 included, however far the plan prunes the contact
    or the broad phase separates it."""
    y0, v = TOP + 1e-3, 1.0
    system = scene(beam_data, 10, UnilateralNewtonImpact(0.0), (0.085, y0, 0.01), (0.0, v, 0.0),
                   residual=residual)[0]
    res = system.simulate(0.3, 1e-3, integrator="moreau", contacts=True, t_out=np.linspace(0.0, 0.3, 31))
    gap = res.contacts["c"]["gap"]
    assert np.abs(gap - (y0 + v * res.t - TOP)).max() < 1e-12
    assert not res.contacts["c"]["active"].any() and not res.contacts["c"]["deflection"].any()


def test_recorded_gap_of_a_compliant_contact_is_the_effective_gap(beam_data):
    """The mass on the beam's whole static compliance (no modes, so the surface the search
    sees does not move): while closed the spring's deflection is the mass's depth below
    the top, TOP − y (to the O(v₀Δt) of the midpoint), and the recorded gap, the gap of the
    deflected surface g_N + δ, is zero to the solver's tolerance; open, it is y − TOP."""
    x, z, v0, m, dt = 0.085, 0.01, 0.2, 0.05, 2e-6
    system, beam, point, top, contact = scene(beam_data, 0, UnilateralNewtonImpact(0.0), (x, TOP + 1e-5, z),
                                              (0.0, -v0, 0.0), mass=m)
    res = system.simulate(2e-3, dt, integrator="moreau", contacts=True, plan=False,
                          solver=ProxSolver("gauss-seidel", tol=1e-13, max_iter=5000))
    rec, y = res.contacts["c"], res.q[:, point.q_slice][:, 1]
    closed = rec["active"].astype(bool)
    depth = (TOP - y).max()
    assert closed.sum() > 100 and depth > 1e-5
    assert np.abs(rec["deflection"][closed] - (TOP - y[closed])).max() < v0 * dt
    assert np.abs(rec["gap"][closed]).max() < 1e-3 * depth
    assert np.abs(rec["gap"][~closed] - (y[~closed] - TOP)).max() < 1e-12
    assert not rec["deflection"][~closed].any()


@pytest.mark.slow
def test_a_face_of_compliant_contacts_creates_no_energy():
    """Two free rods 100 x 20 x 20 mm (E = 50 MPa, 20 free-free modes each) end to end at
    0.2 m/s, the 25 end-face nodes of one against the other's face with residual
    flexibility, e = 0, Δt = 4 µs: when the face contacts close one after another, a
    closing contact starts with the deflection its neighbours' forces already cause at its
    point (contact.compliance). After the rods part (t = 1.2 ms, the springs relaxed) their energy is at most E₀.
    (Measured: the last contact opens at 0.93 ms, E/E₀ − 1 = −5.9 % as at Δt = 2 µs; with
    δ = 0 at a closing contact the face is still closed at 1.2 ms, at Δt = 2 and 4 µs,
    not at 8 µs.)"""
    L, H, v0, dt = 0.1, 0.02, 0.2, 4e-6
    rod = build_body(box(L, H, H, None, order=1, divisions=(4, 4, 4)), Material(920.0, 5e7, 0.3), n_modes=20)
    system = System()
    r1 = system.add(FlexibleBodyFFR(rod, modes=20, frame="free", name="rod1"))
    r1.set_initial(R=(-L - 1e-5, 0.0, 0.0), v=(v0, 0.0, 0.0))
    r2 = system.add(FlexibleBodyFFR(rod, modes=20, frame="free", name="rod2"))
    face = Contour2sNeutralFFR(r2, "x0", residual_flexibility=True)
    for j in r1.node_group("x1"):
        system.add(Contact(ContactKinematicsPointContour2s(PointContour(r1.node(int(j))), face),
                           UnilateralNewtonImpact(0.0), name=f"n{j}"))
    assert len(system.contacts) == 25
    e0 = system.kinetic_energy(0.0, *system.initial_state())
    model = compile_model(system, None, theta=0.5, solver=ProxSolver("gauss-seidel", tol=1e-10, max_iter=20000))
    data = Data(model)
    data.q[:], data.u[:] = system.initial_state()
    while data.t < 1.2e-3 - 0.5 * dt:
        stages.step(model, data, dt)
    assert not data.closed.any()
    energy = system.kinetic_energy(data.t, data.q, data.u) + system.potential_energy(data.t, data.q)
    assert energy <= e0, energy / e0 - 1.0
