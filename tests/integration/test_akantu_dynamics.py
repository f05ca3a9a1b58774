"""Akantu's explicit dynamics as a peer (validation/peers/akantu_dynamics.py).

Checked against references computed here, independently of the adapter: the
centre-of-mass motion of a free body (exact for central differences under constant
loads), the modal superposition of the semi-discrete clamped beam with Akantu's own
K and masses (all modes, dense eigensolver), rigid-rotation kinematics for follower
loads. Skipped when akantu is not installed: it is an optional reference code.
"""

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.integrate import quad

pytest.importorskip("akantu")

from preprocess.geometry import box  # noqa: E402
from validation.peers import akantu_dynamics, akantu_fe  # noqa: E402

RHO, E, NU = 8000.0, 200e9, 0.3


@pytest.fixture(scope="module")
def beam():
    """A coarse tet4 beam 1 x 1 x 3 m (z along the axis), 258 nodes."""
    return box(1.0, 1.0, 3.0, 0.5, order=1)


@pytest.fixture(scope="module")
def step_and_masses(beam):
    """The step [s] the adapter takes for ``beam`` (factor 0.8) and Akantu's masses (N,)."""
    n = beam.n_nodes
    res = akantu_dynamics.explicit_dynamics(
        beam.points, beam.tets, RHO, E, NU, load_times=[0.0],
        load_forces=np.zeros((1, n, 3)), t_end=1e-9, output_times=[0.0])
    return res["dt"], res["masses"]


def _run(mesh, **kwargs):
    return akantu_dynamics.explicit_dynamics(mesh.points, mesh.tets, RHO, E, NU, **kwargs)


def _com(result):
    """Centre-of-mass displacement (n_out, 3) [m] from the lumped masses."""
    m = result["masses"]
    return np.einsum("i,tij->tj", m, result["displacement"]) / m.sum()


def test_available():
    assert akantu_dynamics.available()


@pytest.mark.parametrize("order", [1, 2])
def test_free_body_under_constant_force_moves_its_centre_of_mass_exactly(order):
    """Central differences are exact for constant acceleration: the centre of mass
    moves by F t²/(2m), also under a load on one face that deforms the body (the
    internal forces sum to zero). Mass-proportional nodal forces translate every
    node rigidly. Measured: 4e-16 relative (tet4 beam), 1.4e-15 (tet10 unit cube)."""
    mesh = box(1.0, 1.0, 3.0, 0.5, order=1) if order == 1 else box(1.0, 1.0, 1.0, 0.5, order=2)
    n = mesh.n_nodes
    F = np.array([1e5, -2e5, 3e5])
    probe = _run(mesh, load_times=[0.0], load_forces=np.zeros((1, n, 3)), t_end=1e-9,
                 output_times=[0.0])
    dt, m = probe["dt"], probe["masses"]
    assert m.sum() == pytest.approx(RHO * np.prod(np.ptp(mesh.points, axis=0)), rel=1e-12)
    t_out = dt * np.arange(0, 41, 5)

    face = np.zeros((1, n, 3))
    z1 = mesh.group("z1")
    face[0, z1] = F / len(z1)
    res = _run(mesh, load_times=[0.0], load_forces=face, t_end=t_out[-1], output_times=t_out)
    assert res["n_steps"] == 40 and res["dt"] == dt
    expected = F[None] / m.sum() * t_out[:, None] ** 2 / 2
    np.testing.assert_allclose(_com(res), expected, rtol=0, atol=1e-10 * np.abs(expected).max())
    assert np.ptp(res["displacement"][-1, :, 0]) > 1e-3 * np.abs(expected[-1, 0])  # deformed

    uniform = (m[:, None] / m.sum() * F)[None]
    res = _run(mesh, load_times=[0.0], load_forces=uniform, t_end=t_out[-1], output_times=t_out)
    np.testing.assert_allclose(res["displacement"], np.repeat(expected[:, None], n, axis=1),
                               rtol=0, atol=1e-10 * np.abs(expected).max())
    np.testing.assert_allclose(res["velocity"][:, 0], F[None] / m.sum() * t_out[:, None],
                               rtol=1e-10)


def test_step_table_acts_from_each_load_time_on(beam, step_and_masses):
    """No force before load_times[0]; F_j from load_times[j] on, evaluated at the step
    times (a load time between steps acts from the next step). Reference: the
    central-difference recursion (β = 0, γ = 1/2) of the centre of mass written out here,
    M a_n = F(t_n)."""
    dt, m = step_and_masses
    M = m.sum()
    F1, F2 = np.array([2e5, 0.0, -1e5]), np.array([-3e5, 1e5, 0.0])
    table = np.stack([m[:, None] / M * F1, m[:, None] / M * F2])
    load_times = np.array([2.5 * dt, 6 * dt])
    t_out = dt * np.arange(13)
    res = _run(beam, load_times=load_times, load_forces=table, t_end=t_out[-1], output_times=t_out)

    def force(t):
        return np.zeros(3) if t < load_times[0] else (F1 if t < load_times[1] else F2)

    u, v, a = np.zeros(3), np.zeros(3), force(0.0) / M
    ref = [u]
    for k in range(1, 13):
        u = u + dt * v + dt**2 / 2 * a
        a_new = force(k * dt) / M
        v = v + dt / 2 * (a + a_new)
        a = a_new
        ref.append(u)
    ref = np.array(ref)
    np.testing.assert_array_equal(ref[:4], 0.0)
    np.testing.assert_allclose(_com(res), ref, rtol=0, atol=1e-10 * np.abs(ref).max())


def test_clamped_beam_step_load_matches_modal_superposition(beam, step_and_masses):
    """Clamped face z = 0, step shear load on the face z = 3 from t = 0, 20 ms (about two
    periods of the first bending mode, ~92 Hz). Reference: the semi-discrete system
    M ü + K u = f with Akantu's own K and masses (akantu_fe.assemble), all 684 modes of
    the free DOFs, u(t) = Σ φ_j φ_jᵀ f (1 − cos ω_j t)/ω_j².

    Measured: tip node 9.8e-4 relative (max over time) from the exact semi-discrete
    solution, the central-difference phase error ω̃ = (2/Δt) arcsin(ωΔt/2) of the stiff
    modes (ω_max Δt = 0.60); with that ω̃ in place of ω the whole field agrees to 7e-13.
    """
    dt, _ = step_and_masses
    n = beam.n_nodes
    clamp, z1 = beam.group("z0"), beam.group("z1")
    f = np.zeros((n, 3))
    f[z1, 0] = 1e6 / len(z1)
    t_out = dt * np.arange(0, int(0.02 / dt) + 1, 5)
    res = _run(beam, load_times=[0.0], load_forces=f[None], t_end=t_out[-1], output_times=t_out,
               clamped_nodes=clamp)

    K, m = akantu_fe.assemble(beam.points, beam.tets, RHO, E, NU)
    np.testing.assert_allclose(res["masses"], m, rtol=1e-14)
    free = np.setdiff1d(np.arange(n), clamp)
    dofs = (3 * free[:, None] + np.arange(3)).ravel()
    w2, phi = sla.eigh(K[dofs][:, dofs].toarray(), np.diag(np.repeat(m[free], 3)))
    omega = np.sqrt(w2)
    static = phi * (phi.T @ f[free].ravel()) / w2  # (n_dof, n_modes)
    exact = static @ (1.0 - np.cos(np.outer(omega, t_out)))  # (n_dof, n_out)
    omega_cd = 2.0 / dt * np.arcsin(omega * dt / 2.0)
    discrete = static @ (1.0 - np.cos(np.outer(omega_cd, t_out)))

    np.testing.assert_array_equal(res["displacement"][:, clamp], 0.0)
    tip = z1[np.argmax(beam.points[z1, 0] + beam.points[z1, 1])]
    row = np.searchsorted(dofs, 3 * tip)
    u_tip = res["displacement"][:, tip, 0]
    err_exact = np.abs(u_tip - exact[row]).max() / np.abs(exact[row]).max()
    assert err_exact < 2e-3, f"tip: {err_exact:.2e} from the semi-discrete solution"
    field = res["displacement"][:, free].reshape(len(t_out), -1).T
    err_cd = np.abs(field - discrete).max() / np.abs(discrete).max()
    assert err_cd < 1e-9, f"field: {err_cd:.2e} from the central-difference modal solution"


def test_outputs_between_steps_are_interpolated_linearly(beam, step_and_masses):
    """Output at a step time: that step, bitwise. Between steps k and k+1: the linear
    interpolation (1 − w) S_k + w S_{k+1}."""
    dt, _ = step_and_masses
    n = beam.n_nodes
    f = np.zeros((1, n, 3))
    f[0, beam.group("z1"), 1] = 1e6
    common = dict(load_times=[0.0], load_forces=f, t_end=12 * dt,
                  clamped_nodes=beam.group("z0"))
    steps = _run(beam, output_times=dt * np.arange(13), **common)
    mixed = _run(beam, output_times=dt * np.array([0, 3, 3.25, 7.5, 9, 12]), **common)
    for key in ("displacement", "velocity"):
        for i, k in ((0, 0), (1, 3), (4, 9), (5, 12)):
            np.testing.assert_array_equal(mixed[key][i], steps[key][k])
        for i, k, w in ((2, 3, 0.25), (3, 7, 0.5)):
            lo, hi = steps[key][k], steps[key][k + 1]
            np.testing.assert_allclose(mixed[key][i], (1 - w) * lo + w * hi, rtol=1e-12,
                                       atol=1e-14 * np.abs(hi).max())
            assert np.all(mixed[key][i] >= np.minimum(lo, hi) - 1e-14 * np.abs(hi).max())
            assert np.all(mixed[key][i] <= np.maximum(lo, hi) + 1e-14 * np.abs(hi).max())
        assert np.abs(steps[key][7] - steps[key][8]).max() > 0


def _inertia(points, m):
    """Centre of mass C (3,), arms r = X − C (N, 3), second moment J and inertia I (3, 3)."""
    C = m @ points / m.sum()
    r = points - C
    J = np.einsum("i,ij,ik->jk", m, r, r)
    return C, r, J, np.trace(J) * np.eye(3) - J


def test_pure_couple_small_rotation(beam, step_and_masses):
    """Free body, equal and opposite y-forces on the end faces z = 0 and z = 3 (a couple T
    about x, zero resultant). The linearized rotation θ = I⁻¹ Σ m_i r_i × u_i is the
    rigid-rotation coordinate of the linear model, so θ = I⁻¹ T t²/2 exactly for
    inertial forces (measured 6e-16). Follower forces rotate with the body by θ, which
    changes the torque only at second order: with θ_max = 5.7e-3 rad the deviation is
    7.1e-6 relative, asserted below θ_max²."""
    dt, m = step_and_masses
    n = beam.n_nodes
    z0, z1 = beam.group("z0"), beam.group("z1")
    f = np.zeros((n, 3))
    f[z1, 1] = 1e6 / len(z1)
    f[z0, 1] = -1e6 / len(z0)
    _, r, _, inertia = _inertia(beam.points, m)
    T = np.cross(r, f).sum(axis=0)
    t_out = dt * np.arange(0, 1201, 100)
    expected = np.linalg.solve(inertia, T)[None] * t_out[:, None] ** 2 / 2
    theta_max = np.abs(expected).max()
    assert 1e-3 < theta_max < 1e-2
    for follower, tol in ((False, 1e-10), (True, theta_max**2)):
        res = _run(beam, load_times=[0.0], load_forces=f[None], t_end=t_out[-1],
                   output_times=t_out, follower=follower)
        moment = np.einsum("i,tij->tj", m, np.cross(r[None], res["displacement"]))
        theta = np.linalg.solve(inertia, moment.T).T
        err = np.abs(theta - expected).max() / theta_max
        assert err < tol, f"follower={follower}: θ off by {err:.2e} (relative)"


def test_follower_force_turns_with_a_spinning_body(beam, step_and_masses):
    """Free body spinning at ω = 500 rad/s about z (initial velocity ω × r), body-fixed
    mass-proportional force m_i g with g = 1000 m/s² along body x, 4 ms.

    In the linear model the spin gives u = t ω × r with zero internal force, and the
    uniform field adds a common translation d(t), so the configuration is x = C + d +
    (1 + t[ω]×) r and its best-fit rotation is R(t) = polar((1 + t[ω]×) J) (J = Σ m r rᵀ;
    here about 63° at 4 ms). Reference: d(t) = ∫₀ᵗ (t − s) R(s) g ds by quadrature, R
    from scipy.linalg.polar. Measured: 2.0e-6 relative for follower=True (the
    central-difference error of the turning load); follower=False gives g t²/2 to 3e-14
    and is 56 % off the follower reference."""
    dt, m = step_and_masses
    _, r, J, _ = _inertia(beam.points, m)
    omega, g = np.array([0.0, 0.0, 500.0]), np.array([1000.0, 0.0, 0.0])
    spin = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]],
                     [-omega[1], omega[0], 0.0]])
    t_out = dt * np.arange(0, int(round(4e-3 / dt)) + 1, 25)
    common = dict(load_times=[0.0], load_forces=(m[:, None] * g)[None], t_end=t_out[-1],
                  output_times=t_out, initial_velocity=np.cross(omega[None], r))

    def rotation(t):
        return sla.polar((np.eye(3) + t * spin) @ J)[0]

    reference = np.array([[quad(lambda s: (t - s) * (rotation(s) @ g)[k], 0.0, t,
                                epsabs=0.0, epsrel=1e-12)[0] for k in range(3)]
                          for t in t_out])
    scale = np.abs(reference).max()
    inertial = _com(_run(beam, follower=False, **common))
    follower = _com(_run(beam, follower=True, **common))
    np.testing.assert_allclose(inertial, g[None] * t_out[:, None] ** 2 / 2, rtol=0,
                               atol=1e-12 * scale)
    err = np.abs(follower - reference).max() / scale
    assert err < 2e-5, f"follower: centre of mass off by {err:.2e} (relative)"
    assert np.abs(inertial - reference).max() / scale > 0.3


@pytest.mark.parametrize("change, match", [
    (lambda n: dict(load_forces=np.zeros((1, n - 1, 3))), "load_forces must have shape"),
    (lambda n: dict(load_forces=np.zeros((n, 3))), "load_forces must have shape"),
    (lambda n: dict(load_times=[0.0, 0.0], load_forces=np.zeros((2, n, 3))),
     "strictly increasing"),
    (lambda n: dict(load_times=[1e-3, 0.0], load_forces=np.zeros((2, n, 3))),
     "strictly increasing"),
    (lambda n: dict(output_times=[0.0, 2e-3]), r"within \[0, t_end\]"),
    (lambda n: dict(output_times=[-1e-6]), r"within \[0, t_end\]"),
    (lambda n: dict(output_times=[2e-4, 1e-4]), "increasing"),
    (lambda n: dict(t_end=0.0), "t_end"),
    (lambda n: dict(points=np.zeros((n, 2))), "points must have shape"),
    (lambda n: dict(initial_velocity=np.zeros((n - 1, 3))), "initial_velocity must have shape"),
    (lambda n: dict(clamped_nodes=[n]), "clamped_nodes"),
    (lambda n: dict(time_step_factor=-1.0), "time_step_factor"),
])
def test_bad_input_raises_value_error(beam, change, match):
    kwargs = dict(points=beam.points, tets=beam.tets, density=RHO, young=E, poisson=NU,
                  load_times=[0.0], load_forces=np.zeros((1, beam.n_nodes, 3)), t_end=1e-3,
                  output_times=[0.0, 1e-3])
    kwargs.update(change(beam.n_nodes))
    args = [kwargs.pop(k) for k in ("points", "tets", "density", "young", "poisson")]
    with pytest.raises(ValueError, match=match):
        akantu_dynamics.explicit_dynamics(*args, **kwargs)


def test_unstable_step_raises_runtime_error(beam):
    """Five times Akantu's stable step blows up; the error names the time and step."""
    f = np.zeros((1, beam.n_nodes, 3))
    f[0, beam.group("z1"), 0] = 1e3
    with pytest.raises(RuntimeError, match=r"non-finite at t = .* s \(step \d+ of \d+"):
        _run(beam, load_times=[0.0], load_forces=f, t_end=0.05, output_times=[0.05],
             time_step_factor=5.0)


def test_cache_reloads_identical_calls_only(beam, tmp_path):
    n = beam.n_nodes
    f = np.zeros((1, n, 3))
    f[0, beam.group("z1"), 2] = 1e5
    kwargs = dict(load_times=[0.0], load_forces=f, t_end=2e-4, output_times=[0.0, 1e-4, 2e-4],
                  clamped_nodes=beam.group("z0"), cache_dir=tmp_path)
    first = _run(beam, **kwargs)
    assert not first["cached"]
    assert [p.suffix for p in tmp_path.iterdir()] == [".npz"]
    second = _run(beam, **kwargs)
    assert second["cached"]
    assert set(second) == set(first)
    for key in ("t", "displacement", "velocity", "masses"):
        np.testing.assert_array_equal(second[key], first[key])
    for key in ("dt", "n_steps", "cpu_s", "loop_cpu_s"):
        assert second[key] == first[key] and type(second[key]) is type(first[key])

    changed = dict(kwargs, load_forces=f * (1 + 1e-12))
    assert not _run(beam, **changed)["cached"]
    assert not akantu_dynamics.explicit_dynamics(
        beam.points, beam.tets, RHO, E, 0.25, **kwargs)["cached"]
    assert len(list(tmp_path.glob("*.npz"))) == 3
    assert not list(tmp_path.glob("*.tmp"))
