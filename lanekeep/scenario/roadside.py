"""The `[roadside]` table of a scenario: what stands beside and over the road (props).

Everything is off by default, so a scenario without the table keeps a bare verge. The props are
built by lanekeep/world/props.py; every random choice (tree and building places, sizes, colours,
facades, hills) is drawn from the scenario seed.

    [roadside]
    guard_rail_sides = ["right"]   # W-beam on posts beyond the gravel
    barrier_sides = ["left"]       # concrete (jersey) barrier beyond the gravel: a median
    pole_spacing_m = 50.0          # light poles every 50 m (0 = none) on pole_sides
    signs_m = [120.0]              # roadside signs (right side) at these arc lengths
    gantries_m = [250.0]           # overhead sign gantries across the road
    overpasses_m = [400.0]         # bridges across the road, with their shadow band
    trees_per_100m = 4.0           # scenery trees per 100 m and side, 4..35 m beyond the gravel
    buildings_per_100m = 0.0       # scenery buildings per 100 m and side, 15..60 m beyond it
    skyline = "hills"              # "none" | "hills" | "city": far hills or far buildings
"""

from __future__ import annotations

from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue

SIDES = ("left", "right")
SKYLINES = ("none", "hills", "city")


@dataclass(frozen=True)
class Roadside:
    """Props beside and over the road; see the module docstring for the keys."""

    guard_rail_sides: tuple[str, ...] = ()
    barrier_sides: tuple[str, ...] = ()
    pole_spacing_m: float = 0.0
    pole_sides: tuple[str, ...] = ("right",)
    signs_m: tuple[float, ...] = ()
    gantries_m: tuple[float, ...] = ()
    overpasses_m: tuple[float, ...] = ()
    trees_per_100m: float = 0.0
    buildings_per_100m: float = 0.0
    skyline: str = "none"
    shadow_darkness: float = 0.55  # as conditions.shadows[].darkness (lanekeep/world/shade.py)

    def __post_init__(self):
        for key in ("guard_rail_sides", "barrier_sides", "pole_sides"):
            sides = getattr(self, key)
            for i, side in enumerate(sides):
                if side not in SIDES:
                    raise InvalidValue(f"{key}[{i}]", f"must be one of {SIDES}, got {side!r}")
            if len(set(sides)) != len(sides):
                raise InvalidValue(key, f"a side is named twice: {sides}")
        both = set(self.guard_rail_sides) & set(self.barrier_sides)
        if both:
            raise InvalidValue("barrier_sides", f"{sorted(both)} already has a guard rail")
        if not (self.pole_spacing_m == 0.0 or 10.0 <= self.pole_spacing_m <= 500.0):
            raise InvalidValue("pole_spacing_m",
                               f"must be 0 (none) or in [10, 500] m, got {self.pole_spacing_m}")
        for key in ("signs_m", "gantries_m", "overpasses_m"):
            for i, s in enumerate(getattr(self, key)):
                if not s >= 0.0:
                    raise InvalidValue(f"{key}[{i}]", f"must be >= 0, got {s}")
        for key in ("trees_per_100m", "buildings_per_100m"):
            if not 0.0 <= getattr(self, key) <= 20.0:
                raise InvalidValue(key, f"must be in [0, 20], got {getattr(self, key)}")
        if self.skyline not in SKYLINES:
            raise InvalidValue("skyline", f"must be one of {SKYLINES}, got {self.skyline!r}")
        if not 0.0 <= self.shadow_darkness <= 1.0:
            raise InvalidValue("shadow_darkness",
                               f"must be in [0, 1], got {self.shadow_darkness}")
