"""Unit systems of the body files (thesis Table 5.1).

- ``"si"``     m, N, kg, s, Pa, kg/m³ — the units of :class:`preprocess.body.BodyData`.
- ``"si-mm"``  mm, N, t (= 1e3 kg), s, MPa, t/mm³ — the "SI(mm)" system of Table 5.1,
  the usual one of ABAQUS models given in millimetres.

Each :class:`UnitSystem` holds the factors that convert a value in its units to SI
(``value_si = value_file * factor``). Force and time are N and s in both systems.
"""

from __future__ import annotations

from dataclasses import dataclass

from ffrmbs.errors import ModelError


@dataclass(frozen=True)
class UnitSystem:
    """Conversion factors of one unit system to SI (multiply to get SI)."""

    name: str
    length_unit: str   # the length unit's symbol, "m" or "mm" (CAD files are converted to it)
    length: float      # length unit -> m        (mm -> m: 1e-3)
    mass: float        # mass unit -> kg         (t -> kg: 1e3)
    stiffness: float   # force/length -> N/m     (N/mm -> N/m: 1e3)
    density: float     # mass/length³ -> kg/m³   (t/mm³ -> kg/m³: 1e12)
    stress: float      # force/length² -> Pa     (MPa -> Pa: 1e6)
    mass_unit: str = "kg"           # the symbols of the units, for messages
    density_unit: str = "kg/m³"
    stress_unit: str = "Pa"


UNIT_SYSTEMS = {
    "si": UnitSystem("si", length_unit="m", length=1.0, mass=1.0, stiffness=1.0, density=1.0, stress=1.0),
    "si-mm": UnitSystem("si-mm", length_unit="mm", length=1e-3, mass=1e3, stiffness=1e3, density=1e12, stress=1e6,
                        mass_unit="t", density_unit="t/mm³", stress_unit="N/mm²"),
}


def unit_system(name: str) -> UnitSystem:
    """The :class:`UnitSystem` called ``name``; ModelError listing the valid names if unknown."""
    try:
        return UNIT_SYSTEMS[name]
    except (KeyError, TypeError):
        raise ModelError(
            f"unknown unit system {name!r}; valid: {', '.join(UNIT_SYSTEMS)}") from None
