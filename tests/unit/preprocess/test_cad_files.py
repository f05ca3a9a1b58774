"""``ffrmbs preprocess`` of STEP and IGES files: gmsh's OpenCASCADE reader, the file's
length unit converted to the run's, node groups from the CAD names, selection boxes and
bounding planes; checked against the analytic volume, beam theory and the ``.geo`` route
(``Merge "part.step";``)."""

import math
import re

import numpy as np
import pytest

from ffrmbs_app.cli import main
from preprocess import read_body, read_mesh

L, B, H, R = 200.0, 40.0, 10.0, 6.0          # plate [mm] and its through hole's radius, hole at (100, 20)
ALUMINIUM_SI = ["--density", "2700", "--young", "70e9", "--poisson", "0.33"]
ALUMINIUM_MM = ["--density", "2.7e-9", "--young", "70000", "--poisson", "0.33"]


def write_cad(path, hole=True, product=None):
    """A 200 x 40 x 10 mm plate (with its 12 mm through hole) written by gmsh's OCC API
    (STEP or IGES by the suffix; gmsh states mm as the file's unit); ``product``
    renames the STEP product (its id and name; the solid's label)."""
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        plate = gmsh.model.occ.addBox(0, 0, 0, L, B, H)
        if hole:
            gmsh.model.occ.cut([(3, plate)], [(3, gmsh.model.occ.addCylinder(L / 2, B / 2, -1, 0, 0, H + 2, R))])
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    if product is not None:
        path.write_text(re.sub(r"PRODUCT\('[^']*',\s*'[^']*'", f"PRODUCT('{product}','{product}'", path.read_text()))
    return path


def preprocess(capsys, *args):
    """Run ``ffrmbs preprocess`` (first mode clamped at x0); (stdout, stderr), status 0."""
    rc = main(["preprocess", *map(str, args), "--modes", "1", "--clamp", "x0"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return out, err


def printed_mass(out) -> float:
    return float(re.search(r"^total mass:\s+(\S+) kg", out, re.MULTILINE)[1])


def first_frequency(out) -> float:
    return float(re.search(r"^\s+1\s+\S+\s+(\S+)$", out, re.MULTILINE)[1])


@pytest.mark.slow
def test_a_step_plate_with_a_hole_is_meshed_in_metres_with_its_groups(tmp_path, capsys):
    """The mm STEP file read with --units si is 0.2 m long: its mass is ρ·V of the
    analytic volume (L B H − π R² H); the box group holds the hole's face (every node at
    R from its axis), the product's name is a group of every node; the first frequency
    is the .geo route's (``Merge`` of the same file, in mm: the same geometry)."""
    step = write_cad(tmp_path / "plate.step", product="bracket")
    out, err = preprocess(capsys, step, "--mesh-size", "0.01", *ALUMINIUM_SI, "--out", tmp_path / "step",
                          "--group", "hole=0.09,0.01,-1,0.11,0.03,1")
    assert "warning" not in err
    volume = (L * B * H - math.pi * R ** 2 * H) * 1e-9                       # m³
    assert printed_mass(out) == pytest.approx(2700 * volume, rel=2e-4)
    body = read_body(tmp_path / "step" / "body.h5")
    assert np.ptp(body.u0, axis=0) == pytest.approx([0.2, 0.04, 0.01], rel=1e-9)
    hole = body.u0[body.node_groups["hole"]]
    assert len(hole) > 20 and np.allclose(np.hypot(hole[:, 0] - 0.1, hole[:, 1] - 0.02), R * 1e-3, atol=1e-9)
    assert len(body.node_groups["bracket"]) == body.n_nodes
    assert np.allclose(body.u0[body.node_groups["x0"], 0], 0.0)

    (tmp_path / "plate.geo").write_text('SetFactory("OpenCASCADE");\nMerge "plate.step";\n'
                                        'Physical Surface("x0") = Surface In BoundingBox{-1, -1, -1, 1, 41, 11};\n')
    geo_out, _ = preprocess(capsys, tmp_path / "plate.geo", "--units", "si-mm", "--mesh-size", "10",
                            *ALUMINIUM_MM, "--out", tmp_path / "geo")
    assert first_frequency(out) == pytest.approx(first_frequency(geo_out), rel=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".stp", ".igs"])
def test_a_cad_bar_in_mm_weighs_rho_v_and_rings_at_beam_theory(tmp_path, capsys, suffix):
    """The plate without its hole, in mm (--units si-mm): mass ρ·L·B·H, first bending
    frequency (about the thin axis) within 3 % of Euler–Bernoulli's clamped-free beam,
    f1 = (1.8751²/2π) √(E I / (ρ A L⁴)), I = B H³/12 (L/H = 20)."""
    cad = write_cad(tmp_path / f"bar{suffix}", hole=False)
    out, _ = preprocess(capsys, cad, "--units", "si-mm", "--mesh-size", "10", *ALUMINIUM_MM, "--out", tmp_path / "o")
    assert printed_mass(out) == pytest.approx(2700 * L * B * H * 1e-9, rel=1e-9)
    E, rho, area, inertia = 70e9, 2700.0, B * H * 1e-6, B * H ** 3 / 12 * 1e-12
    f1 = 1.87510407 ** 2 / (2 * math.pi) * math.sqrt(E * inertia / (rho * area * (L * 1e-3) ** 4))
    assert first_frequency(out) == pytest.approx(f1, rel=0.03)


@pytest.mark.parametrize("length_unit, per_metre", [("m", 1.0), ("mm", 1e3)])
def test_a_step_file_in_metres_is_read_in_the_runs_unit(tmp_path, length_unit, per_metre):
    """The plate's numbers in a STEP file that states metres: a 200 m plate, 200 in m and
    200 000 in mm."""
    step = write_cad(tmp_path / "bar.step", hole=False)
    text = step.read_text()
    assert "SI_UNIT(.MILLI.,.METRE.)" in text                 # gmsh states mm for the numbers it writes
    step.write_text(text.replace("SI_UNIT(.MILLI.,.METRE.)", "SI_UNIT($,.METRE.)"))
    mesh = read_mesh(step, order=1, mesh_size=L * per_metre, length_unit=length_unit)
    assert np.ptp(mesh.points, axis=0) == pytest.approx(np.array([L, B, H]) * per_metre, rel=1e-9)


def test_a_box_selecting_no_face_is_one_line(tmp_path, capsys):
    """A --group box that holds no face: one line naming the group, the box and the model's extent."""
    step = write_cad(tmp_path / "plate.step")
    rc = main(["preprocess", str(step), *ALUMINIUM_SI, "--modes", "1", "--free", "--out", str(tmp_path / "o"),
               "--group", "nothing=5,5,5,6,6,6"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert re.fullmatch(rf"ffrmbs: error: {re.escape(str(step))}: group 'nothing': no face lies inside the box "
                        r"5, 5, 5, 6, 6, 6 \(the model spans .*\)", err.strip().splitlines()[-1])
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, fault", [
    (["--group", "clamp=0,0,0,1,1"], "--group needs NAME=XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX"),
    (["--group", "clamp=1,0,0,0,1,1"], "--group clamp: each minimum must be at most its maximum"),
    (["--group", "a=0,0,0,1,1,1", "--group", "a=0,0,0,1,1,1"], "--group a is given twice"),
])
def test_a_malformed_group_is_refused_before_meshing(tmp_path, capsys, args, fault):
    (tmp_path / "part.step").write_text("not read")
    rc = main(["preprocess", str(tmp_path / "part.step"), *ALUMINIUM_SI, "--modes", "1", "--free",
               "--out", str(tmp_path / "o"), *args])
    out, err = capsys.readouterr()
    assert rc == 2 and err.strip().splitlines()[-1].startswith(f"ffrmbs: error: {fault}") and "meshing" not in err


def test_a_group_for_a_mesh_file_is_refused(tmp_path, capsys):
    (tmp_path / "part.msh").write_text("not read")
    rc = main(["preprocess", str(tmp_path / "part.msh"), *ALUMINIUM_SI, "--modes", "1", "--free",
               "--out", str(tmp_path / "o"), "--group", "a=0,0,0,1,1,1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.strip().splitlines()[-1] == (
        "ffrmbs: error: --group applies to STEP and IGES files (.step, .stp, .iges, .igs), "
        f"not {tmp_path / 'part.msh'}")


def test_a_cad_file_without_a_solid_or_unreadable_is_one_line(tmp_path, capsys):
    """A STEP file of an open surface only, and one that is not STEP at all: one line
    each, nothing written."""
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addRectangle(0, 0, 0, 10, 5)
        gmsh.model.occ.synchronize()
        gmsh.write(str(tmp_path / "sheet.step"))
    finally:
        gmsh.finalize()
    (tmp_path / "junk.step").write_text("not a STEP file\n")
    for name, fault in (("sheet.step", "no solid in the CAD file, and the 1 face(s) in it do not close into one"),
                        ("junk.step", "gmsh cannot read the CAD file")):
        rc = main(["preprocess", str(tmp_path / name), *ALUMINIUM_SI, "--modes", "1", "--free",
                   "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert rc == 2 and "Traceback" not in err
        assert err.strip().splitlines()[-1].startswith(f"ffrmbs: error: {tmp_path / name}: {fault}")
        assert not (tmp_path / "o").exists()
