"""The sliding ball of thesis Sec. 5.3 and its moving-load oracle.

Oracle tests check :mod:`validation.moving_load` against facts that do not use it: the
orthogonality relations and boundary conditions of the clamped–free modes, the static
influence function P x²(3a − x)/(6EI), a numerical ODE solution of each modal equation,
and the quasi-static limit c → 0. Scene tests check the FFR beam, the moving force and
the case's quick run against Euler–Bernoulli references with tolerances derived from the
known model error of the 3D tet10 beam.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ffrmbs.errors import ModelError
from validation.moving_load import CantileverEB, static_cantilever_deflection
from ffrmbs_app.scenes import sliding_ball as sb

pytestmark = pytest.mark.slow   # seconds each: left out of the fast subset (-m "not slow")

E, RHO, L, H = 5e7, 920.0, 1.5, 0.05
I, A = H**4 / 12, H * H


@pytest.fixture(scope="module")
def beam_eb():
    return CantileverEB(E, I, RHO, A, L, n_modes=60)


def _gauss(n_panels=60, order=20):
    """Composite Gauss–Legendre nodes and weights on [0, L] (exact for the smooth modes)."""
    g, w = np.polynomial.legendre.leggauss(order)
    edges = np.linspace(0.0, L, n_panels + 1)
    x = (0.5 * (edges[1:] - edges[:-1])[:, None] * (g + 1) + edges[:-1, None]).ravel()
    weights = (0.5 * (edges[1:] - edges[:-1])[:, None] * w).ravel()
    return x, weights


# --- the oracle ---------------------------------------------------------------------------

def test_roots_and_frequencies(beam_eb):
    """β_nL of cos βL cosh βL = −1 (Rao 2019, Table 11.2) and ω_n = β_n² (EI/ρA)^½."""
    assert np.allclose(beam_eb.beta[:4] * L, [1.875104, 4.694091, 7.854757, 10.995541], atol=2e-6)
    assert np.isclose(beam_eb.omega[0], 1.875104**2 * np.sqrt(E * I / (RHO * A * L**4)), rtol=1e-6)


def test_modes_are_mass_orthonormal_and_stiffness_orthogonal(beam_eb):
    """∫ρA φ_m φ_n = δ_mn and ∫EI φ_m'' φ_n'' = ω_n² δ_mn, by quadrature of the closed form."""
    x, w = _gauss()
    phi, phi2 = beam_eb.mode_shapes(x), beam_eb.mode_shapes(x, 2)
    M = RHO * A * (phi * w) @ phi.T
    K = E * I * (phi2 * w) @ phi2.T
    assert np.abs(M - np.eye(60)).max() < 1e-9
    scale = np.outer(beam_eb.omega, beam_eb.omega)
    assert np.abs(K / scale - np.eye(60)).max() < 1e-9


def test_boundary_conditions(beam_eb):
    """Clamped at 0 (φ = φ' = 0), free at L (φ'' = φ''' = 0), relative to β^k C."""
    for k, x in ((0, 0.0), (1, 0.0), (2, L), (3, L)):
        value = beam_eb.mode_shapes([x], k)[:, 0] / (beam_eb.beta**k * beam_eb.C)
        assert np.abs(value).max() < 1e-10, (k, x)


@pytest.mark.parametrize("a", [0.3, 0.75, 1.5])
def test_static_series_equals_influence_function(beam_eb, a):
    """Σ φ_n(x) φ_n(a)/ω_n² P = P x²(3a − x)/(6EI) (x <= a) or P a²(3x − a)/(6EI); the
    terms fall like (β_n L)^-4, so the truncation after 60 modes is ~1e-6 of the largest
    deflection (1e-5 allowed)."""
    x = np.linspace(0.0, L, 31)
    exact = static_cantilever_deflection(x, a, 2.0, E, I)
    err = np.abs(beam_eb.static_deflection(x, a, 2.0) - exact).max()
    assert err < 1e-5 * np.abs(exact).max()


def mode_shape(beam, n):
    """φ_n(x) [kg^-½] of ``beam`` as a scalar function of x [m] (the overflow-free form of
    :mod:`validation.moving_load`, real part written out): for an ODE right-hand side
    called ~1e5 times, where :meth:`CantileverEB.mode_shapes` would evaluate every mode."""
    be, a, b, s, C = beam.beta[n], beam.a[n], beam.b[n], beam.sigma[n], beam.C

    def phi(x):
        return C * (a * math.exp(be * (x - beam.L)) + b * math.exp(-be * x) - math.cos(be * x) + s * math.sin(be * x))
    return phi


def test_scalar_mode_shape_is_the_oracles(beam_eb):
    x = np.linspace(0.0, L, 7)
    for n in (0, 1, 5, 59):
        phi = mode_shape(beam_eb, n)
        assert np.allclose([phi(v) for v in x], beam_eb.mode_shapes(x)[n], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("n", [0, 1, 5])
def test_duhamel_closed_form_matches_ode(beam_eb, n):
    """q̈_n + ω_n² q_n = P φ_n(x0 + c t) from rest, integrated by DOP853 (rtol 1e-12)."""
    P, c, x0 = 1.0, 0.5, 0.1
    t = np.linspace(0.0, 2.5, 26)
    q = beam_eb.modal_response(t, P, c, x0)[:, n]
    w = beam_eb.omega[n]
    phi = mode_shape(beam_eb, n)

    def rhs(tt, y):
        return [y[1], -w * w * y[0] + P * phi(x0 + c * tt)]
    sol = solve_ivp(rhs, (0.0, 2.5), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-12, atol=1e-16)
    assert np.abs(sol.y[0] - q).max() < 1e-7 * np.abs(sol.y[0]).max()


def test_load_held_still(beam_eb):
    """c = 0: each mode responds P φ_n(x0)(1 − cos ω_n t)/ω_n²; the time average over 2000
    periods of mode 1 is the static deflection (within 1/(ω_1 T) ~ 1e-4). The average by
    the trapezoidal rule, exact for mode 1 (whole periods) at 10 samples per period
    (measured 1.4e-6 off the static deflection; the plain mean of 10× the samples: 6e-6)."""
    x0 = 0.6
    t = np.linspace(0.0, 2000 * 2 * np.pi / beam_eb.omega[0], 20001)
    q = beam_eb.modal_response(t[:50], 1.0, 0.0, x0)
    expect = beam_eb.mode_shapes([x0])[:, 0] * (1 - np.cos(np.outer(t[:50], beam_eb.omega))) / beam_eb.omega**2
    assert np.allclose(q, expect, rtol=1e-10, atol=1e-16)
    w = beam_eb.moving_load_response([L, 0.75], t, 1.0, 0.0, x0)
    assert np.allclose(np.trapezoid(w, t, axis=0) / t[-1], static_cantilever_deflection(np.array([L, 0.75]), x0, 1.0, E, I), rtol=1e-4)


@pytest.mark.parametrize("c, tol", [(0.01, 5e-5), (0.001, 5e-7)])
def test_quasi_static_limit(beam_eb, c, tol):
    """A slow load entering at the clamp (no sudden application) follows the static
    influence function, the difference shrinking like (c/c_cr)² (c_cr = ω_1/β_1 = 4.2 m/s)."""
    t = np.linspace(0.0, 1.0 / c, 101)
    w = beam_eb.moving_load_response([L, 0.75], t, 1.0, c, 0.0)
    ws = np.column_stack([static_cantilever_deflection(x, c * t, 1.0, E, I) for x in (L, 0.75)])
    assert np.abs(w - ws).max() < tol * np.abs(ws).max()


def test_oracle_rejects_bad_input(beam_eb):
    c_cr = beam_eb.omega[0] / beam_eb.beta[0]
    with pytest.raises(ModelError, match="critical"):
        beam_eb.modal_response([0.1], 1.0, c_cr, 0.0)
    with pytest.raises(ModelError, match="leaves the beam"):
        beam_eb.modal_response([0.0, 2.0], 1.0, 1.0, 0.0)


# --- the FFR scene ------------------------------------------------------------------------

@pytest.fixture(scope="module")
def data():
    return sb.default_beam_data()


def test_mesh_axis_and_bending_frequencies(data, beam_eb):
    """61 equally spaced axis nodes; the first y-bending frequencies within 1 %, 1 %, 2 %
    of Euler–Bernoulli: one tet10 across the section is accurate in bending, and at
    L/h = 30 shear and rotary inertia lower the exact 3D frequencies below EB by
    ~0.1 %, 0.5 %, 1.2 % (Timoshenko) while the lumped masses raise them slightly."""
    nodes = sb.axis_nodes(data)
    assert len(nodes) == 61 and np.allclose(np.diff(data.u0[nodes, 0]), 0.025, atol=1e-12)
    _, omega = sb.bending_modes(data)
    assert np.all(np.abs(omega[:3] / beam_eb.omega[:3] - 1) < [0.01, 0.01, 0.02])


def test_moving_force_is_the_mode_shapes_at_the_point(data):
    """Prescribed fixed frame: J_T(η) = Φ(η), so at an axis node the generalized force is
    Φ_nodeᵀ F; η(x) affine in x (collinear equally spaced nodes)."""
    scene = sb.build_moving_load(-0.3, 0.5, x0=0.0, modes=20, data=data)
    system, beam = scene.system, scene.beam
    q, u = system.initial_state()
    for t, x in ((1.0, 0.5), (2.9, 1.45)):
        h = np.zeros(system.nu)
        scene.load.add_forces(t, q, u, h)
        j = data.node_at((x, sb.AXIS[1], sb.AXIS[2]))
        assert np.allclose(h[beam.u_slice], beam.phi_nodes[j].T @ [0.0, -0.3, 0.0], rtol=1e-9, atol=1e-14)
        assert np.isclose(scene.load.point(t, q).r[0], x, atol=1e-12)
    with pytest.raises(ModelError, match="left the contour"):
        scene.load.add_forces(3.1, q, u, np.zeros(system.nu))


# --- the case's quick run -----------------------------------------------------------------

@pytest.fixture(scope="module")
def quick_rows():
    from validation.cases import contact_sliding_ball as case
    result = case.run(quick=True)
    return result.rows


def _rows(rows, check, kind=None):
    return [r for r in rows if r["config"]["check"] == check and (kind is None or r["error_kind"].startswith(kind))]


def test_quick_rows_are_complete(quick_rows):
    assert {r["config"]["check"] for r in quick_rows} >= {
        "mesh", "moving load slow", "moving load medium", "moving load fast", "sliding ball", "knots, bent beam",
        "static deflection"}
    assert all(np.isfinite(r["error"]) for r in quick_rows)
    assert all(r["config"]["residual_flexibility"] in ("on", "off") for r in quick_rows)
    on = {r["config"]["check"] for r in quick_rows if r["config"]["residual_flexibility"] == "on"}
    assert on == {"sliding ball", "static deflection"}, on


def test_moving_load_against_the_oracle(quick_rows, beam_eb):
    """Moving load vs Euler–Bernoulli. c = 0.5, 1.5 m/s (smooth start at the clamp): the
    3D tet10 beam differs from EB by ~1 % (first frequency +0.4 %, shear flexibility
    ~(h/L)² E/(κG) ≈ 0.3 %, local deformation under a point load on one node), so 1.5 % at
    the tip, 2 % at midspan. c = 0.01 m/s (load suddenly applied at 0.75 m): mode 1 rings
    with amplitude A_1 for 3 s, and the FE's frequency error δω shifts its phase by δω T;
    allowed: that floor plus 1 %."""
    for load in ("medium", "fast"):
        for kind, tol in (("moving load: tip", 0.015), ("moving load: mid", 0.02)):
            rows = _rows(quick_rows, f"moving load {load}", kind)
            assert rows and all(r["error"] < tol for r in rows), (load, kind, [r["error"] for r in rows])
    omega_fe = [r["value"] for r in _rows(quick_rows, "mesh") if r["config"]["mode"] == 1][0]
    w1, x0, T = beam_eb.omega[0], 0.75, 3.0
    a1 = abs(0.1 * beam_eb.mode_shapes([x0])[0, 0] * beam_eb.mode_shapes([L])[0, 0]) / w1**2
    peak = np.abs(beam_eb.moving_load_response([L], np.linspace(0, T, 301), -0.1, 0.01, x0)).max()
    floor = abs(omega_fe - w1) * T * a1 / peak
    assert 0.01 < floor < 0.05          # the floor is real: ~3 %
    rows = _rows(quick_rows, "moving load slow", "moving load: tip")
    assert rows and all(r["error"] < floor + 0.01 for r in rows), ([r["error"] for r in rows], floor)


def test_sliding_ball_frequency_energy_and_knots(quick_rows):
    """The ball's y oscillation frequency within 1 % of the EB cantilever with the 1 kg
    point mass at the ball's mean x (FE frequency error 0.4 %, the ball's 5 cm travel
    changes it by ±0.35 % about the mean); with θ = 0.5 total energy conserved to 5 % of
    the vibration energy at Δt <= 2 ms (exact: constant; Moreau's velocity-level
    constraint costs O(Δt)), and less at the smaller step; θ = 1 (implicit Euler) damps
    the vibration by design (more than 10 % at Δt = 1 ms, less than all of it); no outlier
    velocity jump at the knot crossing."""
    freq = _rows(quick_rows, "sliding ball", "ball y frequency")
    assert freq and all(abs(r["error"]) < 0.01 for r in freq), [r["error"] for r in freq]
    energy = {(r["config"]["modes"], r["config"]["theta"], r["config"]["dt"], r["config"]["residual_flexibility"]):
              r["error"] for r in _rows(quick_rows, "sliding ball", "energy drift")}
    assert all(e < 0.05 for (_, theta, _, _), e in energy.items() if theta == 0.5), energy
    assert 0.1 < energy[20, 1.0, 1e-3, "off"] < 1.0, energy
    assert energy[20, 0.5, 1e-3, "off"] < 0.6 * energy[20, 0.5, 2e-3, "off"], energy
    knots = _rows(quick_rows, "sliding ball", "knot")
    assert knots and all(r["error"] < 1.5 for r in knots), [r["error"] for r in knots]
    # drift of the velocity-level constraint: Δt/2 · 0.002 m/s from the first step, plus O(Δt²)
    # (with the correction |g| also holds the spring's deflection δ = C F: not a drift)
    assert all(r["max_gap_m"] < r["config"]["dt"] * 0.002 * 1.05 for r in knots
               if r["config"]["residual_flexibility"] == "off")


def test_sliding_ball_energy_with_residual_flexibility_holds_the_spring(quick_rows):
    """With the correction (θ = 0.5) the energy balance closes only with the spring's
    ½ Fᵀδ: the spring holds a share of the vibration energy far above the drift allowed
    (so leaving it out would show as drift), and with it the drift stays within the
    5 % the rigid runs are held to."""
    row = [r for r in _rows(quick_rows, "sliding ball", "energy drift")
           if r["config"]["residual_flexibility"] == "on" and r["config"]["theta"] == 0.5]
    assert row and all(r["error"] < 0.05 < r["spring_share"] for r in row), row


def test_static_deflection_under_the_ball_against_the_full_fe_model(quick_rows):
    """The ball pressed at rest on an axis node: with the correction its deflection is the
    full FE model's K⁻¹f to the floor of its slide along the tilted axis (≈ 3Δx/x: c ∝ x³,
    allowed 2 × that plus 1e-9); without it, short by the dropped modes' compliance —
    at least 10× the corrected error (the check must be able to fail), and less with 100
    modes than with 20."""
    rows = {(r["config"]["x"], r["config"]["modes"], r["config"]["residual_flexibility"]): r
            for r in _rows(quick_rows, "static deflection")}
    assert len(rows) == 8
    for (x, modes, rf), r in rows.items():
        if rf == "on":
            assert abs(r["error"]) < 2 * 3 * abs(r["slide_m"]) / x + 1e-9, (x, modes, r["error"], r["slide_m"])
            off = rows[x, modes, "off"]["error"]
            assert off < 0 and abs(off) > 10 * abs(r["error"]), (x, modes, off, r["error"])
    for x in {x for x, _, _ in rows}:
        assert abs(rows[x, 100, "off"]["error"]) < abs(rows[x, 20, "off"]["error"]), x


def test_knot_crossings_on_the_bent_beam(quick_rows):
    """C² contour: the largest step acceleration is of the order of the centripetal v²κ
    (≤ 2 v²κ(0.1 m)); the C⁰ control (degree 1) must show impulses (≥ 10 v²κ), or this
    check could not fail."""
    rows = {r["config"]["degree"]: r for r in _rows(quick_rows, "knots, bent beam")}
    assert rows[3]["crossings"] > 40
    assert rows[3]["error"] < 2.0, rows[3]["error"]
    assert rows[1]["error"] > 10.0, rows[1]["error"]
