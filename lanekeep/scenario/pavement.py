"""The `[road.pavement]` table of a scenario: how the carriageway is surfaced (the texture that
shows it is drawn by lanekeep/world/pavement.py)."""

from __future__ import annotations

from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue

SURFACES = ("asphalt", "concrete")


@dataclass(frozen=True)
class PavementStyle:
    """How the carriageway is surfaced. Densities are 0 (none) .. 1 (a road overdue for repair)."""

    surface: str = "asphalt"  # "asphalt" | "concrete" (light grey slabs with joints)
    asphalt_tone: float = 0.5  # 0 fresh black asphalt .. 1 old, sun-bleached grey
    cracks: float = 0.3
    patches: float = 0.2
    tyre_marks: float = 0.4  # darkness of the wheel paths and the oil strip between them

    def __post_init__(self):
        if self.surface not in SURFACES:
            raise InvalidValue("surface", f"must be one of {SURFACES}, got {self.surface!r}")
        for key in ("asphalt_tone", "cracks", "patches", "tyre_marks"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise InvalidValue(key, f"must be in [0, 1], got {getattr(self, key)}")
