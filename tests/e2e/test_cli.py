"""The command line: preprocess -> files -> info, clear one-line errors, the main job.

``ffrmbs preprocess`` (the module's body) and the main job run as the user runs them, a
process each; the other commands run through ``main`` in the test's process
(:func:`cli_in_process.run_cli`: an exception escaping it, which would be a traceback, fails
the test)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from preprocess import read_body
from preprocess.textfiles import TEXT_FILES, read_text_body

from cli_in_process import run_cli


def ffrmbs(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ffrmbs_app.cli", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.fixture(scope="module")
def preprocessed(tmp_path_factory):
    out = tmp_path_factory.mktemp("beam")
    res = ffrmbs("preprocess", "box:1,1,5", "--modes", "4", "--clamp", "z0", "--density", "8000",
                 "--young", "200e9", "--poisson", "0", "--mesh-size", "0.5", "--geometric-stiffness", "--out", str(out))
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
    # --geometric-stiffness: a spin about x tensions the beam along z and stiffens its bending pair
    assert body.geometric_stiffness.shape == (12, 4, 4)
    assert np.linalg.eigvalsh(body.geometric_stiffness[0, :2, :2]).min() > 0


def test_info_reads_directory_and_hdf5(preprocessed):
    out, _ = preprocessed
    for path in (out, out / "body.h5"):
        code, stdout, stderr = run_cli("info", path)
        assert code == 0, stderr
        assert "nodes:          579" in stdout
        assert "total mass:     40000 kg" in stdout
        assert "centre of mass: (0.5, 0.5, 2.5) m" in stdout
    assert "surface nodes:  426" in run_cli("info", out / "body.h5")[1]


def test_bad_body_file_is_one_clear_line(preprocessed, tmp_path):
    out, _ = preprocessed
    for name in TEXT_FILES:
        (tmp_path / name).write_bytes((out / name).read_bytes())
    lines = (tmp_path / "mij.dat").read_text().splitlines()
    lines[2] = "-1.0\t% node: 3"
    (tmp_path / "mij.dat").write_text("\n".join(lines) + "\n")
    code, _, stderr = run_cli("info", tmp_path)
    assert code == 2
    assert "Traceback" not in stderr and stderr.count("\n") == 1
    assert "mij.dat, line 3" in stderr and "mass" in stderr


def test_preprocess_unknown_group_writes_nothing(tmp_path):
    out = tmp_path / "out"
    code, _, stderr = run_cli("preprocess", "box:1,1,2", "--modes", "2", "--clamp", "left", "--density", "1000",
                              "--young", "1e9", "--poisson", "0.3", "--out", out)
    assert code == 2 and "Traceback" not in stderr
    assert "unknown node group 'left'" in stderr and "z0" in stderr
    assert not out.exists() or not any(out.iterdir())


def test_preprocess_missing_mesh_file(tmp_path):
    code, _, stderr = run_cli("preprocess", tmp_path / "none.msh", "--modes", "2", "--free", "--density", "1",
                              "--young", "1", "--poisson", "0.3", "--out", tmp_path / "o")
    assert code == 2 and "none.msh" in stderr and "not found" in stderr


SOFT = ["--density", "1000", "--young", "1e9", "--poisson", "0.3"]


def preprocess_in_process(capsys, *argv):
    """``ffrmbs preprocess`` run by main() in this process: (exit status, stdout, stderr)."""
    from ffrmbs_app.cli import main

    rc = main(["preprocess", *argv])
    out, err = capsys.readouterr()
    return rc or 0, out, err


def test_preprocess_structured_box_gives_grid_faces(tmp_path, capsys):
    """--structured 5,2,3 on a 0.25 x 0.05 x 0.05 m box, tet10: the face y = 0.05 is the
    (2·5 + 1) x (2·3 + 1) node grid x = i·0.025, z = j·0.05/6 (longer side first)."""
    from contours.node_grid import node_matrix

    rc, _, err = preprocess_in_process(capsys, "box:0.25,0.05,0.05", "--structured", "5,2,3", "--modes", "2",
                                       "--clamp", "x0", *SOFT, "--out", str(tmp_path))
    assert rc == 0, err
    body = read_body(tmp_path / "body.h5")
    assert body.n_nodes == 11 * 5 * 7 and body.params["structured"] == "5,2,3"
    O = node_matrix(body.u0, body.node_groups["y1"])
    assert O.shape == (11, 7)
    i, j = np.meshgrid(np.arange(11), np.arange(7), indexing="ij")
    np.testing.assert_allclose(body.u0[O], np.stack([i * 0.025, np.full(i.shape, 0.05), j * 0.05 / 6], axis=-1),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("source, options, fault", [
    ("box:1,1,1", ("--structured", "5,2"), "--structured needs three whole numbers >= 1"),
    ("box:1,1,1", ("--structured", "5,2,2,2"), "--structured needs three whole numbers"),
    ("box:1,1,1", ("--structured", "5,0,2"), "--structured needs three whole numbers"),
    ("box:1,1,1", ("--structured", "2.5,2,2"), "--structured needs three whole numbers"),
    ("box:1,1,1", ("--structured", "nan,2,2"), "--structured needs three whole numbers"),
    ("box:1,1,1", ("--structured", "a,b,c"), "--structured needs three whole numbers"),
    ("box:1,1,1", ("--structured", "2,2,2", "--mesh-size", "0.5"), "--mesh-size does not apply with --structured"),
    ("stepped-beam", ("--structured", "2,2,2"), "--structured applies to the built-in box:LX,LY,LZ only"),
    ("cylinder:1,2", ("--structured", "2,2,2"), "--structured applies to the built-in box:LX,LY,LZ only"),
    ("{tmp}/part.geo", ("--structured", "2,2,2"), "--structured applies to the built-in box:LX,LY,LZ only"),
    ("cylinder:1", (), "built-in cylinder needs two lengths R,L"),
    ("cylinder:1,x", (), "built-in cylinder needs two lengths R,L"),
    ("cylinder:1,-2", (), "cylinder L must be positive"),
    ("spherical-cap:1,2", (), "cap height must be below twice the radius"),
    ("spherical-cap:1,0.5,3", (), "built-in spherical-cap needs two lengths R,H"),
    ("grooved-block:1,1,1", (), "built-in grooved-block needs four lengths LX,LY,LZ,R"),
    ("grooved-block:1,1,1,0.5", (), "groove radius must be below min(ly/2, lz) = 0.5"),
    ("grooved-block:1,1,1,nan", (), "grooved-block R must be positive and finite"),
])
def test_preprocess_bad_mesh_options_are_one_line_before_meshing(tmp_path, capsys, source, options, fault):
    (tmp_path / "part.geo").write_text('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 1, 1, 1};\n')
    rc, out, err = preprocess_in_process(capsys, source.format(tmp=tmp_path), *options, "--modes", "2", "--free",
                                         *SOFT, "--out", str(tmp_path / "out"))
    assert rc == 2 and out == ""
    assert err.startswith("ffrmbs: error: ") and err.count("\n") == 1 and fault in err   # nothing meshed
    assert not (tmp_path / "out").exists()


def _radius(p):
    return np.hypot(p[:, 0], p[:, 1])


@pytest.mark.parametrize("source, mesh_size, surfaces", [
    ("cylinder:0.05,0.3", "0.03", {"lateral": lambda p: _radius(p) - 0.05, "end1": lambda p: p[:, 2] - 0.3,
                                   "rim0": lambda p: np.abs(_radius(p) - 0.05) + np.abs(p[:, 2])}),
    ("spherical-cap:0.1,0.04", "0.02", {"cap": lambda p: np.linalg.norm(p, axis=1) - 0.1,
                                        "base": lambda p: p[:, 2] - 0.06}),
    ("grooved-block:0.06,0.12,0.06,0.04", "0.02", {"groove": lambda p: np.hypot(p[:, 1] - 0.06, p[:, 2] - 0.06) - 0.04,
                                                   "bottom": lambda p: p[:, 2]}),
])
def test_preprocess_curved_builtins_name_their_exact_surfaces(tmp_path, capsys, source, mesh_size, surfaces):
    """The body file of each new built-in carries its named face groups, every node (mid-edge
    nodes included) on the exact surface (SI input, so lengths in m)."""
    rc, _, err = preprocess_in_process(capsys, source, "--mesh-size", mesh_size, "--modes", "1", "--free", *SOFT,
                                       "--out", str(tmp_path))
    assert rc == 0, err
    body = read_body(tmp_path / "body.h5")
    assert body.params["element_order"] == 2
    for group, distance in surfaces.items():
        nodes = body.node_groups[group]
        assert len(nodes) >= 10, group
        np.testing.assert_allclose(distance(body.u0[nodes]), 0.0, rtol=0, atol=1e-12, err_msg=group)


@pytest.mark.slow
def test_main_job_runs_the_point_mass_on_the_beam(tmp_path):
    """``ffrmbs run`` with no argument, as the README shows it (tests/e2e/test_readme.py
    leaves it to this test): setup A of thesis Sec. 5.2. Independent checks: the point mass
    falls 2 mm at 0.2 m/s, so the contact closes at 10 ms; before it the mass moves
    uniformly; the energy balance closes; files are written into ``ffrmbs-run/``."""
    import h5py

    res = ffrmbs("run", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    out = tmp_path / "ffrmbs-run"
    text = res.stdout
    for key in ("contact: force transmitted in", "maximum penetration",
                "energy balance [J]: E(t) - E(0) = W_loads - D_damping + W_impulses + residual", "accuracy (time step",
                "accuracy (modal truncation: max |run - run with 40 modes|)", "cost:"):
        assert key in text
    with h5py.File(out / "point_mass_beam.h5") as f:
        t, y, vy = f["t"][()], f["outputs/y"][()], f["outputs/vy"][()]
        summary = json.loads(f.attrs["summary"])
        assert f["outputs/node19"].shape == (t.size, 3) and f["trace/closed"].size == 10000
        assert f.attrs["status"] == "complete"
    first_close = summary["contact_intervals_s"][0][0]
    assert abs(first_close - 0.010) <= 1e-5
    before = t < 0.0099
    assert np.allclose(y[before], 0.052 - 0.2 * t[before], atol=1e-12) and np.all(vy[before] == -0.2)
    e = summary["energy_balance_J"]
    assert e["initial"] == pytest.approx(0.5 * 0.5 * 0.2 ** 2) and abs(e["residual"]) < 1e-3 * e["initial"]
    assert e["load_work"] == e["damping_loss"] == 0.0           # no load, no damping, no gravity
    # e = 0 on the contour's residual flexibility: the spring stores and returns the energy of
    # the impact, so the impulses do little net work: O((ω Δt)²) per contact phase, plus the
    # ½ Fᵀ dC F a point sliding over the contour exchanges (contact.compliance; 1.6e-3 here)
    # largest penetration of the effective gap g_N + δ: the closing step's 0.2 m/s · Δt, plus
    # the change of δ between the step's start (δ_k) and its midpoint (g_N(q_m))
    assert abs(e["impulse_work"]) < 1e-2 * e["initial"] and 0 < summary["max_penetration_m"] <= 1.5 * 0.2 * 1e-5
    assert (out / "point_mass_beam.png").stat().st_size > 10_000
    pvd = out / "point_mass_beam-paraview" / "point_mass_beam.pvd"
    assert pvd.is_file() and pvd.read_text().count("<DataSet") >= 1001


def test_contact_intervals_from_a_trace():
    from ffrmbs_app.job import contact_intervals

    t = np.arange(1, 11) * 0.1
    closed = np.array([0, 1, 1, 0, 0, 1, 0, 0, 1, 1])
    assert np.allclose(contact_intervals(t, np.full(10, 0.1), closed), [(0.1, 0.3), (0.5, 0.6), (0.8, 1.0)])
    assert contact_intervals(t, np.full(10, 0.1), np.zeros(10)) == []
