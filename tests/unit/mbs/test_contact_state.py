"""The contours' and contacts' run state lies in Data (mbs.run.contact_state): for every
registered pair kind each state array of the contours, points, kinematics and searches is
a view of Data's two vectors, and so are the arrays the fused detection's kernel takes;
the closed contacts' columns of W and closing terms read from Data through the Model's
contact table are those of the contact objects;
a view that a class forgets to re-derive is refused when Data is made; a second Data of
the same Model starts afresh and takes the state over, the first one keeps what it had;
a System compiled again after a run starts from its first contact state."""

import numpy as np
import pytest

from contact import BILATERAL_KINEMATICS, PAIR_KINEMATICS, UnilateralCoulombContact
from contact.solver import ProxSolver
from mbs.run import _stage_kernels as SK
from mbs.run import stages
from mbs.run.contact_state import ContactState
from mbs.run.model import Data, compile_model
from validation.bench.pair_cost import pair_scene

PAIRS = [(pair, False) for pair in PAIR_KINEMATICS.names()] + [(pair, True) for pair in BILATERAL_KINEMATICS.names()]


def _model(pair, bilateral, law="impact"):
    system, contact, q, u = pair_scene(pair, bilateral, law=law)
    model = compile_model(system, None, theta=0.5, solver=ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000))
    return model, q, u


def _in(array, data) -> bool:
    return np.shares_memory(array, data.contact_f) or np.shares_memory(array, data.contact_i)


@pytest.mark.parametrize("pair, bilateral", PAIRS, ids=lambda v: "/".join(v) if isinstance(v, tuple) else str(v))
def test_every_state_array_and_kernel_argument_is_data(pair, bilateral):
    model, q, u = _model(pair, bilateral)
    data = Data(model)
    assert model.contact_state.slots, "the pair keeps run state"
    for obj, name, *_ in model.contact_state.slots:
        assert _in(getattr(obj, name), data), f"{type(obj).__name__}.{name}"
    fused = model.fused[0]
    k = fused.kinematics
    args = [a for a in fused._args if isinstance(a, np.ndarray)]
    for array in (k.buffer, k.point1.buffer, k.point2.buffer, k.contour1.state if hasattr(k.contour1, "state")
                  else k.contour1._state):
        assert any(a is array for a in args) and _in(array, data)


class _Forgetful:
    """State in ``buffer`` whose bind_views forgets the view ``head``."""

    state_slots = ("buffer",)

    def __init__(self):
        self.buffer = np.arange(4.0)
        self.head = self.buffer[:2]

    def bind_views(self):
        pass


class _Careful(_Forgetful):
    def bind_views(self):
        self.head = self.buffer[:2]


def test_a_view_left_on_the_old_memory_is_refused():
    state = ContactState([_Forgetful()])
    with pytest.raises(RuntimeError, match=r"_Forgetful\.head"):
        state.bind(*state.pools())
    careful = _Careful()
    state = ContactState([careful])
    f, i = state.pools()
    state.bind(f, i)
    careful.head[0] = 7.0
    assert f[0] == 7.0 and np.array_equal(f, [7.0, 1.0, 2.0, 3.0])


def test_state_that_is_no_array_is_refused():
    thing = _Careful()
    thing.buffer = 1.5
    with pytest.raises(TypeError, match=r"_Careful\.buffer: run state must be a float64 or int64 array"):
        ContactState([thing])


def test_a_second_data_starts_afresh_and_takes_the_state_over():
    """A second Data of the same Model starts from the contact state the first started
    from (the Model's, not where the first run stands); steps on it change its vectors,
    not the first's, and give what the first run's steps gave."""
    model, q, u = _model(("point", "2s"), False)
    first = Data(model)
    start_f, start_i = first.contact_f.copy(), first.contact_i.copy()
    first.q[:], first.u[:] = q, u
    for _ in range(5):
        stages.step(model, first, 1e-5)
    kept_f, kept_i = first.contact_f.copy(), first.contact_i.copy()
    assert not np.array_equal(kept_f, start_f, equal_nan=True)
    second = Data(model)
    assert np.array_equal(second.contact_f, start_f, equal_nan=True) and np.array_equal(second.contact_i, start_i)
    second.q[:], second.u[:] = q, u
    for _ in range(5):
        stages.step(model, second, 1e-5)
    assert np.array_equal(second.contact_f, kept_f, equal_nan=True) and np.array_equal(second.contact_i, kept_i)
    assert np.array_equal(second.q, first.q) and np.array_equal(second.u, first.u)
    for _ in range(5):
        stages.step(model, second, 1e-5)
    assert np.array_equal(first.contact_f, kept_f, equal_nan=True) and np.array_equal(first.contact_i, kept_i)


@pytest.mark.parametrize("pair, bilateral", PAIRS, ids=lambda v: "/".join(v) if isinstance(v, tuple) else str(v))
def test_a_system_compiled_again_after_a_run_lays_out_its_first_state(pair, bilateral):
    """Every pair kind: a second Model of the System, compiled while the contact state is
    a first run's Data, finds the same slots (the views told apart by memory, not by
    owner) and starts from the state the first started from, not where that run stands;
    five steps on it give what the first run's five steps gave."""
    system, contact, q, u = pair_scene(pair, bilateral)
    solver = ProxSolver("gauss-seidel", tol=1e-10, max_iter=2000)
    first_model = compile_model(system, None, theta=0.5, solver=solver)
    first = Data(first_model)
    start_f, start_i = first.contact_f.copy(), first.contact_i.copy()
    first.q[:], first.u[:] = q, u
    for _ in range(5):
        stages.step(first_model, first, 1e-5)
    assert not np.array_equal(first.contact_f, start_f, equal_nan=True)
    model = compile_model(system, None, theta=0.5, solver=solver)
    assert [s[1:] for s in model.contact_state.slots] == [s[1:] for s in first_model.contact_state.slots]
    data = Data(model)
    assert np.array_equal(data.contact_f, start_f, equal_nan=True) and np.array_equal(data.contact_i, start_i)
    data.q[:], data.u[:] = q, u
    for _ in range(5):
        stages.step(model, data, 1e-5)
    assert np.array_equal(data.q, first.q) and np.array_equal(data.u, first.u)
    assert np.array_equal(data.contact_f, first.contact_f, equal_nan=True)


ROWS = [pytest.param(pair, bilateral, law, id=f"{'/'.join(pair)}-{name}")
        for pair, bilateral in PAIRS
        for name, law in ((("bilateral", None),) if bilateral else
                          (("impact", "impact"), ("coulomb", UnilateralCoulombContact(0.0, 0.3))))]


@pytest.mark.parametrize("pair, bilateral, law", ROWS)
@pytest.mark.parametrize("g_N", [None, 4e-13])
def test_the_contact_rows_from_the_table_are_the_contacts_own(pair, bilateral, law, g_N):
    """W's columns of the closed contact (after a joint row's worth of offset) and its
    closing term by :func:`contact_rows_into` over Data and the contact table, against
    ``Contact.jacobian`` and g_N/Δt of the objects, bit for bit — W_N alone (impact),
    with W_T (Coulomb), [w_N, w_T2] (a point kept on a curve); pressed in (no closing)
    and resting 4e-13 m apart (closing g_N/Δt for a unilateral contact)."""
    model, q, u = _model(pair, bilateral, law)
    data = Data(model)
    contact = model.contacts[0]
    assert model.fused[0].locate(q, u, 0.0)
    if g_N is not None:
        contact.kinematics.g_N = g_N
    n_c, dim, dt = 1, model.dims[0], 1e-5
    warm = np.array([True])
    W, closing = np.zeros((model.nu, n_c + dim)), np.zeros(n_c + dim)
    SK.contact_rows_into(W, closing, data.contact_f, model.contact_table, np.array([0]), 1, n_c, warm, dt)
    W_ref, closing_ref = np.zeros_like(W), np.zeros_like(closing)
    contact.jacobian(W_ref, n_c)
    if contact.unilateral and contact.kinematics.g_N > 0.0:
        closing_ref[n_c] = contact.kinematics.g_N / dt
    assert np.any(W_ref[:, n_c:] != 0.0)
    assert W.tobytes() == W_ref.tobytes() and closing.tobytes() == closing_ref.tobytes()
    assert (closing[n_c] > 0.0) == (g_N is not None and contact.unilateral)

