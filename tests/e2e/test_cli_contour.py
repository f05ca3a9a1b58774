"""``ffrmbs contour BODY GROUP``: the fit report of a 2s contour on a face group, its PNG and
.vtu files, checked against the exact geometry of the faces (a box's planes, a cylinder),
and one-line refusals that write nothing."""

import re

import numpy as np
import pytest

from contours.fitting import SMOOTHING
from ffrmbs_app.cli import build_parser, main
from ffrmbs_app.contour_report import file_stem
from preprocess import Material, box, build_body, write_body

import gmsh_parts

LX, LY, LZ = 0.2, 0.1, 0.05            # box [m]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
N_MODES = 3


def _write(mesh, path, clamp=None, **groups):
    """Build a steel body of ``mesh`` with N_MODES modes, add ``groups`` (node indices, or
    a function of the body giving them), write it to the directory ``path``."""
    body = build_body(mesh, Material(7800.0, 2.1e11, 0.3), N_MODES, clamp=clamp)
    body.node_groups.update({k: v(body) if callable(v) else v for k, v in groups.items()})
    write_body(path, body)
    return body


@pytest.fixture(scope="module")
def unstructured(tmp_path_factory):
    """A tet10 box meshed by gmsh's default (unstructured) mesher, clamped at x0; extra
    groups: two opposite faces, every node, every surface node, a name that is a path's parent (HDF5 allows
    no "/" in a name)."""
    path = tmp_path_factory.mktemp("box")
    mesh = box(LX, LY, LZ, 0.025)
    g = mesh.node_groups
    body = _write(mesh, path, "x0", **{"x0+x1": np.union1d(g["x0"], g["x1"]), "all": np.arange(mesh.n_nodes),
                                       "surface": lambda b: b.surface_nodes, "..": g["z1"]})
    return path / "body.h5", body


@pytest.fixture(scope="module")
def structured(tmp_path_factory):
    """A tet10 box meshed as a transfinite grid of 4 x 3 x 2 elements."""
    path = tmp_path_factory.mktemp("grid")
    _write(box(LX, LY, LZ, None, divisions=(4, 3, 2)), path, "x0")
    return path


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def report_row(out, field):
    """The four numbers of a row of the printed fit report."""
    line = next(line for line in out.splitlines() if line.split()[:len(field.split())] == field.split())
    return [float(v) for v in line.split()[len(field.split()):len(field.split()) + 4]]


def test_flat_face_report_png_and_vtu(unstructured, tmp_path, capsys):
    import meshio

    path, body = unstructured
    out = tmp_path / "out"
    code, text, err = run(capsys, "contour", path, "z1", "--out", out)
    assert code == 0, err
    assert "not a structured grid" in text
    # the exact face is the plane z = LZ over [0, LX] x [0, LY]: an affine map of the
    # parameters, which the cubic fit reproduces at every node and mid-point
    assert max(report_row(text, "geometry")) < 1e-12
    for j in range(1, N_MODES + 1):
        assert len(report_row(text, f"mode {j}")) == 4
    assert "normal angle error" in text and f"wrote {out / 'z1-fit.png'}" in text

    png = (out / "z1-fit.png").read_bytes()
    assert png.startswith(PNG_SIGNATURE)
    from matplotlib.image import imread
    assert imread(out / "z1-fit.png").shape[2] in (3, 4)

    nodes = body.node_groups["z1"]
    fe = meshio.read(out / "z1-fit.vtu")
    assert len(fe.points) == nodes.size
    np.testing.assert_array_equal(np.sort(fe.point_data["node"]), nodes)
    np.testing.assert_allclose(fe.points, body.u0[fe.point_data["node"]])
    tri = body.surface_triangles[np.isin(body.surface_triangles, nodes).all(axis=1)]
    assert fe.cells[0].type == "triangle6" and len(fe.cells[0].data) == len(tri)
    assert fe.point_data["deviation"].shape == (nodes.size,) and fe.point_data["deviation"].max() < 1e-12
    assert fe.cell_data["mid_deviation"][0].shape == (len(tri),)
    for key in ("eta", "xi"):
        assert fe.point_data[key].min() == pytest.approx(0.0, abs=1e-12)
        assert fe.point_data[key].max() == pytest.approx(1.0, abs=1e-12)

    contour = meshio.read(out / "z1-contour.vtu")
    x = contour.points
    np.testing.assert_allclose(x[:, 2], LZ, atol=1e-12)                     # on the plane
    np.testing.assert_allclose(x[:, :2].min(axis=0), 0.0, atol=1e-12)      # spanning the face
    np.testing.assert_allclose(x[:, :2].max(axis=0), (LX, LY), atol=1e-12)
    ne, nx = (np.unique(contour.point_data[k]).size for k in ("eta", "xi"))
    assert ne * nx == len(x) and len(contour.cells[0].data) == (ne - 1) * (nx - 1)
    assert sorted(p.name for p in out.iterdir()) == ["z1-contour.vtu", "z1-fit.png", "z1-fit.vtu"]


def test_mode_rows_are_the_fit_error_of_each_mode(unstructured, tmp_path, capsys):
    """A mode of the clamped box, fitted with few control points, has a visible error; the
    reported row is the node distance relative to the mode's largest nodal value, recomputed
    here by a dense least-squares solve (the module docstring of contours.fitting.bspline_fit)
    at the nodes' parameters."""
    from contours.fitting import surface_fit
    from contours.fitting.bspline_fit import FitDirection

    path, body = unstructured
    code, text, err = run(capsys, "contour", path, "z1", "--control-points", "5,4", "--out", tmp_path)
    assert code == 0, err
    assert "5 x 4 control points" in text
    fit, patch = surface_fit(body.u0, body.surface_triangles, body.node_groups["z1"], (5, 4), 3, SMOOTHING)
    phi = body.phi.reshape(body.n_nodes, 3, -1)[patch.nodes][:, :, 0]
    # least squares by a dense solve, independent of the factored normal equations
    B = fit.collocation(fit.params).toarray()
    G = [[FitDirection(n, 3).gram(d).toarray() for d in range(3)] for n in (5, 4)]
    S = np.kron(G[0][2], G[1][0]) + 2 * np.kron(G[0][1], G[1][1]) + np.kron(G[0][0], G[1][2])
    lam = SMOOTHING * np.trace(B.T @ B) / np.trace(S)
    P = np.linalg.solve(B.T @ B + lam * S, B.T @ phi)
    expected = np.linalg.norm(B @ P - phi, axis=1).max() / np.linalg.norm(phi, axis=1).max()
    assert expected > 1e-4
    assert report_row(text, "mode 1")[0] == pytest.approx(expected, rel=1e-3)


def test_structured_grid_is_named_as_such(structured, tmp_path, capsys):
    code, text, err = run(capsys, "contour", structured / "body.h5", "z1", "--out", tmp_path)
    assert code == 0, err
    # 4 x 3 tet10 elements on the face: 9 x 7 nodes with the mid-edge nodes
    assert "a structured grid of 9 x 7 nodes" in text and "interpolates the nodes exactly" in text
    assert max(report_row(text, "geometry")) < 1e-12


def test_closed_band_on_a_cylinder(tmp_path, capsys):
    """The lateral surface of a gmsh cylinder (tet4): a band periodic in eta; the contour's
    samples lie on the cylinder r = R within the reported mid-point bound's order, and its
    quads close across the seam."""
    import meshio

    mesh = gmsh_parts.cylinder_mesh(0.02, order=1)
    r = np.hypot(mesh.points[:, 0], mesh.points[:, 1])
    side = np.flatnonzero(np.abs(r - gmsh_parts.RADIUS) < 1e-9)
    _write(mesh, tmp_path / "cyl", **{"side": side})
    code, text, err = run(capsys, "contour", tmp_path / "cyl", "side", "--out", tmp_path / "o")
    assert code == 0, err
    assert "a closed band, periodic in eta" in text
    assert meshio.read(tmp_path / "o" / "side-fit.vtu").cells[0].type == "triangle"
    contour = meshio.read(tmp_path / "o" / "side-contour.vtu")
    ne, nx = (np.unique(contour.point_data[k]).size for k in ("eta", "xi"))
    assert len(contour.cells[0].data) == ne * (nx - 1)                # closed in eta: ne quads around
    radius = np.hypot(contour.points[:, 0], contour.points[:, 1])
    # linear triangles' chords sit inside the circle by up to h²/(8R); the fit follows them
    h = 0.02
    assert np.abs(radius - gmsh_parts.RADIUS).max() < h ** 2 / (8 * gmsh_parts.RADIUS) * 2


def test_face_with_a_hole_is_trimmed_with_its_rims(tmp_path, capsys):
    """``ffrmbs contour`` on a plate's top face with a 12 mm hole (tet4): a face with one
    hole, not a band; trimmed; the rims reported (the outer edge's length 2 (lx + ly), the
    hole's centre and radius); the fit on the plane to rounding; no quad of the contour's
    grid with its centre in the hole."""
    import meshio

    from validation.cases import contact_hole as case

    mesh = case.plate_hole_mesh(0.008, order=1)
    _write(mesh, tmp_path / "plate")
    code, text, err = run(capsys, "contour", tmp_path / "plate", "top", "--out", tmp_path / "o")
    assert code == 0, err
    assert "a face with 1 hole" in text and "band" not in text and "trimmed" in text
    lx, ly, lz = case.PLATE
    hx, hy, radius = case.HOLE
    assert re.search(rf"outer edge: \d+ nodes, length {2 * (lx + ly):.4g} m", text)
    assert "rim 1: " in text and f"centre ({hx:.4g}, {hy:.4g}, {lz:.4g}) m, mean radius {radius:.4g} m" in text
    assert max(report_row(text, "geometry")) < 1e-12
    contour = meshio.read(tmp_path / "o" / "top-contour.vtu")
    centres = contour.points[contour.cells[0].data].mean(axis=1)
    cell = np.sqrt(np.ptp(contour.points[:, 0]) * np.ptp(contour.points[:, 1]) / len(centres))
    assert np.linalg.norm(centres[:, :2] - (hx, hy), axis=1).min() > radius - cell
    assert np.abs(contour.points[:, 2] - lz).max() < 1e-12


@pytest.mark.parametrize("args, fault", [
    (("nope",), "no node group 'nope'"),
    (("x0+x1",), "separate pieces"),
    (("all",), "not a surface patch"),
    (("surface",), "closed surface"),
    (("z1", "--control-points", "0"), "--control-points"),
    (("z1", "--control-points", "2"), "--control-points"),
    (("z1", "--control-points", "4.5"), "--control-points"),
    (("z1", "--control-points", "nan"), "--control-points"),
    (("z1", "--control-points", "-5"), "--control-points"),
    (("z1", "--control-points", "4,5,6"), "--control-points"),
    (("z1", "--control-points", "40", "--smoothing", "0"), "singular"),
    (("z1", "--smoothing", "nan"), "--smoothing"),
    (("z1", "--smoothing", "-1"), "--smoothing"),
    (("z1", "--smoothing", "inf"), "--smoothing"),
    (("z1", "--smoothing", "x"), "--smoothing"),
])
def test_refusals_are_one_line_and_write_nothing(unstructured, tmp_path, capsys, args, fault):
    path, _ = unstructured
    out = tmp_path / "new" / "out"
    code, text, err = run(capsys, "contour", path, *args, "--out", out)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("ffrmbs: error: ") and fault in err, err
    assert "Traceback" not in err and text == ""
    assert not (tmp_path / "new").exists()


def test_unknown_group_lists_the_known_ones(unstructured, tmp_path, capsys):
    path, body = unstructured
    code, _, err = run(capsys, "contour", path, "nope", "--out", tmp_path / "o")
    assert code == 2 and all(name in err for name in body.node_groups)


def test_group_names_stay_inside_the_output_directory(unstructured, tmp_path, capsys):
    path, _ = unstructured
    out = tmp_path / "a" / "out"
    code, text, err = run(capsys, "contour", path, "..", "--out", out)
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["out"]
    assert sorted(p.name for p in out.iterdir()) == ["__-contour.vtu", "__-fit.png", "__-fit.vtu"]
    assert file_stem("a/../..") == "a______" and file_stem("") == "_"


def test_default_output_directory_and_overwriting(unstructured, tmp_path, capsys, monkeypatch):
    path, _ = unstructured
    monkeypatch.chdir(tmp_path)
    for _ in range(2):                       # a second run replaces the files, leaves no temporaries
        code, _, err = run(capsys, "contour", path, "z1")
        assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "ffrmbs-contour").iterdir()) == \
        ["z1-contour.vtu", "z1-fit.png", "z1-fit.vtu"]


def test_help_names_the_default_smoothing():
    help_text = build_parser()._subparsers._group_actions[0].choices["contour"].format_help()
    assert float(re.search(r"\(default ([0-9.e+-]+)\)", " ".join(help_text.split())).group(1)) == SMOOTHING
