"""Property: any body of accepted values (finite, |value| <= MAX_MAGNITUDE) survives the
thesis's text files bit for bit (SI)."""

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from preprocess.body import MAX_MAGNITUDE, BodyData
from preprocess.textfiles import read_text_body, write_text_body

finite = st.floats(min_value=-MAX_MAGNITUDE, max_value=MAX_MAGNITUDE, width=64)
positive = st.floats(min_value=1e-300, max_value=MAX_MAGNITUDE)


@st.composite
def bodies(draw):
    n = draw(st.integers(1, 4))
    n_f = draw(st.integers(1, 3))
    u0 = draw(arrays(np.float64, (n, 3), elements=finite))
    phi = draw(arrays(np.float64, (3 * n, n_f), elements=finite))
    masses = draw(arrays(np.float64, (n,), elements=positive))
    lower = np.tril(draw(arrays(np.float64, (3 * n, 3 * n), elements=finite)))
    lower[np.diag_indices(3 * n)] = draw(arrays(np.float64, (3 * n,), elements=positive))
    K = sp.csr_matrix(lower + np.tril(lower, -1).T)
    return BodyData(u0=u0, phi=phi, masses=masses, stiffness=K)


@settings(max_examples=40, deadline=None)
@given(body=bodies())
def test_text_files_round_trip_bitwise(tmp_path_factory, body):
    d = tmp_path_factory.mktemp("body")
    write_text_body(d, body)
    back = read_text_body(d)
    np.testing.assert_array_equal(back.u0, body.u0)
    np.testing.assert_array_equal(back.phi, body.phi)
    np.testing.assert_array_equal(back.masses, body.masses)
    np.testing.assert_array_equal(back.stiffness.toarray(), body.stiffness.toarray())


def test_zero_stiffness_is_refused_before_writing(tmp_path):
    import pytest

    from ffrmbs.errors import ModelError

    body = BodyData(u0=np.zeros((1, 3)), phi=np.ones((3, 1)), masses=np.ones(1),
                    stiffness=sp.csr_matrix((3, 3)))
    with pytest.raises(ModelError, match="stiffness matrix is zero"):
        write_text_body(tmp_path, body)
    assert not any(tmp_path.iterdir())
