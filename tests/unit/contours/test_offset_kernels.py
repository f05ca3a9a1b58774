"""The compiled offset contours (band, cylinder) against their numpy reference
(``compiled=False``, :func:`contours.derived.offset_frame`): fields, frame, velocity and
Jacobians at random deformed, moving states and random surface coordinates; the compiled
search's Newton on them (:func:`contact._detection_kernels.newton_offset`) against the
Python Newton over the reference contour."""

import numpy as np
import pytest

from contact.search import Contact2sSearch
from contours import FlexibleBand, FlexibleCylinder
from validation.bench.common import moving_state

L, H, W = 0.25, 0.05, 0.05
RTOL = 1e-12


def contour_pair(kind, axis):
    """(compiled, reference) contours of ``kind`` on the neutral curve ``axis``."""
    if kind == "cylinder":
        return FlexibleCylinder(axis, radius=0.02), FlexibleCylinder(axis, radius=0.02, compiled=False)
    offset = {"band": 0.0, "offset band": H / 2}[kind]
    return FlexibleBand(axis, W, offset), FlexibleBand(axis, W, offset, compiled=False)


def surface_coordinates(contour, rng, n):
    """n random (η, ξ) in the domain, then its corners and points near the ends of η."""
    (ea, eb), (xa, xb) = contour.domain
    coords = list(rng.uniform([ea, xa], [eb, xb], size=(n, 2)))
    coords += [(ea, xa), (eb, xb), (ea + 1e-9, 0.5 * (xa + xb)), (eb - 1e-9, xb - 1e-9), (ea, xb), (eb, xa)]
    return coords


def assert_close(a, b, what):
    scale = max(np.abs(b).max(), 1e-300)
    assert np.abs(a - b).max() <= RTOL * scale, f"{what}: {np.abs(a - b).max() / scale:.2e} relative"


@pytest.mark.parametrize("kind", ["band", "offset band", "cylinder"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compiled_offset_contour_equals_the_numpy_reference(thesis_beam, thesis_centre_line, kind, seed):
    compiled, reference = contour_pair(kind, thesis_centre_line)
    assert compiled.compiled and not reference.compiled
    rng = np.random.default_rng(seed)
    q, u = moving_state(thesis_beam, rng, 3e-3)
    compiled.update(q, u)   # both read the shared neutral contour's state
    pc, pr = compiled.new_point(), reference.new_point()
    for eta, xi in surface_coordinates(compiled, rng, 12):
        compiled.evaluate(pc, eta, xi, velocity=True, jacobians=True)
        reference.evaluate(pr, eta, xi, velocity=True, jacobians=True)
        assert (pc.eta, pc.xi) == (pr.eta, pr.xi) == (eta, xi)
        for row in range(6):
            assert_close(pc.derivs[row], pr.derivs[row], f"{kind} derivs row {row} at {(eta, xi)}")
        assert_close(pc.frame, pr.frame, f"{kind} frame at {(eta, xi)}")
        assert_close(pc.v, pr.v, f"{kind} velocity at {(eta, xi)}")
        assert_close(pc.J_T, pr.J_T, f"{kind} J_T at {(eta, xi)}")
        elastic = slice(thesis_beam.nu - thesis_beam.n_modes, thesis_beam.nu)   # A Φ_P, Φ_P = Φ + G Φ_η
        assert_close(pc.J_T[:, elastic], pr.J_T[:, elastic], f"{kind} J_T elastic block at {(eta, xi)}")
        assert_close(pc.J_R, pr.J_R, f"{kind} J_R at {(eta, xi)}")


def test_compiled_band_without_velocity_or_jacobians_and_out_of_domain(thesis_beam, thesis_centre_line):
    """Fields alone (no Φ formed), and η beyond the ends clipped like the reference."""
    compiled, reference = contour_pair("offset band", thesis_centre_line)
    q, _ = moving_state(thesis_beam, np.random.default_rng(5), 3e-3)
    compiled.update(q)
    pc, pr = compiled.new_point(), reference.new_point()
    for eta, xi in [(0.4, 0.01), (-0.1, 0.02), (1.2, -0.02)]:
        compiled.evaluate(pc, eta, xi)
        reference.evaluate(pr, eta, xi)
        assert_close(pc.derivs, pr.derivs, f"derivs at {(eta, xi)}")
        assert_close(pc.frame, pr.frame, f"frame at {(eta, xi)}")


@pytest.mark.parametrize("kind", ["band", "offset band", "cylinder"])
def test_compiled_newton_on_offset_contours_follows_the_python_newton(thesis_beam, thesis_centre_line, kind):
    """Same roots from the same starts (cold: the coarse level; warm) for points off the
    contour; tolerance 1e-13 so that the two agree to rounding (see
    tests/unit/contact/test_compiled_contact.py)."""
    compiled, reference = contour_pair(kind, thesis_centre_line)
    searches = Contact2sSearch(compiled, tol=1e-13), Contact2sSearch(reference, tol=1e-13, compiled=False)
    assert searches[0].compiled and not searches[1].compiled
    rng = np.random.default_rng(11)
    q, u = moving_state(thesis_beam, np.random.default_rng(12), 3e-3)
    compiled.update(q, u)
    (ea, eb), (xa, xb) = compiled.domain
    point, found_any = compiled.new_point(), 0
    for eta, xi in rng.uniform([ea + 0.05, xa + 0.1 * (xb - xa)], [eb - 0.05, xb - 0.1 * (xb - xa)], size=(8, 2)):
        compiled.evaluate(point, eta, xi)
        r = point.r + rng.uniform(1e-3 if kind == "cylinder" else -2e-3, 4e-3) * point.n
        for start in (None, (eta + 0.04, xi - 0.1 * (xb - xa))):
            found = [s.solve(r, start) for s in searches]
            assert (found[0] is None) == (found[1] is None)
            if found[0] is not None:
                found_any += 1
                assert np.abs(np.subtract(found[0], found[1])).max() <= 1e-12 * (1.0 + abs(xb - xa))
                assert np.allclose(found[0], (eta, xi), atol=1e-9)
    assert found_any == 16
    for counter in ("newton_solves", "newton_iterations", "coarse_searches"):
        assert getattr(searches[0], counter) == getattr(searches[1], counter), counter
