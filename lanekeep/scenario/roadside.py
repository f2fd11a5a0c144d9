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
from lanekeep.core.setting import check_settings, choices_text, setting

SIDES = ("left", "right")
SKYLINES = ("none", "hills", "city")


@dataclass(frozen=True)
class Roadside:
    """Props beside and over the road; see the module docstring for the keys."""

    guard_rail_sides: tuple[str, ...] = setting(
        (), "W-beam guard rail beyond the gravel.", allowed=f"each of {choices_text(SIDES)}, once")
    barrier_sides: tuple[str, ...] = setting(
        (), "Concrete (jersey) barrier beyond the gravel.",
        allowed=f"each of {choices_text(SIDES)}, once; not where a guard rail is")
    pole_spacing_m: float = setting(0.0, "Light poles every so many metres; 0 = none.",
                                    allowed="0 or 10..500")
    pole_sides: tuple[str, ...] = setting(("right",), "Sides with light poles.",
                                          allowed=f"each of {choices_text(SIDES)}, once")
    signs_m: tuple[float, ...] = setting((), "Roadside signs (right side) at these arc lengths.",
                                         allowed="each >= 0")
    gantries_m: tuple[float, ...] = setting((), "Overhead sign gantries at these arc lengths.",
                                            allowed="each >= 0")
    overpasses_m: tuple[float, ...] = setting((), "Bridges across the road (with their shadow "
                                              "band).", allowed="each >= 0")
    trees_per_100m: float = setting(0.0, "Trees per 100 m and side, 4..35 m beyond the gravel.",
                                    bounds=(0.0, 20.0))
    buildings_per_100m: float = setting(0.0, "Buildings per 100 m and side, 15..60 m beyond it.",
                                        bounds=(0.0, 20.0))
    skyline: str = setting("none", "Far background: hills or buildings.", choices=SKYLINES)
    shadow_darkness: float = setting(0.55, "How dark the props' shadows are, as "
                                     "`conditions.shadows[].darkness`.", bounds=(0.0, 1.0))

    def __post_init__(self):
        check_settings(self)
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
