"""The pavement keys of a scenario's `[road]` table: how the carriageway is surfaced (the
texture that shows it is drawn by lanekeep/world/pavement.py)."""

from __future__ import annotations

from dataclasses import dataclass

from lanekeep.core.setting import check_settings, setting

SURFACES = ("asphalt", "concrete")


@dataclass(frozen=True)
class PavementStyle:
    """How the carriageway is surfaced. Densities are 0 (none) .. 1 (a road overdue for repair).
    A scenario holds these keys in `[road]` (lanekeep/scenario/road.py `RoadConfig`, whose
    fields are these)."""

    surface: str = setting("asphalt", "Pavement material (concrete: light grey slabs with "
                           "joints).", choices=SURFACES)
    asphalt_tone: float = setting(0.5, "0 fresh black .. 1 old, sun-bleached grey.",
                                  bounds=(0.0, 1.0))
    cracks: float = setting(0.3, "Amount of cracks in the pavement.", bounds=(0.0, 1.0))
    patches: float = setting(0.2, "Amount of repair patches.", bounds=(0.0, 1.0))
    tyre_marks: float = setting(0.4, "Darker wheel paths and oil strip in every lane.",
                                bounds=(0.0, 1.0))

    def __post_init__(self):
        check_settings(self)
