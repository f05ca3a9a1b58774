"""Units mistakes caught by ``ffrmbs preprocess``: the printed total mass is ρ·V, and a
density, Young's modulus or mass outside the ranges of engineering materials
(:mod:`preprocess.plausible`) is named in a warning, in the units chosen."""

import re

import pytest

from ffrmbs_app.cli import main
from preprocess import plausible

#: (density kg/m³, Young's modulus Pa) of engineering materials, from handbooks
MATERIALS = {"steel": (7850.0, 210e9), "aluminium": (2700.0, 70e9), "rubber": (1100.0, 5e6)}
SI_MM = {"density": 1e-12, "young": 1e-6}     # kg/m³ -> t/mm³, Pa -> N/mm²


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_engineering_materials_give_no_warning_in_either_unit_system(name):
    density, young = MATERIALS[name]
    assert plausible.material_warnings(density, young, "si") == []
    assert plausible.material_warnings(density * SI_MM["density"], young * SI_MM["young"], "si-mm") == []


@pytest.mark.parametrize("mass", [1e-6, 0.0027, 1.0, 5e3, 1e6])
def test_parts_from_a_milligram_to_a_thousand_tonnes_give_no_warning(mass):
    assert plausible.mass_warnings(mass, "si") == [] and plausible.mass_warnings(mass, "si-mm") == []


def test_si_values_typed_for_si_mm_are_named_with_their_conversion():
    """Aluminium's kg/m³ and Pa typed for si-mm: each is outside its range and the
    warning gives the value in the system's unit (2700 kg/m³ = 2.7e-9 t/mm³)."""
    density, young = plausible.material_warnings(2700, 70e9, "si-mm")
    assert density.startswith("density 2700 t/mm³ is outside the range of engineering materials, "
                              "1e-11 to 2.5e-08 t/mm³")
    assert density.endswith("2700 kg/m³ = 2.7e-09 t/mm³")
    assert young.startswith("Young's modulus 7e+10 N/mm² is outside") and young.endswith("7e+10 Pa = 7e+04 N/mm²")
    assert plausible.material_warnings(2.7e-9, 70e3, "si")[0].endswith("2.7e-09 t/mm³ = 2.7e+03 kg/m³")


def printed_mass(out) -> float:
    return float(re.search(r"^total mass:\s+(\S+) kg", out, re.MULTILINE)[1])


#: the same 100 x 10 x 10 mm box and its element size in the lengths of each system
BOX = {"si": ("box:0.1,0.01,0.01", "0.01"), "si-mm": ("box:100,10,10", "10")}


def preprocess_box(capsys, tmp_path, units, density, young, box=None):
    """``ffrmbs preprocess`` of the box of :data:`BOX` (or ``box``: the other system's
    numbers), tet4, one mode clamped at x0; (stdout, stderr)."""
    spec, size = BOX[box or units]
    rc = main(["preprocess", spec, "--mesh-size", size, "--order", "1", "--units", units,
               "--density", str(density), "--young", str(young), "--poisson", "0.3", "--modes", "1",
               "--clamp", "x0", "--out", str(tmp_path / "o")])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return out, err


def warnings_in(err) -> list:
    return [line for line in err.splitlines() if line.startswith("ffrmbs: warning: ")]


def test_the_si_mm_density_mistake_is_warned_and_the_mass_printed(tmp_path, capsys):
    """--units si-mm --density 2700 (kg/m³ by mistake) on the 100 x 10 x 10 mm box: the
    printed mass is ρ·V = 2700 t/mm³ x 1e4 mm³ = 2.7e7 t = 2.7e10 kg, and both the
    density and that mass are warned of."""
    out, err = preprocess_box(capsys, tmp_path, "si-mm", 2700, 70000)
    assert printed_mass(out) == pytest.approx(2700 * 1e12 * 1e-5, rel=1e-12)
    warned = warnings_in(err)
    assert len(warned) == 2
    assert warned[0].startswith("ffrmbs: warning: density 2700 t/mm³ is outside the range of engineering materials")
    assert warned[1].startswith("ffrmbs: warning: the body's mass 2.7e+10 kg is outside 1e-06 to 1e+06 kg")


@pytest.mark.parametrize("units", ["si", "si-mm"])
@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_engineering_materials_print_their_mass_and_no_warning(tmp_path, capsys, units, name):
    """Steel, aluminium and rubber on the 100 x 10 x 10 mm box in either system: no
    warning; the printed mass is ρ·V = ρ x 1e-5 m³."""
    density, young = MATERIALS[name]
    scale = SI_MM if units == "si-mm" else {"density": 1.0, "young": 1.0}
    out, err = preprocess_box(capsys, tmp_path, units, density * scale["density"], young * scale["young"])
    assert printed_mass(out) == pytest.approx(density * 1e-5, rel=1e-12)
    assert warnings_in(err) == []


def test_millimetre_lengths_run_as_metres_are_warned_of(tmp_path, capsys):
    """The mm box's numbers with --units si: a 100 m steel box of 7.85e7 kg, over the mass range."""
    density, young = MATERIALS["steel"]
    out, err = preprocess_box(capsys, tmp_path, "si", density, young, box="si-mm")
    assert printed_mass(out) == pytest.approx(density * 1e4, rel=1e-12)
    assert warnings_in(err) == [
        "ffrmbs: warning: the body's mass 7.85e+07 kg is outside 1e-06 to 1e+06 kg (a milligram part to a "
        "thousand-tonne structure): check the units of the geometry and the density (--units si: lengths in m, "
        "density in kg/m³)"]
