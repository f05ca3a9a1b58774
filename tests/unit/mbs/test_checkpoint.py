"""Checkpoints are the run's state as arrays (mbs.results.checkpoint, mbs.results.codec): a run
stopped at an output sample and continued from its checkpoint — the scene built afresh,
the arrays loaded into it — gives the uninterrupted run's result bit for bit, for every
integrator, with contacts closed at the checkpoint, and for a scene of every registered
contour kind, pair kind and contact law (a kind registered without a scene here fails
the coverage test); a checkpoint of another run, a damaged file and a pickle are refused
with one line, and nothing in the file runs.

The oracle is the uninterrupted run of the same scene in the same process, its result
arrays and its result file compared byte for byte."""

from __future__ import annotations

import pickle
import zipfile

import h5py
import numpy as np
import pytest

from contact import BILATERAL_KINEMATICS, LAWS, PAIR_KINEMATICS, connect, make_law
from contours import (CONTOURS, Contour1sNeutralFFR, Contour1sNeutralRigid, Contour2sNeutralFFR,
                      Contour2sNeutralRigid, FlexibleBand, FlexibleCylinder, PlaneContour, PointContour, SphereContour)
from ffrmbs.errors import InputFileError, RunInterrupted
from ffrmbs_app.scenes import point_mass_beam as pmb
from ffrmbs_app.scenes.cache import cache_dir
from mbs import FlexibleBodyFFR, Joint, PointMass, PrescribedFrameMotion, RigidBody, System, ground_frame
from mbs.results import codec
from mbs.results.checkpoint import read_checkpoint
from mbs.run.fused_detection import fused_detection
from mbs.run.model import compile_model
from mbs.integrators import INTEGRATORS, driver, integrator_class
from mbs.links.joints import JOINTS
from mbs.registry import BODIES, LOADS, ROTATIONS
from mbs.results.result_file import ResultRecorder
from mechanism import mechanism


# --- scenes ---------------------------------------------------------------------------------

def beam_on_mass(modes=20, law="impact", contour="2s"):
    """The default scene (setup A): a point mass falling onto the clamped beam."""
    scene = pmb.build(modes=modes, law=law, contour=contour)
    return scene.system, scene.outputs()


def pendulum(modes=4):
    """The default beam as a free FFR body pinned at its frame origin under gravity (a
    joint: λ)."""
    system = System(gravity=(0.0, -9.81, 0.0))
    beam = system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=modes, name="beam"))
    system.add(Joint.revolute(system.ground, beam.origin, axis=(0.0, 0.0, 1.0)))
    tip = beam.node(int(np.argmax(beam.data.u0[:, 0])), name="tip")
    return system, {"tip": tip}


CASES = {   # name: (scene, integrator options, t_end [s], dt [s], samples, stop at [s], contacts closed there)
    "moreau": (beam_on_mass, dict(integrator="moreau", trace=True), 0.016, 1e-5, 161, 0.0125, True),
    "moreau-theta-1-band-penalty": (lambda: beam_on_mass(law="penalty", contour="band"),
                                    dict(integrator="moreau", trace=True, theta=1.0), 0.016, 1e-5, 161, 0.0132,
                                    True),
    "moreau-adaptive": (beam_on_mass, dict(integrator="moreau-adaptive", trace=True, atol=1e-7),
                        0.016, 1e-4, 161, 0.0125, True),
    "generalized-alpha": (pendulum, dict(integrator="generalized-alpha"), 0.02, 1e-3, 21, 0.01, False),
    "rk4": (pendulum, dict(integrator="rk4"), 0.002, 2e-5, 11, 0.001, False),
}


def simulate(case, path, stop_at=None, checkpoint=None, modes=None):
    """Run ``case`` recording to ``path``; with ``stop_at`` [s] stop at the first output
    sample from then on (a checkpoint is taken there); with ``checkpoint`` continue it."""
    make, options, t_end, dt, n_out, *_ = CASES[case]
    system, outputs = make() if modes is None else make(modes=modes)
    return run_scene(system, outputs, options, t_end, dt, n_out, path, stop_at, checkpoint)


def run_scene(system, outputs, options, t_end, dt, n_out, path, stop_at=None, checkpoint=None):
    """``system.simulate`` with ``options`` to ``t_end`` [s] in steps ``dt`` [s], ``n_out``
    samples, energies and contact records, recording to ``path``; ``stop_at`` and
    ``checkpoint`` as for :func:`simulate`."""
    def progress(t):
        if stop_at is not None and t >= stop_at:
            driver.request_stop("test")

    driver.clear_stop()
    try:
        return system.simulate(t_end, dt, t_out=np.linspace(0.0, t_end, n_out), outputs=outputs, energies=True,
                               contacts=bool(system.contacts), progress=progress, checkpoint=checkpoint,
                               recorder=ResultRecorder(path, checkpoint_every=None), **options)
    finally:
        driver.clear_stop()


def datasets(path) -> dict:
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return found


def assert_same_bits(a, b):
    assert sorted(a) == sorted(b)
    for name in a:
        x, y = np.asarray(a[name]), np.asarray(b[name])
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), f"{name} differs"


def result_arrays(res) -> dict:
    arrays = {"t": res.t, "q": res.q, "u": res.u}
    arrays.update({f"outputs/{k}": v for k, v in res.outputs.items()})
    arrays.update({f"energy/{k}": v for k, v in res.energy.items()})
    arrays.update({f"trace/{k}": v for k, v in res.trace.items()})
    arrays.update({f"contacts/{c}/{k}": v for c, rec in res.contacts.items() for k, v in rec.items()})
    return arrays


COUNTERS = ("steps", "newton_iterations", "closed_contacts", "solver_iterations", "max_penetration",
            "pruned_contacts", "rejected_steps", "forced_steps", "smallest_dt", "largest_dt")


def stopped_and_resumed(run, stop_at, d):
    """(uninterrupted result, its file, the checkpoint, resumed result, its file) of
    ``run(path, stop_at=None, checkpoint=None)`` stopped at ``stop_at`` [s], files in ``d``."""
    whole = run(d / "whole.h5")
    with pytest.raises(RunInterrupted):
        run(d / "cut.h5", stop_at=stop_at)
    kept = d / "kept.h5.ckpt"            # the run removes its checkpoint when it completes
    kept.write_bytes((d / "cut.h5.ckpt").read_bytes())
    ckpt = read_checkpoint(kept)
    resumed = run(d / "cut.h5", checkpoint=ckpt)
    return whole, d / "whole.h5", ckpt, resumed, d / "cut.h5"


def assert_resumed_equals_whole(whole, whole_file, ckpt, resumed, resumed_file):
    """The resumed run's result and file equal the uninterrupted run's bit for bit, its
    counters too, and it says where it resumed."""
    assert 0 < ckpt.arrays["run/recorded"] < len(whole.t)
    assert_same_bits(result_arrays(whole), result_arrays(resumed))
    assert_same_bits(datasets(whole_file), datasets(resumed_file))
    for key in COUNTERS:
        assert whole.stats.get(key) == resumed.stats.get(key), key
    assert resumed.stats["resumed_at"] == [float(ckpt.arrays["data/t"])]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """{case: (uninterrupted result, its file, the checkpoint, resumed result, its file)}."""
    return {case: stopped_and_resumed(lambda path, **kw: simulate(case, path, **kw), CASES[case][5],
                                      tmp_path_factory.mktemp(case))
            for case in CASES}


@pytest.mark.parametrize("case", list(CASES))
def test_a_resumed_run_equals_the_uninterrupted_one_bit_for_bit(runs, case):
    ckpt = runs[case][2]
    assert bool(ckpt.arrays["data/closed"].any()) == CASES[case][6], "the checkpoint is taken with the contact closed"
    assert_resumed_equals_whole(*runs[case])


def test_a_checkpoint_holds_only_plain_arrays(runs):
    """Every entry a numeric, boolean or text array: nothing that needs code to build."""
    ckpt = runs["moreau"][2]
    with zipfile.ZipFile(ckpt.path) as z:
        assert all(i.compress_type == zipfile.ZIP_STORED for i in z.infolist())
    for name, value in ckpt.arrays.items():
        assert value.dtype.kind in "biufU", name
    assert {"data/q", "data/u", "data/lam_prev", "integrator/trace/energy", "data/contact_f", "data/contact_i",
            "result/outputs/y"} <= set(ckpt.arrays)
    assert not any(name.startswith(("contour/", "contact/")) for name in ckpt.arrays), "the contact state is Data"


def test_the_contour_and_search_state_is_in_the_checkpoint(runs):
    """The contours' and contacts' run state is Data's ``contact_f``/``contact_i``: at the
    places the Model gives the contour's state vector (R, A, q_f, …) equals the body
    state at the last midpoint, the search's warm start is a point of the contour's
    domain and its counters count the Newton solves."""
    ckpt = runs["moreau"][2]
    system, _ = beam_on_mass()
    model = compile_model(system)
    k = model.contacts[0].kinematics
    places = {(id(obj), name): (pool, at, shape) for obj, name, pool, at, shape in model.contact_state.slots}

    def saved(obj, name):
        pool, at, shape = places[id(obj), name]
        vector = ckpt.arrays["data/contact_f" if pool == 0 else "data/contact_i"]
        return vector[at:at + int(np.prod(shape))].reshape(shape)

    eta, xi = saved(k, "start")
    assert 0.0 <= eta <= 1.0 and 0.0 <= xi <= 1.0
    modes = 20
    assert np.array_equal(saved(k.contour2, "_state")[-2 * modes:-modes], ckpt.arrays["data/q_m"][:modes])
    assert saved(k.search, "counts")[0] > 0


# --- every contour kind, pair kind and law -----------------------------------------------------

GAP, SPEED = 1e-5, 0.05          # [m] the moving side starts this far above the surface, [m/s] its speed
LAW_PARAMETERS = {"impact": {}, "coulomb": {"e": 0.0, "mu": 0.3}, "penalty": {"k": 1e4, "d": 1.0}, "bilateral": {}}


def moving_side(system, kind, at, up, bilateral):
    """A 50 g point mass (``kind`` "point") or a ball of radius 10 mm ("sphere") touching
    down at ``at`` [m] from ``GAP`` above along ``up``, sliding along x at ``SPEED``;
    on the curve and moving along it only, for a ``bilateral`` law. (contour, frame)."""
    up = np.asarray(up, dtype=float)
    gap = 0.0 if bilateral else GAP
    velocity = (SPEED, 0.0, 0.0) - (0.0 if bilateral else SPEED) * up
    if kind == "point":
        bob = system.add(PointMass(0.05, position=at + gap * up, velocity=velocity, name="bob"))
        return PointContour(bob.point), bob.point
    radius = 0.01
    ball = system.add(RigidBody(0.05, 2e-6 * np.eye(3), name="ball").set_initial(R=at + (gap + radius) * up,
                                                                                   v=velocity))
    return SphereContour(ball.origin, radius), ball.origin


def beam_scene(pair, law):
    """The clamped 250 x 50 x 50 mm beam (4 modes, frame fixed, gravity −y) with the
    surface kind ``pair[1]`` on it — the top face (2s; with residual flexibility for a
    point), the top face's centre line (1s), a band on it, a cylinder of radius 25 mm
    around the beam's axis, the top front edge (edge) — and the side ``pair[0]`` landing
    at x = 0.2 m on top (on the edge for an edge)."""
    system = System(gravity=(0.0, -9.81, 0.0))
    system.cache_dir = cache_dir()
    beam = system.add(FlexibleBodyFFR(pmb.default_beam_data(), modes=4, frame=PrescribedFrameMotion.fixed(),
                                      name="beam"))
    top = lambda: Contour1sNeutralFFR.along_line(beam, (0.0, 0.05, 0.025), (1, 0, 0), normal=(0, 1, 0),  # noqa: E731
                                                 degree=4)
    surface = {"2s": lambda: Contour2sNeutralFFR(beam, "y1", residual_flexibility=pair[0] == "point"),
               "1s": top, "band": lambda: FlexibleBand(top(), width=0.05),
               "edge": lambda: CONTOURS["edge"].along_line(beam, (0.0, 0.05, 0.05), (1, 0, 0), normal=(0, 1, 0),
                                                          degree=4),
               "cylinder": lambda: FlexibleCylinder(Contour1sNeutralFFR.along_line(
                   beam, (0.0, 0.025, 0.025), (1, 0, 0), normal=(0, 1, 0), degree=4), radius=0.025)}[pair[1]]()
    at = np.array([0.2, 0.05, 0.05 if pair[1] == "edge" else 0.025])
    side, frame = moving_side(system, pair[0], at, (0, 1, 0), law == "bilateral")
    system.add(connect(side, surface, make_law(law, **LAW_PARAMETERS[law]), name="contact"))
    return system, {"x": frame}


def table_scene(pair, law):
    """Under gravity −z, the side ``pair[0]`` landing at the origin on the surface kind
    ``pair[1]``: a rigid table welded to the ground (2s-rigid: a 200 mm square; 1s-rigid:
    a 200 mm line along x), the ground plane z = 0, or a ground sphere of radius 0.1 m
    whose top is the origin."""
    system = System(gravity=(0.0, 0.0, -9.81))
    if pair[1] in ("2s-rigid", "1s-rigid"):
        table = system.add(RigidBody(10.0, 0.1 * np.eye(3), name="table"))
        system.add(Joint.fixed(system.ground, table.origin))
        s = np.linspace(-0.1, 0.1, 5)
        if pair[1] == "2s-rigid":
            grid = np.stack(np.meshgrid(s, s, [0.0], indexing="ij"), axis=-1)[:, :, 0]
            surface = Contour2sNeutralRigid(table, grid, outward=1)
        else:
            surface = Contour1sNeutralRigid(table, np.stack((s, 0 * s, 0 * s), axis=-1), normal=(0, 0, 1))
    elif pair[1] == "plane":
        surface = PlaneContour(ground_frame())
    else:
        surface = SphereContour(ground_frame((0.0, 0.0, -0.1)), 0.1)
    side, frame = moving_side(system, pair[0], np.zeros(3), (0, 0, 1), law == "bilateral")
    system.add(connect(side, surface, make_law(law, **LAW_PARAMETERS[law]), name="contact"))
    return system, {"x": frame}


KIND_SCENES = {     # (contour pair, law): the scene's builder
    (("point", "2s"), "impact"): beam_scene, (("sphere", "2s"), "coulomb"): beam_scene,
    (("point", "band"), "penalty"): beam_scene, (("sphere", "band"), "impact"): beam_scene,
    (("point", "cylinder"), "coulomb"): beam_scene, (("sphere", "cylinder"), "penalty"): beam_scene,
    (("point", "1s"), "impact"): beam_scene, (("sphere", "1s"), "coulomb"): beam_scene,
    (("point", "1s"), "bilateral"): beam_scene,
    (("point", "2s-rigid"), "coulomb"): table_scene, (("sphere", "2s-rigid"), "impact"): table_scene,
    (("point", "1s-rigid"), "penalty"): table_scene, (("sphere", "1s-rigid"), "impact"): table_scene,
    (("point", "1s-rigid"), "bilateral"): table_scene,
    (("point", "plane"), "coulomb"): table_scene, (("sphere", "plane"), "impact"): table_scene,
    (("sphere", "sphere"), "penalty"): table_scene, (("point", "sphere"), "impact"): table_scene,
}
KIND_SCENES[("sphere", "edge"), "coulomb"] = beam_scene    # a sharp edge (a hole's rim): the beam's top front edge
KIND_RUN = dict(options=dict(integrator="moreau", trace=True), t_end=2e-3, dt=1e-4, n_out=5)
KIND_STOP = 5e-4        # [s] the checkpoint: the contact closed (it closes at 0.2 ms)


def kind_id(key):
    (side1, side2), law = key
    return f"{side1}-{side2}-{law}"


def test_every_registered_contour_pair_and_law_has_a_checkpoint_scene():
    """The scenes below cover every registered contour kind, pair (unilateral with a
    unilateral law, bilateral with "bilateral") and law, each built through the
    registries: a kind registered without a scene here fails."""
    built = set()
    for (pair, law), make in KIND_SCENES.items():
        system, _ = make(pair, law)
        contact, = system.contacts
        k = contact.kinematics
        built.add(((CONTOURS.name_of(k.contour1), CONTOURS.name_of(k.contour2)), LAWS.name_of(contact.law)))
    assert built == set(KIND_SCENES)
    unilateral = {pair for pair, law in built if law != "bilateral"}
    bilateral = {pair for pair, law in built if law == "bilateral"}
    assert set(PAIR_KINEMATICS.names()) <= unilateral, "a pair kind without a scene"
    assert set(BILATERAL_KINEMATICS.names()) <= bilateral, "a bilateral pair kind without a scene"
    assert {kind for pair in unilateral | bilateral for kind in pair} == set(CONTOURS.names())
    assert {law for _, law in built} == set(LAWS.names())



def test_every_registered_pair_kind_has_a_fused_detection():
    """Each scene's contact — every registered pair kind, unilateral and bilateral, on the
    beam at rest, on a rigid table and on the ground, side 1 on a point mass or a rigid
    ball — has a compiled detection (mbs.run.fused_detection): a pair kind registered
    without its kernel fails here instead of running the Python path."""
    missing = []
    for (pair, law), make in KIND_SCENES.items():
        system, _ = make(pair, law)
        if fused_detection(system.contacts[0]) is None:
            missing.append(f"{pair[0]}/{pair[1]} ({law})")
    assert not missing, f"pair kinds without a fused detection: {', '.join(missing)}"

@pytest.mark.parametrize("key", [pytest.param(key, id=kind_id(key), marks=() if key[1] == "bilateral" else
                                              pytest.mark.slow) for key in KIND_SCENES])
def test_a_resumed_run_of_every_kind_equals_the_uninterrupted_one(key, tmp_path):
    """Stopped at 0.5 ms with the contact closed (the compliant spring's state, the
    searches' warm starts, the bead on its curve), resumed from the checkpoint: the
    uninterrupted run bit for bit. About a second each: the bilateral scenes are in the
    fast subset, the others marked slow."""
    pair, law = key

    def run(path, **kw):
        system, outputs = KIND_SCENES[key](pair, law)
        return run_scene(system, outputs, **KIND_RUN, path=path, **kw)

    runs = stopped_and_resumed(run, KIND_STOP, tmp_path)
    ckpt = runs[2]
    assert ckpt.arrays["data/closed"].all(), "the checkpoint is taken with the contact closed"
    assert_resumed_equals_whole(*runs)


# --- every body kind, rotation parametrization, joint kind, load kind and integrator ---------

MECHANISM_RUNS = {   # integrator: (options, t_end [s], dt [s], samples, stop at [s])
    "moreau": (dict(integrator="moreau", trace=True), 2e-3, 1e-4, 11, 1e-3),
    "moreau-adaptive": (dict(integrator="moreau-adaptive", trace=True, atol=1e-7), 2e-3, 1e-4, 11, 1e-3),
    "generalized-alpha": (dict(integrator="generalized-alpha"), 2e-3, 1e-4, 11, 1e-3),
    "rk4": (dict(integrator="rk4"), 1e-3, 2e-5, 11, 6e-4),
}


def test_the_mechanism_has_every_registered_kind_and_every_integrator_runs_it():
    """A body, rotation parametrization, joint, load kind or integrator registered without
    a place in :func:`mechanism` and :data:`MECHANISM_RUNS` fails here."""
    system, _ = mechanism()
    assert {BODIES.name_of(b) for b in system.bodies} == set(BODIES.names())
    assert {ROTATIONS.name_of(b.param) for b in system.bodies if getattr(b, "param", None)} == set(ROTATIONS.names())
    assert {j.kind for j in system.constraints} == set(JOINTS.names())
    assert {LOADS.name_of(f) for f in system.forces} - {None} == set(LOADS.names())
    assert set(MECHANISM_RUNS) == set(INTEGRATORS.names())


@pytest.mark.parametrize("integrator", list(MECHANISM_RUNS))
def test_a_resumed_mechanism_equals_the_uninterrupted_one(integrator, tmp_path):
    """Stopped halfway (the nodal forces stepped, every joint's λ and the integrator's own
    state in the checkpoint), resumed: the uninterrupted run bit for bit, and the
    mechanism moved (the slider slid, the beam turned)."""
    options, t_end, dt, n_out, stop_at = MECHANISM_RUNS[integrator]

    def run(path, **kw):
        system, outputs = mechanism()
        return run_scene(system, outputs, options, t_end, dt, n_out, path, **kw)

    runs = stopped_and_resumed(run, stop_at, tmp_path)
    assert_resumed_equals_whole(*runs)
    whole = runs[0]
    assert whole.t[-1] == pytest.approx(t_end)
    assert np.all(np.isfinite(whole.q))
    assert whole["slider"][-1, 0] > 0.0 and not np.array_equal(whole["tip"][-1], whole["tip"][0])


def started(system, integrator, dt, t_end, **options):
    """``integrator`` prepared on ``system`` for a run to ``t_end`` [s] in steps ``dt`` [s]
    (no plan, no outputs) and started at its initial state."""
    integ = integrator_class(integrator)(system, **options)
    q0, u0 = system.initial_state()
    integ.dt = dt
    integ.state = integ._prepare(q0, u0, t_end, dt, None, {}, False, (), None, False)
    integ.start(integ.t, integ.q, integ.u)
    return integ


def run_state(integ) -> dict:
    """What a checkpoint keeps of ``integ``'s Data (its contours' and contacts' run state
    included), but the factors of M̂ kept per step size (a cache)."""
    arrays, kinds = {}, {}
    integ.data.collect("data", arrays, kinds)
    return {key: np.array(value) for key, value in arrays.items() if not key.startswith("data/factors/")}


@pytest.mark.parametrize("key", [(("point", "2s"), "impact"), (("sphere", "band"), "impact")], ids=kind_id)
def test_a_step_the_adaptive_integrator_takes_back_leaves_no_trace(key):
    """Step doubling takes a step of H, puts the state back and takes two of H/2: those
    must start from the state before the step of H — the compliant spring's force and
    deflection, the contact searches' warm starts and counters included — i.e. equal
    bit for bit two steps of H/2 of the same scene that never took the step of H."""
    pair, law = key
    h, t_closed = 1e-4, 5e-4          # [s] the step of H is taken with the contact closed
    taken_back, direct = (started(KIND_SCENES[key](pair, law)[0], "moreau-adaptive", h, 2e-3) for _ in range(2))
    for integ in (taken_back, direct):
        integ.advance(t_closed, h)
        assert integ.data.closed.all()
    taken_back._save()
    taken_back.step(h)
    taken_back._restore()
    for integ in (taken_back, direct):
        integ.step(0.5 * h)
        integ.step(0.5 * h)
    assert_same_bits(run_state(direct), run_state(taken_back))


# --- refusals --------------------------------------------------------------------------------

def _resume_error(case, ckpt, tmp_path, **kw):
    with pytest.raises(InputFileError) as err:
        simulate(case, tmp_path / "other.h5", checkpoint=ckpt, **kw)
    message = str(err.value)
    assert "\n" not in message and str(ckpt.path) in message
    return message


def test_a_checkpoint_of_another_mode_count_is_refused(runs, tmp_path):
    message = _resume_error("moreau", runs["moreau"][2], tmp_path, modes=10)
    assert "a checkpoint of another run: its bodies" in message and "restart the run" in message


def test_a_checkpoint_of_another_integrator_is_refused(runs, tmp_path):
    ckpt = runs["generalized-alpha"][2]
    message = _resume_error("rk4", ckpt, tmp_path)
    assert "its integrator is '\"generalized-alpha\"'" in message


def test_an_array_of_the_wrong_shape_is_refused(runs, tmp_path):
    ckpt = runs["moreau"][2]
    edited = read_checkpoint(ckpt.path)
    edited.arrays["data/lam_prev"] = np.zeros(7)
    message = _resume_error("moreau", edited, tmp_path)
    assert "data/lam_prev has shape (7,) float64, this run's (1,) float64" in message


def test_a_missing_array_is_refused(runs, tmp_path):
    edited = read_checkpoint(runs["moreau"][2].path)
    del edited.arrays["data/contact_f"]
    assert "data/contact_f is missing" in _resume_error("moreau", edited, tmp_path)


@pytest.mark.parametrize("magic", [b"ffrmbs-checkpoint-1\n", b"ffrmbs-checkpoint-2\n" + b"0" * 64 + b"\n"])
def test_an_old_pickled_checkpoint_is_refused_unread(tmp_path, magic):
    marker = tmp_path / "marker"
    ckpt = tmp_path / "x.h5.ckpt"
    ckpt.write_bytes(magic + pickle.dumps(_Plant(marker)))
    with pytest.raises(InputFileError, match=r"a pickled checkpoint of an older ffrmbs \(ffrmbs-checkpoint-[12]"
                                             r"\): refused unread"):
        read_checkpoint(ckpt)
    assert not marker.exists()


class _Plant:
    """A pickle that, once loaded, creates the file ``marker`` (the stand-in of os.system)."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return type(self.marker).touch, (self.marker,)


@pytest.mark.parametrize("where", ["plain pickle", "object array in an npz"])
def test_a_planted_pickle_is_refused_and_runs_nothing(tmp_path, where):
    marker = tmp_path / "marker"
    ckpt = tmp_path / "x.h5.ckpt"
    if where == "plain pickle":
        ckpt.write_bytes(pickle.dumps(_Plant(marker)))
    else:
        with open(ckpt, "wb") as f:
            np.savez(f, header=np.frombuffer(b'{"format": "ffrmbs-checkpoint"}', dtype=np.uint8),
                     plant=np.array([_Plant(marker)], dtype=object))
    with pytest.raises(InputFileError, match="not an ffrmbs checkpoint, or damaged"):
        read_checkpoint(ckpt)
    assert not marker.exists()


@pytest.mark.parametrize("damage", ["cut in half", "one byte changed", "empty", "text"])
def test_a_damaged_checkpoint_is_one_clear_line(runs, tmp_path, damage):
    data = runs["moreau"][2].path.read_bytes()
    ckpt = tmp_path / "x.h5.ckpt"
    if damage == "cut in half":
        data = data[:len(data) // 2]
    elif damage == "one byte changed":
        with zipfile.ZipFile(runs["moreau"][2].path) as z:
            info = z.getinfo("data/q.npy")
        at = info.header_offset + 30 + len(info.filename) + len(info.extra) + info.file_size - 3   # inside q's data
        data = data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1:]
    elif damage == "empty":
        data = b""
    else:
        data = b"garbage\n" * 10
    ckpt.write_bytes(data)
    with pytest.raises(InputFileError) as err:
        read_checkpoint(ckpt)
    message = str(err.value)
    assert "\n" not in message and "x.h5.ckpt" in message and "checkpoint" in message


def test_a_directory_as_checkpoint_is_refused(tmp_path):
    (tmp_path / "x.h5.ckpt").mkdir()
    with pytest.raises(InputFileError, match="not a regular file"):
        read_checkpoint(tmp_path / "x.h5.ckpt")


# --- the codec ---------------------------------------------------------------------------------

VALUES = {"x": 2.5, "n": 7, "flag": False, "h": 1e-3, "start": (0.125, 0.75), "nothing": None}


def test_the_codec_round_trip_keeps_types_and_views():
    """Scalars come back as their Python types, tuples as tuples, None as None, and an
    array is written into the one the fresh run holds (a view of it stays one)."""
    arrays, kinds = {}, {}
    for key, value in VALUES.items():
        codec.put(key, value, arrays, kinds)
    codec.put("a", np.array([1.0, 2.0, 3.0, 4.0]), arrays, kinds)
    assert kinds == {"x": "float", "n": "int", "flag": "bool", "h": "float", "start": "tuple", "nothing": "none",
                     "a": "array"}
    back = {key: codec.take(key, None, arrays, kinds) for key in VALUES}
    assert back == VALUES
    assert [type(back[k]) for k in ("x", "n", "flag", "start")] == [float, int, bool, tuple]
    base = np.zeros(4)
    view = base[1:3]
    assert codec.take("a", base, arrays, kinds) is base
    assert np.array_equal(view, [2.0, 3.0])


def test_the_codec_refuses_what_does_not_fit():
    arrays, kinds = {}, {}
    codec.put("a", np.zeros(5), arrays, kinds)
    codec.put("n", 3, arrays, kinds)
    with pytest.raises(codec.StateMismatch, match=r"a has shape \(5,\) float64, this run's \(3,\) float64"):
        codec.take("a", np.zeros(3), arrays, kinds)
    arrays["n"] = np.array(1.5)
    with pytest.raises(codec.StateMismatch, match="n is not a int"):
        codec.take("n", 0, arrays, kinds)
    with pytest.raises(codec.StateMismatch, match="b is missing"):
        codec.take("b", None, arrays, kinds)
