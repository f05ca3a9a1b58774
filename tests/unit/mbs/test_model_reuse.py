"""One Model, many Datas (System.compile, simulate(model=...)): runs on a Model compiled
once — after other runs on it, of another Δt and length — equal the runs of freshly built
scenes bit for bit; a Model of other options or of another System is refused."""

import numpy as np
import pytest

from ffrmbs.errors import ModelError
from ffrmbs_app.scenes import point_mass_beam as pmb

T_END, DT = 0.02, 1e-5        # [s] the contact closes at 10 ms
RUN = dict(integrator="moreau", theta=0.5, trace=True, contacts=True)


def _run(scene, dt=DT, t_end=T_END, model=None):
    return scene.system.simulate(t_end, dt, t_out=np.linspace(0.0, t_end, 21), outputs=scene.outputs(),
                                 model=model, **RUN)


def _same(a, b):
    assert np.array_equal(a.t, b.t) and np.array_equal(a.q, b.q) and np.array_equal(a.u, b.u)
    for name in a.outputs:
        assert np.array_equal(a[name], b[name]), name
    for key in a.trace:
        assert np.array_equal(a.trace[key], b.trace[key]), key
    for name, rec in a.contacts.items():
        for key, values in rec.items():
            assert np.array_equal(values, b.contacts[name][key], equal_nan=True), (name, key)


@pytest.mark.parametrize("law", ["impact", "penalty"])
def test_runs_on_one_model_equal_runs_of_fresh_scenes(law):
    """A warm-up (Δt = 1e-4 s, 12.5 ms), the run and its Δt/2 check on one Model, as the
    job runs them, against each run on a scene built afresh: bit for bit, the contact
    state (warm starts, searches' counters and length scale, residual springs) included."""
    scene = pmb.build("A", modes=20, law=law)
    model, _ = scene.system.compile(T_END, integrator="moreau", theta=0.5, trace=True)
    _run(scene, dt=1e-4, t_end=0.0125, model=model)
    run = _run(scene, model=model)
    half = _run(scene, dt=0.5 * DT, model=model)
    assert run.trace["pressed"].any(), "the contact transmits a force in the run"
    _same(run, _run(pmb.build("A", modes=20, law=law)))
    _same(half, _run(pmb.build("A", modes=20, law=law), dt=0.5 * DT))


def test_a_model_of_other_options_or_another_system_is_refused():
    scene = pmb.build("A", modes=20)
    model, _ = scene.system.compile(T_END, integrator="moreau", theta=0.5)
    with pytest.raises(ModelError, match="compiled with theta = 0.5 .* this run asks for theta = 1"):
        scene.system.simulate(T_END, DT, integrator="moreau", theta=1.0, model=model)
    with pytest.raises(ModelError, match="another System"):
        pmb.build("A", modes=20).system.simulate(T_END, DT, integrator="moreau", model=model)


def test_a_body_in_two_systems_runs_in_each_at_its_own_rows():
    """The beam, the mass and their contact of one scene also in a second System, after
    a drifting point mass that takes that System's first rows: the bodies' rows are those
    of the System that runs (its Model's layout, given back when a Data is made), so runs
    of the two Models taken in turn equal a fresh scene's run bit for bit, and the extra
    mass drifts at its speed (z = z₀ + v t)."""
    from mbs import PointMass, System

    scene = pmb.build("A", modes=20)
    other = System()
    drop = other.add(PointMass(1.0, position=(0.0, 0.0, 5.0), velocity=(0.0, 0.0, 2.0), name="drop"))
    for item in (scene.beam, scene.mass, scene.contact):
        other.add(item)
    assert (scene.mass.q_slice, drop.q_slice) == (slice(3 + scene.beam.nq, 6 + scene.beam.nq), slice(0, 3))
    model_a, _ = scene.system.compile(T_END, integrator="moreau", theta=0.5, trace=True)
    model_b, _ = other.compile(T_END, integrator="moreau", theta=0.5, trace=True)
    run_b = other.simulate(T_END, DT, t_out=np.linspace(0.0, T_END, 21), outputs=scene.outputs(), model=model_b,
                           **RUN)          # the scene's outputs read the rows of the System that runs
    run_a = _run(scene, model=model_a)
    _same(run_a, _run(pmb.build("A", modes=20)))
    for name in run_a.outputs:
        assert np.array_equal(run_a[name], run_b[name]), name
    t = run_b.t
    assert np.allclose(run_b.q[:, 2], 5.0 + 2.0 * t, rtol=0.0, atol=1e-11)      # 2000 sums of ~5 m
    with pytest.raises(ModelError, match="already in this system"):
        other.add(drop)


@pytest.mark.parametrize("law", ["impact", "penalty"])
def test_a_system_simulated_twice_runs_alike(law):
    """simulate() twice on one System (each compiles a Model, the second after the first
    run left the contact state in its Data): no error, and the second run equals the first
    bit for bit — it starts from the contact state of the first, not from where it ended."""
    scene = pmb.build("A", modes=20, law=law)
    first, second = _run(scene), _run(scene)
    assert first.trace["pressed"].any(), "the contact transmits a force in the run"
    _same(first, second)
