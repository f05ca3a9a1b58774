"""ffrmbs.vec3.cross3 against numpy's cross product: the same bits for a vector and,
column by column, for a (3, n) Jacobian and two (3, n) arrays (mbs.links.joints' rows)."""

import numpy as np

from ffrmbs.vec3 import cross3


def test_cross3_equals_numpy_cross_to_the_bit():
    rng = np.random.default_rng(7)
    a, b, J = rng.normal(size=3), rng.normal(size=3), rng.normal(size=(3, 5))
    assert np.array_equal(cross3(a, b), np.cross(a, b))
    assert np.array_equal(cross3(a, J), np.cross(a[:, None], J, axis=0))
    assert np.array_equal(cross3(J, b), np.cross(J, b[:, None], axis=0))           # rows of mbs.links.joints
    assert np.array_equal(cross3(J, J[::-1]), np.cross(J, J[::-1], axis=0))
    assert np.array_equal(cross3(a, a), np.zeros(3))                   # and it is a cross product
    assert np.array_equal(cross3(np.eye(3)[0], np.eye(3)[1]), np.eye(3)[2])
