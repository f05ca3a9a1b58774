"""The summary of ``ffrmbs run`` (:mod:`ffrmbs_app.job`) for every kind of scene — with and
without contacts, gravity, loads and damping — against hand calculations: the energy
balance E(t) − E(0) = W_loads − D_damping + W_impulses + residual (:mod:`mbs.run.step_work`)
and the intervals in which a contact transmits a force.

The scenes are small TOML files in ``fixtures/summary_scenes``: point masses, and a
clamped tet4 beam (6 modes) whose body file is written here beside its scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ffrmbs_app.job import run_scene
from ffrmbs_app.scene_loader import load_scene

import paths

SCENES = paths.FIXTURES / "summary_scenes"

CANTILEVER = (SCENES / "cantilever.toml").read_text()     # beside its body written here


def run(path, out, overrides=()):
    """(summary, printed lines) of ``ffrmbs run`` on a scene file, in process."""
    lines = []
    summary = run_scene(lambda: load_scene(path, overrides), out, check=False, export=False, plot=False,
                        log=lines.append)
    return summary, lines


def line(lines, start) -> str:
    hits = [text for text in lines if text.startswith(start)]
    assert len(hits) == 1, (start, lines)
    return hits[0]


def test_a_mass_falling_from_the_gravity_datum_reaches_its_summary(tmp_path):
    """fall.toml: 1 kg at rest at z = 0 (E(0) = 0 exactly) falls h = 0.1 m onto a plane,
    e = 0.5. By hand: impacts at t_1 = √(2h/g) and then every 2 e^k v_1 / g later; the
    energy lost in the k impacts is m g h (1 − e^(2k)) (each keeps e² of the kinetic energy);
    no load, no damping, gravity in E. The force acts in one step per impact."""
    g, h, e = 9.81, 0.1, 0.5
    s, lines = run(SCENES / "fall.toml", tmp_path)
    b = s["energy_balance_J"]
    assert b["initial"] == 0.0 and b["load_work"] == 0.0 and b["damping_loss"] == 0.0
    v1 = math.sqrt(2 * g * h)
    impacts = [math.sqrt(2 * h / g)]
    for k in range(1, 4):
        impacts.append(impacts[-1] + 2 * e ** k * v1 / g)
    iv = s["contact_intervals_s"]
    assert len(iv) == 4
    for (start, end), t_k in zip(iv, impacts):
        assert end - start == pytest.approx(1e-4) and start <= t_k + 1e-4 and end >= t_k - 1e-4
    assert b["impulse_work"] == pytest.approx(-g * h * (1 - e ** 8), rel=2e-3)
    assert b["final"] == pytest.approx(b["impulse_work"], abs=1e-12)
    assert b["largest"] in ("change", "impulse_work") and b["relative"] < 1e-10
    text = line(lines, "energy balance [J]: E(t) - E(0) = W_loads - D_damping + W_impulses + residual with")
    assert "W_loads = 0, D_damping = 0, W_impulses = -0.97" in text and "E(0) = 0," in text
    assert line(lines, "contact: force transmitted in 4 interval(s)")


@pytest.mark.parametrize("integrator", ["moreau", "moreau-adaptive"])
def test_a_constant_load_does_F_times_the_displacement(tmp_path, integrator):
    """pushed.toml: 2 kg at rest, no gravity, 3 N along x for 0.5 s: W_loads = F x(t) with
    x(t) from the output, = F² t² / (2 m) = 0.5625 J by hand; E(0) = 0. The adaptive
    integrator's accepted step is two half steps: its terms are theirs."""
    s, lines = run(SCENES / "pushed.toml", tmp_path, [f'scene.integrator="{integrator}"'])
    b = s["energy_balance_J"]
    assert b["load_work"] == pytest.approx(3.0 * s["final"]["x"], rel=1e-12)
    assert b["load_work"] == pytest.approx(3.0 ** 2 * 0.5 ** 2 / (2 * 2.0), rel=1e-12)
    assert b["largest"] in ("change", "load_work") and b["relative"] < 1e-12
    assert b["damping_loss"] == b["impulse_work"] == 0.0
    assert "contact_intervals_s" not in s and not any(text.startswith("contact") for text in lines)


def test_a_damper_takes_out_what_the_exact_oscillator_loses(tmp_path):
    """damped.toml: 1 kg on k = 400 N/m, c = 2 N s/m, from the spring's free length at
    0.1 m/s. Exact: x(t) = v0/ω_d e^(−ζω t) sin ω_d t; the damper takes out E(0) − E(t) of
    that solution (the step's error is (ω Δt)² ~ 4e-4 of it, ω Δt = 0.02)."""
    m, k, c, v0, t = 1.0, 400.0, 2.0, 0.1, 0.5
    s, _ = run(SCENES / "damped.toml", tmp_path)
    b = s["energy_balance_J"]
    w0 = math.sqrt(k / m)
    zeta = c / (2 * math.sqrt(k * m))
    wd = w0 * math.sqrt(1 - zeta ** 2)
    x = v0 / wd * math.exp(-zeta * w0 * t) * math.sin(wd * t)
    v = v0 * math.exp(-zeta * w0 * t) * (math.cos(wd * t) - zeta * w0 / wd * math.sin(wd * t))
    lost = 0.5 * m * v0 ** 2 - (0.5 * m * v ** 2 + 0.5 * k * x ** 2)
    assert b["damping_loss"] == pytest.approx(lost, rel=1e-3)
    assert b["largest"] == "damping_loss" and b["relative"] < 1e-10
    assert b["load_work"] == b["impulse_work"] == 0.0


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory):
    """The scene file of a clamped beam (tet4, 5 x 2 x 2 divisions, 6 modes) beside its body."""
    from preprocess import Material, build_body, write_body
    from preprocess.geometry import box

    data = build_body(box(0.25, 0.05, 0.05, None, order=1, divisions=(5, 2, 2)), Material(920.0, 5e7, 0.3),
                      n_modes=6, clamp="x0")
    directory = tmp_path_factory.mktemp("cantilever")
    write_body(directory / "body", data)
    path = directory / "cantilever.toml"
    path.write_text(CANTILEVER)
    return path


def test_a_cantilever_solved_by_the_plan_alone_reaches_its_summary(cantilever, tmp_path):
    """No contact: the plan solves the beam by exact modal propagation, the integrator takes
    no step and keeps an empty trace. The summary gives the sampled energies: E(0) = 0
    (undeformed, at rest), E(t) > 0."""
    s, lines = run(cantilever, tmp_path)
    assert s["steps"] == 0 and s["solved_apart"] == ["beam"] and "energy_balance_J" not in s
    assert s["energy_J"]["initial"] == 0.0 and s["energy_J"]["final"] > 0.0
    assert line(lines, "energy (kinetic + potential of every body, at the output samples): initial 0 J")
    assert line(lines, "energy balance: no time step taken (the plan solves every body apart")
    assert line(lines, "cost: no time step, ")


def test_an_integrated_damped_cantilever_balances_load_work_and_damping(cantilever, tmp_path):
    """The same beam integrated (plan = false): a linear body on a fixed frame, θ = ½, so
    E(t) − E(0) = W_loads − D_damping to rounding; a constant load on a node does
    W_loads = F · u_tip(t) (u_tip the output displacement) exactly."""
    s, lines = run(cantilever, tmp_path, ["scene.plan=false"])
    b = s["energy_balance_J"]
    tip = np.array(s["final"]["tip"])
    assert b["load_work"] == pytest.approx(-20.0 * tip[1], rel=1e-9)
    assert 0.0 < b["damping_loss"] < b["load_work"] and b["impulse_work"] == 0.0
    assert b["largest"] == "load_work" and b["relative"] < 1e-10
    assert "solved_apart" not in s


BALL = """
[[body]]
name = "ball"
kind = "point_mass"
mass = 1.0
position = [1.0, 0.0, 0.0]
velocity = [0.0, 0.0, -1.0]

[[contact]]
name = "floor"
contour1 = { kind = "point", body = "ball" }
contour2 = { kind = "plane", point = [0.0, 0.0, -0.01] }
law = "impact"
"""


def test_a_body_the_plan_solves_apart_is_named_and_left_out_of_the_balance(cantilever, tmp_path):
    """The loaded beam (solved apart by the plan) beside a 1 kg ball at 1 m/s that lands
    plastically (e = 0) on a plane: the balance is the ball's, E(0) = ½ m v² = 0.5 J and
    W_impulses = −0.5 J by hand, no load work (the beam's load is not integrated); the
    sampled energies are every body's (the beam's strain energy at the end)."""
    path = cantilever.with_name("mixed.toml")
    path.write_text(CANTILEVER.replace('name = "cantilever"', 'name = "mixed"') + BALL)
    s, lines = run(path, tmp_path)
    b = s["energy_balance_J"]
    assert s["solved_apart"] == ["beam"]
    assert b["initial"] == 0.5 and b["impulse_work"] == pytest.approx(-0.5, rel=1e-12) and b["load_work"] == 0.0
    assert abs(b["residual"]) < 1e-12 and s["energy_J"]["final"] > 0.0
    assert line(lines, "energy balance of the integrated bodies ('beam' solved apart by the plan, exactly, and "
                       "left out) [J]")
    assert line(lines, "energy (kinetic + potential of every body, at the output samples): initial 0.5 J")


def test_a_compliant_contact_closed_at_the_end_keeps_the_balance(cantilever, tmp_path):
    """0.5 kg at 0.2 m/s lands (e = 0) at 10 ms on the top face of the beam, 2 modes kept
    and the rest as the contact's residual flexibility; the run ends at 10.5 ms with the
    contact pressed. The spring ½ Fᵀδ holds energy the impulses took from the bodies: it is
    in E(t) and not lost, so with θ = ½ the balance closes to rounding (no load, damping
    or gravity); without counting the spring in W_impulses the residual would be all of
    it (h5 trace ``contact_springs``)."""
    import h5py

    path = cantilever.with_name("compliant.toml")
    path.write_text((SCENES / "compliant.toml").read_text())
    s, _ = run(path, tmp_path)
    b = s["energy_balance_J"]
    (start, end), = s["contact_intervals_s"]
    assert start == pytest.approx(0.010, abs=2e-5) and end == pytest.approx(0.0105, abs=1e-12)
    with h5py.File(tmp_path / "compliant.h5") as f:
        held = f["trace/contact_springs"][-1]
    assert held > 1e-3 * b["initial"]                   # the spring holds a sizeable share at the end
    assert abs(b["residual"]) < 1e-10 * held


def test_contact_intervals_are_where_the_contact_force_acts(tmp_path):
    """The puck touches the plane throughout (its gap is 0: closed in every step) but the
    plane pushes back only while the load presses: one interval, 0.1 s to 0.2 s (the load's
    steps; the integrator stops 1e-12 s before each load step)."""
    s, lines = run(SCENES / "pressed.toml", tmp_path / "out")
    iv = s["contact_intervals_s"]
    assert len(iv) == 1 and iv[0] == pytest.approx((0.1, 0.2), abs=1e-9)
    assert line(lines, "contact: force transmitted in 1 interval(s): 100.000-200.000 ms")
    assert s["final"]["z"] == 0.0


# --- the per-step terms (mbs.run.step_work) --------------------------------------------------------

def test_the_energy_term_kernels_are_their_numpy_references():
    from mbs.run import _stage_kernels as SK

    rng = np.random.default_rng(7)
    u, u_prev, Q = rng.normal(size=(3, 9))
    rows = np.array([1, 4, 5, 8], dtype=np.int64)
    A = rng.normal(size=(4, 4))
    D = A @ A.T
    for theta in (0.5, 0.8, 1.0):
        v = theta * u + (1 - theta) * u_prev
        assert SK.path_power(theta, u, u_prev, Q) == pytest.approx(v @ Q, rel=1e-13)
        assert SK.damping_power(theta, u, u_prev, rows, D) == pytest.approx(v[rows] @ D @ v[rows], rel=1e-13)
    warm = np.array([True, True, False, False, True])
    set_valued = np.array([True, True, True, False, False])
    lam_rows = np.array([[0, 3], [3, 1], [4, 3], [7, 0], [7, 0]], dtype=np.int64)
    table = np.zeros((5, SK.TABLE_COLUMNS), dtype=np.int64)        # the contact table's columns
    table[:, SK.LAM_AT], table[:, SK.DIM] = lam_rows.T
    lam_prev, comp_force = np.zeros(7), np.zeros(7)
    lam_prev[1] = 0.1           # contact 0: a tangential impulse only
    comp_force[3] = 2.0         # contact 1: its spring pushes
    lam_prev[5] = 1.0           # contact 2: not closed this step (a stale block)
    closed = np.array([True, True, False, True, True])
    force_N = np.array([0.0, 0.0, 0.0, 0.0, 5.0])    # contact 3 touches without force, 4 pushes
    reference = sum(1 for i in range(5) if (set_valued[i] and warm[i] and (
        lam_prev[lam_rows[i, 0]:][:lam_rows[i, 1]].any() or comp_force[lam_rows[i, 0]:][:lam_rows[i, 1]].any()))
        or (not set_valued[i] and closed[i] and force_N[i] != 0.0))
    assert SK.pressed_contacts(table, warm, lam_prev, comp_force, closed, force_N) == reference == 3
    compliant = np.array([True, True, True, False, True])
    table[:, SK.COMPLIANT] = compliant
    delta = rng.normal(size=7)
    comp_force[:] = rng.normal(size=7)
    springs = sum(0.5 * comp_force[a:a + d] @ delta[a:a + d] for i, (a, d) in enumerate(lam_rows)
                  if compliant[i] and warm[i])
    assert SK.spring_energy(table, warm, comp_force, delta) == pytest.approx(springs, rel=1e-14)


def test_the_trace_terms_allocate_no_more_than_the_step_s_own_loads(cantilever):
    """A damped beam under a tip load, integrated, after warm-up steps: the damping loss and
    the pressed count allocate no numpy array; the load work allocates what the body stage
    allocates for the same load (stage 2: here the FFR point load's own path), nothing more."""
    from numpy_allocations import NumpyAllocations

    from contact.solver import ProxSolver
    from mbs.run import stages
    from mbs.run.model import Data, compile_model
    from mbs.run.step_work import StepWork

    scene = load_scene(cantilever, ["scene.plan=false"])
    model = compile_model(scene.system, None, theta=0.5, solver=ProxSolver("gauss-seidel"))
    data = Data(model)
    data.q[:], data.u[:] = scene.system.initial_state()
    work = StepWork(model)
    assert work.loads and work.damped_rows.size == 6
    dt = 1e-4
    for _ in range(5):
        stages.step(model, data, dt)
        work.load_work(data, dt), work.damping_loss(data, dt), work.pressed(data)
    counts = {}
    for name, call in (("damping and pressed", lambda: work.damping_loss(data, dt) + work.pressed(data)),
                       ("load work", lambda: work.load_work(data, dt)),
                       ("body stage", lambda: stages.bodies(model, data, dt))):
        with NumpyAllocations() as count:
            for _ in range(20):
                call()
        counts[name] = count.sizes
    assert counts["damping and pressed"] == []
    assert counts["load work"] == counts["body stage"]
