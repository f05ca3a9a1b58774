"""The gallery's example scripts (examples/gallery/) run and obey the physics they show."""

import importlib.util
import io

import matplotlib.pyplot as plt
import numpy as np
import pytest

import paths


def load_example(name):
    """The gallery script examples/gallery/plot_NN_<name>.py as a module (its checks and
    plots, under ``__main__``, do not run)."""
    (path,) = (paths.EXAMPLES / "gallery").glob(f"plot_[0-9][0-9]_{name}.py")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def pendulum():
    out = io.StringIO()
    system, result = load_example("flexible_pendulum").main(t_end=0.1, dt=1e-3, modes=4, out=out)
    return system, result, out.getvalue()


def _corner_node(beam):
    """The FE node at (0, 0, 0), the corner of the z = 0 face."""
    (j,) = np.flatnonzero(np.all(np.abs(beam.data.u0) < 1e-12, axis=1))
    return int(j)


def test_flexible_pendulum_conserves_energy_and_keeps_its_pivot(pendulum):
    system, result, text = pendulum
    assert "energy drift" in text
    assert result.energy_drift() < 1e-5
    beam = system.bodies[0]
    pivot = beam.node(_corner_node(beam))           # the corner node, not the frame origin
    assert np.abs([pivot.position(q[beam.q_slice]) for q in result.q]).max() < 1e-9
    # the tip swings on a circle about the pivot axis x, to within the elastic displacements
    # of tip and pivot (a rotation about x keeps distances from the x axis)
    tip = beam.node(int(np.argmax(beam.data.u0[:, 2])))
    r0 = np.linalg.norm(tip.u0[1:] - pivot.u0[1:])
    elastic = [np.linalg.norm(tip.elastic_displacement(q[beam.q_slice]) - pivot.elastic_displacement(q[beam.q_slice]))
               for q in result.q]
    radius = np.linalg.norm(result["tip"][:, 1:], axis=1)
    assert np.all(np.abs(radius - r0) <= np.array(elastic) + 1e-12)
    assert result["tip"][-1, 1] < -0.02      # it fell


def test_flexible_pendulum_bends_as_beam_theory_says(pendulum):
    """Pinned at one end and released horizontally, the beam (L = 1 m, 0.1 m square, steel)
    starts to swing with α = 3g/(2L) and carries the transverse load q(z) = ρAg(1 − 3z/(2L))
    (its weight less the inertia of the swing; it balances on the pin). Euler-Bernoulli beam:
    M(z) = q0 z (L − z)²/(4L); the deflection measured from the body's mean axes (free-free
    modes carry no rigid motion: ∫ v dz = ∫ z v dz = 0) is q0 L⁴/(560 EI) at the tip, about
    7.9e-7 m. Released from rest, the load is a step: an undamped structure swings up to
    twice its static deflection. The largest elastic tip displacement over 0.1 s lies within
    a factor 3 of 2 q0 L⁴/(560 EI); pinning the frame origin instead of the corner node gave
    5e-10 m."""
    system, result, text = pendulum
    rho, young, g, side, length = 7850.0, 210e9, 9.81, 0.1, 1.0
    q0 = rho * side ** 2 * g
    ei = young * side ** 4 / 12
    estimate = 2 * q0 * length ** 4 / (560 * ei)
    largest = np.linalg.norm(result["tip_elastic"], axis=1).max()
    assert estimate / 3 < largest < 3 * estimate
    assert f"largest elastic tip displacement {largest:.3e} m" in text


def test_modal_impact_moves_the_centre_of_mass_by_the_impulse():
    """F = (100, 0, 10) N for τ = 10 ms on a 40 000 kg beam: the centre of mass moves
    ½ a τ² + a τ (t − τ) with a = F/m, whatever the rotation (F turns by < 1e-6 rad)."""
    out = io.StringIO()
    result, verdict = load_example("modal_impact").main(t_end=0.2, out=out)
    assert verdict == "SimpleRB"
    a = np.array([100.0, 0.0, 10.0]) / result.basis.total_mass
    tau, t = 0.01, result.t[-1]
    expected = 0.5 * a * tau ** 2 + a * tau * (t - tau)
    np.testing.assert_allclose(result.rho[-1] - result.rho[0], expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    assert "surface nodes" in out.getvalue()


def test_deformed_beam_contour_writes_a_png(tmp_path):
    out, path = io.StringIO(), tmp_path / "beam.png"
    info = load_example("deformed_beam_contour").main(["--out", str(path), "--tip", "0.02"], out=out)
    plt.close("all")                     # the script leaves its figure open for the gallery to show
    assert path.is_file() and path.stat().st_size > 1000
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert info["max_distance"] < 1e-12
    np.testing.assert_allclose(info["tip"][1], 0.02, rtol=1e-10)     # the requested tip deflection
    assert f"wrote {path}" in out.getvalue() and "max distance" in out.getvalue()
