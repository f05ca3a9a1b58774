"""The example model script runs and obeys the physics it shows."""

import importlib.util
import io
from pathlib import Path

import numpy as np


def load_example(name):
    path = Path(__file__).resolve().parents[1] / "examples" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_flexible_pendulum_conserves_energy_and_keeps_its_pivot():
    out = io.StringIO()
    system, result = load_example("flexible_pendulum").main(t_end=0.1, dt=1e-3, modes=4, out=out)
    assert "energy drift" in out.getvalue()
    assert result.energy_drift() < 1e-5
    beam = system.bodies[0]
    pivot = np.array([beam.origin.position(q[beam.q_slice]) for q in result.q])
    assert np.abs(pivot).max() < 1e-9
    # the tip swings on a circle about the pivot axis x, to within its elastic displacement
    radius = np.linalg.norm(result["tip"][:, 1:], axis=1)
    assert np.ptp(radius) < 1e-8
    assert result["tip"][-1, 1] < -0.02      # it fell


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
    assert path.is_file() and path.stat().st_size > 1000
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert info["max_distance"] < 1e-12
    np.testing.assert_allclose(info["tip"][1], 0.02, rtol=1e-10)     # the requested tip deflection
    assert f"wrote {path}" in out.getvalue() and "max distance" in out.getvalue()
