"""The `[conditions]` table of a scenario: light, weather, road surface, other vehicles and image
conditions, with its nested shadow zones and vehicles; all off by default.
"""

from __future__ import annotations

from dataclasses import dataclass

from lanekeep.core.config_io import InvalidValue
from lanekeep.core.setting import check_settings, setting
from lanekeep.scenario.roadside import SIDES

TIMES_OF_DAY = ("day", "dawn", "dusk", "night")
SHADOW_KINDS = ("buildings", "trees")


@dataclass(frozen=True)
class ShadowZone:
    """Hard shadows cast across the road by buildings or trees standing on one side of it.

    The casters' heights are chosen so that, with the scenario's sun, their shadows reach
    `reach` of the carriageway's width (1 = to the far edge line) from the `side` they stand on.
    """

    s_start_m: float = setting(doc="Start of the zone along the road.", allowed=">= 0")
    s_end_m: float = setting(doc="End of the zone along the road.", allowed="> s_start_m")
    kind: str = setting("buildings", "What casts the shadows.", choices=SHADOW_KINDS)
    side: str = setting("left", "Side of the road the casters stand on.", choices=SIDES)
    reach: float = setting(1.0, "How far across the carriageway the shadows reach; 1 = to the far "
                           "edge line.", allowed="(0, 1.5]")
    coverage: float = setting(0.6, "Share of the zone's length in shadow.", bounds=(0.05, 1.0))
    darkness: float = setting(0.55, "How dark the shade is, as the casters' optical depth: 0 "
                              "none, 0.55 a solid building's shade lit by the open sky (about "
                              "0.2-0.35 of the sunlit road's light, from the sun's height, the "
                              "time of day and fog; lanekeep/world/shade.py), more darker still.",
                              bounds=(0.0, 1.0))

    def __post_init__(self):
        check_settings(self)
        if not self.s_end_m > self.s_start_m >= 0.0:
            raise InvalidValue("s_end_m", "need 0 <= s_start_m < s_end_m")
        if not 0.0 < self.reach <= 1.5:
            raise InvalidValue("reach", f"must be in (0, 1.5], got {self.reach}")


@dataclass(frozen=True)
class VehicleSpec:
    """Another car (or truck) driving along a lane at constant speed; it hides markings.

    Driven kinematically (a mocap body): s(t) = s_m + speed_mps * t; negative speeds drive
    towards decreasing s (oncoming traffic, facing the other way).
    """

    lane: int = setting(1, "Its lane; 0 = the rightmost.", allowed="0..n_lanes - 1")
    s_m: float = setting(30.0, "Arc length of its centre at t = 0.")
    speed_mps: float = setting(15.0, "Constant speed along s; negative = oncoming (facing the "
                               "other way).")
    offset_m: float = setting(0.0, "From its lane's centre; + = left.")
    length_m: float = setting(4.6, "Body length.", bounds=(0.5, 20.0))
    width_m: float = setting(1.85, "Body width.", bounds=(0.5, 20.0))
    height_m: float = setting(1.5, "Body height.", bounds=(0.5, 20.0))
    colour: tuple[float, float, float] = setting(
        (0.6, 0.08, 0.08), "Body colour, RGB.", allowed="3 values in 0..1")

    def __post_init__(self):
        check_settings(self)
        if len(self.colour) != 3 or not all(0.0 <= c <= 1.0 for c in self.colour):
            raise InvalidValue("colour", f"must be 3 values in [0, 1], got {self.colour}")


@dataclass(frozen=True)
class Conditions:
    """Light, weather, road surface, traffic and sensor conditions; all off by default.

    Rendered by MuJoCo (lanekeep/world/conditions.py): sun and time of day, shadows, speed bumps,
    wet asphalt and puddles, headlights, other vehicles, snow on the verges. Applied to the
    images with the render's depth (lanekeep/sensing/weather.py): Koschmieder fog, rain streaks
    in depth, wet-road reflections, lens drops, snowflakes, motion blur; `noise` is extra read
    noise of the camera model (lanekeep/sensing/camera_sensor.py, which also does the exposure). The
    default sun reproduces world.py's clear-day light.
    """

    time_of_day: str = setting("day", "Light; headlights are on unless day.",
                               choices=TIMES_OF_DAY)
    sun_elevation_deg: float = setting(66.7, "Sun above the horizon.", bounds=(2.0, 90.0))
    sun_azimuth_deg: float = setting(-144.5, "Direction towards the sun from the road's start "
                                     "heading; + = to the left (anticlockwise).")
    shadows: tuple[ShadowZone, ...] = setting((), "Zones of hard shadows cast across the road.",
                                              allowed="any number")
    speed_bumps_m: tuple[float, ...] = setting((), "Arc length of each speed bump across the "
                                               "road.", allowed="each >= 0")
    speed_bump_height_m: float = setting(0.08, "Height of every speed bump.", bounds=(0.02, 0.15))
    wet: float = setting(0.0, "0 dry .. 1 soaked: darker, glossier asphalt and puddles.",
                         bounds=(0.0, 1.0))
    fog: float = setting(0.0, "0 none .. 1 dense (visibility 400 m .. 25 m).", bounds=(0.0, 1.0))
    rain: float = setting(0.0, "Rain streaks and lens drops (image effect).", bounds=(0.0, 1.0))
    snow: float = setting(0.0, "Flakes and whitening (image), snow on the verges (world).",
                          bounds=(0.0, 1.0))
    noise: float = setting(0.0, "Extra sensor noise of the camera model (read + shot noise).",
                           bounds=(0.0, 1.0))
    motion_blur: float = setting(0.0, "Scale of the speed-proportional motion blur.",
                                 bounds=(0.0, 1.0))
    vehicles: tuple[VehicleSpec, ...] = setting((), "Other vehicles driving along a lane at "
                                                "constant speed.", allowed="any number")

    def __post_init__(self):
        check_settings(self)
        for i, s in enumerate(self.speed_bumps_m):
            if not s >= 0.0:
                raise InvalidValue(f"speed_bumps_m[{i}]", f"must be >= 0, got {s}")

    @property
    def headlights(self) -> bool:
        return self.time_of_day != "day"
