"""The full-FE contact peer (:mod:`validation.peers.full_fe_contact`) on the 25 mm tet10
beam, short runs:

1. no contact (the mass far away): central differences keep the energy of a free
   vibration from a static deflection, and that vibration has the first bending frequency
   of the mesh (the lowest clamped eigenvalue of the same K, M from
   :func:`preprocess.modes.clamped_modes`);
2. the numba kernels equal plain-numpy references written here (CSR mat-vec; the
   projection on the quadratic faces against scipy's root finder; the contact force
   and the stepping against a numpy step loop);
3. an independent oracle of the contact: ffrmbs's reduced model of the same tet10 mesh
   with ALL its clamped modes (the same linear space as the full mesh) and the same
   linear penalty law on a 2s neutral contour of the top face;

plus the cache (atomic npz, read back without pickle) and the one-line faults.
"""

import json

import numpy as np
import pytest
import scipy.sparse.linalg as sla
from scipy.optimize import root

from ffrmbs.errors import ModelError
from ffrmbs_app.scenes import point_mass_beam as pmb
from preprocess.modes import clamped_modes
from validation.peers import _full_fe_kernels as kern
from validation.peers import full_fe_contact as ffe

COARSE = ffe.ELEMENT_SIZES[0.025]     # (10, 2, 2): 525 nodes, 1500 free DOFs


@pytest.fixture(scope="module")
def model():
    return ffe.build_model(COARSE)


def static_deflection(model, total=-1.0):
    """u = K_ff⁻¹ f (3N,) [m] for ``total`` [N] in y spread evenly over the end face x = L."""
    f = np.zeros(model.stiffness.shape[0])
    end = np.flatnonzero(np.isclose(model.points[:, 0], pmb.LENGTH))
    f[3 * end + 1] = total / len(end)
    free = model.free
    u = np.zeros_like(f)
    u[free] = sla.spsolve(model.stiffness[free][:, free].tocsc(), f[free])
    return u


# --- 1. no contact: energy and the first bending frequency -----------------------------

@pytest.fixture(scope="module")
def free_vibration(model):
    far = (0.1, 1.0, 0.025)                # 0.95 m above the top face, at rest: never touches
    return ffe.run(model, far, (0.0, 0.0, 0.0), t_end=0.1, n_out=2001, u0=static_deflection(model))


def test_central_differences_keep_the_energy_of_a_free_vibration(free_vibration):
    """Central differences conserve E_n = ½ v_{n−1/2}ᵀ M v_{n+1/2} + ½ u_nᵀ K u_n exactly
    (the peer's docstring): to rounding over 6000 steps (measured 3e-12)."""
    e = free_vibration.energy
    assert np.all(free_vibration.penalty == 0.0) and np.all(free_vibration.y == 1.0)
    assert np.abs(e - e[0]).max() < 1e-10 * e[0]


def test_free_vibration_has_the_first_bending_frequency_of_the_mesh(model, free_vibration):
    """Node 19's u_y after release from a static tip deflection: its mean period between
    zero crossings against 2π/ω₁ of the lowest clamped modes of the same K, M (the y-bending
    one of the nearly degenerate y/z pair of the square section). The static deflection's
    higher-mode content shifts single crossings a little; central differences shift the
    frequency by (ωΔt)²/24 ~ 1e-6. Tolerance 0.5 %."""
    vals, phi = clamped_modes(model.stiffness, model.masses, 4,
                              np.flatnonzero(np.isclose(model.points[:, 0], 0.0)))
    bending_y = max(range(4), key=lambda i: abs(phi[3 * model.node19 + 1, i]))
    omega = np.sqrt(vals[bending_y])
    t, u = free_vibration.t, free_vibration.node19
    s = np.flatnonzero(np.sign(u[1:]) != np.sign(u[:-1]))
    crossings = t[s] - u[s] * (t[s + 1] - t[s]) / (u[s + 1] - u[s])
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert len(crossings) >= 5
    assert abs(period * omega / (2 * np.pi) - 1) < 5e-3


# --- 2. the kernels against plain numpy ------------------------------------------------

def tri6(xi, eta):
    """Quadratic triangle shape functions N (6,) (corners, then mid-edges 01, 12, 20)."""
    L = np.array([1 - xi - eta, xi, eta])
    return np.array([*(L * (2 * L - 1)), 4 * L[0] * L[1], 4 * L[1] * L[2], 4 * L[2] * L[0]])


def smooth_displacement(model, scale=2e-3):
    """A smooth displacement field (3N,) [m]: bending, twist and a bump under the mass."""
    x, y, z = model.points.T / pmb.LENGTH
    u = np.column_stack([0.1 * x * z, -(x ** 2) - 0.5 * np.sin(9 * x) * x * z, 0.3 * x * y]) * scale
    u[np.isclose(model.points[:, 0], 0.0)] = 0.0
    return u.ravel()


def reference_projection(xp, X, u, faces):
    """(face, ξ, η, gap y_p − y_face, N, x_face, normal scaled to unit y): on every face near
    xp, scipy's root of the ray
    condition (x(ξ, η) − xp)_{x, z} = 0 (x_face straight below or above xp), from the
    centroid; the face whose point is inside its triangle (smallest violation) wins.
    Faces whose centroid is more than 30 mm (an element) from xp in x-z are skipped."""
    pos = X + u.reshape(-1, 3)
    best = None
    for f, face in enumerate(faces):
        P = pos[face]
        if np.linalg.norm((P[:3].mean(axis=0) - xp)[[0, 2]]) > 0.03:
            continue
        xi, eta = root(lambda s: (tri6(*s) @ P - xp)[[0, 2]], [1 / 3, 1 / 3], tol=1e-15).x
        outside = max(-xi, -eta, xi + eta - 1)
        if best is None or outside < best[0] - 1e-12:
            best = (outside, f, xi, eta)
    _, f, xi, eta = best
    P, h = pos[faces[f]], 1e-30                      # complex-step tangents: exact to rounding
    m = np.cross((tri6(xi + 1j * h, eta) @ P).imag / h, (tri6(xi, eta + 1j * h) @ P).imag / h)
    x = tri6(xi, eta) @ P
    return f, xi, eta, xp[1] - x[1], tri6(xi, eta), x, m / m[1]


def scratch():
    return np.zeros(6), np.zeros((6, 2)), np.zeros(3), np.zeros((2, 3)), np.zeros(3)


def test_csr_matvec_equals_scipy(model):
    x = np.random.default_rng(0).standard_normal(model.stiffness.shape[0])
    out = np.empty_like(x)
    K = model.stiffness
    kern.csr_matvec(K.indptr, K.indices, K.data, x, out)
    assert np.allclose(out, K @ x, rtol=0, atol=1e-12 * np.abs(K @ x).max())


@pytest.mark.parametrize("xp", [(0.235, 0.0515, 0.025), (0.235, 0.0491, 0.040), (0.1337, 0.052, 0.0071),
                                (0.2375, 0.05, 0.0125)])
def test_projection_equals_scipy_root(model, xp):
    """The point of the deformed quadratic top face straight below (or above) xp: face,
    (ξ, η), gap y_p − y_face, N, x_face and the scaled normal against scipy; on a shared edge
    or a node (the first and last points) faces tie in x and gap."""
    xp = np.array(xp)
    u = smooth_displacement(model)
    N, dN, x, tang, normal = scratch()
    f, xi, eta, gap = kern.project_on_faces(xp, model.points, u, model.faces, ffe.TOP_AXES, ffe.FACE_TOL, N, dN, x,
                                            tang, normal)
    rf, rxi, reta, rgap, rN, rx, rm = reference_projection(xp, model.points, u, model.faces)
    assert abs(gap - rgap) < 1e-12 and np.allclose(x, rx, rtol=0, atol=1e-12)
    assert normal[1] == pytest.approx(1.0, abs=1e-15)
    if f == rf:
        assert abs(xi - rxi) < 1e-9 and abs(eta - reta) < 1e-9 and np.allclose(N, rN, atol=1e-9)
        assert np.allclose(normal, rm, rtol=0, atol=1e-9)
    assert np.allclose((xp - x)[[0, 2]], 0.0, atol=1e-14)                  # xp − x along the ray e_y


def reference_step_loop(model, xp, vp, k, dt, n_steps, m_p=pmb.MASS):
    """The stepping of :func:`kern.advance` in plain numpy (scipy K @ u, the scipy projection,
    the semi-implicit penalty of the module docstring); returns (u, v, xp, vp)."""
    K, inv_m3 = model.stiffness, model.inv_m3
    u, v = np.zeros(K.shape[0]), np.zeros(K.shape[0])
    xp, vp = np.array(xp, float), np.array(vp, float)

    def accelerations(u, v, xp, vp):
        a = -inv_m3 * (K @ u)
        ap = np.zeros(3)
        f, _, _, gap, N, _, n = reference_projection(xp, model.points, u, model.faces)
        nodes = model.faces[f]
        dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
        W = np.zeros(K.shape[0])
        W[dofs] = -(N[:, None] * n).ravel()
        w = n @ n / m_p + W @ (inv_m3 * W)
        g_pred = gap + dt * (n @ vp + W @ (v + dt * a))
        lam = -k * g_pred / (1 + k * dt * dt * w) if g_pred < 0 else 0.0
        return a + inv_m3 * W * lam, ap + lam * n / m_p

    a, ap = accelerations(u, v, xp, vp)
    v -= 0.5 * dt * a
    vp -= 0.5 * dt * ap
    for _ in range(n_steps):
        v += dt * a
        u += dt * v
        vp += dt * ap
        xp += dt * vp
        a, ap = accelerations(u, v, xp, vp)
    return u, v, xp, vp


def test_stepping_with_contact_equals_the_numpy_step_loop(model):
    """40 steps of a stiff contact (k = 1e9 N/m, k Δt² w ≫ 1) from 1 µm above the face:
    :func:`ffe.run` (the numba kernels) against :func:`reference_step_loop`."""
    dt, n = 0.5 * model.dt_crit, 40
    start, velocity = (0.235, 0.050001, 0.040), (0.0, -0.2, 0.0)
    res = ffe.run(model, start, velocity, k=1e9, t_end=n * dt, n_out=2, dt=dt)
    u, v, xp, vp = reference_step_loop(model, start, velocity, 1e9, dt, n)
    assert res.steps == n and res.min_gap < 0 and res.y[-1] != start[1]
    assert abs(res.y[-1] - xp[1]) < 1e-12
    assert abs(res.node19[-1] - u[3 * model.node19 + 1]) < 1e-12 * np.abs(u).max() + 1e-18
    assert res.elastic[-1] == pytest.approx(0.5 * u @ (model.stiffness @ u), rel=1e-9)


# --- 3. ffrmbs's all-mode reduced model of the same mesh as the contact oracle --------------

START = pmb.SETUPS["A"][0], pmb.HEIGHT + 2e-4, pmb.SETUPS["A"][2]   # [m] setup A 0.2 mm above the face
T_ORACLE = 0.021           # [s]: approach (1 ms) and 20 ms of contact dynamics (the beam rests until then)
K_SOFT = 1e5               # [N/m]: a smooth contact both codes resolve (period ~ 7 ms)


@pytest.fixture(scope="module")
def ffrmbs_run(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FFRMBS_CACHE", str(tmp_path_factory.mktemp("cache")))
        data = pmb.default_beam_data(divisions=COARSE, order=2)
        mp.setitem(pmb.SETUPS, "A", START)
        scene = pmb.build("A", "all", "penalty", k=K_SOFT, d=0.0, data=data)
    res = scene.system.simulate(T_ORACLE, 1e-4, integrator="moreau", theta=0.5,
                                t_out=np.linspace(0.0, T_ORACLE, 301), outputs=scene.outputs())
    return data, res


@pytest.mark.slow      # seconds: the dense all-mode eigensolve and 1500-mode Moreau steps
def test_the_reduced_body_is_the_same_tet10_mesh(model, ffrmbs_run):
    data, _ = ffrmbs_run
    assert data.n_modes == 3 * (len(model.points) - np.isclose(model.points[:, 0], 0).sum())   # all modes
    assert np.array_equal(data.u0, model.points) and np.array_equal(data.masses, model.masses)
    assert data.node_at(pmb.NODE_19) == model.node19


@pytest.mark.slow
def test_penalty_contact_agrees_with_ffrmbs_all_modes(model, ffrmbs_run):
    """Mass v_y and node-19 u_y of the full FE against ffrmbs with all 1500 clamped modes of
    the same mesh (the same linear space), the same law F = k max(0, −g), k = 1e5 N/m.
    The models differ in (a) the face: ffrmbs's 2s contour interpolates the face nodes with
    a NURBS, the full FE uses the quadratic triangles — equal at the nodes, apart between
    them by the deflection's third-order terms (~1e-3 of the ~2 mm deflection over 12.5 mm
    node spacing); (b) the integrators: Moreau θ = ½ at Δt = 1e-4 s (implicit
    trapezoidal, phase error (ωΔt)²/12 ~ 1e-3 for the contact mode ω ≈ 950 rad/s) against
    central differences at 1.7e-5 s whose penalty carries the numerical damper kΔt/2 of
    the semi-implicit contact (module docstring; ~1 % of the energy lost over the impact at
    k = 1e5). Measured (setup A from 0.2 mm, 20 ms of contact dynamics): 0.32 % (v_y RMS
    / 0.2 m/s) and 0.25 % (node-19 RMS / peak); with the full FE at Δt/4 the difference is
    0.07 % / 0.07 %: what is left of (a) and Moreau's step; tolerance 1 %."""
    _, res = ffrmbs_run
    fe = ffe.run(model, START, pmb.VELOCITY, k=K_SOFT, t_end=T_ORACLE, n_out=301)
    peak = np.abs(fe.node19).max()
    assert peak > 1e-3                                      # the beam did deflect by mm
    assert np.sqrt(np.mean((res["vy"] - fe.vy) ** 2)) / 0.2 < 1e-2
    assert np.sqrt(np.mean((res["node19"][:, 1] - fe.node19) ** 2)) / peak < 1e-2


# --- cache and faults -------------------------------------------------------------------

def test_results_are_cached_atomically_and_read_without_pickle(monkeypatch, tmp_path):
    monkeypatch.setenv("FFRMBS_CACHE", str(tmp_path))
    first = ffe.simulate("B", COARSE, t_end=2e-3, n_out=21)
    again = ffe.simulate("B", COARSE, t_end=2e-3, n_out=21)
    files = sorted(p.name for p in tmp_path.iterdir())
    assert files == [ffe.cache_path(first.recipe).name] and files[0].startswith("full_fe_contact-")
    assert not first.cached and again.cached and again.dt == first.dt and again.steps == first.steps
    for name in ffe.FullFEResult.ARRAYS:
        assert np.array_equal(getattr(again, name), getattr(first, name))
    with np.load(tmp_path / files[0], allow_pickle=False) as z:
        assert json.loads(str(z["recipe"])) == first.recipe
    assert ffe.recipe("A", COARSE)["position"] == list(pmb.SETUPS["A"])


@pytest.mark.parametrize("call, message", [
    (lambda m: ffe.recipe("C"), "setup must be one of"),
    (lambda m: ffe.check_divisions((10, 2, 3)), "nz even"),
    (lambda m: ffe.step_size(m, 0.1, 1001, dt=2 * m.dt_crit), "time step must lie in"),
    (lambda m: ffe.run(m, (0, 1, 0), (0, 0, 0), k=-1.0), "penalty k must be positive"),
    (lambda m: ffe.run(m, (0, 1, 0), (0, 0, 0), n_out=1), "n_out must be"),
])
def test_bad_input_is_one_model_error_line(model, call, message):
    with pytest.raises(ModelError, match=message) as info:
        call(model)
    assert "\n" not in str(info.value)


def test_the_tet4_beam_keeps_its_cache_key():
    assert pmb.recipe() == {"scene": "point_mass_beam", "size": [0.25, 0.05, 0.05], "divisions": [10, 4, 4],
                            "material": [920.0, 5e7, 0.3], "clamp": "x0", "modes": "all", "version": 1}
    assert pmb.recipe(COARSE, "all", 2)["order"] == 2
    with pytest.raises(ModelError, match="order must be 1"):
        pmb.default_beam_data(order=3)
