"""ParaView export of result files: deformed surfaces, point bodies and contacts over time.

The oracle is the deformed position computed by hand, node by node, from the synthetic
result file's frame motion (R_k, a rotation by k·30° about z) and modal coordinates, with
one sample written out as literal numbers.
"""

import json
import math
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

import ffrmbs_app.export as export_mod
from ffrmbs_app import cli
from ffrmbs.errors import FfrmbsError, InputFileError, OutputFileError
from ffrmbs_app.export import export_paraview

N = 5                                        # samples
T = np.array([0.0, 0.1, 0.2, 0.3, 0.4])      # [s]
U0 = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])  # unit square [m]
TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]])
NODES = np.array([10, 11, 12, 13])


def frame(k):
    """R_k [m], A_k (rotation by k·30° about z) and q_f,k of sample k."""
    th = k * math.pi / 6
    c, s = math.cos(th), math.sin(th)
    R = np.array([0.1 * k, 0.2 * k, 0.0])
    A = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q = np.array([0.01 * k, -0.02 * k])
    return R, A, q


def phi():
    """Mode 1 lifts a node by its x (w = x), mode 2 shears it along x by its y (u = y)."""
    p = np.zeros((4, 3, 2))
    p[:, 2, 0] = U0[:, 0]
    p[:, 0, 1] = U0[:, 1]
    return p


def deformed_by_hand(k):
    """x = R + A (u0 + Φ q) node by node, with the modes written out, not as matrices."""
    R, A, (q1, q2) = frame(k)
    out = []
    for X, Y, Z in U0:
        ub = (X + q2 * Y, Y, Z + q1 * X)       # ū = u0 + Φ q, mode by mode
        out.append([R[i] + sum(A[i, j] * ub[j] for j in range(3)) for i in range(3)])
    return np.array(out)


def write_result(path, **overrides):
    """A small result file per the layout of mbs.results.result_file: a flexible square 'plate'
    (2 triangles, 2 modes), a point mass 'ball' and one contact 'impact'."""
    with h5py.File(path, "w") as f:
        f.attrs.update(format="ffrmbs-result", format_version=1, status="complete", scene="square",
                       integrator="moreau", dt=1e-3, t_end=0.4, n_out=N)
        for k, v in overrides.items():
            f.attrs[k] = v
        f["t"] = T
        plate = f.create_group("bodies/plate")
        plate.attrs.update(kind="FlexibleBodyFFR", n_modes=2)
        frames = [frame(k) for k in range(N)]
        plate["R"] = np.array([fr[0] for fr in frames])
        plate["A"] = np.array([fr[1] for fr in frames])
        plate["q_f"] = np.array([fr[2] for fr in frames])
        s = plate.create_group("surface")
        s["nodes"], s["u0"], s["phi"], s["triangles"] = NODES, U0, phi(), TRIANGLES
        ball = f.create_group("bodies/ball")
        ball.attrs.update(kind="PointMass", n_modes=0)
        ball["R"] = np.array([[0.5, 0.5, 1.0 - 0.1 * k] for k in range(N)])
        ball["A"] = np.repeat(np.eye(3)[None], N, axis=0)
        ball["q"] = ball["R"][...]
        ball["u"] = np.array([[0.0, 0.0, -1.0 + 0.01 * k] for k in range(N)])
        c = f.create_group("contacts/impact")
        c.attrs.update(law="NewtonImpact", set_valued=True)
        c["active"] = np.array([0, 0, 1, 1, 0], dtype=np.int8)
        c["gap"] = np.array([np.nan, 0.02, 0.0, -1e-6, 0.01])
        point = np.array([[0.5, 0.5, 0.1 * k] for k in range(N)])
        point[0] = np.nan
        c["point"] = point
        normal = np.tile([0.0, 0.0, 1.0], (N, 1))
        normal[0] = np.nan
        c["normal"] = normal
        c["force"] = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 12.5], [0, 0.5, 3.0], [0, 0, 0]], dtype=float)
    return path


@pytest.fixture
def result(tmp_path):
    return write_result(tmp_path / "square.h5")


def read_pvd(path):
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    return [ds.attrib for ds in root.iter("DataSet")]


def test_the_literal_sample_of_the_hand_oracle():
    # k = 3: R = (0.3, 0.6, 0), a quarter turn about z, q = (0.03, -0.06); node (1, 1, 0):
    # ū = (1 - 0.06, 1, 0.03), A ū = (-1, 0.94, 0.03)
    np.testing.assert_allclose(deformed_by_hand(3)[2], [-0.7, 1.54, 0.03], atol=1e-15)


def test_surface_points_are_the_deformed_positions(result):
    pvd = export_paraview(result)
    out = result.parent / "square-paraview"
    assert pvd == out / "square.pvd" and pvd.is_file()
    for k in range(N):
        mesh = meshio.read(out / "plate" / f"plate_{k:06d}.vtu")
        x = deformed_by_hand(k)
        np.testing.assert_allclose(mesh.points, x, atol=1e-14)
        np.testing.assert_array_equal(mesh.cells_dict["triangle"], TRIANGLES)
        np.testing.assert_allclose(mesh.point_data["displacement"], x - U0, atol=1e-14)
        _, _, (q1, q2) = frame(k)
        elastic = np.hypot(q2 * U0[:, 1], q1 * U0[:, 0])      # |A Φ q| = |Φ q|, A a rotation
        np.testing.assert_allclose(mesh.point_data["elastic_displacement_magnitude"], elastic, atol=1e-15)
        np.testing.assert_allclose(np.linalg.norm(mesh.point_data["elastic_displacement"], axis=1), elastic,
                                   atol=1e-15)
        np.testing.assert_array_equal(mesh.point_data["node"], NODES)


def test_small_blocks_give_the_same_points(result, monkeypatch):
    monkeypatch.setattr(export_mod, "_CHUNK_VALUES", 1)       # one sample per block
    export_paraview(result, result.parent / "blocks", every=2)
    for k in (0, 2, 4):
        mesh = meshio.read(result.parent / "blocks" / "plate" / f"plate_{k:06d}.vtu")
        np.testing.assert_allclose(mesh.points, deformed_by_hand(k), atol=1e-14)


def test_pvd_lists_every_sample_with_its_time(result):
    pvd = export_paraview(result)
    entries = read_pvd(pvd)
    assert len(entries) == 3 * N                               # plate, ball, contacts per sample
    by_name = {}
    for e in entries:
        by_name.setdefault(e["name"], []).append(e)
        assert (pvd.parent / e["file"]).is_file()
    assert set(by_name) == {"plate", "ball", "contacts"}
    for name, es in by_name.items():
        assert [float(e["timestep"]) for e in es] == T.tolist()
        assert len({e["part"] for e in es}) == 1
    assert len({es[0]["part"] for es in by_name.values()}) == 3
    own = read_pvd(pvd.parent / "plate" / "plate.pvd")
    assert [float(e["timestep"]) for e in own] == T.tolist()
    assert all((pvd.parent / "plate" / e["file"]).is_file() for e in own)


def test_every_nth_sample(result, tmp_path):
    pvd = export_paraview(result, tmp_path / "every2", every=2)
    entries = read_pvd(pvd)
    assert sorted({float(e["timestep"]) for e in entries}) == [0.0, 0.2, 0.4]
    files = sorted(p.name for p in (tmp_path / "every2" / "plate").glob("*.vtu"))
    assert files == ["plate_000000.vtu", "plate_000002.vtu", "plate_000004.vtu"]
    with pytest.raises(FfrmbsError, match="positive integer"):
        export_paraview(result, tmp_path / "every0", every=0)
    assert not (tmp_path / "every0").exists()


def test_point_mass_is_one_vertex_with_velocity(result):
    out = export_paraview(result).parent
    for k in range(N):
        mesh = meshio.read(out / "ball" / f"ball_{k:06d}.vtu")
        np.testing.assert_array_equal(mesh.points, [[0.5, 0.5, 1.0 - 0.1 * k]])
        np.testing.assert_array_equal(mesh.cells_dict["vertex"], [[0]])
        np.testing.assert_array_equal(mesh.point_data["velocity"], [[0.0, 0.0, -1.0 + 0.01 * k]])


def test_contact_point_data_round_trips(result):
    out = export_paraview(result).parent
    with h5py.File(result) as f:
        c = {k: f["contacts/impact"][k][...] for k in ("active", "gap", "force")}
    for k in range(N):
        mesh = meshio.read(out / "contacts" / f"contacts_{k:06d}.vtu")
        np.testing.assert_array_equal(mesh.cells_dict["vertex"], [[0]])
        np.testing.assert_array_equal(mesh.point_data["force"], c["force"][k:k + 1])
        np.testing.assert_array_equal(mesh.point_data["gap"], c["gap"][k:k + 1])    # NaN stays NaN
        np.testing.assert_array_equal(mesh.point_data["active"], c["active"][k:k + 1])
        np.testing.assert_array_equal(mesh.point_data["located"], [0 if k == 0 else 1])
        np.testing.assert_array_equal(mesh.point_data["contact"], [0])
        # not located at sample 0: the vertex waits at the first located point
        np.testing.assert_array_equal(mesh.points, [[0.5, 0.5, 0.1 * max(k, 1)]])
        np.testing.assert_array_equal(mesh.point_data["normal"], [[0.0, 0.0, 0.0 if k == 0 else 1.0]])


def test_body_selection_and_unknown_body(result, tmp_path):
    pvd = export_paraview(result, tmp_path / "only", bodies=["ball"])
    assert {e["name"] for e in read_pvd(pvd)} == {"ball", "contacts"}
    assert not (tmp_path / "only" / "plate").exists()
    with pytest.raises(InputFileError, match="no body 'wing'.*ball, plate"):
        export_paraview(result, tmp_path / "wing", bodies=["wing"])
    assert not (tmp_path / "wing").exists()


def leftovers(directory):
    return sorted(p.name for p in directory.iterdir() if p.name.startswith("."))


@pytest.mark.parametrize("damage, fault", [
    ("text", "not an HDF5 file"),
    ("format", "not an ffrmbs result file"),
    ("version", "format version 2"),
    ("no_A", "missing dataset /bodies/plate/A"),
    ("no_bodies", "missing group /bodies"),
    ("no_t", "missing dataset /t"),
    ("bad_triangles", "outside 0..3"),
    ("phi_shape", "/bodies/plate/surface/phi has shape"),
])
def test_bad_files_raise_and_leave_nothing(tmp_path, damage, fault):
    path = tmp_path / "bad.h5"
    if damage == "text":
        path.write_text("t,y\n0,1\n")
    else:
        write_result(path)
        with h5py.File(path, "a") as f:
            if damage == "format":
                f.attrs["format"] = "something-else"
            elif damage == "version":
                f.attrs["format_version"] = 2
            elif damage == "no_A":
                del f["bodies/plate/A"]
            elif damage == "no_bodies":
                del f["bodies"]
            elif damage == "no_t":
                del f["t"]
            elif damage == "bad_triangles":
                del f["bodies/plate/surface/triangles"]
                f["bodies/plate/surface/triangles"] = np.array([[0, 1, 4]])
            elif damage == "phi_shape":
                del f["bodies/plate/surface/phi"]
                f["bodies/plate/surface/phi"] = np.zeros((3, 3, 2))
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(InputFileError, match=fault) as err:
        export_paraview(path, tmp_path / "deep" / "out")
    assert err.value.path == str(path) and err.value.line is None
    assert sorted(p.name for p in tmp_path.iterdir()) == before    # no out dir, no parents, no temp dir


def test_missing_file_raises(tmp_path):
    with pytest.raises(InputFileError, match="file not found"):
        export_paraview(tmp_path / "none.h5")
    assert list(tmp_path.iterdir()) == []


def test_a_failure_while_writing_leaves_nothing(result, monkeypatch):
    calls = []
    real = export_mod._write_vtu

    def failing(path, *args):
        calls.append(path)
        if len(calls) == 4:
            raise OSError("disk full")
        real(path, *args)

    monkeypatch.setattr(export_mod, "_write_vtu", failing)
    with pytest.raises(OutputFileError, match="cannot write the ParaView export: disk full"):
        export_paraview(result)
    assert len(calls) == 4
    assert sorted(p.name for p in result.parent.iterdir()) == ["square.h5"]


def test_reexport_replaces_an_export_but_not_other_directories(result, tmp_path):
    out = tmp_path / "view"
    export_paraview(result, out)
    (out / "plate" / "plate_000099.vtu").write_text("stale")
    export_paraview(result, out, every=4)
    assert sorted(p.name for p in (out / "plate").glob("*.vtu")) == ["plate_000000.vtu", "plate_000004.vtu"]
    assert json.loads((out / export_mod.MARKER).read_text())["every"] == 4
    assert leftovers(tmp_path) == []
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    with pytest.raises(FfrmbsError, match="not an ffrmbs export"):
        export_paraview(result, mine)
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]


def test_running_file_exports_the_samples_all_datasets_have(tmp_path):
    path = write_result(tmp_path / "running.h5", status="running")
    with h5py.File(path, "a") as f:               # the writer has appended /t and R but not yet A, q_f
        del f["t"]
        f["t"] = np.append(T, 0.5)
    pvd = export_paraview(path)
    assert sorted({float(e["timestep"]) for e in read_pvd(pvd)}) == T.tolist()


def test_cli_export(result, tmp_path, capsys):
    assert cli.main(["export", str(result), "--out", str(tmp_path / "cli"), "--every", "2"]) == 0
    assert str(tmp_path / "cli" / "square.pvd") in capsys.readouterr().out
    assert len(read_pvd(tmp_path / "cli" / "square.pvd")) == 3 * 3
    bad = tmp_path / "bad.h5"
    bad.write_text("nope")
    assert cli.main(["export", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ffrmbs: error: ") and "not an HDF5 file" in err and "Traceback" not in err


def test_compressed_files_hold_the_same_points(result, tmp_path):
    export_paraview(result, tmp_path / "zip", every=3, compress=True)
    vtu = tmp_path / "zip" / "plate" / "plate_000003.vtu"
    assert 'compressor="vtkZLibDataCompressor"' in vtu.read_text()
    np.testing.assert_allclose(meshio.read(vtu).points, deformed_by_hand(3), atol=1e-14)
    plain = tmp_path / "plain"
    export_paraview(result, plain, every=3)
    assert "compressor" not in (plain / "plate" / "plate_000003.vtu").read_text()


def test_a_run_that_has_written_nothing_yet(tmp_path):
    path = tmp_path / "fresh.h5"
    with h5py.File(path, "w") as f:               # the writer's layout before its first flush
        f.attrs.update(format="ffrmbs-result", format_version=1, status="running")
        f.create_group("bodies/plate")
    with pytest.raises(InputFileError, match="no samples written yet"):
        export_paraview(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh.h5"]
