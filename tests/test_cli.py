"""The command line: preprocess -> files -> info, clear one-line errors, the main job."""

import json
import subprocess
import sys

import numpy as np
import pytest

from preprocess import read_body
from preprocess.textfiles import TEXT_FILES, read_text_body


def ffrmbs(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.fixture(scope="module")
def preprocessed(tmp_path_factory):
    out = tmp_path_factory.mktemp("beam")
    res = ffrmbs("preprocess", "box:1,1,5", "--modes", "4", "--clamp", "z0", "--density", "8000",
                 "--young", "200e9", "--poisson", "0", "--mesh-size", "0.5", "--out", str(out))
    return out, res


def test_preprocess_writes_body_files_and_prints_statistics(preprocessed):
    out, res = preprocessed
    assert res.returncode == 0, res.stderr
    assert "579" in res.stdout and "426" in res.stdout and "254" in res.stdout  # report Table 1
    for name in (*TEXT_FILES, "body.h5"):
        assert (out / name).is_file()
    body = read_body(out / "body.h5")
    # first bending pair of the clamped report beam, Akantu's assembly gives 197.6 rad/s
    assert body.frequencies()[0][0] == pytest.approx(197.6, rel=2e-3)
    text = read_text_body(out)
    np.testing.assert_array_equal(text.phi, body.phi)


def test_info_reads_directory_and_hdf5(preprocessed):
    out, _ = preprocessed
    for path in (out, out / "body.h5"):
        res = ffrmbs("info", str(path))
        assert res.returncode == 0, res.stderr
        assert "nodes:          579" in res.stdout
        assert "total mass:     40000 kg" in res.stdout
        assert "centre of mass: (0.5, 0.5, 2.5) m" in res.stdout
    assert "surface nodes:  426" in ffrmbs("info", str(out / "body.h5")).stdout


def test_bad_body_file_is_one_clear_line(preprocessed, tmp_path):
    out, _ = preprocessed
    for name in TEXT_FILES:
        (tmp_path / name).write_bytes((out / name).read_bytes())
    lines = (tmp_path / "mij.dat").read_text().splitlines()
    lines[2] = "-1.0\t% node: 3"
    (tmp_path / "mij.dat").write_text("\n".join(lines) + "\n")
    res = ffrmbs("info", str(tmp_path))
    assert res.returncode == 2
    assert "Traceback" not in res.stderr
    assert "mij.dat, line 3" in res.stderr and "mass" in res.stderr


def test_preprocess_unknown_group_writes_nothing(tmp_path):
    out = tmp_path / "out"
    res = ffrmbs("preprocess", "box:1,1,2", "--modes", "2", "--clamp", "left", "--density", "1000",
                 "--young", "1e9", "--poisson", "0.3", "--out", str(out))
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "unknown node group 'left'" in res.stderr and "z0" in res.stderr
    assert not out.exists() or not any(out.iterdir())


def test_preprocess_missing_mesh_file(tmp_path):
    res = ffrmbs("preprocess", str(tmp_path / "none.msh"), "--modes", "2", "--free", "--density", "1",
                 "--young", "1", "--poisson", "0.3", "--out", str(tmp_path / "o"))
    assert res.returncode == 2 and "none.msh" in res.stderr and "not found" in res.stderr


@pytest.mark.slow
def test_main_job_runs_the_point_mass_on_the_beam(tmp_path):
    """``ffrmbs run`` with no scene argument: setup A of thesis Sec. 5.2. Independent
    checks: the point mass falls 2 mm at 0.2 m/s, so the contact closes at 10 ms; before
    it the mass moves uniformly; the energy balance closes; files are written."""
    import h5py

    res = ffrmbs("run", "--out", str(tmp_path / "out"))
    assert res.returncode == 0, res.stderr
    text = res.stdout
    for key in ("contact: closed in", "maximum penetration", "energy: initial 0.01 J", "accuracy", "cost:"):
        assert key in text
    with h5py.File(tmp_path / "out" / "point_mass_beam.h5") as f:
        t, y, vy = f["t"][()], f["outputs/y"][()], f["outputs/vy"][()]
        summary = json.loads(f.attrs["summary"])
        assert f["outputs/node19"].shape == (t.size, 3) and f["trace/closed"].size == 10000
        assert f.attrs["status"] == "complete"
    first_close = summary["contact_intervals_s"][0][0]
    assert abs(first_close - 0.010) <= 1e-5
    before = t < 0.0099
    assert np.allclose(y[before], 0.052 - 0.2 * t[before], atol=1e-12) and np.all(vy[before] == -0.2)
    e = summary["energy_J"]
    assert e["initial"] == pytest.approx(0.5 * 0.5 * 0.2 ** 2) and abs(e["residual"]) < 1e-3 * e["initial"]
    assert e["impulse_work"] < 0 and 0 < summary["max_penetration_m"] <= 0.2 * 1e-5
    assert (tmp_path / "out" / "point_mass_beam.png").stat().st_size > 10_000
    pvd = tmp_path / "out" / "point_mass_beam-paraview" / "point_mass_beam.pvd"
    assert pvd.is_file() and pvd.read_text().count("<DataSet") >= 1001


def test_contact_intervals_from_a_trace():
    from ffrmbs_app.job import contact_intervals

    t = np.arange(1, 11) * 0.1
    closed = np.array([0, 1, 1, 0, 0, 1, 0, 0, 1, 1])
    assert np.allclose(contact_intervals(t, np.full(10, 0.1), closed), [(0.1, 0.3), (0.5, 0.6), (0.8, 1.0)])
    assert contact_intervals(t, np.full(10, 0.1), np.zeros(10)) == []
