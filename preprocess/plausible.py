"""Ranges of engineering materials and parts, to catch input given in the wrong units.

A density, Young's modulus or body mass far outside what any engineering part has is
almost always a unit mistake — ``--units si-mm --density 2700`` (kg/m³ typed where
t/mm³ is meant) makes a 2.1e11 kg body whose first frequency is 0.2 Hz. The ranges, in
SI (each system's values are converted before the comparison):

* density :data:`DENSITY` = 10 to 25 000 kg/m³: from rigid foams (polystyrene, about
  15–30 kg/m³) to osmium and iridium (22 600 kg/m³), tungsten 19 300;
* Young's modulus :data:`YOUNG` = 1e4 Pa to 1.2e12 Pa: from soft gels and foams
  (10 kPa) to diamond (about 1.05–1.2 TPa); rubber is 1e6–1e8, steel 2.1e11;
* body mass :data:`MASS` = 1e-6 kg to 1e6 kg: a milligram part to a thousand-tonne
  structure (a lengths-in-mm mesh read as metres weighs 1e9 times its mass).

Values outside are not refused (a user may mean them), only named by
:func:`material_warnings` and :func:`mass_warnings`, which ``ffrmbs preprocess`` prints as
``ffrmbs: warning: …``.
"""

from __future__ import annotations

from preprocess import units as unitsys

DENSITY = (10.0, 25_000.0)      # kg/m³
YOUNG = (1e4, 1.2e12)           # Pa
MASS = (1e-6, 1e6)              # kg

_KINDS = {"density": (DENSITY, "foams to osmium"), "young": (YOUNG, "gels to diamond")}


def _outside(value_si, bounds) -> bool:
    return not bounds[0] <= value_si <= bounds[1]


def _range(bounds, factor, unit) -> str:
    """'lo to hi unit' of SI ``bounds`` in a unit worth ``factor`` SI units."""
    return f"{bounds[0] / factor:.3g} to {bounds[1] / factor:.3g} {unit}"


def _unit(system, kind):
    """(factor to SI, symbol) of ``system``'s unit of ``kind`` ("density" or "young")."""
    return (system.density, system.density_unit) if kind == "density" else (system.stress, system.stress_unit)


def _material_warning(label, kind, value, units) -> str | None:
    """The warning for the material value ``value`` (``kind`` "density" or "young", in the
    units of ``units``), None inside the range; it names the unit of another system in
    which the value would be inside, if there is one, and the value converted from it."""
    system = unitsys.unit_system(units)
    bounds, what = _KINDS[kind]
    factor, unit = _unit(system, kind)
    if not _outside(value * factor, bounds):
        return None
    si = unitsys.UNIT_SYSTEMS["si"]
    message = (f"{label} {value:g} {unit} is outside the range of engineering materials, "
               f"{_range(bounds, factor, unit)} ({what}"
               + (f"; {_range(bounds, 1.0, _unit(si, kind)[1])})" if factor != 1.0 else ")"))
    for other in unitsys.UNIT_SYSTEMS.values():
        other_factor, other_unit = _unit(other, kind)
        if other is not system and not _outside(value * other_factor, bounds):
            message += (f"; in {other_unit} it would be one: --units {units} takes {unit}, "
                        f"{value:g} {other_unit} = {value * other_factor / factor:.3g} {unit}")
    return message


def material_warnings(density, young, units="si") -> list[str]:
    """The warnings (one line each; none inside the ranges) for a ``density`` and a
    Young's modulus ``young`` given in the units of ``units`` (:mod:`preprocess.units`)
    outside :data:`DENSITY` and :data:`YOUNG`."""
    found = [_material_warning("density", "density", density, units),
             _material_warning("Young's modulus", "young", young, units)]
    return [w for w in found if w is not None]


def mass_warnings(total_mass_kg, units="si") -> list[str]:
    """The warning (a list of one line; none inside the range) for a body of
    ``total_mass_kg`` [kg] outside :data:`MASS`, naming the units ``units`` takes."""
    if not _outside(total_mass_kg, MASS):
        return []
    system = unitsys.unit_system(units)
    return [f"the body's mass {total_mass_kg:.3g} kg is outside {_range(MASS, 1.0, 'kg')} (a milligram part to "
            f"a thousand-tonne structure): check the units of the geometry and the density (--units {units}: "
            f"lengths in {system.length_unit}, density in {system.density_unit})"]
